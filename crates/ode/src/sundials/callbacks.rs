//! The `extern "C"` trampolines SUNDIALS calls, and the per-solver data they reach.
//!
//! Every trampoline catches panics (a panic must never unwind into C): the payload is stored
//! and −1 (unrecoverable) is returned; the solver turns it into
//! [`ErrorKind::CallbackPanic`](crate::integrate::ErrorKind) once SUNDIALS has returned.
//! Non-finite right-hand-side or Jacobian values are reported as recoverable (+1).

use super::ffi;
use super::vector::{slice, slice_mut};
use crate::integrate::{
    panic_message, ErrorWeights, ImexSystem, JacobianMatrix, OdeSystem, ParametricSystem,
    RootFunction,
};
use std::ffi::{c_char, c_int, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// What SUNDIALS and the callbacks reported, outside the return codes.
#[derive(Debug, Default)]
pub(crate) struct Diagnostics {
    /// Last error message from SUNDIALS' error handler (function, message).
    pub last_error: Option<String>,
    /// Warnings since the solver was created (at most [`MAX_KEPT_WARNINGS`] are kept).
    pub warnings: Vec<String>,
    /// "t + h = t" warnings since the solver was created.
    pub step_underflows: u64,
    /// Values of (`nonfinite_rhs`, `step_underflows`) when the current `advance` call started.
    at_call: (u64, u64),
    /// Message of a panic caught in a callback, not yet reported.
    pub panic: Option<String>,
    /// RHS calls that produced non-finite values.
    pub nonfinite_rhs: u64,
    /// Why the root function failed, if it did.
    pub root_failure: Option<String>,
    /// Stop the integration at the first "t + h = t" (`fail_on_step_underflow`): the next
    /// right-hand-side call after the warning fails unrecoverably, so SUNDIALS returns at once.
    pub stop_on_underflow: bool,
    /// Set when a right-hand-side call refused to continue because of a step underflow.
    pub stopped_for_underflow: bool,
    /// Time of the previous right-hand-side call (SUNDIALS 7: when to read the warning log).
    #[cfg(sundials7)]
    last_rhs_t: Option<f64>,
    /// SUNDIALS 7's warning stream (the logger's), read after each call and, with
    /// `stop_on_underflow`, in every right-hand-side call.
    #[cfg(sundials7)]
    pub warning_log: Option<super::context::WarningLog>,
}

const MAX_KEPT_WARNINGS: usize = 64;

impl Diagnostics {
    /// Marks the start of a call into SUNDIALS.
    pub fn begin_call(&mut self) {
        self.last_error = None;
        self.stopped_for_underflow = false;
        self.at_call = (self.nonfinite_rhs, self.step_underflows);
    }

    /// Records one message from SUNDIALS: an error (negative code) or a warning, counting
    /// "t + h = t" step underflows.
    fn record(&mut self, message: String, is_error: bool) {
        if message.contains("t + h = t") {
            self.step_underflows += 1;
        }
        if is_error {
            self.last_error = Some(message);
        } else if self.warnings.len() < MAX_KEPT_WARNINGS {
            self.warnings.push(message);
        }
    }

    /// Brings the warning counters up to date. SUNDIALS 6 reports warnings through the error
    /// handler as they happen (nothing to do); SUNDIALS 7 writes them to its logger, read here.
    pub fn poll_warnings(&mut self) {
        #[cfg(sundials7)]
        if let Some(log) = self.warning_log.as_mut() {
            let text = log.take_new();
            for line in text.lines().filter(|l| !l.is_empty()) {
                self.record(line.to_string(), false);
            }
        }
    }

    /// Whether the right-hand side must refuse to continue: `stop_on_underflow` is set and a
    /// step underflow happened during the current call.
    #[cfg_attr(not(sundials7), allow(unused_variables))]
    fn must_stop_for_underflow(&mut self, t: f64) -> bool {
        if !self.stop_on_underflow {
            return false;
        }
        // On 7 a look at the warning log costs a system call, too much for every call. A step
        // below the spacing of t evaluates the right-hand side at the time of the previous
        // evaluation (t + c·h = t), so look then: at the latest the second evaluation of the
        // step that makes no progress. (Every warning is still counted after the call.)
        #[cfg(sundials7)]
        if self.last_rhs_t.replace(t) == Some(t) {
            self.poll_warnings();
        }
        if self.step_underflows > self.at_call.1 {
            self.stopped_for_underflow = true;
        }
        self.stopped_for_underflow
    }

    /// (non-finite RHS results, step underflows) since [`Diagnostics::begin_call`].
    pub fn since_call(&self) -> (u64, u64) {
        (self.nonfinite_rhs - self.at_call.0, self.step_underflows - self.at_call.1)
    }

    /// Runs a user callback, catching a panic. Returns false if it panicked (or an earlier
    /// panic is pending, in which case `f` is not run).
    fn guarded(&mut self, f: impl FnOnce()) -> bool {
        if self.panic.is_some() {
            return false;
        }
        match catch_unwind(AssertUnwindSafe(f)) {
            Ok(()) => true,
            Err(payload) => {
                self.panic = Some(panic_message(&*payload));
                false
            }
        }
    }
}

/// The data behind SUNDIALS' `user_data` pointer: the system, the current root functions, the
/// diagnostics and (ARKStep) the ends of the last accepted steps. Boxed by the solver so its
/// address never changes.
pub(crate) struct Shared<S> {
    pub system: S,
    pub dim: usize,
    pub roots: Option<RootFunction>,
    pub root_count: usize,
    pub diag: Diagnostics,
    /// Kept by [`step_end`] when it is registered (ARKStep); `None` otherwise (CVODE).
    pub step_ends: Option<StepEnds>,
    /// The tolerances behind [`error_weights`], when it is registered.
    pub weights: Option<ErrorWeights>,
    /// ∂f/∂y and ∂f/∂p for [`sensitivity_rhs`], when it is registered (CVODES).
    pub sensitivity: Option<SensitivityScratch>,
}

/// ∂f/∂y and ∂f/∂p at the (t, y) of the last sensitivity right-hand-side call. CVODES asks for
/// s_j' one parameter at a time, each time at the same (t, y): both matrices are evaluated
/// once per point, not once per parameter.
#[derive(Debug)]
pub(crate) struct SensitivityScratch {
    /// Number of parameters m.
    params: usize,
    /// Whether the matrices belong to (`t`, `y`) (not before the first evaluation, nor after a
    /// failed one).
    valid: bool,
    t: f64,
    y: Vec<f64>,
    /// ∂f/∂y, n × n, column-major.
    jacobian: Vec<f64>,
    /// ∂f/∂p, n × m, column-major.
    param_jacobian: Vec<f64>,
    /// Sensitivity right-hand sides that came out non-finite (reported as recoverable).
    pub nonfinite: u64,
    /// Whether the system forms the sensitivity right-hand side itself
    /// ([`ParametricSystem::sensitivity_rhs`]); the matrices are unused then.
    own_rhs: bool,
}

impl SensitivityScratch {
    /// Room for a system of dimension `n` with `params` parameters; `own_rhs`: the system
    /// forms the sensitivity right-hand side itself.
    pub fn new(n: usize, params: usize, own_rhs: bool) -> Self {
        // No matrices when the system forms the right-hand side itself.
        let n = if own_rhs { 0 } else { n };
        Self {
            params,
            valid: false,
            t: 0.0,
            y: vec![0.0; n],
            jacobian: vec![0.0; n * n],
            param_jacobian: vec![0.0; n * params],
            nonfinite: 0,
            own_rhs,
        }
    }

    /// The return code for a sensitivity right-hand side `sdot`: 0, or +1 (recoverable) if a
    /// value is not finite.
    fn finite(&mut self, sdot: &[f64]) -> c_int {
        if sdot.iter().all(|v| v.is_finite()) {
            0
        } else {
            self.nonfinite += 1;
            1
        }
    }

    /// Forgets the matrices (the system changed).
    pub fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Whether the matrices were evaluated at exactly (t, y).
    fn holds(&self, t: f64, y: &[f64]) -> bool {
        self.valid && self.t == t && self.y == y
    }
}

/// ewt_i = 1/tolerance_i with the tolerances of [`ErrorWeights::scale`]. False if a weight is
/// not finite and positive (a zero tolerance for a zero component), which SUNDIALS must be
/// told.
fn fill_weights(weights: &ErrorWeights, y: &[f64], ewt: &mut [f64]) -> bool {
    for (i, w) in ewt.iter_mut().enumerate() {
        let tolerance = weights.scale(i, y[i].abs());
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return false;
        }
        *w = 1.0 / tolerance;
    }
    true
}

