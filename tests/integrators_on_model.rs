//! The integrators on the library's spring-slider (the DRR model and its PRZ law): the tests
//! of stickslip-ode's methods that need the model, so they live here and not in
//! crates/ode/tests (where the contract over every method, the method table's suite, each
//! method's own tests, the stiff test set and SUNDIALS' replayed examples are). The homemade
//! methods at γ = 1e8 from the slow manifold against CVODE's BDF; the Jacobian check at a far
//! state; Rodas5P on the PRZ cells it once failed on; extrapolation on the deep arrest floor.

use stickslip::integrate::{
    check_jacobian, Clock, ErrorKind, Extrapolation, Integrator, JacobianMatrix, OdeSystem,
    Options, Radau5, Rodas5p, Task, Time, Tolerance,
};
use stickslip::model::{Drr, DrrParams, Friction, StateLaw};
use stickslip::solver::{build_default, Method};

/// A homemade method's spring-slider case.
struct DrrCase {
    /// Rodas5P: f declared independent of t.
    autonomous: bool,
    /// Bound on the accepted steps over t ∈ [0, 100] (each rtol).
    max_steps: u64,
}

/// The case of each homemade method.
fn drr_case(method: Method) -> DrrCase {
    match method {
        // Measured: 1339 and 2871 steps (CVODE: 6727 and 12097).
        Method::Radau5 => DrrCase { autonomous: false, max_steps: 10_000 },
        // Measured: 1711 and 4393 steps (CVODE: 6727 and 12097).
        Method::Rodas5p => DrrCase { autonomous: true, max_steps: 15_000 },
        // Measured: 283 and 396 steps (CVODE: 6727 and 12097).
        Method::Extrapolation => DrrCase { autonomous: false, max_steps: 2000 },
        other => panic!("{other}: not a homemade method"),
    }
}

/// A method under test: the Integrator contract, and extrapolation's scheme switches.
enum Subject {
    /// Extrapolation, which switches between its schemes.
    Extrapolation(Box<Extrapolation<Drr>>),
    /// Radau5 or Rodas5P.
    Plain(Box<dyn Integrator>),
}

impl Subject {
    /// The homemade `method` on `drr` from (0, y0), Rodas5P declared `autonomous` or not.
    fn build(method: Method, autonomous: bool, drr: Drr, y0: &[f64], options: &Options) -> Self {
        match method {
            Method::Radau5 => Subject::Plain(Box::new(Radau5::new(drr, 0.0, y0, options).unwrap())),
            Method::Rodas5p => {
                let s = Rodas5p::new(drr, 0.0, y0, options).unwrap();
                Subject::Plain(if autonomous { Box::new(s.autonomous()) } else { Box::new(s) })
            }
            Method::Extrapolation => {
                Subject::Extrapolation(Box::new(Extrapolation::new(drr, 0.0, y0, options).unwrap()))
            }
            other => panic!("{other}: not a homemade method"),
        }
    }

    /// The integrator.
    fn integ(&mut self) -> &mut dyn Integrator {
        match self {
            Subject::Extrapolation(e) => e.as_mut(),
            Subject::Plain(p) => p.as_mut(),
        }
    }

    /// Extrapolation's (switches so far, whether the linearly implicit scheme is in use);
    /// None for a method with one scheme.
    fn switches(&self) -> Option<(u64, bool)> {
        match self {
            Subject::Extrapolation(e) => Some((e.switches(), e.is_stiff())),
            Subject::Plain(_) => None,
        }
    }
}

/// The spring-slider at γ = 1e8 from the scene default start: v = 0.5, θ at its fixed-point
/// value, u on the slow manifold.
fn drr_start() -> (Drr, [f64; 3]) {
    let drr = Drr::new(DrrParams::new(1e8, 0.8, 1.0, Friction::Log));
    let (w, theta) = (0.5f64.ln(), drr.fixed_point()[2]);
    (drr, [drr.manifold_u(w, theta), w, theta])
}

/// The spring-slider's tolerances: atol = rtol/100 on each component.
fn drr_options(rtol: f64) -> Options {
    Options::new(rtol, Tolerance::PerComponent(vec![rtol * 1e-2; 3]))
}

