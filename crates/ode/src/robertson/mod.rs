//! Robertson's chemical kinetics, the stiff test problem of SUNDIALS' examples
//! `cvode/serial/cvRoberts_dns.c` and `arkode/C_serial/ark_robertson_root.c`, which
//! [`examples`] replays through the wrappers.
//!
//! dy1/dt = −0.04 y1 + 1e4 y2 y3, dy2/dt = 0.04 y1 − 1e4 y2 y3 − 3e7 y2², dy3/dt = 3e7 y2²,
//! y(0) = (1, 0, 0); roots g1 = y1 − 1e-4, g2 = y3 − 0.01.
//!
//! Reference: Hindmarsh et al., SUNDIALS example programs (Debian package libsundials-dev,
//! /usr/share/doc/libsundials-dev/examples).

use crate::integrate::{JacobianMatrix, OdeSystem, Roots};

pub mod examples;

/// The Robertson system.
#[derive(Debug, Clone, Copy, Default)]
pub struct Robertson;

impl OdeSystem for Robertson {
    fn dim(&self) -> usize {
        3
    }

    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        let yd1 = -0.04 * y[0] + 1.0e4 * y[1] * y[2];
        let yd3 = 3.0e7 * y[1] * y[1];
        dydt[0] = yd1;
        dydt[2] = yd3;
        dydt[1] = -yd1 - yd3;
    }

    fn has_jacobian(&self) -> bool {
        true
    }

    fn jacobian(&self, _t: f64, y: &[f64], jac: &mut JacobianMatrix<'_>) {
        let (y2, y3) = (y[1], y[2]);
        jac.set(0, 0, -0.04);
        jac.set(0, 1, 1.0e4 * y3);
        jac.set(0, 2, 1.0e4 * y2);
        jac.set(1, 0, 0.04);
        jac.set(1, 1, -1.0e4 * y3 - 6.0e7 * y2);
        jac.set(1, 2, -1.0e4 * y2);
        jac.set(2, 1, 6.0e7 * y2);
    }
}

/// The examples' root functions: y1 = 1e-4 and y3 = 0.01.
pub fn roots() -> Roots {
    Roots::new(2, |_t, y, g| {
        g[0] = y[0] - 1.0e-4;
        g[1] = y[2] - 0.01;
    })
}
