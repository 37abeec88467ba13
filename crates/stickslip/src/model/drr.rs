//! The Dieterich–Ruina–Rice spring-slider in dimensionless form, integrated in
//! y = (u, w = ln v, θ):
//!
//! ```text
//! du/dt = v − 1,
//! dw/dt = −γ² e^{−w} G,   G = u + (θ + f(v) + η v)/ξ,
//! dθ/dt = (1+ε) v F(x),   x = θ/(1+ε) + f(v),
//! ```
//!
//! with the friction law f (see [`Friction`]), the state law F (see [`StateLaw`]; the slip law
//! F(x) = −x gives the paper's dθ/dt = −v(θ + (1+ε) f(v))) and the radiation damping η ≥ 0
//! (η v is the damping stress η_dim·V over A; see docs/state-laws.md).
//!
//! Working in w keeps v > 0 automatically and lets v span 1e-30 … 1e10.
//!
//! Without inertia (`inertia: false`, the quasi-dynamic limit γ → ∞ at fixed η > 0) the w
//! equation is the stabilised force balance of [`super::quasi_dynamic`] instead.
//!
//! Reference: Pomeau & Le Berre, "Critical speed-up vs critical slow-down" (eqs. DR1–DR3
//! rescaled); Rice & Tse (1986); Dieterich (1979); Ruina (1983); Perrin, Rice & Zheng (1995).

use super::friction::{Friction, Strength};
use super::quasi_dynamic::{self, CONSTRAINT_RELAXATION_RATE};
use super::state_law::{LawTerms, StateLaw};
use crate::integrate::{ImexSystem, JacobianMatrix, OdeSystem};

/// Parameters of the dimensionless DRR model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DrrParams {
    /// γ = (D_c/v0)·√(k/M) > 0, the stiffness parameter; +∞ without inertia.
    pub gamma: f64,
    /// ξ = k·D_c/A > 0.
    pub xi: f64,
    /// ε = (B − A)/A.
    pub epsilon: f64,
    /// The friction law f(v).
    pub friction: Friction,
    /// The state-evolution law.
    pub state_law: StateLaw,
    /// Radiation damping η = η_dim·v0/A ≥ 0 (dimensionless; η_dim = G/(2c_s)).
    pub eta: f64,
    /// Whether the block has inertia. Without it (the quasi-dynamic model, η > 0) the force
    /// balance determines v ([`super::quasi_dynamic`]) and `gamma` is +∞, the limit it is.
    pub inertia: bool,
}

impl DrrParams {
    /// The paper's model: the slip law without radiation damping.
    pub fn new(gamma: f64, xi: f64, epsilon: f64, friction: Friction) -> Self {
        Self { gamma, xi, epsilon, friction, state_law: StateLaw::Slip, eta: 0.0, inertia: true }
    }

    /// The quasi-dynamic model (no inertia) with radiation damping η > 0 and the slip law;
    /// γ is +∞, the limit this model is.
    pub fn quasi_dynamic(xi: f64, epsilon: f64, eta: f64, friction: Friction) -> Self {
        Self { eta, inertia: false, ..Self::new(f64::INFINITY, xi, epsilon, friction) }
    }

    /// Whether this is the paper's model (slip law, η = 0), for which the paper-specific
    /// analyses are derived.
    pub fn is_papers_model(&self) -> bool {
        self.state_law == StateLaw::Slip
            && self.eta == 0.0
            && self.inertia
            && self.friction.is_classic()
    }
}

/// Index of u in the state vector.
pub const U: usize = 0;
/// Index of w = ln v in the state vector.
pub const W: usize = 1;
/// Index of θ in the state vector.
pub const THETA: usize = 2;

/// ln v below which the arrest rate γ²e^(−w) is held at its value here ([`Drr`]).
///
/// Where an arrest's floor −(ξu + θ) lies far below (a far-off start: after v = 1e30 the floor
/// is near ln v = −2e21), e^(−w) leaves the range of doubles and no integrator can pass. Below
/// ln v = −500 (v < 1e-217) the block is stuck to every digit: v − 1 rounds to −1, and the
/// distance G to the slow manifold relaxes at a rate above γ²e^500/ξ ≈ 1e217 γ², so on any
/// resolvable time scale G = 0 to all digits whatever the rate. Holding the rate at its value
/// at −500 keeps the same solution in double precision (G still relaxes to 0 within
/// ~1e-217/γ², ln v follows −(ξu + θ)) with finite values everywhere. Only under logarithmic
/// friction, the one law with such a floor: under the power law f(v) stays bounded as v → 0
/// and under the asinh law v reaches 0 in finite time, so no slow manifold lies below.
pub const ARREST_RATE_HELD_BELOW: f64 = -500.0;

/// The DRR system in (u, w, θ).
#[derive(Debug, Clone, Copy)]
pub struct Drr {
    params: DrrParams,
    gamma2: f64,
}