/// The error-weight function (CVEwtFn / ARKEwtFn) for [`crate::integrate::Options::error_scales`].
pub(crate) unsafe extern "C" fn error_weights<S>(
    y: ffi::N_Vector,
    ewt: ffi::N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: `data` is the `Shared<S>` registered as user data, alive for the solver's life;
    // no other reference to it is alive during a SUNDIALS call.
    let shared = unsafe { &*(data as *const Shared<S>) };
    let Some(weights) = shared.weights.as_ref() else { return -1 };
    // SAFETY: `y` and `ewt` are distinct serial vectors of length `dim`, valid for this call.
    let (y, ewt) = unsafe { (slice(y, shared.dim), slice_mut(ewt, shared.dim)) };
    if fill_weights(weights, y, ewt) {
        0
    } else {
        -1
    }
}

/// The ends of the last two steps ARKODE's post-step function saw. On a failure ARKStep returns
/// the last accepted state with the time of the failed attempt's current stage, so the solver
/// takes the time from here: the end of the last accepted step, where that state belongs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepEnds {
    /// Post-step calls since the last (re)start.
    calls: u64,
    /// ARKODE's step count at the last (re)start.
    steps_at_start: u64,
    /// The ends of the steps of the last two post-step calls (the start time before them).
    ends: [f64; 2],
}

