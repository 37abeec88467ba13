//! Work–precision runner (issues #6 and #7): run time per settled limit cycle against the
//! relative error in period, t0 and ln v_max, for every stickslip method and for the peers a
//! user would otherwise pick — the plain-C CVODE replica of the engine, diffsol (BDF,
//! ESDIRK34, TR-BDF2), differential-equations (Radau5, BDF) and scipy's solve_ivp (LSODA,
//! Radau, BDF) — on the same problem: the DRR spring-slider at ξ = 0.8, ε = 1,
//! γ ∈ {1e1, 1e3, 1e5, 1e8}, rtol 1e-3 … 1e-12 (atol = rtol·1e-2 on u, ln v and θ).
//!
//! A tool, not a benchmark: it rewrites committed documentation, as tools/reference_table
//! rewrites data/reference/. Run (about an hour on 2 shared cores; writes
//! data/work-precision/results.json, the SVG diagrams there and docs/work-precision.md, keeping
//! that file's hand-written notes):
//!
//!     cargo run --release --example work_precision
//!     cargo run --release --example work_precision -- --quick           # 2 γ × 3 tolerances
//!     cargo run --release --example work_precision -- --gammas 1e8 --rtols 1e-6,1e-8 --only radau5,scipy-lsoda --no-write
//!
//! Options: `--gammas LIST`, `--rtols LIST`, `--only METHODS` (names as in the tables),
//! `--runs N` (timed runs per cell, default 5), `--budget S` (seconds of timed runs per cell,
//! default 2), `--limit S` (time limit of one peer process, default 900), `--no-peers`,
//! `--no-write` (print, write nothing), `--reanalyse` (tables and diagrams again from the
//! committed results.json, no measurement), `--wrapper` (the same after measuring the wrapper
//! against plain C anew, into data/work-precision/wrapper.json), `--smoke` (one small cell of
//! our side, nothing written: a check that the runner works).
//!
//! What is measured (protocol.rs): every method starts from the same state on the settled
//! cycle, 2 % of a period before an upward crossing of v = 1, and integrates through 3 cycles;
//! the period, t0 and ln v_max are the means over those cycles, the time is the minimum over
//! the timed runs of one whole run (solver creation included) divided by 3. The reference at
//! each γ is radau5 at rtol 1e-14 and rodas5p at rtol 1e-13 from the same start (their mean;
//! their difference is the reference's accuracy, reported). Failures are rows with their
//! reason, never dropped.

#[path = "../../benches/common/mod.rs"]
#[allow(dead_code)]
mod common;
mod peers;
mod protocol;
mod report;

use protocol::{Counts, Measured, Start};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use stickslip::scene::Method;

/// The relative errors of a run against the reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Errors {
    /// |period − reference| / reference.
    pub period: f64,
    /// |t0 − reference| / reference.
    pub t0: f64,
    /// |ln v_max − reference| / reference.
    pub ln_v_max: f64,
}

/// One grid cell of one method (and setting).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Row {
    /// Method name as in the tables (e.g. "radau5", "c-cvode-bdf", "scipy-lsoda").
    pub method: String,
    /// "stickslip" or "peer".
    pub side: String,
    /// "library defaults" (ours), "engine settings" (plain C), "default" or "tuned" (peers).
    pub setting: String,
    /// What the tuned setting changes.
    pub tuning: Option<String>,
    /// γ.
    pub gamma: f64,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance on each of u, ln v, θ.
    pub atol: f64,
    /// Whether the run succeeded.
    pub ok: bool,
    /// Why it failed.
    pub error: Option<String>,
    /// The means over the measured cycles.
    pub measured: Option<Measured>,
    /// Relative errors against the reference.
    pub errors: Option<Errors>,
    /// Minimum over the timed runs of (run time / cycles), seconds.
    pub time_per_cycle_s: Option<f64>,
    /// Timed runs.
    pub runs: Option<u64>,
    /// Work counters of one run (3 cycles plus the 2 % lead-in).
    pub counts: Counts,
}

