//! Small dense linear algebra shared by the homemade integrators (Radau5, Rodas5p): LU
//! factorisation with partial pivoting of column-major n×n matrices in place (no allocation),
//! the matching solve, and the scaled RMS norm of the step-size controls.

/// Scaled RMS norm ‖v/scal‖.
pub(super) fn rms(v: &[f64], scal: &[f64]) -> f64 {
    let sum: f64 = v.iter().zip(scal).map(|(a, s)| (a / s) * (a / s)).sum();
    (sum / v.len() as f64).sqrt()
}

/// Evaluates `body` with the dimension `n` as a compile-time constant for the small systems
/// that dominate the integrators' cost (n = 3, as in a 3-component friction model; E5's n = 4), so that the
/// loops in it unroll and lose their bounds checks and iterator bookkeeping; any other n runs
/// the same body with n at run time. The arithmetic, and so the result, is the same in every
/// case. (A macro, not a function taking a closure: a closure called from three arms is not
/// inlined, and then n is not constant.)
macro_rules! with_small_n {
    ($n:ident, $body:expr) => {
        match $n {
            3 => {
                let $n = 3;
                $body
            }
            4 => {
                let $n = 4;
                $body
            }
            _ => $body,
        }
    };
}
pub(super) use with_small_n;

/// LU factorisation with partial pivoting of the column-major n×n matrix `a` (LINPACK DGEFA
/// layout: row interchanges applied to the columns to the right only). False if singular.
pub(super) fn lu_real(a: &mut [f64], ip: &mut [usize], n: usize) -> bool {
    with_small_n!(n, lu_real_n(&mut a[..n * n], &mut ip[..n], n))
}

/// The pivot row of column k in partial pivoting: the first row i in k..n of the largest
/// `magnitude(i)`; `None` if that is zero or not finite (the matrix is singular, or holds a
/// NaN or an infinity). Shared by the real and the complex LU.
#[inline(always)]
pub(super) fn pivot(k: usize, n: usize, magnitude: impl Fn(usize) -> f64) -> Option<usize> {
    let mut p = k;
    let mut big = magnitude(k);
    for i in k + 1..n {
        let v = magnitude(i);
        if v > big {
            big = v;
            p = i;
        }
    }
    (big != 0.0 && big.is_finite()).then_some(p)
}

#[inline(always)]
fn lu_real_n(a: &mut [f64], ip: &mut [usize], n: usize) -> bool {
    for k in 0..n {
        let col = k * n;
        let Some(p) = pivot(k, n, |i| a[col + i].abs()) else {
            return false;
        };
        ip[k] = p;
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

/// The inverse of the column-major 3×3 matrix `a` into `inv` (column-major): the adjugate
/// (transposed cofactors) times the reciprocal of the determinant, expanded along the first
/// row. False if the determinant is zero or not finite.
pub(super) fn inverse3(a: &[f64], inv: &mut [f64]) -> bool {
    let m = |i: usize, j: usize| a[j * 3 + i];
    // The cofactors C_ij in row-major order: (a⁻¹)_ji = C_ij / det sits at inv[i·3 + j].
    let c = [
        m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1),
        m(1, 2) * m(2, 0) - m(1, 0) * m(2, 2),
        m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0),
        m(0, 2) * m(2, 1) - m(0, 1) * m(2, 2),
        m(0, 0) * m(2, 2) - m(0, 2) * m(2, 0),
        m(0, 1) * m(2, 0) - m(0, 0) * m(2, 1),
        m(0, 1) * m(1, 2) - m(0, 2) * m(1, 1),
        m(0, 2) * m(1, 0) - m(0, 0) * m(1, 2),
        m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0),
    ];
    let det = m(0, 0) * c[0] + m(0, 1) * c[1] + m(0, 2) * c[2];
    if det == 0.0 || !det.is_finite() {
        return false;
    }
    let r = 1.0 / det;
    for (x, ci) in inv[..9].iter_mut().zip(c) {
        *x = ci * r;
    }
    true
}

/// b ← M b for the column-major 3×3 matrix `m` (e.g. an [`inverse3`]).
pub(super) fn multiply3(m: &[f64], b: &mut [f64]) {
    let (m, x) = (&m[..9], [b[0], b[1], b[2]]);
    for (i, bi) in b[..3].iter_mut().enumerate() {
        *bi = m[i] * x[0] + m[3 + i] * x[1] + m[6 + i] * x[2];
    }
}

/// Solves with the factors of [`lu_real`], in place.
pub(super) fn solve_real(a: &[f64], ip: &[usize], n: usize, b: &mut [f64]) {
    with_small_n!(n, solve_real_n(a, ip, n, b))
}

