//! The homemade Rosenbrock integrator Rodas5P: the autonomous declaration, its dense
//! derivatives and Jacobian counts and the failures its own knobs produce (the orders,
//! Prothero–Robinson, VDPOL and dense output are tests/methods.rs, run over every homemade
//! method; the Integrator contract is tests/contract.rs, run over every method; the model cells
//! it once failed on are the workspace's tests/integrators_on_model.rs). Mirrors tests/radau5.rs.

use stickslip_ode::integrate::{
    ErrorKind, Integrator, JacobianMatrix, OdeSystem, Options, Rodas5p, Task, Tolerance,
};

mod common;
use common::{Linear, NanAfter, Oscillator, Tan, Warped};

fn fixed_options(tend: f64) -> Options {
    Options {
        stop_time: Some(tend),
        max_steps: Some(100_000),
        ..Options::new(1e-13, Tolerance::Scalar(1e-13))
    }
}

fn rodas<S: OdeSystem>(system: S, y0: &[f64], tend: f64) -> Rodas5p<S> {
    Rodas5p::new(system, 0.0, y0, &fixed_options(tend)).unwrap()
}

/// On an autonomous system the finite-difference ∂f/∂t is exactly zero: declaring the system
/// autonomous changes nothing but the number of right-hand-side calls (fixed steps).
#[test]
fn declaring_the_system_autonomous_saves_only_the_time_derivative() {
    let plain = rodas(Warped, &Warped::exact(0.0), 2.0).fixed_step(0.1);
    let declared = rodas(Warped, &Warped::exact(0.0), 2.0).autonomous().fixed_step(0.1);
    let mut runs = [plain, declared];
    for r in &mut runs {
        r.advance(3.0, Task::Normal).unwrap();
    }
    assert_eq!(runs[0].state(), runs[1].state());
    let (a, b) = (runs[0].stats(), runs[1].stats());
    assert_eq!((a.steps, a.rhs_evals, a.jac_evals), (b.steps, b.rhs_evals, b.jac_evals));
    assert_eq!(
        a.rhs_evals_jacobian,
        b.rhs_evals_jacobian + a.jac_evals,
        "one ∂f/∂t call per Jacobian"
    );
    assert_eq!(
        a.rhs_evals,
        8 * a.steps + 1,
        "7 stages + f at the new point per step, f(t0, y0) once"
    );
}

/// Rodas5P's own part of the contract (the rest, restarts included, is tests/contract.rs, over
/// every method): the quartic's derivatives up to the fourth and the Jacobian's count (one a
/// step, no Newton iteration).
#[test]
fn dense_derivatives_and_jacobian_counts() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    let mut solver = Rodas5p::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap();
    assert_eq!(solver.name(), "rodas5p");
    // Before any step: the derivative at t0 only up to the first.
    assert_eq!(solver.dense(0.0, 2).unwrap_err().kind, ErrorKind::InvalidInput);
    solver.advance(1.0, Task::Normal).unwrap();
    let end = solver.advance(10.0, Task::OneStep).unwrap().t;
    let (y, dy) = (solver.state().to_vec(), solver.dense(end, 1).unwrap().to_vec());
    assert!((y[0] - end.sin()).abs() < 1e-7 && (dy[0] - end.cos()).abs() < 1e-6, "{y:?} {dy:?}");
    // Derivatives up to the quartic's fourth; k = 5 is refused.
    let d4 = solver.dense(end, 4).unwrap().to_vec();
    assert!((d4[0] - end.sin()).abs() < 0.1 && (d4[1] - end.cos()).abs() < 0.1, "{d4:?}");
    assert_eq!(solver.dense(end, 5).unwrap_err().kind, ErrorKind::InvalidInput);

    // Finite-difference Jacobian: n RHS calls per Jacobian plus one for ∂f/∂t, counted apart.
    let s = solver.stats();
    assert!(s.jac_evals > 0 && s.rhs_evals_jacobian == 3 * s.jac_evals, "{s:?}");
    assert_eq!(s.jac_evals, s.steps, "{s:?}");
    assert_eq!(s.nonlin_iters, 0);
}

#[test]
fn failures_specific_to_rodas5p() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));

    // NaN from t > 0.5 on (the typed error: tests/contract.rs): halved steps do not help;
    // the error comes after 10 of them.
    let mut solver = Rodas5p::new(NanAfter(0.5), 0.0, &[1.0], &options).unwrap();
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::RhsFailure);
    assert!(solver.stats().nonfinite_rhs >= 10);
    // NaN with a fixed step: no escape.
    let mut fixed = Rodas5p::new(NanAfter(0.5), 0.0, &[1.0], &options).unwrap().fixed_step(0.3);
    assert_eq!(fixed.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::RhsFailure);

    // A singular matrix: y' = λy with λ = 1/(γh) exactly (fixed step, no escape).
    let h = 0.5;
    let gamma = 0.21193756319429014;
    let mut solver =
        Rodas5p::new(Linear(1.0 / (gamma * h)), 0.0, &[1.0], &options).unwrap().fixed_step(h);
    let e = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::LinearSolver, "{e}");
    // Adaptive steps escape the same singularity by halving h.
    let adaptive = Options { initial_step: Some(h), ..options.clone() };
    let mut adaptive = Rodas5p::new(Linear(1.0 / (gamma * h)), 0.0, &[1.0], &adaptive).unwrap();
    adaptive.advance(0.1, Task::Normal).unwrap();

    // Repeated error-test failures: a tiny budget of rejections with a huge first step.
    let strict =
        Options { max_err_test_fails: Some(1), initial_step: Some(10.0), ..options.clone() };
    let mut solver = Rodas5p::new(Tan, 0.0, &[0.0], &strict).unwrap();
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::ErrorTestFailures);
    // ... or a minimum step that is too large.
    let floor = Options { min_step: Some(0.5), ..options.clone() };
    let mut solver = Rodas5p::new(Tan, 0.0, &[0.0], &floor).unwrap();
    assert_eq!(solver.advance(1.5, Task::Normal).unwrap_err().kind, ErrorKind::ErrorTestFailures);

    // Time too large for the steps the problem needs: t + h = t.
    let mut solver = Rodas5p::new(Linear(-1.0), 1e20, &[1.0], &options).unwrap();
    let e = solver.advance(1e20 + 1e6, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::StepUnderflow, "{e}");

    // A Jacobian that is not finite.
    struct BadJacobian;
    impl OdeSystem for BadJacobian {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
            dydt[0] = -y[0];
        }
        fn has_jacobian(&self) -> bool {
            true
        }
        fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
            jac.set(0, 0, f64::INFINITY);
        }
    }
    let e = Rodas5p::new(BadJacobian, 0.0, &[1.0], &options)
        .unwrap()
        .advance(1.0, Task::Normal)
        .unwrap_err();
    assert_eq!(e.kind, ErrorKind::RhsFailure, "{e}");

    // A negative fixed step.
    let mut solver = Rodas5p::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap().fixed_step(-1.0);
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::InvalidInput);
}
