//! The engine: a validated scene in, a report out, computing only what the scene asks for.

use crate::analysis::continuation::{self, ContinuationReport, ContinuationSettings};
use crate::analysis::cycle::CycleOptions;
use crate::analysis::hopf::{self, HopfReport};
use crate::analysis::noise::{self, models::NoiseModel};
use crate::analysis::shooting;
use crate::analysis::time_series::{
    self, DiscardSink, SeriesSink, TimeSeriesOutcome, TimeSeriesSettings,
};
use crate::analysis::{cycle, AnalysisError};
use crate::integrate::{
    ErrorKind, ErrorScale, ImexSystem, Integrator, Options, SolverError, Stats, Tolerance,
};
use crate::model::drr::W;
use crate::model::{Drr, Variational};
use crate::model::{SaddleNode, VanDerPol};
use crate::numerics::finite;
use crate::paper::{asymptotics, lyapunov, quoted};
use crate::report::lab::LabReport;
use crate::report::{
    AnyReport, CyclePhysical, CycleSection, ModelReport, ModelSection, Physical, Report,
    SolverSection,
};
use crate::scene::lab::LabScene;
use crate::scene::{AnalysisKind, AnyScene, OtherModel, OtherScene, Scene, SolverSpec};
use crate::solver::{self, MethodSettings};
use crate::sundials;

mod cancel;
mod forced;
mod guard;
mod imex_stick;
pub mod lab;
mod methods;
mod options;
pub use cancel::{Cancel, RunError};
pub use methods::EngineSettings;
pub use options::{ProgressSink, RunOptions};

/// Builds the scene's integrator on the DRR system, starting at (0, y0). Also returns the
/// Butcher tables used (ARKStep).
pub fn integrator(
    drr: Drr,
    spec: &SolverSpec,
    y0: &[f64; 3],
) -> Result<(Box<dyn Integrator>, Vec<String>), SolverError> {
    integrator_for(drr, &drr, spec, y0, Tolerance::PerComponent(spec.atol.to_vec()))
}

/// Builds the scene's integrator on any system derived from `drr` (e.g. its variational
/// equations), starting at (0, y0) with absolute tolerances `atol`. Also returns the Butcher
/// tables used (ARKStep). The DRR system and its derivatives are autonomous.
pub fn integrator_for<S: ImexSystem + 'static>(
    system: S,
    drr: &Drr,
    spec: &SolverSpec,
    y0: &[f64],
    atol: Tolerance,
) -> Result<(Box<dyn Integrator>, Vec<String>), SolverError> {
    integrator_cancellable(system, drr, spec, y0, atol, None)
}

/// [`integrator_for`], failing once `cancel` is set.
fn integrator_cancellable<S: ImexSystem + 'static>(
    system: S,
    drr: &Drr,
    spec: &SolverSpec,
    y0: &[f64],
    atol: Tolerance,
    cancel: Option<&Cancel>,
) -> Result<(Box<dyn Integrator>, Vec<String>), SolverError> {
    // The no-healing law has no fixed point, so no linear period to bound the steps by.
    let max_step = drr.params().state_law.heals().then(|| max_step(&hopf::analyse(drr)));
    integrator_with_max_step(system, drr, max_step, spec, y0, atol, cancel, true)
}

