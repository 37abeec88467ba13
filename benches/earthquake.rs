//! The earthquake scene (data/scenes/earthquake.json: γ = 1e8, ξ = 0.8, ε = 1, CVODE BDF at
//! rtol 1e-10): the whole scene's wall time, and the cost per limit cycle of our engine
//! against a plain-C CVODE program with identical settings.
//!
//! Group `earthquake_scene`, function `engine_run`: `stickslip::engine::run` on the parsed
//! scene (Hopf analysis, cycle analysis to convergence, paper comparison, report assembly) —
//! the "cycle report in under 50 ms" number.
//!
//! Group `earthquake_cycles`: one full integration from the scene's initial state through the
//! N cycles the engine computes (N = 5 today), solver creation and teardown included, on both
//! sides. `rust_engine` runs `engine::integrator` + `analysis::cycle::analyse` with the
//! engine's settings; `plain_c` times `benches/c/earthquake_cvode.c`, which replicates the
//! engine's stepping, event location and restarts in C (compiled here with `cc -O3` against
//! the same system SUNDIALS; it times itself with CLOCK_MONOTONIC and criterion gets its
//! total through `iter_custom`, so process start-up is never timed).
//!
//! Before any timing, the step count of every cycle, the total CVODE counters (steps, RHS and
//! Jacobian evaluations, error-test failures, ...) and every cycle's period must be identical
//! on both sides (periods compared bit for bit). After the groups, an independent measurement
//! (minimum of ROUNDS × ROUND_RUNS single runs per side after warm-up, in alternating rounds
//! so both sides see the same machine load) prints `per-cycle ratio rust/c = X`.
//!
//! Run: `cargo bench --bench earthquake` (results in docs/bench-cycle.md).

mod common;

use criterion::{Criterion, SamplingMode};
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, SystemTime};
use stickslip::analysis::{cycle, hopf};
use stickslip::engine;
use stickslip::integrate::Stats;
use stickslip::model::{Drr, Friction};
use stickslip::scene::{self, Method, Scene};

const SCENE: &str = "data/scenes/earthquake.json";
const C_OPT: &str = "-O3";
/// No FMA contraction: the C arithmetic must be the Rust arithmetic, operation for operation.
const C_FLAGS: &[&str] = &[C_OPT, "-ffp-contract=off"];
/// Untimed Rust runs before the independent measurement (the C program does EACH_WARMUP = 3).
const INDEPENDENT_WARMUP: usize = 3;
/// The independent measurement: ROUNDS × ROUND_RUNS single runs per side.
const ROUNDS: usize = 10;
const ROUND_RUNS: usize = 10;

/// `key value` lines of the C program's output.
fn fields(out: &str) -> std::collections::HashMap<String, String> {
    out.lines()
        .filter_map(|l| l.split_once(' '))
        .filter(|(k, _)| *k != "cycle")
        .map(|(k, v)| (k.to_string(), v.trim().to_string()))
        .collect()
}

/// The scene, its JSON, and the number of cycles the engine computes on it.
struct Setup {
    scene: Scene,
    json: serde_json::Value,
    drr: Drr,
    stable: bool,
    settings: cycle::CycleSettings,
    cycles: usize,
    /// The C program's arguments after N: the engine's max step and `EscapeStep::near`.
    limits: [String; 2],
}

