//! Extrapolation with stiffness switching: the pair of methods behind Mathematica's NDSolve
//! `Method -> "StiffnessSwitching"` (used by Pomeau & Le Berre): extrapolation of the linearly
//! implicit Euler method for stiff phases, of the explicit modified midpoint rule otherwise.
//!
//! Stiff scheme: the linearly implicit Euler extrapolation of Deuflhard, after Hairer & Wanner,
//! "Solving ODEs II", IV.9, and their code SEULEX (1995):
//! - step-number sequence n_j = 2, 3, 4, … (Mathematica's choice; SEULEX's NSEQU = 4;
//!   [`Extrapolation::implicit_sequence`] sets the harmonic 1, 2, 3, …, SEULEX's default);
//!   row j takes n_j steps of h_j = H/n_j,
//!   (I − h_j J) Δ_i = h_j f(x + (i+1) h_j, y_i) (SEULEX's form for non-autonomous f), J the
//!   Jacobian at the step start; Aitken–Neville extrapolation in h (T_{j,k} has order k);
//! - the error estimate ‖T_{j,j} − T_{j,j−1}‖ and SEULEX's order and step-size control: work per
//!   unit step W_j = A_j/H_j (A_j counts f-calls and solves, LU decompositions, the Jacobian),
//!   the convergence monitor in columns k−1, k, k+1, FAC1..4 = 0.1, 4, 0.7, 0.9, SAFE1/2 = 0.6,
//!   0.93, at most 12 columns, and only as many as keep the extrapolation's roundoff below rtol
//!   (Λ_k·u ≤ rtol, Λ_k the sum of the moduli of the Aitken–Neville weights; an addition to
//!   SEULEX: beyond it the error estimate is roundoff and the step size collapses);
//! - the rows hold increments T_j − y (extrapolated as such, y added once the step is
//!   accepted), and a rounding test (see [`rounding`], an addition to SEULEX): the rows'
//!   rounding errors in f, carried by the solves and amplified by the extrapolation weights,
//!   must stay below the absolute tolerance, or the step is retried with a smaller H. The error
//!   estimate cannot see them, and linear invariants of f keep them for ever (E5's mass
//!   balance, docs/test-set.md);
//! - Jacobian reuse: a new Jacobian only when the last stability-check ratio θ exceeded
//!   THET = min(1e-4, rtol), or after a rejection;
//! - the stability check (rows 1–2, after their first step: θ = ‖(I − h_jJ)⁻¹(h_j f(y_1) −
//!   Δ_0)‖/max(1, ‖Δ_0‖) > 1 stops the row) and the check that the error estimates decrease
//!   along a row; either retries with H/2;
//! - SEULEX's dense output (Hairer & Ostermann 1990) with its λ = 1: the derivatives at the
//!   right end are extrapolated from backward differences of the rows' increments (the first
//!   increment of each row, which carries the stiff initial layer, left out), and the polynomial
//!   of degree k_c through y_old, y_new and these derivatives is the continuous output. λ = 0
//!   (SEULEX's default) was 300 times less accurate on the stiff van der Pol component.
//!
//! Non-stiff scheme: the Gragg–Bulirsch–Stoer extrapolation of the explicit modified midpoint
//! rule with Gragg's smoothing step, after Hairer, Nørsett & Wanner, "Solving ODEs I", II.9, and
//! their code ODEX:
//! - sequence n_j = 2, 6, 10, … (ODEX's choice for dense output), extrapolation in h² (T_{j,k}
//!   has order 2k), at most 9 columns;
//! - ODEX's order and step-size control (FAC1..4 = 0.02, 4, 0.8, 0.9, SAFE1/2 = 0.65, 0.94,
//!   A_1 = n_1 + 1, A_j = A_{j−1} + n_j) and its stability check (first substep of rows 1–2:
//!   ‖h_j(f(y_0 + h_j f_0) − f_0)‖ > 2·max(‖h_j f_0‖, 1) retries with H/2 — the floor 1, i.e.
//!   increments below the tolerance, is ours: ODEX's u-floor fails spuriously when f_0 = 0);
//! - ODEX's dense output: the cubic Hermite interpolant of the end values and slopes plus
//!   (θ(1−θ))²·Q(θ − ½), Q of degree 2k_c − 3 matching the midpoint value and derivatives, which
//!   are extrapolated from each row's midpoint value and central differences of its f-values;
//!   ODEX's error estimate of this interpolant bounds the next step and rejects the step when
//!   above 10. (A plain cubic Hermite on ODEX's long high-order steps missed the oscillator's
//!   solution by 7e9 times the tolerance at rtol 1e-12.)
//!
//! Stiffness switching, in the spirit of Mathematica's "StiffnessTest" and "NonstiffTest" (an
//! eigenvalue estimate times the step against a fraction of the explicit scheme's linear
//! stability boundary, and a test that must fire 3 times within the last 5 before it counts).
//! The integration starts with the explicit scheme; `reinit` keeps the scheme in use. LSB(k) is the
//! linear stability boundary on the negative real axis of the midpoint scheme's T_{k,k} (from its
//! stability function, computed once; 3.09, 5.02, 7.36, 6.39, 7.27, 8.25, … for k = 1, 2, 3, …).
//! - Explicit → implicit: after every explicit step attempt, ρ = max over consecutive rows of
//!   ‖f(x+H, ỹ_j) − f(x+H, ỹ_{j−1})‖/‖ỹ_j − ỹ_{j−1}‖ (ỹ_j the unsmoothed end value of row j; a
//!   secant estimate of the dominant eigenvalue's modulus at no extra f-call). The attempt
//!   counts as stiff when |H|·ρ > LSB(k)/2 (k its last row) or when the stability check stopped
//!   a row. After 3 stiff attempts among the last 5, the integration goes on (the failed step
//!   retried, or the next one) with the linearly implicit scheme, keeping H. (With 4/5 instead of
//!   1/2 the midpoint scheme ran stability-limited at |H|·λ ≈ 0.75·LSB for 11 000 steps.)
//! - Implicit → explicit: after every accepted implicit step in column k_c, H_acc = the step
//!   that column's error estimate asks for without SEULEX's growth limits, and ρ_J = the
//!   smallest of ‖J‖₁, ‖J‖_∞ of the Jacobian in use, unscaled and scaled by the error weights
//!   (each an upper bound of the spectral radius). The step counts as non-stiff when
//!   H_acc·ρ_J ≤ LSB(k_E)/4, k_E the explicit scheme's starting column. After 3 non-stiff
//!   steps among the last 5, the integration goes on with the explicit scheme. (H_acc rather
//!   than the next step: right after a switch the implicit scheme still runs at the explicit
//!   scheme's stability-limited H, which would pass the test at once.)
//!
//! Each switch is counted ([`Extrapolation::switches`]) and starts the new scheme afresh: its starting column from the
//! tolerance and SEULEX/ODEX's first-step procedure (accept as soon as a column converges).
//! [`Stats::last_order`] is the order of the last accepted step: k_c for the linearly implicit
//! scheme, 2k_c for the midpoint scheme.
//!
//! Also different from SEULEX/ODEX: the initial step (when none is given) is Hairer–Wanner's
//! explicit estimate (Solving ODEs I, II.4); steps go past `tout` (Normal task) and the result
//! is interpolated, as in CVODE; SEULEX's stability check uses the f-value of the row's next
//! step (at x + 2h_j instead of x + h_j, saving one f-call); non-finite right-hand sides stop the
//! row and halve H, ten of them in one step are an error; the step underflow test is
//! "0.1·|h| ≤ u·|t|" as in RADAU5. The linearly implicit tableau amplifies roundoff (about 1e5
//! at 11 columns of the harmonic sequence, 4e5 with 2, 3, 4, …): its accuracy levels off near
//! 1e-11 relative.
//!
//! Error flags ([`SolverError::flag`]): −1 invalid input, −2 too many steps, −3 step size too
//! small, −4 matrix repeatedly singular, −5 repeated row failures (stability checks), −6
//! right-hand-side failure, −7 repeated error-test failures.
//!
//! Layout: [`tableau`] holds what both schemes share (sequences, work model, work arrays, the
//! extrapolation tableau with its convergence monitor and order and step-size selection),
//! [`implicit`] the linearly implicit Euler scheme, [`rounding`] its rounding test,
//! [`explicit`] the modified midpoint scheme, [`switching`] the stiffness tests; this file the integrator: construction, the step loop
//! and the [`Integrator`] contract.

