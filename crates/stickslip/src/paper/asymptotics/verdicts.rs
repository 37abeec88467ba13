//! The claims of the asymptotic analysis with their verdicts. Each criterion comes from what
//! the claim says, stated in the claim; the numbers behind each verdict are in the section.

use super::manifold::ManifoldReport;
use super::matching::{MatchingReport, PAPER_ZERO_ACCELERATION, THETA_EXTREMA, ZERO_ACCELERATION};
use super::scan::ScanValues;
use super::singular_limit::SingularLimitReport;
use super::slip_scaling::SlipScalingReport;
use super::AsymptoticsOptions;
use crate::model::{DrrParams, Friction};
use crate::numerics::fit::least_squares;
use crate::paper::claims::{Claim, Source};

/// The claims about the stick and the matching (the paper's Fig. 3): the first of
/// [`claims`], empty without a cycle.
pub fn stick_claims(i: &Inputs) -> Vec<Claim> {
    let mut out = Vec::new();
    if let Some(m) = i.manifold {
        manifold_claims(m, i, &mut out);
        if let Some(mt) = i.matching {
            matching_claims(mt, m.t0_3d, &mut out);
        }
    }
    out
}

/// What the claims are judged on.
pub struct Inputs<'a> {
    /// Model parameters of the scene.
    pub params: &'a DrrParams,
    /// The analysis options.
    pub options: &'a AsymptoticsOptions,
    /// The manifold part (None without a cycle).
    pub manifold: Option<&'a ManifoldReport>,
    /// The matching part (None without a cycle).
    pub matching: Option<&'a MatchingReport>,
    /// The slip-scaling part.
    pub slip: &'a SlipScalingReport,
    /// The singular-limit part.
    pub singular: &'a SingularLimitReport,
    /// All periodic scan points, increasing γ.
    pub all: &'a [(f64, ScanValues)],
}

fn manifold_claims(m: &ManifoldReport, i: &Inputs, out: &mut Vec<Claim>) {
    let g2 = i.params.gamma * i.params.gamma;
    out.push(Claim::absolute(
        "the stick follows the 2D slow flow on S (deviation O(1/γ²))",
        Source::Paper,
        0.0,
        m.stick_deviation.max_abs_ln_v,
        i.options.manifold_tolerance,
        "the tolerance that defines \"on S\", option manifold_tolerance",
        format!(
            "max |ln v₃ − ln v₂| at equal times over {} step ends of the stick (to v = 1); × γ² = {:.4}; max |Δu| = {:.3e}, max |Δθ| = {:.3e} (γ² = {g2:e})",
            m.stick_deviation.samples, m.stick_deviation.max_abs_ln_v_times_gamma2, m.stick_deviation.max_abs_u, m.stick_deviation.max_abs_theta
        ),
    ));
    let tol = 0.05 * m.t0_3d;
    match m.blow_up_offset {
        Some(offset) => out.push(Claim::absolute(
            "the 2D slow flow blows up in finite time at the end of the stick: t_c(2D) − t_c = 0",
            Source::Paper,
            0.0,
            offset,
            tol,
            "5 % of t0, the time scale of the final acceleration",
            format!(
                "2D flow from the 3D cycle's v minimum; t0(2D) = {:?}, t0(3D) = {:.6}",
                m.t0_2d, m.t0_3d
            ),
        )),
        None => out.push(Claim::absolute(
            "the 2D slow flow blows up in finite time at the end of the stick: t_c(2D) − t_c = 0",
            Source::Paper,
            0.0,
            m.followed_until,
            tol,
            "5 % of t0",
            "NO blow-up of the 2D flow within two periods; ours is a lower bound on the offset"
                .into(),
        )),
    }
    if let (Some(t0_2d), Some((g, last))) = (m.t0_2d, i.all.last()) {
        out.push(Claim::relative(
            "t0 is a γ-independent constant of the reduced 2D flow (time from v = 1 to its blow-up)",
            Source::Prediction,
            last.t0,
            t0_2d,
            0.05,
            format!("reference: 3D t0 at the largest γ of the scan ({g:e}); ours: the 2D flow from this scene's cycle (3D t0 here {:.6})", m.t0_3d),
        ));
    }
    if let Some(p) = &m.leaves_manifold {
        out.push(Claim::absolute(
            "the 3D flow leaves S near the adiabatic limit v = γ (θ = −ξu − f(γ)): ln(v/γ) = 0",
            Source::Paper,
            0.0,
            p.v_over_gamma.ln(),
            std::f64::consts::LN_10,
            "an order-of-magnitude estimate: v within a factor 10 of γ",
            format!(
                "first point of the rise with |ln v − ln v_S| > {} (v/γ = {:.3e}, t_c − t = {:.3e})",
                m.departure_offset, p.v_over_gamma, p.time_before_tc
            ),
        ));
    }
}

