//! One safe solver type over CVODE and ARKStep: both expose the same C interface shape, so a
//! table of their functions ([`Api`]) lets a single implementation drive either.

use super::callbacks::{self, Diagnostics, Shared, StepEnds};
use super::context::Context;
use super::dense::DenseLinearSolver;
use super::ffi;
use super::vector::SerialVector;
use crate::integrate::{
    panic_message, ErrorKind, ErrorWeights, Integrator, Options, Roots, SolverError, Stats, Step,
    StepEvent, Task, Tolerance,
};
use crate::method::Method;
use std::ffi::{c_int, c_long, c_void};
use std::ptr::NonNull;

type Mem = *mut c_void;

/// The SUNDIALS functions one solver family provides (CVODE or ARKStep).
pub(crate) struct Api {
    pub name: &'static str,
    pub free: unsafe extern "C" fn(*mut Mem),
    pub evolve: unsafe extern "C" fn(Mem, f64, ffi::N_Vector, *mut f64, c_int) -> c_int,
    pub get_dky: unsafe extern "C" fn(Mem, f64, c_int, ffi::N_Vector) -> c_int,
    pub set_user_data: unsafe extern "C" fn(Mem, *mut c_void) -> c_int,
    /// SUNDIALS 6's per-memory error handler setter (7 has one handler stack per context).
    #[cfg(not(sundials7))]
    pub set_err_handler: unsafe extern "C" fn(Mem, ffi::CVErrHandlerFn, *mut c_void) -> c_int,
    pub ss_tolerances: unsafe extern "C" fn(Mem, f64, f64) -> c_int,
    pub sv_tolerances: unsafe extern "C" fn(Mem, f64, ffi::N_Vector) -> c_int,
    /// Registers a user error-weight function (replacing SS/SV tolerances).
    pub wf_tolerances: unsafe extern "C" fn(Mem, ffi::CVEwtFn) -> c_int,
    pub set_linear_solver: unsafe extern "C" fn(Mem, ffi::SUNLinearSolver, ffi::SUNMatrix) -> c_int,
    pub set_jac_fn: unsafe extern "C" fn(Mem, ffi::CVLsJacFn) -> c_int,
    pub root_init: unsafe extern "C" fn(Mem, c_int, ffi::CVRootFn) -> c_int,
    pub set_root_direction: unsafe extern "C" fn(Mem, *mut c_int) -> c_int,
    pub get_root_info: unsafe extern "C" fn(Mem, *mut c_int) -> c_int,
    pub set_stop_time: unsafe extern "C" fn(Mem, f64) -> c_int,
    pub set_max_num_steps: unsafe extern "C" fn(Mem, c_long) -> c_int,
    pub set_init_step: unsafe extern "C" fn(Mem, f64) -> c_int,
    pub set_min_step: unsafe extern "C" fn(Mem, f64) -> c_int,
    pub set_max_step: unsafe extern "C" fn(Mem, f64) -> c_int,
    pub set_max_err_test_fails: unsafe extern "C" fn(Mem, c_int) -> c_int,
    pub set_max_nonlin_iters: unsafe extern "C" fn(Mem, c_int) -> c_int,
    pub set_max_conv_fails: unsafe extern "C" fn(Mem, c_int) -> c_int,
    pub set_nonlin_conv_coef: unsafe extern "C" fn(Mem, f64) -> c_int,
    pub set_max_hnil_warns: unsafe extern "C" fn(Mem, c_int) -> c_int,
    /// Sets the most steps between linear-solver setups and between Jacobian evaluations
    /// ([`Options::jacobian_max_age`]); needs a linear solver attached.
    pub set_jacobian_max_age: unsafe fn(Mem, i64) -> c_int,
    /// Restarts at (t0, y0) keeping the options.
    pub reinit: unsafe extern "C" fn(Mem, f64, ffi::N_Vector) -> c_int,
    /// Whether `reinit` zeroes the counters (then the solver keeps a running total).
    pub reinit_resets_counters: bool,
    /// The getters of the counters and step sizes both families have ([`read_shared_stats`]).
    pub stats: StatGetters,
    /// Reads the counters of this family alone into the result of [`read_shared_stats`].
    pub read_own_stats: unsafe fn(Mem, &mut Stats),
    /// Maps a negative return code to an error kind.
    pub classify: fn(c_int) -> ErrorKind,
    /// Why the solver stopped, for return codes whose kind and SUNDIALS message leave it out.
    pub explain: fn(c_int) -> Option<&'static str>,
    /// Whether the order of the last step bounds the dense output's derivatives (CVODE, whose
    /// `GetDky` refuses a higher k itself); otherwise the interpolant's degree does
    /// ([`Solver::max_dense_order`], checked by the wrapper: ARKODE answers zero above it).
    pub dense_order_is_last_order: bool,
}

/// An [`ErrorKind::InvalidInput`] error unless the initial state `y0` of the method `name`
/// has the system's dimension `dim`.
pub(crate) fn check_dimension(
    name: &'static str,
    dim: usize,
    t0: f64,
    y0: &[f64],
) -> Result<(), SolverError> {
    if y0.len() == dim {
        return Ok(());
    }
    Err(SolverError {
        solver: name,
        kind: ErrorKind::InvalidInput,
        t: t0,
        state: y0.to_vec(),
        flag: 0,
        message: format!("y0 has {} components; the system has {dim}", y0.len()),
    })
}

