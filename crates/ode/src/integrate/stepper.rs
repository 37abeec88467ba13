//! The driver shared by the homemade one-step integrators (Radau5, Rodas5P, Extrapolation):
//! the state every method keeps in the same way ([`Core`]: current point, last step, returned
//! state, options of the step sequence, statistics) and, on top of a method's "take one step /
//! interpolate inside the last step" ([`Stepper`]), [`Integrator::advance`] for both tasks,
//! stop time, `max_steps` per call, dense output and the errors with their t and state (a
//! panicking callback included).
//!
//! [`Integrator::advance`]: super::Integrator::advance

use super::linalg::rms;
use super::{
    panic_message, ErrorKind, ErrorScale, JacobianMatrix, OdeSystem, Options, SolverError, Stats,
    Step, StepEvent, Task, DEFAULT_MAX_STEPS,
};
use crate::method::Method;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The unit roundoff of RADAU5, RODAS, SEULEX and ODEX (step-underflow test, difference
/// increments, tolerance floors).
pub(super) const UROUND: f64 = 1e-16;
/// Consecutive non-finite right-hand sides in one step before giving up.
const MAX_NONFINITE: u32 = 10;
/// Consecutive singular iteration matrices in one step before giving up (RADAU5: 5).
pub(super) const MAX_SINGULAR: u32 = 5;
/// The default of [`Options::max_err_test_fails`] (RADAU5, RODAS and SEULEX do not bound the
/// error-test failures; they rely on the step underflow test).
pub(super) const DEFAULT_MAX_ERR_TEST_FAILS: u32 = 50;
/// Failed attempts of any kind in one step before giving up (a guard; the Fortran codes have
/// none).
const MAX_ATTEMPTS: u32 = 500;

/// The errors of the homemade methods, each an [`ErrorKind`] with its flag
/// ([`SolverError::flag`], RADAU5's IDID where it has one) as discriminant: the one table
/// behind the error flags the methods document.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Cause {
    InvalidInput = -1,
    /// `max_steps` reached.
    TooMuchWork = -2,
    StepUnderflow = -3,
    /// A singular iteration matrix.
    LinearSolver = -4,
    /// Newton, or a stability check, failed.
    ConvergenceFailures = -5,
    /// A non-finite right-hand side or Jacobian.
    RhsFailure = -6,
    ErrorTestFailures = -7,
    CallbackPanic = -8,
}

impl Cause {
    /// The error's kind.
    fn kind(self) -> ErrorKind {
        match self {
            Self::InvalidInput => ErrorKind::InvalidInput,
            Self::TooMuchWork => ErrorKind::TooMuchWork,
            Self::StepUnderflow => ErrorKind::StepUnderflow,
            Self::LinearSolver => ErrorKind::LinearSolver,
            Self::ConvergenceFailures => ErrorKind::ConvergenceFailures,
            Self::RhsFailure => ErrorKind::RhsFailure,
            Self::ErrorTestFailures => ErrorKind::ErrorTestFailures,
            Self::CallbackPanic => ErrorKind::CallbackPanic,
        }
    }

    /// The error's flag.
    fn flag(self) -> i32 {
        self as i32
    }
}

/// An absolute error scale never asks for less than this many units of round-off of the
/// component (`f64::EPSILON`·|y_i|): far from its usual range (a log-scaled component at
/// −1e11) a fixed tolerance would lie below the spacing of the doubles there, and the error
/// test could not be met (SUNDIALS stops with "too much accuracy requested").
const ABSOLUTE_FLOOR_ULPS: f64 = 100.0 * f64::EPSILON;

/// The error weights of an integration, the one definition that the homemade methods and
/// SUNDIALS' user error-weight function use: component i's local error is measured against
/// atol_i + rtol·|y_i| ([`ErrorScale::Relative`], and every component when `scales` is
/// `None`) or atol_i + max(rtol·c, 100·ε·|y_i|) ([`ErrorScale::Absolute`]`(c)`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ErrorWeights {
    /// The relative tolerance (a method's own: RADAU5 transforms it).
    pub rtol: f64,
    /// One absolute tolerance per component.
    pub atol: Vec<f64>,
    /// One scale per component; `None` weighs every component relative to its size.
    pub scales: Option<Vec<ErrorScale>>,
}

impl ErrorWeights {
    /// The weights that `options` give a system of dimension `n` (options validated).
    pub fn new(options: &Options, n: usize) -> Self {
        Self {
            rtol: options.rtol,
            atol: options.atol.to_vec(n),
            scales: options.error_scales.clone(),
        }
    }

    /// The tolerance of component i whose size is `y_abs` (|y_i|, or a method's larger of
    /// |y_i| at the two ends of a step).
    #[inline]
    pub fn scale(&self, i: usize, y_abs: f64) -> f64 {
        let relative = match self.scales.as_ref().map(|s| s[i]) {
            None | Some(ErrorScale::Relative) => self.rtol * y_abs,
            Some(ErrorScale::Absolute(c)) => (self.rtol * c).max(ABSOLUTE_FLOOR_ULPS * y_abs),
        };
        self.atol[i] + relative
    }

