//! The "lyapunov" analysis (the paper's section "Lyapunov analysis along the trajectory"):
//!
//! - [`local`]: the eigenvalues of the Jacobian along the cycle (the paper's "Lyapunov
//!   exponents", Fig. 5) from the characteristic polynomial, checked against a matrix
//!   eigensolver, beside the paper's quasi-static formula; when the slow pair turns complex
//!   before the catastrophe t_c (the v maximum) and when its real part crosses zero;
//! - [`ftle`]: finite-time Lyapunov exponents from the variational equations with QR
//!   re-orthonormalisation, and their link to the Floquet multipliers found by shooting.
//!
//! Times are "before t_c": t_c − t along the stick that ends in the catastrophe.

pub mod ftle;
pub mod local;

use crate::analysis::cycle::CycleReport;
use crate::analysis::{AnalysisError, InvalidOption};
use crate::integrate::{Integrator, SolverError};
use crate::model::{Drr, DrrParams, Friction};
use crate::numerics::series::{decimate, pick};
use crate::paper::claims::{Claim, Source};
use crate::paper::cycle_period::CyclePeriod;
use crate::solver::SolverSpec;
use local::Crossing;
use serde::{Deserialize, Serialize};

/// Options of the "lyapunov" analysis (scene: `{"lyapunov": {...}}`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LyapunovOptions {
    /// Periods of the finite-time Lyapunov exponents (default 3; 0: no FTLE).
    pub ftle_periods: usize,
    /// At most this many points per figure series (default 2000).
    pub series_points: usize,
}

impl Default for LyapunovOptions {
    fn default() -> Self {
        Self { ftle_periods: 3, series_points: 2000 }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOptions {
    ftle_periods: Option<usize>,
    series_points: Option<usize>,
}

impl LyapunovOptions {
    /// Parses and validates the options object; the error names the field (empty: the
    /// object).
    pub fn from_json(value: serde_json::Value) -> Result<Self, InvalidOption> {
        let raw: RawOptions = InvalidOption::parse(value)?;
        let d = Self::default();
        let o = Self {
            ftle_periods: raw.ftle_periods.unwrap_or(d.ftle_periods),
            series_points: raw.series_points.unwrap_or(d.series_points),
        };
        if o.ftle_periods > 1000 {
            return Err(InvalidOption::new(
                "ftle_periods",
                format!("{} must be between 0 (no FTLE) and 1000", o.ftle_periods),
            ));
        }
        if !(10..=1_000_000).contains(&o.series_points) {
            return Err(InvalidOption::new(
                "series_points",
                format!("{} must be between 10 and 1000000", o.series_points),
            ));
        }
        Ok(o)
    }
}

/// The quasi-static formula's own transitions and its distance from the exact eigenvalues.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuasiStatic {
    /// t_c − t where the formula's pair turns complex.
    pub complex_onset_before_tc: Option<f64>,
    /// t_c − t where the formula's real part crosses zero.
    pub zero_crossing_before_tc: Option<f64>,
    /// max |λ_formula − λ_exact| / |λ_exact| over the slow pair along the stick (v ≤ 1).
    pub max_relative_difference_on_stick: f64,
}

/// The polynomial's eigenvalues against nalgebra's Schur decomposition of the matrix.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MatrixCheck {
    /// Samples where the matrix route resolves the slow pair (1e-16 ‖J‖ ≤ 1e-10 (1 + |λ_slow|)).
    pub samples: usize,
    /// Samples where it cannot (‖J‖ ~ γ² f'(v)/ξ too large).
    pub unresolvable: usize,
    /// max |λ_poly − λ_matrix| / (1 + |λ|) over the resolvable samples, all three eigenvalues.
    pub max_difference: Option<f64>,
}

/// Eigenvalues along the stick to t_c (the paper's Fig. 5).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig5 {
    /// t − t_c.
    pub t: Vec<f64>,
    /// v.
    pub v: Vec<f64>,
    /// The fast real eigenvalue.
    pub fast: Vec<f64>,
    /// Slow pair, larger real part.
    pub slow_re_1: Vec<f64>,
    /// Slow pair, smaller real part (= slow_re_1 when complex).
    pub slow_re_2: Vec<f64>,
    /// Slow pair, imaginary part (≥ 0).
    pub slow_im: Vec<f64>,
    /// Quasi-static formula, larger real part.
    pub quasi_re_1: Vec<f64>,
    /// Quasi-static formula, smaller real part.
    pub quasi_re_2: Vec<f64>,
    /// Quasi-static formula, imaginary part.
    pub quasi_im: Vec<f64>,
}

