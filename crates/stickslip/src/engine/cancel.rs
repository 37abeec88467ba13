//! Cancelling a run from outside (Ctrl-C in the Python package): a shared flag, checked by
//! every integrator of the run before each call to `Integrator::advance` ([`super::guard`]).

use super::lab::LabError;
use super::EngineError;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A request to stop a run early. The caller keeps a clone and calls [`Cancel::cancel`] (from
/// any thread); the run ([`super::run`] with [`super::RunOptions::cancel`]) checks it before each integrator call, so
/// it stops within one call (a step, or an advance to the next output time), and returns
/// [`RunError::Cancelled`].
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl From<LabError> for RunError {
    fn from(e: LabError) -> Self {
        RunError::Lab(Box::new(e))
    }
}

impl RunError {
    /// Whether the input is at fault rather than the computation (an option that does not fit
    /// the computed orbit, named by its field; [`EngineError::is_bad_input`]): the CLI's exit
    /// code 2, not 1.
    pub fn is_bad_input(&self) -> bool {
        matches!(self, RunError::Failed(e) if e.is_bad_input())
    }

    /// A short label of the failure's kind, as the stress grid tallies them: the analysis
    /// error's ([`crate::analysis::AnalysisError::label`]), "LabRun" or "Cancelled".
    pub fn label(&self) -> String {
        match self {
            RunError::Failed(e) => e.kind.label(),
            RunError::Lab(_) => "LabRun".into(),
            RunError::Cancelled => "Cancelled".into(),
        }
    }
}

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

/// Why [`super::run`] returned no report.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The run failed: the analysis at fault, where and why.
    #[error(transparent)]
    Failed(#[from] EngineError),
    /// A laboratory run failed (boxed: it is large).
    #[error(transparent)]
    Lab(Box<LabError>),
    /// The caller cancelled the run ([`Cancel::cancel`]) before it finished.
    #[error("the run was cancelled")]
    Cancelled,
}

/// Whether `cancel` is given and set.
pub(super) fn is_set(cancel: Option<&Cancel>) -> bool {
    cancel.is_some_and(Cancel::is_cancelled)
}