impl Row {
    /// An empty (failed, reasonless) row.
    pub fn new(method: &str, side: &str, setting: &str, gamma: f64, rtol: f64) -> Self {
        Self {
            method: method.into(),
            side: side.into(),
            setting: setting.into(),
            tuning: None,
            gamma,
            rtol,
            atol: protocol::atol(rtol),
            ok: false,
            error: None,
            measured: None,
            errors: None,
            time_per_cycle_s: None,
            runs: None,
            counts: Counts::default(),
        }
    }
}

/// The reference at one γ.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Reference {
    /// γ.
    pub gamma: f64,
    /// The common start and the settling run's period.
    pub start: Start,
    /// The reference values (mean of the two runs).
    pub values: Measured,
    /// radau5 at rtol 1e-14.
    pub radau5: Measured,
    /// rodas5p at rtol 1e-13.
    pub rodas5p: Measured,
    /// |radau5 − rodas5p| / |reference| per quantity: the reference's accuracy.
    pub agreement: Errors,
    /// The period and ln v_max of data/reference/drr_cycles.json at this γ (the limit cycle
    /// from the engine's convergence rule, CVODE and ARKStep at rtol 1e-11), relative to ours.
    pub drr_cycles_table: Option<Errors>,
}

/// The wrapper against plain C at one tolerance: cvode-bdf through the library and the C
/// replica of the engine, minimum time per cycle of each over alternating rounds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WrapperRow {
    /// γ.
    pub gamma: f64,
    /// Relative tolerance.
    pub rtol: f64,
    /// Library: minimum seconds per cycle.
    pub library_s: f64,
    /// Plain C: minimum seconds per cycle.
    pub c_s: f64,
    /// library_s / c_s.
    pub ratio: f64,
    /// Alternating rounds (library, then C, in each).
    pub rounds: usize,
    /// Timed runs per side in each round.
    pub runs_per_round: usize,
}

/// Rounds and runs per round of the wrapper-against-C measurement.
const WRAPPER_ROUNDS: usize = 40;
const WRAPPER_RUNS: usize = 5;
/// (WRAPPER_ROUNDS, WRAPPER_RUNS) for the report.
pub const WRAPPER_ROUNDS_DOC: (usize, usize) = (WRAPPER_ROUNDS, WRAPPER_RUNS);

/// The wrapper against plain C at (γ, rtol): WRAPPER_ROUNDS alternating rounds, each a process
/// of the C program and one of this benchmark in `--cell` mode, both doing one warm-up and
/// WRAPPER_RUNS timed runs, so that both sides see the same machine load and the same process
/// life cycle; the minimum of each side over all rounds.
fn wrapper_vs_c(
    c: &std::path::Path,
    gamma: f64,
    rtol: f64,
    start: &Start,
    limit_s: u64,
) -> Result<WrapperRow, String> {
    let (mut lib, mut cmin) = (f64::INFINITY, f64::INFINITY);
    let me = std::env::current_exe().map_err(|e| format!("this benchmark's path: {e}"))?;
    for _ in 0..WRAPPER_ROUNDS {
        cmin = cmin.min(peers::c_min_time(c, gamma, rtol, start, WRAPPER_RUNS, limit_s)?);
        let out = std::process::Command::new(&me)
            .arg("--cell")
            .args([gamma, rtol, start.y0[0], start.y0[1], start.y0[2]].map(|x| x.to_string()))
            .arg(WRAPPER_RUNS.to_string())
            .output()
            .map_err(|e| format!("{}: {e}", me.display()))?;
        let text = String::from_utf8_lossy(&out.stdout);
        let t: f64 = text.trim().parse().map_err(|_| {
            format!("--cell printed {text:?}: {}", String::from_utf8_lossy(&out.stderr))
        })?;
        lib = lib.min(t);
    }
    Ok(WrapperRow {
        gamma,
        rtol,
        library_s: lib,
        c_s: cmin,
        ratio: lib / cmin,
        rounds: WRAPPER_ROUNDS,
        runs_per_round: WRAPPER_RUNS,
    })
}

