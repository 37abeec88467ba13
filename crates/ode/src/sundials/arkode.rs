//! ARKODE's ARKStep: diagonally implicit (DIRK), implicit–explicit (IMEX) and explicit (ERK)
//! Runge–Kutta methods with embedded error estimates.

use super::callbacks;
use super::ffi;
use super::solver::{check_dimension, counter, Api, Creation, Solver, StatGetters};
use crate::integrate::{ErrorKind, ImexSystem, OdeSystem, Options, SolverError, Stats};
use crate::method::Method;
use std::ffi::{c_int, c_long, c_void};

/// Declares `mod ark` with one name per ARKStep operation, from rows
/// `Name: SUNDIALS 7 spelling, SUNDIALS 6 spelling;`. SUNDIALS 7 deprecates the `ARKStep*`
/// spellings of the operations every ARKODE stepper shares in favour of the generic `ARKode*`
/// ones (same signatures); 6.x has only the former.
macro_rules! ark_names {
    ($($name:ident: $v7:ident, $v6:ident;)*) => {
        #[cfg(sundials7)]
        mod ark {
            pub(super) use super::ffi::{$($v7 as $name),*};
        }
        #[cfg(not(sundials7))]
        mod ark {
            pub(super) use super::ffi::{$($v6 as $name),*};
        }
    };
}

ark_names! {
    Evolve: ARKodeEvolve, ARKStepEvolve;
    Free: ARKodeFree, ARKStepFree;
    GetActualInitStep: ARKodeGetActualInitStep, ARKStepGetActualInitStep;
    GetCurrentStep: ARKodeGetCurrentStep, ARKStepGetCurrentStep;
    GetDky: ARKodeGetDky, ARKStepGetDky;
    GetLastStep: ARKodeGetLastStep, ARKStepGetLastStep;
    GetNumErrTestFails: ARKodeGetNumErrTestFails, ARKStepGetNumErrTestFails;
    GetNumGEvals: ARKodeGetNumGEvals, ARKStepGetNumGEvals;
    GetNumJacEvals: ARKodeGetNumJacEvals, ARKStepGetNumJacEvals;
    GetNumLinRhsEvals: ARKodeGetNumLinRhsEvals, ARKStepGetNumLinRhsEvals;
    GetNumLinSolvSetups: ARKodeGetNumLinSolvSetups, ARKStepGetNumLinSolvSetups;
    GetNumNonlinSolvConvFails: ARKodeGetNumNonlinSolvConvFails, ARKStepGetNumNonlinSolvConvFails;
    GetNumNonlinSolvIters: ARKodeGetNumNonlinSolvIters, ARKStepGetNumNonlinSolvIters;
    GetNumStepAttempts: ARKodeGetNumStepAttempts, ARKStepGetNumStepAttempts;
    GetNumStepSolveFails: ARKodeGetNumStepSolveFails, ARKStepGetNumStepSolveFails;
    GetNumSteps: ARKodeGetNumSteps, ARKStepGetNumSteps;
    GetRootInfo: ARKodeGetRootInfo, ARKStepGetRootInfo;
    Reset: ARKodeReset, ARKStepReset;
    RootInit: ARKodeRootInit, ARKStepRootInit;
    SStolerances: ARKodeSStolerances, ARKStepSStolerances;
    SVtolerances: ARKodeSVtolerances, ARKStepSVtolerances;
    SetDeduceImplicitRhs: ARKodeSetDeduceImplicitRhs, ARKStepSetDeduceImplicitRhs;
    SetFixedStepBounds: ARKodeSetFixedStepBounds, ARKStepSetFixedStepBounds;
    SetInitStep: ARKodeSetInitStep, ARKStepSetInitStep;
    SetInterpolantType: ARKodeSetInterpolantType, ARKStepSetInterpolantType;
    SetJacEvalFrequency: ARKodeSetJacEvalFrequency, ARKStepSetJacEvalFrequency;
    SetJacFn: ARKodeSetJacFn, ARKStepSetJacFn;
    SetLSetupFrequency: ARKodeSetLSetupFrequency, ARKStepSetLSetupFrequency;
    SetLinearSolver: ARKodeSetLinearSolver, ARKStepSetLinearSolver;
    SetMaxConvFails: ARKodeSetMaxConvFails, ARKStepSetMaxConvFails;
    SetMaxErrTestFails: ARKodeSetMaxErrTestFails, ARKStepSetMaxErrTestFails;
    SetMaxHnilWarns: ARKodeSetMaxHnilWarns, ARKStepSetMaxHnilWarns;
    SetMaxNonlinIters: ARKodeSetMaxNonlinIters, ARKStepSetMaxNonlinIters;
    SetMaxNumSteps: ARKodeSetMaxNumSteps, ARKStepSetMaxNumSteps;
    SetMaxStep: ARKodeSetMaxStep, ARKStepSetMaxStep;
    SetMinStep: ARKodeSetMinStep, ARKStepSetMinStep;
    SetNonlinConvCoef: ARKodeSetNonlinConvCoef, ARKStepSetNonlinConvCoef;
    SetPostprocessStepFn: ARKodeSetPostprocessStepFn, ARKStepSetPostprocessStepFn;
    SetPredictorMethod: ARKodeSetPredictorMethod, ARKStepSetPredictorMethod;
    SetRootDirection: ARKodeSetRootDirection, ARKStepSetRootDirection;
    SetStopTime: ARKodeSetStopTime, ARKStepSetStopTime;
    SetUserData: ARKodeSetUserData, ARKStepSetUserData;
    WFtolerances: ARKodeWFtolerances, ARKStepWFtolerances;
}

