//! Fig. 2: the slip in the fast units of the paper's eq. (UV): T = γ(t − t_c), V = v/γ,
//! U = u − (ε/ξ) ln γ, Θ = θ + (1+ε) ln γ, for several γ at ξ = 0.7, ε = 0.72 (the paper
//! shows γ = 10³; overlaying several γ tests the γ-free scaling).

use super::cases;
use super::fig1::UNITS;
use super::{Context, Output, ReproduceError, Row};
use crate::figure::scale::power_of_ten;
use crate::figure::{Axis, Dash, Figure, LegendPlace, Panel, Series, Style};
use stickslip::analysis::cycle::TrajectoryCycle;

/// The window of fast time drawn.
const WINDOW: (f64, f64) = (-8.0, 12.0);

fn gammas(reduced: bool) -> Vec<f64> {
    if reduced {
        vec![1e3, 1e5]
    } else {
        vec![1e2, 1e3, 1e4, 1e6, 1e8]
    }
}

/// The samples of one trajectory inside the fast-time window around its v maximum (plus one
/// on each side so that lines reach the edges), as (T, V, U, Θ).
pub fn fast_units(tr: &TrajectoryCycle, gamma: f64, xi: f64, epsilon: f64) -> [Vec<f64>; 4] {
    let k = cases::peak_index(tr);
    let tc = tr.t[k];
    let ln_g = gamma.ln();
    let big_t: Vec<f64> = tr.t.iter().map(|t| gamma * (t - tc)).collect();
    let first = big_t.iter().rposition(|&x| x < WINDOW.0).unwrap_or(0);
    let last = big_t.iter().position(|&x| x > WINDOW.1).unwrap_or(big_t.len() - 1);
    let r = first..last + 1;
    [
        big_t[r.clone()].to_vec(),
        tr.v[r.clone()].iter().map(|v| v / gamma).collect(),
        tr.u[r.clone()].iter().map(|u| u - epsilon / xi * ln_g).collect(),
        tr.theta[r].iter().map(|th| th + (1.0 + epsilon) * ln_g).collect(),
    ]
}

/// Makes Fig. 2.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let base = cases::shipped(cases::FIG1);
    let (xi, epsilon) = (0.7, 0.72);
    let gammas = gammas(ctx.reduced);
    let scenes: Vec<_> = gammas
        .iter()
        .map(|&g| {
            cases::variant(
                &base,
                &format!("fig2-gamma-1e{}", g.log10().round()),
                &[("gamma", g)],
                false,
                1,
            )
        })
        .collect();
    let reports = cases::run_scenes(ctx, &scenes)?;
    let t_axis = || Axis::linear("T = γ(t − t_{c})").dimensionless().range(WINDOW.0, WINDOW.1);
    let mut v_lin = Panel::new("(a) V = v/γ", t_axis(), Axis::linear("V = v/γ").dimensionless());
    let mut v_log =
        Panel::new("(b) V = v/γ, log scale", t_axis(), Axis::log10("V = v/γ").dimensionless())
            .legend(LegendPlace::Hidden);
    let mut u = Panel::new("(c) U = u − (ε/ξ) ln γ", t_axis(), Axis::linear("U").unit("D_{c}"))
        .legend(LegendPlace::Hidden);
    let mut th = Panel::new("(d) Θ = θ + (1 + ε) ln γ", t_axis(), Axis::linear("Θ").unit("A"))
        .legend(LegendPlace::Hidden);
    let mut widths = Vec::new();
    for (i, (report, &g)) in reports.iter().zip(&gammas).enumerate() {
        let tr = cases::trajectory(report)?;
        let [big_t, v, uu, tt] = fast_units(&tr, g, xi, epsilon);
        let label = format!("γ = {}", power_of_ten(g.log10().round() as i64));
        let style = Style::line(i).dash(Dash::nth(i));
        v_lin = v_lin.series(Series::new(label.clone(), big_t.clone(), v.clone(), style.clone()));
        v_log = v_log.series(Series::new(label.clone(), big_t.clone(), v, style.clone()));
        u = u.series(Series::new(label.clone(), big_t.clone(), uu, style.clone()));
        th = th.series(Series::new(label, big_t, tt, style));
        let values = report.cycle.as_ref().and_then(|c| c.values);
        if let Some(w) = values.and_then(|v| v.main.slip_half_width) {
            out.claims.push(Row::numeric(
                "Fig. 2",
                &format!(
                    "slip half-width δt ≈ 2.5/γ (γ = 1e{}, ξ = 0.7, ε = 0.72)",
                    g.log10().round()
                ),
                2.5,
                w * g,
                "full width of v(t) at half its maximum, times γ (limit cycle)".into(),
            ));
            widths.push(format!("{:.3}", w * g));
        }
        out.files.push(ctx.write_json(&format!("{}.json", report.name), report)?);
    }
    let fig = Figure::new("Fig. 2: the slip in fast units (ξ = 0.7, ε = 0.72)")
        .columns(2)
        .panel_size(480.0, 320.0)
        .panel(v_lin)
        .panel(v_log)
        .panel(u)
        .panel(th)
        .caption(format!(
            "The limit cycle near its velocity maximum t_{{c}} in the variables of the γ-free fast system (the paper's eq. UV), with the predicted shifts c_{{u}} = ε/ξ and c_{{θ}} = −(1 + ε) of u and θ per unit ln γ. \
             Curves that coincide obey the scaling; residual drifts with γ are the corrections to it. Slip half-width × γ: {}.",
            widths.join(", ")
        ))
        .caption(UNITS);
    out.files.insert(0, ctx.write_figure("fig2.svg", &fig)?);
    Ok(out)
}
