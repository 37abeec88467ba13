//! Lab scenes (`"model": {"kind": "lab", …}`): the laboratory spring-slider driven through a
//! load-point history (docs/lab.md). Parsed apart from the DRR scenes: their keys differ.

use super::solver_block::{self, RawAtol, RawSolver, LAB_DEFAULTS};
use super::{finite, positive, SceneError};
use crate::analysis::lab::{LabSolver, Output, MAX_STATES};
use crate::model::{LabLaw, LabParams, LabState, Loading, Segment, StateLaw};
use serde::Deserialize;
use std::path::Path;

/// A validated lab scene.
#[derive(Debug, Clone, PartialEq)]
pub struct LabScene {
    /// Scene name.
    pub name: String,
    /// Free text.
    pub description: Option<String>,
    /// The model's parameters.
    pub params: LabParams,
    /// The load-point history.
    pub loading: Loading,
    /// The start (ln V, ln θ_1, …) at the loading's start.
    pub initial: Vec<f64>,
    /// The solver.
    pub solver: LabSolver,
    /// Why this solver runs: the scene's block, or the defaults and why (the report's
    /// `solver.chosen_by`; [`LAB_DEFAULTS`]).
    pub solver_chosen_by: String,
    /// Which rows to write.
    pub output: Output,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    name: String,
    #[serde(default)]
    description: Option<String>,
    model: RawModel,
    loading: RawLoading,
    #[serde(default)]
    initial: Option<RawInitial>,
    #[serde(default)]
    solver: Option<RawSolver>,
    #[serde(default)]
    analyses: Vec<RawAnalysis>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    /// "lab" ([`KIND`]).
    kind: String,
    mu0: f64,
    a: f64,
    #[serde(default)]
    v0: Option<f64>,
    k: f64,
    states: Vec<RawState>,
    #[serde(default)]
    mass: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawState {
    law: String,
    b: f64,
    d_c: f64,
    #[serde(default)]
    c: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoading {
    #[serde(default)]
    segments: Option<Vec<RawSegment>>,
    #[serde(default)]
    t_end: Option<f64>,
    #[serde(default)]
    steps: Option<Vec<RawStep>>,
    #[serde(default)]
    t_start: Option<f64>,
    #[serde(default)]
    csv: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSegment {
    t_start: f64,
    velocity: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStep {
    velocity: f64,
    #[serde(default)]
    displacement: Option<f64>,
    #[serde(default)]
    duration: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawInitial {
    Named(String),
    Explicit { mu: f64, theta: Vec<f64> },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAnalysis {
    time_series: RawTimes,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTimes {
    times: Vec<f64>,
}

/// The `model.kind` of a lab scene.
pub const KIND: &str = "lab";

/// Parses and validates a lab scene. `source_name` names it in errors; a relative
/// `loading.csv` path is read relative to `source_name`'s folder.
pub fn parse(text: &str, source_name: &str) -> Result<LabScene, SceneError> {
    let err = |field: &str, message: String| SceneError {
        source_name: source_name.into(),
        field: field.into(),
        message,
    };
    from_json(&super::json(text, &err)?, source_name)
}

/// [`parse`] on the scene's JSON, parsed once by `scene::parse_any`.
pub(super) fn from_json(
    json: &serde_json::Value,
    source_name: &str,
) -> Result<LabScene, SceneError> {
    let err = |field: &str, message: String| SceneError {
        source_name: source_name.into(),
        field: field.into(),
        message,
    };
    let raw: Raw = super::deserialize(json, &err)?;
    if raw.model.kind != KIND {
        return Err(err(
            "model.kind",
            format!("\"{}\": a lab scene has \"kind\": \"{KIND}\"", raw.model.kind),
        ));
    }
    if raw.name.trim().is_empty() {
        return Err(err("name", "must not be empty".into()));
    }
    let params = params(&raw.model, &err)?;
    let loading = loading(&raw.loading, source_name, &err)?;
    let v_first = loading.segments[0].velocity;
    let initial = match &raw.initial {
        None => steady(&params, v_first, &err)?,
        Some(RawInitial::Named(s)) if s == "steady" => steady(&params, v_first, &err)?,
        Some(RawInitial::Named(s)) => {
            return Err(err(
                "initial",
                format!("\"{s}\": use \"steady\" or {{\"mu\": μ, \"theta\": [θ_1, …]}}"),
            ))
        }
        Some(RawInitial::Explicit { mu, theta }) => {
            finite("initial.mu", *mu, &err)?;
            if theta.len() != params.states.len() {
                return Err(err(
                    "initial.theta",
                    format!(
                        "{} values for {} state variables; give one θ per state",
                        theta.len(),
                        params.states.len()
                    ),
                ));
            }
            for (i, t) in theta.iter().enumerate() {
                positive(&format!("initial.theta[{i}]"), *t, "θ > 0", &err)?;
            }
            let y = params.state_from(*mu, theta);
            if !y[0].exp().is_finite() || y[0].exp() <= 0.0 {
                return Err(err("initial.mu", format!("μ = {mu} gives V = e^{} outside the floating-point range; choose μ nearer the steady state", y[0])));
            }
            y
        }
    };
    let (solver, solver_chosen_by) = solver(raw.solver.as_ref(), &err)?;
    let output = match raw.analyses.as_slice() {
        [] => Output::EveryStep,
        [a] => {
            let times = &a.time_series.times;
            crate::analysis::lab::check_times(times, &loading)
                .map_err(|e| err("analyses[0].time_series.times", e.to_string()))?;
            Output::Times(times.clone())
        }
        _ => return Err(err("analyses", "a lab scene takes at most one analysis, {\"time_series\": {\"times\": [...]}} (without it every step is a row)".into())),
    };
    Ok(LabScene {
        name: raw.name,
        description: raw.description,
        params,
        loading,
        initial,
        solver,
        solver_chosen_by,
        output,
    })
}

fn params(
    m: &RawModel,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<LabParams, SceneError> {
    let mu0 = finite("model.mu0", m.mu0, err)?;
    let a = positive("model.a", m.a, "the direct effect a, e.g. 0.01", err)?;
    let v0 =
        positive("model.v0", m.v0.unwrap_or(1.0), "the reference velocity V0 (default 1)", err)?;
    let k = positive(
        "model.k",
        m.k,
        "the stiffness in friction per unit displacement (per µm), e.g. 1e-3",
        err,
    )?;
    if m.states.is_empty() || m.states.len() > MAX_STATES {
        return Err(err(
            "model.states",
            format!(
                "{} state variables; give 1 to {MAX_STATES}, each {{\"law\", \"b\", \"d_c\"}}",
                m.states.len()
            ),
        ));
    }
    let mut states = Vec::new();
    for (i, s) in m.states.iter().enumerate() {
        let field = |name: &str| format!("model.states[{i}].{name}");
        let b = finite(&field("b"), s.b, err)?;
        let d_c =
            positive(&field("d_c"), s.d_c, "the critical slip distance D_c, e.g. 10 (µm)", err)?;
        let law = match (s.law.as_str(), StateLaw::from_name(&s.law)) {
            ("nagata", _) => {
                let c = s.c.ok_or_else(|| {
                    err(&field("c"), "missing: the Nagata law needs c (e.g. 2)".into())
                })?;
                if b == 0.0 {
                    return Err(err(&field("b"), "the Nagata law divides by b: give b ≠ 0".into()));
                }
                LabLaw::Nagata { c: finite(&field("c"), c, err)? }
            }
            (_, Some(StateLaw::Ageing)) => LabLaw::Ageing,
            (_, Some(StateLaw::Slip)) => LabLaw::Slip,
            (_, Some(StateLaw::Prz)) => LabLaw::Prz,
            (other, Some(StateLaw::NoHealing) | None) => {
                return Err(err(
                    &field("law"),
                    format!("\"{other}\" is not a state law of the lab model; use ageing, slip, prz or nagata (also aging, dieterich, ruina)"),
                ))
            }
        };
        if s.c.is_some() && !matches!(law, LabLaw::Nagata { .. }) {
            return Err(err(
                &field("c"),
                format!("only the nagata law takes c (this state's law is {})", law.name()),
            ));
        }
        states.push(LabState { law, b, d_c });
    }
    let mass = match m.mass {
        None => None,
        Some(mass) => Some(positive(
            "model.mass",
            mass,
            "the slider's inertia m/(σA) in friction·s²/µm (leave it out for the quasi-static model)",
            err,
        )?),
    };
    Ok(LabParams { mu0, a, v0, k, states, mass })
}

fn loading(
    l: &RawLoading,
    source_name: &str,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Loading, SceneError> {
    let given = [l.segments.is_some(), l.steps.is_some(), l.csv.is_some()];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(err(
            "loading",
            "give exactly one of \"segments\" (with \"t_end\"), \"steps\" or \"csv\"".into(),
        ));
    }
    let bad = |field: &'static str| {
        move |e: crate::model::loading::LoadingError| err(field, e.to_string())
    };
    if let Some(segs) = &l.segments {
        if l.t_start.is_some() {
            return Err(err("loading.t_start", "segments carry their own t_start".into()));
        }
        let t_end = l.t_end.ok_or_else(|| {
            err("loading.t_end", "missing: the end time of the last segment".into())
        })?;
        let segments =
            segs.iter().map(|s| Segment { t_start: s.t_start, velocity: s.velocity }).collect();
        return Loading::new(segments, t_end).map_err(bad("loading.segments"));
    }
    if l.t_end.is_some() {
        return Err(err(
            "loading.t_end",
            "only \"segments\" take t_end (steps and csv end where they end)".into(),
        ));
    }
    if let Some(steps) = &l.steps {
        let mut t = finite("loading.t_start", l.t_start.unwrap_or(0.0), err)?;
        let mut segments = Vec::new();
        for (i, s) in steps.iter().enumerate() {
            let field = |name: &str| format!("loading.steps[{i}].{name}");
            let v = finite(&field("velocity"), s.velocity, err)?;
            let duration =
                match (s.displacement, s.duration) {
                    (Some(x), None) if v > 0.0 => {
                        positive(
                            &field("displacement"),
                            x,
                            "the load-point displacement of this step",
                            err,
                        )? / v
                    }
                    (None, Some(d)) => {
                        positive(&field("duration"), d, "the duration of this step (s)", err)?
                    }
                    (Some(_), None) => {
                        return Err(err(
                            &field("displacement"),
                            "a hold (velocity 0) has no displacement; give its \"duration\"".into(),
                        ))
                    }
                    _ => return Err(err(
                        &field("displacement"),
                        "give exactly one of \"displacement\" (load-point, µm) or \"duration\" (s)"
                            .into(),
                    )),
                };
            segments.push(Segment { t_start: t, velocity: v });
            t += duration;
        }
        return Loading::new(segments, t).map_err(bad("loading.steps"));
    }
    let file = l.csv.as_deref().unwrap_or_default();
    if l.t_start.is_some() {
        return Err(err("loading.t_start", "a csv loading starts at its first time".into()));
    }
    let path = Path::new(source_name)
        .parent()
        .map_or_else(|| Path::new(file).to_path_buf(), |d| d.join(file));
    let text = std::fs::read_to_string(&path)
        .map_err(|e| err("loading.csv", format!("cannot read {}: {e}", path.display())))?;
    let mut samples = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let cols: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed = (cols.len() >= 2).then(|| (cols[0].parse::<f64>(), cols[1].parse::<f64>()));
        match parsed {
            Some((Ok(t), Ok(x))) => samples.push((t, x)),
            _ if n == 0 => {} // a header
            _ if line.trim().is_empty() => {}
            _ => {
                return Err(err(
                    "loading.csv",
                    format!(
                    "{} line {}: expected \"time,load-point displacement\" numbers, got {line:?}",
                    path.display(),
                    n + 1
                ),
                ))
            }
        }
    }
    Loading::from_displacement(&samples).map_err(bad("loading.csv"))
}

fn steady(
    p: &LabParams,
    v: f64,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Vec<f64>, SceneError> {
    if v <= 0.0 {
        return Err(err("initial", "\"steady\" needs the first segment to slide (velocity > 0); start with a slide or give {\"mu\", \"theta\"}".into()));
    }
    Ok(p.steady_state(v))
}

/// The lab's solver from the scene's `solver` block ([`LAB_DEFAULTS`] for what it leaves
/// out): atol is one number, the absolute tolerance of ln V and each ln θ_i (by default rtol);
/// no Butcher table, no step budget.
fn solver(
    raw: Option<&RawSolver>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(LabSolver, String), SceneError> {
    let block = solver_block::parse(raw, &LAB_DEFAULTS, err)?;
    let atol = match &block.atol {
        None => block.rtol,
        Some(RawAtol::Scalar(a)) => *a,
        Some(RawAtol::PerComponent(v)) => {
            return Err(err(
                "solver.atol",
                format!(
                    "{v:?}: give one number, the absolute tolerance of ln V and each ln θ_i \
                     (an absolute error in a logarithm is a relative one in V and θ), e.g. 1e-12"
                ),
            ))
        }
    };
    let atol = positive("solver.atol", atol, "absolute in ln V and ln θ, e.g. 1e-12", err)?;
    for (field, given) in [
        ("table", block.table.is_some()),
        ("explicit_table", block.explicit_table.is_some()),
        ("max_steps", block.max_steps.is_some()),
    ] {
        if given {
            return Err(err(
                &format!("solver.{field}"),
                "a lab scene's solver takes method, rtol and atol only".into(),
            ));
        }
    }
    Ok((LabSolver { method: block.method, rtol: block.rtol, atol }, block.chosen_by))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::Method;

    const STEP: &str = r#"{"name": "s", "model": {"kind": "lab", "mu0": 0.6, "a": 0.005, "k": 1e-3,
        "states": [{"law": "ageing", "b": 0.01, "d_c": 10}]},
        "loading": {"steps": [{"velocity": 1, "displacement": 10}, {"velocity": 0, "duration": 100}, {"velocity": 10, "displacement": 300}]}}"#;

    #[test]
    fn parses_steps_into_segments() {
        let s = parse(STEP, "x.json").unwrap();
        assert_eq!(s.loading.segments.len(), 3);
        assert_eq!(s.loading.segments[2].t_start, 110.0);
        assert_eq!(s.loading.t_end, 140.0);
        assert_eq!(s.output, Output::EveryStep);
    }

    #[test]
    fn takes_the_state_law_names_and_aliases_every_model_takes() {
        for (name, law) in
            [("aging", LabLaw::Ageing), ("dieterich", LabLaw::Ageing), ("ruina", LabLaw::Slip)]
        {
            let s = parse(&STEP.replace("\"ageing\"", &format!("\"{name}\"")), "x").unwrap();
            assert_eq!(s.params.states[0].law, law, "{name}");
        }
        let e = parse(&STEP.replace("\"ageing\"", "\"no_healing\""), "x").unwrap_err();
        assert_eq!(e.field, "model.states[0].law");
    }

    #[test]
    fn a_scene_without_a_solver_block_runs_the_lab_default_and_says_why() {
        let s = parse(STEP, "x").unwrap();
        assert_eq!((s.solver.method, s.solver.rtol, s.solver.atol), (Method::Radau5, 1e-12, 1e-12));
        assert_eq!(s.solver_chosen_by, crate::scene::LAB_CHOSEN_BY_DEFAULT);
        let e = parse(
            &STEP.replace("\"loading\"", "\"solver\": {\"atol\": [1e-12, 1e-12]}, \"loading\""),
            "x",
        )
        .unwrap_err();
        assert_eq!(e.field, "solver.atol");
    }

    #[test]
    fn names_the_bad_field() {
        let bad = STEP.replace("\"ageing\"", "\"aging-law\"");
        assert_eq!(parse(&bad, "x").unwrap_err().field, "model.states[0].law");
        let bad = STEP.replace("\"k\": 1e-3", "\"k\": -1");
        assert_eq!(parse(&bad, "x").unwrap_err().field, "model.k");
        let bad = STEP.replace("\"duration\": 100", "\"displacement\": 100");
        assert_eq!(parse(&bad, "x").unwrap_err().field, "loading.steps[1].displacement");
    }
}
