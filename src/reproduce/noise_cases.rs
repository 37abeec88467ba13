//! The noise scenes behind Figs. 6, 7 and 9 (data/scenes/noise-*.json, docs/noise.md): run as
//! `stickslip run` would, with fewer realisations in the reduced (test) version.

use super::{Context, ReproduceError, Row};
use serde_json::Value;
use std::sync::{Arc, Mutex};
use stickslip::analysis::noise::{CorrelationPoint, NoiseReport};
use stickslip::engine::RunOptions;
use stickslip::report::AnyReport;
use stickslip::scene;

/// Runs already made in this process, by scene (Figs. 6 and 7 both need the DRR scene; its
/// results do not depend on the thread count, so a second run would give the same numbers).
static DONE: Mutex<Vec<(String, Arc<NoiseRun>)>> = Mutex::new(Vec::new());

/// data/scenes/noise-drr.json: γ = 1e3, ξ = 0.7, ε = 0.72.
pub const DRR: &str = include_str!("../../data/scenes/noise-drr.json");
/// data/scenes/noise-power-law.json: α = 0.15, γ = 1e3, ξ = 0.7, ε = 0.78.
pub const POWER_LAW: &str = include_str!("../../data/scenes/noise-power-law.json");
/// data/scenes/noise-saddle-node.json: μ0 = 1, r = 0.01.
pub const SADDLE_NODE: &str = include_str!("../../data/scenes/noise-saddle-node.json");
/// data/scenes/noise-van-der-pol.json: β = 30, a = 0.
pub const VAN_DER_POL: &str = include_str!("../../data/scenes/noise-van-der-pol.json");

/// A noise scene's full report (as JSON) and its noise section.
#[derive(Debug)]
pub struct NoiseRun {
    /// The scene's name.
    pub name: String,
    /// The whole report.
    pub report: Value,
    /// Its noise section.
    pub noise: NoiseReport,
}

/// Runs a shipped noise scene on the context's threads (reduced: 24 realisations, a coarser
/// grid, the saddle-node from 40 before its escape), or returns the same scene's earlier run.
pub fn run(ctx: &Context, text: &str) -> Result<Arc<NoiseRun>, ReproduceError> {
    let mut json: Value = serde_json::from_str(text).expect("the shipped scenes are valid JSON");
    if ctx.reduced {
        let n = &mut json["analyses"][0]["noise"];
        n["realisations"] = 24.into();
        n["grid_points"] = 300.into();
        n["report_points"] = 20.into();
        if json["model"]["kind"] == "saddle_node" {
            json["analyses"][0]["noise"]["start_before_event"] = 40.into();
        }
    }
    let key = json.to_string();
    if let Some((_, done)) =
        DONE.lock().unwrap_or_else(|e| e.into_inner()).iter().find(|(k, _)| *k == key)
    {
        return Ok(done.clone());
    }
    let name = json["name"].as_str().unwrap_or("?").to_string();
    let failed = |source| ReproduceError::Run { case: name.clone(), source };
    let progress = |done, total| ctx.progress.points(done, total);
    let scene = scene::parse_any(&json.to_string(), &name)
        .map_err(|e| ReproduceError::Scene(e.to_string()))?;
    let options = RunOptions::echoing(json.clone()).threads(ctx.threads).progress(&progress);
    let report = stickslip::engine::run(&scene, options).map_err(failed)?;
    let noise = match &report {
        AnyReport::Drr(r) => r.noise.clone(),
        AnyReport::Other(r) => Some(r.noise.clone()),
        AnyReport::Lab(_) => None,
    };
    let noise =
        noise.ok_or_else(|| ReproduceError::Missing(format!("{name}: no noise section")))?;
    let report = serde_json::to_value(&report).expect("a report serialises");
    let run = Arc::new(NoiseRun { name, report, noise });
    DONE.lock().unwrap_or_else(|e| e.into_inner()).push((key, run.clone()));
    Ok(run)
}

/// (t_c − t, τ) of the defined points of a correlation-time curve, ensemble or linear response.
pub fn curve(points: &[CorrelationPoint], linear: bool) -> (Vec<f64>, Vec<f64>) {
    points
        .iter()
        .filter_map(|p| {
            if linear { p.tau_linear_response } else { p.tau }.map(|tau| (p.t_before_event, tau))
        })
        .unzip()
}

/// "0.123 at t_c − 4.5" for the largest τ of a curve, with the curve's ends.
pub fn describe(x: &[f64], y: &[f64]) -> String {
    match (x.first(), x.last(), y.iter().cloned().enumerate().max_by(|a, b| a.1.total_cmp(&b.1))) {
        (Some(&x0), Some(&x1), Some((i, ymax))) => format!(
            "τ = {:.3} at t_c − {:.3} … largest {:.3} at t_c − {:.3} … {:.3} at t_c − {:.3}",
            y[0],
            x0,
            ymax,
            x[i],
            y[y.len() - 1],
            x1
        ),
        _ => "no correlation time defined in the window".into(),
    }
}

/// A qualitative claim on the linear response's correlation time `points`: `holds` judges the
/// curve (ordered from the window's start towards the event), which the row describes.
pub fn tau_claim(
    figure: &str,
    claim: &str,
    paper: &str,
    points: &[CorrelationPoint],
    holds: fn(&[f64]) -> bool,
    note: String,
) -> Row {
    let (x, y) = curve(points, true);
    Row::qualitative(figure, claim, paper, describe(&x, &y), holds(&y), note)
}

/// Whether a curve (ordered from the window's start towards the event) has its largest value
/// strictly inside and at least 1.5 times each end.
pub fn peaks_inside(y: &[f64]) -> bool {
    let Some((i, ymax)) = y.iter().cloned().enumerate().max_by(|a, b| a.1.total_cmp(&b.1)) else {
        return false;
    };
    i > 0 && i + 1 < y.len() && ymax >= 1.5 * y[0] && ymax >= 1.5 * y[y.len() - 1]
}

/// Whether a curve ends (next to the event) below half its largest value.
pub fn falls_towards_the_event(y: &[f64]) -> bool {
    let ymax = y.iter().cloned().fold(0.0, f64::max);
    y.last().is_some_and(|&last| last < 0.5 * ymax)
}

/// The half-height width of a correlation curve Γ(t') (lags ascending from 0): the first lag
/// where Γ falls to Γ(0)/2, interpolated linearly; None if it never does.
pub fn half_width(lag: &[f64], gamma: &[f64]) -> Option<f64> {
    let half = 0.5 * gamma.first()?;
    let k = gamma.iter().position(|&g| g <= half)?;
    if k == 0 {
        return Some(0.0);
    }
    let (g0, g1) = (gamma[k - 1], gamma[k]);
    Some(lag[k - 1] + (g0 - half) / (g0 - g1) * (lag[k] - lag[k - 1]))
}
