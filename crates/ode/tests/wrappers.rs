//! Behaviour of the safe SUNDIALS wrappers: every method, options, roots, dense output,
//! restarts, statistics and typed errors (panics, NaN, work limits, step underflow, bad input).

use stickslip_ode::integrate::{
    ErrorKind, ImexSystem, JacobianMatrix, OdeSystem, Options, Roots, StepEvent, Task, Tolerance,
};
use stickslip_ode::robertson::examples as robertson;
use stickslip_ode::robertson::Robertson;
use stickslip_ode::sundials::{
    self, ArkMethod, ArkSettings, CvodeMethod, CvodeSettings, DirkTable, ErkTable, Solver,
};

mod common;
use common::{Decay, Oscillator, ProtheroRobinson};

/// Prothero–Robinson split: the stiff relaxation is the implicit part, the forcing −sin t the
/// explicit part.
impl ImexSystem for ProtheroRobinson {
    fn rhs_explicit(&self, t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -t.sin();
    }
    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * (y[0] - t.cos());
    }
    fn has_implicit_jacobian(&self) -> bool {
        true
    }
    fn implicit_jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.0);
    }
}

/// A right-hand side that misbehaves once t passes `from`.
struct Faulty {
    from: f64,
    panic: bool,
}

impl OdeSystem for Faulty {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        if t > self.from {
            if self.panic {
                panic!("deliberate panic in the RHS at t = {t}");
            }
            dydt[0] = f64::NAN;
        } else {
            dydt[0] = -y[0];
        }
    }
}

fn tight() -> Options {
    Options::new(1e-10, Tolerance::Scalar(1e-12))
}

/// Every constructor the crate offers, on the decay problem.
fn all_methods(system: fn() -> Decay, options: &Options) -> Vec<Solver<Decay>> {
    let y0 = [1.0];
    let bdf = CvodeSettings::default();
    let adams = CvodeSettings { method: CvodeMethod::Adams, ..bdf };
    let ark = ArkSettings::default();
    vec![
        Solver::cvode(system(), bdf, 0.0, &y0, options).unwrap(),
        Solver::cvode(system(), adams, 0.0, &y0, options).unwrap(),
        Solver::arkstep(system(), ArkMethod::default(), ark, 0.0, &y0, options).unwrap(),
        Solver::arkstep(system(), ArkMethod::Erk(ErkTable::default()), ark, 0.0, &y0, options)
            .unwrap(),
    ]
}

#[test]
fn linked_sundials_is_debians_6x_or_7x() {
    let version = sundials::version();
    assert!(version.starts_with("6.") || version.starts_with("7."), "linked SUNDIALS {version}");
    // build.rs read the version from the headers and chose the API (cfg sundials7) from it;
    // the library loaded at run time must be the same release.
    assert_eq!(version, sundials::HEADER_VERSION, "headers and library agree");
}

#[test]
fn every_method_solves_decay_to_tolerance() {
    for mut solver in all_methods(|| Decay(1.0), &tight()) {
        let step = solver.advance(2.0, Task::Normal).unwrap();
        assert_eq!(step.event, StepEvent::Reached);
        let error = (solver.state()[0] - (-2.0f64).exp()).abs();
        assert!(error < 1e-8, "{}: error {error:e}", solver.name());
        let stats = solver.stats();
        assert!(
            stats.steps > 0 && stats.step_attempts >= stats.steps,
            "{}: {stats:?}",
            solver.name()
        );
        assert!(stats.rhs_evals + stats.rhs_evals_explicit > 0);
        assert!(stats.last_order >= 1, "{}: order {}", solver.name(), stats.last_order);
    }
}

