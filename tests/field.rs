//! Input in the field's terms (`model.dimensional` with a, b, σ; `initial.velocity`/`state`)
//! and the physical output `cycle.physical` (issue #26): the QDYN-style scene equals its
//! dimensionless twin, every output key is the documented conversion, and every bad input is
//! refused naming its field (exit 2 from the CLI).

use stickslip::scene;

mod common;
use common::{cli_run, run_scene, scene_file_text};

/// The QDYN scene with `from` replaced by `to` (each must occur).
fn qdyn_with(from: &str, to: &str) -> String {
    let text = scene_file_text("qdyn-spring-block.json");
    assert!(text.contains(from), "{from} not in the scene");
    text.replacen(from, to, 1)
}

const DIMENSIONLESS_TWIN: &str = r#"{"name": "twin",
    "model": {"inertia": false, "state_law": "ageing", "xi": 0.25, "epsilon": 0.5, "radiation_damping": 5e-8},
    "initial": {"v": 0.5, "theta": 0},
    "solver": {"method": "radau5", "rtol": 1e-10, "atol": [1e-12, 1e-12, 1e-12]},
    "analyses": ["hopf", "cycle"]}"#;

#[test]
fn the_qdyn_scene_is_its_dimensionless_twin() {
    let s = scene::parse(&scene_file_text("qdyn-spring-block.json"), "t").unwrap();
    let p = s.params;
    assert!((p.xi - 0.25).abs() < 1e-15 && (p.epsilon - 0.5).abs() < 1e-15, "{p:?}");
    assert!((p.eta - 5e-8).abs() < 1e-21, "η = {:e}", p.eta);
    // V = 0.5 V_pl, Θ = D_c/V_pl: v = 0.5, θ = 0, u on the force balance.
    assert_eq!(s.initial[1], 0.5f64.ln());
    assert_eq!(s.initial[2], 0.0);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);

    let field =
        run_scene(&scene_file_text("qdyn-spring-block.json")).cycle.unwrap().values.unwrap();
    let twin = run_scene(DIMENSIONLESS_TWIN).cycle.unwrap().values.unwrap();
    let pairs = [
        ("period", field.main.period, twin.main.period),
        ("t0", field.main.t0, twin.main.t0),
        ("v_max", field.main.v_max, twin.main.v_max),
        ("slip", field.main.slip, twin.main.slip),
        ("slip_duration", field.main.slip_duration, twin.main.slip_duration),
        ("u_min", field.extremes.u_min, twin.extremes.u_min),
        ("u_max", field.extremes.u_max, twin.extremes.u_max),
    ];
    for (name, a, b) in pairs {
        assert!((a - b).abs() <= 1e-12 * b.abs(), "{name}: {a} vs {b}");
    }
}

