//! The Ornstein–Uhlenbeck noise: stationary, zero mean, unit variance and correlation time τ,
//!
//!   ⟨f(t) f(t')⟩ = exp(−|t − t'|/τ),   i.e.  df = −f/τ dt + √(2/τ) dW.
//!
//! It is sampled exactly on a grid of step h: f(t + h) = a f(t) + √(1 − a²) Z with a = e^{−h/τ}
//! and Z standard normal (the transition law of the process, with no discretisation error), and
//! the first value is drawn from the stationary law N(0, 1). Its intensity ∫⟨f(t)f(0)⟩dt is 2τ.

use super::rng::Rng;

/// The exact transition of the OU process over one grid step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OuStep {
    /// a = e^{−h/τ}.
    pub decay: f64,
    /// √(1 − a²), computed as √(−expm1(−2h/τ)) (accurate for h ≪ τ).
    pub innovation: f64,
}

impl OuStep {
    /// The transition over a step `h` for correlation time `tau`.
    pub fn new(h: f64, tau: f64) -> Self {
        Self { decay: (-h / tau).exp(), innovation: (-(-2.0 * h / tau).exp_m1()).sqrt() }
    }

    /// Advances every component of `eta` by one step with fresh normal deviates from `rng`.
    pub fn advance(&self, eta: &mut [f64], rng: &mut Rng) {
        for e in eta.iter_mut() {
            *e = self.decay * *e + self.innovation * rng.normal();
        }
    }
}

/// Draws each component of `eta` from the stationary law N(0, 1).
pub fn stationary(eta: &mut [f64], rng: &mut Rng) {
    for e in eta.iter_mut() {
        *e = rng.normal();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_process_has_the_exact_autocorrelation() {
        // 2e5 samples with lag correlation e^{−1/4} per step (h = τ/4): the lag-k sample
        // correlation has standard error ≈ √((1+a²)/(1−a²)/n) ≈ 5e-3 at most.
        let (h, tau) = (0.25, 1.0);
        let step = OuStep::new(h, tau);
        let mut rng = Rng::for_realisation(11, 0);
        let mut eta = [0.0];
        stationary(&mut eta, &mut rng);
        let n = 200_000;
        let mut xs = Vec::with_capacity(n);
        for _ in 0..n {
            xs.push(eta[0]);
            step.advance(&mut eta, &mut rng);
        }
        let var = xs.iter().map(|x| x * x).sum::<f64>() / n as f64;
        assert!((var - 1.0).abs() < 0.03, "variance {var}");
        for lag in [1usize, 2, 4, 8] {
            let c = xs.iter().zip(&xs[lag..]).map(|(a, b)| a * b).sum::<f64>() / (n - lag) as f64;
            let exact = (-(lag as f64) * h / tau).exp();
            assert!((c - exact).abs() < 0.03, "lag {lag}: {c} vs {exact}");
        }
    }
}
