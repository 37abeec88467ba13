//! The homemade extrapolation integrator with stiffness switching (linearly implicit Euler
//! extrapolation / modified midpoint extrapolation, as Mathematica's "StiffnessSwitching"):
//! the orders of the tableaux with fixed steps, convergence with the tolerance, the stiff van der
//! Pol benchmark against the Test Set reference and CVODE, switching in both directions, dense
//! output of both schemes, its derivatives and counts, the failures its own knobs produce and
//! the DRR model at γ = 1e8 (the Integrator contract itself is tests/contract.rs, run over
//! every method).

use stickslip::integrate::{
    ErrorKind, Extrapolation, Integrator, JacobianMatrix, OdeSystem, Options, StepEvent, Task,
    Tolerance,
};
use stickslip::model::{Drr, DrrParams, Friction};
use stickslip::sundials::{CvodeSettings, Solver};

mod common;
use common::{drr_cycles, observed_orders, sci, Linear, NanAfter, Oscillator, Tan, VanDerPol};

/// Prothero–Robinson with a stiffness pulse: y' = −λ(t)(y − cos t) − sin t, exact y = cos t,
/// λ(t) = 1 + 1e5·exp(−(t − 5)²): non-stiff at both ends, stiff around t = 5.
struct StiffnessPulse;

impl StiffnessPulse {
    fn lambda(t: f64) -> f64 {
        1.0 + 1e5 * (-(t - 5.0) * (t - 5.0)).exp()
    }
}

impl OdeSystem for StiffnessPulse {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = -Self::lambda(t) * (y[0] - t.cos()) - t.sin();
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -Self::lambda(t));
    }
}

/// Integrates to `tend` with the constant step h and the fixed column k of the given scheme
/// (the stop time makes the last step land on `tend` exactly) and returns y(tend).
fn fixed_step<S: OdeSystem>(
    system: S,
    y0: &[f64],
    tend: f64,
    h: f64,
    k: usize,
    stiff: bool,
) -> Vec<f64> {
    let options = Options {
        stop_time: Some(tend),
        max_steps: Some(100_000),
        ..Options::new(1e-13, Tolerance::Scalar(1e-13))
    };
    let mut solver =
        Extrapolation::new(system, 0.0, y0, &options).unwrap().force_scheme(stiff).fixed_step(h, k);
    let step = solver.advance(tend + 1.0, Task::Normal).unwrap();
    assert_eq!(step, stickslip::integrate::Step { t: tend, event: StepEvent::StopTime });
    assert_eq!(solver.stats().steps, (tend / h).round() as u64, "h = {h}");
    assert_eq!(solver.switches(), 0);
    solver.state().to_vec()
}

#[test]
fn fixed_steps_give_the_orders_of_the_extrapolation_tableaux() {
    // Linearly implicit Euler: T_{k,k} has order k; modified midpoint: order 2k.
    for (stiff, columns, steps) in [
        (true, [2usize, 3, 4], [0.2, 0.1, 0.05, 0.025]),
        (false, [1, 2, 3], [0.5, 0.25, 0.125, 0.0625]),
    ] {
        for first in [1usize, 2] {
            if !stiff && first == 2 {
                continue;
            }
            for k in columns {
                let expected = if stiff { k as f64 } else { 2.0 * k as f64 };
                let errors: Vec<f64> = steps
                    .iter()
                    .map(|&h| {
                        let options = Options {
                            stop_time: Some(1.0),
                            ..Options::new(1e-13, Tolerance::Scalar(1e-13))
                        };
                        let mut s = Extrapolation::new(Tan, 0.0, &[0.0], &options)
                            .unwrap()
                            .implicit_sequence(first)
                            .force_scheme(stiff)
                            .fixed_step(h, k);
                        s.advance(2.0, Task::Normal).unwrap();
                        (s.state()[0] - 1f64.tan()).abs()
                    })
                    .collect();
                let orders = observed_orders(&errors);
                println!(
                    "tan, {} first {first}, k = {k}: errors {}, observed orders {orders:.3?}",
                    if stiff { "linearly implicit Euler" } else { "midpoint" },
                    sci(&errors)
                );
                // The asymptotic value is approached from below (measured within 0.2 on the
                // last halving).
                let last = orders[orders.len() - 1];
                assert!(
                    (last - expected).abs() < 0.25,
                    "k = {k}: errors {}, orders {orders:?}",
                    sci(&errors)
                );
            }
        }
    }
    // The oscillator with the midpoint scheme, column 2 (order 4).
    let errors: Vec<f64> = [0.5, 0.25, 0.125]
        .iter()
        .map(|&h| {
            let y = fixed_step(Oscillator, &[0.0, 1.0], 2.0, h, 2, false);
            (y[0] - 2f64.sin()).hypot(y[1] - 2f64.cos())
        })
        .collect();
    let orders = observed_orders(&errors);
    assert!(orders.iter().all(|p| (p - 4.0).abs() < 0.2), "oscillator: {orders:?}");
}

