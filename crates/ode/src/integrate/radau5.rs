//! Radau IIA of order 5 (three stages), after Hairer & Wanner, "Solving Ordinary Differential
//! Equations II", Section IV.8, and their Fortran code RADAU5 (version of 2002), for a full
//! Jacobian and identity mass matrix.
//!
//! What follows RADAU5 line by line:
//! - the simplified Newton iteration on the stage increments Z, transformed by T⁻¹ so that the
//!   3n×3n system splits into one real n×n system (γ/h − J) and one complex one
//!   ((α + iβ)/h − J), with (γ, α ± iβ) the eigenvalues of A⁻¹;
//! - its convergence monitor (θ, the predicted "slow convergence" step reduction, at most
//!   `max_nonlin_iters` = 7 iterations, stopping test `faccon·‖ΔZ‖ ≤ fnewt` with fnewt =
//!   max(10u/rtol', min(0.03, √rtol')));
//! - Jacobian reuse: a new Jacobian only after a step whose Newton contraction θ exceeded 0.001
//!   (or after a failure with a reused one); the LU factors are kept when moreover the step size
//!   would change by a factor in [1, 1.2] (the step size is then left unchanged);
//! - the embedded error estimate filtered by (I − hγ₀J)⁻¹, re-filtered with a fresh f on the
//!   first step and after a rejection when it fails;
//! - the step-size control: h_new = h·fac/err^{1/4} with the safety factor 0.9 lowered for
//!   many Newton iterations, ratio limits [0.2, 8], no increase right after a rejection, and
//!   the predictive (Gustafsson) controller; the first step, when rejected, is cut by 10;
//! - starting values for Newton from the previous step's collocation polynomial, and the same
//!   cubic polynomial as continuous output on the last step;
//! - the tolerances: RADAU5 replaces rtol by rtol' = 0.1·rtol^{2/3} and atol by rtol'·atol/rtol,
//!   so that a given rtol buys about the accuracy it buys in CVODE
//!   ([`ToleranceTransform::Hairer`], the default; [`ToleranceTransform::AsGiven`] keeps them as
//!   scipy's Radau does).
//!
//! What differs: the initial step (when none is given) is Hairer–Wanner's explicit estimate
//! (Solving ODEs I, II.4) instead of 1e-6; steps go past `tout` (Normal task) and the result
//! is interpolated, as in CVODE; non-finite right-hand sides are Newton failures (h halved),
//! ten of them in one step an error; a step underflow is "0.1·|h| ≤ u·|t|" as in RADAU5.
//!
//! Error flags ([`SolverError::flag`]), RADAU5's IDID where it has one: −1 invalid input,
//! −2 too many steps, −3 step size too small, −4 matrix repeatedly singular, −5 repeated
//! Newton failures, −6 right-hand-side failure, −7 repeated error-test failures.

// RADAU5's coefficients are kept with the digits it publishes.
#![allow(clippy::excessive_precision)]

use super::linalg::{lu_real, pivot, rms, solve_real, with_small_n};
use super::stepper::{
    self, all_finite, Cause, Core, StepControl, Stepper, DEFAULT_MAX_ERR_TEST_FAILS, MAX_SINGULAR,
    UROUND,
};
use super::{ErrorWeights, Integrator, OdeSystem, Options, SolverError, Stats, Step, Task};
use crate::method::Method;

/// This method's row of the method table (its name and dense-output order).
const METHOD: Method = Method::Radau5;
/// Safety factor of the step-size control.
const SAFE: f64 = 0.9;
/// Jacobian reuse threshold on the Newton contraction θ.
const THET: f64 = 0.001;
/// Keep h (and the LU factors) when the proposed ratio lies in [QUOT1, QUOT2].
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
/// 1/FACL ≤ h_new/h ≤ 1/FACR.
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;
/// Defaults for options RADAU5 does not bound (it relies on the step underflow test).
const DEFAULT_MAX_CONV_FAILS: u32 = 10;
const DEFAULT_NIT: u32 = 7;

// The transformation T (A⁻¹ = T Λ T⁻¹) and its inverse, from RADAU5. T32 = 1, T33 = 0.
const T11: f64 = 9.123_239_487_089_294_279_2e-2;
const T12: f64 = -0.141_255_295_020_954_208_43;
const T13: f64 = -3.002_919_410_514_742_449_2e-2;
const T21: f64 = 0.241_717_932_707_107_018_96;
const T22: f64 = 0.204_129_352_293_799_931_99;
const T23: f64 = 0.382_942_112_757_261_937_79;
const T31: f64 = 0.966_048_182_615_092_936_19;
const TI11: f64 = 4.325_579_890_063_155_351;
const TI12: f64 = 0.339_199_251_815_809_869_54;
const TI13: f64 = 0.541_770_539_935_874_871_19;
const TI21: f64 = -4.178_718_591_551_904_727_3;
const TI22: f64 = -0.327_682_820_761_062_387_08;
const TI23: f64 = 0.476_623_554_500_550_451_96;
const TI31: f64 = -0.502_872_634_945_786_875_95;
const TI32: f64 = 2.571_926_949_855_605_429_2;
const TI33: f64 = -0.596_039_204_828_224_924_97;

/// The method's nodes, error-estimate weights and the eigenvalues of A⁻¹.
#[derive(Debug, Clone, Copy)]
struct Coeffs {
    c1: f64,
    c2: f64,
    c1m1: f64,
    c2m1: f64,
    c1mc2: f64,
    dd1: f64,
    dd2: f64,
    dd3: f64,
    /// Real eigenvalue γ of A⁻¹.
    u1: f64,
    /// Complex pair α ± iβ of A⁻¹.
    alph: f64,
    beta: f64,
}

impl Coeffs {
    fn new() -> Self {
        let sq6 = 6f64.sqrt();
        let c1 = (4.0 - sq6) / 10.0;
        let c2 = (4.0 + sq6) / 10.0;
        let (r81, r9) = (81f64.cbrt(), 9f64.cbrt());
        let u1 = (6.0 + r81 - r9) / 30.0;
        let alph = (12.0 - r81 + r9) / 60.0;
        let beta = (r81 + r9) * 3f64.sqrt() / 60.0;
        let cno = alph * alph + beta * beta;
        Self {
            c1,
            c2,
            c1m1: c1 - 1.0,
            c2m1: c2 - 1.0,
            c1mc2: c1 - c2,
            dd1: -(13.0 + 7.0 * sq6) / 3.0,
            dd2: (-13.0 + 7.0 * sq6) / 3.0,
            dd3: -1.0 / 3.0,
            u1: 1.0 / u1,
            alph: alph / cno,
            beta: beta / cno,
        }
    }
}

