//! CVODES' forward sensitivities: y(t) and s_j(t) = ∂y(t)/∂p_j of a [`ParametricSystem`],
//! integrated together by CVODE's BDF (or Adams) with the analytic Jacobian.
//!
//! Built on the CVODE wrapper ([`Solver::cvode`]): the same context, vectors, dense linear
//! solver, options, error capture and statistics; CVODES only adds the sensitivity equations
//! s_j' = J s_j + ∂f/∂p_j (`CVodeSensInit1` with [`callbacks::sensitivity_rhs`]), their
//! tolerances and corrector, and `CVodeSensReInit` beside every `CVodeReInit`.

use super::callbacks::{self, SensitivityScratch};
use super::cvode::CvodeSettings;
use super::ffi;
use super::solver::{counter, Getter, Solver};
use super::vector::SerialVector;
use crate::integrate::{ErrorKind, Options, ParametricSystem, SolverError, Stats, Step, Task};
use std::ffi::c_int;

/// How the sensitivities' corrector runs beside the state's (CVODES' `ism`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SensitivityCorrector {
    /// One Newton iteration for y and every s_j together (`CV_SIMULTANEOUS`).
    #[default]
    Simultaneous,
    /// The state's corrector first, then all s_j together (`CV_STAGGERED`).
    Staggered,
    /// The state's corrector first, then each s_j in turn (`CV_STAGGERED1`).
    Staggered1,
}

impl SensitivityCorrector {
    fn ism(self) -> c_int {
        match self {
            Self::Simultaneous => ffi::CV_SIMULTANEOUS,
            Self::Staggered => ffi::CV_STAGGERED,
            Self::Staggered1 => ffi::CV_STAGGERED1,
        }
    }
}

/// The sensitivities' tolerances.
#[derive(Debug, Clone, PartialEq)]
pub enum SensitivityTolerance {
    /// Estimated from the state's (`CVodeSensEEtolerances`): the state's rtol, and for s_j the
    /// state's absolute tolerances (or error weights) divided by the parameter's scale p̄_j
    /// ([`SensitivitySettings::param_scales`]).
    Estimated,
    /// A relative tolerance and one absolute tolerance per parameter (`CVodeSensSStolerances`).
    Scalar {
        /// Relative tolerance (> 0).
        rtol: f64,
        /// Absolute tolerance of each s_j (≥ 0), one per parameter.
        atol: Vec<f64>,
    },
}

/// What a [`SensitivitySolver`] takes besides the [`Options`] of the state.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivitySettings {
    /// CVODE's method (BDF for stiff problems) and stability-limit detection.
    pub cvode: CvodeSettings,
    /// The sensitivities' corrector.
    pub corrector: SensitivityCorrector,
    /// The sensitivities' tolerances.
    pub tolerance: SensitivityTolerance,
    /// Whether the sensitivities enter the local error test (`CVodeSetSensErrCon`); without,
    /// only y controls the step and the s_j are as accurate as that makes them.
    pub error_control: bool,
    /// The parameters' scales p̄_j (finite, nonzero), one per parameter
    /// (`CVodeSetSensParams`): they scale the estimated tolerances. `None`: |p_j|, or 1 for a
    /// parameter that is 0, as in SUNDIALS' examples.
    pub param_scales: Option<Vec<f64>>,
}

impl Default for SensitivitySettings {
    /// BDF, simultaneous corrector, estimated tolerances, with error control.
    fn default() -> Self {
        Self {
            cvode: CvodeSettings::default(),
            corrector: SensitivityCorrector::default(),
            tolerance: SensitivityTolerance::Estimated,
            error_control: true,
            param_scales: None,
        }
    }
}

/// CVODES' counters of the sensitivity equations, over the solver's life (restarts included).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SensitivityStats {
    /// Sensitivity right-hand-side calls (one parameter each).
    pub rhs_evals: u64,
    /// Local error-test failures caused by the sensitivities (with error control).
    pub err_test_fails: u64,
    /// Linear-solver setups of the sensitivity corrector (staggered correctors).
    pub lin_setups: u64,
    /// Nonlinear iterations of the sensitivity corrector (staggered correctors; the
    /// simultaneous one counts them with the state's).
    pub nonlin_iters: u64,
    /// Nonlinear convergence failures of the sensitivity corrector (staggered correctors).
    pub nonlin_conv_fails: u64,
}

