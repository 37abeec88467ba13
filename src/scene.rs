//! Scenes: what to compute, as JSON. Parsing rejects unknown keys and wrong types (naming the
//! path); validation rejects values outside the model's domain (naming the field and what
//! would be valid). The schema is documented in docs/scenes.md.

use crate::analysis::cycle::CycleOptions;
use crate::analysis::noise::options::{self as noise_options, NoiseOptions};
use crate::analysis::shooting::ShootingOptions;
use crate::analysis::time_series::TimeSeriesOptions;
use crate::model::{
    Drr, DrrParams, Friction, PhysicalScales, SaddleNodeParams, StateLaw, VanDerPolParams,
};
pub use crate::solver::{Method, SolverSpec};
use serde::{Deserialize, Serialize};

/// A bad scene: the field at fault and how to fix it. CLI exit code 2.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("scene {source_name}: {field}: {message}")]
pub struct SceneError {
    /// The scene file (or `"<built-in>"`).
    pub source_name: String,
    /// Path of the offending field, e.g. "model.gamma".
    pub field: String,
    /// What is wrong and what would be valid.
    pub message: String,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: String,
    #[serde(default)]
    description: Option<String>,
    model: RawModel,
    #[serde(default)]
    units: Option<Units>,
    #[serde(default)]
    initial: Option<RawInitial>,
    #[serde(default)]
    solver: Option<RawSolver>,
    analyses: Vec<RawAnalysis>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    gamma: Option<f64>,
    xi: Option<f64>,
    epsilon: Option<f64>,
    dimensional: Option<Dimensional>,
    #[serde(default)]
    friction: Option<RawFriction>,
    /// "slip" (default), "ageing" or "prz".
    #[serde(default)]
    state_law: Option<String>,
    /// Radiation damping η (dimensionless, ≥ 0).
    #[serde(default)]
    radiation_damping: Option<f64>,
    /// false: the quasi-dynamic model (no inertia; needs η > 0, takes no γ). Default true.
    #[serde(default)]
    inertia: Option<bool>,
    /// "drr" (default), "saddle_node" or "van_der_pol".
    #[serde(default)]
    kind: Option<String>,
    /// Saddle-node: μ0, r and the start x0.
    #[serde(default)]
    mu0: Option<f64>,
    #[serde(default)]
    r: Option<f64>,
    #[serde(default)]
    x0: Option<f64>,
    /// Van der Pol: β, a and the start (x0, y0).
    #[serde(default)]
    beta: Option<f64>,
    #[serde(default)]
    a: Option<f64>,
    #[serde(default)]
    y0: Option<f64>,
}

/// Dimensional parameters (any consistent units, per unit area of the interface):
/// γ = (D_c/v0)·√(k/M), ξ = k·D_c/A, ε = (B−A)/A, and the radiation damping
/// η = G·v0/(2·c_s·A) when the shear modulus G and shear-wave speed c_s are given.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dimensional {
    /// Spring stiffness k.
    pub k: f64,
    /// Block mass M (absent in a quasi-dynamic scene, which has no inertia).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Direct-effect coefficient A.
    pub a: f64,
    /// State-effect coefficient B.
    pub b: f64,
    /// Critical slip distance D_c.
    pub d_c: f64,
    /// Driving velocity v0.
    pub v0: f64,
    /// Shear modulus G of the surrounding medium (radiation damping; with `shear_wave_speed`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_modulus: Option<f64>,
    /// Shear-wave speed c_s (radiation damping; with `shear_modulus`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_wave_speed: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum RawFriction {
    Log,
    Asinh,
    Power { alpha: f64 },
}