impl StepEnds {
    /// A (re)start at `t0`, with ARKODE's step counter at `steps`.
    pub fn new(t0: f64, steps: u64) -> Self {
        Self { calls: 0, steps_at_start: steps, ends: [t0, t0] }
    }

    /// One post-step call, for a step ending at `t`.
    fn record(&mut self, t: f64) {
        self.calls += 1;
        self.ends = [self.ends[1], t];
    }

    /// The end of the last accepted step (or the start time), given ARKODE's step count now.
    /// ARKODE calls the post-step function before it completes the step; a completion that
    /// then fails (SUNDIALS 6 evaluates f at the new point there) leaves one call more than
    /// steps, and the state is the one before it. `None` if the counts do not fit together.
    pub fn last_accepted(&self, steps: u64) -> Option<f64> {
        match self.calls.checked_sub(steps.checked_sub(self.steps_at_start)?)? {
            0 => Some(self.ends[1]),
            1 => Some(self.ends[0]),
            _ => None,
        }
    }
}

/// ARKODE's post-step function (ARKPostProcessFn): records where each step ends; leaves the
/// state alone.
pub(crate) unsafe extern "C" fn step_end<S>(t: f64, _y: ffi::N_Vector, data: *mut c_void) -> c_int {
    // SAFETY: `data` is the `Shared<S>` registered as user data (ARKODE passes the user data
    // set before the post-step function), alive for the solver's life; no other reference to
    // it is alive during a SUNDIALS call.
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    if let Some(ends) = shared.step_ends.as_mut() {
        ends.record(t);
    }
    0
}

/// Calls an RHS-like function and maps the outcome to a SUNDIALS return code.
fn rhs_code(diag: &mut Diagnostics, t: f64, dydt: &mut [f64], f: impl FnOnce(&mut [f64])) -> c_int {
    if diag.must_stop_for_underflow(t) {
        return -1;
    }
    if !diag.guarded(|| f(&mut *dydt)) {
        return -1;
    }
    if dydt.iter().all(|v| v.is_finite()) {
        0
    } else {
        diag.nonfinite_rhs += 1;
        1
    }
}

