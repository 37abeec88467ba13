//! The event catalogue (issue #45 Deliver 1): an event under way at t = 0 is catalogued and
//! flagged, a run that stays near steady sliding has none, and every event peaks above the
//! threshold with a positive stress drop. On copies of a pyqdyn-written file
//! (data/qdyn/classic_ageing.in) with V_0 = 2·V_PL, and with a = 0.012 > b = 0.008.

use std::path::{Path, PathBuf};
use std::process::Command;
use stickslip::scene::qdyn_input;
use stickslip::{engine, scene};

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

/// data/qdyn/classic_ageing.in with its line 16 (SIGMA, V_0, TH_0, A, B, …) edited by `edit`
/// and TMAX set to `tmax` (s).
fn classic_ageing(edit: impl Fn(&mut Vec<String>), tmax: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/qdyn/classic_ageing.in");
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert!(lines[10].starts_with("0.1 0 208334765.05483 1e-11"), "{}", lines[10]);
    lines[10] = lines[10].replace("208334765.05483", tmax);
    let mut values: Vec<String> = lines[15].split_whitespace().map(String::from).collect();
    edit(&mut values);
    lines[15] = values.join(" ");
    lines.join("\n") + "\n"
}

/// The report of a mapped file, run in the library (radau5 at the file's ACC = 1e-11), with
/// `replace` applied to the scene text.
fn run(text: &str, replace: &[(&str, &str)]) -> serde_json::Value {
    let mut scene_text = qdyn_input::to_scene(text, "test.in", "test").unwrap();
    for (from, to) in replace {
        assert!(scene_text.contains(from), "{from} in {scene_text}");
        scene_text = scene_text.replace(from, to);
    }
    let scene = scene::parse(&scene_text, "test").unwrap();
    serde_json::from_str(&engine::run(&scene, engine::RunOptions::default()).unwrap().to_json())
        .unwrap()
}

