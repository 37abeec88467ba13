//! What the benches that time a Rust side against a plain-C SUNDIALS program share: compiling
//! the C program in benches/c/ against the system SUNDIALS, running it and reading what it
//! prints (its own CLOCK_MONOTONIC timings in nanoseconds, its CVODE counters), criterion's
//! median estimates, and the independent measurement in alternating C/Rust rounds.
//!
//! Used by each bench through `mod common;`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant, SystemTime};
use stickslip::integrate::Stats;

/// Link flags of a C program using CVODE with a dense matrix and linear solver.
pub const CVODE_DENSE_LIBS: &[&str] = &[
    "-lsundials_cvode",
    "-lsundials_nvecserial",
    "-lsundials_sunmatrixdense",
    "-lsundials_sunlinsoldense",
    "-lm",
];

/// Whether criterion will really measure (`cargo bench`), rather than run each benchmark once
/// as a test (`cargo test --benches`, `--test`), list them or profile.
pub fn benchmarking() -> bool {
    let args: Vec<String> = std::env::args().collect();
    let has = |flag: &str| args.iter().any(|a| a == flag);
    has("--bench") && !has("--test") && !has("--list") && !has("--profile-time")
}

/// Where the C binary goes: cargo's per-target scratch directory when it provides one.
fn scratch_dir() -> PathBuf {
    option_env!("CARGO_TARGET_TMPDIR").map(PathBuf::from).unwrap_or_else(std::env::temp_dir)
}

/// Compiles benches/c/`name`.c once, with the compiler flags `flags` and the link flags
/// `libs`, and returns the binary's path (`name` in the scratch directory). `$CC` overrides
/// the compiler; `$SUNDIALS_INCLUDE_DIR` and `$SUNDIALS_LIBRARY_DIR` add search paths.
pub fn compile_c(name: &str, flags: &[&str], libs: &[&str]) -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/c").join(format!("{name}.c"));
    let dir = scratch_dir();
    std::fs::create_dir_all(&dir)
        .unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    let binary = dir.join(name);
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let mut cmd = Command::new(&compiler);
    cmd.args(flags).arg("-o").arg(&binary).arg(&source);
    if let Some(inc) = std::env::var_os("SUNDIALS_INCLUDE_DIR") {
        cmd.arg("-I").arg(inc);
    }
    if let Some(lib) = std::env::var_os("SUNDIALS_LIBRARY_DIR") {
        let lib = PathBuf::from(lib);
        cmd.arg("-L").arg(&lib).arg(format!("-Wl,-rpath,{}", lib.display()));
    }
    cmd.args(libs);
    let status =
        cmd.status().unwrap_or_else(|e| panic!("cannot run the C compiler `{compiler}`: {e}"));
    assert!(status.success(), "compiling {} failed: {cmd:?}", source.display());
    binary
}

/// Runs the C program and returns its stdout; panics on failure (including a failed check
/// inside the C program, which exits with a non-zero status).
pub fn run_c(binary: &Path, args: &[&str]) -> String {
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

/// A nanosecond total `value` the C program printed in its output `out`.
pub fn c_nanos(value: &str, out: &str) -> Duration {
    Duration::from_nanos(
        value.parse().unwrap_or_else(|e| panic!("bad C timing output {out:?}: {e}")),
    )
}

/// Single-run times measured by the C program itself: it is run with `args` and prints one
/// nanosecond count a line.
pub fn c_singles(binary: &Path, args: &[&str]) -> Vec<Duration> {
    let out = run_c(binary, args);
    out.lines()
        .map(|l| Duration::from_nanos(l.trim().parse().expect("C single-run time")))
        .collect()
}

/// The counter `name` of the C program's `check` output (`name value` pairs).
pub fn counter(c: &HashMap<String, String>, name: &str) -> u64 {
    c.get(name).unwrap_or_else(|| panic!("C check output lacks {name}")).parse().expect("counter")
}

/// Asserts that the Rust side (`rust_side`, e.g. "Rust wrapper") ran CVODE exactly as the C
/// program did: the solver counters in `stats`, then `extra`, against the C program's
/// `check` output `c`.
pub fn assert_counters(
    c: &HashMap<String, String>,
    rust_side: &str,
    stats: &Stats,
    extra: (&str, u64),
) {
    let pairs = [
        ("steps", stats.steps),
        ("rhs_evals", stats.rhs_evals),
        ("lin_setups", stats.lin_setups),
        ("err_test_fails", stats.err_test_fails),
        ("step_solve_fails", stats.step_solve_fails),
        ("nonlin_iters", stats.nonlin_iters),
        ("nonlin_conv_fails", stats.nonlin_conv_fails),
        ("jac_evals", stats.jac_evals),
        ("rhs_evals_jacobian", stats.rhs_evals_jacobian),
        extra,
    ];
    for (name, rust_value) in pairs {
        assert_eq!(
            rust_value,
            counter(c, name),
            "{name}: {rust_side} {rust_value} vs plain C {}",
            counter(c, name)
        );
    }
}

/// Criterion's median point estimate (ns) for one function of a group, if it was written
/// during this run (since `since`).
pub fn criterion_median(group: &str, function: &str, since: SystemTime) -> Option<f64> {
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
    let file = root.join(group).join(function).join("new/estimates.json");
    if std::fs::metadata(&file).and_then(|m| m.modified()).ok()? < since {
        return None;
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file).ok()?).ok()?;
    json["median"]["point_estimate"].as_f64()
}

/// The wall time of one call of `f`.
pub fn time_one(f: impl FnOnce()) -> Duration {
    let start = Instant::now();
    f();
    start.elapsed()
}

/// The independent measurement: `rounds` alternating rounds so that both sides see the same
/// machine load. Each round runs `c_round` (the C program's single-run times, measured in C),
/// then `warm_up(round)` (untimed Rust runs), then `run` `round_runs` times (one time per
/// Rust-side series). Returns the C times and the Rust series, each sorted ascending.
pub fn alternate<const N: usize>(
    rounds: usize,
    round_runs: usize,
    mut c_round: impl FnMut() -> Vec<Duration>,
    mut warm_up: impl FnMut(usize),
    mut run: impl FnMut() -> [Duration; N],
) -> (Vec<Duration>, [Vec<Duration>; N]) {
    let mut c = Vec::new();
    let mut rust: [Vec<Duration>; N] = std::array::from_fn(|_| Vec::new());
    for round in 0..rounds {
        c.extend(c_round());
        warm_up(round);
        for _ in 0..round_runs {
            for (series, t) in rust.iter_mut().zip(run()) {
                series.push(t);
            }
        }
    }
    c.sort();
    for series in &mut rust {
        series.sort();
    }
    (c, rust)
}

/// The median of sorted times (the upper one for an even count).
pub fn median(sorted: &[Duration]) -> Duration {
    sorted[sorted.len() / 2]
}

/// `a / b` as a float.
pub fn ratio(a: Duration, b: Duration) -> f64 {
    a.as_secs_f64() / b.as_secs_f64()
}
