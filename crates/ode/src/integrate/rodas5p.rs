//! Rodas5P: the Rosenbrock method of G. Steinebach, "Construction of Rosenbrock–Wanner method
//! Rodas5P and numerical benchmarks within the Julia Differential Equations package", BIT
//! Numer. Math. 63, 27 (2023) (the successor of RODASP and of Rodas4P2, from his "Improvement
//! of Rosenbrock–Wanner method RODASP", 2020) — order 5 with an embedded order-4 solution,
//! 8 stages, stiffly accurate (and so is the embedded solution), L-stable, with a continuous
//! output of order 4. The coefficients are those of the Julia package OrdinaryDiffEq.jl
//! (`Rodas5PTableau` in lib/OrdinaryDiffEqRosenbrock/src/rosenbrock_tableaus.jl), in
//! Hairer–Wanner's transformed form (Solving ODEs II, IV.7, (7.25)): with W = I/(hγ) − J,
//!
//!   W k_i = f(t + c_i h, y + Σ_{j<i} a_ij k_j) + Σ_{j<i} (c_ij/h) k_j + h d_i ∂f/∂t,
//!   y_new = y + Σ_{j<8} a_8j k_j + k_8,   error estimate k_8,
//!
//! and the dense output y(t + θh) = (1−θ) y + θ (y_new + (1−θ)(K1 + θ(K2 + θ K3))) with
//! K_m = Σ_i h_mi k_i. The unit tests below recover the classical coefficients (α, Γ, b) from
//! this form and check every order condition (all rooted trees up to order 5 for the
//! solution, order 4 for the embedded one and for the dense output at any θ), the stiff
//! accuracy and R(∞) = 0.
//!
//! Step-size control as in Hairer–Wanner's code RODAS: the error is the scaled RMS norm of the
//! difference between the two solutions with weights atol + rtol·max(|y|, |y_new|) (no
//! tolerance transformation), h_new = h/clamp(err^{1/5}/0.9, 1/6, 5) (so 0.2 ≤ h_new/h ≤ 6),
//! Gustafsson's predictive controller on consecutive accepted steps, no increase right after
//! a rejection, a first step cut by 10 when rejected. Acceptance when err ≤ 1. Two additions
//! for layers far sharper than the step (both measured on a stiff friction law,
//! docs/robustness.md):
//! from the second rejection in a row h is cut by the largest factor, 5, as CVODE does after
//! two error-test failures (an error that did not fall like h⁵ is not in the asymptotic
//! regime the controller assumes); and a stage with a non-finite right-hand side cuts h to at
//! most the local time scale 0.01·‖y‖/‖f(y)‖ (max norms in the error weights) instead of
//! only halving it.
//!
//! Jacobian: a Rosenbrock method is linearly implicit and needs the exact Jacobian at every
//! step (it is evaluated once per step and kept across rejections, the LU factors of W are
//! renewed whenever h changes). Use an analytic Jacobian ([`OdeSystem::has_jacobian`]): the
//! forward-difference one (RADAU5's increments, n extra right-hand-side calls) works, but its
//! O(√u) error goes straight into the stages — there is no Newton iteration to correct it.
//!
//! Time dependence: the method needs ∂f/∂t as well. A system that provides it
//! ([`OdeSystem::has_time_derivative`], e.g. the noise realisations' cubic forcing) gives it
//! exactly; otherwise it is taken by a forward difference in t (as RODAS does with IFCN = 1; one extra right-hand-side
//! call per Jacobian, counted in [`Stats::rhs_evals_jacobian`]); it is exact (zero) for an
//! autonomous system, where [`Rodas5p::autonomous`] saves that call. For non-autonomous
//! systems this finite difference limits the attainable accuracy (relative error ~1e-8 in
//! ∂f/∂t); [`Rodas5p::autonomous`] avoids it for autonomous systems.
//!
//! Error flags ([`SolverError::flag`]), RODAS's IDID where it has one: −1 invalid input, −2 too
//! many steps, −3 step size too small, −4 matrix repeatedly singular, −6 right-hand-side failure,
//! −7 repeated error-test failures.

// The published coefficients are kept with all their digits.
#![allow(clippy::excessive_precision)]

use super::linalg::{inverse3, lu_real, multiply3, rms, solve_real, solve_refined, with_small_n};
use super::stepper::{
    self, all_finite, Cause, Core, StepControl, Stepper, DEFAULT_MAX_ERR_TEST_FAILS, MAX_SINGULAR,
    UROUND,
};
use super::{ErrorWeights, Integrator, OdeSystem, Options, SolverError, Stats, Step, Task};
use crate::method::Method;

