//! The measurement every method goes through, ours and the peers alike: start on the settled
//! limit cycle of (γ, ξ = 0.8, ε = 1) a little before an upward crossing of v = 1, integrate
//! through K cycles, and report the mean period, t0 (upward crossing to the v maximum) and
//! ln v_max of those K cycles, the work counters, and the wall time per cycle.
//!
//! Our side goes through the library exactly as the engine does: [`engine::integrator`] on
//! the scene's solver settings, then [`cycle::analyse`] with its default settings except that
//! the convergence rule is made unsatisfiable (`settle` = 1000) and the run stops after
//! `max_cycles` = K closed cycles (status "not converged", every cycle listed).

use std::time::{Duration, Instant};
use stickslip::analysis::{cycle, hopf};
use stickslip::engine;
use stickslip::integrate::{OdeSystem, Stats};
use stickslip::model::drr::{DrrParams, W};
use stickslip::model::{Drr, Friction};
use stickslip::scene::{Method, SolverSpec};

/// ξ of the benchmark problem.
pub const XI: f64 = 0.8;
/// ε of the benchmark problem.
pub const EPSILON: f64 = 1.0;
/// Cycles per measured run.
pub const CYCLES: usize = 3;
/// The start lies this fraction of a period before the first upward crossing of v = 1.
pub const LEAD: f64 = 0.02;
/// Peers integrate to t_end = (LEAD + CYCLES + TAIL)·P: TAIL covers the last crossing.
pub const TAIL: f64 = 0.01;

/// The model at γ.
pub fn drr(gamma: f64) -> Drr {
    Drr::new(DrrParams::new(gamma, XI, EPSILON, Friction::Log))
}

/// Absolute tolerance of every grid cell: rtol·1e-2 on each of (u, ln v, θ) (the scene
/// default).
pub fn atol(rtol: f64) -> f64 {
    rtol * 1e-2
}

/// What one run of a method measured: the means over its K cycles.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Measured {
    /// Mean period of the K cycles.
    pub period: f64,
    /// Mean time from the upward crossing of v = 1 to the v maximum.
    pub t0: f64,
    /// Mean ln v_max.
    pub ln_v_max: f64,
}

/// Work counters of one run (what the method reports; absent ones are None).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Counts {
    /// Accepted steps.
    pub steps: Option<u64>,
    /// Right-hand-side evaluations (the method's own; finite-difference Jacobians apart).
    pub rhs: Option<u64>,
    /// Jacobian evaluations.
    pub jac: Option<u64>,
    /// LU factorisations (linear-solver setups).
    pub lu: Option<u64>,
    /// Rejected steps (error test and convergence failures).
    pub rejected: Option<u64>,
}

impl Counts {
    /// The counters of our library's [`Stats`].
    pub fn from_stats(s: &Stats) -> Self {
        Self {
            steps: Some(s.steps),
            rhs: Some(s.rhs_evals + s.rhs_evals_explicit + s.rhs_evals_jacobian),
            jac: Some(s.jac_evals),
            lu: Some(s.lin_setups),
            rejected: Some(s.step_attempts.saturating_sub(s.steps)),
        }
    }
}

/// The settled start of the benchmark at one γ.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Start {
    /// (u, w = ln v, θ) on the settled cycle, LEAD·P before an upward crossing of v = 1.
    pub y0: [f64; 3],
    /// The period of the settling run (to size the peers' time span).
    pub period: f64,
}

impl Start {
    /// The end of the peers' time span: (LEAD + CYCLES + TAIL)·P.
    pub fn t_end(&self) -> f64 {
        (LEAD + CYCLES as f64 + TAIL) * self.period
    }
}

/// Settles on the limit cycle at γ: radau5 at rtol 1e-12 from v = 0.5 on the slow manifold,
/// to the engine's convergence rule, keeping the last cycle's steps; the start is the step
/// end of that cycle closest below (1 − LEAD)·P.
pub fn settle(gamma: f64) -> Result<Start, String> {
    let drr = drr(gamma);
    let theta = 0.0;
    let w = 0.5f64.ln();
    let y0 = [drr.manifold_u(w, theta), w, theta];
    let spec = spec(Method::Radau5, 1e-12);
    let (mut integ, _) = engine::integrator(drr, &spec, &y0).map_err(|e| e.to_string())?;
    let settings = cycle::CycleSettings {
        trajectory_cycles: 1,
        ..cycle::CycleSettings::defaults(1e-12, atol(1e-12))
    };
    let stable = hopf::analyse(&drr).max_real_part < 0.0;
    let report =
        cycle::analyse(integ.as_mut(), &drr, &settings, stable).map_err(|e| e.to_string())?;
    let values = report.values.ok_or_else(|| {
        format!("γ = {gamma:e}: the settling run did not converge ({:?})", report.status)
    })?;
    let tr = report.trajectory.last().ok_or("no trajectory kept")?;
    let target = (1.0 - LEAD) * values.main.period;
    let i = tr.t.iter().rposition(|&t| t <= target).ok_or("empty trajectory")?;
    let y0 = [tr.u[i], tr.v[i].ln(), tr.theta[i]];
    // Exactly LEAD·P before the crossing is not needed; a stick-phase point (v < 1) is.
    if y0[W] >= 0.0 {
        return Err(format!("γ = {gamma:e}: the start {y0:?} is not in the stick phase"));
    }
    Ok(Start { y0, period: values.main.period })
}

/// The scene solver settings of one grid cell.
pub fn spec(method: Method, rtol: f64) -> SolverSpec {
    SolverSpec { method, rtol, atol: [atol(rtol); 3], table: None, explicit_table: None }
}

/// One run of one of our methods from `start` through CYCLES cycles: the means, the
/// counters, and the time of the whole run (integrator creation included).
pub fn run_ours(
    method: Method,
    gamma: f64,
    rtol: f64,
    start: &Start,
) -> Result<(Measured, Counts, Duration), String> {
    let drr = drr(gamma);
    let stable = hopf::analyse(&drr).max_real_part < 0.0;
    let settings = cycle::CycleSettings {
        settle: 1000,
        max_cycles: CYCLES,
        ..cycle::CycleSettings::defaults(rtol, atol(rtol))
    };
    let spec = spec(method, rtol);
    let clock = Instant::now();
    let (mut integ, _) = engine::integrator(drr, &spec, &start.y0).map_err(|e| e.to_string())?;
    let report =
        cycle::analyse(integ.as_mut(), &drr, &settings, stable).map_err(|e| e.to_string())?;
    let stats = integ.stats();
    let elapsed = clock.elapsed();
    let cycles = &report.last_cycles;
    if cycles.len() != CYCLES {
        return Err(format!(
            "{} cycles closed ({:?}), {CYCLES} expected",
            cycles.len(),
            report.status
        ));
    }
    let mean =
        |f: fn(&cycle::CycleValues) -> f64| cycles.iter().map(f).sum::<f64>() / CYCLES as f64;
    let measured = Measured {
        period: mean(|c| c.main.period),
        t0: mean(|c| c.main.t0),
        ln_v_max: mean(|c| c.main.ln_v_max),
    };
    if ![measured.period, measured.t0, measured.ln_v_max].iter().all(|v| v.is_finite()) {
        return Err(format!("non-finite cycle values {measured:?}"));
    }
    Ok((measured, Counts::from_stats(&stats), elapsed))
}

/// dw/dt of the model at y (used by the tests of the peers' event code).
#[allow(dead_code)]
pub fn dw_dt(drr: &Drr, y: &[f64; 3]) -> f64 {
    let mut d = [0.0; 3];
    drr.rhs(0.0, y, &mut d);
    d[W]
}
