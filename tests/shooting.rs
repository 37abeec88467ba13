//! Shooting and continuation against the brute-force reference table
//! (data/reference/drr_cycles.json: CVODE and ARKStep at rtol 1e-11, agreeing to 6e-9).

use stickslip::{engine, scene};

fn reference_rows() -> Vec<serde_json::Value> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/data/reference/drr_cycles.json");
    let table: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    table["rows"].as_array().unwrap().clone()
}

fn run(text: &str) -> stickslip::report::Report {
    let s = scene::parse(text, "test").unwrap();
    engine::run(&s, serde_json::Value::Null).unwrap()
}

#[test]
fn shooting_agrees_with_brute_force_on_every_reference_cycle() {
    let mut worst: f64 = 0.0;
    for row in reference_rows() {
        let (gamma, xi, epsilon) = (row["gamma"].as_f64().unwrap(), row["xi"].as_f64().unwrap(), row["epsilon"].as_f64().unwrap());
        let report = run(&format!(
            r#"{{"name": "s", "model": {{"gamma": {gamma:e}, "xi": {xi}, "epsilon": {epsilon}}},
                "solver": {{"method": "radau5", "rtol": 1e-10, "atol": 1e-12}}, "analyses": ["shooting"]}}"#
        ));
        let shooting = report.shooting.unwrap();
        let orbit = shooting.orbit.unwrap_or_else(|| panic!("γ = {gamma}: {:?}", shooting.failure));
        let reference = row["reference"]["period"].as_f64().unwrap();
        let rel = (orbit.period - reference).abs() / reference;
        worst = worst.max(rel);
        assert!(rel < 1e-8, "ξ={xi} ε={epsilon} γ={gamma:e}: shooting {} vs brute force {reference} ({rel:.1e})", orbit.period);
        let ln_v_max = row["reference"]["ln_v_max"].as_f64().unwrap();
        assert!((orbit.ln_v_max - ln_v_max).abs() < 1e-6 * ln_v_max, "γ={gamma:e}: ln v_max {} vs {ln_v_max}", orbit.ln_v_max);
        assert!(orbit.stable, "γ={gamma:e}: the relaxation cycle is an attractor: {:?}", orbit.multipliers);
        // The trivial multiplier: 1 to 1e-6 up to γ = 1e3 (its accuracy degrades ∝ γ, see
        // analysis::shooting: ~1e-6 at 1e4), and no worse than 5e-2 at γ = 1e8.
        let bound = if gamma <= 1e3 { 1e-6 } else if gamma <= 1e4 { 1e-5 } else { 5e-2 };
        assert!(orbit.trivial_multiplier_error < bound, "γ={gamma:e}: |μ − 1| = {:e}", orbit.trivial_multiplier_error);
    }
    eprintln!("worst relative period difference shooting vs brute force: {worst:.2e}");
}

#[test]
fn shooting_converges_near_the_hopf_threshold_where_brute_force_is_slow() {
    // ε 1e-3 above ε_c at γ = 10: the orbit's non-trivial multiplier is close to 1, so plain
    // iteration (brute force) converges slowly; Newton does not care.
    let report = run(
        r#"{"name": "h", "model": {"gamma": 10, "xi": 0.7, "epsilon": 0.6961},
            "solver": {"method": "radau5", "rtol": 1e-10, "atol": 1e-12}, "analyses": ["hopf", "shooting"]}"#,
    );
    let hopf = report.hopf.unwrap();
    assert!(hopf.above_threshold && report.model.epsilon - hopf.epsilon_c < 1.1e-3);
    let orbit = report.shooting.unwrap().orbit.unwrap();
    assert!(orbit.trivial_multiplier_error < 1e-6, "{:?}", orbit.multipliers);
    // Near a supercritical Hopf the period is close to 2π/ω_c.
    assert!((orbit.period - hopf.period_c).abs() < 0.05 * hopf.period_c, "period {} vs {}", orbit.period, hopf.period_c);
}

