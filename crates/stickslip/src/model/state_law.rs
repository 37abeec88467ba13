//! State-evolution laws of rate-and-state friction, in the paper's scaling.
//!
//! With φ = ln(v0·Θ/D_c), θ = (1+ε)φ, v = V/v0 and time in D_c/v0, every law reads
//!
//! ```text
//! dθ/dt = (1+ε) · v · F(x),   x = θ/(1+ε) + f(v)   (x = ln(VΘ/D_c) for f = ln v),
//! ```
//!
//! where the dimensional law dΘ/dt = G(VΘ/D_c) gives dφ/dt = v e^{−x} G(e^x), i.e.
//! F(x) = e^{−x} G(e^x):
//!
//! ```text
//! slip (Ruina):          dΘ/dt = −(VΘ/D_c) ln(VΘ/D_c)   F(x) = −x
//! ageing (Dieterich):    dΘ/dt = 1 − VΘ/D_c             F(x) = e^{−x} − 1
//! PRZ (Perrin–Rice–Zheng): dΘ/dt = 1 − (VΘ/(2D_c))²     F(x) = e^{−x} − e^{x}/4
//! no healing (QDYN's THETA_LAW = 0): dΘ/dt = −VΘ/D_c   F(x) = −1
//! ```
//!
//! For f = ln v the ageing law is dθ/dt = (1+ε)(e^{−θ/(1+ε)} − v). Other friction laws replace
//! ln v by f(v) inside x, the paper's convention for the slip law (its eq. puiss). The
//! derivation is in docs/state-laws.md.
//!
//! Steady sliding is F(x*) = 0: x* = 0 (slip, ageing), x* = ln 2 (PRZ), and the relaxation rate
//! there, κ = −F'(x*), is 1 for all three, so their linearisations at steady sliding coincide.
//!
//! The ageing law without healing is the ageing law without its healing term 1: F = −1 has no
//! zero, so the state only falls (dθ/dt = −(1+ε)v), friction only weakens, and there is no
//! steady sliding, no stability threshold and no cycle ([`StateLaw::heals`]); the block runs
//! away (docs/state-laws.md).

use serde::{Deserialize, Serialize};

/// The state-evolution law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StateLaw {
    /// Ruina's slip law (the paper's law).
    #[default]
    Slip,
    /// Dieterich's ageing law.
    Ageing,
    /// The Perrin–Rice–Zheng (1995) law.
    Prz,
    /// The ageing law without healing, dΘ/dt = −VΘ/D_c (QDYN's `THETA_LAW = 0`; scene name
    /// "no_healing"): no steady state, the block runs away.
    NoHealing,
}

/// v·F(x), v·F'(x) and v·F''(x) at (w = ln v, x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawTerms {
    /// v F(x).
    pub f: f64,
    /// v F'(x).
    pub d1: f64,
    /// v F''(x).
    pub d2: f64,
}

