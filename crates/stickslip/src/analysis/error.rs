//! The analysis layer's errors: one enum for every analysis. An integrator's own failure is
//! wrapped unchanged ([`AnalysisError::Solver`]); everything else says what the analysis found
//! (an option that does not fit the orbit, no limit cycle, an event that never came, a
//! non-finite result) and, where there is one, where (t and the state).

use crate::integrate::{Clock, SolverError};

/// An option outside its valid range: the field, relative to the analysis's options object
/// (empty for the object itself), and what is wrong and what would be valid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct InvalidOption {
    /// The field, e.g. `gammas` or `amplitudes[1]` (empty: the whole object).
    pub field: String,
    /// What is wrong and what would be valid.
    pub message: String,
}

impl InvalidOption {
    /// The error for `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self { field: field.into(), message: message.into() }
    }

    /// The options object `T` read from `value`; a parse error names the whole object.
    pub fn parse<T: serde::de::DeserializeOwned>(value: serde_json::Value) -> Result<T, Self> {
        serde_json::from_value(value).map_err(|e| Self::new("", e.to_string()))
    }

    /// Checks that the field `tolerance`, if given, lies in (0, 0.1]; `example` is a valid
    /// value the message suggests.
    pub fn check_tolerance(tolerance: Option<f64>, example: &str) -> Result<(), Self> {
        match tolerance {
            Some(t) if !(t > 0.0 && t <= 0.1) => {
                Err(Self::new("tolerance", format!("{t} must be in (0, 0.1], e.g. {example}")))
            }
            _ => Ok(()),
        }
    }

    /// The field's full path below `base` (e.g. `analyses[2].noise`), as a scene names it.
    pub fn path_below(&self, base: &str) -> String {
        if self.field.is_empty() {
            base.to_string()
        } else {
            format!("{base}.{}", self.field)
        }
    }
}

/// Why an analysis failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    /// An integration failed (the integrator's error, unchanged).
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// An option does not fit this model or orbit (e.g. a window longer than the period).
    #[error(transparent)]
    InvalidOption(#[from] InvalidOption),
    /// The analysis does not apply here (e.g. a stable fixed point has no event to align on).
    #[error("{reason}")]
    NotApplicable {
        /// Why, and what would apply.
        reason: String,
    },
    /// There is no (usable) limit cycle to work on.
    #[error("{reason}")]
    NoLimitCycle {
        /// Why.
        reason: String,
    },
    /// An iteration that the analysis builds on did not converge (e.g. shooting).
    #[error("{what} did not converge: {reason}")]
    NotConverged {
        /// The iteration, e.g. "shooting".
        what: &'static str,
        /// Its own account of the failure.
        reason: String,
    },
    /// The analysis's computation failed at a point of an orbit (an event that never came, a
    /// flow that left its domain, a tangent frame that overflowed).
    #[error("{analysis} {}", failed_at(.t, .state, .message))]
    Failed {
        /// The analysis or its part, e.g. "noise" or "the 2D slow flow"; under the analysis's
        /// own heading ([`AnalysisError::message_under`]) the analysis is not named again.
        analysis: &'static str,
        /// The time reached.
        t: f64,
        /// The state there (empty when none applies).
        state: Vec<f64>,
        /// What happened and, where known, what to change.
        message: String,
    },
    /// The analysis's own budget (its step or time limit, an option named in the message) ran
    /// out before the integration reached what the analysis integrates for (a settled cycle, a
    /// return to the section). The integrator itself did not fail.
    #[error("{analysis} {}", out_of_budget_at(.t, .state, .message))]
    Budget {
        /// The analysis or its part, e.g. "cycle" or "the return to the section v = 1"; under
        /// the analysis's own heading ([`AnalysisError::message_under`]) the analysis is not
        /// named again.
        analysis: &'static str,
        /// The time reached.
        t: f64,
        /// The state there.
        state: Vec<f64>,
        /// Which limit, its value, and what to raise (the option's field, e.g.
        /// "cycle.max_steps", where the limit is an option).
        message: String,
    },
    /// The caller asked the analysis to stop (its `stop` function returned true) before it
    /// finished.
    #[error("stopped at the caller's request")]
    Stopped,
    /// A result contains a NaN or an infinity; it is not reported.
    #[error("a non-finite number at {path}; refusing to report it")]
    NonFinite {
        /// Path of the first non-finite number, or the section.
        path: String,
    },
}

/// [`AnalysisError::Failed`] after the name of the analysis or its part.
fn failed_at(t: &f64, state: &[f64], message: &str) -> String {
    format!("failed at t = {t:e} (state {state:?}): {message}")
}

/// [`AnalysisError::Budget`] after the name of the analysis or its part.
fn out_of_budget_at(t: &f64, state: &[f64], message: &str) -> String {
    format!("ran out of its budget at t = {t:e} (state {state:?}): {message}")
}