    /// [`scale`](Self::scale), or the smallest positive double where that is not positive (a
    /// zero tolerance for a zero component), as the homemade methods divide by it.
    #[inline]
    pub fn positive_scale(&self, i: usize, y_abs: f64) -> f64 {
        let s = self.scale(i, y_abs);
        if s > 0.0 {
            s
        } else {
            f64::MIN_POSITIVE
        }
    }

    /// The positive scales at `y` into `scal`.
    pub fn fill(&self, y: &[f64], scal: &mut [f64]) {
        for (i, (s, y)) in scal.iter_mut().zip(y).enumerate() {
            *s = self.positive_scale(i, y.abs());
        }
    }
}

/// State and options every homemade integrator shares.
pub(super) struct Core {
    pub name: &'static str,
    // Options.
    pub max_steps: u64,
    pub hmin: f64,
    pub hmax: f64,
    pub initial_step: Option<f64>,
    pub stop_time: Option<f64>,
    pub fail_on_step_underflow: bool,
    // Integration state.
    pub x: f64,
    pub y: Vec<f64>,
    /// f(x, y), valid when `f0_valid`.
    pub f0: Vec<f64>,
    pub f0_valid: bool,
    /// Direction, step size and step history set up (after new/reinit: at the first advance).
    pub started: bool,
    pub posneg: f64,
    /// Step size to try next (signed).
    pub h: f64,
    /// Last accepted step (signed) and its start.
    pub hold: f64,
    pub xold: f64,
    /// An accepted step exists since the last (re)start: the dense output is valid.
    pub have_step: bool,
    pub reject: bool,
    /// In the current step, h was cut to the local time scale of f after a non-finite stage
    /// (Rodas5P): a step underflow that follows is a layer sharper than the clock, not steps
    /// shrinking onto a point where f turns non-finite.
    pub layer_step: bool,
    /// The internal point x is a stop time that a call has not returned yet (a step ended
    /// there while the call returned an earlier tout).
    pub stop_pending: bool,
    // Returned state.
    pub t_out: f64,
    pub y_out: Vec<f64>,
    /// Buffer of [`dense`].
    pub dense: Vec<f64>,
    pub stats: Stats,
}

impl Core {
    /// Books an accepted step of size `h`.
    pub(super) fn count_accepted(&mut self, h: f64) {
        self.have_step = true;
        if self.stats.steps == 0 {
            self.stats.initial_step = h;
        }
        self.stats.steps += 1;
        self.stats.last_step = h;
    }

    /// Checks (system dimension `n`, t0, y0, options) and the common state at (t0, y0) of
    /// `method`.
    pub fn new(
        method: Method,
        n: usize,
        t0: f64,
        y0: &[f64],
        options: &Options,
        stats: Stats,
    ) -> Result<Self, SolverError> {
        let name = method.name();
        let invalid = |message: String| SolverError {
            solver: name,
            kind: ErrorKind::InvalidInput,
            t: t0,
            state: y0.to_vec(),
            flag: Cause::InvalidInput.flag(),
            message,
        };
        if n == 0 {
            return Err(invalid("the system has no components".into()));
        }
        if y0.len() != n {
            return Err(invalid(format!("y0 has {} components; the system has {n}", y0.len())));
        }
        if !t0.is_finite() {
            return Err(invalid(format!("t0 = {t0} must be finite")));
        }
        if let Some(i) = y0.iter().position(|v| !v.is_finite()) {
            return Err(invalid(format!("y0[{i}] = {} must be finite", y0[i])));
        }
        options.validate(n).map_err(|e| invalid(e.to_string()))?;
        Ok(Self {
            name,
            max_steps: options.max_steps.unwrap_or(DEFAULT_MAX_STEPS).max(1) as u64,
            hmin: options.min_step.unwrap_or(0.0),
            hmax: options.max_step.unwrap_or(f64::INFINITY),
            initial_step: options.initial_step,
            stop_time: options.stop_time,
            fail_on_step_underflow: options.fail_on_step_underflow,
            x: t0,
            y: y0.to_vec(),
            f0: vec![0.0; n],
            f0_valid: false,
            started: false,
            posneg: 1.0,
            h: 0.0,
            hold: 0.0,
            xold: t0,
            have_step: false,
            reject: false,
            layer_step: false,
            stop_pending: false,
            t_out: t0,
            y_out: y0.to_vec(),
            dense: vec![0.0; n],
            stats,
        })
    }

    /// An error at the internal point (the last accepted step's end).
    pub fn error(&self, cause: Cause, message: String) -> SolverError {
        let (kind, flag) = (cause.kind(), cause.flag());
        SolverError { solver: self.name, kind, t: self.x, state: self.y.clone(), flag, message }
    }

    /// Options the method does not have, as (name, is set, why): an invalid-input error naming
    /// the first one that is set (an option is never silently ignored).
    pub fn reject_unsupported(&self, options: &[(&str, bool, &str)]) -> Result<(), SolverError> {
        match options.iter().find(|(_, set, _)| *set) {
            Some((name, _, why)) => Err(self.invalid(format!(
                "{name} is not an option of {} ({why}): leave it unset (None)",
                self.name
            ))),
            None => Ok(()),
        }
    }

