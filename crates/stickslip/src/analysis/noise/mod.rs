//! The "noise" analysis: the response of a relaxation oscillation to weak coloured noise, from
//! ensembles of realisations and from the linear (small-noise) response, aligned on the event.
//!
//! Pipeline ([`run`], one function per step, plus the settings resolved on the orbit):
//! 1. the deterministic orbit (Rodas5P, rtol 1e-10): for periodic models (DRR, van der Pol) the
//!    converged limit cycle, the start `start_before_event` before an event, the deterministic
//!    event time t_c and (DRR) t0, the time from v = 1 to t_c; for the saddle-node the passage
//!    from t = 0;
//! 2. `realisations` runs of the random ODE from that start ([`scheme`], [`ensemble`]), each
//!    with its own exactly sampled OU noises ([`ou`], [`rng`]) and its own event time t_c,i;
//! 3. statistics on a grid of times s = t − t_c before the event ([`statistics`]), aligned on
//!    each realisation's own event (default) or on the deterministic one: means, σ_x(t),
//!    Γ_x(t, t − t'), the correlation time of the first observable (u for the DRR, x
//!    otherwise) as the half-height width of Γ in t' (and of the correlation coefficient), and
//!    for the DRR the growth of σ_v against v over (t_f − t0, t_f), t_f = t_c − 0.1;
//! 4. the same quantities from the linear response ([`linear_response`]), and where ensemble
//!    and linear response agree within the sampling error.

pub mod ensemble;
pub mod linear_response;
pub mod models;
pub mod options;
pub mod ou;
pub mod report;
pub mod rng;
pub mod scheme;
pub mod statistics;
mod summary;

use crate::analysis::{AnalysisError, InvalidOption};
use crate::integrate::OdeSystem;
use models::{EventKind, NoiseModel};
use options::{Alignment, NoiseOptions};
use scheme::{DeterministicRun, SchemeSettings, Start};
use serde::Serialize;

/// How the scheme works, in one paragraph (echoed in reports).
pub const SCHEME: &str = "Each realisation is a random ODE dx/dt = F(t,x) + B(x)η(t): the OU noises η (unit \
variance, correlation time τ) are sampled exactly at nodes h = τ/steps_per_correlation_time apart and joined by the C1 \
cubic (Catmull-Rom) spline; on each interval the smooth ODE is integrated by Rodas5P (Rosenbrock, order 5, L-stable: \
the deterministic part is linearly implicit) with error control, stopping at every node. Deterministic error: order 5 \
(rtol/atol). Noise discretisation (the OU bridge replaced by the spline): weak order 2 in h/τ for responses slower or \
much faster than h, first order for responses on the time scale h (at most 0.5 % of a variance at h = τ/10). Ordinary \
calculus (coloured noise): the noise on v enters ln v as η_v f_v/v.";

/// Deterministic tolerances (orbit, events, start).
const DET_RTOL: f64 = 1e-10;
/// Relative tolerance of the linear response (Radau5).
const LR_RTOL: f64 = 1e-6;
/// The grid starts this fraction of `start_before_event` after the start (room for events
/// earlier than the deterministic one).
const GRID_MARGIN: f64 = 0.05;

/// The settings as used (defaults resolved).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settings {
    /// Noise amplitudes, one per component.
    pub amplitudes: Vec<f64>,
    /// OU correlation time τ.
    pub correlation_time: f64,
    /// Node spacing h = τ/steps_per_correlation_time.
    pub noise_step: f64,
    /// τ/h.
    pub steps_per_correlation_time: f64,
    /// Number of realisations.
    pub realisations: usize,
    /// Seed of the random streams.
    pub seed: u64,
    /// Start of the realisations before the deterministic event.
    pub start_before_event: f64,
    /// [from, to] times before the event of the reported correlation times.
    pub window: [f64; 2],
    /// "own_event" or "deterministic".
    pub alignment: Alignment,
    /// Equally spaced grid points (plus a fifth as many log-spaced towards the event).
    pub grid_points: usize,
    /// Times in the window at which correlation times are reported.
    pub report_points: usize,
    /// Rodas5P's tolerances per realisation.
    pub rtol: f64,
    /// Absolute tolerances per component.
    pub atol: Vec<f64>,
    /// Whether the linear response was computed.
    pub linear_response: bool,
    /// Γ curves reported at these times before the event.
    pub correlation_curves_at: Vec<f64>,
    /// The event, in words.
    pub event: String,
}