/// The Kepler problem with eccentricity 0.5 over one period (the orbit closes: y(2π) = y(0)).
struct Kepler;

impl OdeSystem for Kepler {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let r3 = (y[0] * y[0] + y[1] * y[1]).powf(1.5);
        dydt[0] = y[2];
        dydt[1] = y[3];
        dydt[2] = -y[0] / r3;
        dydt[3] = -y[1] / r3;
    }
}

#[test]
fn the_error_decreases_consistently_with_the_tolerance() {
    let e = 0.5f64;
    let y0 = [1.0 - e, 0.0, 0.0, ((1.0 + e) / (1.0 - e)).sqrt()];
    let period = 2.0 * std::f64::consts::PI;
    // Default (switching, stays explicit on this non-stiff problem) down to 1e-12; the
    // linearly implicit scheme alone down to 1e-10 (its tableau amplifies roundoff by ~1e5 at
    // 12 columns: it levels off near 1e-11).
    for (stiff, rtols) in [
        (None, &[1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12][..]),
        (Some(true), &[1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10][..]),
    ] {
        let mut errors = Vec::new();
        for &rtol in rtols {
            let options =
                Options { max_steps: Some(100_000), ..Options::new(rtol, Tolerance::Scalar(rtol)) };
            let mut solver = Extrapolation::new(Kepler, 0.0, &y0, &options).unwrap();
            if let Some(s) = stiff {
                solver = solver.force_scheme(s);
            }
            assert_eq!(solver.advance(period, Task::Normal).unwrap().t, period);
            let err = (0..4).map(|i| (solver.state()[i] - y0[i]).abs()).fold(0.0, f64::max);
            let s = solver.stats();
            println!(
                "Kepler, {}: rtol {rtol:.0e}: error {err:.2e} ({:.0} × rtol), {} steps, {} RHS, last order {}, {} switches",
                if stiff.is_some() { "linearly implicit only" } else { "switching" },
                err / rtol,
                s.steps,
                s.rhs_evals,
                s.last_order,
                solver.switches()
            );
            if stiff.is_none() {
                assert_eq!(solver.switches(), 0, "a non-stiff problem must not switch");
            }
            errors.push(err);
        }
        // Decreasing (strictly for the explicit scheme; over every two decades for the linearly
        // implicit one with the default sequence 2, 3, 4, …, whose error rises from 4e-7 to 2e-6
        // between rtol 1e-7 and 1e-8 — the harmonic 1, 2, 3, … decreased strictly, at 2–20×
        // the error for 1e-7 … 1e-10), within 500 × rtol (measured ≤ 133 and ≤ 182), and about
        // proportional to rtol over the whole range (measured slopes 1.05 and 1.01).
        if stiff.is_none() {
            assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
        } else {
            assert!(errors.windows(3).all(|w| w[2] < w[0]), "{errors:?}");
        }
        assert!(errors.iter().zip(rtols).all(|(e, r)| e / r < 500.0), "{errors:?}");
        let n = errors.len() - 1;
        let slope = (errors[0] / errors[n]).log10() / (rtols[0] / rtols[n]).log10();
        assert!((0.8..1.2).contains(&slope), "slope {slope}: {errors:?}");
    }
}