    /// An invalid-input error at the last returned point.
    pub fn invalid(&self, message: String) -> SolverError {
        SolverError {
            solver: self.name,
            kind: ErrorKind::InvalidInput,
            t: self.t_out,
            state: self.y_out.clone(),
            flag: Cause::InvalidInput.flag(),
            message,
        }
    }

    /// Round-off allowance on times around the last step.
    pub fn fuzz(&self) -> f64 {
        100.0 * f64::EPSILON * (self.x.abs() + self.hold.abs())
    }

    /// Evaluates f(x, y) into `f0` if needed; false if it is not finite.
    pub fn ensure_f0<S: OdeSystem>(&mut self, system: &S) -> bool {
        if !self.f0_valid {
            system.rhs(self.x, &self.y, &mut self.f0);
            self.stats.rhs_evals += 1;
            if !all_finite(&self.f0) {
                self.stats.nonfinite_rhs += 1;
                return false;
            }
            self.f0_valid = true;
        }
        true
    }

    /// At the start of a step: a stop time already reached is disabled (as in SUNDIALS).
    pub fn drop_passed_stop_time(&mut self) {
        if let Some(ts) = self.stop_time {
            if (ts - self.x) * self.posneg <= 0.0 {
                self.stop_time = None;
            }
        }
    }

    /// Before an attempt: shortens h so as not to step past the stop time; true if the step
    /// then ends there.
    pub fn clip_to_stop_time(&mut self) -> bool {
        if let Some(ts) = self.stop_time {
            if (self.x + 1.0001 * self.h - ts) * self.posneg >= 0.0 {
                self.h = ts - self.x;
                return true;
            }
        }
        false
    }

    /// Readies an attempt: the fixed step `fixed_h` (testing aid) in the direction of
    /// integration, then h clipped at the stop time and the step-underflow test. Returns the
    /// step planned before clipping and whether the attempt ends at the stop time.
    pub fn prepare_attempt(&mut self, fixed_h: Option<f64>) -> Result<(f64, bool), SolverError> {
        if let Some(h) = fixed_h {
            if self.h.abs() != h {
                self.h = self.posneg * h;
            }
        }
        // Do not step past the stop time.
        let planned = self.h;
        let last = self.clip_to_stop_time();
        self.check_step_underflow()?;
        Ok((planned, last))
    }

    /// The end of the step being attempted: the stop time if the step was clipped to it
    /// (`last`), otherwise x + h.
    pub fn step_end(&self, last: bool) -> f64 {
        if last {
            self.stop_time.unwrap_or(self.x + self.h)
        } else {
            self.x + self.h
        }
    }

    /// The start of a method's `Debug` output: its name, `n` and the returned and internal
    /// times.
    pub fn debug_struct<'a, 'b>(
        &self,
        f: &'a mut std::fmt::Formatter<'b>,
        name: &str,
        n: usize,
    ) -> std::fmt::DebugStruct<'a, 'b> {
        let mut d = f.debug_struct(name);
        d.field("n", &n).field("t", &self.t_out).field("t_internal", &self.x);
        d
    }

    /// Step underflow (RADAU5's test: 0.1·|h| ≤ u·|x|): an error if t + h = t or
    /// `fail_on_step_underflow`, otherwise a counted warning.
    pub fn check_step_underflow(&mut self) -> Result<(), SolverError> {
        if 0.1 * self.h.abs() <= self.x.abs() * UROUND {
            let message =
                format!("step size h = {:e} too small at t = {:e} (t + h = t)", self.h, self.x);
            if self.fail_on_step_underflow || self.x + self.h == self.x {
                return Err(self.error(Cause::StepUnderflow, message));
            }
            self.stats.step_underflow_warnings += 1;
        }
        Ok(())
    }

    /// Counts one more attempt at the current step (`attempts` in this step): an error once
    /// they exceed MAX_ATTEMPTS, a guard against failures that each stay within their own
    /// limit.
    #[inline]
    pub fn count_attempt(&self, attempts: &mut u32) -> Result<(), SolverError> {
        *attempts += 1;
        if *attempts > MAX_ATTEMPTS {
            let message = format!("{MAX_ATTEMPTS} failed attempts in one step (h = {:e})", self.h);
            return Err(self.error(Cause::ConvergenceFailures, message));
        }
        Ok(())
    }

    /// A step rejected by the error test with the error `err`: counted (`rejections` in this
    /// step), an error once they reach `max`.
    pub fn rejected(
        &mut self,
        rejections: &mut u32,
        max: u32,
        err: f64,
    ) -> Result<(), SolverError> {
        self.stats.err_test_fails += 1;
        *rejections += 1;
        if *rejections >= max {
            let message = format!(
                "{rejections} error-test failures in one step (h = {:e}, err = {err:e})",
                self.h
            );
            return Err(self.error(Cause::ErrorTestFailures, message));
        }
        Ok(())
    }

