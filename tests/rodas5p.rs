//! The homemade Rosenbrock integrator Rodas5P: convergence orders with fixed steps, the stiff
//! van der Pol benchmark against the Test Set reference, dense output, the DRR model at
//! γ = 1e8, its dense derivatives and Jacobian counts, and the failures its own knobs produce
//! (the Integrator contract itself is tests/contract.rs, run over every method). Mirrors
//! tests/radau5.rs.

use stickslip::integrate::{
    ErrorKind, Integrator, JacobianMatrix, OdeSystem, Options, Radau5, Rodas5p, StepEvent, Task,
    Tolerance,
};
use stickslip::model::{Drr, DrrParams, Friction};
use stickslip::sundials::{CvodeSettings, Solver};

mod common;
use common::{drr_cycles, observed_orders, sci, Linear, NanAfter, Oscillator, Tan, VanDerPol};

/// A nonlinear system with every elementary differential of order ≤ 5 independent:
/// y = φ(z) with z' = M z (rotation in (z1, z2), decay of z3) and φ(z) = (z1, z2 + z1²,
/// z3 + z1 z2), so f(y) = Dφ(φ⁻¹(y)) M φ⁻¹(y) (finite-difference Jacobian).
struct Warped;

impl Warped {
    fn z(y: &[f64]) -> [f64; 3] {
        let z1 = y[0];
        let z2 = y[1] - z1 * z1;
        [z1, z2, y[2] - z1 * z2]
    }
    fn exact(t: f64) -> [f64; 3] {
        // z(0) = (0.3, 0.8, 1): z1 = 0.3 cos t + 0.8 sin t, z2 = −0.3 sin t + 0.8 cos t.
        let (s, c) = t.sin_cos();
        let z = [0.3 * c + 0.8 * s, -0.3 * s + 0.8 * c, (-0.5 * t).exp()];
        [z[0], z[1] + z[0] * z[0], z[2] + z[0] * z[1]]
    }
}

impl OdeSystem for Warped {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let z = Self::z(y);
        let dz = [z[1], -z[0], -0.5 * z[2]];
        dydt[0] = dz[0];
        dydt[1] = dz[1] + 2.0 * z[0] * dz[0];
        dydt[2] = dz[2] + dz[0] * z[1] + z[0] * dz[1];
    }
}

/// y' = y cos t, y(0) = 1: y = e^{sin t} (non-autonomous: needs ∂f/∂t).
struct Forced;

impl OdeSystem for Forced {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[0] * t.cos();
    }
}

/// Prothero–Robinson y' = −λ (y − cos t) − sin t, exact y = cos t from y(0) = 1.
struct ProtheroRobinson(f64);

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -self.0 * (y[0] - t.cos()) - t.sin();
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.0);
    }
}

/// Integrates to `tend` with the constant step h (the stop time makes the last step land on
/// `tend` exactly) and returns y(tend).
fn fixed_step<S: OdeSystem>(solver: Rodas5p<S>, tend: f64, h: f64) -> Vec<f64> {
    let mut solver = solver.fixed_step(h);
    let step = solver.advance(tend + 1.0, Task::Normal).unwrap();
    assert_eq!(step, stickslip::integrate::Step { t: tend, event: StepEvent::StopTime });
    let expected = (tend / h).round() as u64;
    assert_eq!(solver.stats().steps, expected, "h = {h}");
    solver.state().to_vec()
}

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

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

