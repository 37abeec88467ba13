//! The Dieterich–Ruina–Rice spring-slider in dimensionless form, integrated in
//! y = (u, w = ln v, θ):
//!
//!   du/dt = v − 1,  dw/dt = −γ² e^{−w} (u + (θ + f(v))/ξ),  dθ/dt = −v (θ + (1+ε) f(v)).
//!
//! Working in w keeps v > 0 automatically and lets v span 1e-30 … 1e10.
//!
//! Reference: Pomeau & Le Berre, "Critical speed-up vs critical slow-down" (eqs. DR1–DR3
//! rescaled); Rice & Tse (1986); Dieterich (1979); Ruina (1983).

use super::friction::Friction;
use crate::integrate::{ImexSystem, JacobianMatrix, OdeSystem};

/// Parameters of the dimensionless DRR model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DrrParams {
    /// γ = (D_c/v0)·√(k/M) > 0, the stiffness parameter.
    pub gamma: f64,
    /// ξ = k·D_c/A > 0.
    pub xi: f64,
    /// ε = (B − A)/A.
    pub epsilon: f64,
    /// The friction law f(v).
    pub friction: Friction,
}

/// Index of u in the state vector.
pub const U: usize = 0;
/// Index of w = ln v in the state vector.
pub const W: usize = 1;
/// Index of θ in the state vector.
pub const THETA: usize = 2;

/// The DRR system in (u, w, θ).
#[derive(Debug, Clone, Copy)]
pub struct Drr {
    params: DrrParams,
    gamma2: f64,
}

impl Drr {
    /// The system for the given parameters.
    pub fn new(params: DrrParams) -> Self {
        Self { params, gamma2: params.gamma * params.gamma }
    }

    /// The parameters.
    pub fn params(&self) -> &DrrParams {
        &self.params
    }

    /// The fixed point (u*, w* = 0, θ*): v = 1, θ* = −(1+ε) f(1), u* = ε f(1)/ξ.
    pub fn fixed_point(&self) -> [f64; 3] {
        let p = &self.params;
        let (f1, _) = p.friction.eval(0.0);
        [p.epsilon * f1 / p.xi, 0.0, -(1.0 + p.epsilon) * f1]
    }

    /// The distance to the slow manifold, G = u + (θ + f(v))/ξ (dv/dt = −γ² G).
    pub fn manifold_offset(&self, y: &[f64]) -> f64 {
        let (f, _) = self.params.friction.eval(y[W]);
        y[U] + (y[THETA] + f) / self.params.xi
    }

    /// w on the slow manifold G = 0 for given (u, θ), if the friction law allows it
    /// (f(v) = −(ξu + θ) must be in the range of f).
    pub fn manifold_w(&self, u: f64, theta: f64) -> Option<f64> {
        let target = -(self.params.xi * u + theta);
        let w = match self.params.friction {
            Friction::Log => target,
            Friction::Asinh => (target > 0.0).then(|| target.sinh().ln())?,
            Friction::Power { alpha } => {
                let base = 1.0 + alpha * target;
                (base > 0.0).then(|| base.ln() / alpha)?
            }
        };
        w.is_finite().then_some(w)
    }

    /// u on the slow manifold for given (w, θ).
    pub fn manifold_u(&self, w: f64, theta: f64) -> f64 {
        let (f, _) = self.params.friction.eval(w);
        -(theta + f) / self.params.xi
    }

    fn split(&self, y: &[f64]) -> (f64, f64, f64) {
        let w = y[W];
        let (f, _) = self.params.friction.eval(w);
        let g = y[U] + (y[THETA] + f) / self.params.xi;
        let dw = -self.gamma2 * (-w).exp() * g;
        let dtheta = -w.exp() * (y[THETA] + (1.0 + self.params.epsilon) * f);
        (w.exp_m1(), dw, dtheta)
    }
}

impl OdeSystem for Drr {
    fn dim(&self) -> usize {
        3
    }

    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let (du, dw, dtheta) = self.split(y);
        dydt[U] = du;
        dydt[W] = dw;
        dydt[THETA] = dtheta;
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let p = &self.params;
        let w = y[W];
        let v = w.exp();
        let (f, vfp) = p.friction.eval(w);
        let g = y[U] + (y[THETA] + f) / p.xi;
        let a = self.gamma2 * (-w).exp();
        jac.set(U, W, v);
        jac.set(W, U, -a);
        jac.set(W, W, a * (g - vfp / p.xi));
        jac.set(W, THETA, -a / p.xi);
        jac.set(THETA, W, -v * (y[THETA] + (1.0 + p.epsilon) * f) - v * (1.0 + p.epsilon) * vfp);
        jac.set(THETA, THETA, -v);
    }

    fn has_jacobian_derivative(&self) -> bool {
        true
    }

    fn jacobian_derivative(&self, _t: f64, y: &[f64], k: usize, out: &mut JacobianMatrix<'_>) {
        let p = &self.params;
        let w = y[W];
        let v = w.exp();
        let (f, vfp) = p.friction.eval(w);
        let h = p.friction.d_vfprime_dw(w);
        let g = y[U] + (y[THETA] + f) / p.xi;
        let a = self.gamma2 * (-w).exp();
        let c = 1.0 + p.epsilon;
        match k {
            U => out.set(W, W, a),
            THETA => {
                out.set(W, W, a / p.xi);
                out.set(THETA, W, -v);
            }
            _ => {
                out.set(U, W, v);
                out.set(W, U, a);
                out.set(W, W, -a * g + 2.0 * a * vfp / p.xi - a * h / p.xi);
                out.set(W, THETA, a / p.xi);
                out.set(THETA, W, -v * (y[THETA] + c * f) - 2.0 * c * v * vfp - c * v * h);
                out.set(THETA, THETA, -v);
            }
        }
    }
}