    /// Sets a reduced step size after a failure (`why`); an error of `cause` if h is already
    /// at `min_step`.
    pub fn reduce(&mut self, hnew: f64, cause: Cause, why: &str) -> Result<(), SolverError> {
        let mut hnew = hnew;
        if hnew.abs() < self.hmin {
            if self.h.abs() <= self.hmin {
                let message = format!("{why} with |h| = min_step = {:e}", self.hmin);
                return Err(self.error(cause, message));
            }
            hnew = self.posneg * self.hmin;
        }
        self.h = hnew;
        self.reject = true;
        Ok(())
    }

    /// A non-finite right-hand side: halve h, or fail after MAX_NONFINITE in one step (at
    /// once with a fixed step).
    pub fn nonfinite_failure(&mut self, count: &mut u32, fixed: bool) -> Result<(), SolverError> {
        *count += 1;
        if *count >= MAX_NONFINITE || fixed {
            let message =
                format!("the right-hand side returned non-finite values {count} times in one step (h = {:e})", self.h);
            return Err(self.error(Cause::RhsFailure, message));
        }
        self.reduce(0.5 * self.h, Cause::RhsFailure, "non-finite right-hand side")
    }

    /// The common part of `reinit`: checks (t0, y0) and restarts the point, the returned
    /// state and the step history; statistics run on.
    pub fn restart(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        let n = self.y.len();
        if y0.len() != n || !t0.is_finite() || y0.iter().any(|v| !v.is_finite()) {
            let message = format!(
                "reinit needs finite t0 and {n} finite components, got t0 = {t0}, y0 = {}",
                super::brief_state(y0)
            );
            return Err(self.invalid(message));
        }
        self.x = t0;
        self.xold = t0;
        self.y.copy_from_slice(y0);
        self.t_out = t0;
        self.y_out.copy_from_slice(y0);
        self.f0_valid = false;
        self.started = false;
        self.have_step = false;
        self.reject = false;
        self.stop_pending = false;
        self.stats.reinits += 1;
        Ok(())
    }
}

impl Core {
    /// Moves the time origin to the last returned point, keeping the step size, the step
    /// history and the method's own state: every time (internal point, last step start, stop
    /// time) shifts by t_out, so the dense output of the last step stays valid in the new
    /// frame. Exact for an autonomous system (after a one-step return, x = t_out becomes 0).
    pub fn shift_origin(&mut self) {
        let shift = self.t_out;
        self.x -= shift;
        self.xold -= shift;
        self.t_out = 0.0;
        self.stop_time = self.stop_time.map(|t| t - shift);
    }
}

impl Core {
    /// The step size to try after an accepted step (RADAU5's and RODAS's acceptance branch):
    /// the proposed `hnew` within [min_step, max_step], no longer than the step just taken
    /// right after a rejection, the `planned` step again after a `last` step clipped to the
    /// stop time (which is then disabled), and the fixed step of a testing aid if any.
    pub fn next_step(&mut self, hnew: f64, last: bool, planned: f64, fixed: Option<f64>) -> f64 {
        let mut hnew = self.posneg * hnew.abs().min(self.hmax).max(self.hmin);
        if self.reject {
            hnew = self.posneg * hnew.abs().min(self.h.abs());
        }
        self.reject = false;
        if last {
            self.stop_time = None;
            hnew = planned;
        }
        if let Some(hf) = fixed {
            hnew = self.posneg * hf;
        }
        hnew
    }
}

/// The step-size control of RADAU5 and RODAS: h_new = h/q with q = err^e/fac clamped to
/// [`quot_min`, `quot_max`] (e the error exponent, fac a safety factor), and on accepted steps
/// Gustafsson's predictive controller (Hairer–Wanner, Solving ODEs II, IV.8, (8.21)), which
/// remembers the last accepted step and its error.
///
/// [`quot_min`]: StepControl::new
/// [`quot_max`]: StepControl::new
#[derive(Debug, Clone)]
pub(super) struct StepControl {
    exponent: f64,
    safe: f64,
    quot_min: f64,
    quot_max: f64,
    /// Accepted steps since the last (re)start, the last one and its error (at least 1e-2).
    naccpt: u64,
    hacc: f64,
    erracc: f64,
}

impl StepControl {
    /// The control of a method whose error estimate is O(h^(1/`exponent`)), with the safety
    /// factor `safe` and the step ratio h/h_new kept within [`quot_min`, `quot_max`].
    pub const fn new(exponent: f64, safe: f64, quot_min: f64, quot_max: f64) -> Self {
        Self { exponent, safe, quot_min, quot_max, naccpt: 0, hacc: 0.0, erracc: 0.0 }
    }

    /// The ratio h/h_new the error `err` asks for with the safety factor `fac`, clamped.
    pub fn quotient(&self, err: f64, fac: f64) -> f64 {
        (err.powf(self.exponent) / fac).clamp(self.quot_min, self.quot_max)
    }