/// The "lyapunov" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LyapunovReport {
    /// The options used.
    pub options: LyapunovOptions,
    /// Why the section is empty, if it is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// t_c − t where the slow pair turns complex: the last real → complex transition before
    /// the zero crossing (exact eigenvalues).
    pub complex_onset_before_tc: Option<f64>,
    /// t_c − t where the slow pair's real part first crosses zero upward on the stick.
    pub zero_crossing_before_tc: Option<f64>,
    /// The two transitions with the sample spacing that bounds their location.
    pub onset: Option<Crossing>,
    /// See `zero_crossing_before_tc`.
    pub zero_crossing: Option<Crossing>,
    /// |Im λ| of the slow pair at the zero crossing (its angular frequency).
    pub frequency_at_zero_crossing: Option<f64>,
    /// v at the zero crossing.
    pub v_at_zero_crossing: Option<f64>,
    /// t0 of the cycle (v = 1 to t_c), to compare the transitions with.
    pub t0: Option<f64>,
    /// The paper's formula.
    pub quasi_static: Option<QuasiStatic>,
    /// Largest fast eigenvalue over the whole cycle.
    pub fast_eigenvalue_max: Option<f64>,
    /// Polynomial against matrix.
    pub matrix_check: Option<MatrixCheck>,
    /// Figure data.
    pub along_cycle: Option<Fig5>,
    /// Finite-time Lyapunov exponents (null with ftle_periods = 0 or without a cycle).
    pub ftle: Option<ftle::FtleReport>,
    /// Every claim with its verdict.
    pub claims: Vec<Claim>,
}

fn empty(options: &LyapunovOptions, note: String) -> LyapunovReport {
    LyapunovReport {
        options: options.clone(),
        note: Some(note),
        complex_onset_before_tc: None,
        zero_crossing_before_tc: None,
        onset: None,
        zero_crossing: None,
        frequency_at_zero_crossing: None,
        v_at_zero_crossing: None,
        t0: None,
        quasi_static: None,
        fast_eigenvalue_max: None,
        matrix_check: None,
        along_cycle: None,
        ftle: None,
        claims: vec![],
    }
}

/// Builds an integrator of the variational equations (state and fundamental matrix Φ) of a
/// DRR system with the given solver settings, starting at (0, y0) with Φ = I (the engine's
/// `variational_integrator`).
pub type VariationalFactory<'a> =
    dyn FnMut(Drr, &SolverSpec, &[f64; 3]) -> Result<Box<dyn Integrator>, SolverError> + 'a;