/// What [`Radau5`] makes of the tolerances of its [`Options`] (`rtol`, `atol`, and the absolute
/// scales of `error_scales`). Both keep every other part of the method (the error estimate,
/// the step-size control, the Newton iteration and its stopping test fnewt =
/// max(10u/rtol', min(0.03, √rtol')) on the rtol' in force) but one: the Newton iteration's
/// earliest stop (see [`ToleranceTransform::AsGiven`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ToleranceTransform {
    /// RADAU5's own (Hairer & Wanner): rtol' = 0.1·rtol^(2/3) and atol' = rtol'·atol/rtol, so
    /// that a given rtol buys about the accuracy it buys in CVODE (rtol 1e-10 weighs the error
    /// at 2.2e-8). The default, and what the stiff test set runs.
    #[default]
    Hairer,
    /// The tolerances as given: each component's local error estimate below rtol·|y_i| +
    /// atol_i, and fnewt = max(10u/rtol, min(0.03, √rtol)): how scipy's `Radau` reads rtol and
    /// atol (its error weights and Newton tolerance are these formulas), for a caller that
    /// wants scipy's reading. The Newton iteration then also stops no
    /// earlier than its second iteration (unless `max_nonlin_iters` is 1), as scipy's: RADAU5
    /// lets the first one stop on the contraction carried from the previous step, which at
    /// tolerances read as given left Newton errors that cost POLLU 1.6 digits on average over
    /// rtol 1e-4 … 1e-10 (docs/python.md).
    AsGiven,
}

/// What the next step attempt must recompute first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Action {
    /// A new Jacobian at the current point, then new LU factors.
    Jacobian,
    /// New LU factors with the current Jacobian (the step size changed).
    Decompose,
    /// Keep both (the LU factors still match h).
    Reuse,
}

/// Outcome of the simplified Newton iteration.
enum Newton {
    /// Converged after this many iterations.
    Converged(u32),
    /// Diverged or too slow (θ ≥ 0.99, or more than `nit` iterations).
    Diverged,
    /// Predicted not to converge in time: retry with h multiplied by this factor.
    Slow(f64),
    /// The right-hand side returned a non-finite value.
    NonFinite,
}

/// Work arrays, allocated once.
#[derive(Debug, Clone)]
struct Work {
    z1: Vec<f64>,
    z2: Vec<f64>,
    z3: Vec<f64>,
    f1: Vec<f64>,
    f2: Vec<f64>,
    f3: Vec<f64>,
    tmp: Vec<f64>,
    ynew: Vec<f64>,
    fnew: Vec<f64>,
    /// Collocation polynomial of the last step: y(x + s·hold) = y + s(a1 + (s−c2m1)(a2 +
    /// (s−c1m1)a3)), s ∈ [−1, 0].
    a1: Vec<f64>,
    a2: Vec<f64>,
    a3: Vec<f64>,
    /// Jacobian, column-major.
    jac: Vec<f64>,
    /// LU factors of γ/h − J (column-major, LINPACK layout) and pivots.
    e1: Vec<f64>,
    ip1: Vec<usize>,
    /// LU factors of (α + iβ)/h − J: real and imaginary parts.
    e2r: Vec<f64>,
    e2i: Vec<f64>,
    ip2: Vec<usize>,
}

/// The vector [`Work::solve_real`] solves for in place.
#[derive(Debug, Clone, Copy)]
enum Stage {
    /// The real stage system's right-hand side.
    Z1,
    /// The error estimate's.
    Tmp,
}

/// Whether the column-major n × n matrix `jac` is block diagonal with n/m copies of its
/// leading m × m block (exactly: every block equal to the first, zeros elsewhere).
fn repeats_block(jac: &[f64], n: usize, m: usize) -> bool {
    jac.chunks_exact(n).enumerate().all(|(j, column)| {
        column.iter().enumerate().all(|(i, &a)| {
            if i / m == j / m {
                a == jac[(j % m) * n + i % m]
            } else {
                a == 0.0
            }
        })
    })
}

impl Work {
    /// Solves (γ/h − J) x = b for b = `which`, in place, with the factors of m × m blocks
    /// (m = n: the whole matrix) applied to each m-slice.
    fn solve_real(&mut self, m: usize, which: Stage) {
        let b = match which {
            Stage::Z1 => &mut self.z1,
            Stage::Tmp => &mut self.tmp,
        };
        if m == b.len() {
            solve_real(&self.e1, &self.ip1, m, b);
        } else {
            for slice in b.chunks_exact_mut(m) {
                solve_real(&self.e1, &self.ip1, m, slice);
            }
        }
    }

    /// Solves ((α + iβ)/h − J) x = z2 + i·z3, in place, as [`Work::solve_real`] does.
    fn solve_complex(&mut self, m: usize) {
        let (e2r, e2i, ip2) = (&self.e2r, &self.e2i, &self.ip2);
        if m == self.z2.len() {
            solve_complex(e2r, e2i, ip2, m, &mut self.z2, &mut self.z3);
        } else {
            for (br, bi) in self.z2.chunks_exact_mut(m).zip(self.z3.chunks_exact_mut(m)) {
                solve_complex(e2r, e2i, ip2, m, br, bi);
            }
        }
    }

    fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Self {
            z1: v(),
            z2: v(),
            z3: v(),
            f1: v(),
            f2: v(),
            f3: v(),
            tmp: v(),
            ynew: v(),
            fnew: v(),
            a1: v(),
            a2: v(),
            a3: v(),
            jac: vec![0.0; n * n],
            e1: vec![0.0; n * n],
            ip1: vec![0; n],
            e2r: vec![0.0; n * n],
            e2i: vec![0.0; n * n],
            ip2: vec![0; n],
        }
    }
}