/// IMEX split: the plate drive (the −1 of du/dt = v − 1) explicit; the friction and inertia
/// terms implicit. At large γ no state component is non-stiff in every phase: w relaxes onto
/// the slow manifold at rate γ²/(ξv) and drags u with it through −γ² e^{−w} u, and θ relaxes
/// at rate v ≈ γ ln γ during a slip. Splitting any of them off (tried: u, θ) makes the
/// scheme stability-limited, with 1e5 steps per cycle and periods wrong at 1e-5.
impl ImexSystem for Drr {
    fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt[U] = -1.0;
        dydt[W] = 0.0;
        dydt[THETA] = 0.0;
    }

    fn rhs_implicit(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let (_, dw, dtheta) = self.split(y);
        dydt[U] = y[W].exp();
        dydt[W] = dw;
        dydt[THETA] = dtheta;
    }

    fn has_implicit_jacobian(&self) -> bool {
        true
    }

    fn implicit_jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.jacobian(t, y, jac);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;

    fn laws() -> [Friction; 3] {
        [Friction::Log, Friction::Asinh, Friction::Power { alpha: 0.31 }]
    }

    #[test]
    fn jacobian_matches_central_differences() {
        for friction in laws() {
            let drr = Drr::new(DrrParams { gamma: 10.0, xi: 0.7, epsilon: 0.72, friction });
            for y in [[0.3, -0.4, 0.2], [-1.0, 2.5, 0.7], [2.0, -3.0, -1.0]] {
                for (row, col, exact, fd) in jacobian_against_differences(&drr, &y, |x| 1e-6 * (1.0 + x.abs())) {
                    assert!((fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()), "{friction:?} y={y:?} ({row},{col}): {exact} vs {fd}");
                }
            }
        }
    }

    #[test]
    fn jacobian_derivative_matches_central_differences_of_the_jacobian() {
        for friction in laws() {
            let drr = Drr::new(DrrParams { gamma: 10.0, xi: 0.7, epsilon: 0.72, friction });
            for y in [[0.3, -0.4, 0.2], [-1.0, 2.5, 0.7], [2.0, -3.0, -1.0]] {
                for k in 0..3 {
                    let mut exact = [0.0; 9];
                    drr.jacobian_derivative(0.0, &y, k, &mut JacobianMatrix::new(&mut exact, 3));
                    let h = 1e-6 * (1.0 + y[k].abs());
                    let (mut yp, mut ym) = (y, y);
                    yp[k] += h;
                    ym[k] -= h;
                    let (mut jp, mut jm) = ([0.0; 9], [0.0; 9]);
                    drr.jacobian(0.0, &yp, &mut JacobianMatrix::new(&mut jp, 3));
                    drr.jacobian(0.0, &ym, &mut JacobianMatrix::new(&mut jm, 3));
                    for i in 0..9 {
                        let fd = (jp[i] - jm[i]) / (2.0 * h);
                        assert!((fd - exact[i]).abs() <= 1e-5 * (1.0 + exact[i].abs()), "{friction:?} y={y:?} k={k} entry {i}: {} vs {fd}", exact[i]);
                    }
                }
            }
        }
    }

    #[test]
    fn fixed_point_is_stationary_and_on_the_manifold() {
        for friction in laws() {
            let drr = Drr::new(DrrParams { gamma: 1e8, xi: 0.8, epsilon: 1.0, friction });
            let y = drr.fixed_point();
            let mut f = [1.0; 3];
            drr.rhs(0.0, &y, &mut f);
            assert!(f.iter().all(|v| v.abs() < 1e-12), "{friction:?}: {f:?}");
            let w = drr.manifold_w(y[U], y[THETA]).unwrap();
            assert!(w.abs() < 1e-12, "{friction:?}: {w}");
        }
    }

    #[test]
    fn imex_parts_add_up_to_the_full_rhs() {
        let drr = Drr::new(DrrParams { gamma: 1e3, xi: 0.7, epsilon: 0.72, friction: Friction::Log });
        let y = [0.4, 1.3, -0.8];
        let (mut full, mut e, mut i) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        drr.rhs(0.0, &y, &mut full);
        drr.rhs_explicit(0.0, &y, &mut e);
        drr.rhs_implicit(0.0, &y, &mut i);
        for k in 0..3 {
            assert_eq!(full[k], e[k] + i[k]);
        }
    }
}
