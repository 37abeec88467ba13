//! The `Integrator` contract, written once and run over every method through the one
//! constructor (`solver::build`): output times, the stop time, restarts, typed errors.
//! Method-specific behaviour (orders, fixed steps, Jacobian counts, the highest derivative of
//! the dense output, failures that need a method's own knobs) is in tests/methods.rs (one
//! table over the methods) and each method's own tests (tests/radau5.rs, rodas5p.rs,
//! extrapolation.rs, wrappers.rs).

use std::cell::Cell;
use stickslip_ode::integrate::{
    ErrorKind, ImexSystem, Integrator, JacobianMatrix, OdeSystem, Options, SolverError, Step,
    StepEvent, Task, Tolerance,
};
use stickslip_ode::solver::{self, Method, MethodSettings};

/// y0' = y1, y1' = −y0 from (0, 1): y = (sin t, cos t). All of it implicit in the IMEX split.
#[derive(Clone, Copy)]
struct Oscillator;

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[1];
        dydt[1] = -y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 1, 1.0);
        jac.set(1, 0, -1.0);
    }
}

/// y' = −y, with NaN once t passes `from`. All of it implicit in the IMEX split.
#[derive(Clone, Copy)]
struct NanAfter(f64);

impl OdeSystem for NanAfter {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = if t > self.0 { f64::NAN } else { -y[0] };
    }
}

/// `ImexSystem` for the test systems: all of it implicit (f_E = 0, f_I = f, with the system's
/// Jacobian when it has one).
macro_rules! all_implicit {
    ($($T:ty),*) => {$(
        impl ImexSystem for $T {
            fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
                dydt.fill(0.0);
            }
            fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
                self.rhs(t, y, dydt);
            }
            fn has_implicit_jacobian(&self) -> bool {
                self.has_jacobian()
            }
            fn implicit_jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
                self.jacobian(t, y, jac);
            }
        }
    )*};
}

all_implicit!(Oscillator, NanAfter, PanicOnce, JacobianPanics);

fn methods() -> impl Iterator<Item = Method> {
    Method::ALL.iter().map(|(_, m)| *m)
}

fn build(method: Method, options: &Options) -> Box<dyn Integrator> {
    solver::build(method, &MethodSettings::default(), Oscillator, 0.0, &[0.0, 1.0], options)
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .integrator
}

fn error_at(integ: &dyn Integrator) -> f64 {
    let t = integ.t();
    (integ.state()[0] - t.sin()).abs().max((integ.state()[1] - t.cos()).abs())
}

#[test]
fn normal_task_returns_the_state_at_tout() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        let mut integ = build(method, &options);
        assert_eq!(
            integ.advance(1.0, Task::Normal).unwrap(),
            Step { t: 1.0, event: StepEvent::Reached },
            "{method}"
        );
        assert_eq!(integ.t(), 1.0, "{method}");
        assert!(error_at(integ.as_ref()) < 1e-6, "{method}: error {:e}", error_at(integ.as_ref()));
        // The returned state is the interpolant's value there.
        let interpolated = integ.dense(1.0, 0).unwrap().to_vec();
        assert!((0..2).all(|i| (integ.state()[i] - interpolated[i]).abs() <= 1e-14), "{method}");
        // One internal step goes beyond the returned time, and its end is the interpolant's.
        let one = integ.advance(10.0, Task::OneStep).unwrap();
        assert!(one.t > 1.0 && one.t < 10.0, "{method}: {one:?}");
        let end = integ.dense(one.t, 0).unwrap().to_vec();
        assert!((0..2).all(|i| (integ.state()[i] - end[i]).abs() <= 1e-14), "{method}");
        assert_eq!(
            integ.advance(f64::NAN, Task::Normal).unwrap_err().kind,
            ErrorKind::InvalidInput,
            "{method}"
        );
        assert_eq!(
            integ.dense(one.t + 1.0, 0).unwrap_err().kind,
            ErrorKind::InvalidInput,
            "{method}"
        );
        // An output time inside the last step takes no new step.
        let steps = integ.stats().steps;
        let inside = 0.5 * (1.0 + one.t);
        assert_eq!(
            integ.advance(inside, Task::Normal).unwrap(),
            Step { t: inside, event: StepEvent::Reached },
            "{method}"
        );
        assert_eq!(integ.stats().steps, steps, "{method}");
        // An output time behind the last step is refused.
        assert_eq!(
            integ.advance(0.5, Task::Normal).unwrap_err().kind,
            ErrorKind::InvalidInput,
            "{method}"
        );
    }
}

