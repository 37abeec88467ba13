//! Small dense linear algebra shared by the homemade integrators (Radau5, Rodas5p): LU
//! factorisation with partial pivoting of column-major n×n matrices in place (no allocation),
//! the matching solve, and the scaled RMS norm of the step-size controls.

/// Scaled RMS norm ‖v/scal‖.
pub(super) fn rms(v: &[f64], scal: &[f64]) -> f64 {
    let sum: f64 = v.iter().zip(scal).map(|(a, s)| (a / s) * (a / s)).sum();
    (sum / v.len() as f64).sqrt()
}

/// LU factorisation with partial pivoting of the column-major n×n matrix `a` (LINPACK DGEFA
/// layout: row interchanges applied to the columns to the right only). False if singular.
pub(super) fn lu_real(a: &mut [f64], ip: &mut [usize], n: usize) -> bool {
    for k in 0..n {
        let col = k * n;
        let mut p = k;
        let mut big = a[col + k].abs();
        for i in k + 1..n {
            let v = a[col + i].abs();
            if v > big {
                big = v;
                p = i;
            }
        }
        ip[k] = p;
        if big == 0.0 || !big.is_finite() {
            return false;
        }
        if p != k {
            for j in k..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let inv = 1.0 / a[col + k];
        for i in k + 1..n {
            a[col + i] *= -inv;
        }
        for j in k + 1..n {
            let t = a[j * n + k];
            if t != 0.0 {
                for i in k + 1..n {
                    a[j * n + i] += a[col + i] * t;
                }
            }
        }
    }
    true
}

/// Solves with the factors of [`lu_real`], in place. (Column slices instead of indices: the
/// same operations in the same order, without bounds checks in the inner loops.)
pub(super) fn solve_real(a: &[f64], ip: &[usize], n: usize, b: &mut [f64]) {
    let (a, ip, b) = (&a[..n * n], &ip[..n], &mut b[..n]);
    for (k, col) in a.chunks_exact(n).enumerate() {
        let p = ip[k];
        if p != k {
            b.swap(k, p);
        }
        let (head, tail) = b.split_at_mut(k + 1);
        let t = head[k];
        for (bi, &aik) in tail.iter_mut().zip(&col[k + 1..]) {
            *bi += aik * t;
        }
    }
    for (k, col) in a.chunks_exact(n).enumerate().rev() {
        let (head, tail) = b.split_at_mut(k);
        tail[0] /= col[k];
        let t = -tail[0];
        for (bi, &aik) in head.iter_mut().zip(&col[..k]) {
            *bi += aik * t;
        }
    }
}

/// Solves (d·I − J) x = b, J column-major, with the LU factors `a`, `ip` of the rounded
/// matrix, then refines x once with the residual b − d·x + J·x evaluated in compensated
/// (error-free product and sum) arithmetic; `x` holds b on entry and x on return, `r` is
/// scratch. Forming d − J_ii rounds each diagonal entry by u·|J_ii|, which moves the solution
/// by u·h‖J‖ relative: with h‖J‖ ~ 1e6 that breaks the linear invariants of f (e.g. the mass
/// balance y₂ = y₃ + y₄ of E5) by 1e-10 per step, far above an atol of 1e-24. The residual
/// from d and J themselves restores x to working accuracy.
pub(super) fn solve_refined(a: &[f64], ip: &[usize], jac: &[f64], d: f64, b: &[f64], x: &mut [f64], r: &mut [f64]) {
    let n = b.len();
    solve_real(a, ip, n, x);
    for i in 0..n {
        let (mut s, mut c) = (b[i], 0.0);
        let mut add = |p: f64, e: f64| {
            let t = s + p;
            let bb = t - s;
            c += (s - (t - bb)) + (p - bb) + e;
            s = t;
        };
        let p = -d * x[i];
        add(p, (-d).mul_add(x[i], -p));
        for j in 0..n {
            let jij = jac[j * n + i];
            if jij != 0.0 {
                let p = jij * x[j];
                add(p, jij.mul_add(x[j], -p));
            }
        }
        r[i] = s + c;
    }
    solve_real(a, ip, n, r);
    for (xi, ri) in x.iter_mut().zip(r.iter()) {
        *xi += ri;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_solves_with_pivoting_and_detects_singularity() {
        let n = 3;
        // Column-major, needs pivoting (zero leading entry).
        let a = [0.0, 2.0, 1.0, 1.0, 1.0, 3.0, 2.0, -1.0, 1.0];
        let x = [1.0, -2.0, 0.5];
        let mut b = [0.0; 3];
        for j in 0..n {
            for i in 0..n {
                b[i] += a[j * n + i] * x[j];
            }
        }
        let (mut lu, mut ip) = (a, [0; 3]);
        assert!(lu_real(&mut lu, &mut ip, n));
        solve_real(&lu, &ip, n, &mut b);
        for i in 0..n {
            assert!((b[i] - x[i]).abs() < 1e-14, "{b:?}");
        }
        let mut singular = [1.0, 2.0, 2.0, 4.0];
        assert!(!lu_real(&mut singular, &mut [0; 2], 2));
        let mut nan = [f64::NAN, 0.0, 0.0, 1.0];
        assert!(!lu_real(&mut nan, &mut [0; 2], 2));
        assert!((rms(&[3.0, 4.0], &[1.0, 2.0]) - 6.5f64.sqrt()).abs() < 1e-15);
    }

    /// E5's Jacobian (column-major) at a state of its t ≈ 1e4 phase, with the slow rate A = 0
    /// and y₂ = 0 so that J₂ − J₃ − J₄ = 0 holds exactly in floating point (otherwise the
    /// entries A − B·y₃ and −B·y₁ − CM·y₂ round, and J itself breaks the invariant by u·B·y₁).
    fn e5_jacobian(y: [f64; 4]) -> Vec<f64> {
        let (a, b, cm, c) = (0.0, 1.1e7, 1.13e9, 1.13e3);
        let rows = [
            [-a - b * y[2], 0.0, -b * y[0], 0.0],
            [a, -cm * y[2], -cm * y[1], 0.0],
            [a - b * y[2], -cm * y[2], -b * y[0] - cm * y[1], c],
            [b * y[2], 0.0, b * y[0], -c],
        ];
        (0..16).map(|k| rows[k % 4][k / 4]).collect()
    }

    #[test]
    fn refined_solve_keeps_a_linear_invariant_that_the_plain_solve_loses() {
        let jac = e5_jacobian([7.24e-4, 0.0, 7.96e-12, 5.61e-11]);
        let d = 1.0 / (4500.0 * 0.21);
        let mut w: Vec<f64> = jac.iter().map(|v| -v).collect();
        for i in 0..4 {
            w[i * 4 + i] += d;
        }
        let mut ip = [0; 4];
        assert!(lu_real(&mut w, &mut ip, 4));
        // b₂ − b₃ − b₄ = 0 exactly (powers of two), so x₂ − x₃ − x₄ = 0 in exact arithmetic.
        let b = [-2f64.powi(-24), 2f64.powi(-40), 2f64.powi(-42), 3.0 * 2f64.powi(-42)];
        let balance = |x: &[f64]| (x[1] - x[2] - x[3]).abs() / x[1].abs();
        let mut plain = b;
        solve_real(&w, &ip, 4, &mut plain);
        let (mut refined, mut r) = (b, [0.0; 4]);
        solve_refined(&w, &ip, &jac, d, &b, &mut refined, &mut r);
        assert!(balance(&refined) < 1e-14, "refined: {:e}", balance(&refined));
        assert!(balance(&plain) > 100.0 * balance(&refined), "plain {:e}, refined {:e}", balance(&plain), balance(&refined));
    }
}
