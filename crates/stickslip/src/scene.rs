//! Scenes: what to compute, as JSON. Parsing rejects unknown keys and wrong types (naming the
//! path); validation rejects values outside the model's domain (naming the field and what
//! would be valid). The schema is documented in docs/scenes.md.

use crate::analysis::cycle::CycleOptions;
use crate::analysis::noise::options::NoiseOptions;
use crate::analysis::shooting::ShootingOptions;
use crate::analysis::time_series::TimeSeriesOptions;
use crate::model::{
    Drr, DrrParams, Friction, FrictionReference, ModelKind, PeriodicLoading, PhysicalScales,
    SaddleNodeParams, StateLaw, VanDerPolParams,
};
pub use crate::solver::{Method, SolverSpec};
use serde::{Deserialize, Serialize};

mod analyses;
pub mod lab;
pub mod qdyn_input;
mod solver_block;
pub use analyses::{analysis_names, AnalysisKind};
use solver_block::RawSolver;
pub use solver_block::{
    SolverDefaults, CHOSEN_BY_DEFAULT, CHOSEN_BY_SCENE, DEFAULT_METHOD, DEFAULT_RTOL,
    LAB_CHOSEN_BY_DEFAULT, LAB_DEFAULTS, LAB_DEFAULT_RTOL, SPRING_SLIDER_DEFAULTS,
};

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
    /// "slip" (default), "ageing", "prz" or "no_healing".
    #[serde(default)]
    state_law: Option<String>,
    /// Radiation damping η (dimensionless, ≥ 0).
    #[serde(default)]
    radiation_damping: Option<f64>,
    /// false: the quasi-dynamic model (no inertia; needs η > 0, takes no γ). Default true.
    #[serde(default)]
    inertia: Option<bool>,
    /// Periodic loading, dimensionless (amplitude in A = aσ, period in D_c/v0).
    #[serde(default)]
    periodic_loading: Option<PeriodicLoadingInput>,
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

/// Dimensional parameters in the field's terms (any consistent units, SI in the docs; per unit
/// area of the interface), as in QDYN's spring-block: the friction coefficients a, b with the
/// effective normal stress σ (or A = aσ, B = bσ directly as `a_sigma`, `b_sigma`), D_c, the
/// loading velocity v0, the stiffness k (or G/L), the mass M for inertia, G and c_s for
/// radiation damping and optionally μ0 at V_ref. They give
/// γ = (D_c/v0)·√(k/M), ξ = k·D_c/(aσ), ε = b/a − 1 and η = G·v0/(2·c_s·aσ)
/// (docs/from-qdyn.md).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dimensional {
    /// Direct-effect friction coefficient a (dimensionless; needs `sigma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<f64>,
    /// State-effect friction coefficient b (dimensionless; needs `sigma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<f64>,
    /// Effective normal stress σ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// A = aσ in stress units (instead of `a` with `sigma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a_sigma: Option<f64>,
    /// B = bσ in stress units (instead of `b` with `sigma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b_sigma: Option<f64>,
    /// Critical slip distance D_c.
    pub d_c: f64,
    /// Loading velocity v0 (QDYN's V_pl).
    pub v0: f64,
    /// Spring stiffness k (or `shear_modulus` with `length`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// Length L of the slipping patch: k = G/L with `shear_modulus` (instead of `k`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<f64>,
    /// Block mass M (absent in a quasi-dynamic scene, which has no inertia).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Shear modulus G of the surrounding medium (radiation damping with `shear_wave_speed`;
    /// stiffness with `length`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_modulus: Option<f64>,
    /// Shear-wave speed c_s (radiation damping; with `shear_modulus`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_wave_speed: Option<f64>,
    /// The unit system of these values: "SI" (Pa, m, m/s, s) lets reports state their units;
    /// absent, any consistent system is accepted and the units are left to the reader.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_system: Option<UnitSystem>,
    /// The radiation-damping coefficient η_dim = G/(2c_s) in stress per velocity (e.g. Pa·s/m),
    /// instead of `shear_modulus` with `shear_wave_speed`: η = η_dim·v0/(aσ).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiation_damping: Option<f64>,
    /// μ0, the steady-state friction coefficient at `v_ref` (with `v_ref` and σ).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu0: Option<f64>,
    /// V_ref, the velocity at which the steady-state friction is `mu0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_ref: Option<f64>,
    /// Periodic loading (QDYN's APER, TPER): the amplitude A_per in stress units, the period
    /// T_per in time units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periodic_loading: Option<PeriodicLoadingInput>,
}