/// The velocity-dependent part of the force balance, f(v) + η v, at w = ln v: its value, its
/// w-derivative v f'(v) + η v and the w-derivative of that.
#[derive(Debug, Clone, Copy)]
struct Resistance {
    value: f64,
    slope: f64,
    curvature: f64,
}

impl Drr {
    /// The system for the given parameters.
    pub fn new(params: DrrParams) -> Self {
        Self { params, gamma2: params.gamma * params.gamma }
    }

    /// The parameters.
    pub fn params(&self) -> &DrrParams {
        &self.params
    }

    fn resistance(&self, w: f64) -> Resistance {
        let p = &self.params;
        let (f, vfp) = p.friction.eval(w);
        let h = p.friction.d_vfprime_dw(w);
        if p.eta == 0.0 {
            return Resistance { value: f, slope: vfp, curvature: h };
        }
        let v = w.exp();
        let ev = p.eta * v;
        Resistance { value: self.resistance_value(f, v), slope: vfp + ev, curvature: h + ev }
    }

    /// Φ(w, θ) + η v at y with its derivatives in (w, θ) ([`Strength`]); the third ones only
    /// when `third` gives v = e^w (the quasi-dynamic Jacobian and ∂J/∂y need them; their caller
    /// has v at hand, so it is not computed twice). For the paper's laws Φ = θ + f(v), with the
    /// value formed as θ + (f + η v).
    fn total(&self, y: &[f64], third: Option<f64>) -> Strength {
        let p = &self.params;
        let w = y[W];
        if !p.friction.is_classic() {
            let v = third.unwrap_or_else(|| w.exp());
            return p.friction.strength(w, y[THETA], 1.0 + p.epsilon).damped(p.eta, v);
        }
        let r = self.resistance(w);
        let d3 = match third {
            Some(v) => p.friction.d2_vfprime_dw2(w) + if p.eta == 0.0 { 0.0 } else { p.eta * v },
            None => 0.0,
        };
        Strength {
            value: y[THETA] + r.value,
            d1: [r.slope, 1.0],
            d2: [r.curvature, 0.0, 0.0],
            d3: [d3, 0.0, 0.0, 0.0],
        }
    }

    /// Φ + η v at y with its derivatives in (w, θ) up to third order: the friction and damping
    /// of the force balance G = u + (Φ + η v)/ξ.
    pub fn strength(&self, y: &[f64]) -> Strength {
        self.total(y, Some(y[W].exp()))
    }

    /// f(v) + η v alone, the value of [`Drr::resistance`], given f = f(v) and v: the right-hand
    /// side's path, which needs no derivatives.
    fn resistance_value(&self, f: f64, v: f64) -> f64 {
        let eta = self.params.eta;
        if eta == 0.0 {
            f
        } else {
            f + eta * v
        }
    }

    /// G = u + (θ + r)/ξ at y, given the resistance r = f(v) + η v there.
    fn offset(&self, y: &[f64], resistance: f64) -> f64 {
        self.offset_given(y, y[THETA] + resistance)
    }

    /// G = u + (Φ + η v)/ξ at y, given Φ + η v there.
    fn offset_given(&self, y: &[f64], total: f64) -> f64 {
        y[U] + total / self.params.xi
    }

    /// The fixed point (u*, w* = 0, θ*): v = 1, θ* = (1+ε)(x* − f(1)) with x* the state law's
    /// steady value of x, and u* = −(θ* + f(1) + η)/ξ. The no-healing law has no fixed point
    /// ([`StateLaw::heals`]): for it this is the point of the slow manifold at v = 1 with
    /// x = 0, the reference its scenes start from by default, and not stationary.
    pub fn fixed_point(&self) -> [f64; 3] {
        let p = &self.params;
        if !p.friction.is_classic() {
            // x = θ/(1+ε) + ln v: θ* = (1+ε) x*.
            let theta = (1.0 + p.epsilon) * p.state_law.steady_x();
            return [-self.total(&[0.0, 0.0, theta], None).value / p.xi, 0.0, theta];
        }
        let (f1, _) = p.friction.eval(0.0);
        let theta = (1.0 + p.epsilon) * (p.state_law.steady_x() - f1);
        [-(theta + f1 + p.eta) / p.xi, 0.0, theta]
    }

    /// Whether `y` is a rest point of the unforced system: its right-hand side is exactly
    /// zero, so the state never changes (a start on the fixed point, v = 1 with θ at its
    /// steady value, where nothing happens).
    pub fn at_rest(&self, y: &[f64; 3]) -> bool {
        let mut dydt = [0.0; 3];
        OdeSystem::rhs(self, 0.0, y, &mut dydt);
        dydt.iter().all(|d| *d == 0.0)
    }