/// Runs the analysis on the model `params` whose "cycle" analysis produced `cycle`, with
/// `solver`'s tolerances; `variational` builds the integrators of the variational equations.
pub fn analyse(
    params: &DrrParams,
    solver: &SolverSpec,
    variational: &mut VariationalFactory<'_>,
    cycle: Option<&CycleReport>,
    options: &LyapunovOptions,
) -> Result<LyapunovReport, AnalysisError> {
    let orbit = match CyclePeriod::of_scene(cycle) {
        Ok(o) => o,
        Err(why) => return Ok(empty(options, why.into_note()?)),
    };
    let p = params;
    let drr = Drr::new(*p);
    let n = orbit.peak + 1;
    let locals: Vec<local::Local> =
        (0..orbit.len()).map(|k| local::at(&drr, &orbit.state(k))).collect();
    let stick = &locals[..n];
    let re_max: Vec<f64> = stick.iter().map(|l| l.slow_re[0]).collect();
    let disc: Vec<f64> = stick.iter().map(|l| l.slow_discriminant).collect();
    let zero = local::first_up(&orbit, &re_max, 0, n);
    let onset = zero.and_then(|z| local::last_down(&orbit, &disc, 0, z.index));
    let q_re: Vec<f64> = stick.iter().map(|l| l.quasi_re[0]).collect();
    let q_disc: Vec<f64> = stick.iter().map(|l| l.quasi_discriminant).collect();
    let q_zero = local::first_up(&orbit, &q_re, 0, n);
    let q_onset = q_zero.and_then(|z| local::last_down(&orbit, &q_disc, 0, z.index));
    let rel = |l: &local::Local| {
        let exact = [(l.slow_re[0], l.slow_im), (l.slow_re[1], -l.slow_im)];
        let quasi = [(l.quasi_re[0], l.quasi_im), (l.quasi_re[1], -l.quasi_im)];
        exact
            .iter()
            .zip(&quasi)
            .map(|(e, q)| (e.0 - q.0).hypot(e.1 - q.1) / e.0.hypot(e.1).max(f64::MIN_POSITIVE))
            .fold(0.0, f64::max)
    };
    let max_rel = locals[..=orbit.up].iter().map(rel).fold(0.0, f64::max);

    let mut check = MatrixCheck { samples: 0, unresolvable: 0, max_difference: None };
    for (k, l) in locals.iter().enumerate() {
        let slow_scale = 1.0 + l.slow_re[0].abs().max(l.slow_re[1].abs()).max(l.slow_im);
        let (fast, slow, amax) = local::matrix_eigenvalues(&drr, &orbit.state(k));
        if 1e-16 * amax > 1e-10 * slow_scale || l.fast.abs() < 10.0 * slow_scale {
            check.unresolvable += 1;
            continue;
        }
        check.samples += 1;
        let mut ours = if l.slow_im > 0.0 {
            [[l.slow_re[0], -l.slow_im], [l.slow_re[0], l.slow_im]]
        } else {
            [[l.slow_re[1], 0.0], [l.slow_re[0], 0.0]]
        };
        ours.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        let d_fast = (l.fast - fast[0]).abs() / (1.0 + l.fast.abs());
        let d_slow = ours
            .iter()
            .zip(&slow)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]) / (1.0 + b[0].hypot(b[1])))
            .fold(0.0, f64::max);
        check.max_difference = Some(check.max_difference.unwrap_or(0.0).max(d_fast).max(d_slow));
    }

    let t: Vec<f64> = orbit.s[..n].to_vec();
    let col = |f: &dyn Fn(&local::Local) -> f64| stick.iter().map(f).collect::<Vec<f64>>();
    let (fast, s1, s2, si) =
        (col(&|l| l.fast), col(&|l| l.slow_re[0]), col(&|l| l.slow_re[1]), col(&|l| l.slow_im));
    let (q1, q2, qi) = (col(&|l| l.quasi_re[0]), col(&|l| l.quasi_re[1]), col(&|l| l.quasi_im));
    let v: Vec<f64> = orbit.w[..n].iter().map(|w| w.exp()).collect();
    // Spacing by the slow pair, compressed (it spans 1e-2 … 1e3 near t_c).
    let a1: Vec<f64> = s1.iter().map(|x| x.asinh()).collect();
    let ai: Vec<f64> = si.iter().map(|x| x.asinh()).collect();
    let keep = decimate(&t, &[&a1, &ai], options.series_points);
    let fig5 = Fig5 {
        t: pick(&t, &keep),
        v: pick(&v, &keep),
        fast: pick(&fast, &keep),
        slow_re_1: pick(&s1, &keep),
        slow_re_2: pick(&s2, &keep),
        slow_im: pick(&si, &keep),
        quasi_re_1: pick(&q1, &keep),
        quasi_re_2: pick(&q2, &keep),
        quasi_im: pick(&qi, &keep),
    };
    // The frequency and v at the zero crossing: at the sample just after it.
    let at_zero = zero.map(|z| (locals[z.index].slow_im, orbit.w[z.index].exp()));
    let ftle = if options.ftle_periods > 0 {
        Some(ftle::analyse(
            *params,
            solver,
            variational,
            &orbit,
            options.ftle_periods,
            options.series_points,
        )?)
    } else {
        None
    };
    let mut report = LyapunovReport {
        options: options.clone(),
        note: None,
        complex_onset_before_tc: onset.map(|c| c.time_before_tc),
        zero_crossing_before_tc: zero.map(|c| c.time_before_tc),
        onset,
        zero_crossing: zero,
        frequency_at_zero_crossing: at_zero.map(|a| a.0),
        v_at_zero_crossing: at_zero.map(|a| a.1),
        t0: Some(-orbit.s[orbit.up]),
        quasi_static: Some(QuasiStatic {
            complex_onset_before_tc: q_onset.map(|c| c.time_before_tc),
            zero_crossing_before_tc: q_zero.map(|c| c.time_before_tc),
            max_relative_difference_on_stick: max_rel,
        }),
        fast_eigenvalue_max: Some(locals.iter().map(|l| l.fast).fold(f64::NEG_INFINITY, f64::max)),
        matrix_check: Some(check),
        along_cycle: Some(fig5),
        ftle,
        claims: vec![],
    };
    report.claims = claims(p, &report);
    Ok(report)
}

