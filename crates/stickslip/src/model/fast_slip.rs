//! The fast (slip) system of the paper's eq. UV: with v = γV, t = t_c + T/γ,
//! u = U + c_u ln γ, θ = Θ + c_θ ln γ and the −1 of du/dt neglected,
//!
//! ```text
//! U' = V,   V' = −[U + (Θ + ln V)/ξ],   Θ' = −V [Θ + (1+ε) ln V],
//! ```
//!
//! free of γ when c_θ = −(1+ε) and c_u = ε/ξ (the paper's eq. cut). Only for f = ln v: other
//! friction laws do not turn ln γ into a shift. Integrated in (U, W = ln V, Θ) like the 3D
//! model.

use super::drr::DrrParams;
use super::friction::Friction;
use crate::integrate::{JacobianMatrix, OdeSystem};

/// The fast system in (U, W = ln V, Θ).
#[derive(Debug, Clone, Copy)]
pub struct FastSlip {
    xi: f64,
    epsilon: f64,
}

/// The predicted shifts (c_u, c_θ) = (ε/ξ, −(1+ε)).
pub fn shifts(xi: f64, epsilon: f64) -> (f64, f64) {
    (epsilon / xi, -(1.0 + epsilon))
}

impl FastSlip {
    /// The fast system of a model with f = ln v; None for other friction laws.
    pub fn new(params: &DrrParams) -> Option<Self> {
        (params.friction == Friction::Log)
            .then_some(Self { xi: params.xi, epsilon: params.epsilon })
    }

    /// Maps a 3D state (u, w = ln v, θ) to fast variables (U, W = ln V, Θ) at this γ.
    pub fn to_fast(&self, gamma: f64, y: &[f64; 3]) -> [f64; 3] {
        let l = gamma.ln();
        let (cu, ct) = shifts(self.xi, self.epsilon);
        [y[0] - cu * l, y[1] - l, y[2] - ct * l]
    }

    /// Maps fast variables back to the 3D state at this γ.
    pub fn from_fast(&self, gamma: f64, z: &[f64; 3]) -> [f64; 3] {
        let l = gamma.ln();
        let (cu, ct) = shifts(self.xi, self.epsilon);
        [z[0] + cu * l, z[1] + l, z[2] + ct * l]
    }
}

impl OdeSystem for FastSlip {
    fn dim(&self) -> usize {
        3
    }

    fn rhs(&self, _t: f64, z: &[f64], dz: &mut [f64]) {
        let big_v = z[1].exp();
        let g = z[0] + (z[2] + z[1]) / self.xi;
        dz[0] = big_v;
        dz[1] = -(-z[1]).exp() * g;
        dz[2] = -big_v * (z[2] + (1.0 + self.epsilon) * z[1]);
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, z: &[f64], jac: &mut JacobianMatrix<'_>) {
        let (big_v, inv) = (z[1].exp(), (-z[1]).exp());
        let g = z[0] + (z[2] + z[1]) / self.xi;
        jac.set(0, 1, big_v);
        jac.set(1, 0, -inv);
        jac.set(1, 1, inv * (g - 1.0 / self.xi));
        jac.set(1, 2, -inv / self.xi);
        jac.set(2, 1, -big_v * (z[2] + (1.0 + self.epsilon) * z[1]) - big_v * (1.0 + self.epsilon));
        jac.set(2, 2, -big_v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;
    use crate::model::Drr;

    fn params(gamma: f64) -> DrrParams {
        DrrParams::new(gamma, 0.7, 0.72, Friction::Log)
    }

    #[test]
    fn the_shifts_remove_gamma_up_to_the_neglected_drive() {
        // The 3D right-hand side, rescaled, equals the fast one except for du/dt's −1.
        let fast = FastSlip::new(&params(1.0)).unwrap();
        for gamma in [1e3, 1e8] {
            let drr = Drr::new(params(gamma));
            let z = [0.3, -0.5, 1.2];
            let y = fast.from_fast(gamma, &z);
            let (mut dy, mut dz) = ([0.0; 3], [0.0; 3]);
            drr.rhs(0.0, &y, &mut dy);
            fast.rhs(0.0, &z, &mut dz);
            // d/dT = (1/γ) d/dt.
            assert!(((dy[0] + 1.0) / gamma - dz[0]).abs() < 1e-12 * dz[0].abs());
            assert!(
                (dy[1] / gamma - dz[1]).abs() < 1e-9 * (1.0 + dz[1].abs()),
                "{gamma}: {} vs {}",
                dy[1] / gamma,
                dz[1]
            );
            assert!((dy[2] / gamma - dz[2]).abs() < 1e-9 * (1.0 + dz[2].abs()));
            assert_eq!(
                fast.to_fast(gamma, &y).map(|x| (x * 1e9).round()),
                z.map(|x| (x * 1e9).round())
            );
        }
        assert!(FastSlip::new(&DrrParams {
            friction: Friction::Power { alpha: 0.3 },
            ..params(1.0)
        })
        .is_none());
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let fast = FastSlip::new(&params(1.0)).unwrap();
        let z = [0.4, 1.3, -2.0];
        for (row, col, exact, fd) in jacobian_against_differences(&fast, &z, |_| 1e-6) {
            assert!((fd - exact).abs() < 1e-6 * (1.0 + fd.abs()), "({row},{col})");
        }
    }
}
