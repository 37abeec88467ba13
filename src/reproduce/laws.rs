//! Beyond the paper: the state laws compared (issue #16). At ξ = 0.8, ε = 1, f = ln v: (a) the
//! limit cycle's period against γ = 1e1 … 1e8 under Ruina's slip law, Dieterich's ageing law
//! and the Perrin–Rice–Zheng law, with the reference tables (data/reference/drr_cycles.json
//! and drr_cycles_ageing.json, two independent integrators at rtol 1e-11); (b) one cycle of
//! each at γ = 1e3. Claims: our periods against both tables, and the three laws' shared Hopf
//! threshold ε_c and frequency ω_c (docs/state-laws.md).

use super::cases;
use super::fig1::UNITS;
use super::{Context, Output, ReproduceError, Row};
use crate::figure::{Axis, Dash, Figure, LegendPlace, Marker, Panel, RefLine, Series, Style};
use serde_json::{json, Value};
use stickslip::model::StateLaw;
use stickslip::paper::claims::{Claim, Source};
use stickslip::report::Report;

/// The slip law's reference table (ξ = 0.7 and 0.8 rows).
const SLIP_TABLE: &str = include_str!("../../data/reference/drr_cycles.json");
/// The ageing law's reference table.
const AGEING_TABLE: &str = include_str!("../../data/reference/drr_cycles_ageing.json");

const XI: f64 = 0.8;
const EPSILON: f64 = 1.0;
/// The γ of panel (b)'s cycles.
const CYCLE_GAMMA: f64 = 1e3;
/// Relative agreement asked of our periods (radau5 at rtol 1e-10) with a table built at rtol
/// 1e-11 whose two integrators agree to 1e-8: the engine's accuracy, tested at 2e-7 in
/// tests/reference.rs and tests/reference_ageing.rs.
const PERIOD_TOL: f64 = 1e-6;

fn gammas(reduced: bool) -> Vec<f64> {
    if reduced {
        vec![1e1, 1e3, 1e8]
    } else {
        (1..=8).map(|k| 10f64.powi(k)).collect()
    }
}

/// The scene of one point: cycle (and Hopf) analysis, radau5 at rtol 1e-10, one trajectory
/// cycle kept at [`CYCLE_GAMMA`].
fn scene(law: StateLaw, gamma: f64) -> Value {
    let mut analyses = vec![json!("hopf"), json!("cycle")];
    if gamma == CYCLE_GAMMA {
        analyses.push(json!({ "trajectory": { "cycles": 1 } }));
    }
    json!({
        "name": format!("laws-{}-gamma-1e{}", law.name(), gamma.log10().round()),
        "model": { "gamma": gamma, "xi": XI, "epsilon": EPSILON, "state_law": law.name() },
        "solver": { "method": "radau5", "rtol": 1e-10, "atol": 1e-12 },
        "analyses": analyses,
    })
}

/// The reference period at (γ, ξ = 0.8, ε = 1) in a table, if it has that row.
fn reference_period(table: &Value, gamma: f64) -> Option<f64> {
    table["rows"].as_array()?.iter().find_map(|r| {
        let same =
            |key: &str, x: f64| r[key].as_f64().is_some_and(|v| (v - x).abs() <= 1e-12 * x.abs());
        (same("gamma", gamma) && same("xi", XI) && same("epsilon", EPSILON))
            .then(|| r["reference"]["period"].as_f64())
            .flatten()
    })
}