/// Implicit (DIRK) Butcher tables of the linked ARKODE, by name without the `ARKODE_` prefix.
const DIRK_TABLES: &[(&str, c_int)] = &[
    ("SDIRK_2_1_2", ffi::ARKODE_DIRKTableID_ARKODE_SDIRK_2_1_2),
    ("BILLINGTON_3_3_2", ffi::ARKODE_DIRKTableID_ARKODE_BILLINGTON_3_3_2),
    ("TRBDF2_3_3_2", ffi::ARKODE_DIRKTableID_ARKODE_TRBDF2_3_3_2),
    ("KVAERNO_4_2_3", ffi::ARKODE_DIRKTableID_ARKODE_KVAERNO_4_2_3),
    ("ARK324L2SA_DIRK_4_2_3", ffi::ARKODE_DIRKTableID_ARKODE_ARK324L2SA_DIRK_4_2_3),
    ("CASH_5_2_4", ffi::ARKODE_DIRKTableID_ARKODE_CASH_5_2_4),
    ("CASH_5_3_4", ffi::ARKODE_DIRKTableID_ARKODE_CASH_5_3_4),
    ("SDIRK_5_3_4", ffi::ARKODE_DIRKTableID_ARKODE_SDIRK_5_3_4),
    ("KVAERNO_5_3_4", ffi::ARKODE_DIRKTableID_ARKODE_KVAERNO_5_3_4),
    ("ARK436L2SA_DIRK_6_3_4", ffi::ARKODE_DIRKTableID_ARKODE_ARK436L2SA_DIRK_6_3_4),
    ("KVAERNO_7_4_5", ffi::ARKODE_DIRKTableID_ARKODE_KVAERNO_7_4_5),
    ("ARK548L2SA_DIRK_8_4_5", ffi::ARKODE_DIRKTableID_ARKODE_ARK548L2SA_DIRK_8_4_5),
    ("ARK437L2SA_DIRK_7_3_4", ffi::ARKODE_DIRKTableID_ARKODE_ARK437L2SA_DIRK_7_3_4),
    ("ARK548L2SAb_DIRK_8_4_5", ffi::ARKODE_DIRKTableID_ARKODE_ARK548L2SAb_DIRK_8_4_5),
    ("ESDIRK324L2SA_4_2_3", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK324L2SA_4_2_3),
    ("ESDIRK325L2SA_5_2_3", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK325L2SA_5_2_3),
    ("ESDIRK32I5L2SA_5_2_3", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK32I5L2SA_5_2_3),
    ("ESDIRK436L2SA_6_3_4", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK436L2SA_6_3_4),
    ("ESDIRK43I6L2SA_6_3_4", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK43I6L2SA_6_3_4),
    ("QESDIRK436L2SA_6_3_4", ffi::ARKODE_DIRKTableID_ARKODE_QESDIRK436L2SA_6_3_4),
    ("ESDIRK437L2SA_7_3_4", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK437L2SA_7_3_4),
    ("ESDIRK547L2SA_7_4_5", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK547L2SA_7_4_5),
    ("ESDIRK547L2SA2_7_4_5", ffi::ARKODE_DIRKTableID_ARKODE_ESDIRK547L2SA2_7_4_5),
];

