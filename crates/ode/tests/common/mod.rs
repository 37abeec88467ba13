//! Test problems and helpers shared by the integrator tests (tests/methods.rs,
//! tests/radau5.rs, tests/rodas5p.rs, tests/extrapolation.rs, tests/wrappers.rs,
//! tests/solver.rs, tests/unsupported_options.rs).
#![allow(dead_code)]

use stickslip_ode::integrate::{ImexSystem, JacobianMatrix, OdeSystem};

/// y' = 1 + y², y(0) = 0: y = tan t (nonlinear, non-stiff; finite-difference Jacobian).
pub struct Tan;

impl OdeSystem for Tan {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = 1.0 + y[0] * y[0];
    }
}

/// Harmonic oscillator x' = v, v' = −x from (0, 1): x = sin t, v = cos t.
pub struct Oscillator;

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[1];
        dydt[1] = -y[0];
    }
}

/// y' = k·y with an analytic Jacobian.
pub struct Linear(pub f64);

impl OdeSystem for Linear {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = self.0 * y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, self.0);
    }
}

/// Van der Pol in the Test Set's scaled form: y1' = y2, y2' = ((1 − y1²) y2 − y1)/ε.
#[derive(Clone, Copy)]
pub struct VanDerPol(pub f64);

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[1];
        dydt[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.0;
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 1, 1.0);
        jac.set(1, 0, (-2.0 * y[0] * y[1] - 1.0) / self.0);
        jac.set(1, 1, (1.0 - y[0] * y[0]) / self.0);
    }
}

/// A right-hand side that returns NaN once t passes `from`.
pub struct NanAfter(pub f64);

impl OdeSystem for NanAfter {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = if t > self.0 { f64::NAN } else { -y[0] };
    }
}

/// Prothero–Robinson y' = −λ (y − cos t) − sin t, exact y = cos t from y(0) = 1 (analytic
/// Jacobian).
pub struct ProtheroRobinson(pub f64);

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * (y[0] - t.cos()) - t.sin();
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.0);
    }
}

/// y' = −k y, exact solution y0·e^{−kt} (analytic Jacobian); as an IMEX system all of it is
/// implicit.
pub struct Decay(pub f64);

impl OdeSystem for Decay {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.0);
    }
}

impl ImexSystem for Decay {
    fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt[0] = 0.0;
    }
    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.rhs(t, y, dydt);
    }
}

/// A nonlinear system with every elementary differential of order ≤ 5 independent:
/// y = φ(z) with z' = M z (rotation in (z1, z2), decay of z3) and φ(z) = (z1, z2 + z1²,
/// z3 + z1 z2), so f(y) = Dφ(φ⁻¹(y)) M φ⁻¹(y) (finite-difference Jacobian).
pub struct Warped;

impl Warped {
    fn z(y: &[f64]) -> [f64; 3] {
        let z1 = y[0];
        let z2 = y[1] - z1 * z1;
        [z1, z2, y[2] - z1 * z2]
    }

    /// The solution at t from z(0) = (0.3, 0.8, 1).
    pub fn exact(t: f64) -> [f64; 3] {
        // z1 = 0.3 cos t + 0.8 sin t, z2 = −0.3 sin t + 0.8 cos t.
        let (s, c) = t.sin_cos();
        let z = [0.3 * c + 0.8 * s, -0.3 * s + 0.8 * c, (-0.5 * t).exp()];
        [z[0], z[1] + z[0] * z[0], z[2] + z[0] * z[1]]
    }
}

impl OdeSystem for Warped {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let z = Self::z(y);
        let dz = [z[1], -z[0], -0.5 * z[2]];
        dydt[0] = dz[0];
        dydt[1] = dz[1] + 2.0 * z[0] * dz[0];
        dydt[2] = dz[2] + dz[0] * z[1] + z[0] * dz[1];
    }
}

/// y' = y cos t, y(0) = 1: y = e^{sin t} (non-autonomous: needs ∂f/∂t).
pub struct Forced;

impl OdeSystem for Forced {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[0] * t.cos();
    }
}

/// Numbers in scientific notation with 16 digits.
pub fn sci(v: &[f64]) -> String {
    v.iter().map(|x| format!("{x:.16e}")).collect::<Vec<_>>().join(", ")
}

/// Observed orders log2(e(h)/e(h/2)) for successive halvings.
pub fn observed_orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}
