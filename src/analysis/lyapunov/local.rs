//! Local ("quasi-static") Lyapunov exponents: the eigenvalues of the 3×3 Jacobian in (u, v, θ)
//! (the paper's eq. jacobian) at each step end of the cycle, computed two ways, beside the
//! paper's large-γ formula (its eq. lambda):
//!
//! - from the characteristic polynomial λ³ + a₂λ² + a₁λ + a₀ (eq. lambda3, with
//!   a₂ = γ² f'(v)/ξ + v, a₁ = γ² [(v f'(v) − A)/ξ + 1], a₀ = γ² v and
//!   A = θ + (1+ε) (f(v) + v f'(v)), = θ + (1+ε)(1 + ln v) for f = ln v), by the stable
//!   Newton-and-deflation of [`crate::analysis::hopf::cubic_roots`] — the values reported;
//! - with nalgebra's Schur decomposition of the matrix, as a check where it can resolve the slow
//!   pair: its absolute error is ~1e-16 ‖J‖ ≈ 1e-16 γ² f'(v)/ξ, which at γ = 1e8 exceeds the
//!   slow pair itself;
//! - the quasi-static formula λ = −B ± √(B² − C), B = ½ (v + (ξ − A)/f'(v)), C = ξ v/f'(v)
//!   (B = ½ v (1 − A + ξ), C = ξ v² for f = ln v), the slow roots of the polynomial divided by
//!   a₂ ≈ γ² f'/ξ.

use crate::analysis::hopf::cubic_roots;
use crate::analysis::orbit::Orbit;
use crate::model::DrrParams;
use nalgebra::Matrix3;

/// The local exponents at one state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    /// The fast (most negative, real) eigenvalue.
    pub fast: f64,
    /// The slow pair: real parts (equal when complex), larger first.
    pub slow_re: [f64; 2],
    /// Imaginary part of the slow pair (≥ 0; 0 when real).
    pub slow_im: f64,
    /// Signed discriminant of the slow pair: (λ₁ − λ₂)² when real, −(λ₁ − λ₂)²/… < 0 when
    /// complex (= −4 im²); continuous through the real/complex transition.
    pub slow_discriminant: f64,
    /// The quasi-static formula: real parts, larger first.
    pub quasi_re: [f64; 2],
    /// The quasi-static formula: imaginary part (≥ 0).
    pub quasi_im: f64,
    /// The quasi-static discriminant B² − C.
    pub quasi_discriminant: f64,
}

/// The Jacobian in (u, v, θ) and its characteristic polynomial (a₂, a₁, a₀) at (u, ln v, θ).
pub fn jacobian(params: &DrrParams, y: &[f64; 3]) -> (Matrix3<f64>, [f64; 3], f64, f64) {
    let (w, theta) = (y[1], y[2]);
    let v = w.exp();
    let g = params.gamma * params.gamma;
    let (f, vfp) = params.friction.eval(w);
    let fprime = vfp / v;
    let a_entry = theta + (1.0 + params.epsilon) * (f + vfp);
    let a = g * fprime / params.xi;
    let j = Matrix3::new(0.0, 1.0, 0.0, -g, -a, -g / params.xi, 0.0, -a_entry, -v);
    (j, [a + v, g * ((vfp - a_entry) / params.xi + 1.0), g * v], a_entry, fprime)
}

/// The local exponents at (u, ln v, θ).
pub fn at(params: &DrrParams, y: &[f64; 3]) -> Local {
    let v = y[1].exp();
    let (_, [a2, a1, a0], a_entry, fprime) = jacobian(params, y);
    let roots = cubic_roots(a2, a1, a0);
    let (r1, r2) = (roots[1], roots[2]);
    let (slow_re, slow_im, slow_discriminant) = if r1[1] != 0.0 {
        ([r1[0], r1[0]], r1[1].abs(), -4.0 * r1[1] * r1[1])
    } else {
        ([r1[0].max(r2[0]), r1[0].min(r2[0])], 0.0, (r1[0] - r2[0]).powi(2))
    };
    let b = 0.5 * (v + (params.xi - a_entry) / fprime);
    let c = params.xi * v / fprime;
    let d = b * b - c;
    let (quasi_re, quasi_im) = if d >= 0.0 {
        // Stable quadratic formula.
        let q = -b - b.signum() * d.sqrt();
        let (x1, x2) = if q != 0.0 { (q, c / q) } else { (0.0, 0.0) };
        ([x1.max(x2), x1.min(x2)], 0.0)
    } else {
        ([-b, -b], (-d).sqrt())
    };
    Local { fast: roots[0][0], slow_re, slow_im, slow_discriminant, quasi_re, quasi_im, quasi_discriminant: d }
}

