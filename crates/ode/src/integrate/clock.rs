//! Time bookkeeping for integrations whose steps fall far below the spacing of their clock.
//!
//! A relaxation oscillation can span ~17 decades of time scale and more: in a very stiff
//! phase a cycle lasting ~50 needs steps of 1e-17, or 1e-40 and below where a log-scaled
//! component falls towards a deep floor. No double-precision clock
//! that keeps running resolves that: an integrator fails with "t + h = t" (or with
//! error-test and Newton failures just before, where t + h already rounds).
//!
//! [`Clock`] is the one mechanism every analysis uses for it. It drives an [`Integrator`] one
//! step at a time on a *local* clock and moves the local origin to the current point
//! ([`Integrator::rebase`]) whenever the last step fell below [`Clock::threshold`] × |local t|
//! (and when the caller asks, e.g. at an event). The global time of the local origin, the
//! epoch, is kept exactly as an unevaluated sum of two doubles ([`Time`]), so durations read
//! off the global clock are exact to ~1e-30 relative however many re-bases occur.
//!
//! What a re-base costs: the homemade one-step methods (Radau5, Rodas5P, extrapolation) shift
//! their clock and keep their step size, Jacobian and error history (an exact time shift for an
//! autonomous system); SUNDIALS' CVODE and ARKStep restart (BDF at order 1).
//!
//! Requirements: the system must be autonomous (f independent of t), since the integrator
//! sees the local time only.

use super::{ErrorKind, Integrator, SolverError, StepEvent, Task};

/// A time as an unevaluated sum `hi + lo` of two doubles (|lo| ≤ ulp(hi)/2): about 106 bits.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Time {
    hi: f64,
    lo: f64,
}

/// Error-free sum: a + b = s + e exactly (Knuth's two-sum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

impl Time {
    /// The time `t`.
    pub fn new(t: f64) -> Self {
        Self { hi: t, lo: 0.0 }
    }

    /// This time plus `dt`, to ~1e-32 relative.
    pub fn plus(self, dt: f64) -> Self {
        let (s, e) = two_sum(self.hi, dt);
        let (hi, lo) = two_sum(s, e + self.lo);
        Self { hi, lo }
    }

    /// `self − earlier`, rounded once to a double.
    pub fn since(self, earlier: Time) -> f64 {
        let (s, e) = two_sum(self.hi, -earlier.hi);
        s + (e + (self.lo - earlier.lo))
    }

    /// The nearest double.
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
}

/// One step taken through a [`Clock`], in local time.
#[derive(Debug, Clone, PartialEq)]
pub struct ClockStep {
    /// Local time where the step started: the previous step's end, or 0 when the clock was
    /// re-based before this step.
    pub start: f64,
    /// Local time where the step ended (the integrator's `t()`).
    pub t: f64,
    /// Why the integrator returned.
    pub event: StepEvent,
}

/// Default [`Clock::threshold`] for integrators whose re-base is an exact time shift (free):
/// re-base when the last step is below 1e-3 of the local time, ~13 decades before t + h = t.
/// Measured on the physical grid against 1e-9: the same cells converge but for two more with
/// extrapolation (3713 against 3711 of 4680). A step that collapses by 13 decades inside one
/// call (Radau5 after an accepted step undershot a stiff phase's floor) is beyond any
/// threshold.
pub const DEFAULT_THRESHOLD: f64 = 1e-3;

/// Threshold for integrators whose re-base is a restart (SUNDIALS): only when the clock is
/// about to run out, the last step within 1e4 ulps of the local time. A restart costs work
/// and some accuracy (BDF restarts at order 1), and where f is a stiffness-amplified
/// residual (on a slow manifold) a restarted BDF can fail: callers re-base such integrators earlier
/// only at points they know to be safe ([`Clock::rebase`]).
pub const RESTART_THRESHOLD: f64 = 1e4 * f64::EPSILON;

/// An integrator driven step by step on a local clock that is re-based before it runs out;
/// the global time is kept exactly. See the module documentation.
pub struct Clock<'a> {
    integ: &'a mut dyn Integrator,
    epoch: Time,
    threshold: f64,
    last_step: f64,
    rebases: u64,
}

/// The `tout` of every one-step call, past any time a step reaches: a fixed horizon keeps the
/// integration independent of the caller's stopping rules (CVODE sizes its first step after
/// a restart from |tout − t|).
const HORIZON: f64 = 1e6;

impl<'a> Clock<'a> {
    /// Drives `integ` from its current point, whose global time is `start`, with the
    /// threshold its kind of re-base calls for (`DEFAULT_THRESHOLD` for an exact time shift,
    /// `RESTART_THRESHOLD` for a restart).
    pub fn new(integ: &'a mut dyn Integrator, start: Time) -> Self {
        let epoch = start.plus(-integ.t());
        let threshold = if integ.rebase_restarts() { RESTART_THRESHOLD } else { DEFAULT_THRESHOLD };
        Self { integ, epoch, threshold, last_step: f64::INFINITY, rebases: 0 }
    }