/// Explicit (ERK) Butcher tables of the linked ARKODE, by name without the `ARKODE_` prefix.
const ERK_TABLES: &[(&str, c_int)] = &[
    ("HEUN_EULER_2_1_2", ffi::ARKODE_ERKTableID_ARKODE_HEUN_EULER_2_1_2),
    ("BOGACKI_SHAMPINE_4_2_3", ffi::ARKODE_ERKTableID_ARKODE_BOGACKI_SHAMPINE_4_2_3),
    ("ARK324L2SA_ERK_4_2_3", ffi::ARKODE_ERKTableID_ARKODE_ARK324L2SA_ERK_4_2_3),
    ("ZONNEVELD_5_3_4", ffi::ARKODE_ERKTableID_ARKODE_ZONNEVELD_5_3_4),
    ("ARK436L2SA_ERK_6_3_4", ffi::ARKODE_ERKTableID_ARKODE_ARK436L2SA_ERK_6_3_4),
    ("SAYFY_ABURUB_6_3_4", ffi::ARKODE_ERKTableID_ARKODE_SAYFY_ABURUB_6_3_4),
    ("CASH_KARP_6_4_5", ffi::ARKODE_ERKTableID_ARKODE_CASH_KARP_6_4_5),
    ("FEHLBERG_6_4_5", ffi::ARKODE_ERKTableID_ARKODE_FEHLBERG_6_4_5),
    ("DORMAND_PRINCE_7_4_5", ffi::ARKODE_ERKTableID_ARKODE_DORMAND_PRINCE_7_4_5),
    ("ARK548L2SA_ERK_8_4_5", ffi::ARKODE_ERKTableID_ARKODE_ARK548L2SA_ERK_8_4_5),
    ("VERNER_8_5_6", ffi::ARKODE_ERKTableID_ARKODE_VERNER_8_5_6),
    ("FEHLBERG_13_7_8", ffi::ARKODE_ERKTableID_ARKODE_FEHLBERG_13_7_8),
    ("KNOTH_WOLKE_3_3", ffi::ARKODE_ERKTableID_ARKODE_KNOTH_WOLKE_3_3),
    ("ARK437L2SA_ERK_7_3_4", ffi::ARKODE_ERKTableID_ARKODE_ARK437L2SA_ERK_7_3_4),
    ("ARK548L2SAb_ERK_8_4_5", ffi::ARKODE_ERKTableID_ARKODE_ARK548L2SAb_ERK_8_4_5),
];

macro_rules! table_type {
    ($(#[$doc:meta])* $name:ident, $list:ident) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub struct $name(c_int);

        impl $name {
            /// Looks a table up by its ARKODE name without the `ARKODE_` prefix.
            pub fn from_name(name: &str) -> Option<Self> {
                $list.iter().find(|(n, _)| *n == name).map(|&(_, id)| Self(id))
            }

            /// The table's ARKODE name (without the `ARKODE_` prefix).
            pub fn name(self) -> &'static str {
                $list.iter().find(|(_, id)| *id == self.0).map_or("?", |(n, _)| n)
            }

            /// Names of every table of this kind in the linked ARKODE.
            pub fn names() -> impl Iterator<Item = &'static str> {
                $list.iter().map(|(n, _)| *n)
            }
        }
    };
}

