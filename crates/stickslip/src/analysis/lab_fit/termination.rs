//! Why a fit stopped, in documented words (docs/lab.md) rather than the optimiser's own.

use levenberg_marquardt::TerminationReason;
use serde::Serialize;

/// Why a fit stopped (the JSON report's `termination`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// Converged: the sum of squares (ftol) or the parameters (xtol) stopped changing, by
    /// MINPACK's tests.
    Converged,
    /// Converged: the residuals are orthogonal to every column of the Jacobian (gtol), a
    /// stationary point.
    Orthogonal,
    /// Converged: the residuals are exactly zero.
    ResidualsZero,
    /// Not converged: the tolerances cannot be met in floating point (no step improves the
    /// fit at machine precision).
    NoImprovementPossible,
    /// Not converged: `--max-evaluations` reached.
    MaxEvaluations,
    /// Not converged: `--max-time` passed.
    MaxTime,
    /// Not converged: an evaluation took far more steps than the first.
    ExpensiveEvaluation,
    /// Not converged: the optimiser met a non-finite number.
    NumericalFailure,
}

impl Termination {
    /// The word for the optimiser's reason. Its `User` reason arises only when a limit stops
    /// the fit, which [`super::fit`] reports itself; `LostPatience` is the evaluation limit.
    pub fn from_report(reason: &TerminationReason) -> Self {
        match reason {
            TerminationReason::Converged { .. } => Self::Converged,
            TerminationReason::Orthogonal => Self::Orthogonal,
            TerminationReason::ResidualsZero => Self::ResidualsZero,
            TerminationReason::NoImprovementPossible(_) => Self::NoImprovementPossible,
            TerminationReason::LostPatience | TerminationReason::User(_) => Self::MaxEvaluations,
            TerminationReason::Numerical(_)
            | TerminationReason::NoParameters
            | TerminationReason::NoResiduals
            | TerminationReason::WrongDimensions(_) => Self::NumericalFailure,
        }
    }

    /// Whether the fit converged.
    pub fn is_converged(self) -> bool {
        matches!(self, Self::Converged | Self::Orthogonal | Self::ResidualsZero)
    }

    /// The word as in the report, e.g. "max_evaluations".
    pub fn name(self) -> &'static str {
        match self {
            Self::Converged => "converged",
            Self::Orthogonal => "orthogonal",
            Self::ResidualsZero => "residuals_zero",
            Self::NoImprovementPossible => "no_improvement_possible",
            Self::MaxEvaluations => "max_evaluations",
            Self::MaxTime => "max_time",
            Self::ExpensiveEvaluation => "expensive_evaluation",
            Self::NumericalFailure => "numerical_failure",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The report's word is the serialised one.
    #[test]
    fn names_are_the_serialised_words() {
        for t in [
            Termination::Converged,
            Termination::Orthogonal,
            Termination::ResidualsZero,
            Termination::NoImprovementPossible,
            Termination::MaxEvaluations,
            Termination::MaxTime,
            Termination::ExpensiveEvaluation,
            Termination::NumericalFailure,
        ] {
            assert_eq!(serde_json::to_value(t).unwrap(), t.name());
        }
    }
}