/// Physical time units for reports: one dimensionless time unit (D_c/v0) is `time_scale`
/// `time_unit`s, e.g. 2.7 years.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// Name of the physical time unit, e.g. "years".
    pub time_unit: String,
    /// D_c/v0 in that unit.
    pub time_scale: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawInitial {
    u: Option<f64>,
    v: Option<f64>,
    theta: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
enum RawAtol {
    Scalar(f64),
    PerComponent(Vec<f64>),
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    #[serde(default)]
    method: Option<String>,
    #[serde(default)]
    rtol: Option<f64>,
    #[serde(default)]
    atol: Option<RawAtol>,
    #[serde(default)]
    table: Option<String>,
    #[serde(default)]
    explicit_table: Option<String>,
    #[serde(default)]
    max_steps: Option<u64>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
enum RawAnalysis {
    Name(String),
    WithOptions(std::collections::BTreeMap<String, serde_json::Value>),
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawContinuation {
    parameter: String,
    to: f64,
    points: usize,
    #[serde(default)]
    log: Option<bool>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawTrajectory {
    cycles: usize,
}

/// The "continuation" analysis: from the scene's value of `parameter` to `to`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContinuationOptions {
    /// The parameter.
    pub parameter: crate::analysis::continuation::Parameter,
    /// Final value.
    pub to: f64,
    /// Grid points, both ends included.
    pub points: usize,
    /// Grid uniform in log10 (default: true for γ, false otherwise).
    pub log: bool,
}

/// Which analyses to run; everything else is neither computed nor stored.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Analyses {
    /// Fixed point, eigenvalues and Hopf threshold.
    pub hopf: bool,
    /// The limit cycle (None: not asked).
    pub cycle: Option<CycleOptions>,
    /// Keep every step of the last this many cycles (needs "cycle").
    pub trajectory_cycles: Option<usize>,
    /// Compare with the paper's quoted values.
    pub paper: bool,
    /// Matched asymptotics against the numerics (needs "cycle").
    pub asymptotics: Option<crate::analysis::asymptotics::AsymptoticsOptions>,
    /// Local and finite-time Lyapunov exponents along the cycle (needs "cycle").
    pub lyapunov: Option<crate::analysis::lyapunov::LyapunovOptions>,
    /// The periodic orbit by shooting (None: not asked).
    pub shooting: Option<ShootingOptions>,
    /// Continuation of the orbit in a parameter (None: not asked).
    pub continuation: Option<ContinuationOptions>,
    /// Response to noise: ensembles and linear response (None: not asked).
    pub noise: Option<NoiseOptions>,
    /// A run of fixed length from t = 0 with its event catalogue (None: not asked); `t_max`
    /// as the scene gave it, in the scene's time unit (D_c/v0, or the dimensional input's).
    pub time_series: Option<TimeSeriesOptions>,
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// Free text.
    pub description: Option<String>,
    /// Dimensionless model parameters.
    pub params: DrrParams,
    /// The dimensional input, when given.
    pub dimensional: Option<Dimensional>,
    /// Physical time units for reports.
    pub units: Option<Units>,
    /// The physical scales (D_c/v0, v0, D_c, aσ, σ, k, μ0 at V_ref), with dimensional input.
    pub scales: Option<PhysicalScales>,
    /// Initial state (u, ln v, θ).
    pub initial: [f64; 3],
    /// Solver settings.
    pub solver: SolverSpec,
    /// Requested analyses.
    pub analyses: Analyses,
}

const ANALYSIS_NAMES: &str = "\"hopf\", \"cycle\", \"paper\", \"shooting\", {\"cycle\": {...}}, {\"trajectory\": {\"cycles\": N}}, {\"shooting\": {...}}, {\"continuation\": {\"parameter\": \"epsilon\"|\"xi\"|\"gamma\"|\"radiation_damping\", \"to\": X, \"points\": N}}, {\"noise\": {\"amplitudes\": [...]}}, {\"time_series\": {\"t_max\": T}}, \"asymptotics\", {\"asymptotics\": {...}}, \"lyapunov\", {\"lyapunov\": {...}}";

/// A model other than the DRR: only the "noise" analysis runs on it.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum OtherModel {
    /// dx/dt = μ0 − r t − x², starting at x0 when t = 0.
    SaddleNode {
        /// μ0 and r.
        params: SaddleNodeParams,
        /// x at t = 0.
        x0: f64,
    },
    /// dy/dt = x + a, dx/dt = β²(x − x³/3 − y), starting at (x0, y0).
    VanDerPol {
        /// β and a.
        params: VanDerPolParams,
        /// (x, y) at the start of the deterministic orbit.
        initial: [f64; 2],
    },
}

/// A validated scene of a model other than the DRR.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OtherScene {
    /// Scene name.
    pub name: String,
    /// Free text.
    pub description: Option<String>,
    /// The model.
    pub model: OtherModel,
    /// The noise analysis's options.
    pub noise: NoiseOptions,
}

/// Any validated scene: the DRR (every analysis) or another model (noise only).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyScene {
    /// A DRR scene.
    Drr(Box<Scene>),
    /// A saddle-node or van der Pol scene.
    Other(Box<OtherScene>),
}

/// Parses and validates a scene of any model kind (`"model": {"kind": ...}`).
pub fn parse_any(text: &str, source_name: &str) -> Result<AnyScene, SceneError> {
    let err = |field: &str, message: String| SceneError {
        source_name: source_name.into(),
        field: field.into(),
        message,
    };
    let raw = parse_raw(text, &err)?;
    match raw.model.kind.as_deref() {
        None | Some("drr") => validate(raw, &err).map(|s| AnyScene::Drr(Box::new(s))),
        Some(_) => validate_other(raw, &err).map(|s| AnyScene::Other(Box::new(s))),
    }
}

fn parse_raw(
    text: &str,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<RawScene, SceneError> {
    let deserializer = &mut serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let path = e.path().to_string();
        let field = if path == "." || path.is_empty() { "(document)".to_string() } else { path };
        err(&field, e.into_inner().to_string())
    })
}