mod explicit;
mod implicit;
mod rounding;
mod switching;
mod tableau;

use super::stepper::{
    self, all_finite, Cause, Core, FixedStepError, Stepper, DEFAULT_MAX_ERR_TEST_FAILS,
    MAX_SINGULAR,
};
use super::{ErrorWeights, Integrator, OdeSystem, Options, SolverError, Stats, Step, Task};
use crate::method::Method;
use explicit::stability_boundaries;
use tableau::{Control, Failure, Work, DEFAULT_FIRST, KM_EXPLICIT, KM_IMPLICIT};

/// This method's row of the method table (its name and dense-output order).
const METHOD: Method = Method::Extrapolation;
const DEFAULT_MAX_ROW_FAILS: u32 = 50;

/// Failures counted within one step, each against its own limit.
#[derive(Debug, Default)]
struct StepFailures {
    attempts: u32,
    rejections: u32,
    row_fails: u32,
    nonfinite: u32,
    singular: u32,
}

/// Which scheme is in use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Extrapolated explicit modified midpoint rule (ODEX).
    Explicit,
    /// Extrapolated linearly implicit Euler method (SEULEX).
    Implicit,
}

/// Extrapolation with stiffness switching on the system `S`: the linearly implicit Euler
/// extrapolation of SEULEX (stiff) and the Gragg–Bulirsch–Stoer modified-midpoint extrapolation
/// of ODEX (non-stiff), with their order and step-size controls, and a documented switching rule
/// (see the module documentation) — the pair behind Mathematica's "StiffnessSwitching".
///
/// Implements [`Integrator`]: `dense(t, k)` for k = 0..3 on the last step (SEULEX's continuous
/// output of degree k_c after an implicit step, ODEX's of degree 2k_c + 1 after an explicit one),
/// `reinit` restarts with the scheme in use and fresh step-size history and keeps the statistics
/// and the switch count. Options: `rtol`/`atol` (used as given, as in SEULEX/ODEX), `error_scales`
/// (in the error weights; the rounding test's bound, atol plus the round-off of the step, does not
/// involve rtol and stays as it is), `max_steps` (per call, default
/// [`DEFAULT_MAX_STEPS`](super::DEFAULT_MAX_STEPS)), `max_order` (4 to 12: caps the tableau at
/// max_order rows for the linearly implicit scheme and max(4, ⌈max_order/2⌉) for the midpoint one),
/// `initial_step`, `min_step`, `max_step`, `stop_time` (not stepped past; disabled once reached),
/// `max_err_test_fails` (consecutive rejections by the error test or the rounding test in one step,
/// default 50), `max_conv_fails` (rows stopped by the stability checks in one step, default 50),
/// `fail_on_step_underflow`. `max_nonlin_iters` and `nonlin_conv_coef` are InvalidInput errors (no
/// Newton iteration), as is a `max_order` outside 4..=12.
///
/// Statistics: `lin_setups` counts LU decompositions (one per linearly implicit row),
/// `step_solve_fails` attempts stopped by a row failure (stability check, growing error,
/// non-finite f, singular matrix), `err_test_fails` rejections by the error test;
/// `last_order` is the order of the last accepted step.
pub struct Extrapolation<S: OdeSystem> {
    system: S,
    n: usize,
    /// Error weights (tolerances used as given).
    weights: ErrorWeights,
    // Options.
    max_err_test_fails: u32,
    max_row_fails: u32,
    /// Testing aids: constant step and column; a scheme without switching.
    fixed: Option<(f64, usize)>,
    forced: Option<Mode>,
    imp: Control,
    exp: Control,
    /// Linear stability boundaries of the explicit T_{k,k} (1-based), as |z| with z < 0.
    lsb: Vec<f64>,
    /// SEULEX's Jacobian-reuse threshold.
    thet: f64,
    // Integration state.
    scal: Vec<f64>,
    mode: Mode,
    k: usize,
    /// Use the first-step procedure (columns 2..k accepted as soon as one converges).
    first: bool,
    err: f64,
    errold: f64,
    /// Optimal step sizes and work per unit step of the rows computed (1-based).
    hh: Vec<f64>,
    w: Vec<f64>,
    last_row: usize,
    /// SEULEX's stability-check ratio; the Jacobian is at the current point; ρ_J of it.
    theta: f64,
    caljac: bool,
    rho_jac: f64,
    /// Explicit attempt's eigenvalue estimate; None when no pair of rows gave one.
    rho: Option<f64>,
    /// Outcomes of the last stiffness tests (bit set: the test asks for a switch).
    history: u32,
    switches: u64,
    // Continuous output of the last step.
    degree: usize,
    /// The last step's continuous output is ODEX's (explicit step), with this many midpoint
    /// derivatives (−1: cubic Hermite only).
    dense_odex: bool,
    kmit: isize,
    kmit_next: isize,
    /// ODEX's bound on the next step from the dense output's error estimate.
    hoptde: f64,
    /// The bound on the next step from the rounding test of the last implicit step.
    h_rounding: f64,
    /// Point, last step, returned state, step-sequence options and statistics.
    core: Core,
    work: Work,
}