fn setup() -> Setup {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENE);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let scene = scene::parse(&text, SCENE).unwrap_or_else(|e| panic!("{SCENE}: {e:?}"));
    let json: serde_json::Value = serde_json::from_str(&text).expect("scene JSON");
    // The C program hard-codes these values; they must be the parsed ones, bit for bit.
    let p = &scene.params;
    let s = &scene.solver;
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
    assert!(
        same(p.gamma, 1e8)
            && same(p.xi, 0.8)
            && same(p.epsilon, 1.0)
            && p.friction == Friction::Log,
        "the earthquake scene's model changed ({p:?}); update benches/c/earthquake_cvode.c"
    );
    assert!(
        s.method == Method::CvodeBdf
            && same(s.rtol, 1e-10)
            && s.atol.iter().all(|&a| same(a, 1e-12)),
        "the earthquake scene's solver changed ({s:?}); update benches/c/earthquake_cvode.c"
    );
    let initial = [1.0, 0.45f64.ln(), 0.0];
    assert!(
        scene.initial.iter().zip(initial).all(|(&a, b)| same(a, b)),
        "the earthquake scene's initial state changed ({:?}); update benches/c/earthquake_cvode.c",
        scene.initial
    );
    let a = &scene.analyses;
    let options = a.cycle.as_ref().expect("the earthquake scene asks for the cycle analysis");
    let no_overrides = options.tolerance.is_none()
        && options.settle.is_none()
        && options.max_cycles.is_none()
        && options.max_time.is_none()
        && options.max_steps.is_none();
    assert!(
        no_overrides,
        "the scene overrides cycle settings; replicate them here and in the C program"
    );
    let drr = Drr::new(scene.params);
    let linear = hopf::analyse(&drr);
    let stable = linear.max_real_part < 0.0;
    // The C program leaves out the fixed-point test that only runs at a linearly stable fixed
    // point.
    assert!(
        !stable,
        "the earthquake scene's fixed point became stable; replicate the fixed-point test in C"
    );
    // engine::cycle_with's settings: the engine's max step (engine::max_step, 1/8 of the
    // linear period, which engine::integrator sets) and the EscapeStep limits.
    let max_step = linear.period_c / 8.0;
    let escape = cycle::EscapeStep::for_eigenvalues(&linear.eigenvalues, Some(max_step))
        .expect("an unstable fixed point has an escape step");
    let settings = cycle::CycleSettings {
        trajectory_cycles: 0,
        escape: Some(escape),
        ..cycle::CycleSettings::defaults(s.rtol, s.atol[1])
    };
    let limits = [format!("{max_step:e}"), format!("{:e}", escape.near)];
    let report = engine::run(&scene, engine::RunOptions::echoing(json.clone()))
        .expect("the earthquake scene runs");
    let c = report.cycle.as_ref().expect("cycle section");
    assert!(c.converged, "the earthquake scene no longer converges");
    assert_eq!(
        (c.deep_sticks, c.fixed_point_escapes),
        (0, 0),
        "the C program replicates neither deep sticks nor the escape's step limits in action"
    );
    let cycles = c.cycles_computed;
    Setup { scene, json, drr, stable, settings, cycles, limits }
}

/// What the engine does for the cycle section: build the integrator, integrate through the
/// cycles to convergence, drop the integrator. Returns the report and the solver statistics.
fn rust_cycles(s: &Setup, settings: &cycle::CycleSettings) -> (cycle::CycleReport, Stats) {
    let (mut integ, _) =
        engine::integrator(s.drr, &s.scene.solver, &s.scene.initial).expect("integrator");
    let report =
        cycle::analyse(integ.as_mut(), &s.drr, settings, s.stable).expect("cycle analysis");
    let stats = integ.stats();
    (report, stats)
}

