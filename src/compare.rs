//! Cross-checking: the same scene through several methods, or a user's trajectory or report
//! against a SUNDIALS (CVODE BDF) reference.
//!
//! User trajectories are CSV with a header `t,u,v,theta` (any order, extra columns ignored,
//! `#` comment lines allowed) or JSON `{"t": [...], "u": [...], "v": [...], "theta": [...]}`;
//! times must increase. A user report is any JSON with a `cycle` object holding the keys of
//! docs/reports.md. See docs/compare.md.

use crate::engine;
use crate::integrate::{SolverError, Task};
use crate::model::drr::{THETA, U, W};
use crate::model::Drr;
use crate::report::Report;
use crate::scene::{Method, Scene, SolverSpec};
use serde::Serialize;

/// Quantities compared between methods or against a user's report (cycle keys).
const QUANTITIES: [&str; 8] = ["period", "t0", "slip_half_width", "ln_v_max", "ln_v_min", "u_at_v_max", "theta_at_v_max", "slip"];

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
    if n % 2 == 1 { x[n / 2] } else { 0.5 * (x[n / 2 - 1] + x[n / 2]) }
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
                let status = r.cycle.as_ref().map_or("no cycle analysis".into(), |c| format!("{:?}", c.status));
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
                let (lo, hi) = present.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
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

/// A user's trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Times (increasing).
    pub t: Vec<f64>,
    /// States (u, v, θ).
    pub y: Vec<[f64; 3]>,
}

/// A user's file: a trajectory or a report.
#[derive(Debug, Clone, PartialEq)]
pub enum UserData {
    /// t, u, v, θ samples.
    Trajectory(Trajectory),
    /// A report-like JSON with a `cycle` object.
    Report(serde_json::Value),
}

/// Reads a user's CSV or JSON file; errors say what is wrong and where.
pub fn read_user_data(text: &str) -> Result<UserData, String> {
    let trimmed = text.trim_start();
    if trimmed.starts_with('{') {
        let json: serde_json::Value = serde_json::from_str(text).map_err(|e| format!("invalid JSON: {e}"))?;
        if json.get("cycle").is_some() {
            return Ok(UserData::Report(json));
        }
        let column = |name: &str| -> Result<Vec<f64>, String> {
            json.get(name)
                .and_then(|c| c.as_array())
                .ok_or_else(|| format!("JSON trajectory: missing array \"{name}\" (need t, u, v, theta)"))?
                .iter()
                .enumerate()
                .map(|(i, x)| x.as_f64().ok_or_else(|| format!("JSON trajectory: {name}[{i}] is not a number")))
                .collect()
        };
        let (t, u, v, theta) = (column("t")?, column("u")?, column("v")?, column("theta")?);
        if [u.len(), v.len(), theta.len()].iter().any(|&n| n != t.len()) {
            return Err("JSON trajectory: t, u, v and theta must have the same length".into());
        }
        let y = (0..t.len()).map(|i| [u[i], v[i], theta[i]]).collect();
        return check(Trajectory { t, y }).map(UserData::Trajectory);
    }
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (_, header) = lines.next().ok_or("empty file")?;
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_lowercase()).collect();
    let index = |name: &str| {
        names.iter().position(|n| n == name).ok_or_else(|| format!("CSV header {header:?} lacks column \"{name}\" (need t,u,v,theta)"))
    };
    let cols = [index("t")?, index("u")?, index("v")?, index("theta")?];
    let mut trajectory = Trajectory { t: Vec::new(), y: Vec::new() };
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let value = |c: usize| -> Result<f64, String> {
            let cell = cells.get(c).ok_or_else(|| format!("line {}: too few columns", n + 1))?;
            cell.trim().parse::<f64>().map_err(|_| format!("line {}: {:?} is not a number", n + 1, cell.trim()))
        };
        trajectory.t.push(value(cols[0])?);
        trajectory.y.push([value(cols[1])?, value(cols[2])?, value(cols[3])?]);
    }
    check(trajectory).map(UserData::Trajectory)
}