/// [`integrator_for`] with the largest step `max_step` (None: unbounded), failing once
/// `cancel` is set, for an `autonomous` system or not (a periodically loaded one,
/// [`forced`]). The run's guards ([`guard::guarded`]) wrap it.
#[allow(clippy::too_many_arguments)]
fn integrator_with_max_step<S: ImexSystem + 'static>(
    system: S,
    drr: &Drr,
    max_step: Option<f64>,
    spec: &SolverSpec,
    y0: &[f64],
    atol: Tolerance,
    cancel: Option<&Cancel>,
    autonomous: bool,
) -> Result<(Box<dyn Integrator>, Vec<String>), SolverError> {
    // Up to 20 error-test failures per step (as SUNDIALS' ark_robertson_root allows): the
    // default 7 fails in the rise at γ = 1e8, rtol 1e-6 (CVODE) and on the stick at γ = 1e4,
    // rtol 1e-11 (ARKStep).
    // A start far from v = 1 (|ln v| > 30, e.g. v = 1e-30 or 1e30): there dw/dt = −γ² e^{−w} G
    // or du/dt = v − 1 is astronomically large, and a solver's own first-step estimate
    // overshoots out of the range of exp (v = e^w overflows). Start with a step that changes
    // each component by at most 1e-3 of max(1, |y|).
    let initial_step = (y0[W].abs() > 30.0)
        .then(|| {
            let mut f = vec![0.0; system.dim()];
            system.rhs(0.0, y0, &mut f);
            y0.iter()
                .zip(&f)
                .map(|(y, f)| 1e-3 * y.abs().max(1.0) / f.abs().max(1e-300))
                .fold(f64::INFINITY, f64::min)
        })
        .filter(|h| h.is_finite() && *h > 0.0);
    // A fresh Jacobian at every step for SUNDIALS' implicit methods: the stiff rate
    // γ²e^(−w)/ξ grows by e per unit fall of w, and on the stick w changes by O(1) within
    // CVODE's default 20 steps between setups (51 between Jacobians). With the older
    // Jacobian the Newton iteration leaves an error in the distance to the slow manifold that
    // the next steps amplify (×2–3 a step at γ = 1e8, ξ = 2, ε = 5) until the step collapses.
    // Measured: the quick stress grid's 35 CVODE/ARKStep failures from the manifold and
    // v = 1e-30 starts go to 3, and the earthquake scene takes 18394 CVODE steps, not 31528.
    // Not for cvode-adams (a non-stiff method, used at small γ): there the fresh Jacobian
    // only costs steps (γ = 10, ξ = 0.8, ε = 1: 1053 → 778 steps per cycle at rtol 1e-6, 1864
    // → 1503 at 1e-8, the same period error). Which methods: [`EngineSettings::of`].
    let engine = EngineSettings::of(spec.method);
    // ARKStep DIRK: a Newton test 100 times tighter than ARKODE's default 0.1, with up to 5
    // iterations instead of 3. The Jacobian is fresh at each step but not at each stage, and
    // on the stick the stiff rate γ²e^(−w)/ξ falls by e^(ξ c_i h) from the step's start to
    // stage i (×6 at ξ = 5, h = 0.35); the simplified Newton iteration then converges only
    // linearly (rate ~0.8), and ARKODE's test, which takes the rate as at most 1, stops with
    // an error several times its tolerance in the distance G to the slow manifold. That error
    // grew ×1.45 a step until repeated error-test failures (γ = 1e4, ξ = 5, ε = 10,
    // h → 1e-10). Measured on the physical grid's arkode-dirk cells: 906 of 936 → 936 (also
    // with 3 iterations, at 1.2× the steps; 5 iterations cost the same as before); 1e-4
    // fails in the earthquake scene's initial layer, where the round-off of G sets a floor.
    // That floor also bounds the test from below at tight tolerances: the iteration stops on
    // a correction below nonlin_conv_coef · rtol (weighted), which at 1e-3 · 1e-11 lies under
    // the round-off of the stage residual, so Newton "fails" in the first slip (earthquake,
    // rtol 1e-11: repeated convergence failures at h = 1.5e-11). The test is kept at least
    // 1000 u / rtol: 100 u still fails there, 1000 u converges (5 cycles: 56 970 steps,
    // 47 251 since solver::dirk_settings); 5000 u also fails there (20 M steps). Physical
    // grid's arkode-dirk cells: 936 of 936.
    // CVODE BDF (`EngineSettings::absolute_ln_v`): ln v's error is measured absolutely, at a
    // tenth of rtol. An absolute error in w = ln v is v's relative error, and the size of w
    // (up to 21 at the earthquake's peak, down to −690 for v = 1e-300) says nothing about the
    // accuracy wanted; weighed relative to it, the slip's v was held to 20·rtol. BDF's global
    // error on this problem is also some tens of times its local tolerance, hence the tenth.
    // Measured on the earthquake scene (rtol 1e-10; reference 56.4124686977): period error
    // −3.4e-8 weighed relative to |w|,
    // −3.5e-9 absolute at rtol, −4.8e-10 absolute at rtol/10 (1.8× the steps); u's and θ's
    // weights change it by under 1e-10 (docs/work-precision.md, "CVODE's weight on ln v").
    // With ln v held this tightly, CVODE's own first step overshoots the initial layer of an
    // off-manifold start (width ~ξv/γ², 4e-17 for the earthquake scene) by up to 1e6, and the
    // default 10 convergence failures (each cutting h by 4) stop the run at t = 0 from
    // rtol 1e-11 on; 20 let it shrink h by 4^20 (rtol 1e-11, 1e-12, 1e-13: period errors
    // −1.6e-10, −1.1e-10, −8.4e-11, where every rtol ≥ 1e-12 failed before).
    // Radau5 and Rodas5P weigh ln v the same way, for the same reason: on the 12
    // quasi-dynamic cases of issue #28 (data/reference/quasi_dynamic_cycles.json, rtol 1e-10),
    // weighed relative to |w| ≈ 19 at the peak, v_max was off by up to 1.2e-8 (radau5, whose
    // RADAU5 transform makes its local tolerance 2e-8) and 1.6e-9 (rodas5p); absolute at
    // rtol/10: 3.4e-10 and 1.6e-10, periods within 3e-11, for 1.5–2× the steps (absolute at
    // rtol: radau5 still 3.6e-9). The earthquake period with radau5 goes from 6.0e-10 to 9e-13
    // off (2.1× the steps). Extrapolation weighs it absolutely at rtol (v_max 2.3e-9 → 1.2e-9):
    // it keeps as many columns as hold its round-off Λ_k·u below rtol (tableau.rs), so a
    // tenth of rtol lies under that round-off, and two stress cells failed with repeated
    // error-test failures at ln v ≈ −6 (γ = 1e4, ξ = 2, ε = 5 from v = 1e30; γ = 1e9, ξ = 0.7,
    // ε = 10; rtol 1e-10), which reach the cycle at rtol.
    // ARKStep DIRK weighs ln v absolutely too, at rtol: its Newton test (above) must stay
    // above the round-off of the stage solution, and on the slow manifold w is fixed by
    // G = u + (θ + w)/ξ only to ξ·ulp(u) + ulp(θ), whatever |w|. Weighed relative to |w|, the
    // weight near v = 1 is atol alone (1e-12 in the far-start scenes), 5 of those ulps after
    // the start (1e6, 1e-300, 1e3), where the slip comes at u ≈ −1241, θ ≈ 993, so the
    // round-off alone is ~100 times the Newton test (2e-13 against 2.2e-3 · 1e-12): 10
    // convergence failures down to h = 3e-12 at v ≈ 0.96 (also from a fresh start at
    // (−1241, 0.5, 993), no deep stick; a looser test, 0.03, passes with 4.6× the steps of
    // the weight below and 145 224 error-test failures). Absolute at rtol the weight is
    // 1e-10: every far start reaches the cycle (tests/cycle_accuracy.rs), and the earthquake
    // scene's period error goes from −1.7e-11 to −6.3e-12 (relative) at 1.4× the steps
    // (41 930 → 58 668 in 8 cycles). A tenth of rtol fails at the stick's exit, where
    // ln v = −50 is also weighed at 1e-11. It also allows 20 convergence failures per step
    // (`EngineSettings::max_conv_fails`), which changed none of those runs.
    let error_scales = engine.absolute_ln_v.map(|c| {
        (0..system.dim())
            .map(|i| if i == W { ErrorScale::Absolute(c) } else { ErrorScale::Relative })
            .collect()
    });
    // ARKStep's implicit methods deduce their stage derivatives here
    // (`MethodSettings::deduce_implicit_rhs`): evaluating f_I at converged stages
    // re-amplifies the Newton residual by the stiffness in ARKStep's error estimate, which
    // makes it fail at γ ≥ 1e3.
    let dirk = engine.dirk_newton;
    let dirk_conv_coef = (1e3 * f64::EPSILON / spec.rtol).clamp(1e-3, 0.1);
    let options = &Options {
        max_step,
        max_err_test_fails: Some(20),
        initial_step,
        jacobian_max_age: engine.jacobian_max_age,
        nonlin_conv_coef: dirk.then_some(dirk_conv_coef),
        max_nonlin_iters: dirk.then_some(5),
        error_scales,
        max_conv_fails: engine.max_conv_fails,
        ..Options::new(spec.rtol, atol)
    };
    let settings = MethodSettings {
        deduce_implicit_rhs: engine.deduce_implicit_rhs,
        ..spec.method_settings(autonomous)
    };
    let built = solver::build(spec.method, &settings, system, 0.0, y0, options)?;
    let frozen = engine.stop_when_u_freezes.then(|| imex_stick::FrozenU::new(drr, y0));
    Ok((guard::guarded(built.integrator, cancel, frozen), built.tables))
}