/// Our methods at γ: the stiff ones everywhere, the explicit ones only at γ = 1e1.
pub fn our_methods(gamma: f64) -> Vec<(&'static str, Method)> {
    Method::ALL
        .iter()
        .copied()
        .filter(|(_, m)| gamma <= 10.0 || !matches!(m, Method::CvodeAdams | Method::ArkodeErk))
        .collect()
}

/// Command-line options.
#[derive(Debug, Clone)]
pub struct Args {
    gammas: Vec<f64>,
    rtols: Vec<f64>,
    only: Option<Vec<String>>,
    runs: usize,
    budget_s: f64,
    limit_s: u64,
    peers: bool,
    write: bool,
    smoke: bool,
    reanalyse: bool,
    wrapper_only: bool,
    /// `--cell GAMMA RTOL U0 W0 THETA0 RUNS`: (γ, rtol, start, runs).
    cell: Option<(f64, f64, [f64; 3], usize)>,
}

fn list(s: &str) -> Vec<f64> {
    s.split(',')
        .map(|x| x.trim().parse().unwrap_or_else(|_| panic!("not a number list: {s}")))
        .collect()
}

fn parse_args() -> Args {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let mut a = Args {
        gammas: vec![1e1, 1e3, 1e5, 1e8],
        rtols: (3..=12).map(|k| 10f64.powi(-k)).collect(),
        only: None,
        runs: 5,
        budget_s: 2.0,
        limit_s: 900,
        peers: true,
        write: true,
        smoke: false,
        reanalyse: false,
        wrapper_only: false,
        cell: None,
    };
    let mut it = argv.iter();
    while let Some(flag) = it.next() {
        let mut value = || it.next().unwrap_or_else(|| panic!("{flag} needs a value")).clone();
        match flag.as_str() {
            "--quick" => {
                a.gammas = vec![1e3, 1e8];
                a.rtols = vec![1e-4, 1e-6, 1e-8];
                a.runs = 3;
            }
            "--gammas" => a.gammas = list(&value()),
            "--rtols" => a.rtols = list(&value()),
            "--only" => a.only = Some(value().split(',').map(String::from).collect()),
            "--runs" => a.runs = value().parse().expect("--runs N"),
            "--budget" => a.budget_s = value().parse().expect("--budget S"),
            "--limit" => a.limit_s = value().parse().expect("--limit S"),
            "--no-peers" => a.peers = false,
            "--no-write" => a.write = false,
            "--smoke" => a.smoke = true,
            "--reanalyse" => a.reanalyse = true,
            "--cell" => {
                let mut num = || value().parse::<f64>().expect("--cell GAMMA RTOL U0 W0 THETA0 RUNS");
                let (gamma, rtol) = (num(), num());
                let y0 = [num(), num(), num()];
                a.cell = Some((gamma, rtol, y0, num() as usize));
                a.smoke = false;
            }
            "--wrapper" => {
                a.reanalyse = true;
                a.wrapper_only = true;
            }
            other => panic!("unknown option {other} (see the options at the top of tools/work_precision/main.rs)"),
        }
    }
    a
}

impl Args {
    fn wants(&self, method: &str) -> bool {
        self.only.as_ref().is_none_or(|o| o.iter().any(|m| m == method))
    }
}

/// One cell of our side: one warm-up run (timed); if it took longer than the budget it is the
/// only run, otherwise up to `runs` timed runs until they add up to the budget.
fn run_ours(name: &str, method: Method, gamma: f64, rtol: f64, start: &Start, args: &Args) -> Row {
    let mut row = Row::new(name, "stickslip", "library defaults", gamma, rtol);
    let mut times = Vec::new();
    let mut outcome = protocol::run_ours(method, gamma, rtol, start);
    if let Ok((_, _, warm_up)) = &outcome {
        let warm_up = warm_up.as_secs_f64();
        if warm_up > args.budget_s {
            times.push(warm_up);
        } else {
            while times.len() < args.runs && times.iter().sum::<f64>() < args.budget_s {
                outcome = protocol::run_ours(method, gamma, rtol, start);
                match &outcome {
                    Ok((_, _, t)) => times.push(t.as_secs_f64()),
                    Err(_) => break,
                }
            }
        }
    }
    match outcome {
        Ok((m, c, _)) => {
            row.ok = true;
            row.measured = Some(m);
            row.counts = c;
            row.time_per_cycle_s =
                Some(times.iter().copied().fold(f64::INFINITY, f64::min) / protocol::CYCLES as f64);
            row.runs = Some(times.len() as u64);
        }
        Err(e) => row.error = Some(e),
    }
    row
}

