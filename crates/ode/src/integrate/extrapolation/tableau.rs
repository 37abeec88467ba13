//! What both schemes share: their step-number sequences, work model and control parameters
//! ([`Control`]: SEULEX's and ODEX's), the work arrays, and the extrapolation tableau — the
//! Aitken–Neville extrapolation of each new row with its error estimate, the convergence
//! monitor that accepts or rejects a step after a row, and the order and step-size selection
//! after an accepted step.

use super::{Extrapolation, Mode};
use crate::integrate::stepper::UROUND;
use crate::integrate::OdeSystem;

/// Maximal tableau sizes (SEULEX: 12 columns, ODEX: 9).
pub(super) const KM_IMPLICIT: usize = 12;
pub(super) const KM_EXPLICIT: usize = 9;
/// SEULEX's estimated work of one f-call (+ solve), Jacobian and LU decomposition.
const WK_ROW: f64 = 2.0;
const WK_JAC: f64 = 5.0;
const WK_DEC: f64 = 1.0;
/// First element of the linearly implicit scheme's step-number sequence n_j = first + j − 1:
/// 2, 3, 4, … (Mathematica's LinearlyImplicitEuler). Measured against the harmonic 1, 2, 3, …
/// (`.implicit_sequence(1)`): on van der Pol (ε = 1e-6, t ∈ [0, 2]) 1.5–22× fewer steps and
/// 1–5× less time at rtol = atol = 1e-3 … 1e-12 for equal or smaller errors (the n₁ = 1 row
/// damps stiff components weakly); on a rate-and-state friction oscillator with stiffness
/// 1e1 … 1e8 (rtol 1e-3 … 1e-12, three settled cycles) period errors of the same size,
/// −5 … +30 % right-hand sides and −21 … +14 % factorisations, and no wrong cycle (the
/// harmonic sequence, at rtol 1e-12 and stiffness 1e3, let the explicit scheme take one step
/// in a stiff phase that put that cycle's period off by 8e-4). Costs: on non-stiff problems forced onto the linearly implicit scheme its
/// dense output is 3–4× less accurate (tests/extrapolation.rs).
pub(super) const DEFAULT_FIRST: usize = 2;

/// One scheme's step-number sequence, work model and control parameters (1-based arrays).
#[derive(Debug, Clone)]
pub(super) struct Control {
    pub(super) km: usize,
    pub(super) nj: Vec<f64>,
    /// off[j] = n_1 + … + n_{j−1}: where row j's per-substep values are stored.
    pub(super) off: Vec<usize>,
    pub(super) a: Vec<f64>,
    pub(super) fac1: f64,
    pub(super) fac2: f64,
    pub(super) fac3: f64,
    pub(super) fac4: f64,
    pub(super) safe1: f64,
    pub(super) safe2: f64,
    /// Step reduction after a row failure.
    pub(super) safe3: f64,
    /// weights[k] = [`weight_moduli`] of column k (the linearly implicit scheme only; empty
    /// for the explicit one).
    pub(super) weights: Vec<Vec<f64>>,
}

fn offsets(nj: &[f64]) -> Vec<usize> {
    let mut off = vec![0; nj.len() + 1];
    for j in 2..=nj.len() {
        off[j] = off[j - 1] + nj[j - 1] as usize;
    }
    off
}

/// The moduli of the Aitken–Neville weights of T_{k,k} in h_j = H/n_j: |c_i| for the rows
/// i = 1..=k (index 0 unused), T_{k,k} = Σ c_i T_i. Their sum is Λ_k, the amplification of
/// the rows' rounding errors by the extrapolation.
pub(super) fn weight_moduli(nj: &[f64], k: usize) -> Vec<f64> {
    let mut c = vec![0.0; k + 1];
    for (i, ci) in c.iter_mut().enumerate().skip(1) {
        *ci = (1..=k)
            .filter(|&l| l != i)
            .map(|l| (1.0 / nj[l]) / (1.0 / nj[l] - 1.0 / nj[i]))
            .product::<f64>()
            .abs();
    }
    c
}

/// The number of columns (at least 4, at most `km`) whose extrapolation amplifies roundoff
/// by less than rtol/u: Λ_k·u ≤ rtol, with Λ_k = Σ_i |c_i| the sum of the Aitken–Neville
/// weights of T_{k,k} in h_j = H/n_j (Λ_k = 3, 9, 28, …, 1.3e5 at k = 11 for the harmonic
/// sequence; 5, 19, 68, …, 4.1e5 for 2, 3, 4, …). Beyond it the error estimate is roundoff,
/// and SEULEX's control, asking for ever smaller steps, ends in a step underflow (measured
/// with 2, 3, 4, … at rtol 1e-12 on the same oscillator at stiffness 1e3 and 1e8).
fn roundoff_columns(nj: &[f64], km: usize, rtol: f64) -> usize {
    let amplification = |k: usize| -> f64 { weight_moduli(nj, k).iter().sum() };
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
    pub(super) fn seulex(km: usize, first: usize, rtol: f64) -> Self {
        let nj: Vec<f64> =
            (0..=km).map(|j| if j == 0 { 0.0 } else { (first + j - 1) as f64 }).collect();
        let mut a = vec![0.0; km + 1];
        a[1] = WK_JAC + nj[1] * WK_ROW + WK_DEC;
        for j in 2..=km {
            a[j] = a[j - 1] + (nj[j] - 1.0) * WK_ROW + WK_DEC;
        }
        let off = offsets(&nj);
        let weights = (0..=km).map(|k| weight_moduli(&nj, k)).collect();
        let km = roundoff_columns(&nj, km, rtol);
        Self {
            km,
            nj,
            off,
            a,
            fac1: 0.1,
            fac2: 4.0,
            fac3: 0.7,
            fac4: 0.9,
            safe1: 0.6,
            safe2: 0.93,
            safe3: 0.5,
            weights,
        }
    }

    /// ODEX with the sequence 2, 6, 10, … (its NSEQU = 3, required by its dense output).
    pub(super) fn odex(km: usize) -> Self {
        let nj: Vec<f64> =
            (0..=km).map(|j| if j == 0 { 0.0 } else { 4.0 * j as f64 - 2.0 }).collect();
        let mut a = vec![0.0; km + 1];
        a[1] = 1.0 + nj[1];
        for j in 2..=km {
            a[j] = a[j - 1] + nj[j];
        }
        let off = offsets(&nj);
        Self {
            km,
            nj,
            off,
            a,
            fac1: 0.02,
            fac2: 4.0,
            fac3: 0.8,
            fac4: 0.9,
            safe1: 0.65,
            safe2: 0.94,
            safe3: 0.5,
            weights: Vec::new(),
        }
    }
}

