//! `stickslip compare --against` with QDYN's own output, and the checks that refuse at once a
//! file that does not fit the scene (issue #37): QDYN's cut-off-law trajectory
//! (data/reference/qdyn_trajectory/) against the scene its qdyn.in maps to, the same file with
//! its time column altered, and the same samples in SI units or offset as a CSV; and
//! stickslip's own `--qdyn-output` (issue #45): tied times, output_vmax and output_ox, and the
//! reference's accuracy estimated in phase.

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const SCENE: &str = "data/qdyn/cut_a_slip.in";
const OUTPUT: &str = "data/reference/qdyn_trajectory/output_ot_0";

fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stickslip-compare-qdyn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn compare(scene: &str, file: &Path, extra: &[&str]) -> (Option<i32>, String, String) {
    common::compare_cli(Path::new(scene), file, extra)
}

/// A QDYN file (its text) with each row's time multiplied by `factor`.
fn stretched_text(text: &str, factor: f64) -> String {
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with('#') {
            out += line;
        } else {
            let mut cells: Vec<String> = line.split_whitespace().map(String::from).collect();
            cells[0] = format!("{:.14E}", cells[0].parse::<f64>().unwrap() * factor);
            out += &cells.join("  ");
        }
        out.push('\n');
    }
    out
}

/// QDYN's trajectory file with each row's time multiplied by `factor`.
fn stretched(factor: f64) -> String {
    stretched_text(&std::fs::read_to_string(OUTPUT).unwrap(), factor)
}

/// The QDYN samples in the scene's variables (u from the force balance).
fn dimensionless() -> stickslip::compare::Trajectory {
    let text = std::fs::read_to_string(SCENE).unwrap();
    let scene_text = stickslip::scene::qdyn_input::to_scene(&text, SCENE, "cut_a_slip").unwrap();
    let scene = stickslip::scene::parse(&scene_text, SCENE).unwrap();
    let output = std::fs::read_to_string(OUTPUT).unwrap();
    let q = stickslip::compare::qdyn::read_qdyn_output(&output).unwrap();
    stickslip::compare::qdyn::to_trajectory(&scene, &q).unwrap()
}

fn csv(rows: impl Iterator<Item = [f64; 4]>) -> String {
    let mut out = String::from("t,u,v,theta\n");
    for [t, u, v, theta] in rows {
        out += &format!("{t:e},{u:e},{v:e},{theta:e}\n");
    }
    out
}

#[test]
fn qdyns_cut_off_trajectory_agrees_at_1e_6_and_its_u_comes_from_the_force_balance() {
    let (code, out, err) = compare(SCENE, Path::new(OUTPUT), &["--tolerance", "1e-6", "--json"]);
    assert_eq!(code, Some(0), "{out}\n{err}");
    assert!(err.contains("the last row, repeats the row before it"), "{err}");
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(c["verdict"], "agrees");
    assert_eq!(c["events"], serde_json::json!([2, 2, 2]), "{c}");
    assert!(c["max_state_deviation"]["u"].is_null(), "u is not compared: {c}");
    // The deviations are QDYN's printed digits (E15.7), not a loose tolerance.
    let period = c["period_error"]["deviation"].as_f64().unwrap();
    assert!(period < 1e-8, "period {period:e}");
    for q in ["ln_v", "theta"] {
        let d = c["max_state_deviation"][q].as_f64().unwrap();
        assert!(d > 1e-8 && d < 1e-6, "{q} {d:e}");
    }
}

#[test]
fn time_stretched_by_1e_4_disagrees_and_names_the_period() {
    // Stretched by a relative 1e-4: a period error of 1e-4.
    let file = temp_file("stretched_relative", &stretched(1.0 + 1e-4));
    let (code, out, err) = compare(SCENE, &file, &["--tolerance", "1e-6"]);
    assert_eq!(code, Some(3), "{out}\n{err}");
    assert!(out.contains("period error: the period differs by 1.00e-4"), "{out}");
    // Scaled by 1e-4: the file's events recur 1e4 times too fast.
    let file = temp_file("stretched_scaled", &stretched(1e-4));
    let (code, out, err) = compare(SCENE, &file, &["--tolerance", "1e-6"]);
    assert_eq!(code, Some(3), "{out}\n{err}");
    assert!(out.contains("2 complete events against the reference's 0"), "{out}");
    let line = out.lines().find(|l| l.contains("period: your events recur every")).unwrap();
    assert!(line.contains("times its period (the t column in other units?)"), "{line}");
    let ratio: f64 = line.split(": ").nth(3).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((ratio / 1e-4 - 1.0).abs() < 0.05, "{line}");
}

