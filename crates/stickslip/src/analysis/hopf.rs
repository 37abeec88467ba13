//! Linear stability of the fixed point and the Hopf threshold.
//!
//! At the fixed point (v = 1, see [`Drr::fixed_point`]) the Jacobian in (u, v, θ) has the
//! characteristic polynomial λ³ + a₂λ² + a₁λ + a₀ with g = γ², f₁ = f'(1), the radiation
//! damping η and the state law's relaxation rate κ = −F'(x*) (1 for the slip, ageing and PRZ
//! laws, so that their linearisations coincide):
//!
//! ```text
//! a₂ = κ + g (f₁ + η)/ξ,   a₁ = g (1 + κ (η − ε f₁)/ξ),   a₀ = g κ.
//! ```
//!
//! Routh–Hurwitz (a₂a₁ = a₀) gives the threshold and the frequency there:
//!
//! ```text
//! ε_c = [η + ξ g (f₁ + η) / (κ (κξ + g (f₁ + η)))] / f₁,   ω_c² = a₀/a₂ = g κ ξ/(κξ + g (f₁ + η)),
//! ```
//!
//! i.e. ε_c = ξγ²/(γ²+ξ) for f = ln v, η = 0; as γ → ∞, ε_c → (ξ/κ + η)/f₁ and
//! ω_c² → κξ/(f₁ + η): damping raises the threshold by η/f₁ and slows the oscillation
//! (derivation: docs/state-laws.md).
//!
//! **Quasi-dynamic model** (no inertia, [`crate::model::quasi_dynamic`]): on the force balance
//! G = 0 the linearisation in (u, θ) has λ² + bλ + c with F = f₁ + η,
//!
//! ```text
//! b = (ξ + κ (η − ε f₁))/F,   c = κ ξ/F,
//! ```
//!
//! the γ → ∞ limit of a₁/a₂ and a₀/a₂: ε_c = (ξ/κ + η)/f₁ and ω_c² = κξ/(f₁ + η) exactly (the
//! inertial formulas' limits). Its stabilised w equation adds the eigenvalue −κ_G (the
//! relaxation of G), which is not a property of the model and is not reported.
//!
//! **QDYN's friction laws** (cut-off and regularised, [`crate::model::Friction`]), where the
//! friction Φ(v, θ) is not θ + f(v): with A = Φ_v + η and P = Φ_θ at the fixed point and the
//! state law's argument x = θ/(1+ε) + ln v, the same polynomial holds with f₁ + η → A and
//! (1+ε) f₁ → B = (1+ε) P:
//!
//! ```text
//! a₂ = κ + g A/ξ,   a₁ = g (1 + κ (A − B)/ξ),   a₀ = g κ,
//! ```
//!
//! so the threshold is B = A + ξ g A/(κ (κξ + g A)) (quasi-dynamic: A + ξ/κ), solved for ε:
//! ε_c = B/P − 1 for the cut-off law (A and P do not depend on ε), by bisection for the
//! regularised law (whose P does, through ε ln v*).
//!
//! The eigenvalues are computed from the polynomial, not from the 3×3 matrix: at γ = 1e8 its
//! entries reach 1e16 and a matrix eigen-solver would lose the O(1) real part of the slow pair.
//! The large real root is found by Newton's method from the left of all roots, then deflated
//! without cancellation (q = −a₀/λ_r, p = (q − a₁)/λ_r).

use crate::model::{Drr, DrrParams};
use serde::Serialize;