table_type!(
    /// A diagonally implicit Runge–Kutta table, e.g. `DirkTable::from_name("SDIRK_5_3_4")`.
    DirkTable,
    DIRK_TABLES
);
table_type!(
    /// An explicit Runge–Kutta table, e.g. `ErkTable::from_name("DORMAND_PRINCE_7_4_5")`.
    ErkTable,
    ERK_TABLES
);

impl Default for DirkTable {
    /// SDIRK-5-3-4 (Hairer–Wanner): order 4, L-stable and stiffly accurate; ARKODE's own
    /// default implicit table.
    fn default() -> Self {
        Self(ffi::ARKODE_DIRKTableID_ARKODE_SDIRK_5_3_4)
    }
}

impl Default for ErkTable {
    /// Zonneveld-5-3-4, ARKODE's default order-4 explicit table.
    fn default() -> Self {
        Self(ffi::ARKODE_ERKTableID_ARKODE_ZONNEVELD_5_3_4)
    }
}

/// Which ARKStep form to use on a plain [`OdeSystem`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArkMethod {
    /// Fully implicit DIRK (stiff problems), Newton with a dense direct linear solver.
    Dirk(DirkTable),
    /// Fully explicit Runge–Kutta (non-stiff problems).
    Erk(ErkTable),
}

impl Default for ArkMethod {
    fn default() -> Self {
        ArkMethod::Dirk(DirkTable::default())
    }
}

/// ARKStep-only settings.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ArkSettings {
    /// Implicit-stage predictor (ARKStepSetPredictorMethod: 0 trivial … 5); `None` keeps
    /// ARKODE's default (0), or 1 (maximum order) for implicit stages without
    /// `deduce_implicit_rhs`, which also default to `nonlin_conv_coef` = 1e-7 and
    /// `max_err_test_fails` = 20 (the settings of SUNDIALS' ark_robertson example).
    pub predictor_method: Option<i32>,
    /// Deduce each implicit stage derivative from the stage equation, (z_i − a_i)/(h γ),
    /// instead of evaluating f_I(z_i) (ARKStepSetDeduceImplicitRhs). On very stiff problems
    /// the evaluated f_I carries the Newton residual times the stiffness into the error
    /// estimate; deducing it avoids that.
    pub deduce_implicit_rhs: bool,
    /// Apply every step-size change the controller proposes (ARKStepSetFixedStepBounds(1, 1)).
    /// By default ARKODE keeps h when the proposed growth factor lies in [1, 1.5], which
    /// saves linear-solver setups; when the error estimate stays at a level independent of h
    /// (a round-off or Newton-error floor, e.g. on a slow manifold) that proposal can stay in
    /// the window for ever, and h with it.
    pub resize_every_step: bool,
    /// Rebuild the Newton matrix (Jacobian and LU) at every implicit stage, not only at the
    /// first stage of a step (ARKStepSetLSetupFrequency(−1)). This also restarts ARKODE's
    /// Newton convergence-rate estimate at each stage: otherwise the rate measured on an
    /// earlier stage (decayed by 0.3 an iteration) carries over, and ARKODE's stopping test,
    /// min(1, rate) · ‖correction‖ < `nonlin_conv_coef`, can stop a stage far from its
    /// solution. Overrides the setup frequency of [`Options::jacobian_max_age`].
    pub setup_every_stage: bool,
}