#[test]
fn adams_and_erk_solve_an_oscillator() {
    let options = tight();
    let adams = CvodeSettings { method: CvodeMethod::Adams, ..Default::default() };
    let erk = ArkMethod::Erk(ErkTable::from_name("DORMAND_PRINCE_7_4_5").unwrap());
    let mut solvers = vec![
        Solver::cvode(Oscillator, adams, 0.0, &[0.0, 1.0], &options).unwrap(),
        Solver::arkstep(Oscillator, erk, ArkSettings::default(), 0.0, &[0.0, 1.0], &options)
            .unwrap(),
    ];
    for solver in &mut solvers {
        solver.advance(10.0, Task::Normal).unwrap();
        let (x, v) = (solver.state()[0], solver.state()[1]);
        assert!(
            (x - 10f64.sin()).abs() < 1e-7 && (v - 10f64.cos()).abs() < 1e-7,
            "{}",
            solver.name()
        );
    }
    assert_eq!(solvers[1].stats().jac_evals, 0, "an explicit method builds no Jacobian");
}

#[test]
fn imex_splits_stiff_and_nonstiff_parts() {
    let (implicit, explicit) = sundials::default_imex_tables();
    let mut options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    options.max_steps = Some(100_000);
    let mut solver = Solver::arkstep_imex(
        ProtheroRobinson(1e6),
        implicit,
        explicit,
        ArkSettings::default(),
        0.0,
        &[1.0],
        &options,
    )
    .unwrap();
    solver.advance(3.0, Task::Normal).unwrap();
    assert!((solver.state()[0] - 3f64.cos()).abs() < 1e-7);
    let stats = solver.stats();
    assert!(stats.rhs_evals > 0 && stats.rhs_evals_explicit > 0, "{stats:?}");
    // λ = 1e6 with an explicit method would need > 1e6 steps (h < 2.8/λ); IMEX needs far
    // fewer, although DIRK stage-order reduction on this problem costs some.
    assert!(stats.steps < 50_000, "{} steps", stats.steps);
}

#[test]
fn dirk_tables_are_selectable_by_name() {
    assert!(DirkTable::names().any(|n| n == "ARK548L2SA_DIRK_8_4_5"));
    assert!(DirkTable::from_name("NO_SUCH_TABLE").is_none());
    let table = DirkTable::from_name("ESDIRK547L2SA2_7_4_5").unwrap();
    assert_eq!(table.name(), "ESDIRK547L2SA2_7_4_5");
    let mut solver = Solver::arkstep(
        Decay(50.0),
        ArkMethod::Dirk(table),
        ArkSettings::default(),
        0.0,
        &[1.0],
        &tight(),
    )
    .unwrap();
    solver.advance(0.1, Task::Normal).unwrap();
    assert!((solver.state()[0] - (-5.0f64).exp()).abs() < 1e-9);
    assert_eq!(solver.stats().last_order, 5);
}

#[test]
fn finite_difference_jacobian_when_none_is_given() {
    struct NoJacobian;
    impl OdeSystem for NoJacobian {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
            Robertson.rhs(t, y, dydt)
        }
    }
    let options = Options::new(1e-6, Tolerance::PerComponent(vec![1e-10, 1e-14, 1e-8]));
    let mut fd =
        Solver::cvode(NoJacobian, CvodeSettings::default(), 0.0, &[1.0, 0.0, 0.0], &options)
            .unwrap();
    let mut exact =
        Solver::cvode(Robertson, CvodeSettings::default(), 0.0, &[1.0, 0.0, 0.0], &options)
            .unwrap();
    fd.advance(40.0, Task::Normal).unwrap();
    exact.advance(40.0, Task::Normal).unwrap();
    assert!((fd.state()[0] - exact.state()[0]).abs() < 1e-5);
    assert!(fd.stats().rhs_evals_jacobian > 0, "FD Jacobian costs RHS evaluations");
    assert_eq!(exact.stats().rhs_evals_jacobian, 0, "analytic Jacobian costs none");
}

