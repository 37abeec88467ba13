//! The crate diffsol: BDF, ESDIRK34 and TR-BDF2 on `OdeBuilder::rhs_implicit` (the
//! right-hand side and the analytic Jacobian–vector product, from which diffsol builds its
//! dense Jacobian) with nalgebra matrices and LU, stepped with `step()` to the end time; the
//! measurement feeds every step and `interpolate()` inside it to the [`Meter`].

use crate::meter::{Measured, Meter};
use crate::{Counts, Run, Setting};
use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason};
use std::cell::Cell;

/// The three methods of the crate.
#[derive(Debug, Clone, Copy)]
pub enum Method {
    /// `problem.bdf()`.
    Bdf,
    /// `problem.esdirk34()`.
    Esdirk34,
    /// `problem.tr_bdf2()`.
    TrBdf2,
}

type Ls = NalgebraLU<f64>;

/// The tuned setting's step floor (diffsol's default `min_timestep` is 1e-13, while the
/// arrest of a slip at γ = 1e8 needs steps of ~1e-17).
pub const TUNED_MIN_TIMESTEP: f64 = 1e-22;
/// The tuned setting's limits on consecutive error-test and Newton failures (defaults 40, 50).
pub const TUNED_MAX_FAILURES: usize = 1000;

/// Steps `solver` (any diffsol method) to `run.t_end`, feeding `meter`; evaluates to the
/// solver's statistics. (A macro: the problem's equation type, built from closures, has no
/// name to write generic bounds on.)
macro_rules! drive {
    ($solver:expr, $run:expr, $meter:expr) => {{
        let mut solver = $solver.map_err(|e| e.to_string())?;
        solver.set_stop_time($run.t_end).map_err(|e| e.to_string())?;
        $meter.step(0.0, $run.y0, |_| Err("no step yet".into()))?;
        loop {
            let reason = solver.step().map_err(|e| e.to_string())?;
            let (t, y) = (solver.state().t, solver.state().y);
            let y = [y[0], y[1], y[2]];
            $meter.step(t, y, |s| {
                let z = solver.interpolate(s).map_err(|e| e.to_string())?;
                Ok([z[0], z[1], z[2]])
            })?;
            if matches!(reason, OdeSolverStopReason::TstopReached) {
                break solver.get_statistics().clone();
            }
        }
    }};
}

/// One run through `cycles` cycles (see [`crate::run_one`]).
pub fn run(method: Method, setting: Setting, run: &Run) -> Result<(Measured, Counts), String> {
    let drr = run.drr;
    let y0 = run.y0;
    let (rhs_calls, jvp_calls) = (Cell::new(0u64), Cell::new(0u64));
    let mut problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .rtol(run.rtol)
        .atol([run.atol; 3])
        .rhs_implicit(
            |x: &[f64], _p: &[f64], _t: f64, y: &mut [f64]| {
                rhs_calls.set(rhs_calls.get() + 1);
                drr.rhs(x, y);
            },
            |x: &[f64], _p: &[f64], _t: f64, v: &[f64], y: &mut [f64]| {
                jvp_calls.set(jvp_calls.get() + 1);
                let j = drr.jacobian(x);
                for i in 0..3 {
                    y[i] = j[i][0] * v[0] + j[i][1] * v[1] + j[i][2] * v[2];
                }
            },
        )
        .init(move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&y0), 3)
        .build()
        .map_err(|e| e.to_string())?;
    if setting == Setting::Tuned {
        let o = &mut problem.ode_options;
        o.min_timestep = TUNED_MIN_TIMESTEP;
        o.max_error_test_failures = TUNED_MAX_FAILURES;
        o.max_nonlinear_solver_failures = TUNED_MAX_FAILURES;
    }
    let mut meter = Meter::new(drr);
    let stats = match method {
        Method::Bdf => drive!(problem.bdf::<Ls>(), run, meter),
        Method::Esdirk34 => drive!(problem.esdirk34::<Ls>(), run, meter),
        Method::TrBdf2 => drive!(problem.tr_bdf2::<Ls>(), run, meter),
    };
    let measured = meter.finish(run.cycles)?;
    let counts = Counts {
        steps: Some(stats.number_of_steps as u64),
        rhs: Some(rhs_calls.get()),
        // diffsol builds its dense Jacobian from n = 3 Jacobian–vector products.
        jac: Some(jvp_calls.get() / 3),
        lu: Some(stats.number_of_linear_solver_setups as u64),
        rejected: Some(
            (stats.number_of_error_test_failures + stats.number_of_nonlinear_solver_fails) as u64,
        ),
    };
    Ok((measured, counts))
}