#[test]
fn fixed_steps_converge_with_order_five_on_smooth_problems() {
    let tan: Vec<f64> = [0.2, 0.1, 0.05, 0.025]
        .iter()
        .map(|&h| (fixed_step(rodas(Tan, &[0.0], 1.0), 1.0, h)[0] - 1f64.tan()).abs())
        .collect();
    let oscillator: Vec<f64> = [0.5, 0.25, 0.125, 0.0625]
        .iter()
        .map(|&h| {
            distance(
                &fixed_step(rodas(Oscillator, &[0.0, 1.0], 2.0), 2.0, h),
                &[2f64.sin(), 2f64.cos()],
            )
        })
        .collect();
    let warped: Vec<f64> = [0.4, 0.2, 0.1, 0.05]
        .iter()
        .map(|&h| {
            distance(
                &fixed_step(rodas(Warped, &Warped::exact(0.0), 2.0), 2.0, h),
                &Warped::exact(2.0),
            )
        })
        .collect();
    // Non-autonomous: ∂f/∂t by a forward difference.
    let forced: Vec<f64> = [0.2, 0.1, 0.05, 0.025]
        .iter()
        .map(|&h| (fixed_step(rodas(Forced, &[1.0], 2.0), 2.0, h)[0] - 2f64.sin().exp()).abs())
        .collect();
    // On linear problems only the stability function counts: it matches e^z to order 6 (the
    // tall-tree condition of order 6 holds), so the oscillator shows order 6.
    for (name, errors, order) in [
        ("tan", tan, 5.0),
        ("oscillator", oscillator, 6.0),
        ("warped", warped, 5.0),
        ("forced", forced, 5.0),
    ] {
        let orders = observed_orders(&errors);
        println!("{name}: errors {}, observed orders {orders:.3?}", sci(&errors));
        assert!(
            orders.iter().all(|p| (p - order).abs() < 0.35),
            "{name}: errors {}, orders {orders:?}",
            sci(&errors)
        );
    }
    // On an autonomous system the finite-difference ∂f/∂t is exactly zero: declaring the system
    // autonomous changes nothing but the number of right-hand-side calls.
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

#[test]
fn fixed_steps_on_stiff_prothero_robinson_do_not_collapse() {
    // With hλ ≫ 1 the error stays small (∝ 1/λ) and still falls like h³: no collapse of the
    // order (Rodas5P was built with Prothero–Robinson in view, as Rodas4P and Rodas4P2).
    for lambda in [1e3, 1e6] {
        let errors: Vec<f64> = [0.2, 0.1, 0.05, 0.025]
            .iter()
            .map(|&h| {
                (fixed_step(rodas(ProtheroRobinson(lambda), &[1.0], 1.0), 1.0, h)[0] - 1f64.cos())
                    .abs()
            })
            .collect();
        let orders = observed_orders(&errors);
        println!(
            "Prothero–Robinson λ = {lambda:e}: errors {}, observed orders {orders:.3?}",
            sci(&errors)
        );
        // Measured: λ = 1e3 errors 2.5e-8 … 1.6e-12 (orders 3.5, 3.9, 6.5 through the
        // transition hλ ~ 1); λ = 1e6 errors 3.3e-11 … 5.6e-14 (orders 3.10, 3.06, 3.04: the
        // error behaves like h³/λ, the same with an exact ∂f/∂t through the autonomised form).
        assert!(errors.iter().all(|&e| e < 5e-8 * 1e3 / lambda), "errors {}", sci(&errors));
        assert!(orders.iter().all(|&p| p > 2.95), "errors {}, orders {orders:?}", sci(&errors));
    }
}

#[test]
fn van_der_pol_eps_1e6_against_the_test_set() {
    // Test Set for IVP Solvers (Mazzia & Magherini), problem VDPOL: reference at t = 2.
    let reference = [0.1706167732170483e1, -0.8928097010247975];
    for rtol in [1e-6, 1e-8, 1e-10] {
        let options =
            Options { max_steps: Some(1_000_000), ..Options::new(rtol, Tolerance::Scalar(rtol)) };
        let mut rodas =
            Rodas5p::new(VanDerPol(1e-6), 0.0, &[2.0, 0.0], &options).unwrap().autonomous();
        assert_eq!(rodas.advance(2.0, Task::Normal).unwrap().event, StepEvent::Reached);
        assert_eq!(rodas.t(), 2.0);
        let mut radau = Radau5::new(VanDerPol(1e-6), 0.0, &[2.0, 0.0], &options).unwrap();
        radau.advance(2.0, Task::Normal).unwrap();
        let mut cvode =
            Solver::cvode(VanDerPol(1e-6), CvodeSettings::default(), 0.0, &[2.0, 0.0], &options)
                .unwrap();
        cvode.advance(2.0, Task::Normal).unwrap();
        let ours = rodas.state().to_vec();
        let relative: Vec<f64> =
            (0..2).map(|i| ((ours[i] - reference[i]) / reference[i]).abs()).collect();
        let rel = |y: &[f64]| {
            (0..2).map(|i| ((y[i] - reference[i]) / reference[i]).abs()).fold(0.0, f64::max)
        };
        let (s, r, c) = (rodas.stats(), radau.stats(), cvode.stats());
        println!(
            "rtol = atol = {rtol:e}: Rodas5P {} (relative errors {:.1e}, {:.1e}): {} steps ({} attempts, {} rejected), \
             {} RHS, {} Jacobians, {} LU | Radau5 error {:.1e}: {} steps, {} RHS, {} LU | CVODE error {:.1e}: {} steps, {} RHS, {} LU",
            sci(&ours),
            relative[0],
            relative[1],
            s.steps,
            s.step_attempts,
            s.err_test_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            rel(radau.state()),
            r.steps,
            r.rhs_evals,
            r.lin_setups,
            rel(cvode.state()),
            c.steps,
            c.rhs_evals,
            c.lin_setups
        );
        assert_eq!((s.last_order, s.rhs_evals_jacobian, s.nonlin_iters), (5, 0, 0));
        assert!(
            s.step_attempts == s.steps + s.err_test_fails && s.lin_setups == s.step_attempts,
            "{s:?}"
        );
        assert_eq!(s.jac_evals, s.steps, "one Jacobian per step, kept across rejections: {s:?}");
        assert_eq!(
            s.rhs_evals,
            7 * s.step_attempts + s.steps + 2,
            "7 stages per attempt, f at each accepted point, f(t0) and the initial-step probe"
        );
        if rtol <= 1e-10 {
            assert!(relative.iter().all(|&e| e < 1e-6), "relative errors {relative:?}");
        }
    }
}

#[test]
fn dense_output_matches_a_tight_run_and_the_right_hand_side() {
    let vdp = VanDerPol(1.0);
    let thetas = [0.1, 0.25, 0.5, 0.75, 0.9];
    for rtol in [1e-6, 1e-8] {
        let atol = rtol;
        let scale = |y: f64| rtol * y.abs() + atol;
        let options =
            Options { max_steps: Some(100_000), ..Options::new(rtol, Tolerance::Scalar(atol)) };
        let mut solver = Rodas5p::new(vdp, 0.0, &[2.0, 0.0], &options).unwrap();
        let (mut samples, mut prev) = (Vec::new(), 0.0);
        let (mut defect, mut fd_mismatch) = (0.0f64, 0.0f64);
        let mut previous_end = vec![2.0, 0.0];
        while solver.t() < 3.0 {
            let step = solver.advance(3.0, Task::OneStep).unwrap();
            let end = solver.state().to_vec();
            assert_eq!(
                solver.dense(step.t, 0).unwrap(),
                &end[..],
                "the continuous output ends at the step end"
            );
            // ... and starts at the previous step end (up to rounding in θ).
            let start = solver.dense(prev, 0).unwrap().to_vec();
            for i in 0..2 {
                assert!(
                    (start[i] - previous_end[i]).abs() <= 1e-13 * (1.0 + previous_end[i].abs()),
                    "{start:?}"
                );
            }
            previous_end = end.clone();
            samples.push((step.t, end, true));
            let h = step.t - prev;
            for &theta in &thetas {
                let t = prev + theta * h;
                let y = solver.dense(t, 0).unwrap().to_vec();
                let d = solver.dense(t, 1).unwrap().to_vec();
                let mut f = [0.0; 2];
                vdp.rhs(t, &y, &mut f);
                defect = defect
                    .max((0..2).map(|i| (d[i] - f[i]).abs() / scale(f[i])).fold(0.0, f64::max));
                samples.push((t, y.clone(), false));
                // dense(t, k + 1) is the derivative of dense(t, k).
                let delta = 1e-5 * h;
                for k in 0..4 {
                    let up = solver.dense(t + delta, k).unwrap().to_vec();
                    let down = solver.dense(t - delta, k).unwrap().to_vec();
                    let dk = solver.dense(t, k + 1).unwrap().to_vec();
                    for i in 0..2 {
                        let fd = (up[i] - down[i]) / (2.0 * delta);
                        let size = dk[i].abs() + (up[i].abs() + down[i].abs()) / h;
                        fd_mismatch = fd_mismatch.max((fd - dk[i]).abs() / (1.0 + size));
                    }
                }
            }
            prev = step.t;
        }
        // A much tighter run, interpolating at the same times (Normal task).
        let tight =
            Options { max_steps: Some(1_000_000), ..Options::new(1e-13, Tolerance::Scalar(1e-13)) };
        let mut reference = Radau5::new(vdp, 0.0, &[2.0, 0.0], &tight).unwrap();
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
            "rtol {rtol:e}: {} steps; error/tol at step ends {at_ends:.2}, inside steps {inside:.2}; \
             |dense'(t) − f(dense(t))|/tol {defect:.1}; finite-difference mismatch of the derivatives {fd_mismatch:.1e}",
            solver.stats().steps
        );
        // Measured (rtol 1e-6, 1e-8): inside 1.74, 2.60 × tol against 1.63, 2.53 at the step ends
        // (the order-4 continuous output adds almost nothing to the global error); the defect
        // of the interpolant 35 and 94 × tol (Radau5's cubic: 450 and 5300 between its nodes).
        assert!(
            inside < 10.0 && inside < 2.0 * at_ends.max(1.0),
            "inside {inside}, ends {at_ends}"
        );
        assert!(defect < 1e3, "defect {defect}");
        assert!(
            fd_mismatch < 1e-5,
            "dense(t, k + 1) is not the derivative of dense(t, k): {fd_mismatch:e}"
        );
    }
}

