//! The reference integrations of `compare --against`: the scene's model from a given state,
//! driven by the engine's time bookkeeping ([`Clock`]: re-based before its steps outrun the
//! local clock, global time kept as a double-double), so it does not drift from clock
//! rounding at any length.

use super::error::CompareError;
use super::scale::{event_budget, SceneMismatch, MAX_REFERENCE_STEPS};
use crate::engine;
use crate::integrate::{Clock, SolverError, Time};
use crate::model::Drr;
use crate::scene::{Method, SolverSpec};

fn spec(method: Method, rtol: f64) -> SolverSpec {
    SolverSpec { method, rtol, atol: [rtol; 3], table: None, explicit_table: None }
}

/// The state (u, w = ln v, θ) at `times` (any order, all ≥ `start`), integrated by
/// `method` through a [`Clock`] from (start, y0), evaluated on the integrator's dense output.
/// Returns the states and the re-bases made.
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
    let (mut integ, _) = engine::integrator(drr, &spec(method, rtol), &y0)?;
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

/// Steps `method` from (start, y0) through a [`Clock`], handing each step end (global time,
/// (u, w, θ)) to `each` until it returns false. Returns None when `each` stopped it, or the
/// time reached when [`MAX_REFERENCE_STEPS`] ran out first.
fn march(
    drr: Drr,
    method: Method,
    rtol: f64,
    start: f64,
    y0: [f64; 3],
    mut each: impl FnMut(f64, [f64; 3]) -> bool,
) -> Result<Option<f64>, SolverError> {
    let (mut integ, _) = engine::integrator(drr, &spec(method, rtol), &y0)?;
    let mut clock = Clock::new(integ.as_mut(), Time::new(start));
    for _ in 0..MAX_REFERENCE_STEPS {
        clock.step().map_err(|e| clock.at_global(e))?;
        let y = clock.state();
        if !each(clock.now().to_f64(), [y[0], y[1], y[2]]) {
            return Ok(None);
        }
    }
    Ok(Some(clock.now().to_f64()))
}

/// The step ends (global time, (u, w, θ)) of `method` from (start, y0) to past `end`,
/// through a [`Clock`]. A file with `user_events` events over the span lets the reference
/// have at most [`event_budget`] (v ≥ 1) and [`MAX_REFERENCE_STEPS`] steps
/// ([`SceneMismatch`], see [`super::scale`]).
pub fn reference_steps(
    drr: Drr,
    method: Method,
    rtol: f64,
    start: f64,
    y0: [f64; 3],
    end: f64,
    user_events: usize,
) -> Result<(Vec<f64>, Vec<[f64; 3]>), CompareError> {
    let (mut times, mut states) = (vec![start], vec![y0]);
    let (budget, mut events) = (event_budget(user_events), 0);
    let mut beyond = None;
    let exhausted = march(drr, method, rtol, start, y0, |t, y| {
        if states.last().is_some_and(|p| p[1] < 0.0) && y[1] >= 0.0 {
            events += 1;
        }
        if events > budget {
            beyond = Some(t);
            return false;
        }
        times.push(t);
        states.push(y);
        t < end
    })?;
    if let Some(at) = beyond {
        let events = budget;
        return Err(SceneMismatch::TooManyEvents { start, end, user_events, events, at }.into());
    }
    if let Some(at) = exhausted {
        return Err(
            SceneMismatch::TooManySteps { start, end, steps: MAX_REFERENCE_STEPS, at }.into()
        );
    }
    Ok((times, states))
}

/// The reference's mean time between upward crossings of v = 1 (located linearly in ln v)
/// over its first `crossings` of them from (start, y0); None if it has fewer than two within
/// [`MAX_REFERENCE_STEPS`] steps.
pub fn reference_recurrence(
    drr: Drr,
    method: Method,
    rtol: f64,
    start: f64,
    y0: [f64; 3],
    crossings: usize,
) -> Result<Option<f64>, SolverError> {
    let mut found: Vec<f64> = Vec::new();
    let mut previous = (start, y0[1]);
    march(drr, method, rtol, start, y0, |t, y| {
        let (t0, w0) = previous;
        if w0 < 0.0 && y[1] >= 0.0 {
            found.push(t0 + (t - t0) * (-w0) / (y[1] - w0));
        }
        previous = (t, y[1]);
        found.len() < crossings
    })?;
    Ok((found.len() >= 2).then(|| (found[found.len() - 1] - found[0]) / (found.len() - 1) as f64))
}
