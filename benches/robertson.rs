//! Robertson (SUNDIALS' `cvode/serial/cvRoberts_dns.c`): our safe wrapper against plain C.
//!
//! `rust_wrapper` times `stickslip::model::robertson::cvode_example()` (build the solver, run
//! the whole example, free everything). `plain_c` times `benches/c/robertson_cvode.c`, the same
//! example with identical settings and no I/O, compiled here with `cc -O3` (cargo's bench
//! profile is opt-level 3) against the same system SUNDIALS libraries; the C program times
//! itself with CLOCK_MONOTONIC and criterion receives its total through `iter_custom`, so
//! process start-up is never timed.
//!
//! Before any timing, both sides must produce the same output rows and the same counters
//! (steps, RHS/Jacobian/root evaluations, ...); the C program also checks its final state
//! against the example's reference solution. After the criterion group, an independent
//! measurement (minimum of 200 single runs per side after warm-up, taken in 10 alternating
//! rounds of 20 so both sides see the same machine load) prints `ratio rust/c = X`.
//!
//! Run: `cargo bench --bench robertson` (results in docs/benchmarks.md).

use criterion::Criterion;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant, SystemTime};
use stickslip::model::robertson::{cvode_example, ExampleRun};

const GROUP: &str = "robertson_cvode";
const C_OPT: &str = "-O3";
/// Untimed Rust runs before the independent measurement (the C program does the same number).
const INDEPENDENT_WARMUP: usize = 50;
/// The independent measurement: ROUNDS × ROUND_RUNS = 200 single runs per side.
const ROUNDS: usize = 10;
const ROUND_RUNS: usize = 20;

/// Where the C binary goes: cargo's per-target scratch directory when it provides one.
fn scratch_dir() -> PathBuf {
    option_env!("CARGO_TARGET_TMPDIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir)
}

/// Compiles benches/c/robertson_cvode.c once and returns the binary's path.
fn compile_c() -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/c/robertson_cvode.c");
    let dir = scratch_dir();
    std::fs::create_dir_all(&dir)
        .unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    let binary = dir.join("robertson_cvode");
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let mut cmd = Command::new(&compiler);
    cmd.arg(C_OPT).arg("-o").arg(&binary).arg(&source);
    if let Some(inc) = std::env::var_os("SUNDIALS_INCLUDE_DIR") {
        cmd.arg("-I").arg(inc);
    }
    if let Some(lib) = std::env::var_os("SUNDIALS_LIBRARY_DIR") {
        let lib = PathBuf::from(lib);
        cmd.arg("-L")
            .arg(&lib)
            .arg(format!("-Wl,-rpath,{}", lib.display()));
    }
    cmd.args([
        "-lsundials_cvode",
        "-lsundials_nvecserial",
        "-lsundials_sunmatrixdense",
        "-lsundials_sunlinsoldense",
        "-lm",
    ]);
    let status = cmd
        .status()
        .unwrap_or_else(|e| panic!("cannot run the C compiler `{compiler}`: {e}"));
    assert!(
        status.success(),
        "compiling {} failed: {cmd:?}",
        source.display()
    );
    binary
}

