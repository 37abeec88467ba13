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

use super::linalg::{lu_real, rms, solve_real, solve_refined};
use super::stepper::{self, all_finite, Core, Stepper};
use super::{
    ErrorKind, Integrator, JacobianMatrix, OdeSystem, Options, SolverError, Stats, Step, Task, Tolerance,
};

const NAME: &str = "Extrapolation";
/// Unit roundoff as in SEULEX and ODEX.
const UROUND: f64 = 1e-16;
/// Maximal tableau sizes (SEULEX: 12 columns, ODEX: 9).
const KM_IMPLICIT: usize = 12;
const KM_EXPLICIT: usize = 9;
/// SEULEX's estimated work of one f-call (+ solve), Jacobian and LU decomposition.
const WK_ROW: f64 = 2.0;
const WK_JAC: f64 = 5.0;
const WK_DEC: f64 = 1.0;
/// Explicit → implicit when |H|·ρ exceeds this fraction of the stability boundary.
const STIFF_FRACTION: f64 = 0.5;
/// Implicit → explicit when |H_acc|·ρ_J is below this fraction of the stability boundary.
const NONSTIFF_FRACTION: f64 = 0.25;
/// A switch needs this many failed (passed) tests among the last `WINDOW` ones.
const REPEATS: u32 = 3;
const WINDOW: u32 = 5;
/// Consecutive singular iteration matrices before giving up.
const MAX_SINGULAR: u32 = 5;
const DEFAULT_MAX_ERR_TEST_FAILS: u32 = 50;
const DEFAULT_MAX_ROW_FAILS: u32 = 50;
/// Failed attempts of any kind in one step before giving up (a guard).
const MAX_ATTEMPTS: u32 = 500;
/// First element of the linearly implicit scheme's step-number sequence n_j = first + j − 1:
/// 2, 3, 4, … (Mathematica's LinearlyImplicitEuler). Measured against the harmonic 1, 2, 3, …
/// (`.implicit_sequence(1)`): on van der Pol (ε = 1e-6, t ∈ [0, 2]) 1.5–22× fewer steps and
/// 1–5× less time at rtol = atol = 1e-3 … 1e-12 for equal or smaller errors (the n₁ = 1 row
/// damps stiff components weakly); on the DRR model (ξ = 0.8, ε = 1, γ = 1e1 … 1e8, rtol 1e-3
/// … 1e-12, three settled cycles) period errors of the same size, −5 … +30 % right-hand sides
/// and −21 … +14 % factorisations, and no wrong cycle (the harmonic sequence, at rtol 1e-12
/// and γ = 1e3, let the explicit scheme take one step in a stick that put that cycle's period
/// off by 8e-4). Costs: on non-stiff problems forced onto the linearly implicit scheme its
/// dense output is 3–4× less accurate (tests/extrapolation.rs).
const DEFAULT_FIRST: usize = 2;
/// SEULEX's dense-output parameter λ.
const DENSE_LAMBDA: usize = 1;
/// ODEX's MUDIF: the dense output's degree is 2k_c + 4 − MUDIF.
const MUDIF: usize = 4;

/// Which scheme is in use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Extrapolated explicit modified midpoint rule (ODEX).
    Explicit,
    /// Extrapolated linearly implicit Euler method (SEULEX).
    Implicit,
}

/// One scheme's step-number sequence, work model and control parameters (1-based arrays).
#[derive(Debug, Clone)]
struct Control {
    km: usize,
    nj: Vec<f64>,
    /// off[j] = n_1 + … + n_{j−1}: where row j's per-substep values are stored.
    off: Vec<usize>,
    a: Vec<f64>,
    fac1: f64,
    fac2: f64,
    fac3: f64,
    fac4: f64,
    safe1: f64,
    safe2: f64,
    /// Step reduction after a row failure.
    safe3: f64,
}

fn offsets(nj: &[f64]) -> Vec<usize> {
    let mut off = vec![0; nj.len() + 1];
    for j in 2..=nj.len() {
        off[j] = off[j - 1] + nj[j - 1] as usize;
    }
    off
}

/// The number of columns (at least 4, at most `km`) whose extrapolation amplifies roundoff
/// by less than rtol/u: Λ_k·u ≤ rtol, with Λ_k = Σ_i |c_i| the sum of the Aitken–Neville
/// weights of T_{k,k} in h_j = H/n_j (Λ_k = 3, 9, 28, …, 1.3e5 at k = 11 for the harmonic
/// sequence; 5, 19, 68, …, 4.1e5 for 2, 3, 4, …). Beyond it the error estimate is roundoff,
/// and SEULEX's control, asking for ever smaller steps, ends in a step underflow (measured
/// with 2, 3, 4, … at rtol 1e-12 on the DRR model at γ = 1e3 and 1e8).
fn roundoff_columns(nj: &[f64], km: usize, rtol: f64) -> usize {
    let amplification = |k: usize| -> f64 {
        (1..=k)
            .map(|i| (1..=k).filter(|&l| l != i).map(|l| (1.0 / nj[l]) / (1.0 / nj[l] - 1.0 / nj[i])).product::<f64>().abs())
            .sum()
    };
    let mut k = km.min(4);
    while k < km && amplification(k + 1) * UROUND <= rtol {
        k += 1;
    }
    k
}

impl Control {
    /// SEULEX with the sequence n_j = first + j − 1 (first = 1: the harmonic sequence, its
    /// NSEQU = 3; first = 2: its NSEQU = 4), arrays for `km` columns, and the columns in use
    /// limited to those whose roundoff stays below `rtol` (see [`roundoff_columns`]).
    fn seulex(km: usize, first: usize, rtol: f64) -> Self {
        let nj: Vec<f64> = (0..=km).map(|j| if j == 0 { 0.0 } else { (first + j - 1) as f64 }).collect();
        let mut a = vec![0.0; km + 1];
        a[1] = WK_JAC + nj[1] * WK_ROW + WK_DEC;
        for j in 2..=km {
            a[j] = a[j - 1] + (nj[j] - 1.0) * WK_ROW + WK_DEC;
        }
        let off = offsets(&nj);
        let km = roundoff_columns(&nj, km, rtol);
        Self { km, nj, off, a, fac1: 0.1, fac2: 4.0, fac3: 0.7, fac4: 0.9, safe1: 0.6, safe2: 0.93, safe3: 0.5 }
    }

    /// ODEX with the sequence 2, 6, 10, … (its NSEQU = 3, required by its dense output).
    fn odex(km: usize) -> Self {
        let nj: Vec<f64> = (0..=km).map(|j| if j == 0 { 0.0 } else { 4.0 * j as f64 - 2.0 }).collect();
        let mut a = vec![0.0; km + 1];
        a[1] = 1.0 + nj[1];
        for j in 2..=km {
            a[j] = a[j - 1] + nj[j];
        }
        let off = offsets(&nj);
        Self { km, nj, off, a, fac1: 0.02, fac2: 4.0, fac3: 0.8, fac4: 0.9, safe1: 0.65, safe2: 0.94, safe3: 0.5 }
    }
}

