//! The "asymptotics" analysis: the paper's matched asymptotics set beside the numerics.
//!
//! - [`manifold`]: the stick as the 2D slow flow on S, its finite-time blow-up against the 3D
//!   v maximum, where the 3D flow leaves S (Fig. 3a);
//! - [`matching`]: the matching curves before and after the catastrophe, the finite-time
//!   condition c < 0 and the blow-up time it predicts, the zero-acceleration line and the
//!   adiabatic limit (Fig. 3b);
//! - [`scan`], [`slip_scaling`]: the brute-force cycle across a list of γ, the shifts c_u, c_θ
//!   per unit ln γ, the slip half-width × γ and its limit, the fast system on the scene's slip
//!   (Fig. 4);
//! - [`singular_limit`]: the period, v_max, half-width and γ-independence predictions;
//! - [`verdicts`]: every claim as {claim, reference, ours, difference, verdict}.
//!
//! The parts that need the scene's own cycle (manifold, matching, fast system) are absent,
//! with a note, when the scene's cycle is not a period-1 limit cycle; the γ scan runs anyway.

pub mod manifold;
pub mod matching;
pub mod scan;
pub mod singular_limit;
pub mod slip_scaling;
pub mod slow_run;
pub mod verdicts;

use crate::analysis::cycle::CycleReport;
use crate::analysis::{AnalysisError, InvalidOption};
use crate::model::{Drr, DrrParams};
use crate::paper::claims::Claim;
use crate::paper::cycle_period::CyclePeriod;
use serde::{Deserialize, Serialize};

/// Options of the "asymptotics" analysis (scene: `{"asymptotics": {...}}`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AsymptoticsOptions {
    /// The γ scan (default 1e2, 1e3, …, 1e12).
    pub gammas: Vec<f64>,
    /// Fits use scan points with γ ≥ this (default 1e4).
    pub fit_min_gamma: f64,
    /// Matching windows: v ≥ this (1 ≪ v; default 10).
    pub matching_v_min: f64,
    /// Matching windows and the stick test: |ln v − ln v_S(u, θ)| ≤ this counts as on S
    /// (default 0.01).
    pub manifold_tolerance: f64,
    /// The 3D flow has left S where |ln v − ln v_S(u, θ)| exceeds this (default 0.1).
    pub departure_offset: f64,
    /// The fast system starts where v/γ first reaches this (default 0.05).
    pub fast_start: f64,
    /// At most this many points per figure series (default 2000).
    pub series_points: usize,
    /// Relative tolerance of the 2D and fast-system integrations (default 1e-12).
    pub rtol: f64,
}

