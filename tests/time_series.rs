//! The "time_series" analysis (issue #26 items 3–4): a run of fixed length from t = 0 in
//! absolute time, written by `stickslip run --series FILE` as CSV or .npy, and its event
//! catalogue in the report under `events`. Checked against the cycle analysis of the same
//! scene run tight (an independent event rule: upward crossings of v = 1 averaged over
//! settled cycles, against the time series' peak-to-peak recurrences).

use engine::RunOptions;
use std::path::{Path, PathBuf};
use std::process::Command;
use stickslip::analysis::time_series::SeriesCollector;
use stickslip::report::Report;
use stickslip::series_file::{self, ReadSeries};
use stickslip::{engine, scene};

/// The report of `scene` with its "time_series" rows kept in memory.
fn run_collecting(scene: &scene::Scene) -> (Report, SeriesCollector) {
    let mut series = SeriesCollector::default();
    let report = engine::run(scene, RunOptions::default().series(&mut series)).unwrap();
    (report, series)
}

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

/// The field scene of issue #26 in dimensionless form: ξ = 0.25, ε = 0.5, η = 5e-8,
/// quasi-dynamic, ageing law, v = 0.5, θ = 0; its cycle run tight (convergence tolerance
/// 1e-11) beside a time series of `t_max`.
fn field_scene(time_series: &str) -> String {
    format!(
        r#"{{"name": "field", "model": {{"xi": 0.25, "epsilon": 0.5, "radiation_damping": 5e-8,
            "inertia": false, "state_law": "ageing"}},
          "initial": {{"v": 0.5, "theta": 0}},
          "solver": {{"method": "radau5", "rtol": 1e-12}},
          "analyses": [{{"cycle": {{"tolerance": 1e-11}}}}, {{"time_series": {time_series}}}]}}"#
    )
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stickslip-ts-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `stickslip run SCENE --out REPORT [--series FILE]`; returns the exit code, stderr and
/// the report (if written).
fn run_cli(dir: &Path, scene: &str, series: Option<&Path>) -> (i32, String, serde_json::Value) {
    let scene_path = dir.join("scene.json");
    let out = dir.join("report.json");
    std::fs::write(&scene_path, scene).unwrap();
    std::fs::remove_file(&out).ok();
    let mut cmd = Command::new(EXE);
    cmd.args(["run", scene_path.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    if let Some(s) = series {
        cmd.args(["--series", s.to_str().unwrap()]);
    }
    let run = cmd.output().unwrap();
    let report = std::fs::read_to_string(&out)
        .ok()
        .map_or(serde_json::Value::Null, |t| serde_json::from_str(&t).unwrap());
    (run.status.code().unwrap(), String::from_utf8_lossy(&run.stderr).into(), report)
}

fn read_csv(path: &Path) -> ReadSeries {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let names: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut columns = vec![Vec::new(); names.len()];
    for line in lines {
        for (c, cell) in columns.iter_mut().zip(line.split(',')) {
            c.push(cell.parse::<f64>().unwrap());
        }
    }
    ReadSeries { names, columns }
}

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} missing in {v}"))
}

