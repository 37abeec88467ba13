//! The Poincaré map of the DRR flow on the section w = ln v = 0 (upward crossings of v = 1),
//! with its linearisation: the state and the fundamental matrix Φ are integrated together
//! ([`Variational`]) from a point of the section to the next upward crossing, where Φ is the
//! monodromy matrix of the orbit through that point when it is periodic.
//!
//! Intermediate sections. Along the slip, dy/dt reaches ~γ (u, θ) and ~γ² (w, in the arrest),
//! and the fundamental matrix at fixed time, Φ = f τᵀ + Ψ (τ: how the start shifts the timing),
//! grows with f: the O(1) part Ψ that survives the slip is lost to cancellation (at γ = 1e8 the
//! trivial multiplier came out as 0.98 with Radau5 and 29 with CVODE at rtol 1e-10). So the
//! return is cut at the crossings of w = ½ ln γ (up and down; ½ ln(1/η) without inertia, where
//! radiation damping caps v near 1/η) and of w = 0 (down): at each cut
//! the segment's Φ is projected onto the section (which removes the timing part) and Φ
//! restarts from I. The Jacobian of the map is the product of the segments' section
//! Jacobians; the fixed-time monodromy is the product of the segments' Φ. A cut happens only
//! where a restart is safe (as for the re-base below).
//!
//! Events are located on the integrator's interpolant, as in the cycle analysis: crossings
//! of w = 0 on the state, the v maximum where dw/dt of the interpolant changes sign. Time
//! is re-based once, after the v maximum at the first step end where the model's dw/dt is
//! resolved (the cycle analysis' criterion), so that the slip arrest runs at local t ~ 1e-8 where
//! its tiny steps are representable (see the cycle analysis). Restarting keeps Φ: it is part of
//! the state.

use super::cycle::restart_safe;
use super::AnalysisError;
use crate::integrate::{Clock, Integrator, SolverError, Time};
use crate::model::drr::{Drr, THETA, U, W};
use crate::model::Variational;
use crate::numerics::events;
use nalgebra::{Matrix2, Matrix3};

/// The flow from one point of the section to its next upward crossing of v = 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Return {
    /// Start (u, w, θ).
    pub start: [f64; 3],
    /// Return time.
    pub period: f64,
    /// The state at the return (u, w = 0, θ).
    pub end: [f64; 3],
    /// dy/dt at the return, from the integrator's interpolant (the model's dw/dt is noise on
    /// the slow manifold at large γ).
    pub velocity: [f64; 3],
    /// ∂end/∂start along the flow (rows: component of the end state, columns: of the start),
    /// at fixed time; the monodromy matrix when the orbit is periodic. The product of the
    /// segments' fundamental matrices (see the module docs).
    pub fundamental: Matrix3<f64>,
    /// The linearised map from the start's section coordinates (u, θ) to the end's: the
    /// product of the segments' section Jacobians.
    pub section_jacobian: Matrix2<f64>,
    /// Time from the start to the v maximum.
    pub t_peak: f64,
    /// State at the v maximum.
    pub peak: [f64; 3],
    /// Minimum of ln v on the way.
    pub ln_v_min: f64,
    /// Integrator steps taken.
    pub steps: u64,
}

/// Limits of one return.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// The integrator's (rtol, atol) on w, to judge where a restart is safe.
    pub w_tolerance: (f64, f64),
    /// Give up after this much time without a return.
    pub max_time: f64,
    /// Give up after this many steps without a return.
    pub max_steps: u64,
}

/// One sample of the integration: local time, state, and the interpolant's derivative.
#[derive(Debug, Clone, Copy)]
struct Sample {
    t: f64,
    y: [f64; 3],
    d: [f64; 3],
}

fn first3(z: &[f64]) -> [f64; 3] {
    [z[0], z[1], z[2]]
}