/// Evaluates `f` of the registered system at (t, y) into `ydot` and maps the outcome to a
/// return code.
///
/// # Safety
/// `data` must be the registered `Shared<S>`, alive for the solver's life; `y` and `ydot`
/// distinct serial vectors of length `dim` owned by SUNDIALS for the duration of the call.
unsafe fn rhs_with<S>(
    t: f64,
    y: ffi::N_Vector,
    ydot: ffi::N_Vector,
    data: *mut c_void,
    f: impl FnOnce(&S, f64, &[f64], &mut [f64]),
) -> c_int {
    // SAFETY: `data` is the `Shared<S>` registered as user data (caller's guarantee).
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    // SAFETY: `y` and `ydot` are distinct serial vectors of length `dim`, valid for this call.
    let (y, dy) = unsafe { (slice(y, shared.dim), slice_mut(ydot, shared.dim)) };
    let system = &shared.system;
    rhs_code(&mut shared.diag, t, dy, |dy| f(system, t, y, dy))
}

/// f(t, y) for CVODE, and for ARKStep's fully implicit or fully explicit forms.
pub(crate) unsafe extern "C" fn rhs<S: OdeSystem>(
    t: f64,
    y: ffi::N_Vector,
    ydot: ffi::N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: SUNDIALS calls this with the user data and vectors `rhs_with` requires.
    unsafe { rhs_with(t, y, ydot, data, S::rhs) }
}

/// f_E(t, y) for ARKStep IMEX.
pub(crate) unsafe extern "C" fn rhs_explicit<S: ImexSystem>(
    t: f64,
    y: ffi::N_Vector,
    ydot: ffi::N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: as in `rhs`.
    unsafe { rhs_with(t, y, ydot, data, S::rhs_explicit) }
}

/// f_I(t, y) for ARKStep IMEX.
pub(crate) unsafe extern "C" fn rhs_implicit<S: ImexSystem>(
    t: f64,
    y: ffi::N_Vector,
    ydot: ffi::N_Vector,
    data: *mut c_void,
) -> c_int {
    // SAFETY: as in `rhs`.
    unsafe { rhs_with(t, y, ydot, data, S::rhs_implicit) }
}