fn matching_claims(m: &MatchingReport, t0: f64, out: &mut Vec<Claim>) {
    let scale = 0.01 * m.theta_range;
    if let Some(b) = &m.before {
        out.push(Claim::negative(
            "finite-time condition: c < 0 on the matching curve before the catastrophe",
            Source::Paper,
            b.c,
            format!(
                "least-squares c over {} step ends with v in [{:.3e}, {:.3e}] on S",
                b.points, b.v_range[0], b.v_range[1]
            ),
        ));
    }
    if m.after.is_none() {
        out.push(Claim::at_least(
            "a matching region exists after the catastrophe: the descent is back on S while v ≥ window_v_min",
            Source::Paper,
            m.window_v_min,
            m.descent_on_manifold_v_max.unwrap_or(1.0),
            format!(
                "largest v at which the descent is within {} of S in ln v (1 if only below v = 1): the slip arrest brings v down \
                 off S, so the paper's second matching branch has no data here",
                m.window_manifold_tolerance
            ),
        ));
    }
    for (branch, which) in [(&m.before, "before"), (&m.after, "after")] {
        if let Some(b) = branch {
            out.push(Claim::absolute(
                &format!("θ(u) = c e^{{εu}} − K(1+εu) fits the cycle {which} the catastrophe"),
                Source::Paper,
                0.0,
                b.residual_rms,
                scale,
                "1 % of the cycle's θ range: indistinguishable in Fig. 3b",
                format!("RMS residual in θ over {} step ends (max {:.3e}), c = {:.6e}, u in [{:.4}, {:.4}]", b.points, b.residual_max, b.c, b.u_range[0], b.u_range[1]),
            ));
        }
    }
    if let Some(p) = &m.predicted_blow_up {
        out.push(Claim::absolute(
            "the matching solution u' = e^{Φ(u)} blows up at the catastrophe: t_c(matching) − t_c = 0",
            Source::Paper,
            0.0,
            p.offset_from_tc,
            0.05 * t0,
            "5 % of t0",
            format!("∫ e^{{−Φ}} du = {:.6e} from u = {:.4} (t_c − t = {:.4e}) with c before", p.integral, p.u_start, p.from_time_before_tc),
        ));
    }
    let line_claim = |index: usize, source: Source, claim: &str| {
        let d = &m.extrema_distances[index];
        Claim::absolute(
            claim,
            source,
            0.0,
            d.at_theta_max.abs().max(d.at_theta_min.abs()),
            0.05 * m.theta_range,
            "5 % of the cycle's θ range: visibly on the line in Fig. 3b",
            format!(
                "θ − line(u) at the θ maximum {:.4}, at the θ minimum {:.4}",
                d.at_theta_max, d.at_theta_min
            ),
        )
    };
    out.push(line_claim(
        PAPER_ZERO_ACCELERATION,
        Source::Paper,
        "the zero-acceleration line, as printed εθ = (1+ε)u − ξ, joins the two θ extrema of the cycle",
    ));
    out.push(line_claim(
        ZERO_ACCELERATION,
        Source::Prediction,
        "the derived zero-acceleration line εθ = −(1+ε)ξu − ξ joins the two θ extrema",
    ));
    let d = &m.extrema_distances[THETA_EXTREMA];
    out.push(Claim::absolute(
        "the stick's θ maximum lies on εθ = −(1+ε)ξu (dθ/dt = 0 on S)",
        Source::Prediction,
        0.0,
        d.at_theta_max,
        1e-3 * m.theta_range,
        "0.1 % of the θ range (the maximum is on S to O(1/γ²))",
        format!("θ − line(u) at the θ maximum; the θ minimum, reached during the slip off S, is {:.4} from the line", d.at_theta_min),
    ));
}

