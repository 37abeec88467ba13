//! The homemade Radau IIA (order 5) integrator: convergence orders with fixed steps, the
//! stiff van der Pol benchmark against the Test Set reference and CVODE, dense output, the DRR
//! model at γ = 1e8, its dense derivatives and Jacobian counts, and the failures its own knobs
//! produce (the Integrator contract itself is tests/contract.rs, run over every method).

use stickslip::integrate::{
    ErrorKind, Integrator, OdeSystem, Options, Radau5, StepEvent, Task, Tolerance,
};
use stickslip::model::{Drr, DrrParams, Friction};
use stickslip::sundials::{CvodeSettings, Solver};

mod common;
use common::{
    drr_cycles, observed_orders, sci, Linear, NanAfter, Oscillator, ProtheroRobinson, Tan,
    VanDerPol,
};

/// Integrates to `tend` with the constant step h (the stop time makes the last step land on
/// `tend` exactly) and returns y(tend).
fn fixed_step<S: OdeSystem>(system: S, y0: &[f64], tend: f64, h: f64) -> Vec<f64> {
    let options = Options {
        stop_time: Some(tend),
        max_steps: Some(100_000),
        // Zero starting values on the first step need more than RADAU5's 7 iterations at
        // this Newton tolerance when h may not shrink.
        max_nonlin_iters: Some(50),
        ..Options::new(1e-13, Tolerance::Scalar(1e-13))
    };
    let mut solver = Radau5::new(system, 0.0, y0, &options).unwrap().fixed_step(h);
    let step = solver.advance(tend + 1.0, Task::Normal).unwrap();
    assert_eq!(step, stickslip::integrate::Step { t: tend, event: StepEvent::StopTime });
    let expected = (tend / h).round() as u64;
    assert_eq!(solver.stats().steps, expected, "h = {h}");
    solver.state().to_vec()
}

#[test]
fn fixed_steps_converge_with_order_five_on_smooth_problems() {
    let tan: Vec<f64> = [0.2, 0.1, 0.05, 0.025]
        .iter()
        .map(|&h| (fixed_step(Tan, &[0.0], 1.0, h)[0] - 1f64.tan()).abs())
        .collect();
    let oscillator: Vec<f64> = [0.5, 0.25, 0.125, 0.0625]
        .iter()
        .map(|&h| {
            let y = fixed_step(Oscillator, &[0.0, 1.0], 2.0, h);
            (y[0] - 2f64.sin()).hypot(y[1] - 2f64.cos())
        })
        .collect();
    for (name, errors) in [("tan", tan), ("oscillator", oscillator)] {
        let orders = observed_orders(&errors);
        println!("{name}: errors {}, observed orders {orders:.3?}", sci(&errors));
        assert!(
            orders.iter().all(|p| (p - 5.0).abs() < 0.3),
            "{name}: errors {}, orders {orders:?}",
            sci(&errors)
        );
    }
}

#[test]
fn fixed_steps_keep_the_stage_order_on_stiff_prothero_robinson() {
    // Radau IIA is stiffly accurate: with hλ ≫ 1 the error at the grid points falls like
    // h^3 (the stage order), without the order collapse of non-stiffly-accurate methods.
    let errors: Vec<f64> = [0.2, 0.1, 0.05, 0.025]
        .iter()
        .map(|&h| (fixed_step(ProtheroRobinson(1e6), &[1.0], 1.0, h)[0] - 1f64.cos()).abs())
        .collect();
    let orders = observed_orders(&errors);
    println!("Prothero–Robinson λ = 1e6: errors {}, observed orders {orders:.3?}", sci(&errors));
    // Measured 3.09, 3.05, 3.02 (the asymptotic value is 3 exactly, approached from above).
    assert!(orders.iter().all(|&p| p > 2.95), "errors {}, orders {orders:?}", sci(&errors));
}

