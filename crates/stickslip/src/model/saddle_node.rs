//! The slowly passed saddle-node ("potential model"): an overdamped particle in a cubic
//! potential that tilts slowly with time,
//!
//!   dx/dt = μ(t) − x²,  μ(t) = μ0 − r·t.
//!
//! For μ > 0 the particle rests near the stable equilibrium x = +√μ, whose relaxation rate 2√μ
//! vanishes at the fold μ = 0 (t* = μ0/r). The passage is delayed: with x = r^{1/3} X and
//! t − t* = r^{−1/3} T the equation becomes dX/dT = −T − X² (Airy/Riccati), and x escapes to −∞
//! in finite time at t* + a₁ r^{−1/3} with a₁ = 2.33811 (the first zero of Ai(−s)). This is the
//! standard saddle-node transition of relaxation oscillations of van der Pol type, the reference
//! for "critical slowing-down" in Pomeau & Le Berre.

use crate::integrate::{JacobianMatrix, OdeSystem};

/// Parameters of the saddle-node model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SaddleNodeParams {
    /// μ at t = 0 (> 0: the particle starts near the stable equilibrium √μ0).
    pub mu0: f64,
    /// The tilting rate r > 0 (μ = μ0 − r t).
    pub r: f64,
}

/// The system dx/dt = μ0 − r t − x² (one component).
#[derive(Debug, Clone, Copy)]
pub struct SaddleNode {
    params: SaddleNodeParams,
}

impl SaddleNode {
    /// The system for the given parameters.
    pub fn new(params: SaddleNodeParams) -> Self {
        Self { params }
    }

    /// The parameters.
    pub fn params(&self) -> &SaddleNodeParams {
        &self.params
    }

    /// μ(t) = μ0 − r t.
    pub fn mu(&self, t: f64) -> f64 {
        self.params.mu0 - self.params.r * t
    }

    /// The time of the fold, t* = μ0/r.
    pub fn fold_time(&self) -> f64 {
        self.params.mu0 / self.params.r
    }

    /// The slow-passage time scale r^{−1/3}: the escape comes 2.338·r^{−1/3} after the fold.
    pub fn passage_scale(&self) -> f64 {
        self.params.r.powf(-1.0 / 3.0)
    }
}

impl OdeSystem for SaddleNode {
    fn dim(&self) -> usize {
        1
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = self.mu(t) - y[0] * y[0];
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -2.0 * y[0]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rhs_and_jacobian() {
        let s = SaddleNode::new(SaddleNodeParams { mu0: 1.0, r: 0.01 });
        let mut f = [0.0];
        s.rhs(50.0, &[0.3], &mut f);
        assert!((f[0] - (0.5 - 0.09)).abs() < 1e-15);
        let mut storage = [0.0];
        let mut jac = JacobianMatrix::new(&mut storage, 1);
        s.jacobian(50.0, &[0.3], &mut jac);
        assert_eq!(jac.get(0, 0), -0.6);
        assert_eq!(s.fold_time(), 100.0);
    }
}