/// Dense output holds the last step only (before any step, or since a restart, only the
/// initial point) and refuses a non-finite time; OneStep takes exactly one step.
fn check_interpolation(method: Method) {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    let mut integ = build(method, &options);
    assert_eq!(integ.dense(0.0, 0).unwrap(), &[0.0, 1.0], "{method}");
    assert_eq!(integ.dense(0.0, 1).unwrap(), &[1.0, 0.0], "{method}");
    assert_eq!(integ.dense(0.1, 0).unwrap_err().kind, ErrorKind::InvalidInput, "{method}");
    integ.advance(1.0, Task::Normal).unwrap();
    assert_eq!(integ.dense(f64::NAN, 0).unwrap_err().kind, ErrorKind::InvalidInput, "{method}");
    // OneStep continues from the internal step end (beyond tout), one step per call.
    let steps = integ.stats().steps;
    let one = integ.advance(10.0, Task::OneStep).unwrap();
    assert!(one.t > 1.0 && integ.stats().steps == steps + 1, "{method}: {one:?}");
    integ.reinit(0.0, &[0.0, 1.0]).unwrap();
    assert_eq!(
        integ.dense(0.5, 0).unwrap_err().kind,
        ErrorKind::InvalidInput,
        "{method}: no step since the restart"
    );
}

#[test]
fn dense_output_holds_the_last_step_only() {
    methods().for_each(check_interpolation);
}

#[test]
fn the_stop_time_and_max_step_options_and_backward_integration() {
    for method in methods() {
        // Options set at construction, as set_stop_time / set_max_step set them later.
        let options = Options {
            stop_time: Some(0.75),
            max_step: Some(0.05),
            ..Options::new(1e-8, Tolerance::Scalar(1e-10))
        };
        let mut integ = build(method, &options);
        assert_eq!(
            integ.advance(1.0, Task::Normal).unwrap(),
            Step { t: 0.75, event: StepEvent::StopTime },
            "{method}"
        );
        assert!(error_at(integ.as_ref()) < 1e-6, "{method}");
        assert!(integ.stats().last_step <= 0.05 * (1.0 + 1e-12), "{method}: {:?}", integ.stats());
        assert_eq!(integ.advance(1.0, Task::Normal).unwrap().event, StepEvent::Reached, "{method}");
        // Backward in time: the same solution for t < 0.
        let mut backward = build(method, &Options::new(1e-8, Tolerance::Scalar(1e-10)));
        assert_eq!(
            backward.advance(-1.0, Task::Normal).unwrap(),
            Step { t: -1.0, event: StepEvent::Reached },
            "{method}"
        );
        assert!(
            error_at(backward.as_ref()) < 1e-6,
            "{method}: error {:e}",
            error_at(backward.as_ref())
        );
        let end = backward.advance(-5.0, Task::OneStep).unwrap().t;
        assert!(end < -1.0 && backward.dense(end, 0).is_ok(), "{method}: {end}");
    }
}

#[test]
fn the_stop_time_is_reached_exactly_then_disabled() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        let mut integ = build(method, &options);
        integ.set_stop_time(0.75).unwrap();
        assert_eq!(
            integ.advance(1.0, Task::Normal).unwrap(),
            Step { t: 0.75, event: StepEvent::StopTime },
            "{method}"
        );
        assert!(error_at(integ.as_ref()) < 1e-6, "{method}");
        assert_eq!(integ.advance(1.0, Task::Normal).unwrap().event, StepEvent::Reached, "{method}");
        assert_eq!(
            integ.set_stop_time(f64::NAN).unwrap_err().kind,
            ErrorKind::InvalidInput,
            "{method}"
        );
        // OneStep lands on a stop time exactly.
        integ.set_stop_time(1.5).unwrap();
        let last = loop {
            let step = integ.advance(10.0, Task::OneStep).unwrap();
            if step.event != StepEvent::Reached {
                break step;
            }
            assert!(step.t < 1.5, "{method}: {step:?}");
        };
        assert_eq!(last, Step { t: 1.5, event: StepEvent::StopTime }, "{method}");
    }
}