/// This method's row of the method table (its name and dense-output order).
const METHOD: Method = Method::Rodas5p;
/// Safety factor of the step-size control.
const SAFE: f64 = 0.9;
/// 1/FAC1 ≤ h_new/h ≤ 1/FAC2 (RODAS's WORK(3) = 0.2, WORK(4) = 6).
const FAC1: f64 = 5.0;
const FAC2: f64 = 1.0 / 6.0;
/// The error estimate is O(h⁵).
const EXPONENT: f64 = 0.2;

/// Number of stages.
const STAGES: usize = 8;
/// The diagonal coefficient γ.
const GAMMA: f64 = 0.21193756319429014;
/// a_ij (j < i): stage points y + Σ a_ij k_j.
#[rustfmt::skip]
const A: [[f64; 7]; STAGES] = [
    [0.0; 7],
    [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.849394379747939, 0.45842242204463923, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-6.954028509809101, 2.489845061869568, -10.358996098473584, 0.0, 0.0, 0.0, 0.0],
    [2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641, 0.0, 0.0, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256, 0.030198172008377946, 0.0, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256, 0.030198172008377946, 1.0, 0.0],
    [-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256, 0.030198172008377946, 1.0, 1.0],
];
/// c_ij (j < i): the coupling terms (c_ij/h) k_j.
#[rustfmt::skip]
const C: [[f64; 7]; STAGES] = [
    [0.0; 7],
    [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [-17.97296035885952, -2.859693295451294, 0.0, 0.0, 0.0, 0.0, 0.0],
    [147.12150275711716, -1.41221402718213, 71.68940251302358, 0.0, 0.0, 0.0, 0.0],
    [165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306, 0.0, 0.0, 0.0],
    [24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125, -0.6610691825249471, 0.0, 0.0],
    [30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783, -19.097331116725623, -28.087943162872662, 0.0],
    [37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047, -40.06618937091002, -54.66780262877968, -9.48861652309627],
];
/// The nodes c_i (c_2 = 3γ).
const NODES: [f64; STAGES] = [
    0.0,
    0.6358126895828704,
    0.4095798393397535,
    0.9769306725060716,
    0.4288403609558664,
    1.0,
    1.0,
    1.0,
];
/// d_i = Σ_j γ_ij: the coefficients of h ∂f/∂t.
const D: [f64; STAGES] = [
    0.21193756319429014,
    -0.42387512638858027,
    -0.3384627126235924,
    1.8046452872882734,
    2.325825639765069,
    0.0,
    0.0,
    0.0,
];
/// Dense output: K_m = Σ_i h_mi k_i.
#[rustfmt::skip]
const HD: [[f64; STAGES]; 3] = [
    [25.948786856663858, -2.5579724845846235, 10.433815404888879, -2.3679251022685204, 0.524948541321073, 1.1241088310450404, 0.4272876194431874, -0.17202221070155493],
    [-9.91568850695171, -0.9689944594115154, 3.0438037242978453, -24.495224566215796, 20.176138334709044, 15.98066361424651, -6.789040303419874, -6.710236069923372],
    [11.419903575922262, 2.8879645146136994, 72.92137995996029, 80.12511834622643, -52.072871366152654, -59.78993625266729, -0.15582684282751913, 4.883087185713722],
];

/// Work arrays, allocated once.
#[derive(Debug, Clone)]
struct Work {
    /// The stage increments k_1..k_8, stage-major (k_i at [i·n, (i+1)·n)).
    k: Vec<f64>,
    /// Stage point; after the last stage, the embedded (order-4) solution.
    u: Vec<f64>,
    ynew: Vec<f64>,
    fnew: Vec<f64>,
    tmp: Vec<f64>,
    /// Error weights.
    scal: Vec<f64>,
    /// ∂f/∂t at the current point.
    dfdt: Vec<f64>,
    /// Jacobian, column-major.
    jac: Vec<f64>,
    /// LU factors of W = I/(hγ) − J and pivots (or, with [`Rodas5p::explicit_inverse`],
    /// W⁻¹ itself in `e`).
    e: Vec<f64>,
    ip: Vec<usize>,
    /// Start of the last step and its dense-output coefficients K1, K2, K3 (stage-major).
    yold: Vec<f64>,
    cont: Vec<f64>,
}

impl Work {
    fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Self {
            k: vec![0.0; STAGES * n],
            u: v(),
            ynew: v(),
            fnew: v(),
            tmp: v(),
            scal: v(),
            dfdt: v(),
            jac: vec![0.0; n * n],
            e: vec![0.0; n * n],
            ip: vec![0; n],
            yold: v(),
            cont: vec![0.0; 3 * n],
        }
    }
}

