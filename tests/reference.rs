//! The engine at rtol 1e-10 against the reference table (data/reference/drr_cycles.json, two
//! independent integrators at rtol 1e-11 that agree to 6e-9 on the period).

mod common;
use common::reference::{check_against_table, Run, Table, BOUNDS};

/// The slip law's table: 16 rows, the two reference integrators within 1e-8 on the period.
const TABLE: Table = Table { file: "drr_cycles.json", rows: 16, state_law: None, agreement: 1e-8 };

#[test]
fn engine_matches_the_reference_table() {
    check("cvode-bdf");
}

#[test]
fn radau5_matches_the_reference_table() {
    check("radau5");
}

#[test]
fn rodas5p_matches_the_reference_table() {
    check("rodas5p");
}

/// `method` at rtol 1e-10, atol 1e-12 against the table.
fn check(method: &str) {
    check_against_table(&TABLE, &BOUNDS, &Run { method, rtol: 1e-10, atol: Some(1e-12) });
}