/// A SUNDIALS getter of one counter.
pub(crate) type Getter = unsafe extern "C" fn(Mem, *mut c_long) -> c_int;

/// The counter `get` reads from the solver memory `m` (a negative count reads as 0).
///
/// # Safety
/// `m` is live memory of the solver `get` belongs to.
pub(crate) unsafe fn counter(m: Mem, get: Getter) -> u64 {
    let mut v: c_long = 0;
    // SAFETY: `m` is live solver memory (caller's guarantee); the getter writes one long.
    unsafe { get(m, &mut v) };
    v.max(0) as u64
}

/// A SUNDIALS getter of one step size.
pub(crate) type StepGetter = unsafe extern "C" fn(Mem, *mut f64) -> c_int;

/// The getters of the counters and step sizes that CVODE and ARKStep both have, each family
/// its own spelling ([`read_shared_stats`]).
pub(crate) struct StatGetters {
    pub steps: Getter,
    pub lin_setups: Getter,
    pub err_test_fails: Getter,
    pub step_solve_fails: Getter,
    pub nonlin_iters: Getter,
    pub nonlin_conv_fails: Getter,
    /// Asked only with a linear solver attached.
    pub jac_evals: Getter,
    /// Asked only with a linear solver attached.
    pub lin_rhs_evals: Getter,
    /// Asked only with root functions (now or before).
    pub root_evals: Getter,
    pub last_step: StepGetter,
    pub current_step: StepGetter,
    pub initial_step: StepGetter,
}

/// Reads the counters and step sizes of `get`; the other fields stay at zero for
/// [`Api::read_own_stats`] to fill. Getters that do not apply (no root functions, no linear solver)
/// are not asked, and leave their counter at zero: ARKODE answers them through the error handler
/// ("arkode_mem = NULL illegal." for the root count), which cost an ERK run 30 % of its time when
/// the counters were read after every step, and left that message as the solver's last error.
///
/// # Safety
/// `m` is live memory of the solver the getters belong to.
unsafe fn read_shared_stats(m: Mem, attached: Attached, get: &StatGetters) -> Stats {
    let mut s = Stats::default();
    // SAFETY: `m` is live memory of the getters' solver (caller's guarantee).
    let count = |getter: Getter| unsafe { counter(m, getter) };
    s.steps = count(get.steps);
    s.lin_setups = count(get.lin_setups);
    s.err_test_fails = count(get.err_test_fails);
    s.step_solve_fails = count(get.step_solve_fails);
    s.nonlin_iters = count(get.nonlin_iters);
    s.nonlin_conv_fails = count(get.nonlin_conv_fails);
    if attached.linear_solver {
        s.jac_evals = count(get.jac_evals);
        s.rhs_evals_jacobian = count(get.lin_rhs_evals);
    }
    if attached.roots {
        s.root_evals = count(get.root_evals);
    }
    // SAFETY: as above; each getter writes one value of the pointed-to type.
    unsafe {
        (get.last_step)(m, &mut s.last_step);
        (get.current_step)(m, &mut s.current_step);
        (get.initial_step)(m, &mut s.initial_step);
    }
    s
}

/// What is attached to the solver memory, so that [`read_shared_stats`] asks only the getters
/// that apply.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Attached {
    /// A linear solver (not for ERK or Adams with functional iteration).
    pub linear_solver: bool,
    /// Root functions (now or before).
    pub roots: bool,
}

/// A SUNDIALS integrator (CVODE or ARKStep) for the system `S`, built by
/// [`Solver::cvode`](crate::sundials::Solver::cvode),
/// [`Solver::arkstep`](crate::sundials::Solver::arkstep) or
/// [`Solver::arkstep_imex`](crate::sundials::Solver::arkstep_imex).
///
/// Owns every SUNDIALS object it uses and frees them in the required order: solver memory,
/// linear solver and matrix, vectors, then the context.
pub struct Solver<S> {
    mem: NonNull<c_void>,
    api: &'static Api,
    /// The method's name ([`Method::name`] of [`Creation::method`]).
    name: &'static str,
    /// The largest k of dense output after a step ([`Method::dense_order`] of
    /// [`Creation::method`]; CVODE: further limited by the order of the last step).
    max_dense_order: u32,
    /// See [`Creation::jacobian_hint`].
    jacobian_hint: fn(&S, SolverError) -> SolverError,
    // Field order is drop order: all of these must go before `ctx`.
    linear: Option<DenseLinearSolver>,
    y: SerialVector,
    scratch: SerialVector,
    _atol: Option<SerialVector>,
    /// The user data SUNDIALS calls back with: a leaked `Box`, reclaimed in `Drop` after the
    /// solver memory is freed. Held as a raw pointer (not a `Box`) so that Rust never asserts
    /// unique access to it while SUNDIALS holds pointers into it.
    shared: NonNull<Shared<S>>,
    t: f64,
    fail_on_step_underflow: bool,
    /// The initial step of the options (0: SUNDIALS estimates it), restored by `reinit` after
    /// a `rebase` started with the step in progress.
    initial_step: f64,
    rebased: bool,
    /// See [`Creation::rhs`].
    rhs: fn(&S, f64, &[f64], &mut [f64]),
    /// Whether a step was taken since construction, the last restart or a failure located
    /// before SUNDIALS' own time (see `advance`): otherwise dense output holds only the point
    /// (t, y, f(t, y)).
    stepped: bool,
    /// Whether the last return was the end of the last internal step. After an interpolated
    /// return SUNDIALS' one-step mode returns that step's end without taking a step; the
    /// contract's `OneStep` takes one.
    at_step_end: bool,
    counters_before_reinit: Stats,
    reinits: u64,
    /// Whether root functions were ever attached (SUNDIALS keeps their counter after they are
    /// removed; before the first, ARKODE has no root memory to ask).
    had_roots: bool,
    ctx: Context,
}