/// A shear stress amplitude·sin(2πt/period) added to the spring's load (QDYN's APER, TPER),
/// t from the start of the run: dimensionless under `model.periodic_loading` (amplitude in
/// A = aσ, period in D_c/v0), in the input's units under `model.dimensional.periodic_loading`
/// (A_per in stress units, e.g. Pa, T_per in time units, e.g. s).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PeriodicLoadingInput {
    /// The stress amplitude (a_per or A_per).
    pub amplitude: f64,
    /// The period (T or T_per), > 0.
    pub period: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum RawFriction {
    Log,
    Asinh,
    Power {
        alpha: f64,
    },
    /// QDYN's cut-off velocity law: v1 = V1/v0, v2 = V2/v0, or in a dimensional scene the
    /// velocities V1, V2 themselves.
    CutOff {
        #[serde(default)]
        v1: Option<f64>,
        #[serde(default)]
        v2: Option<f64>,
        #[serde(default)]
        velocity_1: Option<f64>,
        #[serde(default)]
        velocity_2: Option<f64>,
        /// μ* (dimensional scenes, optional): the absolute level μ = μ* + aΦ, which only
        /// shifts μ (for QDYN's output files' τ).
        #[serde(default)]
        mu_star: Option<f64>,
    },
    /// QDYN's regularised law: f* = μ*/a and v* = V*/v0, or in a dimensional scene μ* and V*.
    Regularised {
        #[serde(default)]
        f_star: Option<f64>,
        #[serde(default)]
        v_star: Option<f64>,
        #[serde(default)]
        mu_star: Option<f64>,
        #[serde(default)]
        velocity_star: Option<f64>,
    },
}