#[test]
fn roots_with_directions_and_replacement_between_calls() {
    let mut solver =
        Solver::cvode(Oscillator, CvodeSettings::default(), 0.0, &[0.0, 1.0], &tight()).unwrap();
    // x = sin t rising through zero only: t = 2π, 4π (not π, 3π).
    solver.set_roots(Some(Roots::new(1, |_t, y, g| g[0] = y[0]).with_directions(vec![1]))).unwrap();
    let mut found = Vec::new();
    while let StepEvent::Root(info) = solver.advance(13.0, Task::Normal).unwrap().event {
        assert_eq!(info, vec![1]);
        found.push(solver.t());
    }
    assert_eq!(found.len(), 2, "{found:?}");
    for (k, t) in found.iter().enumerate() {
        let exact = 2.0 * std::f64::consts::PI * (k + 1) as f64;
        assert!((t - exact).abs() < 1e-7, "root {t} vs {exact}");
    }
    // Replace by v = cos t falling through zero: t = 4π + π/2.
    solver
        .set_roots(Some(Roots::new(1, |_t, y, g| g[0] = y[1]).with_directions(vec![-1])))
        .unwrap();
    let step = solver.advance(20.0, Task::Normal).unwrap();
    assert_eq!(step.event, StepEvent::Root(vec![-1]));
    assert!((step.t - 4.5 * std::f64::consts::PI).abs() < 1e-7);
    // Disable: runs to tout.
    solver.set_roots(None).unwrap();
    assert_eq!(solver.advance(20.0, Task::Normal).unwrap().event, StepEvent::Reached);
    assert!(solver.stats().root_evals > 0);
}

#[test]
fn dense_output_inside_the_last_step() {
    let mut solver =
        Solver::cvode(Decay(1.0), CvodeSettings::default(), 0.0, &[1.0], &tight()).unwrap();
    let mut step = solver.advance(5.0, Task::OneStep).unwrap();
    while step.t < 1.0 {
        step = solver.advance(5.0, Task::OneStep).unwrap();
    }
    let h = solver.stats().last_step;
    assert!(h > 0.0 && step.t < 5.0);
    let t_mid = step.t - 0.5 * h;
    let y = solver.dense(t_mid, 0).unwrap()[0];
    assert!((y - (-t_mid).exp()).abs() < 1e-8, "dense y({t_mid}) = {y}");
    let dy = solver.dense(t_mid, 1).unwrap()[0];
    assert!((dy + (-t_mid).exp()).abs() < 1e-6, "dense y'({t_mid}) = {dy}");
    let outside = solver.dense(step.t + 10.0 * h, 0).unwrap_err();
    assert_eq!(outside.kind, ErrorKind::InvalidInput, "{outside}");
}

#[test]
fn stop_time_is_honoured() {
    let mut options = tight();
    options.stop_time = Some(1.25);
    let mut solver =
        Solver::cvode(Decay(1.0), CvodeSettings::default(), 0.0, &[1.0], &options).unwrap();
    let step = solver.advance(10.0, Task::Normal).unwrap();
    assert_eq!(step.event, StepEvent::StopTime);
    assert_eq!(step.t, 1.25);
    solver.set_stop_time(2.0).unwrap();
    assert_eq!(solver.advance(10.0, Task::Normal).unwrap().t, 2.0);
}

#[test]
fn reinit_restarts_and_statistics_keep_running() {
    for mut solver in all_methods(|| Decay(1.0), &tight()) {
        solver.advance(1.0, Task::Normal).unwrap();
        let first = solver.stats();
        solver.reinit(10.0, &[2.0]).unwrap();
        let step = solver.advance(11.0, Task::Normal).unwrap();
        assert_eq!(step.t, 11.0);
        assert!((solver.state()[0] - 2.0 * (-1.0f64).exp()).abs() < 1e-8, "{}", solver.name());
        let total = solver.stats();
        assert_eq!(total.reinits, 1);
        assert!(
            total.steps > first.steps,
            "{}: steps {} then {}",
            solver.name(),
            first.steps,
            total.steps
        );
        assert!(
            total.rhs_evals + total.rhs_evals_explicit > first.rhs_evals + first.rhs_evals_explicit
        );
        // The second segment is a copy of the first (same ODE shifted in t and scaled): the
        // running total must be close to twice the first count, not to once or thrice.
        let ratio = total.steps as f64 / first.steps as f64;
        assert!((1.5..2.6).contains(&ratio), "{}: step ratio {ratio}", solver.name());
    }
}