/// TMAX = 2.1e7 s as the mapped scene prints it.
const T_MAX: &str = r#""t_max": 21000000.0"#;

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// V_0 = 2·V_PL (1 nm/s): the block is past steady sliding at t = 0 and accelerates into the
/// first event, which QDYN's output shows and which the catalogue now lists, flagged.
#[test]
fn an_event_under_way_at_the_start_is_listed_and_flagged() {
    // 4 periods (5.2e6 s each) after the first event: 5 events.
    let text = classic_ageing(|v| v[1] = "2e-09".into(), "2.1e7");
    let report = run(&text, &[]);
    let ts = &report["time_series"];
    assert_eq!(num(ts, "event_threshold"), 100.0, "the default, 100·V_PL");
    assert!((num(ts, "event_threshold_physical") - 1e-7).abs() < 1e-20);
    let events = report["events"].as_array().unwrap();
    assert_eq!(events.len(), 5, "{events:?}");
    let first = &events[0];
    assert_eq!(first["started_before_run"], true);
    assert_eq!(num(first, "t_start"), 0.0);
    assert!(first["recurrence"].is_null());
    // Measured: the first peak at 76178.4788 s, 0.07247 m/s (the settled ones 0.1430 m/s).
    let p = &first["physical"];
    assert!((num(p, "t_peak") / 76178.4788 - 1.0).abs() < 1e-8, "{p}");
    assert!((num(p, "v_max") / 0.0724663 - 1.0).abs() < 1e-5, "{p}");
    for e in &events[1..] {
        assert_eq!(e["started_before_run"], false);
        assert!(num(e, "t_start") > num(&events[0], "t_end"));
    }
    for e in events {
        assert!(num(e, "v_max") > 100.0 && num(e, "stress_drop") > 0.0, "{e}");
    }
    // The peaks against an independent integrator (Rodas5P at rtol 1e-12): within 1e-9.
    let rodas = run(&text, &[("\"radau5\"", "\"rodas5p\""), ("1e-11", "1e-12")]);
    let theirs = rodas["events"].as_array().unwrap();
    assert_eq!(theirs.len(), events.len());
    for (a, b) in events.iter().zip(theirs) {
        let (ta, tb) = (num(&a["physical"], "t_peak"), num(&b["physical"], "t_peak"));
        assert!((ta / tb - 1.0).abs() < 1e-9, "{ta} against {tb}");
        assert_eq!(a["started_before_run"], b["started_before_run"]);
    }

    // The same start below an explicit threshold under its first peak: that peak is not an
    // event, the next ones are.
    let high = run(&text, &[(T_MAX, r#""t_max": 21000000.0, "event_threshold": 1e8"#)]);
    let high_events = high["events"].as_array().unwrap();
    assert_eq!(num(&high["time_series"], "event_threshold"), 1e8);
    assert_eq!(high_events.len(), 4, "{high_events:?}");
    assert!(high_events.iter().all(|e| e["started_before_run"] == false));
    assert_eq!(high_events[0]["t_peak"], events[1]["t_peak"], "the same episodes");
}

/// a = 0.012 > b = 0.008: velocity strengthening, the oscillation dies out and V creeps back
/// to V_PL, crossing it again and again by round-off: no event (it listed 194 with v_max
/// = 1.000000 and a stress drop of 0 when every excursion above V_PL was one).
#[test]
fn a_run_near_steady_sliding_has_no_event() {
    let text = classic_ageing(
        |v| {
            v[3] = "0.012".into();
            v[4] = "0.008".into();
        },
        "208334765.05483",
    );
    let dir = std::env::temp_dir().join(format!("stickslip-events-vs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file: PathBuf = dir.join("vs.in");
    std::fs::write(&file, &text).unwrap();
    let out = Command::new(EXE).args(["run", file.to_str().unwrap(), "--json"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["cycle"]["status"], "fixed_point", "{}", report["cycle"]);
    assert_eq!(report["events"].as_array().unwrap().len(), 0, "{}", report["events"]);
    assert_eq!(report["time_series"]["in_event_at_end"], false);
    let summary = Command::new(EXE).args(["run", file.to_str().unwrap()]).output().unwrap();
    let summary = String::from_utf8_lossy(&summary.stdout);
    assert!(summary.contains("0 events (episodes above v = 1 peaking above v = 100"), "{summary}");
    std::fs::remove_dir_all(&dir).ok();
}

/// QDYN's V_TH is the file's event threshold where IASP = 1 (QDYN lists the peaks above it
/// there); with IASP = 0 QDYN does not use it and the default holds.
#[test]
fn v_th_is_the_threshold_where_iasp_is_one() {
    let threshold = |iasp: &str| {
        let text = classic_ageing(|v| v[11] = iasp.into(), "2.1e7");
        let scene = scene::parse(&qdyn_input::to_scene(&text, "t.in", "t").unwrap(), "t").unwrap();
        scene.analyses.time_series.unwrap().event_threshold()
    };
    assert_eq!(threshold("0"), 100.0);
    // V_TH = 0.01 m/s over V_PL = 1e-9 m/s.
    assert!((threshold("1") / 1e7 - 1.0).abs() < 1e-15);
    // V_TH at V_PL would count steady sliding: refused on its line.
    let text = classic_ageing(|v| v[11] = "1".into(), "2.1e7")
        .replace("3000 30000000000 30000000000 0 0 0.01", "3000 30000000000 30000000000 0 0 1e-9");
    let e = qdyn_input::to_scene(&text, "t.in", "t").unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (9, "V_TH"), "{e}");
    assert!(e.message.contains("above V_PL"), "{e}");
}

/// A threshold at or below the loading velocity is not an event threshold: exit 2.
#[test]
fn a_threshold_at_the_loading_velocity_is_refused() {
    let text = classic_ageing(|_| {}, "2.1e7");
    let scene_text = qdyn_input::to_scene(&text, "t.in", "t")
        .unwrap()
        .replace(T_MAX, r#""t_max": 21000000.0, "event_threshold": 1"#);
    let e = scene::parse(&scene_text, "t").unwrap_err();
    assert!(e.to_string().contains("event_threshold") && e.to_string().contains("above 1"), "{e}");
}
