//! The standard stiff test set as tests: HIRES, OREGO, ROBER, E5, POLLU, VDPOL (ε = 1e-6) and
//! MEDAKZO (400 equations) from the Test Set for IVP Solvers (Mazzia & Magherini, Bari,
//! release 2.4), solved by every stiff method of stickslip at rtol 1e-4, 1e-7 and 1e-10 against
//! the published reference solutions. Each (problem, method, tolerance) asserts the mixed-error
//! significant correct digits measured for it (minus 0.5 digit of margin), or the typed error
//! the method returns; see docs/test-set.md for the table and the reasons.
//!
//! Print the measured table: `cargo test --release -p stickslip-ode --test test_set -- --ignored --nocapture print_table`.
//! The slow cells (MEDAKZO below rtol 1e-4, ARKStep's DIRK at 1e-10) run with
//! `cargo test --release -p stickslip-ode --test test_set -- --ignored slow_cells`.

// The reference values are quoted digit for digit from the Test Set's solut routines.
#![allow(clippy::excessive_precision)]

mod e5;
mod expected;
mod hires;
mod library_user;
mod medakzo;
mod orego;
mod pollu;
mod problem;
mod rober;
mod vdpol;

use e5::E5;
pub use expected::RTOLS;
use expected::{expectation, is_slow, Expect};
use hires::Hires;
use medakzo::Medakzo;
use orego::Orego;
use pollu::Pollu;
use problem::{run, scd_of, TestProblem, MEASURED};
use rober::Rober;
use stickslip_ode::integrate::{ErrorKind, JacobianMatrix};
use stickslip_ode::solver::Method;
use vdpol::Vdpol;

/// One measured cell: the scd, or the error kind and message.
struct Cell {
    problem: &'static str,
    method: Method,
    rtol: f64,
    outcome: Result<(f64, problem::Run), (ErrorKind, String)>,
}

fn measure<P: TestProblem>(method: Method, rtol: f64) -> Cell {
    let outcome = match run::<P>(method, rtol) {
        Ok(r) => Ok((scd_of::<P>(&r.y, rtol), r)),
        Err(e) => Err((e.kind.clone(), e.to_string())),
    };
    Cell { problem: P::NAME, method, rtol, outcome }
}

/// Which cells to measure.
#[derive(Clone, Copy, PartialEq)]
enum Which {
    Fast,
    Slow,
    All,
}

fn measure_all<P: TestProblem>(cells: &mut Vec<Cell>, methods: &[Method], which: Which) {
    for &method in methods {
        for rtol in RTOLS {
            let slow = is_slow(P::NAME, method.name(), rtol);
            if which == Which::All || slow == (which == Which::Slow) {
                cells.push(measure::<P>(method, rtol));
            }
        }
    }
}

/// Every problem with `methods`.
fn measure_problems(methods: &[Method], which: Which) -> Vec<Cell> {
    let mut cells = Vec::new();
    measure_all::<Hires>(&mut cells, methods, which);
    measure_all::<Orego>(&mut cells, methods, which);
    measure_all::<Rober>(&mut cells, methods, which);
    measure_all::<E5>(&mut cells, methods, which);
    measure_all::<Pollu>(&mut cells, methods, which);
    measure_all::<Vdpol>(&mut cells, methods, which);
    measure_all::<Medakzo>(&mut cells, methods, which);
    cells
}

