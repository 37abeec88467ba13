//! A laboratory run: the lab model ([`crate::model::lab`]) driven through its load-point
//! history, with the numbers the laboratory reads off the record.
//!
//! The run integrates each segment of constant V_lp on its own, in local time from 0, starting
//! from the state where the previous one ended: no step crosses a jump of V_lp. Along the way
//! it finds
//! - the maxima of V (dense output; the root of d ln V/dt by bisection inside the step) that
//!   stand out of the integration's noise ([`MAXIMUM_PROMINENCE`]);
//! - the friction peak of each reload after a hold (μ is largest where V rises through V_lp);
//! - a finite-time blow-up: once V exceeds [`BLOW_UP_FACTOR`] times the fastest velocity of
//!   the run and still accelerates, ln V becomes the independent variable (dt/d ln V =
//!   1/(d ln V/dt)) and the integration goes on to ln V + [`BLOW_UP_SPAN`], where the time
//!   left is below e^(−span) of the time scale: t there is the blow-up time. If V turns back
//!   instead, the ordinary integration goes on.
//!
//! From the record: per velocity step the steady-state change Δμ_ss/Δln V = a − b, per hold
//! the peak Δμ_peak above the pre-hold steady state, and over the holds the healing rate
//! β = dΔμ_peak/d log10(t_hold) (least squares).

use crate::integrate::{Integrator, OdeSystem, Options, SolverError, Task, Tolerance};
use crate::model::lab::{LabParams, LabSystem, LN_V};
use crate::model::Loading;
use crate::solver::{self, Method, MethodSettings};
use serde::Serialize;

/// V above this multiple of the run's fastest velocity (load-point or initial) and still
/// accelerating: the blow-up test starts.
pub const BLOW_UP_FACTOR: f64 = 1e8;
/// How far in ln V the blow-up integration goes past its start.
pub const BLOW_UP_SPAN: f64 = 400.0;
/// A maximum of V counts only if ln V rose by more than this many times the integration's
/// tolerance on ln V (atol + rtol·|ln V|) since the lowest ln V after the previous maximum:
/// near steady sliding d ln V/dt is round-off, and its sign flips are no maxima.
pub const MAXIMUM_PROMINENCE: f64 = 10.0;
/// Most state variables a run takes (one output column each).
pub const MAX_STATES: usize = 8;

/// The output columns: t, x_lp, delta, mu, v, theta_1 … theta_8 (the first 5 + n are used).
pub const COLUMNS: [&str; 5 + MAX_STATES] = [
    "t", "x_lp", "delta", "mu", "v", "theta_1", "theta_2", "theta_3", "theta_4", "theta_5",
    "theta_6", "theta_7", "theta_8",
];

/// How to integrate a lab run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabSolver {
    /// The method (any of the method table).
    pub method: Method,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance of ln V and each ln θ_i (an absolute error in a logarithm is a
    /// relative error of V or θ).
    pub atol: f64,
}

/// Which rows the run writes.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Output {
    /// A row at the start and after every internal step.
    EveryStep,
    /// Rows exactly at these times (non-decreasing, inside the run).
    Times(Vec<f64>),
}

/// A maximum of V.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VelocityMaximum {
    /// Time (s).
    pub t: f64,
    /// V there (µm/s).
    pub v: f64,
    /// μ there.
    pub mu: f64,
}

/// A velocity step between two segments that both slide.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VelocityStep {
    /// Time of the step (s).
    pub t: f64,
    /// Load-point velocity before (µm/s).
    pub v_before: f64,
    /// Load-point velocity after (µm/s).
    pub v_after: f64,
    /// μ at the end of the segment before and after the step.
    pub mu_before: f64,
    /// μ at the end of the segment after the step.
    pub mu_after: f64,
    /// The measured (μ_after − μ_before)/ln(v_after/v_before): a − b if both ends are steady.
    pub a_minus_b_measured: f64,
    /// The parameters' a − Σ b_i.
    pub a_minus_b_model: f64,
    /// |ln(V/V_lp)| at the end of the segment after the step (0 at steady sliding).
    pub end_ln_v_offset: f64,
}

/// A hold (V_lp = 0) and the reload after it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Hold {
    /// Start of the hold (s).
    pub t_start: f64,
    /// Its duration (s).
    pub t_hold: f64,
    /// μ at the start of the hold (the pre-hold steady state if the slide before reached it).
    pub mu_pre_hold: f64,
    /// Slowest V in the hold (its end, µm/s).
    pub v_min: f64,
    /// Time of the friction peak after the reload (None: no reload, or V never rose back
    /// through the reload velocity before the next jump).
    pub t_peak: Option<f64>,
    /// The friction peak after the reload.
    pub mu_peak: Option<f64>,
    /// Δμ_peak = μ_peak − μ_pre_hold.
    pub delta_mu_peak: Option<f64>,
}