    /// The distance to the slow manifold, G = u + (Φ + η v)/ξ (θ + f(v) + η v for the paper's
    /// laws; dv/dt = −γ² G).
    pub fn manifold_offset(&self, y: &[f64]) -> f64 {
        self.offset_given(y, self.total(y, None).value)
    }

    /// ∂G/∂w = (Φ_w + η v)/ξ ((v f'(v) + η v)/ξ for the paper's laws) at y: how an error in
    /// w shows in the manifold offset G.
    pub fn manifold_offset_slope(&self, y: &[f64]) -> f64 {
        self.total(y, None).d1[0] / self.params.xi
    }

    /// w on the slow manifold G = 0 for given (u, θ), if the friction law allows it
    /// (f(v) + η v = −(ξu + θ) must be in the range of f + η v).
    pub fn manifold_w(&self, u: f64, theta: f64) -> Option<f64> {
        let target = -(self.params.xi * u + theta);
        let w = match self.params.friction {
            // Φ + η v increases strictly with w (Φ_w > 0): solve Φ + η v = −ξu.
            Friction::CutOff { .. } | Friction::Regularised { .. } => solve(|w| {
                let t = self.total(&[u, w, theta], None);
                (t.value + self.params.xi * u, t.d1[0])
            })?,
            _ if self.params.eta > 0.0 => solve(|w| {
                let r = self.resistance(w);
                (r.value - target, r.slope)
            })?,
            Friction::Log => target,
            Friction::Asinh => (target > 0.0).then(|| target.sinh().ln())?,
            Friction::Power { alpha } => {
                let base = 1.0 + alpha * target;
                (base > 0.0).then(|| base.ln() / alpha)?
            }
        };
        w.is_finite().then_some(w)
    }

    /// u on the slow manifold for given (w, θ).
    pub fn manifold_u(&self, w: f64, theta: f64) -> f64 {
        if !self.params.friction.is_classic() {
            return -self.total(&[0.0, w, theta], None).value / self.params.xi;
        }
        -(theta + self.resistance(w).value) / self.params.xi
    }

    /// x = θ/(1+ε) + σ(w), the state law's argument, with σ' and σ''
    /// ([`Friction::state_argument`]: σ = f(v) for the paper's laws, ln v for QDYN's).
    fn law_argument(&self, y: &[f64]) -> (f64, f64, f64) {
        let (sigma, s, h) = self.params.friction.state_argument(y[W]);
        (self.law_x(y[THETA], sigma), s, h)
    }

    /// x = θ/(1+ε) + σ, given σ(w).
    fn law_x(&self, theta: f64, f: f64) -> f64 {
        theta / (1.0 + self.params.epsilon) + f
    }

    /// dθ/dt = (1+ε) v F(x) alone, the value of [`Drr::state_rate`], given f = f(v) and
    /// v = e^w: the right-hand side's path, which needs no derivatives.
    fn state_rate_value(&self, y: &[f64], f: f64, v: f64) -> f64 {
        let p = &self.params;
        (1.0 + p.epsilon) * p.state_law.rate(y[W], v, self.law_x(y[THETA], f))
    }

    /// dθ/dt = R = (1+ε) v F(x) at y, given v = e^w, with the terms its derivatives in (w, θ)
    /// are formed from ([`StateRate`]).
    fn state_rate(&self, y: &[f64], v: f64) -> StateRate {
        let p = &self.params;
        let (x, s, h) = self.law_argument(y);
        StateRate { c: 1.0 + p.epsilon, law: p.state_law.terms(y[W], v, x), s, h }
    }

    /// The arrest rate γ²e^(−w) (held below [`ARREST_RATE_HELD_BELOW`] under logarithmic
    /// friction) and whether it depends on w there.
    fn arrest_rate(&self, w: f64) -> (f64, bool) {
        if w > ARREST_RATE_HELD_BELOW || self.params.friction != Friction::Log {
            (self.gamma2 * (-w).exp(), true)
        } else {
            (self.gamma2 * (-ARREST_RATE_HELD_BELOW).exp(), false)
        }
    }

    /// [`Drr::arrest_rate`] with e^(−w) given (as 1/v by the noise analysis's forced
    /// right-hand side and Jacobian).
    fn arrest_rate_given(&self, w: f64, inverse_speed: f64) -> (f64, bool) {
        if w > ARREST_RATE_HELD_BELOW || self.params.friction != Friction::Log {
            (self.gamma2 * inverse_speed, true)
        } else {
            self.arrest_rate(w)
        }
    }