impl SensitivityStats {
    fn accumulate(&mut self, other: &Self) {
        self.rhs_evals += other.rhs_evals;
        self.err_test_fails += other.err_test_fails;
        self.lin_setups += other.lin_setups;
        self.nonlin_iters += other.nonlin_iters;
        self.nonlin_conv_fails += other.nonlin_conv_fails;
    }
}

/// CVODE with forward sensitivities (CVODES) for a [`ParametricSystem`]: y(t) and
/// s_j(t) = ∂y(t)/∂p_j at the requested times, with restarts.
///
/// The sensitivities are stored column by column, n × m (n = [`OdeSystem::dim`],
/// m = [`ParametricSystem::n_params`]): entry (i, j) = ∂y_i/∂p_j at index `j * n + i`, for the
/// initial values as for the results.
///
/// A restart is [`SensitivitySolver::reinit`], which restarts both (`CVodeReInit` and
/// `CVodeSensReInit`); the plain solver's `set_max_step` and `rebase`, which may restart the
/// state alone, are not offered.
///
/// [`OdeSystem::dim`]: crate::integrate::OdeSystem::dim
pub struct SensitivitySolver<S> {
    /// s_j at the last return, column-major n × m.
    s: Vec<f64>,
    /// One serial vector per parameter, handed to CVODES (initial values, results).
    vectors: Vec<SerialVector>,
    /// The raw handles of `vectors`, as CVODES takes them (an `N_Vector*` array).
    handles: Vec<ffi::N_Vector>,
    corrector: SensitivityCorrector,
    /// Sensitivity counters before the last restart (CVodeSensReInit zeroes CVODES' own).
    stats_before_reinit: SensitivityStats,
    /// Dropped last: frees the CVODES memory, then the vectors it was made from, then the
    /// context (the vectors above are freed before it, and CVODES keeps no pointer to them).
    solver: Solver<S>,
}