/// Without re-basing, the arrest after the first slip needs steps below the spacing of t: a
/// typed step underflow just after t = 5 (as for CVODE).
fn drr_needs_rebasing(method: Method, autonomous: bool) {
    let (drr, y0) = drr_start();
    let mut plain = Subject::build(method, autonomous, drr, &y0, &drr_options(1e-8));
    let integ = plain.integ();
    let error = loop {
        match integ.advance(100.0, Task::OneStep) {
            Ok(step) => assert!(step.t < 100.0, "expected a step underflow in the first arrest"),
            Err(e) => break e,
        }
    };
    println!(
        "{method} without re-basing: {:?} at t = {} after {} steps",
        error.kind,
        error.t,
        integ.stats().steps
    );
    assert_eq!(error.kind, ErrorKind::StepUnderflow, "{error}");
    assert!(error.t > 5.0 && error.t < 5.1 && error.state.iter().all(|v| v.is_finite()), "{error}");
}

/// The spring-slider at γ = 1e8 over t ∈ [0, 100], re-basing time after each slip peak: the
/// peaks of CVODE's BDF, the same at rtol 1e-10 within 1e-6 (measured: within 3e-8; CVODE's
/// second peak moves by 2e-6 between the two tolerances).
fn drr_at_gamma_1e8_from_the_slow_manifold(method: Method) {
    let case = drr_case(method);
    drr_needs_rebasing(method, case.autonomous);
    let (drr, y0) = drr_start();
    for rtol in [1e-8, 1e-10] {
        let mut ours = Subject::build(method, case.autonomous, drr, &y0, &drr_options(rtol));
        let (steps, peaks) = drr_cycles(ours.integ(), 100.0).unwrap_or_else(|e| panic!("{e}"));
        let s = ours.integ().stats();
        let mut cvode = build_default(Method::CvodeBdf, drr, 0.0, &y0, &drr_options(rtol)).unwrap();
        let (cvode_steps, cvode_peaks) =
            drr_cycles(cvode.as_mut(), 100.0).unwrap_or_else(|e| panic!("{e}"));
        println!(
            "DRR γ = 1e8, rtol {rtol:e}, t ∈ [0, 100]: {method} {steps} steps ({} attempts, {} \
             rejected), {} RHS, {} Jacobians, {} LU, {} restarts, switches {:?}, peaks at \
             {peaks:.9?}; CVODE {cvode_steps} steps, {} RHS, peaks at {cvode_peaks:.9?}",
            s.step_attempts,
            s.err_test_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            s.reinits,
            ours.switches(),
            cvode.stats().rhs_evals,
        );
        assert_eq!(s.steps, steps);
        assert_eq!(s.reinits, peaks.len() as u64);
        assert_eq!(peaks.len(), cvode_peaks.len());
        assert!(!peaks.is_empty());
        if let Some((switches, _)) = ours.switches() {
            assert!(switches > 0, "the method must switch schemes");
        }
        assert!(steps < case.max_steps, "{steps} steps");
        if rtol <= 1e-10 {
            for (a, b) in peaks.iter().zip(&cvode_peaks) {
                assert!(((a - b) / b).abs() < 1e-6, "peaks {peaks:?} vs CVODE {cvode_peaks:?}");
            }
        }
    }
}

/// OneStep integration of the DRR model from `y0` to total time `tend`, re-basing time (a
/// restart at local t = 0) at the first step end after each slip peak, as the cycle engine
/// does. Returns (steps, peak times).
pub fn drr_cycles(
    integ: &mut dyn Integrator,
    tend: f64,
) -> Result<(u64, Vec<f64>), stickslip::integrate::SolverError> {
    let (mut elapsed, mut steps, mut peaks) = (0.0, 0u64, Vec::new());
    let mut prev_dw = integ.dense(integ.t(), 1)?[1];
    let mut rebase_pending = false;
    while elapsed + integ.t() < tend {
        let step = integ.advance(1e6, Task::OneStep)?;
        steps += 1;
        let y = integ.state().to_vec();
        let dw = integ.dense(step.t, 1)?[1];
        if prev_dw > 0.0 && dw <= 0.0 && y[1] > 5.0 {
            peaks.push(elapsed + step.t);
            rebase_pending = true;
        } else if rebase_pending {
            integ.reinit(0.0, &y)?;
            elapsed += step.t;
            rebase_pending = false;
        }
        prev_dw = dw;
    }
    Ok((steps, peaks))
}