/// Checks that the C program integrates exactly as the engine does: per-cycle steps, counters
/// and periods. Returns (total steps, per-cycle steps).
fn compare(binary: &Path, s: &Setup) -> (u64, Vec<u64>) {
    // Same integration, but the convergence rule made unsatisfiable so that the report lists
    // every cycle (`last_cycles`); the run stops at max_cycles = N, exactly where the default
    // rule stops (the rule only reads closed cycles, it never changes the stepping).
    let listing = cycle::CycleSettings { settle: 1000, max_cycles: s.cycles, ..s.settings.clone() };
    let (listed, stats) = rust_cycles(s, &listing);
    assert_eq!(
        listed.last_cycles.len(),
        s.cycles,
        "the listing run must list all {} cycles",
        s.cycles
    );
    let (default_report, default_stats) = rust_cycles(s, &s.settings);
    assert_eq!(default_report.cycles_computed, s.cycles);
    assert_eq!(stats, default_stats, "the listing run must integrate exactly like the default one");

    let n = s.cycles.to_string();
    let out = common::run_c(binary, &["check", &n, &s.limits[0], &s.limits[1]]);
    // "cycle k steps S period P t0 T ln_v_max A ln_v_min B slip C slip_half_width H"
    let c_cycles: Vec<std::collections::HashMap<String, String>> = out
        .lines()
        .filter(|l| l.starts_with("cycle "))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w[2..].chunks(2).map(|kv| (kv[0].to_string(), kv[1].to_string())).collect()
        })
        .collect();
    assert_eq!(
        c_cycles.len(),
        s.cycles,
        "C computed {} cycles, the engine {}",
        c_cycles.len(),
        s.cycles
    );
    let mut c_steps = Vec::new();
    for (k, (rust, c)) in listed.last_cycles.iter().zip(&c_cycles).enumerate() {
        let steps: u64 = c["steps"].parse().expect("steps");
        assert_eq!(rust.steps, steps, "cycle {k}: Rust {} steps, C {steps}", rust.steps);
        c_steps.push(steps);
        let half_width = rust.main.slip_half_width.unwrap_or(f64::NAN);
        let values = [
            ("period", rust.main.period),
            ("t0", rust.main.t0),
            ("ln_v_max", rust.main.ln_v_max),
            ("ln_v_min", rust.main.ln_v_min),
            ("slip", rust.main.slip),
            ("slip_half_width", half_width),
        ];
        for (name, rust_value) in values {
            let c_value: f64 = c[name].parse().expect(name);
            let same = rust_value.to_bits() == c_value.to_bits()
                || (rust_value.is_nan() && c_value.is_nan());
            assert!(same, "cycle {k}: {name} Rust {rust_value:.17e}, C {c_value:.17e}");
        }
    }
    let f = fields(&out);
    common::assert_counters(&f, "Rust engine", &stats, ("reinits", stats.reinits));
    // The C program ran with the engine's limits, and like the engine met no "t + h = t" (so
    // the Clock's retry after a step underflow never fired) and no escape.
    for (name, value) in [("max_step", &s.limits[0]), ("escape_near", &s.limits[1])] {
        let rust: f64 = value.parse().expect(name);
        let c: f64 = f[name].parse().expect(name);
        assert_eq!(rust.to_bits(), c.to_bits(), "{name}: Rust {rust:e}, C {c:e}");
    }
    assert_eq!(
        (stats.step_underflow_warnings, listed.fixed_point_escapes),
        (common::counter(&f, "step_underflows"), common::counter(&f, "fixed_point_escapes")),
        "step underflows and escapes: Rust engine vs plain C"
    );
    eprintln!(
        "earthquake: clock re-bases {} ({} automatic: last step below 1e4 ulps of the local time), \
         retries after a step underflow {}, escapes {} (max step {}, escape step {})",
        f["clock_rebases"],
        f["clock_rebases_automatic"],
        f["underflow_retries"],
        f["fixed_point_escapes"],
        s.limits[0],
        s.limits[1]
    );
    let c_time: f64 = f["time_integrated"].parse().expect("time_integrated");
    assert_eq!(listed.time_integrated.to_bits(), c_time.to_bits(), "time integrated differs");
    (stats.steps, c_steps)
}

/// `earthquake_cvode R N`: total nanoseconds of R runs of N cycles, checking the step count.
fn c_total(binary: &Path, s: &Setup, iters: u64, steps_per_run: u64) -> Duration {
    let (r, n) = (iters.to_string(), s.cycles.to_string());
    let out = common::run_c(binary, &[&r, &n, &s.limits[0], &s.limits[1]]);
    let f = fields(&out);
    let steps: u64 = f["steps"].parse().expect("steps");
    assert_eq!(steps, iters * steps_per_run, "C steps changed between runs");
    common::c_nanos(&f["elapsed_ns"], &out)
}

