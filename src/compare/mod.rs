//! Cross-checking: the same scene through several methods, or a user's trajectory or report
//! against a reference, with a verdict.
//!
//! User trajectories are CSV with a header `t,u,v,theta` (any order, extra columns ignored,
//! `#` comment lines allowed) or JSON `{"t": [...], "u": [...], "v": [...], "theta": [...]}`;
//! times must increase ([`input`]); they are compared cycle by cycle ([`trajectory`]). A user
//! report is JSON with a `cycle` object holding keys of docs/reports.md. See docs/compare.md.

pub mod input;
pub mod trajectory;

pub use input::{read_user_data, InputError, Trajectory, UserCycle, UserData};
pub use trajectory::{
    against_trajectory, CompareError, SamplingError, TrajectoryComparison, Verdict,
};

use crate::engine::{self, EngineError};
use crate::report::Report;
use crate::scene::{Method, Scene, SolverSpec};
use serde::Serialize;

/// Quantities compared between methods or against a user's report (cycle keys).
const QUANTITIES: [&str; 8] = [
    "period",
    "t0",
    "slip_half_width",
    "ln_v_max",
    "ln_v_min",
    "u_at_v_max",
    "theta_at_v_max",
    "slip",
];

/// The scale a difference in `key` is measured against: the value itself for durations and
/// the slip (positive, with their own units), max(|value|, 1) for ln v, u and θ (offsets).
fn scale(key: &str, value: f64) -> f64 {
    match key {
        "period" | "t0" | "slip_half_width" | "slip" => value.abs().max(f64::MIN_POSITIVE),
        _ => value.abs().max(1.0),
    }
}

fn quantity(report: &Report, key: &str) -> Option<f64> {
    let v = report.cycle.as_ref()?.values?;
    match key {
        "period" => Some(v.period),
        "t0" => Some(v.t0),
        "slip_half_width" => v.slip_half_width,
        "ln_v_max" => Some(v.ln_v_max),
        "ln_v_min" => Some(v.ln_v_min),
        "u_at_v_max" => Some(v.u_at_v_max),
        "theta_at_v_max" => Some(v.theta_at_v_max),
        "slip" => Some(v.slip),
        _ => None,
    }
}

/// One quantity across methods.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantityRow {
    /// The report key.
    pub quantity: String,
    /// Value per method (null where the method found no periodic cycle).
    pub values: Vec<(String, Option<f64>)>,
    /// (max − min) over the methods that have a value, relative to the median (durations,
    /// slip) or to max(|median|, 1) (ln v, u, θ).
    pub spread: Option<f64>,
    /// The spread allowed: max(1e3 · rtol, 1e-9).
    pub allowed: f64,
    /// Methods farther than `allowed` from the median.
    pub outliers: Vec<String>,
}

/// A scene run through several methods.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MethodComparison {
    /// Per method: its cycle status, or its error.
    pub runs: Vec<(String, String)>,
    /// Per quantity: values, spread and outliers.
    pub rows: Vec<QuantityRow>,
    /// Wall time per method (seconds; null on failure).
    pub wall_time_s: Vec<(String, Option<f64>)>,
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

/// Runs `scene` once per method (same tolerances, default tables) and compares the cycle.
pub fn methods(scene: &Scene, methods: &[Method]) -> MethodComparison {
    let mut runs = Vec::new();
    let mut reports = Vec::new();
    let mut times = Vec::new();
    for &method in methods {
        let mut s = scene.clone();
        s.solver = SolverSpec { method, table: None, explicit_table: None, ..scene.solver.clone() };
        // The noise analysis does not depend on the method (its realisations use Rodas5P).
        s.analyses.noise = None;
        match engine::run(&s, serde_json::Value::Null) {
            Ok(r) => {
                let status = r
                    .cycle
                    .as_ref()
                    .map_or("no cycle analysis".into(), |c| format!("{:?}", c.status));
                runs.push((method.name().to_string(), status));
                times.push((method.name().to_string(), Some(r.wall_time_s)));
                reports.push(Some(r));
            }
            Err(e) => {
                runs.push((method.name().to_string(), format!("error: {e}")));
                times.push((method.name().to_string(), None));
                reports.push(None);
            }
        }
    }
    let allowed = (1e3 * scene.solver.rtol).max(1e-9);
    let rows = QUANTITIES
        .iter()
        .map(|&key| {
            let values: Vec<(String, Option<f64>)> = methods
                .iter()
                .zip(&reports)
                .map(|(m, r)| (m.name().to_string(), r.as_ref().and_then(|r| quantity(r, key))))
                .collect();
            let present: Vec<f64> = values.iter().filter_map(|(_, v)| *v).collect();
            let (spread, outliers) = if present.len() >= 2 {
                let mid = median(present.clone());
                let scale = scale(key, mid);
                let (lo, hi) = present
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
                let outliers = values
                    .iter()
                    .filter(|(_, v)| v.is_some_and(|v| (v - mid).abs() > allowed * scale))
                    .map(|(m, _)| m.clone())
                    .collect();
                (Some((hi - lo) / scale), outliers)
            } else {
                (None, Vec::new())
            };
            QuantityRow { quantity: key.into(), values, spread, allowed, outliers }
        })
        .collect();
    MethodComparison { runs, rows, wall_time_s: times }
}

/// One key of a user's report against ours.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportRow {
    /// The report key.
    pub quantity: String,
    /// The user's value.
    pub user: f64,
    /// Ours.
    pub reference: f64,
    /// |user − ours| relative to the value (durations, slip) or to max(|value|, 1) (ln v, u, θ).
    pub deviation: f64,
    /// Whether the deviation exceeds the tolerance.
    pub beyond_tolerance: bool,
}

/// A user's report against ours (the scene run with CVODE BDF at its own tolerances).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportComparison {
    /// "agrees" or "disagrees".
    pub verdict: Verdict,
    /// Relative tolerance used.
    pub tolerance: f64,
    /// The reference: method and tolerances.
    pub reference: String,
    /// Per key the user gave.
    pub rows: Vec<ReportRow>,
}

/// Compares the `cycle` keys a user's report has with the reference run of the scene.
pub fn against_report(
    scene: &Scene,
    user: &UserCycle,
    tolerance: f64,
) -> Result<ReportComparison, EngineError> {
    let mut s = scene.clone();
    s.solver.method = Method::CvodeBdf;
    s.solver.table = None;
    s.solver.explicit_table = None;
    s.analyses.cycle.get_or_insert_with(Default::default);
    s.analyses.noise = None;
    let ours = engine::run(&s, serde_json::Value::Null)?;
    let rows: Vec<ReportRow> = QUANTITIES
        .iter()
        .filter_map(|&key| {
            let theirs = user.get(key)?;
            let mine = quantity(&ours, key)?;
            let deviation = (theirs - mine).abs() / scale(key, mine);
            Some(ReportRow {
                quantity: key.into(),
                user: theirs,
                reference: mine,
                deviation,
                beyond_tolerance: deviation.is_nan() || deviation > tolerance,
            })
        })
        .collect();
    Ok(ReportComparison {
        verdict: if rows.iter().any(|r| r.beyond_tolerance) {
            Verdict::Disagrees
        } else {
            Verdict::Agrees
        },
        tolerance,
        reference: format!("the scene's cycle analysis with cvode-bdf at rtol {:e}", s.solver.rtol),
        rows,
    })
}