/// A finite-time blow-up: V → ∞ at `t`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BlowUp {
    /// The blow-up time (s).
    pub t: f64,
    /// When the blow-up integration started (V = `v_start`).
    pub t_start: f64,
    /// V when it started (µm/s).
    pub v_start: f64,
}

/// What a lab run found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabOutcome {
    /// The output's column names: t, x_lp, delta, mu, v, theta_1, ….
    pub columns: Vec<&'static str>,
    /// Maxima of V (stick-slip, overshoots after steps).
    pub v_maxima: Vec<VelocityMaximum>,
    /// Velocity steps.
    pub velocity_steps: Vec<VelocityStep>,
    /// Holds.
    pub holds: Vec<Hold>,
    /// The healing rate β = dΔμ_peak/d log10(t_hold), least squares over the holds with a
    /// peak (None with fewer than two distinct hold times).
    pub healing_rate: Option<f64>,
    /// A finite-time blow-up, which ends the run.
    pub blow_up: Option<BlowUp>,
    /// End time of the run (s): the loading's end, or the blow-up time.
    pub t_end: f64,
    /// Internal steps taken (all segments).
    pub steps: u64,
    /// Right-hand-side evaluations (all segments).
    pub rhs_evaluations: u64,
}

/// Why a lab run failed: the solver's typed error, with the segment it happened in.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LabRunError {
    /// The integrator failed.
    #[error("segment {segment} (V_lp = {v_lp}, from t = {t_start}): {source}")]
    Solver {
        /// Index of the segment.
        segment: usize,
        /// Its load-point velocity.
        v_lp: f64,
        /// Its start time.
        t_start: f64,
        /// The solver's error (local time).
        source: SolverError,
    },
    /// A requested output time lies outside the run, or the times decrease.
    #[error("{0}")]
    BadTimes(String),
    /// More state variables than the output has columns for.
    #[error("{0} state variables; at most {MAX_STATES} are supported")]
    TooManyStates(usize),
}

