//! Fig. 9: the correlation time of u before the slip with power-law friction
//! (data/scenes/noise-power-law.json: α = 0.15, γ = 1e3, ε = 0.78, ξ = 0.7).

use super::fig1::UNITS;
use super::noise_cases::{self, curve, falls_towards_the_event, tau_claim};
use super::{Context, Output, ReproduceError};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Marker, Panel, Series, Style};

/// Makes Fig. 9.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let run = noise_cases::run(ctx, noise_cases::POWER_LAW)?;
    let points = &run.noise.correlation_time;
    let (xe, ye) = curve(points, false);
    let (xl, yl) = curve(points, true);
    let panel = Panel::new(
        "half-height width of Γ_{u}(t, t − t′)",
        Axis::log10("t_{c} − t").unit("D_{c}/v_{0}"),
        Axis::log10("τ").unit("D_{c}/v_{0}"),
    )
    .series(Series::new("ensemble", xe, ye, Style::markers(0, Marker::Circle)))
    .series(Series::new("linear response", xl, yl, Style::line(1).dash(Dash::Dashed)))
    .legend(LegendPlace::Auto);
    let t0 = run.noise.deterministic.t0.map_or("-".to_string(), |t| format!("{t:.3}"));
    let fig = Figure::new("Fig. 9: correlation time before the slip, power-law friction (α = 0.15, γ = 10^{3}, ε = 0.78, ξ = 0.7)")
        .panel_size(560.0, 360.0)
        .panel(panel)
        .caption(format!(
            "{} realisations aligned on their own slip, and the linear response; t_{{0}} = {t0} (v = 1 to the slip peak). Missing points: Γ_{{u}} does not fall to half within the record.",
            run.noise.settings.realisations
        ))
        .caption(UNITS);
    out.files.push(ctx.write_figure("fig9.svg", &fig)?);
    out.files.push(ctx.write_json(&format!("{}.json", run.name), &run.report)?);
    out.claims.push(tau_claim(
        "Fig. 9",
        "power-law friction: the correlation time decreases during an interval of a few t0 before t_c (speed-up)",
        "decreases",
        points,
        falls_towards_the_event,
        format!("linear response; t0 = {t0}"),
    ));
    Ok(out)
}