impl<S: OdeSystem> std::fmt::Debug for Extrapolation<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.core
            .debug_struct(f, "Extrapolation", self.n)
            .field("stiff", &(self.mode == Mode::Implicit))
            .field("switches", &self.switches)
            .finish()
    }
}

impl<S: OdeSystem> Extrapolation<S> {
    /// An extrapolation integrator of `system` starting at (t0, y0) with the explicit scheme.
    /// Errors (InvalidInput): a system without components, y0 of the wrong length or
    /// non-finite, non-finite t0, invalid options.
    pub fn new(system: S, t0: f64, y0: &[f64], options: &Options) -> Result<Self, SolverError> {
        let n = system.dim();
        let core = Core::new(METHOD, n, t0, y0, options, Stats::default())?;
        let no_newton = "linearly implicit extrapolation has no Newton iteration";
        core.reject_unsupported(&[
            ("max_nonlin_iters", options.max_nonlin_iters.is_some(), no_newton),
            ("nonlin_conv_coef", options.nonlin_conv_coef.is_some(), no_newton),
            (
                "jacobian_max_age",
                options.jacobian_max_age.is_some(),
                "the Jacobian is reused by the stability-check ratio",
            ),
        ])?;
        let (km_imp, km_exp) = match options.max_order {
            Some(m) if !(4..=KM_IMPLICIT as i32).contains(&m) => {
                let message = format!("max_order = {m} must be in 4..={KM_IMPLICIT} (tableau rows of the linearly implicit scheme)");
                return Err(core.invalid(message));
            }
            Some(m) => {
                let m = m as usize;
                (m, m.div_ceil(2).clamp(4, KM_EXPLICIT))
            }
            None => (KM_IMPLICIT, KM_EXPLICIT),
        };
        let imp = Control::seulex(km_imp, DEFAULT_FIRST, options.rtol);
        let exp = Control::odex(km_exp);
        let work = Work::new(
            n,
            km_imp.max(km_exp) + 1,
            imp.off[km_imp + 1],
            exp.off[km_exp + 1],
            (km_imp + 1).max(2 * km_exp + 3),
        );
        let lsb = stability_boundaries()[..=km_exp].to_vec();
        let km = km_imp.max(km_exp);
        let positive = |v: Option<i32>, default: u32| v.map_or(default, |v| v.max(1) as u32);
        let thet = options.rtol.min(1e-4);
        let mut solver = Self {
            system,
            n,
            weights: ErrorWeights::new(options, n),
            max_err_test_fails: positive(options.max_err_test_fails, DEFAULT_MAX_ERR_TEST_FAILS),
            max_row_fails: positive(options.max_conv_fails, DEFAULT_MAX_ROW_FAILS),
            fixed: None,
            forced: None,
            imp,
            exp,
            lsb,
            thet,
            scal: vec![1.0; n],
            mode: Mode::Explicit,
            k: 3,
            first: true,
            err: 0.0,
            errold: 1.0,
            hh: vec![0.0; km + 2],
            w: vec![0.0; km + 2],
            last_row: 0,
            theta: 2.0 * thet,
            caljac: false,
            rho_jac: f64::INFINITY,
            rho: None,
            history: 0,
            switches: 0,
            degree: 0,
            dense_odex: false,
            kmit: -1,
            kmit_next: -1,
            hoptde: f64::INFINITY,
            h_rounding: f64::INFINITY,
            core,
            work,
        };
        solver.enter(Mode::Explicit);
        solver.update_scal();
        Ok(solver)
    }