/// Fills a dense Jacobian through `fill` and maps the outcome to a return code.
///
/// # Safety
/// `data` must be the registered `Shared<S>`, `y` a serial vector of length `dim` and `jac` a
/// dense `dim`×`dim` SUNMatrix, all valid for the duration of the call.
unsafe fn jacobian_code<S>(
    y: ffi::N_Vector,
    jac: ffi::SUNMatrix,
    data: *mut c_void,
    fill: impl FnOnce(&S, &[f64], &mut JacobianMatrix<'_>),
) -> c_int {
    // SAFETY: guaranteed by the caller.
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    let n = shared.dim;
    // SAFETY: `y` is a serial vector of length `n`, valid for this call (caller's guarantee).
    let y = unsafe { slice(y, n) };
    // SAFETY: a dense SUNMatrix stores n*n reals contiguously in column-major order.
    let storage = unsafe { std::slice::from_raw_parts_mut(ffi::SUNDenseMatrix_Data(jac), n * n) };
    storage.fill(0.0);
    let mut matrix = JacobianMatrix::new(storage, n);
    let system = &shared.system;
    if !shared.diag.guarded(|| fill(system, y, &mut matrix)) {
        return -1;
    }
    if matrix.is_finite() {
        0
    } else {
        1
    }
}

/// Defines `$name`, a dense-Jacobian trampoline (CVLsJacFn / ARKLsJacFn signature) that fills
/// the matrix through the system's method `$fill`.
macro_rules! jacobian_trampoline {
    ($(#[$doc:meta])* $name:ident, $bound:ident, $fill:ident) => {
        $(#[$doc])*
        pub(crate) unsafe extern "C" fn $name<S: $bound>(
            t: f64,
            y: ffi::N_Vector,
            _fy: ffi::N_Vector,
            jac: ffi::SUNMatrix,
            data: *mut c_void,
            _tmp1: ffi::N_Vector,
            _tmp2: ffi::N_Vector,
            _tmp3: ffi::N_Vector,
        ) -> c_int {
            // SAFETY: SUNDIALS passes the registered user data, the current state and the
            // dense matrix attached at construction.
            unsafe { jacobian_code::<S>(y, jac, data, |s, y, m| s.$fill(t, y, m)) }
        }
    };
}

jacobian_trampoline!(
    /// Dense ∂f/∂y (CVLsJacFn / ARKLsJacFn signature).
    jacobian,
    OdeSystem,
    jacobian
);
jacobian_trampoline!(
    /// Dense ∂f_I/∂y for ARKStep IMEX.
    implicit_jacobian,
    ImexSystem,
    implicit_jacobian
);

/// The sensitivity right-hand side of parameter `is` (CVSensRhs1Fn signature):
/// s_is' = (∂f/∂y) s_is + ∂f/∂p_is at (t, y), from the system's analytic Jacobian and
/// [`ParametricSystem::param_jacobian`], or from [`ParametricSystem::sensitivity_rhs`] when
/// the system has its own. A panic returns −1 (unrecoverable), a non-finite
/// result +1 (recoverable: CVODES retries with a smaller step).
pub(crate) unsafe extern "C" fn sensitivity_rhs<S: ParametricSystem>(
    _ns: c_int,
    t: f64,
    y: ffi::N_Vector,
    _ydot: ffi::N_Vector,
    is: c_int,
    ys: ffi::N_Vector,
    ysdot: ffi::N_Vector,
    data: *mut c_void,
    _tmp1: ffi::N_Vector,
    _tmp2: ffi::N_Vector,
) -> c_int {
    // SAFETY: `data` is the `Shared<S>` registered as user data (CVODES passes the same user
    // data to f and fS), alive for the solver's life; no other reference to it is alive
    // during a SUNDIALS call.
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    let n = shared.dim;
    // SAFETY: `y`, `ys` and `ysdot` are serial vectors of length `n` (clones of the state
    // vector), valid for this call; `ysdot` is distinct from the other two.
    let (y, s, sdot) = unsafe { (slice(y, n), slice(ys, n), slice_mut(ysdot, n)) };
    let (system, diag) = (&shared.system, &mut shared.diag);
    let Some(scratch) = shared.sensitivity.as_mut() else { return -1 };
    let Some(j) = usize::try_from(is).ok().filter(|j| *j < scratch.params) else { return -1 };
    if scratch.own_rhs {
        if !diag.guarded(|| system.sensitivity_rhs(t, y, j, s, sdot)) {
            return -1;
        }
        return scratch.finite(sdot);
    }
    if !scratch.holds(t, y) {
        scratch.valid = false;
        let (jac, dfdp) = (&mut scratch.jacobian, &mut scratch.param_jacobian);
        jac.fill(0.0);
        dfdp.fill(0.0);
        let params = scratch.params;
        let evaluated = diag.guarded(|| {
            system.jacobian(t, y, &mut JacobianMatrix::new(jac, n));
            system.param_jacobian(t, y, &mut JacobianMatrix::rectangular(dfdp, n, params));
        });
        if !evaluated {
            return -1;
        }
        scratch.t = t;
        scratch.y.copy_from_slice(y);
        scratch.valid = true;
    }
    // J·s column by column, then ∂f/∂p_j.
    sdot.fill(0.0);
    for (k, sk) in s.iter().enumerate() {
        for (out, jik) in sdot.iter_mut().zip(&scratch.jacobian[k * n..(k + 1) * n]) {
            *out += jik * sk;
        }
    }
    for (out, dfdp) in sdot.iter_mut().zip(&scratch.param_jacobian[j * n..(j + 1) * n]) {
        *out += dfdp;
    }
    scratch.finite(sdot)
}

/// Root functions g(t, y) (CVRootFn / ARKRootFn signature).
pub(crate) unsafe extern "C" fn roots<S>(
    t: f64,
    y: ffi::N_Vector,
    gout: *mut f64,
    data: *mut c_void,
) -> c_int {
    // SAFETY: `data` is the registered `Shared<S>`; `gout` has room for the `root_count`
    // values declared to SUNDIALS in the root-init call that installed this trampoline.
    let shared = unsafe { &mut *(data as *mut Shared<S>) };
    // SAFETY: `y` is a serial vector of length `dim`, valid for this call.
    let y = unsafe { slice(y, shared.dim) };
    // SAFETY: `gout` has `root_count` slots: SUNDIALS allocated that many in the root-init call.
    let g = unsafe { std::slice::from_raw_parts_mut(gout, shared.root_count) };
    let Some(function) = shared.roots.as_mut() else {
        shared.diag.root_failure = Some("root function called but none is set".into());
        return -1;
    };
    if !shared.diag.guarded(|| function(t, y, g)) {
        return -1;
    }
    if let Some(i) = g.iter().position(|v| !v.is_finite()) {
        shared.diag.root_failure =
            Some(format!("root function {i} returned {} at t = {t:e}", g[i]));
        return -1;
    }
    0
}

/// Text of a C string from SUNDIALS (empty for null).
///
/// # Safety
/// `p` is null or a NUL-terminated string valid for the call.
unsafe fn text(p: *const c_char) -> String {
    if p.is_null() {
        String::new()
    } else {
        // SAFETY: guaranteed by the caller.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// SUNDIALS 6's error handler (CVErrHandlerFn / ARKErrHandlerFn, set per solver memory):
/// records errors and warnings instead of printing them.
#[cfg(not(sundials7))]
pub(crate) unsafe extern "C" fn error_handler(
    error_code: c_int,
    _module: *const c_char,
    function: *const c_char,
    msg: *mut c_char,
    data: *mut c_void,
) {
    // SAFETY: SUNDIALS passes NUL-terminated strings valid for this call.
    let message = unsafe { format!("{}: {}", text(function), text(msg)) };
    // SAFETY: `data` is the `Diagnostics` inside the registered `Shared<S>`.
    let diag = unsafe { &mut *(data as *mut Diagnostics) };
    diag.record(message, error_code < 0);
}

/// SUNDIALS 7's error handler (SUNErrHandlerFn, pushed on the context): records errors instead
/// of logging them. Warnings do not come here in 7 (see [`Diagnostics::poll_warnings`]).
#[cfg(sundials7)]
pub(crate) unsafe extern "C" fn error_handler(
    _line: c_int,
    function: *const c_char,
    _file: *const c_char,
    msg: *const c_char,
    error_code: ffi::SUNErrCode,
    data: *mut c_void,
    _ctx: ffi::SUNContext,
) {
    // SAFETY: SUNDIALS passes NUL-terminated strings (or null) valid for this call.
    let message = unsafe { format!("{}: {}", text(function), text(msg)) };
    // SAFETY: `data` is the `Diagnostics` inside the solver's boxed `Shared<S>`.
    let diag = unsafe { &mut *(data as *mut Diagnostics) };
    diag.record(message, error_code < 0);
}

#[cfg(test)]
mod tests {
    use super::StepEnds;

    #[test]
    fn the_last_accepted_step_end_follows_the_step_count() {
        let mut ends = StepEnds::new(1.0, 7);
        assert_eq!(ends.last_accepted(7), Some(1.0), "no step yet: the start");
        ends.record(1.5);
        ends.record(2.0);
        assert_eq!(ends.last_accepted(9), Some(2.0), "both steps completed");
        assert_eq!(ends.last_accepted(8), Some(1.5), "the second step's completion failed");
        assert_eq!(ends.last_accepted(7), None, "counts that do not fit");
        assert_eq!(ends.last_accepted(6), None, "a counter below the start");
    }
}
