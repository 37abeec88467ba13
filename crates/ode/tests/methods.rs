//! One suite over the methods, driven by the table [`row`]: for every homemade method
//! (radau5, rodas5p, extrapolation) the convergence order with fixed steps, the stiff
//! Prothero–Robinson problem, the Test Set's VDPOL at ε = 1e-6, dense output against a tight
//! run; for CVODE's BDF and ARKStep's DIRK, VDPOL (CVODE's BDF is the partner of the others
//! there). Each row carries its method's bounds (measured, see the comments); what only one
//! method has is tested in tests/radau5.rs, tests/rodas5p.rs and tests/extrapolation.rs, and
//! the Integrator contract over every method in tests/contract.rs. The homemade methods on
//! the stickslip library's spring-slider are the workspace's tests/integrators_on_model.rs.

use std::ops::RangeInclusive;

use stickslip_ode::integrate::{
    Extrapolation, Integrator, OdeSystem, Options, Radau5, Rodas5p, Stats, Step, StepEvent, Task,
    Tolerance,
};
use stickslip_ode::solver::{build_default, Method};

mod common;
use common::{observed_orders, sci, Forced, Oscillator, ProtheroRobinson, Tan, VanDerPol, Warped};

/// Settings of a method that a case turns (each method's defaults otherwise).
#[derive(Debug, Clone, Copy, Default)]
struct Knobs {
    /// Rodas5P: f declared independent of t.
    autonomous: bool,
    /// Extrapolation: only the linearly implicit (true) or only the explicit (false) scheme.
    scheme: Option<bool>,
    /// Extrapolation: the first step number n_1 of the linearly implicit sequence (None: the
    /// default).
    first: Option<usize>,
    /// Extrapolation: the tableau column of a fixed step.
    column: usize,
}

/// A method under test: the Integrator contract, and extrapolation's scheme switches.
enum Subject<S: OdeSystem + 'static> {
    /// Extrapolation, which switches between its schemes.
    Extrapolation(Box<Extrapolation<S>>),
    /// Any other method.
    Plain(Box<dyn Integrator>),
}

