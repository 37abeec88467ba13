//! Cancelling a run from outside (Ctrl-C in the Python package): a shared flag, checked by
//! every integrator of the run before each call to `Integrator::advance` ([`super::guard`]).

use super::EngineError;
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