/// Which right-hand side(s) a new solver memory is created with; used by the constructors.
pub(crate) struct Creation<S> {
    /// The method: its row of the method table gives the name (errors and
    /// `Integrator::name`) and the dense-output order.
    pub method: Method,
    /// Appends to an error the Jacobian's disagreement with differences at the failure point
    /// (`integrate::jacobian_hint`), or leaves it.
    pub jacobian_hint: fn(&S, SolverError) -> SolverError,
    pub system: S,
    pub t0: f64,
    pub y0: Vec<f64>,
    pub needs_linear_solver: bool,
    pub jacobian: ffi::CVLsJacFn,
    /// The whole right-hand side f(t, y), for the derivative at t0 before any step (SUNDIALS'
    /// dense output holds nothing then).
    pub rhs: fn(&S, f64, &[f64], &mut [f64]),
}

impl<S> Solver<S> {
    /// Common construction: validates input, creates the context and vectors, lets `create`
    /// make the solver memory, then attaches user data, error handler, tolerances, options and
    /// the dense linear solver.
    pub(crate) fn build(
        api: &'static Api,
        creation: Creation<S>,
        options: &Options,
        create: impl FnOnce(&SerialVector, &Context) -> Mem,
    ) -> Result<Self, SolverError> {
        let Creation { method, jacobian_hint, system, t0, y0, needs_linear_solver, jacobian, rhs } =
            creation;
        let (name, max_dense_order) = (method.name(), method.dense_order());
        let dim = y0.len();
        let invalid = |message: String| SolverError {
            solver: name,
            kind: ErrorKind::InvalidInput,
            t: t0,
            state: y0.clone(),
            flag: 0,
            message,
        };
        if dim == 0 {
            return Err(invalid("the system has no components".into()));
        }
        if !t0.is_finite() {
            return Err(invalid(format!("t0 = {t0} must be finite")));
        }
        if let Some(i) = y0.iter().position(|v| !v.is_finite()) {
            return Err(invalid(format!("y0[{i}] = {} must be finite", y0[i])));
        }
        options.validate(dim).map_err(|e| invalid(e.to_string()))?;
        let resource = |what: &str| invalid(format!("could not allocate the SUNDIALS {what}"));

        let ctx = Context::new().ok_or_else(|| resource("context"))?;
        let y = SerialVector::from_slice(&y0, &ctx).ok_or_else(|| resource("state vector"))?;
        let scratch = SerialVector::from_slice(&y0, &ctx).ok_or_else(|| resource("vector"))?;
        let atol = match &options.atol {
            Tolerance::PerComponent(v) => Some(
                SerialVector::from_slice(v, &ctx).ok_or_else(|| resource("tolerance vector"))?,
            ),
            Tolerance::Scalar(_) => None,
        };
        let mem = NonNull::new(create(&y, &ctx)).ok_or_else(|| resource("solver memory"))?;
        let mut diag = Diagnostics::default();
        diag.stop_on_underflow = options.fail_on_step_underflow;
        #[cfg(sundials7)]
        {
            let log = ctx
                .warning_log()
                .map_err(|e| invalid(format!("could not open SUNDIALS' warning log: {e}")))?;
            diag.warning_log = Some(log);
        }
        let shared = Box::new(Shared {
            system,
            dim,
            roots: None,
            root_count: 0,
            diag,
            step_ends: None,
            weights: None,
            sensitivity: None,
        });
        let shared = NonNull::from(Box::leak(shared));
        let mut solver = Self {
            mem,
            api,
            name,
            max_dense_order,
            jacobian_hint,
            linear: None,
            y,
            scratch,
            _atol: None,
            shared,
            t: t0,
            fail_on_step_underflow: options.fail_on_step_underflow,
            initial_step: options.initial_step.unwrap_or(0.0),
            rebased: false,
            rhs,
            stepped: false,
            at_step_end: true,
            counters_before_reinit: Stats::default(),
            reinits: 0,
            had_roots: false,
            ctx,
        };
        let m = solver.mem.as_ptr();
        let user_data = solver.shared.as_ptr() as *mut c_void;
        // SAFETY: `shared` points to a live, leaked Box; taking a field's address creates no
        // reference.
        let diag = unsafe { &raw mut (*solver.shared.as_ptr()).diag } as *mut c_void;
        // SAFETY: `m` is live solver memory; `user_data` and `diag` point into the boxed
        // `Shared`, which lives (at a fixed address) as long as the solver memory.
        #[cfg(not(sundials7))]
        solver.check(unsafe { (api.set_err_handler)(m, Some(callbacks::error_handler), diag) })?;
        #[cfg(sundials7)]
        {
            let flag = solver.ctx.capture_errors(diag as *mut Diagnostics);
            solver.check(flag)?;
        }
        // SAFETY: `m` is live; `user_data` points into the leaked `Shared`, alive until Drop, after the memory is freed.
        solver.check(unsafe { (api.set_user_data)(m, user_data) })?;
        // Every "t + h = t" warning is issued and counted (SUNDIALS stops issuing them after
        // 10 by default).
        // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
        solver.check(unsafe { (api.set_max_hnil_warns)(m, c_int::MAX) })?;
        match &atol {
            // SAFETY: `m` is live; the tolerance vector is kept alive in `_atol` below.
            Some(v) => solver.check(unsafe { (api.sv_tolerances)(m, options.rtol, v.raw()) })?,
            None => {
                let Tolerance::Scalar(a) = options.atol else { unreachable!("matched above") };
                // SAFETY: `m` is live; scalar tolerances are copied.
                solver.check(unsafe { (api.ss_tolerances)(m, options.rtol, a) })?
            }
        };
        solver._atol = atol;
        if options.error_scales.is_some() {
            let weights = ErrorWeights::new(options, dim);
            // SAFETY: `shared` is the live leaked Box; no SUNDIALS call is running, so no
            // other reference to it exists.
            unsafe { (*solver.shared.as_ptr()).weights = Some(weights) };
            // SAFETY: `m` is live; `error_weights::<S>` reads the `Shared<S>` registered as
            // user data above, which outlives the solver memory.
            solver.check(unsafe { (api.wf_tolerances)(m, Some(callbacks::error_weights::<S>)) })?;
        }
        solver.apply_options(options)?;
        if needs_linear_solver {
            let linear = DenseLinearSolver::new(&solver.y, dim, &solver.ctx)
                .ok_or_else(|| resource("dense linear solver"))?;
            // SAFETY: `m` is live; the matrix and linear solver are owned by `solver.linear`,
            // which is dropped only after the solver memory is freed.
            solver
                .check(unsafe { (api.set_linear_solver)(m, linear.solver(), linear.matrix()) })?;
            solver.linear = Some(linear);
            if jacobian.is_some() {
                // SAFETY: `m` is live and has a linear solver attached just above; the trampoline matches CVLsJacFn/ARKLsJacFn.
                solver.check(unsafe { (api.set_jac_fn)(m, jacobian) })?;
            }
        }
        if let Some(age) = options.jacobian_max_age {
            if !needs_linear_solver {
                return Err(invalid(format!("jacobian_max_age = {age}: an explicit method has no Jacobian; leave it unset (None)")));
            }
            // SAFETY: `m` is live and has its linear solver attached above; stores two scalars.
            solver.check(unsafe { (api.set_jacobian_max_age)(m, age) })?;
        }
        Ok(solver)
    }

