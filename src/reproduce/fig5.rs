//! Fig. 5: the paper's "Lyapunov exponents" — the three eigenvalues of the Jacobian — along
//! the stick of the Fig. 1a cycle (data/scenes/fig1-asymptotics.json: γ = 10³, ξ = 0.7,
//! ε = 0.72), from the "lyapunov" analysis (docs/asymptotics.md): (a) the fast real
//! eigenvalue, (b) the real parts of the slow pair, (c) its imaginary part, with the paper's
//! quasi-static formula λ = −B ± √(B² − ξv²) dashed, against t − t_c (t_c: the v maximum).

use super::cases;
use super::fig1::UNITS;
use super::{Context, Output, ReproduceError, Row};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Panel, RefLine, Series, Style};
use serde_json::json;

/// Window of panels (b) and (c): t − t_c from this to 0.
const WINDOW: f64 = -8.0;

/// y range of panel (b): the slow pair's real parts grow to O(γ) at t_c, outside the panel.
const RE_RANGE: (f64, f64) = (-0.8, 2.5);
/// Top of panel (c).
const IM_TOP: f64 = 1.3;

/// Makes Fig. 5.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let mut scene = cases::shipped(cases::FIG1_ASYMPTOTICS);
    scene["name"] = json!("fig5");
    // The shipped settings (FTLE over 3 periods), also in the reduced run: about 0.1 s.
    scene["analyses"] = json!(["cycle", "lyapunov"]);
    let report = cases::run_scene(&scene)?;
    let ly = report
        .lyapunov
        .as_ref()
        .ok_or_else(|| ReproduceError::Missing("fig5: no lyapunov section".into()))?;
    let f = ly.along_cycle.as_ref().ok_or_else(|| {
        ReproduceError::Missing(format!(
            "fig5: no eigenvalues along the cycle ({})",
            ly.note.as_deref().unwrap_or("no reason given")
        ))
    })?;
    let window: Vec<usize> = (0..f.t.len()).filter(|&k| f.t[k] >= WINDOW).collect();
    let pick = |x: &[f64]| window.iter().map(|&k| x[k]).collect::<Vec<f64>>();
    let t = pick(&f.t);
    let marks = |mut p: Panel| {
        if let Some(z) = ly.zero_crossing_before_tc {
            p = p.line(RefLine::vertical(
                -z,
                "Re λ = 0",
                Style::line(4).dash(Dash::Dotted).width(1.0),
            ));
        }
        if let Some(o) = ly.complex_onset_before_tc.filter(|o| -o >= WINDOW) {
            p = p.line(RefLine::vertical(
                -o,
                "pair turns complex",
                Style::line(4).dash(Dash::Dashed).width(1.0),
            ));
        }
        p
    };
    // (a) The fast eigenvalue over the whole stick, as −λ on a log axis (it reaches −γ²/ξ…).
    let a = Panel::new(
        "(a) the fast real eigenvalue",
        Axis::linear("t − t_{c}").unit("D_{c}/v_{0}"),
        Axis::log10("−λ_{1}").unit("v_{0}/D_{c}"),
    )
    .series(Series::new("", f.t.clone(), f.fast.iter().map(|x| -x).collect(), Style::line(0)))
    .legend(LegendPlace::Hidden);
    let b = Panel::new(
        "(b) real parts of the slow pair",
        Axis::linear("t − t_{c}").unit("D_{c}/v_{0}").range(WINDOW, 0.0),
        Axis::linear("Re λ").unit("v_{0}/D_{c}").range(RE_RANGE.0, RE_RANGE.1),
    )
    .series(Series::new("Re λ_{2}", t.clone(), pick(&f.slow_re_1), Style::line(1).width(2.6)))
    .series(Series::new("Re λ_{3}", t.clone(), pick(&f.slow_re_2), Style::line(0).width(2.6)))
    .series(Series::new(
        "quasi-static formula",
        t.clone(),
        pick(&f.quasi_re_1),
        Style::line(3).dash(Dash::Dashed),
    ))
    .series(Series::new("", t.clone(), pick(&f.quasi_re_2), Style::line(3).dash(Dash::Dashed)))
    .line(RefLine::horizontal(0.0, "", Style::line(3).width(0.6)))
    .legend(LegendPlace::Auto);
    let c = Panel::new(
        "(c) imaginary part of the slow pair",
        Axis::linear("t − t_{c}").unit("D_{c}/v_{0}").range(WINDOW, 0.0),
        Axis::linear("Im λ").unit("v_{0}/D_{c}").range(0.0, IM_TOP),
    )
    .series(Series::new(
        "Im λ_{2} = −Im λ_{3}",
        t.clone(),
        pick(&f.slow_im),
        Style::line(1).width(2.6),
    ))
    .series(Series::new(
        "quasi-static formula",
        t,
        pick(&f.quasi_im),
        Style::line(3).dash(Dash::Dashed),
    ))
    .legend(LegendPlace::Auto);
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3}"));
    let q = ly.quasi_static.as_ref();
    let fig = Figure::new("Fig. 5: eigenvalues of the Jacobian along the cycle (γ = 10^{3}, ξ = 0.7, ε = 0.72)")
        .columns(3)
        .panel_size(400.0, 320.0)
        .panel(a)
        .panel(marks(b))
        .panel(marks(c))
        .caption(format!(
            "The roots of the characteristic cubic along the stick of the Fig. 1a cycle, from its v minimum to the catastrophe t_{{c}} (the v maximum); dashed: the quasi-static formula \
             λ = −B ± √(B² − ξv²). The slow pair turns complex at t_{{c}} − {} (formula: t_{{c}} − {}) and its real part crosses zero at t_{{c}} − {} (formula: t_{{c}} − {}), \
             with ω = {} there; t0 = {}. Near t_{{c}} the pair is real again and grows to O(γ), out of panels (b) and (c).",
            opt(ly.complex_onset_before_tc),
            opt(q.and_then(|q| q.complex_onset_before_tc)),
            opt(ly.zero_crossing_before_tc),
            opt(q.and_then(|q| q.zero_crossing_before_tc)),
            opt(ly.frequency_at_zero_crossing),
            opt(ly.t0),
        ))
        .caption(UNITS);
    out.files.push(ctx.write_figure("fig5.svg", &fig)?);
    out.files.push(ctx.write_json("fig5.json", &report)?);
    out.claims.extend(ly.claims.iter().map(|c| Row::from_analysis("Fig. 5", c)));
    Ok(out)
}
