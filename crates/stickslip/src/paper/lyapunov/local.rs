//! Local ("quasi-static") Lyapunov exponents: the eigenvalues of the 3×3 Jacobian in (u, v, θ)
//! (the paper's eq. jacobian, for any state law and radiation damping η) at each step end of
//! the cycle, computed two ways, beside the large-γ formula (the paper's eq. lambda):
//!
//! - with g = γ², a = g (f'(v) + η)/ξ, p = ∂θ̇/∂v and q = ∂θ̇/∂θ the Jacobian is
//!   [[0, 1, 0], [−g, −a, −g/ξ], [0, p, q]], with the characteristic polynomial
//!   λ³ + a₂λ² + a₁λ + a₀, a₂ = a − q, a₁ = g (1 + p/ξ) − a q, a₀ = −g q (the paper's eq.
//!   lambda3 for the slip law: p = −A, q = −v, A = θ + (1+ε)(f(v) + v f'(v))); its roots by
//!   the stable Newton-and-deflation of [`crate::analysis::hopf::cubic_roots`] are the values
//!   reported;
//! - with nalgebra's Schur decomposition of the matrix, as a check where it can resolve the slow
//!   pair: its absolute error is ~1e-16 ‖J‖ ≈ 1e-16 γ² f'(v)/ξ, which at γ = 1e8 exceeds the
//!   slow pair itself;
//! - the quasi-static formula λ = −B ± √(B² − C), the slow roots of the polynomial divided by
//!   a ≈ a₂ to leading order in γ: B = ½ (−q + (ξ + p)/(f'(v) + η)), C = −ξ q/(f'(v) + η)
//!   (the paper's B = ½ (v + (ξ − A)/f'(v)), C = ξ v/f'(v) for the slip law without damping).

use crate::analysis::hopf::cubic_roots;
use crate::model::Drr;
use crate::paper::cycle_period::CyclePeriod;
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

/// The Jacobian in (u, v, θ) and its characteristic polynomial (a₂, a₁, a₀) at (u, ln v, θ),
/// with the slopes f'(v) + η, p and q of the module documentation.
pub fn jacobian(drr: &Drr, y: &[f64; 3]) -> (Matrix3<f64>, [f64; 3], [f64; 3]) {
    let params = drr.params();
    let g = params.gamma * params.gamma;
    let slopes @ [resistance, p, q] = drr.velocity_slopes(y);
    let a = g * resistance / params.xi;
    let j = Matrix3::new(0.0, 1.0, 0.0, -g, -a, -g / params.xi, 0.0, p, q);
    (j, [a - q, g * (1.0 + p / params.xi) - a * q, -g * q], slopes)
}

/// The local exponents at (u, ln v, θ).
pub fn at(drr: &Drr, y: &[f64; 3]) -> Local {
    let xi = drr.params().xi;
    let (_, [a2, a1, a0], [resistance, p, q]) = jacobian(drr, y);
    let roots = cubic_roots(a2, a1, a0);
    let (r1, r2) = (roots[1], roots[2]);
    let (slow_re, slow_im, slow_discriminant) = if r1[1] != 0.0 {
        ([r1[0], r1[0]], r1[1].abs(), -4.0 * r1[1] * r1[1])
    } else {
        ([r1[0].max(r2[0]), r1[0].min(r2[0])], 0.0, (r1[0] - r2[0]).powi(2))
    };
    let b = 0.5 * (-q + (xi + p) / resistance);
    let c = -xi * q / resistance;
    let d = b * b - c;
    let (quasi_re, quasi_im) = if d >= 0.0 {
        // Stable quadratic formula.
        let q = -b - b.signum() * d.sqrt();
        let (x1, x2) = if q != 0.0 { (q, c / q) } else { (0.0, 0.0) };
        ([x1.max(x2), x1.min(x2)], 0.0)
    } else {
        ([-b, -b], (-d).sqrt())
    };
    Local {
        fast: roots[0][0],
        slow_re,
        slow_im,
        slow_discriminant,
        quasi_re,
        quasi_im,
        quasi_discriminant: d,
    }
}