fn check(cells: &[Cell]) {
    let mut failures = Vec::new();
    for c in cells {
        let expected = expectation(c.problem, c.method.name(), c.rtol);
        let ok = match (&expected, &c.outcome) {
            (Expect::Scd(min), Ok((scd, _))) => scd >= min,
            _ => false,
        };
        if !ok {
            let got = match &c.outcome {
                Ok((scd, r)) => format!("scd {scd:.2} ({} steps)", r.stats.steps),
                Err((_, m)) => m.chars().take(300).collect(),
            };
            failures.push(format!(
                "{} {} rtol {:e}: expected {expected:?}, got {got}",
                c.problem,
                c.method.name(),
                c.rtol
            ));
        }
    }
    assert!(failures.is_empty(), "{} cells off:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn cvode_bdf_on_the_test_set() {
    check(&measure_problems(&[Method::CvodeBdf], Which::Fast));
}

#[test]
fn arkode_dirk_on_the_test_set() {
    check(&measure_problems(&[Method::ArkodeDirk], Which::Fast));
}

#[test]
fn radau5_on_the_test_set() {
    check(&measure_problems(&[Method::Radau5], Which::Fast));
}

#[test]
fn rodas5p_on_the_test_set() {
    check(&measure_problems(&[Method::Rodas5p], Which::Fast));
}

#[test]
fn extrapolation_on_the_test_set() {
    check(&measure_problems(&[Method::Extrapolation], Which::Fast));
}

/// The cells of more than about a second each (see `expected::is_slow`), about 4 minutes:
/// `cargo test --release -p stickslip-ode --test test_set -- --ignored slow_cells`.
#[test]
#[ignore = "about 4 minutes; run with --ignored"]
fn slow_cells() {
    check(&measure_problems(&MEASURED, Which::Slow));
}

/// The extrapolation method kept E5's mass balance y₂ = y₃ + y₄ only to about 1e-20 (rtol
/// 1e-4), so y₃ ended near 1.4e-20 instead of 8.9e-23 while it reported success: the rows'
/// rounding errors in f, amplified by the extrapolation weights. The rounding test of the
/// linearly implicit rows (src/integrate/extrapolation/rounding.rs) now bounds them by the
/// absolute tolerance; the balance ends at 1.5e-24 (docs/test-set.md).
#[test]
fn extrapolation_e5_mass_balance() {
    for rtol in RTOLS {
        let run = run::<E5>(Method::Extrapolation, rtol).unwrap();
        let scd = scd_of::<E5>(&run.y, rtol);
        assert!(scd > 3.0, "rtol {rtol:e}: scd {scd:.2}, y = {:?}", run.y);
        let balance = run.y[1] - run.y[2] - run.y[3];
        assert!(balance.abs() < 2e-23, "rtol {rtol:e}: y2 − y3 − y4 = {balance:e}");
    }
}

/// Prints problem, method, rtol, scd, steps, RHS evaluations, Jacobians, LU factorisations and
/// wall time of every cell (the table of docs/test-set.md).
#[test]
#[ignore = "prints the work–precision table; run with --ignored --nocapture"]
fn print_table() {
    println!("| problem | method | rtol | scd | steps | f evals | J evals | LU | time (ms) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for c in measure_problems(&MEASURED, Which::All) {
        match &c.outcome {
            Ok((scd, r)) => {
                let s = r.stats;
                println!(
                    "| {} | {} | {:.0e} | {scd:.2} | {} | {} | {} | {} | {:.2} |",
                    c.problem,
                    c.method.name(),
                    c.rtol,
                    s.steps,
                    s.rhs_evals + s.rhs_evals_jacobian,
                    s.jac_evals,
                    s.lin_setups,
                    r.wall.as_secs_f64() * 1e3
                );
            }
            Err((kind, message)) => {
                println!(
                    "| {} | {} | {:.0e} | {kind:?} | | | | | | {}",
                    c.problem,
                    c.method.name(),
                    c.rtol,
                    message
                );
            }
        }
    }
}

/// The analytic Jacobian of `P` against central differences of its right-hand side at a
/// state near the initial one.
fn jacobian_matches<P: TestProblem>() {
    let system = P::new();
    let n = system.dim();
    let y: Vec<f64> = P::y0()
        .iter()
        .enumerate()
        .map(|(i, v)| v + 1e-3 * (1.0 + 0.1 * i as f64) * (1.0 + v.abs()))
        .collect();
    let mut storage = vec![0.0; n * n];
    let mut jac = JacobianMatrix::new(&mut storage, n);
    system.jacobian(1.0, &y, &mut jac);
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    for col in 0..n {
        let h = 1e-6 * (1.0 + y[col].abs());
        let (mut yp, mut ym) = (y.clone(), y.clone());
        yp[col] += h;
        ym[col] -= h;
        system.rhs(1.0, &yp, &mut fp);
        system.rhs(1.0, &ym, &mut fm);
        for row in 0..n {
            let fd = (fp[row] - fm[row]) / (2.0 * h);
            let an = jac.get(row, col);
            // Differences of a row lose digits to its largest terms: allow 1e-9 of the row.
            let row_scale = (0..n).map(|c| jac.get(row, c).abs()).fold(0.0, f64::max);
            let tolerance = 1e-5 * an.abs().max(fd.abs()) + 1e-9 * row_scale + 1e-12;
            assert!(
                (an - fd).abs() <= tolerance,
                "{} J[{row}][{col}]: analytic {an:e}, differences {fd:e}",
                P::NAME
            );
        }
    }
}

#[test]
fn analytic_jacobians_match_differences() {
    jacobian_matches::<Hires>();
    jacobian_matches::<Orego>();
    jacobian_matches::<Rober>();
    jacobian_matches::<E5>();
    jacobian_matches::<Pollu>();
    jacobian_matches::<Vdpol>();
    jacobian_matches::<Medakzo>();
}

/// E5's mass balance y₂ = y₃ + y₄ (f₂ − f₃ − f₄ = 0) decides its end state: y₂ and y₃ decay as
/// 1/(1.13e9·t) to 8.9e-23 while y₃ tends to −(y₂ − y₃ − y₄), so an offset of the balance of
/// 1e-19 leaves y₃ a thousand times too large. Rodas5P's stage solves refined with a compensated
/// residual keep the balance to the absolute tolerance 1.7e-24 (before: −8.6e-20, y₃ = 8.6e-20).
#[test]
fn e5_mass_balance_kept_by_rodas5p() {
    let run = run::<E5>(Method::Rodas5p, 1e-4).unwrap();
    let y = &run.y;
    let reference = E5::reference();
    let balance = y[1] - y[2] - y[3];
    assert!(balance.abs() < 2e-23, "y2 − y3 − y4 = {balance:e}");
    for i in [1, 2] {
        let relative = (y[i] - reference[i]).abs() / reference[i];
        assert!(relative < 0.1, "y{} = {:e}, reference {:e}", i + 1, y[i], reference[i]);
    }
}