/// The Radau IIA method of order 5 with RADAU5's step-size and Newton control, on the system
/// `S`: simplified Newton on the stage increments split into one real and one complex n×n
/// system by RADAU5's transformation T, Jacobian and LU reuse (θ ≤ 0.001, h ratio in
/// [1, 1.2]), the (I − hγ₀J)⁻¹-filtered embedded error estimate, Gustafsson's predictive
/// step-size control, Newton starting values and continuous output from the collocation
/// polynomial. Sources: Hairer & Wanner, Solving ODEs II, IV.8, and their code RADAU5.
///
/// Implements [`Integrator`]: `dense(t, k)` for k = 0..3 on the last step (the collocation
/// polynomial is cubic), `reinit` restarts with fresh step-size history and accumulated statistics.
/// Options: `rtol`/`atol` (transformed as in RADAU5 by [`Radau5::new`], as given with
/// [`ToleranceTransform::AsGiven`] and [`Radau5::with_tolerances`]), `error_scales` (an
/// absolute scale c weighs rtol'·c with the rtol' in force), `max_steps` (per call, default
/// [`DEFAULT_MAX_STEPS`](super::DEFAULT_MAX_STEPS)), `initial_step`, `min_step`, `max_step`,
/// `stop_time` (not stepped past; disabled once reached, as in SUNDIALS), `max_nonlin_iters`
/// (RADAU5's NIT, default 7), `nonlin_conv_coef` (RADAU5's FNEWT), `max_conv_fails` (consecutive
/// Newton failures in one step, default 10), `max_err_test_fails` (consecutive rejections, default
/// 50), `jacobian_max_age` (a new Jacobian after that many accepted steps even when the Newton
/// contraction allows reuse), `fail_on_step_underflow`. `max_order` is an InvalidInput error (the
/// order is 5). Statistics: `lin_setups` counts one per pair of real and complex factorisations.
pub struct Radau5<S: OdeSystem> {
    system: S,
    n: usize,
    c: Coeffs,
    /// Error weights (the tolerances after the [`ToleranceTransform`]).
    weights: ErrorWeights,
    // Options.
    nit: u32,
    /// The fewest Newton iterations that may stop: 1 (RADAU5, whose first iteration's test
    /// uses the contraction carried from the previous step), 2 with
    /// [`ToleranceTransform::AsGiven`] (scipy's, whose test needs a contraction measured in
    /// this step).
    newton_min_iters: u32,
    fnewt: f64,
    max_conv_fails: u32,
    max_err_test_fails: u32,
    fixed_h: Option<f64>,
    // Integration state.
    scal: Vec<f64>,
    faccon: f64,
    theta: f64,
    /// The step-size control with Gustafsson's memory.
    control: StepControl,
    /// The Jacobian was computed at the current point (no step accepted since).
    caljac: bool,
    /// Steps accepted since the Jacobian in use was computed, and the most allowed
    /// ([`Options::jacobian_max_age`]; `u64::MAX` when unset).
    jacobian_age: u64,
    jacobian_max_age: u64,
    action: Action,
    /// Step size the LU factors were computed for (NaN: none).
    lu_h: f64,
    /// The block size the system declares ([`OdeSystem::repeated_jacobian_block`]) when it
    /// divides n and is smaller, with an analytic Jacobian; None otherwise.
    declared_block: Option<usize>,
    /// The size m of the matrices factorised: the declared block when the current Jacobian
    /// has that structure (n/m copies of its leading m × m block on the diagonal, zeros
    /// elsewhere), else n. The solves apply the factors to each m-slice of a stage vector.
    block: usize,
    /// Point, last step, returned state, step-sequence options and statistics.
    core: Core,
    work: Work,
}

impl<S: OdeSystem> std::fmt::Debug for Radau5<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.core.debug_struct(f, "Radau5", self.n).finish()
    }
}

/// Complex division (a + ib)/(c + id) by Smith's method.
fn cdiv(a: f64, b: f64, c: f64, d: f64) -> (f64, f64) {
    if c.abs() >= d.abs() {
        let r = d / c;
        let den = c + d * r;
        ((a + b * r) / den, (b - a * r) / den)
    } else {
        let r = c / d;
        let den = c * r + d;
        ((a * r + b) / den, (b * r - a) / den)
    }
}

/// Complex LU factorisation with partial pivoting (real parts `ar`, imaginary `ai`). (Column
/// slices instead of indices, as in [`solve_complex`]: the same operations in the same order,
/// without bounds checks in the inner loops; n unrolled for the small systems, see
/// [`with_small_n`].)
fn lu_complex(ar: &mut [f64], ai: &mut [f64], ip: &mut [usize], n: usize) -> bool {
    with_small_n!(n, lu_complex_n(ar, ai, ip, n))
}

#[inline(always)]
fn lu_complex_n(ar: &mut [f64], ai: &mut [f64], ip: &mut [usize], n: usize) -> bool {
    let (ar, ai, ip) = (&mut ar[..n * n], &mut ai[..n * n], &mut ip[..n]);
    for k in 0..n {
        // Column k, and the columns right of it.
        let ((left_r, right_r), (left_i, right_i)) =
            (ar.split_at_mut((k + 1) * n), ai.split_at_mut((k + 1) * n));
        let (cr, ci) = (&mut left_r[k * n..], &mut left_i[k * n..]);
        let Some(p) = pivot(k, n, |i| cr[i].abs() + ci[i].abs()) else {
            return false;
        };
        ip[k] = p;
        if p != k {
            cr.swap(k, p);
            ci.swap(k, p);
            for (col_r, col_i) in right_r.chunks_exact_mut(n).zip(right_i.chunks_exact_mut(n)) {
                col_r.swap(k, p);
                col_i.swap(k, p);
            }
        }
        let (inv_r, inv_i) = cdiv(-1.0, 0.0, cr[k], ci[k]);
        for (xr, xi) in cr[k + 1..].iter_mut().zip(ci[k + 1..].iter_mut()) {
            let (r, i) = (*xr, *xi);
            *xr = r * inv_r - i * inv_i;
            *xi = r * inv_i + i * inv_r;
        }
        let (mr, mi) = (&cr[k + 1..], &ci[k + 1..]);
        for (col_r, col_i) in right_r.chunks_exact_mut(n).zip(right_i.chunks_exact_mut(n)) {
            let (tr, ti) = (col_r[k], col_i[k]);
            if tr != 0.0 || ti != 0.0 {
                for (((xr, xi), &ar_), &ai_) in
                    col_r[k + 1..].iter_mut().zip(col_i[k + 1..].iter_mut()).zip(mr).zip(mi)
                {
                    *xr += ar_ * tr - ai_ * ti;
                    *xi += ar_ * ti + ai_ * tr;
                }
            }
        }
    }
    true
}

