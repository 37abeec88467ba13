//! The "time_series" analysis's options (scene: `{"time_series": {"t_max": T, ...}}`): parsed
//! and validated here, where they are used; the scene only dispatches by name and converts
//! `t_max` from the input's time unit.

use crate::analysis::InvalidOption;
use serde::{Deserialize, Serialize};

/// Options of the "time_series" analysis as the scene gives them.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSeriesOptions {
    /// End of the run, in the scene's time unit: D_c/v0 for a dimensionless model, the
    /// input's time unit (e.g. s) with `model.dimensional`. The run starts at t = 0.
    pub t_max: f64,
    /// Write every N-th integrator step (default: every step).
    #[serde(default)]
    pub every: Option<u64>,
    /// Write N rows uniform in time from 0 to t_max (dense output) instead of the steps.
    #[serde(default)]
    pub points: Option<u64>,
    /// The peak slip rate v (dimensionless, units of v0) an episode of v above 1 (faster
    /// than the loading) must exceed to be an event (default [`DEFAULT_EVENT_THRESHOLD`]).
    #[serde(default)]
    pub event_threshold: Option<f64>,
    /// Fail after this many integrator steps (default 1e9).
    #[serde(default)]
    pub max_steps: Option<u64>,
    /// Stop where the slip rate rises to this value, in the scene's velocity unit (units of
    /// v0 for a dimensionless model, the input's, e.g. m/s, with `model.dimensional`): the
    /// run ends there and the report's `runaway` section gives the time it was reached
    /// (located on ln v by root finding). Required under the no-healing law, whose slip rate
    /// runs away.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runaway_velocity: Option<f64>,
}

/// Which rows a run writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Every integrator step (the start and t_max included).
    Steps,
    /// Every N-th integrator step (the start and t_max included).
    Every(u64),
    /// N rows uniform in time from 0 to t_max, from the integrator's dense output.
    Points(u64),
}

/// The default step budget: 1e9 steps (a γ = 1e8 cycle takes ~1e4).
pub const DEFAULT_MAX_STEPS: u64 = 1_000_000_000;

/// The default event threshold: an episode of v above 1 is an event when its peak exceeds
/// 100 v0 (100·V_pl), the rule QDYN's users compare peaks by (data/qdyn/periodic_reference.py):
/// far above the creep transients of a few V_pl and far below a slip event's peak (1.4e8 V_pl
/// on the field scene of docs/from-qdyn.md).
pub const DEFAULT_EVENT_THRESHOLD: f64 = 100.0;

/// The largest `points`: 1e9 rows (~90 GB of binary output).
pub const MAX_POINTS: u64 = 1_000_000_000;

impl TimeSeriesOptions {
    /// Parses and validates the options object; the error names the field (empty: the
    /// object).
    pub fn from_json(value: serde_json::Value) -> Result<Self, InvalidOption> {
        let o: Self = serde_json::from_value(value).map_err(|e| {
            InvalidOption::new(
                "",
                format!(
                    "{e} (fields: t_max, every, points, event_threshold, max_steps, \
                     runaway_velocity)"
                ),
            )
        })?;
        if !(o.t_max.is_finite() && o.t_max > 0.0) {
            return Err(InvalidOption::new(
                "t_max",
                format!(
                    "{} must be a finite time > 0 in the scene's time unit (D_c/v0, or the \
                     dimensional input's unit), e.g. 1000",
                    o.t_max
                ),
            ));
        }
        if o.every.is_some() && o.points.is_some() {
            return Err(InvalidOption::new(
                "points",
                "give either \"every\" (every N-th step) or \"points\" (N rows uniform in time), not both",
            ));
        }
        if o.every == Some(0) {
            return Err(InvalidOption::new("every", "0 must be ≥ 1 (1 writes every step)"));
        }
        if let Some(n) = o.points {
            if !(2..=MAX_POINTS).contains(&n) {
                return Err(InvalidOption::new(
                    "points",
                    format!("{n} must be between 2 and {MAX_POINTS} (rows from t = 0 to t_max)"),
                ));
            }
        }
        if let Some(v) = o.event_threshold {
            if !(v.is_finite() && v > 1.0) {
                return Err(InvalidOption::new(
                    "event_threshold",
                    format!(
                        "{v} must be a peak slip rate v above 1 (dimensionless, in units of v0, \
                         the loading velocity: every excursion above v = 1 whose peak exceeds it \
                         is an event), e.g. 100 (the default) or 1e4"
                    ),
                ));
            }
        }
        if let Some(v) = o.runaway_velocity {
            if !(v.is_finite() && v > 0.0) {
                return Err(InvalidOption::new(
                    "runaway_velocity",
                    format!(
                        "{v} must be a slip rate > 0 in the scene's velocity unit (v0 for a \
                         dimensionless model, e.g. 1e9; the input's with model.dimensional, \
                         e.g. 1 m/s)"
                    ),
                ));
            }
        }
        if o.max_steps == Some(0) {
            return Err(InvalidOption::new("max_steps", "0 must be ≥ 1, e.g. 1e8"));
        }
        Ok(o)
    }

    /// The event threshold asked for, or [`DEFAULT_EVENT_THRESHOLD`].
    pub fn event_threshold(&self) -> f64 {
        self.event_threshold.unwrap_or(DEFAULT_EVENT_THRESHOLD)
    }

    /// The rows asked for.
    pub fn sampling(&self) -> Sampling {
        match (self.every, self.points) {
            (_, Some(n)) => Sampling::Points(n),
            (Some(n), None) if n > 1 => Sampling::Every(n),
            _ => Sampling::Steps,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn field_of(v: serde_json::Value) -> String {
        TimeSeriesOptions::from_json(v).unwrap_err().field
    }

    #[test]
    fn each_bad_option_names_its_field() {
        assert_eq!(field_of(json!({"t_max": -1.0})), "t_max");
        assert_eq!(field_of(json!({"t_max": 0.0})), "t_max");
        assert_eq!(field_of(json!({"t_max": 10.0, "every": 0})), "every");
        assert_eq!(field_of(json!({"t_max": 10.0, "points": 1})), "points");
        assert_eq!(field_of(json!({"t_max": 10.0, "points": 10, "every": 2})), "points");
        assert_eq!(field_of(json!({"t_max": 10.0, "event_threshold": 0.0})), "event_threshold");
        assert_eq!(field_of(json!({"t_max": 10.0, "event_threshold": 1.0})), "event_threshold");
        assert_eq!(field_of(json!({"t_max": 10.0, "max_steps": 0})), "max_steps");
        assert_eq!(field_of(json!({"t_max": 10.0, "runaway_velocity": 0.0})), "runaway_velocity");
        let unknown = TimeSeriesOptions::from_json(json!({"t_max": 1.0, "tmax": 2})).unwrap_err();
        assert!(unknown.message.contains("tmax"), "{unknown}");
        let missing = TimeSeriesOptions::from_json(json!({})).unwrap_err();
        assert!(missing.message.contains("t_max"), "{missing}");
    }

    #[test]
    fn sampling_follows_the_options() {
        let o = |v| TimeSeriesOptions::from_json(v).unwrap().sampling();
        assert_eq!(o(json!({"t_max": 1.0})), Sampling::Steps);
        assert_eq!(o(json!({"t_max": 1.0, "every": 1})), Sampling::Steps);
        assert_eq!(o(json!({"t_max": 1.0, "every": 3})), Sampling::Every(3));
        assert_eq!(o(json!({"t_max": 1.0, "points": 5})), Sampling::Points(5));
    }
}