    /// Testing aid: use only the linearly implicit (`stiff = true`) or only the explicit scheme,
    /// never switching.
    #[doc(hidden)]
    pub fn force_scheme(mut self, stiff: bool) -> Self {
        let mode = if stiff { Mode::Implicit } else { Mode::Explicit };
        self.forced = Some(mode);
        self.enter(mode);
        self
    }

    /// Testing aid: integrate with the constant step `h` (clipped only at the stop time) and the
    /// fixed column `k` (the result T_{k,k}), every step accepted whatever its error estimate;
    /// the stability checks are off and a row failure is an error. No switching.
    #[doc(hidden)]
    pub fn fixed_step(mut self, h: f64, k: usize) -> Self {
        self.fixed = Some((h, k));
        if self.forced.is_none() {
            self.forced = Some(self.mode);
        }
        self
    }

    /// Sets the linearly implicit scheme's step-number sequence to n_j = first + j − 1 (first ≥ 1):
    /// 1 gives the harmonic sequence 1, 2, 3, … (SEULEX's default), 2 the sequence 2, 3, 4, … that
    /// Mathematica's "LinearlyImplicitEuler" uses (the default here). Call before the first
    /// `advance`.
    pub fn implicit_sequence(mut self, first: usize) -> Self {
        let first = first.max(1);
        let km = self.imp.nj.len() - 1;
        self.imp = Control::seulex(km, first, self.weights.rtol);
        let need = self.imp.off[km + 1];
        let n = self.n;
        self.work.incr.resize_with(need, || vec![0.0; n]);
        let mode = self.mode;
        self.enter(mode);
        self
    }

