//! The reference integrations of `compare --against`: the scene's model from a given state,
//! driven by the engine's time bookkeeping ([`Clock`]: re-based before its steps outrun the
//! local clock, global time kept as a double-double), so it does not drift from clock
//! rounding at any length.

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

/// The step ends (global time, (u, w, θ)) of `method` from (start, y0) to past `end`,
/// through a [`Clock`].
pub fn reference_steps(
    drr: Drr,
    method: Method,
    rtol: f64,
    start: f64,
    y0: [f64; 3],
    end: f64,
) -> Result<(Vec<f64>, Vec<[f64; 3]>), SolverError> {
    let (mut integ, _) = engine::integrator(drr, &spec(method, rtol), &y0)?;
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