#[test]
fn stability_limit_detection_can_be_switched_on() {
    let settings = CvodeSettings { method: CvodeMethod::Bdf, stability_limit_detection: true };
    let mut options = Options::new(1e-6, Tolerance::PerComponent(vec![1e-10, 1e-14, 1e-8]));
    options.max_steps = Some(20_000);
    let mut with = Solver::cvode(Robertson, settings, 0.0, &[1.0, 0.0, 0.0], &options).unwrap();
    let mut without =
        Solver::cvode(Robertson, CvodeSettings::default(), 0.0, &[1.0, 0.0, 0.0], &options)
            .unwrap();
    with.advance(4e5, Task::Normal).unwrap();
    without.advance(4e5, Task::Normal).unwrap();
    let (a, b) = (with.state()[0], without.state()[0]);
    assert!((a - b).abs() < 1e-4 * b, "y1(4e5) with STALD {a}, without {b}");
}

#[test]
fn panic_in_rhs_becomes_an_error() {
    let system = || Faulty { from: 0.5, panic: true };
    let mut solver =
        Solver::cvode(system(), CvodeSettings::default(), 0.0, &[1.0], &tight()).unwrap();
    let error = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::CallbackPanic);
    assert!(error.message.contains("deliberate panic"), "{error}");
    assert!(error.t > 0.4 && error.t <= 0.5 + 1e-12, "t = {}", error.t);
    assert_eq!(error.state.len(), 1);
    let mut ark = Solver::arkstep(
        system(),
        ArkMethod::default(),
        ArkSettings::default(),
        0.0,
        &[1.0],
        &tight(),
    )
    .unwrap();
    assert_eq!(ark.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::CallbackPanic);
}

#[test]
fn panic_in_root_and_jacobian_becomes_an_error() {
    let mut solver =
        Solver::cvode(Decay(1.0), CvodeSettings::default(), 0.0, &[1.0], &tight()).unwrap();
    solver
        .set_roots(Some(Roots::new(1, |t, _y, g| {
            assert!(t < 0.3, "deliberate panic in g");
            g[0] = 1.0;
        })))
        .unwrap();
    let error = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::CallbackPanic, "{error}");

    struct BadJacobian;
    impl OdeSystem for BadJacobian {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&self, _t: f64, y: &[f64], d: &mut [f64]) {
            d[0] = -y[0];
        }
        fn has_jacobian(&self) -> bool {
            true
        }
        fn jacobian(&self, _t: f64, _y: &[f64], _j: &mut JacobianMatrix<'_>) {
            panic!("deliberate panic in the Jacobian");
        }
    }
    let mut solver =
        Solver::cvode(BadJacobian, CvodeSettings::default(), 0.0, &[1.0], &tight()).unwrap();
    let error = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::CallbackPanic, "{error}");
    assert!(error.message.contains("Jacobian"));
}

#[test]
fn nan_from_rhs_is_an_error_not_a_hang() {
    // NaN from the very first call, and NaN after t = 0.5 (retried with smaller steps first).
    for from in [-1.0, 0.5] {
        let system = || Faulty { from, panic: false };
        let mut cvode =
            Solver::cvode(system(), CvodeSettings::default(), 0.0, &[1.0], &tight()).unwrap();
        let error = cvode.advance(1.0, Task::Normal).unwrap_err();
        assert_eq!(error.kind, ErrorKind::RhsFailure, "{error}");
        assert!(error.message.contains("non-finite"), "{error}");
        assert!(cvode.stats().nonfinite_rhs > 0);
        assert!(error.state.iter().all(|v| v.is_finite()));
        let mut ark = Solver::arkstep(
            system(),
            ArkMethod::default(),
            ArkSettings::default(),
            0.0,
            &[1.0],
            &tight(),
        )
        .unwrap();
        assert_eq!(ark.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::RhsFailure);
    }
}