/// Solves with the factors of [`lu_complex`], in place on (br, bi). (Column slices instead of
/// indices: the same operations in the same order, without bounds checks in the inner loops;
/// n unrolled for the small systems, see [`with_small_n`].)
fn solve_complex(ar: &[f64], ai: &[f64], ip: &[usize], n: usize, br: &mut [f64], bi: &mut [f64]) {
    with_small_n!(n, solve_complex_n(ar, ai, ip, n, br, bi))
}

#[inline(always)]
fn solve_complex_n(ar: &[f64], ai: &[f64], ip: &[usize], n: usize, br: &mut [f64], bi: &mut [f64]) {
    let (ar, ai, ip, br, bi) = (&ar[..n * n], &ai[..n * n], &ip[..n], &mut br[..n], &mut bi[..n]);
    for (k, (cr, ci)) in ar.chunks_exact(n).zip(ai.chunks_exact(n)).enumerate() {
        let p = ip[k];
        if p != k {
            br.swap(k, p);
            bi.swap(k, p);
        }
        let ((hr, tr_), (hi, ti_)) = (br.split_at_mut(k + 1), bi.split_at_mut(k + 1));
        let (tr, ti) = (hr[k], hi[k]);
        for (((xr, xi), &mr), &mi) in
            tr_.iter_mut().zip(ti_.iter_mut()).zip(&cr[k + 1..]).zip(&ci[k + 1..])
        {
            *xr += mr * tr - mi * ti;
            *xi += mr * ti + mi * tr;
        }
    }
    for (k, (cr, ci)) in ar.chunks_exact(n).zip(ai.chunks_exact(n)).enumerate().rev() {
        let ((hr, tr_), (hi, ti_)) = (br.split_at_mut(k), bi.split_at_mut(k));
        let (qr, qi) = cdiv(tr_[0], ti_[0], cr[k], ci[k]);
        tr_[0] = qr;
        ti_[0] = qi;
        let (tr, ti) = (-qr, -qi);
        for (((xr, xi), &mr), &mi) in hr.iter_mut().zip(hi.iter_mut()).zip(&cr[..k]).zip(&ci[..k]) {
            *xr += mr * tr - mi * ti;
            *xi += mr * ti + mi * tr;
        }
    }
}

/// Evaluates the k-th time derivative of the collocation polynomial at t into `out`.
#[allow(clippy::too_many_arguments)]
fn interpolate(
    c: &Coeffs,
    w: &Work,
    y: &[f64],
    x: f64,
    hold: f64,
    t: f64,
    k: u32,
    out: &mut [f64],
) {
    let s = (t - x) / hold;
    let (b, cc) = (c.c2m1, c.c1m1);
    for i in 0..out.len() {
        let (a1, a2, a3) = (w.a1[i], w.a2[i], w.a3[i]);
        out[i] = match k {
            0 => y[i] + s * (a1 + (s - b) * (a2 + (s - cc) * a3)),
            1 => {
                let b1 = a1 - b * a2 + b * cc * a3;
                let b2 = a2 - (b + cc) * a3;
                (b1 + s * (2.0 * b2 + 3.0 * s * a3)) / hold
            }
            2 => (2.0 * (a2 - (b + cc) * a3) + 6.0 * s * a3) / (hold * hold),
            _ => 6.0 * a3 / (hold * hold * hold),
        };
    }
}

impl<S: OdeSystem> Radau5<S> {
    /// A Radau5 integrator of `system` starting at (t0, y0), with RADAU5's tolerance transform
    /// ([`ToleranceTransform::Hairer`]). Errors (InvalidInput): a system without components,
    /// y0 of the wrong length or non-finite, non-finite t0, invalid options.
    pub fn new(system: S, t0: f64, y0: &[f64], options: &Options) -> Result<Self, SolverError> {
        Self::with_tolerances(system, t0, y0, options, ToleranceTransform::Hairer)
    }

    /// [`Radau5::new`] with the tolerances read as `transform` says.
    pub fn with_tolerances(
        system: S,
        t0: f64,
        y0: &[f64],
        options: &Options,
        transform: ToleranceTransform,
    ) -> Result<Self, SolverError> {
        let n = system.dim();
        let core =
            Core::new(METHOD, n, t0, y0, options, Stats { last_order: 5, ..Stats::default() })?;
        core.reject_unsupported(&[(
            "max_order",
            options.max_order.is_some(),
            "the order is fixed at 5",
        )])?;
        // RADAU5's tolerance transformation (an absolute error scale c weighs rtol'·c).
        let mut weights = ErrorWeights::new(options, n);
        let rtol = match transform {
            ToleranceTransform::Hairer => {
                let rtol = 0.1 * options.rtol.powf(2.0 / 3.0);
                weights.atol.iter_mut().for_each(|a| *a = rtol * *a / options.rtol);
                weights.rtol = rtol;
                rtol
            }
            ToleranceTransform::AsGiven => options.rtol,
        };
        let fnewt = options
            .nonlin_conv_coef
            .unwrap_or((10.0 * UROUND / rtol).max(0.03f64.min(rtol.sqrt())));
        let positive = |v: Option<i32>, default: u32| v.map_or(default, |v| v.max(1) as u32);
        let nit = positive(options.max_nonlin_iters, DEFAULT_NIT);
        let declared_block = system
            .repeated_jacobian_block()
            .filter(|&m| system.has_jacobian() && m > 0 && m < n && n.is_multiple_of(m));
        let mut solver = Self {
            system,
            n,
            c: Coeffs::new(),
            weights,
            nit,
            newton_min_iters: match transform {
                ToleranceTransform::Hairer => 1,
                ToleranceTransform::AsGiven => nit.min(2),
            },
            fnewt,
            max_conv_fails: positive(options.max_conv_fails, DEFAULT_MAX_CONV_FAILS),
            max_err_test_fails: positive(options.max_err_test_fails, DEFAULT_MAX_ERR_TEST_FAILS),
            fixed_h: None,
            scal: vec![1.0; n],
            faccon: 1.0,
            theta: THET,
            control: StepControl::new(0.25, SAFE, FACR, FACL),
            caljac: false,
            jacobian_age: 0,
            jacobian_max_age: options.jacobian_max_age.map_or(u64::MAX, |a| a as u64),
            action: Action::Jacobian,
            lu_h: f64::NAN,
            declared_block,
            block: n,
            core,
            work: Work::new(n),
        };
        solver.update_scal();
        Ok(solver)
    }