/// The Rosenbrock method Rodas5P (Steinebach, BIT 2023; order 5(4), 8 stages, stiffly accurate,
/// L-stable, continuous output of order 4) with RODAS's step-size control, on the system `S`. One
/// Jacobian (and, unless [`Rodas5p::autonomous`], one finite-difference ∂f/∂t) per step, one LU
/// factorisation of I/(hγ) − J per step attempt (its explicit inverse instead for a 3-component
/// system that [allows it](OdeSystem::allows_explicit_inverse)), seven right-hand-side calls per
/// step attempt (the stages) and one at each accepted point (f there, which the next step starts
/// from), no Newton iteration.
///
/// Implements [`Integrator`]: `dense(t, k)` for k = 0..4 on the last step (the continuous output is
/// a quartic), `reinit` restarts with fresh step-size history and accumulated statistics. Options:
/// `rtol`/`atol` (used as given, as in RODAS), `error_scales`, `max_steps` (per call, default
/// [`DEFAULT_MAX_STEPS`](super::DEFAULT_MAX_STEPS)), `initial_step`, `min_step`, `max_step`,
/// `stop_time` (not stepped past; disabled once reached, as in SUNDIALS), `max_err_test_fails`
/// (consecutive rejections, default 50), `fail_on_step_underflow`. `max_order` (the order is 5),
/// `max_nonlin_iters`, `max_conv_fails` and `nonlin_conv_coef` (there is no nonlinear iteration)
/// are InvalidInput errors.
///
/// Non-autonomous systems: ∂f/∂t is a forward difference (see the module documentation).
///
/// Statistics: `rhs_evals_jacobian` includes the finite-difference ∂f/∂t calls;
/// `nonlin_iters` stays 0.
pub struct Rodas5p<S: OdeSystem> {
    system: S,
    n: usize,
    weights: ErrorWeights,
    // Options.
    max_err_test_fails: u32,
    fixed_h: Option<f64>,
    autonomous: bool,
    /// Stage solves by W⁻¹ (n = 3, [`OdeSystem::allows_explicit_inverse`]).
    explicit_inverse: bool,
    // Integration state.
    /// The step-size control with Gustafsson's memory.
    control: StepControl,
    /// The Jacobian (and ∂f/∂t) are those of the current point.
    jac_current: bool,
    /// Step size the LU factors were computed for (NaN: none valid).
    lu_h: f64,
    /// Point, last step, returned state, step-sequence options and statistics.
    core: Core,
    work: Work,
}

impl<S: OdeSystem> std::fmt::Debug for Rodas5p<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.core.debug_struct(f, "Rodas5p", self.n).finish()
    }
}

/// Evaluates the k-th time derivative of the continuous output of the last step [x − hold, x]
/// at t into `out`.
fn interpolate(w: &Work, y: &[f64], x: f64, hold: f64, t: f64, k: u32, out: &mut [f64]) {
    let n = out.len();
    // θ = 1 + s exactly 1 and 1 − θ exactly 0 at the step end: the output ends on y.
    let s = (t - x) / hold;
    let (th, th1) = (1.0 + s, -s);
    for i in 0..n {
        let (y0, y1) = (w.yold[i], y[i]);
        let (k1, k2, k3) = (w.cont[i], w.cont[n + i], w.cont[2 * n + i]);
        out[i] = match k {
            0 => th1 * y0 + th * (y1 + th1 * (k1 + th * (k2 + th * k3))),
            1 => {
                ((y1 - y0 + k1) + th * (2.0 * (k2 - k1) + th * (3.0 * (k3 - k2) - 4.0 * th * k3)))
                    / hold
            }
            2 => (2.0 * (k2 - k1) + th * (6.0 * (k3 - k2) - 12.0 * th * k3)) / (hold * hold),
            3 => (6.0 * (k3 - k2) - 24.0 * th * k3) / (hold * hold * hold),
            _ => -24.0 * k3 / (hold * hold * hold * hold),
        };
    }
}

impl<S: OdeSystem> Rodas5p<S> {
    /// A Rodas5P integrator of `system` starting at (t0, y0). Errors (InvalidInput): a system
    /// without components, y0 of the wrong length or non-finite, non-finite t0, invalid
    /// options.
    pub fn new(system: S, t0: f64, y0: &[f64], options: &Options) -> Result<Self, SolverError> {
        let n = system.dim();
        let core =
            Core::new(METHOD, n, t0, y0, options, Stats { last_order: 5, ..Stats::default() })?;
        let no_newton = "a Rosenbrock method has no nonlinear iteration";
        core.reject_unsupported(&[
            ("max_order", options.max_order.is_some(), "the order is fixed at 5"),
            ("max_nonlin_iters", options.max_nonlin_iters.is_some(), no_newton),
            ("max_conv_fails", options.max_conv_fails.is_some(), no_newton),
            ("nonlin_conv_coef", options.nonlin_conv_coef.is_some(), no_newton),
        ])?;
        let positive = |v: Option<i32>, default: u32| v.map_or(default, |v| v.max(1) as u32);
        let explicit_inverse =
            n == 3 && system.allows_explicit_inverse() && !system.has_linear_invariants();
        Ok(Self {
            system,
            n,
            weights: ErrorWeights::new(options, n),
            max_err_test_fails: positive(options.max_err_test_fails, DEFAULT_MAX_ERR_TEST_FAILS),
            fixed_h: None,
            autonomous: false,
            control: StepControl::new(EXPONENT, SAFE, FAC2, FAC1),
            explicit_inverse,
            jac_current: false,
            lu_h: f64::NAN,
            core,
            work: Work::new(n),
        })
    }