#[test]
fn van_der_pol_eps_1e6_against_the_test_set_and_cvode() {
    // Test Set for IVP Solvers (Mazzia & Magherini), problem VDPOL: reference at t = 2.
    let reference = [0.1706167732170483e1, -0.8928097010247975];
    let options =
        Options { max_steps: Some(100_000), ..Options::new(1e-10, Tolerance::Scalar(1e-10)) };
    let mut cvode =
        Solver::cvode(VanDerPol(1e-6), CvodeSettings::default(), 0.0, &[2.0, 0.0], &options)
            .unwrap();
    cvode.advance(2.0, Task::Normal).unwrap();
    let theirs = cvode.state().to_vec();
    let c = cvode.stats();
    println!(
        "CVODE    {}: {} steps, {} RHS, {} LU",
        sci(&theirs),
        c.steps,
        c.rhs_evals,
        c.lin_setups
    );
    // SEULEX's harmonic sequence 1, 2, 3, … and the default (Mathematica's) 2, 3, 4, …: measured
    // 3452 and 249 steps, 86 735 and 16 759 RHS, 24 741 and 2 069 LU.
    for first in [1usize, 2] {
        let mut solver = Extrapolation::new(VanDerPol(1e-6), 0.0, &[2.0, 0.0], &options)
            .unwrap()
            .implicit_sequence(first);
        assert_eq!(solver.advance(2.0, Task::Normal).unwrap().event, StepEvent::Reached);
        assert_eq!(solver.t(), 2.0);
        let ours = solver.state().to_vec();
        let s = solver.stats();
        println!(
            "Extrapolation (n_j = {first}, {}, …) {}: {} steps ({} attempts, {} error-test and {} row failures), {} RHS, \
             {} Jacobians, {} LU, last order {}, {} switches, stiff at the end: {}",
            first + 1,
            sci(&ours),
            s.steps,
            s.step_attempts,
            s.err_test_fails,
            s.step_solve_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            s.last_order,
            solver.switches(),
            solver.is_stiff()
        );
        for i in 0..2 {
            let relative = |y: f64| ((y - reference[i]) / reference[i]).abs();
            // Measured (n_1 = 1): 1e-10 and 4e-10; (n_1 = 2): 1e-10 and 2e-10.
            assert!(relative(ours[i]) < 1e-8, "y{i} = {:e}: {:e}", ours[i], relative(ours[i]));
            assert!(
                relative(theirs[i]) < 1e-6,
                "CVODE y{i} = {:e}: {:e}",
                theirs[i],
                relative(theirs[i])
            );
            assert!(
                ((ours[i] - theirs[i]) / theirs[i]).abs() < 1e-6,
                "Extrapolation and CVODE disagree on y{i}"
            );
        }
        // Starts explicit, detects the stiffness at once; the two fast jumps are taken
        // explicitly (2 switches each).
        assert!(solver.switches() > 0 && solver.is_stiff(), "switches {}", solver.switches());
        assert_eq!(s.rhs_evals_jacobian, 0, "analytic Jacobian: no RHS calls for it");
        assert!(s.steps > 50 && s.step_attempts >= s.steps + s.err_test_fails);
        assert!(s.jac_evals <= s.step_attempts && s.jac_evals <= s.lin_setups, "{s:?}");
        assert!((1..=12).contains(&s.last_order));
    }
}