/// Independent measurement: ROUNDS alternating rounds of ROUND_RUNS single runs per side, after
/// warm-up. Returns sorted single-run times (rust, c, engine_run).
fn independent(binary: &Path, s: &Setup) -> (Vec<Duration>, Vec<Duration>, Vec<Duration>) {
    for _ in 0..INDEPENDENT_WARMUP {
        black_box(rust_cycles(s, &s.settings));
        black_box(
            engine::run(&s.scene, engine::RunOptions::echoing(s.json.clone())).expect("scene"),
        );
    }
    let (c, [rust, scene]) = common::alternate(
        ROUNDS,
        ROUND_RUNS,
        || {
            common::c_singles(
                binary,
                &[
                    &ROUND_RUNS.to_string(),
                    "each",
                    &s.cycles.to_string(),
                    &s.limits[0],
                    &s.limits[1],
                ],
            )
        },
        |_| {},
        || {
            [
                common::time_one(|| {
                    black_box(rust_cycles(s, &s.settings));
                }),
                common::time_one(|| {
                    black_box(
                        engine::run(&s.scene, engine::RunOptions::echoing(s.json.clone()))
                            .expect("scene"),
                    );
                }),
            ]
        },
    );
    (rust, c, scene)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let benchmarking = common::benchmarking();

    let s = setup();
    let binary = common::compile_c("earthquake_cvode", C_FLAGS, common::CVODE_DENSE_LIBS);
    let (steps, per_cycle) = compare(&binary, &s);
    let n = s.cycles;
    eprintln!(
        "earthquake: C ({} {C_OPT}) and the Rust engine agree: {n} cycles, {steps} steps in all \
         (per cycle {per_cycle:?}), same CVODE counters, per-cycle values (period, t0, ln v_max, ln v_min, slip, half width) bit-for-bit identical",
        binary.display()
    );

    let start = SystemTime::now();
    let mut criterion = Criterion::default().configure_from_args();
    {
        let mut group = criterion.benchmark_group("earthquake_scene");
        group
            .sampling_mode(SamplingMode::Flat)
            .sample_size(20)
            .measurement_time(Duration::from_secs(8));
        group.bench_function("engine_run", |b| {
            b.iter(|| {
                engine::run(&s.scene, engine::RunOptions::echoing(s.json.clone())).expect("scene")
            })
        });
        group.finish();
    }
    {
        let mut group = criterion.benchmark_group("earthquake_cycles");
        group
            .sampling_mode(SamplingMode::Flat)
            .sample_size(20)
            .measurement_time(Duration::from_secs(8));
        group.bench_function("rust_engine", |b| b.iter(|| rust_cycles(&s, &s.settings)));
        group.bench_function("plain_c", |b| {
            b.iter_custom(|iters| c_total(&binary, &s, iters, steps))
        });
        group.finish();
    }
    criterion.final_summary();

    if !benchmarking {
        return;
    }
    let nf = n as f64;
    let scene_median = common::criterion_median("earthquake_scene", "engine_run", start);
    let rust_median = common::criterion_median("earthquake_cycles", "rust_engine", start);
    let c_median = common::criterion_median("earthquake_cycles", "plain_c", start);
    if let Some(t) = scene_median {
        eprintln!("criterion median: earthquake scene (engine::run) {:.2} ms", t / 1e6);
    }
    if let (Some(r), Some(c)) = (rust_median, c_median) {
        eprintln!(
            "criterion medians per cycle ({n} cycles per run): rust {:.3} ms, c {:.3} ms, ratio rust/c = {:.3}",
            r / 1e6 / nf,
            c / 1e6 / nf,
            r / c
        );
    }
    let (rust, c, scene) = independent(&binary, &s);
    eprintln!(
        "independent, {} single runs per side ({ROUNDS} alternating rounds) after warm-up:",
        ROUNDS * ROUND_RUNS
    );
    eprintln!(
        "  earthquake scene (engine::run): min {:.2} ms, median {:.2} ms",
        ms(scene[0]),
        ms(common::median(&scene))
    );
    eprintln!(
        "  {n} cycles: rust min {:.2} ms (median {:.2}), c min {:.2} ms (median {:.2})",
        ms(rust[0]),
        ms(common::median(&rust)),
        ms(c[0]),
        ms(common::median(&c))
    );
    eprintln!(
        "  per cycle: rust {:.3} ms, c {:.3} ms; steps per cycle {per_cycle:?} on both sides",
        ms(rust[0]) / nf,
        ms(c[0]) / nf
    );
    eprintln!("per-cycle ratio rust/c = {:.3}", common::ratio(rust[0], c[0]));
}