    /// An accepted step `h` with error `err`: from the second accepted step on, Gustafsson's
    /// ratio raises `quot` (and so shortens `hnew` = h/quot) when the error grows.
    pub fn accepted(&mut self, h: f64, err: f64, quot: &mut f64, hnew: &mut f64) {
        self.naccpt += 1;
        if self.naccpt > 1 {
            let ratio = (self.hacc / h) * (err * err / self.erracc).powf(self.exponent);
            let facgus = (ratio / self.safe).clamp(self.quot_min, self.quot_max);
            *quot = quot.max(facgus);
            *hnew = h / *quot;
        }
        self.hacc = h;
        self.erracc = err.max(1e-2);
    }

    /// An accepted step `h` with error `err` whose successor's size does not come from the
    /// controller (it ends at the stop time and the planned step follows): only counted and
    /// remembered for the next Gustafsson ratio.
    pub fn accepted_uncontrolled(&mut self, h: f64, err: f64) {
        self.naccpt += 1;
        self.hacc = h;
        self.erracc = err.max(1e-2);
    }

    /// Forgets the accepted steps (after a restart).
    pub fn restart(&mut self) {
        self.naccpt = 0;
    }
}

/// Hairer–Wanner's initial step (Solving ODEs I, II.4) at the point of `c` (with `c.f0`
/// valid), at most `bound`, for a method whose error estimate is O(h^(1/`exponent`)), measured
/// in the RMS norm with the weights `scal`: h0 = 0.01·‖y‖/‖f‖ (1e-6 when either is below 1e-5
/// or the ratio is not a positive number), an explicit Euler step of h0 (cut by 10 while f is
/// not finite there) for ‖f'‖, and h = min(100·h0, (0.01/max(‖f‖, ‖f'‖))^exponent, bound),
/// h0 if that is not a positive number. `tmp` and `fnew` are scratch of length n.
pub(super) fn initial_step<S: OdeSystem>(
    system: &S,
    c: &mut Core,
    scal: &[f64],
    tmp: &mut [f64],
    fnew: &mut [f64],
    bound: f64,
    exponent: f64,
) -> f64 {
    let d0 = rms(&c.y, scal);
    let d1 = rms(&c.f0, scal);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
    if !(h0.is_finite() && h0 > 0.0) {
        // Degenerate weights (atol = 0 on a zero component): SEULEX's default.
        h0 = 1e-6;
    }
    h0 = h0.min(bound).max(100.0 * UROUND * c.x.abs()).max(f64::MIN_POSITIVE);
    let mut d2 = None;
    for _ in 0..12 {
        let th = c.posneg * h0;
        for ((t, y), f) in tmp.iter_mut().zip(&c.y).zip(&c.f0) {
            *t = y + th * f;
        }
        system.rhs(c.x + th, tmp, fnew);
        c.stats.rhs_evals += 1;
        if all_finite(fnew) {
            for ((t, fnew), f) in tmp.iter_mut().zip(&*fnew).zip(&c.f0) {
                *t = fnew - f;
            }
            d2 = Some(rms(tmp, scal) / h0);
            break;
        }
        c.stats.nonfinite_rhs += 1;
        h0 *= 0.1;
    }
    let Some(d2) = d2.filter(|d| d.is_finite()) else { return h0 };
    let dm = d1.max(d2);
    let h1 = if dm <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / dm).powf(exponent) };
    let h = (100.0 * h0).min(h1).min(bound);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        h0
    }
}

pub(super) fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A testing aid's fixed step (see [`Stepper::check_fixed`]) that cannot be taken; reported
/// as [`ErrorKind::InvalidInput`] with this message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(super) enum FixedStepError {
    /// The fixed step size is not finite or not > 0.
    #[error("fixed step {h} must be finite and > 0")]
    Step {
        /// The step size given.
        h: f64,
    },
    /// Extrapolation's fixed step and tableau column: the step not finite or not > 0, or the
    /// column outside 1..=km.
    #[error("fixed step {h} must be finite and > 0, column {k} in 1..={km}")]
    StepAndColumn {
        /// The step size given.
        h: f64,
        /// The column given.
        k: usize,
        /// The last column of the tableau.
        km: usize,
    },
}

/// What a method provides to the shared driver.
pub(super) trait Stepper {
    /// The method: its row of the method table gives the highest derivative [`dense`] gives
    /// ([`Method::dense_order`]).
    const METHOD: Method;
    fn core(&self) -> &Core;
    fn core_mut(&mut self) -> &mut Core;
    /// Evaluates f at the current point into `core.f0` if needed (see [`Core::ensure_f0`]).
    fn ensure_f0(&mut self) -> bool;
    /// Testing aid: the constant step size, if any.
    fn fixed_h(&self) -> Option<f64>;
    /// Checks the testing aids before a call to `advance` (by default: the fixed step).
    fn check_fixed(&self) -> Result<(), FixedStepError> {
        if let Some(h) = self.fixed_h() {
            if !(h.is_finite() && h > 0.0) {
                return Err(FixedStepError::Step { h });
            }
        }
        Ok(())
    }
    /// Initial step size (unsigned) at most `bound`, with `core.f0` valid.
    fn estimate_initial_step(&mut self, bound: f64) -> f64;
    /// One accepted step (with as many attempts as needed); true if it ended at the stop time.
    fn step(&mut self) -> Result<bool, SolverError>;
    /// The k-th derivative of the last step's continuous output at t into `out`.
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]);
}