/// Runs the lab model from `y0` (at the loading's start) through `loading`, handing each
/// output row (the [`LabOutcome::columns`]) to `row`.
pub fn run(
    params: &LabParams,
    loading: &Loading,
    y0: &[f64],
    solver: &LabSolver,
    output: &Output,
    row: &mut dyn FnMut(&[f64]),
) -> Result<LabOutcome, LabRunError> {
    let n = params.states.len();
    if n > MAX_STATES {
        return Err(LabRunError::TooManyStates(n));
    }
    if let Output::Times(times) = output {
        check_times(times, loading)?;
    }
    let mu_init = params.measured_friction(y0);
    let x_starts = loading.start_displacements();
    let v_fast = loading.segments.iter().map(|s| s.velocity).fold(y0[LN_V].exp(), f64::max);
    let w_blow = (v_fast * BLOW_UP_FACTOR).ln();
    let mut out = LabOutcome {
        columns: COLUMNS[..5 + n].to_vec(),
        v_maxima: vec![],
        velocity_steps: vec![],
        holds: vec![],
        healing_rate: None,
        blow_up: None,
        t_end: loading.t_end,
        steps: 0,
        rhs_evaluations: 0,
    };
    let mut next_time = 0; // index into the requested times
    let mut y = y0.to_vec();
    let mut segment_end_mu: Vec<f64> = Vec::new();
    let mut buf = vec![0.0; 5 + n];
    // The lowest ln V since the previous maximum of V (or the start).
    let mut w_low = y[LN_V];
    'segments: for (j, seg) in loading.segments.iter().enumerate() {
        let t0 = seg.t_start;
        let duration = loading.segment_end(j) - t0;
        let system = LabSystem { params, v_lp: seg.velocity };
        let fail =
            |source| LabRunError::Solver { segment: j, v_lp: seg.velocity, t_start: t0, source };
        let emit = |t: f64, y: &[f64], buf: &mut Vec<f64>, row: &mut dyn FnMut(&[f64])| {
            let mu = params.measured_friction(y);
            let x_lp = x_starts[j] + seg.velocity * (t - t0);
            buf[0] = t;
            buf[1] = x_lp;
            buf[2] = x_lp - (mu - mu_init) / params.k;
            buf[3] = mu;
            buf[4] = y[LN_V].exp();
            for i in 0..n {
                buf[5 + i] = y[1 + i].exp();
            }
            row(buf);
        };
        if j == 0 && *output == Output::EveryStep {
            emit(t0, &y, &mut buf, row);
        }
        let options = Options {
            stop_time: Some(duration),
            max_err_test_fails: Some(20),
            ..Options::new(solver.rtol, Tolerance::Scalar(solver.atol))
        };
        let settings = MethodSettings { autonomous: true, ..MethodSettings::default() };
        let mut integ = solver::build(solver.method, &settings, system.clone(), 0.0, &y, &options)
            .map_err(fail)?
            .integrator;
        let after_hold = j > 0 && loading.segments[j - 1].velocity == 0.0 && seg.velocity > 0.0;
        let mut peak_found = !after_hold;
        let mut f = vec![0.0; params.dim()];
        system.rhs(0.0, &y, &mut f);
        let (mut t_prev, mut dw_prev, mut w_prev) = (0.0, f[LN_V], y[LN_V]);
        loop {
            let step = integ.advance(duration, Task::OneStep).map_err(fail)?;
            let t = step.t;
            y.copy_from_slice(integ.state());
            system.rhs(t, &y, &mut f);
            let dw = f[LN_V];
            // Rows at the requested times inside this step.
            match output {
                Output::EveryStep => emit(t0 + t, &y, &mut buf, row),
                Output::Times(times) => {
                    while next_time < times.len() && times[next_time] - t0 <= t {
                        let local = (times[next_time] - t0).max(t_prev);
                        let ys = if local >= t {
                            y.clone()
                        } else {
                            integ.dense(local, 0).map_err(fail)?.to_vec()
                        };
                        emit(times[next_time], &ys, &mut buf, row);
                        buf[0] = times[next_time];
                        next_time += 1;
                    }
                }
            }
            // A maximum of V inside the step.
            if dw_prev > 0.0 && dw <= 0.0 && t > t_prev {
                let tm = bisect(&mut *integ, t_prev, t, 1, |dy| dy[LN_V] > 0.0).map_err(fail)?;
                let ym = integ.dense(tm, 0).map_err(fail)?.to_vec();
                let noise = solver.atol + solver.rtol * ym[LN_V].abs();
                if ym[LN_V] - w_low > MAXIMUM_PROMINENCE * noise {
                    out.v_maxima.push(VelocityMaximum {
                        t: t0 + tm,
                        v: ym[LN_V].exp(),
                        mu: params.measured_friction(&ym),
                    });
                    w_low = ym[LN_V];
                }
            }
            w_low = w_low.min(y[LN_V]);
            // The friction peak of a reload: V rises through V_lp.
            let lv = seg.velocity.ln();
            if !peak_found && w_prev < lv && y[LN_V] >= lv {
                let tp = bisect(&mut *integ, t_prev, t, 0, |y| y[LN_V] < lv).map_err(fail)?;
                let yp = integ.dense(tp, 0).map_err(fail)?.to_vec();
                let hold = out.holds.last_mut().expect("a hold precedes a reload");
                let mu_peak = params.measured_friction(&yp);
                hold.t_peak = Some(t0 + tp);
                hold.mu_peak = Some(mu_peak);
                hold.delta_mu_peak = Some(mu_peak - hold.mu_pre_hold);
                peak_found = true;
            }
            // A blow-up?
            if y[LN_V] > w_blow && dw > 0.0 {
                if let Some(b) = blow_up(params, seg.velocity, t0 + t, &y, solver) {
                    out.blow_up = Some(b);
                    out.t_end = b.t;
                    let stats = integ.stats();
                    out.steps += stats.steps as u64;
                    out.rhs_evaluations += stats.rhs_evals as u64;
                    break 'segments;
                }
            }
            (t_prev, dw_prev, w_prev) = (t, dw, y[LN_V]);
            if t >= duration {
                break;
            }
        }
        let stats = integ.stats();
        out.steps += stats.steps as u64;
        out.rhs_evaluations += stats.rhs_evals as u64;
        let mu_end = params.measured_friction(&y);
        if seg.velocity == 0.0 {
            let mu_pre_hold = segment_end_mu.last().copied().unwrap_or(mu_init);
            out.holds.push(Hold {
                t_start: t0,
                t_hold: duration,
                mu_pre_hold,
                v_min: y[LN_V].exp(),
                t_peak: None,
                mu_peak: None,
                delta_mu_peak: None,
            });
        } else if j > 0 {
            let prev = loading.segments[j - 1].velocity;
            if prev > 0.0 && prev != seg.velocity {
                let mu_before = segment_end_mu[j - 1];
                out.velocity_steps.push(VelocityStep {
                    t: t0,
                    v_before: prev,
                    v_after: seg.velocity,
                    mu_before,
                    mu_after: mu_end,
                    a_minus_b_measured: (mu_end - mu_before) / (seg.velocity / prev).ln(),
                    a_minus_b_model: params.a_minus_b(),
                    end_ln_v_offset: (y[LN_V] - seg.velocity.ln()).abs(),
                });
            }
        }
        segment_end_mu.push(mu_end);
    }
    out.healing_rate = healing_rate(&out.holds);
    Ok(out)
}

