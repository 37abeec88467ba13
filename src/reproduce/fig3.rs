//! Fig. 3: the stick as the 2D slow flow on S and the matching curves, from the
//! "asymptotics" analysis (docs/asymptotics.md) on the Fig. 1a cycle
//! (data/scenes/fig1-asymptotics.json: γ = 10³, ξ = 0.7, ε = 0.72): (a) v/γ of the 2D flow on
//! S and of the 3D flow against t − t_c near the catastrophe t_c (the 3D v maximum); (b) the
//! (u, θ) plane: the 3D cycle, the 2D flow on S, the two matching curves
//! θ = c e^{εu} − K(1 + εu), the zero-acceleration lines and the adiabatic limit
//! θ = −ξu − ln γ.

use super::cases;
use super::fig1::UNITS;
use super::{Context, Output, ReproduceError, Row};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Panel, RefLine, Series, Style};
use serde_json::json;
use stickslip::paper::asymptotics::{matching, scan, verdicts};

/// Window of the zoom (b) in t − t_c: the slip lasts a few 1/γ.
const ZOOM: (f64, f64) = (-0.015, 0.02);

/// Makes Fig. 3.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let mut scene = cases::shipped(cases::FIG1_ASYMPTOTICS);
    scene["name"] = json!("fig3");
    // The γ scan (1e2 … 1e12, about a second) is kept: the claim "t0 is γ-independent" takes
    // its reference at the largest γ.
    scene["analyses"] = json!(["cycle", "asymptotics"]);
    let params = stickslip::scene::parse(&scene.to_string(), "fig3")
        .map_err(|e| ReproduceError::Scene(e.to_string()))?
        .params;
    let report = cases::run_scene(&scene)?;
    let a = report
        .asymptotics
        .as_ref()
        .ok_or_else(|| ReproduceError::Missing("fig3: no asymptotics section".into()))?;
    let why = || a.note.clone().unwrap_or_else(|| "no reason given".into());
    let m = a.manifold.as_ref().ok_or_else(|| {
        ReproduceError::Missing(format!("fig3: no slow-manifold part ({})", why()))
    })?;
    let mt = a
        .matching
        .as_ref()
        .ok_or_else(|| ReproduceError::Missing(format!("fig3: no matching part ({})", why())))?;
    let f = &m.fig3a;
    let gamma = params.gamma;

    // (a) v/γ over the whole stick, log scale.
    let departure = m.leaves_manifold.map(|p| -p.time_before_tc);
    let mark = |p: Panel| match departure {
        Some(t) => p.line(RefLine::vertical(
            t,
            "3D leaves S",
            Style::line(3).dash(Dash::Dotted).width(1.0),
        )),
        None => p,
    };
    let pa = Panel::new(
        "(a) v/γ of the 2D flow on S and of the 3D flow",
        Axis::linear("t − t_{c}").unit("D_{c}/v_{0}"),
        Axis::log10("v/γ").dimensionless(),
    )
    .series(Series::new(
        "3D flow",
        f.t_3d.clone(),
        f.v_over_gamma_3d.clone(),
        Style::line(0).width(2.6),
    ))
    .series(Series::new(
        "2D flow on S",
        f.t_2d.clone(),
        f.v_over_gamma_2d.clone(),
        Style::line(1).dash(Dash::Dashed),
    ))
    .legend(LegendPlace::TopLeft);
    // (b) zoom on the catastrophe, linear scale, clipped at 1.2 × the 3D maximum.
    let v3max = f.v_over_gamma_3d.iter().copied().fold(0.0, f64::max);
    let window = |t: &[f64], y: &[f64]| -> (Vec<f64>, Vec<f64>) {
        let first = t.iter().rposition(|&x| x < ZOOM.0).unwrap_or(0);
        (t[first..].to_vec(), y[first..].to_vec())
    };
    let (t3, y3) = window(&f.t_3d, &f.v_over_gamma_3d);
    let (t2, y2) = window(&f.t_2d, &f.v_over_gamma_2d);
    let pb = Panel::new(
        "(b) the same near t_{c}",
        Axis::linear("t − t_{c}").unit("D_{c}/v_{0}").range(ZOOM.0, ZOOM.1),
        Axis::linear("v/γ").dimensionless().range(0.0, 1.2 * v3max),
    )
    .series(Series::new("3D flow", t3, y3, Style::line(0).width(2.6)))
    .series(Series::new("2D flow on S", t2, y2, Style::line(1).dash(Dash::Dashed)))
    .legend(LegendPlace::TopRight);

    // (c) the (u, θ) plane.
    let b = &mt.fig3b;
    let (u_lo, u_hi) = (b.u_span[0], b.u_span[1]);
    let (th_lo, th_hi) = b
        .cycle_theta
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let (du, dth) = (0.08 * (u_hi - u_lo), 0.12 * (th_hi - th_lo));
    let (x0, x1) = (u_lo - du, u_hi + du);
    let line = |l: &matching::Line, label: &str, style: Style| {
        Series::new(
            label,
            vec![x0, x1],
            vec![l.intercept + l.slope * x0, l.intercept + l.slope * x1],
            style,
        )
    };
    let mut pc = Panel::new(
        "(c) the (u, θ) plane",
        Axis::linear("u").unit("D_{c}").range(x0, x1),
        Axis::linear("θ").unit("A").range(th_lo - dth, th_hi + 4.0 * dth),
    )
    .series(Series::new(
        "3D limit cycle",
        b.cycle_u.clone(),
        b.cycle_theta.clone(),
        Style::line(0).dash(Dash::Dashed).width(1.6),
    ))
    .series(Series::new(
        "2D flow on S",
        b.slow_u.clone(),
        b.slow_theta.clone(),
        Style::line(3).width(2.6),
    ));
    if !b.before_u.is_empty() {
        pc = pc.series(Series::new(
            "matching, c before t_{c}",
            b.before_u.clone(),
            b.before_theta.clone(),
            Style::line(4).width(1.6),
        ));
    }
    if !b.after_u.is_empty() {
        pc = pc.series(Series::new(
            "matching, c after t_{c}",
            b.after_u.clone(),
            b.after_theta.clone(),
            Style::line(2).width(1.6),
        ));
    }
    let lines = &mt.lines;
    pc = pc
        .series(line(
            &lines[matching::PAPER_ZERO_ACCELERATION],
            "zero acceleration (as printed)",
            Style::line(5).dash(Dash::DashDot).width(1.2),
        ))
        .series(line(
            &lines[matching::ZERO_ACCELERATION],
            "zero acceleration (derived)",
            Style::line(6).dash(Dash::Dotted).width(1.4),
        ))
        .series(line(
            &lines[matching::ADIABATIC],
            "adiabatic limit",
            Style::line(1).dash(Dash::Dashed).width(1.2),
        ))
        .legend(LegendPlace::TopRight);

    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3e}"));
    let fig = Figure::new("Fig. 3: the stick as the slow flow on S and the matching curves (γ = 10^{3}, ξ = 0.7, ε = 0.72)")
        .columns(3)
        .panel_size(420.0, 360.0)
        .panel(mark(pa))
        .panel(mark(pb))
        .panel(pc)
        .caption(format!(
            "The 2D flow on S (ξu + θ + ln v = 0) started at the 3D cycle's v minimum blows up at t_{{c}}(2D) − t_{{c}} = {}; along the stick it stays within {:.1e} of the 3D flow in ln v, \
             which leaves S (|Δ ln v| > {}) at t_{{c}} − {} (v/γ = {}). t_{{c}}: the 3D v maximum.",
            opt(m.blow_up_offset),
            m.stick_deviation.max_abs_ln_v,
            m.departure_offset,
            m.leaves_manifold.map_or("-".into(), |p| format!("{:.2e}", p.time_before_tc)),
            m.leaves_manifold.map_or("-".into(), |p| format!("{:.3}", p.v_over_gamma)),
        ))
        .caption(format!(
            "(c) matching curves θ = c e^{{εu}} − K(1+εu), K = {:.4}, c fitted on the cycle where v ≥ {} on S: before t_{{c}} c = {}, after c = {}. \
             Zero acceleration as printed in the paper: εθ = (1+ε)u − ξ; as derived on S for v ≫ 1: εθ = −(1+ε)ξu − ξ; adiabatic limit: θ = −ξu − ln γ, γ = {gamma:e}.",
            mt.k,
            mt.window_v_min,
            mt.before.as_ref().map_or("-".into(), |b| format!("{:.4e}", b.c)),
            mt.after.as_ref().map_or("-".into(), |b| format!("{:.4e}", b.c)),
        ))
        .caption(UNITS);
    out.files.push(ctx.write_figure("fig3.svg", &fig)?);
    out.files.push(ctx.write_json("fig3.json", &report)?);
    let all = scan::usable(&a.scan, 0.0);
    let inputs = verdicts::Inputs {
        params: &params,
        options: &a.options,
        manifold: Some(m),
        matching: Some(mt),
        slip: &a.slip_scaling,
        singular: &a.singular_limit,
        all: &all,
    };
    let stick = verdicts::stick_claims(&inputs);
    debug_assert!(
        stick.iter().zip(&a.claims).all(|(s, c)| s == c),
        "the stick claims are the report's first claims"
    );
    out.claims.extend(stick.iter().map(|c| Row::from_analysis("Fig. 3", c)));
    Ok(out)
}
