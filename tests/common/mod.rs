//! Test problems and helpers shared by the integrator tests (tests/radau5.rs, tests/rodas5p.rs,
//! tests/extrapolation.rs, tests/wrappers.rs) and the reference tables' check ([`reference`]).
#![allow(dead_code)]

pub mod reference;

use stickslip::integrate::{Integrator, JacobianMatrix, OdeSystem, Task};

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

/// Prothero–Robinson y' = −λ (y − cos t) − sin t, exact y = cos t from y(0) = 1.
pub struct ProtheroRobinson(pub f64);

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * (y[0] - t.cos()) - t.sin();
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

/// OneStep integration of the DRR model from `y0` to total time `tend`, re-basing time (a
/// restart at local t = 0) at the first step end after each slip peak, as the cycle engine
/// does. Returns (steps, peak times).
pub fn drr_cycles(
    integ: &mut dyn Integrator,
    tend: f64,
) -> Result<(u64, Vec<f64>), stickslip::integrate::SolverError> {
    let (mut elapsed, mut steps, mut peaks) = (0.0, 0u64, Vec::new());
    let mut prev_dw = integ.dense(integ.t(), 1)?[1];
    let mut rebase_pending = false;
    while elapsed + integ.t() < tend {
        let step = integ.advance(1e6, Task::OneStep)?;
        steps += 1;
        let y = integ.state().to_vec();
        let dw = integ.dense(step.t, 1)?[1];
        if prev_dw > 0.0 && dw <= 0.0 && y[1] > 5.0 {
            peaks.push(elapsed + step.t);
            rebase_pending = true;
        } else if rebase_pending {
            integ.reinit(0.0, &y)?;
            elapsed += step.t;
            rebase_pending = false;
        }
        prev_dw = dw;
    }
    Ok((steps, peaks))
}