fn classify(flag: c_int) -> ErrorKind {
    match flag {
        ffi::ARK_TOO_MUCH_WORK => ErrorKind::TooMuchWork,
        ffi::ARK_TOO_MUCH_ACC => ErrorKind::AccuracyNotAttainable,
        ffi::ARK_ERR_FAILURE => ErrorKind::ErrorTestFailures,
        ffi::ARK_CONV_FAILURE
        | ffi::ARK_NLS_INIT_FAIL
        | ffi::ARK_NLS_SETUP_FAIL
        | ffi::ARK_NLS_OP_ERR => ErrorKind::ConvergenceFailures,
        ffi::ARK_LINIT_FAIL | ffi::ARK_LSETUP_FAIL | ffi::ARK_LSOLVE_FAIL => {
            ErrorKind::LinearSolver
        }
        ffi::ARK_RHSFUNC_FAIL
        | ffi::ARK_FIRST_RHSFUNC_ERR
        | ffi::ARK_REPTD_RHSFUNC_ERR
        | ffi::ARK_UNREC_RHSFUNC_ERR => ErrorKind::RhsFailure,
        ffi::ARK_RTFUNC_FAIL => ErrorKind::RootFunctionFailure,
        ffi::ARK_ILL_INPUT
        | ffi::ARK_BAD_K
        | ffi::ARK_BAD_T
        | ffi::ARK_BAD_DKY
        | ffi::ARK_TOO_CLOSE
        | ffi::ARK_NO_MALLOC
        | ffi::ARK_INVALID_TABLE => ErrorKind::InvalidInput,
        _ => ErrorKind::Other,
    }
}

/// What ARKStep's return codes leave unsaid.
fn explain(flag: c_int) -> Option<&'static str> {
    // ARKStep retries a smaller step only when f fails inside a Newton iteration; after an
    // explicit stage, or the evaluation that follows a converged implicit stage, it stops.
    (flag == ffi::ARK_UNREC_RHSFUNC_ERR)
        .then_some("ARKStep tries no smaller step when f fails at an explicit stage or after an implicit stage's solve")
}

/// [`Api::read_own_stats`] for ARKStep: attempts, f evaluations and the method's order.
unsafe fn read_own_stats(m: *mut c_void, s: &mut Stats) {
    // SAFETY: `m` is live ARKStep memory (caller's guarantee), and every getter is ARKStep's.
    s.step_attempts = unsafe { counter(m, ark::GetNumStepAttempts) };
    let (mut nfe, mut nfi): (c_long, c_long) = (0, 0);
    let (mut implicit, mut explicit): (ffi::ARKodeButcherTable, ffi::ARKodeButcherTable) =
        (std::ptr::null_mut(), std::ptr::null_mut());
    // SAFETY: as above; each getter writes values of the pointed-to types. The Butcher-table
    // pointers refer to ARKStep's own tables (or are null before the first step) and are only
    // read here, while the memory is alive.
    unsafe {
        ffi::ARKStepGetNumRhsEvals(m, &mut nfe, &mut nfi);
        ffi::ARKStepGetCurrentButcherTables(m, &mut implicit, &mut explicit);
        let table = if implicit.is_null() { explicit } else { implicit };
        if !table.is_null() {
            s.last_order = (*table).q;
        }
    }
    s.rhs_evals = nfi.max(0) as u64;
    s.rhs_evals_explicit = nfe.max(0) as u64;
}

/// [`Api::set_jacobian_max_age`] for ARKStep.
///
/// # Safety
/// `m` is live ARKStep memory with a linear solver attached.
unsafe fn set_jacobian_max_age(m: *mut c_void, age: i64) -> c_int {
    // SAFETY: per this function's contract; the setter stores a scalar.
    let flag = unsafe { ark::SetLSetupFrequency(m, c_int::try_from(age).unwrap_or(c_int::MAX)) };
    if flag != 0 {
        return flag;
    }
    // SAFETY: as above.
    unsafe { ark::SetJacEvalFrequency(m, age as c_long) }
}