/// The deterministic orbit the realisations start from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Deterministic {
    /// Period of the limit cycle (periodic models).
    pub period: Option<f64>,
    /// Events computed to converge the limit cycle.
    pub burn_in_events: usize,
    /// DRR: time from the upward crossing of v = 1 to t_c.
    pub t0: Option<f64>,
    /// Start time of the realisations (model time; 0 for autonomous models).
    pub start_time: f64,
    /// Start state (components as named in `components`).
    pub start_state: Vec<f64>,
    /// Names of the state components.
    pub components: Vec<&'static str>,
    /// The deterministic event time t_c (model time).
    pub event_time: f64,
    /// State at t_c.
    pub event_state: Vec<f64>,
    /// The event time of a realisation with zero amplitudes (the scheme's deterministic error).
    pub event_time_without_noise: f64,
    /// event_time_without_noise − event_time.
    pub scheme_event_time_error: f64,
}

/// The realisations' event times.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Events {
    /// Mean of t_c,i − t_c.
    pub mean_shift: f64,
    /// Standard deviation of t_c,i.
    pub std: f64,
    /// The linear response's standard deviation of the event time.
    pub std_linear_response: Option<f64>,
    /// Whether the linear response's event time (and so its own-event alignment) is inside
    /// its validity; with the linear response only.
    pub linearity: Option<EventLinearity>,
}

/// The validity of the linearised event time δt_c = −δg(t_c)/ġ (g the event function, δg its
/// fluctuation, ġ its slope on the orbit), from the linear response. Each realisation's event
/// is a root of g_i(t) ≈ ḡ(t) + δg(t); the linearisation takes that root from g's values at
/// t_c alone, and so holds while, in each realisation's own frame (read at t + δt_c), g stays
/// the orbit's: δg̃(t) = δg(t) + ġ(t)δt_c (zero at t_c) must stay small against ġσ_tc over the
/// spread σ_tc. A coherent time shift of the orbit (an inertial slip arriving early or late)
/// keeps δg̃ = 0 at any lag; a δg that fluctuates faster than σ_tc (a slip peak slaved to the
/// noise, with radiation damping) makes it ~√2.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventLinearity {
    /// σ(δg̃(t_c − σ_tc))/(|ġ|σ_tc): the event function's deviation in each realisation's own
    /// frame one spread before its event, relative to the orbit's change over the spread.
    pub own_frame_deviation: f64,
    /// Half-height width of ρ_g(s), the correlation coefficient of δg(t_c) and δg(t_c − s):
    /// the shorter of the fluctuation's memory and the orbit's time scale at the event (null
    /// where ρ_g does not cross 1/2 between the shortest and longest lags examined,
    /// 1e-4 · min(σ_tc, h) and min(0.9 (t_c − t_start), 1e3 · max(σ_tc, h))).
    pub event_function_correlation_time: Option<f64>,
    /// own_frame_deviation ≤ [`EVENT_LINEARITY_LIMIT`]: the own-event linear response
    /// (event-time spread, and σ and Γ aligned on each realisation's event) is meaningful. When
    /// false, compare the ensemble with the linear response on the deterministic alignment.
    pub valid: bool,
}

/// Largest own-frame deviation of the event function for which the linearised event time is
/// taken as valid (docs/noise.md).
pub const EVENT_LINEARITY_LIMIT: f64 = 0.1;

/// Mean and σ of one observable on the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Series {
    /// Observable name (u, v, theta; x, y).
    pub name: &'static str,
    /// Ensemble mean.
    pub mean: Vec<f64>,
    /// The deterministic orbit's value (the linear response's mean).
    pub deterministic: Vec<f64>,
    /// Ensemble standard deviation σ_x(t) = √Γ_x(t, t).
    pub sigma: Vec<f64>,
    /// Linear-response standard deviation.
    pub sigma_linear_response: Option<Vec<f64>>,
}

