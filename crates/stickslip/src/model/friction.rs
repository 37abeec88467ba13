//! Friction laws of the Dieterich–Ruina model: the dimensionless friction Φ(v, θ) = μ/a (up to
//! a constant) of the force balance u + (Φ + η v)/ξ = 0.
//!
//! The paper's laws (`log`, `asinh`, `power`) are Φ = θ + f(v); QDYN's cut-off velocity and
//! regularised laws (docs/state-laws.md, "QDYN's friction laws") are not of that form:
//!
//! ```text
//! cut-off:     Φ = −ln(1 + v1/v) + (1+ε) ln(1 + v2 e^{θ/(1+ε)})
//! regularised: Φ = asinh(½ exp(ln v + θ + f* + ε ln v*))
//! ```
//!
//! with θ = (1+ε) ln(V_pl Θ/D_c) as for every law, v1 = V1/V_pl, v2 = V2/V_pl, f* = μ*/a and
//! v* = V*/V_pl.

use serde::{Deserialize, Serialize};

/// The friction law: the paper's velocity dependence f(v) (Φ = θ + f(v)) or one of QDYN's laws.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Friction {
    /// f = ln v (Dieterich–Ruina).
    Log,
    /// f = asinh v = ln(v + √(v²+1)), regularised at v → 0 (Lapusta et al.).
    Asinh,
    /// f = g_α(v) = (v^α − 1)/α, α > 0 (tends to ln v as α → 0).
    Power {
        /// Exponent α > 0.
        alpha: f64,
    },
    /// QDYN's cut-off velocity law (`RNS_LAW = 1`): μ = μ* − a ln(1 + V1/V) + b ln(1 + ΘV2/D_c).
    CutOff {
        /// v1 = V1/V_pl > 0, the cut-off of the direct effect.
        v1: f64,
        /// v2 = V2/V_pl > 0, the cut-off of the state effect.
        v2: f64,
    },
    /// QDYN's regularised law (`RNS_LAW = 2`): μ = a asinh[V/(2V*) exp((μ* + b ln(ΘV*/D_c))/a)].
    Regularised {
        /// f* = μ*/a.
        f_star: f64,
        /// v* = V*/V_pl > 0.
        v_star: f64,
    },
}

/// The dimensionless friction Φ(w, θ) (plus η v where [`Strength::damped`]) and its
/// derivatives in (w = ln v, θ) up to third order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Strength {
    /// Φ.
    pub value: f64,
    /// [Φ_w, Φ_θ].
    pub d1: [f64; 2],
    /// [Φ_ww, Φ_wθ, Φ_θθ].
    pub d2: [f64; 3],
    /// [Φ_www, Φ_wwθ, Φ_wθθ, Φ_θθθ].
    pub d3: [f64; 4],
}

impl Strength {
    /// Φ + η v: radiation damping adds η v to the value and to every pure w-derivative.
    pub fn damped(mut self, eta: f64, v: f64) -> Self {
        if eta != 0.0 {
            let ev = eta * v;
            self.value += ev;
            self.d1[0] += ev;
            self.d2[0] += ev;
            self.d3[0] += ev;
        }
        self
    }
}

/// ln(1 + e^z) without overflow.
fn softplus(z: f64) -> f64 {
    if z > 0.0 {
        z + (-z).exp().ln_1p()
    } else {
        z.exp().ln_1p()
    }
}

/// 1/(1 + e^{−z}) without overflow.
fn logistic(z: f64) -> f64 {
    if z > 0.0 {
        1.0 / (1.0 + (-z).exp())
    } else {
        let e = z.exp();
        e / (1.0 + e)
    }
}

impl Friction {
    /// Whether the law is the paper's Φ = θ + f(v) (`log`, `asinh`, `power`), for which
    /// [`Friction::eval`] gives f; QDYN's cut-off and regularised laws are not of that form.
    pub fn is_classic(self) -> bool {
        !matches!(self, Friction::CutOff { .. } | Friction::Regularised { .. })
    }