    /// Testing aid: integrate with the constant step `h` (clipped only at the stop time), every
    /// step accepted whatever its error estimate; a Newton failure is then an error.
    #[doc(hidden)]
    pub fn fixed_step(mut self, h: f64) -> Self {
        self.fixed_h = Some(h);
        self
    }

    fn update_scal(&mut self) {
        self.weights.fill(&self.core.y, &mut self.scal);
    }

    /// Hairer–Wanner's initial step (Solving ODEs I, II.4) for an error ~ h⁴ (the embedded
    /// estimate's order), measured with the scaled norm of the step-size control.
    fn estimate_initial_step(&mut self, bound: f64) -> f64 {
        let (w, c) = (&mut self.work, &mut self.core);
        stepper::initial_step(&self.system, c, &self.scal, &mut w.tmp, &mut w.fnew, bound, 0.25)
    }

    /// Jacobian at (x, y) into `work.jac`: analytic, or forward differences (RADAU5's
    /// increments √(u·max(1e-5, |y_i|))). False if not finite.
    /// Also sets the block size of the factorisations from the Jacobian's structure.
    fn compute_jacobian(&mut self) -> bool {
        let w = &mut self.work;
        let ok =
            stepper::jacobian(&self.system, &mut self.core, &mut w.jac, &mut w.tmp, &mut w.fnew);
        self.block = match self.declared_block {
            Some(m) if repeats_block(&w.jac, self.n, m) => m,
            _ => self.n,
        };
        ok
    }

    /// LU factors of γ/h − J and (α + iβ)/h − J (of their leading `block` × `block` blocks).
    /// False if either is singular.
    fn decompose(&mut self) -> bool {
        let (n, m) = (self.n, self.block);
        let h = self.core.h;
        let fac1 = self.c.u1 / h;
        let (alphn, betan) = (self.c.alph / h, self.c.beta / h);
        let w = &mut self.work;
        // The leading m × m block of −J (columns of length n in `jac`).
        let columns = w.e1.chunks_exact_mut(m).zip(w.e2r.chunks_exact_mut(m));
        for ((e1, e2r), jac) in columns.zip(w.jac.chunks_exact(n)).take(m) {
            for ((a, b), &j) in e1.iter_mut().zip(e2r.iter_mut()).zip(&jac[..m]) {
                *a = -j;
                *b = -j;
            }
        }
        w.e2i[..m * m].fill(0.0);
        for j in 0..m {
            w.e1[j * m + j] += fac1;
            w.e2r[j * m + j] += alphn;
            w.e2i[j * m + j] = betan;
        }
        self.core.stats.lin_setups += 1;
        let ok =
            lu_real(&mut w.e1, &mut w.ip1, m) && lu_complex(&mut w.e2r, &mut w.e2i, &mut w.ip2, m);
        self.lu_h = if ok { h } else { f64::NAN };
        ok
    }

    /// The simplified Newton iteration for the stage increments (RADAU5's loop 40).
    fn newton(&mut self) -> Newton {
        let n = self.n;
        let h = self.core.h;
        let c = self.c;
        let fac1 = c.u1 / h;
        let (alphn, betan) = (c.alph / h, c.beta / h);
        let w = &mut self.work;
        // Starting values: zero on the first step, else the previous collocation polynomial.
        if !self.core.have_step {
            for v in [&mut w.z1, &mut w.z2, &mut w.z3, &mut w.f1, &mut w.f2, &mut w.f3] {
                v.iter_mut().for_each(|x| *x = 0.0);
            }
        } else {
            let c3q = h / self.core.hold;
            let (c1q, c2q) = (c.c1 * c3q, c.c2 * c3q);
            for i in 0..n {
                let (ak1, ak2, ak3) = (w.a1[i], w.a2[i], w.a3[i]);
                let z1 = c1q * (ak1 + (c1q - c.c2m1) * (ak2 + (c1q - c.c1m1) * ak3));
                let z2 = c2q * (ak1 + (c2q - c.c2m1) * (ak2 + (c2q - c.c1m1) * ak3));
                let z3 = c3q * (ak1 + (c3q - c.c2m1) * (ak2 + (c3q - c.c1m1) * ak3));
                w.z1[i] = z1;
                w.z2[i] = z2;
                w.z3[i] = z3;
                w.f1[i] = TI11 * z1 + TI12 * z2 + TI13 * z3;
                w.f2[i] = TI21 * z1 + TI22 * z2 + TI23 * z3;
                w.f3[i] = TI31 * z1 + TI32 * z2 + TI33 * z3;
            }
        }
        self.faccon = self.faccon.max(UROUND).powf(0.8);
        self.theta = THET;
        let (mut dynold, mut thqold) = (0.0f64, 0.0f64);
        let mut newt = 0u32;
        loop {
            if newt >= self.nit {
                return Newton::Diverged;
            }
            // The right-hand side at the three stages.
            let mut finite = true;
            for (cs, z) in [(c.c1, &mut w.z1), (c.c2, &mut w.z2), (1.0, &mut w.z3)] {
                for ((point, y), z) in w.tmp.iter_mut().zip(&self.core.y).zip(z.iter()) {
                    *point = y + z;
                }
                let t = if cs == 1.0 { self.core.x + h } else { self.core.x + cs * h };
                self.system.rhs(t, &w.tmp, z);
                self.core.stats.rhs_evals += 1;
                if !all_finite(z) {
                    self.core.stats.nonfinite_rhs += 1;
                    finite = false;
                    break;
                }
            }
            if !finite {
                return Newton::NonFinite;
            }
            // Transform with T⁻¹ and solve the real and complex systems.
            for i in 0..n {
                let (a1, a2, a3) = (w.z1[i], w.z2[i], w.z3[i]);
                let z1 = TI11 * a1 + TI12 * a2 + TI13 * a3;
                let z2 = TI21 * a1 + TI22 * a2 + TI23 * a3;
                let z3 = TI31 * a1 + TI32 * a2 + TI33 * a3;
                let (s2, s3) = (-w.f2[i], -w.f3[i]);
                w.z1[i] = z1 - w.f1[i] * fac1;
                w.z2[i] = z2 + s2 * alphn - s3 * betan;
                w.z3[i] = z3 + s3 * alphn + s2 * betan;
            }
            w.solve_real(self.block, Stage::Z1);
            w.solve_complex(self.block);
            newt += 1;
            self.core.stats.nonlin_iters += 1;
            let mut sum = 0.0;
            for i in 0..n {
                let s = self.scal[i];
                sum += (w.z1[i] / s).powi(2) + (w.z2[i] / s).powi(2) + (w.z3[i] / s).powi(2);
            }
            let dyno = (sum / (3 * n) as f64).sqrt();
            if !dyno.is_finite() {
                return Newton::Diverged;
            }
            if newt > 1 && newt < self.nit {
                let thq = dyno / dynold;
                self.theta = if newt == 2 { thq } else { (thq * thqold).sqrt() };
                thqold = thq;
                if self.theta < 0.99 {
                    self.faccon = self.theta / (1.0 - self.theta);
                    let rest = (self.nit - 1 - newt) as i32;
                    let dyth = self.faccon * dyno * self.theta.powi(rest) / self.fnewt;
                    if dyth >= 1.0 && self.fixed_h.is_none() {
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        return Newton::Slow(0.8 * qnewt.powf(-1.0 / (4.0 + rest as f64)));
                    }
                } else {
                    return Newton::Diverged;
                }
            }
            dynold = dyno.max(UROUND);
            for i in 0..n {
                let f1 = w.f1[i] + w.z1[i];
                let f2 = w.f2[i] + w.z2[i];
                let f3 = w.f3[i] + w.z3[i];
                w.f1[i] = f1;
                w.f2[i] = f2;
                w.f3[i] = f3;
                w.z1[i] = T11 * f1 + T12 * f2 + T13 * f3;
                w.z2[i] = T21 * f1 + T22 * f2 + T23 * f3;
                w.z3[i] = T31 * f1 + f2;
            }
            if newt >= self.newton_min_iters && self.faccon * dyno <= self.fnewt {
                return Newton::Converged(newt);
            }
        }
    }

