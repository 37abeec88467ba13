//! Periodic loading (docs/periodic-loading.md): every method integrates the forced system to
//! the same events (inertial, and quasi-dynamic through restarts and exact time shifts of the
//! local clock, which move the forcing's time origin), and a zero amplitude is no loading.

mod common;

use common::run_scene;
use stickslip::analysis::time_series::Event;

/// An inertial forced scene (γ = 10, ξ = 0.8, ε = 1, a_per = 0.3, T = 7) with `method`.
fn inertial(method: &str, loading: &str) -> String {
    format!(
        r#"{{"name": "forced", "model": {{"gamma": 10, "xi": 0.8, "epsilon": 1.0{loading}}},
        "initial": {{"u": 0.0, "v": 1.2, "theta": 0.0}},
        "solver": {{"method": "{method}", "rtol": 1e-10}},
        "analyses": [{{"time_series": {{"t_max": 120, "event_threshold": 1.01}}}}]}}"#
    )
}

const LOADING: &str = r#", "periodic_loading": {"amplitude": 0.3, "period": 7.0}"#;

const METHODS: [&str; 8] = [
    "cvode-bdf",
    "cvode-adams",
    "arkode-dirk",
    "arkode-imex",
    "arkode-erk",
    "radau5",
    "rodas5p",
    "extrapolation",
];

fn assert_same_events(a: &[Event], b: &[Event], tolerance: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: event counts");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let (x, y) = (&x.values, &y.values);
        for (key, p, q) in [("t_peak", x.t_peak, y.t_peak), ("v_max", x.v_max, y.v_max)] {
            assert!(
                (p - q).abs() <= tolerance * q.abs(),
                "{what} event {i}: {key} {p} vs {q} ({:.1e} relative)",
                (p - q).abs() / q.abs()
            );
        }
    }
}

/// Measured at rtol 1e-10: within 1.1e-8 (peak times) and 2.2e-8 (v_max) of radau5.
#[test]
fn every_method_gives_the_same_forced_events() {
    let reports: Vec<_> = std::thread::scope(|s| {
        let runs: Vec<_> =
            METHODS.iter().map(|m| s.spawn(move || run_scene(&inertial(m, LOADING)))).collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    let reference = reports[5].events.as_deref().unwrap();
    assert!(reference.len() >= 8, "{} events", reference.len());
    for (method, report) in METHODS.iter().zip(&reports) {
        assert_same_events(report.events.as_deref().unwrap(), reference, 1e-7, method);
        let forcing = report.forcing.as_ref().unwrap();
        assert_eq!((forcing.amplitude, forcing.period), (0.3, 7.0));
    }
    // The forcing moves the events: the unforced run's differ.
    let unforced = run_scene(&inertial("radau5", ""));
    assert!(unforced.forcing.is_none());
    let free = unforced.events.unwrap();
    assert!((free[3].values.t_peak - reference[3].values.t_peak).abs() > 1e-3);
}

/// A zero amplitude is no loading: the same events, no `forcing` section.
#[test]
fn zero_amplitude_is_the_unforced_run() {
    let zero = run_scene(&inertial("radau5", &LOADING.replace("0.3", "0")));
    let unforced = run_scene(&inertial("radau5", ""));
    assert!(zero.forcing.is_none());
    assert_eq!(zero.events, unforced.events);
}

/// The quasi-dynamic QDYN case at crustal damping (data/qdyn/classic_slip_per3.in as a scene)
/// with a restarting method (cvode-bdf: 15 restarts of its clock) and an exactly shifting one
/// (rodas5p, with the analytic ∂f/∂t: 240 shifts) agree: the origin moves right either way.
#[test]
fn restarts_and_time_shifts_agree_under_crustal_damping() {
    let file = format!("{}/data/qdyn/classic_slip_per3.in", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&file).unwrap();
    let scene = stickslip::scene::qdyn_input::to_scene(&text, &file, "per3").unwrap();
    let with = |method: &str| {
        let mut v: serde_json::Value = serde_json::from_str(&scene).unwrap();
        v["solver"] = serde_json::json!({"method": method, "rtol": 1e-10});
        v["analyses"] = serde_json::json!([{"time_series": {"t_max": 5e7}}]);
        run_scene(&v.to_string())
    };
    let (bdf, rodas) = std::thread::scope(|s| {
        let b = s.spawn(|| with("cvode-bdf"));
        let r = s.spawn(|| with("rodas5p"));
        (b.join().unwrap(), r.join().unwrap())
    });
    let (b, r) = (bdf.events.unwrap(), rodas.events.unwrap());
    assert!(b.len() >= 10, "{} events", b.len());
    assert!(bdf.time_series.unwrap().rebases > 0 && rodas.time_series.unwrap().rebases > 0);
    assert_same_events(&b, &r, 1e-7, "cvode-bdf vs rodas5p");
}

/// A forced scene built in code (not through `scene::parse`, which refuses it) with an
/// analysis that assumes an autonomous system: the engine refuses it as bad input.
#[test]
fn the_engine_refuses_autonomous_analyses_of_a_forced_scene() {
    let text = inertial("radau5", LOADING);
    let mut scene = stickslip::scene::parse(&text, "forced").unwrap();
    scene.analyses.cycle = Some(Default::default());
    let stickslip::engine::RunError::Failed(e) = stickslip::engine::run(
        &scene,
        stickslip::engine::RunOptions::echoing(serde_json::from_str(&text).unwrap()),
    )
    .unwrap_err() else {
        panic!("a failed run")
    };
    assert!(e.is_bad_input() && e.message.contains("autonomous"), "{e}");
    let mut scene = stickslip::scene::parse(&text, "forced").unwrap();
    scene.analyses.hopf = true;
    let stickslip::engine::RunError::Failed(e) = stickslip::engine::run(
        &scene,
        stickslip::engine::RunOptions::echoing(serde_json::from_str(&text).unwrap()),
    )
    .unwrap_err() else {
        panic!("a failed run")
    };
    assert!(e.is_bad_input() && e.message.contains("autonomous"), "{e}");
}