    /// ∂f/∂y of [`Drr::rhs_with_velocity_force`]: [`OdeSystem::jacobian`]'s formulas plus
    /// the force's −`amplitude`·e^(−w)·`force` in ∂(dw/dt)/∂w, with one exponential (v = e^w,
    /// e^(−w) = 1/v, as there) where the model's Jacobian and the force's take three: a
    /// noise realisation's every step (issue #30).
    pub fn jacobian_with_velocity_force(
        &self,
        y: &[f64],
        amplitude: f64,
        force: f64,
        jac: &mut JacobianMatrix<'_>,
    ) {
        let w = y[W];
        let v = w.exp();
        let inverse_speed = 1.0 / v;
        self.jacobian_at(y, v, || self.arrest_rate_given(w, inverse_speed), jac);
        jac.set(W, W, jac.get(W, W) - (amplitude * inverse_speed) * force);
    }

    /// The Jacobian at y given v = e^w and the arrest rate (asked for only with inertia).
    fn jacobian_at(
        &self,
        y: &[f64],
        v: f64,
        arrest_rate: impl FnOnce() -> (f64, bool),
        jac: &mut JacobianMatrix<'_>,
    ) {
        let p = &self.params;
        let law = self.state_rate(y, v);
        jac.set(U, W, v);
        if p.inertia {
            let t = self.total(y, None);
            let g = self.offset_given(y, t.value);
            let (a, varies) = arrest_rate();
            let da = if varies { a } else { 0.0 };
            jac.set(W, U, -a);
            jac.set(W, W, da * g - a * t.d1[0] / p.xi);
            jac.set(W, THETA, -a * t.d1[1] / p.xi);
        } else {
            let (_, grad, _) = self.force_balance_rate(y);
            for k in [U, W, THETA] {
                jac.set(W, k, grad[k]);
            }
        }
        jac.set(THETA, W, law.w());
        jac.set(THETA, THETA, law.theta());
    }

    /// The quasi-dynamic dw/dt = −(ξ(v − 1) + P R + κ_G ξG)/S with its gradient and Hessian in
    /// (u, w, θ) ([`quasi_dynamic`]), where P = Φ_θ (1 for the paper's laws) and S = Φ_w + η v.
    fn force_balance_rate(&self, y: &[f64]) -> (f64, [f64; 3], [[f64; 3]; 3]) {
        let p = &self.params;
        let k = CONSTRAINT_RELAXATION_RATE;
        let w = y[W];
        let v = w.exp();
        let t = self.total(y, Some(v));
        let g = self.offset_given(y, t.value);
        let law = self.state_rate(y, v);
        let r = law.value();
        // P = Φ_θ and its derivatives P_w, P_θ, P_ww, P_wθ, P_θθ.
        let (pp, pw, pt) = (t.d1[1], t.d2[1], t.d2[2]);
        let (pww, pwt, ptt) = (t.d3[1], t.d3[2], t.d3[3]);
        let n = p.xi * w.exp_m1() + pp * r + k * p.xi * g;
        let n_grad = [
            k * p.xi,
            p.xi * v + (pp * law.w() + pw * r) + k * t.d1[0],
            (pp * law.theta() + pt * r) + k * pp,
        ];
        let mut n_hess = [[0.0; 3]; 3];
        n_hess[W][W] = p.xi * v + (pp * law.ww() + 2.0 * pw * law.w() + pww * r) + k * t.d2[0];
        n_hess[W][THETA] =
            (pp * law.w_theta() + pw * law.theta() + pt * law.w() + pwt * r) + k * t.d2[1];
        n_hess[THETA][W] = n_hess[W][THETA];
        n_hess[THETA][THETA] = (pp * law.theta_theta() + 2.0 * pt * law.theta() + ptt * r) + k * pt;
        let s_grad = [0.0, t.d2[0], t.d2[1]];
        let mut s_hess = [[0.0; 3]; 3];
        s_hess[W][W] = t.d3[0];
        s_hess[W][THETA] = t.d3[1];
        s_hess[THETA][W] = t.d3[1];
        s_hess[THETA][THETA] = t.d3[2];
        quasi_dynamic::quotient(n, n_grad, n_hess, (t.d1[0], s_grad, s_hess))
    }

    /// The slopes of the inertial model in the paper's coordinates (u, v, θ) at (u, ln v, θ),
    /// for its local eigenvalues: [f'(v) + η, ∂θ̇/∂v, ∂θ̇/∂θ], i.e. the resistance's slope (the
    /// velocity row is dv/dt = −γ²(u + (θ + f(v) + ηv)/ξ)) and the state law's.
    pub fn velocity_slopes(&self, y: &[f64]) -> [f64; 3] {
        let v_inverse = (-y[W]).exp();
        let law = self.state_rate(y, y[W].exp());
        [self.total(y, None).d1[0] * v_inverse, law.w() * v_inverse, law.theta()]
    }

    /// ∂(dw/dt)/∂G at y, how an error in the distance G to the force balance shows in dw/dt:
    /// −γ²e^(−w) with inertia, −κ_G ξ/S without (S = Φ_w + η v).
    pub fn offset_feedback(&self, y: &[f64]) -> f64 {
        if self.params.inertia {
            -self.arrest_rate(y[W]).0
        } else {
            -CONSTRAINT_RELAXATION_RATE * self.params.xi / self.total(y, None).d1[0]
        }
    }

