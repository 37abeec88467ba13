//! The peers, each a separate program that prints one JSON line per run (see
//! benches/peers/src/main.rs, benches/scipy_peer.py and the "wp" mode of
//! benches/c/earthquake_cvode.c): building them, running them with a time limit, and reading
//! their lines into [`Row`]s.

use crate::protocol::{self, Counts, Measured, Start, CYCLES, EPSILON, XI};
use crate::Row;
use std::path::{Path, PathBuf};
use std::process::Command;
use stickslip::analysis::hopf;

/// The repository root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A peer program and how to call it.
#[derive(Debug, Clone)]
pub enum Program {
    /// The plain-C CVODE replica of the engine (one setting: the engine's).
    C(PathBuf),
    /// benches/peers: a method of diffsol or differential-equations.
    Rust(PathBuf, &'static str),
    /// benches/scipy_peer.py: LSODA, Radau or BDF.
    Scipy(&'static str),
}

impl Program {
    /// The method name in the results.
    pub fn name(&self) -> String {
        match self {
            Program::C(_) => "c-cvode-bdf".into(),
            Program::Rust(_, m) => m.to_string(),
            Program::Scipy(m) => format!("scipy-{}", m.to_lowercase()),
        }
    }

    /// Whether the program has a tuned setting to try after a failure with its defaults.
    fn tunable(&self) -> bool {
        !matches!(self, Program::C(_))
    }
}

/// The Rust peers (benches/peers), in the order of the tables.
pub const RUST_PEERS: [&str; 5] =
    ["de-radau5", "de-bdf", "diffsol-bdf", "diffsol-esdirk34", "diffsol-tr-bdf2"];
/// The scipy methods.
pub const SCIPY_PEERS: [&str; 3] = ["LSODA", "Radau", "BDF"];

/// Builds benches/peers (its own workspace, `--locked`) into target/peers; returns the binary.
pub fn build_rust_peers() -> Result<PathBuf, String> {
    let target = root().join("target/peers");
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["build", "--release", "--locked", "--manifest-path"])
        .arg(root().join("benches/peers/Cargo.toml"))
        .arg("--target-dir")
        .arg(&target)
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("building benches/peers failed ({status})"));
    }
    Ok(target.join("release/stickslip-peers"))
}