/// The relative errors of `x` against `r`.
pub fn relative(x: &Measured, r: &Measured) -> Errors {
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    Errors {
        period: rel(x.period, r.period),
        t0: rel(x.t0, r.t0),
        ln_v_max: rel(x.ln_v_max, r.ln_v_max),
    }
}

/// The row of data/reference/drr_cycles.json at (ξ, ε) = (0.8, 1) and γ, as Measured (t0
/// included).
fn drr_cycles_row(gamma: f64) -> Option<Measured> {
    let text =
        std::fs::read_to_string(peers::root().join("data/reference/drr_cycles.json")).ok()?;
    let table: serde_json::Value = serde_json::from_str(&text).ok()?;
    let row = table["rows"].as_array()?.iter().find(|r| {
        r["xi"].as_f64() == Some(protocol::XI)
            && r["epsilon"].as_f64() == Some(protocol::EPSILON)
            && r["gamma"].as_f64() == Some(gamma)
    })?;
    let r = &row["reference"];
    Some(Measured {
        period: r["period"].as_f64()?,
        t0: r["t0"].as_f64()?,
        ln_v_max: r["ln_v_max"].as_f64()?,
    })
}

/// The start and the reference at γ.
fn reference(gamma: f64) -> Result<Reference, String> {
    let start = protocol::settle(gamma)?;
    let (a, _, _) = protocol::run_ours(Method::Radau5, gamma, 1e-14, &start)
        .map_err(|e| format!("reference radau5: {e}"))?;
    let (b, _, _) = protocol::run_ours(Method::Rodas5p, gamma, 1e-13, &start)
        .map_err(|e| format!("reference rodas5p: {e}"))?;
    let values = Measured {
        period: 0.5 * (a.period + b.period),
        t0: 0.5 * (a.t0 + b.t0),
        ln_v_max: 0.5 * (a.ln_v_max + b.ln_v_max),
    };
    let agreement = Errors {
        period: (a.period - b.period).abs() / values.period.abs(),
        t0: (a.t0 - b.t0).abs() / values.t0.abs(),
        ln_v_max: (a.ln_v_max - b.ln_v_max).abs() / values.ln_v_max.abs(),
    };
    let drr_cycles_table = drr_cycles_row(gamma).map(|t| relative(&t, &values));
    Ok(Reference { gamma, start, values, radau5: a, rodas5p: b, agreement, drr_cycles_table })
}

fn print_row(r: &Row) {
    match (&r.errors, r.time_per_cycle_s) {
        (Some(e), Some(t)) => eprintln!(
            "  {:<18} {:<16} rtol {:.0e}: {:>10.4} ms/cycle, errors period {:.1e} t0 {:.1e} ln v_max {:.1e}, steps {}",
            r.method,
            r.setting,
            r.rtol,
            t * 1e3,
            e.period,
            e.t0,
            e.ln_v_max,
            r.counts.steps.map_or("-".into(), |s| s.to_string())
        ),
        _ => eprintln!("  {:<18} {:<16} rtol {:.0e}: FAILED: {}", r.method, r.setting, r.rtol, r.error.as_deref().unwrap_or("?")),
    }
}