/// Runs the C program and returns its stdout; panics on failure (including a failed
/// reference-solution check, exit status 2).
fn run_c(binary: &Path, args: &[&str]) -> String {
    let out = Command::new(binary)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", binary.display()));
    assert!(
        out.status.success(),
        "{} {args:?} failed ({}): {}",
        binary.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("the C program prints ASCII")
}

/// `robertson_cvode N`: total nanoseconds of N runs.
fn c_total(binary: &Path, iters: u64) -> Duration {
    let out = run_c(binary, &[&iters.to_string()]);
    Duration::from_nanos(
        out.trim()
            .parse()
            .unwrap_or_else(|e| panic!("bad C timing output {out:?}: {e}")),
    )
}

/// Compares the C program's `check` output with one Rust run: every output row and every
/// counter must agree. Returns (Rust steps, C steps, whether all rows are bit-for-bit
/// identical).
fn compare(binary: &Path, rust: &ExampleRun) -> (u64, u64, bool) {
    let out = run_c(binary, &["check"]);
    let mut rows = Vec::new();
    let mut counters = std::collections::HashMap::new();
    for line in out.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.as_slice() {
            ["row", rest @ ..] => {
                let v: Vec<f64> = rest[..4]
                    .iter()
                    .map(|s| s.parse().expect("row value"))
                    .collect();
                let r: Vec<i32> = rest[4..]
                    .iter()
                    .map(|s| s.parse().expect("root flag"))
                    .collect();
                rows.push((v, r));
            }
            [name, value] => {
                counters.insert(name.to_string(), value.to_string());
            }
            _ => panic!("unexpected C check line {line:?}"),
        }
    }
    let counter = |name: &str| -> u64 {
        counters
            .get(name)
            .unwrap_or_else(|| panic!("C check output lacks {name}"))
            .parse()
            .expect("counter")
    };
    let s = &rust.stats;
    let pairs = [
        ("steps", s.steps),
        ("rhs_evals", s.rhs_evals),
        ("lin_setups", s.lin_setups),
        ("err_test_fails", s.err_test_fails),
        ("step_solve_fails", s.step_solve_fails),
        ("nonlin_iters", s.nonlin_iters),
        ("nonlin_conv_fails", s.nonlin_conv_fails),
        ("jac_evals", s.jac_evals),
        ("rhs_evals_jacobian", s.rhs_evals_jacobian),
        ("root_evals", s.root_evals),
    ];
    for (name, rust_value) in pairs {
        assert_eq!(
            rust_value,
            counter(name),
            "{name}: Rust wrapper {rust_value} vs plain C {}",
            counter(name)
        );
    }
    assert_eq!(
        rows.len(),
        rust.rows.len(),
        "number of output rows differs: C {} vs Rust {}",
        rows.len(),
        rust.rows.len()
    );
    let mut bitwise = true;
    for (i, ((cv, cr), r)) in rows.iter().zip(&rust.rows).enumerate() {
        let rust_values = [r.t, r.y[0], r.y[1], r.y[2]];
        let rust_roots = r.roots.clone();
        let c_roots = (cr[0] == 1).then(|| cr[1..].to_vec());
        assert_eq!(rust_roots, c_roots, "row {i}: root information differs");
        for (c, rv) in cv.iter().zip(rust_values) {
            bitwise &= c.to_bits() == rv.to_bits();
            assert!(
                (c - rv).abs() <= 1e-10 * c.abs().max(1e-300),
                "row {i}: C {cv:?} vs Rust {rust_values:?}"
            );
        }
    }
    (s.steps, counter("steps"), bitwise)
}

/// Criterion's median point estimate (ns) for one function of the group, if it was written
/// during this run.
fn criterion_median(function: &str, since: SystemTime) -> Option<f64> {
    let root = std::env::var_os("CRITERION_HOME")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("CARGO_TARGET_DIR").map(|d| PathBuf::from(d).join("criterion"))
        })
        .or_else(|| {
            option_env!("CARGO_TARGET_TMPDIR")
                .and_then(|t| Path::new(t).parent().map(|p| p.join("criterion")))
        })
        .unwrap_or_else(|| PathBuf::from("target/criterion"));
    let file = root.join(GROUP).join(function).join("new/estimates.json");
    if std::fs::metadata(&file).and_then(|m| m.modified()).ok()? < since {
        return None;
    }
    let json = std::fs::read_to_string(file).ok()?;
    // {"mean":{...},"median":{"confidence_interval":{...},"point_estimate":X,...},...}
    let median = &json[json.find("\"median\"")?..];
    let value = &median[median.find("\"point_estimate\":")? + "\"point_estimate\":".len()..];
    let end = value.find([',', '}'])?;
    value[..end].trim().parse().ok()
}