    /// The scale of v in a slip, which sets the fastest time scale 1/scale: γ with inertia,
    /// 1/η without (radiation damping caps v near 1/η).
    pub fn slip_speed_scale(&self) -> f64 {
        if self.params.inertia {
            self.params.gamma
        } else {
            1.0 / self.params.eta
        }
    }

    /// (du/dt, dw/dt, dθ/dt). With inertia (every benchmark and the paper's model) only the
    /// values are computed, e^w and f(v) once: the derivative terms of [`Drr::state_rate`] and
    /// [`Drr::resistance`] cost an ERK cycle 4 % of its instructions (issue #17).
    fn split(&self, y: &[f64]) -> (f64, f64, f64) {
        let p = &self.params;
        let w = y[W];
        if !p.inertia {
            return (w.exp_m1(), self.force_balance_rate(y).0, self.state_rate(y, w.exp()).value());
        }
        let v = w.exp();
        if !p.friction.is_classic() {
            let dw = -self.arrest_rate(w).0 * self.offset_given(y, self.total(y, None).value);
            return (w.exp_m1(), dw, self.state_rate(y, v).value());
        }
        let (f, _) = p.friction.eval(w);
        let dw = -self.arrest_rate(w).0 * self.offset(y, self.resistance_value(f, v));
        (w.exp_m1(), dw, self.state_rate_value(y, f, v))
    }

    /// The right-hand side with an extra force `amplitude`·`force` on dv/dt, which enters
    /// dw/dt = (dv/dt)/v as (`amplitude`·e^(−w))·`force` (the noise analysis's forcing on v).
    ///
    /// With inertia it takes one exponential where `Drr::split` takes three: v = e^w, then
    /// du/dt = v − 1 and e^(−w) = 1/v (for the arrest rate and the force). The same formulas;
    /// only the last bits differ (v − 1 against e^w − 1 computed as such: an absolute 1e-16),
    /// far below the tolerances of the noise ensembles, which evaluate it tens of millions of
    /// times (the two exponentials were a fifth of their instructions, issue #30). The
    /// deterministic runs keep [`OdeSystem::rhs`].
    pub fn rhs_with_velocity_force(&self, y: &[f64], amplitude: f64, force: f64, dydt: &mut [f64]) {
        let p = &self.params;
        let w = y[W];
        if !p.inertia || !p.friction.is_classic() {
            let (du, dw, dtheta) = self.split(y);
            dydt[U] = du;
            dydt[W] = dw + (amplitude * (-w).exp()) * force;
            dydt[THETA] = dtheta;
            return;
        }
        let v = w.exp();
        let inverse_speed = 1.0 / v;
        let (f, _) = p.friction.eval(w);
        let arrest = self.arrest_rate_given(w, inverse_speed).0;
        let dw = -arrest * self.offset(y, self.resistance_value(f, v));
        dydt[U] = v - 1.0;
        dydt[W] = dw + (amplitude * inverse_speed) * force;
        dydt[THETA] = self.state_rate_value(y, f, v);
    }
}

/// The root w of a residual that increases strictly with w, given as (residual, slope),
/// e.g. f(e^w) + η e^w − target (η > 0): bisection on a bracket, finished by Newton steps
/// that stay inside it.
fn solve(residual: impl Fn(f64) -> (f64, f64)) -> Option<f64> {
    let r = |w: f64| residual(w).0;
    // Bracket: w ≤ 700 keeps e^w finite; below, f + ηv tends to inf f (−∞ for ln v).
    let (mut lo, mut hi) = (-700.0f64, 700.0f64);
    if !(r(lo) < 0.0 && r(hi) > 0.0) {
        return None;
    }
    let mut w = 0.0f64.clamp(lo, hi);
    for _ in 0..400 {
        let value = r(w);
        if value == 0.0 {
            return Some(w);
        }
        if value < 0.0 {
            lo = w
        } else {
            hi = w
        }
        let newton = w - value / residual(w).1;
        let next = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        if (next - w).abs() <= 4.0 * f64::EPSILON * w.abs().max(1.0) {
            return Some(next);
        }
        w = next;
    }
    Some(w)
}

/// dθ/dt = R = (1+ε) v F(x) at a point ([`Drr::state_rate`]) and its derivatives in (w, θ),
/// each formed when asked for (the Jacobian needs only the first ones): with c = 1+ε,
/// s = v f'(v), h = ds/dw, ∂R/∂w = c (vF + vF' s), ∂R/∂θ = vF', ∂²R/∂w² =
/// c (vF + 2vF' s + vF'' s² + vF' h), ∂²R/∂θ∂w = vF' + vF'' s, ∂²R/∂θ² = vF''/c.
#[derive(Debug, Clone, Copy)]
struct StateRate {
    c: f64,
    law: LawTerms,
    s: f64,
    h: f64,
}

