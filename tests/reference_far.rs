//! The engine far from the stability threshold against data/reference/drr_cycles_far.json
//! (ε/ξ = 1.5 … 25, i.e. k/k_c = 0.67 … 0.04, at γ = 1e2 … 1e12, slip law, from the default
//! start; Radau5 and Rodas5P at rtol 1e-12 that agree to 1.2e-10 on the period and ln v_max,
//! built by `cargo run --release --example reference_table -- far`).
//!
//! Each method runs the cycle analysis at scene defaults (atol = rtol/100) and must match the
//! reference within `PERIOD_FACTOR`·rtol on the period and ln v_max and `T0_FACTOR`·rtol on t0
//! (the time from v = 1 to the v maximum, a located event). The slip half-width is not checked:
//! at γ ≥ 1e10 even the two reference integrators agree on it only to ~1e-5 (see the table).
//! Rows on which the reference integrators did not agree (`"agrees": false`) are skipped.
//!
//! Measured worst relative deviations over the 42 rows (period, ln v_max, t0):
//! radau5 8.7e-10, 2.3e-9, 2.1e-7 at rtol 1e-10 and 4.7e-8, 3.4e-8, 1.9e-6 at rtol 1e-8;
//! rodas5p 6.6e-10, 1.8e-10, 9.9e-9 at rtol 1e-10 and 2.0e-8, 2.2e-9, 5.2e-8 at rtol 1e-8.
//!
//! CVODE BDF (with a fresh Jacobian at every step, docs/robustness.md) completes all 42 rows at
//! both tolerances (it failed on 25 rows before): worst 3.0e-6, 5.8e-8, 2.9e-7 at rtol 1e-8 and
//! 7.0e-8, 1.1e-9, 1.6e-8 at rtol 1e-10. Its rtol-1e-10 period was off by 1.0e-7 to 1.3e-7 on 5
//! rows at γ = 1e12 (the test was ignored) while the cycle analysis restarted CVODE at every
//! slip peak; see docs/robustness.md for where that error was made.

use stickslip::{engine, scene};

mod common;
use common::reference::{self, Quantity, Run, Table};

/// Bound on the relative deviation of the period and ln v_max, in units of rtol.
const PERIOD_FACTOR: f64 = 1e3;
/// Bound on the relative deviation of t0, in units of rtol.
const T0_FACTOR: f64 = 1e4;

#[test]
fn radau5_matches_the_far_table_at_rtol_1e_10() {
    check_against_table("radau5", 1e-10);
}

#[test]
fn rodas5p_matches_the_far_table_at_rtol_1e_10() {
    check_against_table("rodas5p", 1e-10);
}

#[test]
fn cvode_bdf_matches_the_far_table_at_rtol_1e_10() {
    check_against_table("cvode-bdf", 1e-10);
}

#[test]
fn radau5_matches_the_far_table_at_rtol_1e_8() {
    check_against_table("radau5", 1e-8);
}

#[test]
fn rodas5p_matches_the_far_table_at_rtol_1e_8() {
    check_against_table("rodas5p", 1e-8);
}

#[test]
fn cvode_bdf_matches_the_far_table_at_rtol_1e_8() {
    check_against_table("cvode-bdf", 1e-8);
}

/// Runs `method` at `rtol` (atol the scene default) on every agreeing row: 42 rows, the two
/// reference integrators within 1e-9 on the period.
fn check_against_table(method: &str, rtol: f64) {
    let table = Table { file: "drr_cycles_far.json", rows: 42, state_law: None, agreement: 1e-9 };
    let bounds = [
        (Quantity::Period, PERIOD_FACTOR * rtol),
        (Quantity::LnVMax, PERIOD_FACTOR * rtol),
        (Quantity::T0, T0_FACTOR * rtol),
    ];
    reference::check_against_table(&table, &bounds, &Run { method, rtol, atol: None });
}

/// Radau5 at rtol 1e-4 from v = 1e30 (γ = 1e8, ξ = 2, ε = 5; a cell of `stickslip stress
/// --quick`) reaches the cycle that Rodas5P finds at rtol 1e-10 from the default start. It used
/// to end in a typed right-hand-side failure: after the deep stick, a step collapsed below the
/// clock's spacing with one non-finite Newton iterate among its rejections, and that step
/// underflow was relabelled, so the Clock did not re-base and retry (docs/robustness.md).
#[test]
fn radau5_from_v_1e30_at_rtol_1e_4_reaches_the_cycle() {
    let run = |method: &str, rtol: f64, initial: &str| {
        let text = format!(
            r#"{{"name": "far-start", "model": {{"gamma": 1e8, "xi": 2, "epsilon": 5}}, {initial}
                "solver": {{"method": "{method}", "rtol": {rtol:e}, "atol": {:e}}},
                "analyses": [{{"cycle": {{"max_cycles": 60, "max_time": 1e23, "max_steps": 2000000}}}}]}}"#,
            rtol * 1e-2
        );
        let s = scene::parse(&text, "reference_far").unwrap();
        let report = engine::run(&s, engine::RunOptions::default())
            .unwrap_or_else(|e| panic!("{method}: {e} [{e:?}]"));
        let c = report.cycle.unwrap();
        c.values
            .unwrap_or_else(|| {
                panic!("{method}: {:?} after {} cycles", c.status, c.cycles_computed)
            })
            .main
            .period
    };
    let reference = run("rodas5p", 1e-10, "");
    let period = run("radau5", 1e-4, r#""initial": {"u": 0, "v": 1e30, "theta": 0},"#);
    let rel = (period - reference).abs() / reference;
    assert!(rel < 1e-3, "radau5 period {period} vs rodas5p {reference}: {rel:.1e}");
}
