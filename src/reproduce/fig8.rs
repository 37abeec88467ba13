//! Fig. 8: power-law friction g_α(v) = (v^α − 1)/α in place of ln v (γ = 10, ξ = 0.7,
//! ε = 1): (a, b) the two limit cycles (α = 0.31, data/scenes/power-law.json); (c) the laws;
//! (d) the ratios of the power-law cycle's period and amplitude to the ln v cycle's, against α.

use super::cases;
use super::fig1::UNITS;
use super::{Context, Output, ReproduceError, Row};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Marker, Panel, RefLine, Series, Style};
use stickslip::analysis::cycle::CycleValues;
use stickslip::model::Friction;

fn alphas(reduced: bool) -> Vec<f64> {
    // Up to 0.3: from α ≈ 0.32 on (γ = 10, ξ = 0.7, ε = 1) v falls to 0 in finite time after
    // the slip (g_α is bounded below: the block stops), which the integration in ln v cannot
    // pass; those runs end in a typed error.
    if reduced {
        vec![0.1, 0.3]
    } else {
        (1..=12).map(|i| 0.025 * i as f64).collect()
    }
}

/// The amplitude compared in (d): the range of u over the cycle (units of D_c).
fn amplitude(v: &CycleValues) -> f64 {
    v.extremes.u_max - v.extremes.u_min
}