impl<S: OdeSystem + 'static> Subject<S> {
    /// `method` with `knobs` on `system` from (0, y0); with a constant step h if `fixed`.
    fn build(
        method: Method,
        knobs: Knobs,
        system: S,
        y0: &[f64],
        options: &Options,
        fixed: Option<f64>,
    ) -> Self {
        match method {
            Method::Radau5 => {
                let mut s = Radau5::new(system, 0.0, y0, options).unwrap();
                if let Some(h) = fixed {
                    s = s.fixed_step(h);
                }
                Subject::Plain(Box::new(s))
            }
            Method::Rodas5p => {
                let mut s = Rodas5p::new(system, 0.0, y0, options).unwrap();
                if knobs.autonomous {
                    s = s.autonomous();
                }
                if let Some(h) = fixed {
                    s = s.fixed_step(h);
                }
                Subject::Plain(Box::new(s))
            }
            Method::Extrapolation => {
                Subject::Extrapolation(Box::new(extrapolation(knobs, system, y0, options, fixed)))
            }
            _ => {
                assert!(fixed.is_none(), "{method}: no fixed step");
                Subject::Plain(build_default(method, system, 0.0, y0, options).unwrap())
            }
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

/// Extrapolation with `knobs`, as [`Subject::build`].
fn extrapolation<S: OdeSystem>(
    knobs: Knobs,
    system: S,
    y0: &[f64],
    options: &Options,
    fixed: Option<f64>,
) -> Extrapolation<S> {
    let mut s = Extrapolation::new(system, 0.0, y0, options).unwrap();
    if let Some(first) = knobs.first {
        s = s.implicit_sequence(first);
    }
    if let Some(stiff) = knobs.scheme {
        s = s.force_scheme(stiff);
    }
    if let Some(h) = fixed {
        s = s.fixed_step(h, knobs.column);
    }
    s
}

/// A problem with a known solution for the fixed-step tests.
#[derive(Debug, Clone, Copy)]
enum Problem {
    /// [`Tan`] to t = 1.
    Tan,
    /// [`Oscillator`] to t = 2.
    Oscillator,
    /// [`Warped`] to t = 2.
    Warped,
    /// [`Forced`] to t = 2.
    Forced,
    /// [`ProtheroRobinson`] with this λ to t = 1.
    ProtheroRobinson(f64),
}

impl Problem {
    /// The error (Euclidean norm) at the end of a run of `method` with the constant step h.
    fn fixed_step_error(self, method: Method, knobs: Knobs, h: f64) -> f64 {
        let run = |y0: &[f64], tend| (method, knobs, y0.to_vec(), tend, h);
        match self {
            Problem::Tan => distance(&fixed_step(Tan, run(&[0.0], 1.0)), &[1f64.tan()]),
            Problem::Oscillator => {
                distance(&fixed_step(Oscillator, run(&[0.0, 1.0], 2.0)), &[2f64.sin(), 2f64.cos()])
            }
            Problem::Warped => {
                distance(&fixed_step(Warped, run(&Warped::exact(0.0), 2.0)), &Warped::exact(2.0))
            }
            Problem::Forced => distance(&fixed_step(Forced, run(&[1.0], 2.0)), &[2f64.sin().exp()]),
            Problem::ProtheroRobinson(lambda) => {
                distance(&fixed_step(ProtheroRobinson(lambda), run(&[1.0], 1.0)), &[1f64.cos()])
            }
        }
    }
}

/// Euclidean distance.
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// Integrates `system` from (0, y0) to `tend` with the constant step h (the stop time makes
/// the last step land on `tend` exactly): `run` is (method, knobs, y0, tend, h). Returns
/// y(tend).
fn fixed_step<S: OdeSystem + 'static>(
    system: S,
    run: (Method, Knobs, Vec<f64>, f64, f64),
) -> Vec<f64> {
    let (method, knobs, y0, tend, h) = run;
    let options = Options {
        stop_time: Some(tend),
        max_steps: Some(100_000),
        // Zero starting values on the first step need more than RADAU5's 7 iterations at
        // this Newton tolerance when h may not shrink.
        max_nonlin_iters: (method == Method::Radau5).then_some(50),
        ..Options::new(1e-13, Tolerance::Scalar(1e-13))
    };
    let mut subject = Subject::build(method, knobs, system, &y0, &options, Some(h));
    let integ = subject.integ();
    let step = integ.advance(tend + 1.0, Task::Normal).unwrap();
    assert_eq!(step, Step { t: tend, event: StepEvent::StopTime });
    assert_eq!(integ.stats().steps, (tend / h).round() as u64, "h = {h}");
    let y = integ.state().to_vec();
    assert_eq!(subject.switches().map_or(0, |s| s.0), 0, "a fixed step never switches");
    y
}

/// A convergence-order case: the error at the end of fixed-step runs with the steps h.
struct OrderCase {
    /// The problem.
    problem: Problem,
    /// The method's settings.
    knobs: Knobs,
    /// The constant steps, each half the one before.
    steps: &'static [f64],
    /// The order expected.
    order: f64,
    /// How far each observed order may be from it.
    within: f64,
    /// Only the last halving is checked (an order approached from below).
    last_only: bool,
}

/// A Prothero–Robinson case: the stiff problem with fixed steps hλ ≫ 1.
struct ProtheroCase {
    /// λ.
    lambda: f64,
    /// The method's settings.
    knobs: Knobs,
    /// The constant steps, each half the one before.
    steps: &'static [f64],
    /// Bound below on every observed order.
    min_order: f64,
    /// Bound on every error.
    max_error: f64,
}

/// A VDPOL case: the run at rtol = atol.
struct VdpolCase {
    /// The method's settings.
    knobs: Knobs,
    /// rtol = atol.
    rtol: f64,
    /// The step budget.
    max_steps: i64,
    /// Bound on the relative error of each component against the Test Set.
    error: Option<f64>,
    /// Bound on the relative difference of each component from CVODE's BDF at the same
    /// tolerances.
    cvode: Option<f64>,
}

/// The VDPOL cases of a method and what its statistics must show.
struct Vdpol {
    /// The runs.
    cases: Vec<VdpolCase>,
    /// Bound below on the accepted steps.
    min_steps: u64,
    /// The order of the last step.
    last_order: RangeInclusive<i32>,
    /// The method's own relations between its counters.
    counts: fn(&Stats),
}

/// A dense-output case on van der Pol (ε = 1) to t = 3, against a tight Radau5 run.
struct DenseCase {
    /// The method's settings.
    knobs: Knobs,
    /// rtol = atol.
    rtol: f64,
    /// Bound on the error/tol inside the steps, and on its ratio to the error/tol at the step
    /// ends (taken as at least 1).
    inside: (f64, f64),
    /// Bound on |dense'(t) − f(dense(t))|/tol at the sample points inside the steps.
    defect: f64,
    /// Points θ of the step where the method's polynomial satisfies the ODE (collocation
    /// nodes) and the bound on its defect there.
    nodes: Option<(Vec<f64>, f64)>,
    /// Bound on the finite-difference mismatch of dense(t, k + 1) against dense(t, k), k
    /// below the method's dense order.
    fd: f64,
    /// Bound on |dense'(t) − f(y)|/tol at the step ends.
    end_slope: Option<f64>,
}

/// A method's row of the table.
struct Row {
    /// Fixed-step order cases.
    orders: Vec<OrderCase>,
    /// Prothero–Robinson cases.
    prothero: Vec<ProtheroCase>,
    /// VDPOL.
    vdpol: Vdpol,
    /// Dense-output cases.
    dense: Vec<DenseCase>,
}

/// Steps halving from 0.2.
const FROM_0_2: &[f64] = &[0.2, 0.1, 0.05, 0.025];
/// Steps halving from 0.5.
const FROM_0_5: &[f64] = &[0.5, 0.25, 0.125, 0.0625];

/// The table: each method's cases and bounds.
fn row(method: Method) -> Row {
    match method {
        Method::Radau5 => radau5(),
        Method::Rodas5p => rodas5p(),
        Method::Extrapolation => extrapolation_row(),
        Method::CvodeBdf => cvode_bdf(),
        Method::ArkodeDirk => arkode_dirk(),
        other => panic!("{other} has no row"),
    }
}

/// An order case with default knobs, every halving checked.
fn order(problem: Problem, steps: &'static [f64], order: f64, within: f64) -> OrderCase {
    OrderCase { problem, knobs: Knobs::default(), steps, order, within, last_only: false }
}

fn radau5() -> Row {
    let sq6 = 6f64.sqrt();
    Row {
        orders: vec![
            order(Problem::Tan, FROM_0_2, 5.0, 0.3),
            order(Problem::Oscillator, FROM_0_5, 5.0, 0.3),
        ],
        // Radau IIA is stiffly accurate: with hλ ≫ 1 the error at the grid points falls like
        // h^3 (the stage order), without the order collapse of non-stiffly-accurate methods.
        // Measured: errors 6.1e-11 … 1.1e-13, orders 3.09, 3.05, 3.02 (the asymptotic value
        // is 3 exactly, approached from above).
        prothero: vec![ProtheroCase {
            lambda: 1e6,
            knobs: Knobs::default(),
            steps: FROM_0_2,
            min_order: 2.95,
            max_error: 1e-10,
        }],
        vdpol: Vdpol {
            // Test Set and CVODE to eight digits.
            cases: vec![VdpolCase {
                knobs: Knobs::default(),
                rtol: 1e-12,
                max_steps: 100_000,
                error: Some(1e-8),
                cvode: Some(1e-8),
            }],
            min_steps: 100,
            last_order: 5..=5,
            counts: |s| {
                assert!(s.lin_setups <= s.step_attempts && s.jac_evals <= s.lin_setups, "{s:?}")
            },
        },
        dense: [1e-6, 1e-8]
            .map(|rtol| DenseCase {
                knobs: Knobs::default(),
                rtol,
                // Measured (rtol 1e-6, 1e-8): inside 7.9, 13.4 × tol over the whole run
                // (mostly global error; the cubic continuous output is of order 3 against the
                // step's 5).
                inside: (30.0, 20.0),
                // Between the collocation nodes the defect of a stage-order-3 polynomial is
                // O(h³) (measured 431 and 5298 × tol; CVODE's interpolant: 390 and 1200 ×
                // tol); at the nodes the derivative is f up to the Newton tolerance (measured
                // 90 and 51 × tol).
                defect: 2e4,
                nodes: Some((vec![(4.0 - sq6) / 10.0, (4.0 + sq6) / 10.0, 1.0], 500.0)),
                fd: 1e-6,
                end_slope: None,
            })
            .into(),
    }
}

fn rodas5p() -> Row {
    let autonomous = Knobs { autonomous: true, ..Knobs::default() };
    Row {
        // On linear problems only the stability function counts: it matches e^z to order 6
        // (the tall-tree condition of order 6 holds), so the oscillator shows order 6.
        // Forced is non-autonomous: ∂f/∂t by a forward difference.
        orders: vec![
            order(Problem::Tan, FROM_0_2, 5.0, 0.35),
            order(Problem::Oscillator, FROM_0_5, 6.0, 0.35),
            order(Problem::Warped, &[0.4, 0.2, 0.1, 0.05], 5.0, 0.35),
            order(Problem::Forced, FROM_0_2, 5.0, 0.35),
        ],
        // With hλ ≫ 1 the error stays small (∝ 1/λ) and still falls like h³: no collapse of
        // the order (Rodas5P was built with Prothero–Robinson in view, as Rodas4P and
        // Rodas4P2). Measured: λ = 1e3 errors 2.5e-8 … 1.6e-12 (orders 3.5, 3.9, 6.5 through
        // the transition hλ ~ 1); λ = 1e6 errors 3.3e-11 … 5.6e-14 (orders 3.10, 3.06, 3.04:
        // the error behaves like h³/λ, the same with an exact ∂f/∂t through the autonomised
        // form).
        prothero: [1e3, 1e6]
            .map(|lambda| ProtheroCase {
                lambda,
                knobs: Knobs::default(),
                steps: FROM_0_2,
                min_order: 2.95,
                max_error: 5e-8 * 1e3 / lambda,
            })
            .into(),
        vdpol: Vdpol {
            cases: [1e-6, 1e-8, 1e-10]
                // Measured: 623, 1986 and 6926 steps; relative error 1.1e-10 at rtol 1e-10.
                .map(|rtol| VdpolCase {
                    knobs: autonomous,
                    rtol,
                    max_steps: 1_000_000,
                    error: (rtol <= 1e-10).then_some(1e-6),
                    cvode: None,
                })
                .into(),
            min_steps: 100,
            last_order: 5..=5,
            counts: |s| {
                assert_eq!(s.nonlin_iters, 0);
                assert!(
                    s.step_attempts == s.steps + s.err_test_fails
                        && s.lin_setups == s.step_attempts,
                    "{s:?}"
                );
                assert_eq!(s.jac_evals, s.steps, "one Jacobian per step, kept across rejections");
                assert_eq!(
                    s.rhs_evals,
                    7 * s.step_attempts + s.steps + 2,
                    "7 stages per attempt, f at each accepted point, f(t0) and the initial-step \
                     probe"
                );
            },
        },
        dense: [1e-6, 1e-8]
            .map(|rtol| DenseCase {
                knobs: Knobs::default(),
                rtol,
                // Measured (rtol 1e-6, 1e-8): inside 1.74, 2.60 × tol against 1.63, 2.53 at
                // the step ends (the order-4 continuous output adds almost nothing to the
                // global error); the defect of the interpolant 35 and 94 × tol (Radau5's
                // cubic: 450 and 5300 between its nodes).
                inside: (10.0, 2.0),
                defect: 1e3,
                nodes: None,
                fd: 1e-5,
                end_slope: None,
            })
            .into(),
    }
}

/// Extrapolation's order cases on Tan: linearly implicit Euler (n_1 = 1 and 2), T_{k,k} of
/// order k; the modified midpoint rule, order 2k. The asymptotic value is approached from
/// below (measured within 0.2 on the last halving).
fn extrapolation_tableau_orders() -> Vec<OrderCase> {
    let case = |stiff: bool, first: usize, column: usize| OrderCase {
        problem: Problem::Tan,
        knobs: Knobs { scheme: Some(stiff), first: Some(first), column, ..Knobs::default() },
        steps: if stiff { FROM_0_2 } else { FROM_0_5 },
        order: if stiff { column as f64 } else { 2.0 * column as f64 },
        within: 0.25,
        last_only: true,
    };
    let mut cases = Vec::new();
    for first in [1, 2] {
        cases.extend([2, 3, 4].map(|k| case(true, first, k)));
    }
    cases.extend([1, 2, 3].map(|k| case(false, 1, k)));
    cases
}

fn extrapolation_row() -> Row {
    let mut orders = extrapolation_tableau_orders();
    // The oscillator with the midpoint scheme, column 2 (order 4).
    orders.push(OrderCase {
        knobs: Knobs { scheme: Some(false), column: 2, ..Knobs::default() },
        ..order(Problem::Oscillator, &[0.5, 0.25, 0.125], 4.0, 0.2)
    });
    Row {
        orders,
        // Linearly implicit Euler, column 3: measured errors 8.0e-12 … 1.5e-14, orders 3.04,
        // 3.03, 2.95 (the last halving near the rounding level).
        prothero: vec![ProtheroCase {
            lambda: 1e6,
            knobs: Knobs { scheme: Some(true), column: 3, ..Knobs::default() },
            steps: FROM_0_2,
            min_order: 2.9,
            max_error: 1e-11,
        }],
        vdpol: Vdpol {
            // SEULEX's harmonic sequence 1, 2, 3, … and the default (Mathematica's) 2, 3, 4,
            // …: measured 3436 and 294 steps, 85 760 and 17 663 RHS, 24 438 and 2 291 LU;
            // relative errors 2.1e-10 (n_1 = 1) and 1.6e-10 (n_1 = 2). It starts
            // explicit and detects the stiffness at once; the two fast jumps are taken
            // explicitly (2 switches each).
            cases: [1, 2]
                .map(|first| VdpolCase {
                    knobs: Knobs { first: Some(first), ..Knobs::default() },
                    rtol: 1e-10,
                    max_steps: 100_000,
                    error: Some(1e-8),
                    cvode: Some(1e-6),
                })
                .into(),
            min_steps: 50,
            last_order: 1..=12,
            counts: |s| {
                assert!(s.jac_evals <= s.step_attempts && s.jac_evals <= s.lin_setups, "{s:?}")
            },
        },
        dense: extrapolation_dense(),
    }
}

/// Extrapolation's dense output, each scheme alone. Measured, inside steps (ends ≤ 1.3):
/// ODEX's interpolant 5.6 and 8.5 × tol; SEULEX's 24 and 58 × tol with the default sequence
/// 2, 3, 4, … (7 and 16 × tol with the harmonic 1, 2, 3, …, on its 10–15 steps against
/// 11–14): the interpolants stay within two orders of the steps' accuracy (Radau5's: 6.4,
/// 12.8), unlike a cubic Hermite on these long steps. The defect |dense'(t) − f(dense(t))|/tol:
/// measured 43 and 216 (ODEX), 209 and 2956 (SEULEX). ODEX's interpolant has f at the step
/// ends as its slope.
fn extrapolation_dense() -> Vec<DenseCase> {
    let mut cases = Vec::new();
    for stiff in [false, true] {
        let bound = if stiff { 100.0 } else { 40.0 };
        cases.extend([1e-6, 1e-9].map(|rtol| DenseCase {
            knobs: Knobs { scheme: Some(stiff), ..Knobs::default() },
            rtol,
            inside: (bound, bound),
            defect: 1e4,
            nodes: None,
            fd: 1e-5,
            end_slope: (!stiff).then_some(1e-3),
        }));
    }
    cases
}

fn cvode_bdf() -> Row {
    Row {
        orders: Vec::new(),
        prothero: Vec::new(),
        // The partner of radau5's and extrapolation's VDPOL runs, at their tolerances: measured
        // relative errors 1.4e-10 at rtol 1e-12 (11 538 steps) and 9.6e-9 at 1e-10 (6 069).
        vdpol: Vdpol {
            cases: [(1e-12, 1e-8), (1e-10, 1e-6)]
                .map(|(rtol, error)| VdpolCase {
                    knobs: Knobs::default(),
                    rtol,
                    max_steps: 100_000,
                    error: Some(error),
                    cvode: None,
                })
                .into(),
            min_steps: 100,
            last_order: 1..=5,
            counts: |s| assert!(s.jac_evals <= s.lin_setups, "{s:?}"),
        },
        dense: Vec::new(),
    }
}

fn arkode_dirk() -> Row {
    Row {
        orders: Vec::new(),
        prothero: Vec::new(),
        // ARKStep's default DIRK (order 4) as solver::build sets it up: measured relative error
        // 1.4e-9 in 27 174 steps at rtol 1e-8 (2.0e-11 in 253 180 steps, 3 s, at 1e-10: not
        // run).
        vdpol: Vdpol {
            cases: vec![VdpolCase {
                knobs: Knobs::default(),
                rtol: 1e-8,
                max_steps: 1_000_000,
                error: Some(1e-8),
                cvode: None,
            }],
            min_steps: 100,
            last_order: 4..=4,
            counts: |s| assert!(s.jac_evals <= s.lin_setups, "{s:?}"),
        },
        dense: Vec::new(),
    }
}

/// Fixed steps converge with the method's order on smooth problems.
fn fixed_step_order(method: Method) {
    for case in row(method).orders {
        let errors: Vec<f64> = case
            .steps
            .iter()
            .map(|&h| case.problem.fixed_step_error(method, case.knobs, h))
            .collect();
        let orders = observed_orders(&errors);
        println!(
            "{:?} {:?}: errors {}, observed orders {orders:.3?}",
            case.problem,
            case.knobs,
            sci(&errors)
        );
        let checked = if case.last_only { &orders[orders.len() - 1..] } else { &orders[..] };
        assert!(
            checked.iter().all(|p| (p - case.order).abs() < case.within),
            "{:?} {:?}: errors {}, orders {orders:?}",
            case.problem,
            case.knobs,
            sci(&errors)
        );
    }
}

/// Fixed steps on the stiff Prothero–Robinson problem keep an order (no collapse).
fn prothero_robinson(method: Method) {
    for case in row(method).prothero {
        let problem = Problem::ProtheroRobinson(case.lambda);
        let errors: Vec<f64> =
            case.steps.iter().map(|&h| problem.fixed_step_error(method, case.knobs, h)).collect();
        let orders = observed_orders(&errors);
        println!(
            "Prothero–Robinson λ = {:e}: errors {}, observed orders {orders:.3?}",
            case.lambda,
            sci(&errors)
        );
        assert!(errors.iter().all(|&e| e < case.max_error), "errors {}", sci(&errors));
        assert!(
            orders.iter().all(|&p| p > case.min_order),
            "errors {}, orders {orders:?}",
            sci(&errors)
        );
    }
}

/// Test Set for IVP Solvers (Mazzia & Magherini), problem VDPOL: reference at t = 2, computed
/// there with quadruple-precision RADAU5 (rtol = atol = h0 = 1.1e-18).
const VDPOL_REFERENCE: [f64; 2] = [0.1706167732170483e1, -0.8928097010247975];

/// The largest relative difference of y from `reference`, componentwise.
fn relative(y: &[f64], reference: &[f64]) -> f64 {
    y.iter().zip(reference).map(|(a, b)| ((a - b) / b).abs()).fold(0.0, f64::max)
}

/// VDPOL (ε = 1e-6) to t = 2 against the Test Set's reference and CVODE.
fn van_der_pol(method: Method) {
    let vdpol = row(method).vdpol;
    for case in &vdpol.cases {
        let options = Options {
            max_steps: Some(case.max_steps),
            ..Options::new(case.rtol, Tolerance::Scalar(case.rtol))
        };
        let mut subject =
            Subject::build(method, case.knobs, VanDerPol(1e-6), &[2.0, 0.0], &options, None);
        let integ = subject.integ();
        assert_eq!(integ.advance(2.0, Task::Normal).unwrap().event, StepEvent::Reached);
        assert_eq!(integ.t(), 2.0);
        let (ours, s) = (integ.state().to_vec(), integ.stats());
        let error = relative(&ours, &VDPOL_REFERENCE);
        println!(
            "{method} {:?} rtol {:e}: {} (relative error {error:.1e}), {} steps ({} attempts, {} \
             rejected), {} RHS, {} Jacobians, {} LU, last order {}, switches {:?}",
            case.knobs,
            case.rtol,
            sci(&ours),
            s.steps,
            s.step_attempts,
            s.err_test_fails,
            s.rhs_evals,
            s.jac_evals,
            s.lin_setups,
            s.last_order,
            subject.switches()
        );
        if let Some(bound) = case.error {
            assert!(error < bound, "{method}: {} against the Test Set: {error:e}", sci(&ours));
        }
        if let Some(bound) = case.cvode {
            let theirs = vdpol_by_cvode(&options);
            let apart = relative(&ours, &theirs);
            assert!(apart < bound, "{method} and CVODE disagree: {apart:e}");
        }
        assert_eq!(s.rhs_evals_jacobian, 0, "analytic Jacobian: no RHS calls for it");
        assert!(s.steps > vdpol.min_steps && s.step_attempts >= s.steps + s.err_test_fails);
        assert!(vdpol.last_order.contains(&s.last_order), "last order {}", s.last_order);
        (vdpol.counts)(&s);
        if let Some((switches, stiff)) = subject.switches() {
            assert!(switches > 0 && stiff, "switches {switches}, stiff at the end: {stiff}");
        }
    }
}

/// VDPOL (ε = 1e-6) at t = 2 by CVODE's BDF with `options`.
fn vdpol_by_cvode(options: &Options) -> Vec<f64> {
    let mut cvode =
        build_default(Method::CvodeBdf, VanDerPol(1e-6), 0.0, &[2.0, 0.0], options).unwrap();
    cvode.advance(2.0, Task::Normal).unwrap();
    cvode.state().to_vec()
}

/// What a walk through the steps of a run measured on its dense output.
#[derive(Default)]
struct DenseWalk {
    /// (t, y, whether t is a step end).
    samples: Vec<(f64, Vec<f64>, bool)>,
    /// Largest |dense'(t) − f(dense(t))|/tol inside the steps, off the nodes.
    defect: f64,
    /// The same at the collocation nodes.
    node_defect: f64,
    /// Largest |dense'(t) − f(y)|/tol at the step ends.
    end_slope: f64,
    /// Largest relative finite-difference mismatch of dense(t, k + 1), for each k.
    fd: Vec<f64>,
    /// Largest distance of the polynomial at the step start from the previous step end,
    /// relative to 1 + |y|.
    start_gap: f64,
}

/// The sample points θ inside a step.
const THETAS: [f64; 7] = [0.1, 0.25, 0.3, 0.5, 0.7, 0.75, 0.9];

/// Steps `integ` (on van der Pol, ε = 1) to t = 3 one at a time and measures its dense output
/// at the step ends, at [`THETAS`] and at `nodes`; `scale` is the error weight's tol(|y|).
fn walk_dense(integ: &mut dyn Integrator, nodes: &[f64], scale: &dyn Fn(f64) -> f64) -> DenseWalk {
    let mut walk = DenseWalk::default();
    let (mut prev, mut previous_end) = (0.0, integ.state().to_vec());
    while integ.t() < 3.0 {
        let step = integ.advance(3.0, Task::OneStep).unwrap();
        let end = integ.state().to_vec();
        assert_eq!(
            integ.dense(step.t, 0).unwrap(),
            &end[..],
            "the polynomial ends at the step end"
        );
        let start = integ.dense(prev, 0).unwrap().to_vec();
        walk.start_gap = walk.start_gap.max(relative_gap(&start, &previous_end));
        let d = integ.dense(step.t, 1).unwrap().to_vec();
        walk.end_slope = walk.end_slope.max(vdp_defect(step.t, &end, &d, scale));
        sample_inside(integ, (prev, step.t), nodes, scale, &mut walk);
        walk.samples.push((step.t, end.clone(), true));
        (prev, previous_end) = (step.t, end);
    }
    walk
}

/// |y' − f(t, y)|/tol for van der Pol (ε = 1), the largest component.
fn vdp_defect(t: f64, y: &[f64], d: &[f64], scale: &dyn Fn(f64) -> f64) -> f64 {
    let mut f = [0.0; 2];
    VanDerPol(1.0).rhs(t, y, &mut f);
    (0..2).map(|i| (d[i] - f[i]).abs() / scale(f[i])).fold(0.0, f64::max)
}

/// Samples the dense output of the step over `span` at [`THETAS`] and `nodes` into `walk`:
/// the defect, the finite-difference mismatch of the derivatives and the values (at θ < 1).
fn sample_inside(
    integ: &mut dyn Integrator,
    span: (f64, f64),
    nodes: &[f64],
    scale: &dyn Fn(f64) -> f64,
    walk: &mut DenseWalk,
) {
    let h = span.1 - span.0;
    for (j, &theta) in THETAS.iter().chain(nodes).enumerate() {
        let t = span.0 + theta * h;
        let y = integ.dense(t, 0).unwrap().to_vec();
        let d = integ.dense(t, 1).unwrap().to_vec();
        let r = vdp_defect(t, &y, &d, scale);
        if j < THETAS.len() {
            walk.defect = walk.defect.max(r);
        } else {
            walk.node_defect = walk.node_defect.max(r);
        }
        if theta + 1e-5 < 1.0 {
            let mismatch = fd_mismatch(integ, t, 1e-5 * h);
            walk.fd.resize(mismatch.len(), 0.0);
            for (w, m) in walk.fd.iter_mut().zip(mismatch) {
                *w = w.max(m);
            }
            walk.samples.push((t, y, false));
        }
    }
}

/// The largest |a − b|/(1 + |b|), componentwise.
fn relative_gap(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs() / (1.0 + y.abs())).fold(0.0, f64::max)
}