    /// RADAU5's ESTRAD: the filtered embedded error estimate (None: a non-finite f in the
    /// re-filtering).
    fn estimate_error(&mut self) -> Option<f64> {
        let n = self.n;
        let c = self.c;
        let h = self.core.h;
        let (hee1, hee2, hee3) = (c.dd1 / h, c.dd2 / h, c.dd3 / h);
        let w = &mut self.work;
        for i in 0..n {
            w.f2[i] = hee1 * w.z1[i] + hee2 * w.z2[i] + hee3 * w.z3[i];
            w.tmp[i] = w.f2[i] + self.core.f0[i];
        }
        w.solve_real(self.block, Stage::Tmp);
        let mut err = rms(&w.tmp, &self.scal).max(1e-10);
        if err >= 1.0 && (!self.core.have_step || self.core.reject) {
            for i in 0..n {
                w.ynew[i] = self.core.y[i] + w.tmp[i];
            }
            self.system.rhs(self.core.x, &w.ynew, &mut w.f1);
            self.core.stats.rhs_evals += 1;
            if !all_finite(&w.f1) {
                self.core.stats.nonfinite_rhs += 1;
                return None;
            }
            for i in 0..n {
                w.tmp[i] = w.f1[i] + w.f2[i];
            }
            w.solve_real(self.block, Stage::Tmp);
            err = rms(&w.tmp, &self.scal).max(1e-10);
        }
        Some(if err.is_finite() { err } else { 1e20 })
    }

    /// [`Core::reduce`], then a new Jacobian or LU decomposition before the retry.
    fn reduce(&mut self, hnew: f64, cause: Cause, why: &str) -> Result<(), SolverError> {
        self.core.reduce(hnew, cause, why)?;
        self.action = if self.caljac { Action::Decompose } else { Action::Jacobian };
        Ok(())
    }

    /// One accepted step (with as many attempts as needed). Returns true if it ended at the
    /// stop time.
    fn step(&mut self) -> Result<bool, SolverError> {
        let (mut conv_fails, mut nonfinite, mut singular, mut rejections) =
            (0u32, 0u32, 0u32, 0u32);
        let mut attempts = 0u32;
        self.core.drop_passed_stop_time();
        loop {
            self.core.count_attempt(&mut attempts)?;
            let (planned, last) = self.core.prepare_attempt(self.fixed_h)?;
            // Jacobian and LU factors.
            if self.action == Action::Jacobian {
                if !self.compute_jacobian() {
                    return Err(self
                        .core
                        .error(Cause::RhsFailure, "the Jacobian is not finite".into()));
                }
                self.caljac = true;
                self.jacobian_age = 0;
                self.action = Action::Decompose;
            }
            if self.action == Action::Decompose || self.lu_h != self.core.h {
                if !self.decompose() {
                    singular += 1;
                    if singular >= MAX_SINGULAR || self.fixed_h.is_some() {
                        let message = format!(
                            "iteration matrix singular {singular} times (h = {:e})",
                            self.core.h
                        );
                        return Err(self.core.error(Cause::LinearSolver, message));
                    }
                    self.reduce(
                        0.5 * self.core.h,
                        Cause::LinearSolver,
                        "singular iteration matrix",
                    )?;
                    continue;
                }
                self.action = Action::Reuse;
            }
            self.core.stats.step_attempts += 1;
            let newt = match self.newton() {
                Newton::Converged(k) => k,
                Newton::Diverged => {
                    self.core.stats.nonlin_conv_fails += 1;
                    self.core.stats.step_solve_fails += 1;
                    conv_fails += 1;
                    if conv_fails >= self.max_conv_fails || self.fixed_h.is_some() {
                        let message = format!(
                            "Newton failed {conv_fails} times in one step (h = {:e})",
                            self.core.h
                        );
                        return Err(self.core.error(Cause::ConvergenceFailures, message));
                    }
                    self.reduce(0.5 * self.core.h, Cause::ConvergenceFailures, "Newton failure")?;
                    continue;
                }
                Newton::Slow(factor) => {
                    self.core.stats.nonlin_conv_fails += 1;
                    self.core.stats.step_solve_fails += 1;
                    self.reduce(
                        factor * self.core.h,
                        Cause::ConvergenceFailures,
                        "slow Newton convergence",
                    )?;
                    continue;
                }
                Newton::NonFinite => {
                    self.core.stats.step_solve_fails += 1;
                    self.nonfinite_failure(&mut nonfinite)?;
                    continue;
                }
            };
            let Some(err) = self.estimate_error() else {
                self.nonfinite_failure(&mut nonfinite)?;
                continue;
            };
            // The new step size.
            let fac = SAFE.min(SAFE * (1 + 2 * self.nit) as f64 / (newt + 2 * self.nit) as f64);
            let mut quot = self.control.quotient(err, fac);
            let mut hnew = self.core.h / quot;
            if err < 1.0 || self.fixed_h.is_some() {
                // f at the new point (needed next anyway): a non-finite one fails the step.
                let xph = self.core.step_end(last);
                let w = &mut self.work;
                for i in 0..self.n {
                    w.ynew[i] = self.core.y[i] + w.z3[i];
                }
                self.system.rhs(xph, &w.ynew, &mut w.fnew);
                self.core.stats.rhs_evals += 1;
                if !all_finite(&w.fnew) {
                    self.core.stats.nonfinite_rhs += 1;
                    self.nonfinite_failure(&mut nonfinite)?;
                    continue;
                }
                self.accept(xph, err, &mut quot, &mut hnew);
                let h = self.core.h;
                // The next step size (RADAU5 after label 30's acceptance branch).
                hnew = self.core.next_step(hnew, last, planned, self.fixed_h);
                let qt = hnew / h;
                let fresh = self.theta <= THET && self.jacobian_age < self.jacobian_max_age;
                if fresh && (QUOT1..=QUOT2).contains(&qt) {
                    self.action = Action::Reuse;
                } else {
                    self.core.h = hnew;
                    self.action = if fresh { Action::Decompose } else { Action::Jacobian };
                }
                self.core.stats.current_step = self.core.h;
                return Ok(last);
            }
            // Rejected by the error test.
            self.core.rejected(&mut rejections, self.max_err_test_fails, err)?;
            let hnew = if self.core.have_step { hnew } else { 0.1 * self.core.h };
            self.reduce(hnew, Cause::ErrorTestFailures, "error-test failure")?;
        }
    }