/// Integrates `integ` (a [`Variational`] DRR integrator, 12 components) from `start` until the
/// next upward crossing of w = 0. With `on_section`, `start` lies on the section and the
/// crossing must follow a v maximum and a fall of ln v below minus the noise floor (a full
/// turn); otherwise the first upward crossing
/// ends the flow (used to reach the section from an arbitrary start).
///
/// Each step: sample its end, record the v extrema, end at the return, check the budget,
/// then cut at an intermediate section, re-base the clock, or go on.
pub fn flow_to_section(
    integ: &mut dyn Integrator,
    drr: &Drr,
    start: [f64; 3],
    on_section: bool,
    limits: &Limits,
) -> Result<Return, AnalysisError> {
    integ.reinit(0.0, &Variational::<Drr, 3>::initial(&start))?;
    // Global time 0 at the start; the clock re-bases when its steps outrun it.
    let mut clock = Clock::new(integ, Time::new(0.0));
    let mut flow = Progress::new(drr, start, on_section, limits);
    loop {
        let step = clock.step().map_err(|e| in_global_time(&clock, e))?;
        flow.prev.t = step.start;
        flow.steps += 1;
        let next = sample_step_end(&mut clock, step.t)?;
        flow.record_extrema(&mut clock, &next)?;
        if let Some(done) = flow.completed(&mut clock, &next)? {
            return Ok(done);
        }
        flow.check_budget(&clock, &next)?;
        flow.cut_or_rebase(&mut clock, drr, next)?;
    }
}

/// What is known of a return so far, between steps.
struct Progress {
    start: [f64; 3],
    limits: Limits,
    /// The last step end (or restart point).
    prev: Sample,
    steps: u64,
    /// ln v above which a v maximum counts as a turn, not as noise at the start.
    floor: f64,
    /// Whether ln v has fallen below −floor after the v maximum (the fall that precedes the
    /// return).
    down_seen: bool,
    /// The highest v maximum so far: (global time, state).
    peak: Option<(f64, [f64; 3])>,
    /// A v maximum has been seen since the last re-base or cut.
    rebase_pending: bool,
    /// The largest |dw/dt| seen, to judge where a restart is safe.
    rise_rate: f64,
    ln_v_min: f64,
    /// The intermediate section w = ½ ln γ (½ ln(1/η) without inertia).
    cut_level: f64,
    /// The product of the finished segments' fundamental matrices.
    fundamental: Matrix3<f64>,
    /// The product of the finished segments' section Jacobians.
    section_jacobian: Matrix2<f64>,
    /// Cuts made in this return: 0 none, 1 at ½ ln γ up, 2 at ½ ln γ down, 3 at w = 0 down.
    cuts: u8,
}

impl Progress {
    fn new(drr: &Drr, start: [f64; 3], on_section: bool, limits: &Limits) -> Self {
        let mut d0 = [0.0; 3];
        crate::integrate::OdeSystem::rhs(drr, 0.0, &start, &mut d0);
        Self {
            start,
            limits: *limits,
            prev: Sample { t: 0.0, y: start, d: d0 },
            steps: 0,
            // Sub-threshold noise at the start (w = 0 exactly, G ≠ 0 at large γ) must not
            // count as a turn: the return needs a v maximum above the noise floor, then a
            // downward crossing.
            floor: 1e-9f64.max(1e3 * (limits.w_tolerance.0 + limits.w_tolerance.1)),
            down_seen: !on_section,
            peak: None,
            rebase_pending: false,
            rise_rate: 0.0,
            ln_v_min: start[W],
            cut_level: 0.5 * drr.slip_speed_scale().ln(),
            fundamental: Matrix3::identity(),
            section_jacobian: Matrix2::identity(),
            cuts: 0,
        }
    }

    /// The rise rate and ln v minimum at the step end; the v maximum (dw/dt of the
    /// interpolant changing sign downward, above the noise floor) and the v minimum inside
    /// the step.
    fn record_extrema(&mut self, clock: &mut Clock, next: &Sample) -> Result<(), SolverError> {
        self.rise_rate = self.rise_rate.max(next.d[W].abs());
        self.ln_v_min = self.ln_v_min.min(next.y[W]);
        let span = (self.prev.t, next.t);
        if self.prev.d[W] > 0.0 && next.d[W] <= 0.0 {
            let t = refine(clock, span, 1, 0.0)?;
            let yp = first3(&dense(clock, t, 0)?);
            if yp[W] > self.floor && self.peak.is_none_or(|(_, p)| yp[W] > p[W]) {
                self.peak = Some((clock.global(t).to_f64(), yp));
                self.rebase_pending = true;
            }
        }
        if self.prev.d[W] < 0.0 && next.d[W] >= 0.0 {
            let t = refine(clock, span, 1, 0.0)?;
            self.ln_v_min = self.ln_v_min.min(dense(clock, t, 0)?[W]);
        }
        Ok(())
    }