/// Why a tableau row was stopped (SEULEX/ODEX's ATOV): the step is retried with a smaller H.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Failure {
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
pub(super) struct Work {
    /// The extrapolation tableau (rows 1..=km, row 0 unused); t[1] ends as T_{j,j}.
    pub(super) t: Vec<Vec<f64>>,
    pub(super) yh1: Vec<f64>,
    pub(super) yh2: Vec<f64>,
    pub(super) dy: Vec<f64>,
    pub(super) del: Vec<f64>,
    pub(super) tmp: Vec<f64>,
    pub(super) fnew: Vec<f64>,
    /// The previous explicit row's unsmoothed end value and f there (stiffness estimate).
    pub(super) prev_raw: Vec<f64>,
    pub(super) prev_fend: Vec<f64>,
    /// The linearly implicit rows' increments: row j, step i at j(j−1)/2 + i.
    pub(super) incr: Vec<Vec<f64>>,
    /// The linearly implicit rows' rounding noise (rows 1..=km, see `rounding`).
    pub(super) noise: Vec<Vec<f64>>,
    /// The midpoint rows' f-values f_1..f_{n_j} (row j from Σ_{i<j} n_i) and their values at
    /// the step's midpoint (ODEX's FSAFE and YSAFE).
    pub(super) fsafe: Vec<Vec<f64>>,
    pub(super) ysafe: Vec<Vec<f64>>,
    /// Aitken–Neville scratch for the dense-output derivatives.
    pub(super) nev: Vec<Vec<f64>>,
    /// Jacobian (column-major), LU factors of I/h_j − J and pivots.
    pub(super) jac: Vec<f64>,
    pub(super) lu: Vec<f64>,
    pub(super) ip: Vec<usize>,
    /// Continuous output of the last step. After an implicit step: Σ poly[l]·u^l with
    /// u = (t − x)/hold ∈ [−1, 0]. After an explicit one, ODEX's form: poly[0..4] = y_old,
    /// y_new − y_old and the Hermite coefficients, poly[4 + m] = a_m of the correction.
    pub(super) poly: Vec<Vec<f64>>,
    /// An explicit step's continuous output before the step is accepted.
    pub(super) poly_next: Vec<Vec<f64>>,
}

impl Work {
    pub(super) fn new(n: usize, km: usize, incr: usize, fsafe: usize, dense_len: usize) -> Self {
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
            noise: (0..=km).map(|_| v()).collect(),
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

impl<S: OdeSystem> Extrapolation<S> {
    /// The control of the scheme in use.
    pub(super) fn control(&self) -> &Control {
        match self.mode {
            Mode::Explicit => &self.exp,
            Mode::Implicit => &self.imp,
        }
    }

    /// Aitken–Neville on the new row j, the error estimate, the optimal step and work of
    /// column j.
    pub(super) fn extrapolate(&mut self, j: usize) -> Result<(), Failure> {
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
                // ODEX's weights: atol + rtol·max(|y0|, |y1|) (or the absolute scale).
                let y_abs = self.core.y[i].abs().max(w.t[1][i].abs());
                self.scal[i] = self.weights.positive_scale(i, y_abs);
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

    pub(super) fn row(&mut self, j: usize) -> Result<(), Failure> {
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
    pub(super) fn attempt(&mut self, first: bool) -> Result<Option<usize>, Failure> {
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
    pub(super) fn select(&mut self, kc: usize) {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Λ_k for 2, 3, 4, …: 5, 19, 68 as `roundoff_columns` says, and 236 at k = 5, the
    /// amplification of the rows' rounding in docs/test-set.md's E5 section.
    #[test]
    fn weight_moduli_sum_to_the_documented_amplifications() {
        let nj: Vec<f64> = (0..=6).map(|j| if j == 0 { 0.0 } else { (j + 1) as f64 }).collect();
        let lambda = |k: usize| -> f64 { weight_moduli(&nj, k).iter().sum() };
        let c = weight_moduli(&nj, 2);
        assert!(c[0] == 0.0 && (c[1] - 2.0).abs() < 1e-12 && (c[2] - 3.0).abs() < 1e-12, "{c:?}");
        for (k, expected) in [(2, 5.0), (3, 19.0), (4, 68.0), (5, 236.0)] {
            assert!((lambda(k) - expected).abs() < 0.5, "Λ_{k} = {}", lambda(k));
        }
    }
}
