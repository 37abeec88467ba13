//! Integrating your own stiff system with every stiff method of stickslip (docs/library.md).
//!
//! The system is Prothero and Robinson's test equation next to a slow decay,
//!
//! ```text
//! y0' = λ (y0 − sin t) + cos t,   y1' = −y1,   λ = −1e6,   y(0) = (0, 1),
//! ```
//!
//! whose solution is y = (sin t, e^(−t)) exactly: a stiff component that tracks a slow
//! manifold (as ln v does on the stick of the spring-slider) and a smooth one. Each method
//! integrates it to t = 10 at rtol 1e-8 with outputs at t = 1, 2, …, 10, then to a stop time
//! at 10.25, and must match the exact solution to 1e3·rtol there and in its dense output. The example also shows the
//! statistics, a root (CVODE and ARKStep), a typed error and an option a method rejects.
//! It exits with status 1 if any check fails (CI runs it: tools/test.sh).
//!
//!     cargo run --release --example own_system

use std::process::ExitCode;
use stickslip::integrate::{
    ErrorKind, ImexSystem, Integrator, JacobianMatrix, OdeSystem, Options, Radau5, Rodas5p, Roots,
    SolverError, StepEvent, Task, Tolerance,
};
use stickslip::solver::{self, Method, MethodSettings};
use stickslip::sundials::{CvodeSettings, Solver};

/// The test system, with its analytic Jacobian (without one, the implicit methods build it by
/// finite differences).
#[derive(Clone, Copy)]
struct ProtheroRobinson {
    lambda: f64,
}

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        2
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = self.lambda * (y[0] - t.sin()) + t.cos();
        dydt[1] = -y[1];
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, self.lambda);
        jac.set(1, 1, -1.0);
    }
}

fn exact(t: f64) -> [f64; 2] {
    [t.sin(), (-t).exp()]
}

/// The split for ARKStep's IMEX methods: the stiff relaxation implicit, the rest explicit.
impl ImexSystem for ProtheroRobinson {
    fn rhs_explicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = t.cos();
        dydt[1] = -y[1];
    }

    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = self.lambda * (y[0] - t.sin());
        dydt[1] = 0.0;
    }

    fn has_implicit_jacobian(&self) -> bool {
        true
    }

    fn implicit_jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, self.lambda);
    }
}

/// Builds `method` on `system` at (0, y0): the one constructor for every method
/// (`solver::build`; `solver::build_ode` for a system without an IMEX split). Every one
/// returns a typed error on bad input or an unsupported option.
fn build(
    method: Method,
    system: ProtheroRobinson,
    y0: &[f64],
    options: &Options,
) -> Result<Box<dyn Integrator>, SolverError> {
    Ok(solver::build(method, &MethodSettings::default(), system, 0.0, y0, options)?.integrator)
}

/// Relative error against the exact solution (absolute below 1).
fn error(y: &[f64], t: f64) -> f64 {
    let e = exact(t);
    (0..2).map(|i| (y[i] - e[i]).abs() / e[i].abs().max(1.0)).fold(0.0, f64::max)
}