#[test]
fn field_scene_25_cycles_csv_and_npy_recur_at_the_cycle_period() {
    let dir = temp_dir("field");
    // 25 periods of 52.08 and a little more.
    let scene = field_scene(r#"{"t_max": 1310}"#);
    let csv = dir.join("series.csv");
    let (code, stderr, report) = run_cli(&dir, &scene, Some(&csv));
    assert_eq!(code, 0, "{stderr}");
    let npy = dir.join("series.npy");
    let (code, stderr, report_npy) = run_cli(&dir, &scene, Some(&npy));
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(report["events"], report_npy["events"], "the format does not change the run");

    let period = num(&report["cycle"], "period");
    assert_eq!(report["cycle"]["status"], "periodic");
    let events = report["events"].as_array().unwrap();
    assert!(events.len() >= 20, "{} events", events.len());
    assert!(events[0]["recurrence"].is_null(), "the first event has no predecessor");
    // The transient from v = 0.5 is over after the first cycle (measured: the first
    // recurrence is 1.3e-6 off, the next ones 1e-14).
    for (k, e) in events.iter().enumerate().skip(2) {
        let r = num(e, "recurrence");
        assert!((r / period - 1.0).abs() <= 1e-8, "event {k}: recurrence {r} against {period}");
        for key in ["t_start", "t_peak", "t_end", "v_max", "slip", "duration", "stress_drop"] {
            assert!(num(e, key).is_finite(), "{key}");
        }
        assert!(num(e, "t_start") < num(e, "t_peak") && num(e, "t_peak") < num(e, "t_end"));
        assert!(num(e, "stress_drop") > 0.0 && num(e, "slip") > 0.0);
        let slip = num(&report["cycle"], "slip");
        assert!((num(e, "slip") / slip - 1.0).abs() < 1e-6, "slip per event {}", num(e, "slip"));
        let v_max = num(&report["cycle"], "v_max");
        assert!((num(e, "v_max") / v_max - 1.0).abs() < 1e-6);
    }
    // Absolute times: the peaks of the settled events lie a whole number of periods apart.
    let (first, last) = (&events[1], events.last().unwrap());
    let n = (events.len() - 2) as f64;
    let span = num(last, "t_peak") - num(first, "t_peak");
    assert!((span / (n * period) - 1.0).abs() < 1e-10, "{span} over {n} periods of {period}");

    // The files: the same rows, t from 0 to t_max strictly increasing, t,u,v,theta first.
    let ts = &report["time_series"];
    let a = read_csv(&csv);
    let b = series_file::read_npy(&npy).unwrap();
    assert_eq!(a.names, ["t", "u", "v", "theta", "ln_v", "slip", "stress"]);
    assert_eq!(a.names, b.names);
    assert_eq!(a.columns, b.columns, "CSV and .npy hold the same doubles");
    let t = a.column("t").unwrap();
    assert_eq!(t.len() as u64, ts["rows"].as_u64().unwrap());
    assert_eq!((t[0], *t.last().unwrap()), (0.0, 1310.0));
    assert!(t.windows(2).all(|w| w[1] > w[0]), "times increase strictly");
    // Rows are the integrator's steps (plus the start and t_max), less the merged ones.
    let steps = ts["steps"].as_u64().unwrap();
    assert_eq!(t.len() as u64 + ts["merged_rows"].as_u64().unwrap(), steps + 1);
    // The derived columns follow from the first four.
    let (v, ln_v, theta, stress) = (
        a.column("v").unwrap(),
        a.column("ln_v").unwrap(),
        a.column("theta").unwrap(),
        a.column("stress").unwrap(),
    );
    for i in (0..t.len()).step_by(97) {
        assert!((ln_v[i].exp() / v[i] - 1.0).abs() < 1e-14);
        assert_eq!(stress[i], ln_v[i] + theta[i], "log law: stress = ln v + θ");
    }
    // The peak rows hold v_max up to the sampling: the largest v written in the settled
    // cycles is within the dense output's reach of the catalogue's v_max.
    let v_written = v.iter().copied().fold(0.0, f64::max);
    let v_max = events.iter().map(|e| num(e, "v_max")).fold(0.0, f64::max);
    assert!(v_written <= v_max * (1.0 + 1e-9) && v_written > 0.5 * v_max, "{v_written} {v_max}");

    // numpy reads the binary file in one call, when it is installed.
    let numpy = Command::new("python3").args(["-c", "import numpy"]).output();
    if numpy.is_ok_and(|o| o.status.success()) {
        let script = format!(
            "import numpy as np; a = np.load('{}'); assert a.dtype.names[:4] == ('t','u','v','theta'); \
             assert a.shape == ({},); assert a['t'][0] == 0.0 and a['t'][-1] == 1310.0; print('ok')",
            npy.display(),
            t.len()
        );
        let out = Command::new("python3").args(["-c", &script]).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    } else {
        eprintln!("python3 with numpy not available: the .npy file was checked by npyz's reader");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn several_series_files_come_from_one_run() {
    let dir = temp_dir("several");
    let scene_path = dir.join("scene.json");
    std::fs::write(&scene_path, field_scene(r#"{"t_max": 120}"#)).unwrap();
    let (csv, npy) = (dir.join("a.csv"), dir.join("a.npy"));
    let run = Command::new(EXE)
        .args(["run", scene_path.to_str().unwrap(), "--json"])
        .args(["--series", csv.to_str().unwrap(), "--series", npy.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    let (a, b) = (read_csv(&csv), series_file::read_npy(&npy).unwrap());
    assert_eq!(a.names, b.names);
    assert!(a.columns[0].len() > 100, "{} rows", a.columns[0].len());
    assert_eq!(a.columns, b.columns, "the same rows in both files");
    // A file that cannot be created: exit 2 naming it, and no file left behind.
    let bad = dir.join("missing-dir").join("b.csv");
    let other = dir.join("c.npy");
    let run = Command::new(EXE)
        .args(["run", scene_path.to_str().unwrap(), "--json"])
        .args(["--series", other.to_str().unwrap(), "--series", bad.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("b.csv") && !other.exists(), "{stderr}");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(!left.iter().any(|n| n.to_string_lossy().contains("tmp")), "{left:?}");
}

#[test]
fn gamma_1e8_absolute_time_keeps_its_digits() {
    // The earthquake scene (γ = 1e8): the arrests take steps far below the spacing of t ~ 400,
    // so many steps merge into one row, yet the recurrences, differences of absolute times,
    // equal the tight cycle period.
    let text = r#"{"name": "eq", "model": {"gamma": 1e8, "xi": 0.8, "epsilon": 1.0},
        "initial": {"u": 1.0, "v": 0.45, "theta": 0.0},
        "solver": {"method": "radau5", "rtol": 1e-11},
        "analyses": [{"cycle": {"tolerance": 1e-9}}, {"time_series": {"t_max": 400}}]}"#;
    let scene = scene::parse(text, "test").unwrap();
    let (report, series) = run_collecting(&scene);
    let period = report.cycle.as_ref().unwrap().values.unwrap().main.period;
    let events = report.events.as_ref().unwrap();
    assert!(events.len() >= 6, "{}", events.len());
    for e in &events[2..] {
        let r = e.values.recurrence.unwrap();
        assert!((r / period - 1.0).abs() < 1e-9, "recurrence {r} against {period}");
    }
    let ts = report.time_series.as_ref().unwrap();
    assert!(ts.merged_rows > 0, "the arrest's steps fall below the spacing of t");
    let t = series.column("t").unwrap();
    assert_eq!(t.len() as u64, ts.rows);
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(*t.last().unwrap(), 400.0);
}

#[test]
fn every_and_points_choose_the_rows() {
    let base = |ts: &str| {
        let text = field_scene(ts).replace("1e-12", "1e-8");
        run_collecting(&scene::parse(&text, "test").unwrap())
    };
    let (all, s_all) = base(r#"{"t_max": 120}"#);
    let (every, s_every) = base(r#"{"t_max": 120, "every": 10}"#);
    let (points, s_points) = base(r#"{"t_max": 120, "points": 241}"#);
    let steps = all.time_series.as_ref().unwrap().steps;
    assert_eq!(every.time_series.as_ref().unwrap().steps, steps, "same integration");
    // Every 10th step, the start and t_max.
    assert_eq!(s_every.len() as u64, steps / 10 + 2 - every.time_series.unwrap().merged_rows);
    let t = s_points.column("t").unwrap();
    assert_eq!(t.len(), 241);
    for (i, t) in t.iter().enumerate() {
        assert_eq!(*t, 120.0 * i as f64 / 240.0);
    }
    // A t_max whose multiples round (0.1·3/3 > 0.1): the last row is still t_max itself.
    let (_, odd) = base(r#"{"t_max": 0.1, "points": 4}"#);
    assert_eq!(odd.column("t").unwrap(), [0.0, 0.1 / 3.0, 0.2 / 3.0, 0.1]);
    // Dense output agrees with the steps: u is smooth, so the uniform rows interpolate the
    // step rows closely.
    let (ta, ua) = (s_all.column("t").unwrap(), s_all.column("u").unwrap());
    let up = s_points.column("u").unwrap();
    for (i, t) in t.iter().enumerate().step_by(20) {
        let j = ta.partition_point(|x| x < t);
        if ta[j] == *t {
            assert!((ua[j] - up[i]).abs() < 1e-6);
        }
    }
    assert_eq!(all.events, points.events, "the rows do not change the events");
}

/// A time series alone names its integrator as the other analyses do: the method's family
/// (docs/reports.md: CVODE/ARKStep/…), not the method.
#[test]
fn a_time_series_alone_names_the_integrator_family() {
    for method in [scene::Method::CvodeBdf, scene::Method::Radau5] {
        let text = field_scene(r#"{"t_max": 10}"#)
            .replace("radau5", method.name())
            .replace(r#"{"cycle": {"tolerance": 1e-11}}, "#, "");
        let scene = scene::parse(&text, "test").unwrap();
        assert!(scene.analyses.cycle.is_none());
        let report = engine::run(&scene, engine::RunOptions::default()).unwrap();
        assert_eq!(report.solver.integrator, method.capabilities().family, "{method}");
    }
}

#[test]
fn event_threshold_selects_the_episodes_by_their_peak() {
    let run = |ts: &str| {
        let text = field_scene(ts).replace("1e-12", "1e-8");
        engine::run(&scene::parse(&text, "test").unwrap(), engine::RunOptions::default()).unwrap()
    };
    let default = run(r#"{"t_max": 300}"#);
    let high = run(r#"{"t_max": 300, "event_threshold": 1e4}"#);
    let above = run(r#"{"t_max": 300, "event_threshold": 1e9}"#);
    let (e2, e4) = (default.events.unwrap(), high.events.unwrap());
    assert_eq!(default.time_series.unwrap().event_threshold, 100.0, "the default");
    assert!(e2.len() >= 5, "{} events", e2.len());
    assert_eq!(e2, e4, "every slip peaks above v = 1e4: the same episodes, from v = 1 to v = 1");
    for e in &e2 {
        assert!(e.values.v_max > 1e4 && e.values.stress_drop > 0.0, "{e:?}");
        assert!(!e.started_before_run, "the run starts at v = 0.5");
    }
    // No slip peaks above v = 1e9 (v_max = 1.43e8): no event, none under way at the end.
    let above_series = above.time_series.unwrap();
    assert_eq!(above_series.event_threshold, 1e9);
    assert!(above.events.unwrap().is_empty() && !above_series.in_event_at_end);
}

#[test]
fn dimensional_input_adds_physical_columns_and_keys() {
    // The field scene in SI: σ = 10 MPa, a = 0.01, b = 0.015 (A = aσ = 1e5 Pa), k = 0.5 k_c =
    // 2.5e8 Pa/m; D_c/v0 = 1e5 s, so t_max = 3e7 s is 300 units.
    let text = r#"{"name": "si", "model": {"inertia": false, "state_law": "ageing",
        "dimensional": {"sigma": 1e7, "a": 0.01, "b": 0.015, "d_c": 1e-4, "v0": 1e-9,
                        "k": 2.5e8, "shear_modulus": 3e10, "shear_wave_speed": 3e3}},
        "initial": {"velocity": 5e-10, "state": 1e5},
        "solver": {"method": "radau5", "rtol": 1e-9},
        "analyses": [{"time_series": {"t_max": 3e7}}]}"#;
    let dir = temp_dir("si");
    let csv = dir.join("si.csv");
    let (code, stderr, report) = run_cli(&dir, text, Some(&csv));
    assert_eq!(code, 0, "{stderr}");
    let ts = &report["time_series"];
    assert_eq!(num(ts, "t_max"), 300.0);
    assert_eq!(num(ts, "t_max_physical"), 3e7);
    for key in [
        "sampling",
        "columns",
        "rows",
        "merged_rows",
        "steps",
        "rebases",
        "event_threshold",
        "event_threshold_physical",
        "event_count",
        "in_event_at_end",
        "final_state",
    ] {
        assert!(!ts[key].is_null(), "time_series.{key}");
    }
    let events = report["events"].as_array().unwrap();
    assert_eq!(events.len() as u64, ts["event_count"].as_u64().unwrap());
    assert!(events.len() >= 5);
    let scale = [
        ("t_start", 1e5),
        ("t_peak", 1e5),
        ("t_end", 1e5),
        ("v_max", 1e-9),
        ("slip", 1e-4),
        ("duration", 1e5),
        ("stress_drop", 1e5),
        ("recurrence", 1e5),
    ];
    for e in &events[1..] {
        for (key, s) in scale {
            let (d, p) = (num(e, key), num(&e["physical"], key));
            assert!((p / (d * s) - 1.0).abs() < 1e-14, "{key}: {p} against {d} × {s}");
        }
        assert!(num(&e["physical"], "stress_drop") > 0.0, "a positive stress drop in Pa");
    }
    let series = read_csv(&csv);
    assert_eq!(
        series.names,
        [
            "t",
            "u",
            "v",
            "theta",
            "ln_v",
            "slip",
            "stress",
            "t_phys",
            "v_phys",
            "slip_phys",
            "stress_phys"
        ]
    );
    let (t, tp) = (series.column("t").unwrap(), series.column("t_phys").unwrap());
    assert_eq!(*tp.last().unwrap(), 3e7);
    assert!(t.iter().zip(tp).all(|(t, tp)| (t * 1e5 - tp).abs() <= 1e-15 * tp.abs()));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_time_series_input_exits_2_naming_the_field() {
    let dir = temp_dir("bad");
    let cases = [
        (r#"{"t_max": -5}"#, "analyses[1].time_series.t_max"),
        (r#"{"t_max": 0}"#, "analyses[1].time_series.t_max"),
        (r#"{"t_max": 10, "every": 0}"#, "analyses[1].time_series.every"),
        (r#"{"t_max": 10, "points": 1}"#, "analyses[1].time_series.points"),
        (r#"{"t_max": 10, "points": 5, "every": 2}"#, "analyses[1].time_series.points"),
        (r#"{"t_max": 10, "event_threshold": 0}"#, "analyses[1].time_series.event_threshold"),
        (r#"{"t_max": 10, "event_threshold": -1}"#, "analyses[1].time_series.event_threshold"),
        (r#"{"t_max": 10, "max_steps": 0}"#, "analyses[1].time_series.max_steps"),
        (r#"{"t_max": 10, "tmax": 5}"#, "analyses[1].time_series"),
        (r#"{"every": 5}"#, "analyses[1].time_series"),
        (r#"[10]"#, "analyses[1].time_series"),
    ];
    for (options, field) in cases {
        let (code, stderr, report) = run_cli(&dir, &field_scene(options), None);
        assert_eq!(code, 2, "{options}: {stderr}");
        assert!(stderr.contains(&format!("{field}:")), "{options}: {stderr}");
        assert!(report.is_null(), "no report on bad input");
    }
    // "time_series" without options.
    let bare = field_scene("{}").replace(r#"{"time_series": {}}"#, r#""time_series""#);
    let (code, stderr, _) = run_cli(&dir, &bare, None);
    assert_eq!(code, 2);
    assert!(stderr.contains("analyses[1]") && stderr.contains("t_max"), "{stderr}");
    // --series without a time_series analysis, and to a path that cannot be created.
    let cycle_only = field_scene("{}").replace(r#", {"time_series": {}}"#, "");
    let (code, stderr, _) = run_cli(&dir, &cycle_only, Some(&dir.join("x.csv")));
    assert_eq!(code, 2);
    assert!(stderr.contains("--series") && stderr.contains("time_series"), "{stderr}");
    let nowhere = Path::new("/nonexistent-dir/series.npy");
    let (code, stderr, _) = run_cli(&dir, &field_scene(r#"{"t_max": 10}"#), Some(nowhere));
    assert_eq!(code, 2);
    assert!(stderr.contains("--series") && stderr.contains("cannot create"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn absolute_friction_level_adds_shear_stress_and_friction_columns() {
    // σ and μ0 at V_ref given: τ = σμ and μ follow the stress change column,
    // μ = μ_ref + a·stress with μ_ref = μ0 + (a − b) ln(v0/V_ref).
    let text = r#"{"name": "si", "model": {"inertia": false, "state_law": "ageing",
        "dimensional": {"sigma": 1e7, "a": 0.01, "b": 0.015, "d_c": 1e-4, "v0": 1e-9,
                        "k": 2.5e8, "shear_modulus": 3e10, "shear_wave_speed": 3e3,
                        "mu0": 0.6, "v_ref": 1e-6}},
        "initial": {"velocity": 5e-10, "state": 1e5},
        "solver": {"method": "radau5", "rtol": 1e-8},
        "analyses": [{"time_series": {"t_max": 2e7, "points": 101}}]}"#;
    let scene = scene::parse(text, "test").unwrap();
    let (report, series) = run_collecting(&scene);
    let columns = &report.time_series.as_ref().unwrap().columns;
    assert_eq!(columns[columns.len() - 2..], ["tau_phys", "mu"]);
    let mu_ref = 0.6 + (0.01 - 0.015) * (1e-9f64 / 1e-6).ln();
    let (stress, tau, mu) = (
        series.column("stress").unwrap(),
        series.column("tau_phys").unwrap(),
        series.column("mu").unwrap(),
    );
    assert_eq!(mu.len(), 101);
    for i in 0..101 {
        assert!((mu[i] - (mu_ref + 0.01 * stress[i])).abs() < 1e-14, "{} {}", mu[i], stress[i]);
        assert!((tau[i] / (1e7 * mu[i]) - 1.0).abs() < 1e-14);
    }
}

/// A run killed part way (Ctrl-C, or here SIGKILL) leaves the --series file as it was: the
/// rows go to a temporary file beside it, renamed to it only when the run succeeds; a finished
/// run leaves no temporary file.
#[test]
fn a_killed_run_leaves_no_half_written_series_file() {
    let dir = temp_dir("killed");
    let scene_path = dir.join("scene.json");
    let long = r#"{"name": "long", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.72},
        "solver": {"method": "cvode-bdf", "rtol": 1e-10, "atol": 1e-12},
        "analyses": [{"time_series": {"t_max": 1e6, "points": 1000000}}]}"#;
    std::fs::write(&scene_path, long).unwrap();
    let series = dir.join("series.csv");
    std::fs::write(&series, "old\n").unwrap();
    let mut child = Command::new(EXE)
        .args(["run", scene_path.to_str().unwrap(), "--series", series.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let staging = dir.join(format!(".series.csv.tmp-{}", child.id()));
    let started = std::time::Instant::now();
    while std::fs::metadata(&staging).map_or(true, |m| m.len() == 0) {
        assert!(started.elapsed().as_secs() < 60, "no rows streamed to {}", staging.display());
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    assert!(!child.wait().unwrap().success());
    assert_eq!(std::fs::read_to_string(&series).unwrap(), "old\n");
    std::fs::remove_file(&staging).unwrap();
    let (code, stderr, _) = run_cli(&dir, &field_scene(r#"{"t_max": 10}"#), Some(&series));
    assert_eq!(code, 0, "{stderr}");
    assert!(std::fs::read_to_string(&series).unwrap().starts_with("t,"));
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(left.iter().all(|n| !n.to_string_lossy().contains(".tmp-")), "{left:?}");
    std::fs::remove_dir_all(&dir).ok();
}