    /// Number of switches between the schemes so far (over the integrator's whole life).
    pub fn switches(&self) -> u64 {
        self.switches
    }

    /// Whether the linearly implicit (stiff) scheme is in use.
    pub fn is_stiff(&self) -> bool {
        self.mode == Mode::Implicit
    }

    fn update_scal(&mut self) {
        self.weights.fill(&self.core.y, &mut self.scal);
    }

    /// Hairer–Wanner's initial step (Solving ODEs I, II.4) for an order-5 error, measured with
    /// the scaled norm of the step-size control.
    fn estimate_initial_step(&mut self, bound: f64) -> f64 {
        let (w, c) = (&mut self.work, &mut self.core);
        let exponent = 1.0 / 6.0;
        stepper::initial_step(&self.system, c, &self.scal, &mut w.tmp, &mut w.fnew, bound, exponent)
    }

    /// Accepts the step to `xph` in column kc: continuous output (already built for an explicit
    /// step), new state.
    fn accept(&mut self, xph: f64, kc: usize) {
        let h = self.core.h;
        match self.mode {
            Mode::Implicit => {
                self.dense_implicit(kc);
                self.dense_odex = false;
            }
            Mode::Explicit => {
                std::mem::swap(&mut self.work.poly, &mut self.work.poly_next);
                self.dense_odex = true;
                self.kmit = self.kmit_next;
            }
        }
        self.core.xold = self.core.x;
        self.core.hold = h;
        self.core.x = xph;
        self.core.y.copy_from_slice(&self.work.t[1]);
        match self.mode {
            Mode::Explicit => {
                std::mem::swap(&mut self.core.f0, &mut self.work.fnew);
                self.core.f0_valid = true;
            }
            Mode::Implicit => self.core.f0_valid = false,
        }
        self.update_scal();
        self.core.count_accepted(h);
        self.caljac = false;
        self.core.stats.last_order = match self.mode {
            Mode::Explicit => 2 * kc as i32,
            Mode::Implicit => kc as i32,
        };
    }