/// The paper's case this scene reproduces, if any: (γ, ξ, ε, friction) of Fig. 5 or of the
/// power-law example.
fn paper_case(p: &DrrParams) -> Option<(&'static str, Option<f64>, f64)> {
    let base = p.is_papers_model() && p.gamma == 1e3 && p.xi == 0.7;
    match p.friction {
        Friction::Log if base && p.epsilon == 0.72 => {
            Some(("Fig. 5 (γ = 1e3, ξ = 0.7, ε = 0.72)", Some(4.6), 2.3))
        }
        Friction::Power { .. } if base && p.epsilon == 0.78 => Some((
            "power law (γ = 1e3, ξ = 0.7, ε = 0.78; α not stated, Fig. 8 uses 0.15)",
            None,
            2.45,
        )),
        _ => None,
    }
}

fn claims(p: &DrrParams, r: &LyapunovReport) -> Vec<Claim> {
    let mut out = Vec::new();
    let res = |c: &Option<Crossing>| {
        c.map_or(String::new(), |c| format!("located to ±{:.1e} (sample spacing)", c.resolution))
    };
    let q = r.quasi_static.as_ref();
    if let Some((case, onset, zero)) = paper_case(p) {
        if let (Some(paper), Some(ours)) = (onset, r.complex_onset_before_tc) {
            let qs =
                q.and_then(|q| q.complex_onset_before_tc).map_or("-".into(), |x| format!("{x:.4}"));
            out.push(Claim::relative(
                &format!("{case}: the slow pair turns complex at t_c − 4.6"),
                Source::Paper,
                paper,
                ours,
                0.05,
                format!("exact eigenvalues (cubic); quasi-static formula: {qs}; {}", res(&r.onset)),
            ));
        }
        if let Some(ours) = r.zero_crossing_before_tc {
            let qs =
                q.and_then(|q| q.zero_crossing_before_tc).map_or("-".into(), |x| format!("{x:.4}"));
            let caption = r.t0.map_or(String::new(), |t0| {
                format!("; Fig. 5's caption says t_c − 2.3 t0 = t_c − {:.4}", 2.3 * t0)
            });
            out.push(Claim::relative(
                &format!("{case}: the real part of the slow pair crosses zero at t_c − {zero}"),
                Source::Paper,
                zero,
                ours,
                0.05,
                format!(
                    "exact eigenvalues; quasi-static formula: {qs}; {}{caption}",
                    res(&r.zero_crossing)
                ),
            ));
        }
    }
    if let Some(fast) = r.fast_eigenvalue_max {
        out.push(Claim::negative(
            "one eigenvalue is negative all along the trajectory",
            Source::Paper,
            fast,
            "largest fast eigenvalue over every step end of the cycle".into(),
        ));
    }
    if let (Some(z), Some(t0)) = (r.zero_crossing_before_tc, r.t0) {
        out.push(Claim::negative(
            "the real part crosses zero inside the very slow stick, before v = 1 (t_c − t0): t0 − (t_c − t_zero) < 0",
            Source::Paper,
            t0 - z,
            format!("zero crossing at t_c − {z:.4}, t0 = {t0:.4}, v there {:?}", r.v_at_zero_crossing),
        ));
    }
    if let Some(w) = r.frequency_at_zero_crossing.filter(|w| *w > 0.0) {
        out.push(Claim::absolute(
            "the eigenfrequency ω at the zero crossing is of order unity: ln ω = 0",
            Source::Paper,
            0.0,
            w.ln(),
            std::f64::consts::LN_10,
            "order of magnitude: ω within a factor 10 of 1",
            format!("ω = {w:.4}"),
        ));
    }
    if let Some(q) = q {
        out.push(Claim::absolute(
            if p.is_papers_model() {
                "the quasi-static formula λ = −B ± √(B² − ξv²) gives the slow pair for large γ"
            } else {
                "the quasi-static formula λ = −B ± √(B² − C) (the paper's, for this state law and η) gives the slow pair for large γ"
            },
            Source::Paper,
            0.0,
            q.max_relative_difference_on_stick,
            0.01,
            "1 %: the formula is the leading order in 1/γ²",
            "largest relative distance from the exact slow pair over the stick (v ≤ 1)".into(),
        ));
    }
    if let Some(d) = r.matrix_check.as_ref().and_then(|m| m.max_difference) {
        out.push(Claim::absolute(
            "eigenvalues from the characteristic polynomial agree with a matrix eigensolver",
            Source::Check,
            0.0,
            d,
            1e-6,
            "1e-6 relative to 1 + |λ| where the matrix route resolves the slow pair",
            format!(
                "over {} samples ({} too stiff for the matrix route)",
                r.matrix_check.as_ref().map_or(0, |m| m.samples),
                r.matrix_check.as_ref().map_or(0, |m| m.unresolvable)
            ),
        ));
    }
    if let Some(f) = r.ftle.as_ref() {
        if let [.., a, b] = f.per_period[..] {
            out.push(Claim::absolute(
                "FTLE: the second exponent has converged (the last two periods' Σ ln |R₂₂| agree)",
                Source::Check,
                a.ln_r[1],
                b.ln_r[1],
                1e-3 * a.ln_r[1].abs().max(1.0),
                "1e-3 × max(1, |Σ ln |R₂₂||)",
                format!("{} re-orthonormalisations over {} periods", f.cuts, f.periods),
            ));
        }
        if let Some(link) = &f.floquet {
            if let Some(Some(mu)) = link.ln_abs_nontrivial.first() {
                out.push(Claim::absolute(
                    "FTLE: λ₂ T equals ln |μ₂| of the Floquet multiplier found by shooting",
                    Source::Check,
                    *mu,
                    link.last_period_logs[1],
                    1e-3 * mu.abs().max(1.0),
                    "1e-3 × max(1, |ln |μ₂||)",
                    format!(
                        "the last period's Σ ln |R₂₂| (λ₂ T over all {} periods = {:.6}); shooting's section Jacobian has a precision floor \
                         near |μ| ~ 1e-7 at rtol 1e-10 (at γ = 1e4, ξ = 0.8, ε = 1: finite differences of the Poincaré map −17.65, \
                         FTLE −17.651, shooting −16.21; docs/asymptotics.md)",
                        f.periods, link.ftle_times_period[1]
                    ),
                ));
            }
        }
    }
    out
}

