//! The engine's guards around each integrator of a run: the caller's [`Cancel`] flag, checked
//! before each advance, and for the methods whose [`EngineSettings::stop_when_u_freezes`] is
//! set, the stop once their steps no longer move u ([`FrozenU`]).
//!
//! [`EngineSettings::stop_when_u_freezes`]: crate::engine::EngineSettings::stop_when_u_freezes

use super::cancel::Cancel;
use super::imex_stick::FrozenU;
use crate::integrate::{ErrorKind, Integrator, SolverError, Stats, Step, Task};

/// `integrator`, failing every [`Integrator::advance`] once `cancel` is set, and failing with
/// the [`FrozenU`] error once `frozen` counts too many steps that left u unchanged. A cancelled
/// advance is an error of kind [`ErrorKind::Cancelled`] that goes up through the analyses like any
/// integrator failure; the run then reports [`super::RunError::Cancelled`] instead of it.
pub(super) fn guarded<'a>(
    integrator: Box<dyn Integrator + 'a>,
    cancel: Option<&Cancel>,
    frozen: Option<FrozenU>,
) -> Box<dyn Integrator + 'a> {
    if cancel.is_none() && frozen.is_none() {
        return integrator;
    }
    Box::new(Guarded { inner: integrator, cancel: cancel.cloned(), frozen })
}

/// An integrator with the engine's guards (see [`guarded`]).
struct Guarded<'a> {
    inner: Box<dyn Integrator + 'a>,
    cancel: Option<Cancel>,
    frozen: Option<FrozenU>,
}

impl Integrator for Guarded<'_> {
    fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
        if self.cancel.as_ref().is_some_and(Cancel::is_cancelled) {
            return Err(SolverError {
                solver: self.inner.name(),
                kind: ErrorKind::Cancelled,
                t: self.inner.t(),
                state: self.inner.state().to_vec(),
                flag: 0,
                message: String::new(),
            });
        }
        let step = self.inner.advance(tout, task)?;
        if let Some(frozen) = &mut self.frozen {
            frozen.count(self.inner.as_ref())?;
        }
        Ok(step)
    }

    fn state(&self) -> &[f64] {
        self.inner.state()
    }

    fn t(&self) -> f64 {
        self.inner.t()
    }

    fn dense(&mut self, t: f64, k: u32) -> Result<&[f64], SolverError> {
        self.inner.dense(t, k)
    }

    fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        if let Some(frozen) = &mut self.frozen {
            frozen.reset();
        }
        self.inner.reinit(t0, y0)
    }

    fn reinit_with_step(
        &mut self,
        t0: f64,
        y0: &[f64],
        first_step: f64,
    ) -> Result<(), SolverError> {
        if let Some(frozen) = &mut self.frozen {
            frozen.reset();
        }
        self.inner.reinit_with_step(t0, y0, first_step)
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
        self.inner.set_stop_time(t_stop)
    }

    fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
        self.inner.set_max_step(max_step)
    }

    fn rebase(&mut self, first_step: Option<f64>) -> Result<(), SolverError> {
        self.inner.rebase(first_step)
    }

    fn rebase_restarts(&self) -> bool {
        self.inner.rebase_restarts()
    }

    fn stats(&self) -> Stats {
        self.inner.stats()
    }

    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn max_dense_order(&self) -> u32 {
        self.inner.max_dense_order()
    }

    fn warnings(&self) -> &[String] {
        self.inner.warnings()
    }
}