    /// Declares f independent of t: ∂f/∂t is taken as zero instead of by a finite difference,
    /// which saves one right-hand-side call per step. Wrong (order loss) if f depends on t.
    pub fn autonomous(mut self) -> Self {
        self.autonomous = true;
        self
    }

    /// Testing aid: integrate with the constant step `h` (clipped only at the stop time), every
    /// step accepted whatever its error estimate; a singular matrix or a non-finite right-hand
    /// side is then an error.
    #[doc(hidden)]
    pub fn fixed_step(mut self, h: f64) -> Self {
        self.fixed_h = Some(h);
        self
    }

    /// Error weights atol + rtol·max(|y|, |other|) (or their absolute scales) into `scal`.
    fn set_scal(scal: &mut [f64], weights: &ErrorWeights, y: &[f64], other: &[f64]) {
        for i in 0..scal.len() {
            scal[i] = weights.positive_scale(i, y[i].abs().max(other[i].abs()));
        }
    }

    /// Hairer–Wanner's initial step (Solving ODEs I, II.4) for an error ~ h⁵ (the embedded
    /// estimate's order), measured with the weights atol + rtol·|y0|.
    fn estimate_initial_step(&mut self, bound: f64) -> f64 {
        let (w, c) = (&mut self.work, &mut self.core);
        Self::set_scal(&mut w.scal, &self.weights, &c.y, &c.y);
        stepper::initial_step(&self.system, c, &w.scal, &mut w.tmp, &mut w.fnew, bound, EXPONENT)
    }

    /// Jacobian at (x, y) into `work.jac` (analytic, or forward differences with RADAU5's
    /// increments √(u·max(1e-5, |y_i|))) and, unless autonomous, ∂f/∂t by a forward difference
    /// with RODAS's increment √(u·max(1e-5, |t|)) (backward if f is not finite ahead). False if
    /// either is not finite.
    fn compute_jacobian(&mut self) -> bool {
        let w = &mut self.work;
        if !stepper::jacobian(&self.system, &mut self.core, &mut w.jac, &mut w.tmp, &mut w.fnew) {
            return false;
        }
        if self.autonomous {
            return true;
        }
        if self.system.has_time_derivative() {
            self.system.time_derivative(self.core.x, &self.core.y, &mut w.dfdt);
            return all_finite(&w.dfdt);
        }
        let n = self.n;
        let delt = (UROUND * self.core.x.abs().max(1e-5)).sqrt();
        for direction in [self.core.posneg, -self.core.posneg] {
            let xd = self.core.x + direction * delt;
            let delt = xd - self.core.x;
            self.system.rhs(xd, &self.core.y, &mut w.fnew);
            self.core.stats.rhs_evals_jacobian += 1;
            if !all_finite(&w.fnew) {
                self.core.stats.nonfinite_rhs += 1;
                continue;
            }
            for i in 0..n {
                w.dfdt[i] = (w.fnew[i] - self.core.f0[i]) / delt;
            }
            if all_finite(&w.dfdt) {
                return true;
            }
        }
        false
    }

    /// LU factors of I/(hγ) − J, or its inverse (`explicit_inverse`). False if singular.
    fn decompose(&mut self) -> bool {
        let n = self.n;
        let fac = 1.0 / (self.core.h * GAMMA);
        let w = &mut self.work;
        for (e, j) in w.e.iter_mut().zip(&w.jac) {
            *e = -j;
        }
        for j in 0..n {
            w.e[j * n + j] += fac;
        }
        self.core.stats.lin_setups += 1;
        let ok = if self.explicit_inverse {
            let matrix: [f64; 9] = std::array::from_fn(|k| w.e[k]);
            inverse3(&matrix, &mut w.e)
        } else {
            lu_real(&mut w.e, &mut w.ip, n)
        };
        self.lu_h = if ok { self.core.h } else { f64::NAN };
        ok
    }

    /// The eight stages and the new solution `work.ynew` (the embedded one in `work.u`). False
    /// if a right-hand side was not finite. (For n = 3 and 4 the loops run with n a
    /// compile-time constant, [`with_small_n`]: the same arithmetic in the same order, without
    /// the bounds checks and loop bookkeeping that were two thirds of a noise realisation's
    /// own Rodas5P work, issue #30.)
    fn stages(&mut self) -> bool {
        let n = self.n;
        with_small_n!(n, self.stages_n(n))
    }