/// The CLI summary of the section.
pub fn summary(r: &LyapunovReport) -> String {
    let mut s = String::from("lyapunov:\n");
    if let Some(note) = &r.note {
        s += &format!("  (empty: {note})\n");
        return s;
    }
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
    s += &format!(
        "  slow pair complex from t_c − {}, real part > 0 from t_c − {} (ω = {}); quasi-static formula: {}, {}\n",
        opt(r.complex_onset_before_tc),
        opt(r.zero_crossing_before_tc),
        opt(r.frequency_at_zero_crossing),
        opt(r.quasi_static.as_ref().and_then(|q| q.complex_onset_before_tc)),
        opt(r.quasi_static.as_ref().and_then(|q| q.zero_crossing_before_tc)),
    );
    if let Some(f) = &r.ftle {
        s += &format!(
            "  FTLE over {} periods ({}): λ = {:.4e}, {:.4e}, {:.4e}\n",
            f.periods, f.method, f.exponents[0], f.exponents[1], f.exponents[2]
        );
        if let Some(l) = &f.floquet {
            let mu: Vec<String> = l
                .ln_abs_nontrivial
                .iter()
                .map(|m| m.map_or("-∞".into(), |x| format!("{x:.6}")))
                .collect();
            s += &format!(
                "  Floquet (shooting, T = {:.6}): ln|μ| = 0, {}; λ T = {:.6}, {:.6}, {:.4e}; last period's ln R = {:.6}, {:.6}\n",
                l.period,
                mu.join(", "),
                l.ftle_times_period[0],
                l.ftle_times_period[1],
                l.ftle_times_period[2],
                l.last_period_logs[0],
                l.last_period_logs[1]
            );
        }
    }
    s += "  claims:\n";
    s += &crate::paper::claims::summary_lines(&r.claims);
    s
}