#[test]
fn radau5_at_gamma_1e8_from_the_slow_manifold() {
    drr_at_gamma_1e8_from_the_slow_manifold(Method::Radau5);
}

#[test]
fn rodas5p_at_gamma_1e8_from_the_slow_manifold() {
    drr_at_gamma_1e8_from_the_slow_manifold(Method::Rodas5p);
}

#[test]
fn extrapolation_at_gamma_1e8_from_the_slow_manifold() {
    drr_at_gamma_1e8_from_the_slow_manifold(Method::Extrapolation);
}

/// The check blames a Jacobian only where differences resolve its entries: at the state where
/// arkode-imex stops from v = 1e30 (u = 8.7e19, ln v = 69), the step of ln v's column,
/// 1e-6 of the state's largest component (8.7e13), leaves e^(ln v) far behind, and the
/// differences (7e241) said the right Jacobian (8.7e5) was wrong. Differences at h and h/8
/// that disagree are not judged; near the same state with u of usual size, a wrong entry is
/// still found.
#[test]
fn the_jacobian_check_judges_only_entries_that_differences_resolve() {
    let drr = Drr::new(DrrParams::new(1e8, 0.8, 1.0, Friction::Log));
    let far = [8.665426747370406e19, 69.07751524360145, -138.1550306805274];
    assert_eq!(check_jacobian(&drr, 8.7e-11, &far), Ok(()));
    /// The DRR with ∂f_v/∂ln v doubled.
    struct Wrong(Drr);
    impl OdeSystem for Wrong {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
            self.0.rhs(t, y, f)
        }
        fn has_jacobian(&self) -> bool {
            true
        }
        fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
            self.0.jacobian(t, y, jac);
            jac.set(1, 1, 2.0 * jac.get(1, 1));
        }
    }
    let near = [1.0, 2.0, -3.0];
    let mismatch = check_jacobian(&Wrong(drr), 0.0, &near).unwrap_err();
    assert_eq!((mismatch.row, mismatch.col), (1, 1), "{mismatch}");
}

/// A cell of `stickslip stress` (PRZ law, rtol 1e-6) with Rodas5P finds the cycle that Radau5
/// finds on the same scene, within the grid's 1e3·rtol.
fn prz_cell_agrees_with_radau5(
    gamma: f64,
    xi: f64,
    epsilon: f64,
    eta: f64,
    start: Option<[f64; 3]>,
) {
    use stickslip::analysis::cycle::CycleStatus;
    use stickslip_cli::stress::{run_cell, Cell, Outcome};
    let period = |method| {
        let cell =
            Cell { gamma, xi, epsilon, rtol: 1e-6, start, method, state_law: StateLaw::Prz, eta };
        match run_cell(&cell) {
            Outcome::Ok { status: CycleStatus::Periodic, period: Some(p) } => p,
            other => panic!("{}: {other:?}", cell.key()),
        }
    };
    let (ours, reference) = (period(Method::Rodas5p), period(Method::Radau5));
    let rel = (ours - reference).abs() / reference;
    assert!(rel < 1e-3, "rodas5p period {ours} vs radau5 {reference}: {rel:.1e}");
}

/// PRZ with radiation damping η = 0.1, γ = 1e8, ξ = 0.2, ε = 3, from v = 1e30: in the initial
/// layer an accepted step left θ 4e-3 (23 error weights) off its slow manifold (hλ ≈ −3000
/// there: the embedded estimate sees that error only partly); the next step's error estimate
/// then fell like h^0.2, not h⁵, while h shrank from 1e-16 towards 1/λ ≈ 2e-19, so RODAS's
/// controller (h/err^{1/5}) cut h by only 1.2 … 1.4 a rejection and the run ended after 20
/// error-test failures at h = 2.1e-18. Now h is cut by 5 from the second rejection in a row.
#[test]
fn prz_damped_initial_layer_from_v_1e30() {
    prz_cell_agrees_with_radau5(1e8, 0.2, 3.0, 0.1, Some([0.0, 1e30, 0.0]));
}

