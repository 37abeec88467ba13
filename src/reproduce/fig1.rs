//! Fig. 1: (a) the periodic solution at γ = 10³, ξ = 0.7, ε = 0.72 (data/scenes/fig1.json);
//! (b) its period against ε at γ = 10³; (c) against log₁₀ γ at ε = 0.72 (ξ = 0.7 throughout).

use super::cases::{self, CurvePoint, PointOutcome};
use super::{Context, Output, ReproduceError, Row};
use crate::figure::{Anchor, Axis, Dash, Figure, Marker, Note, Panel, RefLine, Series, Style};
use serde_json::json;

/// Units of the dimensionless model, for captions.
pub const UNITS: &str =
    "Units: time t in D_{c}/v_{0}, slip u in D_{c}, velocity v in v_{0}, θ in A.";

/// ε values of Fig. 1b: from just above the threshold ε_c ≈ 0.7 to 1.2.
fn epsilons(reduced: bool) -> Vec<f64> {
    let n = if reduced { 4 } else { 51 };
    (0..n).map(|i| 0.702 + (1.2 - 0.702) * i as f64 / (n - 1) as f64).collect()
}

/// γ values of Fig. 1c: 10 … 10¹² every quarter decade (the paper's range, 10 … 10⁸, and beyond).
fn gammas(reduced: bool) -> Vec<f64> {
    if reduced {
        return vec![1e1, 1e3, 1e5, 1e8];
    }
    (0..=44).map(|i| 10f64.powf(1.0 + 0.25 * i as f64)).collect()
}

/// A period curve sorted for drawing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Split {
    /// (value, period) of the period-1 cycles.
    pub periodic: Vec<(f64, f64)>,
    /// (value, period of each cycle) of period-n orbits.
    pub period_n: Vec<(f64, f64)>,
    /// What happened at the other points.
    pub notes: Vec<String>,
}

/// Sorts the points of a curve into periodic ones, period-n orbits and notes on the rest.
pub fn split(points: &[CurvePoint], name: &str) -> Split {
    let mut periodic = Vec::new();
    let mut period_n = Vec::new();
    let mut notes = Vec::new();
    for p in points {
        match &p.outcome {
            PointOutcome::Periodic { period } => periodic.push((p.value, *period)),
            PointOutcome::PeriodN { periods } => {
                period_n.extend(periods.iter().map(|&t| (p.value, t)));
                notes.push(format!(
                    "{name} = {}: a period-{} orbit (each cycle's period is drawn)",
                    p.value,
                    periods.len()
                ));
            }
            PointOutcome::FixedPoint => notes.push(format!(
                "{name} = {}: the oscillation dies out (stable fixed point)",
                p.value
            )),
            PointOutcome::NotConverged { .. } => notes.push(format!(
                "{name} = {}: the cycle analysis did not converge within its limits (not drawn)",
                p.value
            )),
            PointOutcome::Failed { error } => {
                notes.push(format!("{name} = {}: failed: {error} (not drawn)", p.value))
            }
        }
    }
    Split { periodic, period_n, notes }
}