/// The "hopf" analysis of a scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HopfReport {
    /// Fixed point (u, v, θ) (dimensionless).
    pub fixed_point: [f64; 3],
    /// Eigenvalues of the Jacobian at the fixed point, as [re, im] (1/time unit), fast real
    /// one first; without inertia the two of the quasi-dynamic model (see the module docs).
    pub eigenvalues: Vec<[f64; 2]>,
    /// Threshold ε_c (dimensionless; ξγ²/(ξ + γ²) for f = ln v without damping). Under the
    /// regularised law with v* < 1 the fixed point may stay stable for every ε: then the
    /// largest double (no threshold below it).
    pub epsilon_c: f64,
    /// Angular frequency at threshold ω_c = √(a₀/a₂) (1/time unit).
    pub omega_c: f64,
    /// Period at threshold 2π/ω_c (time units); → 2π/√ξ as γ → ∞ for f = ln v.
    pub period_c: f64,
    /// The paper's large-γ threshold period 2π/√ξ (time units).
    pub period_c_large_gamma: f64,
    /// Whether ε > ε_c (fixed point unstable, oscillation expected).
    pub above_threshold: bool,
    /// Largest real part of the eigenvalues (> 0: unstable).
    pub max_real_part: f64,
}

/// Coefficients (a₂, a₁, a₀) of the inertial model's characteristic polynomial at the fixed
/// point.
pub fn characteristic_polynomial(drr: &Drr) -> (f64, f64, f64) {
    let p = drr.params();
    if !p.friction.is_classic() {
        let (a, b, kappa) = slopes(drr);
        let g = p.gamma * p.gamma;
        return (kappa + g * a / p.xi, g * (1.0 + kappa * (a - b) / p.xi), g * kappa);
    }
    let g = p.gamma * p.gamma;
    let (_, f1) = p.friction.eval(0.0);
    let kappa = p.state_law.steady_rate();
    (
        kappa + g * (f1 + p.eta) / p.xi,
        g * (1.0 + kappa * (p.eta - p.epsilon * f1) / p.xi),
        g * kappa,
    )
}

/// Coefficients (b, c) of the quasi-dynamic model's characteristic polynomial λ² + bλ + c at
/// the fixed point, on the force balance (see the module docs).
pub fn quasi_dynamic_polynomial(drr: &Drr) -> (f64, f64) {
    let p = drr.params();
    if !p.friction.is_classic() {
        let (a, b, kappa) = slopes(drr);
        return ((p.xi + kappa * (a - b)) / a, kappa * p.xi / a);
    }
    let (_, f1) = p.friction.eval(0.0);
    let kappa = p.state_law.steady_rate();
    let e = f1 + p.eta;
    ((p.xi + kappa * (p.eta - p.epsilon * f1)) / e, kappa * p.xi / e)
}

/// The threshold ε_c at the parameters' γ, ξ, η, friction and state law (their ε is ignored);
/// without inertia, its γ → ∞ limit (ξ/κ + η)/f₁.
pub fn epsilon_c(drr: &Drr) -> f64 {
    let p = drr.params();
    if !p.friction.is_classic() {
        return qdyn_epsilon_c(drr);
    }
    let (_, f1) = p.friction.eval(0.0);
    let kappa = p.state_law.steady_rate();
    if !p.inertia {
        return (p.xi / kappa + p.eta) / f1;
    }
    let g = p.gamma * p.gamma;
    let e = f1 + p.eta;
    (p.eta + p.xi * g * e / (kappa * (kappa * p.xi + g * e))) / f1
}

/// (A, B, κ) at the fixed point under QDYN's laws (module docs): A = Φ_w + η, B = (1+ε)Φ_θ.
fn slopes(drr: &Drr) -> (f64, f64, f64) {
    let p = drr.params();
    let t = drr.strength(&drr.fixed_point());
    (t.d1[0], (1.0 + p.epsilon) * t.d1[1], p.state_law.steady_rate())
}

/// B at threshold minus B at the parameters' ε, under QDYN's laws: < 0 where the fixed point
/// is unstable.
fn threshold_margin(drr: &Drr) -> f64 {
    let p = drr.params();
    let (a, b, kappa) = slopes(drr);
    let critical = if p.inertia {
        let g = p.gamma * p.gamma;
        a + p.xi * g * a / (kappa * (kappa * p.xi + g * a))
    } else {
        a + p.xi / kappa
    };
    critical - b
}