static ARKSTEP: Api = Api {
    name: "ARKStep",
    free: ark::Free,
    evolve: ark::Evolve,
    get_dky: ark::GetDky,
    set_user_data: ark::SetUserData,
    #[cfg(not(sundials7))]
    set_err_handler: ffi::ARKStepSetErrHandlerFn,
    ss_tolerances: ark::SStolerances,
    sv_tolerances: ark::SVtolerances,
    wf_tolerances: ark::WFtolerances,
    set_linear_solver: ark::SetLinearSolver,
    set_jac_fn: ark::SetJacFn,
    root_init: ark::RootInit,
    set_root_direction: ark::SetRootDirection,
    get_root_info: ark::GetRootInfo,
    set_stop_time: ark::SetStopTime,
    set_max_num_steps: ark::SetMaxNumSteps,
    set_init_step: ark::SetInitStep,
    set_min_step: ark::SetMinStep,
    set_max_step: ark::SetMaxStep,
    set_max_err_test_fails: ark::SetMaxErrTestFails,
    set_max_nonlin_iters: ark::SetMaxNonlinIters,
    set_max_conv_fails: ark::SetMaxConvFails,
    set_nonlin_conv_coef: ark::SetNonlinConvCoef,
    set_max_hnil_warns: ark::SetMaxHnilWarns,
    // ARKStepReset keeps options and counters; only time, state and step history restart.
    set_jacobian_max_age,
    reinit: ark::Reset,
    reinit_resets_counters: false,
    stats: StatGetters {
        steps: ark::GetNumSteps,
        lin_setups: ark::GetNumLinSolvSetups,
        err_test_fails: ark::GetNumErrTestFails,
        step_solve_fails: ark::GetNumStepSolveFails,
        nonlin_iters: ark::GetNumNonlinSolvIters,
        nonlin_conv_fails: ark::GetNumNonlinSolvConvFails,
        jac_evals: ark::GetNumJacEvals,
        lin_rhs_evals: ark::GetNumLinRhsEvals,
        root_evals: ark::GetNumGEvals,
        last_step: ark::GetLastStep,
        current_step: ark::GetCurrentStep,
        initial_step: ark::GetActualInitStep,
    },
    read_own_stats,
    classify,
    explain,
    dense_order_is_last_order: false,
};

/// An explicit method has no Newton iteration: its options are an error naming the first one
/// set (SUNDIALS' own answer is a raw "no nonlinear solver" message).
fn no_newton(
    name: &'static str,
    options: &Options,
    t0: f64,
    y0: &[f64],
) -> Result<(), SolverError> {
    let newton = [
        ("max_nonlin_iters", options.max_nonlin_iters.is_some()),
        ("max_conv_fails", options.max_conv_fails.is_some()),
        ("nonlin_conv_coef", options.nonlin_conv_coef.is_some()),
    ];
    match newton.iter().find(|(_, set)| *set) {
        None => Ok(()),
        Some((option, _)) => Err(SolverError {
            solver: name,
            kind: ErrorKind::InvalidInput,
            t: t0,
            state: y0.to_vec(),
            flag: 0,
            message: format!("{option} is not an option of {name} (an explicit method has no Newton iteration): leave it unset (None)"),
        }),
    }
}