/// First advance after new/reinit: direction, f(t0, y0), initial step.
fn start<M: Stepper>(m: &mut M, tout: f64, task: Task) -> Result<(), SolverError> {
    if m.core().started {
        return Ok(());
    }
    let c = m.core_mut();
    c.posneg = if tout < c.x { -1.0 } else { 1.0 };
    if !m.ensure_f0() {
        let c = m.core();
        return Err(c.error(
            Cause::RhsFailure,
            "the right-hand side at the initial point is not finite".into(),
        ));
    }
    let c = m.core();
    let mut bound = c.hmax;
    if task == Task::Normal && tout != c.x {
        bound = bound.min((tout - c.x).abs());
    }
    if let Some(ts) = c.stop_time {
        if (ts - c.x) * c.posneg > 0.0 {
            bound = bound.min((ts - c.x).abs());
        }
    }
    let (fixed, initial) = (m.fixed_h(), c.initial_step);
    let h = match (fixed, initial) {
        (Some(h), _) => h,
        (None, Some(h)) => h.min(bound),
        (None, None) => m.estimate_initial_step(bound),
    };
    let c = m.core_mut();
    c.h = c.posneg * h.max(c.hmin);
    c.started = true;
    Ok(())
}

fn advance_inner<M: Stepper>(m: &mut M, tout: f64, task: Task) -> Result<Step, SolverError> {
    if !tout.is_finite() {
        return Err(m.core().invalid(format!("tout = {tout} must be finite")));
    }
    m.check_fixed().map_err(|e| m.core().invalid(e.to_string()))?;
    start(m, tout, task)?;
    // A stop time reached by a step whose call returned an earlier tout: return it now.
    if m.core().stop_pending
        && (task == Task::OneStep || (tout - m.core().x) * m.core().posneg >= 0.0)
    {
        let c = m.core_mut();
        c.stop_pending = false;
        c.t_out = c.x;
        c.y_out.copy_from_slice(&c.y);
        return Ok(Step { t: c.x, event: StepEvent::StopTime });
    }
    if task == Task::OneStep {
        let stopped = m.step()?;
        let c = m.core_mut();
        c.t_out = c.x;
        c.y_out.copy_from_slice(&c.y);
        let event = if stopped { StepEvent::StopTime } else { StepEvent::Reached };
        return Ok(Step { t: c.x, event });
    }
    let mut taken = 0u64;
    let mut stopped = false;
    loop {
        let c = m.core();
        if (c.x - tout) * c.posneg >= 0.0 {
            if tout == c.x {
                let c = m.core_mut();
                c.y_out.copy_from_slice(&c.y);
            } else if c.have_step && (tout - c.xold) * c.posneg >= -c.fuzz() {
                let mut out = std::mem::take(&mut m.core_mut().y_out);
                m.interpolate(tout, 0, &mut out);
                m.core_mut().y_out = out;
            } else {
                let message = format!("tout = {tout:e} is behind the last step (t = {:e})", c.x);
                return Err(c.invalid(message));
            }
            let c = m.core_mut();
            c.t_out = tout;
            // The step ended at the stop time beyond tout: the next call returns it.
            c.stop_pending = stopped && tout != c.x;
            return Ok(Step { t: tout, event: StepEvent::Reached });
        }
        if stopped {
            let c = m.core_mut();
            c.t_out = c.x;
            c.y_out.copy_from_slice(&c.y);
            return Ok(Step { t: c.x, event: StepEvent::StopTime });
        }
        let c = m.core();
        if taken >= c.max_steps {
            let message =
                format!("{} steps taken before tout = {tout:e} (raise max_steps)", c.max_steps);
            return Err(c.error(Cause::TooMuchWork, message));
        }
        stopped = m.step()?;
        taken += 1;
    }
}

/// Runs `f`, which may call the system (right-hand side, Jacobian), on the method, and turns
/// a panic there into an [`ErrorKind::CallbackPanic`] error with the panic's message at the
/// internal point, the last accepted step's end: a panic never unwinds to the caller, as in
/// the SUNDIALS wrappers, which must catch it before it reaches C.
///
/// Why the method stays usable (and `AssertUnwindSafe` is sound): every method changes its
/// point (`x`, `y`, and `f0` with `f0_valid` set after f0 is written), its last step (`xold`,
/// `hold`, continuous output) and `have_step` only in its `accept`, which calls no callback,
/// and marks a Jacobian or LU factors current only once they are complete. A panic thus
/// leaves the method as a failed attempt does: at the last accepted step with its dense
/// output, its scratch (stages, Newton iterates, a Jacobian half built) rebuilt by the next
/// attempt. A later `advance` goes on from there.
fn guarded<M: Stepper, T>(
    m: &mut M,
    f: impl FnOnce(&mut M) -> Result<T, SolverError>,
) -> Result<T, SolverError> {
    match catch_unwind(AssertUnwindSafe(|| f(m))) {
        Ok(result) => result,
        Err(payload) => Err(m.core().error(Cause::CallbackPanic, panic_message(&*payload))),
    }
}

