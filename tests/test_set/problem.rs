//! What a Test Set problem provides, the five stiff methods, one run of a method on a problem
//! at a tolerance, and the Test Set's accuracy measure.

use std::time::{Duration, Instant};
use stickslip::integrate::{
    Extrapolation, Integrator, OdeSystem, Options, Radau5, Rodas5p, SolverError, Stats, Task,
    Tolerance,
};
use stickslip::sundials::{ArkMethod, ArkSettings, CvodeSettings, Solver};

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

/// The stiff methods of stickslip, each with its library defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    CvodeBdf,
    ArkodeDirk,
    Radau5,
    Rodas5p,
    Extrapolation,
}

impl Method {
    pub const ALL: [Method; 5] = [
        Method::CvodeBdf,
        Method::ArkodeDirk,
        Method::Radau5,
        Method::Rodas5p,
        Method::Extrapolation,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::CvodeBdf => "cvode-bdf",
            Method::ArkodeDirk => "arkode-dirk",
            Method::Radau5 => "radau5",
            Method::Rodas5p => "rodas5p",
            Method::Extrapolation => "extrapolation",
        }
    }

    fn build<S: OdeSystem + 'static>(
        self,
        system: S,
        t0: f64,
        y0: &[f64],
        options: &Options,
    ) -> Result<Box<dyn Integrator>, SolverError> {
        Ok(match self {
            Method::CvodeBdf => {
                Box::new(Solver::cvode(system, CvodeSettings::default(), t0, y0, options)?)
            }
            Method::ArkodeDirk => Box::new(Solver::arkstep(
                system,
                ArkMethod::default(),
                ArkSettings::default(),
                t0,
                y0,
                options,
            )?),
            Method::Radau5 => Box::new(Radau5::new(system, t0, y0, options)?),
            Method::Rodas5p => Box::new(Rodas5p::new(system, t0, y0, options)?),
            Method::Extrapolation => Box::new(Extrapolation::new(system, t0, y0, options)?),
        })
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
        let mut solver = method.build(P::new(), t0, &y, &options)?;
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
