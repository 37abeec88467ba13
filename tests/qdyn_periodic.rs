//! Periodic loading (QDYN's APER, TPER) against QDYN: the pyqdyn-written files
//! data/qdyn/classic_slip_per03.in and classic_slip_per3.in (APER = 40 kPa, TPER = 0.3 and 3
//! times classic_slip's unforced period) run directly, and their first 20 events (peak times,
//! v_max) agree with QDYN's runs of the same files (data/reference/qdyn_periodic.json, made by
//! data/qdyn/periodic_reference.py) within 1e-6 relative. A forced scene reports its event
//! catalogue and its locking to the forcing, never an unforced cycle.

use std::path::{Path, PathBuf};
use std::process::Command;

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(path)
}

fn run(file: &Path) -> serde_json::Value {
    let out = Command::new(EXE).args(["run", file.to_str().unwrap(), "--json"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn first_20_events_agree_with_qdyn_within_1e_6() {
    let text = std::fs::read_to_string(data("reference/qdyn_periodic.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let cases = reference["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2);
    let reports: Vec<serde_json::Value> = std::thread::scope(|s| {
        let runs: Vec<_> = cases
            .iter()
            .map(|c| {
                let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(c["file"].as_str().unwrap());
                s.spawn(move || run(&file))
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    for (case, report) in cases.iter().zip(&reports) {
        let name = case["file"].as_str().unwrap();
        assert!(report.get("cycle").is_none(), "{name}: a forced scene has no unforced cycle");
        let ours = report["events"].as_array().unwrap();
        let theirs = case["events"].as_array().unwrap();
        assert_eq!(theirs.len(), 20, "{name}");
        assert!(ours.len() >= 20, "{name}: {} events", ours.len());
        for (i, (o, q)) in ours.iter().zip(theirs).enumerate() {
            for (key, their_key) in [("t_peak", "t_peak_s"), ("v_max", "v_max_m_per_s")] {
                let a = o["physical"][key].as_f64().unwrap();
                let b = q[their_key].as_f64().unwrap();
                assert!(
                    (a - b).abs() <= 1e-6 * b.abs(),
                    "{name} event {i}: {key} {a} vs QDYN {b} ({:.2e} relative)",
                    (a - b).abs() / b.abs()
                );
            }
        }
        let forcing = &report["forcing"];
        assert_eq!(forcing["physical"]["amplitude"], 4e4, "{name}");
        assert!(forcing["statement"].as_str().is_some_and(|s| !s.is_empty()), "{name}");
    }
    // TPER = 3 P: three events in each forcing period, at three phases.
    let long = &reports[1]["forcing"];
    assert_eq!(long["locked"], true, "{}", long["statement"]);
    assert_eq!((long["lock_events"].as_u64(), long["lock_periods"].as_u64()), (Some(3), Some(1)));
    // TPER = 0.3 P: 0.3 events per period on average, not locked to 1e-3·T within 30 P.
    let short = &reports[0]["forcing"];
    let rate = short["events_per_period"].as_f64().unwrap();
    assert!((rate - 0.3).abs() < 0.01, "{rate}");
    assert_eq!(short["locked"], false, "{}", short["statement"]);
    assert!(short["statement"].as_str().unwrap().starts_with("not locked"));
}

/// `APER`, `TPER` map to `dimensional.periodic_loading`, and the analyses to the time series
/// alone; `--print-scene` shows them.
#[test]
fn aper_and_tper_map_to_the_scenes_periodic_loading() {
    let file = data("qdyn/classic_slip_per3.in");
    let out =
        Command::new(EXE).args(["run", file.to_str().unwrap(), "--print-scene"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let scene: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let loading = &scene["model"]["dimensional"]["periodic_loading"];
    assert_eq!(loading["amplitude"], 4e4);
    assert_eq!(loading["period"], 14337603.1780457);
    assert_eq!(
        scene["analyses"],
        serde_json::json!([{"time_series": {"t_max": 143376031.780457}}])
    );
    let parsed = stickslip::scene::parse(&scene.to_string(), "per3").unwrap();
    let l = parsed.loading.unwrap();
    // a_per = A_per/(aσ) = 0.4, T = T_per·V_pl/D_c.
    assert!((l.amplitude - 0.4).abs() < 1e-15 && (l.period - 143.376031780457).abs() < 1e-12);
}

/// A forced scene asks only for what a forced system has: the unforced analyses exit 2
/// naming the field.
#[test]
fn forced_scenes_refuse_the_autonomous_analyses() {
    let scene = |analyses: &str| {
        format!(
            r#"{{"name": "forced", "model": {{"xi": 0.25, "epsilon": 0.5, "inertia": false,
            "radiation_damping": 0.05, "periodic_loading": {{"amplitude": 0.4, "period": 14.3}}}},
            "analyses": {analyses}}}"#
        )
    };
    for analysis in ["\"cycle\"", "\"hopf\"", "{\"shooting\": {}}"] {
        let e = stickslip::scene::parse(&scene(&format!("[{analysis}]")), "forced").unwrap_err();
        assert_eq!(e.field, "analyses", "{e}");
        assert!(e.message.contains("autonomous"), "{e}");
    }
    let e = stickslip::scene::parse(&scene("[]"), "forced").unwrap_err();
    assert!(e.message.contains("time_series"), "{e}");
    let bad = scene(r#"[{"time_series": {"t_max": 100}}]"#).replace("14.3", "-1");
    let e = stickslip::scene::parse(&bad, "forced").unwrap_err();
    assert_eq!(e.field, "model.periodic_loading.period", "{e}");
    let ok = stickslip::scene::parse(&scene(r#"[{"time_series": {"t_max": 100}}]"#), "f").unwrap();
    let loading = ok.loading.unwrap();
    assert_eq!((loading.amplitude, loading.period), (0.4, 14.3));
}
