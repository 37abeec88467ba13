//! arkode-imex stops with an error when its steps no longer move u, deep on a stick
//! ([`crate::engine::EngineSettings::stop_when_u_freezes`]).
//!
//! Every ARK pair's implicit table has an explicit first stage, whose derivative f_I(y_n)
//! ARKStep evaluates afresh at each step (SUNDIALS 6.4.1 always; 7.1.1 reuses the last stage's
//! only when both tables are stiffly accurate, which no ARK explicit table is). On the slow
//! manifold f_I's ln v component is −γ²e^(−w)G: the round-off of G = u + (θ + ln v)/ξ times
//! the stiff rate γ²e^(−w)/ξ, and the step's update carries it into y_{n+1} and the error
//! estimate. After a stick crossed in closed form ([`crate::model::DeepStick`]) the
//! integration resumes at ln v = −50, where that rate is γ²e^(50)/ξ (6.5e37 at γ = 1e8,
//! ξ = 0.8). Measured on the earthquake scene (rtol 1e-10):
//!
//! - from (1e6, 1e-300, 1e3), resumed at (−1187.5, ln v = −50, 1000): the steps grew to
//!   3.6e-13, failed the error test 8 times and then stayed at 1.0003e-17 for millions of
//!   steps, ARKODE keeping h because the proposed growth lay in its window [1, 1.5], with
//!   u's increments of 1e-17 below its spacing. With every step change applied
//!   (ARKStepSetFixedStepBounds(1, 1)) ln v alternated between −50 and −50 + 1e-11 from step
//!   to step, with an error-test failure every other step, at steps of 5e-19 … 2e-17;
//! - from (−1e6, 1e-300, 0), resumed at (125.966, −50, −50.773): h stayed at 2.457e-16.
//!
//! The stick ahead lasts tens of time units, so both runs ended only at the cycle's 20
//! million steps, after more than 150 s. With this check they stop after 10 000 steps of one
//! size that leave u unchanged (0.07 s and 0.2 s). A step that does not move u although
//! du/dt = v − 1 ≠ 0 is below u's spacing; one of the same size from the same u follows only
//! while ARKODE keeps h, i.e. while its error estimate stays level. Legitimate runs of
//! arkode-imex do not trip it: the shipped earthquake scene, and the quick stress grid's
//! arkode-imex cells, which reach the same outcomes as without it except those that ran into
//! it (issue #28).

use crate::integrate::{ErrorKind, Integrator, SolverError};
use crate::model::drr::{U, W};
use crate::model::Drr;

/// Consecutive steps of one size that leave u unchanged, to the last bit, while
/// du/dt = v − 1 ≠ 0, after which a run is stopped: each lies below u's spacing, and ARKODE
/// keeps h only while its error estimate stays level, so such a run crawls on for ever. At
/// 10 000 the check costs the two measured runs 0.07 s and 0.2 s.
const FROZEN_STEPS: u32 = 10_000;

/// The count of steps that left u unchanged; an error once [`FROZEN_STEPS`] consecutive steps
/// of one size did so while u must move (v ≠ 1; see the module documentation).
pub(super) struct FrozenU {
    /// γ²/ξ of the model.
    gamma2_over_xi: f64,
    /// u after the last step.
    last_u: f64,
    /// The size of the last step, read only while the state stays unchanged (NaN otherwise).
    last_h: f64,
    /// Consecutive steps of size `last_h` that left the state unchanged.
    repeats: u32,
}

impl FrozenU {
    /// A count for arkode-imex on `drr` (or a system derived from it, whose state starts with
    /// the DRR's) starting at `y0`.
    pub(super) fn new(drr: &Drr, y0: &[f64]) -> Self {
        let p = drr.params();
        let gamma2_over_xi = p.gamma * p.gamma / p.xi;
        Self { gamma2_over_xi, last_u: y0[U], last_h: f64::NAN, repeats: 0 }
    }

    /// Forgets the steps counted (the integrator restarts).
    pub(super) fn reset(&mut self) {
        (self.last_h, self.repeats) = (f64::NAN, 0);
    }

    /// Counts the step `integrator` just took; the error once [`FROZEN_STEPS`] in a row, of one
    /// size, left u unchanged while its derivative v − 1 is not zero. The step size is read (the
    /// integrator's statistics) only while u stays unchanged.
    pub(super) fn count(&mut self, integrator: &dyn Integrator) -> Result<(), SolverError> {
        if integrator.state()[U] != self.last_u {
            self.last_u = integrator.state()[U];
            self.reset();
            return Ok(());
        }
        let h = integrator.stats().last_step;
        self.repeats = if h == self.last_h { self.repeats + 1 } else { 0 };
        self.last_h = h;
        let (t, y) = (integrator.t(), integrator.state());
        let w = y[W];
        if self.repeats < FROZEN_STEPS || w.exp() - 1.0 == 0.0 {
            return Ok(());
        }
        let rate = self.gamma2_over_xi * (-w).exp();
        Err(SolverError {
            solver: integrator.name(),
            kind: ErrorKind::NoProgress,
            t,
            state: y.to_vec(),
            flag: 0,
            message: format!(
                "{FROZEN_STEPS} steps in a row, each of h = {h:.3e}, left u = {} \
                 unchanged to the last bit, though du/dt = v − 1 = {:.3}: the steps lie below \
                 u's spacing. At ln v = {w} the stiff rate γ²e^(−ln v)/ξ = {rate:.1e} amplifies \
                 the round-off of arkode-imex's explicit first stage f_I(y_n), which holds its \
                 steps there; use cvode-bdf, radau5, rodas5p, extrapolation or arkode-dirk",
                y[U],
                w.exp() - 1.0,
            ),
        })
    }
}
