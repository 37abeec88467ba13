//! The physical scales of a scene given in the field's terms (`model.dimensional`): the one
//! definition of how the dimensionless model's time, velocity, slip, stress and state map to
//! physical units.
//!
//! With the friction μ = μ0 + a ln(V/V_ref) + b ln(Θ V_ref/D_c) on a fault under the effective
//! normal stress σ, loaded through a spring k at the velocity v0 (QDYN's V_pl), the
//! dimensionless model (see [`super::drr`]) uses
//!
//! ```text
//! t = t_phys / (D_c/v0),   v = V/v0,   θ = (b/a) ln(v0 Θ/D_c),
//! u = (δ − v0 t_phys)/D_c  (δ the slip; u + t = δ/D_c up to a constant),
//! stresses in units of aσ (= A):  ξ = k D_c/(aσ),  ε = b/a − 1,  η = G v0/(2 c_s aσ).
//! ```
//!
//! **Shear stress.** One definition throughout: the shear stress τ is the frictional strength
//! σμ, which the quasi-dynamic force balance equates to the spring stress minus the radiation
//! damping G V/(2 c_s) (QDYN's convention). In the model's terms
//!
//! ```text
//! μ = μ_ref + a (θ + f(v)),   μ_ref = μ0 + (a − b) ln(v0/V_ref),
//! τ = σ μ = σ μ_ref + aσ (θ + f(v)),
//! ```
//!
//! where μ_ref is the steady-state friction at v0 (ageing and slip laws) and θ + f(v) is the
//! dimensionless friction of the force balance u + (θ + f(v) + η v)/ξ = 0 (f = ln v). Without
//! μ0 and V_ref only the change τ − σμ_ref = aσ(θ + f(v)) is known; that is what
//! [`PhysicalScales::shear_stress_change`] gives.
//!
//! **Stress drop.** The spring stress is k(v0 t − δ) + const = −k D_c u + const, so a slip that
//! takes u from u₁ to u₂ drops the stress by k D_c (u₂ − u₁) ([`PhysicalScales::stress_drop`]),
//! positive when the block slips ahead of the load point.

use super::drr::DrrParams;
use serde::Serialize;

/// The absolute friction level: μ0 at the reference velocity V_ref.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrictionReference {
    /// μ0, the steady-state friction coefficient at `v_ref` (dimensionless).
    pub mu0: f64,
    /// V_ref, the reference velocity (velocity units).
    pub v_ref: f64,
}

/// The physical scales of a dimensional scene, in the input's (consistent) units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhysicalScales {
    /// Critical slip distance D_c (length): the slip scale.
    pub d_c: f64,
    /// Loading velocity v0 (QDYN's V_pl): the velocity scale.
    pub v0: f64,
    /// A = aσ (stress): the stress scale.
    pub a_sigma: f64,
    /// B = bσ (stress).
    pub b_sigma: f64,
    /// The effective normal stress σ, when given (needed for friction coefficients).
    pub sigma: Option<f64>,
    /// Spring stiffness k (stress per length).
    pub k: f64,
    /// μ0 at V_ref, when given (needed for absolute shear stress and friction).
    pub reference: Option<FrictionReference>,
    /// QDYN's cut-off law's μ* (μ = μ* + aΦ), when given.
    pub mu_star: Option<f64>,
}

impl PhysicalScales {
    /// The time scale D_c/v0 (time units per dimensionless time unit).
    pub fn time_scale(&self) -> f64 {
        self.d_c / self.v0
    }

    /// The dimensionless friction coefficients (a, b) = (A/σ, B/σ), when σ is known.
    pub fn friction_coefficients(&self) -> Option<(f64, f64)> {
        self.sigma.map(|s| (self.a_sigma / s, self.b_sigma / s))
    }

    /// A dimensionless time (or duration) in time units: t·D_c/v0.
    pub fn time(&self, t: f64) -> f64 {
        t * self.time_scale()
    }

    /// A dimensionless velocity v = V/v0 as the slip rate V = v·v0.
    pub fn velocity(&self, v: f64) -> f64 {
        v * self.v0
    }

    /// A dimensionless slip (in units of D_c) as a length: s·D_c.
    pub fn slip(&self, s: f64) -> f64 {
        s * self.d_c
    }

    /// The slip δ at (u, t), measured from the start of the load point: D_c·(u + t), since
    /// u = (δ − v0 t_phys)/D_c. Differences of it are the slip between two instants.
    pub fn slip_at(&self, u: f64, t: f64) -> f64 {
        self.d_c * (u + t)
    }

    /// The drop of the spring stress while u goes from `u_before` to `u_after`:
    /// k·D_c·(u_after − u_before) (positive when the block slips ahead of the load point).
    pub fn stress_drop(&self, u_before: f64, u_after: f64) -> f64 {
        self.k * self.d_c * (u_after - u_before)
    }

    /// The shear stress relative to steady sliding at v0, τ − σμ_ref = aσ·φ, for the
    /// dimensionless friction φ = θ + f(v) ([`dimensionless_friction`]).
    pub fn shear_stress_change(&self, phi: f64) -> f64 {
        self.a_sigma * phi
    }

    /// μ_ref = μ0 + (a − b) ln(v0/V_ref), the steady-state friction at v0; None without σ,
    /// μ0 and V_ref.
    pub fn reference_friction(&self) -> Option<f64> {
        let (a, b) = self.friction_coefficients()?;
        let r = self.reference?;
        Some(r.mu0 + (a - b) * (self.v0 / r.v_ref).ln())
    }

