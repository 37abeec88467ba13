//! VDPOL: the van der Pol oscillator with ε = 1e-6, t ∈ [0, 2].
//!
//! Problem definition and reference solution: Test Set for IVP Solvers, release 2.4
//! (F. Mazzia, C. Magherini, Università di Bari, 2008), problem file `vdpol.f`
//! (revision `vdpol.F,v 1.2 2006/10/02`), subroutines `feval`, `jeval` and `solut`. The
//! reference was "computed using double precision RADAU on an Alphaserver DS20E, uround =
//! 1.01e-19, rtol = atol = h0 = 1.1e-18". Test Set tolerances: rtol = atol.

use super::problem::TestProblem;
use stickslip_ode::integrate::{JacobianMatrix, OdeSystem};

#[derive(Debug, Clone, Copy)]
pub struct Vdpol;

const EPS: f64 = 1e-6;

impl OdeSystem for Vdpol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = y[1];
        f[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / EPS;
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut JacobianMatrix<'_>) {
        j.set(0, 1, 1.0);
        j.set(1, 0, (-2.0 * y[0] * y[1] - 1.0) / EPS);
        j.set(1, 1, (1.0 - y[0] * y[0]) / EPS);
    }
}

impl TestProblem for Vdpol {
    const NAME: &'static str = "VDPOL";
    const T_END: f64 = 2.0;
    fn new() -> Self {
        Vdpol
    }
    fn y0() -> Vec<f64> {
        vec![2.0, 0.0]
    }
    fn reference() -> Vec<f64> {
        vec![0.1706167732170483e1, -0.8928097010247975e0]
    }
}