#[test]
fn drr_at_gamma_1e8_from_the_slow_manifold() {
    let drr = Drr::new(DrrParams::new(1e8, 0.8, 1.0, Friction::Log));
    let (w, theta) = (0.5f64.ln(), drr.fixed_point()[2]);
    let y0 = [drr.manifold_u(w, theta), w, theta];
    let options = |rtol: f64| Options::new(rtol, Tolerance::PerComponent(vec![rtol * 1e-2; 3]));

    // Without re-basing, the arrest after the first slip needs steps below the spacing of t
    // (measured: after 561 steps, at t = 5.0764), as for Radau5 and CVODE.
    let mut plain = Rodas5p::new(drr, 0.0, &y0, &options(1e-8)).unwrap().autonomous();
    let error = loop {
        match plain.advance(100.0, Task::OneStep) {
            Ok(step) => assert!(step.t < 100.0, "expected a step underflow in the first arrest"),
            Err(e) => break e,
        }
    };
    println!(
        "DRR γ = 1e8 without re-basing: {:?} at t = {} after {} steps",
        error.kind,
        error.t,
        plain.stats().steps
    );
    assert_eq!(error.kind, ErrorKind::StepUnderflow, "{error}");
    assert!(error.t > 5.0 && error.t < 5.1 && error.state.iter().all(|v| v.is_finite()), "{error}");

    for rtol in [1e-8, 1e-10] {
        let mut rodas = Rodas5p::new(drr, 0.0, &y0, &options(rtol)).unwrap().autonomous();
        let (steps, peaks) = drr_cycles(&mut rodas, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let s = rodas.stats();
        let mut radau = Radau5::new(drr, 0.0, &y0, &options(rtol)).unwrap();
        let (radau_steps, radau_peaks) =
            drr_cycles(&mut radau, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let r = radau.stats();
        let mut cvode =
            Solver::cvode(drr, CvodeSettings::default(), 0.0, &y0, &options(rtol)).unwrap();
        let (cvode_steps, cvode_peaks) =
            drr_cycles(&mut cvode, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let c = cvode.stats();
        println!(
            "DRR γ = 1e8, rtol {rtol:e}, t ∈ [0, 100]: Rodas5P {steps} steps ({} attempts, {} rejected), {} RHS, \
             {} Jacobians, {} LU, {} restarts, peaks at {peaks:.9?}; Radau5 {radau_steps} steps, {} RHS, {} LU, \
             peaks at {radau_peaks:.9?}; CVODE {cvode_steps} steps, {} RHS, {} LU, peaks at {cvode_peaks:.9?}",
            s.step_attempts,
            s.err_test_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            s.reinits,
            r.rhs_evals,
            r.lin_setups,
            c.rhs_evals,
            c.lin_setups
        );
        assert_eq!(s.steps, steps);
        assert_eq!(s.reinits, peaks.len() as u64);
        assert_eq!(peaks.len(), cvode_peaks.len());
        assert_eq!(peaks.len(), radau_peaks.len());
        assert!(!peaks.is_empty());
        if rtol <= 1e-10 {
            for (a, b) in peaks.iter().zip(&cvode_peaks) {
                assert!(((a - b) / b).abs() < 1e-6, "peaks {peaks:?} vs CVODE {cvode_peaks:?}");
            }
        }
    }
}

/// Rodas5P's own part of the contract (the rest is tests/contract.rs, over every method): the
/// quartic's derivatives up to the fourth, the first step kept across restarts, and the
/// Jacobian's count (one a step, no Newton iteration).
#[test]
fn dense_derivatives_restarts_and_jacobian_counts() {
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

    // Restart: the step history starts afresh, the first step of the run is kept.
    let before = solver.stats();
    solver.reinit(0.0, &[0.0, 1.0]).unwrap();
    solver.advance(2.0, Task::Normal).unwrap();
    assert_eq!(solver.stats().initial_step, before.initial_step, "the very first step of the run");
    assert!((solver.state()[0] - 2f64.sin()).abs() < 1e-7);

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
    use stickslip::model::StateLaw;
    use stickslip::scene::Method;
    use stickslip::stress::{run_cell, Cell, Outcome};
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
    use stickslip::integrate::{Clock, Time};
    use stickslip::model::StateLaw;
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