/// The correlation time at one time before the event.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CorrelationPoint {
    /// t_c − t.
    pub t_before_event: f64,
    /// Half-height width in t' of the ensemble's Γ(t, t − t') (null: beyond the grid).
    pub tau: Option<f64>,
    /// The same from the linear response.
    pub tau_linear_response: Option<f64>,
    /// Half-height width of the ensemble's correlation coefficient Γ(t,t−t')/(σ(t)σ(t−t')).
    pub tau_coefficient: Option<f64>,
    /// The same from the linear response.
    pub tau_coefficient_linear_response: Option<f64>,
}

/// Γ(t, t − t') against t' at one time t.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CorrelationCurve {
    /// t_c − t.
    pub t_before_event: f64,
    /// Lags t' (ascending from 0).
    pub lag: Vec<f64>,
    /// Ensemble Γ(t, t − t').
    pub gamma: Vec<f64>,
    /// Linear-response Γ(t, t − t').
    pub gamma_linear_response: Option<Vec<f64>>,
}

/// DRR: growth of σ_v against v over (t_f − t0, t_f).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Growth {
    /// t_c − t_f (0.1).
    pub t_f_before_event: f64,
    /// The interval's length t0.
    pub interval: f64,
    /// mean v(t_f)/mean v(t_f − t0) (ensemble).
    pub v_growth: f64,
    /// σ_v(t_f)/σ_v(t_f − t0) (ensemble).
    pub sigma_v_growth: f64,
    /// sigma_v_growth / v_growth.
    pub ratio: f64,
    /// log10(ratio): the paper reports about 3.
    pub log10_ratio: f64,
    /// The same three from the linear response.
    pub v_growth_linear_response: Option<f64>,
    /// σ_v growth from the linear response.
    pub sigma_v_growth_linear_response: Option<f64>,
    /// Their ratio.
    pub ratio_linear_response: Option<f64>,
}

/// Agreement of ensemble and linear response for one observable over the window.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Agreement {
    /// Observable.
    pub name: &'static str,
    /// Relative standard error of an ensemble σ, 1/√(2(R−1)).
    pub sigma_standard_error: f64,
    /// Largest |σ_ensemble/σ_linear − 1| over the window.
    pub sigma_max_relative_difference: f64,
    /// Window times (before the event) where σ differs by more than 4 standard errors.
    pub sigma_disagree_at: Vec<f64>,
    /// Median |τ_ensemble/τ_linear − 1| over the window (where both exist).
    pub tau_median_relative_difference: Option<f64>,
    /// Largest |τ_ensemble/τ_linear − 1| over the window.
    pub tau_max_relative_difference: Option<f64>,
}

/// Work done by the realisations.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Work {
    /// Rodas5P steps over all realisations.
    pub steps: u64,
    /// Step attempts.
    pub step_attempts: u64,
    /// Right-hand-side evaluations (including ∂f/∂t differences).
    pub rhs_evals: u64,
    /// Jacobian evaluations.
    pub jac_evals: u64,
    /// Noise nodes per realisation (mean).
    pub nodes_per_realisation: f64,
    /// Linear response: steps of the orbit (Rodas5P), covariance and adjoints (Radau5).
    pub linear_response_steps: Option<u64>,
    /// Wall-clock time of the ensemble (seconds).
    pub ensemble_wall_time_s: f64,
}