    /// Notes the fall of ln v below −floor after a v maximum; at the upward crossing of w = 0
    /// after it, the return. A mere crossing of w = 0 is not enough: where the slip's arrest
    /// crosses v = 1 on the slow manifold (dw/dt ≈ −25 against a model noise of ±70 at
    /// γ = 1e8, ξ = 0.7, ε = 0.72), the integrator's first steps after the cut there wiggled
    /// by ±5e-14 around w = 0 (CVODE), which ended the return 0.97 after its start, and Newton
    /// then converged on the arrest's crossing as the section point (t0 one period, multipliers
    /// 574 … 3e5 in fig1c-extended at 5 of 41 points).
    fn completed(
        &mut self,
        clock: &mut Clock,
        next: &Sample,
    ) -> Result<Option<Return>, SolverError> {
        let prev = &self.prev;
        if !self.down_seen && self.peak.is_some() && next.y[W] < -self.floor {
            self.down_seen = true;
            return Ok(None);
        }
        if !(self.down_seen && prev.y[W] < 0.0 && next.y[W] >= 0.0) {
            return Ok(None);
        }
        let (t, y, velocity, phi) = crossing(clock, (prev.t, next.t), 0.0)?;
        let (t_peak, peak) = self.peak.unwrap_or((clock.global(t).to_f64(), y));
        Ok(Some(Return {
            start: self.start,
            period: clock.global(t).to_f64(),
            end: y,
            velocity,
            fundamental: phi * self.fundamental,
            section_jacobian: section_map(&phi, &velocity) * self.section_jacobian,
            t_peak,
            peak,
            ln_v_min: self.ln_v_min,
            steps: self.steps,
        }))
    }

    /// A [`AnalysisError::Budget`] when the time or step limit is passed without a return.
    fn check_budget(&self, clock: &Clock, next: &Sample) -> Result<(), AnalysisError> {
        let out_of_time = clock.global(next.t).to_f64() > self.limits.max_time;
        if !(out_of_time || self.steps > self.limits.max_steps) {
            return Ok(());
        }
        let limit = if out_of_time {
            format!("t = {:e}", self.limits.max_time)
        } else {
            format!("{} steps", self.limits.max_steps)
        };
        Err(AnalysisError::Budget {
            analysis: "the return to the section v = 1",
            t: clock.now().to_f64(),
            state: next.y.to_vec(),
            message: format!(
                "no return within {limit} (the orbit may have decayed to the fixed point)"
            ),
        })
    }

    /// The intermediate section crossed in this step, if it is the next one due: w = ½ ln γ
    /// (up, then down) and w = 0 downward once a v maximum has been seen, each once per
    /// return and in order (a restart on the level must not cut again). Counts the cut.
    fn due_cut(&mut self, next: &Sample) -> Option<f64> {
        let prev = &self.prev;
        let crosses = |level: f64, up: bool, down: bool| {
            (up && prev.y[W] < level && next.y[W] >= level)
                || (down && prev.y[W] >= level && next.y[W] < level)
        };
        let cut_level = self.cut_level;
        let (level, count) = if cut_level > 0.0 && self.cuts == 0 && crosses(cut_level, true, false)
        {
            (cut_level, 1)
        } else if cut_level > 0.0 && self.cuts == 1 && crosses(cut_level, false, true) {
            (cut_level, 2)
        } else if self.peak.is_some() && self.cuts < 3 && crosses(0.0, false, true) {
            (0.0, 3)
        } else {
            return None;
        };
        self.cuts = count;
        Some(level)
    }