/// Makes the state-law comparison.
pub fn make(ctx: &Context) -> Result<Output, ReproduceError> {
    let mut out = Output::default();
    let gammas = gammas(ctx.reduced);
    // The laws with a cycle (the no-healing law has none).
    let laws: Vec<StateLaw> = StateLaw::ALL.iter().map(|(_, l)| *l).filter(|l| l.heals()).collect();
    let points: Vec<(StateLaw, f64)> =
        laws.iter().flat_map(|&l| gammas.iter().map(move |&g| (l, g))).collect();
    let scenes: Vec<Value> = points.iter().map(|&(l, g)| scene(l, g)).collect();
    let reports = cases::run_scenes(ctx, &scenes)?;
    let tables = [
        (StateLaw::Slip, cases::shipped(SLIP_TABLE)),
        (StateLaw::Ageing, cases::shipped(AGEING_TABLE)),
    ];

    let mut a = Panel::new(
        "(a) period against γ (ξ = 0.8, ε = 1)",
        Axis::log10("γ").dimensionless(),
        Axis::linear("period").unit("D_{c}/v_{0}"),
    )
    .legend(LegendPlace::TopLeft);
    let mut b = Panel::new(
        "(b) one cycle at γ = 10^{3}",
        Axis::linear("t").unit("D_{c}/v_{0}"),
        Axis::log10("v").unit("v_{0}"),
    )
    .line(RefLine::horizontal(1.0, "", Style::line(3).dash(Dash::Dotted).width(1.0)));
    let markers = [Marker::Circle, Marker::Square, Marker::Triangle];
    let mut rows = Vec::new();
    for (i, &law) in laws.iter().enumerate() {
        let mine: Vec<(&(StateLaw, f64), &Report)> =
            points.iter().zip(&reports).filter(|(p, _)| p.0 == law).collect();
        let mut curve = Vec::new();
        for &(&(_, gamma), report) in &mine {
            match report.cycle.as_ref().and_then(|c| c.values) {
                Some(v) => curve.push((gamma, v.main.period)),
                None => out.notes.push(format!(
                    "{} law, γ = {gamma:e}: no period-1 limit cycle found (not drawn)",
                    law.name()
                )),
            }
            if gamma == CYCLE_GAMMA {
                let tr = cases::trajectory(report)?;
                b = b.series(Series::new(
                    format!("{} law", law.name()),
                    tr.t,
                    tr.v,
                    Style::line(i).dash(Dash::nth(i)),
                ));
            }
        }
        let style = Style::markers(i, markers[i]);
        a = a.series(Series::new(
            format!("{} law", law.name()),
            curve.iter().map(|p| p.0).collect(),
            curve.iter().map(|p| p.1).collect(),
            style,
        ));
        if let Some((_, table)) = tables.iter().find(|(l, _)| *l == law) {
            let reference: Vec<(f64, f64)> =
                gammas.iter().filter_map(|&g| reference_period(table, g).map(|p| (g, p))).collect();
            let label = format!("{} law, reference table", law.name());
            a = a.series(Series::new(
                label,
                reference.iter().map(|p| p.0).collect(),
                reference.iter().map(|p| p.1).collect(),
                Style::line(i).dash(Dash::Dotted),
            ));
            for &(gamma, period) in &curve {
                if let Some(reference) = reference_period(table, gamma) {
                    let claim = Claim::relative(
                        &format!("{} law, γ = 1e{}: period as in the reference table", law.name(), gamma.log10().round()),
                        Source::Check,
                        reference,
                        period,
                        PERIOD_TOL,
                        "radau5 at rtol 1e-10 against the mean of radau5 and ARKStep DIRK at rtol 1e-11 (data/reference/)".into(),
                    );
                    out.claims.push(Row::from_analysis("State laws (a)", &claim));
                }
            }
        }
        rows.push(json!({ "state_law": law.name(), "points": curve.iter().map(|p| json!({"gamma": p.0, "period": p.1})).collect::<Vec<_>>() }));
    }
    threshold_claims(&mut out, &points, &reports);

    let fig = Figure::new("State laws: slip (Ruina), ageing (Dieterich) and PRZ (Perrin–Rice–Zheng), ξ = 0.8, ε = 1, f = ln v")
        .columns(2)
        .panel_size(480.0, 320.0)
        .panel(a)
        .panel(b)
        .caption(
            "(a) Limit-cycle period against γ for the three state laws (markers), with the slip and ageing reference tables (dotted; \
             two independent integrators at rtol 1e-11). (b) One cycle of each law at γ = 10^{3}, t = 0 at an upward crossing of v = 1.",
        )
        .caption(UNITS);
    out.files.push(ctx.write_figure("laws.svg", &fig)?);
    out.files.push(
        ctx.write_json(
            "laws-periods.json",
            &json!({ "xi": XI, "epsilon": EPSILON, "laws": rows }),
        )?,
    );
    Ok(out)
}

/// The three laws share ε_c and ω_c at every γ (κ = −F'(x*) = 1 for all three): the largest
/// relative difference of each from the slip law's, over the γ run.
fn threshold_claims(out: &mut Output, points: &[(StateLaw, f64)], reports: &[Report]) {
    let hopf = |law: StateLaw, gamma: f64| {
        points
            .iter()
            .zip(reports)
            .find(|(p, _)| p.0 == law && p.1 == gamma)
            .and_then(|(_, r)| r.hopf.as_ref())
            .map(|h| (h.epsilon_c, h.omega_c))
    };
    let (mut eps, mut omega) = (0.0f64, 0.0f64);
    let mut compared = 0;
    for &(law, gamma) in points.iter().filter(|p| p.0 != StateLaw::Slip) {
        if let (Some(slip), Some(other)) = (hopf(StateLaw::Slip, gamma), hopf(law, gamma)) {
            eps = eps.max(((other.0 - slip.0) / slip.0).abs());
            omega = omega.max(((other.1 - slip.1) / slip.1).abs());
            compared += 1;
        }
    }
    let note = format!("largest relative difference from the slip law's, ageing and PRZ, {compared} (law, γ) pairs; each law's value is also found by bisection on the Jacobian's eigenvalues in the unit tests");
    let why = "the laws' linearisations coincide (κ = 1), so only rounding may differ";
    for (name, value) in [("ε_c", eps), ("ω_c", omega)] {
        let claim = Claim::absolute(
            &format!("slip, ageing and PRZ share the Hopf {name}"),
            Source::Prediction,
            0.0,
            value,
            1e-12,
            why,
            note.clone(),
        );
        out.claims.push(Row::from_analysis("State laws", &claim));
    }
}
