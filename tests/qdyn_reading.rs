//! qdyn.in read as QDYN reads it (issue #45 Deliver 3): blank lines skipped, NTOUT_OT and
//! NTOUT thinning `--qdyn-output` as QDYN thins its files, and a start on the fixed point
//! refused in the file's terms. On copies of data/qdyn/classic_ageing.in (pyqdyn-written).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use stickslip::scene::qdyn_input::{self, QdynOutputIntervals};

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

fn classic_ageing() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/qdyn/classic_ageing.in");
    std::fs::read_to_string(path).unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stickslip-qdynin-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stickslip(args: &[&str]) -> Output {
    Command::new(EXE).args(args).output().unwrap()
}

/// The data lines (not `#` headers) of a QDYN output file.
fn data_lines(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().filter(|l| !l.starts_with('#')).map(String::from).collect()
}

#[test]
fn blank_lines_are_skipped_as_qdyn_skips_them() {
    let text = classic_ageing();
    let lines: Vec<&str> = text.lines().collect();
    // A blank line before line 6 (the case), blanks of spaces and tabs, and one at
    // the end: the same scene.
    let spaced =
        [&lines[..5], &[""], &lines[5..9], &["   \t "], &lines[9..], &[""]].concat().join("\n");
    let plain = qdyn_input::read(&text, "a.in", "a").unwrap();
    let blank = qdyn_input::read(&spaced, "a.in", "a").unwrap();
    assert_eq!(plain, blank);
    // A missing value is still named, on its own line number in the file.
    let short = spaced.replace("0     i_sigma_law", "     i_sigma_law");
    let e = qdyn_input::to_scene(&short, "a.in", "a").unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (7, "SIGMA_CPL"), "{e}");
}

#[test]
fn ntout_ot_and_ntout_thin_the_qdyn_files() {
    let text = classic_ageing()
        .replace("1 1000000 1 1 1 1 1 0 0 ", "10 100 1 1 1 1 1 0 0 ")
        .replace(" 208334765.05483 ", " 2.1e7 ");
    let input = qdyn_input::read(&text, "t.in", "t").unwrap();
    assert_eq!(input.output, QdynOutputIntervals { time_series: 10, snapshots: 100 });
    let dir = temp_dir("thin");
    let file = dir.join("thin.in");
    std::fs::write(&file, &text).unwrap();
    let out_dir = dir.join("out");
    let out = stickslip(&[
        "run",
        file.to_str().unwrap(),
        "--json",
        "--qdyn-output",
        out_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stderr.is_empty(), "no size notice for a small run");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = report["time_series"]["rows"].as_u64().unwrap();
    assert!(rows > 1000, "{rows}");
    // QDYN writes steps 0, n, 2n, … and the last (here row k is step k).
    let thinned = |n: u64| (rows - 1) / n + 1 + u64::from(!(rows - 1).is_multiple_of(n));
    let ot = data_lines(&out_dir.join("output_ot_0"));
    assert_eq!(ot.len() as u64, thinned(10));
    assert_eq!(data_lines(&out_dir.join("output_vmax")).len() as u64, thinned(10));
    assert_eq!(data_lines(&out_dir.join("output_ox")).len() as u64, thinned(100));
    // The last row is the state at TMAX.
    let t_last: f64 = ot.last().unwrap()[..24].trim().parse().unwrap();
    assert_eq!(t_last, 2.1e7);
    // NTOUT_OT = 0 is no interval (QDYN would divide by it).
    let zero = text.replace("10 100 1 1 1 1 1 0 0 ", "0 100 1 1 1 1 1 0 0 ");
    let e = qdyn_input::to_scene(&zero, "t.in", "t").unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (8, "NTOUT_OT"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_start_on_the_fixed_point_is_said_in_the_files_terms() {
    // V_0 = V_PL = 1e-9 m/s, TH_0 = DC/V_PL = 1e5 s: the right-hand side is zero there.
    let text = classic_ageing().replace("10000000 5e-10 100000 ", "10000000 1e-09 100000 ");
    let dir = temp_dir("rest");
    let file = dir.join("rest.in");
    std::fs::write(&file, &text).unwrap();
    let out = stickslip(&["run", file.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    for says in [
        "line 16: V_0, TH_0",
        "starts on the fixed point",
        "V_0 = 1e-9 m/s is V_PL",
        "TH_0 = 1e5 s",
        "nothing happens",
        "Perturb the start, e.g. V_0 = 5e-10 m/s",
    ] {
        assert!(stderr.contains(says), "{says}: {stderr}");
    }
    assert!(!stderr.contains("max_time"), "no JSON advice: {stderr}");
    // Off the fixed point by one part in 1e6 it runs (and has events).
    let near = text.replace("10000000 1e-09 100000 ", "10000000 1.000001e-09 100000 ");
    assert!(qdyn_input::to_scene(&near, "near.in", "near").is_ok());
    // Under periodic loading the same start is not at rest.
    let forced = text.replace("31536000 0 ", "31536000 40000 ");
    assert!(qdyn_input::to_scene(&forced, "forced.in", "forced").is_ok());
    std::fs::remove_dir_all(&dir).ok();
}
