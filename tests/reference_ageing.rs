//! The engine at rtol 1e-10 against the ageing-law reference table
//! (data/reference/drr_cycles_ageing.json: radau5 and ARKStep DIRK at rtol 1e-11, built by
//! `cargo run --release --example reference_table -- ageing`), with the methods that
//! tests/reference.rs checks on the slip law's table, and cvode-bdf (which failed in the ageing
//! law's deep stick from γ ≈ 1e4 until the engine gave it a fresh Jacobian at every step).

mod common;
use common::reference::{check_against_table, Run, Table, BOUNDS};

/// The ageing law's table: 16 rows, each naming the ageing law, the two reference integrators
/// within 1e-8 on the period.
const TABLE: Table =
    Table { file: "drr_cycles_ageing.json", rows: 16, state_law: Some("ageing"), agreement: 1e-8 };

#[test]
fn radau5_matches_the_ageing_reference_table() {
    check("radau5");
}

#[test]
fn rodas5p_matches_the_ageing_reference_table() {
    check("rodas5p");
}

#[test]
fn cvode_bdf_matches_the_ageing_reference_table() {
    check("cvode-bdf");
}

/// `method` at rtol 1e-10, atol 1e-12 against the table.
fn check(method: &str) {
    check_against_table(&TABLE, &BOUNDS, &Run { method, rtol: 1e-10, atol: Some(1e-12) });
}