impl StateRate {
    /// R.
    fn value(&self) -> f64 {
        self.c * self.law.f
    }

    /// ∂R/∂w.
    fn w(&self) -> f64 {
        self.c * (self.law.f + self.law.d1 * self.s)
    }

    /// ∂R/∂θ.
    fn theta(&self) -> f64 {
        self.law.d1
    }

    /// ∂²R/∂w².
    fn ww(&self) -> f64 {
        let (law, s) = (&self.law, self.s);
        self.c * (law.f + 2.0 * law.d1 * s + law.d2 * s * s + law.d1 * self.h)
    }

    /// ∂²R/∂θ∂w.
    fn w_theta(&self) -> f64 {
        self.law.d1 + self.law.d2 * self.s
    }

    /// ∂²R/∂θ².
    fn theta_theta(&self) -> f64 {
        self.law.d2 / self.c
    }
}

impl OdeSystem for Drr {
    fn dim(&self) -> usize {
        3
    }

    /// None: no combination c·(u, w, θ) is conserved, and rodas5p's refinement does not make
    /// the periods more accurate: without it its periods on the three reference tables (γ up
    /// to 1e12) and the earthquake move by at most 1.7e-9 relative, far inside their distance
    /// from the references, and the physical, laws and quick stress grids pass; it runs 30 %
    /// fewer instructions (docs/test-set.md, E5, "Its cost"). Extrapolation refines whatever
    /// this says (see `Extrapolation`'s stage solve).
    fn has_linear_invariants(&self) -> bool {
        false
    }

    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let (du, dw, dtheta) = self.split(y);
        dydt[U] = du;
        dydt[W] = dw;
        dydt[THETA] = dtheta;
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let w = y[W];
        self.jacobian_at(y, w.exp(), || self.arrest_rate(w), jac);
    }

    fn has_jacobian_derivative(&self) -> bool {
        true
    }

    fn jacobian_derivative(&self, _t: f64, y: &[f64], k: usize, out: &mut JacobianMatrix<'_>) {
        let p = &self.params;
        let w = y[W];
        let v = w.exp();
        let law = self.state_rate(y, v);
        match k {
            U => {}
            THETA => {
                out.set(THETA, W, law.w_theta());
                out.set(THETA, THETA, law.theta_theta());
            }
            _ => {
                out.set(U, W, v);
                out.set(THETA, W, law.ww());
                out.set(THETA, THETA, law.w_theta());
            }
        }
        if !p.inertia {
            let (_, _, hess) = self.force_balance_rate(y);
            for j in [U, W, THETA] {
                out.set(W, j, hess[j][k]);
            }
            return;
        }
        let t = self.total(y, None);
        let g = self.offset_given(y, t.value);
        let (a, varies) = self.arrest_rate(w);
        // da/dw = −a where the rate varies, 0 where it is held. With dw/dt = −aG, G_θ = P/ξ
        // (P = Φ_θ, 1 for the paper's laws): ∂_j ∂_k (−aG) = −a_jk G − a_k G_j − a_j G_k − a G_jk.
        let da = if varies { a } else { 0.0 };
        let (pp, pw, pt) = (t.d1[1], t.d2[1], t.d2[2]);
        match k {
            U => out.set(W, W, da),
            THETA => {
                out.set(W, W, da * pp / p.xi - a * pw / p.xi);
                if pt != 0.0 {
                    out.set(W, THETA, -a * pt / p.xi);
                }
            }
            _ => {
                out.set(W, U, da);
                out.set(W, W, -da * g + 2.0 * da * t.d1[0] / p.xi - a * t.d2[0] / p.xi);
                out.set(W, THETA, da * pp / p.xi - a * pw / p.xi);
            }
        }
    }
}

/// IMEX split: the plate drive (the −1 of du/dt = v − 1) explicit; the friction and inertia
/// terms implicit. At large γ no state component is non-stiff in every phase: w relaxes onto
/// the slow manifold at rate γ²/(ξv) and drags u with it through −γ² e^{−w} u, and θ relaxes
/// at rate v ≈ γ ln γ during a slip. Splitting any of them off (tried: u, θ) makes the
/// scheme stability-limited, with 1e5 steps per cycle and periods wrong at 1e-5.
impl ImexSystem for Drr {
    fn rhs_explicit(&self, _t: f64, _y: &[f64], dydt: &mut [f64]) {
        dydt[U] = -1.0;
        dydt[W] = 0.0;
        dydt[THETA] = 0.0;
    }

    fn rhs_implicit(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let (_, dw, dtheta) = self.split(y);
        dydt[U] = y[W].exp();
        dydt[W] = dw;
        dydt[THETA] = dtheta;
    }

    fn has_implicit_jacobian(&self) -> bool {
        true
    }