/// When `tout` equals the stop time, the output time comes first: every method returns
/// `Reached` exactly there (not `StopTime`), and the stop time is disabled all the same, so
/// that the next call goes on past it (as documented on `Integrator::set_stop_time`).
#[test]
fn tout_at_the_stop_time_is_reached_then_the_stop_time_is_disabled() {
    for method in methods() {
        let options =
            Options { stop_time: Some(0.75), ..Options::new(1e-8, Tolerance::Scalar(1e-10)) };
        let mut integ = build(method, &options);
        assert_eq!(
            integ.advance(0.75, Task::Normal).unwrap(),
            Step { t: 0.75, event: StepEvent::Reached },
            "{method}"
        );
        assert!(error_at(integ.as_ref()) < 1e-6, "{method}");
        let next = integ.advance(1.0, Task::Normal).unwrap_or_else(|e| panic!("{method}: {e}"));
        assert_eq!(next, Step { t: 1.0, event: StepEvent::Reached }, "{method}");
    }
}

/// Each integrator names its method, and `max_dense_order` is the bound `dense` keeps: 1
/// before the first step, then the method's (`Method::dense_order`; CVODE the order of
/// its last step).
#[test]
fn integrators_name_their_method_and_their_dense_order() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        let mut integ = build(method, &options);
        assert_eq!(integ.name(), method.name());
        assert_eq!(integ.max_dense_order(), 1, "{method} before a step");
        assert!(integ.dense(0.0, 1).is_ok() && integ.dense(0.0, 2).is_err(), "{method}");
        integ.advance(1.0, Task::Normal).unwrap();
        let max = integ.max_dense_order();
        let bound = method.dense_order();
        assert!(max >= 1 && max <= bound, "{method}: {max} against {bound}");
        if !method.name().starts_with("cvode") {
            assert_eq!(max, bound, "{method}");
        }
        assert!(integ.dense(1.0, max).is_ok(), "{method}: k = {max}");
        let error = integ.dense(1.0, max + 1).unwrap_err();
        assert_eq!(error.kind, ErrorKind::InvalidInput, "{method}: k = {}", max + 1);
        assert!(integ.warnings().is_empty(), "{method}: {:?}", integ.warnings());
    }
}

/// The oscillator with its Jacobian transposed (J[0][1] = −1, J[1][0] = 1): made stiff
/// (y' = 1e6 (y1 − y0) …) so that a wrong Newton matrix matters.
#[derive(Clone, Copy)]
struct Transposed;

impl OdeSystem for Transposed {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -1e6 * y[0] + 1e3 * y[1];
        dydt[1] = -y[1];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -1e6);
        jac.set(1, 0, 1e3);
        jac.set(1, 1, -1.0);
    }
}

all_implicit!(Transposed);

/// A wrong (transposed) Jacobian: `check_jacobian` finds it, and a stiff method that fails
/// on it says so in its error message instead of only "raise max_steps".
#[test]
fn a_wrong_jacobian_is_named_in_the_error() {
    use stickslip_ode::integrate::check_jacobian;
    let mismatch = check_jacobian(&Transposed, 0.0, &[1.0, 1.0]).unwrap_err();
    assert!([(0, 1), (1, 0)].contains(&(mismatch.row, mismatch.col)), "{mismatch}");
    assert!(check_jacobian(&Oscillator, 0.0, &[0.3, 0.7]).is_ok());
    let options = Options { max_steps: Some(200), ..Options::new(1e-8, Tolerance::Scalar(1e-10)) };
    let mut named = 0;
    for method in methods().filter(|m| m.is_stiff()) {
        let built = solver::build(
            method,
            &MethodSettings::default(),
            Transposed,
            0.0,
            &[1.0, 1.0],
            &options,
        );
        let mut integ = built.unwrap_or_else(|e| panic!("{method}: {e}")).integrator;
        match integ.advance(100.0, Task::Normal) {
            Ok(_) => println!("{method}: succeeds with the transposed Jacobian"),
            Err(e) => {
                println!("{method}: {e}");
                let text = e.to_string();
                assert!(text.contains("the analytic Jacobian disagrees"), "{method}: {e}");
                assert!(text.contains("J[0][1]") || text.contains("J[1][0]"), "{method}: {e}");
                named += 1;
            }
        }
    }
    assert!(named > 0, "no stiff method failed on the transposed Jacobian");
}

