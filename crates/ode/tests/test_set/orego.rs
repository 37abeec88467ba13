//! OREGO: the Oregonator (Field–Noyes), 3 equations, t ∈ [0, 360].
//!
//! Problem definition and reference solution: Test Set for IVP Solvers, release 2.4
//! (F. Mazzia, C. Magherini, Università di Bari, 2008), problem file `orego.f`
//! (revision `orego.F,v 1.4 2006/10/06`), subroutines `feval`, `jeval` and `solut`. The
//! reference was "computed using double precision RADAU on an Alphaserver DS20E, uround =
//! 1.01e-19, rtol = h0 = 1.1e-18, atol = 1.1e-40". Test Set tolerances: rtol = atol.

use super::problem::TestProblem;
use stickslip_ode::integrate::{JacobianMatrix, OdeSystem};

#[derive(Debug, Clone, Copy)]
pub struct Orego;

const S: f64 = 77.27;
const Q: f64 = 8.375e-6;
const W: f64 = 0.161;

impl OdeSystem for Orego {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = S * (y[1] + y[0] * (1.0 - Q * y[0] - y[1]));
        f[1] = (y[2] - (1.0 + y[0]) * y[1]) / S;
        f[2] = W * (y[0] - y[2]);
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut JacobianMatrix<'_>) {
        j.set(0, 0, S * (1.0 - 2.0 * Q * y[0] - y[1]));
        j.set(0, 1, S * (1.0 - y[0]));
        j.set(1, 0, -y[1] / S);
        j.set(1, 1, -(1.0 + y[0]) / S);
        j.set(1, 2, 1.0 / S);
        j.set(2, 0, W);
        j.set(2, 2, -W);
    }
}

impl TestProblem for Orego {
    const NAME: &'static str = "OREGO";
    const T_END: f64 = 360.0;
    fn new() -> Self {
        Orego
    }
    fn y0() -> Vec<f64> {
        vec![1.0, 2.0, 3.0]
    }
    fn reference() -> Vec<f64> {
        vec![0.1000814870318523e1, 0.1228178521549917e4, 0.1320554942846706e3]
    }
}
