//! Friction laws f(v) of the Dieterich–Ruina model.

use serde::{Deserialize, Serialize};

/// The velocity dependence f(v) of the friction.
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
}

impl Friction {
    /// f(v) and v·f'(v), given w = ln v (so that tiny and huge v are handled without
    /// overflow where the law allows it).
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
        }
    }

    /// A short label, e.g. "log", "asinh", "power(alpha=0.31)".
    pub fn label(self) -> String {
        match self {
            Friction::Log => "log".into(),
            Friction::Asinh => "asinh".into(),
            Friction::Power { alpha } => format!("power(alpha={alpha})"),
        }
    }
}