/// The engine's largest step: 1/8 of the linear period 2π/ω_c. Longer steps let BDF damp the
/// growing oscillation near an unstable fixed point (its stability region reaches into the
/// right half-plane), and a start within 1e-10 of it then never grows; where the run comes to
/// rest within round-off of it the cycle analysis limits the steps further
/// ([`cycle::EscapeStep`]).
fn max_step(linear: &HopfReport) -> f64 {
    linear.period_c / 8.0
}

/// Why a run failed: the analysis at fault, its typed error, and where it happened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{analysis}: {message}")]
pub struct EngineError {
    /// The analysis that failed ([`AnalysisKind::name`], e.g. "cycle"), or the report section
    /// refused for a non-finite number.
    pub analysis: &'static str,
    /// The analysis's error (boxed: it is large); an integration failure carries the physical
    /// cause in its message where the engine knows one (see `diagnose`).
    pub kind: Box<AnalysisError>,
    /// The state where it failed, when known (empty otherwise).
    pub state: Vec<f64>,
    /// `kind`'s message under the heading `analysis` (which it does not repeat, see
    /// [`AnalysisError::message_under`]): what failed, where (t and the state) and why.
    pub message: String,
}

impl EngineError {
    /// The error of `analysis`.
    pub fn new(analysis: AnalysisKind, kind: AnalysisError) -> Self {
        Self::in_section(analysis.name(), kind)
    }

    /// The error under the report section `section`: an analysis's name, or the section refused
    /// for a non-finite number.
    fn in_section(analysis: &'static str, kind: AnalysisError) -> Self {
        Self {
            analysis,
            state: kind.state().to_vec(),
            message: kind.message_under(analysis),
            kind: Box::new(kind),
        }
    }

    /// Whether the input is at fault (an option that does not fit the computed orbit, named
    /// by its field) rather than the computation: the CLI's exit code 2, not 1.
    pub fn is_bad_input(&self) -> bool {
        matches!(*self.kind, AnalysisError::InvalidOption(_))
    }

    /// Whether an integration stopped because the run was cancelled ([`Cancel`]): an error of
    /// kind [`ErrorKind::Cancelled`], not a failed computation.
    pub fn is_cancelled(&self) -> bool {
        matches!(&*self.kind, AnalysisError::Solver(e) if e.kind == ErrorKind::Cancelled)
    }
}

/// The engine's error for `analysis` from an analysis error or an integrator's, with the
/// physical cause added (see `diagnose`).
fn failed<'a, E: Into<AnalysisError>>(
    drr: &'a Drr,
    analysis: AnalysisKind,
) -> impl Fn(E) -> EngineError + 'a {
    move |e| EngineError::new(analysis, diagnose(drr, e))
}

fn non_finite(path: &str, section: &'static str) -> EngineError {
    EngineError::in_section(section, AnalysisError::NonFinite { path: path.to_string() })
}

