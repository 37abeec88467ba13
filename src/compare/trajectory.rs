//! A user's trajectory against the reference, cycle by cycle.
//!
//! The reference is Radau5 at rtol = min(1e-12, tolerance/100) driven by [`Clock`] (re-based
//! before its steps outrun the local clock, global time kept exactly), started from the
//! user's first sample with the scene's parameters. Rodas5P at a 10 times tighter rtol is run
//! too: the largest difference between the two at the user's sample times is the reference's
//! stated accuracy (an estimate of its error; independent method, more accurate run). Where
//! it is not below tolerance/10, no verdict is given.
//!
//! Events (upward crossings of v = 1, the v maximum, the half-maximum crossings) are located
//! the same way on the user's samples and on the reference evaluated at the same times, so the
//! interpolation between samples is common to both. Per cycle the period, t0, slip
//! half-width and ln v_max are compared; then the state along each cycle in phase: the user's
//! sample at time τ after its cycle's own crossing against the reference at τ after the
//! reference's crossing of the same cycle.

use super::input::Trajectory;
use crate::engine;
use crate::integrate::{Clock, SolverError, Time};
use crate::model::Drr;
use crate::scene::{Method, Scene, SolverSpec};
use serde::Serialize;

/// Largest |Δ ln v| between the two samples around an event (a crossing of v = 1 or of the
/// half maximum) for the event to be located by interpolation.
pub const MAX_EVENT_JUMP: f64 = 0.5;
/// Largest drop of ln v from the sampled maximum to its neighbours for the parabola through
/// the three to locate the v maximum.
pub const MAX_PEAK_DROP: f64 = 0.1;

/// Agreement or not within the tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every deviation is within the tolerance.
    Agrees,
    /// Some deviation exceeds the tolerance (or the cycle counts differ).
    Disagrees,
}

/// Events of one complete cycle, located on samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CycleEvents {
    /// Time of the upward crossing of v = 1 that starts the cycle.
    pub start: f64,
    /// Time to the next upward crossing.
    pub period: f64,
    /// From the crossing to the v maximum.
    pub t0: f64,
    /// Full width of v at half its maximum (null if v stays above half the maximum).
    pub slip_half_width: Option<f64>,
    /// ln v_max.
    pub ln_v_max: f64,
}

/// One quantity of one cycle, the user's against the reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantityDeviation {
    /// "period", "t0", "slip_half_width" or "ln_v_max".
    pub quantity: String,
    /// Cycle number (1 = the first complete cycle).
    pub cycle: usize,
    /// The user's value.
    pub user: f64,
    /// The reference's value.
    pub reference: f64,
    /// Relative difference for durations, absolute for ln v_max.
    pub deviation: f64,
}

/// The worst deviation of the state along the cycles (compared in phase).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateDeviation {
    /// "u", "ln_v" or "theta".
    pub quantity: String,
    /// The user's sample time.
    pub t: f64,
    /// Where the sample is in the file.
    pub at: String,
    /// Cycle number (0: before the first crossing, compared at equal times).
    pub cycle: usize,
    /// Time since the cycle's own upward crossing of v = 1.
    pub phase: f64,
    /// The user's value.
    pub user: f64,
    /// The reference's value at the same phase.
    pub reference: f64,
    /// |Δu|/max(|u|, 1), |Δ ln v| or |Δθ|/max(|θ|, 1).
    pub deviation: f64,
}

/// The reference integration and its own accuracy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceInfo {
    /// Method, tolerances and time bookkeeping, in words.
    pub method: String,
    /// Its relative tolerance.
    pub rtol: f64,
    /// Largest difference (same measure as the state deviations) between the reference and
    /// Rodas5P at a 10 times tighter rtol, at the user's sample times: an estimate of the
    /// reference's own error.
    pub accuracy: f64,
    /// Re-bases of its clock.
    pub rebases: u64,
}