/// Runs `compare` with its data segment limited to 1 GiB and returns (code, stderr, seconds).
fn bounded(scene: &str, file: &Path) -> (Option<i32>, String, f64) {
    let start = Instant::now();
    let out = std::process::Command::new("prlimit")
        .args(["--data=1073741824", "--", env!("CARGO_BIN_EXE_stickslip"), "compare", scene])
        .args(["--against", file.to_str().unwrap(), "--tolerance", "1e-6"])
        .output()
        .expect("prlimit (util-linux)");
    let seconds = start.elapsed().as_secs_f64();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned(), seconds)
}

#[test]
fn an_si_csv_against_a_dimensionless_scene_exits_2_at_once_in_bounded_memory() {
    // QDYN's samples as a CSV in SI units: t in s, u the slip in m, V in m/s, Θ in s.
    let text = std::fs::read_to_string(OUTPUT).unwrap();
    let q = stickslip::compare::qdyn::read_qdyn_output(&text).unwrap();
    let si = csv((0..q.t.len()).map(|i| [q.t[i], 1e-9 * q.t[i], q.v[i], q.state[i]]));
    let file = temp_file("si.csv", &si);
    let limit = Duration::from_secs(10).as_secs_f64();
    // Quasi-dynamic: the first sample is off the force balance.
    let (code, err, seconds) = bounded("data/scenes/quasi-dynamic.json", &file);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("line 2: the first sample breaks the scene's force balance"), "{err}");
    assert!(err.contains("SI values against a dimensionless scene?"), "{err}");
    assert!(seconds < limit, "{seconds} s");
    // Inertial: the imbalance would drive ln v beyond double precision.
    let (code, err, seconds) = bounded("data/scenes/fig1.json", &file);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("the first sample's force imbalance"), "{err}");
    assert!(seconds < limit, "{seconds} s");
    // The scene's own variables with t in seconds: the span holds thousands of the scene's
    // cycles, found while the reference runs.
    let d = dimensionless();
    let seconds_file = csv((0..d.t.len()).map(|i| [d.t[i] * 1e5, d.y[i][0], d.y[i][1], d.y[i][2]]));
    let file = temp_file("seconds.csv", &seconds_file);
    let (code, err, seconds) = bounded(SCENE, &file);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("the scene's model has more than 30 events"), "{err}");
    assert!(err.contains("the t column is likely in other units"), "{err}");
    assert!(seconds < limit, "{seconds} s");
}

#[test]
fn an_offset_u_and_a_qdyn_file_against_the_wrong_scene_are_refused_naming_the_cause() {
    // u offset to start at 0 (slip − t from QDYN's t = 0).
    let d = dimensionless();
    let u0 = d.y[0][0];
    let offset = csv((0..d.t.len()).map(|i| [d.t[i], d.y[i][0] - u0, d.y[i][1], d.y[i][2]]));
    let (code, _, err) = compare(SCENE, &temp_file("offset.csv", &offset), &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("column u = 0, where the quasi-dynamic balance"), "{err}");
    assert!(err.contains("u is likely offset"), "{err}");
    // QDYN's SI file against a dimensionless scene, and against other friction parameters.
    let (code, _, err) = compare("data/scenes/quasi-dynamic.json", Path::new(OUTPUT), &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("a QDYN output file is in SI units"), "{err}");
    let (code, _, err) = compare("data/qdyn/cut_b_slip.in", Path::new(OUTPUT), &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("line 5: tau = 5932128 Pa, but the scene's friction"), "{err}");
    assert!(err.contains("other friction parameters than the scene"), "{err}");
}