#[test]
fn too_much_work_is_typed_and_located() {
    let mut options = tight();
    options.max_steps = Some(20);
    let mut solver =
        Solver::cvode(Oscillator, CvodeSettings::default(), 0.0, &[0.0, 1.0], &options).unwrap();
    let error = solver.advance(1000.0, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::TooMuchWork);
    assert!(error.t > 0.0 && error.t < 1000.0);
    assert!((error.state[0] - error.t.sin()).abs() < 1e-6, "state at the failure time");
    let text = error.to_string();
    assert!(text.starts_with("cvode-bdf failed") && text.contains("max_steps"), "{text}");
}

/// Fast forcing y' = cos(1e7 (t − 1e10)), run at t ≈ 1e10, where the spacing of t (~2e-6)
/// exceeds the steps it needs: the step-underflow tests' system.
struct Fast;

impl OdeSystem for Fast {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, _y: &[f64], d: &mut [f64]) {
        d[0] = (1e7 * (t - 1e10)).cos();
    }
}

#[test]
fn step_underflow_is_an_error_unless_allowed() {
    // Fast forcing at t ≈ 1e10, where the spacing of t (~2e-6) exceeds the steps needed.
    let mut options = Options::new(1e-10, Tolerance::Scalar(1e-14));
    options.max_steps = Some(5000);
    let t0 = 1e10;
    let mut strict = Solver::cvode(Fast, CvodeSettings::default(), t0, &[0.0], &options).unwrap();
    let error = strict.advance(t0 + 1e-3, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::StepUnderflow, "{error}");
    assert!(strict.stats().step_underflow_warnings > 0);

    options.fail_on_step_underflow = false;
    let mut lenient = Solver::cvode(Fast, CvodeSettings::default(), t0, &[0.0], &options).unwrap();
    // Time cannot advance here at all, so the lenient run still fails, but only once the
    // step budget is spent, and the failure names the cause; every warning was counted.
    let error = lenient.advance(t0 + 1e-3, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::StepUnderflow, "{error}");
    assert!(error.message.contains("mxstep"), "SUNDIALS' own message is kept: {error}");
    assert!(lenient.stats().step_underflow_warnings > 10, "all counted, beyond SUNDIALS' 10");
}

#[test]
fn step_underflow_stops_at_the_first_warning() {
    // With `fail_on_step_underflow` the solver must return at the first "t + h = t", not when
    // the step budget runs out: the right-hand side refuses the step after the warning.
    let mut options = Options::new(1e-10, Tolerance::Scalar(1e-14));
    options.max_steps = Some(1_000_000);
    let t0 = 1e10;
    let solvers = [
        Solver::cvode(Fast, CvodeSettings::default(), t0, &[0.0], &options).unwrap(),
        Solver::arkstep(Fast, ArkMethod::default(), ArkSettings::default(), t0, &[0.0], &options)
            .unwrap(),
        Solver::arkstep(
            Fast,
            ArkMethod::Erk(ErkTable::default()),
            ArkSettings::default(),
            t0,
            &[0.0],
            &options,
        )
        .unwrap(),
    ];
    for mut solver in solvers {
        let error = solver.advance(t0 + 1e-3, Task::Normal).unwrap_err();
        assert_eq!(error.kind, ErrorKind::StepUnderflow, "{}: {error}", solver.name());
        assert!(
            error.message.contains("t + h = t"),
            "{}: SUNDIALS' warning is quoted: {error}",
            solver.name()
        );
        let stats = solver.stats();
        assert_eq!(
            stats.step_underflow_warnings,
            1,
            "{}: stopped at the first warning",
            solver.name()
        );
        assert!(
            stats.steps < 1000,
            "{}: {} steps, far from the budget",
            solver.name(),
            stats.steps
        );
    }
}

