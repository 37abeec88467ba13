//! The crate differential-equations: `ImplicitRungeKutta::radau5()` and
//! `BackwardDifferentiationFormula::adaptive()` on the ODE trait with the analytic Jacobian,
//! through `IVP::ode(..).method(..).solout(..).solve()`; the measurement is a custom `Solout`
//! that feeds every accepted step and the step's interpolant to the [`Meter`].

use crate::meter::{Measured, Meter};
use crate::model::Drr;
use crate::{Counts, Run, Setting};
use differential_equations::interpolate::Interpolation;
use differential_equations::prelude::*;
use differential_equations::solout::Solout;

struct System(Drr);

impl ODE<f64, [f64; 3]> for System {
    fn diff(&self, _t: f64, y: &[f64; 3], dydt: &mut [f64; 3]) {
        self.0.rhs(y, dydt);
    }

    fn jacobian(&self, _t: f64, y: &[f64; 3], j: &mut Matrix<f64>) {
        let a = self.0.jacobian(y);
        for (i, row) in a.iter().enumerate() {
            for (k, v) in row.iter().enumerate() {
                j[(i, k)] = *v;
            }
        }
    }
}

/// Feeds the meter; stops the solve at the first measurement error.
struct Probe<'m> {
    meter: &'m mut Meter,
    error: &'m mut Option<String>,
}

impl Solout<f64, [f64; 3]> for Probe<'_> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        _t_prev: f64,
        y_curr: &[f64; 3],
        _y_prev: &[f64; 3],
        interpolator: &mut I,
        _solution: &mut Solution<f64, [f64; 3]>,
    ) -> ControlFlag<f64, [f64; 3]>
    where
        I: Interpolation<f64, [f64; 3]> + ?Sized,
    {
        let dense =
            |s: f64| interpolator.interpolate(s).map_err(|e| format!("interpolation: {e:?}"));
        match self.meter.step(t_curr, *y_curr, dense) {
            Ok(()) => ControlFlag::Continue,
            Err(e) => {
                *self.error = Some(e);
                ControlFlag::Terminate
            }
        }
    }
}

/// The two methods of the crate.
#[derive(Debug, Clone, Copy)]
pub enum Method {
    /// `ImplicitRungeKutta::radau5()`.
    Radau5,
    /// `BackwardDifferentiationFormula::adaptive()`.
    Bdf,
}

/// One run through `cycles` cycles (see [`crate::run_one`]).
pub fn run(method: Method, setting: Setting, run: &Run) -> Result<(Measured, Counts), String> {
    let system = System(run.drr);
    let mut meter = Meter::new(run.drr);
    let mut error = None;
    let probe = Probe { meter: &mut meter, error: &mut error };
    let problem = IVP::ode(&system, 0.0, run.t_end, run.y0);
    let atol = [run.atol; 3];
    let solution = match (method, setting) {
        (Method::Radau5, Setting::Default) => problem
            .method(ImplicitRungeKutta::radau5().rtol(run.rtol).atol(atol))
            .solout(probe)
            .solve(),
        (Method::Radau5, Setting::Tuned) => problem
            .method(
                ImplicitRungeKutta::radau5().rtol(run.rtol).atol(atol).max_steps(TUNED_MAX_STEPS),
            )
            .solout(probe)
            .solve(),
        (Method::Bdf, Setting::Default) => problem
            .method(BackwardDifferentiationFormula::adaptive().rtol(run.rtol).atol(atol))
            .solout(probe)
            .solve(),
        (Method::Bdf, Setting::Tuned) => problem
            .method(
                BackwardDifferentiationFormula::adaptive()
                    .rtol(run.rtol)
                    .atol(atol)
                    .max_steps(TUNED_MAX_STEPS),
            )
            .solout(probe)
            .solve(),
    }
    .map_err(|e| format!("{e:?}"))?;
    if let Some(e) = error {
        return Err(e);
    }
    if !matches!(solution.status, Status::Complete) {
        return Err(format!("solver status {:?}", solution.status));
    }
    let measured = meter.finish(run.cycles)?;
    let counts = Counts {
        steps: Some(solution.steps.accepted as u64),
        rhs: Some(solution.evals.function as u64),
        jac: Some(solution.evals.jacobian as u64),
        // The crate's BDF does not count its factorisations.
        lu: matches!(method, Method::Radau5).then_some(solution.evals.decompositions as u64),
        rejected: Some(solution.steps.rejected as u64),
    };
    Ok((measured, counts))
}

/// The tuned setting: a step budget for the whole span instead of the default (radau5:
/// 100 000, BDF: 10 000).
pub const TUNED_MAX_STEPS: usize = 100_000_000;
