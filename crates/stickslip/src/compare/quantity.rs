//! The cycle quantities compared between methods or against a user's report (the keys of
//! docs/reports.md's cycle section), one definition with its name, and how a difference in
//! each is measured.

use crate::report::Report;
use serde::Serialize;
use std::fmt;

/// A cycle quantity of a report, compared between methods or against a user's report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Time between upward crossings of v = 1.
    Period,
    /// From the upward crossing of v = 1 to the v maximum.
    T0,
    /// Full width of v(t) at half its maximum.
    SlipHalfWidth,
    /// ln v_max.
    LnVMax,
    /// ln v_min.
    LnVMin,
    /// u at the v maximum.
    UAtVMax,
    /// θ at the v maximum.
    ThetaAtVMax,
    /// Slip per event.
    Slip,
}

impl Quantity {
    /// Every compared quantity, in the order they are listed.
    pub const ALL: [Quantity; 8] = [
        Quantity::Period,
        Quantity::T0,
        Quantity::SlipHalfWidth,
        Quantity::LnVMax,
        Quantity::LnVMin,
        Quantity::UAtVMax,
        Quantity::ThetaAtVMax,
        Quantity::Slip,
    ];

    /// Its report key (docs/reports.md).
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Period => "period",
            Quantity::T0 => "t0",
            Quantity::SlipHalfWidth => "slip_half_width",
            Quantity::LnVMax => "ln_v_max",
            Quantity::LnVMin => "ln_v_min",
            Quantity::UAtVMax => "u_at_v_max",
            Quantity::ThetaAtVMax => "theta_at_v_max",
            Quantity::Slip => "slip",
        }
    }

    /// The scale a difference is measured against: the value itself for durations and the
    /// slip (positive, with their own units), max(|value|, 1) for ln v, u and θ (offsets).
    pub fn scale(self, value: f64) -> f64 {
        match self {
            Quantity::Period | Quantity::T0 | Quantity::SlipHalfWidth | Quantity::Slip => {
                value.abs().max(f64::MIN_POSITIVE)
            }
            Quantity::LnVMax | Quantity::LnVMin | Quantity::UAtVMax | Quantity::ThetaAtVMax => {
                value.abs().max(1.0)
            }
        }
    }

    /// Its value in a stickslip report (None without a converged cycle, or where the cycle
    /// analysis does not compute it).
    pub fn of_report(self, report: &Report) -> Option<f64> {
        let v = report.cycle.as_ref()?.values?;
        match self {
            Quantity::Period => Some(v.main.period),
            Quantity::T0 => Some(v.main.t0),
            Quantity::SlipHalfWidth => v.main.slip_half_width,
            Quantity::LnVMax => Some(v.main.ln_v_max),
            Quantity::LnVMin => Some(v.main.ln_v_min),
            Quantity::UAtVMax => Some(v.extremes.u_at_v_max),
            Quantity::ThetaAtVMax => Some(v.extremes.theta_at_v_max),
            Quantity::Slip => Some(v.main.slip),
        }
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// Whether `x` ≤ `limit`; false for NaN, which is never within a limit.
pub(crate) fn within(x: f64, limit: f64) -> bool {
    x <= limit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_report_keys_and_serialize_as_such() {
        for q in Quantity::ALL {
            assert_eq!(serde_json::to_value(q).unwrap(), q.name());
            assert_eq!(format!("{q:<16}").trim_end(), q.name());
        }
        assert!(!within(f64::NAN, 1.0) && within(1.0, 1.0));
    }
}
