//! CVODE: variable-order BDF (stiff) and Adams–Moulton (non-stiff) multistep methods.

use super::callbacks;
use super::ffi;
use super::solver::{check_dimension, counter, Api, Creation, Getter, Solver, StatGetters};
use crate::integrate::{ErrorKind, OdeSystem, Options, SolverError, Stats};
use crate::method::Method;
use std::ffi::{c_int, c_long, c_void};

/// CVODE's linear multistep family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CvodeMethod {
    /// Backward differentiation formulas, orders 1–5 (stiff problems).
    Bdf,
    /// Adams–Moulton, orders 1–12 (non-stiff problems).
    Adams,
}

/// CVODE-only settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CvodeSettings {
    /// BDF or Adams.
    pub method: CvodeMethod,
    /// BDF stability-limit detection (ignored by Adams).
    pub stability_limit_detection: bool,
}

impl Default for CvodeSettings {
    fn default() -> Self {
        Self { method: CvodeMethod::Bdf, stability_limit_detection: false }
    }
}

fn classify(flag: c_int) -> ErrorKind {
    match flag {
        ffi::CV_TOO_MUCH_WORK => ErrorKind::TooMuchWork,
        ffi::CV_TOO_MUCH_ACC => ErrorKind::AccuracyNotAttainable,
        ffi::CV_ERR_FAILURE => ErrorKind::ErrorTestFailures,
        ffi::CV_CONV_FAILURE
        | ffi::CV_NLS_FAIL
        | ffi::CV_NLS_INIT_FAIL
        | ffi::CV_NLS_SETUP_FAIL => ErrorKind::ConvergenceFailures,
        ffi::CV_LINIT_FAIL | ffi::CV_LSETUP_FAIL | ffi::CV_LSOLVE_FAIL => ErrorKind::LinearSolver,
        ffi::CV_RHSFUNC_FAIL
        | ffi::CV_FIRST_RHSFUNC_ERR
        | ffi::CV_REPTD_RHSFUNC_ERR
        | ffi::CV_UNREC_RHSFUNC_ERR
        // CVODES' forward sensitivities (crates/ode/src/sundials/cvodes.rs): their right-hand
        // side.
        | ffi::CV_SRHSFUNC_FAIL
        | ffi::CV_FIRST_SRHSFUNC_ERR
        | ffi::CV_REPTD_SRHSFUNC_ERR
        | ffi::CV_UNREC_SRHSFUNC_ERR => ErrorKind::RhsFailure,
        ffi::CV_RTFUNC_FAIL => ErrorKind::RootFunctionFailure,
        ffi::CV_ILL_INPUT
        | ffi::CV_BAD_K
        | ffi::CV_BAD_T
        | ffi::CV_BAD_DKY
        | ffi::CV_TOO_CLOSE
        | ffi::CV_NO_MALLOC
        | ffi::CV_NO_SENS
        | ffi::CV_BAD_IS => ErrorKind::InvalidInput,
        _ => ErrorKind::Other,
    }
}

/// [`Api::read_own_stats`] for CVODE: f evaluations, stability-limit order reductions and
/// the order of the last step; the attempts from the steps and failures.
unsafe fn read_own_stats(m: *mut c_void, s: &mut Stats) {
    // SAFETY: `m` is live CVODE memory (caller's guarantee), and every getter is CVODE's.
    let count = |get: Getter| unsafe { counter(m, get) };
    s.rhs_evals = count(ffi::CVodeGetNumRhsEvals);
    s.stab_lim_order_reductions = count(ffi::CVodeGetNumStabLimOrderReds);
    s.step_attempts = s.steps + s.err_test_fails + s.step_solve_fails;
    // SAFETY: as above; the getter writes one int.
    unsafe { ffi::CVodeGetLastOrder(m, &mut s.last_order) };
}

/// [`Api::set_jacobian_max_age`] for CVODE.
///
/// # Safety
/// `m` is live CVODE memory with a linear solver attached.
unsafe fn set_jacobian_max_age(m: *mut c_void, age: i64) -> c_int {
    let age = age as c_long;
    // SAFETY: per this function's contract; the setter stores a scalar.
    let flag = unsafe { ffi::CVodeSetLSetupFrequency(m, age) };
    if flag != 0 {
        return flag;
    }
    // SAFETY: as above.
    unsafe { ffi::CVodeSetJacEvalFrequency(m, age) }
}

