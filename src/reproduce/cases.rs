//! The runs behind the figures: the paper's scenes (data/scenes/) with small changes, run in
//! parallel, and the period curves ([`period_curve`]: shooting and continuation, with the
//! brute-force cycle analysis where continuation does not reach).

use super::{Context, ReproduceError};
use serde::Serialize;
use serde_json::{json, Value};
use stickslip::analysis::cycle::TrajectoryCycle;
use stickslip::report::Report;
use stickslip::{engine, scene};

/// data/scenes/fig1.json: γ = 1e3, ξ = 0.7, ε = 0.72.
pub const FIG1: &str = include_str!("../../data/scenes/fig1.json");
/// data/scenes/fig1-asymptotics.json: the Fig. 1 case with the "asymptotics" and "lyapunov"
/// analyses (Figs. 3 and 5).
pub const FIG1_ASYMPTOTICS: &str = include_str!("../../data/scenes/fig1-asymptotics.json");
/// data/scenes/earthquake.json: γ = 1e8, ξ = 0.8, ε = 1.
pub const EARTHQUAKE: &str = include_str!("../../data/scenes/earthquake.json");
/// data/scenes/power-law.json: α = 0.31, γ = 10, ξ = 0.7, ε = 1.
pub const POWER_LAW: &str = include_str!("../../data/scenes/power-law.json");

/// A shipped scene as JSON (they are part of the crate and always parse).
pub fn shipped(text: &str) -> Value {
    serde_json::from_str(text).expect("the shipped scenes are valid JSON")
}

/// A copy of `base` named `name`, with model parameters set (`gamma`, `xi`, `epsilon`,
/// `alpha` for power-law friction, `friction` = "log") and `trajectory_cycles` cycles of
/// trajectory kept (0: none). Analyses become hopf, cycle and paper.
pub fn variant(
    base: &Value,
    name: &str,
    params: &[(&str, f64)],
    log_friction: bool,
    trajectory_cycles: usize,
) -> Value {
    let mut s = base.clone();
    s["name"] = json!(name);
    for &(key, v) in params {
        if key == "alpha" {
            s["model"]["friction"] = json!({ "power": { "alpha": v } });
        } else {
            s["model"][key] = json!(v);
        }
    }
    if log_friction {
        s["model"]["friction"] = json!("log");
    }
    let mut analyses = vec![json!("hopf"), json!("cycle"), json!("paper")];
    if trajectory_cycles > 0 {
        analyses.push(json!({ "trajectory": { "cycles": trajectory_cycles } }));
    }
    s["analyses"] = Value::Array(analyses);
    s
}

/// Runs one scene as `stickslip run` would.
pub fn run_scene(scene_json: &Value) -> Result<Report, ReproduceError> {
    let name = scene_json["name"].as_str().unwrap_or("?").to_string();
    let s = scene::parse(&scene_json.to_string(), &name)
        .map_err(|e| ReproduceError::Scene(e.to_string()))?;
    engine::run(&s, engine::RunOptions::echoing(scene_json.clone()))
        .map_err(|source| ReproduceError::Run { case: name, source })
}

/// Runs `jobs` on `threads` worker threads, results in input order, reporting progress.
pub fn parallel<T: Sync, R: Send>(ctx: &Context, jobs: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    stickslip::parallel::map(
        jobs.len(),
        ctx.threads,
        &|done, total| ctx.progress.points(done, total),
        |i| f(&jobs[i]),
    )
}

/// Runs several scenes in parallel; every one must succeed.
pub fn run_scenes(ctx: &Context, scenes: &[Value]) -> Result<Vec<Report>, ReproduceError> {
    parallel(ctx, scenes, run_scene).into_iter().collect()
}

/// What the cycle analysis found at one point of a curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum PointOutcome {
    /// A period-1 limit cycle.
    Periodic {
        /// Its period.
        period: f64,
    },
    /// A period-n orbit (e.g. after period doubling).
    PeriodN {
        /// The periods of its n cycles.
        periods: Vec<f64>,
    },
    /// The oscillation died out.
    FixedPoint,
    /// Neither within the analysis' limits.
    NotConverged {
        /// Periods of the last cycles computed.
        last_periods: Vec<f64>,
    },
    /// The computation failed (typed solver error, as text).
    Failed {
        /// The error.
        error: String,
    },
}

/// One point of a period curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CurvePoint {
    /// The swept parameter's value.
    pub value: f64,
    /// The outcome (flattened: `status` and its fields).
    #[serde(flatten)]
    pub outcome: PointOutcome,
}