/// ε_c under QDYN's laws: ε where [`threshold_margin`] vanishes, by bisection between
/// ε = −1 (no state effect: stable) and the first of 1, 2, 4, … 2^40 where it is negative;
/// the largest double when there is none.
fn qdyn_epsilon_c(drr: &Drr) -> f64 {
    let base = *drr.params();
    let margin = |epsilon: f64| threshold_margin(&Drr::new(DrrParams { epsilon, ..base }));
    let mut lo = -1.0f64;
    let mut hi = 1.0f64;
    while margin(hi) > 0.0 {
        lo = hi;
        hi *= 2.0;
        if hi > 1.1e12 {
            return f64::MAX;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if margin(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

/// Roots of λ² + bλ + c as [re, im].
fn quadratic_roots(b: f64, c: f64) -> Vec<[f64; 2]> {
    let disc = b * b - 4.0 * c;
    if disc >= 0.0 {
        // Stable quadratic formula.
        let s = -0.5 * (b + b.signum() * disc.sqrt());
        let (r1, r2) = if s != 0.0 { (s, c / s) } else { (0.0, 0.0) };
        vec![[r1, 0.0], [r2, 0.0]]
    } else {
        let im = 0.5 * (-disc).sqrt();
        vec![[-0.5 * b, im], [-0.5 * b, -im]]
    }
}

/// Roots of λ³ + a₂λ² + a₁λ + a₀ as [re, im], the real root found by Newton first.
pub fn cubic_roots(a2: f64, a1: f64, a0: f64) -> Vec<[f64; 2]> {
    let p = |x: f64| ((x + a2) * x + a1) * x + a0;
    let dp = |x: f64| (3.0 * x + 2.0 * a2) * x + a1;
    // Start left of every root (Cauchy bound): Newton then converges to a real root.
    let mut x = -(1.0 + a2.abs().max(a1.abs()).max(a0.abs()));
    for _ in 0..500 {
        let step = p(x) / dp(x);
        if !step.is_finite() {
            break;
        }
        x -= step;
        if step.abs() <= 1e-16 * x.abs().max(1e-300) {
            break;
        }
    }
    let real = x;
    // Deflate: (λ − r)(λ² + bλ + c) with c = −a₀/r, b = (c − a₁)/r.
    let c = -a0 / real;
    let b = (c - a1) / real;
    let mut roots = vec![[real, 0.0]];
    roots.extend(quadratic_roots(b, c));
    roots
}

/// The Hopf analysis.
pub fn analyse(drr: &Drr) -> HopfReport {
    let params = drr.params();
    let epsilon_c = epsilon_c(drr);
    // ω_c is taken at ε_c: under the regularised law a₂ (and c) depend on ε.
    let at_threshold = Drr::new(DrrParams { epsilon: epsilon_c, ..*params });
    let threshold = if params.friction.is_classic() { drr } else { &at_threshold };
    let (eigenvalues, omega_c) = if params.inertia {
        let (a2, a1, a0) = characteristic_polynomial(drr);
        let (a2_c, _, a0_c) = characteristic_polynomial(threshold);
        (cubic_roots(a2, a1, a0), (a0_c / a2_c).sqrt())
    } else {
        let (b, c) = quasi_dynamic_polynomial(drr);
        // ω_c² = c at b = 0, where c does not depend on ε for the paper's laws.
        (quadratic_roots(b, c), quasi_dynamic_polynomial(threshold).1.sqrt())
    };
    let fp = drr.fixed_point();
    HopfReport {
        fixed_point: [fp[0], fp[1].exp(), fp[2]],
        max_real_part: eigenvalues.iter().map(|e| e[0]).fold(f64::NEG_INFINITY, f64::max),
        eigenvalues,
        epsilon_c,
        omega_c,
        period_c: 2.0 * std::f64::consts::PI / omega_c,
        period_c_large_gamma: 2.0 * std::f64::consts::PI / params.xi.sqrt(),
        above_threshold: params.epsilon > epsilon_c,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::{JacobianMatrix, OdeSystem};
    use crate::model::{DrrParams, Friction, StateLaw};
    use nalgebra::Matrix3;

    fn drr(gamma: f64, xi: f64, epsilon: f64, friction: Friction) -> Drr {
        Drr::new(DrrParams::new(gamma, xi, epsilon, friction))
    }

    fn frictions() -> [Friction; 5] {
        [
            Friction::Log,
            Friction::Asinh,
            Friction::Power { alpha: 0.31 },
            Friction::CutOff { v1: 0.3, v2: 0.5 },
            Friction::Regularised { f_star: 0.7, v_star: 3.0 },
        ]
    }

    /// The model's analytic Jacobian at its fixed point, in (u, w, θ). At v = 1 the change of
    /// variables w = ln v is the identity to first order, so its eigenvalues are those of the
    /// linearisation in (u, v, θ).
    fn matrix_at_fixed_point(d: &Drr) -> Matrix3<f64> {
        let mut columns = [0.0; 9];
        d.jacobian(0.0, &d.fixed_point(), &mut JacobianMatrix::new(&mut columns, 3));
        Matrix3::from_column_slice(&columns)
    }

    fn matrix_eigenvalues(d: &Drr) -> Vec<[f64; 2]> {
        matrix_at_fixed_point(d).complex_eigenvalues().iter().map(|z| [z.re, z.im]).collect()
    }

    /// Two eigenvalue lists agree, once sorted, within `tolerance` × (1 + |λ|) (relative) or
    /// `tolerance` (absolute, `relative` false).
    fn assert_same_eigenvalues(
        mut ours: Vec<[f64; 2]>,
        mut reference: Vec<[f64; 2]>,
        tolerance: f64,
        relative: bool,
        what: &str,
    ) {
        let key = |a: &[f64; 2], b: &[f64; 2]| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1]));
        reference.sort_by(key);
        ours.sort_by(key);
        for (a, b) in ours.iter().zip(&reference) {
            let scale = if relative { 1.0 + b[0].hypot(b[1]) } else { 1.0 };
            assert!(
                (a[0] - b[0]).abs() < tolerance * scale && (a[1] - b[1]).abs() < tolerance * scale,
                "{what}: {ours:?} vs {reference:?}"
            );
        }
    }

    /// ε_c and ω_c of `base` (its ε ignored) against the analytic Jacobian: the ε where the
    /// largest real part of its numerically computed eigenvalues crosses 0 (bisection) to 1e-9,
    /// and the imaginary part there to 1e-7. Returns the derived report.
    fn assert_threshold_matches_the_eigenvalues(base: DrrParams) -> HopfReport {
        let max_re = |p: DrrParams| {
            matrix_eigenvalues(&Drr::new(p)).iter().map(|e| e[0]).fold(f64::NEG_INFINITY, f64::max)
        };
        let derived = analyse(&Drr::new(base));
        let (mut lo, mut hi) = (0.0, 20.0);
        assert!(
            max_re(DrrParams { epsilon: lo, ..base }) < 0.0
                && max_re(DrrParams { epsilon: hi, ..base }) > 0.0
        );
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if max_re(DrrParams { epsilon: mid, ..base }) < 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let eps = 0.5 * (lo + hi);
        assert!(
            (eps - derived.epsilon_c).abs() < 1e-9 * derived.epsilon_c,
            "{base:?}: {eps} vs {}",
            derived.epsilon_c
        );
        let omega = matrix_eigenvalues(&Drr::new(DrrParams { epsilon: eps, ..base }))
            .iter()
            .map(|e| e[1])
            .fold(0.0, f64::max);
        assert!(
            (omega - derived.omega_c).abs() < 1e-7 * derived.omega_c,
            "{base:?}: ω {omega} vs {}",
            derived.omega_c
        );
        derived
    }

    #[test]
    fn eigenvalues_agree_with_a_matrix_eigensolver_for_every_law_at_moderate_gamma() {
        for friction in frictions() {
            // The no-healing law has no fixed point to linearise at.
            for (_, state_law) in StateLaw::ALL.into_iter().filter(|(_, l)| l.heals()) {
                for eta in [0.0, 0.05, 0.8] {
                    for gamma in [1.0, 3.0, 10.0, 100.0] {
                        let d = Drr::new(DrrParams {
                            state_law,
                            eta,
                            ..DrrParams::new(gamma, 0.7, 0.72, friction)
                        });
                        assert_same_eigenvalues(
                            analyse(&d).eigenvalues,
                            matrix_eigenvalues(&d),
                            1e-9,
                            true,
                            &format!("{friction:?} {state_law:?} η={eta} γ={gamma}"),
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn threshold_is_where_the_slow_pair_crosses_the_axis() {
        for gamma in [10.0, 1e3, 1e8] {
            let base = analyse(&drr(gamma, 0.7, 0.72, Friction::Log));
            let ec = base.epsilon_c;
            assert!((ec - 0.7 * gamma * gamma / (gamma * gamma + 0.7)).abs() < 1e-14);
            let below = analyse(&drr(gamma, 0.7, ec * (1.0 - 1e-6), Friction::Log));
            let above = analyse(&drr(gamma, 0.7, ec * (1.0 + 1e-6), Friction::Log));
            assert!(below.max_real_part < 0.0 && !below.above_threshold, "γ={gamma}: {below:?}");
            assert!(above.max_real_part > 0.0 && above.above_threshold, "γ={gamma}: {above:?}");
            let at = analyse(&drr(gamma, 0.7, ec, Friction::Log));
            let slow = at.eigenvalues.iter().find(|e| e[1] > 0.0).unwrap();
            assert!(
                (slow[1] - at.omega_c).abs() < 1e-8 * at.omega_c,
                "γ={gamma}: {slow:?} vs ω_c {}",
                at.omega_c
            );
        }
        let large = analyse(&drr(1e8, 0.8, 1.0, Friction::Log));
        assert!((large.period_c - large.period_c_large_gamma).abs() < 1e-12 * large.period_c);
    }

    /// ε_c and ω_c against the matrix eigenvalues: the ε where the largest real part of the
    /// numerically computed eigenvalues of the analytic Jacobian crosses 0 (bisection), and the
    /// imaginary part there. Every state law, friction law and damping, at moderate γ where a
    /// matrix eigensolver is accurate.
    #[test]
    fn threshold_and_frequency_match_the_jacobians_eigenvalues_for_every_law_and_damping() {
        for friction in frictions() {
            // The no-healing law has no fixed point to linearise at.
            for (_, state_law) in StateLaw::ALL.into_iter().filter(|(_, l)| l.heals()) {
                for eta in [0.0, 0.1, 1.0] {
                    for gamma in [2.0, 10.0, 50.0] {
                        assert_threshold_matches_the_eigenvalues(DrrParams {
                            state_law,
                            eta,
                            ..DrrParams::new(gamma, 0.7, 0.0, friction)
                        });
                    }
                }
            }
        }
    }

    #[test]
    fn the_three_state_laws_share_the_threshold_and_frequency() {
        // Under QDYN's laws the PRZ fixed point (x* = ln 2) has another Φ_θ: not shared.
        for friction in frictions().into_iter().filter(|f| f.is_classic()) {
            for gamma in [10.0, 1e3, 1e8] {
                let at = |state_law| {
                    analyse(&Drr::new(DrrParams {
                        state_law,
                        ..DrrParams::new(gamma, 0.8, 1.0, friction)
                    }))
                };
                let slip = at(StateLaw::Slip);
                for law in [StateLaw::Ageing, StateLaw::Prz] {
                    let other = at(law);
                    let close = |a: f64, b: f64| (a - b).abs() <= 1e-14 * a.abs().max(b.abs());
                    assert!(
                        close(other.epsilon_c, slip.epsilon_c)
                            && close(other.omega_c, slip.omega_c),
                        "{friction:?} {law:?} γ={gamma}: {other:?} vs {slip:?}"
                    );
                    for (a, b) in other.eigenvalues.iter().zip(&slip.eigenvalues) {
                        assert!(
                            (a[0] - b[0]).abs() <= 1e-13 * b[0].hypot(b[1])
                                && (a[1] - b[1]).abs() <= 1e-13 * b[0].hypot(b[1]),
                            "{friction:?} {law:?} γ={gamma}"
                        );
                    }
                }
            }
        }
    }

    /// The quasi-dynamic threshold against the eigenvalues of its stabilised Jacobian (the
    /// model's pair and the stabilisation's −κ_G): ε_c by bisection on the largest real part,
    /// ω_c there, for every friction law, state law and η; and the inertial threshold tends to
    /// it as γ grows.
    #[test]
    fn quasi_dynamic_threshold_matches_the_eigenvalues_of_its_linearisation() {
        use crate::model::quasi_dynamic::CONSTRAINT_RELAXATION_RATE;
        for friction in frictions() {
            // The no-healing law has no fixed point to linearise at.
            for (_, state_law) in StateLaw::ALL.into_iter().filter(|(_, l)| l.heals()) {
                for eta in [0.01, 0.1, 1.0] {
                    let base = DrrParams {
                        state_law,
                        ..DrrParams::quasi_dynamic(0.7, 0.0, eta, friction)
                    };
                    // Eigenvalues at ε = 1.3: the reported pair and −κ_G.
                    let at = Drr::new(DrrParams { epsilon: 1.3, ..base });
                    let mut ours = analyse(&at).eigenvalues;
                    ours.push([-CONSTRAINT_RELAXATION_RATE, 0.0]);
                    assert_same_eigenvalues(
                        ours,
                        matrix_eigenvalues(&at),
                        1e-10,
                        false,
                        &format!("{friction:?} {state_law:?} η={eta}"),
                    );
                    let derived = assert_threshold_matches_the_eigenvalues(base);
                    // The inertial threshold at γ = 1e6 is the quasi-dynamic one to O(1/γ²).
                    let inertial =
                        analyse(&Drr::new(DrrParams { gamma: 1e6, inertia: true, ..base }));
                    assert!(
                        (inertial.epsilon_c - derived.epsilon_c).abs() < 1e-10
                            && (inertial.omega_c - derived.omega_c).abs() < 1e-10,
                        "{friction:?} {state_law:?} η={eta}: {inertial:?} vs {derived:?}"
                    );
                }
            }
        }
        let qd = analyse(&Drr::new(DrrParams::quasi_dynamic(0.8, 1.0, 0.05, Friction::Log)));
        assert!(
            (qd.epsilon_c - 0.85).abs() < 1e-15
                && (qd.omega_c - (0.8f64 / 1.05).sqrt()).abs() < 1e-15
                && qd.above_threshold,
            "{qd:?}"
        );
    }

    #[test]
    fn damping_raises_the_threshold_by_eta_over_f1_at_large_gamma() {
        for eta in [0.0, 0.3, 2.0] {
            let h = analyse(&Drr::new(DrrParams {
                eta,
                ..DrrParams::new(1e8, 0.8, 1.0, Friction::Log)
            }));
            assert!((h.epsilon_c - (0.8 + eta)).abs() < 1e-12, "η={eta}: {}", h.epsilon_c);
            assert!(
                (h.omega_c - (0.8 / (1.0 + eta)).sqrt()).abs() < 1e-12,
                "η={eta}: {}",
                h.omega_c
            );
        }
    }
}