/// `ROUND_RUNS` single Rust runs, each timed with `Instant`, after `warmup` untimed runs.
fn rust_singles(warmup: usize) -> Vec<Duration> {
    for _ in 0..warmup {
        black_box(cvode_example().expect("Robertson example"));
    }
    (0..ROUND_RUNS)
        .map(|_| {
            let start = Instant::now();
            black_box(cvode_example().expect("Robertson example"));
            start.elapsed()
        })
        .collect()
}

/// `ROUND_RUNS` single C runs, timed in C after its own warm-up (`robertson_cvode N each`).
fn c_singles(binary: &Path) -> Vec<Duration> {
    let out = run_c(binary, &[&ROUND_RUNS.to_string(), "each"]);
    out.lines()
        .map(|l| Duration::from_nanos(l.trim().parse().expect("C single-run time")))
        .collect()
}

/// Independent measurement: `ROUNDS` alternating rounds of `ROUND_RUNS` single runs per side
/// (so both sides see the same machine load), after warm-up. Returns (min, median) per side:
/// ((rust_min, rust_median), (c_min, c_median)).
fn independent(binary: &Path) -> ((Duration, Duration), (Duration, Duration)) {
    let (mut rust, mut c) = (Vec::new(), Vec::new());
    for round in 0..ROUNDS {
        c.extend(c_singles(binary));
        rust.extend(rust_singles(if round == 0 {
            INDEPENDENT_WARMUP
        } else {
            5
        }));
    }
    let summary = |mut v: Vec<Duration>| {
        v.sort();
        (v[0], v[v.len() / 2])
    };
    (summary(rust), summary(c))
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let has = |flag: &str| args.iter().any(|a| a == flag);
    let benchmarking = has("--bench") && !has("--test") && !has("--list") && !has("--profile-time");

    let binary = compile_c();
    let reference = cvode_example().expect("Robertson example through the Rust wrapper");
    let (steps, c_steps, bitwise) = compare(&binary, &reference);
    eprintln!(
        "robertson: C ({} {C_OPT}) and Rust agree: {steps} steps each, same counters, output rows {}",
        binary.display(),
        if bitwise { "bit-for-bit identical" } else { "equal to 1e-10 (not bit-for-bit)" }
    );

    let start = SystemTime::now();
    let mut criterion = Criterion::default().configure_from_args();
    {
        let mut group = criterion.benchmark_group(GROUP);
        group.bench_function("rust_wrapper", |b| b.iter(cvode_example));
        group.bench_function("plain_c", |b| {
            b.iter_custom(|iters| c_total(&binary, iters))
        });
        group.finish();
    }
    criterion.final_summary();

    if !benchmarking {
        return;
    }
    match (
        criterion_median("rust_wrapper", start),
        criterion_median("plain_c", start),
    ) {
        (Some(rust), Some(c)) => eprintln!(
            "criterion medians: rust_wrapper {:.1} µs, plain_c {:.1} µs, ratio rust/c = {:.3}",
            rust / 1e3,
            c / 1e3,
            rust / c
        ),
        _ => eprintln!(
            "criterion medians: not available (a filter skipped a function, or no estimates.json)"
        ),
    }
    let ((rust_min, rust_median), (c_min, c_median)) = independent(&binary);
    eprintln!(
        "independent, {} single runs per side ({ROUNDS} alternating rounds) after warm-up: \
         rust min {:.1} µs (median {:.1}), c min {:.1} µs (median {:.1})",
        ROUNDS * ROUND_RUNS,
        us(rust_min),
        us(rust_median),
        us(c_min),
        us(c_median)
    );
    eprintln!("steps: rust {steps}, c {c_steps}");
    eprintln!(
        "ratio rust/c = {:.3}",
        rust_min.as_secs_f64() / c_min.as_secs_f64()
    );
}
