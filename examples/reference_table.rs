//! Builds data/reference/drr_cycles.json: limit-cycle quantities for γ = 1e1 … 1e8 at
//! (ξ, ε) = (0.7, 0.72) and (0.8, 1.0), from two independent integrators (CVODE BDF and ARKStep
//! DIRK) at rtol 1e-11, with their agreement. Run:
//!
//!     cargo run --release --example reference_table
//!
//! With the argument `ageing`, the same table under Dieterich's ageing law,
//! data/reference/drr_cycles_ageing.json, from stickslip's Radau5 and ARKStep DIRK (CVODE
//! fails in the ageing law's deep stick from γ ≈ 1e4, docs/state-laws.md):
//!
//!     cargo run --release --example reference_table -- ageing
//!
//! The reference value of each quantity is the mean of the two; `agreement` is their relative
//! difference. Tests check the engine against this table (tests/reference.rs).

use serde_json::json;
use stickslip::{engine, scene};

fn cycle(gamma: f64, xi: f64, epsilon: f64, state_law: &str, method: &str) -> serde_json::Value {
    let text = json!({
        "name": format!("reference γ={gamma:e} ξ={xi} ε={epsilon} {state_law} {method}"),
        "model": { "gamma": gamma, "xi": xi, "epsilon": epsilon, "state_law": state_law },
        "solver": { "method": method, "rtol": 1e-11, "atol": 1e-13 },
        "analyses": [{ "cycle": { "tolerance": 1e-8 } }]
    });
    let scene = scene::parse(&text.to_string(), "reference").expect("valid scene");
    let report = engine::run(&scene, text).unwrap_or_else(|e| panic!("{method} γ={gamma}: {e}"));
    let c = report.cycle.expect("cycle asked");
    let v = c.values.unwrap_or_else(|| panic!("{method} γ={gamma}: not periodic: {:?}", c.status));
    json!({
        "period": v.period,
        "t0": v.t0,
        "slip_half_width_times_gamma": v.slip_half_width.map(|w| w * gamma),
        "ln_v_max": v.ln_v_max,
        "cycles_computed": c.cycles_computed,
        "spread_period": c.spread.map(|s| s.period),
        "steps": report.solver.stats.steps,
        "wall_time_s": report.wall_time_s,
    })
}

/// A table: its state law, integrators (scene name, description), file and title.
struct Table {
    state_law: &'static str,
    methods: [(&'static str, &'static str); 2],
    file: &'static str,
    description: &'static str,
}

fn main() {
    let ageing = match std::env::args().nth(1).as_deref() {
        None | Some("slip") => false,
        Some("ageing") => true,
        Some(other) => {
            eprintln!("reference_table: unknown argument \"{other}\"; use no argument (slip law) or \"ageing\"");
            std::process::exit(2);
        }
    };
    let t = if ageing {
        Table {
            state_law: "ageing",
            methods: [("radau5", "radau5 (stickslip's Radau IIA order 5, analytic Jacobian)"), ("arkode-dirk", "arkode-dirk (ARKStep SDIRK-5-3-4, deduced implicit RHS)")],
            file: "drr_cycles_ageing.json",
            description: "Limit cycle of the DRR spring-slider (dimensionless), f = ln v, Dieterich's ageing law. Reference = mean of two independent integrators; relative_agreement = |a − b|/max(|a|, |b|).",
        }
    } else {
        Table {
            state_law: "slip",
            methods: [("cvode-bdf", "cvode-bdf (CVODE BDF, analytic Jacobian)"), ("arkode-dirk", "arkode-dirk (ARKStep SDIRK-5-3-4, deduced implicit RHS)")],
            file: "drr_cycles.json",
            description: "Limit cycle of the DRR spring-slider (dimensionless), f = ln v. Reference = mean of two independent integrators; relative_agreement = |a − b|/max(|a|, |b|).",
        }
    };
    let key = |method: &str| method.replace('-', "_");
    let mut rows = Vec::new();
    let mut worst: f64 = 0.0;
    for (xi, epsilon) in [(0.7, 0.72), (0.8, 1.0)] {
        for k in 1..=8 {
            let gamma = 10f64.powi(k);
            let a = cycle(gamma, xi, epsilon, t.state_law, t.methods[0].0);
            let b = cycle(gamma, xi, epsilon, t.state_law, t.methods[1].0);
            let mut reference = serde_json::Map::new();
            let mut agreement = serde_json::Map::new();
            for key in ["period", "t0", "slip_half_width_times_gamma", "ln_v_max"] {
                let (x, y) = (a[key].as_f64().expect("number"), b[key].as_f64().expect("number"));
                let diff = (x - y).abs() / x.abs().max(y.abs());
                worst = worst.max(if key == "t0" || key == "slip_half_width_times_gamma" { 0.0 } else { diff });
                reference.insert(key.into(), json!(0.5 * (x + y)));
                agreement.insert(key.into(), json!(diff));
            }
            eprintln!("ξ={xi} ε={epsilon} γ=1e{k}: period {} (agreement {:.1e})", reference["period"], agreement["period"].as_f64().unwrap());
            let mut row = json!({
                "gamma": gamma, "xi": xi, "epsilon": epsilon, "friction": "log",
                "reference": reference, "relative_agreement": agreement,
            });
            if ageing {
                row["state_law"] = json!(t.state_law);
            }
            row[key(t.methods[0].0)] = a;
            row[key(t.methods[1].0)] = b;
            rows.push(row);
        }
    }
    let table = json!({
        "description": t.description,
        "provenance": {
            "generator": "cargo run --release --example reference_table",
            "stickslip_version": env!("CARGO_PKG_VERSION"),
            "sundials_version": stickslip::sundials::version(),
            "integrators": [t.methods[0].1, t.methods[1].1],
            "tolerances": "rtol 1e-11, atol 1e-13 on (u, ln v, θ); cycle convergence 1e-8",
            "start": "v = 0.5 on the slow manifold, θ = 0",
            "definitions": "period: between upward crossings of v = 1; t0: v = 1 to the v maximum; slip half-width: full width of v(t) at half maximum",
        },
        "worst_relative_agreement_period_and_ln_v_max": worst,
        "rows": rows,
    });
    let path = format!("{}/data/reference/{}", env!("CARGO_MANIFEST_DIR"), t.file);
    std::fs::write(&path, serde_json::to_string_pretty(&table).expect("json") + "\n").expect("write table");
    eprintln!("wrote {path}; worst agreement on period and ln v_max: {worst:.2e}");
}
