//! The three models the noise analysis drives, each as dx/dt = F(t, x) + B(x) η(t) with one
//! independent OU noise η_i per state component and a diagonal B:
//!
//! - DRR in (u, w = ln v, θ): du/dt = v − 1 + η_u f_u, dv/dt = −γ²G + η_v f_v,
//!   dθ/dt = (1+ε) v F(x) + η_θ f_θ, with [`Drr`]'s right-hand side (any state law F, any
//!   radiation damping η in G). The noise on v enters w = ln v as η_v f_v e^{−w}: with
//!   coloured (OU) noise every realisation is an ordinary differential equation, so ordinary
//!   calculus applies (dw = dv/v; no Itô/Stratonovich correction).
//! - saddle-node in x: dx/dt = μ0 − r t − x² + η_x f_x.
//! - van der Pol in (x, y): dx/dt = β²(x − x³/3 − y) + η_x f_x, dy/dt = x + a + η_y f_y.

use crate::integrate::{JacobianMatrix, OdeSystem};
use crate::model::drr::{Drr, W};
use crate::model::{SaddleNode, VanDerPol};

/// Largest state dimension of the models (the DRR's 3).
pub const MAX_DIM: usize = 3;

/// How an observable is read from the state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Observable {
    /// The state component itself.
    Component(usize),
    /// e^{component} (v = e^w for the DRR).
    ExpOf(usize),
    /// The van der Pol fast variable's distance from its slow manifold, x − x³/3 − y
    /// (= (dx/dt)/β² without noise): the fast fluctuation alone.
    ManifoldOffset,
}

impl Observable {
    /// Its value at the state x.
    pub fn value(self, x: &[f64]) -> f64 {
        match self {
            Observable::Component(i) => x[i],
            Observable::ExpOf(i) => x[i].exp(),
            Observable::ManifoldOffset => x[0] - x[0] * x[0] * x[0] / 3.0 - x[1],
        }
    }

    /// Its gradient with respect to the state at x (for the linear response: δo = ∇o·δx).
    pub fn gradient(self, x: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|g| *g = 0.0);
        match self {
            Observable::Component(i) => out[i] = 1.0,
            Observable::ExpOf(i) => out[i] = x[i].exp(),
            Observable::ManifoldOffset => {
                out[0] = 1.0 - x[0] * x[0];
                out[1] = -1.0;
            }
        }
    }
}

/// What defines the event time t_c.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EventKind {
    /// The maximum of a component over the run (the DRR's v maximum, the paper's t_c). The
    /// search is armed once the component, having been at or below `arm`, exceeds it; a
    /// realisation stops once the component has fallen `drop` below its running maximum.
    Maximum {
        /// The component.
        component: usize,
        /// Arming level.
        arm: f64,
        /// Fall below the running maximum that ends the run.
        drop: f64,
    },
    /// A downward crossing of `level` by a component (the saddle-node's escape, the van der Pol
    /// jump off the fold).
    /// It counts only once the component has been above `arm` (≥ level) since the search began.
    CrossDown {
        /// The component.
        component: usize,
        /// The level.
        level: f64,
        /// Arming level.
        arm: f64,
    },
    /// An upward crossing of `level` by a component (the DRR's v = 1 before a slip, for t0). It
    /// counts only once the component has been below `arm` (≤ level) since the search began.
    CrossUp {
        /// The component.
        component: usize,
        /// The level.
        level: f64,
        /// Arming level.
        arm: f64,
    },
}

