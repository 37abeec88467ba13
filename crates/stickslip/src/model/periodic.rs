//! Periodic loading (QDYN's `APER`, `TPER`): a shear stress A_per·sin(2πt/T_per) added to the
//! spring's load on the DRR spring-block, inertial and quasi-dynamic.
//!
//! Dimensionless (stress in A = aσ, time in D_c/v0): s(t) = a_per sin(Ω t) with
//! a_per = A_per/(aσ) and Ω = 2π/T, T = T_per·v0/D_c. The spring's stress over A is −ξu, so
//! the load is −ξu + s(t) and the force balance's offset becomes
//!
//! ```text
//! G_s = u − s(t)/ξ + (Φ + η v)/ξ:
//! inertial:        dw/dt = −γ² e^{−w} G_s,
//! quasi-dynamic:   dw/dt = −(ξ(v − 1) − s'(t) + P R + κ_G ξ G_s)/S,
//! ```
//!
//! (P = Φ_θ, R = dθ/dt, S = Φ_w + η v; [`super::quasi_dynamic`]), while du/dt = v − 1 and
//! dθ/dt do not change. Both are the unforced right-hand side at the shifted state
//! y_s = (u − s(t)/ξ, w, θ), plus s'(t)/S in the quasi-dynamic dw/dt: so [`ForcedDrr`] is
//! [`Drr`] at y_s, its Jacobian in y is [`Drr`]'s at y_s (∂y_s/∂y = I) plus the derivative of
//! s'/S, and ∂f/∂t is J·∂y_s/∂t = −(s'/ξ) times J's u column, plus s''/S. QDYN (its
//! derivs_all.f90) adds dτ_per/dt = Ω_per A_per cos(Ω_per t) to the stress rate: the same
//! term, t from QDYN's start.
//!
//! The system is not autonomous. The integrations re-base their local clock (a restart or an
//! exact time shift, see [`crate::integrate::Clock`]); the forced system reads the global time
//! as its [`TimeOrigin`] plus the local time, and the engine's integrator moves the origin by
//! the same shift at each re-base. The unforced [`Drr`] never pays for any of this.

use super::drr::{Drr, THETA, U, W};
use crate::integrate::{ImexSystem, JacobianMatrix, OdeSystem};
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// The dimensionless periodic loading s(t) = amplitude·sin(2πt/period).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeriodicLoading {
    /// a_per = A_per/(aσ): the amplitude in units of A.
    pub amplitude: f64,
    /// T = T_per·v0/D_c: the forcing period in units of D_c/v0.
    pub period: f64,
}

impl PeriodicLoading {
    /// Ω = 2π/T.
    pub fn omega(&self) -> f64 {
        std::f64::consts::TAU / self.period
    }

    /// s(t), s'(t) and s''(t) at global time t.
    pub fn stress(&self, t: f64) -> [f64; 3] {
        let omega = self.omega();
        let (sin, cos) = (omega * t).sin_cos();
        let a = self.amplitude;
        [a * sin, a * omega * cos, -a * omega * omega * sin]
    }

    /// The phase of global time t in the forcing period, in [0, 1).
    pub fn phase(&self, t: f64) -> f64 {
        let p = (t / self.period).rem_euclid(1.0);
        if p >= 1.0 {
            0.0
        } else {
            p
        }
    }
}

/// The global time of an integrator's local time 0, shared between the forced system inside
/// the integrator and the integrator's owner, which moves it at each re-base of the local clock.
#[derive(Debug, Clone, Default)]
pub struct TimeOrigin(Arc<AtomicU64>);

impl TimeOrigin {
    /// The origin at global time 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// The global time of local time 0.
    pub fn get(&self) -> f64 {
        f64::from_bits(self.0.load(Ordering::Relaxed))
    }

    /// Moves the origin by `shift` (the local time that becomes the new local 0).
    pub fn advance(&self, shift: f64) {
        self.0.store((self.get() + shift).to_bits(), Ordering::Relaxed);
    }
}