impl Default for AsymptoticsOptions {
    fn default() -> Self {
        Self {
            gammas: (2..=12).map(|k| 10f64.powi(k)).collect(),
            fit_min_gamma: 1e4,
            matching_v_min: 10.0,
            manifold_tolerance: 0.01,
            departure_offset: 0.1,
            fast_start: 0.05,
            series_points: 2000,
            rtol: 1e-12,
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOptions {
    gammas: Option<Vec<f64>>,
    fit_min_gamma: Option<f64>,
    matching_v_min: Option<f64>,
    manifold_tolerance: Option<f64>,
    departure_offset: Option<f64>,
    fast_start: Option<f64>,
    series_points: Option<usize>,
    rtol: Option<f64>,
}

impl AsymptoticsOptions {
    /// Parses and validates the options object; the error names the field (empty: the
    /// object) and what would be valid.
    pub fn from_json(value: serde_json::Value) -> Result<Self, InvalidOption> {
        let raw: RawOptions = InvalidOption::parse(value)?;
        let d = Self::default();
        let o = Self {
            gammas: raw.gammas.unwrap_or(d.gammas),
            fit_min_gamma: raw.fit_min_gamma.unwrap_or(d.fit_min_gamma),
            matching_v_min: raw.matching_v_min.unwrap_or(d.matching_v_min),
            manifold_tolerance: raw.manifold_tolerance.unwrap_or(d.manifold_tolerance),
            departure_offset: raw.departure_offset.unwrap_or(d.departure_offset),
            fast_start: raw.fast_start.unwrap_or(d.fast_start),
            series_points: raw.series_points.unwrap_or(d.series_points),
            rtol: raw.rtol.unwrap_or(d.rtol),
        };
        let bad = |field: &str, message: String| Err(InvalidOption::new(field, message));
        if o.gammas.is_empty() || o.gammas.len() > 100 {
            return bad(
                "gammas",
                format!(
                    "has {} values; give 1 to 100 values of γ, e.g. [1e2, 1e4, 1e6, 1e8]",
                    o.gammas.len()
                ),
            );
        }
        if let Some(g) = o.gammas.iter().find(|g| !(g.is_finite() && (1.0..=1e100).contains(*g))) {
            return bad("gammas", format!("{g} is not a γ in [1, 1e100]"));
        }
        let mut sorted = o.gammas.clone();
        sorted.sort_by(f64::total_cmp);
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return bad("gammas", format!("{} appears twice; give distinct values", w[0]));
        }
        if !(o.fit_min_gamma.is_finite() && o.fit_min_gamma > 0.0) {
            return bad(
                "fit_min_gamma",
                format!("{} must be a finite γ > 0, e.g. 1e4", o.fit_min_gamma),
            );
        }
        if !(o.matching_v_min.is_finite() && o.matching_v_min > 1.0) {
            return bad(
                "matching_v_min",
                format!("{} must be > 1 (the matching region is 1 ≪ v), e.g. 10", o.matching_v_min),
            );
        }
        for (name, x) in [
            ("manifold_tolerance", o.manifold_tolerance),
            ("departure_offset", o.departure_offset),
            ("fast_start", o.fast_start),
        ] {
            if !(x > 0.0 && x < 1.0) {
                return bad(name, format!("{x} must be in (0, 1)"));
            }
        }
        if !(10..=1_000_000).contains(&o.series_points) {
            return bad(
                "series_points",
                format!("{} must be between 10 and 1000000", o.series_points),
            );
        }
        if !(1e-14..=1e-6).contains(&o.rtol) {
            return bad("rtol", format!("{} must be in [1e-14, 1e-6], e.g. 1e-12", o.rtol));
        }
        Ok(o)
    }
}

/// The "asymptotics" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AsymptoticsReport {
    /// The options used.
    pub options: AsymptoticsOptions,
    /// Why the parts that need the scene's cycle are absent, if they are.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The stick as the 2D slow flow (Fig. 3a).
    pub manifold: Option<manifold::ManifoldReport>,
    /// Matching curves and lines (Fig. 3b).
    pub matching: Option<matching::MatchingReport>,
    /// The start (u, v, θ) of every scan run: the scene's (u, θ), v on S.
    pub scan_start: [f64; 3],
    /// The cycle at each γ of the scan.
    pub scan: Vec<scan::ScanRow>,
    /// Shifts per ln γ, half-width limit, fast system (Fig. 4).
    pub slip_scaling: slip_scaling::SlipScalingReport,
    /// The singular-limit predictions across γ.
    pub singular_limit: singular_limit::SingularLimitReport,
    /// Every claim with its verdict.
    pub claims: Vec<Claim>,
}

/// Runs the brute-force "cycle" analysis (the scene's solver and cycle options, recording no
/// trajectory) on a DRR system from a start (the engine's `cycle_with`, with the system's own
/// Hopf analysis).
pub type CycleAt<'a> = dyn FnMut(&Drr, [f64; 3]) -> Result<CycleReport, AnalysisError> + 'a;

/// Runs the analysis on the model `params`, started at `initial`, whose "cycle" analysis
/// produced `cycle`; the γ scan runs its cycles by `cycle_at`.
pub fn analyse(
    params: &DrrParams,
    initial: [f64; 3],
    cycle_at: &mut CycleAt<'_>,
    cycle: Option<&CycleReport>,
    options: &AsymptoticsOptions,
) -> Result<AsymptoticsReport, AnalysisError> {
    let orbit = CyclePeriod::of_scene(cycle);
    let (manifold, matching, note) = match &orbit {
        Ok(o) => {
            let m = manifold::analyse(o, params, options)?;
            let mt = matching::analyse(o, params, options, &m.slow_samples);
            (Some(m), Some(mt), None)
        }
        Err(why) => (None, None, Some(why.clone().into_note()?)),
    };
    let scan = scan::run(params, initial, &options.gammas, cycle_at);
    let all = scan::usable(&scan, 0.0);
    let fit = scan::usable(&scan, options.fit_min_gamma);
    let half_width_3d =
        cycle.and_then(|c| c.values).and_then(|v| v.main.slip_half_width).map(|w| w * params.gamma);
    let spread = cycle
        .and_then(|c| c.spread)
        .map_or([0.0; 2], |s| [s.main.v_max, s.main.slip_half_width.unwrap_or(0.0)]);
    let slip =
        slip_scaling::analyse(&fit, orbit.as_ref().ok(), params, options, half_width_3d, spread)?;
    let singular = singular_limit::analyse(&all, &fit, params);
    let claims = verdicts::claims(&verdicts::Inputs {
        params,
        options,
        manifold: manifold.as_ref(),
        matching: matching.as_ref(),
        slip: &slip,
        singular: &singular,
        all: &all,
    });
    let [u, w, theta] = scan::start(params, initial);
    Ok(AsymptoticsReport {
        options: options.clone(),
        note,
        manifold,
        matching,
        scan_start: [u, w.exp(), theta],
        scan,
        slip_scaling: slip,
        singular_limit: singular,
        claims,
    })
}

/// The CLI summary of the section: the main numbers, then every claim.
pub fn summary(a: &AsymptoticsReport) -> String {
    let mut s = String::from("asymptotics:\n");
    if let Some(note) = &a.note {
        s += &format!("  (no manifold/matching/fast-system parts: {note})\n");
    }
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.6}"));
    if let Some(m) = &a.manifold {
        s += &format!(
            "  2D slow flow from the v minimum (t_c − t = {:.4}): t_c(2D) − t_c = {}, t0(2D) = {}, t0(3D) = {:.6}\n",
            m.start.time_before_tc,
            m.blow_up_offset.map_or("none (no blow-up)".to_string(), |v| format!("{v:.3e}")),
            opt(m.t0_2d),
            m.t0_3d
        );
        s += &format!(
            "  stick: max |ln v(3D) − ln v(2D)| = {:.3e} (× γ² = {:.4}); 3D leaves S (|Δ ln v| > {}) at {}\n",
            m.stick_deviation.max_abs_ln_v,
            m.stick_deviation.max_abs_ln_v_times_gamma2,
            m.departure_offset,
            m.leaves_manifold.map_or("-".into(), |p| format!("t_c − t = {:.3e}, v/γ = {:.3e}", p.time_before_tc, p.v_over_gamma))
        );
    }
    if let Some(mt) = &a.matching {
        s += &format!(
            "  matching: c before = {}, after = {}; ∫e^−Φ blow-up − t_c = {}\n",
            mt.before
                .as_ref()
                .map_or("-".into(), |b| format!("{:.6e} (rms {:.2e})", b.c, b.residual_rms)),
            mt.after
                .as_ref()
                .map_or("-".into(), |b| format!("{:.6e} (rms {:.2e})", b.c, b.residual_rms)),
            mt.predicted_blow_up
                .as_ref()
                .map_or("-".into(), |p| format!("{:.3e}", p.offset_from_tc))
        );
    }
    let periodic = a.scan.iter().filter(|r| r.values.is_some()).count();
    let sl = &a.slip_scaling;
    let slope = |f: &slip_scaling::ShiftFit| {
        f.with_ln_ln.as_ref().map_or("-".into(), |l| {
            format!("{:.4} (+ {:.3} ln ln γ)", l.coefficients[1], l.coefficients[2])
        })
    };
    s += &format!(
        "  γ scan: {} values, {} periodic; per ln γ: u at v_max {} (c_u = {:.4}), θ at v_max {} (c_θ = {:.4}); half-width × γ → {}\n",
        a.scan.len(),
        periodic,
        slope(&sl.u_at_v_max),
        sl.c_u,
        slope(&sl.theta_at_v_max),
        sl.c_theta,
        sl.half_width.fit.as_ref().map_or("-".into(), |f| format!("{:.5} ± {:.1e}", f.limit, sl.half_width.limit_uncertainty.unwrap_or(0.0)))
    );
    if let Some(f) = &sl.fast_system {
        s += &format!(
            "  fast system from v/γ = {:.3}: V_max {:.6} (3D {:.6}), half-width {} (3D {})\n",
            f.start_v_over_gamma,
            f.v_max_fast,
            f.v_max_over_gamma_3d,
            opt(f.half_width_fast),
            opt(f.half_width_times_gamma_3d)
        );
    }
    s += "  claims:\n";
    s += &crate::paper::claims::summary_lines(&a.claims);
    s
}
