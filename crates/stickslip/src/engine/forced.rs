//! The integrator of a periodically loaded scene ([`ForcedDrr`]): the system is not
//! autonomous, so the method is built for a non-autonomous f (Rodas5P takes the analytic
//! ∂f/∂t), its largest step is at most an eighth of the forcing period, and each re-base of
//! the local clock moves the system's [`TimeOrigin`] by the same shift, so that the forcing's
//! phase follows the global time whatever the integrator's local time.

use super::cancel::Cancel;
use crate::analysis::hopf;
use crate::integrate::{Integrator, SolverError, Stats, Step, Task, Tolerance};
use crate::model::{Drr, ForcedDrr, PeriodicLoading, TimeOrigin};
use crate::scene::SolverSpec;

/// A forced integration's pieces ([`integrator`]).
pub(super) struct Forced {
    /// The integrator, whose re-bases move the system's time origin.
    pub integrator: Box<dyn Integrator>,
    /// The forced system (for its right-hand side at the start).
    pub system: ForcedDrr,
    /// The Butcher tables used (ARKStep).
    pub tables: Vec<String>,
}

/// The scene's integrator on `drr` under `loading`, starting at global time 0 with `y0`.
pub(super) fn integrator(
    drr: &Drr,
    loading: PeriodicLoading,
    spec: &SolverSpec,
    y0: &[f64; 3],
    cancel: Option<&Cancel>,
) -> Result<Forced, SolverError> {
    let origin = TimeOrigin::new();
    let system = ForcedDrr::new(*drr, loading, origin.clone());
    // The forcing's period bounds the steps; the linear period too where the law heals (the
    // no-healing law has no fixed point).
    let linear = drr.params().state_law.heals().then(|| super::max_step(&hopf::analyse(drr)));
    let max_step = Some(linear.map_or(loading.period / 8.0, |m| m.min(loading.period / 8.0)));
    let atol = Tolerance::PerComponent(spec.atol.to_vec());
    let (inner, tables) = super::integrator_with_max_step(
        system.clone(),
        drr,
        max_step,
        spec,
        y0,
        atol,
        cancel,
        false,
    )?;
    Ok(Forced { integrator: Box::new(Rebasing { inner, origin }), system, tables })
}

/// An integrator whose re-base also moves the forced system's time origin.
struct Rebasing {
    inner: Box<dyn Integrator>,
    origin: TimeOrigin,
}

impl Integrator for Rebasing {
    fn advance(&mut self, tout: f64, task: Task) -> Result<Step, SolverError> {
        self.inner.advance(tout, task)
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

    /// A restart at local time t0: local times keep their global meaning (the origin stays).
    fn reinit(&mut self, t0: f64, y0: &[f64]) -> Result<(), SolverError> {
        self.inner.reinit(t0, y0)
    }

    fn reinit_with_step(
        &mut self,
        t0: f64,
        y0: &[f64],
        first_step: f64,
    ) -> Result<(), SolverError> {
        self.inner.reinit_with_step(t0, y0, first_step)
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolverError> {
        self.inner.set_stop_time(t_stop)
    }

    fn set_max_step(&mut self, max_step: Option<f64>) -> Result<(), SolverError> {
        self.inner.set_max_step(max_step)
    }

    /// Moves the origin first: a restarting integrator evaluates f at its new local 0 inside
    /// its re-base.
    fn rebase(&mut self, first_step: Option<f64>) -> Result<(), SolverError> {
        self.origin.advance(self.inner.t());
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