    /// A non-finite right-hand side: halve h, or fail after MAX_NONFINITE in one step.
    fn nonfinite_failure(&mut self, count: &mut u32) -> Result<(), SolverError> {
        self.core.nonfinite_failure(count, self.fixed_h.is_some())?;
        self.action = if self.caljac { Action::Decompose } else { Action::Jacobian };
        Ok(())
    }

    /// Accepts the step to `xph`: Gustafsson's controller, the continuous output, the new
    /// state (RADAU5's acceptance branch).
    fn accept(&mut self, xph: f64, err: f64, quot: &mut f64, hnew: &mut f64) {
        let h = self.core.h;
        self.control.accepted(h, err, quot, hnew);
        self.core.xold = self.core.x;
        self.core.hold = h;
        self.core.x = xph;
        let c = self.c;
        let w = &mut self.work;
        for i in 0..self.n {
            let (z1, z2, z3) = (w.z1[i], w.z2[i], w.z3[i]);
            w.a1[i] = (z2 - z3) / c.c2m1;
            let ak = (z1 - z2) / c.c1mc2;
            let acont3 = (ak - z1 / c.c1) / c.c2;
            w.a2[i] = (ak - w.a1[i]) / c.c1m1;
            w.a3[i] = w.a2[i] - acont3;
        }
        std::mem::swap(&mut self.core.y, &mut w.ynew);
        std::mem::swap(&mut self.core.f0, &mut w.fnew);
        self.core.f0_valid = true;
        self.update_scal();
        self.core.count_accepted(h);
        self.caljac = false;
        self.jacobian_age += 1;
    }

    /// Restarts at (t0, y0): step-size history, Jacobian and polynomial are dropped; options
    /// and statistics are kept.
    pub fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        self.core.restart(t0, y0)?;
        self.update_scal();
        self.faccon = 1.0;
        self.theta = THET;
        self.control.restart();
        self.caljac = false;
        self.action = Action::Jacobian;
        self.lu_h = f64::NAN;
        Ok(())
    }
}