/// [`solve_real`]'s body. (Column slices instead of indices: the same operations in the same
/// order, without bounds checks in the inner loops when n is only known at run time.)
#[inline(always)]
fn solve_real_n(a: &[f64], ip: &[usize], n: usize, b: &mut [f64]) {
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

/// Veltkamp's split of `a` into a high part of 26 significant bits and the exact rest.
#[inline(always)]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// The rounding error a·b − p of the product p = fl(a·b), exactly (Dekker's TwoProduct), in
/// plain f64 arithmetic: the same value as `a.mul_add(b, -p)`, which without a target FMA is a
/// software `fma` call several times as expensive. Exact unless a partial product underflows
/// (|a·b| below about 1e-292, where the error is below 1e-308 either way); NaN if |a| or |b|
/// exceeds about 1e299 (the split overflows) — [`solve_refined`] falls back to `mul_add` then.
#[inline(always)]
fn product_error(a: f64, b: f64, p: f64) -> f64 {
    let ((ah, al), (bh, bl)) = (split(a), split(b));
    ((ah * bh - p) + ah * bl + al * bh) + al * bl
}

/// Solves (d·I − J) x = b, J column-major, with the LU factors `a`, `ip` of the rounded
/// matrix, then refines x once with the residual b − d·x + J·x evaluated in compensated
/// (error-free product and sum) arithmetic; `x` holds b on entry and x on return, `r` is
/// scratch. Forming d − J_ii rounds each diagonal entry by u·|J_ii|, which moves the solution
/// by u·h‖J‖ relative: with h‖J‖ ~ 1e6 that breaks the linear invariants of f (e.g. the mass
/// balance y₂ = y₃ + y₄ of E5) by 1e-10 per step, far above an atol of 1e-24. The residual
/// from d and J themselves restores x to working accuracy.
pub(super) fn solve_refined(
    a: &[f64],
    ip: &[usize],
    jac: &[f64],
    d: f64,
    b: &[f64],
    x: &mut [f64],
    r: &mut [f64],
) {
    let n = b.len();
    with_small_n!(n, {
        solve_real_n(a, ip, n, x);
        residual(jac, d, &b[..n], &x[..n], &mut r[..n], product_error);
        if !r[..n].iter().all(|v| v.is_finite()) {
            residual(jac, d, &b[..n], &x[..n], &mut r[..n], |a, b, p| a.mul_add(b, -p));
        }
        solve_real_n(a, ip, n, r);
    });
    for (xi, ri) in x.iter_mut().zip(r.iter()) {
        *xi += ri;
    }
}

/// The residual r = b − d·x + J·x of [`solve_refined`], each product's rounding error
/// (`error(a, b, fl(a·b))`) and each sum's carried in a compensation term.
#[inline(always)]
fn residual(
    jac: &[f64],
    d: f64,
    b: &[f64],
    x: &[f64],
    r: &mut [f64],
    error: impl Fn(f64, f64, f64) -> f64,
) {
    let n = b.len();
    let jac = &jac[..n * n];
    for i in 0..n {
        let (mut s, mut c) = (b[i], 0.0);
        let mut add = |p: f64, e: f64| {
            let t = s + p;
            let bb = t - s;
            c += (s - (t - bb)) + (p - bb) + e;
            s = t;
        };
        let p = -d * x[i];
        add(p, error(-d, x[i], p));
        for j in 0..n {
            let jij = jac[j * n + i];
            if jij != 0.0 {
                let p = jij * x[j];
                add(p, error(jij, x[j], p));
            }
        }
        r[i] = s + c;
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

    #[test]
    fn inverse3_inverts_and_detects_singularity() {
        // Column-major; a stiff diagonal beside O(1) couplings, as in I/(hγ) − J.
        let a = [2.0e7, 3.0, -1.0, 0.5, 4.0, 2.0, 1.0, -3.0, 7.0];
        let mut inv = [0.0; 9];
        assert!(inverse3(&a, &mut inv));
        for col in 0..3 {
            let mut e = [0.0; 3];
            e[col] = 1.0;
            // a · (inv e_col) = e_col.
            let mut x = e;
            multiply3(&inv, &mut x);
            for i in 0..3 {
                let ax: f64 = (0..3).map(|j| a[j * 3 + i] * x[j]).sum();
                assert!((ax - e[i]).abs() < 1e-14, "column {col}, row {i}: {ax}");
            }
        }
        let singular = [1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 5.0];
        assert!(!inverse3(&singular, &mut inv));
        let nan = [f64::NAN, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        assert!(!inverse3(&nan, &mut inv));
    }

    #[test]
    fn product_error_is_the_fused_multiply_add_error() {
        // Quasi-random operands over 1e-120 … 1e120, of both signs.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let m = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            m * 10f64.powi((state % 240) as i32 - 120)
        };
        for _ in 0..10_000 {
            let (a, b) = (next(), next());
            let p = a * b;
            assert_eq!(product_error(a, b, p), a.mul_add(b, -p), "{a:e} × {b:e}");
        }
        // Beyond the split's range the refined solve falls back to mul_add: still finite.
        assert!(product_error(1e305, 3.0, 3e305).is_nan());
        let (jac, ip, lu) = ([-1e305, 0.0, 0.0, -1.0], [0, 1], [1e305 + 1.0, 0.0, 0.0, 2.0]);
        let (b, mut x, mut r) = ([1.0, 1.0], [1.0, 1.0], [0.0; 2]);
        solve_refined(&lu, &ip, &jac, 1.0, &b, &mut x, &mut r);
        assert!(x.iter().all(|v| v.is_finite()) && (x[1] - 0.5).abs() < 1e-16, "{x:?}");
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
        assert!(
            balance(&plain) > 100.0 * balance(&refined),
            "plain {:e}, refined {:e}",
            balance(&plain),
            balance(&refined)
        );
    }
}
