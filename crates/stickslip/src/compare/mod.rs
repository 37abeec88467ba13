//! Cross-checking: the same scene through several methods, or a user's trajectory or report
//! against a reference, with a verdict.
//!
//! User trajectories are CSV with a header `t,u,v,theta` (any order, extra columns ignored,
//! `#` comment lines allowed) or JSON `{"t": [...], "u": [...], "v": [...], "theta": [...]}`;
//! times must increase ([`input`]; QDYN's files: [`qdyn`]; which is which: [`user_data`]);
//! they are compared event by event, then between events in phase ([`trajectory`], events on
//! samples: [`sampled`], the reference runs: [`reference`](mod@reference)). A user report is
//! JSON with a `cycle` object holding keys of docs/reports.md ([`Quantity`]). See
//! docs/compare.md.
//!
//! The files import one way, each only from files listed before it (no circle; tests/compare.rs
//! checks it): quantity, sampled; input; scale; qdyn, error; user_data, reference; trajectory;
//! this module.

pub mod error;
pub mod input;
pub mod qdyn;
pub mod quantity;
pub mod reference;
pub mod sampled;
pub mod scale;
pub mod trajectory;
pub mod user_data;

pub use error::CompareError;
pub use input::{InputError, Trajectory, UserCycle};
pub use quantity::Quantity;
pub use sampled::SamplingError;
pub use scale::SceneMismatch;
pub use trajectory::{against_trajectory, TrajectoryComparison, Verdict};
pub use user_data::{read_user_data, UserData};

use crate::engine;
use crate::report::Report;
use crate::scene::{Method, Scene, SolverSpec};
use quantity::within;
use serde::Serialize;

/// One quantity across methods.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantityRow {
    /// The report key.
    pub quantity: Quantity,
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
        match engine::run(&s, engine::RunOptions::default()) {
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
    let rows = Quantity::ALL
        .into_iter()
        .map(|key| {
            let values: Vec<(String, Option<f64>)> = methods
                .iter()
                .zip(&reports)
                .map(|(m, r)| (m.name().to_string(), r.as_ref().and_then(|r| key.of_report(r))))
                .collect();
            let present: Vec<f64> = values.iter().filter_map(|(_, v)| *v).collect();
            let (spread, outliers) = if present.len() >= 2 {
                let mid = median(present.clone());
                let scale = key.scale(mid);
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
            QuantityRow { quantity: key, values, spread, allowed, outliers }
        })
        .collect();
    MethodComparison { runs, rows, wall_time_s: times }
}

/// One key of a user's report against ours.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportRow {
    /// The report key.
    pub quantity: Quantity,
    /// The user's value.
    pub user: f64,
    /// Ours.
    pub reference: f64,
    /// |user − ours| relative to the value (durations, slip) or to max(|value|, 1) (ln v, u, θ).
    pub deviation: f64,
    /// The reference's own accuracy in the same measure: its difference from the check run.
    pub reference_accuracy: f64,
    /// Whether the deviation exceeds the tolerance.
    pub beyond_tolerance: bool,
}

/// The reference run of a report comparison and its check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportReference {
    /// The reference's method: the scene's, or the one named (`--reference-method`).
    pub method: String,
    /// Its relative tolerance: min(the scene's rtol, tolerance/100), divided by 100 while
    /// the check finds it too inaccurate, at least 1e-13.
    pub rtol: f64,
    /// The check run's method: rodas5p, or radau5 when the reference is rodas5p.
    pub check_method: String,
    /// The check run's relative tolerance: the reference's / 10, at least 1e-13.
    pub check_rtol: f64,
}

/// A user's report against ours (the scene's cycle analysis run tightly enough for the
/// tolerance, its accuracy checked by an independent method).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportComparison {
    /// "agrees" or "disagrees".
    pub verdict: Verdict,
    /// Relative tolerance used.
    pub tolerance: f64,
    /// The reference and its check.
    pub reference: ReportReference,
    /// Per key the user gave.
    pub rows: Vec<ReportRow>,
}