#[test]
fn van_der_pol_eps_1e6_to_eight_digits_against_the_test_set_and_cvode() {
    // Test Set for IVP Solvers (Mazzia & Magherini), problem VDPOL: reference at t = 2,
    // computed there with quadruple-precision RADAU5 (rtol = atol = h0 = 1.1e-18).
    let reference = [0.1706167732170483e1, -0.8928097010247975];
    let options =
        Options { max_steps: Some(100_000), ..Options::new(1e-12, Tolerance::Scalar(1e-12)) };
    let mut radau = Radau5::new(VanDerPol(1e-6), 0.0, &[2.0, 0.0], &options).unwrap();
    assert_eq!(radau.advance(2.0, Task::Normal).unwrap().event, StepEvent::Reached);
    assert_eq!(radau.t(), 2.0);
    let mut cvode =
        Solver::cvode(VanDerPol(1e-6), CvodeSettings::default(), 0.0, &[2.0, 0.0], &options)
            .unwrap();
    cvode.advance(2.0, Task::Normal).unwrap();
    let (ours, theirs) = (radau.state().to_vec(), cvode.state().to_vec());
    let s = radau.stats();
    println!("Radau5   {}\nCVODE    {}\nTest Set {}", sci(&ours), sci(&theirs), sci(&reference));
    println!(
        "Radau5: {} steps ({} attempts), {} RHS, {} Jacobians, {} LU; CVODE: {} steps, {} RHS, {} LU",
        s.steps,
        s.step_attempts,
        s.rhs_evals,
        s.jac_evals,
        s.lin_setups,
        cvode.stats().steps,
        cvode.stats().rhs_evals,
        cvode.stats().lin_setups
    );
    for i in 0..2 {
        let relative = |y: f64| ((y - reference[i]) / reference[i]).abs();
        assert!(relative(ours[i]) < 1e-8, "Radau5 y{i} = {:e}: {:e}", ours[i], relative(ours[i]));
        assert!(
            relative(theirs[i]) < 1e-8,
            "CVODE y{i} = {:e}: {:e}",
            theirs[i],
            relative(theirs[i])
        );
        assert!(
            ((ours[i] - theirs[i]) / theirs[i]).abs() < 1e-8,
            "Radau5 and CVODE disagree on y{i}"
        );
    }
    assert_eq!(
        (s.last_order, s.rhs_evals_jacobian),
        (5, 0),
        "analytic Jacobian: no RHS calls for it"
    );
    assert!(s.steps > 100 && s.step_attempts >= s.steps + s.err_test_fails);
    assert!(s.lin_setups <= s.step_attempts && s.jac_evals <= s.lin_setups, "{s:?}");
}

#[test]
fn dense_output_matches_a_tight_run_and_the_right_hand_side() {
    let vdp = VanDerPol(1.0);
    let sq6 = 6f64.sqrt();
    let nodes = [(4.0 - sq6) / 10.0, (4.0 + sq6) / 10.0, 1.0];
    let between = [0.1, 0.3, 0.5, 0.7, 0.9];
    for rtol in [1e-6, 1e-8] {
        let atol = rtol;
        let scale = |y: f64| rtol * y.abs() + atol;
        let options =
            Options { max_steps: Some(100_000), ..Options::new(rtol, Tolerance::Scalar(atol)) };
        let mut solver = Radau5::new(VanDerPol(1.0), 0.0, &[2.0, 0.0], &options).unwrap();
        let (mut samples, mut prev) = (Vec::new(), 0.0);
        let (mut at_nodes, mut off_nodes, mut fd_mismatch) = (0.0f64, 0.0f64, 0.0f64);
        while solver.t() < 3.0 {
            let step = solver.advance(3.0, Task::OneStep).unwrap();
            let end = solver.state().to_vec();
            assert_eq!(
                solver.dense(step.t, 0).unwrap(),
                &end[..],
                "the polynomial ends at the step end"
            );
            samples.push((step.t, end, true));
            let h = step.t - prev;
            for (k, &theta) in nodes.iter().chain(&between).enumerate() {
                let t = prev + theta * h;
                let y = solver.dense(t, 0).unwrap().to_vec();
                let d = solver.dense(t, 1).unwrap().to_vec();
                let mut f = [0.0; 2];
                vdp.rhs(t, &y, &mut f);
                // dy/dt of the interpolant against the right-hand side at the interpolant.
                let residual =
                    (0..2).map(|i| (d[i] - f[i]).abs() / scale(f[i])).fold(0.0, f64::max);
                if k < nodes.len() {
                    at_nodes = at_nodes.max(residual);
                } else {
                    off_nodes = off_nodes.max(residual);
                    samples.push((t, y.clone(), false));
                }
                // dense(t, 1) is the derivative of dense(t, 0).
                if theta < 1.0 {
                    let delta = 1e-5 * h;
                    let up = solver.dense(t + delta, 0).unwrap().to_vec();
                    let down = solver.dense(t - delta, 0).unwrap().to_vec();
                    for i in 0..2 {
                        let fd = (up[i] - down[i]) / (2.0 * delta);
                        fd_mismatch = fd_mismatch.max((fd - d[i]).abs() / (1.0 + d[i].abs()));
                    }
                }
            }
            prev = step.t;
        }
        // A much tighter run, interpolating at the same times (Normal task).
        let tight =
            Options { max_steps: Some(1_000_000), ..Options::new(1e-13, Tolerance::Scalar(1e-13)) };
        let mut reference = Radau5::new(VanDerPol(1.0), 0.0, &[2.0, 0.0], &tight).unwrap();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (mut at_ends, mut inside) = (0.0f64, 0.0f64);
        for (t, y, is_end) in &samples {
            reference.advance(*t, Task::Normal).unwrap();
            let r = reference.state();
            let e = (0..2).map(|i| (y[i] - r[i]).abs() / scale(r[i])).fold(0.0, f64::max);
            if *is_end {
                at_ends = at_ends.max(e);
            } else {
                inside = inside.max(e);
            }
        }
        println!(
            "rtol {rtol:e}: error/tol at step ends {at_ends:.2}, inside steps {inside:.2}; \
             |dense'(t) − f(dense(t))|/tol at the collocation nodes {at_nodes:.1}, between them {off_nodes:.1}; \
             finite-difference mismatch {fd_mismatch:.1e}"
        );
        // Measured (rtol 1e-6, 1e-8): inside 6.4, 12.8 × tol over the whole run (mostly global
        // error; the cubic continuous output is of order 3 against the step's 5).
        assert!(
            inside < 30.0 && inside < 20.0 * at_ends.max(1.0),
            "inside {inside}, ends {at_ends}"
        );
        // At the collocation nodes the derivative is f up to the Newton tolerance (measured
        // ≤ 90 × tol); between nodes the defect of a stage-order-3 polynomial is O(h³)
        // (measured 450 and 5300 × tol; CVODE's interpolant: 390 and 1200 × tol).
        assert!(at_nodes < 500.0, "residual at nodes {at_nodes}");
        assert!(off_nodes < 2e4, "residual between nodes {off_nodes}");
        assert!(
            fd_mismatch < 1e-6,
            "dense(t, 1) is not the derivative of dense(t, 0): {fd_mismatch:e}"
        );
    }
}