/// Makes Fig. 8.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let power = cases::shipped(cases::POWER_LAW);
    let log_scene = cases::variant(&power, "fig8-log", &[], true, 2);
    let power_scene = cases::variant(&power, "fig8-power-0.31", &[], false, 2);
    let alphas = alphas(ctx.reduced);
    let mut scenes = vec![log_scene, power_scene];
    scenes.extend(alphas.iter().map(|&a| {
        let mut s =
            cases::variant(&power, &format!("fig8-power-{a:.3}"), &[("alpha", a)], false, 0);
        s["analyses"] = serde_json::json!(["cycle"]);
        s
    }));
    let results = cases::parallel(ctx, &scenes, cases::run_scene);
    let mut results = results.into_iter();
    let log = results.next().expect("scene 0")?;
    let pow = results.next().expect("scene 1")?;
    let periodic = |r: &stickslip::report::Report| r.cycle.as_ref().and_then(|c| c.values);
    let log_values = periodic(&log)
        .ok_or_else(|| ReproduceError::Missing("fig8: the ln v cycle is not periodic".into()))?;
    let pow_values = periodic(&pow).ok_or_else(|| {
        ReproduceError::Missing("fig8: the power-law cycle is not periodic".into())
    })?;
    let (tl, tp) = (cases::trajectory(&log)?, cases::trajectory(&pow)?);

    let a = Panel::new(
        "(a, b) velocity: ln v and power-law friction",
        Axis::linear("t").unit("D_{c}/v_{0}"),
        Axis::log10("v").unit("v_{0}"),
    )
    .series(Series::new("f = ln v", tl.t.clone(), tl.v.clone(), Style::line(1)))
    .series(Series::new(
        "f = g_{α}(v), α = 0.31",
        tp.t.clone(),
        tp.v.clone(),
        Style::line(0).dash(Dash::Dashed),
    ))
    .line(RefLine::horizontal(1.0, "", Style::line(3).dash(Dash::Dotted).width(1.0)));
    let b = Panel::new(
        "(a, b) the two limit cycles in the (u, θ) plane",
        Axis::linear("u").unit("D_{c}"),
        Axis::linear("θ").unit("A"),
    )
    .series(Series::new("f = ln v", tl.u.clone(), tl.theta.clone(), Style::line(1)))
    .series(Series::new(
        "f = g_{α}(v), α = 0.31",
        tp.u.clone(),
        tp.theta.clone(),
        Style::line(0).dash(Dash::Dashed),
    ));

    let vs: Vec<f64> = (0..=200).map(|i| 10f64.powf(-2.0 + 4.0 * i as f64 / 200.0)).collect();
    let law = |f: Friction| vs.iter().map(|v| f.eval(v.ln()).0).collect::<Vec<f64>>();
    let c = Panel::new(
        "(c) friction laws",
        Axis::log10("v").unit("v_{0}"),
        Axis::linear("f(v)").dimensionless(),
    )
    .series(Series::new("ln v", vs.clone(), law(Friction::Log), Style::line(1)))
    .series(Series::new(
        "g_{α}, α = 0.143",
        vs.clone(),
        law(Friction::Power { alpha: 0.143 }),
        Style::line(0).dash(Dash::Dashed),
    ))
    .series(Series::new(
        "g_{α}, α = 0.333",
        vs.clone(),
        law(Friction::Power { alpha: 0.333 }),
        Style::line(2).dash(Dash::DashDot),
    ))
    .legend(LegendPlace::TopLeft);

    let mut ratio_points = Vec::new();
    for (r, &alpha) in results.zip(&alphas) {
        match r {
            Ok(report) => match periodic(&report) {
                Some(v) => ratio_points.push((
                    alpha,
                    v.main.period / log_values.main.period,
                    amplitude(&v) / amplitude(&log_values),
                    v.main.period,
                )),
                None => out.notes.push(format!(
                    "Fig. 8d: α = {alpha:.3}: no period-1 limit cycle found (not drawn)"
                )),
            },
            Err(e) => out.notes.push(format!("Fig. 8d: α = {alpha:.3}: {e} (not drawn)")),
        }
    }
    let xs: Vec<f64> = ratio_points.iter().map(|p| p.0).collect();
    let d = Panel::new(
        "(d) power law / ln v, against α",
        Axis::linear("α").dimensionless(),
        Axis::linear("ratio").dimensionless(),
    )
    .series(Series::new(
        "period ratio",
        xs.clone(),
        ratio_points.iter().map(|p| p.1).collect(),
        Style::markers(0, Marker::Circle),
    ))
    .series(Series::new(
        "amplitude ratio (range of u)",
        xs,
        ratio_points.iter().map(|p| p.2).collect(),
        Style::markers(2, Marker::Square),
    ))
    .line(RefLine::horizontal(1.0, "", Style::line(3).dash(Dash::Dotted).width(1.0)));

    let fig = Figure::new("Fig. 8: power-law friction g_{α}(v) = (v^{α} − 1)/α against ln v (γ = 10, ξ = 0.7, ε = 1)")
        .columns(2)
        .panel_size(480.0, 320.0)
        .panel(a)
        .panel(b)
        .panel(c)
        .panel(d)
        .caption(format!(
            "(a, b) Two periods of each limit cycle (t = 0 at an upward crossing of v = 1): ln v, period {:.4}; g_{{α}} with α = 0.31, period {:.4}. \
             (d) Period and amplitude (range of u over the cycle) of the power-law cycle divided by those of the ln v cycle.",
            log_values.main.period, pow_values.main.period
        ))
        .caption(UNITS);
    out.files.push(ctx.write_figure("fig8.svg", &fig)?);
    out.files.push(ctx.write_json("fig8-log.json", &log)?);
    out.files.push(ctx.write_json("fig8-power-0.31.json", &pow)?);
    out.files.push(ctx.write_json(
        "fig8d-ratios.json",
        &serde_json::json!({
            "log_period": log_values.main.period,
            "log_amplitude": amplitude(&log_values),
            "points": ratio_points.iter().map(|p| serde_json::json!({"alpha": p.0, "period": p.3, "period_ratio": p.1, "amplitude_ratio": p.2})).collect::<Vec<_>>(),
        }),
    )?);
    for c in log.paper.iter().flatten() {
        out.claims.push(Row::from_claim("Fig. 8a (ln v, γ = 10)", c));
    }
    for c in pow.paper.iter().flatten() {
        out.claims.push(Row::from_claim("Fig. 8b (α = 0.31, γ = 10)", c));
    }
    if ratio_points.len() >= 2 {
        let up = ratio_points.windows(2).filter(|w| w[1].3 > w[0].3).count();
        out.claims.push(Row::qualitative(
            "Fig. 8d",
            "with power-law friction the period increases with α",
            "increases",
            format!(
                "increases at {up} of {} steps: {:.3} (α = {:.3}) → {:.3} (α = {:.3})",
                ratio_points.len() - 1,
                ratio_points[0].3,
                ratio_points[0].0,
                ratio_points[ratio_points.len() - 1].3,
                ratio_points[ratio_points.len() - 1].0
            ),
            up == ratio_points.len() - 1,
            "limit-cycle periods at γ = 10, ξ = 0.7, ε = 1".into(),
        ));
    }
    Ok(out)
}