impl<S: ParametricSystem> SensitivitySolver<S> {
    /// CVODE (`settings.cvode`) with a dense direct linear solver and the system's analytic
    /// Jacobian, starting at (t0, y0) with the sensitivities `s0` (n × m, column-major: all
    /// zeros when y0 does not depend on p), the state's tolerances and options from `options`.
    ///
    /// Errors ([`ErrorKind::InvalidInput`]): a system without parameters or without an analytic
    /// Jacobian, `s0` or the sensitivity settings of the wrong length or not finite, and
    /// everything [`Solver::cvode`] refuses.
    pub fn new(
        system: S,
        settings: &SensitivitySettings,
        t0: f64,
        y0: &[f64],
        s0: &[f64],
        options: &Options,
    ) -> Result<Self, SolverError> {
        let (n, m) = (system.dim(), system.n_params());
        let params = system.params();
        let has_jacobian = system.has_jacobian();
        let own_rhs = system.has_sensitivity_rhs();
        let mut solver = Solver::cvode(system, settings.cvode, t0, y0, options)?;
        let invalid =
            |solver: &Solver<S>, message: String| solver.error(ErrorKind::InvalidInput, 0, message);
        if !has_jacobian && !own_rhs {
            return Err(invalid(&solver, "forward sensitivities need the analytic Jacobian: implement OdeSystem::jacobian and return true from has_jacobian (or supply ParametricSystem::sensitivity_rhs)".into()));
        }
        if m == 0 {
            return Err(invalid(&solver, "the system has no parameters (n_params() = 0)".into()));
        }
        if params.len() != m {
            return Err(invalid(
                &solver,
                format!("params() returned {} values; n_params() says {m}", params.len()),
            ));
        }
        check_sensitivities(n, m, s0).map_err(|message| invalid(&solver, message))?;
        let Ok(ns) = c_int::try_from(m) else {
            return Err(invalid(&solver, format!("{m} parameters exceed what CVODES can take")));
        };
        let mut scales = match &settings.param_scales {
            Some(scales) => scales.clone(),
            None => params
                .iter()
                .map(|p| if *p != 0.0 && p.is_finite() { p.abs() } else { 1.0 })
                .collect(),
        };
        if scales.len() != m || scales.iter().any(|p| !(p.is_finite() && *p != 0.0)) {
            return Err(invalid(&solver, format!("param_scales {scales:?} must hold {m} finite, nonzero values (or be None: |p_j|)")));
        }
        let mut vectors = Vec::with_capacity(m);
        for column in s0.chunks(n) {
            match SerialVector::from_slice(column, solver.context()) {
                Some(v) => vectors.push(v),
                None => {
                    return Err(invalid(
                        &solver,
                        "could not allocate the sensitivity vectors".into(),
                    ))
                }
            }
        }
        let mut handles: Vec<ffi::N_Vector> = vectors.iter().map(SerialVector::raw).collect();
        solver.shared_mut().sensitivity = Some(SensitivityScratch::new(n, m, own_rhs));
        let mem = solver.mem();
        let rhs: ffi::CVSensRhs1Fn = Some(callbacks::sensitivity_rhs::<S>);
        // SAFETY: `mem` is live CVODES memory whose user data is the `Shared<S>` the
        // trampoline reads (its `sensitivity` scratch set just above); `handles` holds `ns`
        // live serial vectors of the state's length, which CVODES copies (it clones its own).
        solver.check(unsafe {
            ffi::CVodeSensInit1(mem, ns, settings.corrector.ism(), rhs, handles.as_mut_ptr())
        })?;
        // SAFETY: live memory with sensitivities initialised; `scales` holds `ns` values, which
        // CVODES copies; p = NULL is allowed since the sensitivity right-hand side is ours.
        solver.check(unsafe {
            ffi::CVodeSetSensParams(
                mem,
                std::ptr::null_mut(),
                scales.as_mut_ptr(),
                std::ptr::null_mut(),
            )
        })?;
        match &settings.tolerance {
            SensitivityTolerance::Estimated => {
                // SAFETY: live memory with sensitivities initialised; stores a switch.
                solver.check(unsafe { ffi::CVodeSensEEtolerances(mem) })?
            }
            SensitivityTolerance::Scalar { rtol, atol } => {
                let valid = rtol.is_finite()
                    && *rtol > 0.0
                    && atol.len() == m
                    && atol.iter().all(|a| a.is_finite() && *a >= 0.0);
                if !valid {
                    return Err(invalid(&solver, format!("sensitivity tolerances: rtol = {rtol} must be finite and > 0, atol {atol:?} one finite value ≥ 0 per parameter ({m})")));
                }
                let mut atol = atol.clone();
                // SAFETY: live memory with sensitivities initialised; `atol` holds `ns`
                // values, which CVODES copies.
                solver
                    .check(unsafe { ffi::CVodeSensSStolerances(mem, *rtol, atol.as_mut_ptr()) })?
            }
        };
        // SAFETY: live memory with sensitivities initialised; stores a flag.
        solver
            .check(unsafe { ffi::CVodeSetSensErrCon(mem, c_int::from(settings.error_control)) })?;
        Ok(Self {
            s: s0.to_vec(),
            vectors,
            handles,
            corrector: settings.corrector,
            stats_before_reinit: SensitivityStats::default(),
            solver,
        })
    }