#[test]
fn cycle_physical_is_the_cycle_in_si_units() {
    let report = run_scene(&scene_file_text("qdyn-spring-block.json"));
    let c = report.cycle.unwrap();
    let v = c.values.unwrap();
    let ph = c.physical.clone().expect("dimensional input gives cycle.physical");
    let close = |name: &str, x: f64, y: f64| {
        assert!((x - y).abs() <= 1e-13 * y.abs(), "{name}: {x} vs {y}");
    };
    // Time D_c/V_pl = 1e5 s, velocity V_pl = 1e-9 m/s, slip D_c = 1e-4 m.
    close("period", ph.period, 1e5 * v.main.period);
    close("t0", ph.t0, 1e5 * v.main.t0);
    close("slip_duration", ph.slip_duration, 1e5 * v.main.slip_duration);
    close("v_max", ph.v_max, 1e-9 * v.main.v_max);
    close("v_min", ph.v_min, 1e-9 * v.main.v_min);
    close("slip", ph.slip, 1e-4 * v.main.slip);
    // Stress drop: k·D_c·Δu over the event, u_max − u_min; against Δu = slip − duration
    // (du/dt = v − 1), an independent value (slip is the cycle analysis's ∫v dt), so to the
    // run's accuracy (4e-8 measured at rtol 1e-10).
    assert!(ph.stress_drop > 0.0);
    close("stress_drop", ph.stress_drop, 2.5e8 * 1e-4 * (v.extremes.u_max - v.extremes.u_min));
    let from_slip = 2.5e8 * 1e-4 * (v.main.slip - v.main.slip_duration);
    assert!(
        (ph.stress_drop - from_slip).abs() < 1e-6 * from_slip,
        "{} vs {from_slip}",
        ph.stress_drop
    );
    // Crustal magnitudes: a period of weeks to months, v_max of cm/s to m/s, slip of mm, a
    // stress drop of MPa.
    assert!((1e5..1e8).contains(&ph.period), "{}", ph.period);
    assert!((1e-3..10.0).contains(&ph.v_max) && (1e-4..1e-1).contains(&ph.slip), "{ph:?}");
    assert!((1e5..1e7).contains(&ph.stress_drop), "{}", ph.stress_drop);
    // Shear stress σμ at the event's start and end: their difference is the stress drop, and
    // μ = τ/σ. With μ0 = 0.6 at 1e-6 m/s: μ_ref = 0.6 + (a − b) ln(V_pl/V_ref).
    let (before, after) = (ph.shear_stress_before.unwrap(), ph.shear_stress_after.unwrap());
    close("shear stress drop", before - after, ph.stress_drop);
    close("friction_before", ph.friction_before.unwrap(), before / 1e7);
    close("friction_after", ph.friction_after.unwrap(), after / 1e7);
    let mu_ref = 0.6 + (0.01 - 0.015) * (1e-9f64 / 1e-6).ln();
    close("friction_steady", ph.friction_steady.unwrap(), mu_ref);
    // At the start (v = 1, u = u_min) the force balance gives θ + ln v = −ξu − η.
    close("before", before, 1e7 * mu_ref + 1e5 * (-0.25 * v.extremes.u_min - 5e-8));
    assert_eq!(ph.shear_stress_reference, Some("absolute (σμ)"));
    assert!(ph.in_time_unit.is_none());
    let json = serde_json::to_value(&report.warnings).unwrap();
    assert_eq!(json, serde_json::json!([]));
}

#[test]
fn without_mu0_shear_stress_is_relative_and_units_add_durations() {
    let text = qdyn_with(r#""mu0": 0.6, "v_ref": 1e-6,"#, "").replacen(
        r#""initial""#,
        r#""units": {"time_unit": "days", "time_scale": 1.1574074074074074}, "initial""#,
        1,
    );
    let ph = run_scene(&text).cycle.unwrap().physical.clone().unwrap();
    assert_eq!(ph.shear_stress_reference, Some("relative to σμ_ref, steady sliding at v0"));
    assert!(ph.friction_before.is_none() && ph.friction_steady.is_none());
    let rel = ph.shear_stress_before.unwrap() - ph.shear_stress_after.unwrap();
    assert!((rel - ph.stress_drop).abs() < 1e-9 * ph.stress_drop);
    let days = ph.in_time_unit.unwrap();
    assert_eq!(days.time_unit, "days");
    assert!((days.period - ph.period / 86400.0).abs() < 1e-12 * days.period);
    assert!((days.t0 - ph.t0 / 86400.0).abs() < 1e-12 * days.t0);
}

