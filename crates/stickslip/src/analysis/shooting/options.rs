//! The "shooting" analysis's options (scene: `"shooting"` or `{"shooting": {...}}`): parsed
//! and validated here, where they are used; the scene only dispatches by name.

use super::ShootingSettings;
use crate::analysis::InvalidOption;
use serde::{Deserialize, Serialize};

/// Options of the "shooting" analysis (None: the default of [`ShootingSettings::defaults`]).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ShootingOptions {
    /// Newton convergence tolerance (relative residual).
    pub tolerance: Option<f64>,
    /// Newton iterations at most.
    pub max_iterations: Option<usize>,
}

impl ShootingOptions {
    /// Parses and validates the options object; the error names the field (empty: the
    /// object).
    pub fn from_json(value: serde_json::Value) -> Result<Self, InvalidOption> {
        let o: Self = InvalidOption::parse(value)?;
        InvalidOption::check_tolerance(o.tolerance, "1e-8")?;
        if let Some(n) = o.max_iterations {
            if n == 0 || n > 1000 {
                return Err(InvalidOption::new(
                    "max_iterations",
                    format!("{n} must be between 1 and 1000"),
                ));
            }
        }
        Ok(o)
    }

    /// The settings for an integration at `rtol` with absolute tolerance `atol_w` on w: the
    /// defaults, overridden by the options given.
    pub fn settings(&self, rtol: f64, atol_w: f64) -> ShootingSettings {
        let d = ShootingSettings::defaults(rtol, atol_w);
        ShootingSettings {
            tolerance: self.tolerance.unwrap_or(d.tolerance),
            max_iterations: self.max_iterations.unwrap_or(d.max_iterations),
            ..d
        }
    }
}