#[test]
fn stiffness_switching_goes_both_ways() {
    // λ from 1 to 1e5 and back: explicit, linearly implicit through the pulse, explicit again.
    for rtol in [1e-6, 1e-8, 1e-10] {
        let options = Options {
            max_steps: Some(100_000),
            ..Options::new(rtol, Tolerance::Scalar(rtol * 1e-2))
        };
        let mut solver = Extrapolation::new(StiffnessPulse, 0.0, &[1.0], &options).unwrap();
        let mut segments: Vec<(bool, f64)> = Vec::new();
        while solver.t() < 10.0 {
            solver.advance(10.0, Task::OneStep).unwrap();
            if segments.last().map(|s| s.0) != Some(solver.is_stiff()) {
                segments.push((solver.is_stiff(), solver.t()));
            }
        }
        let y = solver.dense(10.0, 0).unwrap()[0];
        let err = (y - 10f64.cos()).abs();
        let s = solver.stats();
        println!(
            "pulse, rtol {rtol:.0e}: error at t = 10 {err:.2e}, {} steps, {} switches, (stiff, from t) {segments:.3?}",
            s.steps,
            solver.switches()
        );
        assert!(solver.switches() >= 2 && solver.switches() == segments.len() as u64 - 1);
        assert!(!segments[0].0 && !solver.is_stiff(), "explicit at both ends: {segments:?}");
        // The linearly implicit scheme covers the peak of the pulse (λ ≥ 1e4 on [3.5, 6.5]):
        // the explicit one runs there for less than 1e-2 in all. (Measured: at rtol 1e-10, one
        // explicit excursion of 8e-4 from t = 6.316, λ = 1.8e4, at a step the accuracy keeps
        // within the explicit stability bound; none at 1e-6 and 1e-8.)
        let explicit_in_pulse: f64 = segments
            .iter()
            .zip(segments.iter().skip(1).map(|s| s.1).chain([10.0]))
            .filter(|(s, _)| !s.0)
            .map(|(s, end)| (end.min(6.5) - s.1.max(3.5)).max(0.0))
            .sum();
        assert!(
            explicit_in_pulse < 1e-2,
            "explicit for {explicit_in_pulse} in [3.5, 6.5]: {segments:?}"
        );
        assert!(segments.iter().any(|s| s.0 && s.1 < 3.5), "{segments:?}");
        assert!(err < 100.0 * rtol, "error {err:e}");
        assert!(s.steps < 1000, "{} steps", s.steps);
    }
    // A non-stiff problem never switches.
    let mut solver = Extrapolation::new(
        Oscillator,
        0.0,
        &[0.0, 1.0],
        &Options::new(1e-8, Tolerance::Scalar(1e-8)),
    )
    .unwrap();
    solver.advance(20.0, Task::Normal).unwrap();
    assert_eq!((solver.switches(), solver.is_stiff()), (0, false));
    assert!((solver.state()[0] - 20f64.sin()).abs() < 1e-6);
}