    fn implicit_jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        self.jacobian(t, y, jac);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;

    fn frictions() -> [Friction; 7] {
        [
            Friction::Log,
            Friction::Asinh,
            Friction::Power { alpha: 0.31 },
            Friction::CutOff { v1: 3.0, v2: 0.5 },
            Friction::CutOff { v1: 1e-3, v2: 40.0 },
            Friction::Regularised { f_star: 1.3, v_star: 2.0 },
            Friction::Regularised { f_star: -0.4, v_star: 0.1 },
        ]
    }

    /// Every friction law × state law, without and with radiation damping, and quasi-dynamic.
    fn models(gamma: f64, xi: f64, epsilon: f64) -> Vec<Drr> {
        let mut out = Vec::new();
        for friction in frictions() {
            for (_, state_law) in StateLaw::ALL {
                for eta in [0.0, 0.37] {
                    out.push(Drr::new(DrrParams {
                        state_law,
                        eta,
                        ..DrrParams::new(gamma, xi, epsilon, friction)
                    }));
                }
                out.push(Drr::new(DrrParams {
                    state_law,
                    ..DrrParams::quasi_dynamic(xi, epsilon, 0.37, friction)
                }));
            }
        }
        out
    }

    const STATES: [[f64; 3]; 3] = [[0.3, -0.4, 0.2], [-1.0, 2.5, 0.7], [2.0, -3.0, -1.0]];

