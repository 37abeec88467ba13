//! The measured accuracy of every (problem, method, rtol): the mixed-error significant correct
//! digits of `print_table` (docs/test-set.md) less 0.5 digit, rounded down to 0.1. Re-measure
//! and update together with docs/test-set.md; never lower a value to make a run pass.

/// The three tolerances of the test set runs.
pub const RTOLS: [f64; 3] = [1e-4, 1e-7, 1e-10];

/// What a run must give.
#[derive(Debug, Clone, PartialEq)]
pub enum Expect {
    /// Success with at least this many mixed-error significant correct digits.
    Scd(f64),
}

/// Minimum scd at rtol 1e-4, 1e-7, 1e-10 (measured on 2026-11-23, see docs/test-set.md).
const MINIMUM_SCD: &[(&str, &str, [f64; 3])] = &[
    ("HIRES", "cvode-bdf", [3.0, 5.3, 8.3]),
    ("HIRES", "arkode-dirk", [5.6, 7.6, 10.4]),
    ("HIRES", "radau5", [2.8, 6.6, 9.0]),
    ("HIRES", "rodas5p", [2.3, 6.8, 10.5]),
    ("HIRES", "extrapolation", [2.2, 6.1, 8.9]),
    ("OREGO", "cvode-bdf", [1.6, 4.8, 7.5]),
    ("OREGO", "arkode-dirk", [4.3, 7.1, 9.6]),
    ("OREGO", "radau5", [4.4, 6.3, 8.7]),
    ("OREGO", "rodas5p", [3.9, 6.9, 10.1]),
    ("OREGO", "extrapolation", [2.8, 6.6, 8.3]),
    ("ROBER", "cvode-bdf", [3.6, 5.7, 9.0]),
    ("ROBER", "arkode-dirk", [9.7, 12.4, 13.1]),
    ("ROBER", "radau5", [6.2, 8.7, 11.2]),
    ("ROBER", "rodas5p", [5.9, 8.1, 10.4]),
    ("ROBER", "extrapolation", [4.3, 7.1, 10.2]),
    ("E5", "cvode-bdf", [3.1, 7.4, 10.5]),
    ("E5", "arkode-dirk", [4.7, 7.4, 9.3]),
    ("E5", "radau5", [4.2, 7.9, 11.0]),
    ("E5", "rodas5p", [3.4, 6.5, 10.2]),
    // Measured on 2026-11-25 with the rounding test of the linearly implicit rows (before: a
    // known wrong answer, 0.08 / 2.01 / 6.08 digits reported as success).
    ("E5", "extrapolation", [3.7, 7.1, 9.3]),
    ("POLLU", "cvode-bdf", [3.1, 6.1, 8.2]),
    ("POLLU", "arkode-dirk", [6.4, 8.7, 11.1]),
    ("POLLU", "radau5", [2.4, 4.5, 7.0]),
    ("POLLU", "rodas5p", [5.2, 7.6, 10.2]),
    ("POLLU", "extrapolation", [4.2, 7.8, 9.3]),
    ("VDPOL", "cvode-bdf", [2.5, 5.0, 7.8]),
    ("VDPOL", "arkode-dirk", [4.7, 7.7, 10.6]),
    ("VDPOL", "radau5", [4.9, 7.6, 10.0]),
    ("VDPOL", "rodas5p", [4.1, 6.7, 9.7]),
    ("VDPOL", "extrapolation", [3.5, 6.7, 9.6]),
    ("MEDAKZO", "cvode-bdf", [2.3, 5.1, 8.1]),
    ("MEDAKZO", "arkode-dirk", [5.6, 7.8, 9.3]),
    ("MEDAKZO", "radau5", [3.3, 6.0, 8.7]),
    ("MEDAKZO", "rodas5p", [4.3, 6.3, 9.0]),
    ("MEDAKZO", "extrapolation", [2.6, 6.1, 8.6]),
];

/// Where the linked SUNDIALS genuinely gives a different result, from 6.7.0 on (Debian 13's
/// 7.1.1), measured on 2026-11-24 and replacing the row of `MINIMUM_SCD` above.
///
/// ROBER with ARKStep's DIRK (SDIRK-5-3-4, stiffly accurate): SUNDIALS 6.7.0 (commit
/// e659bb8, "Update Full RHS Calls") made `arkStep_ComputeSolutions` return the last stage z_s
/// as y_{n+1} for a stiffly accurate table, where 6.4.1 formed y_n + h Σ b_j f_I(z_j) from the
/// evaluated stage derivatives. The two differ by the Newton stopping error of the last stage,
/// which 7.x keeps in the solution; no ARKODE option restores the 6.x formula. Measured on
/// 7.1.1: 8.70, 10.59 and 13.62 digits (2336, 5410, 79717 steps) against 10.20, 12.96 and
/// 13.61 on 6.4.1. The same 7.1.1 library with that one line reverted gives 10.20 and 12.96
/// in 2790 and 5635 steps, 6.4.1's digits and step counts exactly; with a 1000× tighter
/// Newton tolerance (1e-10) 7.1.1 gets 10.66 and 14.17. See docs/debian.md.
const MINIMUM_SCD_SINCE_6_7: &[(&str, &str, [f64; 3])] =
    &[("ROBER", "arkode-dirk", [8.2, 10.0, 13.1])];

/// Whether the linked SUNDIALS is 6.7.0 or newer.
fn sundials_since_6_7() -> bool {
    let version = stickslip_ode::sundials::version();
    let mut parts = version.split('.').map(|p| p.parse::<u32>().unwrap_or(0));
    let (major, minor) = (parts.next().unwrap_or(0), parts.next().unwrap_or(0));
    (major, minor) >= (6, 7)
}

/// The expectation of one cell.
pub fn expectation(problem: &str, method: &str, rtol: f64) -> Expect {
    let index = RTOLS.iter().position(|r| *r == rtol).expect("one of RTOLS");
    let by_version = if sundials_since_6_7() { MINIMUM_SCD_SINCE_6_7 } else { &[] };
    let (_, _, minimum) = by_version
        .iter()
        .chain(MINIMUM_SCD)
        .find(|(p, m, _)| *p == problem && *m == method)
        .unwrap_or_else(|| panic!("no expectation for {problem} {method}"));
    Expect::Scd(minimum[index])
}

/// Cells of more than about a second each (dense LU of MEDAKZO's 400 equations; ARKStep's DIRK
/// at rtol 1e-10, which takes 1e5 steps and more): run by the ignored `slow_cells` test.
pub fn is_slow(problem: &str, method: &str, rtol: f64) -> bool {
    (problem == "MEDAKZO" && (rtol < 1e-4 || method == "arkode-dirk"))
        || (method == "arkode-dirk" && rtol < 1e-7 && problem != "POLLU" && problem != "HIRES")
}
