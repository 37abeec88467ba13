//! The "cycle" analysis's options (scene: `"cycle"` or `{"cycle": {...}}`): parsed and
//! validated here, where they are used; the scene only dispatches by name.

use super::CycleSettings;
use crate::analysis::InvalidOption;
use serde::{Deserialize, Serialize};

/// Options of the "cycle" analysis (None: the default of [`CycleSettings::defaults`]).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CycleOptions {
    /// Relative tolerance of the convergence rule.
    pub tolerance: Option<f64>,
    /// Consecutive agreeing cycle pairs that make a period-n orbit (n > 1); 2·settle cycles at
    /// most are averaged (see [`CycleSettings::settle`]).
    pub settle: Option<usize>,
    /// Maximum number of cycles.
    pub max_cycles: Option<usize>,
    /// Maximum dimensionless time.
    pub max_time: Option<f64>,
    /// Maximum total integrator steps.
    pub max_steps: Option<u64>,
}

impl CycleOptions {
    /// Parses and validates the options object; the error names the field (empty: the
    /// object).
    pub fn from_json(value: serde_json::Value) -> Result<Self, InvalidOption> {
        let o: Self = InvalidOption::parse(value)?;
        InvalidOption::check_tolerance(o.tolerance, "1e-7")?;
        if let Some(t) = o.max_time {
            if !(t.is_finite() && t >= 1.0) {
                return Err(InvalidOption::new(
                    "max_time",
                    format!("{t} must be a finite time ≥ 1, e.g. 1e5"),
                ));
            }
        }
        let bounds = [
            ("settle", o.settle.map(|v| v as u64), 1000),
            ("max_cycles", o.max_cycles.map(|v| v as u64), 10_000_000),
            ("max_steps", o.max_steps, u64::MAX),
        ];
        for (name, value, max) in bounds {
            if let Some(v) = value {
                if v == 0 || v > max {
                    return Err(InvalidOption::new(
                        name,
                        format!("{v} must be between 1 and {max}"),
                    ));
                }
            }
        }
        Ok(o)
    }

    /// The settings for an integration at `rtol` with absolute tolerance `atol_w` on w: the
    /// defaults, overridden by the options given.
    pub fn settings(&self, rtol: f64, atol_w: f64) -> CycleSettings {
        let d = CycleSettings::defaults(rtol, atol_w);
        CycleSettings {
            tolerance: self.tolerance.unwrap_or(d.tolerance),
            settle: self.settle.unwrap_or(d.settle),
            max_cycles: self.max_cycles.unwrap_or(d.max_cycles),
            max_time: self.max_time.unwrap_or(d.max_time),
            max_steps: self.max_steps.unwrap_or(d.max_steps),
            ..d
        }
    }
}