#[test]
fn dense_output_of_both_schemes_matches_a_tight_run() {
    let vdp = VanDerPol(1.0);
    let between = [0.1, 0.3, 0.5, 0.7, 0.9];
    for stiff in [false, true] {
        for rtol in [1e-6, 1e-9] {
            let atol = rtol;
            let scale = |y: f64| rtol * y.abs() + atol;
            let options =
                Options { max_steps: Some(100_000), ..Options::new(rtol, Tolerance::Scalar(atol)) };
            let mut solver = Extrapolation::new(VanDerPol(1.0), 0.0, &[2.0, 0.0], &options)
                .unwrap()
                .force_scheme(stiff);
            let (mut samples, mut prev) = (Vec::new(), 0.0);
            let (mut residual, mut fd_mismatch, mut end_slope) = (0.0f64, 0.0f64, 0.0f64);
            while solver.t() < 3.0 {
                let step = solver.advance(3.0, Task::OneStep).unwrap();
                let end = solver.state().to_vec();
                assert_eq!(
                    solver.dense(step.t, 0).unwrap(),
                    &end[..],
                    "the interpolant ends at the step end"
                );
                let mut f = [0.0; 2];
                vdp.rhs(step.t, &end, &mut f);
                let d = solver.dense(step.t, 1).unwrap().to_vec();
                end_slope = end_slope
                    .max((0..2).map(|i| (d[i] - f[i]).abs() / scale(f[i])).fold(0.0, f64::max));
                samples.push((step.t, end, true));
                let h = step.t - prev;
                for &theta in &between {
                    let t = prev + theta * h;
                    let y = solver.dense(t, 0).unwrap().to_vec();
                    let d = solver.dense(t, 1).unwrap().to_vec();
                    vdp.rhs(t, &y, &mut f);
                    residual = residual
                        .max((0..2).map(|i| (d[i] - f[i]).abs() / scale(f[i])).fold(0.0, f64::max));
                    samples.push((t, y, false));
                    // dense(t, k + 1) is the derivative of dense(t, k), k = 0, 1, 2.
                    let delta = 1e-5 * h;
                    for k in 0..3 {
                        let up = solver.dense(t + delta, k).unwrap().to_vec();
                        let down = solver.dense(t - delta, k).unwrap().to_vec();
                        let exact = solver.dense(t, k + 1).unwrap().to_vec();
                        let size = exact.iter().chain(&up).fold(1.0f64, |m, v| m.max(v.abs()));
                        for i in 0..2 {
                            let fd = (up[i] - down[i]) / (2.0 * delta);
                            fd_mismatch = fd_mismatch.max((fd - exact[i]).abs() / size);
                        }
                    }
                }
                prev = step.t;
            }
            let tight = Options {
                max_steps: Some(1_000_000),
                ..Options::new(1e-13, Tolerance::Scalar(1e-13))
            };
            let mut reference =
                stickslip::integrate::Radau5::new(VanDerPol(1.0), 0.0, &[2.0, 0.0], &tight)
                    .unwrap();
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
                "{}, rtol {rtol:.0e}: {} steps; error/tol at step ends {at_ends:.2}, inside steps {inside:.2}; \
                 |dense'(t) − f(dense(t))|/tol inside {residual:.1}, at the ends {end_slope:.1}; finite-difference mismatch {fd_mismatch:.1e}",
                if stiff { "linearly implicit (SEULEX dense output)" } else { "midpoint (ODEX dense output)" },
                solver.stats().steps
            );
            // Measured, inside steps (ends ≤ 1.3): ODEX's interpolant 5.6 and 8.5 × tol; SEULEX's
            // 24 and 58 × tol with the default sequence 2, 3, 4, … (7 and 16 × tol with the
            // harmonic 1, 2, 3, …, on its 10–15 steps against 11–14): the interpolants stay within
            // two orders of the steps' accuracy (Radau5's: 6.4, 12.8), unlike a cubic Hermite on
            // these long steps.
            let bound = if stiff { 100.0 } else { 40.0 };
            assert!(
                inside < bound && inside < bound * at_ends.max(1.0),
                "inside {inside}, ends {at_ends}"
            );
            assert!(
                fd_mismatch < 1e-5,
                "dense(t, k + 1) is not the derivative of dense(t, k): {fd_mismatch:e}"
            );
            if !stiff {
                // ODEX's interpolant has f at the step ends as its slope.
                assert!(end_slope < 1e-3, "{end_slope}");
            }
        }
    }
}