/// Adds the physical cause to a failure at a state where one is known, and only where it is
/// true.
///
/// - v falling to 0 in finite time: with dv/dt = −γ² G and G > 0 at v → 0, e^w decreases
///   linearly to 0 and w = ln v → −∞: the block stops. That needs a friction law bounded below
///   (no point of the slow manifold at this (u, θ)): with the regularised asinh law the block
///   would go on and reverse, which the ln v formulation cannot follow. Under f = ln v,
///   G → −∞ as v → 0 and v cannot reach 0.
/// - An arrest deeper than doubles reach: ln v falls towards its floor, the slow manifold's
///   w at this (u, θ); below w = −700, v = e^w and the rate γ² e^{−w} leave the range of
///   doubles although the solution is smooth.
fn diagnose<E: Into<AnalysisError>>(drr: &Drr, error: E) -> AnalysisError {
    let mut error = error.into();
    let cause = match *error.state() {
        [u, w, theta] => {
            let g = drr.manifold_offset(&[u, w, theta]);
            let floor = drr.manifold_w(u, theta);
            if w < -10.0 && g > 0.0 && floor.is_none() {
                let pull = if drr.params().inertia {
                    "dv/dt = −γ²G with G"
                } else {
                    "the quasi-dynamic force balance is off by G"
                };
                Some(format!(
                    " [v = {:.3e} is falling to 0 in finite time ({pull} = {g:.3e} > 0 and no slow manifold \
                     below it): the block stops, which the integration in ln v cannot pass]",
                    w.exp()
                ))
            } else {
                floor.filter(|f| *f < -700.0 && w < 0.0).map(|floor| {
                    format!(
                        " [the arrest is deeper than double precision reaches: ln v falls towards its floor {floor:.1} \
                         (the slow manifold at u = {u:.4e}, θ = {theta:.4e}), below −700, where v = e^w and the rate \
                         γ²e^(−w) leave the range of doubles]"
                    )
                })
            }
        }
        _ => None,
    };
    if let (Some(cause), Some(message)) = (cause, error.message_mut()) {
        message.push_str(&cause);
    }
    error
}

/// Runs the "cycle" analysis with the scene's solver, start and cycle options on `drr`'s
/// parameters (which may differ from the scene's, e.g. in a γ scan), keeping the trajectory of
/// the last `trajectory_cycles` cycles. `linear` is `drr`'s Hopf analysis (the fixed point's
/// stability, the largest step and the escape limits come from it). Returns the report, the
/// integrator's name, its Butcher tables and statistics; a failure carries its physical cause
/// where one is known.
pub fn cycle_with(
    scene: &Scene,
    drr: &Drr,
    o: &CycleOptions,
    trajectory_cycles: usize,
    linear: &HopfReport,
) -> Result<(cycle::CycleReport, String, Vec<String>, Stats), AnalysisError> {
    cycle_cancellable(scene, drr, o, trajectory_cycles, linear, None)
}

/// [`cycle_with`], failing once `cancel` is set.
fn cycle_cancellable(
    scene: &Scene,
    drr: &Drr,
    o: &CycleOptions,
    trajectory_cycles: usize,
    linear: &HopfReport,
    cancel: Option<&Cancel>,
) -> Result<(cycle::CycleReport, String, Vec<String>, Stats), AnalysisError> {
    unforced(scene, "cycle")?;
    let settings = cycle::CycleSettings {
        trajectory_cycles,
        escape: cycle::EscapeStep::for_eigenvalues(&linear.eigenvalues, Some(max_step(linear))),
        ..o.settings(scene.solver.rtol, scene.solver.atol[1])
    };
    let atol = Tolerance::PerComponent(scene.solver.atol.to_vec());
    let (mut integ, tables) = integrator_with_max_step(
        *drr,
        drr,
        Some(max_step(linear)),
        &scene.solver,
        &scene.initial,
        atol,
        cancel,
        true,
    )?;
    let stable = linear.max_real_part < 0.0;
    let report =
        cycle::analyse(integ.as_mut(), drr, &settings, stable).map_err(|e| diagnose(drr, e))?;
    Ok((report, scene.solver.method.capabilities().family.to_string(), tables, integ.stats()))
}

/// Runs a validated scene: the one entry of the engine. `options` say how (the scene as given,
/// echoed in the report; worker threads; where the time-series rows go; cancellation; the
/// progress of ensembles; [`RunOptions`]); none of them changes a number of the report.
///
/// The report's type follows the scene's: a spring-slider [`Scene`] gives a [`Report`], a
/// saddle-node or van der Pol [`OtherScene`] a [`ModelReport`], a laboratory [`LabScene`] a
/// [`LabReport`], and a scene of any kind ([`AnyScene`], what `scene::parse_any` gives) an
/// [`AnyReport`].
///
/// For the spring-slider the pipeline is the linear analysis, the cycle, shooting and
/// continuation, the time series, the analyses of the recorded cycle (asymptotics, lyapunov),
/// the paper's claims and noise; then one check that every number reported is finite.
///
/// # Errors
/// [`RunError::Failed`] names the analysis that failed, where and why;
/// [`RunError::Lab`] a laboratory run's failure; [`RunError::Cancelled`] a run stopped
/// through [`RunOptions::cancel`] (whatever it computed on the way is dropped).
pub fn run<S: Runnable>(scene: &S, options: RunOptions<'_>) -> Result<S::Report, RunError> {
    let cancel = options.cancel;
    match scene.carry_out(options) {
        Err(RunError::Failed(e)) if e.is_cancelled() => Err(RunError::Cancelled),
        // A noise analysis stopped between realisations, or an analysis skipped.
        _ if cancel.is_some_and(Cancel::is_cancelled) => Err(RunError::Cancelled),
        report => report,
    }
}