/// [`Integrator::advance`](super::Integrator::advance) of a method. On an error, the returned
/// t and state are the last accepted step's end.
pub(super) fn advance<M: Stepper>(m: &mut M, tout: f64, task: Task) -> Result<Step, SolverError> {
    let before = m.core().stats;
    guarded(m, |m| advance_inner(m, tout, task)).map_err(|mut e| {
        let c = m.core_mut();
        if e.kind != ErrorKind::InvalidInput {
            c.t_out = c.x;
            c.y_out.copy_from_slice(&c.y);
        }
        // Name the root cause, as the SUNDIALS wrapper does: steps shrinking onto the
        // point where f turns non-finite end in a step underflow or too much work. A step
        // underflow is that only when the non-finite values failed at least half of the
        // failed attempts; when the attempts failed mostly otherwise (Newton divergence, error
        // tests: a layer sharper than the clock resolves) and a non-finite value came from the
        // trial point of one of them, it stays a step underflow, which the Clock cures by
        // re-basing (measured: radau5 at rtol 1e-4 on a stiff start 30 decades off, one
        // non-finite Newton iterate among the rejections of a step collapsing to 4e-16 at
        // local t = 0.63; docs/robustness.md). Likewise when Rodas5P cut h to the local time
        // scale of f after a non-finite stage (`layer_step`): the layer is sharper than the
        // clock, and the Clock's re-base lets the step be taken.
        let nonfinite = c.stats.nonfinite_rhs - before.nonfinite_rhs;
        if nonfinite > 0 {
            let attempts = c.stats.step_attempts.saturating_sub(before.step_attempts);
            let failed = attempts.saturating_sub(c.stats.steps.saturating_sub(before.steps));
            let from_rhs =
                e.kind != ErrorKind::StepUnderflow || (2 * nonfinite >= failed && !c.layer_step);
            if !matches!(e.kind, ErrorKind::InvalidInput | ErrorKind::CallbackPanic) && from_rhs {
                e.kind = ErrorKind::RhsFailure;
            }
            e.message.push_str(&format!(
                " [{nonfinite} right-hand-side calls returned non-finite values]"
            ));
        }
        e
    })
}

/// [`Integrator::dense`](super::Integrator::dense) of a method: the k-th derivative
/// (k ≤ the dense order of `M::METHOD`) of the continuous output at t inside the last step; before the
/// first step, only t = t0 and k ≤ 1.
pub(super) fn dense<M: Stepper>(m: &mut M, t: f64, k: u32) -> Result<&[f64], SolverError> {
    let max = M::METHOD.dense_order();
    if !t.is_finite() || k > max {
        return Err(m.core().invalid(format!(
            "dense output needs a finite t and k ≤ {max}, got t = {t}, k = {k}"
        )));
    }
    if !m.core().have_step {
        let c = m.core();
        if t != c.x || k > 1 {
            let message =
                format!("no step taken yet: dense output only at t = {:e} with k ≤ 1", c.x);
            return Err(c.invalid(message));
        }
        if k == 0 {
            let c = m.core_mut();
            c.dense.copy_from_slice(&c.y);
        } else {
            if !guarded(m, |m| Ok(m.ensure_f0()))? {
                return Err(m
                    .core()
                    .error(Cause::RhsFailure, "the right-hand side is not finite".into()));
            }
            let c = m.core_mut();
            c.dense.copy_from_slice(&c.f0);
        }
        return Ok(&m.core().dense);
    }
    let c = m.core();
    let fuzz = c.fuzz();
    let (lo, hi) = (c.xold.min(c.x) - fuzz, c.xold.max(c.x) + fuzz);
    if t < lo || t > hi {
        let message = format!("t = {t:e} is outside the last step [{:e}, {:e}]", c.xold, c.x);
        return Err(c.invalid(message));
    }
    let mut out = std::mem::take(&mut m.core_mut().dense);
    m.interpolate(t, k, &mut out);
    m.core_mut().dense = out;
    Ok(&m.core().dense)
}

/// The Jacobian at the internal point (`c.x`, `c.y`) into `jac` (n×n, column j from j·n):
/// the system's analytic one, or forward differences with RADAU5's increments
/// √(u·max(1e-5, |y_j|)) against `c.f0` (valid), with `tmp` and `fnew` as scratch. Counts the
/// evaluations. False if an entry is not finite.
pub(super) fn jacobian<S: OdeSystem>(
    system: &S,
    c: &mut Core,
    jac: &mut [f64],
    tmp: &mut [f64],
    fnew: &mut [f64],
) -> bool {
    let n = c.y.len();
    c.stats.jac_evals += 1;
    if system.has_jacobian() {
        jac.iter_mut().for_each(|v| *v = 0.0);
        let mut m = JacobianMatrix::new(jac, n);
        system.jacobian(c.x, &c.y, &mut m);
    } else {
        tmp.copy_from_slice(&c.y);
        for j in 0..n {
            let ysafe = tmp[j];
            let delt = (UROUND * ysafe.abs().max(1e-5)).sqrt();
            tmp[j] = ysafe + delt;
            let delt = tmp[j] - ysafe;
            system.rhs(c.x, tmp, fnew);
            c.stats.rhs_evals_jacobian += 1;
            for i in 0..n {
                jac[j * n + i] = (fnew[i] - c.f0[i]) / delt;
            }
            tmp[j] = ysafe;
        }
    }
    all_finite(jac)
}