fn slip_claims(s: &SlipScalingReport, out: &mut Vec<Claim>) {
    for (fit, name, c) in
        [(&s.u_at_v_max, "u", "c_u = ε/ξ"), (&s.theta_at_v_max, "θ", "c_θ = −(1+ε)")]
    {
        if let Some(f) = &fit.with_ln_ln {
            let linear = fit.linear.as_ref().map_or("-".into(), |l| {
                format!("{:.4} (rms {:.1e})", l.coefficients[1], l.residual_rms)
            });
            out.push(Claim::relative(
                &format!("{name} at the v maximum moves by {c} per unit ln γ"),
                Source::Paper,
                fit.predicted_slope,
                f.coefficients[1],
                0.05,
                format!(
                    "b of a + b ln γ + d ln ln γ over {} scan points (γ ≥ {:e}): d = {:.4}, rms {:.1e}; without the ln ln γ term b = {linear}",
                    f.points, s.fit_min_gamma, f.coefficients[2], f.residual_rms
                ),
            ));
        }
    }
    let h = &s.half_width;
    if let (Some(at), Some(gamma)) = (h.at_largest_gamma, h.largest_gamma) {
        let limit = h.fit.as_ref().map_or("no power-law fit".into(), |f| {
            format!("extrapolated limit {:.5} (exponent {:.2})", f.limit, f.exponent)
        });
        out.push(Claim::relative(
            "the slip half-width is about 2.5/γ \"in a wide range of parameters\" (half-width × γ at the largest γ)",
            Source::Paper,
            2.5,
            at,
            0.05,
            format!("at γ = {gamma:e}, decreasing with γ across the scan; {limit}"),
        ));
    }
    if let (Some(f), Some(unc)) = (&h.fit, h.limit_uncertainty) {
        let reference = 2.0 * std::f64::consts::PI / 3.0;
        out.push(Claim::absolute(
            "half-width × γ → 2π/3 (half-sine of frequency γ)",
            Source::Prediction,
            reference,
            f.limit,
            (3.0 * unc).max(1e-3 * reference),
            "3 × the limit's change when the fit drops its smallest or largest γ, at least 0.1 %",
            format!("limit of a + b (ln γ)^(−p) over {} scan points: p = {:.3}, b = {:.3}, rms {:.1e}; value at the largest γ {:?}", f.points, f.exponent, f.amplitude, f.residual_rms, h.at_largest_gamma),
        ));
    }
    if let Some(f) = &s.fast_system {
        let why = "tolerance: the larger of 1/v at the start (the neglected drive's relative size) and the 3D value's spread over the converged cycles";
        out.push(Claim::relative(
            "the γ-free fast system reproduces the slip: V_max",
            Source::Check,
            f.v_max_over_gamma_3d,
            f.v_max_fast,
            f.neglected_drive.max(f.spread_3d[0]),
            format!("fast system from the 3D state at v/γ = {:.3e}; {why}", f.start_v_over_gamma),
        ));
        if let (Some(a), Some(b)) = (f.half_width_times_gamma_3d, f.half_width_fast) {
            out.push(Claim::relative(
                "the γ-free fast system reproduces the slip: half-width in T = γt",
                Source::Check,
                a,
                b,
                f.neglected_drive.max(f.spread_3d[1]),
                why.into(),
            ));
        }
    }
}