/// Why a tableau row was stopped (SEULEX/ODEX's ATOV): the step is retried with a smaller H.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Failure {
    /// The stability check failed, or the row's values are not finite.
    Unstable,
    /// The error estimate did not decrease along the row.
    ErrorGrowth,
    /// The right-hand side returned a non-finite value.
    NonFinite,
    /// The iteration matrix I/h_j − J is singular.
    Singular,
}

/// Work arrays, allocated once.
#[derive(Debug, Clone)]
struct Work {
    /// The extrapolation tableau (rows 1..=km, row 0 unused); t[1] ends as T_{j,j}.
    t: Vec<Vec<f64>>,
    yh1: Vec<f64>,
    yh2: Vec<f64>,
    dy: Vec<f64>,
    del: Vec<f64>,
    tmp: Vec<f64>,
    fnew: Vec<f64>,
    /// The previous explicit row's unsmoothed end value and f there (stiffness estimate).
    prev_raw: Vec<f64>,
    prev_fend: Vec<f64>,
    /// The linearly implicit rows' increments: row j, step i at j(j−1)/2 + i.
    incr: Vec<Vec<f64>>,
    /// The midpoint rows' f-values f_1..f_{n_j} (row j from Σ_{i<j} n_i) and their values at
    /// the step's midpoint (ODEX's FSAFE and YSAFE).
    fsafe: Vec<Vec<f64>>,
    ysafe: Vec<Vec<f64>>,
    /// Aitken–Neville scratch for the dense-output derivatives.
    nev: Vec<Vec<f64>>,
    /// Jacobian (column-major), LU factors of I/h_j − J and pivots.
    jac: Vec<f64>,
    lu: Vec<f64>,
    ip: Vec<usize>,
    /// Continuous output of the last step. After an implicit step: Σ poly[l]·u^l with
    /// u = (t − x)/hold ∈ [−1, 0]. After an explicit one, ODEX's form: poly[0..4] = y_old,
    /// y_new − y_old and the Hermite coefficients, poly[4 + m] = a_m of the correction.
    poly: Vec<Vec<f64>>,
    /// An explicit step's continuous output before the step is accepted.
    poly_next: Vec<Vec<f64>>,
}

impl Work {
    fn new(n: usize, km: usize, incr: usize, fsafe: usize, dense_len: usize) -> Self {
        let v = || vec![0.0; n];
        Self {
            t: (0..=km).map(|_| v()).collect(),
            yh1: v(),
            yh2: v(),
            dy: v(),
            del: v(),
            tmp: v(),
            fnew: v(),
            prev_raw: v(),
            prev_fend: v(),
            incr: (0..incr).map(|_| v()).collect(),
            fsafe: (0..fsafe).map(|_| v()).collect(),
            ysafe: (0..=km).map(|_| v()).collect(),
            nev: (0..=km).map(|_| v()).collect(),
            jac: vec![0.0; n * n],
            lu: vec![0.0; n * n],
            ip: vec![0; n],
            poly: (0..dense_len).map(|_| v()).collect(),
            poly_next: (0..dense_len).map(|_| v()).collect(),
        }
    }
}

/// Extrapolation with stiffness switching on the system `S`: the linearly implicit Euler
/// extrapolation of SEULEX (stiff) and the Gragg–Bulirsch–Stoer modified-midpoint extrapolation
/// of ODEX (non-stiff), with their order and step-size controls, and a documented switching rule
/// (see the module documentation) — the pair behind Mathematica's "StiffnessSwitching".
///
/// Implements [`Integrator`]: `dense(t, k)` for k = 0..3 on the last step (SEULEX's
/// continuous output of degree k_c after an implicit step, ODEX's of degree 2k_c + 1 after an
/// explicit one), `reinit` restarts with the scheme in use and fresh step-size history and
/// keeps the statistics and the switch count. Options: `rtol`/`atol` (used as given, as in
/// SEULEX/ODEX), `max_steps` (per call, default [`DEFAULT_MAX_STEPS`](super::DEFAULT_MAX_STEPS)),
/// `max_order` (4 to 12: caps the tableau at max_order rows for the linearly implicit scheme and
/// max(4, ⌈max_order/2⌉) for the midpoint one), `initial_step`, `min_step`, `max_step`,
/// `stop_time` (not stepped past; disabled once reached), `max_err_test_fails` (consecutive
/// rejections in one step, default 50), `max_conv_fails` (rows stopped by the stability checks in
/// one step, default 50), `fail_on_step_underflow`. `max_nonlin_iters` and `nonlin_conv_coef`
/// are InvalidInput errors (no Newton iteration), as is a `max_order` outside 4..=12.
pub struct Extrapolation<S: OdeSystem> {
    system: S,
    n: usize,
    rtol: f64,
    atol: Vec<f64>,
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
    /// Explicit attempt's eigenvalue estimate.
    rho: f64,
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
    /// Point, last step, returned state, step-sequence options and statistics.
    core: Core,
    work: Work,
}

impl<S: OdeSystem> std::fmt::Debug for Extrapolation<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Extrapolation")
            .field("n", &self.n)
            .field("t", &self.core.t_out)
            .field("t_internal", &self.core.x)
            .field("stiff", &(self.mode == Mode::Implicit))
            .field("switches", &self.switches)
            .finish()
    }
}


/// Weighted Euclidean norm ‖v/scal‖₂ (SEULEX's stability check).
fn norm2(v: &[f64], scal: &[f64]) -> f64 {
    v.iter().zip(scal).map(|(a, s)| (a / s) * (a / s)).sum::<f64>().sqrt()
}

/// The stability function T_{k,k}(z) of the extrapolated modified midpoint rule with smoothing
/// (sequence `nj`, 1-based) applied to y' = λy, z = Hλ.
fn midpoint_stability(nj: &[f64], k: usize, z: f64) -> f64 {
    let mut t = vec![0.0; k + 1];
    for j in 1..=k {
        let zj = z / nj[j];
        let (mut y1, mut y2) = (1.0, 1.0 + zj);
        for _ in 1..nj[j] as usize {
            let ys = y1;
            y1 = y2;
            y2 = ys + 2.0 * zj * y2;
        }
        t[j] = 0.5 * (y1 + y2 + zj * y2);
        for l in (2..=j).rev() {
            let r = nj[j] / nj[l - 1];
            t[l - 1] = t[l] + (t[l] - t[l - 1]) / (r * r - 1.0);
        }
    }
    t[1]
}

/// The linear stability boundary of T_{k,k} on the negative real axis: the first z < 0 where
/// |R(z)| exceeds 1 (scanned in steps of 0.01, then bisected).
/// The linear stability boundaries of the explicit T_{k,k}, k = 1..=KM_EXPLICIT (index 0
/// unused), of ODEX's step-number sequence: a constant of the method, computed on first use
/// (a scan of about a millisecond) and shared by every integrator.
fn stability_boundaries() -> &'static [f64] {
    static BOUNDARIES: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    BOUNDARIES.get_or_init(|| {
        let nj = Control::odex(KM_EXPLICIT).nj;
        (0..=KM_EXPLICIT).map(|k| if k == 0 { 0.0 } else { stability_boundary(&nj, k) }).collect()
    })
}