fn main() {
    let args = parse_args();
    if args.smoke {
        // `--smoke`: one cell of our side, nothing written.
        let start = protocol::settle(1e3).expect("settling at γ = 1e3");
        let row = run_ours("radau5", Method::Radau5, 1e3, 1e-6, &start, &Args { runs: 1, ..args });
        assert!(row.ok, "{:?}", row.error);
        eprintln!(
            "work_precision smoke test: radau5 at γ = 1e3, rtol 1e-6 ran ({:?})",
            row.measured
        );
        return;
    }
    if let Some(cell) = &args.cell {
        // One side of the wrapper-against-C measurement, in its own process (see wrapper_vs_c):
        // cvode-bdf at (γ, rtol) from the given start; prints the minimum seconds per cycle of
        // `runs` timed runs after one warm-up.
        let (gamma, rtol, y0, runs) = (cell.0, cell.1, cell.2, cell.3);
        let start = Start { y0, period: f64::NAN };
        let mut best = f64::INFINITY;
        for k in 0..=runs {
            let (_, _, t) = protocol::run_ours(Method::CvodeBdf, gamma, rtol, &start)
                .unwrap_or_else(|e| panic!("{e}"));
            if k > 0 {
                best = best.min(t.as_secs_f64() / protocol::CYCLES as f64);
            }
        }
        println!("{best:e}");
        return;
    }
    if args.reanalyse {
        // Tables, targets and diagrams again from the committed results; with --wrapper, the
        // wrapper-against-C measurement at γ = 1e8 is taken anew first.
        let mut results = report::read().unwrap_or_else(|e| panic!("{e}"));
        if args.wrapper_only {
            let c = common::compile_c(
                "earthquake_cvode",
                &["-O3", "-ffp-contract=off"],
                common::CVODE_DENSE_LIBS,
            );
            // The start again (deterministic) rather than read back: serde_json's float parsing
            // is not exact to the last bit, and CVODE's loose-tolerance runs depend on it.
            let stored =
                results.references.iter().find(|r| r.gamma == 1e8).expect("γ = 1e8 in the results");
            let start = protocol::settle(1e8).unwrap_or_else(|e| panic!("{e}"));
            let close = start
                .y0
                .iter()
                .zip(&stored.start.y0)
                .all(|(a, b)| (a - b).abs() <= 1e-15 * a.abs().max(1.0));
            assert!(
                close,
                "the start {:?} is not the stored {:?}: measure the whole grid again",
                start.y0, stored.start.y0
            );
            let mut rtols: Vec<f64> = results
                .rows
                .iter()
                .filter(|w| w.gamma == 1e8 && w.method == "cvode-bdf")
                .map(|w| w.rtol)
                .collect();
            rtols.dedup();
            results.wrapper.clear();
            for rtol in rtols {
                match wrapper_vs_c(&c, 1e8, rtol, &start, args.limit_s) {
                    Ok(w) => {
                        eprintln!(
                            "  wrapper/C rtol {rtol:.0e}: {:.4} / {:.4} ms per cycle = {:.3}",
                            w.library_s * 1e3,
                            w.c_s * 1e3,
                            w.ratio
                        );
                        results.wrapper.push(w);
                    }
                    Err(e) => eprintln!("  wrapper/C rtol {rtol:.0e}: not measured ({e})"),
                }
            }
            let measured = serde_json::json!({
                "command": "cargo run --release --example work_precision -- --wrapper",
                "commit": report::machine()["stickslip_commit"],
                "date_utc": report::machine()["date_utc"],
                "load_average_end": report::load_average(),
            });
            if args.write {
                report::write_wrapper(&results.wrapper, measured.clone())
                    .unwrap_or_else(|e| panic!("writing wrapper.json: {e}"));
            }
            results.machine["wrapper_measured"] = measured;
        }
        let analysis = report::analyse(&results);
        eprintln!("{}", analysis.summary);
        if args.write {
            report::write(&results, &analysis, false)
                .unwrap_or_else(|e| panic!("writing the results: {e}"));
        }
        return;
    }
    let started = Instant::now();
    let mut machine = report::machine();
    let mut programs = Vec::new();
    if args.peers {
        if args.wants("c-cvode-bdf") {
            let c = common::compile_c(
                "earthquake_cvode",
                &["-O3", "-ffp-contract=off"],
                common::CVODE_DENSE_LIBS,
            );
            programs.push(peers::Program::C(c));
        }
        if peers::RUST_PEERS.iter().any(|m| args.wants(m)) {
            match peers::build_rust_peers() {
                Ok(binary) => programs.extend(
                    peers::RUST_PEERS
                        .iter()
                        .filter(|m| args.wants(m))
                        .map(|m| peers::Program::Rust(binary.clone(), m)),
                ),
                Err(e) => panic!("{e}"),
            }
        }
        if peers::SCIPY_PEERS.iter().any(|m| args.wants(&format!("scipy-{}", m.to_lowercase()))) {
            let versions = peers::scipy_versions().unwrap_or_else(|e| panic!("{e}"));
            machine["python"] = versions;
            programs.extend(
                peers::SCIPY_PEERS
                    .iter()
                    .filter(|m| args.wants(&format!("scipy-{}", m.to_lowercase())))
                    .map(|m| peers::Program::Scipy(m)),
            );
        }
    }
    let mut references = Vec::new();
    let mut rows = Vec::new();
    let mut wrapper = Vec::new();
    for &gamma in &args.gammas {
        let r = reference(gamma).unwrap_or_else(|e| panic!("γ = {gamma:e}: {e}"));
        eprintln!(
            "γ = {gamma:e}: start {:?}, reference period {:.15} (radau5/rodas5p agree to {:.1e}; t0 {:.1e}, ln v_max {:.1e})",
            r.start.y0, r.values.period, r.agreement.period, r.agreement.t0, r.agreement.ln_v_max
        );
        for (name, method) in our_methods(gamma) {
            if !args.wants(name) {
                continue;
            }
            for &rtol in &args.rtols {
                let mut row = run_ours(name, method, gamma, rtol, &r.start, &args);
                row.errors = row.measured.map(|m| relative(&m, &r.values));
                print_row(&row);
                rows.push(row);
            }
        }
        for program in &programs {
            for &rtol in &args.rtols {
                for mut row in peers::run(
                    program,
                    gamma,
                    rtol,
                    &r.start,
                    args.runs,
                    args.budget_s,
                    args.limit_s,
                ) {
                    row.errors = row.measured.map(|m| relative(&m, &r.values));
                    print_row(&row);
                    rows.push(row);
                }
            }
        }
        // The wrapper against plain C (the target is stated at γ = 1e8).
        let c_binary = programs.iter().find_map(|p| {
            if let peers::Program::C(b) = p {
                Some(b.clone())
            } else {
                None
            }
        });
        if let (Some(c), true) = (c_binary, gamma == 1e8 && args.wants("cvode-bdf")) {
            for &rtol in &args.rtols {
                match wrapper_vs_c(&c, gamma, rtol, &r.start, args.limit_s) {
                    Ok(w) => {
                        eprintln!(
                            "  wrapper/C rtol {rtol:.0e}: {:.4} / {:.4} ms per cycle = {:.3}",
                            w.library_s * 1e3,
                            w.c_s * 1e3,
                            w.ratio
                        );
                        wrapper.push(w);
                    }
                    Err(e) => eprintln!("  wrapper/C rtol {rtol:.0e}: not measured ({e})"),
                }
            }
        }
        references.push(r);
    }
    machine["load_average_end"] = serde_json::json!(report::load_average());
    machine["wall_time_s"] = serde_json::json!(started.elapsed().as_secs_f64());
    let extra: Vec<String> = std::env::args().skip(1).collect();
    let command = if extra.is_empty() {
        "cargo run --release --example work_precision".to_string()
    } else {
        format!("cargo run --release --example work_precision -- {}", extra.join(" "))
    };
    let results = report::Results {
        machine,
        command,
        runs: args.runs,
        budget_s: args.budget_s,
        references,
        rows,
        wrapper,
    };
    let analysis = report::analyse(&results);
    eprintln!("{}", analysis.summary);
    if args.write {
        report::write(&results, &analysis, true)
            .unwrap_or_else(|e| panic!("writing the results: {e}"));
    }
}