impl<S> Solver<S> {
    fn finish_arkstep(
        &mut self,
        options: &Options,
        settings: ArkSettings,
        tables: (c_int, c_int),
    ) -> Result<(), SolverError> {
        let m = self.mem();
        if let Some(order) = options.max_order {
            let message = format!("max_order = {order} applies to CVODE; ARKStep's order is that of its Butcher table");
            return Err(SolverError {
                solver: self.name(),
                kind: ErrorKind::InvalidInput,
                t: self.t(),
                state: self.state().to_vec(),
                flag: 0,
                message,
            });
        }
        // SAFETY: live ARKStep memory; the ids name built-in tables of this ARKODE.
        self.check(unsafe { ffi::ARKStepSetTableNum(m, tables.0, tables.1) })?;
        // Implicit defaults (unless set, or deducing the stage derivatives): SUNDIALS'
        // ark_robertson settings. With ARKODE's own defaults the Newton residual, times the
        // stiffness, enters the error estimate through f_I(z_i), and OREGO, ROBER and E5 end
        // in repeated error-test failures (docs/test-set.md).
        let tight_newton =
            tables.0 != ffi::ARKODE_DIRKTableID_ARKODE_DIRK_NONE && !settings.deduce_implicit_rhs;
        let predictor = settings.predictor_method.or(tight_newton.then_some(1));
        if tight_newton && options.nonlin_conv_coef.is_none() {
            // SAFETY: live ARKStep memory; stores a scalar.
            self.check(unsafe { ffi::ARKStepSetNonlinConvCoef(m, 1e-7) })?;
        }
        if tight_newton && options.max_err_test_fails.is_none() {
            // SAFETY: live ARKStep memory; stores a scalar.
            self.check(unsafe { ffi::ARKStepSetMaxErrTestFails(m, 20) })?;
        }
        if let Some(p) = predictor {
            // SAFETY: live ARKStep memory; stores a scalar.
            self.check(unsafe { ark::SetPredictorMethod(m, p) })?;
        }
        if settings.deduce_implicit_rhs {
            // SAFETY: live ARKStep memory; stores a flag.
            self.check(unsafe { ark::SetDeduceImplicitRhs(m, 1) })?;
        }
        if settings.resize_every_step {
            // SAFETY: live ARKStep memory; stores two scalars (an interval enclosing 1).
            self.check(unsafe { ark::SetFixedStepBounds(m, 1.0, 1.0) })?;
        }
        if settings.setup_every_stage {
            // SAFETY: live ARKStep memory with a linear solver (an implicit table); stores a
            // scalar (negative: a setup at every stage).
            self.check(unsafe { ark::SetLSetupFrequency(m, -1) })?;
        }
        // A failure is located at the end of the last accepted step (ARKStep itself returns
        // the failed attempt's stage time with the last accepted state), kept by a post-step
        // function. Not for DIRK on SUNDIALS 6: with a post-step function set, 6 evaluates
        // f(t_n, y_n) afresh for the Hermite interpolant at every step end instead of taking
        // the last stage's (tables with c_s = 1, SDIRK-5-3-4 among them), which costs one
        // implicit evaluation per step and changes the dense output (docs/debian.md). There
        // the stage time stays: docs/robustness.md, "Where a failure is located".
        let dirk_only = tables.1 == ffi::ARKODE_ERKTableID_ARKODE_ERK_NONE;
        if cfg!(sundials7) || !dirk_only {
            self.keep_step_ends(ark::SetPostprocessStepFn)?;
        }
        Ok(())
    }
}

impl<S: OdeSystem> Solver<S> {
    /// ARKStep on the whole right-hand side: implicit DIRK (dense Newton, the analytic
    /// Jacobian when the system has one) or explicit ERK.
    pub fn arkstep(
        system: S,
        method: ArkMethod,
        settings: ArkSettings,
        t0: f64,
        y0: &[f64],
        options: &Options,
    ) -> Result<Self, SolverError> {
        let implicit = matches!(method, ArkMethod::Dirk(_));
        // The method-table row of this ArkMethod (its name and dense-output order).
        let row = if implicit { Method::ArkodeDirk } else { Method::ArkodeErk };
        check_dimension(row.name(), system.dim(), t0, y0)?;
        if !implicit {
            no_newton(row.name(), options, t0, y0)?;
        }
        let jacobian_hint: fn(&S, SolverError) -> SolverError =
            if implicit { crate::integrate::jacobian_hint::<S> } else { |_, e| e };
        let jacobian: ffi::CVLsJacFn =
            if implicit && system.has_jacobian() { Some(callbacks::jacobian::<S>) } else { None };
        let creation = Creation {
            method: row,
            jacobian_hint,
            system,
            t0,
            y0: y0.to_vec(),
            needs_linear_solver: implicit,
            jacobian,
            rhs: S::rhs,
        };
        let f: ffi::ARKRhsFn = Some(callbacks::rhs::<S>);
        let (fe, fi) = if implicit { (None, f) } else { (f, None) };
        let mut solver = Solver::build(&ARKSTEP, creation, options, |y, ctx| {
            // SAFETY: creates ARKStep memory in a live context; ARKStepCreate copies `y`.
            unsafe { ffi::ARKStepCreate(fe, fi, t0, y.raw(), ctx.raw()) }
        })?;
        let tables = match method {
            ArkMethod::Dirk(t) => (t.0, ffi::ARKODE_ERKTableID_ARKODE_ERK_NONE),
            ArkMethod::Erk(t) => (ffi::ARKODE_DIRKTableID_ARKODE_DIRK_NONE, t.0),
        };
        solver.finish_arkstep(options, settings, tables)?;
        Ok(solver)
    }
}

