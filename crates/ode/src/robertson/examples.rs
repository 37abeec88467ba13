//! SUNDIALS' Robertson examples (`cvode/serial/cvRoberts_dns.c`,
//! `arkode/C_serial/ark_robertson_root.c`) replayed through the safe wrappers with identical
//! settings, and their output printed as the C programs print it: crates/ode/tests/
//! sundials_examples.rs checks them against the examples' own output files; the `stickslip
//! robertson` command prints them and the robertson benchmark times them.

use super::{roots, Robertson};
use crate::integrate::{Options, SolverError, Stats, StepEvent, Task, Tolerance};
use crate::sundials::{ArkMethod, ArkSettings, CvodeSettings, Solver};

/// One printed line of an example: the time, the state and, after a root return, which roots
/// were found.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Output time.
    pub t: f64,
    /// State at `t`.
    pub y: [f64; 3],
    /// Root information after a root return.
    pub roots: Option<Vec<i32>>,
}

/// The printed rows and final statistics of one example run.
#[derive(Debug, Clone)]
pub struct ExampleRun {
    /// Printed rows, in order.
    pub rows: Vec<Row>,
    /// Final solver statistics.
    pub stats: Stats,
}

const OUTPUTS: usize = 12;

fn row(t: f64, y: &[f64], event: &StepEvent) -> Row {
    let roots = match event {
        StepEvent::Root(info) => Some(info.clone()),
        _ => None,
    };
    Row { t, y: [y[0], y[1], y[2]], roots }
}

/// Replays `cvRoberts_dns.c`: CVODE BDF, rtol 1e-4, atol (1e-8, 1e-14, 1e-6), analytic
/// Jacobian, outputs at 0.4·10^k, k = 0..11, plus the root returns.
pub fn cvode_example() -> Result<ExampleRun, SolverError> {
    let options = Options::new(1.0e-4, Tolerance::PerComponent(vec![1.0e-8, 1.0e-14, 1.0e-6]));
    let mut solver =
        Solver::cvode(Robertson, CvodeSettings::default(), 0.0, &[1.0, 0.0, 0.0], &options)?;
    solver.set_roots(Some(roots()))?;
    let mut rows = Vec::new();
    let (mut tout, mut printed) = (0.4, 0);
    while printed < OUTPUTS {
        let step = solver.advance(tout, Task::Normal)?;
        rows.push(row(step.t, solver.state(), &step.event));
        if step.event == StepEvent::Reached {
            printed += 1;
            tout *= 10.0;
        }
    }
    Ok(ExampleRun { rows, stats: solver.stats() })
}

/// Replays `ark_robertson_root.c`: ARKStep with ARKODE's default DIRK table, rtol 1e-4, atol
/// (1e-8, 1e-11, 1e-8), max 20 error-test failures, 8 nonlinear iterations, nonlinear
/// convergence coefficient 1e-7, 100000 steps, maximum-order predictor; the first row is the
/// initial condition.
pub fn arkode_example() -> Result<ExampleRun, SolverError> {
    let mut options = Options::new(1.0e-4, Tolerance::PerComponent(vec![1.0e-8, 1.0e-11, 1.0e-8]));
    options.max_err_test_fails = Some(20);
    options.max_nonlin_iters = Some(8);
    options.nonlin_conv_coef = Some(1.0e-7);
    options.max_steps = Some(100_000);
    let settings = ArkSettings { predictor_method: Some(1), ..ArkSettings::default() };
    let y0 = [1.0, 0.0, 0.0];
    let mut solver =
        Solver::arkstep(Robertson, ArkMethod::default(), settings, 0.0, &y0, &options)?;
    solver.set_roots(Some(roots()))?;
    let mut rows = vec![row(0.0, &y0, &StepEvent::Reached)];
    let mut tout = 0.4;
    for _ in 0..OUTPUTS {
        let step = solver.advance(tout, Task::Normal)?;
        rows.push(row(step.t, solver.state(), &step.event));
        tout *= 10.0;
    }
    Ok(ExampleRun { rows, stats: solver.stats() })
}

/// C's `printf("%.{precision}e")` (two-digit signed exponent), e.g. `2.6391e-01`.
pub fn c_exponential(x: f64, precision: usize) -> String {
    let s = format!("{x:.precision$e}");
    let (mantissa, exponent) = s.split_once('e').expect("Rust's {:e} always has an exponent");
    let exponent: i32 = exponent.parse().expect("Rust's exponent is an integer");
    let sign = if exponent < 0 { '-' } else { '+' };
    format!("{mantissa}e{sign}{:02}", exponent.abs())
}

/// The rows as `cvRoberts_dns` prints them.
pub fn format_cvode_rows(rows: &[Row]) -> Vec<String> {
    let mut lines = Vec::new();
    for r in rows {
        let y: Vec<String> = r.y.iter().map(|v| format!("{:>14}", c_exponential(*v, 6))).collect();
        lines.push(format!(
            "At t = {}      y ={}  {}  {}",
            c_exponential(r.t, 4),
            y[0],
            y[1],
            y[2]
        ));
        if let Some(info) = &r.roots {
            lines.push(format!("    rootsfound[] = {:>3} {:>3}", info[0], info[1]));
        }
    }
    lines
}

/// The rows as `ark_robertson_root` prints them.
pub fn format_arkode_rows(rows: &[Row]) -> Vec<String> {
    let mut lines = Vec::new();
    for r in rows {
        let cells: Vec<String> = std::iter::once(r.t)
            .chain(r.y)
            .map(|v| format!("{:>12}", c_exponential(v, 5)))
            .collect();
        lines.push(format!("  {}", cells.join("  ")));
        if let Some(info) = &r.roots {
            lines.push(format!("      rootsfound[] = {:>3} {:>3}", info[0], info[1]));
        }
    }
    lines
}