fn main() -> ExitCode {
    let system = ProtheroRobinson { lambda: -1e6 };
    let rtol = 1e-8;
    let options = Options::new(rtol, Tolerance::Scalar(1e-10));
    let bound = 1e3 * rtol;
    let mut failures = Vec::new();

    for method in Method::ALL.iter().map(|(_, m)| *m).filter(|m| m.is_stiff()) {
        let mut integ = match build(method, system, &[0.0, 1.0], &options) {
            Ok(i) => i,
            Err(e) => {
                failures.push(format!("{method}: {e}"));
                continue;
            }
        };
        let mut worst: f64 = 0.0;
        // The same stop-time call on every method (set before the integration passes it: the
        // one-step methods step past an output time and interpolate back).
        if let Err(e) = integ.set_stop_time(10.25) {
            failures.push(format!("{method}: {e}"));
        }
        for k in 1..=10 {
            // Task::Normal returns the state at tout (interpolated from the last step).
            match integ.advance(k as f64, Task::Normal) {
                Ok(step) => worst = worst.max(error(integ.state(), step.t)),
                Err(e) => {
                    failures.push(format!("{method}: {e}"));
                    break;
                }
            }
        }
        // The step ends exactly at the stop time.
        match integ.advance(20.0, Task::Normal) {
            Ok(step) if step.event == StepEvent::StopTime && step.t == 10.25 => {
                worst = worst.max(error(integ.state(), step.t))
            }
            other => failures.push(format!("{method}: stop time 10.25 gave {other:?}")),
        }
        if integ.set_stop_time(f64::NAN).map_err(|e| e.kind) != Err(ErrorKind::InvalidInput) {
            failures.push(format!("{method}: a NaN stop time was accepted"));
        }
        // One internal step, then the dense output inside it (value and first derivative).
        let start = integ.t();
        let dense_error = match integ.advance(start + 1.0, Task::OneStep) {
            Ok(step) => {
                let mid = 0.5 * (start + step.t);
                let y = integ.dense(mid, 0).map(|y| error(y, mid)).unwrap_or(f64::INFINITY);
                let dy = integ
                    .dense(mid, 1)
                    .map(|d| (d[1] + (-mid).exp()).abs())
                    .unwrap_or(f64::INFINITY);
                y.max(dy)
            }
            Err(e) => {
                failures.push(format!("{method}: {e}"));
                f64::INFINITY
            }
        };
        let s = integ.stats();
        println!(
            "{method:13} error at t = 1…10.25: {worst:.1e}, dense output: {dense_error:.1e}; {} steps, {} RHS, {} Jacobians, {} error-test failures",
            s.steps, s.rhs_evals, s.jac_evals, s.err_test_fails
        );
        if !(worst <= bound && dense_error <= bound) {
            failures.push(format!(
                "{method}: error {worst:.1e} (dense {dense_error:.1e}) above {bound:.0e}"
            ));
        }
    }

    // Roots (CVODE and ARKStep): the first time y1 = e^(−t) falls through 1/2, at t = ln 2.
    let mut cvode = Solver::cvode(system, CvodeSettings::default(), 0.0, &[0.0, 1.0], &options)
        .expect("valid input");
    cvode.set_roots(Some(Roots::new(1, |_t, y, g| g[0] = y[1] - 0.5))).expect("one root function");
    match cvode.advance(10.0, Task::Normal) {
        Ok(step)
            if matches!(step.event, StepEvent::Root(_)) && (step.t - 2f64.ln()).abs() < 1e-7 =>
        {
            println!("cvode-bdf root: y1 = 1/2 at t = {:.10} (ln 2 = {:.10})", step.t, 2f64.ln());
        }
        other => failures.push(format!("cvode-bdf root: expected t = ln 2, got {other:?}")),
    }

    // A typed error: too small a step budget says where it stopped and why.
    let tight = Options { max_steps: Some(5), ..options.clone() };
    let mut radau = Radau5::new(system, 0.0, &[0.0, 1.0], &tight).expect("valid input");
    match radau.advance(10.0, Task::Normal) {
        Err(e) if e.kind == ErrorKind::TooMuchWork => println!("radau5 with max_steps = 5: {e}"),
        other => failures.push(format!("radau5 max_steps: expected TooMuchWork, got {other:?}")),
    }

    // An option a method does not have is an error, never ignored.
    let ordered = Options { max_order: Some(3), ..options.clone() };
    match Rodas5p::new(system, 0.0, &[0.0, 1.0], &ordered) {
        Err(e) if e.kind == ErrorKind::InvalidInput => println!("rodas5p with max_order: {e}"),
        Err(e) => failures.push(format!("rodas5p max_order: expected InvalidInput, got {e}")),
        Ok(_) => failures.push("rodas5p accepted max_order".into()),
    }

    if failures.is_empty() {
        println!("all checks passed");
        ExitCode::SUCCESS
    } else {
        for f in &failures {
            eprintln!("FAILED: {f}");
        }
        ExitCode::FAILURE
    }
}
