//! Stiffness switching between the two schemes (see the parent module's documentation for the
//! rule and its measurements): the explicit → implicit test on the secant eigenvalue estimate of
//! an explicit attempt, the implicit → explicit test on a bound of the Jacobian's spectral
//! radius, the window of recent outcomes, and entering a scheme afresh.

use super::{Extrapolation, Mode};
use crate::integrate::OdeSystem;

/// Explicit → implicit when |H|·ρ exceeds this fraction of the stability boundary.
const STIFF_FRACTION: f64 = 0.5;
/// Implicit → explicit when |H_acc|·ρ_J is below this fraction of the stability boundary.
const NONSTIFF_FRACTION: f64 = 0.25;
/// A switch needs this many failed (passed) tests among the last `WINDOW` ones.
const REPEATS: u32 = 3;
const WINDOW: u32 = 5;

/// min(‖J‖₁, ‖J‖_∞) of the column-major `jac`, unscaled and scaled as D⁻¹JD with D = diag(scal):
/// each an upper bound of the spectral radius.
pub(super) fn jacobian_bound(jac: &[f64], scal: &[f64], n: usize) -> f64 {
    let mut best = f64::INFINITY;
    for scaled in [false, true] {
        let entry = |i: usize, j: usize| {
            let v = jac[j * n + i].abs();
            if scaled {
                v * scal[j] / scal[i]
            } else {
                v
            }
        };
        let inf = (0..n).map(|i| (0..n).map(|j| entry(i, j)).sum::<f64>()).fold(0.0, f64::max);
        let one = (0..n).map(|j| (0..n).map(|i| entry(i, j)).sum::<f64>()).fold(0.0, f64::max);
        best = best.min(inf).min(one);
    }
    if best.is_nan() {
        f64::INFINITY
    } else {
        best
    }
}

impl<S: OdeSystem> Extrapolation<S> {
    /// SEULEX's and ODEX's starting column for the tolerance.
    pub(super) fn initial_k(&self, mode: Mode) -> usize {
        let tol = match mode {
            Mode::Explicit => self.weights.rtol,
            Mode::Implicit => self.weights.rtol + self.weights.atol[0],
        };
        let guess = (-tol.log10() * 0.6 + 1.5).floor().max(0.0) as usize;
        match mode {
            Mode::Explicit => guess.min(self.exp.km - 1).max(3),
            Mode::Implicit => guess.min(self.imp.km - 2).max(3),
        }
    }

    /// Starts `mode` afresh: its starting column, the first-step procedure, no history.
    pub(super) fn enter(&mut self, mode: Mode) {
        self.mode = mode;
        self.k = self.initial_k(mode);
        self.first = true;
        self.core.reject = false;
        self.history = 0;
        self.theta = 2.0 * self.thet;
        self.caljac = false;
        self.hoptde = f64::INFINITY;
        self.w[1] = if mode == Mode::Implicit { 1e30 } else { 0.0 };
    }

    /// Records one stiffness-test outcome; true when a switch is due.
    fn record(&mut self, asks_switch: bool) -> bool {
        self.history = ((self.history << 1) | asks_switch as u32) & ((1 << WINDOW) - 1);
        self.history.count_ones() >= REPEATS
    }

    fn switch_to(&mut self, mode: Mode) {
        self.switches += 1;
        self.enter(mode);
    }

    /// The explicit → implicit test after an explicit attempt of size `h_used`. An attempt
    /// that was not unstable and gave no eigenvalue estimate (every pair of rows ended at the
    /// same point, or the f-differences overflowed) is no evidence either way and is not
    /// recorded: where a stiff rate reaches 1e170 (a rate-and-state friction problem whose
    /// log-rate component fell to −340) steps of 1e-13 leave the state unchanged to the last bit, and counting them as non-stiff
    /// between the unstable attempts kept the midpoint scheme there for 2e6 steps.
    pub(super) fn stiffness_test(&mut self, h_used: f64, unstable: bool) {
        if self.forced.is_some() || self.mode != Mode::Explicit {
            return;
        }
        let stiff = match self.rho {
            _ if unstable => true,
            Some(rho) => {
                h_used.abs() * rho > STIFF_FRACTION * self.lsb[self.last_row.clamp(1, self.exp.km)]
            }
            None => return,
        };
        if self.record(stiff) {
            self.switch_to(Mode::Implicit);
        }
    }

    /// The implicit → explicit test after an implicit step of size `h_used` accepted in column
    /// kc: H_acc, the step the column's error estimate asks for without SEULEX's growth
    /// limits, against the explicit scheme's stability bound.
    pub(super) fn nonstiffness_test(&mut self, h_used: f64, kc: usize) {
        if self.forced.is_some() || self.mode != Mode::Implicit {
            return;
        }
        let ke = self.initial_k(Mode::Explicit);
        let ctl = &self.imp;
        let fac = (self.err / ctl.safe1).powf(1.0 / kc as f64) / ctl.safe2;
        let h_acc = (h_used.abs() / fac).min(self.core.hmax);
        let nonstiff = h_acc * self.rho_jac <= NONSTIFF_FRACTION * self.lsb[ke];
        if self.record(nonstiff) {
            self.switch_to(Mode::Explicit);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_bound_covers_the_spectral_radius() {
        // [[0, 1], [-1e6, -1e3]]: eigenvalues ≈ −1e3 ± i·999.5, |λ| = 1e3.
        let jac = [0.0, -1e6, 1.0, -1e3];
        let b = jacobian_bound(&jac, &[1.0, 1e3], 2);
        assert!((1e3..=2.1e3).contains(&b), "{b}");
    }
}