    /// Integrates y and the s_j towards `tout` (see [`Task`]; with [`Task::Normal`] both are
    /// interpolated to `tout`) and returns where and why it stopped; the results are
    /// [`SensitivitySolver::state`] and [`SensitivitySolver::sensitivities`].
    ///
    /// Errors: those of [`Solver::advance`], at the last accepted point, and failures of the
    /// sensitivity right-hand side (a panic in the Jacobian or in ∂f/∂p is
    /// [`ErrorKind::CallbackPanic`]; non-finite sensitivity derivatives that smaller steps do
    /// not cure are [`ErrorKind::RhsFailure`], the message saying so).
    pub fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
        let nonfinite_before = self.nonfinite();
        let step = match self.solver.advance(tout, task) {
            Ok(step) => step,
            Err(e) => return Err(self.explain(e, nonfinite_before)),
        };
        let mut t = step.t;
        // SAFETY: live memory with sensitivities; `handles` holds one live serial vector of
        // the state's length per parameter, which CVODES fills with s_j at the last return.
        let flag =
            unsafe { ffi::CVodeGetSens(self.solver.mem(), &mut t, self.handles.as_mut_ptr()) };
        self.solver.check(flag)?;
        let n = self.solver.state().len();
        for (column, v) in self.s.chunks_mut(n).zip(&self.vectors) {
            column.copy_from_slice(v.as_slice());
        }
        Ok(step)
    }

    /// Restarts y and the s_j at (t0, y0, s0) (`CVodeReInit`, then `CVodeSensReInit`), keeping
    /// options, tolerances, the corrector and the running statistics: at a discontinuity of f
    /// (a velocity step of a load point) y and s_j go on from their values there, and a
    /// parameter that moves the jump itself adds its own term to s0.
    pub fn reinit(&mut self, t0: f64, y0: &[f64], s0: &[f64]) -> Result<(), SolverError> {
        self.check_restart(t0, y0, s0)?;
        let n = self.solver.state().len();
        let before = self.raw_sensitivity_stats();
        if let Some(scratch) = self.solver.shared_mut().sensitivity.as_mut() {
            scratch.invalidate();
        }
        self.solver.reinit(t0, y0)?;
        for (v, column) in self.vectors.iter_mut().zip(s0.chunks(n)) {
            v.as_mut_slice().copy_from_slice(column);
        }
        // SAFETY: live memory with sensitivities; `handles` holds the `m` vectors just filled,
        // which CVODES copies.
        let flag = unsafe {
            ffi::CVodeSensReInit(self.solver.mem(), self.corrector.ism(), self.handles.as_mut_ptr())
        };
        self.solver.check(flag).map_err(|mut e| {
            e.message.push_str(" [CVodeSensReInit failed after CVodeReInit succeeded: the sensitivities are not restarted; do not go on]");
            e
        })?;
        self.stats_before_reinit.accumulate(&before);
        self.s.copy_from_slice(s0);
        Ok(())
    }

    /// Changes the system (its parameters, its forcing: the load point's new velocity after a
    /// step) and restarts at (t0, y0, s0) as [`SensitivitySolver::reinit`] does. The only way
    /// to change the system: a change without a restart would leave CVODES' history
    /// describing another right-hand side.
    pub fn reinit_with(
        &mut self,
        t0: f64,
        y0: &[f64],
        s0: &[f64],
        change: impl FnOnce(&mut S),
    ) -> Result<(), SolverError> {
        self.check_restart(t0, y0, s0)?;
        change(&mut self.solver.shared_mut().system);
        self.reinit(t0, y0, s0)
    }

    /// Sets (or moves) the stop time (see [`Solver::set_stop_time`]): put it at the next
    /// discontinuity, and restart there with [`SensitivitySolver::reinit`].
    pub fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
        self.solver.set_stop_time(t_stop)
    }

    /// The state at the time of the last return ([`SensitivitySolver::t`]).
    pub fn state(&self) -> &[f64] {
        self.solver.state()
    }

    /// Time of the last return.
    pub fn t(&self) -> f64 {
        self.solver.t()
    }

    /// Every s_j at the time of the last return, column-major n × m: ∂y_i/∂p_j at `j * n + i`.
    pub fn sensitivities(&self) -> &[f64] {
        &self.s
    }

    /// s_j = ∂y/∂p_j at the time of the last return.
    ///
    /// # Panics
    /// If `j` ≥ [`SensitivitySolver::n_params`].
    pub fn sensitivity(&self, j: usize) -> &[f64] {
        let n = self.solver.state().len();
        &self.s[j * n..(j + 1) * n]
    }

    /// The number of parameters m.
    pub fn n_params(&self) -> usize {
        self.vectors.len()
    }

    /// The state's statistics over the solver's whole life, restarts included (as
    /// [`Solver::stats`]).
    pub fn stats(&self) -> Stats {
        self.solver.stats()
    }

    /// The sensitivities' statistics over the solver's whole life, restarts included.
    pub fn sensitivity_stats(&self) -> SensitivityStats {
        let mut stats = self.stats_before_reinit;
        stats.accumulate(&self.raw_sensitivity_stats());
        stats
    }

    /// Warnings SUNDIALS issued (the first 64), e.g. "t + h = t".
    pub fn warnings(&self) -> &[String] {
        self.solver.warnings()
    }

    /// The system being integrated.
    pub fn system(&self) -> &S {
        self.solver.system()
    }

    /// The method's name ("cvode-bdf" or "cvode-adams"), as in errors.
    pub fn name(&self) -> &'static str {
        self.solver.name()
    }

    /// An [`ErrorKind::InvalidInput`] error unless t0, y0 and s0 are a finite restart point of
    /// the right dimensions.
    fn check_restart(&self, t0: f64, y0: &[f64], s0: &[f64]) -> Result<(), SolverError> {
        let (n, m) = (self.solver.state().len(), self.vectors.len());
        let state = if y0.len() != n || !t0.is_finite() || y0.iter().any(|v| !v.is_finite()) {
            Err(format!(
                "a restart needs a finite t0 and {n} finite components, got t0 = {t0}, y0 = {}",
                crate::integrate::brief_state(y0)
            ))
        } else {
            Ok(())
        };
        state
            .and_then(|()| check_sensitivities(n, m, s0))
            .map_err(|message| self.solver.error(ErrorKind::InvalidInput, 0, message))
    }

    /// CVODES' sensitivity counters since the last (re)start.
    fn raw_sensitivity_stats(&self) -> SensitivityStats {
        let m = self.solver.mem();
        // SAFETY: `m` is live CVODES memory with sensitivities initialised; each getter
        // writes one long.
        let count = |get: Getter| unsafe { counter(m, get) };
        SensitivityStats {
            rhs_evals: count(ffi::CVodeGetSensNumRhsEvals),
            err_test_fails: count(ffi::CVodeGetSensNumErrTestFails),
            lin_setups: count(ffi::CVodeGetSensNumLinSolvSetups),
            nonlin_iters: count(ffi::CVodeGetSensNumNonlinSolvIters),
            nonlin_conv_fails: count(ffi::CVodeGetSensNumNonlinSolvConvFails),
        }
    }

    /// Non-finite sensitivity right-hand sides so far.
    fn nonfinite(&self) -> u64 {
        self.solver.shared().sensitivity.as_ref().map_or(0, |s| s.nonfinite)
    }

    /// Adds to a failure of `advance` what the sensitivities had to do with it.
    fn explain(&self, mut e: SolverError, nonfinite_before: u64) -> SolverError {
        if let Some(why) = sensitivity_flag(e.flag) {
            e.message.push_str(&format!(" [{why}]"));
        }
        let nonfinite = self.nonfinite() - nonfinite_before;
        if nonfinite > 0 && e.kind != ErrorKind::CallbackPanic {
            // The steps shrank (to a step underflow, to too much work) because the sensitivity
            // right-hand side kept failing: that is the root cause.
            e.kind = ErrorKind::RhsFailure;
        }
        if nonfinite > 0 {
            e.message.push_str(&format!(
                " [{nonfinite} sensitivity right-hand sides J·s_j + ∂f/∂p_j were not finite]"
            ));
        }
        e
    }
}