    /// One accepted step (with as many attempts as needed). Returns true if it ended at the
    /// stop time.
    fn step(&mut self) -> Result<bool, SolverError> {
        let mut failures = StepFailures::default();
        self.core.drop_passed_stop_time();
        loop {
            self.core.count_attempt(&mut failures.attempts)?;
            let (planned, last) = self.prepare_attempt()?;
            let first = std::mem::replace(&mut self.first, false);
            let h_used = self.core.h;
            match self.attempt(first) {
                Ok(Some(kc)) => {
                    let xph = self.core.step_end(last);
                    if self.mode == Mode::Explicit
                        && !self.explicit_end_holds(xph, kc, h_used, &mut failures)?
                    {
                        continue;
                    }
                    if self.mode == Mode::Implicit {
                        if !self.rounding_holds(kc, h_used, &mut failures.rejections)? {
                            continue;
                        }
                        self.add_increment();
                    }
                    self.complete_step(xph, kc, h_used, planned, last);
                    return Ok(last);
                }
                Ok(None) => self.after_rejection(h_used, &mut failures)?,
                Err(failure) => self.after_row_failure(failure, h_used, &mut failures)?,
            }
        }
    }

    /// Readies one attempt: the fixed step (testing aid), the step clipped at the stop time,
    /// the step-underflow test, f at the current point and the Jacobian when the scheme needs
    /// them. Returns the step planned before clipping and whether the attempt ends at the stop
    /// time.
    fn prepare_attempt(&mut self) -> Result<(f64, bool), SolverError> {
        if let Some((h, _)) = self.fixed {
            self.core.h = self.core.posneg * h;
        }
        // Do not step past the stop time.
        let planned = self.core.h;
        let last = self.core.clip_to_stop_time();
        self.core.check_step_underflow()?;
        let need_jacobian = self.mode == Mode::Implicit && {
            if self.core.reject {
                self.theta = 2.0 * self.thet;
            }
            self.theta > self.thet && !self.caljac
        };
        if (self.mode == Mode::Explicit || (need_jacobian && !self.system.has_jacobian()))
            && !self.ensure_f0()
        {
            return Err(self.core.error(
                Cause::RhsFailure,
                "the right-hand side at the current point is not finite".into(),
            ));
        }
        if need_jacobian {
            if !self.compute_jacobian() {
                return Err(self
                    .core
                    .error(Cause::RhsFailure, "the Jacobian is not finite".into()));
            }
            self.caljac = true;
        }
        self.core.stats.step_attempts += 1;
        self.rho = None;
        self.last_row = 0;
        Ok((planned, last))
    }