/// The tightest relative tolerance a reference run is asked for.
pub const TIGHTEST_RTOL: f64 = 1e-13;

/// The scene's cycle analysis alone, by `method` at `rtol` (absolute tolerances no looser).
fn cycle_run(scene: &Scene, method: Method, rtol: f64) -> Result<Report, engine::RunError> {
    let mut s = scene.clone();
    s.solver = SolverSpec {
        method,
        rtol,
        atol: scene.solver.atol.map(|a| a.min(rtol)),
        table: None,
        explicit_table: None,
    };
    let cycle = s.analyses.cycle.take().unwrap_or_default();
    s.analyses = crate::scene::Analyses { cycle: Some(cycle), ..Default::default() };
    engine::run(&s, engine::RunOptions::default())
}

/// Compares the `cycle` keys a user's report has with the scene's cycle analysis run by
/// `method` (None: the scene's) at rtol = min(scene's rtol, tolerance/100) (at least
/// [`TIGHTEST_RTOL`]). Its accuracy per key is its difference from an independent method
/// (rodas5p, or radau5 for rodas5p) at a 10 times tighter rtol; while that is not below
/// tolerance/10 the rtol is divided by 100; where it is still not below at
/// [`TIGHTEST_RTOL`] there is no verdict ([`CompareError::InaccurateReference`]).
pub fn against_report(
    scene: &Scene,
    user: &UserCycle,
    tolerance: f64,
    method: Option<Method>,
) -> Result<ReportComparison, CompareError> {
    let method = method.unwrap_or(scene.solver.method);
    let check_method = if method == Method::Rodas5p { Method::Radau5 } else { Method::Rodas5p };
    let mut rtol = scene.solver.rtol.min(tolerance / 100.0).max(TIGHTEST_RTOL);
    // Tightened by 100 while the check finds the reference too inaccurate for the tolerance.
    let (rows, check_rtol) = loop {
        let check_rtol = (rtol / 10.0).max(TIGHTEST_RTOL);
        let ours = cycle_run(scene, method, rtol).map_err(CompareError::ReferenceRun)?;
        let check =
            cycle_run(scene, check_method, check_rtol).map_err(CompareError::ReferenceRun)?;
        let mut rows = Vec::new();
        let mut inaccurate = Vec::new();
        for key in Quantity::ALL {
            let Some(theirs) = user.get(key) else { continue };
            let (Some(mine), Some(checked)) = (key.of_report(&ours), key.of_report(&check)) else {
                inaccurate.push((format!("{key} (not computed by the reference)"), f64::NAN));
                continue;
            };
            let deviation = (theirs - mine).abs() / key.scale(mine);
            let reference_accuracy = (checked - mine).abs() / key.scale(mine);
            if !within(reference_accuracy, tolerance / 10.0) {
                inaccurate.push((key.name().to_string(), reference_accuracy));
            }
            rows.push(ReportRow {
                quantity: key,
                user: theirs,
                reference: mine,
                deviation,
                reference_accuracy,
                beyond_tolerance: !within(deviation, tolerance),
            });
        }
        if inaccurate.is_empty() {
            break (rows, check_rtol);
        }
        if rtol <= TIGHTEST_RTOL {
            return Err(CompareError::InaccurateReference { quantities: inaccurate, tolerance });
        }
        rtol = (rtol / 100.0).max(TIGHTEST_RTOL);
    };
    Ok(ReportComparison {
        verdict: if rows.iter().any(|r| r.beyond_tolerance) {
            Verdict::Disagrees
        } else {
            Verdict::Agrees
        },
        tolerance,
        reference: ReportReference {
            method: method.name().into(),
            rtol,
            check_method: check_method.name().into(),
            check_rtol,
        },
        rows,
    })
}