/// Options an explicit method has no use for are typed errors naming them, whichever
/// constructor is used.
#[test]
fn newton_options_on_arkode_erk_are_named() {
    use stickslip_ode::sundials::{ArkMethod, ErkTable, Solver};
    let options =
        Options { max_nonlin_iters: Some(4), ..Options::new(1e-8, Tolerance::Scalar(1e-10)) };
    let error = solver::build(
        Method::ArkodeErk,
        &MethodSettings::default(),
        Oscillator,
        0.0,
        &[0.0, 1.0],
        &options,
    )
    .err()
    .unwrap();
    assert_eq!(error.kind, ErrorKind::InvalidInput);
    assert!(error.message.contains("max_nonlin_iters"), "{error}");
    let direct = Solver::arkstep(
        Oscillator,
        ArkMethod::Erk(ErkTable::default()),
        Default::default(),
        0.0,
        &[0.0, 1.0],
        &options,
    )
    .err()
    .unwrap();
    assert_eq!(direct.kind, ErrorKind::InvalidInput);
    assert_eq!(direct.solver, "arkode-erk");
    assert!(direct.message.contains("max_nonlin_iters"), "{direct}");
}

/// A long state is shortened in messages: its first components, its size and its largest
/// magnitude.
#[test]
fn long_states_are_shortened_in_messages() {
    let error = SolverError {
        solver: "radau5",
        kind: ErrorKind::TooMuchWork,
        t: 1.0,
        state: (0..400).map(f64::from).collect(),
        flag: -1,
        message: String::new(),
    };
    let text = error.to_string();
    assert!(text.len() < 250, "{text}");
    assert!(text.contains("400 components") && text.contains("3.99e2"), "{text}");
}

#[test]
fn the_max_step_can_be_changed_between_steps() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        let mut integ = build(method, &options);
        integ.advance(1.0, Task::Normal).unwrap();
        // After the step already taken beyond t = 1, no step is longer than the limit;
        // lifted, they grow again.
        integ.set_max_step(Some(1e-3)).unwrap();
        integ.advance(10.0, Task::OneStep).unwrap();
        let mut t = integ.advance(10.0, Task::OneStep).unwrap().t;
        for _ in 0..20 {
            let next = integ.advance(10.0, Task::OneStep).unwrap().t;
            assert!(
                next - t <= 1e-3 * (1.0 + 1e-12),
                "{method}: step {:e} above the limit",
                next - t
            );
            t = next;
        }
        assert!(error_at(integ.as_ref()) < 1e-6, "{method}");
        integ.set_max_step(None).unwrap();
        let steps = integ.stats().steps;
        integ.advance(t + 1.0, Task::Normal).unwrap();
        assert!(integ.stats().steps - steps < 100, "{method}: the limit was not lifted");
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                integ.set_max_step(Some(bad)).unwrap_err().kind,
                ErrorKind::InvalidInput,
                "{method}: {bad}"
            );
        }
    }
}

