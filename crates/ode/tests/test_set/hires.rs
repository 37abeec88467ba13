//! HIRES: 8 chemical reactions in plant physiology (Schäfer 1975), t ∈ [0, 321.8122].
//!
//! Problem definition and reference solution: Test Set for IVP Solvers, release 2.4
//! (F. Mazzia, C. Magherini, Università di Bari, 2008), problem file `hires.f`
//! (revision `hires.F,v 1.2 2006/10/02`), subroutines `feval`, `jeval` and `solut`. The
//! reference was "computed using true double precision RADAU5 on Cray C90, uround = 1.01e-19,
//! rtol = atol = h0 = 1.1e-18". Test Set tolerances: rtol = atol.

use super::problem::TestProblem;
use stickslip_ode::integrate::{JacobianMatrix, OdeSystem};

#[derive(Debug, Clone, Copy)]
pub struct Hires;

impl OdeSystem for Hires {
    fn dim(&self) -> usize {
        8
    }
    fn rhs(&self, _t: f64, y: &[f64], f: &mut [f64]) {
        f[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007;
        f[1] = 1.71 * y[0] - 8.75 * y[1];
        f[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4];
        f[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3];
        f[4] = -1.745 * y[4] + 0.43 * (y[5] + y[6]);
        f[5] = -280.0 * y[5] * y[7] + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6];
        f[6] = 280.0 * y[5] * y[7] - 1.81 * y[6];
        f[7] = -f[6];
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut JacobianMatrix<'_>) {
        let entries = [
            (0, 0, -1.71),
            (0, 1, 0.43),
            (0, 2, 8.32),
            (1, 0, 1.71),
            (1, 1, -8.75),
            (2, 2, -10.03),
            (2, 3, 0.43),
            (2, 4, 0.035),
            (3, 1, 8.32),
            (3, 2, 1.71),
            (3, 3, -1.12),
            (4, 4, -1.745),
            (4, 5, 0.43),
            (4, 6, 0.43),
            (5, 3, 0.69),
            (5, 4, 1.71),
            (5, 5, -280.0 * y[7] - 0.43),
            (5, 6, 0.69),
            (5, 7, -280.0 * y[5]),
            (6, 5, 280.0 * y[7]),
            (6, 6, -1.81),
            (6, 7, 280.0 * y[5]),
            (7, 5, -280.0 * y[7]),
            (7, 6, 1.81),
            (7, 7, -280.0 * y[5]),
        ];
        for (r, c, v) in entries {
            j.set(r, c, v);
        }
    }
}

impl TestProblem for Hires {
    const NAME: &'static str = "HIRES";
    const T_END: f64 = 321.8122;
    fn new() -> Self {
        Hires
    }
    fn y0() -> Vec<f64> {
        vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0057]
    }
    fn reference() -> Vec<f64> {
        vec![
            0.7371312573325668e-3,
            0.1442485726316185e-3,
            0.5888729740967575e-4,
            0.1175651343283149e-2,
            0.2386356198831331e-2,
            0.6238968252742796e-2,
            0.2849998395185769e-2,
            0.2850001604814231e-2,
        ]
    }
}
