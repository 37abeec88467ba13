//! Reports: the JSON a scene produces (schema in docs/reports.md), its atomic writing and the
//! CLI summary (src/report/summary.rs).

use crate::analysis::continuation::ContinuationReport;
use crate::analysis::cycle::{CycleReport, CycleValues};
use crate::analysis::hopf::HopfReport;
use crate::analysis::noise::NoiseReport;
use crate::analysis::shooting::ShootingReport;
use crate::analysis::time_series::{Event, Runaway, TimeSeriesReport};
use crate::integrate::Stats;
use crate::model::{DrrParams, Friction, PhysicalScales, StateLaw};
use crate::paper::asymptotics::AsymptoticsReport;
use crate::paper::claims::Claim;
use crate::scene::{Dimensional, Method, OtherModel, Units};
use serde::Serialize;
use std::io::Write;
use std::path::Path;

pub mod lab;
pub mod lab_fit;
mod summary;

/// Model parameters as used (dimensionless).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelSection {
    /// γ; +∞ without inertia (the quasi-dynamic model is the γ → ∞ limit), which JSON writes
    /// as null.
    pub gamma: f64,
    /// Whether the block has inertia (false: the quasi-dynamic model).
    pub inertia: bool,
    /// ξ.
    pub xi: f64,
    /// ε.
    pub epsilon: f64,
    /// The friction law, e.g. "log" or "power(alpha=0.31)".
    pub friction: String,
    /// The state law (JSON: "slip", "ageing" or "prz").
    pub state_law: StateLaw,
    /// Radiation damping η (dimensionless; 0: none).
    pub radiation_damping: f64,
    /// The dimensional input, when the scene gave one.
    pub dimensional: Option<Dimensional>,
    /// Initial state (u, v, θ).
    pub initial: [f64; 3],
}

/// Solver settings and statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolverSection {
    /// The method, e.g. "cvode-bdf".
    pub method: Method,
    /// Integrator family actually run ("CVODE" or "ARKStep").
    pub integrator: String,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerances of (u, ln v, θ).
    pub atol: [f64; 3],
    /// Why this method and rtol ran: the scene's `solver` block, or the defaults and why
    /// (`Scene::solver_chosen_by`).
    pub chosen_by: String,
    /// Butcher table(s) for ARKStep.
    pub tables: Vec<String>,
    /// Statistics of the whole run.
    pub stats: Stats,
}

/// Durations of the cycle in physical units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Physical {
    /// The unit, e.g. "years".
    pub time_unit: String,
    /// One dimensionless time unit (D_c/v0) in that unit.
    pub time_scale: f64,
    /// Period.
    pub period: f64,
    /// t0 (v = 1 to the v maximum).
    pub t0: f64,
    /// Slip half-width.
    pub slip_half_width: Option<f64>,
    /// Time with v > 1.
    pub slip_duration: f64,
}

/// The "cycle" section: the analysis's report, and with dimensional input its values in
/// physical units (`physical`). Dereferences to the [`CycleReport`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleSection {
    /// The cycle analysis (its keys appear at the section's top level).
    #[serde(flatten)]
    pub analysis: CycleReport,
    /// The converged cycle in the input's units (dimensional input and a periodic cycle).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub physical: Option<CyclePhysical>,
}

impl std::ops::Deref for CycleSection {
    type Target = CycleReport;
    fn deref(&self) -> &CycleReport {
        &self.analysis
    }
}

impl std::ops::DerefMut for CycleSection {
    fn deref_mut(&mut self) -> &mut CycleReport {
        &mut self.analysis
    }
}

