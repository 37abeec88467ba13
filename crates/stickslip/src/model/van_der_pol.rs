//! The van der Pol oscillator in Liénard form, the prototype of relaxation oscillations with a
//! saddle-node (fold) transition (Pomeau & Le Berre, eq. 1):
//!
//!   dy/dt = x + a,  dx/dt = β² (x − x³/3 − y),
//!
//! stored as (x, y), x the fast variable. For large β the motion drifts along the stable
//! branches |x| > 1 of the slow manifold y = x − x³/3 and jumps at the folds (x, y) = (±1, ±2/3).
//! For |a| < 1 the fixed point x = −a lies on the unstable middle branch and the orbit is a
//! relaxation oscillation.

use crate::integrate::{JacobianMatrix, OdeSystem};

/// Parameters of the van der Pol (Liénard) model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct VanDerPolParams {
    /// β > 0: β² is the rate of the fast variable x.
    pub beta: f64,
    /// The shift a of dy/dt = x + a (|a| < 1: relaxation oscillation).
    pub a: f64,
}

/// Index of the fast variable x.
pub const X: usize = 0;
/// Index of the slow variable y.
pub const Y: usize = 1;

/// The system in (x, y).
#[derive(Debug, Clone, Copy)]
pub struct VanDerPol {
    params: VanDerPolParams,
    beta2: f64,
}

impl VanDerPol {
    /// The system for the given parameters.
    pub fn new(params: VanDerPolParams) -> Self {
        Self { params, beta2: params.beta * params.beta }
    }

    /// The parameters.
    pub fn params(&self) -> &VanDerPolParams {
        &self.params
    }
}

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }

    fn rhs(&self, _t: f64, z: &[f64], dzdt: &mut [f64]) {
        let x = z[X];
        dzdt[X] = self.beta2 * (x - x * x * x / 3.0 - z[Y]);
        dzdt[Y] = x + self.params.a;
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, z: &[f64], jac: &mut JacobianMatrix<'_>) {
        let x = z[X];
        jac.set(X, X, self.beta2 * (1.0 - x * x));
        jac.set(X, Y, -self.beta2);
        jac.set(Y, X, 1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::jacobian_against_differences;

    #[test]
    fn jacobian_matches_central_differences() {
        let m = VanDerPol::new(VanDerPolParams { beta: 3.0, a: 0.4 });
        for z in [[1.5, 0.2], [-0.7, 0.6], [2.1, -0.66]] {
            for (row, col, exact, fd) in jacobian_against_differences(&m, &z, |_| 1e-6) {
                assert!((fd - exact).abs() < 1e-6 * (1.0 + fd.abs()), "({row},{col})");
            }
        }
    }
}