#[test]
fn drr_at_gamma_1e8_from_the_slow_manifold() {
    let drr = Drr::new(DrrParams::new(1e8, 0.8, 1.0, Friction::Log));
    // The scene default start: v = 0.5, θ at its fixed-point value, u on the slow manifold.
    let (w, theta) = (0.5f64.ln(), drr.fixed_point()[2]);
    let y0 = [drr.manifold_u(w, theta), w, theta];
    let options = |rtol: f64| Options::new(rtol, Tolerance::PerComponent(vec![rtol * 1e-2; 3]));

    // Without re-basing, the arrest after the first slip needs steps below the spacing of t
    // (as for Radau5 and CVODE).
    let mut plain = Extrapolation::new(drr, 0.0, &y0, &options(1e-8)).unwrap();
    let error = loop {
        match plain.advance(100.0, Task::OneStep) {
            Ok(step) => assert!(step.t < 100.0, "expected a step underflow in the first arrest"),
            Err(e) => break e,
        }
    };
    assert_eq!(error.kind, ErrorKind::StepUnderflow, "{error}");
    assert!(error.t > 5.0 && error.t < 5.1 && error.state.iter().all(|v| v.is_finite()), "{error}");

    for rtol in [1e-8, 1e-10] {
        let mut ours = Extrapolation::new(drr, 0.0, &y0, &options(rtol)).unwrap();
        let (steps, peaks) = drr_cycles(&mut ours, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let s = ours.stats();
        let mut cvode =
            Solver::cvode(drr, CvodeSettings::default(), 0.0, &y0, &options(rtol)).unwrap();
        let (cvode_steps, cvode_peaks) =
            drr_cycles(&mut cvode, 100.0).unwrap_or_else(|e| panic!("{e}"));
        let c = cvode.stats();
        println!(
            "DRR γ = 1e8, rtol {rtol:.0e}, t ∈ [0, 100]: Extrapolation {steps} steps ({} attempts, {} error-test and {} row \
             failures), {} RHS, {} Jacobians, {} LU, {} restarts, {} switches, peaks at {peaks:.9?}; CVODE {cvode_steps} \
             steps, {} RHS, {} LU, peaks at {cvode_peaks:.9?}",
            s.step_attempts,
            s.err_test_fails,
            s.step_solve_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            s.reinits,
            ours.switches(),
            c.rhs_evals,
            c.lin_setups
        );
        assert_eq!(s.steps, steps);
        assert_eq!(s.reinits, peaks.len() as u64);
        assert_eq!(peaks.len(), cvode_peaks.len());
        assert!(!peaks.is_empty() && ours.switches() > 0);
        // Measured: 288 and 375 steps (CVODE: 6520 and 12457).
        assert!(steps < 2000, "{steps} steps");
        if rtol <= 1e-10 {
            // Measured: the peaks agree with CVODE's within 3e-8 (CVODE's second peak moves
            // by 2e-6 between the two tolerances) and with Radau5's within 5e-10.
            for (a, b) in peaks.iter().zip(&cvode_peaks) {
                assert!(((a - b) / b).abs() < 1e-6, "peaks {peaks:?} vs CVODE {cvode_peaks:?}");
            }
        }
    }
}

/// Extrapolation's own part of the contract (the rest is tests/contract.rs, over every
/// method): derivatives up to the third, the first step kept across restarts, the linearly
/// implicit scheme's Jacobian and LU counts, and backward integration with either scheme.
#[test]
fn dense_derivatives_restarts_jacobian_counts_and_both_schemes_backward() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));
    let mut solver = Extrapolation::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap();
    assert_eq!(solver.name(), "extrapolation");
    solver.advance(1.0, Task::Normal).unwrap();
    let end = solver.advance(10.0, Task::OneStep).unwrap().t;
    let (y, dy) = (solver.state().to_vec(), solver.dense(end, 1).unwrap().to_vec());
    assert!((y[0] - end.sin()).abs() < 1e-7 && (dy[0] - end.cos()).abs() < 1e-6, "{y:?} {dy:?}");
    // Derivatives up to the third; k = 4 is refused.
    let d3 = solver.dense(end, 3).unwrap().to_vec();
    assert!((d3[0] + end.cos()).abs() < 1e-4, "{d3:?}");
    assert_eq!(solver.dense(end, 4).unwrap_err().kind, ErrorKind::InvalidInput);

    // Restart: the step history starts afresh, the first step of the run is kept.
    let before = solver.stats();
    solver.reinit(0.0, &[0.0, 1.0]).unwrap();
    solver.advance(2.0, Task::Normal).unwrap();
    assert_eq!(solver.stats().initial_step, before.initial_step, "the very first step of the run");
    assert!((solver.state()[0] - 2f64.sin()).abs() < 1e-7);

    // The linearly implicit scheme with a finite-difference Jacobian: n RHS calls per
    // Jacobian, counted apart; one LU per row.
    let mut implicit =
        Extrapolation::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap().force_scheme(true);
    implicit.advance(2.0, Task::Normal).unwrap();
    assert!(implicit.is_stiff() && (implicit.state()[0] - 2f64.sin()).abs() < 1e-7);
    let s = implicit.stats();
    assert!(s.jac_evals > 0 && s.rhs_evals_jacobian == 2 * s.jac_evals, "{s:?}");
    assert!(s.lin_setups >= 2 * s.step_attempts, "{s:?}");
    // A restart keeps a forced scheme.
    implicit.reinit(0.0, &[0.0, 1.0]).unwrap();
    assert!(implicit.is_stiff());

    // Backward in time: y' = −y from y(0) = 1 to t = −1 gives e; both schemes.
    for stiff in [false, true] {
        let options = Options::new(1e-10, Tolerance::Scalar(1e-12));
        let mut backward =
            Extrapolation::new(Linear(-1.0), 0.0, &[1.0], &options).unwrap().force_scheme(stiff);
        backward.advance(-1.0, Task::Normal).unwrap();
        assert!(
            (backward.state()[0] - std::f64::consts::E).abs() < 1e-8,
            "{}",
            backward.state()[0]
        );
        let end = backward.advance(-5.0, Task::OneStep).unwrap().t;
        assert!(
            end < -1.0
                && backward.dense(end, 0).is_ok()
                && backward.dense(0.5 * (end - 1.0), 1).is_ok()
        );
    }
}