/// A validated scene that [`run`] carries out, and the report it gives. Implemented for every
/// kind of scene and for [`AnyScene`]; sealed (a new kind of model gets its arm here).
pub trait Runnable: sealed::CarryOut {}

mod sealed {
    use super::{RunError, RunOptions};

    /// How each kind of scene is carried out ([`super::run`] is the one way to call it).
    pub trait CarryOut {
        /// The report of a run.
        type Report;
        /// Runs the scene.
        fn carry_out(&self, options: RunOptions<'_>) -> Result<Self::Report, RunError>;
    }
}

impl Runnable for Scene {}
impl sealed::CarryOut for Scene {
    type Report = Report;
    fn carry_out(&self, mut options: RunOptions<'_>) -> Result<Report, RunError> {
        let threads = options.worker_threads();
        let progress = options.progress.unwrap_or(&|_, _| {});
        let mut discard = DiscardSink;
        let series = options.series.take().unwrap_or(&mut discard);
        Ok(run_drr(self, options.echo, threads, progress, series, options.cancel)?)
    }
}

impl Runnable for OtherScene {}
impl sealed::CarryOut for OtherScene {
    type Report = ModelReport;
    fn carry_out(&self, options: RunOptions<'_>) -> Result<ModelReport, RunError> {
        let threads = options.worker_threads();
        let progress = options.progress.unwrap_or(&|_, _| {});
        Ok(run_other(self, options.echo, threads, progress, options.cancel)?)
    }
}

impl Runnable for LabScene {}
impl sealed::CarryOut for LabScene {
    type Report = LabReport;
    fn carry_out(&self, mut options: RunOptions<'_>) -> Result<LabReport, RunError> {
        let mut discard = DiscardSink;
        let series = options.series.take().unwrap_or(&mut discard);
        Ok(lab::run(self, options.echo, series)?)
    }
}

impl<S: Runnable> Runnable for Box<S> {}
impl<S: Runnable> sealed::CarryOut for Box<S> {
    type Report = S::Report;
    fn carry_out(&self, options: RunOptions<'_>) -> Result<S::Report, RunError> {
        (**self).carry_out(options)
    }
}

impl Runnable for AnyScene {}
impl sealed::CarryOut for AnyScene {
    type Report = AnyReport;
    fn carry_out(&self, options: RunOptions<'_>) -> Result<AnyReport, RunError> {
        Ok(match self {
            AnyScene::Drr(s) => AnyReport::Drr(Box::new(s.carry_out(options)?)),
            AnyScene::Other(s) => AnyReport::Other(Box::new(s.carry_out(options)?)),
            AnyScene::Lab(s) => AnyReport::Lab(Box::new(s.carry_out(options)?)),
        })
    }
}

/// Runs a spring-slider scene ([`run`]), stopping early once `cancel` is given and set.
fn run_drr(
    scene: &Scene,
    scene_json: serde_json::Value,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    series: &mut dyn SeriesSink,
    cancel: Option<&Cancel>,
) -> Result<Report, EngineError> {
    let started = std::time::Instant::now();
    let drr = Drr::new(scene.params);
    let a = &scene.analyses;
    let autonomous_only = a.hopf
        || a.paper
        || a.shooting.is_some()
        || a.continuation.is_some()
        || a.asymptotics.is_some()
        || a.lyapunov.is_some()
        || a.noise.is_some();
    if autonomous_only {
        unforced(scene, "analyses").map_err(|e| EngineError::in_section("analyses", e))?;
    }
    let linear = (a.hopf || a.cycle.is_some()).then(|| hopf::analyse(&drr));
    let (mut cycle, mut integration) = cycle_step(scene, &drr, linear.as_ref(), cancel)?;
    let (shooting, continuation) =
        shooting_step(scene, &drr, &mut integration, cycle.is_some(), cancel)?;
    let integrated = cycle.is_some() || a.shooting.is_some() || a.continuation.is_some();
    let series = time_series_step(scene, &drr, &mut integration, integrated, series, cancel)?;
    let asymptotics = asymptotics_step(scene, &drr, cycle.as_ref(), cancel)?;
    let lyapunov = lyapunov_step(scene, &drr, cycle.as_ref(), cancel)?;
    // The trajectory recorded only for the analyses above is not reported.
    if a.trajectory_cycles.is_none() {
        if let Some(c) = &mut cycle {
            c.trajectory.clear();
        }
    }
    let values = cycle.as_ref().and_then(|c| c.values);
    // The explicit `units` only: the scene's default ones (from the dimensional input) are the
    // input's own time unit, given by `period` etc. already.
    let explicit_units = scene.units.as_ref().filter(|_| scene_json.get("units").is_some());
    let cycle_physical = scene
        .scales
        .as_ref()
        .zip(values.as_ref())
        .map(|(s, v)| CyclePhysical::new(v, s, &scene.params, explicit_units));
    let cycle = cycle.map(|analysis| CycleSection { analysis, physical: cycle_physical });
    let physical = scene.units.as_ref().zip(values).map(|(u, v)| Physical {
        time_unit: u.time_unit.clone(),
        time_scale: u.time_scale,
        period: v.main.period * u.time_scale,
        t0: v.main.t0 * u.time_scale,
        slip_half_width: v.main.slip_half_width.map(|w| w * u.time_scale),
        slip_duration: v.main.slip_duration * u.time_scale,
    });
    let paper = linear
        .as_ref()
        .filter(|_| a.paper)
        .map(|h| quoted::compare(&scene.params, h, values.as_ref()));
    let noise = match &a.noise {
        // Cancelled: the report is dropped.
        Some(_) if cancel::is_set(cancel) => None,
        Some(options) => {
            let amplitudes = [options.amplitudes[0], options.amplitudes[1], options.amplitudes[2]];
            let model = NoiseModel::Drr { system: drr, amplitudes };
            let stop = || cancel::is_set(cancel);
            Some(
                noise::run_stoppable(&model, &scene.initial, options, threads, progress, &stop)
                    .map_err(failed(&drr, AnalysisKind::Noise))?,
            )
        }
        None => None,
    };
    let y = scene.initial;
    let report = Report {
        stickslip_version: env!("CARGO_PKG_VERSION"),
        sundials_version: sundials::version(),
        name: scene.name.clone(),
        scene: scene_json,
        model: ModelSection {
            gamma: scene.params.gamma,
            inertia: scene.params.inertia,
            xi: scene.params.xi,
            epsilon: scene.params.epsilon,
            friction: scene.params.friction.label(),
            state_law: scene.params.state_law,
            radiation_damping: scene.params.eta,
            dimensional: scene.dimensional,
            initial: [y[0], y[1].exp(), y[2]],
        },
        solver: SolverSection {
            method: scene.solver.method,
            integrator: integration.name,
            rtol: scene.solver.rtol,
            atol: scene.solver.atol,
            chosen_by: scene.solver_chosen_by.clone(),
            tables: integration.tables,
            stats: integration.stats,
        },
        units: scene.units.clone(),
        hopf: linear.filter(|_| a.hopf),
        cycle,
        asymptotics,
        lyapunov,
        physical,
        paper,
        shooting,
        continuation,
        noise,
        time_series: series.as_ref().map(|s| s.report.clone()),
        runaway: series.as_ref().and_then(|s| s.runaway.clone()),
        forcing: scene.loading.as_ref().zip(series.as_ref()).map(|(loading, s)| {
            crate::analysis::locking::analyse(&s.events, loading, scene.scales.as_ref())
        }),
        events: series.map(|s| s.events),
        warnings: scene.warnings.clone(),
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    refuse_non_finite(&report)?;
    Ok(report)
}

/// Refuses a periodically loaded scene for an analysis that assumes an autonomous system
/// (scene::parse refuses such scenes already; this guards scenes built in code).
fn unforced(scene: &Scene, what: &str) -> Result<(), AnalysisError> {
    match scene.loading {
        None => Ok(()),
        Some(_) => Err(crate::analysis::InvalidOption::new(
            what,
            "this analysis assumes an autonomous system and the scene is periodically loaded \
             (Scene::loading): a forced scene runs time_series alone (docs/periodic-loading.md)",
        )
        .into()),
    }
}

/// The integrator a report names: the one of the first integrating analysis.
struct Integration {
    name: String,
    tables: Vec<String>,
    stats: Stats,
}

/// The "cycle" analysis, keeping one recorded cycle when asymptotics or lyapunov need it.
fn cycle_step(
    scene: &Scene,
    drr: &Drr,
    linear: Option<&HopfReport>,
    cancel: Option<&Cancel>,
) -> Result<(Option<cycle::CycleReport>, Integration), EngineError> {
    let a = &scene.analyses;
    let (Some(options), Some(linear)) = (&a.cycle, linear) else {
        let none = Integration {
            name: "none (no integration asked for)".to_string(),
            tables: Vec::new(),
            stats: Stats::default(),
        };
        return Ok((None, none));
    };
    let needs_orbit = a.asymptotics.is_some() || a.lyapunov.is_some();
    let keep = a.trajectory_cycles.unwrap_or(0).max(usize::from(needs_orbit));
    // cycle_with has added the physical cause already (once: not `failed`, which adds it again).
    let (report, name, tables, stats) =
        cycle_cancellable(scene, drr, options, keep, linear, cancel)
            .map_err(|e| EngineError::new(AnalysisKind::Cycle, e))?;
    Ok((Some(report), Integration { name, tables, stats }))
}

/// "shooting" and "continuation" (which starts from the shooting orbit); their integrator is
/// the report's when no cycle was integrated before.
fn shooting_step(
    scene: &Scene,
    drr: &Drr,
    integration: &mut Integration,
    cycle_ran: bool,
    cancel: Option<&Cancel>,
) -> Result<(Option<shooting::ShootingReport>, Option<ContinuationReport>), EngineError> {
    let a = &scene.analyses;
    if a.shooting.is_none() && a.continuation.is_none() {
        return Ok((None, None));
    }
    let settings =
        a.shooting.clone().unwrap_or_default().settings(scene.solver.rtol, scene.solver.atol[1]);
    let (mut integ, tables) =
        variational_integrator_with_tables(*drr, &scene.solver, &scene.initial, cancel)
            .map_err(failed(drr, AnalysisKind::Shooting))?;
    let report = shooting::analyse(integ.as_mut(), drr, scene.initial, &settings)
        .map_err(failed(drr, AnalysisKind::Shooting))?;
    if !cycle_ran {
        let family = scene.solver.method.capabilities().family.to_string();
        (integration.name, integration.tables) = (family, tables);
    }
    integration.stats.accumulate(&integ.stats());
    let curve = a.continuation.as_ref().map(|c| {
        let cs = ContinuationSettings {
            parameter: c.parameter,
            to: c.to,
            points: c.points,
            log: c.log,
            shooting: settings,
        };
        match &report.orbit {
            Some(orbit) => {
                let mut factory = |drr: Drr, y0: [f64; 3]| {
                    Ok(variational_integrator_with_tables(drr, &scene.solver, &y0, cancel)?.0)
                };
                continuation::run(&mut factory, &scene.params, orbit.clone(), &cs)
            }
            None => ContinuationReport::not_started(&cs, &scene.params, report.failure.as_ref()),
        }
    });
    Ok((a.shooting.is_some().then_some(report), curve))
}

/// "time_series": from t = 0 to t_max with the scene's integrator and start, rows to
/// `series`; its integrator is the report's when nothing was integrated before.
fn time_series_step(
    scene: &Scene,
    drr: &Drr,
    integration: &mut Integration,
    integrated: bool,
    series: &mut dyn SeriesSink,
    cancel: Option<&Cancel>,
) -> Result<Option<TimeSeriesOutcome>, EngineError> {
    let Some(o) = &scene.analyses.time_series else { return Ok(None) };
    let scales = scene.scales;
    let t_max = o.t_max / scales.map_or(1.0, |s| s.time_scale());
    if !(t_max.is_finite() && t_max > 0.0) {
        let option = crate::analysis::InvalidOption::new(
            "time_series.t_max",
            format!(
                "{} in the input's time unit is {t_max:e} in units of D_c/v0; it must be a \
                 finite time > 0",
                o.t_max
            ),
        );
        return Err(EngineError::new(AnalysisKind::TimeSeries, option.into()));
    }
    let runaway_v = match o.runaway_velocity {
        None => None,
        Some(velocity) => {
            let v = velocity / scales.map_or(1.0, |s| s.v0);
            let start = scene.initial[W].exp();
            if !(v.is_finite() && v > start) {
                let option = crate::analysis::InvalidOption::new(
                    "time_series.runaway_velocity",
                    format!(
                        "{velocity} in the scene's velocity unit is v = {v:e} (units of v0), \
                         not above the start's v = {start:e}: give a threshold above the initial \
                         slip rate"
                    ),
                );
                return Err(EngineError::new(AnalysisKind::TimeSeries, option.into()));
            }
            Some(v)
        }
    };
    let settings = TimeSeriesSettings {
        runaway_v,
        t_max,
        sampling: o.sampling(),
        event_threshold: o.event_threshold(),
        max_steps: o.max_steps.unwrap_or(time_series::options::DEFAULT_MAX_STEPS),
        w_tolerance: (scene.solver.rtol, scene.solver.atol[W]),
    };
    let outcome = match scene.loading {
        None => {
            let atol = Tolerance::PerComponent(scene.solver.atol.to_vec());
            let (mut integ, tables) =
                integrator_cancellable(*drr, drr, &scene.solver, &scene.initial, atol, cancel)
                    .map_err(failed(drr, AnalysisKind::TimeSeries))?;
            time_series::run(integ.as_mut(), drr, drr, &settings, scales, series)
                .map(|o| (o, integ.stats(), tables))
        }
        Some(loading) => {
            let mut f = forced::integrator(drr, loading, &scene.solver, &scene.initial, cancel)
                .map_err(failed(drr, AnalysisKind::TimeSeries))?;
            time_series::run(f.integrator.as_mut(), drr, &f.system, &settings, scales, series)
                .map(|o| (o, f.integrator.stats(), f.tables))
        }
    };
    let (outcome, stats, tables) = outcome.map_err(failed(drr, AnalysisKind::TimeSeries))?;
    if !integrated {
        let family = scene.solver.method.capabilities().family.to_string();
        (integration.name, integration.tables) = (family, tables);
    }
    integration.stats.accumulate(&stats);
    Ok(Some(outcome))
}

/// "asymptotics", with the γ scan's cycles run by [`cycle_with`] at the scene's options.
fn asymptotics_step(
    scene: &Scene,
    drr: &Drr,
    cycle: Option<&cycle::CycleReport>,
    cancel: Option<&Cancel>,
) -> Result<Option<asymptotics::AsymptoticsReport>, EngineError> {
    let Some(o) = &scene.analyses.asymptotics else { return Ok(None) };
    let options = scene.analyses.cycle.clone().unwrap_or_default();
    let mut cycle_at = |drr: &Drr, start: [f64; 3]| {
        Ok(cycle_cancellable(
            &Scene { initial: start, ..scene.clone() },
            drr,
            &options,
            0,
            &hopf::analyse(drr),
            cancel,
        )?
        .0)
    };
    asymptotics::analyse(&scene.params, scene.initial, &mut cycle_at, cycle, o)
        .map(Some)
        .map_err(failed(drr, AnalysisKind::Asymptotics))
}

/// "lyapunov", with the variational equations integrated by the scene's method.
fn lyapunov_step(
    scene: &Scene,
    drr: &Drr,
    cycle: Option<&cycle::CycleReport>,
    cancel: Option<&Cancel>,
) -> Result<Option<lyapunov::LyapunovReport>, EngineError> {
    let Some(o) = &scene.analyses.lyapunov else { return Ok(None) };
    let mut variational = |drr, spec: &SolverSpec, y0: &[f64; 3]| {
        Ok(variational_integrator_with_tables(drr, spec, y0, cancel)?.0)
    };
    lyapunov::analyse(&scene.params, &scene.solver, &mut variational, cycle, o)
        .map(Some)
        .map_err(failed(drr, AnalysisKind::Lyapunov))
}

/// The one check that every number in the analyses' sections is finite (serde_json would
/// write NaN and infinity as null): the error names the first one's path. The model section
/// is not checked: its γ is +∞ for the quasi-dynamic model, written as null by design.
fn refuse_non_finite(r: &Report) -> Result<(), EngineError> {
    let sections = [
        first_non_finite_in(AnalysisKind::Hopf.name(), r.hopf.as_ref()),
        first_non_finite_in(AnalysisKind::Cycle.name(), r.cycle.as_ref()),
        first_non_finite_in(AnalysisKind::Shooting.name(), r.shooting.as_ref()),
        first_non_finite_in(AnalysisKind::Continuation.name(), r.continuation.as_ref()),
        first_non_finite_in(AnalysisKind::Asymptotics.name(), r.asymptotics.as_ref()),
        first_non_finite_in(AnalysisKind::Lyapunov.name(), r.lyapunov.as_ref()),
        first_non_finite_in("physical", r.physical.as_ref()),
        first_non_finite_in(AnalysisKind::Paper.name(), r.paper.as_ref()),
        first_non_finite_in(AnalysisKind::Noise.name(), r.noise.as_ref()),
        first_non_finite_in(AnalysisKind::TimeSeries.name(), r.time_series.as_ref()),
        first_non_finite_in("events", r.events.as_ref()),
        first_non_finite_in("runaway", r.runaway.as_ref()),
        first_non_finite_in("forcing", r.forcing.as_ref()),
        first_non_finite_in("solver", Some(&r.solver)),
    ];
    match sections.into_iter().flatten().next() {
        Some((section, path)) => Err(non_finite(&path, section)),
        None => Ok(()),
    }
}

/// The section and the path of the first non-finite number in it, if any.
fn first_non_finite_in<T: serde::Serialize>(
    section: &'static str,
    value: Option<&T>,
) -> Option<(&'static str, String)> {
    value.and_then(|v| finite::first_non_finite(v, section)).map(|path| (section, path))
}

/// The scene's integrator on the DRR variational equations (state and fundamental matrix Φ),
/// starting at (0, y0) with Φ = I. Φ's entries get the absolute tolerance rtol (they are
/// O(1) where they matter; the components that decay on the slow manifold need no more).
/// Radau5 gets the Newton-only Jacobian ([`Variational::for_newton`]).
pub fn variational_integrator(
    drr: Drr,
    spec: &SolverSpec,
    y0: &[f64; 3],
) -> Result<Box<dyn Integrator>, SolverError> {
    Ok(variational_integrator_with_tables(drr, spec, y0, None)?.0)
}

/// [`variational_integrator`] with its Butcher tables, failing once `cancel` is set.
fn variational_integrator_with_tables(
    drr: Drr,
    spec: &SolverSpec,
    y0: &[f64; 3],
    cancel: Option<&Cancel>,
) -> Result<(Box<dyn Integrator>, Vec<String>), SolverError> {
    let mut atol = spec.atol.to_vec();
    atol.extend([spec.rtol; 9]);
    let z0 = Variational::<Drr, 3>::initial(y0);
    // The method table says which methods take the simplified Jacobian (Radau5, whose Newton
    // iteration failed with the coupling block; EngineSettings::variational_newton_jacobian).
    let system: Variational<Drr, 3> = if EngineSettings::of(spec.method).variational_newton_jacobian
    {
        Variational::for_newton(drr)
    } else {
        Variational::new(drr)
    };
    integrator_cancellable(system, &drr, spec, &z0, Tolerance::PerComponent(atol), cancel)
}

/// Runs a saddle-node or van der Pol scene (the noise analysis alone, [`run`]) on `threads`
/// threads; `progress(done, total)` after each realisation; stops between realisations once
/// `cancel` is set.
fn run_other(
    scene: &OtherScene,
    scene_json: serde_json::Value,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: Option<&Cancel>,
) -> Result<ModelReport, EngineError> {
    let started = std::time::Instant::now();
    let a = &scene.noise.amplitudes;
    let (model, initial) = match &scene.model {
        OtherModel::SaddleNode { params, x0 } => (
            NoiseModel::SaddleNode { system: SaddleNode::new(*params), amplitude: a[0] },
            vec![*x0],
        ),
        OtherModel::VanDerPol { params, initial } => (
            NoiseModel::VanDerPol { system: VanDerPol::new(*params), amplitudes: [a[0], a[1]] },
            initial.to_vec(),
        ),
    };
    let stop = || cancel::is_set(cancel);
    let noise = noise::run_stoppable(&model, &initial, &scene.noise, threads, progress, &stop)
        .map_err(|e| EngineError::new(AnalysisKind::Noise, e))?;
    let section = AnalysisKind::Noise.name();
    if let Some(path) = finite::first_non_finite(&noise, section) {
        return Err(non_finite(&path, section));
    }
    Ok(ModelReport {
        stickslip_version: env!("CARGO_PKG_VERSION"),
        name: scene.name.clone(),
        scene: scene_json,
        model: scene.model.clone(),
        noise,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}
