//! The slow manifold S of the DRR model and the 2D flow on it (the paper's eq. 2D).
//!
//! Setting the coefficient of γ² to zero gives S: ξu + θ + f(v) = 0, i.e. v = v_S(u, θ) with
//! f(v_S) = −(ξu + θ) (v_S = e^{−(ξu+θ)} for f = ln v). On S the 3D flow reduces to
//!
//! ```text
//! du/dt = v_S − 1,   dθ/dt = v_S [εθ + (1+ε) ξ u],
//! ```
//!
//! free of γ (the θ equation is −v(θ + (1+ε) f(v)) with f(v) = −(ξu + θ), for every friction
//! law). For f = ln v it blows up in finite time (v_S → ∞ at t_c) when the matching constant
//! c of [`matching_c`] is ≤ 0.
//!
//! To follow the blow-up to its end, the flow is integrated in the arc parameter s with
//! dt/ds = 1/(1 + v): y = (t, u, θ) obeys dt/ds = q, du/ds = (v − 1) q, dθ/ds = v q [εθ + (1+ε)ξu]
//! with q = 1/(1 + v), a smooth system without singularity; t(s) converges to t_c as s → ∞.
//!
//! Matching (the paper's eqs. racor1, raccord, dvg): where 1 ≪ v ≪ γ, u' = v and
//! dθ/du = εθ + (1+ε)ξu, so θ(u) = c e^{εu} − K (1 + εu) with K = (1+ε)ξ/ε², and u' = e^{Φ(u)}
//! with Φ(u) = −c e^{εu} + (ξ/ε) u + K.

use super::drr::{Drr, DrrParams};
use crate::integrate::{JacobianMatrix, OdeSystem};

/// Index of t in the arc-parameter state.
pub const T: usize = 0;
/// Index of u in the arc-parameter state.
pub const U: usize = 1;
/// Index of θ in the arc-parameter state.
pub const THETA: usize = 2;

/// The 2D slow flow on S, integrated in the arc parameter s (state (t, u, θ)).
#[derive(Debug, Clone, Copy)]
pub struct SlowFlow {
    drr: Drr,
}

/// q = 1/(1 + e^w) and 1 − q = e^w/(1 + e^w), without overflow for any w.
fn q_pair(w: f64) -> (f64, f64) {
    if w > 0.0 {
        let e = (-w).exp();
        (e / (1.0 + e), 1.0 / (1.0 + e))
    } else {
        let e = w.exp();
        (1.0 / (1.0 + e), e / (1.0 + e))
    }
}

impl SlowFlow {
    /// The slow flow of the model with these parameters.
    pub fn new(params: DrrParams) -> Self {
        Self { drr: Drr::new(params) }
    }

    /// The parameters.
    pub fn params(&self) -> &DrrParams {
        self.drr.params()
    }

    /// ln v_S(u, θ), None where the friction law has no point of S (e.g. asinh with ξu + θ ≥ 0).
    pub fn w(&self, u: f64, theta: f64) -> Option<f64> {
        self.drr.manifold_w(u, theta)
    }

    /// (du/dt, dθ/dt) of the 2D flow at (u, θ).
    pub fn velocity(&self, u: f64, theta: f64) -> Option<(f64, f64)> {
        let p = self.params();
        let v = self.w(u, theta)?.exp();
        Some((v - 1.0, v * (p.epsilon * theta + (1.0 + p.epsilon) * p.xi * u)))
    }

    /// d(ln v_S)/dt along the 2D flow: −(ξ u' + θ') / (v f'(v)).
    pub fn dw_dt(&self, u: f64, theta: f64) -> Option<f64> {
        let w = self.w(u, theta)?;
        let (du, dtheta) = self.velocity(u, theta)?;
        let (_, vfp) = self.params().friction.eval(w);
        Some(-(self.params().xi * du + dtheta) / vfp)
    }
}

impl OdeSystem for SlowFlow {
    fn dim(&self) -> usize {
        3
    }

    fn rhs(&self, _s: f64, y: &[f64], dy: &mut [f64]) {
        let p = self.params();
        let Some(w) = self.w(y[U], y[THETA]) else {
            dy.fill(f64::NAN);
            return;
        };
        let (q, vq) = q_pair(w);
        dy[T] = q;
        dy[U] = vq - q;
        dy[THETA] = vq * (p.epsilon * y[THETA] + (1.0 + p.epsilon) * p.xi * y[U]);
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _s: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let p = self.params();
        let Some(w) = self.w(y[U], y[THETA]) else { return };
        let (q, vq) = q_pair(w);
        let (_, vfp) = p.friction.eval(w);
        // q² dv_S/dθ·(−1) = q² v/(v f'(v)) = q (1 − q)/(v f'(v)); dv_S/du = ξ dv_S/dθ.
        let k = q * vq / vfp;
        let h = p.epsilon * y[THETA] + (1.0 + p.epsilon) * p.xi * y[U];
        jac.set(T, U, p.xi * k);
        jac.set(T, THETA, k);
        jac.set(U, U, -2.0 * p.xi * k);
        jac.set(U, THETA, -2.0 * k);
        jac.set(THETA, U, -p.xi * k * h + vq * (1.0 + p.epsilon) * p.xi);
        jac.set(THETA, THETA, -k * h + vq * p.epsilon);
    }
}