    /// Φ(w, θ) and its derivatives for ε = `c` − 1 (module docs).
    pub fn strength(self, w: f64, theta: f64, c: f64) -> Strength {
        match self {
            Friction::CutOff { v1, v2 } => {
                // Φ = −softplus(ln v1 − w) + c softplus(θ/c + ln v2).
                let z1 = v1.ln() - w;
                let p = logistic(z1);
                let p2 = p * (1.0 - p);
                let z2 = theta / c + v2.ln();
                let q = logistic(z2);
                let q2 = q * (1.0 - q);
                Strength {
                    value: -softplus(z1) + c * softplus(z2),
                    d1: [p, q],
                    d2: [-p2, 0.0, q2 / c],
                    d3: [p2 * (1.0 - 2.0 * p), 0.0, 0.0, q2 * (1.0 - 2.0 * q) / (c * c)],
                }
            }
            Friction::Regularised { f_star, v_star } => {
                // Φ = asinh(½ e^z) = asinh(e^{z − ln 2}), z = w + θ + f* + ε ln v*: the asinh
                // law's f at w' = z − ln 2, with the same derivative in w and θ.
                let z = w + theta + f_star + (c - 1.0) * v_star.ln() - std::f64::consts::LN_2;
                let asinh = Friction::Asinh;
                let (a, a1) = asinh.eval(z);
                let (a2, a3) = (asinh.d_vfprime_dw(z), asinh.d2_vfprime_dw2(z));
                Strength { value: a, d1: [a1, a1], d2: [a2; 3], d3: [a3; 4] }
            }
            classic => {
                let (f, vfp) = classic.eval(w);
                Strength {
                    value: theta + f,
                    d1: [vfp, 1.0],
                    d2: [classic.d_vfprime_dw(w), 0.0, 0.0],
                    d3: [classic.d2_vfprime_dw2(w), 0.0, 0.0, 0.0],
                }
            }
        }
    }

    /// The velocity term σ(w) of the state laws' argument x = θ/(1+ε) + σ(w) with σ' and σ'':
    /// f(v) for the paper's laws (its convention, docs/state-laws.md), ln v = w for QDYN's,
    /// whose state laws evolve with VΘ/D_c itself.
    pub fn state_argument(self, w: f64) -> (f64, f64, f64) {
        if self.is_classic() {
            let (f, vfp) = self.eval(w);
            (f, vfp, self.d_vfprime_dw(w))
        } else {
            (w, 1.0, 0.0)
        }
    }

    /// f(v) and v·f'(v), given w = ln v (so that tiny and huge v are handled without
    /// overflow where the law allows it). For QDYN's laws, which have no f(v), Φ and Φ_w at
    /// θ = 0 and ε = 0; the model uses [`Friction::strength`] for them.
    pub fn eval(self, w: f64) -> (f64, f64) {
        match self {
            Friction::Log => (w, 1.0),
            Friction::Asinh => {
                let v = w.exp();
                // asinh(v) = ln(v + √(v²+1)): for v ≫ 1 use w + ln(1 + √(1 + v⁻²)) to avoid
                // overflow of v²; v f'(v) = v/√(v²+1).
                if w > 0.0 {
                    let r = (-w).exp();
                    (w + (1.0 + (1.0 + r * r).sqrt()).ln(), 1.0 / (1.0 + r * r).sqrt())
                } else {
                    (v.asinh(), v / (v * v + 1.0).sqrt())
                }
            }
            Friction::Power { alpha } => {
                let va = (alpha * w).exp();
                ((alpha * w).exp_m1() / alpha, va)
            }
            other => {
                let s = other.strength(w, 0.0, 1.0);
                (s.value, s.d1[0])
            }
        }
    }

    /// d(v f'(v))/dw, needed by the Jacobian in w = ln v.
    pub fn d_vfprime_dw(self, w: f64) -> f64 {
        match self {
            Friction::Log => 0.0,
            Friction::Asinh => {
                // v/√(v²+1) differentiated in w: v/(v²+1)^{3/2}.
                let v = w.exp();
                if w > 0.0 {
                    let r = (-w).exp();
                    r * r / (1.0 + r * r).powf(1.5)
                } else {
                    v / (v * v + 1.0).powf(1.5)
                }
            }
            Friction::Power { alpha } => alpha * (alpha * w).exp(),
            other => other.strength(w, 0.0, 1.0).d2[0],
        }
    }