#[test]
fn fig1c_continuation_in_gamma_reproduces_the_reference_periods() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes/fig1c.json")).unwrap();
    let c = run(&text).continuation.unwrap();
    assert!(c.completed, "{:?}", c.stopped);
    assert_eq!(c.points.len(), 71);
    for row in reference_rows().iter().filter(|r| r["xi"].as_f64() == Some(0.7)) {
        let gamma = row["gamma"].as_f64().unwrap();
        let point = c.points.iter().find(|p| (p.value / gamma - 1.0).abs() < 1e-9).expect("a decade of γ is a grid point");
        let reference = row["reference"]["period"].as_f64().unwrap();
        let rel = (point.orbit.period - reference).abs() / reference;
        assert!(rel < 1e-8, "γ={gamma:e}: continuation {} vs brute force {reference} ({rel:.1e})", point.orbit.period);
    }
    // The period per decade of γ: between 4.5 and 5.5 over the whole range (the paper: "about 5").
    let slope = c.period_per_decade[0].slope;
    assert!((4.5..5.5).contains(&slope), "{slope}");
}

#[test]
fn continuation_in_epsilon_stops_near_the_threshold_and_says_why() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes/fig1b.json")).unwrap();
    let report = run(&text);
    let eps_c = report.hopf.unwrap().epsilon_c;
    let c = report.continuation.unwrap();
    let stop = c.stopped.expect("the relaxation branch cannot be followed down to ε_c");
    assert!(stop.last_value - eps_c < 1e-3 && stop.last_value > eps_c, "stopped at {} (ε_c = {eps_c})", stop.last_value);
    assert!(stop.reason.contains("abruptly") || stop.reason.contains("fixed point"), "{}", stop.reason);
    // Periods fall monotonically towards the threshold.
    assert!(c.points.windows(2).all(|w| w[1].orbit.period < w[0].orbit.period));
}

#[test]
fn bad_continuation_options_name_the_field() {
    let bad = [
        (r#"{"continuation": {"parameter": "k", "to": 1, "points": 5}}"#, "parameter"),
        (r#"{"continuation": {"parameter": "gamma", "to": -1, "points": 5}}"#, "to"),
        (r#"{"continuation": {"parameter": "gamma", "to": 1e3, "points": 1}}"#, "points"),
        (r#"{"continuation": {"parameter": "epsilon", "to": 1, "points": 5, "log": true}}"#, "log"),
        (r#"{"shooting": {"tolerance": 0}}"#, "tolerance"),
        (r#""continuation""#, "continuation"),
    ];
    for (analysis, field) in bad {
        let text = format!(r#"{{"name": "b", "model": {{"gamma": 1e3, "xi": 0.7, "epsilon": 0.72}}, "analyses": [{analysis}]}}"#);
        let e = scene::parse(&text, "bad").unwrap_err();
        assert!(e.field.contains(field) || (e.field.starts_with("analyses") && e.message.contains(field)), "{analysis}: {e}");
    }
}

#[test]
fn period_doubling_is_detected_and_the_doubled_orbit_matches_brute_force() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes/period-doubling.json")).unwrap();
    let report = run(&text);
    let shooting = report.shooting.unwrap();
    let single = shooting.orbit.unwrap();
    assert!(!single.stable, "the period-1 orbit has lost stability: {:?}", single.multipliers);
    let pd = shooting.period_doubling.expect("a multiplier below −1");
    assert!(pd.multiplier < -1.1, "{}", pd.multiplier);
    let doubled = pd.doubled.unwrap_or_else(|| panic!("doubled orbit not found: {}", pd.note));
    assert_eq!(doubled.returns_per_period, 2);
    assert!(doubled.stable && doubled.trivial_multiplier_error < 1e-6, "{:?}", doubled.multipliers);
    // Brute force settles on the same period-2 orbit.
    let cycle = report.cycle.unwrap();
    assert_eq!(cycle.cycles_per_period, Some(2));
    let brute = cycle.orbit_period.unwrap();
    assert!((doubled.period - brute).abs() < 1e-8 * brute, "shooting {} vs brute force {brute}", doubled.period);
    let (mut a, mut b) = (doubled.return_times.clone(), cycle.orbit.iter().map(|c| c.period).collect::<Vec<_>>());
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-7 * y, "return times {a:?} vs cycles {b:?}");
    }
}
