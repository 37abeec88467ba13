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
use super::events;
use super::AnalysisError;
use crate::integrate::{Clock, Integrator, SolverError, Time};
use crate::model::drr::{Drr, THETA, U, W};
use crate::model::Variational;
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
/// crossing must follow a downward one (a full turn); otherwise the first upward crossing
/// ends the flow (used to reach the section from an arbitrary start).
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
    // A failure of the integrator: the global time, the state without Φ.
    let with_context = |clock: &Clock, e: SolverError| {
        let mut e = clock.at_global(e);
        e.state.truncate(3);
        e
    };
    let mut d0 = [0.0; 3];
    crate::integrate::OdeSystem::rhs(drr, 0.0, &start, &mut d0);
    let mut prev = Sample { t: 0.0, y: start, d: d0 };
    let mut steps = 0u64;
    // Sub-threshold noise at the start (w = 0 exactly, G ≠ 0 at large γ) must not count as a
    // turn: the return needs a v maximum above the noise floor, then a downward crossing.
    let floor = 1e-9f64.max(1e3 * (limits.w_tolerance.0 + limits.w_tolerance.1));
    let mut down_seen = !on_section;
    let mut peak: Option<(f64, [f64; 3])> = None;
    let mut rebase_pending = false;
    let mut rise_rate: f64 = 0.0;
    let mut ln_v_min = start[W];
    let cut_level = 0.5 * drr.slip_speed_scale().ln();
    let mut fundamental = Matrix3::identity();
    let mut section_jacobian = Matrix2::identity();
    // Cuts made in this return: 0 none, 1 at ½ ln γ up, 2 at ½ ln γ down, 3 at w = 0 down.
    let mut cuts = 0u8;
    loop {
        let step = clock.step().map_err(|e| with_context(&clock, e))?;
        prev.t = step.start;
        steps += 1;
        let y = first3(clock.state());
        let d = first3(&clock.integrator().dense(step.t, 1).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?);
        let next = Sample { t: step.t, y, d };
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
        rise_rate = rise_rate.max(d[W].abs());
        ln_v_min = ln_v_min.min(y[W]);
        let span = (prev.t, next.t);
        if prev.d[W] > 0.0 && next.d[W] <= 0.0 {
            let t = events::refine(clock.integrator(), span, 1, W, 0.0).map_err(|e| with_context(&clock, e))?;
            let yp = first3(&clock.integrator().dense(t, 0).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?);
            if yp[W] > floor && peak.is_none_or(|(_, p)| yp[W] > p[W]) {
                peak = Some((clock.global(t).to_f64(), yp));
                rebase_pending = true;
            }
        }
        if prev.d[W] < 0.0 && next.d[W] >= 0.0 {
            let t = events::refine(clock.integrator(), span, 1, W, 0.0).map_err(|e| with_context(&clock, e))?;
            ln_v_min = ln_v_min.min(clock.integrator().dense(t, 0).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?[W]);
        }
        if peak.is_some() && prev.y[W] >= 0.0 && next.y[W] < 0.0 {
            down_seen = true;
        } else if down_seen && prev.y[W] < 0.0 && next.y[W] >= 0.0 {
            let t = events::refine(clock.integrator(), span, 0, W, 0.0).map_err(|e| with_context(&clock, e))?;
            let z = clock.integrator().dense(t, 0).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?;
            let velocity = first3(&clock.integrator().dense(t, 1).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?);
            let phi = fundamental_of(&z);
            let (t_peak, peak) = peak.unwrap_or((clock.global(t).to_f64(), first3(&z)));
            return Ok(Return {
                start,
                period: clock.global(t).to_f64(),
                end: first3(&z),
                velocity,
                fundamental: phi * fundamental,
                section_jacobian: section_map(&phi, &velocity) * section_jacobian,
                t_peak,
                peak,
                ln_v_min,
                steps,
            });
        }
        let out_of_time = clock.global(next.t).to_f64() > limits.max_time;
        if out_of_time || steps > limits.max_steps {
            let limit = if out_of_time { format!("t = {:e}", limits.max_time) } else { format!("{} steps", limits.max_steps) };
            return Err(AnalysisError::Budget {
                analysis: "the return to the section v = 1",
                t: clock.now().to_f64(),
                state: y.to_vec(),
                message: format!("no return within {limit} (the orbit may have decayed to the fixed point)"),
            });
        }
        // A cut: the first crossing in this step of w = ½ ln γ (either way) or of w = 0
        // downward (the latter only once a v maximum has been seen).
        let crosses = |level: f64, up: bool, down: bool| {
            (up && prev.y[W] < level && next.y[W] >= level) || (down && prev.y[W] >= level && next.y[W] < level)
        };
        // Each cut once per return, in order (a restart on the level must not cut again).
        let hit = if cut_level > 0.0 && cuts == 0 && crosses(cut_level, true, false) {
            Some((cut_level, 1))
        } else if cut_level > 0.0 && cuts == 1 && crosses(cut_level, false, true) {
            Some((cut_level, 2))
        } else if peak.is_some() && cuts < 3 && crosses(0.0, false, true) {
            Some((0.0, 3))
        } else {
            None
        };
        let cut = match hit {
            Some((level, count)) => {
                cuts = count;
                let t = events::refine(clock.integrator(), span, 0, W, level).map_err(|e| with_context(&clock, e))?;
                let z = clock.integrator().dense(t, 0).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?;
                let velocity = first3(&clock.integrator().dense(t, 1).map(<[f64]>::to_vec).map_err(|e| with_context(&clock, e))?);
                let y = first3(&z);
                restart_safe(drr, limits.w_tolerance, &y, velocity[W].abs().max(rise_rate)).then_some((t, z, velocity))
            }
            None => None,
        };
        if let Some((t, z, velocity)) = cut {
            let phi = fundamental_of(&z);
            fundamental = phi * fundamental;
            section_jacobian = section_map(&phi, &velocity) * section_jacobian;
            let y = first3(&z);
            let at = clock.global(t);
            clock.reinit(at, &Variational::<Drr, 3>::initial(&y)).map_err(|e| with_context(&clock, e))?;
            rebase_pending = false;
            prev = Sample { t: 0.0, y, d: velocity };
        } else if rebase_pending && next.y[W] > 0.0 && restart_safe(drr, limits.w_tolerance, &y, rise_rate) {
            rebase_pending = false;
            clock.rebase().map_err(|e| with_context(&clock, e))?;
            prev = Sample { t: 0.0, ..next };
        } else {
            prev = next;
        }
    }
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