    /// d²(v f'(v))/dw², needed by the w-derivative of the quasi-dynamic model's Jacobian.
    pub fn d2_vfprime_dw2(self, w: f64) -> f64 {
        match self {
            Friction::Log => 0.0,
            Friction::Asinh => {
                // v (v²+1)^{−3/2} differentiated in w: v (1 − 2v²)/(v²+1)^{5/2}; for v > 1 in
                // r = 1/v: r² (r² − 2)/(1 + r²)^{5/2}.
                if w > 0.0 {
                    let r2 = (-2.0 * w).exp();
                    r2 * (r2 - 2.0) / (1.0 + r2).powf(2.5)
                } else {
                    let v = w.exp();
                    v * (1.0 - 2.0 * v * v) / (v * v + 1.0).powf(2.5)
                }
            }
            Friction::Power { alpha } => alpha * alpha * (alpha * w).exp(),
            other => other.strength(w, 0.0, 1.0).d3[0],
        }
    }

    /// A short label, e.g. "log", "asinh", "power(alpha=0.31)".
    pub fn label(self) -> String {
        match self {
            Friction::Log => "log".into(),
            Friction::Asinh => "asinh".into(),
            Friction::Power { alpha } => format!("power(alpha={alpha})"),
            Friction::CutOff { v1, v2 } => format!("cut_off(v1={v1}, v2={v2})"),
            Friction::Regularised { f_star, v_star } => {
                format!("regularised(f_star={f_star}, v_star={v_star})")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// QDYN's laws in the field's variables against Φ: with V_pl = 1e-9, D_c = 1e-4, a = 0.01,
    /// b = 0.014 (1+ε = b/a), θ = (b/a) ln(V_pl Θ/D_c), w = ln(V/V_pl).
    #[test]
    fn qdyn_laws_are_their_dimensional_formulas() {
        let (v_pl, d_c, a, b, mu_star) = (1e-9f64, 1e-4f64, 0.01f64, 0.014f64, 0.6f64);
        let c = b / a;
        for (big_v, big_theta) in [(3e-12f64, 2e7f64), (1e-9, 1e5), (2.5e-6, 40.0), (1.0, 1e-4)] {
            let w = (big_v / v_pl).ln();
            let theta = c * (v_pl * big_theta / d_c).ln();
            let (v1, v2) = (1e-6f64, 1e-7f64);
            let cut = Friction::CutOff { v1: v1 / v_pl, v2: v2 / v_pl }.strength(w, theta, c);
            let mu = mu_star - a * (1.0 + v1 / big_v).ln() + b * (1.0 + big_theta * v2 / d_c).ln();
            assert!((mu_star + a * cut.value - mu).abs() < 1e-14, "cut-off {big_v}: {mu}");
            let v_star = 1e-6f64;
            let reg = Friction::Regularised { f_star: mu_star / a, v_star: v_star / v_pl }
                .strength(w, theta, c);
            let mu = a
                * (big_v / (2.0 * v_star)
                    * ((mu_star + b * (big_theta * v_star / d_c).ln()) / a).exp())
                .asinh();
            assert!((a * reg.value - mu).abs() < 1e-14 * mu.abs().max(1.0), "regularised {big_v}");
        }
    }

    /// Every derivative of Φ against central differences of the one below.
    #[test]
    fn strength_derivatives_match_differences() {
        let laws = [
            Friction::Log,
            Friction::Asinh,
            Friction::Power { alpha: 0.3 },
            Friction::CutOff { v1: 2.0, v2: 0.3 },
            Friction::CutOff { v1: 1e3, v2: 1e2 },
            Friction::Regularised { f_star: 0.5, v_star: 3.0 },
            Friction::Regularised { f_star: 60.0, v_star: 1e3 },
        ];
        let c = 1.4;
        let h = 1e-5;
        for law in laws {
            for (w, theta) in [(-3.0, 0.4), (0.0, 0.0), (2.0, -1.5), (12.0, -60.0)] {
                let s = law.strength(w, theta, c);
                let dw = |f: &dyn Fn(&Strength) -> f64| {
                    (f(&law.strength(w + h, theta, c)) - f(&law.strength(w - h, theta, c)))
                        / (2.0 * h)
                };
                let dt = |f: &dyn Fn(&Strength) -> f64| {
                    (f(&law.strength(w, theta + h, c)) - f(&law.strength(w, theta - h, c)))
                        / (2.0 * h)
                };
                let checks = [
                    (s.d1[0], dw(&|s| s.value)),
                    (s.d1[1], dt(&|s| s.value)),
                    (s.d2[0], dw(&|s| s.d1[0])),
                    (s.d2[1], dt(&|s| s.d1[0])),
                    (s.d2[1], dw(&|s| s.d1[1])),
                    (s.d2[2], dt(&|s| s.d1[1])),
                    (s.d3[0], dw(&|s| s.d2[0])),
                    (s.d3[1], dt(&|s| s.d2[0])),
                    (s.d3[1], dw(&|s| s.d2[1])),
                    (s.d3[2], dt(&|s| s.d2[1])),
                    (s.d3[2], dw(&|s| s.d2[2])),
                    (s.d3[3], dt(&|s| s.d2[2])),
                ];
                for (i, (exact, fd)) in checks.into_iter().enumerate() {
                    assert!(
                        (exact - fd).abs() <= 1e-8 * (1.0 + exact.abs()),
                        "{law:?} w={w} θ={theta} check {i}: {exact} vs {fd}"
                    );
                }
            }
        }
    }

    /// With f* = 60 the regularised law is the classic one to round-off: asinh(x/2) =
    /// ln x + O(x⁻²), and x = e^{f* + …} ≈ 1e26.
    #[test]
    fn regularised_law_at_large_f_star_is_the_classic_law() {
        let (f_star, v_star, c) = (60.0f64, 7.0f64, 1.3f64);
        let law = Friction::Regularised { f_star, v_star };
        for (w, theta) in [(-5.0, 1.0), (0.0, 0.0), (10.0, -3.0)] {
            // Classic: f* + ln(v/v*) + (1+ε) ln(Th v*) = f* + w + θ + ε ln v*.
            let classic = f_star + w + theta + (c - 1.0) * v_star.ln();
            let s = law.strength(w, theta, c);
            assert!((s.value - classic).abs() <= 4.0 * f64::EPSILON * classic, "{w}: {}", s.value);
            assert!((s.d1[0] - 1.0).abs() < 1e-15 && (s.d1[1] - 1.0).abs() < 1e-15);
        }
    }

    /// Cut-off velocities far below the slip rate and state (V1, V2 → 0 relative): the direct
    /// effect vanishes like v1/v and the state effect like v2 Th.
    #[test]
    fn cut_off_law_limits() {
        let c = 1.5;
        let (w, theta) = (2.0f64, 0.9f64);
        let small = Friction::CutOff { v1: 1e-12, v2: 1e-12 }.strength(w, theta, c);
        // −ln(1 + v1/v) + c ln(1 + v2 Th), Th = e^{θ/c}: first order in v1, v2.
        let expected = -1e-12 * (-w).exp() + c * 1e-12 * (theta / c).exp();
        assert!((small.value - expected).abs() < 1e-23, "{} vs {expected}", small.value);
        // V1, V2 ≫ V, V_pl/Θ: Φ = ln(v/v1) + c ln(v2 Th) + O(v/v1, 1/(v2 Th)), the classic law
        // with v* shifts.
        let large = Friction::CutOff { v1: 1e12, v2: 1e12 }.strength(w, theta, c);
        let classic = w - 1e12f64.ln() + c * (1e12f64.ln() + theta / c);
        assert!((large.value - classic).abs() < 1e-10, "{} vs {classic}", large.value);
    }
}