/// Least-squares slope of y against x.
pub fn slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (mx, my) =
        (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

fn curve_panel(title: &str, x: Axis, periodic: &[(f64, f64)], period_n: &[(f64, f64)]) -> Panel {
    let (xs, ys): (Vec<f64>, Vec<f64>) = periodic.iter().copied().unzip();
    let mut p = Panel::new(title, x, Axis::linear("period τ").unit("D_{c}/v_{0}")).series(
        Series::new(
            "limit cycle (shooting and continuation)",
            xs,
            ys,
            Style::line(0).marker(Marker::Circle),
        )
        .width(1.2),
    );
    if !period_n.is_empty() {
        let (xs, ys): (Vec<f64>, Vec<f64>) = period_n.iter().copied().unzip();
        p = p.series(Series::new(
            "cycles of a period-n orbit",
            xs,
            ys,
            Style::markers(1, Marker::Triangle),
        ));
    }
    p
}

/// Makes Fig. 1.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let base = cases::shipped(cases::FIG1);
    let scene = cases::variant(&base, "fig1", &[], false, 2);
    let report = cases::run_scene(&scene)?;
    let tr = cases::trajectory(&report)?;
    let values = report
        .cycle
        .as_ref()
        .and_then(|c| c.values)
        .ok_or_else(|| ReproduceError::Missing("fig1: the cycle is not periodic".into()))?;

    let gamma_base = base.clone();
    let mut eps_base = base.clone();
    eps_base["model"]["epsilon"] = json!(0.72);
    let eps = cases::period_curve(ctx, &eps_base, "epsilon", &epsilons(ctx.reduced));
    let gam = cases::period_curve(ctx, &gamma_base, "gamma", &gammas(ctx.reduced));
    let Split { periodic: eps_ok, period_n: eps_n, notes: eps_notes } = split(&eps, "ε");
    let Split { periodic: gam_ok, period_n: gam_n, notes: gam_notes } = split(&gam, "γ");
    out.notes.extend(eps_notes.into_iter().map(|n| format!("Fig. 1b: {n}")));
    out.notes.extend(gam_notes.into_iter().map(|n| format!("Fig. 1c: {n}")));

    // (a) the solution over two cycles.
    let t = &tr.t;
    let lnv_line =
        RefLine::horizontal(1.0, "v = 1 (the drive)", Style::line(3).dash(Dash::Dotted).width(1.0));
    let a_v = Panel::new(
        "(a) velocity",
        Axis::linear("t").unit("D_{c}/v_{0}"),
        Axis::log10("v").unit("v_{0}"),
    )
    .series(Series::new("", t.clone(), tr.v.clone(), Style::line(0)))
    .line(lnv_line);
    let a_u = Panel::new(
        "(a) slip",
        Axis::linear("t").unit("D_{c}/v_{0}"),
        Axis::linear("u").unit("D_{c}"),
    )
    .series(Series::new("", t.clone(), tr.u.clone(), Style::line(1)));
    let a_th =
        Panel::new("(a) state", Axis::linear("t").unit("D_{c}/v_{0}"), Axis::linear("θ").unit("A"))
            .series(Series::new("", t.clone(), tr.theta.clone(), Style::line(2)));
    let a_cycle = Panel::new(
        "(a) the limit cycle in the (u, v) plane",
        Axis::linear("u").unit("D_{c}"),
        Axis::log10("v").unit("v_{0}"),
    )
    .series(Series::new("", tr.u.clone(), tr.v.clone(), Style::line(0)))
    .line(RefLine::horizontal(1.0, "", Style::line(3).dash(Dash::Dotted).width(1.0)))
    .note(
        Note::new(
            values.extremes.u_at_v_max,
            values.main.v_max,
            format!("v_{{max}} = {:.1}", values.main.v_max),
            Anchor::Middle,
        )
        .offset(0.0, 22.0),
    );

    // (b) and (c).
    let b = curve_panel(
        "(b) period against ε (γ = 10^{3})",
        Axis::linear("ε").dimensionless(),
        &eps_ok,
        &eps_n,
    );
    let log_g: Vec<(f64, f64)> = gam_ok.iter().map(|&(g, p)| (g.log10(), p)).collect();
    let log_gn: Vec<(f64, f64)> = gam_n.iter().map(|&(g, p)| (g.log10(), p)).collect();
    let c = curve_panel(
        "(c) period against log_{10} γ (ε = 0.72)",
        Axis::linear("log_{10} γ").dimensionless(),
        &log_g,
        &log_gn,
    );

    let fig = Figure::new("Fig. 1: periodic solution and its period (ξ = 0.7)")
        .columns(3)
        .panel_size(420.0, 310.0)
        .panel(a_v)
        .panel(a_u)
        .panel(a_th)
        .panel(a_cycle)
        .panel(b)
        .panel(c)
        .caption(format!(
            "(a) The converged limit cycle for γ = 10^{{3}}, ξ = 0.7, ε = 0.72 (two periods; t = 0 at an upward crossing of v = 1): period {:.4}, t_{{0}} = {:.4}, v_{{max}} = {:.1}. \
             (b, c) Period of the periodic orbit by shooting and continuation (Radau5; beyond γ = 10^{{8}} the brute-force cycle analysis, {}), {} and {} points at rtol {:e}.",
            values.main.period,
            values.main.t0,
            values.main.v_max,
            report.solver.method.name(),
            eps.len(),
            gam.len(),
            report.solver.rtol
        ))
        .caption(UNITS);
    out.files.push(ctx.write_figure("fig1.svg", &fig)?);
    out.files.push(ctx.write_json("fig1.json", &report)?);
    out.files.push(ctx.write_json(
        "fig1b-period-vs-epsilon.json",
        &json!({ "gamma": 1e3, "xi": 0.7, "points": eps }),
    )?);
    out.files.push(ctx.write_json(
        "fig1c-period-vs-gamma.json",
        &json!({ "xi": 0.7, "epsilon": 0.72, "points": gam }),
    )?);

    // Claims.
    for c in report.paper.iter().flatten() {
        out.claims.push(Row::from_claim("Fig. 1a", c));
    }
    let increasing = eps_ok.windows(2).filter(|w| w[1].1 > w[0].1).count();
    if eps_ok.len() >= 2 {
        out.claims.push(Row::qualitative(
            "Fig. 1b",
            "the period increases with ε (γ = 10³, ξ = 0.7)",
            "increases",
            format!(
                "increases at {increasing} of {} steps, {:.3} → {:.3}",
                eps_ok.len() - 1,
                eps_ok[0].1,
                eps_ok[eps_ok.len() - 1].1
            ),
            increasing == eps_ok.len() - 1,
            format!(
                "periods by continuation at ε = {:.3} … {:.3}",
                eps_ok[0].0,
                eps_ok[eps_ok.len() - 1].0
            ),
        ));
    }
    let lower: Vec<(f64, f64)> =
        eps_ok.iter().copied().filter(|p| (0.9..=1.05).contains(&p.0)).collect();
    let upper: Vec<(f64, f64)> =
        eps_ok.iter().copied().filter(|p| (1.05..=1.2).contains(&p.0)).collect();
    if let (Some(s1), Some(s2)) = (slope(&lower), slope(&upper)) {
        let ratio = s2 / s1;
        out.claims.push(Row::qualitative(
            "Fig. 1b",
            "the period reaches a linear dependence on ε",
            "linear",
            format!("dτ/dε = {s1:.3} on [0.9, 1.05], {s2:.3} on [1.05, 1.2] (ratio {ratio:.3})"),
            (ratio - 1.0).abs() <= 0.05,
            "least-squares slopes on two halves of the large-ε range; linear if they agree within 5 %".into(),
        ));
    }
    let paper_range: Vec<(f64, f64)> =
        log_g.iter().copied().filter(|p| p.0 <= 8.0 + 1e-9).collect();
    if let Some(s) = slope(&paper_range) {
        let local = |lo: f64, hi: f64| {
            slope(
                &log_g
                    .iter()
                    .copied()
                    .filter(|p| p.0 >= lo - 1e-9 && p.0 <= hi + 1e-9)
                    .collect::<Vec<_>>(),
            )
        };
        let fmt = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.3}"));
        out.claims.push(Row::numeric(
            "Fig. 1c",
            "the period grows nearly as 5 log₁₀ γ (ε = 0.72, ξ = 0.7)",
            5.0,
            s,
            format!(
                "least-squares slope of the period per decade of γ over γ = 10 … 10⁸; local slopes: {} (10 … 10³), {} (10³ … 10⁸), {} (10⁸ … 10¹²)",
                fmt(local(1.0, 3.0)),
                fmt(local(3.0, 8.0)),
                fmt(local(8.0, 12.0))
            ),
        ));
    }
    // The paper's earthquake case (text after Fig. 1): τ = 28 for γ = 1e8, ξ = 0.8, ε = 1.
    let quake = cases::run_scene(&cases::variant(
        &cases::shipped(cases::EARTHQUAKE),
        "earthquake",
        &[],
        false,
        0,
    ))?;
    out.files.push(ctx.write_json("earthquake.json", &quake)?);
    for c in quake.paper.iter().flatten().filter(|c| c.claim.starts_with("earthquake")) {
        out.claims.push(Row::from_claim("text (earthquake case)", c));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slopes_and_splits() {
        assert_eq!(slope(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]), Some(2.0));
        assert_eq!(slope(&[(1.0, 1.0)]), None);
        assert_eq!(slope(&[(1.0, 1.0), (1.0, 2.0)]), None);
        let pts = vec![
            CurvePoint { value: 1.0, outcome: PointOutcome::Periodic { period: 10.0 } },
            CurvePoint { value: 2.0, outcome: PointOutcome::PeriodN { periods: vec![9.0, 11.0] } },
            CurvePoint { value: 3.0, outcome: PointOutcome::NotConverged { last_periods: vec![] } },
            CurvePoint { value: 4.0, outcome: PointOutcome::Failed { error: "boom".into() } },
        ];
        let s = split(&pts, "ε");
        assert_eq!(s.periodic, vec![(1.0, 10.0)]);
        assert_eq!(s.period_n, vec![(2.0, 9.0), (2.0, 11.0)]);
        assert_eq!(s.notes.len(), 3);
        assert!(s.notes[2].contains("boom"));
        assert_eq!(epsilons(false).len(), 51);
        assert!((epsilons(false)[50] - 1.2).abs() < 1e-12);
        assert_eq!(gammas(false).len(), 45);
        assert!((gammas(false)[44] / 1e12 - 1.0).abs() < 1e-12);
    }
}
