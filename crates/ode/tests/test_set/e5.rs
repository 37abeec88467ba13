//! E5: the stiff DETEST problem E5 (Enright, Hull & Lindberg 1975), 4 equations,
//! t ∈ [0, 1e13]; the solution spans 300 orders of magnitude.
//!
//! Problem definition and reference solution: Test Set for IVP Solvers, release 2.4
//! (F. Mazzia, C. Magherini, Università di Bari, 2008), problem file `e5.f`
//! (revision `e5.F,v 1.3 2006/10/03`), subroutines `feval`, `jeval` and `solut`. The
//! reference was "computed using double precision RADAU on an Alphaserver DS20E, uround =
//! 1.01e-19, rtol = h0 = 1.1e-18, atol = 1.1e-40". Test Set tolerances: atol = 1.7e-24.

use super::problem::TestProblem;
use stickslip_ode::integrate::{JacobianMatrix, OdeSystem};

#[derive(Debug, Clone, Copy)]
pub struct E5;

const A: f64 = 7.89e-10;
const B: f64 = 1.1e7;
const CM: f64 = 1.13e9;
const C: f64 = 1.13e3;

impl OdeSystem for E5 {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        let prod1 = A * y[0];
        let prod2 = B * y[0] * y[2];
        let prod3 = CM * y[1] * y[2];
        let prod4 = C * y[3];
        f[0] = -prod1 - prod2;
        f[1] = prod1 - prod3;
        f[3] = prod2 - prod4;
        f[2] = f[1] - f[3];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut JacobianMatrix<'_>) {
        j.set(0, 0, -A - B * y[2]);
        j.set(0, 2, -B * y[0]);
        j.set(1, 0, A);
        j.set(1, 1, -CM * y[2]);
        j.set(1, 2, -CM * y[1]);
        j.set(2, 0, A - B * y[2]);
        j.set(2, 1, -CM * y[2]);
        j.set(2, 2, -B * y[0] - CM * y[1]);
        j.set(2, 3, C);
        j.set(3, 0, B * y[2]);
        j.set(3, 2, B * y[0]);
        j.set(3, 3, -C);
    }
}

impl TestProblem for E5 {
    const NAME: &'static str = "E5";
    const T_END: f64 = 1e13;
    fn new() -> Self {
        E5
    }
    fn y0() -> Vec<f64> {
        vec![1.76e-3, 0.0, 0.0, 0.0]
    }
    fn reference() -> Vec<f64> {
        vec![0.1152903278711829e-290, 0.8867655517642120e-22, 0.8854814626268838e-22, 0.0]
    }
    fn atol(_rtol: f64) -> f64 {
        1.7e-24
    }
}
