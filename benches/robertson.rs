//! Robertson (SUNDIALS' `cvode/serial/cvRoberts_dns.c`): our safe wrapper against plain C.
//!
//! `rust_wrapper` times `stickslip::robertson::examples::cvode_example()` (build the solver, run
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

mod common;

use criterion::Criterion;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, SystemTime};
use stickslip::robertson::examples::{cvode_example, ExampleRun};

const GROUP: &str = "robertson_cvode";
const C_OPT: &str = "-O3";
/// Untimed Rust runs before the independent measurement (the C program does the same number).
const INDEPENDENT_WARMUP: usize = 50;
/// The independent measurement: ROUNDS × ROUND_RUNS = 200 single runs per side.
const ROUNDS: usize = 10;
const ROUND_RUNS: usize = 20;

/// `robertson_cvode N`: total nanoseconds of N runs.
fn c_total(binary: &Path, iters: u64) -> Duration {
    let out = common::run_c(binary, &[&iters.to_string()]);
    common::c_nanos(out.trim(), &out)
}

/// Compares the C program's `check` output with one Rust run: every output row and every
/// counter must agree. Returns (Rust steps, C steps, whether all rows are bit-for-bit
/// identical).
fn compare(binary: &Path, rust: &ExampleRun) -> (u64, u64, bool) {
    // Panics on a failed reference-solution check in C (exit status 2).
    let out = common::run_c(binary, &["check"]);
    let mut rows = Vec::new();
    let mut counters = std::collections::HashMap::new();
    for line in out.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.as_slice() {
            ["row", rest @ ..] => {
                let v: Vec<f64> = rest[..4].iter().map(|s| s.parse().expect("row value")).collect();
                let r: Vec<i32> = rest[4..].iter().map(|s| s.parse().expect("root flag")).collect();
                rows.push((v, r));
            }
            [name, value] => {
                counters.insert(name.to_string(), value.to_string());
            }
            _ => panic!("unexpected C check line {line:?}"),
        }
    }
    let s = &rust.stats;
    common::assert_counters(&counters, "Rust wrapper", s, ("root_evals", s.root_evals));
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
    (s.steps, common::counter(&counters, "steps"), bitwise)
}

/// Independent measurement: `ROUNDS` alternating rounds of `ROUND_RUNS` single runs per side
/// (so both sides see the same machine load), after warm-up (`INDEPENDENT_WARMUP` untimed Rust
/// runs in the first round, 5 in each later one; the C program warms up itself). Returns (min,
/// median) per side: ((rust_min, rust_median), (c_min, c_median)).
fn independent(binary: &Path) -> ((Duration, Duration), (Duration, Duration)) {
    let (c, [rust]) = common::alternate(
        ROUNDS,
        ROUND_RUNS,
        // `robertson_cvode N each`: N single runs, timed in C after its own warm-up.
        || common::c_singles(binary, &[&ROUND_RUNS.to_string(), "each"]),
        |round| {
            let warmup = if round == 0 { INDEPENDENT_WARMUP } else { 5 };
            for _ in 0..warmup {
                black_box(cvode_example().expect("Robertson example"));
            }
        },
        || {
            [common::time_one(|| {
                black_box(cvode_example().expect("Robertson example"));
            })]
        },
    );
    let summary = |v: &[Duration]| (v[0], common::median(v));
    (summary(&rust), summary(&c))
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn main() {
    let benchmarking = common::benchmarking();

    let binary = common::compile_c("robertson_cvode", &[C_OPT], common::CVODE_DENSE_LIBS);
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
        group.bench_function("plain_c", |b| b.iter_custom(|iters| c_total(&binary, iters)));
        group.finish();
    }
    criterion.final_summary();

    if !benchmarking {
        return;
    }
    match (
        common::criterion_median(GROUP, "rust_wrapper", start),
        common::criterion_median(GROUP, "plain_c", start),
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
    eprintln!("ratio rust/c = {:.3}", common::ratio(rust_min, c_min));
}
