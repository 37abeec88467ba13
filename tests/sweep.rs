//! Sweeps: a killed and resumed sweep yields exactly the rows of an uninterrupted one, and
//! shards merge into the full sweep.

use std::path::{Path, PathBuf};
use std::process::Command;

const EXE: &str = env!("CARGO_BIN_EXE_stickslip");

/// A directory of this test's own (tests run in parallel in one process).
fn dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("stickslip-sweep-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scene(d: &Path) -> PathBuf {
    let path = d.join("scene.json");
    std::fs::write(
        &path,
        r#"{"name": "sweep", "model": {"gamma": 100, "xi": 0.7, "epsilon": 0.8},
            "solver": {"rtol": 1e-9, "atol": 1e-11}, "analyses": ["hopf", "cycle"]}"#,
    )
    .unwrap();
    path
}

fn sweep(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(EXE)
        .args([
            "sweep",
            scene.to_str().unwrap(),
            "--param",
            "epsilon=0.72:1.2:7",
            "--param",
            "gamma=1e1:1e4:3:log",
        ])
        .args(["--out", out.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap()
}

/// The rows of a sweep file, sorted by index (as `merge` writes them).
fn sorted_rows(path: &Path) -> Vec<String> {
    let merged = path.with_extension("merged");
    let out = Command::new(EXE)
        .args(["merge", "--out", merged.to_str().unwrap(), "--total", "21", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::read_to_string(&merged).unwrap().lines().map(String::from).collect()
}

#[test]
fn a_killed_and_resumed_sweep_yields_the_uninterrupted_rows() {
    let d = dir("resume");
    let s = scene(&d);
    let full = d.join("full.jsonl");
    assert!(sweep(&s, &full, &["--threads", "2"]).status.success());
    let reference = sorted_rows(&full);
    assert_eq!(reference.len(), 21);

    // A kill leaves some finished rows and possibly half of a line: simulate exactly that.
    let text = std::fs::read_to_string(&full).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let killed = d.join("killed.jsonl");
    let partial = &lines[8][..lines[8].len() / 2];
    std::fs::write(&killed, lines[..8].join("\n") + "\n" + partial).unwrap();
    let resumed = sweep(&s, &killed, &["--resume", "--threads", "1"]);
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    assert!(
        String::from_utf8_lossy(&resumed.stdout).contains("13 points run"),
        "{}",
        String::from_utf8_lossy(&resumed.stdout)
    );
    assert_eq!(sorted_rows(&killed), reference, "nothing lost, nothing repeated, same rows");

    // A real kill of a running sweep, then resume.
    let real = d.join("real.jsonl");
    let mut child = Command::new(EXE)
        .args([
            "sweep",
            s.to_str().unwrap(),
            "--param",
            "epsilon=0.72:1.2:7",
            "--param",
            "gamma=1e1:1e4:3:log",
        ])
        .args(["--out", real.to_str().unwrap(), "--threads", "1"])
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(60));
    let _ = child.kill();
    let _ = child.wait();
    assert!(sweep(&s, &real, &["--resume"]).status.success());
    assert_eq!(sorted_rows(&real), reference);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn shards_merge_into_the_full_sweep() {
    let d = dir("shards");
    let s = scene(&d);
    let full = d.join("full.jsonl");
    assert!(sweep(&s, &full, &[]).status.success());
    let parts: Vec<PathBuf> = (1..=3).map(|k| d.join(format!("part{k}.jsonl"))).collect();
    for (k, part) in parts.iter().enumerate() {
        assert!(sweep(&s, part, &["--shard", &format!("{}/3", k + 1)]).status.success());
    }
    let merged = d.join("merged.jsonl");
    let mut args = vec![
        "merge".to_string(),
        "--out".into(),
        merged.display().to_string(),
        "--total".into(),
        "21".into(),
    ];
    args.extend(parts.iter().map(|p| p.display().to_string()));
    assert!(Command::new(EXE).args(&args).output().unwrap().status.success());
    let merged_rows: Vec<String> =
        std::fs::read_to_string(&merged).unwrap().lines().map(String::from).collect();
    assert_eq!(merged_rows, sorted_rows(&full));
    // A missing shard is reported.
    let out = Command::new(EXE)
        .args([
            "merge",
            "--out",
            d.join("m2").to_str().unwrap(),
            "--total",
            "21",
            parts[0].to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing"));
    std::fs::remove_dir_all(&d).ok();
}

/// `merge` writes each row exactly as the sweep did: 12.589254117941675 (γ at index 1 of
/// `gamma=1e1:1e12:111:log`) is one of the numbers that serde_json's default parser reads
/// one ulp off, so parsing and printing a row again would change it (found by tools/slurm.sh
/// comparing merged Slurm shards with an unsharded sweep).
#[test]
fn merge_keeps_each_row_as_written() {
    let d = dir("verbatim");
    let rows = [
        r#"{"index":0,"params":{"gamma":10.0},"report":{"cycle":{"period":12.48191460503766}},"error":null}"#,
        r#"{"index":1,"params":{"gamma":12.589254117941675},"report":null,"error":"e"}"#,
    ];
    std::fs::write(d.join("b.jsonl"), format!("{}\n", rows[1])).unwrap();
    std::fs::write(d.join("a.jsonl"), format!("{}\n{}\n", rows[1], rows[0])).unwrap();
    let merged = d.join("merged.jsonl");
    let out = Command::new(EXE)
        .args(["merge", "--out", merged.to_str().unwrap(), "--total", "2"])
        .args([d.join("b.jsonl"), d.join("a.jsonl")])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(&merged).unwrap(), format!("{}\n{}\n", rows[0], rows[1]));
    std::fs::remove_dir_all(&d).ok();
}

/// A sweep over the radiation damping η under the ageing law: each row's Hopf threshold is
/// ε_c(η) = η + ξγ²(1 + η)/(ξ + γ²(1 + η)) (docs/state-laws.md, f = ln v, κ = 1).
#[test]
fn a_sweep_over_the_radiation_damping_sets_eta() {
    let d = dir("eta");
    let s = d.join("scene.json");
    std::fs::write(&s, r#"{"name": "eta", "model": {"gamma": 100, "xi": 0.7, "epsilon": 1.2, "state_law": "ageing"}, "analyses": ["hopf"]}"#).unwrap();
    let out = d.join("eta.jsonl");
    let r = Command::new(EXE)
        .args([
            "sweep",
            s.to_str().unwrap(),
            "--param",
            "radiation_damping=0:0.2:3",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let rows: Vec<serde_json::Value> = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 3);
    let (gamma, xi) = (100.0f64, 0.7f64);
    let g = gamma * gamma;
    for row in &rows {
        let text = row.to_string();
        let eta = row["params"]["radiation_damping"].as_f64().unwrap_or_else(|| panic!("{text}"));
        let eps_c = row["report"]["hopf"]["epsilon_c"].as_f64().unwrap_or_else(|| panic!("{text}"));
        let expected = eta + xi * g * (1.0 + eta) / (xi + g * (1.0 + eta));
        assert!((eps_c - expected).abs() < 1e-12, "η = {eta}: ε_c {eps_c} vs {expected}");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_sweep_arguments_exit_2() {
    let d = dir("bad");
    let s = scene(&d);
    let out = d.join("o.jsonl");
    for args in [
        ["--param", "delta=1:2:3"],
        ["--param", "epsilon=1:2"],
        ["--param", "gamma=0:1e3:3:log"],
        ["--shard", "4/3"],
    ] {
        let mut all = vec!["sweep", s.to_str().unwrap(), "--out", out.to_str().unwrap()];
        if args[0] == "--shard" {
            all.extend(["--param", "epsilon=1:2:2"]);
        }
        all.extend(args);
        let r = Command::new(EXE).args(&all).output().unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(&format!("{} \"{}\"", args[0], args[1])), "{args:?}: {stderr}");
    }
}

/// clap parses `--methods` (compare, stress) with the one parser of method names: an unknown
/// name exits 2 before anything runs, and the message lists the valid ones.
#[test]
fn an_unknown_method_exits_2_naming_the_valid_ones() {
    let d = dir("methods");
    let s = scene(&d);
    for args in [
        vec!["compare", s.to_str().unwrap(), "--methods", "radau5,bogus"],
        vec!["stress", "--quick", "--methods", "bogus"],
    ] {
        let r = Command::new(EXE).args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("--methods"), "{args:?}: {stderr}");
        assert!(stderr.contains("\"bogus\" is not a method; use one of cvode-bdf"), "{stderr}");
    }
    std::fs::remove_dir_all(&d).ok();
}