impl StateLaw {
    /// Every law with its scene name.
    pub const ALL: [(&'static str, StateLaw); 4] = [
        ("slip", StateLaw::Slip),
        ("ageing", StateLaw::Ageing),
        ("prz", StateLaw::Prz),
        ("no_healing", StateLaw::NoHealing),
    ];

    /// The scene name: "slip", "ageing", "prz" or "no_healing".
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(_, l)| *l == self).map_or("?", |(n, _)| n)
    }

    /// Other names the field uses for a law, accepted wherever a scene names a state law (the
    /// spring-slider's `model.state_law`, the laboratory's `model.states[i].law`): the
    /// American spelling and the laws' authors. Reports use the names of [`StateLaw::ALL`].
    pub const ALIASES: [(&'static str, StateLaw); 3] =
        [("aging", StateLaw::Ageing), ("dieterich", StateLaw::Ageing), ("ruina", StateLaw::Slip)];

    /// The law by its scene name or one of its [`StateLaw::ALIASES`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().chain(&Self::ALIASES).find(|(n, _)| *n == name).map(|(_, l)| *l)
    }

    /// v·F(x) alone at w = ln v, given v = e^w: the `f` of [`StateLaw::terms`], for a
    /// right-hand side that needs no derivatives. The exponentials are combined (e^{w∓x}) so
    /// that v e^{∓x} does not overflow where the product is finite.
    pub fn rate(self, w: f64, v: f64, x: f64) -> f64 {
        match self {
            StateLaw::Slip => -v * x,
            StateLaw::Ageing => (w - x).exp() - v,
            StateLaw::Prz => (w - x).exp() - 0.25 * (w + x).exp(),
            StateLaw::NoHealing => -v,
        }
    }

    /// Whether the law heals (F has a zero): false only for [`StateLaw::NoHealing`], which
    /// has no steady sliding, so no fixed point, stability threshold or cycle.
    pub fn heals(self) -> bool {
        self != StateLaw::NoHealing
    }

    /// v·F(x) and its first two x-derivatives times v, at w = ln v, given v = e^w (see
    /// [`StateLaw::rate`]).
    pub fn terms(self, w: f64, v: f64, x: f64) -> LawTerms {
        let f = self.rate(w, v, x);
        match self {
            StateLaw::Slip => LawTerms { f, d1: -v, d2: 0.0 },
            StateLaw::Ageing => {
                let a = (w - x).exp();
                LawTerms { f, d1: -a, d2: a }
            }
            StateLaw::Prz => {
                let (a, b) = ((w - x).exp(), 0.25 * (w + x).exp());
                LawTerms { f, d1: -a - b, d2: a - b }
            }
            StateLaw::NoHealing => LawTerms { f, d1: 0.0, d2: 0.0 },
        }
    }

    /// x* with F(x*) = 0: the value of ln(VΘ/D_c) at steady sliding. The no-healing law has
    /// none (see [`StateLaw::heals`]); for it this is x = 0 (Θ = D_c/V, where the ageing law
    /// heals no more), the reference state its scenes start from by default.
    pub fn steady_x(self) -> f64 {
        match self {
            StateLaw::Slip | StateLaw::Ageing | StateLaw::NoHealing => 0.0,
            StateLaw::Prz => std::f64::consts::LN_2,
        }
    }

    /// κ = −F'(x*), the relaxation rate of the state at steady sliding (per unit v); 0 for the
    /// no-healing law, which does not relax.
    pub fn steady_rate(self) -> f64 {
        -self.terms(0.0, 1.0, self.steady_x()).d1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_match_differences_and_vanish_at_steady_sliding() {
        for (_, law) in StateLaw::ALL {
            let w = 0.7f64;
            let v = w.exp();
            for x in [-2.0, -0.3, 0.0, 0.4, 1.5] {
                let t = law.terms(w, v, x);
                let h = 1e-6;
                let (p, m) = (law.terms(w, v, x + h), law.terms(w, v, x - h));
                assert!(
                    ((p.f - m.f) / (2.0 * h) - t.d1).abs() < 1e-7 * (1.0 + t.d1.abs()),
                    "{law:?} x={x}"
                );
                assert!(
                    ((p.d1 - m.d1) / (2.0 * h) - t.d2).abs() < 1e-7 * (1.0 + t.d2.abs()),
                    "{law:?} x={x}"
                );
            }
            if !law.heals() {
                continue;
            }
            assert!(law.terms(0.3, 0.3f64.exp(), law.steady_x()).f.abs() < 1e-15, "{law:?}");
            assert!((law.steady_rate() - 1.0).abs() < 1e-15, "{law:?}: κ = {}", law.steady_rate());
        }
    }

    #[test]
    fn no_healing_is_the_ageing_law_without_its_healing_term() {
        // dΘ/dt = −VΘ/D_c: dθ/dt = −(1+ε) v whatever θ; the ageing law's rate minus its
        // healing term (1+ε) e^{−θ/(1+ε)}.
        let (eps, theta, w) = (0.5f64, -3.7, 2.2f64);
        let c = 1.0 + eps;
        let x = theta / c + w;
        let ours = c * StateLaw::NoHealing.rate(w, w.exp(), x);
        assert_eq!(ours, -c * w.exp());
        let ageing = c * StateLaw::Ageing.rate(w, w.exp(), x);
        assert!((ageing - c * (-theta / c).exp() - ours).abs() < 1e-13 * ours.abs());
        assert!(!StateLaw::NoHealing.heals() && StateLaw::Ageing.heals());
        assert_eq!(StateLaw::from_name("no_healing"), Some(StateLaw::NoHealing));
        for (alias, law) in [("aging", "ageing"), ("dieterich", "ageing"), ("ruina", "slip")] {
            assert_eq!(StateLaw::from_name(alias), StateLaw::from_name(law), "{alias}");
        }
        assert_eq!(StateLaw::from_name("agin"), None);
    }

    #[test]
    fn ageing_with_log_friction_is_dieterichs_law_in_the_papers_scaling() {
        // dθ/dt = (1+ε)(e^{−θ/(1+ε)} − v) with x = θ/(1+ε) + ln v.
        let (eps, theta, w) = (1.0f64, 0.37, -1.2f64);
        let c = 1.0 + eps;
        let ours = c * StateLaw::Ageing.rate(w, w.exp(), theta / c + w);
        let direct = c * ((-theta / c).exp() - w.exp());
        assert!((ours - direct).abs() < 1e-15, "{ours} vs {direct}");
    }
}