#[test]
fn drr_at_gamma_1e8_from_the_slow_manifold() {
    let drr = Drr::new(DrrParams::new(1e8, 0.8, 1.0, Friction::Log));
    // The scene default start: v = 0.5, θ at its fixed-point value, u on the slow manifold.
    let (w, theta) = (0.5f64.ln(), drr.fixed_point()[2]);
    let y0 = [drr.manifold_u(w, theta), w, theta];
    let options = |rtol: f64| Options::new(rtol, Tolerance::PerComponent(vec![rtol * 1e-2; 3]));

    // Without re-basing, the arrest after the first slip needs steps below the spacing of t.
    let mut plain = Radau5::new(drr, 0.0, &y0, &options(1e-8)).unwrap();
    let error = loop {
        match plain.advance(100.0, Task::OneStep) {
            Ok(step) => assert!(step.t < 100.0, "expected a step underflow in the first arrest"),
            Err(e) => break e,
        }
    };
    assert_eq!(error.kind, ErrorKind::StepUnderflow, "{error}");
    assert!(error.t > 5.0 && error.t < 5.1 && error.state.iter().all(|v| v.is_finite()), "{error}");

    for rtol in [1e-8, 1e-10] {
        let mut radau = Radau5::new(drr, 0.0, &y0, &options(rtol)).unwrap();
        let (steps, peaks) = drr_cycles(&mut radau, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let s = radau.stats();
        let mut cvode =
            Solver::cvode(drr, CvodeSettings::default(), 0.0, &y0, &options(rtol)).unwrap();
        let (cvode_steps, cvode_peaks) =
            drr_cycles(&mut cvode, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let c = cvode.stats();
        println!(
            "DRR γ = 1e8, rtol {rtol:e}, t ∈ [0, 100]: Radau5 {steps} steps ({} attempts, {} rejected), {} RHS, \
             {} Jacobians, {} LU, {} restarts, peaks at {peaks:.9?}; CVODE {cvode_steps} steps, {} RHS, {} LU, \
             peaks at {cvode_peaks:.9?}",
            s.step_attempts,
            s.err_test_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            s.reinits,
            c.rhs_evals,
            c.lin_setups
        );
        assert_eq!(s.steps, steps);
        assert_eq!(s.reinits, peaks.len() as u64);
        assert_eq!(peaks.len(), cvode_peaks.len());
        assert!(!peaks.is_empty());
        if rtol <= 1e-10 {
            // Measured: the two integrators place the second peak (t ≈ 59) within 3e-8.
            for (a, b) in peaks.iter().zip(&cvode_peaks) {
                assert!(((a - b) / b).abs() < 1e-6, "peaks {peaks:?} vs CVODE {cvode_peaks:?}");
            }
        }
    }
}

/// Radau5's own part of the contract (the rest is tests/contract.rs, over every method): the
/// cubic's derivatives up to the third, the first step kept across restarts, and the
/// finite-difference Jacobian's count.
#[test]
fn dense_derivatives_restarts_and_jacobian_counts() {
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

    // Restart: the step history starts afresh, the first step of the run is kept.
    let before = solver.stats();
    solver.reinit(0.0, &[0.0, 1.0]).unwrap();
    solver.advance(2.0, Task::Normal).unwrap();
    assert_eq!(solver.stats().initial_step, before.initial_step, "the very first step of the run");
    assert!((solver.state()[0] - 2f64.sin()).abs() < 1e-7);

    // Finite-difference Jacobian: n RHS calls per Jacobian, counted apart.
    let s = solver.stats();
    assert!(s.jac_evals > 0 && s.rhs_evals_jacobian == 2 * s.jac_evals, "{s:?}");
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