    /// [`Rodas5p::stages`]'s body for dimension `n`: the eight stages with the stage index a
    /// compile-time constant too ([`Rodas5p::stage`]), so that the sums over the earlier
    /// stages unroll (the same arithmetic in the same order as a loop over them).
    #[inline(always)]
    fn stages_n(&mut self, n: usize) -> bool {
        let all = self.stage::<0>(n)
            && self.stage::<1>(n)
            && self.stage::<2>(n)
            && self.stage::<3>(n)
            && self.stage::<4>(n)
            && self.stage::<5>(n)
            && self.stage::<6>(n)
            && self.stage::<7>(n);
        if !all {
            return false;
        }
        let w = &mut self.work;
        let last = &w.k[(STAGES - 1) * n..STAGES * n];
        for ((ynew, u), k) in w.ynew[..n].iter_mut().zip(&w.u[..n]).zip(last) {
            *ynew = u + k;
        }
        true
    }

    /// Stage `ST` (0-based): k_ST from the stage point y + Σ_{j<ST} a_ij k_j. False if the
    /// right-hand side there is not finite.
    #[inline(always)]
    fn stage<const ST: usize>(&mut self, n: usize) -> bool {
        let (x, h) = (self.core.x, self.core.h);
        let w = &mut self.work;
        let (done, rest) = w.k.split_at_mut(ST * n);
        let ks = &mut rest[..n];
        if ST == 0 {
            ks.copy_from_slice(&self.core.f0[..n]);
        } else {
            let (y, u) = (&self.core.y[..n], &mut w.u[..n]);
            for i in 0..n {
                let mut v = y[i];
                for j in 0..ST {
                    v += A[ST][j] * done[j * n + i];
                }
                u[i] = v;
            }
            self.system.rhs(x + NODES[ST] * h, u, ks);
            self.core.stats.rhs_evals += 1;
            if !all_finite(ks) {
                self.core.stats.nonfinite_rhs += 1;
                return false;
            }
            for i in 0..n {
                let mut v = 0.0;
                for j in 0..ST {
                    v += C[ST][j] * done[j * n + i];
                }
                ks[i] += v / h;
            }
        }
        if !self.autonomous && D[ST] != 0.0 {
            let hd = h * D[ST];
            for (k, ft) in ks.iter_mut().zip(&w.dfdt[..n]) {
                *k += hd * ft;
            }
        }
        // Solve (I/(hγ) − J) k_s = b_s, refined if f may have linear invariants: see
        // `solve_refined`.
        if self.explicit_inverse {
            multiply3(&w.e, ks);
        } else if self.system.has_linear_invariants() {
            w.tmp.copy_from_slice(ks);
            solve_refined(&w.e, &w.ip, &w.jac, 1.0 / (h * GAMMA), &w.tmp, ks, &mut w.fnew);
        } else {
            solve_real(&w.e, &w.ip, n, ks);
        }
        true
    }

    /// The scaled norm of the error estimate k_8 = y_new − ŷ_new (1e20 if not finite).
    fn estimate_error(&mut self) -> f64 {
        let n = self.n;
        let w = &mut self.work;
        Self::set_scal(&mut w.scal, &self.weights, &self.core.y, &w.ynew);
        let err = rms(&w.k[(STAGES - 1) * n..], &w.scal);
        if err.is_finite() {
            err
        } else {
            1e20
        }
    }