/// A restart (the one restart case, over every method): the state is the one given, the step
/// history starts afresh and reaches the same accuracy, the statistics accumulate and keep the
/// very first step of the run, and a state of the wrong size is refused.
#[test]
fn reinit_restarts_and_statistics_accumulate() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        let mut integ = build(method, &options);
        integ.advance(1.0, Task::Normal).unwrap();
        let before = integ.stats();
        integ.reinit(0.0, &[0.0, 1.0]).unwrap();
        assert_eq!((integ.t(), integ.state()), (0.0, &[0.0, 1.0][..]), "{method}");
        integ.advance(2.0, Task::Normal).unwrap();
        let after = integ.stats();
        assert_eq!(after.reinits, 1, "{method}");
        assert_eq!(after.initial_step, before.initial_step, "{method}: the run's very first step");
        // As accurate as a fresh run of the same method (measured: CVODE and the homemade
        // methods give it to the last bit, ARKStep within 1 %; radau5's 3.6e-8 is the largest
        // error of the homemade methods, so this bounds them below 1e-7).
        let mut fresh = build(method, &options);
        fresh.advance(2.0, Task::Normal).unwrap();
        let (restarted, fresh) = (error_at(integ.as_ref()), error_at(fresh.as_ref()));
        assert!(restarted <= 1.5 * fresh, "{method}: error {restarted:e}, fresh run {fresh:e}");
        // ARKStep counts its explicit evaluations apart (all of ERK's).
        let rhs = |s: &stickslip_ode::integrate::Stats| s.rhs_evals + s.rhs_evals_explicit;
        assert!(
            after.steps > before.steps && rhs(&after) > rhs(&before),
            "{method}: {before:?} {after:?}"
        );
        assert!(error_at(integ.as_ref()) < 1e-6, "{method}");
        assert_eq!(
            integ.reinit(0.0, &[1.0]).unwrap_err().kind,
            ErrorKind::InvalidInput,
            "{method}"
        );
    }
}

#[test]
fn failures_are_typed_errors_with_time_and_state() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        // The step budget of one Normal call, with the time and state where it ran out.
        let few = Options { max_steps: Some(10), ..options.clone() };
        let mut integ = build(method, &few);
        let e = integ.advance(100.0, Task::Normal).unwrap_err();
        assert_eq!(e.kind, ErrorKind::TooMuchWork, "{method}: {e}");
        assert!(
            e.t > 0.0 && e.t < 100.0 && e.state.len() == 2 && e.state.iter().all(|x| x.is_finite()),
            "{method}: {e}"
        );
        assert_eq!(integ.stats().steps, 10, "{method}");
        assert_eq!(
            (integ.t(), integ.state()),
            (e.t, &e.state[..]),
            "{method}: the integrator stays where it failed"
        );
        // The budget is per call: the next call goes on.
        integ.advance(1.1 * e.t, Task::Normal).unwrap_or_else(|e| panic!("{method}: {e}"));
        // A right-hand side that is NaN from t = 0.5 on: smaller steps do not cure it.
        let nan = |from: f64| {
            solver::build(method, &MethodSettings::default(), NanAfter(from), 0.0, &[1.0], &options)
                .unwrap_or_else(|e| panic!("{method}: {e}"))
                .integrator
        };
        let mut integ = nan(0.5);
        let e = integ.advance(1.0, Task::Normal).unwrap_err();
        assert_eq!(e.kind, ErrorKind::RhsFailure, "{method}: {e}");
        assert!(e.t > 0.4 && e.state.len() == 1 && e.state[0].is_finite(), "{method}: {e}");
        assert_eq!((integ.t(), integ.state()), (e.t, &e.state[..]), "{method}");
        // Where it failed: the last good point, before the NaN.
        assert!(e.t <= 0.5 && (e.state[0] - (-e.t).exp()).abs() < 1e-6, "{method}: {e}");
        // NaN at the initial point.
        assert_eq!(
            nan(-1.0).advance(1.0, Task::Normal).unwrap_err().kind,
            ErrorKind::RhsFailure,
            "{method}"
        );
        // Invalid input at construction.
        let bad = |y0: &[f64], t0: f64, options: &Options| {
            solver::build(method, &MethodSettings::default(), Oscillator, t0, y0, options)
                .map(|_| ())
                .unwrap_err()
                .kind
        };
        assert_eq!(bad(&[0.0], 0.0, &options), ErrorKind::InvalidInput, "{method}");
        assert_eq!(bad(&[f64::NAN, 0.0], 0.0, &options), ErrorKind::InvalidInput, "{method}");
        assert_eq!(bad(&[0.0, 0.0], f64::INFINITY, &options), ErrorKind::InvalidInput, "{method}");
        assert_eq!(
            bad(&[0.0, 0.0], 0.0, &Options::new(-1.0, Tolerance::Scalar(1e-8))),
            ErrorKind::InvalidInput,
            "{method}"
        );
    }
}