/// Rejects the keys of `model` that the kind does not take.
fn only_model_keys(
    m: &RawModel,
    kind: &str,
    allowed: &[&str],
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    let given = [
        ("gamma", m.gamma.is_some()),
        ("xi", m.xi.is_some()),
        ("epsilon", m.epsilon.is_some()),
        ("dimensional", m.dimensional.is_some()),
        ("friction", m.friction.is_some()),
        ("state_law", m.state_law.is_some()),
        ("radiation_damping", m.radiation_damping.is_some()),
        ("inertia", m.inertia.is_some()),
        ("mu0", m.mu0.is_some()),
        ("r", m.r.is_some()),
        ("x0", m.x0.is_some()),
        ("beta", m.beta.is_some()),
        ("a", m.a.is_some()),
        ("y0", m.y0.is_some()),
    ];
    for (name, present) in given {
        if present && !allowed.contains(&name) {
            return Err(err(
                &format!("model.{name}"),
                format!(
                    "the {kind} model takes no \"{name}\"; its keys are {}",
                    allowed.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

fn validate_other(
    raw: RawScene,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<OtherScene, SceneError> {
    if raw.name.trim().is_empty() {
        return Err(err("name", "must not be empty".into()));
    }
    let m = &raw.model;
    let kind = m.kind.as_deref().unwrap_or("drr");
    let model = match kind {
        "saddle_node" => {
            only_model_keys(m, kind, &["mu0", "r", "x0"], err)?;
            let mu0 = positive("model.mu0", m.mu0.ok_or_else(|| err("model.mu0", "missing: μ at t = 0, > 0, e.g. 1".into()))?, "μ(0), e.g. 1", err)?;
            let r = positive("model.r", m.r.ok_or_else(|| err("model.r", "missing: the tilting rate r > 0 of μ = μ0 − r t, e.g. 0.01".into()))?, "e.g. 0.01", err)?;
            let x0 = positive("model.x0", m.x0.unwrap_or(mu0.sqrt()), "the start on the stable branch x = √μ0 (default)", err)?;
            OtherModel::SaddleNode { params: SaddleNodeParams { mu0, r }, x0 }
        }
        "van_der_pol" => {
            only_model_keys(m, kind, &["beta", "a", "x0", "y0"], err)?;
            let beta = positive("model.beta", m.beta.ok_or_else(|| err("model.beta", "missing: β > 0 (β² is the fast rate), e.g. 30".into()))?, "e.g. 30", err)?;
            let a = finite("model.a", m.a.unwrap_or(0.0), err)?;
            if a.abs() >= 1.0 {
                return Err(err("model.a", format!("{a}: |a| must be < 1 for a relaxation oscillation (the fixed point x = −a on the unstable middle branch)")));
            }
            let x0 = finite("model.x0", m.x0.unwrap_or(2.0), err)?;
            let y0 = finite("model.y0", m.y0.unwrap_or(-2.0 / 3.0), err)?;
            OtherModel::VanDerPol { params: VanDerPolParams { beta, a }, initial: [x0, y0] }
        }
        other => return Err(err("model.kind", format!("unknown kind \"{other}\"; use \"drr\" (default), \"saddle_node\" or \"van_der_pol\""))),
    };
    for (field, present) in [
        ("initial", raw.initial.is_some()),
        ("units", raw.units.is_some()),
        ("solver", raw.solver.is_some()),
    ] {
        if present {
            return Err(err(field, format!("the {kind} model takes no \"{field}\" (its start is model.x0{}; the noise analysis sets its own solver)", if kind == "van_der_pol" { "/y0" } else { "" })));
        }
    }
    let dim = if kind == "saddle_node" { 1 } else { 2 };
    let analyses = analyses(&raw.analyses, (kind, dim, None), err)?;
    if analyses.hopf
        || analyses.cycle.is_some()
        || analyses.paper
        || analyses.trajectory_cycles.is_some()
        || analyses.shooting.is_some()
        || analyses.continuation.is_some()
        || analyses.asymptotics.is_some()
        || analyses.lyapunov.is_some()
        || analyses.time_series.is_some()
    {
        return Err(err("analyses", format!("the {kind} model runs only the \"noise\" analysis (hopf, cycle, paper, trajectory, shooting, continuation, asymptotics, lyapunov and time_series need the DRR model)")));
    }
    let noise = analyses.noise.ok_or_else(|| err("analyses", format!("the {kind} model runs only the \"noise\" analysis; add {{\"noise\": {{\"amplitudes\": [...]}}}}")))?;
    Ok(OtherScene { name: raw.name, description: raw.description, model, noise })
}

/// Parses and validates a scene from JSON text. `source_name` names it in errors.
pub fn parse(text: &str, source_name: &str) -> Result<Scene, SceneError> {
    let err = |field: &str, message: String| SceneError {
        source_name: source_name.into(),
        field: field.into(),
        message,
    };
    let raw = parse_raw(text, &err)?;
    if let Some(kind) = raw.model.kind.as_deref().filter(|k| *k != "drr") {
        return Err(err("model.kind", format!("\"{kind}\": this command needs a DRR scene; `stickslip run` runs {kind} scenes (noise analysis)")));
    }
    validate(raw, &err)
}

fn finite(
    field: &str,
    value: f64,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<f64, SceneError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(err(field, format!("{value} is not a finite number")))
    }
}

fn positive(
    field: &str,
    value: f64,
    hint: &str,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<f64, SceneError> {
    let v = finite(field, value, err)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(err(field, format!("{v} must be > 0 ({hint})")))
    }
}

fn validate(raw: RawScene, err: &impl Fn(&str, String) -> SceneError) -> Result<Scene, SceneError> {
    if raw.name.trim().is_empty() {
        return Err(err("name", "must not be empty".into()));
    }
    let m = &raw.model;
    only_model_keys(
        m,
        "drr",
        &[
            "gamma",
            "xi",
            "epsilon",
            "dimensional",
            "friction",
            "state_law",
            "radiation_damping",
            "inertia",
        ],
        err,
    )?;
    let inertia = m.inertia.unwrap_or(true);
    if !inertia {
        no_inertial_keys(m, err)?;
    }
    let (gamma, xi, epsilon) = match (m.dimensional, m.gamma, m.xi, m.epsilon) {
        (Some(d), None, None, None) => {
            let mass = if inertia {
                d.mass.ok_or_else(|| err("model.dimensional.mass", "missing: the block mass M (per unit area), or \"inertia\": false for the quasi-dynamic model".into()))?
            } else {
                1.0
            };
            for (name, v) in
                [("k", d.k), ("mass", mass), ("a", d.a), ("b", d.b), ("d_c", d.d_c), ("v0", d.v0)]
            {
                positive(&format!("model.dimensional.{name}"), v, "a physical parameter", err)?;
            }
            let gamma = if inertia { (d.d_c / d.v0) * (d.k / mass).sqrt() } else { f64::INFINITY };
            (gamma, d.k * d.d_c / d.a, (d.b - d.a) / d.a)
        }
        (Some(_), ..) => {
            return Err(err(
                "model",
                "give either gamma/xi/epsilon or dimensional, not both".into(),
            ));
        }
        (None, None, Some(x), Some(e)) if !inertia => (f64::INFINITY, x, e),
        (None, Some(g), Some(x), Some(e)) => (g, x, e),
        (None, g, x, e) => {
            let g = if inertia { g } else { Some(f64::INFINITY) };
            let missing: Vec<&str> = [("gamma", g), ("xi", x), ("epsilon", e)]
                .iter()
                .filter(|(_, v)| v.is_none())
                .map(|(n, _)| *n)
                .collect();
            return Err(err(
                "model",
                format!(
                    "missing {} (or give \"dimensional\": {{k, mass, a, b, d_c, v0}})",
                    missing.join(", ")
                ),
            ));
        }
    };
    if inertia {
        let gamma = positive("model.gamma", gamma, "γ = (D_c/v0)·√(k/M), e.g. 1e3", err)?;
        if !(1e-100..=1e100).contains(&gamma) {
            return Err(err(
                "model.gamma",
                format!("{gamma:e} is outside 1e-100 … 1e100 (γ² must be a normal double)"),
            ));
        }
    }
    let xi = positive("model.xi", xi, "ξ = k·D_c/A, of order one, e.g. 0.7", err)?;
    let epsilon = finite("model.epsilon", epsilon, err)?;
    let friction = match m.friction.clone().unwrap_or(RawFriction::Log) {
        RawFriction::Log => Friction::Log,
        RawFriction::Asinh => Friction::Asinh,
        RawFriction::Power { alpha } => Friction::Power {
            alpha: positive(
                "model.friction.power.alpha",
                alpha,
                "g_α(v) = (v^α − 1)/α, e.g. 0.31",
                err,
            )?,
        },
    };
    let state_law = match m.state_law.as_deref() {
        None => StateLaw::Slip,
        Some(name) => StateLaw::from_name(name).ok_or_else(|| {
            let names: Vec<String> =
                StateLaw::ALL.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            err(
                "model.state_law",
                format!(
                    "\"{name}\" is not a state law; use one of {} (default \"slip\")",
                    names.join(", ")
                ),
            )
        })?,
    };
    let eta = radiation_damping(m, err)?;
    if !inertia && eta == 0.0 {
        return Err(err(
            "model.radiation_damping",
            "the quasi-dynamic model (\"inertia\": false) needs radiation damping η > 0: without it the force balance u + (θ + f(v))/ξ = 0 has no solution once the stress outruns f, and v blows up in finite time; give radiation_damping > 0 (e.g. 0.05) or dimensional.shear_modulus and shear_wave_speed".into(),
        ));
    }
    let params = DrrParams { gamma, xi, epsilon, friction, state_law, eta, inertia };
    let drr = Drr::new(params);

    let units = match raw.units.clone() {
        Some(u) => {
            positive(
                "units.time_scale",
                u.time_scale,
                "D_c/v0 in units.time_unit, e.g. 2.7 (years)",
                err,
            )?;
            if u.time_scale > 1e100 {
                return Err(err(
                    "units.time_scale",
                    format!(
                        "{:e} is too large (physical times would overflow); at most 1e100",
                        u.time_scale
                    ),
                ));
            }
            if u.time_unit.trim().is_empty() {
                return Err(err("units.time_unit", "must name the unit, e.g. \"years\"".into()));
            }
            Some(u)
        }
        None => m.dimensional.map(|d| Units {
            time_unit: "s (if the dimensional input is SI)".into(),
            time_scale: d.d_c / d.v0,
        }),
    };

    let initial = initial_state(&drr, raw.initial.as_ref(), err)?;
    let solver = solver_spec(raw.solver.as_ref(), err)?;
    let analyses = analyses(&raw.analyses, ("drr", 3, Some(gamma * gamma)), err)?;
    papers_model_only(&params, &analyses, err)?;
    if !inertia {
        quasi_dynamic_continuation(analyses.continuation.as_ref(), &raw.analyses, err)?;
    }
    Ok(Scene {
        name: raw.name,
        description: raw.description,
        params,
        dimensional: m.dimensional,
        units,
        scales: m.dimensional.map(|d| PhysicalScales {
            d_c: d.d_c,
            v0: d.v0,
            a_sigma: d.a,
            b_sigma: d.b,
            sigma: None,
            k: d.k,
            reference: None,
        }),
        initial,
        solver,
        analyses,
    })
}

/// η from `model.radiation_damping` (dimensionless) or from `model.dimensional`'s shear
/// modulus G and shear-wave speed c_s: η = G·v0/(2·c_s·A); 0 when neither is given.
fn radiation_damping(
    m: &RawModel,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<f64, SceneError> {
    let from_medium = match m.dimensional {
        Some(Dimensional { shear_modulus: Some(g), shear_wave_speed: Some(c), a, v0, .. }) => {
            let g = positive(
                "model.dimensional.shear_modulus",
                g,
                "the shear modulus G, e.g. 3e10 (Pa)",
                err,
            )?;
            let c = positive(
                "model.dimensional.shear_wave_speed",
                c,
                "the shear-wave speed c_s, e.g. 3e3 (m/s)",
                err,
            )?;
            Some(g * v0 / (2.0 * c * a))
        }
        Some(Dimensional { shear_modulus: Some(_), shear_wave_speed: None, .. }) => {
            return Err(err("model.dimensional.shear_wave_speed", "missing: radiation damping η = G·v0/(2·c_s·A) needs both shear_modulus and shear_wave_speed".into()));
        }
        Some(Dimensional { shear_modulus: None, shear_wave_speed: Some(_), .. }) => {
            return Err(err("model.dimensional.shear_modulus", "missing: radiation damping η = G·v0/(2·c_s·A) needs both shear_modulus and shear_wave_speed".into()));
        }
        _ => None,
    };
    let eta = match (m.radiation_damping, from_medium) {
        (Some(_), Some(_)) => {
            return Err(err("model.radiation_damping", "give either radiation_damping or dimensional.shear_modulus/shear_wave_speed, not both".into()));
        }
        (Some(eta), None) => finite("model.radiation_damping", eta, err)?,
        (None, Some(eta)) => eta,
        (None, None) => 0.0,
    };
    if !(0.0..=1e100).contains(&eta) || !eta.is_finite() {
        return Err(err(
            "model.radiation_damping",
            format!(
                "{eta:e} must be in 0 … 1e100 (η = G·v0/(2·c_s·A) ≥ 0; 0 = no radiation damping)"
            ),
        ));
    }
    Ok(eta)
}

/// Rejects the keys that only the inertial model takes when `"inertia": false`: γ (and the
/// mass that defines it) mean nothing without inertia (a scene asks only for what it needs).
fn no_inertial_keys(
    m: &RawModel,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    let why = "the quasi-dynamic model (\"inertia\": false) has no inertia, so no γ = (D_c/v0)·√(k/M): it is the γ → ∞ limit";
    if m.gamma.is_some() {
        return Err(err(
            "model.gamma",
            format!("{why}; drop \"gamma\" (or drop \"inertia\": false for the inertial model)"),
        ));
    }
    if m.dimensional.is_some_and(|d| d.mass.is_some()) {
        return Err(err(
            "model.dimensional.mass",
            format!("{why}; drop \"mass\" (or drop \"inertia\": false for the inertial model)"),
        ));
    }
    Ok(())
}

/// Continuation of a quasi-dynamic scene: not in γ (it has none), and in η only towards η > 0.
fn quasi_dynamic_continuation(
    c: Option<&ContinuationOptions>,
    raw: &[RawAnalysis],
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    use crate::analysis::continuation::Parameter;
    let Some(c) = c else { return Ok(()) };
    let index = raw
        .iter()
        .position(|a| matches!(a, RawAnalysis::WithOptions(m) if m.contains_key("continuation")))
        .unwrap_or(0);
    let field = format!("analyses[{index}].continuation");
    match c.parameter {
        Parameter::Gamma => Err(err(&format!("{field}.parameter"), "the quasi-dynamic model (\"inertia\": false) has no γ to continue; use \"epsilon\", \"xi\" or \"radiation_damping\"".into())),
        Parameter::Eta if c.to <= 0.0 => Err(err(&format!("{field}.to"), format!("{}: the quasi-dynamic model needs radiation damping η > 0 (at η = 0 v blows up in finite time)", c.to))),
        _ => Ok(()),
    }
}

/// Rejects the analyses derived for the paper's model (slip law, no radiation damping) when
/// the scene has another state law or radiation damping.
fn papers_model_only(
    params: &DrrParams,
    a: &Analyses,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    let inertial_only = [
        (a.noise.is_some(), "noise", "its forcing enters the inertial equation of motion"),
        (
            a.lyapunov.is_some(),
            "lyapunov",
            "its eigenvalues are those of the inertial Jacobian in (u, v, θ)",
        ),
    ];
    if let Some((_, name, why)) = inertial_only.iter().find(|(asked, ..)| *asked && !params.inertia)
    {
        return Err(err(
            "model.inertia",
            format!("the \"{name}\" analysis needs the inertial model ({why}); the quasi-dynamic model (\"inertia\": false) has no inertia: drop \"{name}\" or use an inertial model"),
        ));
    }
    if params.is_papers_model() {
        return Ok(());
    }
    let slip_only = [
        (a.paper, "paper", "the paper's values are for its model"),
        (
            a.asymptotics.is_some(),
            "asymptotics",
            "the slow flow, matching and slip scaling are derived for the slip law",
        ),
    ];
    for (asked, name, why) in slip_only {
        if asked {
            if !params.inertia {
                return Err(err("model.inertia", format!("the \"{name}\" analysis needs the inertial slip-law model without radiation damping ({why}); the quasi-dynamic model (\"inertia\": false) cannot run it: drop \"{name}\"")));
            }
            let field = if params.state_law != StateLaw::Slip {
                "model.state_law"
            } else {
                "model.radiation_damping"
            };
            return Err(err(
                field,
                format!(
                    "the \"{name}\" analysis needs the slip law without radiation damping ({why}); this scene has state_law \"{}\" and radiation_damping {}: drop \"{name}\" or use the slip law with no damping",
                    params.state_law.name(),
                    params.eta
                ),
            ));
        }
    }
    Ok(())
}

/// The start: given values, with v (or u) completed on the slow manifold when missing.
/// Default: v = 0.5, θ at its fixed-point value, u on the slow manifold.
fn initial_state(
    drr: &Drr,
    raw: Option<&RawInitial>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<[f64; 3], SceneError> {
    let theta_star = drr.fixed_point()[2];
    let (u, v, theta) = raw.map_or((None, None, None), |r| (r.u, r.v, r.theta));
    if !drr.params().inertia && u.is_some() && v.is_some() {
        return Err(err("initial.v", "the quasi-dynamic model (\"inertia\": false) has no inertia: the force balance u + (θ + f(v) + ηv)/ξ = 0 gives v from u and θ (and u from v and θ); give u or v, not both".into()));
    }
    let theta = finite("initial.theta", theta.unwrap_or(theta_star), err)?;
    let w = match v {
        Some(v) => positive("initial.v", v, "a velocity in units of v0, e.g. 0.5", err)?.ln(),
        None => match u {
            Some(u) => drr.manifold_w(finite("initial.u", u, err)?, theta).ok_or_else(|| {
                err("initial.v", format!("no point of the slow manifold has u = {u}, θ = {theta} for this friction law; give v"))
            })?,
            None => 0.5f64.ln(),
        },
    };
    let u = match u {
        Some(u) => finite("initial.u", u, err)?,
        None => drr.manifold_u(w, theta),
    };
    if !(u.is_finite() && w.is_finite() && w.exp().is_finite() && w.exp() > 0.0) {
        return Err(err("initial", format!("the start (u, ln v, θ) = ({u}, {w}, {theta}) is not representable; keep |u|, |θ| and |ln v| well below 700")));
    }
    Ok([u, w, theta])
}

fn solver_spec(
    raw: Option<&RawSolver>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<SolverSpec, SceneError> {
    let method = match raw.and_then(|r| r.method.as_deref()) {
        None => Method::CvodeBdf,
        Some(name) => name.parse::<Method>().map_err(|e| err("solver.method", e.to_string()))?,
    };
    let rtol = positive("solver.rtol", raw.and_then(|r| r.rtol).unwrap_or(1e-8), "e.g. 1e-8", err)?;
    let atol = match raw.and_then(|r| r.atol.clone()) {
        None => [rtol * 1e-2; 3],
        Some(RawAtol::Scalar(a)) => [a; 3],
        Some(RawAtol::PerComponent(v)) => {
            let arr: [f64; 3] = v.clone().try_into().map_err(|_| {
                err(
                    "solver.atol",
                    format!(
                        "{v:?} has {} values; give one number or three (for u, ln v, θ)",
                        v.len()
                    ),
                )
            })?;
            arr
        }
    };
    for (i, a) in atol.iter().enumerate() {
        let a = finite(&format!("solver.atol[{i}]"), *a, err)?;
        if a < 0.0 {
            return Err(err(&format!("solver.atol[{i}]"), format!("{a} must be ≥ 0")));
        }
    }
    let table = raw.and_then(|r| r.table.clone());
    let explicit_table = raw.and_then(|r| r.explicit_table.clone());
    let check_table = |field: &str,
                       name: &Option<String>,
                       known: &mut dyn Iterator<Item = &'static str>| {
        let list: Vec<&str> = known.collect();
        match name {
            Some(n) if !list.contains(&n.as_str()) => {
                Err(err(field, format!("unknown table \"{n}\"; available: {}", list.join(", "))))
            }
            _ => Ok(()),
        }
    };
    use crate::sundials::{DirkTable, ErkTable};
    match method {
        Method::ArkodeDirk | Method::ArkodeImex => {
            check_table("solver.table", &table, &mut DirkTable::names())?
        }
        Method::ArkodeErk => check_table("solver.table", &table, &mut ErkTable::names())?,
        _ if table.is_some() => {
            return Err(err("solver.table", format!("{} takes no Butcher table", method.name())))
        }
        _ => {}
    }
    if explicit_table.is_some() && method != Method::ArkodeImex {
        return Err(err(
            "solver.explicit_table",
            "only \"arkode-imex\" takes an explicit table".into(),
        ));
    }
    check_table("solver.explicit_table", &explicit_table, &mut ErkTable::names())?;
    if method == Method::ArkodeImex && explicit_table.is_none() {
        if let Some(t) = &table {
            if ErkTable::from_name(&t.replace("_DIRK_", "_ERK_")).is_none() {
                return Err(err("solver.table", format!("\"{t}\" has no explicit partner; use an ARK pair (e.g. ARK436L2SA_DIRK_6_3_4) or give solver.explicit_table")));
            }
        }
    }
    if raw.and_then(|r| r.max_steps).is_some() {
        return Err(err(
            "solver.max_steps",
            "set the step budget with {\"cycle\": {\"max_steps\": N}}".into(),
        ));
    }
    Ok(SolverSpec { method, rtol, atol, table, explicit_table })
}

/// `model`: (kind, dimension, γ² for the DRR), for the noise options.
fn analyses(
    raw: &[RawAnalysis],
    model: (&str, usize, Option<f64>),
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Analyses, SceneError> {
    let mut out = Analyses::default();
    if raw.is_empty() {
        return Err(err("analyses", format!("is empty; ask for at least one of {ANALYSIS_NAMES}")));
    }
    for (i, entry) in raw.iter().enumerate() {
        let field = format!("analyses[{i}]");
        let (name, options) = match entry {
            RawAnalysis::Name(n) => (n.clone(), None),
            RawAnalysis::WithOptions(map) if map.len() == 1 => {
                let (n, v) = map.iter().next().expect("one entry");
                (n.clone(), Some(v.clone()))
            }
            RawAnalysis::WithOptions(_) => {
                return Err(err(
                    &field,
                    format!(
                        "an object entry must have exactly one key; use one of {ANALYSIS_NAMES}"
                    ),
                ));
            }
        };
        let options_of = |what: &str| -> Result<serde_json::Value, SceneError> {
            Ok(options.clone().unwrap_or(serde_json::Value::Object(Default::default()))).and_then(
                |v| {
                    if v.is_object() {
                        Ok(v)
                    } else {
                        Err(err(&format!("{field}.{what}"), "options must be an object".into()))
                    }
                },
            )
        };
        match name.as_str() {
            "hopf" | "paper" if options.is_some() => {
                return Err(err(&field, format!("\"{name}\" takes no options")))
            }
            "hopf" => out.hopf = true,
            "paper" => out.paper = true,
            "cycle" => {
                let o = CycleOptions::from_json(options_of("cycle")?)
                    .map_err(|e| err(&e.path_below(&format!("{field}.cycle")), e.message))?;
                out.cycle = Some(o);
            }
            "trajectory" => {
                let Some(v) = options.clone() else {
                    return Err(err(
                        &field,
                        "\"trajectory\" needs a sampling spec: {\"trajectory\": {\"cycles\": N}}"
                            .into(),
                    ));
                };
                let t: RawTrajectory = serde_json::from_value(v)
                    .map_err(|e| err(&format!("{field}.trajectory"), e.to_string()))?;
                if t.cycles == 0 || t.cycles > 10_000 {
                    return Err(err(
                        &format!("{field}.trajectory.cycles"),
                        format!("{} must be between 1 and 10000", t.cycles),
                    ));
                }
                out.trajectory_cycles = Some(t.cycles);
            }
            "asymptotics" => {
                let o = crate::analysis::asymptotics::AsymptoticsOptions::from_json(options_of(
                    "asymptotics",
                )?)
                .map_err(|e| err(&e.path_below(&format!("{field}.asymptotics")), e.message))?;
                out.asymptotics = Some(o);
            }
            "lyapunov" => {
                let o =
                    crate::analysis::lyapunov::LyapunovOptions::from_json(options_of("lyapunov")?)
                        .map_err(|e| err(&e.path_below(&format!("{field}.lyapunov")), e.message))?;
                out.lyapunov = Some(o);
            }
            "shooting" => {
                let o = ShootingOptions::from_json(options_of("shooting")?)
                    .map_err(|e| err(&e.path_below(&format!("{field}.shooting")), e.message))?;
                out.shooting = Some(o);
            }
            "continuation" => {
                use crate::analysis::continuation::Parameter;
                let Some(v) = options.clone() else {
                    return Err(err(&field, "\"continuation\" needs {\"parameter\": \"epsilon\", \"to\": 1.2, \"points\": 51}".into()));
                };
                let f = format!("{field}.continuation");
                let c: RawContinuation =
                    serde_json::from_value(v).map_err(|e| err(&f, e.to_string()))?;
                let parameter = match c.parameter.as_str() {
                    "epsilon" => Parameter::Epsilon,
                    "xi" => Parameter::Xi,
                    "gamma" => Parameter::Gamma,
                    "radiation_damping" => Parameter::Eta,
                    other => return Err(err(&format!("{f}.parameter"), format!("\"{other}\" cannot be continued; use \"epsilon\", \"xi\", \"gamma\" or \"radiation_damping\""))),
                };
                let to = finite(&format!("{f}.to"), c.to, err)?;
                if parameter == Parameter::Eta && to < 0.0 {
                    return Err(err(
                        &format!("{f}.to"),
                        format!("{to} must be ≥ 0 for radiation_damping"),
                    ));
                }
                if !matches!(parameter, Parameter::Epsilon | Parameter::Eta) && to <= 0.0 {
                    return Err(err(
                        &format!("{f}.to"),
                        format!("{to} must be > 0 for {}", parameter.name()),
                    ));
                }
                if parameter == Parameter::Gamma && !(1e-100..=1e100).contains(&to) {
                    return Err(err(
                        &format!("{f}.to"),
                        format!("{to:e} is outside 1e-100 … 1e100"),
                    ));
                }
                if !(2..=100_000).contains(&c.points) {
                    return Err(err(
                        &format!("{f}.points"),
                        format!("{} must be between 2 and 100000", c.points),
                    ));
                }
                let log = c.log.unwrap_or(parameter == Parameter::Gamma);
                if log && parameter == Parameter::Epsilon {
                    return Err(err(
                        &format!("{f}.log"),
                        "ε can be negative: continue it on a linear grid (\"log\": false)".into(),
                    ));
                }
                if log && parameter == Parameter::Eta {
                    return Err(err(
                        &format!("{f}.log"),
                        "η can be 0: continue it on a linear grid (\"log\": false)".into(),
                    ));
                }
                out.continuation =
                    Some(ContinuationOptions { parameter, to, points: c.points, log });
            }
            "noise" => {
                let Some(v) = options.clone() else {
                    return Err(err(&field, "\"noise\" needs its amplitudes: {\"noise\": {\"amplitudes\": [...]}} (docs/noise.md)".into()));
                };
                let o: NoiseOptions = serde_path_to_error::deserialize(v).map_err(|e| {
                    let path = e.path().to_string();
                    let sub = if path == "." { String::new() } else { format!(".{path}") };
                    err(&format!("{field}.noise{sub}"), e.into_inner().to_string())
                })?;
                let (kind, dim, gamma2) = model;
                noise_options::validate(&o, dim, kind, gamma2)
                    .map_err(|e| err(&e.path_below(&format!("{field}.noise")), e.message))?;
                out.noise = Some(o);
            }
            "time_series" => {
                let Some(v) = options.clone() else {
                    return Err(err(&field, "\"time_series\" needs its length: {\"time_series\": {\"t_max\": T}} (T in the scene's time unit; docs/scenes.md)".into()));
                };
                if !v.is_object() {
                    return Err(err(
                        &format!("{field}.time_series"),
                        "options must be an object, e.g. {\"t_max\": 1000}".into(),
                    ));
                }
                let o = TimeSeriesOptions::from_json(v)
                    .map_err(|e| err(&e.path_below(&format!("{field}.time_series")), e.message))?;
                out.time_series = Some(o);
            }
            other => {
                return Err(err(
                    &field,
                    format!("unknown analysis \"{other}\"; use one of {ANALYSIS_NAMES}"),
                ))
            }
        }
    }
    if out.trajectory_cycles.is_some() && out.cycle.is_none() {
        return Err(err(
            "analyses",
            "\"trajectory\" records the cycles found by \"cycle\"; add \"cycle\"".into(),
        ));
    }
    for (asked, name) in
        [(out.asymptotics.is_some(), "asymptotics"), (out.lyapunov.is_some(), "lyapunov")]
    {
        if asked && out.cycle.is_none() {
            return Err(err(
                "analyses",
                format!("\"{name}\" works on the limit cycle found by \"cycle\"; add \"cycle\""),
            ));
        }
    }
    if out.paper && (out.cycle.is_none() || !out.hopf) {
        return Err(err(
            "analyses",
            "\"paper\" compares hopf and cycle results; add \"hopf\" and \"cycle\"".into(),
        ));
    }
    Ok(out)
}