    /// One accepted step (with as many attempts as needed). Returns true if it ended at the
    /// stop time.
    fn step(&mut self) -> Result<bool, SolverError> {
        let (mut nonfinite, mut singular, mut rejections) = (0u32, 0u32, 0u32);
        self.core.layer_step = false;
        self.core.drop_passed_stop_time();
        loop {
            let (planned, last) = self.core.prepare_attempt(self.fixed_h)?;
            // Jacobian (once per point) and LU factors (once per step size).
            if !self.jac_current {
                if !self.compute_jacobian() {
                    return Err(self
                        .core
                        .error(Cause::RhsFailure, "the Jacobian or ∂f/∂t is not finite".into()));
                }
                self.jac_current = true;
                self.lu_h = f64::NAN;
            }
            if self.lu_h != self.core.h && !self.decompose() {
                singular += 1;
                if singular >= MAX_SINGULAR || self.fixed_h.is_some() {
                    let message = format!(
                        "matrix I/(hγ) − J singular {singular} times (h = {:e})",
                        self.core.h
                    );
                    return Err(self.core.error(Cause::LinearSolver, message));
                }
                self.core.reduce(0.5 * self.core.h, Cause::LinearSolver, "singular matrix")?;
                continue;
            }
            self.core.stats.step_attempts += 1;
            if !self.stages() {
                self.stage_failure(&mut nonfinite)?;
                continue;
            }
            let err = self.estimate_error();
            let accepted = err <= 1.0 || self.fixed_h.is_some();
            // The new step size. An accepted step that ends at the stop time goes on with the
            // planned step instead, so the controller (two powf) is skipped there: the same
            // steps, and every step of a noise realisation ends at a node (issue #30).
            let control = !(accepted && last);
            let mut quot = if control { self.control.quotient(err, SAFE) } else { 1.0 };
            let mut hnew = self.core.h / quot;
            if accepted {
                // f at the new point (needed next anyway): a non-finite one fails the step.
                let xph = self.core.step_end(last);
                let w = &mut self.work;
                self.system.rhs(xph, &w.ynew, &mut w.fnew);
                self.core.stats.rhs_evals += 1;
                if !all_finite(&w.fnew) {
                    self.core.stats.nonfinite_rhs += 1;
                    self.core.nonfinite_failure(&mut nonfinite, self.fixed_h.is_some())?;
                    continue;
                }
                self.accept(xph, err, control, &mut quot, &mut hnew);
                // The next step size (RODAS's acceptance branch).
                self.core.h = self.core.next_step(hnew, last, planned, self.fixed_h);
                self.core.stats.current_step = self.core.h;
                return Ok(last);
            }
            // Rejected by the error test.
            self.core.rejected(&mut rejections, self.max_err_test_fails, err)?;
            // From the second rejection in a row, the error is evidently not falling like h⁵ (a
            // transient the step does not resolve yet): cut h by the largest factor, 1/FAC1,
            // as CVODE does after two error-test failures (its ETAMXF = 0.2).
            let hnew = if !self.core.have_step {
                0.1 * self.core.h
            } else if rejections >= 2 {
                hnew.abs().min(self.core.h.abs() / FAC1) * self.core.posneg
            } else {
                hnew
            };
            self.core.reduce(hnew, Cause::ErrorTestFailures, "error-test failure")?;
        }
    }

    /// A stage with a non-finite right-hand side: the step is rejected (`Core::nonfinite_failure`
    /// halves h) and h is cut further to the local time scale 0.01·‖y‖/‖f(y)‖ if that is
    /// shorter (Hairer–Wanner's first-step guess, in the error weights' max norm). Stages leave the range
    /// of doubles when h is decades beyond the time f needs to change y (measured: h = 3.5e-14
    /// against a time scale of 1e-193 in a very stiff phase), which halving does not reach in the ten attempts a
    /// step has. A step that then falls below the clock's resolution is a step underflow
    /// (`Core::layer_step` keeps it one), which the [`Clock`](super::Clock) cures by re-basing.
    fn stage_failure(&mut self, nonfinite: &mut u32) -> Result<(), SolverError> {
        self.core.nonfinite_failure(nonfinite, self.fixed_h.is_some())?;
        let w = &mut self.work;
        Self::set_scal(&mut w.scal, &self.weights, &self.core.y, &self.core.y);
        // Max norms: f may be far beyond 1e154, where a sum of squares overflows.
        let norm = |v: &[f64]| v.iter().zip(&w.scal).fold(0.0f64, |m, (x, s)| m.max((x / s).abs()));
        let local = 0.01 * norm(&self.core.y) / norm(&self.core.f0);
        if local.is_finite() && local > 0.0 && local < self.core.h.abs() {
            self.core.h = self.core.posneg * local.max(self.core.hmin);
            self.core.layer_step = true;
        }
        Ok(())
    }

    /// Accepts the step to `xph`: Gustafsson's controller (unless `control` is false: the next
    /// step size is not the controller's), the continuous output, the new state (RODAS's
    /// acceptance branch).
    fn accept(&mut self, xph: f64, err: f64, control: bool, quot: &mut f64, hnew: &mut f64) {
        let h = self.core.h;
        let n = self.n;
        if control {
            self.control.accepted(h, err, quot, hnew);
        } else {
            self.control.accepted_uncontrolled(h, err);
        }
        self.core.xold = self.core.x;
        self.core.hold = h;
        self.core.x = xph;
        let w = &mut self.work;
        with_small_n!(n, {
            let k = &w.k[..STAGES * n];
            for (m, row) in HD.iter().enumerate() {
                for i in 0..n {
                    let mut v = 0.0;
                    for (s, c) in row.iter().enumerate() {
                        v += c * k[s * n + i];
                    }
                    w.cont[m * n + i] = v;
                }
            }
        });
        w.yold.copy_from_slice(&self.core.y);
        std::mem::swap(&mut self.core.y, &mut w.ynew);
        std::mem::swap(&mut self.core.f0, &mut w.fnew);
        self.core.f0_valid = true;
        self.core.count_accepted(h);
        self.jac_current = false;
    }