/// A user's trajectory against the reference (the `--json` object; docs/compare.md).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryComparison {
    /// "agrees" or "disagrees".
    pub verdict: Verdict,
    /// Tolerance: relative for durations, u and θ (u, θ against max(|value|, 1)); absolute for
    /// ln v.
    pub tolerance: f64,
    /// Samples compared.
    pub samples: usize,
    /// Complete cycles in the user's trajectory and in the reference over the same span.
    pub cycles: [usize; 2],
    /// The reference and its accuracy.
    pub reference: ReferenceInfo,
    /// Largest relative period deviation over the cycles (null without a complete cycle).
    pub period_error: Option<QuantityDeviation>,
    /// Per quantity, the worst cycle.
    pub worst_per_quantity: Vec<QuantityDeviation>,
    /// Every cycle's quantities.
    pub per_cycle: Vec<QuantityDeviation>,
    /// The worst state deviation along the cycles, in phase.
    pub worst_state: Option<StateDeviation>,
    /// Largest state deviation per quantity (u, ln_v, theta), in phase.
    pub max_state_deviation: StateMaxima,
    /// Why the verdict is "disagrees", in words (empty when it agrees).
    pub reasons: Vec<String>,
}

/// Largest state deviation per component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StateMaxima {
    /// |Δu|/max(|u|, 1).
    pub u: f64,
    /// |Δ ln v|.
    pub ln_v: f64,
    /// |Δθ|/max(|θ|, 1).
    pub theta: f64,
}

/// Deviations of (u, w, θ) in the measure of [`StateDeviation::deviation`].
fn state_deviation(user: &[f64; 3], reference: &[f64; 3]) -> [f64; 3] {
    [
        (user[0] - reference[0]).abs() / reference[0].abs().max(1.0),
        (user[1] - reference[1]).abs(),
        (user[2] - reference[2]).abs() / reference[2].abs().max(1.0),
    ]
}

/// The state (u, w = ln v, θ) at `times` (any order, all ≥ `start`), integrated by
/// `method` through a [`Clock`] from (start, y0). Returns the states and the re-bases made.
pub fn reference_states(
    drr: Drr,
    method: Method,
    rtol: f64,
    start: f64,
    y0: [f64; 3],
    times: &[f64],
) -> Result<(Vec<[f64; 3]>, u64), SolverError> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let spec = SolverSpec { method, rtol, atol: [rtol; 3], table: None, explicit_table: None };
    let (mut integ, _) = engine::integrator(drr, &spec, &y0)?;
    let mut clock = Clock::new(integ.as_mut(), Time::new(start));
    let mut out = vec![y0; times.len()];
    let mut next = order.iter().take_while(|&&i| times[i] <= start).count();
    while next < order.len() {
        let step = clock.step().map_err(|e| clock.at_global(e))?;
        let epoch = clock.global(0.0);
        while next < order.len() {
            let local = Time::new(times[order[next]]).since(epoch);
            if local > step.t {
                break;
            }
            let y = match clock.integrator().dense(local.max(step.start), 0) {
                Ok(y) => [y[0], y[1], y[2]],
                Err(e) => return Err(clock.at_global(e)),
            };
            out[order[next]] = y;
            next += 1;
        }
    }
    Ok((out, clock.rebases()))
}

/// The Radau5 step ends (global time, (u, w, θ)) from (start, y0) to past `end`, through a
/// [`Clock`].
fn reference_steps(
    drr: Drr,
    rtol: f64,
    start: f64,
    y0: [f64; 3],
    end: f64,
) -> Result<(Vec<f64>, Vec<[f64; 3]>), SolverError> {
    let spec = SolverSpec {
        method: Method::Radau5,
        rtol,
        atol: [rtol; 3],
        table: None,
        explicit_table: None,
    };
    let (mut integ, _) = engine::integrator(drr, &spec, &y0)?;
    let mut clock = Clock::new(integ.as_mut(), Time::new(start));
    let (mut times, mut states) = (vec![start], vec![y0]);
    while clock.now().to_f64() < end {
        clock.step().map_err(|e| clock.at_global(e))?;
        let y = clock.state();
        times.push(clock.now().to_f64());
        states.push([y[0], y[1], y[2]]);
    }
    Ok((times, states))
}

