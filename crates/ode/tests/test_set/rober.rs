//! ROBER: Robertson's chemical kinetics, 3 equations, t ∈ [0, 1e11].
//!
//! Problem definition and reference solution: Test Set for IVP Solvers, release 2.4
//! (F. Mazzia, C. Magherini, Università di Bari, 2008), problem file `rober.f`
//! (revision `rober.F,v 1.2 2006/10/02`), subroutines `feval`, `jeval` and `solut`. The
//! reference was "computed using double precision RADAU on an Alphaserver DS20E, uround =
//! 1.01e-19, rtol = atol = h0 = 1.1e-18". Test Set tolerances: atol = 1e-4·rtol.

use super::problem::TestProblem;
use stickslip_ode::integrate::{JacobianMatrix, OdeSystem};

#[derive(Debug, Clone, Copy)]
pub struct Rober;

impl OdeSystem for Rober {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
        f[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1];
        f[2] = 3e7 * y[1] * y[1];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut JacobianMatrix<'_>) {
        j.set(0, 0, -0.04);
        j.set(0, 1, 1e4 * y[2]);
        j.set(0, 2, 1e4 * y[1]);
        j.set(1, 0, 0.04);
        j.set(1, 1, -1e4 * y[2] - 6e7 * y[1]);
        j.set(1, 2, -1e4 * y[1]);
        j.set(2, 1, 6e7 * y[1]);
    }
}

impl TestProblem for Rober {
    const NAME: &'static str = "ROBER";
    const T_END: f64 = 1e11;
    fn new() -> Self {
        Rober
    }
    fn y0() -> Vec<f64> {
        vec![1.0, 0.0, 0.0]
    }
    fn reference() -> Vec<f64> {
        vec![0.2083340149701255e-7, 0.8333360770334713e-13, 0.9999999791665050e0]
    }
    fn atol(rtol: f64) -> f64 {
        1e-4 * rtol
    }
}