    /// Ends the step: at a due cut where a restart is safe, the segment's Φ goes into the
    /// products and the integration restarts there with Φ = I; after a v maximum, the clock
    /// re-bases at the first safe step end above v = 1; otherwise the step end becomes the
    /// previous sample.
    fn cut_or_rebase(
        &mut self,
        clock: &mut Clock,
        drr: &Drr,
        next: Sample,
    ) -> Result<(), SolverError> {
        if let Some(level) = self.due_cut(&next) {
            let (t, y, velocity, phi) = crossing(clock, (self.prev.t, next.t), level)?;
            if restart_safe(drr, self.limits.w_tolerance, &y, velocity[W].abs().max(self.rise_rate))
            {
                self.fundamental = phi * self.fundamental;
                self.section_jacobian = section_map(&phi, &velocity) * self.section_jacobian;
                let at = clock.global(t);
                clock
                    .reinit(at, &Variational::<Drr, 3>::initial(&y), None)
                    .map_err(|e| in_global_time(clock, e))?;
                self.rebase_pending = false;
                // Back on w = 0 at the arrest's cut: the fall below −floor must be seen anew
                // (the step that crossed may have ended below it already).
                if level == 0.0 {
                    self.down_seen = false;
                }
                self.prev = Sample { t: 0.0, y, d: velocity };
                return Ok(());
            }
        }
        if self.rebase_pending
            && next.y[W] > 0.0
            && restart_safe(drr, self.limits.w_tolerance, &next.y, self.rise_rate)
        {
            self.rebase_pending = false;
            clock.rebase().map_err(|e| in_global_time(clock, e))?;
            self.prev = Sample { t: 0.0, ..next };
        } else {
            self.prev = next;
        }
        Ok(())
    }
}

/// A crossing of a level of w: its local time, the state, the velocity and the segment's
/// fundamental matrix Φ there.
type Crossing = (f64, [f64; 3], [f64; 3], Matrix3<f64>);

/// The crossing of w = `level` inside the step `span` (local times).
fn crossing(clock: &mut Clock, span: (f64, f64), level: f64) -> Result<Crossing, SolverError> {
    let t = refine(clock, span, 0, level)?;
    let z = dense(clock, t, 0)?;
    let velocity = first3(&dense(clock, t, 1)?);
    Ok((t, first3(&z), velocity, fundamental_of(&z)))
}

/// The step end at local time `t`: the state and the interpolant's derivative; an error if
/// the augmented state (Φ included) or the derivative is not finite.
fn sample_step_end(clock: &mut Clock, t: f64) -> Result<Sample, AnalysisError> {
    let y = first3(clock.state());
    let d = first3(&dense(clock, t, 1)?);
    if clock.state().iter().chain(&d).any(|v| !v.is_finite()) {
        return Err(AnalysisError::Failed {
            analysis: "the return to the section v = 1",
            t: clock.now().to_f64(),
            state: y.to_vec(),
            message: format!(
                "{} accepted a step to a non-finite state, Φ or dy/dt (dy/dt = {d:?}); the model or its variational equations have left the range of doubles",
                clock.name()
            ),
        });
    }
    Ok(Sample { t, y, d })
}

/// An integrator failure in global time, with the state without Φ.
fn in_global_time(clock: &Clock, e: SolverError) -> SolverError {
    let mut e = clock.at_global(e);
    e.state.truncate(3);
    e
}

/// The k-th derivative of the interpolant (the augmented state) at local time `t`.
fn dense(clock: &mut Clock, t: f64, k: u32) -> Result<Vec<f64>, SolverError> {
    let z = clock.integrator().dense(t, k).map(<[f64]>::to_vec);
    z.map_err(|e| in_global_time(clock, e))
}

/// Where the k-th derivative of w crosses `level` inside `span` of the last step.
fn refine(clock: &mut Clock, span: (f64, f64), k: u32, level: f64) -> Result<f64, SolverError> {
    let t = events::refine(clock.integrator(), span, k, W, level);
    t.map_err(|e| in_global_time(clock, e))
}

/// Φ from an augmented state of the variational equations.
fn fundamental_of(z: &[f64]) -> Matrix3<f64> {
    let phi = Variational::<Drr, 3>::matrix(z);
    Matrix3::from_fn(|r, c| phi[r][c])
}

/// The linearised map between two sections w = const, in section coordinates (u, θ), from
/// the fixed-time fundamental matrix Φ of the segment and the velocity f at its end:
/// [Φ − f (e_wᵀ Φ)/f_w] restricted to rows and columns u, θ (the crossing time varies with
/// the start; its derivative is the w row of Φ over the crossing speed).
fn section_map(phi: &Matrix3<f64>, f: &[f64; 3]) -> Matrix2<f64> {
    let idx = [U, THETA];
    Matrix2::from_fn(|i, j| phi[(idx[i], idx[j])] - f[idx[i]] * phi[(W, idx[j])] / f[W])
}