    /// The end of an explicit step converged in column kc: f at the new point (for the
    /// continuous output and the next step) and ODEX's continuous output, whose error
    /// estimate bounds the next step and rejects the step when above 10. False when the step
    /// is to be retried (h already reduced).
    fn explicit_end_holds(
        &mut self,
        xph: f64,
        kc: usize,
        h_used: f64,
        failures: &mut StepFailures,
    ) -> Result<bool, SolverError> {
        let w = &mut self.work;
        self.system.rhs(xph, &w.t[1], &mut w.fnew);
        self.core.stats.rhs_evals += 1;
        if !all_finite(&w.fnew) {
            self.core.stats.nonfinite_rhs += 1;
            self.core.nonfinite_failure(&mut failures.nonfinite, self.fixed.is_some())?;
            return Ok(false);
        }
        let errint = self.dense_explicit(kc);
        let degree = (self.kmit_next + 4).max(1) as f64;
        self.hoptde = h_used.abs() / errint.powf(1.0 / degree).max(0.01);
        if errint > 10.0 && self.fixed.is_none() {
            self.core.stats.err_test_fails += 1;
            failures.rejections += 1;
            if failures.rejections >= self.max_err_test_fails {
                let message = format!(
                    "{} error-test failures in one step (dense output, h = {h_used:e})",
                    failures.rejections
                );
                return Err(self.core.error(Cause::ErrorTestFailures, message));
            }
            let hnew = self.core.posneg * self.hoptde;
            self.core.reduce(hnew, Cause::ErrorTestFailures, "dense-output error test")?;
            return Ok(false);
        }
        Ok(true)
    }

    /// Completes a step accepted in column kc at `xph`: the new state, the next order and
    /// step (the planned one again after a step clipped at the stop time), and the stiffness
    /// test of the scheme that took it.
    fn complete_step(&mut self, xph: f64, kc: usize, h_used: f64, planned: f64, last: bool) {
        let explicit = self.mode == Mode::Explicit;
        self.accept(xph, kc);
        if self.fixed.is_none() {
            self.select(kc);
        } else {
            self.core.reject = false;
        }
        if last {
            self.core.stop_time = None;
            if self.fixed.is_none() {
                self.core.h = planned;
            }
        }
        if !explicit && self.h_rounding < self.core.h.abs() {
            self.core.h = self.core.posneg * self.h_rounding.max(self.core.hmin);
        }
        if explicit {
            self.stiffness_test(h_used, false);
        } else {
            self.nonstiffness_test(h_used, kc);
        }
        self.core.stats.current_step = self.core.h;
    }

    /// After a step rejected by the error test (h and k already chosen for the retry): counts
    /// it against `max_err_test_fails`, reduces h, and feeds the stiffness test.
    fn after_rejection(
        &mut self,
        h_used: f64,
        failures: &mut StepFailures,
    ) -> Result<(), SolverError> {
        self.core.stats.err_test_fails += 1;
        failures.rejections += 1;
        if failures.rejections >= self.max_err_test_fails {
            let message = format!(
                "{} error-test failures in one step (h = {:e}, err = {:e})",
                failures.rejections, h_used, self.err
            );
            return Err(self.core.error(Cause::ErrorTestFailures, message));
        }
        let hnew = self.core.h;
        self.core.h = h_used;
        self.core.reduce(hnew, Cause::ErrorTestFailures, "error-test failure")?;
        self.stiffness_test(h_used, false);
        Ok(())
    }