/// Steps one at a time until the integration fails; returns the last accepted point and the error.
fn last_point_and_error(integ: &mut dyn Integrator) -> ((f64, Vec<f64>), SolverError) {
    let mut last = (integ.t(), integ.state().to_vec());
    loop {
        match integ.advance(10.0, Task::OneStep) {
            Ok(step) => last = (step.t, integ.state().to_vec()),
            Err(e) => return (last, e),
        }
    }
}

/// ARKStep's explicit stages retry no smaller step after a right-hand-side failure, and it
/// returns the failed stage's time (here 0.506) with the last accepted state (t = 0.4886); the
/// wrapper names the end of the last accepted step instead.
#[test]
fn a_failure_is_located_at_the_last_good_point_arkode_erk() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    let build = || {
        solver::build(
            Method::ArkodeErk,
            &MethodSettings::default(),
            NanAfter(0.5),
            0.0,
            &[1.0],
            &options,
        )
        .unwrap()
        .integrator
    };
    let mut integ = build();
    let e = integ.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::RhsFailure, "{e}");
    assert!(e.message.contains("tries no smaller step"), "the why: {e}");
    assert!(e.t <= 0.5 && (e.state[0] - (-e.t).exp()).abs() < 1e-6, "{e}");
    assert_eq!((integ.t(), integ.state()), (e.t, &e.state[..]));
    // Dense output at the failure point is the state (ARKStep's own interpolant spans the
    // failed attempt then: 0.6245 here, against the state 0.6135), and nothing else is served.
    assert_eq!(integ.dense(e.t, 0).unwrap(), &e.state[..]);
    assert!((integ.dense(e.t, 1).unwrap()[0] + e.state[0]).abs() < 1e-15);
    assert_eq!(integ.dense(e.t - 1e-3, 0).unwrap_err().kind, ErrorKind::InvalidInput);
    // It goes on from there, not from inside the failed attempt (which ended at 0.506).
    integ.set_stop_time(0.495).unwrap();
    assert_eq!(integ.advance(0.495, Task::Normal).unwrap().t, 0.495);
    assert!((integ.state()[0] - (-0.495f64).exp()).abs() < 1e-8, "{:?}", integ.state());
    // Exactly the last step's end, as one-step mode sees it.
    let ((t, y), e) = last_point_and_error(&mut *build());
    assert_eq!((e.t, e.state), (t, y));
    assert!(t > 0.45, "{t}");
}

/// y' = −y, with a panic at the first call past t = `at` (deliberately impure: the calls after
/// it succeed, so a caller can go on after the error).
struct PanicOnce {
    at: f64,
    armed: Cell<bool>,
}

impl PanicOnce {
    fn new(at: f64) -> Self {
        Self { at, armed: Cell::new(true) }
    }
}

impl OdeSystem for PanicOnce {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        if t > self.at && self.armed.replace(false) {
            panic!("the right-hand side refuses t = {t}");
        }
        dydt[0] = -y[0];
    }
}