/// nalgebra's eigenvalues of the matrix, as (fast, slow pair sorted by real part then
/// imaginary part), and the matrix's largest absolute entry.
pub fn matrix_eigenvalues(params: &DrrParams, y: &[f64; 3]) -> ([f64; 2], [[f64; 2]; 2], f64) {
    let (j, ..) = jacobian(params, y);
    let mut ev: Vec<[f64; 2]> = j.complex_eigenvalues().iter().map(|z| [z.re, z.im]).collect();
    ev.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    (ev[0], [ev[1], ev[2]], j.amax())
}

/// A sign change of a continuous indicator between two samples, located by linear
/// interpolation in time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Crossing {
    /// t_c − t at the crossing.
    pub time_before_tc: f64,
    /// Time between the two samples that bracket it (the resolution of the location).
    pub resolution: f64,
    /// Index of the sample after the crossing.
    #[serde(skip)]
    pub index: usize,
}

/// The first upward crossing of zero by `f` over samples `from..to` of the orbit (`f` must
/// be negative somewhere before it).
pub fn first_up(orbit: &Orbit, values: &[f64], from: usize, to: usize) -> Option<Crossing> {
    (from + 1..to).find(|&k| values[k - 1] < 0.0 && values[k] >= 0.0).map(|k| crossing(orbit, values, k))
}

/// The last downward crossing of zero by `values` over samples `from..to`.
pub fn last_down(orbit: &Orbit, values: &[f64], from: usize, to: usize) -> Option<Crossing> {
    (from + 1..to).rev().find(|&k| values[k - 1] >= 0.0 && values[k] < 0.0).map(|k| crossing(orbit, values, k))
}

fn crossing(orbit: &Orbit, values: &[f64], k: usize) -> Crossing {
    let (a, b) = (values[k - 1], values[k]);
    let x = a / (a - b);
    let s = orbit.s[k - 1] + x * (orbit.s[k] - orbit.s[k - 1]);
    Crossing { time_before_tc: -s, resolution: orbit.s[k] - orbit.s[k - 1], index: k }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Friction;

    fn params(gamma: f64, friction: Friction) -> DrrParams {
        DrrParams::new(gamma, 0.7, 0.72, friction)
    }

    #[test]
    fn polynomial_roots_agree_with_the_matrix_and_the_paper_form() {
        // States of Fig. 1's cycle: stick, late stick, rise, slip peak.
        let states = [[9.12, (0.0785f64).ln(), -3.84], [-0.70, (0.357f64).ln(), 1.52], [0.39, (20.1f64).ln(), -3.28], [8.17, (3422.0f64).ln(), -13.86]];
        for friction in [Friction::Log, Friction::Power { alpha: 0.15 }] {
            let p = params(1e3, friction);
            for y in states {
                let l = at(&p, &y);
                let (fast, slow, _) = matrix_eigenvalues(&p, &y);
                assert!((l.fast - fast[0]).abs() < 1e-9 * fast[0].abs(), "{friction:?} {y:?}: {} vs {fast:?}", l.fast);
                // Slow pair: sort ours like the matrix's (by real part, then imaginary part).
                let mut ours = if l.slow_im > 0.0 { [[l.slow_re[0], -l.slow_im], [l.slow_re[0], l.slow_im]] } else { [[l.slow_re[1], 0.0], [l.slow_re[0], 0.0]] };
                ours.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
                for (a, b) in ours.iter().zip(&slow) {
                    let scale = 1.0 + b[0].hypot(b[1]);
                    assert!((a[0] - b[0]).abs() < 1e-7 * scale && (a[1] - b[1]).abs() < 1e-7 * scale, "{friction:?} {y:?}: {ours:?} vs {slow:?}");
                }
            }
        }
        // The paper's log-law form: B = ½ v (1 − A + ξ), A = θ + (1+ε)(1 + ln v), C = ξ v².
        let y = [0.39, (20.1f64).ln(), -3.28];
        let l = at(&params(1e3, Friction::Log), &y);
        let v: f64 = 20.1;
        let a = -3.28 + 1.72 * (1.0 + v.ln());
        let b = 0.5 * v * (1.0 - a + 0.7);
        assert!((l.quasi_discriminant - (b * b - 0.7 * v * v)).abs() < 1e-9 * (b * b));
    }

    #[test]
    fn quasi_static_formula_is_the_large_gamma_limit() {
        // The formula's error is O(λ_slow/λ_fast) ∝ 1/γ².
        let y = [-0.70, (0.357f64).ln(), 1.52];
        let err = |gamma: f64| {
            let l = at(&params(gamma, Friction::Log), &y);
            (l.quasi_re[0] - l.slow_re[0]).abs() + (l.quasi_im - l.slow_im).abs()
        };
        let (e2, e3) = (err(1e2), err(1e3));
        assert!(e3 < 2e-2 * e2 && e3 > 0.0, "{e2} {e3}");
    }
}
