//! The Gragg–Bulirsch–Stoer extrapolation of the explicit modified midpoint rule (ODEX, the
//! non-stiff scheme): the rows of the tableau with their stability check and the secant
//! estimate of the dominant eigenvalue that the stiffness test uses, ODEX's continuous output
//! and its error estimate, and the linear stability boundaries of the scheme.

use super::tableau::{Control, Failure, KM_EXPLICIT};
use super::Extrapolation;
use crate::integrate::linalg::rms;
use crate::integrate::stepper::all_finite;
use crate::integrate::OdeSystem;

/// ODEX's MUDIF: the dense output's degree is 2k_c + 4 − MUDIF.
const MUDIF: usize = 4;

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

/// The linear stability boundaries of the explicit T_{k,k}, k = 1..=KM_EXPLICIT (index 0
/// unused), of ODEX's step-number sequence: a constant of the method, computed on first use
/// (a scan of about a millisecond) and shared by every integrator.
pub(super) fn stability_boundaries() -> &'static [f64] {
    static BOUNDARIES: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    BOUNDARIES.get_or_init(|| {
        let nj = Control::odex(KM_EXPLICIT).nj;
        (0..=KM_EXPLICIT).map(|k| if k == 0 { 0.0 } else { stability_boundary(&nj, k) }).collect()
    })
}

/// The linear stability boundary of T_{k,k} on the negative real axis: the first z < 0 where
/// |R(z)| exceeds 1 (scanned in steps of 0.01, then bisected).
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

/// The Euclidean norm of `x` without overflow in its squares: max|x_i| · ‖x/max|x_i|‖₂.
fn scaled_norm(x: impl Iterator<Item = f64> + Clone) -> f64 {
    let m = x.clone().fold(0.0, |m: f64, v| m.max(v.abs()));
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * x.map(|v| (v / m) * (v / m)).sum::<f64>().sqrt()
}

impl<S: OdeSystem> Extrapolation<S> {
    /// Row j of the modified midpoint tableau (ODEX's MIDEX).
    pub(super) fn row_explicit(&mut self, j: usize) -> Result<(), Failure> {
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
                let stable = if del1.is_finite() && del2.is_finite() {
                    h2 * del2 <= 4.0 * (h2 * del1).max(1.0)
                } else {
                    // The sums of squares overflowed: the same test on the norms. Where a
                    // stiff rate reaches 1e158 (a rate-and-state friction problem whose
                    // log-rate component fell to −318) f reaches 1e155, inf ≤ inf passed every attempt as stable, the secant
                    // estimate (which skips an overflowed sum) saw no stiffness either, and
                    // the midpoint scheme ran stability-limited at steps of 1e-158 until
                    // max_steps. Failing the check here counts as stiff and switches.
                    let norm_f0 = scaled_norm((0..n).map(|i| self.core.f0[i] / self.scal[i]));
                    let norm_df =
                        scaled_norm((0..n).map(|i| (w.dy[i] - self.core.f0[i]) / self.scal[i]));
                    hj * norm_df <= 2.0 * (hj * norm_f0).max(1.0)
                };
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
                let rho = (num / den).sqrt();
                self.rho = Some(self.rho.map_or(rho, |r| r.max(rho)));
            }
        }
        w.prev_raw.copy_from_slice(&w.yh2);
        w.prev_fend.copy_from_slice(&w.dy);
        self.extrapolate(j)
    }

    /// ODEX's continuous output of an explicit step converged in column kc (into `poly_next`,
    /// taken over by `accept`): the cubic Hermite interpolant of the end values and derivatives
    /// plus (θ(1−θ))²·Q(θ − ½), Q matching the solution and its first kmit = 2kc − 3
    /// derivatives at the midpoint, which are extrapolated from the rows' midpoint values and
    /// central differences of their f-values. Returns ODEX's error estimate of the interpolant.
    #[allow(clippy::needless_range_loop)]
    pub(super) fn dense_explicit(&mut self, kc: usize) -> f64 {
        let n = self.n;
        let h = self.core.h;
        let nj = &self.exp.nj;
        let kmit = 2 * kc as isize - MUDIF as isize + 1;
        let w = &mut self.work;
        // Hermite part: y0, y1 − y0, aspl, bspl.
        for i in 0..n {
            let (y0, y1, yp0, yp1) =
                (self.core.y[i], w.t[1][i], h * self.core.f0[i], h * w.fnew[i]);
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
                        let f = if idx == 0 {
                            self.core.f0[i]
                        } else {
                            w.fsafe[offsets[kk] + idx - 1][i]
                        };
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

    /// The k-th derivative at t of ODEX's continuous output of the last step into `out`.
    pub(super) fn interpolate_explicit(&self, t: f64, k: u32, out: &mut [f64]) {
        let poly = &self.work.poly;
        let scale = self.core.hold.powi(k as i32);
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
                const BINOM: [[f64; 4]; 4] = [
                    [1.0, 0.0, 0.0, 0.0],
                    [1.0, 1.0, 0.0, 0.0],
                    [1.0, 2.0, 1.0, 0.0],
                    [1.0, 3.0, 3.0, 1.0],
                ];
                let k = k as usize;
                for r in 0..=k {
                    corr += BINOM[k][r] * wd[k - r] * qd[r];
                }
            }
            *o = (hermite + corr) / scale;
        }
    }
}

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
}