/// Linear interpolation of the time where w crosses `level` between samples i and i + 1;
/// an error if the samples are too far apart in w to locate it.
fn crossing(
    t: &[f64],
    w: &[f64],
    i: usize,
    level: f64,
    event: &'static str,
    origin: &[String],
) -> Result<f64, SamplingError> {
    if (w[i + 1] - w[i]).abs() > MAX_EVENT_JUMP {
        return Err(SamplingError::Event {
            from: origin[i].clone(),
            to: origin[i + 1].clone(),
            ln_v: [w[i], w[i + 1]],
            event,
        });
    }
    Ok(t[i] + (level - w[i]) / (w[i + 1] - w[i]) * (t[i + 1] - t[i]))
}

/// The complete cycles of a sampled trajectory (t, w = ln v). `origin` names the samples for
/// messages.
pub fn cycle_events(
    t: &[f64],
    w: &[f64],
    origin: &[String],
) -> Result<Vec<CycleEvents>, SamplingError> {
    let ups: Vec<usize> = (0..t.len() - 1).filter(|&i| w[i] < 0.0 && w[i + 1] >= 0.0).collect();
    let times = ups
        .iter()
        .map(|&i| crossing(t, w, i, 0.0, "upward crossing of v = 1", origin))
        .collect::<Result<Vec<_>, _>>()?;
    let mut cycles = Vec::new();
    for k in 0..ups.len().saturating_sub(1) {
        let (a, b) = (ups[k] + 1, ups[k + 1]);
        let j = (a..=b).max_by(|&x, &y| w[x].total_cmp(&w[y])).expect("a non-empty range");
        if j == 0
            || j + 1 >= t.len()
            || w[j] - w[j - 1] > MAX_PEAK_DROP
            || w[j] - w[j + 1] > MAX_PEAK_DROP
        {
            return Err(SamplingError::Peak { at: origin[j].clone(), cycle: k + 1, ln_v: w[j] });
        }
        // The parabola through the three samples around the maximum.
        let (t1, t2, t3, w1, w2, w3) = (t[j - 1], t[j], t[j + 1], w[j - 1], w[j], w[j + 1]);
        let d1 = (w2 - w1) / (t2 - t1);
        let d2 = (w3 - w2) / (t3 - t2);
        let c = (d2 - d1) / (t3 - t1);
        let (t_peak, w_max) = if c < 0.0 {
            let tp = 0.5 * (t1 + t2) - d1 / (2.0 * c);
            (tp, w1 + (tp - t1) * (d1 + c * (tp - t2)))
        } else {
            (t2, w2)
        };
        let level = w_max - std::f64::consts::LN_2;
        let rise = (a.saturating_sub(1)..j).rev().find(|&i| w[i] < level);
        let fall = (j..b).find(|&i| w[i + 1] < level);
        let slip_half_width = match (rise, fall) {
            (Some(r), Some(f)) => Some(
                crossing(t, w, f, level, "half maximum", origin)?
                    - crossing(t, w, r, level, "half maximum", origin)?,
            ),
            _ => None,
        };
        cycles.push(CycleEvents {
            start: times[k],
            period: times[k + 1] - times[k],
            t0: t_peak - times[k],
            slip_half_width,
            ln_v_max: w_max,
        });
    }
    Ok(cycles)
}

/// Why the events of a sampled trajectory cannot be located: the samples around one are too
/// far apart; the message names the samples and the spacing needed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SamplingError {
    /// ln v jumps too far across a crossing.
    #[error(
        "{from}–{to}: ln v jumps from {:.3} to {:.3} across the {event}; sampled too coarsely to locate it \
         (|Δ ln v| ≤ {max} is needed between the samples around each event)",
        ln_v[0],
        ln_v[1],
        max = MAX_EVENT_JUMP
    )]
    Event {
        /// The sample before the event.
        from: String,
        /// The sample after it.
        to: String,
        /// ln v at the two samples.
        ln_v: [f64; 2],
        /// The event: "upward crossing of v = 1" or "half maximum".
        event: &'static str,
    },
    /// The samples either side of a cycle's v maximum are too far below it.
    #[error(
        "{at}: the v maximum of cycle {cycle} (ln v = {ln_v:.3}) is sampled too coarsely to locate it \
         (ln v must be within {max} of the maximum at the samples either side)",
        max = MAX_PEAK_DROP
    )]
    Peak {
        /// The sample at the maximum.
        at: String,
        /// The cycle (1-based).
        cycle: usize,
        /// ln v there.
        ln_v: f64,
    },
}