#[test]
fn stiffness_from_shear_modulus_and_length_and_state_conversions() {
    // k = G/L: L = 120 m gives the scene's 2.5e8 Pa/m.
    let s = scene::parse(&qdyn_with(r#""k": 2.5e8"#, r#""length": 120"#), "t").unwrap();
    assert!((s.params.xi - 0.25).abs() < 1e-15, "{}", s.params.xi);
    // Θ = 2 D_c/V_pl: θ = (b/a) ln 2 (every state law under log friction).
    for law in ["ageing", "slip", "prz"] {
        let text = qdyn_with(r#""state": 1e5"#, r#""state": 2e5"#).replacen(
            r#""state_law": "ageing""#,
            &format!(r#""state_law": "{law}""#),
            1,
        );
        let s = scene::parse(&text, "t").unwrap();
        assert!((s.initial[2] - 1.5 * 2f64.ln()).abs() < 1e-15, "{law}: {}", s.initial[2]);
    }
    // V = 3 V_pl: v = 3.
    let s = scene::parse(&qdyn_with(r#""velocity": 5e-10"#, r#""velocity": 3e-9"#), "t").unwrap();
    assert!((s.initial[1] - 3f64.ln()).abs() < 1e-15);
    // The stress-unit form gives the same model (without σ: no μ outputs, so no mu0).
    let stress_form =
        qdyn_with(r#""sigma": 1e7, "a": 0.01, "b": 0.015"#, r#""a_sigma": 1e5, "b_sigma": 1.5e5"#)
            .replacen(r#""mu0": 0.6, "v_ref": 1e-6,"#, "", 1);
    let s2 = scene::parse(&stress_form, "t").unwrap();
    assert_eq!((s2.params.xi, s2.params.epsilon), (0.25, 0.5));
    assert_eq!(s2.scales.unwrap().sigma, None);
}

#[test]
fn each_bad_field_input_is_refused_naming_its_field() {
    let no_mu0 = |t: String| t.replacen(r#""mu0": 0.6, "v_ref": 1e-6,"#, "", 1);
    let cases: Vec<(String, &str, &str)> = vec![
        (qdyn_with(r#""sigma": 1e7, "#, ""), "model.dimensional.sigma", "a_sigma"),
        (
            qdyn_with(r#""a": 0.01"#, r#""a": 0.01, "a_sigma": 1e5"#),
            "model.dimensional.a",
            "not both",
        ),
        (
            qdyn_with(r#""b": 0.015"#, r#""b_sigma": 1.5e5"#),
            "model.dimensional.b",
            "friction coefficient",
        ),
        (qdyn_with(r#""b": 0.015, "#, ""), "model.dimensional.b", "missing"),
        (qdyn_with(r#""k": 2.5e8, "#, ""), "model.dimensional.k", "shear_modulus and length"),
        (
            qdyn_with(r#""k": 2.5e8"#, r#""k": 2.5e8, "length": 120"#),
            "model.dimensional.length",
            "not both",
        ),
        (
            no_mu0(qdyn_with(
                r#""k": 2.5e8, "shear_modulus": 3e10, "shear_wave_speed": 3e3"#,
                r#""length": 120, "shear_wave_speed": 3e3"#,
            )),
            "model.dimensional.shear_modulus",
            "G/L",
        ),
        (qdyn_with(r#", "v_ref": 1e-6"#, ""), "model.dimensional.v_ref", "missing"),
        (qdyn_with(r#""mu0": 0.6, "#, ""), "model.dimensional.mu0", "missing"),
        (
            qdyn_with(
                r#""sigma": 1e7, "a": 0.01, "b": 0.015"#,
                r#""a_sigma": 1e5, "b_sigma": 1.5e5"#,
            ),
            "model.dimensional.sigma",
            "mu0",
        ),
        (
            qdyn_with(
                r#""inertia": false,"#,
                r#""inertia": false, "friction": {"power": {"alpha": 0.3}},"#,
            ),
            "model.dimensional.mu0",
            "logarithmic",
        ),
        (qdyn_with(r#""sigma": 1e7"#, r#""sigma": -1e7"#), "model.dimensional.sigma", "> 0"),
        (qdyn_with(r#""a": 0.01"#, r#""a": 0"#), "model.dimensional.a", "> 0"),
        (
            qdyn_with(r#""velocity": 5e-10"#, r#""velocity": 5e-10, "v": 0.5"#),
            "initial.velocity",
            "not both",
        ),
        (qdyn_with(r#""state": 1e5"#, r#""state": 1e5, "theta": 0"#), "initial.state", "not both"),
        (qdyn_with(r#""state": 1e5"#, r#""state": -1"#), "initial.state", "> 0"),
        (qdyn_with(r#""velocity": 5e-10"#, r#""velocity": 0"#), "initial.velocity", "> 0"),
        (
            no_mu0(qdyn_with(r#""inertia": false,"#, r#""inertia": false, "friction": "asinh","#)),
            "initial.state",
            "logarithmic",
        ),
        (
            DIMENSIONLESS_TWIN.replacen(r#""v": 0.5"#, r#""velocity": 5e-10"#, 1),
            "initial.velocity",
            "model.dimensional",
        ),
        (
            DIMENSIONLESS_TWIN.replacen(r#""theta": 0"#, r#""state": 1e5"#, 1),
            "initial.state",
            "model.dimensional",
        ),
    ];
    for (text, field, hint) in cases {
        let e = scene::parse(&text, "t").expect_err(&text);
        assert_eq!(e.field, field, "{text}\n{e}");
        assert!(e.message.contains(hint), "{e}");
    }
}

#[test]
fn a_and_b_without_sigma_exit_2_naming_sigma_and_a_sigma() {
    // The issue's case: QDYN's "a": 0.01, "b": 0.015 given without σ.
    let out = cli_run(&qdyn_with(r#""sigma": 1e7, "#, ""), "nosigma", &["--json"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("model.dimensional.sigma") && stderr.contains("a_sigma"), "{stderr}");
}

#[test]
fn parameters_far_outside_the_physical_range_warn_in_the_report_and_on_stderr() {
    // Coefficients far above rock friction's (a = 0.5, b = 0.75) and a shear modulus 1e9 times
    // too large (η = 1).
    let text = qdyn_with(r#""a": 0.01, "b": 0.015"#, r#""a": 0.5, "b": 0.75"#).replacen(
        r#""shear_modulus": 3e10"#,
        r#""shear_modulus": 3e19"#,
        1,
    );
    let s = scene::parse(&text, "t").unwrap();
    let joined = s.warnings.join("\n");
    for needle in ["model.dimensional.a/sigma", "model.dimensional.b/sigma", "η = G·v0"] {
        assert!(joined.contains(needle), "{needle} not in {joined}");
    }
    let huge_xi = qdyn_with(r#""k": 2.5e8"#, r#""k": 2.5e14"#);
    let s = scene::parse(&huge_xi, "t").unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("ξ = k·D_c/(aσ)")), "{:?}", s.warnings);
    let out = cli_run(
        &huge_xi.replacen(r#""analyses": ["hopf", "cycle"]"#, r#""analyses": ["hopf"]"#, 1),
        "xi",
        &["--json"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning") && stderr.contains("model.dimensional.k"), "{stderr}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["warnings"][0].as_str().unwrap().contains("ξ"), "{}", report["warnings"]);
}

#[test]
fn warnings_name_the_fields_the_user_gave() {
    // k as G/L (L = 0.12 mm: k = 2.5e14 Pa/m) and the coefficients as stresses.
    let text = qdyn_with(r#""k": 2.5e8"#, r#""length": 1.2e-4"#)
        .replacen(
            r#""sigma": 1e7, "a": 0.01, "b": 0.015"#,
            r#""a_sigma": 1e5, "b_sigma": 1.5e5"#,
            1,
        )
        .replacen(r#""mu0": 0.6, "v_ref": 1e-6,"#, "", 1);
    let s = scene::parse(&text, "t").unwrap_or_else(|e| panic!("{e}"));
    let joined = s.warnings.join("\n");
    assert!(joined.contains("model.dimensional.shear_modulus/length/d_c/a_sigma"), "{joined}");
    assert!(!joined.contains("model.dimensional.k/"), "{joined}");
}

#[test]
fn a_declared_si_unit_system_names_the_units_without_hedging() {
    let text = qdyn_with(r#""sigma": 1e7,"#, r#""unit_system": "SI", "sigma": 1e7,"#);
    let s = scene::parse(&text, "t").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.units.as_ref().unwrap().time_unit, "s");
    let report = run_scene(&text);
    let summary = report.summary();
    assert!(summary.contains("in SI units") && summary.contains("m/s"), "{summary}");
    assert!(!summary.contains("if the dimensional input is SI"), "{summary}");
    let bad = qdyn_with(r#""sigma": 1e7,"#, r#""unit_system": "cgs", "sigma": 1e7,"#);
    let e = scene::parse(&bad, "t").unwrap_err().to_string();
    assert!(e.contains("unit_system") || e.contains("SI"), "{e}");
}