/// The period of the limit cycle of `base` as `param` (gamma, xi, epsilon or alpha) takes
/// `values`, one point per value, in order.
///
/// For ε, ξ and γ on a uniform grid (linear, or log10 for γ): shooting and continuation
/// (`analysis::continuation`, Radau5 at the scene's tolerances) from the end where the
/// relaxation cycle is robust (the largest ε or ξ, the smallest γ), for γ up to 1e8 (beyond,
/// Newton's steps shrink and the continuation is slower than brute force: docs/shooting.md).
/// The points it does not reach fall back to the brute-force cycle analysis, run per point in
/// parallel — as does any other parameter.
pub fn period_curve(ctx: &Context, base: &Value, param: &str, values: &[f64]) -> Vec<CurvePoint> {
    let mut points: Vec<Option<CurvePoint>> = vec![None; values.len()];
    if matches!(param, "epsilon" | "xi" | "gamma") && values.len() >= 2 {
        let reverse = param != "gamma";
        let grid: &[f64] = if reverse {
            values
        } else {
            &values[..values.iter().take_while(|&&g| g <= 1e8 * (1.0 + 1e-12)).count()]
        };
        let (from, to) =
            if reverse { (grid[grid.len() - 1], grid[0]) } else { (grid[0], grid[grid.len() - 1]) };
        let mut scene = variant(base, &format!("{param}-continuation"), &[(param, from)], false, 0);
        scene["solver"]["method"] = json!("radau5");
        scene["analyses"] = json!([{ "continuation": { "parameter": param, "to": to, "points": grid.len().max(2) } }]);
        if let Ok(report) = run_scene(&scene) {
            for p in report.continuation.iter().flat_map(|c| &c.points) {
                if let Some(i) = values.iter().position(|v| (p.value - v).abs() <= 1e-9 * v.abs()) {
                    points[i] = Some(CurvePoint {
                        value: values[i],
                        outcome: PointOutcome::Periodic { period: p.orbit.period },
                    });
                }
            }
        }
    }
    let missing: Vec<f64> =
        values.iter().zip(&points).filter(|(_, p)| p.is_none()).map(|(v, _)| *v).collect();
    let mut brute = parallel(ctx, &missing, |&value| {
        let mut scene = variant(base, &format!("{param}={value}"), &[(param, value)], false, 0);
        scene["analyses"] = json!(["cycle"]);
        let outcome = match run_scene(&scene) {
            Err(e) => PointOutcome::Failed { error: e.to_string() },
            Ok(report) => outcome(&report),
        };
        CurvePoint { value, outcome }
    })
    .into_iter();
    points
        .into_iter()
        .map(|p| p.or_else(|| brute.next()).expect("every missing point was run"))
        .collect()
}

fn outcome(report: &Report) -> PointOutcome {
    use stickslip::analysis::cycle::CycleStatus;
    let Some(c) = &report.cycle else {
        return PointOutcome::Failed { error: "no cycle section".into() };
    };
    match (c.status, &c.values) {
        (CycleStatus::Periodic, Some(v)) => PointOutcome::Periodic { period: v.main.period },
        (CycleStatus::PeriodN, _) => {
            PointOutcome::PeriodN { periods: c.orbit.iter().map(|o| o.main.period).collect() }
        }
        (CycleStatus::FixedPoint, _) => PointOutcome::FixedPoint,
        _ => PointOutcome::NotConverged {
            last_periods: c.last_cycles.iter().map(|o| o.main.period).collect(),
        },
    }
}

/// The kept trajectory cycles of a report, concatenated on one clock (t = 0 at the first
/// kept cycle's upward crossing of v = 1).
pub fn trajectory(report: &Report) -> Result<TrajectoryCycle, ReproduceError> {
    let cycles = report.cycle.as_ref().map(|c| c.trajectory.as_slice()).unwrap_or_default();
    if cycles.is_empty() {
        return Err(ReproduceError::Missing(format!(
            "scene {}: no trajectory kept (is the cycle periodic?)",
            report.name
        )));
    }
    let mut out = TrajectoryCycle::default();
    let mut offset = 0.0;
    for c in cycles {
        // A cycle's last sample is the next cycle's first (its upward crossing of v = 1).
        let skip = usize::from(!out.t.is_empty());
        out.t.extend(c.t.iter().skip(skip).map(|t| t + offset));
        out.u.extend(c.u.iter().skip(skip));
        out.v.extend(c.v.iter().skip(skip));
        out.theta.extend(c.theta.iter().skip(skip));
        offset += c.t.last().copied().unwrap_or(0.0);
    }
    Ok(out)
}

/// Index of the largest v in the trajectory (the event t_c: the v maximum is a recorded event).
pub fn peak_index(tr: &TrajectoryCycle) -> usize {
    tr.v.iter().enumerate().fold(0, |best, (i, &v)| if v > tr.v[best] { i } else { best })
}