/// Every method names the last accepted point for a right-hand side that fails (NaN) past
/// t = 0.5, and for one that panics there: a panic is a `CallbackPanic` error with the panic's
/// message, never an unwind to the caller, and the integrator goes on from that point. Known
/// exception: ARKStep's DIRK on SUNDIALS 6, which keeps no step ends (src/sundials/arkode.rs)
/// and reports a panic at the failed stage's time.
#[test]
fn every_failure_is_located_at_the_last_accepted_step() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    let sundials6 = !stickslip_ode::sundials::HEADER_VERSION.starts_with('7');
    for method in methods() {
        let mut nan =
            solver::build(method, &MethodSettings::default(), NanAfter(0.5), 0.0, &[1.0], &options)
                .unwrap()
                .integrator;
        let ((t, y), e) = last_point_and_error(&mut *nan);
        assert_eq!((e.t, &e.state), (t, &y), "{method}: {e}");
        assert!(t > 0.45 && t <= 0.5, "{method}: {t}");
        let mut panic = solver::build(
            method,
            &MethodSettings::default(),
            PanicOnce::new(0.5),
            0.0,
            &[1.0],
            &options,
        )
        .unwrap()
        .integrator;
        let ((t, y), e) = last_point_and_error(&mut *panic);
        assert_eq!(e.kind, ErrorKind::CallbackPanic, "{method}: {e}");
        assert!(e.message.contains("the right-hand side refuses t = 0.5"), "{method}: {e}");
        if !(sundials6 && method == Method::ArkodeDirk) {
            assert_eq!((e.t, &e.state), (t, &y), "{method}: {e}");
            assert_eq!((panic.t(), panic.state()), (t, &y[..]), "{method}");
        }
        // No smaller step is tried after a panic: the last accepted step is the start of the
        // one that reached past 0.5 (extrapolation's long steps: t = 0.148).
        assert!(t > 0.1 && t <= 0.5, "{method}: {t}");
        // Usable afterwards: it goes on from there.
        let step = panic
            .advance(1.0, Task::Normal)
            .unwrap_or_else(|e| panic!("{method} after the panic: {e}"));
        assert_eq!(step.t, 1.0);
        assert!((panic.state()[0] - (-1.0f64).exp()).abs() < 1e-6, "{method}: {:?}", panic.state());
    }
}

/// y' = −1e6 y, stiff, with an analytic Jacobian that panics.
#[derive(Clone, Copy)]
struct JacobianPanics;

impl OdeSystem for JacobianPanics {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -1e6 * y[0];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], _jac: &mut JacobianMatrix<'_>) {
        panic!("deliberate panic in the Jacobian");
    }
}

/// Every stiff method asks for the Jacobian of a stiff problem, and a panic there is the same
/// `CallbackPanic` error at the last accepted step (one-step mode's last point; the known
/// exception of DIRK on SUNDIALS 6 as above: there the first stage's time, 1.8e-10).
#[test]
fn a_panic_in_the_jacobian_is_an_error() {
    let options = Options::new(1e-6, Tolerance::Scalar(1e-10));
    let sundials6 = !stickslip_ode::sundials::HEADER_VERSION.starts_with('7');
    for method in methods().filter(|m| m.is_stiff()) {
        let mut integ = solver::build(
            method,
            &MethodSettings::default(),
            JacobianPanics,
            0.0,
            &[1.0],
            &options,
        )
        .unwrap()
        .integrator;
        let ((t, y), e) = last_point_and_error(&mut *integ);
        assert_eq!(e.kind, ErrorKind::CallbackPanic, "{method}: {e}");
        assert!(e.message.contains("deliberate panic in the Jacobian"), "{method}: {e}");
        if !(sundials6 && method == Method::ArkodeDirk) {
            assert_eq!((e.t, &e.state), (t, &y), "{method}: {e}");
        }
    }
}

/// A panic in the one callback dense output makes (f at the start, before any step) is the same
/// error, and the integrator answers the next request.
#[test]
fn a_panic_in_dense_output_is_an_error() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    for method in methods() {
        let mut integ = solver::build(
            method,
            &MethodSettings::default(),
            PanicOnce::new(-1.0),
            0.0,
            &[1.0],
            &options,
        )
        .unwrap()
        .integrator;
        let e = integ.dense(0.0, 1).unwrap_err();
        assert_eq!(e.kind, ErrorKind::CallbackPanic, "{method}: {e}");
        assert!(e.message.contains("refuses t = 0"), "{method}: {e}");
        assert_eq!((e.t, &e.state[..]), (0.0, &[1.0][..]), "{method}: {e}");
        assert_eq!(integ.dense(0.0, 1).unwrap(), &[-1.0], "{method}");
    }
}