fn stability_boundary(nj: &[f64], k: usize) -> f64 {
    let stable = |z: f64| midpoint_stability(nj, k, z).abs() <= 1.0;
    let mut z = 0.0;
    while z > -200.0 && stable(z - 0.01) {
        z -= 0.01;
    }
    let (mut inside, mut outside) = (z, z - 0.01);
    for _ in 0..40 {
        let mid = 0.5 * (inside + outside);
        if stable(mid) {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    -inside
}

/// min(‖J‖₁, ‖J‖_∞) of the column-major `jac`, unscaled and scaled as D⁻¹JD with D = diag(scal):
/// each an upper bound of the spectral radius.
fn jacobian_bound(jac: &[f64], scal: &[f64], n: usize) -> f64 {
    let mut best = f64::INFINITY;
    for scaled in [false, true] {
        let entry = |i: usize, j: usize| {
            let v = jac[j * n + i].abs();
            if scaled {
                v * scal[j] / scal[i]
            } else {
                v
            }
        };
        let inf = (0..n).map(|i| (0..n).map(|j| entry(i, j)).sum::<f64>()).fold(0.0, f64::max);
        let one = (0..n).map(|j| (0..n).map(|i| entry(i, j)).sum::<f64>()).fold(0.0, f64::max);
        best = best.min(inf).min(one);
    }
    if best.is_nan() {
        f64::INFINITY
    } else {
        best
    }
}

fn factorial(l: usize) -> f64 {
    (1..=l).map(|i| i as f64).product()
}

impl<S: OdeSystem> Extrapolation<S> {
    /// An extrapolation integrator of `system` starting at (t0, y0) with the explicit scheme.
    /// Errors (InvalidInput): a system without components, y0 of the wrong length or
    /// non-finite, non-finite t0, invalid options.
    pub fn new(system: S, t0: f64, y0: &[f64], options: &Options) -> Result<Self, SolverError> {
        let n = system.dim();
        let core = Core::new(NAME, n, t0, y0, options, Stats::default())?;
        let no_newton = "linearly implicit extrapolation has no Newton iteration";
        core.reject_unsupported(&[
            ("max_nonlin_iters", options.max_nonlin_iters.is_some(), no_newton),
            ("nonlin_conv_coef", options.nonlin_conv_coef.is_some(), no_newton),
            ("jacobian_max_age", options.jacobian_max_age.is_some(), "the Jacobian is reused by the stability-check ratio"),
        ])?;
        let atol: Vec<f64> = match &options.atol {
            Tolerance::Scalar(a) => vec![*a; n],
            Tolerance::PerComponent(v) => v.clone(),
        };
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
            rtol: options.rtol,
            atol,
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
            rho: 0.0,
            history: 0,
            switches: 0,
            degree: 0,
            dense_odex: false,
            kmit: -1,
            kmit_next: -1,
            hoptde: f64::INFINITY,
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
        self.imp = Control::seulex(km, first, self.rtol);
        let need = self.imp.off[km + 1];
        let n = self.n;
        self.work.incr.resize_with(need, || vec![0.0; n]);
        let mode = self.mode;
        self.enter(mode);
        self
    }

    /// The system being integrated.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// Number of switches between the schemes so far (over the integrator's whole life).
    pub fn switches(&self) -> u64 {
        self.switches
    }

    /// Whether the linearly implicit (stiff) scheme is in use.
    pub fn is_stiff(&self) -> bool {
        self.mode == Mode::Implicit
    }

    fn control(&self) -> &Control {
        match self.mode {
            Mode::Explicit => &self.exp,
            Mode::Implicit => &self.imp,
        }
    }

    /// SEULEX's and ODEX's starting column for the tolerance.
    fn initial_k(&self, mode: Mode) -> usize {
        let tol = match mode {
            Mode::Explicit => self.rtol,
            Mode::Implicit => self.rtol + self.atol[0],
        };
        let guess = (-tol.log10() * 0.6 + 1.5).floor().max(0.0) as usize;
        match mode {
            Mode::Explicit => guess.min(self.exp.km - 1).max(3),
            Mode::Implicit => guess.min(self.imp.km - 2).max(3),
        }
    }

    /// Starts `mode` afresh: its starting column, the first-step procedure, no history.
    fn enter(&mut self, mode: Mode) {
        self.mode = mode;
        self.k = self.initial_k(mode);
        self.first = true;
        self.core.reject = false;
        self.history = 0;
        self.theta = 2.0 * self.thet;
        self.caljac = false;
        self.hoptde = f64::INFINITY;
        self.w[1] = if mode == Mode::Implicit { 1e30 } else { 0.0 };
    }

    /// Records one stiffness-test outcome; true when a switch is due.
    fn record(&mut self, asks_switch: bool) -> bool {
        self.history = ((self.history << 1) | asks_switch as u32) & ((1 << WINDOW) - 1);
        self.history.count_ones() >= REPEATS
    }

    fn switch_to(&mut self, mode: Mode) {
        self.switches += 1;
        self.enter(mode);
    }

    /// The explicit → implicit test after an explicit attempt of size `h_used`.
    fn stiffness_test(&mut self, h_used: f64, unstable: bool) {
        if self.forced.is_some() || self.mode != Mode::Explicit {
            return;
        }
        let k = self.last_row.clamp(1, self.exp.km);
        let stiff = unstable || h_used.abs() * self.rho > STIFF_FRACTION * self.lsb[k];
        if self.record(stiff) {
            self.switch_to(Mode::Implicit);
        }
    }

    /// The implicit → explicit test after an implicit step of size `h_used` accepted in column
    /// kc: H_acc, the step the column's error estimate asks for without SEULEX's growth
    /// limits, against the explicit scheme's stability bound.
    fn nonstiffness_test(&mut self, h_used: f64, kc: usize) {
        if self.forced.is_some() || self.mode != Mode::Implicit {
            return;
        }
        let ke = self.initial_k(Mode::Explicit);
        let ctl = &self.imp;
        let fac = (self.err / ctl.safe1).powf(1.0 / kc as f64) / ctl.safe2;
        let h_acc = (h_used.abs() / fac).min(self.core.hmax);
        let nonstiff = h_acc * self.rho_jac <= NONSTIFF_FRACTION * self.lsb[ke];
        if self.record(nonstiff) {
            self.switch_to(Mode::Explicit);
        }
    }

    fn update_scal(&mut self) {
        for i in 0..self.n {
            let s = self.atol[i] + self.rtol * self.core.y[i].abs();
            self.scal[i] = if s > 0.0 { s } else { f64::MIN_POSITIVE };
        }
    }

    /// Hairer–Wanner's initial step (Solving ODEs I, II.4) for an order-5 error, measured with
    /// the scaled norm of the step-size control.
    fn estimate_initial_step(&mut self, bound: f64) -> f64 {
        let d0 = rms(&self.core.y, &self.scal);
        let d1 = rms(&self.core.f0, &self.scal);
        let mut h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        if !(h0.is_finite() && h0 > 0.0) {
            // Degenerate weights (atol = 0 on a zero component): SEULEX's default.
            h0 = 1e-6;
        }
        h0 = h0.min(bound).max(100.0 * UROUND * self.core.x.abs()).max(f64::MIN_POSITIVE);
        let mut d2 = None;
        for _ in 0..12 {
            let th = self.core.posneg * h0;
            for i in 0..self.n {
                self.work.tmp[i] = self.core.y[i] + th * self.core.f0[i];
            }
            self.system.rhs(self.core.x + th, &self.work.tmp, &mut self.work.fnew);
            self.core.stats.rhs_evals += 1;
            if all_finite(&self.work.fnew) {
                for i in 0..self.n {
                    self.work.tmp[i] = self.work.fnew[i] - self.core.f0[i];
                }
                d2 = Some(rms(&self.work.tmp, &self.scal) / h0);
                break;
            }
            self.core.stats.nonfinite_rhs += 1;
            h0 *= 0.1;
        }
        let Some(d2) = d2.filter(|d| d.is_finite()) else { return h0 };
        let dm = d1.max(d2);
        let h1 = if dm <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / dm).powf(1.0 / 6.0) };
        let h = (100.0 * h0).min(h1).min(bound);
        if h.is_finite() && h > 0.0 {
            h
        } else {
            h0
        }
    }

    /// Jacobian at (x, y) into `work.jac`: analytic, or forward differences (SEULEX's increments
    /// √(u·max(1e-5, |y_i|))). False if not finite.
    fn compute_jacobian(&mut self) -> bool {
        let n = self.n;
        self.core.stats.jac_evals += 1;
        let w = &mut self.work;
        if self.system.has_jacobian() {
            w.jac.iter_mut().for_each(|v| *v = 0.0);
            let mut m = JacobianMatrix::new(&mut w.jac, n);
            self.system.jacobian(self.core.x, &self.core.y, &mut m);
        } else {
            w.tmp.copy_from_slice(&self.core.y);
            for j in 0..n {
                let ysafe = w.tmp[j];
                let delt = (UROUND * ysafe.abs().max(1e-5)).sqrt();
                w.tmp[j] = ysafe + delt;
                let delt = w.tmp[j] - ysafe;
                self.system.rhs(self.core.x, &w.tmp, &mut w.fnew);
                self.core.stats.rhs_evals_jacobian += 1;
                for i in 0..n {
                    w.jac[j * n + i] = (w.fnew[i] - self.core.f0[i]) / delt;
                }
                w.tmp[j] = ysafe;
            }
        }
        let ok = all_finite(&w.jac);
        self.rho_jac = if ok { jacobian_bound(&w.jac, &self.scal, n) } else { f64::INFINITY };
        ok
    }

    /// Row j of the linearly implicit Euler tableau (SEULEX's SEUL).
    fn row_implicit(&mut self, j: usize) -> Result<(), Failure> {
        let n = self.n;
        let m = self.imp.nj[j] as usize;
        let hj = self.core.h / self.imp.nj[j];
        let hji = 1.0 / hj;
        let w = &mut self.work;
        for (e, a) in w.lu.iter_mut().zip(&w.jac) {
            *e = -a;
        }
        for i in 0..n {
            w.lu[i * n + i] += hji;
        }
        self.core.stats.lin_setups += 1;
        if !lu_real(&mut w.lu, &mut w.ip, n) {
            return Err(Failure::Singular);
        }
        self.system.rhs(self.core.x + hj, &self.core.y, &mut w.dy);
        self.core.stats.rhs_evals += 1;
        if !all_finite(&w.dy) {
            self.core.stats.nonfinite_rhs += 1;
            return Err(Failure::NonFinite);
        }
        w.yh1.copy_from_slice(&self.core.y);
        w.del.copy_from_slice(&w.dy);
        // Refined solves keep the linear invariants of f (see `solve_refined`).
        solve_refined(&w.lu, &w.ip, &w.jac, hji, &w.dy, &mut w.del, &mut w.fnew);
        let base = self.imp.off[j];
        w.incr[base].copy_from_slice(&w.del);
        for mm in 1..m {
            for i in 0..n {
                w.yh1[i] += w.del[i];
            }
            self.system.rhs(self.core.x + hj * (mm + 1) as f64, &w.yh1, &mut w.dy);
            self.core.stats.rhs_evals += 1;
            if !all_finite(&w.dy) {
                self.core.stats.nonfinite_rhs += 1;
                return Err(Failure::NonFinite);
            }
            if mm == 1 && j <= 2 && self.fixed.is_none() {
                // Stability check: one Newton correction of the implicit Euler step.
                let del1 = norm2(&w.del, &self.scal);
                for i in 0..n {
                    w.tmp[i] = w.dy[i] - w.del[i] * hji;
                }
                solve_real(&w.lu, &w.ip, n, &mut w.tmp);
                let del2 = norm2(&w.tmp, &self.scal);
                self.theta = del2 / del1.max(1.0);
                let stable = self.theta <= 1.0;
                if !stable {
                    return Err(Failure::Unstable);
                }
            }
            w.del.copy_from_slice(&w.dy);
            solve_refined(&w.lu, &w.ip, &w.jac, hji, &w.dy, &mut w.del, &mut w.fnew);
            w.incr[base + mm].copy_from_slice(&w.del);
        }
        for i in 0..n {
            w.t[j][i] = w.yh1[i] + w.del[i];
        }
        if !all_finite(&w.t[j]) {
            return Err(Failure::Unstable);
        }
        self.extrapolate(j)
    }

    /// Row j of the modified midpoint tableau (ODEX's MIDEX).
    fn row_explicit(&mut self, j: usize) -> Result<(), Failure> {
        let n = self.n;
        let m = self.exp.nj[j] as usize;
        let hj = self.core.h / self.exp.nj[j];
        let w = &mut self.work;
        for i in 0..n {
            w.yh1[i] = self.core.y[i];
            w.yh2[i] = self.core.y[i] + hj * self.core.f0[i];
        }
        let (mid, off) = (m / 2, self.exp.off[j]);
        for mm in 1..m {
            if mm == mid {
                w.ysafe[j].copy_from_slice(&w.yh2);
            }
            self.system.rhs(self.core.x + hj * mm as f64, &w.yh2, &mut w.dy);
            self.core.stats.rhs_evals += 1;
            if !all_finite(&w.dy) {
                self.core.stats.nonfinite_rhs += 1;
                return Err(Failure::NonFinite);
            }
            w.fsafe[off + mm - 1].copy_from_slice(&w.dy);
            for i in 0..n {
                let ys = w.yh1[i];
                w.yh1[i] = w.yh2[i];
                w.yh2[i] = ys + 2.0 * hj * w.dy[i];
            }
            if mm == 1 && j <= 2 && self.fixed.is_none() {
                // Stability check.
                let (mut del1, mut del2) = (0.0, 0.0);
                for i in 0..n {
                    let s = self.scal[i];
                    del1 += (self.core.f0[i] / s).powi(2);
                    del2 += ((w.dy[i] - self.core.f0[i]) / s).powi(2);
                }
                // ODEX's ‖f(y0 + h_j f0) − f0‖ > 2‖f0‖, with the increments h_j·f floored at
                // the tolerance scale (as SEULEX's max(1, ‖Δ0‖)): f0 = 0 is no instability.
                let h2 = hj * hj;
                let stable = h2 * del2 <= 4.0 * (h2 * del1).max(1.0);
                if !stable {
                    return Err(Failure::Unstable);
                }
            }
        }
        self.system.rhs(self.core.x + self.core.h, &w.yh2, &mut w.dy);
        self.core.stats.rhs_evals += 1;
        if !all_finite(&w.dy) {
            self.core.stats.nonfinite_rhs += 1;
            return Err(Failure::NonFinite);
        }
        w.fsafe[off + m - 1].copy_from_slice(&w.dy);
        for i in 0..n {
            w.t[j][i] = 0.5 * (w.yh1[i] + w.yh2[i] + hj * w.dy[i]);
        }
        if !all_finite(&w.t[j]) {
            return Err(Failure::Unstable);
        }
        // Stiffness estimate from the unsmoothed end values of consecutive rows.
        if j > 1 {
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                let s = self.scal[i];
                num += ((w.dy[i] - w.prev_fend[i]) / s).powi(2);
                den += ((w.yh2[i] - w.prev_raw[i]) / s).powi(2);
            }
            if den > 0.0 && num.is_finite() {
                self.rho = self.rho.max((num / den).sqrt());
            }
        }
        w.prev_raw.copy_from_slice(&w.yh2);
        w.prev_fend.copy_from_slice(&w.dy);
        self.extrapolate(j)
    }

    /// Aitken–Neville on the new row j, the error estimate, the optimal step and work of
    /// column j.
    fn extrapolate(&mut self, j: usize) -> Result<(), Failure> {
        self.last_row = j;
        if j == 1 {
            return Ok(());
        }
        let n = self.n;
        let explicit = self.mode == Mode::Explicit;
        let ctl = if explicit { &self.exp } else { &self.imp };
        let w = &mut self.work;
        for l in (2..=j).rev() {
            let r = ctl.nj[j] / ctl.nj[l - 1];
            let fac = if explicit { r * r - 1.0 } else { r - 1.0 };
            let (lo, hi) = w.t.split_at_mut(l);
            let (prev, cur) = (&mut lo[l - 1], &hi[0]);
            for i in 0..n {
                prev[i] = cur[i] + (cur[i] - prev[i]) / fac;
            }
        }
        let mut sum = 0.0;
        for i in 0..n {
            let d = (w.t[1][i] - w.t[2][i]).abs();
            if explicit {
                // ODEX's weights: atol + rtol·max(|y0|, |y1|).
                let s = self.atol[i] + self.rtol * self.core.y[i].abs().max(w.t[1][i].abs());
                self.scal[i] = if s > 0.0 { s } else { f64::MIN_POSITIVE };
                sum += (d / self.scal[i]).powi(2);
            } else {
                sum += (d / self.scal[i]).min(1e15).powi(2);
            }
        }
        let err = (sum / n as f64).sqrt();
        if !err.is_finite() || err * UROUND >= 1.0 {
            return Err(Failure::Unstable);
        }
        if j > 2 && err >= self.errold && self.fixed.is_none() {
            return Err(Failure::ErrorGrowth);
        }
        self.errold = (4.0 * err).max(1.0);
        self.err = err;
        let expo = if explicit { 1.0 / (2 * j - 1) as f64 } else { 1.0 / j as f64 };
        let facmin = ctl.fac1.powf(expo);
        let fac = (ctl.fac2 / facmin).min(facmin.max((err / ctl.safe1).powf(expo) / ctl.safe2));
        self.hh[j] = (self.core.h.abs() / fac).min(self.core.hmax);
        self.w[j] = ctl.a[j] / self.hh[j];
        Ok(())
    }

    fn row(&mut self, j: usize) -> Result<(), Failure> {
        match self.mode {
            Mode::Explicit => self.row_explicit(j),
            Mode::Implicit => self.row_implicit(j),
        }
    }

    /// The convergence monitor's bounds: reject early when the error in column k−1 exceeds
    /// `early`, or that in column k exceeds `late` (no hope for convergence in column k+1).
    fn monitor_bounds(&self, k: usize) -> (f64, f64) {
        match self.mode {
            Mode::Implicit => {
                let nj = &self.imp.nj;
                (nj[k + 1] * nj[k] * 4.0, nj[k + 1] * 2.0)
            }
            Mode::Explicit => {
                let nj = &self.exp.nj;
                (((nj[k + 1] * nj[k]) / 4.0).powi(2), (nj[k + 1] / 2.0).powi(2))
            }
        }
    }

    /// A step rejected by the error test after column `kc` (SEULEX/ODEX's label 100).
    fn rejected(&mut self, kc: usize) -> Option<usize> {
        let fac3 = self.control().fac3;
        let mut k = self.k.min(kc);
        if k > 2 && self.w[k - 1] < self.w[k] * fac3 {
            k -= 1;
        }
        self.k = k;
        self.core.h = self.core.posneg * self.hh[k];
        self.core.reject = true;
        None
    }

    /// One step attempt with the convergence monitor: Some(k_c) accepted in column k_c, None
    /// rejected by the error test (h and k set for the retry).
    fn attempt(&mut self, first: bool) -> Result<Option<usize>, Failure> {
        let k = self.k;
        if let Some((_, kf)) = self.fixed {
            for j in 1..=kf {
                self.row(j)?;
            }
            return Ok(Some(kf));
        }
        let (early, late) = self.monitor_bounds(k);
        if first {
            for j in 1..=k {
                self.row(j)?;
                if j > 1 && self.err <= 1.0 {
                    return Ok(Some(j));
                }
            }
        } else {
            for j in 1..k {
                self.row(j)?;
            }
            if !(k == 2 || self.core.reject) {
                if self.err <= 1.0 {
                    return Ok(Some(k - 1));
                }
                if self.err > early {
                    return Ok(self.rejected(k - 1));
                }
            }
            self.row(k)?;
            if self.err <= 1.0 {
                return Ok(Some(k));
            }
        }
        // Hope for convergence in column k + 1.
        if self.err > late {
            return Ok(self.rejected(k));
        }
        self.row(k + 1)?;
        if self.err > 1.0 {
            return Ok(self.rejected(k + 1));
        }
        Ok(Some(k + 1))
    }

    /// The order and step size after a step accepted in column kc (SEULEX/ODEX after label 60).
    fn select(&mut self, kc: usize) {
        let ctl = match self.mode {
            Mode::Explicit => &self.exp,
            Mode::Implicit => &self.imp,
        };
        let (km, fac3, fac4) = (ctl.km, ctl.fac3, ctl.fac4);
        let (a, w, hh, k) = (&ctl.a, &self.w, &self.hh, self.k);
        let kopt = if kc == 2 {
            if self.core.reject {
                2
            } else {
                3
            }
        } else if kc <= k {
            let mut ko = kc;
            if w[kc - 1] < w[kc] * fac3 {
                ko = kc - 1;
            }
            if w[kc] < w[kc - 1] * fac4 {
                ko = (kc + 1).min(km - 1);
            }
            ko
        } else {
            let mut ko = kc - 1;
            if kc > 3 && w[kc - 2] < w[kc - 1] * fac3 {
                ko = kc - 2;
            }
            if w[kc] < w[ko] * fac4 {
                ko = kc.min(km - 1);
            }
            ko
        };
        let (knew, habs) = if self.core.reject {
            // After a rejection: no increase of the order or the step.
            let kn = kopt.min(kc);
            (kn, self.core.h.abs().min(hh[kn]))
        } else if kopt <= kc {
            (kopt, hh[kopt])
        } else if kc < k && w[kc] < w[kc - 1] * fac4 {
            (kopt, hh[kc] * a[kopt + 1] / a[kc])
        } else {
            (kopt, hh[kc] * a[kopt] / a[kc])
        };
        self.k = knew;
        self.core.reject = false;
        let habs = if self.mode == Mode::Explicit { habs.min(self.hoptde) } else { habs };
        self.core.h = self.core.posneg * habs.min(self.core.hmax).max(self.core.hmin);
    }

    /// SEULEX's continuous output after an implicit step accepted in column kc (before y is
    /// replaced): derivatives at the right end from backward differences of the increments,
    /// extrapolated, and the polynomial of degree kc through y_old and y_new.
    #[allow(clippy::needless_range_loop)]
    fn dense_implicit(&mut self, kc: usize) {
        let n = self.n;
        let lambda = DENSE_LAMBDA;
        let nj = &self.imp.nj;
        let w = &mut self.work;
        w.poly[0].copy_from_slice(&w.t[1]);
        for l in 1..kc {
            let scale = 1.0 / factorial(l);
            let low = l + lambda;
            if low > kc {
                w.poly[l].iter_mut().for_each(|v| *v = 0.0);
                continue;
            }
            for kk in low..=kc {
                let (base, nk) = (self.imp.off[kk], nj[kk] as usize);
                let factor = nj[kk].powi(l as i32) * scale;
                for i in 0..n {
                    // The (l−1)-th backward difference of row kk's last increments.
                    let (mut s, mut binom) = (0.0, 1.0);
                    for m in 0..l {
                        let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
                        s += sign * binom * w.incr[base + nk - 1 - m][i];
                        binom = binom * (l - 1 - m) as f64 / (m + 1) as f64;
                    }
                    w.nev[kk][i] = s * factor;
                }
            }
            for jj in low + 1..=kc {
                for ll in (low + 1..=jj).rev() {
                    let fac = nj[jj] / nj[ll - 1] - 1.0;
                    let (lo, hi) = w.nev.split_at_mut(ll);
                    let (prev, cur) = (&mut lo[ll - 1], &hi[0]);
                    for i in 0..n {
                        prev[i] = cur[i] + (cur[i] - prev[i]) / fac;
                    }
                }
            }
            w.poly[l].copy_from_slice(&w.nev[low]);
        }
        // The top coefficient from P(−1) = y_old.
        let top_sign = if kc.is_multiple_of(2) { 1.0 } else { -1.0 };
        for i in 0..n {
            let mut s = 0.0;
            let mut sign = 1.0;
            for l in 0..kc {
                s += sign * w.poly[l][i];
                sign = -sign;
            }
            w.poly[kc][i] = top_sign * (self.core.y[i] - s);
        }
        self.degree = kc;
    }

    /// ODEX's continuous output of an explicit step converged in column kc (into `poly_next`,
    /// taken over by `accept`): the cubic Hermite interpolant of the end values and derivatives
    /// plus (θ(1−θ))²·Q(θ − ½), Q matching the solution and its first kmit = 2kc − 3
    /// derivatives at the midpoint, which are extrapolated from the rows' midpoint values and
    /// central differences of their f-values. Returns ODEX's error estimate of the interpolant.
    #[allow(clippy::needless_range_loop)]
    fn dense_explicit(&mut self, kc: usize) -> f64 {
        let n = self.n;
        let h = self.core.h;
        let nj = &self.exp.nj;
        let kmit = 2 * kc as isize - MUDIF as isize + 1;
        let w = &mut self.work;
        // Hermite part: y0, y1 − y0, aspl, bspl.
        for i in 0..n {
            let (y0, y1, yp0, yp1) = (self.core.y[i], w.t[1][i], h * self.core.f0[i], h * w.fnew[i]);
            let ydiff = y1 - y0;
            w.poly_next[0][i] = y0;
            w.poly_next[1][i] = ydiff;
            w.poly_next[2][i] = -yp1 + ydiff;
            w.poly_next[3][i] = yp0 - ydiff;
        }
        self.kmit_next = kmit;
        if kmit < 0 {
            return 0.0;
        }
        let kmit = kmit as usize;
        let extrapolate = |nev: &mut [Vec<f64>], from: usize| {
            for j in from + 1..=kc {
                for l in (from + 1..=j).rev() {
                    let r = nj[j] / nj[l - 1];
                    let fac = r * r - 1.0;
                    let (lo, hi) = nev.split_at_mut(l);
                    let (prev, cur) = (&mut lo[l - 1], &hi[0]);
                    for i in 0..n {
                        prev[i] = cur[i] + (cur[i] - prev[i]) / fac;
                    }
                }
            }
        };
        // Derivatives at the midpoint in θ: D_0 = y(mid), D_m = H^m y^(m)(mid), into
        // poly_next[4 + m], then turned into the correction's coefficients a_m.
        let offsets = &self.exp.off;
        for kmi in 0..=kmit {
            let kbeg = kmi.div_ceil(2).max(1);
            for kk in kbeg..=kc {
                if kmi == 0 {
                    w.nev[kk].copy_from_slice(&w.ysafe[kk]);
                    continue;
                }
                // Central difference of order d = kmi − 1, spacing 2, centred at the midpoint
                // index m = n/2: Σ_r (−1)^r C(d, r) f_{m + d − 2r} (f_0 = f(x, y)).
                let d = kmi - 1;
                let m = nj[kk] as usize / 2;
                let facnj = (nj[kk] / 2.0).powi(d as i32) * h;
                for i in 0..n {
                    let (mut s, mut binom) = (0.0, 1.0);
                    for r in 0..=d {
                        let idx = m + d - 2 * r;
                        let f = if idx == 0 { self.core.f0[i] } else { w.fsafe[offsets[kk] + idx - 1][i] };
                        s += if r % 2 == 0 { binom * f } else { -binom * f };
                        binom = binom * (d - r) as f64 / (r + 1) as f64;
                    }
                    w.nev[kk][i] = s * facnj;
                }
            }
            extrapolate(&mut w.nev, kbeg);
            w.poly_next[4 + kmi].copy_from_slice(&w.nev[kbeg]);
        }
        // ODEX's INTERP: a_m from the midpoint derivatives minus the Hermite part's.
        for i in 0..n {
            let p = &w.poly_next;
            let (y0, ydiff, aspl, bspl) = (p[0][i], p[1][i], p[2][i], p[3][i]);
            // The Hermite part's θ-derivatives 0..3 at θ = ½.
            let ph = [
                y0 + 0.5 * ydiff + 0.125 * (aspl + bspl),
                ydiff + (aspl - bspl) * 0.25,
                -(aspl + bspl),
                6.0 * (bspl - aspl),
            ];
            let mut a = [0.0f64; 2 * KM_EXPLICIT + 2];
            for m in 0..=kmit {
                let dm = p[4 + m][i];
                let hermite = if m < 4 { ph[m] } else { 0.0 };
                let mf = m as f64;
                let fac1 = mf * (mf - 1.0) / 2.0;
                let fac2 = mf * (mf - 1.0) * (mf - 2.0) * (mf - 3.0);
                let mut v = dm - hermite;
                if m >= 2 {
                    v += fac1 * a[m - 2];
                }
                if m >= 4 {
                    v -= fac2 * a[m - 4];
                }
                a[m] = 16.0 * v;
            }
            for m in 0..=kmit {
                w.poly_next[4 + m][i] = a[m];
            }
        }
        // ODEX's error estimate of the interpolant.
        let mu = kmit as f64;
        let errx = (mu / (mu + 4.0)).sqrt() * 0.5;
        let errfac = (1..=kmit).fold(1.0 / ((mu + 4.0) * (mu + 4.0)), |p, j| p * errx / j as f64);
        let errint = rms(&w.poly_next[4 + kmit], &self.scal) * errfac;
        if errint.is_finite() {
            errint
        } else {
            f64::INFINITY
        }
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
        let (mut rejections, mut row_fails, mut nonfinite, mut singular, mut attempts) = (0u32, 0u32, 0u32, 0u32, 0u32);
        self.core.drop_passed_stop_time();
        loop {
            attempts += 1;
            if attempts > MAX_ATTEMPTS {
                let message = format!("{MAX_ATTEMPTS} failed attempts in one step (h = {:e})", self.core.h);
                return Err(self.core.error(ErrorKind::ConvergenceFailures, -5, message));
            }
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
            if (self.mode == Mode::Explicit || (need_jacobian && !self.system.has_jacobian())) && !self.ensure_f0() {
                return Err(self.core.error(
                    ErrorKind::RhsFailure,
                    -6,
                    "the right-hand side at the current point is not finite".into(),
                ));
            }
            if need_jacobian {
                if !self.compute_jacobian() {
                    return Err(self.core.error(ErrorKind::RhsFailure, -6, "the Jacobian is not finite".into()));
                }
                self.caljac = true;
            }
            self.core.stats.step_attempts += 1;
            self.rho = 0.0;
            self.last_row = 0;
            let first = std::mem::replace(&mut self.first, false);
            let h_used = self.core.h;
            let outcome = self.attempt(first);
            match outcome {
                Ok(Some(kc)) => {
                    let xph = if last { self.core.stop_time.unwrap_or(self.core.x + self.core.h) } else { self.core.x + self.core.h };
                    if self.mode == Mode::Explicit {
                        // f at the new point (continuous output, next step): a non-finite one
                        // fails the step.
                        let w = &mut self.work;
                        self.system.rhs(xph, &w.t[1], &mut w.fnew);
                        self.core.stats.rhs_evals += 1;
                        if !all_finite(&w.fnew) {
                            self.core.stats.nonfinite_rhs += 1;
                            self.core.nonfinite_failure(&mut nonfinite, self.fixed.is_some())?;
                            continue;
                        }
                        // ODEX: the interpolant's error estimate bounds the next step and
                        // rejects the step when above 10.
                        let errint = self.dense_explicit(kc);
                        let degree = (self.kmit_next + 4).max(1) as f64;
                        self.hoptde = h_used.abs() / errint.powf(1.0 / degree).max(0.01);
                        if errint > 10.0 && self.fixed.is_none() {
                            self.core.stats.err_test_fails += 1;
                            rejections += 1;
                            if rejections >= self.max_err_test_fails {
                                let message = format!(
                                    "{rejections} error-test failures in one step (dense output, h = {h_used:e})"
                                );
                                return Err(self.core.error(ErrorKind::ErrorTestFailures, -7, message));
                            }
                            let hnew = self.core.posneg * self.hoptde;
                            self.core.reduce(hnew, ErrorKind::ErrorTestFailures, -7, "dense-output error test")?;
                            continue;
                        }
                    }
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
                    if explicit {
                        self.stiffness_test(h_used, false);
                    } else {
                        self.nonstiffness_test(h_used, kc);
                    }
                    self.core.stats.current_step = self.core.h;
                    return Ok(last);
                }
                Ok(None) => {
                    self.core.stats.err_test_fails += 1;
                    rejections += 1;
                    if rejections >= self.max_err_test_fails {
                        let message = format!(
                            "{rejections} error-test failures in one step (h = {:e}, err = {:e})",
                            h_used, self.err
                        );
                        return Err(self.core.error(ErrorKind::ErrorTestFailures, -7, message));
                    }
                    let hnew = self.core.h;
                    self.core.h = h_used;
                    self.core.reduce(hnew, ErrorKind::ErrorTestFailures, -7, "error-test failure")?;
                    self.stiffness_test(h_used, false);
                }
                Err(failure) => {
                    if self.fixed.is_some() && failure != Failure::NonFinite {
                        let message = format!(
                            "row {} failed ({failure:?}) with the fixed step h = {:e}",
                            self.last_row + 1,
                            self.core.h
                        );
                        let (kind, flag) = if failure == Failure::Singular {
                            (ErrorKind::LinearSolver, -4)
                        } else {
                            (ErrorKind::ConvergenceFailures, -5)
                        };
                        return Err(self.core.error(kind, flag, message));
                    }
                    let factor = self.control().safe3;
                    match failure {
                        Failure::NonFinite => {
                            self.core.stats.step_solve_fails += 1;
                            self.core.nonfinite_failure(&mut nonfinite, self.fixed.is_some())?;
                        }
                        Failure::Singular => {
                            singular += 1;
                            self.core.stats.step_solve_fails += 1;
                            if singular >= MAX_SINGULAR {
                                let message = format!("iteration matrix singular {singular} times (h = {:e})", self.core.h);
                                return Err(self.core.error(ErrorKind::LinearSolver, -4, message));
                            }
                            self.core.reduce(factor * self.core.h, ErrorKind::LinearSolver, -4, "singular iteration matrix")?;
                        }
                        Failure::Unstable | Failure::ErrorGrowth => {
                            row_fails += 1;
                            self.core.stats.step_solve_fails += 1;
                            if row_fails >= self.max_row_fails {
                                let message = format!(
                                    "{row_fails} rows stopped by the stability checks in one step (h = {:e})",
                                    self.core.h
                                );
                                return Err(self.core.error(ErrorKind::ConvergenceFailures, -5, message));
                            }
                            self.core.reduce(factor * self.core.h, ErrorKind::ConvergenceFailures, -5, "stability check")?;
                        }
                    }
                    // An explicit attempt that overflowed is unstable too (measured: a stiff start
                    // at γ = 1e3, rtol 1e-4, blew up in all ten halvings of H before any
                    // stability check could stop a row).
                    self.stiffness_test(h_used, failure == Failure::Unstable);
                }
            }
        }
    }

    /// Evaluates the k-th derivative of the last step's continuous output at t into `out`.
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]) {
        if k == 0 && t == self.core.x {
            out.copy_from_slice(&self.core.y);
            return;
        }
        let poly = &self.work.poly;
        let scale = self.core.hold.powi(k as i32);
        if !self.dense_odex {
            let u = (t - self.core.x) / self.core.hold;
            let k = k as usize;
            for (i, o) in out.iter_mut().enumerate() {
                let mut s = 0.0;
                for l in (k..=self.degree).rev() {
                    // l!/(l−k)! · a_l, Horner in u.
                    let c: f64 = ((l - k + 1)..=l).map(|v| v as f64).product();
                    s = s * u + c * poly[l][i];
                }
                *o = s / scale;
            }
            return;
        }
        // ODEX's form in θ = (t − t_old)/H: y0 + θ·ydiff + g·s with g = θ(1 − θ),
        // s = bspl + (aspl − bspl)θ, plus W(u)·Q(u), u = θ − ½, W = (¼ − u²)²,
        // Q = Σ a_m u^m/m!.
        let theta = (t - self.core.xold) / self.core.hold;
        let u = theta - 0.5;
        let (g, g1) = (theta * (1.0 - theta), 1.0 - 2.0 * theta);
        let q = 0.25 - u * u;
        let wd = [q * q, -4.0 * u * q, -1.0 + 12.0 * u * u, 24.0 * u];
        let kmit = self.kmit;
        for (i, o) in out.iter_mut().enumerate() {
            let (y0, ydiff, aspl, bspl) = (poly[0][i], poly[1][i], poly[2][i], poly[3][i]);
            let s = bspl + (aspl - bspl) * theta;
            let ds = aspl - bspl;
            let hermite = match k {
                0 => y0 + theta * ydiff + g * s,
                1 => ydiff + g1 * s + g * ds,
                2 => -2.0 * s + 2.0 * g1 * ds,
                _ => -6.0 * ds,
            };
            let mut corr = 0.0;
            if kmit >= 0 {
                // Q^(r)(u) for r = 0..=k.
                let mut qd = [0.0f64; 4];
                for (r, qr) in qd.iter_mut().enumerate().take(k as usize + 1) {
                    let mut acc = 0.0;
                    let mut m = kmit as usize;
                    while m >= r {
                        acc = poly[4 + m][i] + acc * u / (m - r + 1) as f64;
                        if m == 0 {
                            break;
                        }
                        m -= 1;
                    }
                    // acc = Σ_{m≥r} a_m u^{m−r}/(m−r)!
                    *qr = if (kmit as usize) >= r { acc } else { 0.0 };
                }
                const BINOM: [[f64; 4]; 4] =
                    [[1.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0], [1.0, 2.0, 1.0, 0.0], [1.0, 3.0, 3.0, 1.0]];
                let k = k as usize;
                for r in 0..=k {
                    corr += BINOM[k][r] * wd[k - r] * qd[r];
                }
            }
            *o = (hermite + corr) / scale;
        }
    }

    /// Restarts at (t0, y0) with the scheme in use (or the forced one): step-size and order
    /// history, Jacobian, continuous output and stiffness-test history are dropped; options,
    /// statistics and the switch count are kept. The scheme is kept because a restart
    /// continues an integration (at a section, after a stick crossed in closed form) where the
    /// last step tells the stiffness best: the explicit scheme restarted on a slow manifold
    /// with a small first step stays stability-limited (its secant stiffness estimate sees
    /// only round-off there: at ln v = −500 on the DRR's stick, 1e-14-steps for ever).
    pub fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        self.core.restart(t0, y0)?;
        self.update_scal();
        self.enter(self.forced.unwrap_or(self.mode));
        Ok(())
    }

    /// Statistics over the integrator's whole life (restarts included). `lin_setups` counts LU
    /// decompositions (one per linearly implicit row), `step_solve_fails` attempts stopped by a
    /// row failure (stability check, growing error, non-finite f, singular matrix),
    /// `err_test_fails` rejections by the error test; `last_order` is the order of the last
    /// accepted step.
    pub fn stats(&self) -> Stats {
        self.core.stats
    }
}

