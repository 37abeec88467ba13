//! The one contract every integrator follows (SUNDIALS' CVODE and ARKStep, homemade methods).

use super::{SolverError, Stats, Step, Task};

/// A running integrator of a fixed system: steps, dense output, restarts and statistics.
///
/// Requirements: `dense(t, k)` is valid for t inside the last internal step; `reinit` restarts
/// at a new (t, y) keeping tolerances and options, and statistics run on across restarts.
pub trait Integrator {
    /// Integrates towards `tout` (one internal step with [`Task::OneStep`]).
    fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError>;
    /// State at [`Integrator::t`].
    fn state(&self) -> &[f64];
    /// Time of the last return.
    fn t(&self) -> f64;
    /// k-th derivative of the interpolated solution at `t` inside the last step.
    fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError>;
    /// Restarts at (t0, y0).
    fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError>;
    /// Statistics over the integrator's life.
    fn stats(&self) -> Stats;
    /// Short name of the integrator family.
    fn name(&self) -> &'static str;
}