/// The converged cycle in the units of the dimensional input (SI: s, m/s, m, Pa); docs/reports.md
/// defines each key. Built by [`CyclePhysical::new`] from the dimensionless values and the
/// scene's [`PhysicalScales`], the one definition of the conversion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CyclePhysical {
    /// Period (time units of the input).
    pub period: f64,
    /// From V rising through v0 to the V maximum (time units).
    pub t0: f64,
    /// Time with V > v0 (time units).
    pub slip_duration: f64,
    /// The same durations in `units.time_unit`, when the scene gives `units`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub in_time_unit: Option<Durations>,
    /// Maximum slip rate (velocity units).
    pub v_max: f64,
    /// Minimum slip rate (velocity units).
    pub v_min: f64,
    /// Slip per event, ∫V dt while V > v0 (length units).
    pub slip: f64,
    /// Drop of the spring stress over the event, k·D_c·(u_max − u_min) > 0 (stress units).
    pub stress_drop: f64,
    /// The shear stress τ = σμ where V rises through v0 (the event's start): absolute with
    /// μ0 and v_ref, else relative to steady sliding at v0 (see `shear_stress_reference`).
    /// Quasi-dynamic model only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shear_stress_before: Option<f64>,
    /// The shear stress τ = σμ where V falls back through v0 (the event's end).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shear_stress_after: Option<f64>,
    /// What the shear stresses are measured from: "absolute (σμ)" (also under the
    /// regularised law, whose μ = aΦ is absolute), "relative to σμ_ref, steady sliding at v0",
    /// or under the cut-off law "relative to σμ*".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shear_stress_reference: Option<&'static str>,
    /// The friction coefficient μ at the event's start (with μ0, v_ref and σ).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_before: Option<f64>,
    /// The friction coefficient μ at the event's end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_after: Option<f64>,
    /// μ_ref = μ0 + (a − b) ln(v0/V_ref), steady-state friction at v0 (with μ0, v_ref, σ).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_steady: Option<f64>,
}

/// Cycle durations in a named time unit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Durations {
    /// The unit, e.g. "years".
    pub time_unit: String,
    /// Period.
    pub period: f64,
    /// t0.
    pub t0: f64,
    /// Time with V > v0.
    pub slip_duration: f64,
}

impl CyclePhysical {
    /// The cycle `v` (dimensionless) in physical units. In the quasi-dynamic model the force
    /// balance θ + f(v) = −ξu − ηv gives the dimensionless friction φ exactly at the crossings
    /// of v = 1, where u is at its minimum (start) and maximum (end); the inertial model's
    /// friction there is not fixed by u, so its shear stresses are left out.
    pub fn new(
        v: &CycleValues,
        s: &PhysicalScales,
        params: &DrrParams,
        units: Option<&Units>,
    ) -> Self {
        let phi_at = |u: f64| (!params.inertia).then(|| -params.xi * u - params.eta);
        let (phi_before, phi_after) = (phi_at(v.extremes.u_min), phi_at(v.extremes.u_max));
        let stress = |phi: Option<f64>| {
            phi.map(|phi| {
                s.shear_stress(&params.friction, phi).unwrap_or_else(|| s.shear_stress_change(phi))
            })
        };
        let absolute = s.friction_level(&params.friction).is_some();
        Self {
            period: s.time(v.main.period),
            t0: s.time(v.main.t0),
            slip_duration: s.time(v.main.slip_duration),
            in_time_unit: units.map(|u| Durations {
                time_unit: u.time_unit.clone(),
                period: v.main.period * u.time_scale,
                t0: v.main.t0 * u.time_scale,
                slip_duration: v.main.slip_duration * u.time_scale,
            }),
            v_max: s.velocity(v.main.v_max),
            v_min: s.velocity(v.main.v_min),
            slip: s.slip(v.main.slip),
            stress_drop: s.stress_drop(v.extremes.u_min, v.extremes.u_max),
            shear_stress_before: stress(phi_before),
            shear_stress_after: stress(phi_after),
            shear_stress_reference: phi_before.map(|_| match params.friction {
                Friction::Regularised { .. } => "absolute (σμ, the regularised law's μ = aΦ)",
                Friction::CutOff { .. } if absolute => "absolute (σμ, the cut-off law's μ = μ* + aΦ)",
                Friction::CutOff { .. } => "relative to σμ*, the cut-off law's μ* (μ = μ* + aΦ; give cut_off.mu_star for absolute values)",
                _ if absolute => "absolute (σμ)",
                _ => "relative to σμ_ref, steady sliding at v0",
            }),
            friction_before: phi_before.and_then(|phi| s.friction_coefficient(&params.friction, phi)),
            friction_after: phi_after.and_then(|phi| s.friction_coefficient(&params.friction, phi)),
            friction_steady: s.reference_friction(),
        }
    }
}

