//! The homemade Radau IIA (order 5) integrator: its dense derivatives and Jacobian counts, and
//! the failures its own knobs produce (the orders, Prothero–Robinson, VDPOL and dense output
//! are tests/methods.rs, run over every homemade method; the Integrator contract is
//! tests/contract.rs, run over every method; the library's model at γ = 1e8 is the workspace's
//! tests/integrators_on_model.rs).

use stickslip_ode::integrate::{
    ErrorKind, Integrator, Options, Radau5, Task, Tolerance, ToleranceTransform,
};

mod common;
use common::{Linear, NanAfter, Oscillator};

/// Radau5's own part of the contract (the rest, restarts included, is tests/contract.rs, over
/// every method): the cubic's derivatives up to the third and the finite-difference Jacobian's
/// count.
#[test]
fn dense_derivatives_and_jacobian_counts() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    let mut solver = Radau5::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap();
    assert_eq!(solver.name(), "radau5");
    solver.advance(1.0, Task::Normal).unwrap();
    let end = solver.advance(10.0, Task::OneStep).unwrap().t;
    let (y, dy) = (solver.state().to_vec(), solver.dense(end, 1).unwrap().to_vec());
    assert!((y[0] - end.sin()).abs() < 1e-7 && (dy[0] - end.cos()).abs() < 1e-6, "{y:?} {dy:?}");
    // Derivatives up to the cubic's third; k = 4 is refused.
    assert!(solver.dense(end, 3).is_ok());
    assert_eq!(solver.dense(end, 4).unwrap_err().kind, ErrorKind::InvalidInput);

    // Finite-difference Jacobian: n RHS calls per Jacobian, counted apart.
    let s = solver.stats();
    assert!(s.jac_evals > 0 && s.rhs_evals_jacobian == 2 * s.jac_evals, "{s:?}");
}

/// The two readings of the tolerances: as given at (rtol, atol) the run is more accurate than
/// with RADAU5's transform (which loosens rtol 1e-8 to 4.6e-7), within a few rtol of the
/// solution, and its Newton iteration never stops before its second iteration (scipy's rule),
/// where RADAU5's stops after one on most steps of this smooth problem.
#[test]
fn tolerances_as_given_or_transformed() {
    let run = |transform| {
        let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
        let mut solver =
            Radau5::with_tolerances(Oscillator, 0.0, &[0.0, 1.0], &options, transform).unwrap();
        solver.advance(20.0, Task::Normal).unwrap();
        (solver.state().to_vec(), solver.stats())
    };
    let (hairer, as_given) = (run(ToleranceTransform::Hairer), run(ToleranceTransform::AsGiven));
    let default = {
        let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
        let mut solver = Radau5::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap();
        solver.advance(20.0, Task::Normal).unwrap();
        solver.state().to_vec()
    };
    assert_eq!(default, hairer.0, "Radau5::new is RADAU5's transform");
    let error = |y: &[f64]| (y[0] - 20f64.sin()).abs().max((y[1] - 20f64.cos()).abs());
    assert!(as_given.1.steps > 2 * hairer.1.steps, "{:?} {:?}", as_given.1, hairer.1);
    assert!(
        error(&as_given.0) < 1e-7 && error(&as_given.0) < 0.1 * error(&hairer.0),
        "as given {:e}, transformed {:e}",
        error(&as_given.0),
        error(&hairer.0)
    );
    let (a, h) = (as_given.1, hairer.1);
    assert!(a.nonlin_iters >= 2 * a.step_attempts, "{a:?}");
    assert!(h.nonlin_iters < 2 * h.step_attempts, "{h:?}");
}

#[test]
fn failures_specific_to_radau5() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));

    // NaN from t > 0.5 on (the typed error: tests/contract.rs): halved steps do not help;
    // the error comes after 10 of them.
    let mut solver = Radau5::new(NanAfter(0.5), 0.0, &[1.0], &options).unwrap();
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::RhsFailure);
    assert!(solver.stats().nonfinite_rhs >= 10);

    // A singular iteration matrix: y' = λy with λ = γ/h exactly (fixed step, no escape).
    let h = 0.5;
    let gamma = 1.0 / ((6.0 + 81f64.cbrt() - 9f64.cbrt()) / 30.0);
    let mut solver = Radau5::new(Linear(gamma / h), 0.0, &[1.0], &options).unwrap().fixed_step(h);
    let e = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::LinearSolver, "{e}");
    // Adaptive steps escape the same singularity by halving h.
    let mut adaptive = Radau5::new(
        Linear(gamma / h),
        0.0,
        &[1.0],
        &Options { initial_step: Some(h), ..options.clone() },
    )
    .unwrap();
    adaptive.advance(0.1, Task::Normal).unwrap();

    // Newton limited to one iteration with a fixed, large step.
    let one_iteration = Options { max_nonlin_iters: Some(1), ..options.clone() };
    let mut solver =
        Radau5::new(Oscillator, 0.0, &[0.0, 1.0], &one_iteration).unwrap().fixed_step(0.5);
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::ConvergenceFailures);

    // Time too large for the steps the problem needs: t + h = t.
    let mut solver = Radau5::new(Linear(-1.0), 1e20, &[1.0], &options).unwrap();
    let e = solver.advance(1e20 + 1e6, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::StepUnderflow, "{e}");

    // A negative fixed step.
    let mut solver = Radau5::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap().fixed_step(-1.0);
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::InvalidInput);
}