/// `python3 benches/scipy_peer.py --version` (installs scipy into target/scipy-venv if needed):
/// the python, scipy and numpy versions.
pub fn scipy_versions() -> Result<serde_json::Value, String> {
    let out = Command::new("python3")
        .arg(root().join("benches/scipy_peer.py"))
        .arg("--version")
        .output()
        .map_err(|e| format!("cannot run python3: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "scipy_peer.py --version failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    serde_json::from_slice(&out.stdout).map_err(|e| format!("scipy_peer.py --version: {e}"))
}

/// Runs `cmd` under `timeout LIMIT` and returns its JSON line, or an error line's reason.
fn json_line(cmd: Command, limit_s: u64) -> Result<serde_json::Value, String> {
    let program = format!("{cmd:?}");
    let mut timed = Command::new("timeout");
    timed.arg(limit_s.to_string()).arg(cmd.get_program()).args(cmd.get_args());
    if let Some(dir) = cmd.get_current_dir() {
        timed.current_dir(dir);
    }
    let out = timed.output().map_err(|e| format!("cannot run {program}: {e}"))?;
    if out.status.code() == Some(124) {
        return Err(format!("no result within the time limit of {limit_s} s (killed)"));
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().rev().find(|l| l.starts_with('{')).ok_or_else(|| {
        format!(
            "no JSON line ({}); stderr: {}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .rev()
                .take(3)
                .collect::<Vec<_>>()
                .join(" | ")
        )
    })?;
    serde_json::from_str(line).map_err(|e| format!("bad JSON line {line:?}: {e}"))
}

/// Reads a peer's JSON line into a row.
fn row_from(
    program: &Program,
    setting: &str,
    gamma: f64,
    rtol: f64,
    line: Result<serde_json::Value, String>,
) -> Row {
    let mut row = Row::new(&program.name(), "peer", setting, gamma, rtol);
    match line {
        Err(e) => row.error = Some(e),
        Ok(v) => {
            row.tuning = v["tuning"].as_str().map(String::from);
            if v["ok"].as_bool() == Some(true) {
                let num = |k: &str| v[k].as_f64();
                let count = |k: &str| v[k].as_u64();
                match (num("period"), num("t0"), num("ln_v_max"), num("time_per_cycle_s")) {
                    (Some(period), Some(t0), Some(ln_v_max), Some(t)) => {
                        row.ok = true;
                        row.measured = Some(Measured { period, t0, ln_v_max });
                        row.time_per_cycle_s = Some(t);
                        row.runs = count("runs");
                        row.counts = Counts {
                            steps: count("steps"),
                            rhs: count("rhs"),
                            jac: count("jac"),
                            lu: count("lu"),
                            rejected: count("rejected"),
                        };
                    }
                    _ => row.error = Some(format!("incomplete result line {v}")),
                }
            } else {
                row.error =
                    Some(v["error"].as_str().unwrap_or("failed without a reason").to_string());
            }
        }
    }
    row
}

/// The command line of one run of `program` (`setting`: "default" or "tuned").
fn command(
    program: &Program,
    setting: &str,
    gamma: f64,
    rtol: f64,
    start: &Start,
    runs: usize,
    budget_s: f64,
) -> Command {
    let atol = protocol::atol(rtol);
    let [u0, w0, th0] = start.y0;
    let common = |cmd: &mut Command| {
        cmd.args([u0, w0, th0].map(|x| x.to_string()));
    };
    match program {
        Program::C(binary) => {
            let max_step = hopf::analyse(&protocol::drr(gamma)).period_c / 8.0;
            let mut cmd = Command::new(binary);
            cmd.arg("wp").args([gamma, rtol, atol, max_step].map(|x| format!("{x:e}")));
            common(&mut cmd);
            cmd.args([CYCLES.to_string(), runs.to_string(), budget_s.to_string()]);
            cmd
        }
        Program::Rust(binary, method) => {
            let mut cmd = Command::new(binary);
            cmd.args([method, &setting])
                .args([gamma, XI, EPSILON, rtol, atol].map(|x| format!("{x:e}")));
            common(&mut cmd);
            cmd.args([
                start.t_end().to_string(),
                CYCLES.to_string(),
                runs.to_string(),
                budget_s.to_string(),
            ]);
            cmd
        }
        Program::Scipy(method) => {
            let mut cmd = Command::new("python3");
            cmd.arg(root().join("benches/scipy_peer.py"))
                .args([method, &setting])
                .args([gamma, XI, EPSILON, rtol, atol].map(|x| format!("{x:e}")));
            common(&mut cmd);
            cmd.args([
                start.t_end().to_string(),
                CYCLES.to_string(),
                runs.to_string(),
                budget_s.to_string(),
            ]);
            cmd
        }
    }
}

/// The plain-C program's minimum time per cycle over `runs` timed runs (after its warm-up) of
/// one grid cell, with no time budget (the wrapper-against-C measurement).
pub fn c_min_time(
    binary: &Path,
    gamma: f64,
    rtol: f64,
    start: &Start,
    runs: usize,
    limit_s: u64,
) -> Result<f64, String> {
    let program = Program::C(binary.to_path_buf());
    let line = json_line(command(&program, "default", gamma, rtol, start, runs, 1e9), limit_s)?;
    line["time_per_cycle_s"]
        .as_f64()
        .ok_or_else(|| line["error"].as_str().unwrap_or("no time").to_string())
}

/// One grid cell of a peer: its defaults, and if they fail, its tuned setting (both rows are
/// kept). The C program has only the engine's settings.
pub fn run(
    program: &Program,
    gamma: f64,
    rtol: f64,
    start: &Start,
    runs: usize,
    budget_s: f64,
    limit_s: u64,
) -> Vec<Row> {
    let settings: &[&str] =
        if program.tunable() { &["default", "tuned"] } else { &["engine settings"] };
    let mut rows = Vec::new();
    for &setting in settings {
        let arg = if setting == "tuned" { "tuned" } else { "default" };
        let line = json_line(command(program, arg, gamma, rtol, start, runs, budget_s), limit_s);
        let row = row_from(program, setting, gamma, rtol, line);
        let ok = row.ok;
        rows.push(row);
        if ok {
            break;
        }
    }
    rows
}