/// The "noise" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NoiseReport {
    /// "drr", "saddle_node" or "van_der_pol".
    pub model: &'static str,
    /// Settings as used.
    pub settings: Settings,
    /// The scheme, in words.
    pub scheme: &'static str,
    /// The deterministic orbit.
    pub deterministic: Deterministic,
    /// The realisations' event times.
    pub events: Events,
    /// Grid times before the event, t_c − t (descending: from the start towards the event).
    pub t_before_event: Vec<f64>,
    /// Mean and σ per observable on the grid.
    pub series: Vec<Series>,
    /// The observable whose correlation time is `correlation_time`.
    pub correlation_variable: &'static str,
    /// Correlation time of `correlation_variable` at the grid times inside the window.
    pub correlation_time: Vec<CorrelationPoint>,
    /// Correlation times of every observable (same definition).
    pub correlation_time_by_variable: Vec<(String, Vec<CorrelationPoint>)>,
    /// Γ of `correlation_variable` against the lag at `correlation_curves_at`.
    pub correlation_functions: Vec<CorrelationCurve>,
    /// DRR: growth of σ_v against v.
    pub growth: Option<Growth>,
    /// Ensemble against linear response, per observable.
    pub agreement: Vec<Agreement>,
    /// Work done.
    pub work: Work,
}

fn invalid(field: &str, message: String) -> AnalysisError {
    InvalidOption::new(field, message).into()
}

fn not_applicable(reason: &str) -> AnalysisError {
    AnalysisError::NotApplicable { reason: reason.into() }
}

/// The converged limit cycle of a periodic model: (period, state at an event, events used).
/// Converged when three successive periods and the event states agree to 1e-8 (relative;
/// absolute below 1): a decaying oscillation, whose period converges but whose amplitude does
/// not, never qualifies.
fn limit_cycle(
    model: &NoiseModel,
    initial: &[f64],
    event: EventKind,
    atol: &[f64],
) -> Result<(f64, Vec<f64>, usize), AnalysisError> {
    let mut x = initial.to_vec();
    let mut periods: Vec<f64> = Vec::new();
    let mut states: Vec<Vec<f64>> = Vec::new();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-8 * a.abs().max(b.abs()).max(1.0);
    let det = DeterministicRun { model, rtol: DET_RTOL, atol };
    for events in 1..=2000 {
        let (t, xe, _) = det.event(0.0, &x, event, 1e7)?;
        x = xe;
        if events > 1 {
            periods.push(t);
            states.push(x.clone());
        }
        if let ([.., a, b, c], [.., sa, sb, sc]) = (&periods[..], &states[..]) {
            let same_states =
                sa.iter().zip(sb).zip(sc).all(|((p, q), r)| close(*p, *q) && close(*q, *r));
            if close(*a, *b) && close(*b, *c) && same_states {
                return Ok((*c, x, events));
            }
        }
    }
    Err(AnalysisError::NoLimitCycle {
        reason: format!(
            "the deterministic orbit did not settle on a limit cycle in 2000 events (last periods {:?}, last state at an event {x:?})",
            &periods[periods.len().saturating_sub(3)..]
        ),
    })
}

/// Step 1's result: the deterministic orbit settled on its limit cycle (or, for the
/// saddle-node, its passage), its event and the realisations' start.
struct SettledOrbit {
    /// The event the orbit is converged on (before arming at the DRR's slip).
    burn_in_event: EventKind,
    periodic: bool,
    period: Option<f64>,
    burn_in_events: usize,
    /// start_before_event as used.
    before: f64,
    start: Start,
    /// The deterministic event t_c and the state there.
    t_event: f64,
    x_event: Vec<f64>,
    /// DRR: t0, from v = 1 to t_c.
    t0: Option<f64>,
}

/// The settings resolved against the orbit, and the grid of times s = t − t_c.
struct Plan {
    tau: f64,
    steps_per_tau: f64,
    h: f64,
    window: [f64; 2],
    curves_at: Vec<f64>,
    alignment: Alignment,
    grid_points: usize,
    report_count: usize,
    report_times: Vec<f64>,
    rtol: f64,
    realisations: usize,
    seed: u64,
    want_linear: bool,
    growth_points: Vec<f64>,
    /// The grid s.
    s: Vec<f64>,
    /// The event each realisation is aligned on (armed for the DRR).
    event: EventKind,
    event_words: String,
    /// t_c + s.
    times: Vec<f64>,
}

/// Step 2's result: the ensemble and the scheme's own error.
struct Realisations {
    data: ensemble::EnsembleData,
    atol: Vec<f64>,
    event_time_without_noise: f64,
    wall_time_s: f64,
}