    fn apply_options(&mut self, o: &Options) -> Result<(), SolverError> {
        let m = self.mem.as_ptr();
        let api = self.api;
        // SAFETY (all calls below): `m` is live solver memory and each setter only stores a
        // scalar option.
        let max_steps = o.max_steps.unwrap_or(crate::integrate::DEFAULT_MAX_STEPS);
        // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
        self.check(unsafe { (api.set_max_num_steps)(m, max_steps as c_long) })?;
        if let Some(v) = o.initial_step {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_init_step)(m, v) })?;
        }
        if let Some(v) = o.min_step {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_min_step)(m, v) })?;
        }
        if let Some(v) = o.max_step {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_max_step)(m, v) })?;
        }
        if let Some(v) = o.stop_time {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_stop_time)(m, v) })?;
        }
        if let Some(v) = o.max_err_test_fails {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_max_err_test_fails)(m, v) })?;
        }
        if let Some(v) = o.max_nonlin_iters {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_max_nonlin_iters)(m, v) })?;
        }
        if let Some(v) = o.max_conv_fails {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_max_conv_fails)(m, v) })?;
        }
        if let Some(v) = o.nonlin_conv_coef {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (api.set_nonlin_conv_coef)(m, v) })?;
        }
        Ok(())
    }

    /// The callback data, shared. Called only between SUNDIALS calls (or from getters that do
    /// not call back), so no callback holds a reference at the same time.
    pub(crate) fn shared(&self) -> &Shared<S> {
        // SAFETY: the pointer comes from a leaked Box freed only in Drop; no `&mut` to it is
        // alive while `&self` is borrowed (callbacks run only inside `&mut self` methods).
        unsafe { self.shared.as_ref() }
    }

    /// The callback data, exclusively (between SUNDIALS calls).
    pub(crate) fn shared_mut(&mut self) -> &mut Shared<S> {
        // SAFETY: as in `shared`; `&mut self` excludes every other access, and no SUNDIALS
        // call (hence no callback) is in progress.
        unsafe { self.shared.as_mut() }
    }

    /// Raw solver memory, for solver-specific setters in the constructors.
    pub(crate) fn mem(&self) -> Mem {
        self.mem.as_ptr()
    }

    /// The context every SUNDIALS object of this solver is created in.
    pub(crate) fn context(&self) -> &Context {
        &self.ctx
    }

    /// Turns a SUNDIALS return code into `Ok` or a typed error at the current time and state.
    pub(crate) fn check(&mut self, flag: c_int) -> Result<c_int, SolverError> {
        if let Some(panic) = self.shared_mut().diag.panic.take() {
            return Err(self.error(ErrorKind::CallbackPanic, flag, panic));
        }
        if flag >= 0 {
            return Ok(flag);
        }
        let kind = (self.api.classify)(flag);
        let mut message = self.shared_mut().diag.last_error.take().unwrap_or_default();
        if let Some(why) = self.shared_mut().diag.root_failure.take() {
            message.push_str(&format!(" [{why}]"));
        }
        Err(self.error(kind, flag, message))
    }

    /// A typed error at the current time and state.
    pub(crate) fn error(&self, kind: ErrorKind, flag: c_int, message: String) -> SolverError {
        SolverError {
            solver: self.name,
            kind,
            t: self.t,
            state: self.state().to_vec(),
            flag,
            message,
        }
    }

    /// Integrates towards `tout` (see [`Task`]) and returns where and why it stopped. The
    /// state at the returned time is [`Solver::state`].
    ///
    /// Errors: every SUNDIALS failure, a panic in a callback, and — when
    /// `fail_on_step_underflow` is set — a "t + h = t" step underflow during this call.
    pub fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
        if !tout.is_finite() {
            return Err(self.error(
                ErrorKind::InvalidInput,
                0,
                format!("tout = {tout} must be finite"),
            ));
        }
        let task_code = match task {
            Task::Normal => 1,
            Task::OneStep => 2,
        };
        self.shared_mut().diag.begin_call();
        let t_before = self.t;
        let steps_before = (task == Task::OneStep && !self.at_step_end).then(|| self.raw_steps());
        let mut t = self.t;
        // SAFETY: live solver memory; `y` is a vector of the system's length owned by us;
        // callbacks reach `shared`, which outlives the call.
        let mut flag =
            unsafe { (self.api.evolve)(self.mem.as_ptr(), tout, self.y.raw(), &mut t, task_code) };
        if flag == 1 && t == t_before && self.stepped {
            // The stop time without progress: the last call's output time was the stop time,
            // which SUNDIALS returns there as `Reached` and now, once more, as the stop time
            // (disabling it). The contract disables it with the first return: go on.
            // SAFETY: as above.
            flag = unsafe {
                (self.api.evolve)(self.mem.as_ptr(), tout, self.y.raw(), &mut t, task_code)
            };
        }
        // The counter is read only when the check applies: after every step it cost an ERK cycle
        // 4 % of its instructions.
        if flag == 0 && steps_before.is_some_and(|before| before == self.raw_steps()) {
            // One-step mode after an interpolated return gave back the last step's end
            // without a step: take the step the contract promises.
            // SAFETY: as above.
            flag = unsafe {
                (self.api.evolve)(self.mem.as_ptr(), tout, self.y.raw(), &mut t, task_code)
            };
        }
        // A failure is located at the last accepted point, whose state SUNDIALS returned
        // (ARKStep returns the failed attempt's stage time with it).
        let located = if flag < 0 { self.last_accepted_end().filter(|tn| *tn != t) } else { None };
        t = located.unwrap_or(t);
        self.t = t;
        self.stepped |= t != t_before;
        let mut reset_flag = 0;
        if located.is_some() {
            // ARKStep's own time and interpolant still describe the failed attempt, and a later
            // call with an output time inside it would be interpolated over it: restart at the
            // point (options and counters kept). Dense output holds the point until a step.
            // SAFETY: live solver memory; SUNDIALS copies `y`, the state it just returned.
            reset_flag = unsafe { (self.api.reinit)(self.mem.as_ptr(), t, self.y.raw()) };
            let start = StepEnds::new(t, self.raw_steps());
            self.shared_mut().step_ends = Some(start);
            self.stepped = false;
            self.at_step_end = true;
        }
        self.shared_mut().diag.poll_warnings();
        let (nonfinite, underflows) = self.shared_mut().diag.since_call();
        if self.shared().diag.stopped_for_underflow {
            // The right-hand side refused the first step after a "t + h = t" warning, so
            // SUNDIALS' own return code (a right-hand-side failure) is only the consequence.
            self.shared_mut().diag.last_error = None;
            let mut e = self.underflow_error(underflows, flag);
            if nonfinite > 0 {
                // Steps shrank to nothing because the right-hand side kept failing: that is
                // the root cause.
                e.kind = ErrorKind::RhsFailure;
                e.message.push_str(&format!(
                    " [{nonfinite} right-hand-side calls returned non-finite values]"
                ));
            }
            return Err(e);
        }
        let flag = self.check(flag).map_err(|mut e| {
            // Name the root cause: SUNDIALS reports its consequence (e.g. "too much work"
            // when t + h = t stalls time, or repeated failures after NaN values).
            if e.kind != ErrorKind::CallbackPanic && nonfinite > 0 {
                e.kind = ErrorKind::RhsFailure;
            } else if e.kind != ErrorKind::CallbackPanic && underflows > 0 {
                e.kind = ErrorKind::StepUnderflow;
            }
            if nonfinite > 0 {
                e.message.push_str(&format!(" [{nonfinite} right-hand-side calls returned non-finite values]"));
            }
            if let Some(why) = (self.api.explain)(e.flag) {
                e.message.push_str(&format!(" [{why}]"));
            }
            if reset_flag < 0 {
                e.message.push_str(&format!(" [the restart at the failure point failed too (flag {reset_flag}): do not go on]"));
            }
            if underflows > 0 {
                e.message.push_str(&format!(" [{underflows} steps below the spacing of t (t + h = t)]"));
            }
            (self.jacobian_hint)(&self.shared().system, e)
        })?;
        if self.fail_on_step_underflow && underflows > 0 {
            return Err(self.underflow_error(underflows, flag));
        }
        let event = match flag {
            // The output time is the stop time: SUNDIALS 7 returns it as the stop time (and
            // disables it), 6 as the output time; the contract says the output time comes
            // first.
            1 if task == Task::Normal && t == tout => StepEvent::Reached,
            1 => StepEvent::StopTime,
            2 => {
                let mut info = vec![0 as c_int; self.shared().root_count];
                // SAFETY: `info` has one slot per root function declared to SUNDIALS.
                let f = unsafe { (self.api.get_root_info)(self.mem.as_ptr(), info.as_mut_ptr()) };
                self.check(f)?;
                StepEvent::Root(info)
            }
            _ => StepEvent::Reached,
        };
        self.at_step_end = task == Task::OneStep && !matches!(event, StepEvent::Root(_));
        Ok(Step { t, event })
    }

    /// Where the last accepted step ended, when the post-step function keeps it (ARKStep).
    fn last_accepted_end(&self) -> Option<f64> {
        let ends = self.shared().step_ends?;
        ends.last_accepted(self.raw_steps())
    }

    /// The solver's own step counter (since construction; a restart may reset it).
    fn raw_steps(&self) -> u64 {
        // SAFETY: live solver memory of the getter's family.
        unsafe { counter(self.mem.as_ptr(), self.api.stats.steps) }
    }

    /// Registers the post-step function that keeps the ends of the accepted steps, through
    /// which a failure is located ([`StepEnds`]); `set` is ARKODE's setter. Call after the user
    /// data is set (ARKODE hands the post-step function the user data current at this call).
    pub(crate) fn keep_step_ends(
        &mut self,
        set: unsafe extern "C" fn(Mem, ffi::ARKPostProcessFn) -> c_int,
    ) -> Result<(), SolverError> {
        let start = StepEnds::new(self.t, self.raw_steps());
        self.shared_mut().step_ends = Some(start);
        // SAFETY: `mem` is live ARKODE memory whose user data is the boxed `Shared<S>` the
        // trampoline casts to; it stays alive until after the memory is freed.
        self.check(unsafe { set(self.mem.as_ptr(), Some(callbacks::step_end::<S>)) })?;
        Ok(())
    }

    /// The typed error for `fail_on_step_underflow`, quoting SUNDIALS' last "t + h = t" warning.
    fn underflow_error(&self, underflows: u64, flag: c_int) -> SolverError {
        let warning = self.shared().diag.warnings.iter().rev().find(|w| w.contains("t + h = t"));
        let message =
            format!("{underflows} step(s) below the spacing of t: {}", warning.map_or("", |w| w));
        self.error(ErrorKind::StepUnderflow, flag, message)
    }

    /// The state at the time of the last return ([`Solver::t`]).
    pub fn state(&self) -> &[f64] {
        self.y.as_slice()
    }

    /// Time of the last return.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// The k-th derivative of the interpolated solution at `t`, which must lie within the last
    /// internal step (dense output).
    ///
    /// Before any step (since construction, a restart, or an ARKStep failure located before
    /// the failed attempt) only the current t with k ≤ 1 is held: the state and f(t, y). A
    /// non-finite `t` is invalid input.
    pub fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError> {
        if !t.is_finite() {
            return Err(self.error(
                ErrorKind::InvalidInput,
                0,
                format!("dense output needs a finite t, got {t}"),
            ));
        }
        if !self.stepped {
            if t != self.t || k > 1 {
                let message = format!("no step taken yet (or since a failure): dense output only at t = {:e} with k ≤ 1, got t = {t:e}, k = {k}", self.t);
                return Err(self.error(ErrorKind::InvalidInput, 0, message));
            }
            let mut value = self.y.as_slice().to_vec();
            if k == 1 {
                let mut f = vec![0.0; value.len()];
                // Outside SUNDIALS, but a panic is an error here too, as in every integrator.
                let call = || (self.rhs)(&self.shared().system, self.t, &value, &mut f);
                if let Err(payload) = std::panic::catch_unwind(std::panic::AssertUnwindSafe(call)) {
                    return Err(self.error(ErrorKind::CallbackPanic, 0, panic_message(&*payload)));
                }
                if let Some(i) = f.iter().position(|v| !v.is_finite()) {
                    let message = format!(
                        "the right-hand side is not finite at t0 (component {i}: {})",
                        f[i]
                    );
                    return Err(self.error(ErrorKind::RhsFailure, 0, message));
                }
                value = f;
            }
            self.scratch.as_mut_slice().copy_from_slice(&value);
            return Ok(self.scratch.as_slice());
        }
        if !self.api.dense_order_is_last_order && k > self.max_dense_order {
            let message = format!(
                "{} gives dense output up to k = {}, got k = {k}",
                self.name, self.max_dense_order
            );
            return Err(self.error(ErrorKind::InvalidInput, 0, message));
        }
        // SAFETY: live solver memory; `scratch` has the system's length.
        let f = unsafe { (self.api.get_dky)(self.mem.as_ptr(), t, k as c_int, self.scratch.raw()) };
        self.check(f)?;
        Ok(self.scratch.as_slice())
    }

    /// Installs new root functions, replacing any previous ones; `None` disables root finding.
    pub fn set_roots(&mut self, roots: Option<Roots>) -> Result<(), SolverError> {
        let m = self.mem.as_ptr();
        let Some(roots) = roots else {
            // SAFETY: live memory; zero root functions disables root finding.
            self.check(unsafe { (self.api.root_init)(m, 0, None) })?;
            self.shared_mut().roots = None;
            self.shared_mut().root_count = 0;
            return Ok(());
        };
        let bad_directions = !roots.directions.is_empty()
            && (roots.directions.len() != roots.count
                || roots.directions.iter().any(|d| d.abs() > 1));
        if roots.count == 0 || bad_directions {
            let message = format!(
                "roots: count = {} must be ≥ 1 and directions {:?} empty or one of -1/0/+1 per root",
                roots.count, roots.directions
            );
            return Err(self.error(ErrorKind::InvalidInput, 0, message));
        }
        let Ok(count) = c_int::try_from(roots.count) else {
            let message = format!("roots: count = {} exceeds what SUNDIALS can take", roots.count);
            return Err(self.error(ErrorKind::InvalidInput, 0, message));
        };
        // SAFETY: live memory; SUNDIALS allocates `count` slots and calls the trampoline only
        // during later `advance` calls, after `root_count` below is set to the same count.
        let trampoline: ffi::CVRootFn = Some(callbacks::roots::<S>);
        // SAFETY: `m` is live; SUNDIALS allocates `count` slots and calls the trampoline only in later `advance` calls, after `root_count` is set to `count` below.
        self.check(unsafe { (self.api.root_init)(m, count, trampoline) })?;
        self.shared_mut().roots = Some(roots.function);
        self.shared_mut().root_count = roots.count;
        self.had_roots = true;
        if !roots.directions.is_empty() {
            let mut directions: Vec<c_int> = roots.directions.clone();
            // SAFETY: `directions` holds one entry per root function; SUNDIALS copies it.
            self.check(unsafe { (self.api.set_root_direction)(m, directions.as_mut_ptr()) })?;
        }
        Ok(())
    }

    /// Sets (or moves) the stop time past which the solver will not step (see
    /// [`Integrator::set_stop_time`]).
    pub fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
        if !t_stop.is_finite() {
            return Err(self.error(
                ErrorKind::InvalidInput,
                0,
                format!("stop time {t_stop} must be finite"),
            ));
        }
        // SAFETY: live solver memory; stores a scalar.
        self.check(unsafe { (self.api.set_stop_time)(self.mem.as_ptr(), t_stop) })?;
        Ok(())
    }

    /// Sets the largest step from the next step on (`None`: no limit; see
    /// [`Integrator::set_max_step`]); restarts at the last returned point if the current step
    /// size is above the new limit.
    pub fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
        if max_step.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
            let message =
                format!("max step {max_step:?} must be finite and positive (or None: no limit)");
            return Err(self.error(ErrorKind::InvalidInput, 0, message));
        }
        // SAFETY: live solver memory; stores a scalar (0 means no limit in CVODE and ARKODE).
        self.check(unsafe { (self.api.set_max_step)(self.mem.as_ptr(), max_step.unwrap_or(0.0)) })?;
        // CVODE and ARKODE apply the limit only when they enlarge the step: a step size
        // already above it would be kept. Restart there, with the limit as the first step.
        if let Some(h) = max_step.filter(|h| self.raw_stats().current_step.abs() > *h) {
            let (t, y) = (self.t, self.state().to_vec());
            self.restart(t, &y, Some(h))?;
        }
        Ok(())
    }

    /// Restarts the integration at (t0, y0), keeping options, tolerances, root functions and
    /// the running statistics.
    pub fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        if y0.len() != self.shared().dim || !t0.is_finite() || y0.iter().any(|v| !v.is_finite()) {
            let message = format!(
                "reinit needs finite t0 and {} finite components, got t0 = {t0}, y0 = {}",
                self.shared().dim,
                crate::integrate::brief_state(y0)
            );
            return Err(self.error(ErrorKind::InvalidInput, 0, message));
        }
        let before =
            if self.api.reinit_resets_counters { self.raw_stats() } else { Stats::default() };
        self.y.as_mut_slice().copy_from_slice(y0);
        // SAFETY: live memory; SUNDIALS copies `y` into its own history arrays.
        let flag = unsafe { (self.api.reinit)(self.mem.as_ptr(), t0, self.y.raw()) };
        self.check(flag)?;
        if self.api.reinit_resets_counters {
            self.counters_before_reinit.accumulate(&before);
        }
        if self.shared().step_ends.is_some() {
            let start = StepEnds::new(t0, self.raw_steps());
            self.shared_mut().step_ends = Some(start);
        }
        self.t = t0;
        self.stepped = false;
        self.at_step_end = true;
        self.reinits += 1;
        if self.rebased {
            self.rebased = false;
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (self.api.set_init_step)(self.mem.as_ptr(), self.initial_step) })?;
        }
        Ok(())
    }

    /// Moves the time origin to the last returned point (see [`Integrator::rebase`]): SUNDIALS
    /// has no time shift, so the solver restarts at (0, state) (CVODE's BDF at order 1), with
    /// `first_step` as its first step when given, else with its own estimate.
    pub fn rebase(&mut self, first_step: Option<f64>) -> Result<(), SolverError> {
        let y = self.state().to_vec();
        self.restart(0.0, &y, first_step)
    }

    /// [`Solver::reinit`] at (t0, y0), with `first_step` as the first step when given.
    fn restart(&mut self, t0: f64, y0: &[f64], first_step: Option<f64>) -> Result<(), SolverError> {
        self.reinit(t0, y0)?;
        if let Some(h) = first_step.filter(|h| h.is_finite() && *h > 0.0) {
            // SAFETY: `m` is live solver memory; the setter only stores a scalar option.
            self.check(unsafe { (self.api.set_init_step)(self.mem.as_ptr(), h) })?;
            self.rebased = true;
        }
        Ok(())
    }

    fn raw_stats(&self) -> Stats {
        let attached = Attached { linear_solver: self.linear.is_some(), roots: self.had_roots };
        let m = self.mem.as_ptr();
        // SAFETY: live solver memory of the API's family; the readers only call its getters.
        unsafe {
            let mut stats = read_shared_stats(m, attached, &self.api.stats);
            (self.api.read_own_stats)(m, &mut stats);
            stats
        }
    }

    /// Statistics over the solver's whole life, restarts included.
    pub fn stats(&self) -> Stats {
        let mut stats = self.counters_before_reinit;
        stats.accumulate(&self.raw_stats());
        stats.step_underflow_warnings = self.shared().diag.step_underflows;
        stats.nonfinite_rhs = self.shared().diag.nonfinite_rhs;
        stats.reinits = self.reinits;
        stats
    }

    /// Warnings SUNDIALS issued (the first 64), e.g. "t + h = t".
    pub fn warnings(&self) -> &[String] {
        &self.shared().diag.warnings
    }

    /// The system being integrated.
    pub fn system(&self) -> &S {
        &self.shared().system
    }

    /// The method's name ("cvode-bdf", "cvode-adams", "arkode-dirk", "arkode-erk" or
    /// "arkode-imex").
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// The largest k that [`Solver::dense`] accepts now (see
    /// [`Integrator::max_dense_order`]).
    pub fn max_dense_order(&self) -> u32 {
        if !self.stepped {
            return 1;
        }
        if self.api.dense_order_is_last_order {
            (self.raw_stats().last_order.max(1) as u32).min(self.max_dense_order)
        } else {
            self.max_dense_order
        }
    }
}