impl<S: ImexSystem> Solver<S> {
    /// ARKStep IMEX: f_E explicit with `explicit`, f_I implicit with `implicit` (the tables
    /// must form an ARK pair, e.g. ARK436L2SA_DIRK_6_3_4 with ARK436L2SA_ERK_6_3_4). Dense
    /// output uses ARKODE's Lagrange interpolant (solution values only), on SUNDIALS 6 and 7
    /// alike; see the comment in the body.
    #[allow(clippy::too_many_arguments)]
    pub fn arkstep_imex(
        system: S,
        implicit: DirkTable,
        explicit: ErkTable,
        settings: ArkSettings,
        t0: f64,
        y0: &[f64],
        options: &Options,
    ) -> Result<Self, SolverError> {
        let method = Method::ArkodeImex;
        check_dimension(method.name(), system.dim(), t0, y0)?;
        let jacobian: ffi::CVLsJacFn = if system.has_implicit_jacobian() {
            Some(callbacks::implicit_jacobian::<S>)
        } else {
            None
        };
        // Its dense order is that of the Lagrange interpolant (below) of ARKODE's default
        // degree 3.
        let creation = Creation {
            method,
            jacobian_hint: crate::integrate::implicit_jacobian_hint::<S>,
            system,
            t0,
            y0: y0.to_vec(),
            needs_linear_solver: true,
            jacobian,
            rhs: S::rhs,
        };
        let (fe, fi): (ffi::ARKRhsFn, ffi::ARKRhsFn) =
            (Some(callbacks::rhs_explicit::<S>), Some(callbacks::rhs_implicit::<S>));
        let mut solver = Solver::build(&ARKSTEP, creation, options, |y, ctx| {
            // SAFETY: creates ARKStep memory in a live context; ARKStepCreate copies `y`.
            unsafe { ffi::ARKStepCreate(fe, fi, t0, y.raw(), ctx.raw()) }
        })?;
        // The Lagrange interpolant, on every SUNDIALS version: the default Hermite one needs
        // f(t_n, y_n), which SUNDIALS 6 took from the last stage of an ARK pair with c_s = 1
        // (the deduced implicit stage derivative) and SUNDIALS 7 (since 6.7.0) evaluates afresh
        // for a pair whose explicit table is not stiffly accurate, which is every ARK pair. On
        // very stiff problems that fresh f_I carries the error in y_n times the stiffness
        // (~1e16) into the dense output and its derivative, and a cycle of that stiffness
        // fails on 7 ("error test failed repeatedly"). The Lagrange interpolant uses solution
        // values only, so both versions run the same algorithm (docs/debian.md).
        let m = solver.mem();
        // SAFETY: live ARKStep memory, not yet initialised (no step taken): the module may
        // still replace its interpolation module.
        solver.check(unsafe { ark::SetInterpolantType(m, ffi::ARK_INTERP_LAGRANGE as c_int) })?;
        solver.finish_arkstep(options, settings, (implicit.0, explicit.0))?;
        Ok(solver)
    }
}

/// The default IMEX pair: Kennedy & Carpenter's ARK4(3)6L\[2\]SA (L-stable implicit part).
pub fn default_imex_tables() -> (DirkTable, ErkTable) {
    (
        DirkTable(ffi::ARKODE_DIRKTableID_ARKODE_ARK436L2SA_DIRK_6_3_4),
        ErkTable(ffi::ARKODE_ERKTableID_ARKODE_ARK436L2SA_ERK_6_3_4),
    )
}