/// A model with its noise amplitudes.
#[derive(Debug, Clone, Copy)]
pub enum NoiseModel {
    /// The DRR system with amplitudes (η_u, η_v, η_θ).
    Drr {
        /// The deterministic system.
        system: Drr,
        /// (η_u, η_v, η_θ).
        amplitudes: [f64; 3],
    },
    /// The saddle-node with amplitude η_x.
    SaddleNode {
        /// The deterministic system.
        system: SaddleNode,
        /// η_x.
        amplitude: f64,
    },
    /// The van der Pol oscillator with amplitudes (η_x, η_y).
    VanDerPol {
        /// The deterministic system.
        system: VanDerPol,
        /// (η_x, η_y).
        amplitudes: [f64; 2],
    },
    /// The validation model dx/dt = −λx + η f (an OU process driven by OU noise), whose mean
    /// and variance are known exactly: the scheme's weak-convergence test. It has no event.
    Linear {
        /// The relaxation rate λ.
        rate: f64,
        /// η.
        amplitude: f64,
    },
}

impl NoiseModel {
    /// "drr", "saddle_node" or "van_der_pol".
    pub fn kind(&self) -> &'static str {
        match self {
            NoiseModel::Drr { .. } => "drr",
            NoiseModel::SaddleNode { .. } => "saddle_node",
            NoiseModel::VanDerPol { .. } => "van_der_pol",
            NoiseModel::Linear { .. } => "linear",
        }
    }

    /// The same model with every amplitude multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        match *self {
            NoiseModel::Drr { system, amplitudes } => {
                NoiseModel::Drr { system, amplitudes: amplitudes.map(|a| a * factor) }
            }
            NoiseModel::SaddleNode { system, amplitude } => {
                NoiseModel::SaddleNode { system, amplitude: amplitude * factor }
            }
            NoiseModel::VanDerPol { system, amplitudes } => {
                NoiseModel::VanDerPol { system, amplitudes: amplitudes.map(|a| a * factor) }
            }
            NoiseModel::Linear { rate, amplitude } => {
                NoiseModel::Linear { rate, amplitude: amplitude * factor }
            }
        }
    }

    /// The noise amplitudes, one per component.
    pub fn amplitudes(&self) -> Vec<f64> {
        match self {
            NoiseModel::Drr { amplitudes, .. } => amplitudes.to_vec(),
            NoiseModel::SaddleNode { amplitude, .. } => vec![*amplitude],
            NoiseModel::VanDerPol { amplitudes, .. } => amplitudes.to_vec(),
            NoiseModel::Linear { amplitude, .. } => vec![*amplitude],
        }
    }

    /// Names of the state components.
    pub fn component_names(&self) -> &'static [&'static str] {
        match self {
            NoiseModel::Drr { .. } => &["u", "ln_v", "theta"],
            NoiseModel::SaddleNode { .. } => &["x"],
            NoiseModel::VanDerPol { .. } => &["x", "y"],
            NoiseModel::Linear { .. } => &["x"],
        }
    }

    /// The reported observables (name, how to read it). The first one is the variable whose
    /// correlation time is reported (u for the DRR, x otherwise); the van der Pol model adds
    /// x_offset = x − x³/3 − y, the fast variable's distance from its slow manifold.
    pub fn observables(&self) -> &'static [(&'static str, Observable)] {
        match self {
            NoiseModel::Drr { .. } => &[
                ("u", Observable::Component(0)),
                ("v", Observable::ExpOf(1)),
                ("theta", Observable::Component(2)),
            ],
            NoiseModel::SaddleNode { .. } | NoiseModel::Linear { .. } => {
                &[("x", Observable::Component(0))]
            }
            NoiseModel::VanDerPol { .. } => &[
                ("x", Observable::Component(0)),
                ("y", Observable::Component(1)),
                ("x_offset", Observable::ManifoldOffset),
            ],
        }
    }

    /// The diagonal of B(x) into `b` (b_i = amplitude_i, and η_v e^{−w} for the DRR's w).
    pub fn noise_diag(&self, x: &[f64], b: &mut [f64]) {
        match self {
            NoiseModel::Drr { amplitudes, .. } => {
                b[0] = amplitudes[0];
                b[1] = amplitudes[1] * (-x[W]).exp();
                b[2] = amplitudes[2];
            }
            NoiseModel::SaddleNode { amplitude, .. } | NoiseModel::Linear { amplitude, .. } => {
                b[0] = *amplitude
            }
            NoiseModel::VanDerPol { amplitudes, .. } => b[..2].copy_from_slice(amplitudes),
        }
    }

    /// Adds B(x) η to `out`.
    pub fn add_forcing(&self, x: &[f64], eta: &[f64], out: &mut [f64]) {
        let mut b = [0.0; MAX_DIM];
        let n = self.dim();
        self.noise_diag(x, &mut b[..n]);
        for i in 0..n {
            out[i] += b[i] * eta[i];
        }
    }

    /// dx/dt = F(t, x) + B(x) η into `out`: the model's own right-hand side F (for the DRR,
    /// [`Drr`]'s, with its state law and radiation damping: one definition of the dynamics)
    /// plus the forcing.
    pub fn forced_rhs(&self, t: f64, x: &[f64], eta: &[f64], out: &mut [f64]) {
        if let NoiseModel::Drr { system, amplitudes } = self {
            // The same sums as below, with one exponential (issue #30).
            system.rhs_with_velocity_force(x, amplitudes[1], eta[W], out);
            out[0] += amplitudes[0] * eta[0];
            out[2] += amplitudes[2] * eta[2];
            return;
        }
        self.rhs(t, x, out);
        self.add_forcing(x, eta, out);
    }

    /// Whether the drift F is autonomous (true but for the saddle-node's ramp μ0 − r t).
    pub fn drift_is_autonomous(&self) -> bool {
        !matches!(self, NoiseModel::SaddleNode { .. })
    }

    /// ∂/∂x of [`NoiseModel::forced_rhs`] into `jac` (which arrives zeroed): the model's
    /// Jacobian plus ∂(B(x)η)/∂x, of which only the DRR's w entry depends on x
    /// (−η_v e^{−w} η_w; with one exponential, [`Drr::jacobian_with_velocity_force`]).
    pub fn forced_jacobian(&self, t: f64, x: &[f64], eta: &[f64], jac: &mut JacobianMatrix<'_>) {
        if let NoiseModel::Drr { system, amplitudes } = self {
            system.jacobian_with_velocity_force(x, amplitudes[1], eta[W], jac);
            return;
        }
        self.jacobian(t, x, jac);
    }
}

