//! Fig. 7: the correlation time before the event — (a) the saddle-node ("potential") model,
//! the reference for critical slowing-down; (b) the stick-slip (DRR) cycle of Fig. 1;
//! (c) van der Pol near its fold, measured on x and on x − x³/3 − y. Half-height widths of
//! Γ(t, t − t') in t' (the paper's definition), ensembles (markers) and linear response
//! (lines), each realisation aligned on its own event (docs/noise.md).

use super::noise_cases::{self, curve, describe, falls_towards_the_event, peaks_inside, tau_claim};
use super::{Context, Output, ReproduceError};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Marker, Panel, Series, Style};
use stickslip::analysis::noise::CorrelationPoint;

/// A panel of τ against t_c − t (both log scales): ensemble markers, linear-response line.
fn tau_panel(title: &str, curves: &[(&str, &[CorrelationPoint])]) -> Panel {
    let mut p = Panel::new(
        title,
        Axis::log10("t_{c} − t").unit("D_{c}/v_{0}"),
        Axis::log10("τ").unit("D_{c}/v_{0}"),
    )
    .legend(LegendPlace::Auto);
    for (i, (name, points)) in curves.iter().enumerate() {
        let (xe, ye) = curve(points, false);
        let (xl, yl) = curve(points, true);
        if !xe.is_empty() {
            p = p.series(Series::new(
                format!("{name} (ensemble)"),
                xe,
                ye,
                Style::markers(i, Marker::Circle),
            ));
        }
        if !xl.is_empty() {
            p = p.series(Series::new(
                format!("{name} (linear response)"),
                xl,
                yl,
                Style::line(i).dash(Dash::nth(i)),
            ));
        }
    }
    p
}

/// Makes Fig. 7.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let sn = noise_cases::run(ctx, noise_cases::SADDLE_NODE)?;
    let drr = noise_cases::run(ctx, noise_cases::DRR)?;
    let vdp = noise_cases::run(ctx, noise_cases::VAN_DER_POL)?;
    let by_name = |run: &noise_cases::NoiseRun, name: &str| -> Vec<CorrelationPoint> {
        run.noise
            .correlation_time_by_variable
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, p)| p.clone())
            .unwrap_or_default()
    };
    let a = tau_panel(
        "(a) saddle-node dx/dt = μ0 − rt − x² (x)",
        &[("τ_{x}", &sn.noise.correlation_time)],
    );
    let b = tau_panel(
        "(b) stick-slip, γ = 10^{3}, ξ = 0.7, ε = 0.72 (u)",
        &[("τ_{u}", &drr.noise.correlation_time)],
    );
    let x_offset = by_name(&vdp, "x_offset");
    let c = tau_panel(
        "(c) van der Pol, β = 30, a = 0",
        &[("τ_{x}", &vdp.noise.correlation_time), ("τ of x − x^{3}/3 − y", &x_offset)],
    );
    let fig = Figure::new("Fig. 7: correlation time before the event — slowing-down (saddle-node) against speed-up (stick-slip)")
        .columns(3)
        .panel_size(420.0, 320.0)
        .panel(a)
        .panel(b)
        .panel(c)
        .caption(
            "τ: half-height width in t′ of Γ(t, t − t′) relative to Γ(t, t), at times t before the event t_{c} (the saddle-node's escape x = −1, \
             the slip's velocity maximum, the van der Pol jump off the fold); missing points: Γ does not fall to half within the record. \
             Markers: ensembles of realisations with Ornstein–Uhlenbeck noise, each aligned on its own event; lines: the linear response. \
             Time in D_{c}/v_{0} for the stick-slip model, in the models' own units otherwise.",
        );
    out.files.push(ctx.write_figure("fig7.svg", &fig)?);
    // The DRR run is Fig. 6's (shared in this process), its report written again here.
    for run in [&sn, &drr, &vdp] {
        out.files.push(ctx.write_json(&format!("{}.json", run.name), &run.report)?);
    }
    out.claims.push(tau_claim(
        "Fig. 7a",
        "saddle-node: the correlation time grows, is largest shortly before the escape, then drops (slowing-down)",
        "peaks before the event",
        &sn.noise.correlation_time,
        peaks_inside,
        "linear response (the ensemble agrees within its sampling error)".into(),
    ));
    out.claims.push(tau_claim(
        "Fig. 7b",
        "stick-slip: the correlation time decreases until the slip (speed-up)",
        "decreases",
        &drr.noise.correlation_time,
        falls_towards_the_event,
        "linear response, window t_c − 3 … t_c − 30/γ; undefined where Γ_u does not fall to half"
            .into(),
    ));
    let (xv, yv) = curve(&x_offset, true);
    out.notes.push(format!(
        "Fig. 7c (no claim in the paper): van der Pol, τ of x: {}; τ of x − x³/3 − y: {}",
        {
            let (x, y) = curve(&vdp.noise.correlation_time, true);
            describe(&x, &y)
        },
        describe(&xv, &yv)
    ));
    Ok(out)
}
