//! The linearly implicit Euler extrapolation (SEULEX, the stiff scheme): the Jacobian, the
//! rows of the tableau with their stability check, and SEULEX's continuous output.

use super::rounding::add_noise;
use super::switching::jacobian_bound;
use super::tableau::Failure;
use super::Extrapolation;
use crate::integrate::linalg::{lu_real, solve_real, solve_refined};
use crate::integrate::stepper::{self, all_finite};
use crate::integrate::OdeSystem;

/// SEULEX's dense-output parameter λ.
const DENSE_LAMBDA: usize = 1;

/// Weighted Euclidean norm ‖v/scal‖₂ (SEULEX's stability check).
fn norm2(v: &[f64], scal: &[f64]) -> f64 {
    v.iter().zip(scal).map(|(a, s)| (a / s) * (a / s)).sum::<f64>().sqrt()
}

/// l! as a float.
fn factorial(l: usize) -> f64 {
    (1..=l).map(|i| i as f64).product()
}

impl<S: OdeSystem> Extrapolation<S> {
    /// Jacobian at (x, y) into `work.jac`: analytic, or forward differences (SEULEX's increments
    /// √(u·max(1e-5, |y_i|))). False if not finite.
    pub(super) fn compute_jacobian(&mut self) -> bool {
        let w = &mut self.work;
        let ok =
            stepper::jacobian(&self.system, &mut self.core, &mut w.jac, &mut w.tmp, &mut w.fnew);
        self.rho_jac = if ok { jacobian_bound(&w.jac, &self.scal, self.n) } else { f64::INFINITY };
        ok
    }

    /// Row j of the linearly implicit Euler tableau (SEULEX's SEUL), as the increment T_j − y
    /// in `work.t[j]`: the tableau of this scheme holds increments until [`Self::add_increment`].
    pub(super) fn row_implicit(&mut self, j: usize) -> Result<(), Failure> {
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
        add_noise(w, j, true);
        // The row accumulates its increment T_j − y in t[j] (extrapolated as increments, see
        // `rounding`); yh1 = y + that increment is only where f is evaluated.
        w.t[j].iter_mut().for_each(|v| *v = 0.0);
        w.del.copy_from_slice(&w.dy);
        // Refined solves keep the linear invariants of f (see `solve_refined`), and, for every
        // system, the stage solves accurate enough for an error estimate that amplifies their
        // rounding by the extrapolation weights: without refinement a 3-component
        // rate-and-state friction problem with stiff rates near 1e24 (rtol 1e-10) failed with
        // 20 error-test failures in one step at h = 4.3e-24 (docs/test-set.md). Hence no
        // `OdeSystem::has_linear_invariants` here, unlike rodas5p.
        solve_refined(&w.lu, &w.ip, &w.jac, hji, &w.dy, &mut w.del, &mut w.fnew);
        let base = self.imp.off[j];
        w.incr[base].copy_from_slice(&w.del);
        for mm in 1..m {
            for i in 0..n {
                w.t[j][i] += w.del[i];
                w.yh1[i] = self.core.y[i] + w.t[j][i];
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
            add_noise(w, j, false);
            w.del.copy_from_slice(&w.dy);
            solve_refined(&w.lu, &w.ip, &w.jac, hji, &w.dy, &mut w.del, &mut w.fnew);
            w.incr[base + mm].copy_from_slice(&w.del);
        }
        for i in 0..n {
            w.t[j][i] += w.del[i];
        }
        if !all_finite(&w.t[j]) {
            return Err(Failure::Unstable);
        }
        self.extrapolate(j)
    }

    /// T_{kc,kc} = y + its extrapolated increment, in `work.t[1]`, once the step is accepted.
    /// Extrapolating increments rounds by Λ_k·u·|T − y| instead of Λ_k·u·|y|: on E5 at
    /// t ≈ 6e3 (y₂ ≈ 9e-11) the latter alone moves its balance y₂ − y₃ − y₄ by ~1e-24 per step.
    pub(super) fn add_increment(&mut self) {
        let w = &mut self.work;
        for (t, y) in w.t[1].iter_mut().zip(&self.core.y) {
            *t += y;
        }
    }

    /// SEULEX's continuous output after an implicit step accepted in column kc (before y is
    /// replaced): derivatives at the right end from backward differences of the increments,
    /// extrapolated, and the polynomial of degree kc through y_old and y_new.
    #[allow(clippy::needless_range_loop)]
    pub(super) fn dense_implicit(&mut self, kc: usize) {
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

    /// The k-th derivative at t of SEULEX's continuous output of the last step into `out`:
    /// Σ poly[l]·u^l with u = (t − x)/hold ∈ [−1, 0], divided by hold^k.
    pub(super) fn interpolate_implicit(&self, t: f64, k: u32, out: &mut [f64]) {
        let poly = &self.work.poly;
        let scale = self.core.hold.powi(k as i32);
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
    }
}