impl<S: OdeSystem> Stepper for Extrapolation<S> {
    const MAX_DENSE_ORDER: u32 = 3;
    fn core(&self) -> &Core {
        &self.core
    }
    fn core_mut(&mut self) -> &mut Core {
        &mut self.core
    }
    fn ensure_f0(&mut self) -> bool {
        self.core.ensure_f0(&self.system)
    }
    fn fixed_h(&self) -> Option<f64> {
        self.fixed.map(|(h, _)| h)
    }
    fn check_fixed(&self) -> Result<(), String> {
        if let Some((h, k)) = self.fixed {
            let km = self.control().nj.len() - 1;
            if !(h.is_finite() && h > 0.0) || k == 0 || k > km {
                return Err(format!("fixed step {h} must be finite and > 0, column {k} in 1..={km}"));
            }
        }
        Ok(())
    }
    fn estimate_initial_step(&mut self, bound: f64) -> f64 {
        Extrapolation::estimate_initial_step(self, bound)
    }
    fn step(&mut self) -> Result<bool, SolverError> {
        Extrapolation::step(self)
    }
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]) {
        Extrapolation::interpolate(self, t, k, out);
    }
}

stepper::integrator_via_stepper!(Extrapolation);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stability_boundaries_of_the_smoothed_midpoint_rule() {
        let ctl = Control::odex(KM_EXPLICIT);
        let lsb: Vec<f64> = (1..=KM_EXPLICIT).map(|k| stability_boundary(&ctl.nj, k)).collect();
        // T_{1,1} (two midpoint steps and Gragg's smoothing): R(z) = (1 + z/2)(2 + z + z²/2)/2 + ...
        // crosses −1 between z = −3 and z = −4.
        assert!(lsb[0] > 3.0 && lsb[0] < 4.0, "{lsb:?}");
        assert!(lsb.iter().all(|b| *b > 2.0 && b.is_finite()), "{lsb:?}");
        // R(z) ≈ e^z for small z.
        let z = -0.01;
        assert!((midpoint_stability(&ctl.nj, 4, z) - z.exp()).abs() < 1e-15);
    }

    #[test]
    fn jacobian_bound_covers_the_spectral_radius() {
        // [[0, 1], [-1e6, -1e3]]: eigenvalues ≈ −1e3 ± i·999.5, |λ| = 1e3.
        let jac = [0.0, -1e6, 1.0, -1e3];
        let b = jacobian_bound(&jac, &[1.0, 1e3], 2);
        assert!((1e3..=2.1e3).contains(&b), "{b}");
    }
}