/// nalgebra's eigenvalues of the matrix, as (fast, slow pair sorted by real part then
/// imaginary part), and the matrix's largest absolute entry.
pub fn matrix_eigenvalues(drr: &Drr, y: &[f64; 3]) -> ([f64; 2], [[f64; 2]; 2], f64) {
    let (j, ..) = jacobian(drr, y);
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
pub fn first_up(orbit: &CyclePeriod, values: &[f64], from: usize, to: usize) -> Option<Crossing> {
    (from + 1..to)
        .find(|&k| values[k - 1] < 0.0 && values[k] >= 0.0)
        .map(|k| crossing(orbit, values, k))
}

/// The last downward crossing of zero by `values` over samples `from..to`.
pub fn last_down(orbit: &CyclePeriod, values: &[f64], from: usize, to: usize) -> Option<Crossing> {
    (from + 1..to)
        .rev()
        .find(|&k| values[k - 1] >= 0.0 && values[k] < 0.0)
        .map(|k| crossing(orbit, values, k))
}

fn crossing(orbit: &CyclePeriod, values: &[f64], k: usize) -> Crossing {
    let (a, b) = (values[k - 1], values[k]);
    let x = a / (a - b);
    let s = orbit.s[k - 1] + x * (orbit.s[k] - orbit.s[k - 1]);
    Crossing { time_before_tc: -s, resolution: orbit.s[k] - orbit.s[k - 1], index: k }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::OdeSystem;
    use crate::model::{DrrParams, Friction, StateLaw};

    fn params(gamma: f64, friction: Friction) -> Drr {
        Drr::new(DrrParams::new(gamma, 0.7, 0.72, friction))
    }

    fn with_law(gamma: f64, state_law: StateLaw, eta: f64) -> Drr {
        Drr::new(DrrParams { state_law, eta, ..DrrParams::new(gamma, 0.7, 0.72, Friction::Log) })
    }

    #[test]
    fn the_jacobian_in_u_v_theta_matches_differences_for_every_law() {
        // The right-hand side in (u, v, θ): du/dt = v − 1, dv/dt = v dw/dt, dθ/dt as in (u, w, θ).
        let rhs = |drr: &Drr, x: [f64; 3]| {
            let mut d = [0.0; 3];
            drr.rhs(0.0, &[x[0], x[1].ln(), x[2]], &mut d);
            [d[0], x[1] * d[1], d[2]]
        };
        for law in [StateLaw::Slip, StateLaw::Ageing, StateLaw::Prz] {
            for eta in [0.0, 0.05] {
                let drr = with_law(1e3, law, eta);
                for x in [[9.12, 0.0785, -3.84], [0.39, 20.1, -3.28]] {
                    let (j, ..) = jacobian(&drr, &[x[0], x[1].ln(), x[2]]);
                    for k in 0..3 {
                        let h = 1e-6 * x[k].abs().max(1e-3);
                        let (mut plus, mut minus) = (x, x);
                        plus[k] += h;
                        minus[k] -= h;
                        let (fp, fm) = (rhs(&drr, plus), rhs(&drr, minus));
                        for i in 0..3 {
                            let d = (fp[i] - fm[i]) / (2.0 * h);
                            assert!(
                                (j[(i, k)] - d).abs() <= 1e-6 * (1.0 + d.abs()),
                                "{law:?} η = {eta} {x:?}: J[{i}][{k}] = {} vs {d}",
                                j[(i, k)]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn polynomial_roots_agree_with_the_matrix_and_the_paper_form() {
        // States of Fig. 1's cycle: stick, late stick, rise, slip peak.
        let states = [
            [9.12, (0.0785f64).ln(), -3.84],
            [-0.70, (0.357f64).ln(), 1.52],
            [0.39, (20.1f64).ln(), -3.28],
            [8.17, (3422.0f64).ln(), -13.86],
        ];
        let models = [
            params(1e3, Friction::Log),
            params(1e3, Friction::Power { alpha: 0.15 }),
            with_law(1e3, StateLaw::Ageing, 0.0),
            with_law(1e3, StateLaw::Prz, 0.05),
        ];
        for p in &models {
            let friction = (p.params().friction, p.params().state_law, p.params().eta);
            for y in states {
                let l = at(p, &y);
                let (fast, slow, _) = matrix_eigenvalues(p, &y);
                assert!(
                    (l.fast - fast[0]).abs() < 1e-9 * fast[0].abs(),
                    "{friction:?} {y:?}: {} vs {fast:?}",
                    l.fast
                );
                // Slow pair: sort ours like the matrix's (by real part, then imaginary part).
                let mut ours = if l.slow_im > 0.0 {
                    [[l.slow_re[0], -l.slow_im], [l.slow_re[0], l.slow_im]]
                } else {
                    [[l.slow_re[1], 0.0], [l.slow_re[0], 0.0]]
                };
                ours.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
                for (a, b) in ours.iter().zip(&slow) {
                    let scale = 1.0 + b[0].hypot(b[1]);
                    assert!(
                        (a[0] - b[0]).abs() < 1e-7 * scale && (a[1] - b[1]).abs() < 1e-7 * scale,
                        "{friction:?} {y:?}: {ours:?} vs {slow:?}"
                    );
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
        // The formula's error is O(λ_slow/λ_fast) ∝ 1/γ², for every law and η.
        let y = [-0.70, (0.357f64).ln(), 1.52];
        for (law, eta) in [(StateLaw::Slip, 0.0), (StateLaw::Ageing, 0.0), (StateLaw::Prz, 0.05)] {
            let err = |gamma: f64| {
                let l = at(&with_law(gamma, law, eta), &y);
                (l.quasi_re[0] - l.slow_re[0]).abs() + (l.quasi_im - l.slow_im).abs()
            };
            let (e2, e3) = (err(1e2), err(1e3));
            assert!(e3 < 2e-2 * e2 && e3 > 0.0, "{law:?} η = {eta}: {e2} {e3}");
        }
    }
}