    /// Restarts at (t0, y0): step-size history, Jacobian and continuous output are dropped;
    /// options and statistics are kept.
    pub fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        self.core.restart(t0, y0)?;
        self.control.restart();
        self.jac_current = false;
        self.lu_h = f64::NAN;
        Ok(())
    }
}

stepper::integrator_via_stepper!(Rodas5p, METHOD, {
    fn fixed_h(&self) -> Option<f64> {
        self.fixed_h
    }
    fn interpolate(&self, t: f64, k: u32, out: &mut [f64]) {
        interpolate(&self.work, &self.core.y, self.core.x, self.core.hold, t, k, out);
    }
});

#[cfg(test)]
mod tests {
    use super::*;

    type Matrix = [[f64; STAGES]; STAGES];

    fn full(rows: &[[f64; 7]; STAGES]) -> Matrix {
        let mut m = [[0.0; STAGES]; STAGES];
        for i in 0..STAGES {
            m[i][..7].copy_from_slice(&rows[i]);
        }
        m
    }

    fn mul(p: &Matrix, q: &Matrix) -> Matrix {
        let mut r = [[0.0; STAGES]; STAGES];
        for i in 0..STAGES {
            for j in 0..STAGES {
                r[i][j] = (0..STAGES).map(|k| p[i][k] * q[k][j]).sum();
            }
        }
        r
    }

    fn row_times(v: &[f64; STAGES], m: &Matrix) -> [f64; STAGES] {
        let mut r = [0.0; STAGES];
        for j in 0..STAGES {
            r[j] = (0..STAGES).map(|k| v[k] * m[k][j]).sum();
        }
        r
    }

    /// The classical coefficients: Γ = (I/γ − C)⁻¹ (lower triangular, γ on the diagonal),
    /// α = A Γ, b = m Γ with m = (a_8·, 1) and b̂ = (a_8·, 0) Γ (Hairer–Wanner II, (7.25)).
    fn classical() -> (Matrix, Matrix, [f64; STAGES], [f64; STAGES]) {
        let c = full(&C);
        let mut gamma = [[0.0; STAGES]; STAGES];
        for j in 0..STAGES {
            let mut x = [0.0; STAGES];
            for i in 0..STAGES {
                let mut r = if i == j { 1.0 } else { 0.0 };
                for (k, xk) in x.iter().enumerate().take(i) {
                    r += c[i][k] * xk;
                }
                x[i] = r * GAMMA;
            }
            for (row, xi) in gamma.iter_mut().zip(x) {
                row[j] = xi;
            }
        }
        let a = full(&A);
        let alpha = mul(&a, &gamma);
        let mut m = a[STAGES - 1];
        let embedded = row_times(&m, &gamma);
        m[STAGES - 1] = 1.0;
        (alpha, gamma, row_times(&m, &gamma), embedded)
    }

    /// Rooted trees as sorted lists of subtrees.
    #[derive(Clone, PartialEq, Eq, PartialOrd, Ord, Debug)]
    struct Tree(Vec<Tree>);

    impl Tree {
        fn order(&self) -> usize {
            1 + self.0.iter().map(Tree::order).sum::<usize>()
        }
        fn factorial(&self) -> f64 {
            self.order() as f64 * self.0.iter().map(Tree::factorial).product::<f64>()
        }
    }

    /// All rooted trees with up to `max` vertices.
    fn trees(max: usize) -> Vec<Tree> {
        let mut all = vec![Tree(vec![])];
        for _ in 1..max {
            let mut next = all.clone();
            for t in &all {
                // Graft a new leaf onto every vertex of t (all trees of order + 1 arise).
                fn graft(t: &Tree, out: &mut Vec<Tree>) {
                    let mut children = t.0.clone();
                    children.push(Tree(vec![]));
                    children.sort();
                    out.push(Tree(children));
                    for (i, child) in t.0.iter().enumerate() {
                        let mut grafted = Vec::new();
                        graft(child, &mut grafted);
                        for g in grafted {
                            let mut children = t.0.clone();
                            children[i] = g;
                            children.sort();
                            out.push(Tree(children));
                        }
                    }
                }
                graft(t, &mut next);
            }
            next.sort();
            next.dedup();
            all = next;
        }
        all
    }

    /// Stage weights of the B-series of k_i for tree t: k_i(τ) = 1, k_i([t₁…t_m]) =
    /// Π_l Σ_j α_ij k_j(t_l), plus Σ_{j≤i} γ_ij k_j(t₁) when m = 1 (the hJ Σ γ_ij k_j term).
    fn stage_weights(t: &Tree, alpha: &Matrix, gamma: &Matrix) -> [f64; STAGES] {
        let subs: Vec<[f64; STAGES]> = t.0.iter().map(|u| stage_weights(u, alpha, gamma)).collect();
        let mut k = [0.0; STAGES];
        for i in 0..STAGES {
            let mut v = 1.0;
            for s in &subs {
                v *= (0..i).map(|j| alpha[i][j] * s[j]).sum::<f64>();
            }
            if subs.len() == 1 {
                v += (0..=i).map(|j| gamma[i][j] * subs[0][j]).sum::<f64>();
            }
            k[i] = v;
        }
        k
    }