/// The DRR system under periodic loading (see the module documentation), in (u, w, θ) at
/// local time t, global time origin + t.
#[derive(Debug, Clone)]
pub struct ForcedDrr {
    drr: Drr,
    loading: PeriodicLoading,
    origin: TimeOrigin,
}

impl ForcedDrr {
    /// The system `drr` loaded by `loading`, its local time 0 at `origin`'s global time.
    pub fn new(drr: Drr, loading: PeriodicLoading, origin: TimeOrigin) -> Self {
        Self { drr, loading, origin }
    }

    /// The unforced system.
    pub fn drr(&self) -> &Drr {
        &self.drr
    }

    /// The loading.
    pub fn loading(&self) -> &PeriodicLoading {
        &self.loading
    }

    /// s, s', s'' at local time t and the shifted state y_s = (u − s/ξ, w, θ).
    fn shifted(&self, t: f64, y: &[f64]) -> ([f64; 3], [f64; 3]) {
        let s = self.loading.stress(self.origin.get() + t);
        ([y[U] - s[0] / self.drr.params().xi, y[W], y[THETA]], s)
    }

    /// S = Φ_w + η v and its gradient (∂S/∂w, ∂S/∂θ) (quasi-dynamic only).
    fn stiffness(&self, y: &[f64]) -> (f64, [f64; 2]) {
        let t = self.drr.strength(y);
        (t.d1[0], [t.d2[0], t.d2[1]])
    }

    /// The unforced Jacobian at y_s with the quasi-dynamic s'/S term: returns J at y_s alone
    /// in `jac` plus the term, given s'.
    fn jacobian_shifted(&self, ys: &[f64; 3], rate: f64, jac: &mut JacobianMatrix<'_>) {
        self.drr.jacobian(0.0, ys, jac);
        if !self.drr.params().inertia {
            let (s, grad) = self.stiffness(ys);
            let c = -rate / (s * s);
            jac.set(W, W, jac.get(W, W) + c * grad[0]);
            jac.set(W, THETA, jac.get(W, THETA) + c * grad[1]);
        }
    }
}

impl OdeSystem for ForcedDrr {
    fn dim(&self) -> usize {
        3
    }

    fn has_linear_invariants(&self) -> bool {
        self.drr.has_linear_invariants()
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let (ys, s) = self.shifted(t, y);
        self.drr.rhs(t, &ys, dydt);
        if !self.drr.params().inertia {
            dydt[W] += s[1] / self.stiffness(&ys).0;
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let (ys, s) = self.shifted(t, y);
        self.jacobian_shifted(&ys, s[1], jac);
    }

    fn has_time_derivative(&self) -> bool {
        true
    }

    /// ∂f/∂t = J_unforced(y_s)·∂y_s/∂t (∂u_s/∂t = −s'/ξ) plus, quasi-dynamic, s''/S.
    fn time_derivative(&self, t: f64, y: &[f64], out: &mut [f64]) {
        let (ys, s) = self.shifted(t, y);
        let mut j = [0.0; 9];
        self.drr.jacobian(0.0, &ys, &mut JacobianMatrix::new(&mut j, 3));
        let du = -s[1] / self.drr.params().xi;
        let column = |row: usize| j[U * 3 + row];
        for (row, o) in out.iter_mut().enumerate().take(3) {
            *o = column(row) * du;
        }
        if !self.drr.params().inertia {
            out[W] += s[2] / self.stiffness(&ys).0;
        }
    }
}

/// IMEX split as [`Drr`]'s: the plate drive explicit, everything else (the forcing included)
/// implicit.
impl ImexSystem for ForcedDrr {
    fn rhs_explicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.drr.rhs_explicit(t, y, dydt);
    }

    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.rhs(t, y, dydt);
        dydt[U] += 1.0;
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
    use crate::model::{DrrParams, Friction, StateLaw};

