//! The one contract every integrator follows (SUNDIALS' CVODE and ARKStep, homemade methods).

use super::{SolverError, Stats, Step, Task};

/// A running integrator of a fixed system: steps, dense output, restarts and statistics.
///
/// Requirements: `dense(t, k)` is valid for t inside the last internal step; `reinit` restarts
/// at a new (t, y) keeping tolerances and options, and statistics run on across restarts.
pub trait Integrator {
    /// Integrates towards `tout` (one internal step with [`Task::OneStep`]). A failure is an
    /// error at the last accepted step, a panicking callback included
    /// ([`ErrorKind::CallbackPanic`](super::ErrorKind::CallbackPanic)); the integrator can go
    /// on from there.
    fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError>;
    /// State at [`Integrator::t`].
    fn state(&self) -> &[f64];
    /// Time of the last return.
    fn t(&self) -> f64;
    /// k-th derivative of the interpolated solution at `t` inside the last step.
    fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError>;
    /// Restarts at (t0, y0).
    fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError>;
    /// Restarts at (t0, y0) with `first_step` as the first step, for a method that otherwise
    /// sizes its first step (and predicts its first stage) from f(t0, y0): SUNDIALS'. Where
    /// f(y0) is not the derivative of the solution through y0 (on a slow manifold deeper than
    /// its round-off, [`super::Clock::reinit`]'s caller knows the true one), such an estimate
    /// can be off by decades. The homemade methods start their stages from y0 and ignore it.
    fn reinit_with_step(
        &mut self,
        t0: f64,
        y0: &[f64],
        first_step: f64,
    ) -> Result<(), SolverError> {
        let _ = first_step;
        self.reinit(t0, y0)
    }
    /// Sets (or moves) the time the integrator must not step past, as
    /// [`Options::stop_time`](super::Options::stop_time) does at construction. A call whose
    /// `tout` lies beyond the stop time returns there with
    /// [`StepEvent::StopTime`](super::StepEvent::StopTime); a call whose `tout` equals it
    /// returns [`StepEvent::Reached`](super::StepEvent::Reached) (the output time came
    /// first), at exactly the stop time, with the same state; either way the stop time is then
    /// disabled, and the next call may go on past it (every method alike, tests/contract.rs).
    /// A non-finite time is an `InvalidInput` error.
    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError>;
    /// Sets the largest step the integrator may take from its next step on (`None`: no
    /// limit), as [`Options::max_step`](super::Options::max_step) does at construction (a step
    /// already taken beyond the last returned time stays). A value that is not finite and
    /// positive is an `InvalidInput` error.
    fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError>;
    /// Moves the time origin to the last returned point: afterwards `t()` is 0 and the state
    /// is unchanged. Methods that can keep their step size and history do (an exact time shift
    /// for an autonomous system); by default the integrator restarts at (0, state), with
    /// `first_step` as its first step if given (where the step in progress is known to be
    /// right, e.g. deep inside a layer, and a fresh estimate from f is not). The dense output
    /// of the last step is no longer available. Used by [`super::Clock`].
    fn rebase(&mut self, first_step: Option<f64>) -> Result<(), SolverError> {
        let _ = first_step;
        let y = self.state().to_vec();
        self.reinit(0.0, &y)
    }
    /// Whether [`Integrator::rebase`] restarts the method (true by default) rather than
    /// shifting its clock exactly.
    fn rebase_restarts(&self) -> bool {
        true
    }
    /// Statistics over the integrator's life.
    fn stats(&self) -> Stats;
    /// The method's name, e.g. "cvode-bdf" or "radau5" (as
    /// [`SolverError::solver`](super::SolverError::solver)).
    fn name(&self) -> &'static str;
    /// The largest k that [`Integrator::dense`] accepts now: 1 before the first step (and
    /// after a restart), then the method's bound (radau5 3, rodas5p 4, extrapolation 3,
    /// ARKStep DIRK and ERK 5, ARKStep IMEX 3; CVODE the order of its last step, at most 5 for
    /// BDF and 12 for Adams).
    fn max_dense_order(&self) -> u32;
    /// Warnings the integrator issued and went on after (SUNDIALS': "t + h = t" and the like,
    /// the first 64); the homemade methods issue none (they count step underflows in
    /// [`Stats::step_underflow_warnings`]).
    fn warnings(&self) -> &[String] {
        &[]
    }
}