/// Why a comparison cannot be made: bad input (exit 2) or a failed reference (exit 1).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompareError {
    /// The user's data cannot be compared (sampled too coarsely); the message says why.
    #[error("{0}")]
    Input(SamplingError),
    /// The reference's events cannot be located even on its own steps.
    #[error("the reference could not be resolved: {0}")]
    UnresolvedReference(SamplingError),
    /// The reference integration failed.
    #[error("reference run failed: {0}")]
    Reference(SolverError),
    /// The reference's own accuracy (against Rodas5P at rtol/10) is not below tolerance/10.
    #[error("the reference's own accuracy {accuracy:.1e} is not below tolerance/10 = {:.1e}, so no verdict; use a larger --tolerance", tolerance / 10.0)]
    InaccurateReference {
        /// Its accuracy.
        accuracy: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
}

impl From<SolverError> for CompareError {
    fn from(e: SolverError) -> Self {
        Self::Reference(e)
    }
}

/// Compares a user's trajectory with the reference of `scene`'s model, cycle by cycle (see
/// the module docs). Fails with [`CompareError::Reference`] also when the reference's own
/// accuracy is not below tolerance/10 (its verdict would not mean anything).
pub fn against_trajectory(
    scene: &Scene,
    user: &Trajectory,
    tolerance: f64,
) -> Result<TrajectoryComparison, CompareError> {
    let drr = Drr::new(scene.params);
    let rtol = (tolerance / 100.0).min(1e-12);
    let start = user.t[0];
    let y0 = [user.y[0][0], user.y[0][1].ln(), user.y[0][2]];
    let uw: Vec<[f64; 3]> = user.y.iter().map(|y| [y[0], y[1].ln(), y[2]]).collect();
    let (reference, rebases) = reference_states(drr, Method::Radau5, rtol, start, y0, &user.t)?;
    let (check, _) = reference_states(drr, Method::Rodas5p, rtol / 10.0, start, y0, &user.t)?;
    let accuracy =
        reference.iter().zip(&check).flat_map(|(a, b)| state_deviation(a, b)).fold(0.0, f64::max);
    let reference_info = ReferenceInfo {
        method: format!("radau5 through the re-basing clock, rtol {rtol:e}, atol {rtol:e}, from the first sample; accuracy: its largest difference from rodas5p at rtol {:e}", rtol / 10.0),
        rtol,
        accuracy,
        rebases,
    };
    if accuracy > tolerance / 10.0 {
        return Err(CompareError::InaccurateReference { accuracy, tolerance });
    }
    let w_user: Vec<f64> = uw.iter().map(|y| y[1]).collect();
    let w_ref: Vec<f64> = reference.iter().map(|y| y[1]).collect();
    let user_cycles = cycle_events(&user.t, &w_user, &user.origin).map_err(CompareError::Input)?;
    // The reference's events on the user's sample times (interpolation common to both); where
    // the reference is too far off the user's to be resolved at those times (e.g. out of
    // phase), on its own Radau5 steps.
    let ref_cycles = match cycle_events(&user.t, &w_ref, &user.origin) {
        Ok(c) => c,
        Err(_) => {
            let (fine, states) =
                reference_steps(drr, rtol, start, y0, *user.t.last().expect("two samples"))?;
            let w: Vec<f64> = states.iter().map(|y| y[1]).collect();
            let origin: Vec<String> =
                fine.iter().map(|t| format!("reference at t = {t}")).collect();
            cycle_events(&fine, &w, &origin).map_err(CompareError::UnresolvedReference)?
        }
    };
    let mut reasons = Vec::new();
    if user_cycles.len() != ref_cycles.len() {
        reasons.push(format!(
            "{} complete cycles against the reference's {} over the same span",
            user_cycles.len(),
            ref_cycles.len()
        ));
    }
    let mut per_cycle = Vec::new();
    for (k, (u, r)) in user_cycles.iter().zip(&ref_cycles).enumerate() {
        let mut push = |name: &str, user: f64, reference: f64, relative: bool| {
            let scale = if relative { reference.abs() } else { 1.0 };
            per_cycle.push(QuantityDeviation {
                quantity: name.into(),
                cycle: k + 1,
                user,
                reference,
                deviation: (user - reference).abs() / scale,
            });
        };
        push("period", u.period, r.period, true);
        push("t0", u.t0, r.t0, true);
        if let (Some(a), Some(b)) = (u.slip_half_width, r.slip_half_width) {
            push("slip_half_width", a, b, true);
        }
        push("ln_v_max", u.ln_v_max, r.ln_v_max, false);
    }
    let worst = |name: &str| {
        per_cycle
            .iter()
            .filter(|q| q.quantity == name)
            .max_by(|a, b| a.deviation.total_cmp(&b.deviation))
            .cloned()
    };
    let worst_per_quantity: Vec<QuantityDeviation> =
        ["period", "t0", "slip_half_width", "ln_v_max"].iter().filter_map(|n| worst(n)).collect();
    for q in worst_per_quantity.iter().filter(|q| q.deviation > tolerance) {
        reasons.push(format!(
            "{} differs by {:.2e} in cycle {} (yours {}, reference {})",
            if q.quantity == "period" { "period error: the period" } else { q.quantity.as_str() },
            q.deviation,
            q.cycle,
            q.user,
            q.reference
        ));
    }
    // The state in phase: the reference at the same time since its own crossing of the cycle.
    let mut cycle_of = vec![0usize; user.t.len()];
    let mut phase: Vec<f64> = user.t.iter().map(|t| t - start).collect();
    let mut targets = user.t.clone();
    for (i, &t) in user.t.iter().enumerate() {
        if let Some(k) = user_cycles.iter().rposition(|c| c.start <= t) {
            // Samples past the last complete cycle's end belong to the cycle after it.
            let k = if t >= user_cycles[k].start + user_cycles[k].period { k + 1 } else { k };
            let (user_start, ref_start) = if k < user_cycles.len() {
                (user_cycles[k].start, ref_cycles.get(k).map(|c| c.start))
            } else {
                let (u, r) = (user_cycles[k - 1], ref_cycles.get(k - 1));
                (u.start + u.period, r.map(|r| r.start + r.period))
            };
            if let Some(ref_start) = ref_start {
                cycle_of[i] = k + 1;
                phase[i] = t - user_start;
                targets[i] = ref_start + phase[i];
            }
        }
    }
    let (in_phase, _) = reference_states(drr, Method::Radau5, rtol, start, y0, &targets)?;
    let mut maxima = [0.0f64; 3];
    let mut worst_state: Option<StateDeviation> = None;
    let names = ["u", "ln_v", "theta"];
    for i in 0..user.t.len() {
        let d = state_deviation(&uw[i], &in_phase[i]);
        for k in 0..3 {
            maxima[k] = maxima[k].max(d[k]);
            if worst_state.as_ref().is_none_or(|w| d[k] > w.deviation) {
                worst_state = Some(StateDeviation {
                    quantity: names[k].into(),
                    t: user.t[i],
                    at: user.origin[i].clone(),
                    cycle: cycle_of[i],
                    phase: phase[i],
                    user: uw[i][k],
                    reference: in_phase[i][k],
                    deviation: d[k],
                });
            }
        }
    }
    if let Some(w) = worst_state.as_ref().filter(|w| w.deviation > tolerance) {
        reasons.push(format!(
            "state along the cycle: {} = {} against the reference's {} ({:.2e}) at t = {} ({}, cycle {}, {} after its crossing of v = 1)",
            w.quantity, w.user, w.reference, w.deviation, w.t, w.at, w.cycle, w.phase
        ));
    }
    let period_error = worst("period");
    Ok(TrajectoryComparison {
        verdict: if reasons.is_empty() { Verdict::Agrees } else { Verdict::Disagrees },
        tolerance,
        samples: user.t.len(),
        cycles: [user_cycles.len(), ref_cycles.len()],
        reference: reference_info,
        period_error,
        worst_per_quantity,
        per_cycle,
        worst_state,
        max_state_deviation: StateMaxima { u: maxima[0], ln_v: maxima[1], theta: maxima[2] },
        reasons,
    })
}