impl OdeSystem for NoiseModel {
    fn dim(&self) -> usize {
        match self {
            NoiseModel::Drr { .. } => 3,
            NoiseModel::SaddleNode { .. } => 1,
            NoiseModel::VanDerPol { .. } => 2,
            NoiseModel::Linear { .. } => 1,
        }
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        match self {
            NoiseModel::Drr { system, .. } => system.rhs(t, y, dydt),
            NoiseModel::SaddleNode { system, .. } => system.rhs(t, y, dydt),
            NoiseModel::VanDerPol { system, .. } => system.rhs(t, y, dydt),
            NoiseModel::Linear { rate, .. } => dydt[0] = -rate * y[0],
        }
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        match self {
            NoiseModel::Drr { system, .. } => system.jacobian(t, y, jac),
            NoiseModel::SaddleNode { system, .. } => system.jacobian(t, y, jac),
            NoiseModel::VanDerPol { system, .. } => system.jacobian(t, y, jac),
            NoiseModel::Linear { rate, .. } => jac.set(0, 0, -rate),
        }
    }

    /// The deterministic system's answer (the DRR has none); the other models keep the
    /// default (true).
    fn has_linear_invariants(&self) -> bool {
        match self {
            NoiseModel::Drr { system, .. } => system.has_linear_invariants(),
            NoiseModel::SaddleNode { system, .. } => system.has_linear_invariants(),
            NoiseModel::VanDerPol { system, .. } => system.has_linear_invariants(),
            NoiseModel::Linear { .. } => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DrrParams, Friction, StateLaw};

    /// The forced DRR against the closed forms of docs/state-laws.md (f = ln v), written out
    /// here independently of [`Drr`]: du/dt = v − 1 + a_u η_u, dw/dt = (−γ²G + a_v η_v)/v with
    /// G = u + (θ + ln v + ηv)/ξ, and dθ/dt = slip −v(θ + (1+ε) ln v), ageing
    /// (1+ε)(e^{−θ/(1+ε)} − v), PRZ (1+ε)(e^{−θ/(1+ε)} − v² e^{θ/(1+ε)}/4), plus a_θ η_θ.
    #[test]
    fn forced_drr_matches_the_closed_forms_for_every_state_law_and_damping() {
        let (gamma, xi, epsilon) = (30.0, 0.7, 0.72);
        let c = 1.0 + epsilon;
        let amplitudes = [0.1, 3e3, 0.2];
        for (name, state_law) in StateLaw::ALL {
            for eta_damping in [0.0, 0.37] {
                let params = DrrParams {
                    state_law,
                    eta: eta_damping,
                    ..DrrParams::new(gamma, xi, epsilon, Friction::Log)
                };
                let m = NoiseModel::Drr { system: Drr::new(params), amplitudes };
                for x in [[0.3f64, -0.4, 0.2], [1.0, 0.1, -0.3], [-2.0, 2.0, 1.0]] {
                    for noise in [[0.0; 3], [0.5, -1.2, 0.7]] {
                        let (u, w, theta) = (x[0], x[1], x[2]);
                        let v = w.exp();
                        let g = u + (theta + w + eta_damping * v) / xi;
                        let drift_theta = match state_law {
                            StateLaw::Slip => -v * (theta + c * w),
                            StateLaw::Ageing => c * ((-theta / c).exp() - v),
                            StateLaw::Prz => {
                                c * ((-theta / c).exp() - v * v * (theta / c).exp() / 4.0)
                            }
                            StateLaw::NoHealing => -c * v,
                        };
                        let expected = [
                            v - 1.0 + amplitudes[0] * noise[0],
                            (-gamma * gamma * g + amplitudes[1] * noise[1]) / v,
                            drift_theta + amplitudes[2] * noise[2],
                        ];
                        let mut got = [0.0; 3];
                        m.forced_rhs(0.0, &x, &noise, &mut got);
                        for i in 0..3 {
                            // dw/dt is a difference of terms of size γ²(|u| + (|θ| + |ln v| + ηv)/ξ)/v.
                            let terms = (gamma
                                * gamma
                                * (u.abs() + (theta.abs() + w.abs() + eta_damping * v) / xi)
                                + amplitudes[1])
                                / v;
                            let scale = 1.0 + expected[i].abs() + if i == 1 { terms } else { 0.0 };
                            assert!(
                                (got[i] - expected[i]).abs() <= 1e-14 * scale,
                                "{name} η = {eta_damping} {x:?} {noise:?} component {i}: {} vs {}",
                                got[i],
                                expected[i]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn forced_jacobian_matches_differences() {
        let m = NoiseModel::Drr {
            system: Drr::new(DrrParams::new(10.0, 0.7, 0.72, Friction::Log)),
            amplitudes: [0.1, 3.0, 0.2],
        };
        let (x, eta) = ([0.3, -0.4, 0.2], [0.5, -1.2, 0.7]);
        let mut storage = [0.0; 9];
        let mut jac = JacobianMatrix::new(&mut storage, 3);
        m.forced_jacobian(0.0, &x, &eta, &mut jac);
        for col in 0..3 {
            let (mut xp, mut xm) = (x, x);
            xp[col] += 1e-6;
            xm[col] -= 1e-6;
            let (mut fp, mut fm) = ([0.0; 3], [0.0; 3]);
            m.forced_rhs(0.0, &xp, &eta, &mut fp);
            m.forced_rhs(0.0, &xm, &eta, &mut fm);
            for row in 0..3 {
                let fd = (fp[row] - fm[row]) / 2e-6;
                assert!((fd - jac.get(row, col)).abs() < 1e-6 * (1.0 + fd.abs()), "({row},{col})");
            }
        }
    }
}