/// For each k below the method's dense order, the largest relative mismatch of dense(t, k + 1)
/// against the central difference of dense(·, k) over t ± delta.
fn fd_mismatch(integ: &mut dyn Integrator, t: f64, delta: f64) -> Vec<f64> {
    (0..integ.max_dense_order())
        .map(|k| {
            let up = integ.dense(t + delta, k).unwrap().to_vec();
            let down = integ.dense(t - delta, k).unwrap().to_vec();
            let exact = integ.dense(t, k + 1).unwrap().to_vec();
            (0..up.len())
                .map(|i| {
                    let fd = (up[i] - down[i]) / (2.0 * delta);
                    (fd - exact[i]).abs() / exact[i].abs().max(1.0)
                })
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Largest error/tol of `samples` against a much tighter Radau5 run interpolating at the same
/// times (Normal task): (at the step ends, inside the steps).
fn against_tight_run(
    samples: &mut [(f64, Vec<f64>, bool)],
    scale: &dyn Fn(f64) -> f64,
) -> (f64, f64) {
    let tight =
        Options { max_steps: Some(1_000_000), ..Options::new(1e-13, Tolerance::Scalar(1e-13)) };
    let mut reference = Radau5::new(VanDerPol(1.0), 0.0, &[2.0, 0.0], &tight).unwrap();
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut at_ends, mut inside) = (0.0f64, 0.0f64);
    for (t, y, is_end) in samples.iter() {
        reference.advance(*t, Task::Normal).unwrap();
        let r = reference.state();
        let e = (0..2).map(|i| (y[i] - r[i]).abs() / scale(r[i])).fold(0.0, f64::max);
        if *is_end {
            at_ends = at_ends.max(e);
        } else {
            inside = inside.max(e);
        }
    }
    (at_ends, inside)
}

/// Dense output matches a tight run and the right-hand side, and its derivatives are those of
/// one polynomial.
fn dense_output(method: Method) {
    let order = method.dense_order();
    for case in row(method).dense {
        let rtol = case.rtol;
        let scale = move |y: f64| rtol * y.abs() + rtol;
        let options =
            Options { max_steps: Some(100_000), ..Options::new(rtol, Tolerance::Scalar(rtol)) };
        let mut subject =
            Subject::build(method, case.knobs, VanDerPol(1.0), &[2.0, 0.0], &options, None);
        let nodes = case.nodes.as_ref().map_or(&[][..], |n| &n.0[..]);
        let mut walk = walk_dense(subject.integ(), nodes, &scale);
        let (at_ends, inside) = against_tight_run(&mut walk.samples, &scale);
        println!(
            "{method} {:?} rtol {rtol:e}: {} steps; error/tol at step ends {at_ends:.2}, inside \
             steps {inside:.2}; |dense'(t) − f(dense(t))|/tol {:.1}, at nodes {:.1}, at the ends \
             {:.1}; finite-difference mismatch {}; start gap {:.1e}",
            case.knobs,
            subject.integ().stats().steps,
            walk.defect,
            walk.node_defect,
            walk.end_slope,
            walk.fd.iter().map(|m| format!("{m:.1e}")).collect::<Vec<_>>().join(", "),
            walk.start_gap
        );
        assert_eq!(subject.integ().max_dense_order(), order, "the method table's order");
        assert_eq!(walk.fd.len(), order as usize);
        let (bound, ratio) = case.inside;
        assert!(
            inside < bound && inside < ratio * at_ends.max(1.0),
            "inside {inside}, ends {at_ends}"
        );
        assert!(walk.defect < case.defect, "defect {}", walk.defect);
        if let Some((_, bound)) = case.nodes {
            assert!(walk.node_defect < bound, "defect at the nodes {}", walk.node_defect);
        }
        assert!(
            walk.fd.iter().all(|&m| m < case.fd),
            "dense(t, k + 1) is not the derivative of dense(t, k): {:?}",
            walk.fd
        );
        if let Some(bound) = case.end_slope {
            assert!(walk.end_slope < bound, "slope at the ends {}", walk.end_slope);
        }
        // ... and the polynomial starts at the previous step end (up to rounding in θ).
        assert!(walk.start_gap <= 1e-13, "start gap {:e}", walk.start_gap);
    }
}

/// One test module per method, one test per check it runs.
macro_rules! suite {
    ($($module:ident: $method:ident => [$($check:ident),*];)*) => {$(
        mod $module {
            $(
                #[test]
                fn $check() {
                    super::$check(stickslip_ode::solver::Method::$method);
                }
            )*
        }
    )*};
}

suite! {
    radau5: Radau5 => [
        fixed_step_order,
        prothero_robinson,
        van_der_pol,
        dense_output
    ];
    rodas5p: Rodas5p => [
        fixed_step_order,
        prothero_robinson,
        van_der_pol,
        dense_output
    ];
    extrapolation: Extrapolation => [
        fixed_step_order,
        prothero_robinson,
        van_der_pol,
        dense_output
    ];
    cvode_bdf: CvodeBdf => [van_der_pol];
    arkode_dirk: ArkodeDirk => [van_der_pol];
}