    fn systems() -> Vec<ForcedDrr> {
        let loading = PeriodicLoading { amplitude: 0.4, period: 3.7 };
        let mut out = Vec::new();
        for friction in [Friction::Log, Friction::CutOff { v1: 3.0, v2: 0.5 }, Friction::Asinh] {
            for (_, state_law) in StateLaw::ALL {
                let inertial =
                    DrrParams { state_law, eta: 0.2, ..DrrParams::new(30.0, 0.7, 0.72, friction) };
                let quasi =
                    DrrParams { state_law, ..DrrParams::quasi_dynamic(0.7, 0.72, 0.37, friction) };
                for p in [inertial, quasi] {
                    let origin = TimeOrigin::new();
                    origin.advance(1.3);
                    out.push(ForcedDrr::new(Drr::new(p), loading, origin));
                }
            }
        }
        out
    }

    const STATES: [[f64; 3]; 3] = [[0.3, -0.4, 0.2], [-1.0, 2.5, 0.7], [2.0, -3.0, -1.0]];

    #[test]
    fn jacobian_matches_central_differences() {
        for f in systems() {
            for y in STATES {
                for (row, col, exact, fd) in
                    jacobian_against_differences(&f, &y, |x| 1e-6 * (1.0 + x.abs()))
                {
                    assert!(
                        (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                        "{:?} y={y:?} ({row},{col}): {exact} vs {fd}",
                        f.drr().params()
                    );
                }
            }
        }
    }

    #[test]
    fn time_derivative_matches_central_differences() {
        for f in systems() {
            for y in STATES {
                for t in [0.0, 0.9, 2.2] {
                    let mut exact = [0.0; 3];
                    f.time_derivative(t, &y, &mut exact);
                    let h = 1e-6;
                    let (mut p, mut m) = ([0.0; 3], [0.0; 3]);
                    f.rhs(t + h, &y, &mut p);
                    f.rhs(t - h, &y, &mut m);
                    for k in 0..3 {
                        let fd = (p[k] - m[k]) / (2.0 * h);
                        assert!(
                            (fd - exact[k]).abs() <= 1e-6 * (1.0 + exact[k].abs()),
                            "{:?} y={y:?} t={t} k={k}: {} vs {fd}",
                            f.drr().params(),
                            exact[k]
                        );
                    }
                }
            }
        }
    }

    /// Without amplitude the forced system is the unforced one; with it, the force balance
    /// G_s = G − s/ξ relaxes at the constraint rate (quasi-dynamic), the check that the
    /// s'/S term has the right sign.
    #[test]
    fn zero_amplitude_is_the_unforced_system_and_the_forced_balance_relaxes() {
        for f in systems() {
            let zero = ForcedDrr::new(
                *f.drr(),
                PeriodicLoading { amplitude: 0.0, ..*f.loading() },
                TimeOrigin::new(),
            );
            for y in STATES {
                let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
                zero.rhs(0.7, &y, &mut a);
                f.drr().rhs(0.7, &y, &mut b);
                assert_eq!(a, b);
            }
            if f.drr().params().inertia {
                continue;
            }
            let drr = f.drr();
            let t = 0.6;
            for y in STATES {
                let g = |t: f64, y: &[f64]| {
                    drr.manifold_offset(y) - f.loading().stress(1.3 + t)[0] / drr.params().xi
                };
                let mut d = [0.0; 3];
                f.rhs(t, &y, &mut d);
                let h = 1e-6;
                let along = |s: f64| g(t + s, &[y[0] + s * d[0], y[1] + s * d[1], y[2] + s * d[2]]);
                let dg = (along(h) - along(-h)) / (2.0 * h);
                let kappa = crate::model::quasi_dynamic::CONSTRAINT_RELAXATION_RATE;
                assert!(
                    (dg + kappa * g(t, &y)).abs() <= 1e-6 * (1.0 + dg.abs()),
                    "y={y:?}: dG/dt {dg} vs −κG {}",
                    -kappa * g(t, &y)
                );
            }
        }
    }
}