#[test]
fn bad_input_is_rejected_with_the_field_named() {
    let y0 = [1.0];
    let s = CvodeSettings::default();
    let cases: Vec<(Options, &str)> = vec![
        (Options::new(-1e-6, Tolerance::Scalar(1e-8)), "rtol"),
        (Options::new(f64::NAN, Tolerance::Scalar(1e-8)), "rtol"),
        (Options::new(1e-6, Tolerance::Scalar(f64::INFINITY)), "atol"),
        (Options::new(1e-6, Tolerance::PerComponent(vec![1e-8, 1e-8])), "atol"),
        (Options { max_steps: Some(0), ..tight() }, "max_steps"),
        (Options { min_step: Some(-1.0), ..tight() }, "min_step"),
    ];
    for (options, field) in cases {
        let error = Solver::cvode(Decay(1.0), s, 0.0, &y0, &options).unwrap_err();
        assert_eq!(error.kind, ErrorKind::InvalidInput);
        assert!(error.message.contains(field), "{field}: {error}");
    }
    let error = Solver::cvode(Decay(1.0), s, 0.0, &[1.0, 2.0], &tight()).unwrap_err();
    assert!(error.message.contains("components"), "{error}");
    let error = Solver::cvode(Decay(1.0), s, 0.0, &[f64::NAN], &tight()).unwrap_err();
    assert!(error.message.contains("y0[0]"), "{error}");
    let error = Solver::arkstep(
        Decay(1.0),
        ArkMethod::default(),
        ArkSettings::default(),
        0.0,
        &y0,
        &Options { max_order: Some(3), ..tight() },
    )
    .unwrap_err();
    assert!(error.message.contains("max_order"), "{error}");
    let mut solver = Solver::cvode(Decay(1.0), s, 0.0, &y0, &tight()).unwrap();
    assert_eq!(solver.advance(f64::NAN, Task::Normal).unwrap_err().kind, ErrorKind::InvalidInput);
    let bad_roots = Roots::new(2, |_t, _y, _g| {}).with_directions(vec![1]);
    assert_eq!(solver.set_roots(Some(bad_roots)).unwrap_err().kind, ErrorKind::InvalidInput);
    assert_eq!(solver.reinit(0.0, &[1.0, 2.0]).unwrap_err().kind, ErrorKind::InvalidInput);
}

#[test]
fn non_finite_root_values_fail_cleanly() {
    let mut solver =
        Solver::cvode(Decay(1.0), CvodeSettings::default(), 0.0, &[1.0], &tight()).unwrap();
    solver
        .set_roots(Some(Roots::new(1, |t, _y, g| g[0] = if t > 0.2 { f64::NAN } else { 1.0 })))
        .unwrap();
    let error = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(error.kind, ErrorKind::RootFunctionFailure, "{error}");
    assert!(error.message.contains("NaN"), "{error}");
}

#[test]
fn robertson_stats_match_the_c_example_exactly() {
    // Same library, same settings, same arithmetic: the counts are not just within 10 %.
    let run = robertson::cvode_example().unwrap();
    assert_eq!((run.stats.steps, run.stats.rhs_evals, run.stats.jac_evals), (542, 754, 11));
    assert_eq!(
        (run.stats.err_test_fails, run.stats.lin_setups, run.stats.root_evals),
        (22, 107, 570)
    );
    assert_eq!(run.stats.nonlin_iters, 751);
    assert_eq!(run.stats.last_order, 4);
    // ARKODE's counts differ between major versions: the C example prints these with Debian
    // 12's 6.4.1 and Debian 13's 7.1.1 respectively (tests/expected/{6,7}).
    let run = robertson::arkode_example().unwrap();
    let counts = (
        (run.stats.steps, run.stats.step_attempts, run.stats.rhs_evals),
        (run.stats.jac_evals, run.stats.lin_setups, run.stats.nonlin_iters),
        (run.stats.root_evals, run.stats.nonlin_conv_fails, run.stats.err_test_fails),
    );
    if sundials::version().starts_with("6.") {
        assert_eq!(counts, ((1070, 1298, 36412), (66, 590, 29962), (1104, 55, 213)));
    } else {
        assert_eq!(counts, ((748, 813, 25698), (65, 263, 21684), (776, 59, 47)));
    }
}