fn check(trajectory: Trajectory) -> Result<Trajectory, String> {
    if trajectory.t.len() < 2 {
        return Err("a trajectory needs at least two samples".into());
    }
    if let Some(i) = trajectory.t.windows(2).position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater)) {
        return Err(format!("times must increase: row {} (t = {}) follows t = {}", i + 2, trajectory.t[i + 1], trajectory.t[i]));
    }
    if let Some(i) = trajectory.y.iter().position(|y| !(y.iter().all(|v| v.is_finite()) && y[1] > 0.0)) {
        return Err(format!("row {}: u, v, theta must be finite and v > 0", i + 1));
    }
    Ok(trajectory)
}

/// A user's trajectory against the reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryComparison {
    /// Samples compared.
    pub samples: usize,
    /// Tolerance: on u and θ relative to max(|reference|, 1); on ln v absolute.
    pub tolerance: f64,
    /// Largest deviation per quantity (u, ln v, θ) in the measure above.
    pub max_deviation: [f64; 3],
    /// First sample beyond tolerance: (t, quantity, user's value, reference value); None if
    /// the trajectories agree throughout.
    pub first_divergence: Option<(f64, String, f64, f64)>,
    /// The reference: method and tolerances.
    pub reference: String,
}

/// Integrates the scene's model from the user's first sample with CVODE (rtol 1e-11) and
/// compares every sample. The reference integration is not re-based in time, so at γ ≳ 1e6
/// over long spans it may stop with a typed step-underflow error.
pub fn against_trajectory(scene: &Scene, user: &Trajectory, tolerance: f64) -> Result<TrajectoryComparison, SolverError> {
    let drr = Drr::new(scene.params);
    let spec = SolverSpec { method: Method::CvodeBdf, rtol: 1e-11, atol: [1e-13; 3], table: None, explicit_table: None };
    let t0 = user.t[0];
    let y0 = [user.y[0][0], user.y[0][1].ln(), user.y[0][2]];
    let (mut integ, _) = engine::integrator(drr, &spec, &y0)?;
    let mut max_deviation = [0.0f64; 3];
    let mut first_divergence = None;
    for (t, y) in user.t.iter().zip(&user.y).skip(1) {
        integ.advance(t - t0, Task::Normal)?;
        let r = integ.state();
        let deviation = [
            (y[0] - r[U]).abs() / r[U].abs().max(1.0),
            (y[1].ln() - r[W]).abs(),
            (y[2] - r[THETA]).abs() / r[THETA].abs().max(1.0),
        ];
        for k in 0..3 {
            max_deviation[k] = max_deviation[k].max(deviation[k]);
            if first_divergence.is_none() && deviation[k] > tolerance {
                let (name, ours, theirs) = match k {
                    0 => ("u", y[0], r[U]),
                    1 => ("ln v", y[1].ln(), r[W]),
                    _ => ("theta", y[2], r[THETA]),
                };
                first_divergence = Some((*t, name.to_string(), ours, theirs));
            }
        }
    }
    Ok(TrajectoryComparison {
        samples: user.t.len(),
        tolerance,
        max_deviation,
        first_divergence,
        reference: format!("{} from the first sample, rtol 1e-11, atol 1e-13", integ.name()),
    })
}

/// A user's report against ours (the scene run with CVODE BDF at its own tolerances).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportComparison {
    /// Per quantity: (key, user's value, ours, relative difference, beyond tolerance?).
    pub rows: Vec<(String, f64, f64, f64, bool)>,
    /// Relative tolerance used.
    pub tolerance: f64,
}

/// Compares the `cycle` keys a user's report has with the reference run of the scene.
pub fn against_report(scene: &Scene, user: &serde_json::Value, tolerance: f64) -> Result<ReportComparison, SolverError> {
    let mut s = scene.clone();
    s.solver.method = Method::CvodeBdf;
    s.solver.table = None;
    s.solver.explicit_table = None;
    s.analyses.cycle.get_or_insert_with(Default::default);
    s.analyses.noise = None;
    let ours = engine::run(&s, serde_json::Value::Null)?;
    let rows = QUANTITIES
        .iter()
        .filter_map(|&key| {
            let theirs = user["cycle"][key].as_f64()?;
            let mine = quantity(&ours, key)?;
            let rel = (theirs - mine).abs() / scale(key, mine);
            Some((key.to_string(), theirs, mine, rel, rel > tolerance))
        })
        .collect();
    Ok(ReportComparison { rows, tolerance })
}
