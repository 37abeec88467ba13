//! The rounding test of the linearly implicit scheme: the rows' rounding errors in f, as the
//! solves carry them into each row and the extrapolation amplifies them, against the
//! tolerance the error estimate cannot hold them to.
//!
//! Each substep of row j solves (I/h_j − J)Δ = f(y_s). A right-hand side computed with
//! relative rounding u·|f| moves Δ by (I/h_j − J)⁻¹δ: divided by the stiffness in stiff
//! directions, but multiplied by h_j in directions J does not act on — a linear invariant of
//! f, e^T f = 0 with e^T J = 0, such as E5's balance y₂ − y₃ − y₄. Off the slow manifold the
//! stiff components of f are large (at the substeps of E5 near t = 6e3, |f₃| ≈ 6e-11 while
//! f₃ ≈ 3e-17 on the manifold), so each row moves the invariant by ~h_j·u·|f₃| ≈ 1e-23, and
//! T_{k,k} = Σ c_i T_i by Λ_k = Σ|c_i| (236 at k = 5) times more. These errors are far below
//! rtol·|y| (the error estimate, a difference of two extrapolated values, does not see them),
//! but a linear invariant keeps every one of them for ever: on E5 the balance ended 1.4e-20 off
//! at rtol 1e-4 and became y₃'s end value (reference 8.9e-23). The test bounds them instead.
//!
//! Noise model: per substep the solve of u·|f(y_s)| (componentwise moduli), summed over the
//! row's substeps in modulus; for column k the rows' noise weighted by the moduli of the
//! Aitken–Neville weights. The step is rejected when, in some component, the noise exceeds
//! atol_i + u·(2Λ_k·|D_i| + |y_i + D_i|), D = T_{k,k} − y the extrapolated increment: the
//! absolute tolerance, or the rounding the step has anyway (extrapolating the increments,
//! Λ_k·u·|D_i|, which is also about the noise of a component driven by its own f, as a slow one
//! is — hence the factor 2 — and adding them to y); and the next step is limited so that the
//! noise, about ∝ H³ on E5, stays below that bound.

use super::tableau::Work;
use super::Extrapolation;
use crate::integrate::linalg::solve_real;
use crate::integrate::stepper::{Cause, UROUND};
use crate::integrate::{OdeSystem, SolverError};

/// Adds the rounding noise of one substep, the solve of u·|f| with the LU factors of the row,
/// to `noise` (reset first when `first`); `tmp` is scratch.
pub(super) fn add_noise(work: &mut Work, row: usize, first: bool) {
    let n = work.dy.len();
    for (t, f) in work.tmp.iter_mut().zip(&work.dy) {
        *t = UROUND * f.abs();
    }
    solve_real(&work.lu, &work.ip, n, &mut work.tmp);
    let noise = &mut work.noise[row];
    if first {
        noise.iter_mut().for_each(|v| *v = 0.0);
    }
    for (v, t) in noise.iter_mut().zip(&work.tmp) {
        *v += t.abs();
    }
}

impl<S: OdeSystem> Extrapolation<S> {
    /// The ratio of the rounding noise of T_{kc,kc} to its bound, the largest over the
    /// components (0 when nothing is bounded).
    fn rounding_ratio(&self, kc: usize) -> f64 {
        let weights = &self.imp.weights[kc];
        let lambda: f64 = weights.iter().sum();
        let w = &self.work;
        let mut ratio: f64 = 0.0;
        for i in 0..self.n {
            let noise: f64 = (1..=kc).map(|j| weights[j] * w.noise[j][i]).sum();
            let increment = w.t[1][i];
            let bound = self.weights.atol[i]
                + UROUND * (2.0 * lambda * increment.abs() + (self.core.y[i] + increment).abs());
            if bound > 0.0 {
                ratio = ratio.max(noise / bound);
            }
        }
        ratio
    }

    /// The rounding test of a linearly implicit step that the error test accepted in column kc
    /// (see the module documentation). True when it holds; then the next step is limited to
    /// keep it. False when the step is to be retried (h reduced, counted as an error-test
    /// failure); an error after `max_err_test_fails` such failures in one step or when h
    /// reaches `min_step`.
    pub(super) fn rounding_holds(
        &mut self,
        kc: usize,
        h_used: f64,
        rejections: &mut u32,
    ) -> Result<bool, SolverError> {
        self.h_rounding = f64::INFINITY;
        if self.fixed.is_some() {
            return Ok(true);
        }
        let ratio = self.rounding_ratio(kc);
        if ratio <= 1.0 {
            if ratio > 0.0 {
                self.h_rounding = 0.9 * h_used.abs() * ratio.powf(-1.0 / 3.0);
            }
            return Ok(true);
        }
        self.core.stats.err_test_fails += 1;
        *rejections += 1;
        if *rejections >= self.max_err_test_fails {
            let message = format!(
                "{rejections} error-test failures in one step: the rounding errors of f, amplified by the extrapolation, \
                 exceed the absolute tolerance {ratio:.1e} times (h = {h_used:e}, column {kc})"
            );
            return Err(self.core.error(Cause::ErrorTestFailures, message));
        }
        let factor = (0.9 * ratio.powf(-0.5)).max(0.1);
        self.core.h = h_used;
        self.core.reduce(factor * h_used, Cause::ErrorTestFailures, "rounding test")?;
        self.k = self.k.min(kc);
        Ok(false)
    }
}
