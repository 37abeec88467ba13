//! Why a comparison against a user's file cannot be made: bad input (exit 2) or a failed or
//! inaccurate reference (exit 1).

use super::sampled::SamplingError;
use super::scale::SceneMismatch;
use crate::integrate::SolverError;

/// Why a comparison cannot be made: bad input (exit 2) or a failed or inaccurate reference
/// (exit 1).
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// The user's data cannot be compared (sampled too coarsely); the message says why.
    #[error("{0}")]
    Input(SamplingError),
    /// The reference's events cannot be located even on its own steps.
    #[error("the reference could not be resolved: {0}")]
    UnresolvedReference(SamplingError),
    /// The reference integration failed.
    #[error("reference run failed: {0}")]
    Reference(SolverError),
    /// The reference run of a report comparison failed.
    #[error("reference run failed: {0}")]
    ReferenceRun(crate::engine::RunError),
    /// The file does not fit the scene (other units, an offset u, too long a span).
    #[error("{0}")]
    Mismatch(#[from] SceneMismatch),
    /// The reference's own accuracy is not below tolerance/10 for some quantities.
    #[error(
        "the reference's own accuracy is not below tolerance/10 = {:.1e} for {}, so no verdict; \
         use a larger --tolerance (for a report, or another --reference-method)",
        tolerance / 10.0,
        quantities.iter().map(|(q, a)| format!("{q} ({a:.1e})")).collect::<Vec<_>>().join(", ")
    )]
    InaccurateReference {
        /// The quantities and their accuracy.
        quantities: Vec<(String, f64)>,
        /// The tolerance asked for.
        tolerance: f64,
    },
}

impl From<SolverError> for CompareError {
    fn from(e: SolverError) -> Self {
        Self::Reference(e)
    }
}