/// What a sensitivity-specific CVODES return code means.
fn sensitivity_flag(flag: c_int) -> Option<&'static str> {
    Some(match flag {
        ffi::CV_SRHSFUNC_FAIL => "CV_SRHSFUNC_FAIL: the sensitivity right-hand side failed unrecoverably",
        ffi::CV_FIRST_SRHSFUNC_ERR => "CV_FIRST_SRHSFUNC_ERR: the sensitivity right-hand side failed at its first call",
        ffi::CV_REPTD_SRHSFUNC_ERR => "CV_REPTD_SRHSFUNC_ERR: the sensitivity right-hand side failed recoverably again and again (non-finite values)",
        ffi::CV_UNREC_SRHSFUNC_ERR => "CV_UNREC_SRHSFUNC_ERR: the sensitivity right-hand side failed and CVODES could not recover",
        _ => return None,
    })
}

/// Why `s` is not n × m finite sensitivities, if it is not.
fn check_sensitivities(n: usize, m: usize, s: &[f64]) -> Result<(), String> {
    if s.len() != n * m {
        return Err(format!(
            "the sensitivities hold {} values; they must be n × m = {n} × {m} (column j = ∂y/∂p_j)",
            s.len()
        ));
    }
    match s.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(format!("sensitivity ∂y_{}/∂p_{} = {} must be finite", k % n, k / n, s[k])),
        None => Ok(()),
    }
}

impl<S> std::fmt::Debug for SensitivitySolver<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SensitivitySolver")
            .field("solver", &self.solver)
            .field("corrector", &self.corrector)
            .field("n_params", &self.vectors.len())
            .finish()
    }
}