/// `impl Stepper` and `impl Integrator` for the method `$method` ([`Method`]), implemented by
/// `$T<S>` with the fields `core: Core` and `system: S` and the inherent `estimate_initial_step`, `step` and `reinit`; the [`Stepper`]
/// items that differ between methods (`fixed_h`, `interpolate`, and `check_fixed` where the
/// default does not fit) are given in braces.
macro_rules! integrator_via_stepper {
    ($T:ident, $method:expr, { $($items:tt)* }) => {
        impl<S: OdeSystem> stepper::Stepper for $T<S> {
            const METHOD: $crate::method::Method = $method;
            fn core(&self) -> &stepper::Core {
                &self.core
            }
            fn core_mut(&mut self) -> &mut stepper::Core {
                &mut self.core
            }
            fn ensure_f0(&mut self) -> bool {
                self.core.ensure_f0(&self.system)
            }
            fn estimate_initial_step(&mut self, bound: f64) -> f64 {
                $T::estimate_initial_step(self, bound)
            }
            fn step(&mut self) -> Result<bool, SolverError> {
                $T::step(self)
            }
            $($items)*
        }

        impl<S: OdeSystem> $T<S> {
            /// See [`Integrator::advance`]. On an error, `t()` and `state()` are the last
            /// accepted step's end.
            pub fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
                stepper::advance(self, tout, task)
            }

            /// Sets (or moves) the time the integrator must not step past (see
            /// [`Integrator::set_stop_time`]). Lets a caller integrate piecewise-smooth forcing
            /// node by node without restarts.
            pub fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
                let c = self.core();
                if !t_stop.is_finite() {
                    return Err(c.invalid(format!("stop time {t_stop} must be finite")));
                }
                // As CVODE: a stop time behind the internal time cannot be honoured (these
                // methods step past tout and interpolate, so the internal time may already be
                // past a stop time set after a call).
                if c.started && (t_stop - c.x) * c.posneg <= 0.0 {
                    let message = format!(
                        "stop time {t_stop:e} is not ahead of the integrator's internal time {:e} (last returned t = {:e}): set it before the integration passes it",
                        c.x, c.t_out
                    );
                    return Err(c.invalid(message));
                }
                self.core_mut().stop_time = Some(t_stop);
                Ok(())
            }

            /// Sets the largest step from the next step on (see [`Integrator::set_max_step`]);
            /// a step already chosen is shortened to it.
            pub fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
                let c = self.core_mut();
                if max_step.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
                    return Err(c.invalid(format!("max step {max_step:?} must be finite and positive (or None: no limit)")));
                }
                c.hmax = max_step.unwrap_or(f64::INFINITY);
                c.h = c.h.signum() * c.h.abs().min(c.hmax);
                Ok(())
            }

            /// Statistics over the integrator's whole life (restarts included); the type's
            /// documentation says what some counts mean for this method.
            pub fn stats(&self) -> Stats {
                self.core.stats
            }

            /// The system being integrated.
            pub fn system(&self) -> &S {
                &self.system
            }

            /// The state at `t()`.
            pub fn state(&self) -> &[f64] {
                &self.core().y_out
            }

            /// Time of the last return.
            pub fn t(&self) -> f64 {
                self.core().t_out
            }

            /// The k-th derivative (k ≤ the method's dense order) of the continuous output at
            /// t inside the last step [t_prev, t_internal]; before the first step, only t = t0
            /// and k ≤ 1.
            pub fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError> {
                stepper::dense(self, t, k)
            }
        }

        impl<S: OdeSystem> Integrator for $T<S> {
            fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
                $T::advance(self, tout, task)
                    .map_err(|e| super::problem::jacobian_hint(&self.system, e))
            }
            fn state(&self) -> &[f64] {
                $T::state(self)
            }
            fn t(&self) -> f64 {
                $T::t(self)
            }
            fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError> {
                $T::dense(self, t, k)
            }
            fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
                $T::reinit(self, t0, y0)
            }
            fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
                $T::set_stop_time(self, t_stop)
            }
            fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
                $T::set_max_step(self, max_step)
            }
            fn rebase(&mut self, _first_step: Option<f64>) -> Result<(), SolverError> {
                self.core_mut().shift_origin();
                Ok(())
            }
            fn rebase_restarts(&self) -> bool {
                false
            }
            fn stats(&self) -> Stats {
                self.core().stats
            }
            fn name(&self) -> &'static str {
                self.core().name
            }
            fn max_dense_order(&self) -> u32 {
                if self.core().have_step {
                    <Self as stepper::Stepper>::METHOD.dense_order()
                } else {
                    1
                }
            }
        }
    };
}
pub(super) use integrator_via_stepper;
