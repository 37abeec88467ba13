//! The γ scan of the asymptotic analysis: the scene's brute-force cycle (same solver, ξ, ε,
//! friction and cycle options) at each γ of the list. Each run starts at the scene's (u, θ)
//! with v on the slow manifold S (when the friction law has such a v): an off-manifold start
//! creates an initial layer of width ~1/γ² that CVODE cannot start through at γ ≳ 1e9
//! (measured: the earthquake scene's start (1, 0.45, 0) fails at t = 0 for γ = 1e9 … 1e12),
//! while the limit cycle does not depend on the start. A failed or non-periodic point is kept
//! as a row with its status and is left out of the fits.

use super::CycleAt;
use crate::analysis::cycle::{CycleStatus, CycleValues, Extremes};
use crate::model::{Drr, DrrParams};
use serde::{Serialize, Serializer};

/// The cycle quantities the asymptotic fits use (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ScanValues {
    /// Period.
    pub period: f64,
    /// t0: upward crossing of v = 1 to the v maximum.
    pub t0: f64,
    /// Slip half-width × γ (null if v never fell below half its maximum).
    pub half_width_times_gamma: Option<f64>,
    /// ln v_max.
    pub ln_v_max: f64,
    /// u and θ at the v maximum and their ranges.
    #[serde(flatten)]
    pub extremes: Extremes,
}

impl ScanValues {
    fn of(c: &CycleValues, gamma: f64) -> Self {
        ScanValues {
            period: c.main.period,
            t0: c.main.t0,
            half_width_times_gamma: c.main.slip_half_width.map(|w| w * gamma),
            ln_v_max: c.main.ln_v_max,
            extremes: c.extremes,
        }
    }
}

/// How a scan point's run ended: serialised as its [`CycleStatus`] ("periodic", "period_n",
/// "fixed_point", "not_converged") or "failed".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScanStatus {
    /// The cycle analysis ran; what the integration settled to.
    Cycle(CycleStatus),
    /// The run failed with a typed error (the row's `error`).
    Failed,
}

impl Serialize for ScanStatus {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            ScanStatus::Cycle(status) => status.serialize(serializer),
            ScanStatus::Failed => serializer.serialize_str("failed"),
        }
    }
}

/// One γ of the scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScanRow {
    /// γ.
    pub gamma: f64,
    /// What the run settled to, or that it failed.
    pub status: ScanStatus,
    /// The typed error of a failed run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// The cycle, when periodic.
    #[serde(flatten)]
    pub values: Option<ScanValues>,
}

/// The start of every scan run: the scene's (u, θ) (from its start `initial` on the model
/// `params`) with v on S if possible, else `initial`.
pub fn start(params: &DrrParams, initial: [f64; 3]) -> [f64; 3] {
    let [u, w, theta] = initial;
    let drr = Drr::new(*params);
    [u, drr.manifold_w(u, theta).unwrap_or(w), theta]
}

/// Runs the cycle (by `cycle_at`) at each γ on the model `params`, from [`start`].
pub fn run(
    params: &DrrParams,
    initial: [f64; 3],
    gammas: &[f64],
    cycle_at: &mut CycleAt<'_>,
) -> Vec<ScanRow> {
    let start = start(params, initial);
    gammas
        .iter()
        .map(|&gamma| {
            let drr = Drr::new(DrrParams { gamma, ..*params });
            match cycle_at(&drr, start) {
                Ok(report) => {
                    let values = report
                        .values
                        .filter(|_| report.status == CycleStatus::Periodic)
                        .map(|c| ScanValues::of(&c, gamma));
                    ScanRow { gamma, status: ScanStatus::Cycle(report.status), error: None, values }
                }
                Err(e) => ScanRow {
                    gamma,
                    status: ScanStatus::Failed,
                    error: Some(e.to_string()),
                    values: None,
                },
            }
        })
        .collect()
}

/// The periodic rows with γ ≥ `min_gamma`, in increasing γ.
pub fn usable(rows: &[ScanRow], min_gamma: f64) -> Vec<(f64, ScanValues)> {
    let mut v: Vec<(f64, ScanValues)> = rows
        .iter()
        .filter(|r| r.gamma >= min_gamma)
        .filter_map(|r| r.values.map(|x| (r.gamma, x)))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scan row's status reads as the cycle's own status, or "failed".
    #[test]
    fn scan_status_serialises_as_the_cycle_status_or_failed() {
        let json = |s: ScanStatus| serde_json::to_string(&s).unwrap();
        for status in [
            CycleStatus::Periodic,
            CycleStatus::PeriodN,
            CycleStatus::FixedPoint,
            CycleStatus::NotConverged,
        ] {
            assert_eq!(json(ScanStatus::Cycle(status)), serde_json::to_string(&status).unwrap());
        }
        assert_eq!(json(ScanStatus::Cycle(CycleStatus::PeriodN)), "\"period_n\"");
        assert_eq!(json(ScanStatus::Failed), "\"failed\"");
    }
}