impl AnalysisError {
    /// The message as read under the heading `analysis` (the engine's "cycle: …"): a failure
    /// of `analysis` itself does not name it a second time ("cycle: ran out of its budget at
    /// …", not "cycle: cycle ran out …"); a failure of a part of it still names the part
    /// ("shooting: the return to the section v = 1 ran out …"). Every other message is
    /// [`to_string`](ToString::to_string)'s.
    pub fn message_under(&self, analysis: &str) -> String {
        match self {
            Self::Failed { analysis: a, t, state, message } if *a == analysis => {
                failed_at(t, state, message)
            }
            Self::Budget { analysis: a, t, state, message } if *a == analysis => {
                out_of_budget_at(t, state, message)
            }
            other => other.to_string(),
        }
    }

    /// The state where the failure happened, when known (empty otherwise).
    pub fn state(&self) -> &[f64] {
        match self {
            Self::Solver(e) => &e.state,
            Self::Failed { state, .. } | Self::Budget { state, .. } => state,
            _ => &[],
        }
    }

    /// The message of a failure at a point (an integrator's or the analysis's), to append a
    /// cause to; None for the other variants.
    pub fn message_mut(&mut self) -> Option<&mut String> {
        match self {
            Self::Solver(e) => Some(&mut e.message),
            Self::Failed { message, .. } | Self::Budget { message, .. } => Some(message),
            _ => None,
        }
    }

    /// The variant in one word, or the integrator's error kind for a failed integration
    /// (e.g. "TooMuchWork", "NonFinite"): what the stress grid counts by. An analysis's
    /// [`Budget`](Self::Budget) counts as "TooMuchWork", the integrator's own step budget: the
    /// same cause (steps ran out), whichever limit stopped it.
    pub fn label(&self) -> String {
        match self {
            Self::Solver(e) => format!("{:?}", e.kind),
            Self::InvalidOption(_) => "InvalidOption".into(),
            Self::NotApplicable { .. } => "NotApplicable".into(),
            Self::NoLimitCycle { .. } => "NoLimitCycle".into(),
            Self::NotConverged { .. } => "NotConverged".into(),
            Self::Failed { .. } => "Failed".into(),
            Self::Budget { .. } => "TooMuchWork".into(),
            Self::NonFinite { .. } => "NonFinite".into(),
            Self::Stopped => "Stopped".into(),
        }
    }

    /// An integrator's failure re-dated to `clock`'s global time (the integrator reports its
    /// local time); the analysis's own errors carry the global time already.
    pub fn at_global(self, clock: &Clock<'_>) -> Self {
        match self {
            Self::Solver(e) => Self::Solver(clock.at_global(e)),
            other => other,
        }
    }

    /// A part of a report that cannot be computed here becomes a note (Ok: the note's text):
    /// no limit cycle, not applicable or not converged. Failures stay errors.
    pub fn into_note(self) -> Result<String, AnalysisError> {
        match self {
            Self::NotApplicable { .. } | Self::NoLimitCycle { .. } | Self::NotConverged { .. } => {
                Ok(self.to_string())
            }
            other => Err(other),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn under_its_own_heading_a_failure_names_the_analysis_once() {
        let budget = AnalysisError::Budget {
            analysis: "cycle",
            t: 5.5,
            state: vec![1.0, 2.0, 3.0],
            message:
                "501 CVODE steps without settling on a cycle (cycle.max_steps = 500; raise it)"
                    .into(),
        };
        let alone = budget.to_string();
        assert_eq!(alone, "cycle ran out of its budget at t = 5.5e0 (state [1.0, 2.0, 3.0]): 501 CVODE steps without settling on a cycle (cycle.max_steps = 500; raise it)");
        assert_eq!(budget.message_under("cycle"), alone["cycle ".len()..]);
        assert_eq!(
            budget.message_under("asymptotics"),
            alone,
            "a part of another analysis keeps its name"
        );
        let failed = AnalysisError::Failed {
            analysis: "noise",
            t: 1.0,
            state: vec![],
            message: "no event".into(),
        };
        assert_eq!(failed.to_string(), "noise failed at t = 1e0 (state []): no event");
        assert_eq!(failed.message_under("noise"), "failed at t = 1e0 (state []): no event");
        let part = AnalysisError::Failed {
            analysis: "the 2D slow flow",
            t: 1.0,
            state: vec![],
            message: "left".into(),
        };
        assert_eq!(part.message_under("asymptotics"), part.to_string());
        let refused = AnalysisError::NonFinite { path: "cycle.period".into() };
        assert_eq!(
            refused.message_under("cycle"),
            "a non-finite number at cycle.period; refusing to report it"
        );
        let note = AnalysisError::NoLimitCycle { reason: "none".into() };
        assert_eq!(note.message_under("lyapunov"), "none");
    }
}