/// A declared unit system for `model.dimensional`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
pub enum UnitSystem {
    /// Pa, m, m/s, s (and Pa·s/m for `radiation_damping`).
    #[serde(rename = "SI")]
    Si,
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
    /// The slip rate V (velocity units; with `model.dimensional`), instead of v = V/v0.
    velocity: Option<f64>,
    /// The state Θ (time units; with `model.dimensional`), instead of θ = (b/a) ln(v0Θ/D_c).
    state: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
enum RawAnalysis {
    Name(String),
    WithOptions(std::collections::BTreeMap<String, serde_json::Value>),
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
    pub asymptotics: Option<crate::paper::asymptotics::AsymptoticsOptions>,
    /// Local and finite-time Lyapunov exponents along the cycle (needs "cycle").
    pub lyapunov: Option<crate::paper::lyapunov::LyapunovOptions>,
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
    /// Derived parameters far outside the physical range, each naming its input fields
    /// (reported in the report's `warnings` and on stderr).
    pub warnings: Vec<String>,
    /// Initial state (u, ln v, θ).
    pub initial: [f64; 3],
    /// Solver settings.
    pub solver: SolverSpec,
    /// Why this solver runs: the scene's block, or the defaults and why (the report's
    /// `solver.chosen_by`; [`DEFAULT_METHOD`]).
    pub solver_chosen_by: String,
    /// Requested analyses.
    pub analyses: Analyses,
    /// Periodic loading (dimensionless), when given with a non-zero amplitude: the system is
    /// then forced and only the "time_series" analysis runs (see docs/scenes.md).
    pub loading: Option<PeriodicLoading>,
}

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

impl OtherModel {
    /// Its kind (the report's "kind").
    pub fn kind(&self) -> ModelKind {
        match self {
            OtherModel::SaddleNode { .. } => ModelKind::SaddleNode,
            OtherModel::VanDerPol { .. } => ModelKind::VanDerPol,
        }
    }
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
    /// A laboratory scene (`"kind": "lab"`, [`lab`]).
    Lab(Box<lab::LabScene>),
}

impl AnyScene {
    /// The scene's name.
    pub fn name(&self) -> &str {
        match self {
            AnyScene::Drr(s) => &s.name,
            AnyScene::Other(s) => &s.name,
            AnyScene::Lab(s) => &s.name,
        }
    }
}

/// Parses and validates a scene of any model kind (`"model": {"kind": ...}`).
pub fn parse_any(text: &str, source_name: &str) -> Result<AnyScene, SceneError> {
    let err = |field: &str, message: String| SceneError {
        source_name: source_name.into(),
        field: field.into(),
        message,
    };
    let json = json(text, &err)?;
    if json["model"]["kind"].as_str() == Some(lab::KIND) {
        return lab::from_json(&json, source_name).map(|s| AnyScene::Lab(Box::new(s)));
    }
    let raw: RawScene = deserialize(&json, &err)?;
    match raw.model.kind.as_deref().map(ModelKind::from_name) {
        None | Some(Some(ModelKind::Drr)) => {
            validate(raw, &err).map(|s| AnyScene::Drr(Box::new(s)))
        }
        Some(_) => validate_other(raw, &err).map(|s| AnyScene::Other(Box::new(s))),
    }
}

/// The scene text as JSON: the one parse of the text (a syntax error names the document).
fn json(
    text: &str,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<serde_json::Value, SceneError> {
    serde_json::from_str(text).map_err(|e| err("(document)", e.to_string()))
}

/// A scene's raw form from its JSON, an error naming the path of the field at fault.
fn deserialize<T: serde::de::DeserializeOwned>(
    json: &serde_json::Value,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<T, SceneError> {
    serde_path_to_error::deserialize(json).map_err(|e| {
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
        ("periodic_loading", m.periodic_loading.is_some()),
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
    let name = m.kind.as_deref().unwrap_or(ModelKind::Drr.name());
    let kind = ModelKind::from_name(name);
    let model = match kind {
        Some(ModelKind::SaddleNode) => {
            only_model_keys(m, name, &["mu0", "r", "x0"], err)?;
            let mu0 = positive("model.mu0", m.mu0.ok_or_else(|| err("model.mu0", "missing: μ at t = 0, > 0, e.g. 1".into()))?, "μ(0), e.g. 1", err)?;
            let r = positive("model.r", m.r.ok_or_else(|| err("model.r", "missing: the tilting rate r > 0 of μ = μ0 − r t, e.g. 0.01".into()))?, "e.g. 0.01", err)?;
            let x0 = positive("model.x0", m.x0.unwrap_or(mu0.sqrt()), "the start on the stable branch x = √μ0 (default)", err)?;
            OtherModel::SaddleNode { params: SaddleNodeParams { mu0, r }, x0 }
        }
        Some(ModelKind::VanDerPol) => {
            only_model_keys(m, name, &["beta", "a", "x0", "y0"], err)?;
            let beta = positive("model.beta", m.beta.ok_or_else(|| err("model.beta", "missing: β > 0 (β² is the fast rate), e.g. 30".into()))?, "e.g. 30", err)?;
            let a = finite("model.a", m.a.unwrap_or(0.0), err)?;
            if a.abs() >= 1.0 {
                return Err(err("model.a", format!("{a}: |a| must be < 1 for a relaxation oscillation (the fixed point x = −a on the unstable middle branch)")));
            }
            let x0 = finite("model.x0", m.x0.unwrap_or(2.0), err)?;
            let y0 = finite("model.y0", m.y0.unwrap_or(-2.0 / 3.0), err)?;
            OtherModel::VanDerPol { params: VanDerPolParams { beta, a }, initial: [x0, y0] }
        }
        Some(ModelKind::Drr) | None => return Err(err("model.kind", format!("unknown kind \"{name}\"; use \"drr\" (default), \"saddle_node\" or \"van_der_pol\""))),
    };
    let kind = model.kind();
    for (field, present) in [
        ("initial", raw.initial.is_some()),
        ("units", raw.units.is_some()),
        ("solver", raw.solver.is_some()),
    ] {
        if present {
            return Err(err(field, format!("the {kind} model takes no \"{field}\" (its start is model.x0{}; the noise analysis sets its own solver)", if kind == ModelKind::VanDerPol { "/y0" } else { "" })));
        }
    }
    let analyses = analyses::parse(&raw.analyses, (kind, kind.dimension(), None), err)?;
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
    let raw: RawScene = deserialize(&json(text, &err)?, &err)?;
    if let Some(kind) = raw.model.kind.as_deref().filter(|k| *k != ModelKind::Drr.name()) {
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
        ModelKind::Drr.name(),
        &[
            "gamma",
            "xi",
            "epsilon",
            "dimensional",
            "friction",
            "state_law",
            "radiation_damping",
            "inertia",
            "periodic_loading",
        ],
        err,
    )?;
    let inertia = m.inertia.unwrap_or(true);
    if !inertia {
        no_inertial_keys(m, err)?;
    }
    let scales = m.dimensional.as_ref().map(|d| dimensional_scales(d, err)).transpose()?;
    let (gamma, xi, epsilon) = match (m.dimensional.zip(scales), m.gamma, m.xi, m.epsilon) {
        (Some((d, s)), None, None, None) => {
            let gamma = if inertia {
                let mass = d.mass.ok_or_else(|| err("model.dimensional.mass", "missing: the block mass M (per unit area), or \"inertia\": false for the quasi-dynamic model".into()))?;
                let mass = positive("model.dimensional.mass", mass, "a physical parameter", err)?;
                s.time_scale() * (s.k / mass).sqrt()
            } else {
                f64::INFINITY
            };
            (gamma, s.k * s.d_c / s.a_sigma, (s.b_sigma - s.a_sigma) / s.a_sigma)
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
                    "missing {} (or give \"dimensional\": {{a, b, sigma, d_c, v0, k, mass}})",
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
    let friction =
        friction_law(m.friction.clone().unwrap_or(RawFriction::Log), scales.as_ref(), err)?;
    let scales = cut_off_mu_star(m.friction.as_ref(), scales, err)?;
    let state_law = match m.state_law.as_deref() {
        None => StateLaw::Slip,
        Some(name) => StateLaw::from_name(name).ok_or_else(|| {
            let names: Vec<String> =
                StateLaw::ALL.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            let lab = if name == "nagata" {
                " (the nagata law is the laboratory model's, \"kind\": \"lab\")"
            } else {
                ""
            };
            err(
                "model.state_law",
                format!(
                    "\"{name}\" is not a state law of this model{lab}; use one of {} (default \"slip\"; also \"aging\", \"dieterich\", \"ruina\")",
                    names.join(", ")
                ),
            )
        })?,
    };
    let eta = radiation_damping(m, scales.as_ref(), err)?;
    if !inertia && eta == 0.0 {
        return Err(err(
            "model.radiation_damping",
            "the quasi-dynamic model (\"inertia\": false) needs radiation damping η > 0: without it the force balance u + (θ + f(v))/ξ = 0 has no solution once the stress outruns f, and v blows up in finite time; give radiation_damping > 0 (e.g. 0.05) or dimensional.shear_modulus and shear_wave_speed".into(),
        ));
    }
    let params = DrrParams { gamma, xi, epsilon, friction, state_law, eta, inertia };
    if scales.is_some_and(|s| s.reference.is_some()) && friction != Friction::Log {
        return Err(err("model.dimensional.mu0", format!("μ0 at v_ref defines μ = μ0 + a ln(V/V_ref) + b ln(ΘV_ref/D_c), the logarithmic friction law; this scene's friction is {}: drop mu0 and v_ref (shear stress is then reported relative to steady sliding at v0)", friction.label())));
    }
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
        None => scales.map(|s| Units {
            time_unit: match m.dimensional.and_then(|d| d.unit_system) {
                Some(UnitSystem::Si) => "s",
                None => "s (if the dimensional input is SI)",
            }
            .into(),
            time_scale: s.time_scale(),
        }),
    };

    let field_initial =
        raw.initial.as_ref().map(|r| field_start(r, scales.as_ref(), &params, err)).transpose()?;
    let initial = initial_state(&drr, field_initial.as_ref().or(raw.initial.as_ref()), err)?;
    let (solver, solver_chosen_by) =
        solver_block::parse(raw.solver.as_ref(), &SPRING_SLIDER_DEFAULTS, err)?
            .spring_slider(err)?;
    let analyses = analyses::parse(
        &raw.analyses,
        (ModelKind::Drr, ModelKind::Drr.dimension(), Some(gamma * gamma)),
        err,
    )?;
    if !state_law.heals() {
        no_healing_analyses(&analyses, &raw.analyses, err)?;
    }
    papers_model_only(&params, &analyses, err)?;
    let loading = periodic_loading(m, scales.as_ref(), &analyses, err)?;
    if !inertia {
        quasi_dynamic_continuation(analyses.continuation.as_ref(), &raw.analyses, err)?;
    }
    Ok(Scene {
        name: raw.name,
        description: raw.description,
        params,
        dimensional: m.dimensional,
        units,
        scales,
        warnings: m
            .dimensional
            .zip(scales)
            .map_or_else(Vec::new, |(d, s)| field_warnings(&d, &s, &params)),
        initial,
        solver,
        solver_chosen_by,
        analyses,
        loading,
    })
}

/// The dimensionless periodic loading from `model.periodic_loading` (dimensionless scenes) or
/// `model.dimensional.periodic_loading` (a_per = A_per/(aσ), T = T_per·v0/D_c); None when
/// absent or of zero amplitude. A forced system runs only "time_series" (with its event
/// catalogue and the locking to the forcing): the other analyses assume an autonomous system
/// (a fixed point, a limit cycle, its period and Floquet multipliers).
fn periodic_loading(
    m: &RawModel,
    scales: Option<&PhysicalScales>,
    analyses: &Analyses,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Option<PeriodicLoading>, SceneError> {
    let dimensional = m.dimensional.and_then(|d| d.periodic_loading);
    let (input, field, to_dimensionless) = match (m.periodic_loading, dimensional, scales) {
        (Some(_), _, Some(_)) => {
            return Err(err("model.periodic_loading", "a dimensional scene gives its periodic loading in its own units, as model.dimensional.periodic_loading {\"amplitude\": A_per (stress), \"period\": T_per (time)}".into()));
        }
        (Some(p), None, None) => (p, "model.periodic_loading", (1.0, 1.0)),
        (None, Some(p), Some(s)) => {
            (p, "model.dimensional.periodic_loading", (s.a_sigma, s.time_scale()))
        }
        _ => return Ok(None),
    };
    let amplitude = finite(&format!("{field}.amplitude"), input.amplitude, err)?;
    let period = positive(
        &format!("{field}.period"),
        input.period,
        "the forcing period, e.g. 3 times the unforced cycle's",
        err,
    )?;
    if amplitude == 0.0 {
        return Ok(None);
    }
    let loading = PeriodicLoading {
        amplitude: amplitude / to_dimensionless.0,
        period: period / to_dimensionless.1,
    };
    if !(loading.amplitude.is_finite() && loading.period.is_finite() && loading.period > 0.0) {
        return Err(err(
            field,
            format!(
                "{input:?} is {loading:?} in units of A and D_c/v0: out of the range of doubles"
            ),
        ));
    }
    let autonomous_only = [
        (analyses.hopf, AnalysisKind::Hopf),
        (analyses.cycle.is_some(), AnalysisKind::Cycle),
        (analyses.paper, AnalysisKind::Paper),
        (analyses.shooting.is_some(), AnalysisKind::Shooting),
        (analyses.continuation.is_some(), AnalysisKind::Continuation),
        (analyses.asymptotics.is_some(), AnalysisKind::Asymptotics),
        (analyses.lyapunov.is_some(), AnalysisKind::Lyapunov),
        (analyses.noise.is_some(), AnalysisKind::Noise),
    ];
    if let Some((_, name)) = autonomous_only.iter().find(|(asked, _)| *asked) {
        return Err(err("analyses", format!("the \"{name}\" analysis assumes an autonomous system (a fixed point, a limit cycle and its period), and {field} forces this one; a forced scene runs \"time_series\", whose report gives the event catalogue and the locking to the forcing (drop \"{name}\", or the periodic loading)")));
    }
    if analyses.time_series.is_none() {
        return Err(err("analyses", format!("a forced scene ({field}) runs the \"time_series\" analysis (its event catalogue and the locking to the forcing); add {{\"time_series\": {{\"t_max\": ...}}}}")));
    }
    Ok(Some(loading))
}

/// The friction law from `model.friction`: QDYN's laws take dimensionless velocities (v1, v2,
/// v*) and f* = μ*/a in a dimensionless scene, velocities (velocity_1, velocity_2,
/// velocity_star) and μ* (`mu_star`, with σ) in a dimensional one.
fn friction_law(
    raw: RawFriction,
    scales: Option<&PhysicalScales>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Friction, SceneError> {
    // One input of a pair, dimensionless (`plain`) or dimensional (`field`), by the scene's
    // form; the value in units of v0 (velocities) or of a (μ*).
    let pick = |law: &str,
                (plain, plain_value): (&'static str, Option<f64>),
                (field, field_value): (&'static str, Option<f64>),
                hint: &str|
     -> Result<(f64, &'static str), SceneError> {
        let (name, wrong, value) = if scales.is_some() {
            (field, (plain, plain_value), field_value)
        } else {
            (plain, (field, field_value), plain_value)
        };
        let path = |n: &str| format!("model.friction.{law}.{n}");
        if wrong.1.is_some() {
            let form = if scales.is_some() { "a dimensional" } else { "a dimensionless" };
            return Err(err(
                &path(wrong.0),
                format!("{form} scene gives {name} here, not {} ({hint})", wrong.0),
            ));
        }
        let value = value.ok_or_else(|| err(&path(name), format!("missing ({hint})")))?;
        Ok((finite(&path(name), value, err)?, name))
    };
    let velocity =
        |law: &str, plain: (&'static str, Option<f64>), field: (&'static str, Option<f64>)| {
            let hint = "a velocity: v = V/v0 in a dimensionless scene, V in a dimensional one";
            let (value, name) = pick(law, plain, field, hint)?;
            let value = positive(&format!("model.friction.{law}.{name}"), value, hint, err)?;
            Ok::<f64, SceneError>(scales.map_or(value, |s| value / s.v0))
        };
    Ok(match raw {
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
        RawFriction::CutOff { v1, v2, velocity_1, velocity_2, .. } => Friction::CutOff {
            v1: velocity("cut_off", ("v1", v1), ("velocity_1", velocity_1))?,
            v2: velocity("cut_off", ("v2", v2), ("velocity_2", velocity_2))?,
        },
        RawFriction::Regularised { f_star, v_star, mu_star, velocity_star } => {
            let hint = "μ*/a in a dimensionless scene (f_star, e.g. 60), μ* in a dimensional one (mu_star, e.g. 0.6, with sigma)";
            let (value, _) = pick("regularised", ("f_star", f_star), ("mu_star", mu_star), hint)?;
            let f_star = match scales {
                None => value,
                Some(s) => {
                    let (a, _) = s.friction_coefficients().ok_or_else(|| {
                        err("model.dimensional.sigma", "missing: mu_star is a friction coefficient; f* = μ*/a needs a and sigma (not a_sigma alone)".into())
                    })?;
                    value / a
                }
            };
            Friction::Regularised {
                f_star,
                v_star: velocity(
                    "regularised",
                    ("v_star", v_star),
                    ("velocity_star", velocity_star),
                )?,
            }
        }
    })
}

/// The scales with the cut-off law's μ* (`model.friction.cut_off.mu_star`) when given: a
/// friction coefficient, so only in a dimensional scene with `a` and `sigma`.
fn cut_off_mu_star(
    raw: Option<&RawFriction>,
    scales: Option<PhysicalScales>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Option<PhysicalScales>, SceneError> {
    let Some(RawFriction::CutOff { mu_star: Some(mu_star), .. }) = raw else { return Ok(scales) };
    let field = "model.friction.cut_off.mu_star";
    let mu_star = finite(field, *mu_star, err)?;
    match scales {
        Some(s) if s.friction_coefficients().is_some() => {
            Ok(Some(PhysicalScales { mu_star: Some(mu_star), ..s }))
        }
        _ => Err(err(field, "μ* is a friction coefficient: it needs model.dimensional with a, b and sigma (a dimensionless scene's cut-off law has no absolute level)".into())),
    }
}

/// The physical scales from `model.dimensional`: A and B from a, b with σ or from a_sigma,
/// b_sigma; k directly or as G/L; μ0 with V_ref. Each missing or conflicting key is named.
fn dimensional_scales(
    d: &Dimensional,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<PhysicalScales, SceneError> {
    let field = |name: &str| format!("model.dimensional.{name}");
    let phys = |name: &str, v: f64, hint: &str| positive(&field(name), v, hint, err);
    let d_c = phys("d_c", d.d_c, "the critical slip distance D_c, e.g. 1e-4 (m)")?;
    let v0 = phys("v0", d.v0, "the loading velocity V_pl, e.g. 1e-9 (m/s)")?;
    let sigma = d
        .sigma
        .map(|s| phys("sigma", s, "the effective normal stress σ, e.g. 1e7 (Pa)"))
        .transpose()?;
    let coefficient = |name: &str, stress_name: &str, value: Option<f64>, stress: Option<f64>| {
        match (value, stress, sigma) {
            (Some(_), Some(_), _) => Err(err(
                &field(name),
                format!("give {name} (a friction coefficient, with sigma) or {stress_name} (= {name}σ in stress units), not both"),
            )),
            (Some(c), None, Some(s)) => {
                Ok(phys(name, c, "a dimensionless friction coefficient, e.g. 0.01")? * s)
            }
            (Some(_), None, None) => Err(err(
                &field("sigma"),
                format!("missing: {name} is a dimensionless friction coefficient (e.g. 0.01) and needs the effective normal stress sigma beside it (e.g. 1e7 Pa); to give the coefficients in stress units use a_sigma and b_sigma (A = aσ, B = bσ) instead"),
            )),
            (None, Some(st), _) => phys(stress_name, st, "a stress, e.g. 1e5 (Pa)"),
            (None, None, _) => Err(err(
                &field(name),
                format!("missing: give the friction coefficient {name} with sigma, e.g. \"a\": 0.01, \"b\": 0.015, \"sigma\": 1e7 (or {stress_name} in stress units)"),
            )),
        }
    };
    let a_sigma = coefficient("a", "a_sigma", d.a, d.a_sigma)?;
    let b_sigma = coefficient("b", "b_sigma", d.b, d.b_sigma)?;
    if d.a.is_some() != d.b.is_some() {
        let (given, other) = if d.a.is_some() { ("a", "b") } else { ("b", "a") };
        return Err(err(
            &field(other),
            format!(
                "{given} is a friction coefficient, so give {other} as one too (not {other}_sigma)"
            ),
        ));
    }
    let k = match (d.k, d.shear_modulus, d.length) {
        (Some(_), _, Some(_)) => {
            return Err(err(
                &field("length"),
                "give k or shear_modulus with length (k = G/L), not both".into(),
            ));
        }
        (Some(k), _, None) => phys("k", k, "the spring stiffness, e.g. 1e8 (Pa/m)")?,
        (None, Some(g), Some(l)) => {
            phys("shear_modulus", g, "the shear modulus G, e.g. 3e10 (Pa)")?
                / phys("length", l, "the patch length L, e.g. 1e3 (m)")?
        }
        (None, None, Some(_)) => {
            return Err(err(
                &field("shear_modulus"),
                "missing: k = G/L needs shear_modulus beside length".into(),
            ));
        }
        (None, _, None) => {
            return Err(err(
                &field("k"),
                "missing: give the spring stiffness k (stress per length), or shear_modulus and length (k = G/L)".into(),
            ));
        }
    };
    let reference = match (d.mu0, d.v_ref) {
        (Some(mu0), Some(v_ref)) => {
            if sigma.is_none() {
                return Err(err(&field("sigma"), "missing: mu0 is a friction coefficient, so the shear stress σμ needs the effective normal stress sigma".into()));
            }
            Some(FrictionReference {
                mu0: phys("mu0", mu0, "the steady-state friction coefficient at v_ref, e.g. 0.6")?,
                v_ref: phys(
                    "v_ref",
                    v_ref,
                    "the velocity at which friction is mu0, e.g. 1e-6 (m/s)",
                )?,
            })
        }
        (Some(_), None) => {
            return Err(err(&field("v_ref"), "missing: mu0 is the friction at a reference velocity; give v_ref too (e.g. 1e-6 m/s)".into()));
        }
        (None, Some(_)) => {
            return Err(err(&field("mu0"), "missing: v_ref is the velocity at which the steady-state friction is mu0; give mu0 too (e.g. 0.6)".into()));
        }
        (None, None) => None,
    };
    Ok(PhysicalScales { d_c, v0, a_sigma, b_sigma, sigma, k, reference, mu_star: None })
}

/// Warnings for dimensional input whose derived parameters lie far outside the physical range
/// (a value in the wrong units, typically), each naming the fields behind it. The bounds, from
/// DESIGN.md's crustal and laboratory numbers: friction coefficients a, b ≈ 1e-3 … 3e-2 (warn
/// above 0.1: likely a stress given as a coefficient); ξ = k·D_c/(aσ) is O(1e-2 … 10) near
/// the instability ξ_c = ε (warn outside 1e-4 … 1e3); ε = b/a − 1 ≈ −0.5 … 1 (warn above 10);
/// η = G·v0/(2·c_s·aσ) ≈ 5e-8 on crustal faults (warn at η ≥ 0.1, where radiation damping
/// caps the slip rate at v0/η ≤ 10 v0 and no fast slip can happen); μ0 ≈ 0.6 (warn above 2).
fn field_warnings(d: &Dimensional, s: &PhysicalScales, p: &DrrParams) -> Vec<String> {
    // The fields the user gave for each quantity, to name in the warnings.
    let (a, b) = if d.a.is_some() { ("a/sigma", "b") } else { ("a_sigma", "b_sigma") };
    let k = if d.k.is_some() { "k" } else { "shear_modulus/length" };
    let damping = if d.radiation_damping.is_some() {
        "radiation_damping"
    } else {
        "shear_modulus/shear_wave_speed"
    };
    let mut w = Vec::new();
    if let Some((a, b)) = s.friction_coefficients() {
        for (name, value) in [("a", a), ("b", b)] {
            if value > 0.1 {
                w.push(format!("model.dimensional.{name}/sigma: the friction coefficient {name} = {value:e} is far above the usual 1e-3 … 3e-2; if it is a stress, give it as {name}_sigma"));
            }
        }
    }
    if !(1e-4..=1e3).contains(&p.xi) {
        w.push(format!("model.dimensional.{k}/d_c/{a}: ξ = k·D_c/(aσ) = {:e} is far outside the physical 1e-4 … 1e3 (k/k_c = ξ/ε; crustal and laboratory values are O(0.01 … 10)); check the units of {}, d_c and {}", p.xi, k.replace('/', " and "), a.replace('/', " and ")));
    }
    if p.epsilon > 10.0 {
        w.push(format!("model.dimensional.{a}/{b}: ε = b/a − 1 = {:e}: b/a above 11 is far outside laboratory values (b/a ≈ 0.5 … 2)", p.epsilon));
    }
    if p.eta >= 0.1 && m_has_medium(d) {
        w.push(format!("model.dimensional.{damping}/{a}: η = G·v0/(2·c_s·aσ) = {:e} ≥ 0.1 (crustal faults: ≈ 5e-8): radiation damping caps the slip rate near v0/η = {:e} v0, so no fast slip can happen; check the units of {} and {}", p.eta, 1.0 / p.eta, damping.replace('/', " and "), a.replace('/', " and ")));
    }
    if let Some(r) = s.reference.filter(|r| r.mu0 > 2.0) {
        w.push(format!("model.dimensional.mu0: μ0 = {} is far above rock friction (≈ 0.6)", r.mu0));
    }
    w
}

/// Whether the radiation damping came from `model.dimensional` (not from the dimensionless
/// `model.radiation_damping`, which the dimensional warnings do not judge).
fn m_has_medium(d: &Dimensional) -> bool {
    d.radiation_damping.is_some() || d.shear_wave_speed.is_some()
}

/// η from `model.radiation_damping` (dimensionless) or from `model.dimensional`'s shear
/// modulus G and shear-wave speed c_s: η = G·v0/(2·c_s·aσ); 0 when neither is given.
fn radiation_damping(
    m: &RawModel,
    scales: Option<&PhysicalScales>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<f64, SceneError> {
    let from_medium = match (m.dimensional, scales) {
        (Some(Dimensional { radiation_damping: Some(_), shear_wave_speed: Some(_), .. }), _) => {
            return Err(err("model.dimensional.radiation_damping", "give radiation_damping (η_dim = G/(2c_s)) or shear_modulus with shear_wave_speed, not both".into()));
        }
        (Some(Dimensional { radiation_damping: Some(d), .. }), Some(s)) => {
            let d = finite("model.dimensional.radiation_damping", d, err)?;
            if d < 0.0 {
                return Err(err("model.dimensional.radiation_damping", format!("{d} must be ≥ 0 (η_dim = G/(2c_s) in stress per velocity, e.g. 5e6 Pa·s/m; 0 = no radiation damping)")));
            }
            Some(d * s.v0 / s.a_sigma)
        }
        (Some(Dimensional { shear_modulus: Some(g), shear_wave_speed: Some(c), .. }), Some(s)) => {
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
            Some(g * s.v0 / (2.0 * c * s.a_sigma))
        }
        (Some(Dimensional { shear_modulus: Some(_), shear_wave_speed: None, length, .. }), _) => {
            if length.is_none() {
                return Err(err("model.dimensional.shear_wave_speed", "missing: radiation damping η = G·v0/(2·c_s·aσ) needs both shear_modulus and shear_wave_speed (or give length for k = G/L)".into()));
            }
            None
        }
        (Some(Dimensional { shear_modulus: None, shear_wave_speed: Some(_), .. }), _) => {
            return Err(err("model.dimensional.shear_modulus", "missing: radiation damping η = G·v0/(2·c_s·aσ) needs both shear_modulus and shear_wave_speed".into()));
        }
        _ => None,
    };
    let eta = match (m.radiation_damping, from_medium) {
        (Some(_), Some(_)) => {
            return Err(err("model.radiation_damping", "give either radiation_damping or dimensional.radiation_damping (or dimensional.shear_modulus/shear_wave_speed), not both".into()));
        }
        (Some(eta), None) => finite("model.radiation_damping", eta, err)?,
        (None, Some(eta)) => eta,
        (None, None) => 0.0,
    };
    if !(0.0..=1e100).contains(&eta) || !eta.is_finite() {
        return Err(err(
            "model.radiation_damping",
            format!(
                "{eta:e} must be in 0 … 1e100 (η = G·v0/(2·c_s·aσ) ≥ 0; 0 = no radiation damping)"
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
        Parameter::Gamma => {
            let others =
                Parameter::quoted_names(Parameter::ALL.into_iter().filter(|p| *p != Parameter::Gamma));
            Err(err(&format!("{field}.parameter"), format!("the quasi-dynamic model (\"inertia\": false) has no γ to continue; use one of {others}")))
        }
        Parameter::Eta if c.to <= 0.0 => Err(err(&format!("{field}.to"), format!("{}: the quasi-dynamic model needs radiation damping η > 0 (at η = 0 v blows up in finite time)", c.to))),
        _ => Ok(()),
    }
}

/// The analyses a scene under the no-healing law can run: its state only falls and the block
/// runs away, so there is no steady state and no cycle, and only a "time_series" with a runaway
/// threshold (`runaway_velocity`), which ends where v reaches it, makes sense.
fn no_healing_analyses(
    a: &Analyses,
    raw: &[RawAnalysis],
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    let run = "run {\"time_series\": {\"t_max\": T, \"runaway_velocity\": V}} instead (the report's runaway section gives the time v reaches V)";
    let needs = [
        (a.hopf, AnalysisKind::Hopf, "a steady state"),
        (a.paper, AnalysisKind::Paper, "the paper's model"),
        (a.cycle.is_some(), AnalysisKind::Cycle, "a cycle"),
        (a.trajectory_cycles.is_some(), AnalysisKind::Trajectory, "a cycle"),
        (a.asymptotics.is_some(), AnalysisKind::Asymptotics, "a cycle"),
        (a.lyapunov.is_some(), AnalysisKind::Lyapunov, "a cycle"),
        (a.shooting.is_some(), AnalysisKind::Shooting, "a periodic orbit"),
        (a.continuation.is_some(), AnalysisKind::Continuation, "a periodic orbit"),
        (a.noise.is_some(), AnalysisKind::Noise, "a cycle or a steady state to perturb"),
    ];
    if let Some((_, name, what)) = needs.iter().find(|(asked, ..)| *asked) {
        return Err(err(
            "analyses",
            format!("the \"{name}\" analysis needs {what}; the no-healing law (state_law \"no_healing\") has no steady state and no cycle: its state only falls and the block runs away. Drop \"{name}\" and {run}"),
        ));
    }
    let Some(series) = &a.time_series else {
        return Err(err("analyses", format!("the no-healing law (state_law \"no_healing\") has no steady state and no cycle: {run}")));
    };
    if series.runaway_velocity.is_none() {
        let index = raw
            .iter()
            .position(|a| matches!(a, RawAnalysis::WithOptions(m) if m.contains_key("time_series")))
            .unwrap_or(0);
        return Err(err(
            &format!("analyses[{index}].time_series.runaway_velocity"),
            "missing: under the no-healing law (state_law \"no_healing\") the slip rate runs away, so the run needs a threshold to stop at, in the scene's velocity unit (v0 for a dimensionless model, e.g. 1e9; the input's with model.dimensional, e.g. 1 m/s)".into(),
        ));
    }
    Ok(())
}

/// Rejects the analyses derived for the paper's model (slip law, no radiation damping) when
/// the scene has another state law or radiation damping.
fn papers_model_only(
    params: &DrrParams,
    a: &Analyses,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    let inertial_only = [
        (
            a.noise.is_some(),
            AnalysisKind::Noise,
            "its forcing enters the inertial equation of motion",
        ),
        (
            a.lyapunov.is_some(),
            AnalysisKind::Lyapunov,
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
    if !params.friction.is_classic() {
        let derived = [
            (a.paper, AnalysisKind::Paper),
            (a.asymptotics.is_some(), AnalysisKind::Asymptotics),
            (a.lyapunov.is_some(), AnalysisKind::Lyapunov),
        ];
        if let Some((_, name)) = derived.iter().find(|(asked, _)| *asked) {
            return Err(err("model.friction", format!("the \"{name}\" analysis is derived for friction θ + f(v) (log, asinh, power); QDYN's {} law is not of that form: drop \"{name}\" (hopf, cycle, trajectory, time_series, shooting, continuation and noise run with it)", params.friction.label())));
        }
    }
    if params.is_papers_model() {
        return Ok(());
    }
    let slip_only = [
        (a.paper, AnalysisKind::Paper, "the paper's values are for its model"),
        (
            a.asymptotics.is_some(),
            AnalysisKind::Asymptotics,
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

/// `initial.velocity` (V) and `initial.state` (Θ) in the input's units, converted to the model's
/// v = V/v0 and θ = (b/a) ln(v0Θ/D_c) (docs/from-qdyn.md): the start with them replaced, or
/// None when neither is given. Θ is the state of Dieterich's, Ruina's and the PRZ law alike
/// (steady state D_c/V, or 2D_c/V for PRZ) under logarithmic friction; with another friction
/// law it has no such meaning and is refused.
fn field_start(
    r: &RawInitial,
    scales: Option<&PhysicalScales>,
    params: &DrrParams,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<RawInitial, SceneError> {
    if r.velocity.is_none() && r.state.is_none() {
        return Ok(r.clone());
    }
    let Some(s) = scales else {
        let name = if r.velocity.is_some() { "velocity" } else { "state" };
        return Err(err(&format!("initial.{name}"), format!("{name} is in physical units and needs model.dimensional (d_c, v0, a, b, sigma) to convert; with dimensionless parameters give v (= V/v0) and theta instead")));
    };
    if r.velocity.is_some() && r.v.is_some() {
        return Err(err(
            "initial.velocity",
            "give velocity (the slip rate V) or v (= V/v0), not both".into(),
        ));
    }
    if r.state.is_some() && r.theta.is_some() {
        return Err(err(
            "initial.state",
            "give state (Θ in time units) or theta (= (b/a) ln(v0Θ/D_c)), not both".into(),
        ));
    }
    let v = match r.velocity {
        Some(big_v) => Some(
            positive("initial.velocity", big_v, "the slip rate V, e.g. 5e-10 (m/s)", err)? / s.v0,
        ),
        None => r.v,
    };
    let theta = match r.state {
        Some(_)
            if !matches!(
                params.friction,
                Friction::Log | Friction::CutOff { .. } | Friction::Regularised { .. }
            ) =>
        {
            return Err(err("initial.state", format!("the state Θ means θ = (b/a) ln(v0Θ/D_c) only under logarithmic friction (μ = μ0 + a ln(V/V_ref) + b ln(ΘV_ref/D_c)); this scene's friction is {}: give theta instead", params.friction.label())));
        }
        Some(big_theta) => Some(s.theta_from_state(positive(
            "initial.state",
            big_theta,
            "the state Θ in time units, e.g. D_c/v0 = 1e5 (s)",
            err,
        )?)),
        None => r.theta,
    };
    Ok(RawInitial { u: r.u, v, theta, velocity: None, state: None })
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