/// Runs the noise analysis on `model` (with its amplitudes) from the deterministic initial
/// state `initial` (the orbit converges from there; saddle-node: x at t = 0), on `threads`
/// threads; `progress(done, total)` after each realisation. The steps of the module's
/// pipeline, in the order their data need: the deterministic orbit, the settings on it, the
/// linear response (it sets the default absolute tolerances), the realisations, the
/// statistics.
pub fn run(
    model: &NoiseModel,
    initial: &[f64],
    options: &NoiseOptions,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<NoiseReport, AnalysisError> {
    run_stoppable(model, initial, options, threads, progress, &|| false)
}

/// [`run`], failing with [`AnalysisError::Stopped`] once `stop()` returns true (checked before
/// each realisation, which takes milliseconds).
pub fn run_stoppable(
    model: &NoiseModel,
    initial: &[f64],
    options: &NoiseOptions,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<NoiseReport, AnalysisError> {
    let workers = ensemble::Workers { threads, progress, stop };
    let det_atol = vec![1e-12; model.dim()];
    let orbit = deterministic_orbit(model, initial, options, &det_atol)?;
    let plan = plan(model, options, &orbit)?;
    let linear = if plan.want_linear {
        Some(linear_response::compute(
            model,
            orbit.start.t,
            &orbit.start.x,
            &plan.times,
            plan.event,
            plan.tau,
            LR_RTOL,
            &det_atol,
        )?)
    } else {
        None
    };
    let realisations = realisations(model, options, &orbit, &plan, linear.as_ref(), workers)?;
    summary::statistics(model, &orbit, plan, realisations, linear, &det_atol)
}

/// Step 1, the deterministic orbit: for periodic models the converged limit cycle, the start
/// `start_before_event` before an event, t_c and (DRR) t0; for the saddle-node the passage
/// from t = 0.
fn deterministic_orbit(
    model: &NoiseModel,
    initial: &[f64],
    options: &NoiseOptions,
    det_atol: &[f64],
) -> Result<SettledOrbit, AnalysisError> {
    let (event_for_burn_in, periodic) = match model {
        NoiseModel::Drr { .. } => {
            (EventKind::Maximum { component: 1, arm: 0.0, drop: std::f64::consts::LN_2 }, true)
        }
        NoiseModel::VanDerPol { .. } => {
            (EventKind::CrossDown { component: 0, level: 0.0, arm: 1.0 }, true)
        }
        NoiseModel::SaddleNode { .. } => {
            let level = options.event_level.unwrap_or(-1.0);
            (EventKind::CrossDown { component: 0, level, arm: 0.0 }, false)
        }
        NoiseModel::Linear { .. } => {
            return Err(not_applicable("the linear validation model has no event to align on; it serves the scheme's tests"));
        }
    };
    if let NoiseModel::Drr { system, .. } = model {
        if crate::analysis::hopf::analyse(system).max_real_part < 0.0 {
            return Err(not_applicable(
                "the fixed point is stable (ε below ε_c): there is no stick-slip event to align on",
            ));
        }
    }
    let det = DeterministicRun { model, rtol: DET_RTOL, atol: det_atol };
    let (period, burn_in_events, before, start, t_event_det, x_event_det) = if periodic {
        let (period, x_event, events) = limit_cycle(model, initial, event_for_burn_in, det_atol)?;
        let before = options.start_before_event.unwrap_or(match model {
            NoiseModel::Drr { .. } => (0.8 * period).min(6.0),
            _ => 0.45 * period,
        });
        if before >= period {
            return Err(invalid(
                "start_before_event",
                format!("{before} must be shorter than the period {period}"),
            ));
        }
        let x_start = det.state(0.0, &x_event, period - before)?;
        let (tc, xc, _) = det.event(0.0, &x_start, event_for_burn_in, 2.0 * period)?;
        // The event search arms only after the component has been below its arming level: a
        // start already past it (inside a broad damped slip, v > 1) would find the next event,
        // a period later, while the realisations find this one.
        if (tc - before).abs() > 1e-6 * period {
            return Err(invalid(
                "start_before_event",
                format!("{before} starts past the arming of the event search (the next event found from there is {tc} later, not {before}): start earlier, before the slip's onset"),
            ));
        }
        (Some(period), events, before, Start { t: 0.0, x: x_start }, tc, xc)
    } else {
        let (tc, xc, _) = det.event(0.0, initial, event_for_burn_in, 1e7)?;
        let before = options.start_before_event.unwrap_or(tc);
        if before > tc {
            return Err(invalid(
                "start_before_event",
                format!("{before} exceeds the time {tc} from t = 0 to the escape"),
            ));
        }
        let x_start = det.state(0.0, initial, tc - before)?;
        (None, 0, before, Start { t: tc - before, x: x_start }, tc, xc)
    };
    let t0 = match model {
        NoiseModel::Drr { .. } => {
            let up = EventKind::CrossUp { component: 1, level: 0.0, arm: 0.0 };
            det.event(start.t, &start.x, up, t_event_det).ok().map(|(t, _, _)| t_event_det - t)
        }
        _ => None,
    };
    Ok(SettledOrbit {
        burn_in_event: event_for_burn_in,
        periodic,
        period,
        burn_in_events,
        before,
        start,
        t_event: t_event_det,
        x_event: x_event_det,
        t0,
    })
}

/// The settings resolved on the orbit (defaults, checks against the period) and the grid.
fn plan(
    model: &NoiseModel,
    options: &NoiseOptions,
    orbit: &SettledOrbit,
) -> Result<Plan, AnalysisError> {
    let before = orbit.before;
    let tau = options.correlation_time.unwrap_or(match model {
        NoiseModel::Drr { system, .. } => 2.5 / system.params().gamma,
        NoiseModel::SaddleNode { system, .. } => 0.05 / system.params().mu0.sqrt(),
        NoiseModel::VanDerPol { system, .. } => 2.5 / (system.params().beta * system.params().beta),
        NoiseModel::Linear { rate, .. } => 0.1 / rate,
    });
    let steps_per_tau = options.steps_per_correlation_time.unwrap_or(10.0);
    let h = tau / steps_per_tau;
    let window = options.window.unwrap_or(match model {
        NoiseModel::Drr { system, .. } => [3.0, 30.0 / system.params().gamma],
        _ => [0.9 * before, 0.01 * before],
    });
    let far = (1.0 - GRID_MARGIN) * before;
    if window[0] > far {
        return Err(invalid("window", format!("starts {} before the event, before the grid's first time {far} (raise start_before_event)", window[0])));
    }
    let curves_at = options.correlation_curves_at.clone().unwrap_or(match model {
        NoiseModel::Drr { system, .. } => vec![2.3, 1.0, 30.0 / system.params().gamma],
        _ => vec![window[0], (window[0] * window[1]).sqrt(), window[1]],
    });
    if let Some(t) = curves_at.iter().find(|t| **t > far) {
        return Err(invalid(
            "correlation_curves_at",
            format!("{t} is before the grid's first time {far} before the event"),
        ));
    }
    let alignment = options.alignment.unwrap_or(Alignment::OwnEvent);
    let grid_points = options.grid_points.unwrap_or(1000);
    let report_count = options.report_points.unwrap_or(60);
    let report_times: Vec<f64> = (0..report_count)
        .map(|i| {
            let f = if report_count > 1 { i as f64 / (report_count - 1) as f64 } else { 0.0 };
            (window[0].ln() + f * (window[1].ln() - window[0].ln())).exp()
        })
        .collect();
    let growth_points = match (model, orbit.t0) {
        (NoiseModel::Drr { .. }, Some(t0)) if 0.1 + t0 <= far => vec![-0.1, -(0.1 + t0)],
        _ => vec![],
    };
    let mut extra: Vec<f64> = report_times.iter().map(|t| -t).collect();
    extra.extend(curves_at.iter().map(|t| -t));
    extra.extend(&growth_points);
    let s = statistics::grid(far, window[1] / 3.0, grid_points, grid_points / 5, &extra);
    let event = match (model, orbit.burn_in_event) {
        // Armed at half of ln v_max: noise wiggles of ln v on the stick never count.
        (NoiseModel::Drr { .. }, EventKind::Maximum { component, drop, .. }) => {
            EventKind::Maximum { component, arm: 0.5 * orbit.x_event[component], drop }
        }
        (_, e) => e,
    };
    let event_words = match event {
        EventKind::Maximum { .. } => "the maximum of v (slip peak)".to_string(),
        EventKind::CrossDown { level, .. } if orbit.periodic => {
            format!("the downward crossing of x = {level} (jump off the fold x = 1)")
        }
        EventKind::CrossDown { level, .. } => {
            format!("the downward crossing of x = {level} (escape)")
        }
        EventKind::CrossUp { level, .. } => format!("the upward crossing of level {level}"),
    };
    let times: Vec<f64> = s.iter().map(|v| orbit.t_event + v).collect();
    Ok(Plan {
        tau,
        steps_per_tau,
        h,
        window,
        curves_at,
        alignment,
        grid_points,
        report_count,
        report_times,
        rtol: options.rtol.unwrap_or(1e-6),
        realisations: options.realisations.unwrap_or(1000),
        seed: options.seed.unwrap_or(1),
        want_linear: options.linear_response.unwrap_or(true),
        growth_points,
        s,
        event,
        event_words,
        times,
    })
}

/// Step 2, the realisations: the scheme's deterministic error (one realisation with zero
/// amplitudes), then the ensemble, from the orbit's start.
fn realisations(
    model: &NoiseModel,
    options: &NoiseOptions,
    orbit: &SettledOrbit,
    plan: &Plan,
    linear: Option<&linear_response::LinearResponse>,
    workers: ensemble::Workers<'_>,
) -> Result<Realisations, AnalysisError> {
    let n = model.dim();
    let start = &orbit.start;
    // Default atol: 1e-3 of each component's typical (median) linear-response σ, within
    // [1e-14, 1e-6]; 1e-6 without the linear response. (Much tighter values can be out of
    // reach: a stiff component driven by the noise lags its quasi-static value by ~ḟ/λ, and
    // Rosenbrock methods get that lag right only to a fraction of it, whatever the step.)
    let atol = options.atol.clone().unwrap_or_else(|| match linear {
        Some(l) => (0..n)
            .map(|i| {
                let mut sig: Vec<f64> =
                    l.covariance.iter().map(|c| c[i * l.big + i].max(0.0).sqrt()).collect();
                sig.sort_by(|a, b| a.total_cmp(b));
                (1e-3 * sig[sig.len() / 2]).clamp(1e-14, 1e-6)
            })
            .collect(),
        None => vec![1e-6; n],
    });
    let scheme_settings =
        SchemeSettings { h: plan.h, tau: plan.tau, rtol: plan.rtol, atol: atol.clone() };
    // The scheme's deterministic error: one realisation with zero amplitudes.
    let quiet = model.scaled(0.0);
    let t_max = start.t + 2.0 * orbit.before + 10.0 * plan.tau;
    let mut path = scheme::Path::default();
    let mut rng = rng::Rng::for_realisation(plan.seed, u64::MAX);
    scheme::realisation(
        &quiet,
        start,
        &scheme_settings,
        Some(plan.event),
        start.t,
        t_max,
        &mut rng,
        &mut path,
    )?;
    let event_time_without_noise = path.t_event;
    let record_until = match plan.alignment {
        Alignment::OwnEvent => start.t,
        Alignment::Deterministic => orbit.t_event + plan.h,
    };
    let spec = ensemble::EnsembleSpec {
        model,
        start,
        scheme: &scheme_settings,
        event: Some(plan.event),
        record_until,
        t_max,
        seed: plan.seed,
    };
    let fixed_reference = (plan.alignment == Alignment::Deterministic).then_some(orbit.t_event);
    let sampling = ensemble::Sampling { s: &plan.s, fixed_reference };
    let started = std::time::Instant::now();
    let data = ensemble::run(&spec, &sampling, plan.realisations, workers)?;
    Ok(Realisations {
        data,
        atol,
        event_time_without_noise,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}