    /// The friction coefficient at φ = 0 under `friction` (so μ = level + aφ): μ_ref for the
    /// logarithmic law, μ* for QDYN's cut-off law, 0 for its regularised law (μ = aΦ); None
    /// when the scene does not fix it (no σ, no μ0/V_ref or μ*, or another law).
    pub fn friction_level(&self, friction: &super::Friction) -> Option<f64> {
        use super::Friction;
        self.friction_coefficients()?;
        match friction {
            Friction::Log => self.reference_friction(),
            Friction::CutOff { .. } => self.mu_star,
            Friction::Regularised { .. } => Some(0.0),
            _ => None,
        }
    }

    /// The friction coefficient μ = level + a·φ under `friction` for the dimensionless friction
    /// φ ([`dimensionless_friction`]; level: [`PhysicalScales::friction_level`]); None when the
    /// scene does not fix the level.
    pub fn friction_coefficient(&self, friction: &super::Friction, phi: f64) -> Option<f64> {
        let (a, _) = self.friction_coefficients()?;
        Some(self.friction_level(friction)? + a * phi)
    }

    /// The absolute shear stress τ = σμ under `friction` for the dimensionless friction φ;
    /// None when the scene does not fix μ's level.
    pub fn shear_stress(&self, friction: &super::Friction, phi: f64) -> Option<f64> {
        Some(self.sigma? * self.friction_coefficient(friction, phi)?)
    }

    /// The model's θ for the state Θ (time units): θ = (b/a) ln(v0 Θ/D_c), the same for the
    /// slip, ageing and PRZ laws under logarithmic friction (docs/state-laws.md).
    pub fn theta_from_state(&self, state: f64) -> f64 {
        (self.b_sigma / self.a_sigma) * (self.v0 * state / self.d_c).ln()
    }

    /// The state Θ (time units) for the model's θ: Θ = (D_c/v0)·exp(θ a/b), the inverse of
    /// [`PhysicalScales::theta_from_state`].
    pub fn state_from_theta(&self, theta: f64) -> f64 {
        self.time_scale() * (theta * self.a_sigma / self.b_sigma).exp()
    }
}

/// The dimensionless friction φ = θ + f(v) at (θ, w = ln v): the friction's departure from
/// steady sliding at v0 in units of a (so τ − σμ_ref = aσ·φ). Under QDYN's laws φ = Φ(v, θ)
/// ([`super::Friction::strength`]; μ = μ* + aΦ for the cut-off law, μ = aΦ for the
/// regularised law).
pub fn dimensionless_friction(params: &DrrParams, theta: f64, w: f64) -> f64 {
    let friction = params.friction;
    if !friction.is_classic() {
        return friction.strength(w, theta, 1.0 + params.epsilon).value;
    }
    theta + friction.eval(w).0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Friction;

    fn crustal() -> PhysicalScales {
        PhysicalScales {
            d_c: 1e-4,
            v0: 1e-9,
            a_sigma: 1e5,
            b_sigma: 1.5e5,
            sigma: Some(1e7),
            k: 2.5e8,
            reference: Some(FrictionReference { mu0: 0.6, v_ref: 1e-6 }),
            mu_star: None,
        }
    }

    #[test]
    fn state_and_theta_are_inverse_and_steady_sliding_at_v0_is_theta_zero() {
        let s = crustal();
        assert!(s.theta_from_state(s.d_c / s.v0).abs() < 1e-15);
        for theta in [-3.0, 0.2, 7.5] {
            let back = s.theta_from_state(s.state_from_theta(theta));
            assert!((back - theta).abs() < 1e-13, "{theta} → {back}");
        }
    }

    /// The crustal case's law: ε = b/a − 1 = 0.5 under logarithmic friction.
    fn log_law() -> DrrParams {
        DrrParams::new(1.0, 1.0, 0.5, Friction::Log)
    }

    #[test]
    fn friction_at_steady_sliding_is_the_steady_state_law() {
        // At V = v0 with Θ = D_c/v0 (θ = 0, ln v = 0): μ = μ0 + (a − b) ln(v0/V_ref).
        let s = crustal();
        let mu = s
            .friction_coefficient(&Friction::Log, dimensionless_friction(&log_law(), 0.0, 0.0))
            .unwrap();
        let direct = 0.6 + (0.01 - 0.015) * (1e-9f64 / 1e-6).ln();
        assert!((mu - direct).abs() < 1e-15, "{mu} vs {direct}");
        // Any (V, Θ): the dimensional law directly.
        let (big_v, big_theta) = (3e-7f64, 42.0f64);
        let phi =
            dimensionless_friction(&log_law(), s.theta_from_state(big_theta), (big_v / s.v0).ln());
        let direct = 0.6 + 0.01 * (big_v / 1e-6).ln() + 0.015 * (big_theta * 1e-6 / 1e-4).ln();
        assert!((s.friction_coefficient(&Friction::Log, phi).unwrap() - direct).abs() < 1e-14);
        assert!((s.shear_stress(&Friction::Log, phi).unwrap() - 1e7 * direct).abs() < 1e-7);
    }

    #[test]
    fn conversions_scale_by_dc_over_v0_v0_dc_and_k_dc() {
        let s = crustal();
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-15 * y.abs();
        assert!(close(s.time_scale(), 1e5));
        assert!(close(s.time(2.0), 2e5));
        assert!(close(s.velocity(3.0), 3e-9));
        assert!(close(s.slip(4.0), 4e-4));
        assert!(close(s.slip_at(1.0, 2.0), 3e-4));
        assert!(close(s.stress_drop(-1.0, 1.0), 2.0 * 2.5e8 * 1e-4));
        assert!(close(s.shear_stress_change(2.0), 2e5));
        let without = PhysicalScales { reference: None, ..s };
        assert_eq!(without.shear_stress(&Friction::Log, 0.0), None);
        assert_eq!(without.friction_coefficient(&Friction::Log, 0.0), None);
    }
}