    /// Sets the re-base threshold (last step / |local t|), > 0.
    pub fn with_threshold(mut self, threshold: f64) -> Self {
        self.threshold = threshold;
        self
    }

    /// The re-base threshold: the clock is re-based before a step when the last step was
    /// below `threshold` × |local t|.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Whether a re-base restarts the integrator ([`Integrator::rebase_restarts`]): callers
    /// then re-base only where they must, since a restart costs work and accuracy.
    pub fn rebase_restarts(&self) -> bool {
        self.integ.rebase_restarts()
    }

    /// One internal step, re-basing first if the last step was below the threshold.
    pub fn step(&mut self) -> Result<ClockStep, SolverError> {
        let mut start = self.integ.t();
        if self.last_step < self.threshold * start.abs() {
            // Deep in a layer: a restarting integrator goes on with the step it was taking (a
            // fresh estimate from f there can be off by decades).
            self.rebase_with(Some(self.last_step))?;
            start = self.integ.t();
        }
        let step = match self.integ.advance(start + HORIZON, Task::OneStep) {
            // The step collapsed within one call below the spacing of the local clock (e.g. a
            // cascade of rejections where a rise begins): the clock ran out before the
            // threshold could see it. Re-base at the last returned point, going on with that
            // step, and try once more.
            Err(e) if e.kind == ErrorKind::StepUnderflow && start != 0.0 => {
                let h = self.integ.stats().current_step.abs();
                self.rebase_with((h > 0.0).then_some(h))?;
                start = 0.0;
                self.integ.advance(HORIZON, Task::OneStep)?
            }
            other => other?,
        };
        self.last_step = (step.t - start).abs();
        Ok(ClockStep { start, t: step.t, event: step.event })
    }

    /// Moves the local origin to the current point (global time unchanged); returns the local
    /// time it had. The integrator's dense output of the last step is no longer available. A
    /// restarting integrator estimates its first step afresh: call this at points where its
    /// right-hand side is resolved.
    pub fn rebase(&mut self) -> Result<f64, SolverError> {
        self.rebase_with(None)
    }

    fn rebase_with(&mut self, first_step: Option<f64>) -> Result<f64, SolverError> {
        let t = self.integ.t();
        if t != 0.0 {
            self.integ.rebase(first_step)?;
            self.epoch = self.epoch.plus(t);
            self.rebases += 1;
        }
        Ok(t)
    }

    /// Restarts the integrator at global time `at` with state `y0` (local time 0), with
    /// `first_step` as its first step if given ([`Integrator::reinit_with_step`]).
    pub fn reinit(
        &mut self,
        at: Time,
        y0: &[f64],
        first_step: Option<f64>,
    ) -> Result<(), SolverError> {
        match first_step {
            Some(h) => self.integ.reinit_with_step(0.0, y0, h)?,
            None => self.integ.reinit(0.0, y0)?,
        }
        self.epoch = at;
        self.last_step = f64::INFINITY;
        Ok(())
    }

    /// The global time of local time `t`.
    pub fn global(&self, t: f64) -> Time {
        self.epoch.plus(t)
    }

    /// The global time of the current point.
    pub fn now(&self) -> Time {
        self.global(self.integ.t())
    }

    /// Local time of the current point.
    pub fn t(&self) -> f64 {
        self.integ.t()
    }

    /// State at the current point.
    pub fn state(&self) -> &[f64] {
        self.integ.state()
    }

    /// The integrator's name.
    pub fn name(&self) -> &'static str {
        self.integ.name()
    }

    /// Re-bases so far.
    pub fn rebases(&self) -> u64 {
        self.rebases
    }

    /// The integrator (dense output inside the last step, statistics), in local time.
    pub fn integrator(&mut self) -> &mut dyn Integrator {
        self.integ
    }

    /// A failure at the current point with the global time (as [`SolverError::t`]).
    pub fn at_global(&self, mut error: SolverError) -> SolverError {
        if error.t.is_finite() {
            error.t = self.global(error.t).to_f64();
        }
        error
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_keeps_tiny_increments_exactly() {
        let mut t = Time::new(80.0);
        for _ in 0..1000 {
            t = t.plus(1e-20);
        }
        assert_eq!(t.to_f64(), 80.0, "the sum rounds to 80 in one double");
        let since = t.since(Time::new(80.0));
        assert!((since - 1e-17).abs() < 1e-30, "{since:e}");
    }

    #[test]
    fn since_is_exact_for_large_and_small_parts() {
        let a = Time::new(1e8).plus(0.1).plus(1e-12);
        let b = Time::new(1e8).plus(0.05);
        assert!((a.since(b) - (0.05 + 1e-12)).abs() < 1e-24);
    }
}