    /// After a row stopped by `failure`: an error with a fixed step (testing aid) or once its
    /// kind has failed too often in this step, otherwise h reduced by the scheme's factor;
    /// the stiffness test counts an unstable explicit attempt as stiff.
    fn after_row_failure(
        &mut self,
        failure: Failure,
        h_used: f64,
        failures: &mut StepFailures,
    ) -> Result<(), SolverError> {
        if self.fixed.is_some() && failure != Failure::NonFinite {
            let message = format!(
                "row {} failed ({failure:?}) with the fixed step h = {:e}",
                self.last_row + 1,
                self.core.h
            );
            let cause = if failure == Failure::Singular {
                Cause::LinearSolver
            } else {
                Cause::ConvergenceFailures
            };
            return Err(self.core.error(cause, message));
        }
        let factor = self.control().safe3;
        match failure {
            Failure::NonFinite => {
                self.core.stats.step_solve_fails += 1;
                self.core.nonfinite_failure(&mut failures.nonfinite, self.fixed.is_some())?;
            }
            Failure::Singular => {
                failures.singular += 1;
                self.core.stats.step_solve_fails += 1;
                if failures.singular >= MAX_SINGULAR {
                    let message = format!(
                        "iteration matrix singular {} times (h = {:e})",
                        failures.singular, self.core.h
                    );
                    return Err(self.core.error(Cause::LinearSolver, message));
                }
                self.core.reduce(
                    factor * self.core.h,
                    Cause::LinearSolver,
                    "singular iteration matrix",
                )?;
            }
            Failure::Unstable | Failure::ErrorGrowth => {
                failures.row_fails += 1;
                self.core.stats.step_solve_fails += 1;
                if failures.row_fails >= self.max_row_fails {
                    let message = format!(
                        "{} rows stopped by the stability checks in one step (h = {:e})",
                        failures.row_fails, self.core.h
                    );
                    return Err(self.core.error(Cause::ConvergenceFailures, message));
                }
                self.core.reduce(
                    factor * self.core.h,
                    Cause::ConvergenceFailures,
                    "stability check",
                )?;
            }
        }
        // An explicit attempt that overflowed is unstable too (measured: a stiff start at
        // stiffness 1e3, rtol 1e-4, blew up in all ten halvings of H before any stability check
        // could stop a row).
        self.stiffness_test(h_used, failure == Failure::Unstable);
        Ok(())
    }

    /// Evaluates the k-th derivative of the last step's continuous output at t into `out`.
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]) {
        if k == 0 && t == self.core.x {
            out.copy_from_slice(&self.core.y);
        } else if self.dense_odex {
            self.interpolate_explicit(t, k, out);
        } else {
            self.interpolate_implicit(t, k, out);
        }
    }

    /// Restarts at (t0, y0) with the scheme in use (or the forced one): step-size and order
    /// history, Jacobian, continuous output and stiffness-test history are dropped; options,
    /// statistics and the switch count are kept. The scheme is kept because a restart
    /// continues an integration (at a section, after a phase crossed in closed form) where the
    /// last step tells the stiffness best: the explicit scheme restarted on a slow manifold
    /// with a small first step stays stability-limited (its secant stiffness estimate sees
    /// only round-off there: where a log-rate component sits at −500, 1e-14-steps for ever).
    pub fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        self.core.restart(t0, y0)?;
        self.update_scal();
        self.enter(self.forced.unwrap_or(self.mode));
        Ok(())
    }
}

stepper::integrator_via_stepper!(Extrapolation, METHOD, {
    fn fixed_h(&self) -> Option<f64> {
        self.fixed.map(|(h, _)| h)
    }
    fn check_fixed(&self) -> Result<(), FixedStepError> {
        if let Some((h, k)) = self.fixed {
            let km = self.control().nj.len() - 1;
            if !(h.is_finite() && h > 0.0) || k == 0 || k > km {
                return Err(FixedStepError::StepAndColumn { h, k, km });
            }
        }
        Ok(())
    }
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]) {
        Extrapolation::interpolate(self, t, k, out);
    }
});