/// Checks requested output times: finite, non-decreasing and inside the loading.
pub fn check_times(times: &[f64], loading: &Loading) -> Result<(), LabRunError> {
    if let Some(w) = times.windows(2).find(|w| w[1].partial_cmp(&w[0]).is_none_or(|o| o.is_lt())) {
        return Err(LabRunError::BadTimes(format!(
            "output times must not decrease: {} then {}",
            w[0], w[1]
        )));
    }
    let (lo, hi) = (loading.t_start(), loading.t_end);
    if let Some(t) = times.iter().find(|t| !(lo..=hi).contains(*t)) {
        return Err(LabRunError::BadTimes(format!(
            "output time {t} lies outside the loading [{lo}, {hi}]"
        )));
    }
    Ok(())
}

/// Where `before` (true at `a`, false at `b`) of the dense output's derivative of order
/// `order` turns false in [a, b], by bisection to the spacing of t.
fn bisect(
    integ: &mut dyn Integrator,
    a: f64,
    b: f64,
    order: u32,
    before: impl Fn(&[f64]) -> bool,
) -> Result<f64, SolverError> {
    let (mut lo, mut hi) = (a, b);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if before(integ.dense(mid, order)?) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// β = dΔμ_peak/d log10(t_hold) by least squares over the holds with a peak.
fn healing_rate(holds: &[Hold]) -> Option<f64> {
    let pts: Vec<(f64, f64)> =
        holds.iter().filter_map(|h| Some((h.t_hold.log10(), h.delta_mu_peak?))).collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (pts.len() >= 2 && sxx > 0.0).then(|| sxy / sxx)
}

/// The lab system with ln V as the independent variable: state (t, ln θ_1, …), derivatives
/// dt/d ln V = 1/(d ln V/dt) and d ln θ_i/d ln V = (d ln θ_i/dt)/(d ln V/dt).
struct InLnV<'p> {
    system: LabSystem<'p>,
}

impl OdeSystem for InLnV<'_> {
    fn dim(&self) -> usize {
        self.system.dim()
    }

    fn rhs(&self, w: f64, z: &[f64], dz: &mut [f64]) {
        let mut y = z.to_vec();
        y[LN_V] = w;
        let mut f = vec![0.0; z.len()];
        self.system.rhs(z[0], &y, &mut f);
        let inv = 1.0 / f[LN_V];
        // A V that stops accelerating is no blow-up: a non-finite rate makes the solver fail.
        dz[0] = if inv > 0.0 { inv } else { f64::NAN };
        for i in 1..z.len() {
            dz[i] = f[i] * inv;
        }
    }

    fn has_linear_invariants(&self) -> bool {
        false
    }
}

/// Integrates from (t, y) with ln V as the independent variable over [`BLOW_UP_SPAN`]:
/// Some(blow-up) if V goes on accelerating throughout.
fn blow_up(params: &LabParams, v_lp: f64, t: f64, y: &[f64], solver: &LabSolver) -> Option<BlowUp> {
    let w0 = y[LN_V];
    let mut z = y.to_vec();
    z[0] = t;
    let system = InLnV { system: LabSystem { params, v_lp } };
    let options = Options::new(solver.rtol, Tolerance::Scalar(solver.atol));
    // InLnV has no explicit/implicit split: a method that needs one runs radau5 here.
    let method =
        if solver.method.capabilities().needs_imex { Method::Radau5 } else { solver.method };
    let mut integ = solver::build_default(method, system, w0, &z, &options).ok()?;
    integ.set_stop_time(w0 + BLOW_UP_SPAN).ok()?;
    let step = integ.advance(w0 + BLOW_UP_SPAN, Task::Normal).ok()?;
    let z_end = integ.state();
    if step.t < w0 + BLOW_UP_SPAN || !z_end.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(BlowUp { t: z_end[0], t_start: t, v_start: w0.exp() })
}