    #[test]
    fn order_conditions_hold_up_to_order_five_and_four() {
        let (alpha, gamma, b, bhat) = classical();
        let all = trees(6);
        assert_eq!(all.iter().filter(|t| t.order() <= 5).count(), 17);
        assert_eq!(all.len(), 37);
        // Dense-output weights b_i(θ) = θ b_i + θ(1−θ) Σ_m θ^{m−1} (H Γ)_mi.
        let hg: Vec<[f64; STAGES]> = HD.iter().map(|row| row_times(row, &gamma)).collect();
        let dense = |th: f64| {
            let mut w = [0.0; STAGES];
            for i in 0..STAGES {
                w[i] = th * b[i] + th * (1.0 - th) * (hg[0][i] + th * (hg[1][i] + th * hg[2][i]));
            }
            w
        };
        let mut sixth_order_defect = 0.0f64;
        for t in &all {
            let k = stage_weights(t, &alpha, &gamma);
            let exact = 1.0 / t.factorial();
            let defect = |w: &[f64; STAGES]| (0..STAGES).map(|i| w[i] * k[i]).sum::<f64>() - exact;
            let (p, q) = (defect(&b), defect(&bhat));
            match t.order() {
                1..=4 => assert!(p.abs() < 1e-13 && q.abs() < 1e-13, "{t:?}: {p:e}, {q:e}"),
                5 => {
                    assert!(p.abs() < 1e-13, "order 5, {t:?}: {p:e}");
                    assert!(q.abs() > 1e-5, "the embedded method is of order 4 only: {t:?}");
                }
                _ => sixth_order_defect = sixth_order_defect.max(p.abs()),
            }
            if t.order() <= 4 {
                for th in [0.1, 0.3, 0.5, 0.7, 0.9] {
                    let d = (0..STAGES).map(|i| dense(th)[i] * k[i]).sum::<f64>()
                        - th.powi(t.order() as i32) * exact;
                    assert!(d.abs() < 1e-13, "dense output, θ = {th}, {t:?}: {d:e}");
                }
            }
        }
        assert!(sixth_order_defect > 1e-4, "order exactly 5");
        // Consistency: c_i = Σ_j α_ij, d_i = Σ_j γ_ij (autonomous ≡ non-autonomous form).
        for i in 0..STAGES {
            assert!((alpha[i].iter().sum::<f64>() - NODES[i]).abs() < 1e-13, "c_{i}");
            assert!((gamma[i].iter().sum::<f64>() - D[i]).abs() < 1e-13, "d_{i}");
            assert!((gamma[i][i] - GAMMA).abs() < 1e-15);
        }
        // Stiffly accurate: b_j = α_8j + γ_8j and b̂_j = α_7j + γ_7j.
        for j in 0..STAGES {
            assert!((b[j] - alpha[7][j] - gamma[7][j]).abs() < 1e-13);
            assert!((bhat[j] - alpha[6][j] - gamma[6][j]).abs() < 1e-13);
        }
        assert!(
            (b.iter().sum::<f64>() - 1.0).abs() < 1e-13
                && (bhat.iter().sum::<f64>() - 1.0).abs() < 1e-13
        );
    }

    /// One step of the method on y' = λy with h = 1: (R(z), R̂(z)).
    fn stability(z: f64) -> (f64, f64) {
        let mut u = [0.0; STAGES];
        for i in 0..STAGES {
            let g = 1.0 + (0..i).map(|j| A[i][j] * u[j]).sum::<f64>();
            let rhs = z * g + (0..i).map(|j| C[i][j] * u[j]).sum::<f64>();
            u[i] = rhs / (1.0 / GAMMA - z);
        }
        let embedded = 1.0 + (0..7).map(|j| A[7][j] * u[j]).sum::<f64>();
        (embedded + u[7], embedded)
    }

    #[test]
    fn stability_function_vanishes_at_infinity() {
        for z in [-1e8, -1e12] {
            let (r, rhat) = stability(z);
            assert!(
                r.abs() < 20.0 / z.abs() && rhat.abs() < 20.0 / z.abs(),
                "R({z}) = {r:e}, R̂ = {rhat:e}"
            );
        }
        let (r, _) = stability(-0.1);
        assert!((r - (-0.1f64).exp()).abs() < 1e-8, "R(−0.1) = {r} ≈ e^−0.1");
        for z in [-0.5, -1.0, -10.0, -100.0, -1e4] {
            assert!(stability(z).0.abs() < 1.0 && stability(z).1.abs() < 1.0, "|R({z})| < 1");
        }
    }
}
