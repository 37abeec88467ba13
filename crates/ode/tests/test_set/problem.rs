//! What a Test Set problem provides, one run of a method on a problem at a tolerance (built
//! through `solver::build`, as a user's crate builds it), and the Test Set's accuracy measure.

use std::time::{Duration, Instant};
use stickslip_ode::integrate::{
    ImexSystem, JacobianMatrix, OdeSystem, Options, SolverError, Stats, Task, Tolerance,
};
use stickslip_ode::solver::{self, Method, MethodSettings};

/// A problem of the Test Set for IVP Solvers: system, interval, initial value, published
/// reference solution at the end time and the absolute tolerance the Test Set prescribes.
pub trait TestProblem: OdeSystem + Clone + 'static {
    const NAME: &'static str;
    const T_END: f64;
    /// Interior times where the right-hand side is discontinuous: integration restarts there.
    const BREAKPOINTS: &'static [f64] = &[];
    fn new() -> Self;
    fn y0() -> Vec<f64>;
    fn reference() -> Vec<f64>;
    /// Absolute tolerance for the relative tolerance `rtol` (Test Set default: atol = rtol).
    fn atol(rtol: f64) -> f64 {
        rtol
    }
}

/// The stiff methods whose digits docs/test-set.md measures, in its order.
pub const MEASURED: [Method; 5] =
    [Method::CvodeBdf, Method::ArkodeDirk, Method::Radau5, Method::Rodas5p, Method::Extrapolation];

/// A problem as an IMEX system with all of it implicit (f_E = 0), so that `solver::build`
/// takes it for every method, arkode-imex included.
#[derive(Debug, Clone)]
pub struct AllImplicit<P>(pub P);

impl<P: OdeSystem> OdeSystem for AllImplicit<P> {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.0.rhs(t, y, dydt)
    }
    fn has_jacobian(&self) -> bool {
        self.0.has_jacobian()
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.0.jacobian(t, y, jac)
    }
    fn has_linear_invariants(&self) -> bool {
        self.0.has_linear_invariants()
    }
}

impl<P: OdeSystem> ImexSystem for AllImplicit<P> {
    fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt.fill(0.0);
    }
    fn rhs_implicit(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.0.rhs(t, y, dydt)
    }
    fn has_implicit_jacobian(&self) -> bool {
        self.0.has_jacobian()
    }
    fn implicit_jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.0.jacobian(t, y, jac)
    }
}

/// The outcome of one successful run.
#[derive(Debug, Clone)]
pub struct Run {
    pub y: Vec<f64>,
    pub stats: Stats,
    pub wall: Duration,
}

/// Integrates `P` from 0 to `P::T_END` with `method` at `rtol` (atol as the Test Set
/// prescribes) in one `advance` call per smooth segment, restarting at the breakpoints.
pub fn run<P: TestProblem>(method: Method, rtol: f64) -> Result<Run, SolverError> {
    let start = Instant::now();
    let mut y = P::y0();
    let mut t0 = 0.0;
    let mut stats = Stats::default();
    let ends = P::BREAKPOINTS.iter().copied().chain(std::iter::once(P::T_END));
    for t1 in ends {
        let options =
            Options { stop_time: Some(t1), ..Options::new(rtol, Tolerance::Scalar(P::atol(rtol))) };
        let settings = MethodSettings::default();
        let mut solver =
            solver::build(method, &settings, AllImplicit(P::new()), t0, &y, &options)?.integrator;
        let step = solver.advance(t1, Task::Normal)?;
        assert_eq!(
            step.t,
            t1,
            "{} {}: the run must end at the segment end",
            P::NAME,
            method.name()
        );
        y = solver.state().to_vec();
        stats.accumulate(&solver.stats());
        t0 = t1;
    }
    Ok(Run { y, stats, wall: start.elapsed() })
}

/// The Test Set's mixed-error significant correct digits at tolerance `rtol`:
/// mescd = −log10 max_i |y_i − ref_i| / (atol/rtol + |ref_i|) (Mazzia & Magherini, Test Set for
/// IVP Solvers, release 2.4, section "mixed error"): relative for components above atol/rtol,
/// absolute (scaled) below. Infinite when y equals the reference.
pub fn mescd(y: &[f64], reference: &[f64], atol: f64, rtol: f64) -> f64 {
    let floor = atol / rtol;
    let worst = y
        .iter()
        .zip(reference)
        .map(|(v, r)| if v.is_finite() { (v - r).abs() / (floor + r.abs()) } else { f64::INFINITY })
        .fold(0.0, f64::max);
    -worst.log10()
}

/// The mixed-error scd of a run of `P` at `rtol`.
pub fn scd_of<P: TestProblem>(y: &[f64], rtol: f64) -> f64 {
    mescd(y, &P::reference(), P::atol(rtol), rtol)
}