/// `stickslip run data/qdyn/CASE.in --qdyn-output DIR` (40 periods, 1–2 s): its output_ot_0
/// and output_vmax cut to their first `lines` lines, and output_ox.
fn own_qdyn_output(case: &str, lines: usize) -> (PathBuf, PathBuf, PathBuf) {
    let dir =
        std::env::temp_dir().join(format!("stickslip-compare-own-{case}-{}", std::process::id()));
    let scene = format!("data/qdyn/{case}.in");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args(["run", &scene, "--qdyn-output", dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let head = |name: &str| {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        let cut: String = text.lines().take(lines).map(|l| format!("{l}\n")).collect();
        temp_file(&format!("own_{case}_{name}"), &cut)
    };
    (head("output_ot_0"), head("output_vmax"), dir.join("output_ox"))
}

/// The reference's own accuracy estimated in phase: the first events of two files where it was
/// estimated at equal times from peaks located on the reference's own steps, and so measured
/// those peaks' error times a steep slope (no verdict at 1e-6: cut_a_ageing 2.6e-7 in ln v
/// 0.32 after its first peak, classic_ageing 1.5e-6 in ln v_max at its second event).
#[test]
fn the_references_accuracy_is_estimated_in_phase_so_own_output_gets_a_verdict_at_1e_6() {
    for (case, lines) in [("cut_a_ageing", 15_000), ("classic_ageing", 12_000)] {
        let (ot, _, _) = own_qdyn_output(case, lines);
        let scene = format!("data/qdyn/{case}.in");
        let (code, out, err) = compare(&scene, &ot, &["--tolerance", "1e-6", "--json"]);
        assert_eq!(code, Some(0), "{case}: {out}\n{err}");
        let c: serde_json::Value = serde_json::from_str(&out).unwrap();
        for (q, a) in c["reference"]["accuracy"].as_object().unwrap() {
            assert!(a.as_f64().unwrap() < 1e-9, "{case}: {q}: {a}");
        }
    }
}

#[test]
fn stickslips_own_qdyn_output_with_tied_times_agrees_at_1e_6_and_its_stretch_disagrees() {
    let scene = "data/qdyn/cut_b_slip.in";
    // Cut to 25 events; its times tie from line 88 677 on (t ~ 1.02e8 s, 14 printed digits).
    let (ot, vmax, ox) = own_qdyn_output("cut_b_slip", 100_000);
    let (code, out, err) = compare(scene, &ot, &["--tolerance", "1e-6", "--json"]);
    assert_eq!(code, Some(0), "{out}\n{err}");
    // The tied rows are merged, said once.
    let notes: Vec<&str> = err.lines().filter(|l| l.contains("rows left out")).collect();
    assert_eq!(notes.len(), 1, "{err}");
    assert!(notes[0].contains("10 rows left out: 10 runs of rows print the same time"), "{err}");
    assert!(notes[0].contains("the first at line 88677"), "{err}");
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(c["events"], serde_json::json!([25, 25, 25]), "{c}");
    // The reference's own accuracy, estimated in phase, is far below the tolerance.
    for (q, a) in c["reference"]["accuracy"].as_object().unwrap() {
        assert!(a.as_f64().unwrap() < 1e-9, "{q}: {a}");
    }
    // ln v_max within V's printed 7 digits (5e-8 … 5e-7 relative).
    let worst = c["worst_per_quantity"].as_array().unwrap();
    let ln_v_max = worst.iter().find(|q| q["quantity"] == "ln_v_max").unwrap();
    assert!(ln_v_max["deviation"].as_f64().unwrap() < 5e-7, "{ln_v_max}");
    // output_vmax: the same rows, named for what it is.
    let (code, out, err) = compare(scene, &vmax, &["--tolerance", "1e-6"]);
    assert_eq!(code, Some(0), "{out}\n{err}");
    assert!(err.contains("is QDYN's output_vmax (the state at the velocity maximum)"), "{err}");
    // output_ox: named, and the file to give instead.
    let (code, _, err) = compare(scene, &ox, &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("this is QDYN's output_ox: snapshots of the whole fault"), "{err}");
    assert!(err.contains("give output_ot_0 from the same run"), "{err}");
    // Its time stretched by a relative 1e-4: a period error.
    let text = std::fs::read_to_string(&ot).unwrap();
    let file = temp_file("own_stretched", &stretched_text(&text, 1.0 + 1e-4));
    let (code, out, err) = compare(scene, &file, &["--tolerance", "1e-6"]);
    assert_eq!(code, Some(3), "{out}\n{err}");
    assert!(out.contains("period error: the period differs by 1.00e-4"), "{out}");
}