/// y' = y² from y(0) = 1: y = 1/(1 − t) blows up at t = 1.
struct BlowUp;

impl OdeSystem for BlowUp {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = y[0] * y[0];
    }
}

/// A right-hand side that returns +∞ in the first component whenever y0 < 0.5.
struct InfinityBelow;

impl OdeSystem for InfinityBelow {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = if y[0] < 0.5 { f64::INFINITY } else { -y[0] };
        dydt[1] = y[0] - y[1];
    }
}

#[test]
fn failures_specific_to_extrapolation() {
    let options = Options::new(1e-8, Tolerance::Scalar(1e-10));

    // NaN from t > 0.5 on: halved steps do not help; the error names the RHS (both schemes;
    // the default one is also in tests/contract.rs).
    for stiff in [None, Some(true)] {
        let mut solver = Extrapolation::new(NanAfter(0.5), 0.0, &[1.0], &options).unwrap();
        if let Some(s) = stiff {
            solver = solver.force_scheme(s);
        }
        let e = solver.advance(1.0, Task::Normal).unwrap_err();
        assert_eq!(e.kind, ErrorKind::RhsFailure, "{e}");
        assert!(e.t <= 0.5 && e.t > 0.4 && e.state.len() == 1 && e.state[0].is_finite(), "{e}");
        assert!(solver.stats().nonfinite_rhs >= 10);
        assert_eq!((solver.t(), solver.state()), (e.t, &e.state[..]));
    }

    // A singular iteration matrix: y' = λy with λ = 2/h exactly and the first row (two
    // linearly implicit Euler steps of h/2 with the default sequence 2, 3, 4, …: I/(h/2) − λ = 0)
    // at a fixed step: no escape.
    let h = 0.5;
    let mut solver = Extrapolation::new(Linear(2.0 / h), 0.0, &[1.0], &options)
        .unwrap()
        .force_scheme(true)
        .fixed_step(h, 1);
    let e = solver.advance(1.0, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::LinearSolver, "{e}");
    // Adaptive steps escape the same singularity by halving h.
    let mut adaptive = Extrapolation::new(
        Linear(2.0 / h),
        0.0,
        &[1.0],
        &Options { initial_step: Some(h), ..options.clone() },
    )
    .unwrap()
    .force_scheme(true);
    adaptive.advance(0.1, Task::Normal).unwrap();
    assert!((adaptive.state()[0] - 0.4f64.exp()).abs() < 1e-7);

    // Time too large for the steps the problem needs: t + h = t.
    let mut solver = Extrapolation::new(Linear(-1.0), 1e20, &[1.0], &options).unwrap();
    let e = solver.advance(1e20 + 1e6, Task::Normal).unwrap_err();
    assert_eq!(e.kind, ErrorKind::StepUnderflow, "{e}");

    // A negative fixed step.
    let mut solver =
        Extrapolation::new(Oscillator, 0.0, &[0.0, 1.0], &options).unwrap().fixed_step(-1.0, 2);
    assert_eq!(solver.advance(1.0, Task::Normal).unwrap_err().kind, ErrorKind::InvalidInput);

    // Never a panic: blow-up, infinite f, extreme stiffness, tiny tolerances; each call returns
    // a result (an error is fine) and the solver stays usable for a restart.
    let run = |f: &dyn Fn() -> Result<(), stickslip::integrate::SolverError>| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
    };
    let outcomes = [
        run(&|| {
            let mut s = Extrapolation::new(BlowUp, 0.0, &[1.0], &options)?;
            s.advance(2.0, Task::Normal).map(|_| ())
        }),
        run(&|| {
            let mut s = Extrapolation::new(InfinityBelow, 0.0, &[1.0, 0.0], &options)?;
            s.advance(5.0, Task::Normal).map(|_| ())
        }),
        run(&|| {
            let mut s = Extrapolation::new(Linear(-1e300), 0.0, &[1.0], &options)?;
            s.advance(1.0, Task::Normal).map(|_| ())
        }),
        run(&|| {
            let mut s = Extrapolation::new(Linear(1e3), 0.0, &[1.0], &options)?;
            s.advance(10.0, Task::Normal).map(|_| ())
        }),
        run(&|| {
            let mut s = Extrapolation::new(
                VanDerPol(1e-6),
                0.0,
                &[2.0, 0.0],
                &Options::new(1e-16, Tolerance::Scalar(0.0)),
            )?;
            s.advance(0.1, Task::Normal).map(|_| ())
        }),
    ];
    for (i, outcome) in outcomes.iter().enumerate() {
        let result = outcome.as_ref().unwrap_or_else(|_| panic!("case {i} panicked"));
        println!("case {i}: {:?}", result.as_ref().map_err(|e| (e.kind.clone(), e.t)));
    }
    // The blow-up ends in a typed error at the singularity t = 1 (measured: a step underflow
    // at 1 + 1.2e-9, where y ≈ 1e9).
    let e = outcomes[0].as_ref().unwrap().as_ref().unwrap_err();
    assert!((e.t - 1.0).abs() < 1e-6, "{e}");
}

/// The stability boundaries of the explicit scheme are a constant computed once: two integrators
/// built one after the other take the same steps to the same result.
#[test]
fn two_constructions_integrate_identically() {
    let options = Options::new(1e-6, Tolerance::Scalar(1e-6));
    let run = || {
        let mut solver = Extrapolation::new(VanDerPol(1e-3), 0.0, &[2.0, 0.0], &options).unwrap();
        solver.advance(1.0, Task::Normal).unwrap();
        (solver.state().to_vec(), solver.stats(), solver.switches())
    };
    let (first, second) = (run(), run());
    assert_eq!(first, second);
    assert!(first.2 > 0, "the run must switch schemes, so that the boundaries are used: {first:?}");
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
    let report =
        stickslip::engine::run(&scene, serde_json::Value::Null).unwrap_or_else(|e| panic!("{e}"));
    let cycle = report.cycle.expect("the scene asks for the cycle");
    cycle.values.expect("a converged cycle").period
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