impl<S> Integrator for Solver<S> {
    fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
        Solver::advance(self, tout, task)
    }
    fn state(&self) -> &[f64] {
        Solver::state(self)
    }
    fn t(&self) -> f64 {
        Solver::t(self)
    }
    fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError> {
        Solver::dense(self, t, k)
    }
    fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        Solver::reinit(self, t0, y0)
    }
    fn reinit_with_step(
        &mut self,
        t0: f64,
        y0: &[f64],
        first_step: f64,
    ) -> Result<(), SolverError> {
        Solver::restart(self, t0, y0, Some(first_step))
    }
    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
        Solver::set_stop_time(self, t_stop)
    }
    fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
        Solver::set_max_step(self, max_step)
    }
    fn rebase(&mut self, first_step: Option<f64>) -> Result<(), SolverError> {
        Solver::rebase(self, first_step)
    }
    fn stats(&self) -> Stats {
        Solver::stats(self)
    }
    fn name(&self) -> &'static str {
        Solver::name(self)
    }
    fn max_dense_order(&self) -> u32 {
        Solver::max_dense_order(self)
    }
    fn warnings(&self) -> &[String] {
        Solver::warnings(self)
    }
}

impl<S> Drop for Solver<S> {
    fn drop(&mut self) {
        let mut mem = self.mem.as_ptr();
        // SAFETY: frees the solver memory exactly once, before the linear solver, vectors and
        // context (dropped afterwards in field order); then no callback can run, and the leaked
        // user data is reclaimed exactly once.
        unsafe {
            (self.api.free)(&mut mem);
            drop(Box::from_raw(self.shared.as_ptr()));
        }
    }
}

impl<S> std::fmt::Debug for Solver<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Solver").field("solver", &self.api.name).field("t", &self.t).finish()
    }
}
