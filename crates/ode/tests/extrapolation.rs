//! The homemade extrapolation integrator with stiffness switching (linearly implicit Euler
//! extrapolation / modified midpoint extrapolation, as Mathematica's "StiffnessSwitching"):
//! convergence with the tolerance, switching in both directions, its dense derivatives and
//! counts and the failures its own knobs produce (the orders of the tableaux with fixed
//! steps, Prothero–Robinson, VDPOL and dense output of both schemes are tests/methods.rs, run
//! over every homemade method; the Integrator contract is tests/contract.rs, run over every
//! method; the deep arrest floor is the workspace's tests/integrators_on_model.rs).

use stickslip_ode::integrate::{
    ErrorKind, Extrapolation, Integrator, JacobianMatrix, OdeSystem, Options, Task, Tolerance,
};

mod common;
use common::{Linear, NanAfter, Oscillator, VanDerPol};

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

/// Extrapolation's own part of the contract (the rest, restarts included, is tests/contract.rs,
/// over every method): derivatives up to the third, the linearly implicit scheme's Jacobian and
/// LU counts, a forced scheme kept across a restart, and backward integration with either
/// scheme.
#[test]
fn dense_derivatives_jacobian_counts_forced_scheme_and_both_schemes_backward() {
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
    let run = |f: &dyn Fn() -> Result<(), stickslip_ode::integrate::SolverError>| {
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