fn singular_claims(sl: &SingularLimitReport, i: &Inputs, out: &mut Vec<Claim>) {
    let p = &sl.period;
    if let Some(f) = &p.with_ln_ln {
        let lin = p.linear.as_ref().map_or("-".into(), |l| format!("{:.4}", l.coefficients[1]));
        out.push(Claim::relative(
            "period ≈ (2ε/ξ) ln γ + O(ln ln γ): slope per unit ln γ",
            Source::Prediction,
            p.predicted_slope_per_ln_gamma,
            f.coefficients[1],
            0.05,
            format!("b of a + b ln γ + d ln ln γ over {} scan points (d = {:.4}); b of a + b ln γ alone: {lin}", f.points, f.coefficients[2]),
        ));
    }
    if let Some(last) = p.local_slopes.last() {
        out.push(Claim::relative(
            "the period's slope per decade tends to 2ε ln 10/ξ",
            Source::Prediction,
            p.predicted_slope_per_decade,
            last.per_decade,
            0.05,
            format!("local slope between γ = {:e} and {:e}", last.from_gamma, last.to_gamma),
        ));
    }
    let fig1 = i.params.friction == Friction::Log && i.params.xi == 0.7 && i.params.epsilon == 0.72;
    let paper_range: Vec<&(f64, ScanValues)> =
        i.all.iter().filter(|(g, _)| (10.0..=1e4).contains(g)).collect();
    if fig1 && paper_range.len() >= 2 {
        let x: Vec<f64> = paper_range.iter().map(|(g, _)| g.log10()).collect();
        let y: Vec<f64> = paper_range.iter().map(|(_, v)| v.period).collect();
        if let Some(f) = least_squares("a + b log₁₀ γ", &x, &y, &[&|_| 1.0, &|x| x]) {
            out.push(Claim::relative(
                "Fig. 1c: the period grows nearly as 5 log₁₀ γ (ξ = 0.7, ε = 0.72)",
                Source::Paper,
                5.0,
                f.coefficients[1],
                0.05,
                format!("least-squares slope over the {} scan points with 10 ≤ γ ≤ 1e4 (the paper's systematic range)", f.points),
            ));
        }
    }
    if let Some(last) = sl.ln_v_max.last() {
        let trend: Vec<String> = sl
            .ln_v_max
            .iter()
            .map(|r| format!("{:+.3} (γ = {:e})", r.difference, r.gamma))
            .collect();
        out.push(Claim::absolute(
            "ln v_max ≈ ln γ + ln ln γ + ln(ε/ξ)",
            Source::Prediction,
            last.predicted,
            last.ours,
            0.1,
            "v_max within about 10 %",
            format!("at the largest γ; ours − predicted across the scan: {}", trend.join(", ")),
        ));
    }
    for inv in &sl.invariants {
        if let (Some(change), Some(last)) = (inv.relative_change_per_decade, inv.values.last()) {
            out.push(Claim::absolute(
                &format!("{} is independent of γ", inv.quantity),
                Source::Prediction,
                0.0,
                change,
                1e-3,
                "0.1 % per decade",
                format!("relative change per decade between the two largest γ of the scan; {} = {:.8} at γ = {:e}", inv.quantity, last[1], last[0]),
            ));
        }
    }
}

/// Every claim of the asymptotic analysis.
pub fn claims(i: &Inputs) -> Vec<Claim> {
    let mut out = stick_claims(i);
    // The shifts by multiples of ln γ and the singular-limit picture are derived for
    // f = ln v; for other friction laws the scan's data are reported without verdicts.
    if i.params.friction == Friction::Log {
        slip_claims(i.slip, &mut out);
        singular_claims(i.singular, i, &mut out);
    }
    out
}
