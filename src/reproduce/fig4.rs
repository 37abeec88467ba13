//! Fig. 4: the trajectory of Fig. 1a leaving and landing back on the slow manifold
//! S: ξu + θ + ln v = 0. The paper draws a 3D view; here two projections that show the same:
//! (a) along S, with x = ξu + θ and y = ln v, so that S is the line y = −x; (b) the distance
//! to S, ξu + θ + ln v, against fast time around the slip.

use super::cases;
use super::fig1::UNITS;
use super::{Context, Output, ReproduceError};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Panel, RefLine, Series, Style};

/// Fast-time window of panel (b).
const WINDOW: (f64, f64) = (-10.0, 30.0);

/// Makes Fig. 4.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let base = cases::shipped(cases::FIG1);
    let report = cases::run_scene(&cases::variant(&base, "fig4", &[], false, 1))?;
    let m = &report.model;
    let (gamma, xi) = (m.gamma, m.xi);
    let tr = cases::trajectory(&report)?;
    let x: Vec<f64> = tr.u.iter().zip(&tr.theta).map(|(u, th)| xi * u + th).collect();
    let lnv: Vec<f64> = tr.v.iter().map(|v| v.ln()).collect();
    let offset: Vec<f64> = x.iter().zip(&lnv).map(|(a, b)| a + b).collect();
    let (lo, hi) =
        x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let span = hi - lo;
    let manifold_x = vec![lo - 0.05 * span, hi + 0.05 * span];
    let manifold_y: Vec<f64> = manifold_x.iter().map(|x| -x).collect();
    let a = Panel::new(
        "(a) projection along the slow manifold",
        Axis::linear("ξu + θ").unit("A"),
        Axis::linear("ln v").dimensionless(),
    )
    .series(Series::new(
        "slow manifold ξu + θ + ln v = 0",
        manifold_x,
        manifold_y,
        Style::line(3).dash(Dash::Dashed).width(1.4),
    ))
    .series(Series::new("limit cycle (γ = 10^{3})", x.clone(), lnv, Style::line(0)))
    .legend(LegendPlace::Auto);
    let k = cases::peak_index(&tr);
    let tc = tr.t[k];
    let big_t: Vec<f64> = tr.t.iter().map(|t| gamma * (t - tc)).collect();
    let first = big_t.iter().rposition(|&t| t < WINDOW.0).unwrap_or(0);
    let last = big_t.iter().position(|&t| t > WINDOW.1).unwrap_or(big_t.len() - 1);
    let b = Panel::new(
        "(b) distance to the slow manifold around the slip",
        Axis::linear("T = γ(t − t_{c})").dimensionless().range(WINDOW.0, WINDOW.1),
        Axis::linear("ξu + θ + ln v").unit("A"),
    )
    .series(Series::new(
        "",
        big_t[first..=last].to_vec(),
        offset[first..=last].to_vec(),
        Style::line(0),
    ))
    .line(RefLine::horizontal(
        0.0,
        "on the manifold",
        Style::line(3).dash(Dash::Dashed).width(1.4),
    ));
    // Where the trajectory is off the manifold: on the stick (v < 1) and at the slip.
    let stick = offset
        .iter()
        .zip(&tr.v)
        .filter(|(_, &v)| v < 1.0)
        .map(|(g, _)| g.abs())
        .fold(0.0, f64::max);
    let slip = offset.iter().map(|g| g.abs()).fold(0.0, f64::max);
    out.notes.push(format!(
        "largest |ξu + θ + ln v| over the cycle: {slip:.3} (during the slip); over the stick (v < 1): {stick:.2e}"
    ));
    let fig = Figure::new("Fig. 4: the limit cycle leaves and lands back on the slow manifold (γ = 10^{3}, ξ = 0.7, ε = 0.72)")
        .columns(2)
        .panel_size(480.0, 340.0)
        .panel(a)
        .panel(b)
        .caption(format!(
            "One period of the limit cycle of Fig. 1a. On the slow manifold S (ξu + θ + ln v = 0) dv/dt = 0 to leading order: the stick follows S, the slip leaves it \
             (largest distance {slip:.3}) and lands back on it; over the stick the distance stays below {stick:.1e}."
        ))
        .caption(UNITS);
    out.files.push(ctx.write_figure("fig4.svg", &fig)?);
    out.files.push(ctx.write_json("fig4.json", &report)?);
    Ok(out)
}