/// PRZ, γ = 1e12, ξ = 0.7, ε = 10 (`stress --grid laws`): at an arrest an accepted step could
/// land 16.5 above the floor ln v = −(ξu + θ), where f is 1e180 times larger than the step can
/// follow; every stage point then left the range of doubles, and ten halvings of h (to 7e-17,
/// against a time scale of 1e-193) ended the run in a right-hand-side failure.
#[test]
fn prz_deep_arrest_at_gamma_1e12() {
    prz_cell_agrees_with_radau5(1e12, 0.7, 10.0, 0.0, None);
}

/// The state where the PRZ arrest above failed (t = 2296.05, local time 6.6e-14 on the Clock,
/// ln v 16.5 above its floor −(ξu + θ) = −406.8, the step 3.5e-14 that had just been
/// accepted): a non-finite stage cuts h to the local time scale 0.01‖y‖/‖f‖ (~5e-195), the
/// Clock re-bases when that falls below its resolution, and ln v falls onto the floor with u
/// and θ unchanged.
#[test]
fn nonfinite_stage_far_above_the_arrest_floor_steps_down_to_it() {
    let params =
        DrrParams { state_law: StateLaw::Prz, ..DrrParams::new(1e12, 0.7, 10.0, Friction::Log) };
    let y0 = [1045.0786662477906, -390.3242177672276, -324.7411122203327];
    let floor = -(0.7 * y0[0] + y0[2]);
    let options = Options {
        initial_step: Some(3.482098609744186e-14),
        ..Options::new(1e-6, Tolerance::Scalar(1e-8))
    };
    let mut rodas =
        Rodas5p::new(Drr::new(params), 6.61760292161855e-14, &y0, &options).unwrap().autonomous();
    let mut clock = Clock::new(&mut rodas, Time::new(2296.05));
    let mut steps = 0;
    while (clock.state()[1] - floor).abs() > 1e-3 {
        clock.step().unwrap_or_else(|e| panic!("after {steps} steps: {e} [{:?}]", e.kind));
        steps += 1;
        assert!(steps < 1000, "not on the floor after 1000 steps: {:?}", clock.state());
    }
    let y = clock.state().to_vec();
    assert!(
        clock.now().since(Time::new(2296.05)) < 1e-150,
        "the fall is a layer of 1e-193 time units"
    );
    assert!(
        (y[0] - y0[0]).abs() < 1e-12 * y0[0] && (y[2] - y0[2]).abs() < 1e-9,
        "{y:?} from {y0:?}"
    );
    assert!(clock.integrator().stats().nonfinite_rhs > 0, "the start has a non-finite stage");
}

/// The cycle of a physical-grid cell (`stickslip stress --grid physical`'s scene) with
/// extrapolation at rtol 1e-10.
fn deep_floor_period(gamma: f64, xi: f64, epsilon: f64) -> f64 {
    let text = format!(
        r#"{{"name": "deep-floor", "model": {{"gamma": {gamma:e}, "xi": {xi}, "epsilon": {epsilon}}},
            "solver": {{"method": "extrapolation", "rtol": 1e-10, "atol": 1e-12}},
            "analyses": [{{"cycle": {{"max_cycles": 60, "max_time": 3e4, "max_steps": 2000000}}}}]}}"#
    );
    let scene = stickslip::scene::parse(&text, "deep-floor").unwrap();
    let report = stickslip::engine::run(&scene, stickslip::engine::RunOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let cycle = report.cycle.expect("the scene asks for the cycle");
    cycle.values.expect("a converged cycle").main.period
}

/// The arrest floor ln v = −(ξu + θ) at −318 (γ = 1e10) and −340 (γ = 1e11), rates γ²/(ξv) of
/// 1e158 … 1e170: the midpoint scheme's stability check overflowed there (and at γ = 1e11 its
/// steps left the state unchanged, so no eigenvalue estimate) and it never switched back to the
/// linearly implicit scheme, ending in TooMuchWork after 2e6 steps. Periods: radau5 at rtol
/// 1e-10 (docs/robustness.md), within 1e3·rtol.
#[test]
fn deep_arrest_floor_switches_to_the_implicit_scheme() {
    for (gamma, reference) in [(1e10, 1268.799694186796), (1e11, 1363.868100581532)] {
        let period = deep_floor_period(gamma, 0.5, 10.0);
        assert!(
            (period - reference).abs() <= 1e-7 * reference,
            "γ = {gamma:e}: period {period} against {reference}"
        );
    }
}
