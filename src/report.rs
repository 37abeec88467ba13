//! Reports: the JSON a scene produces (schema in docs/reports.md), its atomic writing and the
//! CLI summary.

use crate::analysis::asymptotics::AsymptoticsReport;
use crate::analysis::claims::Claim;
use crate::analysis::continuation::ContinuationReport;
use crate::analysis::cycle::{CycleReport, CycleStatus, CycleValues};
use crate::analysis::hopf::HopfReport;
use crate::analysis::noise::NoiseReport;
use crate::analysis::shooting::ShootingReport;
use crate::analysis::time_series::{Event, TimeSeriesReport};
use crate::integrate::Stats;
use crate::model::{DrrParams, PhysicalScales};
use crate::scene::{Dimensional, Method, OtherModel, Units};
use serde::Serialize;
use std::io::Write;
use std::path::Path;

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
    /// The state law: "slip", "ageing" or "prz".
    pub state_law: &'static str,
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
    /// What the shear stresses are measured from: "absolute (σμ)" or "relative to σμ_ref,
    /// steady sliding at v0".
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
        let (phi_before, phi_after) = (phi_at(v.u_min), phi_at(v.u_max));
        let stress = |phi: Option<f64>| {
            phi.map(|phi| s.shear_stress(phi).unwrap_or_else(|| s.shear_stress_change(phi)))
        };
        let absolute = s.reference_friction().is_some();
        Self {
            period: s.time(v.period),
            t0: s.time(v.t0),
            slip_duration: s.time(v.slip_duration),
            in_time_unit: units.map(|u| Durations {
                time_unit: u.time_unit.clone(),
                period: v.period * u.time_scale,
                t0: v.t0 * u.time_scale,
                slip_duration: v.slip_duration * u.time_scale,
            }),
            v_max: s.velocity(v.v_max),
            v_min: s.velocity(v.v_min),
            slip: s.slip(v.slip),
            stress_drop: s.stress_drop(v.u_min, v.u_max),
            shear_stress_before: stress(phi_before),
            shear_stress_after: stress(phi_after),
            shear_stress_reference: phi_before.map(|_| {
                if absolute {
                    "absolute (σμ)"
                } else {
                    "relative to σμ_ref, steady sliding at v0"
                }
            }),
            friction_before: phi_before.and_then(|phi| s.friction_coefficient(phi)),
            friction_after: phi_after.and_then(|phi| s.friction_coefficient(phi)),
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
    pub lyapunov: Option<crate::analysis::lyapunov::LyapunovReport>,
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

    /// A readable summary for the terminal.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let m = &self.model;
        s += &format!(
            "scene {}: {}, ξ = {}, ε = {}, friction {}, {} law{}\n",
            self.name,
            if m.inertia {
                format!("γ = {:e}", m.gamma)
            } else {
                "quasi-dynamic (no inertia)".into()
            },
            m.xi,
            m.epsilon,
            m.friction,
            m.state_law,
            if m.radiation_damping > 0.0 {
                format!(", radiation damping η = {:e}", m.radiation_damping)
            } else {
                String::new()
            }
        );
        s += &format!(
            "solver {} ({}), rtol {:e}, SUNDIALS {}; {} steps, {} RHS, {} Jacobians, {:.3} s\n",
            self.solver.method.name(),
            self.solver.integrator,
            self.solver.rtol,
            self.sundials_version,
            self.solver.stats.steps,
            self.solver.stats.rhs_evals + self.solver.stats.rhs_evals_explicit,
            self.solver.stats.jac_evals,
            self.wall_time_s
        );
        if let Some(h) = &self.hopf {
            s += &format!(
                "hopf: ε_c = {:.12}, ω_c = {:.9}, period_c = {:.9} (2π/√ξ = {:.9}); {}\n",
                h.epsilon_c,
                h.omega_c,
                h.period_c,
                h.period_c_large_gamma,
                if h.above_threshold {
                    "above threshold: fixed point unstable"
                } else {
                    "below threshold: fixed point stable"
                }
            );
        }
        if let Some(c) = &self.cycle {
            match (c.status, &c.values) {
                (CycleStatus::Periodic, Some(v)) => {
                    s += &format!(
                        "cycle: periodic after {} cycles (mean of the last {}; ± estimated error: transient left plus cycle-to-cycle noise)\n",
                        c.cycles_computed, c.cycles_used,
                    );
                    let e = c.error_estimate;
                    let pm = |x: Option<f64>| x.map_or(String::new(), |x| format!(" ± {x:.1e}"));
                    s += &format!(
                        "  period          {:.10}{}\n  t0              {:.10}{}\n",
                        v.period,
                        pm(e.map(|e| e.period)),
                        v.t0,
                        pm(e.map(|e| e.t0))
                    );
                    let hw = pm(e.and_then(|e| e.slip_half_width));
                    match v.slip_half_width {
                        Some(w) if m.inertia => {
                            s += &format!(
                                "  slip half-width {:.6e}{hw} (× γ = {:.6})\n",
                                w,
                                w * m.gamma
                            )
                        }
                        Some(w) => s += &format!("  slip half-width {:.6e}{hw}\n", w),
                        None => {}
                    }
                    s += &format!(
                        "  v_max           {:.10e}{} (ln {:.9})\n  v_min           {:.6e}{}\n  u, θ at v_max   {:.9}, {:.9}\n  slip            {:.9}{}\n",
                        v.v_max,
                        pm(e.map(|e| e.v_max)),
                        v.ln_v_max,
                        v.v_min,
                        pm(e.map(|e| e.v_min)),
                        v.u_at_v_max,
                        v.theta_at_v_max,
                        v.slip,
                        pm(e.map(|e| e.slip))
                    );
                }
                (CycleStatus::PeriodN, _) => {
                    s += &format!(
                        "cycle: period-{} orbit, total period {:.10}\n",
                        c.orbit.len(),
                        c.orbit_period.unwrap_or(0.0)
                    );
                    for (i, o) in c.orbit.iter().enumerate() {
                        s += &format!(
                            "  cycle {}: period {:.10}, ln v_max {:.9}\n",
                            i + 1,
                            o.period,
                            o.ln_v_max
                        );
                    }
                }
                (CycleStatus::FixedPoint, _) => {
                    s += "cycle: none; the oscillation dies out and the fixed point is stable\n"
                }
                _ => {
                    s += &format!(
                    "cycle: NOT converged after {} cycles / t = {:.6e}{} (see cycle.last_cycles)\n",
                    c.cycles_computed,
                    c.time_integrated,
                    c.stopped_by.map_or(String::new(), |l| format!(", stopped by the limit {l}"))
                )
                }
            }
        }
        if let Some(p) = &self.physical {
            s += &format!("  in {}: period {:.6}, t0 {:.6}\n", p.time_unit, p.period, p.t0);
        }
        if let Some(t) = &self.time_series {
            s += &format!(
                "time series: t = 0 … {:e}{}, {} rows ({} steps), {} events above v = {}{}\n",
                t.t_max,
                t.t_max_physical
                    .map_or(String::new(), |p| format!(" ({p:e} in the input's time unit)")),
                t.rows,
                t.steps,
                t.event_count,
                t.event_threshold,
                if t.in_event_at_end { " (one more under way at t_max)" } else { "" }
            );
            if let Some(last) = self.events.as_ref().and_then(|e| e.last()) {
                let e = &last.values;
                s += &format!(
                    "  last event: peak at t = {:.10e}, v_max {:.6e}, slip {:.6e}, stress drop {:.6e}, recurrence {}\n",
                    e.t_peak,
                    e.v_max,
                    e.slip,
                    e.stress_drop,
                    e.recurrence.map_or("-".to_string(), |r| format!("{r:.10e}"))
                );
            }
        }
        if let Some(p) = self.cycle.as_ref().and_then(|c| c.physical.as_ref()) {
            s += &format!(
                "  in the input's units (cycle.physical): v_max {:.6e}, v_min {:.6e}, slip {:.6e}, stress drop {:.6e}\n",
                p.v_max, p.v_min, p.slip, p.stress_drop
            );
        }
        for w in &self.warnings {
            s += &format!("warning: {w}\n");
        }
        if let Some(a) = &self.asymptotics {
            s += &crate::analysis::asymptotics::summary(a);
        }
        if let Some(l) = &self.lyapunov {
            s += &crate::analysis::lyapunov::summary(l);
        }
        if let Some(r) = &self.shooting {
            match &r.orbit {
                Some(o) => {
                    s += &format!(
                        "shooting: converged in {} iterations (residual {:.1e}); period {:.10}, t0 {:.10}, ln v_max {:.9}\n",
                        o.newton_iterations, o.residual, o.period, o.t0, o.ln_v_max
                    );
                    s += &format!(
                        "  section point (u, v, θ) = ({:.10}, 1, {:.10})\n",
                        o.section_point[0], o.section_point[2]
                    );
                    let mu: Vec<String> = o
                        .nontrivial()
                        .iter()
                        .map(|m| {
                            if m.im == 0.0 {
                                format!("{:.6e}", m.re)
                            } else {
                                format!("{:.6e}{:+.6e}i", m.re, m.im)
                            }
                        })
                        .collect();
                    s += &format!(
                        "  Floquet multipliers: trivial 1{:+.1e}, others {} ({})\n",
                        o.multipliers[0].re - 1.0,
                        mu.join(", "),
                        match o.stable {
                            Some(true) => "stable".to_string(),
                            Some(false) => "unstable".to_string(),
                            None => format!(
                                "stability unknown: {}",
                                o.multipliers_note.as_deref().unwrap_or("")
                            ),
                        }
                    );
                }
                None => {
                    s += &format!(
                        "shooting: NOT converged: {}\n",
                        r.failure.as_ref().map_or("?".to_string(), ToString::to_string)
                    )
                }
            }
            if let Some(pd) = &r.period_doubling {
                s += &format!(
                    "  period doubling: multiplier {:.6}; {}\n",
                    pd.multiplier,
                    match &pd.doubled {
                        Some(d) =>
                            format!("doubled orbit of period {:.10} ({})", d.period, pd.note),
                        None => format!("doubled orbit not found ({})", pd.note),
                    }
                );
            }
        }
        if let Some(c) = &self.continuation {
            s += &format!(
                "continuation in {} from {} to {}: {} points{}\n",
                c.parameter.name(),
                c.from,
                c.to,
                c.points.len(),
                if c.completed { String::new() } else { String::from(" (stopped)") }
            );
            if let (Some(first), Some(last)) = (c.points.first(), c.points.last()) {
                s += &format!(
                    "  period {:.8} at {} … {:.8} at {}\n",
                    first.orbit.period, first.value, last.orbit.period, last.value
                );
            }
            if let Some(stop) = &c.stopped {
                s += &format!(
                    "  stopped after {} (failed at {}): {}\n",
                    stop.last_value, stop.failed_at, stop.reason
                );
            }
            for f in &c.flips {
                s += &format!("  period doubling between {} and {}\n", f.from, f.to);
            }
            if let Some(d) = c.period_per_decade.first() {
                s += &format!(
                    "  period per decade of γ: {:.4} (fit over log10 γ = {} … {})\n",
                    d.slope, d.log10_gamma_from, d.log10_gamma_to
                );
            }
        }
        if let Some(n) = &self.noise {
            s += &n.summary();
        }
        if let Some(claims) = &self.paper {
            s += "paper's claims:\n";
            for c in claims {
                let relative = c
                    .relative_difference
                    .map_or(String::new(), |r| format!(" ({:+.1} %)", 100.0 * r));
                s += &format!(
                    "  {:<9} {} — paper {}, ours {:.6}{relative}\n",
                    c.verdict, c.claim, c.reference, c.ours
                );
            }
        }
        s
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

    /// A readable summary for the terminal.
    pub fn summary(&self) -> String {
        let model = match &self.model {
            OtherModel::SaddleNode { params, x0 } => {
                format!("saddle-node, μ0 = {}, r = {}, x(0) = {x0}", params.mu0, params.r)
            }
            OtherModel::VanDerPol { params, initial } => {
                format!("van der Pol, β = {}, a = {}, start {initial:?}", params.beta, params.a)
            }
        };
        format!("scene {}: {model}; {:.3} s\n{}", self.name, self.wall_time_s, self.noise.summary())
    }
}