    #[test]
    fn jacobian_matches_central_differences() {
        for drr in models(10.0, 0.7, 0.72) {
            let p = drr.params();
            for y in STATES {
                for (row, col, exact, fd) in
                    jacobian_against_differences(&drr, &y, |x| 1e-6 * (1.0 + x.abs()))
                {
                    assert!(
                        (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                        "{p:?} y={y:?} ({row},{col}): {exact} vs {fd}"
                    );
                }
            }
        }
    }

    /// ∂J/∂y_k against central differences of the Jacobian, for each k.
    fn assert_jacobian_derivative_matches_differences(drr: &Drr, y: [f64; 3]) {
        let p = drr.params();
        for k in 0..3 {
            let mut exact = [0.0; 9];
            drr.jacobian_derivative(0.0, &y, k, &mut JacobianMatrix::new(&mut exact, 3));
            let h = 1e-6 * (1.0 + y[k].abs());
            let (mut yp, mut ym) = (y, y);
            yp[k] += h;
            ym[k] -= h;
            let (mut jp, mut jm) = ([0.0; 9], [0.0; 9]);
            drr.jacobian(0.0, &yp, &mut JacobianMatrix::new(&mut jp, 3));
            drr.jacobian(0.0, &ym, &mut JacobianMatrix::new(&mut jm, 3));
            for i in 0..9 {
                let fd = (jp[i] - jm[i]) / (2.0 * h);
                assert!(
                    (fd - exact[i]).abs() <= 1e-5 * (1.0 + exact[i].abs()),
                    "{p:?} y={y:?} k={k} entry {i}: {} vs {fd}",
                    exact[i]
                );
            }
        }
    }

    #[test]
    fn jacobian_derivative_matches_central_differences_of_the_jacobian() {
        for drr in models(10.0, 0.7, 0.72) {
            for y in STATES {
                assert_jacobian_derivative_matches_differences(&drr, y);
            }
        }
    }

    /// Deep below the hold (a far-off start's arrest): the Jacobian and its derivative are
    /// those of the held rate, and the right-hand side is finite and continuous at the hold.
    #[test]
    fn held_arrest_rate_has_consistent_jacobians_and_is_continuous() {
        for drr in
            models(1e8, 0.7, 3.0).into_iter().filter(|d| d.params().friction == Friction::Log)
        {
            let p = drr.params();
            let y = [900.0, -800.0, -1.0];
            for (row, col, exact, fd) in
                jacobian_against_differences(&drr, &y, |x| 1e-6 * (1.0 + x.abs()))
            {
                assert!(
                    exact.is_finite() && (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                    "{p:?} y={y:?} ({row},{col}): {exact} vs {fd}"
                );
            }
            assert_jacobian_derivative_matches_differences(&drr, y);
            let at = |w: f64| {
                let mut d = [0.0; 3];
                drr.rhs(0.0, &[900.0, w, -1.0], &mut d);
                d[W]
            };
            let (below, above) =
                (at(ARREST_RATE_HELD_BELOW - 1e-12), at(ARREST_RATE_HELD_BELOW + 1e-12));
            assert!(
                below.is_finite() && (below - above).abs() <= 1e-9 * above.abs(),
                "{p:?}: {below:e} vs {above:e}"
            );
        }
    }

    #[test]
    fn slip_law_is_the_papers_theta_equation() {
        for friction in frictions() {
            let drr = Drr::new(DrrParams::new(10.0, 0.7, 0.72, friction));
            for y in STATES {
                let mut d = [0.0; 3];
                drr.rhs(0.0, &y, &mut d);
                // The paper's laws evolve with x = θ/(1+ε) + f(v), QDYN's with ln(VΘ/D_c).
                let f = if friction.is_classic() { friction.eval(y[W]).0 } else { y[W] };
                let paper = -y[W].exp() * (y[THETA] + 1.72 * f);
                assert!(
                    (d[THETA] - paper).abs() <= 1e-14 * (1.0 + paper.abs()),
                    "{friction:?} y={y:?}: {} vs {paper}",
                    d[THETA]
                );
            }
        }
    }

    #[test]
    fn fixed_point_is_stationary_and_on_the_manifold() {
        // The no-healing law has none (StateLaw::heals).
        for drr in models(1e8, 0.8, 1.0).into_iter().filter(|d| d.params().state_law.heals()) {
            let p = drr.params();
            let y = drr.fixed_point();
            let mut f = [1.0; 3];
            drr.rhs(0.0, &y, &mut f);
            assert!(f.iter().all(|v| v.abs() < 1e-12), "{p:?}: {f:?}");
            let w = drr.manifold_w(y[U], y[THETA]).unwrap();
            assert!(w.abs() < 1e-12, "{p:?}: {w}");
        }
    }

    #[test]
    fn manifold_w_inverts_manifold_u_with_damping() {
        for drr in models(1e3, 0.7, 0.72) {
            let p = drr.params();
            for (w, theta) in [(-20.0, 0.3), (-1.0, -0.5), (0.4, 1.0), (18.0, -2.0)] {
                let u = drr.manifold_u(w, theta);
                let back = drr.manifold_w(u, theta).unwrap();
                // w is determined by u only to the rounding of ξu + θ over ∂(ξG)/∂w.
                let conditioning = 1e-15 * (1.0 + (p.xi * u).abs() + theta.abs())
                    / (p.xi * drr.manifold_offset_slope(&[u, w, theta]));
                assert!(
                    (back - w).abs() < 1e-10 * (1.0 + w.abs()) + 10.0 * conditioning,
                    "{p:?} w={w}: {back}"
                );
                assert!(
                    drr.manifold_offset(&[u, back, theta]).abs() < 1e-12 * (1.0 + u.abs()),
                    "{p:?} w={w}"
                );
            }
        }
        // Outside the range of f + ηv (asinh: f + ηv > 0): no point of the manifold.
        let asinh =
            Drr::new(DrrParams { eta: 0.5, ..DrrParams::new(1e3, 0.7, 0.72, Friction::Asinh) });
        assert_eq!(asinh.manifold_w(1.0, 0.0), None);
    }

    /// Without inertia the force-balance residual G relaxes exactly at the rate κ_G:
    /// dG/dt = ∂G/∂y · dy/dt = −κ_G G, on and off the manifold.
    #[test]
    fn quasi_dynamic_force_balance_relaxes_at_the_constraint_rate() {
        for drr in models(1.0, 0.7, 0.72).into_iter().filter(|d| !d.params().inertia) {
            let p = drr.params();
            for y in STATES.into_iter().chain([[drr.manifold_u(1.5, 0.2), 1.5, 0.2]]) {
                let mut d = [0.0; 3];
                drr.rhs(0.0, &y, &mut d);
                let g = drr.manifold_offset(&y);
                // G_θ = Φ_θ/ξ: 1/ξ for the paper's laws, by differences for QDYN's.
                let h = 1e-5;
                let (g_theta, tol) = if p.friction.is_classic() {
                    (1.0 / p.xi, 1e-14)
                } else {
                    let at = |d: f64| drr.manifold_offset(&[y[U], y[W], y[THETA] + d]);
                    ((at(h) - at(-h)) / (2.0 * h), 1e-8)
                };
                let slope = drr.manifold_offset_slope(&y);
                let dg = d[U] + g_theta * d[THETA] + slope * d[W];
                let scale = d[U].abs() + (g_theta * d[THETA]).abs() + (slope * d[W]).abs();
                assert!(
                    (dg + CONSTRAINT_RELAXATION_RATE * g).abs() <= tol * scale.max(1.0),
                    "{p:?} y={y:?}: dG/dt {dg} vs G {g}"
                );
            }
        }
    }

    #[test]
    fn imex_parts_add_up_to_the_full_rhs() {
        let drr = Drr::new(DrrParams::new(1e3, 0.7, 0.72, Friction::Log));
        let y = [0.4, 1.3, -0.8];
        let (mut full, mut e, mut i) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        drr.rhs(0.0, &y, &mut full);
        drr.rhs_explicit(0.0, &y, &mut e);
        drr.rhs_implicit(0.0, &y, &mut i);
        for k in 0..3 {
            assert_eq!(full[k], e[k] + i[k]);
        }
    }
}