static CVODE: Api = Api {
    name: "CVODE",
    free: ffi::CVodeFree,
    evolve: ffi::CVode,
    get_dky: ffi::CVodeGetDky,
    set_user_data: ffi::CVodeSetUserData,
    #[cfg(not(sundials7))]
    set_err_handler: ffi::CVodeSetErrHandlerFn,
    ss_tolerances: ffi::CVodeSStolerances,
    sv_tolerances: ffi::CVodeSVtolerances,
    wf_tolerances: ffi::CVodeWFtolerances,
    set_linear_solver: ffi::CVodeSetLinearSolver,
    set_jac_fn: ffi::CVodeSetJacFn,
    root_init: ffi::CVodeRootInit,
    set_root_direction: ffi::CVodeSetRootDirection,
    get_root_info: ffi::CVodeGetRootInfo,
    set_stop_time: ffi::CVodeSetStopTime,
    set_max_num_steps: ffi::CVodeSetMaxNumSteps,
    set_init_step: ffi::CVodeSetInitStep,
    set_min_step: ffi::CVodeSetMinStep,
    set_max_step: ffi::CVodeSetMaxStep,
    set_max_err_test_fails: ffi::CVodeSetMaxErrTestFails,
    set_max_nonlin_iters: ffi::CVodeSetMaxNonlinIters,
    set_max_conv_fails: ffi::CVodeSetMaxConvFails,
    set_nonlin_conv_coef: ffi::CVodeSetNonlinConvCoef,
    set_max_hnil_warns: ffi::CVodeSetMaxHnilWarns,
    set_jacobian_max_age,
    reinit: ffi::CVodeReInit,
    reinit_resets_counters: true,
    stats: StatGetters {
        steps: ffi::CVodeGetNumSteps,
        lin_setups: ffi::CVodeGetNumLinSolvSetups,
        err_test_fails: ffi::CVodeGetNumErrTestFails,
        step_solve_fails: ffi::CVodeGetNumStepSolveFails,
        nonlin_iters: ffi::CVodeGetNumNonlinSolvIters,
        nonlin_conv_fails: ffi::CVodeGetNumNonlinSolvConvFails,
        jac_evals: ffi::CVodeGetNumJacEvals,
        lin_rhs_evals: ffi::CVodeGetNumLinRhsEvals,
        root_evals: ffi::CVodeGetNumGEvals,
        last_step: ffi::CVodeGetLastStep,
        current_step: ffi::CVodeGetCurrentStep,
        initial_step: ffi::CVodeGetActualInitStep,
    },
    read_own_stats,
    classify,
    explain: |_| None,
    dense_order_is_last_order: true,
};

impl<S: OdeSystem> Solver<S> {
    /// CVODE with a dense direct linear solver, the system's analytic Jacobian when it has one
    /// (finite differences otherwise), starting at (t0, y0).
    pub fn cvode(
        system: S,
        settings: CvodeSettings,
        t0: f64,
        y0: &[f64],
        options: &Options,
    ) -> Result<Self, SolverError> {
        let method = match settings.method {
            CvodeMethod::Bdf => Method::CvodeBdf,
            CvodeMethod::Adams => Method::CvodeAdams,
        };
        check_dimension(method.name(), system.dim(), t0, y0)?;
        let jacobian: ffi::CVLsJacFn =
            if system.has_jacobian() { Some(callbacks::jacobian::<S>) } else { None };
        let creation = Creation {
            method,
            jacobian_hint: crate::integrate::jacobian_hint::<S>,
            system,
            t0,
            y0: y0.to_vec(),
            needs_linear_solver: true,
            jacobian,
            rhs: S::rhs,
        };
        let lmm = match settings.method {
            CvodeMethod::Bdf => ffi::CV_BDF,
            CvodeMethod::Adams => ffi::CV_ADAMS,
        };
        let mut solver = Solver::build(&CVODE, creation, options, |y, ctx| {
            // SAFETY: creates CVODE memory in a live context, then initialises it with our
            // RHS trampoline; CVodeInit copies `y`.
            unsafe {
                let m = ffi::CVodeCreate(lmm, ctx.raw());
                if !m.is_null() && ffi::CVodeInit(m, Some(callbacks::rhs::<S>), t0, y.raw()) != 0 {
                    let mut m = m;
                    ffi::CVodeFree(&mut m);
                    return std::ptr::null_mut();
                }
                m
            }
        })?;
        let m = solver.mem();
        if let Some(order) = options.max_order {
            // SAFETY: live CVODE memory; stores a scalar.
            solver.check(unsafe { ffi::CVodeSetMaxOrd(m, order) })?;
        }
        if settings.stability_limit_detection && settings.method == CvodeMethod::Bdf {
            // SAFETY: live CVODE memory; stores a flag.
            solver.check(unsafe { ffi::CVodeSetStabLimDet(m, 1) })?;
        }
        Ok(solver)
    }
}