/// K = (1+ε)ξ/ε² of the matching curve.
pub fn matching_k(xi: f64, epsilon: f64) -> f64 {
    (1.0 + epsilon) * xi / (epsilon * epsilon)
}

/// The matching constant c of the curve θ(u) = c e^{εu} − K(1 + εu) through (u, θ).
pub fn matching_c(xi: f64, epsilon: f64, u: f64, theta: f64) -> f64 {
    (theta + matching_k(xi, epsilon) * (1.0 + epsilon * u)) * (-epsilon * u).exp()
}

/// θ on the matching curve with constant c.
pub fn matching_theta(xi: f64, epsilon: f64, c: f64, u: f64) -> f64 {
    c * (epsilon * u).exp() - matching_k(xi, epsilon) * (1.0 + epsilon * u)
}

/// Φ(u) = −c e^{εu} + (ξ/ε) u + K: u' = e^{Φ(u)} on the matching curve.
pub fn phi(xi: f64, epsilon: f64, c: f64, u: f64) -> f64 {
    // c = 0 exactly: no exponential term (0 · e^{εu} would be NaN once e^{εu} overflows).
    let growth = if c == 0.0 { 0.0 } else { -c * (epsilon * u).exp() };
    growth + xi / epsilon * u + matching_k(xi, epsilon)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;
    use crate::model::Friction;

    fn flow(friction: Friction) -> SlowFlow {
        SlowFlow::new(DrrParams::new(1e3, 0.7, 0.72, friction))
    }

    #[test]
    fn jacobian_matches_central_differences() {
        for friction in [Friction::Log, Friction::Power { alpha: 0.15 }, Friction::Asinh] {
            let f = flow(friction);
            for y in [[0.0, 0.3, -1.2], [1.0, -1.0, 0.4], [2.0, 2.0, -4.5]] {
                for (row, col, exact, fd) in
                    jacobian_against_differences(&f, &y, |x| 1e-6 * (1.0 + x.abs()))
                {
                    assert!(
                        (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                        "{friction:?} {y:?} ({row},{col}): {exact} vs {fd}"
                    );
                }
            }
        }
    }

    #[test]
    fn arc_parameter_flow_is_the_2d_flow_rescaled() {
        let f = flow(Friction::Log);
        let (u, theta) = (0.4, -1.1);
        let (du, dtheta) = f.velocity(u, theta).unwrap();
        let mut d = [0.0; 3];
        f.rhs(0.0, &[0.0, u, theta], &mut d);
        assert!((d[U] / d[T] - du).abs() < 1e-12 && (d[THETA] / d[T] - dtheta).abs() < 1e-12);
        // The paper's form: v = e^{−(ξu+θ)}, dθ/dt = v [εθ + (1+ε)ξu].
        let v = (-(0.7 * u + theta)).exp();
        assert!((dtheta - v * (0.72 * theta + 1.72 * 0.7 * u)).abs() < 1e-12);
        // Far out on the blow-up, nothing overflows.
        f.rhs(0.0, &[0.0, 50.0, -2000.0], &mut d);
        assert!(d.iter().all(|x| x.is_finite()) && d[T] == 0.0);
    }

    #[test]
    fn matching_curve_solves_its_ode_and_phi_is_ln_v() {
        let (xi, e, c) = (0.7, 0.72, -0.3);
        for u in [-1.0, 0.5, 3.0] {
            let h = 1e-6;
            let dtheta =
                (matching_theta(xi, e, c, u + h) - matching_theta(xi, e, c, u - h)) / (2.0 * h);
            let theta = matching_theta(xi, e, c, u);
            assert!((dtheta - (e * theta + (1.0 + e) * xi * u)).abs() < 1e-7);
            assert!((matching_c(xi, e, u, theta) - c).abs() < 1e-12);
            // On the curve, ln v = −(ξu + θ) = Φ(u).
            assert!((-(xi * u + theta) - phi(xi, e, c, u)).abs() < 1e-12);
        }
        // c = 0: no NaN where e^{εu} overflows.
        assert_eq!(phi(xi, e, 0.0, 2000.0), xi / e * 2000.0 + matching_k(xi, e));
    }
}
