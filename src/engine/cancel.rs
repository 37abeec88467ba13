//! Cancelling a run from outside (Ctrl-C in the Python package): a shared flag, checked by
//! every integrator of the run before each call to [`Integrator::advance`].

use super::EngineError;
use crate::integrate::{ErrorKind, Integrator, SolverError, Stats, Step, Task};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A request to stop a run early. The caller keeps a clone and calls [`Cancel::cancel`] (from
/// any thread); the run ([`super::run_cancellable`]) checks it before each integrator call, so
/// it stops within one call (a step, or an advance to the next output time), and returns
/// [`RunError::Cancelled`].
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A flag not yet set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the run to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Why a cancellable run returned no report.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// The run failed (as [`super::run_with_series`] fails).
    #[error(transparent)]
    Failed(#[from] EngineError),
    /// The caller cancelled the run ([`Cancel::cancel`]) before it finished.
    #[error("the run was cancelled")]
    Cancelled,
}

/// Whether `cancel` is given and set.
pub(super) fn is_set(cancel: Option<&Cancel>) -> bool {
    cancel.is_some_and(Cancel::is_cancelled)
}

/// `integrator`, failing every [`Integrator::advance`] once `cancel` is set. The error (kind
/// [`ErrorKind::Other`]) goes up through the analyses like any integrator failure; the run
/// then reports [`RunError::Cancelled`] instead of it.
pub(super) fn cancellable<'a>(
    integrator: Box<dyn Integrator + 'a>,
    cancel: Option<&Cancel>,
) -> Box<dyn Integrator + 'a> {
    match cancel {
        Some(cancel) => Box::new(Cancellable { inner: integrator, cancel: cancel.clone() }),
        None => integrator,
    }
}

/// An integrator that checks a [`Cancel`] before each advance (see [`cancellable`]).
struct Cancellable<'a> {
    inner: Box<dyn Integrator + 'a>,
    cancel: Cancel,
}

impl Integrator for Cancellable<'_> {
    fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
        if self.cancel.is_cancelled() {
            return Err(SolverError {
                solver: self.inner.name(),
                kind: ErrorKind::Other,
                t: self.inner.t(),
                state: self.inner.state().to_vec(),
                flag: 0,
                message: "the run was cancelled".to_string(),
            });
        }
        self.inner.advance(tout, task)
    }

    fn state(&self) -> &[f64] {
        self.inner.state()
    }

    fn t(&self) -> f64 {
        self.inner.t()
    }

    fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError> {
        self.inner.dense(t, k)
    }

    fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        self.inner.reinit(t0, y0)
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
        self.inner.set_stop_time(t_stop)
    }

    fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
        self.inner.set_max_step(max_step)
    }

    fn rebase(&mut self, first_step: Option<f64>) -> Result<(), SolverError> {
        self.inner.rebase(first_step)
    }

    fn rebase_restarts(&self) -> bool {
        self.inner.rebase_restarts()
    }

    fn stats(&self) -> Stats {
        self.inner.stats()
    }

    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn max_dense_order(&self) -> u32 {
        self.inner.max_dense_order()
    }

    fn warnings(&self) -> &[String] {
        self.inner.warnings()
    }
}