stepper::integrator_via_stepper!(Radau5, METHOD, {
    fn fixed_h(&self) -> Option<f64> {
        self.fixed_h
    }
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]) {
        interpolate(&self.c, &self.work, &self.core.y, self.core.x, self.core.hold, t, k, out);
    }
});

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::{JacobianMatrix, Tolerance};

    /// Robertson's stiff kinetics y' = f(y) and one tangent vector w' = J(y) w: z = (y, w).
    /// `declare` is what [`OdeSystem::repeated_jacobian_block`] says; `coupled` adds the block
    /// ∂(J w)/∂y to the Jacobian (which then does not repeat J).
    struct Tangent {
        declare: Option<usize>,
        coupled: bool,
    }

    fn robertson_jacobian(y: &[f64]) -> [[f64; 3]; 3] {
        [
            [-0.04, 1e4 * y[2], 1e4 * y[1]],
            [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]],
            [0.0, 6e7 * y[1], 0.0],
        ]
    }

    impl OdeSystem for Tangent {
        fn dim(&self) -> usize {
            6
        }
        fn rhs(&self, _t: f64, z: &[f64], dz: &mut [f64]) {
            let y = &z[..3];
            dz[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
            dz[2] = 3e7 * y[1] * y[1];
            dz[1] = -dz[0] - dz[2];
            let j = robertson_jacobian(y);
            for (row, r) in j.iter().enumerate() {
                dz[3 + row] = (0..3).map(|k| r[k] * z[3 + k]).sum();
            }
        }
        fn has_jacobian(&self) -> bool {
            true
        }
        fn jacobian(&self, _t: f64, z: &[f64], jac: &mut JacobianMatrix<'_>) {
            let j = robertson_jacobian(&z[..3]);
            for (row, r) in j.iter().enumerate() {
                for (col, &a) in r.iter().enumerate() {
                    jac.set(row, col, a);
                    jac.set(3 + row, 3 + col, a);
                }
            }
            if self.coupled {
                // ∂(J w)_row/∂y_k (J is linear in y).
                let w = &z[3..];
                jac.set(3, 1, 1e4 * w[2]);
                jac.set(3, 2, 1e4 * w[1]);
                jac.set(4, 1, -6e7 * w[1] - 1e4 * w[2]);
                jac.set(4, 2, -1e4 * w[1]);
                jac.set(5, 1, 6e7 * w[1]);
            }
        }
        fn repeated_jacobian_block(&self) -> Option<usize> {
            self.declare
        }
    }

    /// Integrates `system` to t = 1e3 and returns the state, the statistics and the block size
    /// of the last factorisation.
    fn run(system: Tangent) -> (Vec<f64>, Stats, usize) {
        let z0 = [1.0, 0.0, 0.0, 0.3, -0.2, 0.5];
        let options = Options::new(1e-8, Tolerance::Scalar(1e-12));
        let mut solver = Radau5::new(system, 0.0, &z0, &options).unwrap();
        solver.advance(1e3, Task::Normal).unwrap();
        (solver.state().to_vec(), solver.stats(), solver.block)
    }

    /// A Jacobian that repeats its block is factorised block by block with the same numbers as
    /// the whole matrix: the same states and statistics to the bit.
    #[test]
    fn repeated_blocks_give_the_whole_matrix_numbers() {
        let (whole, whole_stats, whole_block) = run(Tangent { declare: None, coupled: false });
        let (blocks, block_stats, block) = run(Tangent { declare: Some(3), coupled: false });
        assert_eq!((whole_block, block), (6, 3));
        assert_eq!(whole, blocks);
        assert_eq!(whole_stats, block_stats);
        assert!(whole_stats.steps > 20, "{whole_stats:?}");
    }

    /// A declared structure the Jacobian does not have (the coupling block) is not used: the
    /// whole matrix is factorised, with the numbers of a system that declares nothing.
    #[test]
    fn a_wrong_declaration_falls_back_to_the_whole_matrix() {
        let (whole, whole_stats, _) = run(Tangent { declare: None, coupled: true });
        let (declared, declared_stats, block) = run(Tangent { declare: Some(3), coupled: true });
        assert_eq!(block, 6);
        assert_eq!(whole, declared);
        assert_eq!(whole_stats, declared_stats);
        // A block size that does not divide n is ignored from the start.
        let (odd, _, block) = run(Tangent { declare: Some(4), coupled: false });
        assert_eq!(block, 6);
        assert!(odd.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn repeats_block_needs_equal_blocks_and_zeros() {
        // Column-major 4×4 with two copies of [[1, 2], [3, 4]].
        let mut m =
            [1.0, 3.0, 0.0, 0.0, 2.0, 4.0, 0.0, 0.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 2.0, 4.0];
        assert!(repeats_block(&m, 4, 2));
        assert!(!repeats_block(&m, 4, 1));
        m[2] = 1e-300;
        assert!(!repeats_block(&m, 4, 2));
        m[2] = 0.0;
        m[15] = 4.5;
        assert!(!repeats_block(&m, 4, 2));
    }

    /// The complex LU solve (the real one is tested in linalg.rs).
    #[test]
    fn complex_lu_solve() {
        let n = 3;
        // Column-major, needs pivoting (zero leading entry).
        let a = [0.0, 2.0, 1.0, 1.0, 1.0, 3.0, 2.0, -1.0, 1.0];
        let x = [1.0, -2.0, 0.5];
        // (A + i·D) (xr + i·xi) = b.
        let ai = [0.5, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 2.0];
        let xi = [0.3, 0.0, -1.0];
        let (mut br, mut bi) = ([0.0; 3], [0.0; 3]);
        for j in 0..n {
            for i in 0..n {
                let (mr, mi) = (a[j * n + i], ai[j * n + i]);
                br[i] += mr * x[j] - mi * xi[j];
                bi[i] += mr * xi[j] + mi * x[j];
            }
        }
        let (mut lr, mut li, mut ip) = (a, ai, [0; 3]);
        assert!(lu_complex(&mut lr, &mut li, &mut ip, n));
        solve_complex(&lr, &li, &ip, n, &mut br, &mut bi);
        for i in 0..n {
            assert!((br[i] - x[i]).abs() < 1e-14 && (bi[i] - xi[i]).abs() < 1e-14, "{br:?} {bi:?}");
        }
        let (mut sr, mut si) = ([1.0, 2.0, 2.0, 4.0], [0.0; 4]);
        assert!(!lu_complex(&mut sr, &mut si, &mut [0; 2], 2));
    }

    #[test]
    fn transformation_diagonalises_the_inverse_coefficient_matrix() {
        // T⁻¹ A⁻¹ T must be diag(γ) ⊕ [[α, −β], [β, α]] (RADAU5's convention).
        let sq6 = 6f64.sqrt();
        let a = [
            [
                (88.0 - 7.0 * sq6) / 360.0,
                (296.0 - 169.0 * sq6) / 1800.0,
                (-2.0 + 3.0 * sq6) / 225.0,
            ],
            [
                (296.0 + 169.0 * sq6) / 1800.0,
                (88.0 + 7.0 * sq6) / 360.0,
                (-2.0 - 3.0 * sq6) / 225.0,
            ],
            [(16.0 - sq6) / 36.0, (16.0 + sq6) / 36.0, 1.0 / 9.0],
        ];
        let t = [[T11, T12, T13], [T21, T22, T23], [T31, 1.0, 0.0]];
        let ti = [[TI11, TI12, TI13], [TI21, TI22, TI23], [TI31, TI32, TI33]];
        let mul = |p: &[[f64; 3]; 3], q: &[[f64; 3]; 3]| {
            let mut r = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    r[i][j] = (0..3).map(|k| p[i][k] * q[k][j]).sum();
                }
            }
            r
        };
        // T⁻¹ A T = Λ⁻¹ (the inverse of the block form above).
        let lam_inv = mul(&mul(&ti, &a), &t);
        let c = Coeffs::new();
        let g = 1.0 / c.u1;
        assert!((lam_inv[0][0] - g).abs() < 1e-14, "{lam_inv:?}");
        let cno = c.alph * c.alph + c.beta * c.beta;
        // Inverse of [[α, −β], [β, α]] is [[α, β], [−β, α]]/(α² + β²).
        assert!((lam_inv[1][1] - c.alph / cno).abs() < 1e-13, "{lam_inv:?}");
        assert!((lam_inv[2][2] - c.alph / cno).abs() < 1e-13, "{lam_inv:?}");
        assert!((lam_inv[1][2] - c.beta / cno).abs() < 1e-13, "{lam_inv:?}");
        assert!((lam_inv[2][1] + c.beta / cno).abs() < 1e-13, "{lam_inv:?}");
        for (i, j) in [(0, 1), (0, 2), (1, 0), (2, 0)] {
            assert!(lam_inv[i][j].abs() < 1e-13, "{lam_inv:?}");
        }
    }
}