/// The report of one scene. Sections appear only when the scene asked for them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// stickslip version.
    pub stickslip_version: &'static str,
    /// SUNDIALS version linked at run time.
    pub sundials_version: String,
    /// Scene name.
    pub name: String,
    /// The scene as given.
    pub scene: serde_json::Value,
    /// Model parameters as used.
    pub model: ModelSection,
    /// Solver settings and statistics.
    pub solver: SolverSection,
    /// Physical time units, when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub units: Option<Units>,
    /// The "hopf" analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hopf: Option<HopfReport>,
    /// The "cycle" analysis, with its values in physical units under `physical`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycle: Option<CycleSection>,
    /// The "asymptotics" analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub asymptotics: Option<AsymptoticsReport>,
    /// The "lyapunov" analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lyapunov: Option<crate::paper::lyapunov::LyapunovReport>,
    /// Cycle durations in physical units (with `units` and a periodic cycle).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub physical: Option<Physical>,
    /// The "paper" comparison.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper: Option<Vec<Claim>>,
    /// The "shooting" analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shooting: Option<ShootingReport>,
    /// The "continuation" analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuation: Option<ContinuationReport>,
    /// The "noise" analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseReport>,
    /// The "time_series" analysis (its rows go to `--series FILE`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_series: Option<TimeSeriesReport>,
    /// The event catalogue of the "time_series" run: one entry per slip episode.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<Vec<Event>>,
    /// Where the "time_series" run stopped at its runaway threshold
    /// (`time_series.runaway_velocity`): the time v reached it, or that it did not by t_max.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runaway: Option<Runaway>,
    /// A forced scene's response to its periodic loading: the locking judged from `events`
    /// ([`crate::analysis::locking`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forcing: Option<crate::analysis::locking::ForcingReport>,
    /// Derived parameters far outside the physical range (dimensional input), each naming its
    /// input fields; absent when there are none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Wall-clock time of the computation (seconds).
    pub wall_time_s: f64,
}

impl Report {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }
}

/// Writes `text` to `path` atomically: a temporary file in the same directory, flushed to
/// disk, then renamed over `path`. A crash leaves either the old file or the new one.
///
/// A path that exists and is not a regular file (`/dev/null`, `/dev/stdout`, a FIFO) is
/// written to directly: renaming over it would replace the device with a regular file. A
/// symbolic link is followed, so the file it points to is replaced, not the link.
pub fn write_atomic(path: &Path, text: &str) -> std::io::Result<()> {
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() && !m.is_dir() => return std::fs::write(path, text),
        Ok(m) if m.is_file() && path.is_symlink() => {
            return write_atomic(&std::fs::canonicalize(path)?, text)
        }
        _ => {}
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::other("the output path has no file name"))?;
    let tmp = dir.join(format!(".{}.tmp-{}", name.to_string_lossy(), std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(text.as_bytes())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The report of a saddle-node or van der Pol scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelReport {
    /// stickslip version.
    pub stickslip_version: &'static str,
    /// Scene name.
    pub name: String,
    /// The scene as given.
    pub scene: serde_json::Value,
    /// The model and its start.
    pub model: OtherModel,
    /// The noise analysis.
    pub noise: NoiseReport,
    /// Wall-clock time of the computation (seconds).
    pub wall_time_s: f64,
}

impl ModelReport {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }
}

/// The report of a scene of any kind ([`crate::engine::run`] on a
/// [`crate::scene::AnyScene`]): its JSON is the kind's own report, unchanged.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum AnyReport {
    /// A spring-slider scene's.
    Drr(Box<Report>),
    /// A saddle-node or van der Pol scene's.
    Other(Box<ModelReport>),
    /// A laboratory scene's.
    Lab(Box<lab::LabReport>),
}

impl AnyReport {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }

    /// The text summary of the kind's report.
    pub fn summary(&self) -> String {
        match self {
            AnyReport::Drr(r) => r.summary(),
            AnyReport::Other(r) => r.summary(),
            AnyReport::Lab(r) => r.summary(),
        }
    }
}
