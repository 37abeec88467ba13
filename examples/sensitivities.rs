//! Forward sensitivities with CVODES through the library (docs/library.md, "Sensitivities to
//! parameters"): y' = k (c·u − y), y(0) = 0, with the parameters p = (k, c) and a forcing u
//! that steps from 1 to 3 at t = 1, where the integration restarts. The exact y and
//! s_j = ∂y/∂p_j are known on each segment; the example exits with status 1 if the solver
//! misses them by more than 1e-6 relative.
//!
//!     cargo run --release --example sensitivities

use std::process::ExitCode;
use stickslip::integrate::{
    JacobianMatrix, OdeSystem, Options, ParametricSystem, SolverError, Task, Tolerance,
};
use stickslip::sundials::{SensitivitySettings, SensitivitySolver};

/// y' = k (c·u − y) with p = (k, c) and the forcing u.
struct Relaxation {
    k: f64,
    c: f64,
    u: f64,
}

impl OdeSystem for Relaxation {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        dydt[0] = self.k * (self.c * self.u - y[0]);
    }
    fn has_jacobian(&self) -> bool {
        true
    }
    fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut JacobianMatrix<'_>) {
        jac.set(0, 0, -self.k);
    }
}

impl ParametricSystem for Relaxation {
    fn n_params(&self) -> usize {
        2
    }
    fn params(&self) -> Vec<f64> {
        vec![self.k, self.c]
    }
    fn set_params(&mut self, p: &[f64]) {
        (self.k, self.c) = (p[0], p[1]);
    }
    fn param_jacobian(&self, _t: f64, y: &[f64], dfdp: &mut JacobianMatrix<'_>) {
        dfdp.set(0, 0, self.c * self.u - y[0]); // ∂f/∂k
        dfdp.set(0, 1, self.k * self.u); // ∂f/∂c
    }
}

/// The exact [y, ∂y/∂k, ∂y/∂c] a time τ after `start` (the same three) under the forcing u.
fn exact(k: f64, c: f64, u: f64, tau: f64, start: [f64; 3]) -> [f64; 3] {
    let (e, level) = ((-k * tau).exp(), c * u);
    let [y1, dk, dc] = start;
    [level + (y1 - level) * e, -tau * (y1 - level) * e + e * dk, u * (1.0 - e) + e * dc]
}

fn main() -> Result<ExitCode, SolverError> {
    let (k, c) = (2.0, 0.5);
    let mut options = Options::new(1.0e-9, Tolerance::Scalar(1.0e-12));
    options.stop_time = Some(1.0); // the step of u: never integrate across it
                                   // BDF, simultaneous corrector, estimated sensitivity tolerances, with error control.
    let settings = SensitivitySettings::default();
    // y0 = 0 depends on neither k nor c: s0 = 0, n = 1 value per parameter.
    let system = Relaxation { k, c, u: 1.0 };
    let mut solver = SensitivitySolver::new(system, &settings, 0.0, &[0.0], &[0.0, 0.0], &options)?;

    let mut worst: f64 = 0.0;
    let mut check = |solver: &SensitivitySolver<Relaxation>, want: [f64; 3]| {
        let got = [solver.state()[0], solver.sensitivity(0)[0], solver.sensitivity(1)[0]];
        for (g, w) in got.iter().zip(&want) {
            worst = worst.max((g - w).abs() / w.abs());
        }
        println!(
            "t = {}: y = {:.9}, ∂y/∂k = {:.9}, ∂y/∂c = {:.9}",
            solver.t(),
            got[0],
            got[1],
            got[2]
        );
    };
    for t in [0.5, 1.0] {
        solver.advance(t, Task::Normal)?;
        check(&solver, exact(k, c, 1.0, t, [0.0; 3]));
    }
    // The step at t = 1: y and s go on from their values; the system gets its new forcing.
    let (y, s) = (solver.state().to_vec(), solver.sensitivities().to_vec());
    solver.reinit_with(1.0, &y, &s, |system| system.u = 3.0)?;
    solver.set_stop_time(2.0)?;
    solver.advance(2.0, Task::Normal)?;
    check(&solver, exact(k, c, 3.0, 1.0, exact(k, c, 1.0, 1.0, [0.0; 3])));

    let stats = solver.sensitivity_stats();
    println!("worst relative error {worst:.1e}; {} sensitivity right-hand sides", stats.rhs_evals);
    if worst > 1.0e-6 {
        eprintln!("the sensitivities miss the exact solution by {worst:e}");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
