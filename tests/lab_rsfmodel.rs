//! rsfmodel's eight test tables (tests/expected/rsfmodel_tables.json, from rsfmodel's
//! tests/rsf_tests.py), reproduced by the lab model to their 8 decimals; and every method of
//! the method table running the lab model.

use stickslip::analysis::lab::{self, LabSolver, Output};
use stickslip::model::{LabLaw, LabParams, LabState, Loading, Segment};
use stickslip::solver::Method;

const TABLES: &str = include_str!("expected/rsfmodel_tables.json");

struct Case {
    name: String,
    params: LabParams,
    /// Expected columns by rsfmodel's names (friction, state/state1/state2, slider_velocity,
    /// time, loadpoint_displacement).
    columns: serde_json::Map<String, serde_json::Value>,
}

fn cases() -> Vec<Case> {
    let doc: serde_json::Value = serde_json::from_str(TABLES).unwrap();
    doc["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let f = |k: &str| c[k].as_f64().unwrap();
            let states = c["states"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| {
                    let law = match s["law"].as_str().unwrap() {
                        "DieterichState" => LabLaw::Ageing,
                        "RuinaState" => LabLaw::Slip,
                        "PrzState" => LabLaw::Prz,
                        "NagataState" => LabLaw::Nagata { c: s["c"].as_f64().unwrap() },
                        other => panic!("unknown law {other}"),
                    };
                    LabState { law, b: s["b"].as_f64().unwrap(), d_c: s["Dc"].as_f64().unwrap() }
                })
                .collect();
            Case {
                name: c["class"].as_str().unwrap().into(),
                params: LabParams {
                    mu0: f("mu0"),
                    a: f("a"),
                    v0: f("vref"),
                    k: f("k"),
                    states,
                    mass: None,
                },
                columns: c["columns"].as_object().unwrap().clone(),
            }
        })
        .collect()
}

/// The tables' scenario: 1 µm/s, 10 µm/s from t = 10 s, rows at t = 0, 1, …, 40 s.
fn rsfmodel_scenario(params: &LabParams, method: Method, rtol: f64) -> Vec<Vec<f64>> {
    let seg = |t_start, velocity| Segment { t_start, velocity };
    let loading = Loading::new(vec![seg(0.0, 1.0), seg(10.0, 10.0)], 40.0).unwrap();
    let times: Vec<f64> = (0..=40).map(f64::from).collect();
    let y0 = params.steady_state(1.0);
    let solver = LabSolver { method, rtol, atol: rtol };
    let mut rows = Vec::new();
    lab::run(params, &loading, &y0, &solver, &Output::Times(times), &mut |r| rows.push(r.to_vec()))
        .unwrap();
    rows
}

/// Column index of rsfmodel's column `name` in our rows (t,x_lp,delta,mu,v,theta_1,…).
fn ours(name: &str) -> usize {
    match name {
        "time" => 0,
        "loadpoint_displacement" => 1,
        "friction" => 3,
        "slider_velocity" => 4,
        "state" | "state1" => 5,
        "state2" => 6,
        other => panic!("unknown column {other}"),
    }
}

/// Largest |ours − rsfmodel's| over every column of every table.
fn worst_error(method: Method, rtol: f64) -> f64 {
    let mut worst = 0.0f64;
    for case in cases() {
        let rows = rsfmodel_scenario(&case.params, method, rtol);
        assert_eq!(rows.len(), 41, "{}", case.name);
        for (name, expected) in &case.columns {
            for (i, e) in expected.as_array().unwrap().iter().enumerate() {
                let err = (rows[i][ours(name)] - e.as_f64().unwrap()).abs();
                assert!(err.is_finite(), "{}: {name}[{i}]", case.name);
                worst = worst.max(err);
                if rtol <= 1e-12 {
                    assert!(
                        err < 1.5e-8,
                        "{} {name}[{i}] (t = {i}): ours {} rsfmodel {e} ({method})",
                        case.name,
                        rows[i][ours(name)]
                    );
                }
            }
        }
    }
    worst
}

#[test]
fn rsfmodel_tables_to_8_decimals() {
    for method in [Method::CvodeBdf, Method::Radau5] {
        let worst = worst_error(method, 1e-13);
        eprintln!("{method}: largest deviation from rsfmodel's tables {worst:.2e}");
    }
}

/// Every method of the method table runs the lab model and reproduces the tables to 1e-5 at
/// rtol 1e-9 (the non-stiff ones included: these scenarios are not stiff).
#[test]
fn every_method_runs_the_lab_model() {
    for (name, method) in Method::ALL {
        let worst = worst_error(method, 1e-9);
        eprintln!("{name}: largest deviation {worst:.2e} at rtol 1e-9");
        assert!(worst < 1e-5, "{name}: {worst:e}");
    }
}
