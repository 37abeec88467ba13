//! The stick as a slow flow: the 2D flow on S started at a point of the 3D cycle's stick (its
//! v minimum, where dv/dt = 0 puts the 3D state on S), its finite-time blow-up t_c(2D) against
//! the 3D v maximum t_c, their agreement along the stick (O(1/γ²): the 3D flow sits at
//! G = −(dv/dt)/γ² off S), where the 3D flow leaves S, and v/γ of both flows (the paper's
//! Fig. 3a).

use super::slow_run::{self, SlowRun};
use super::AsymptoticsOptions;
use crate::analysis::AnalysisError;
use crate::integrate::{Options, Tolerance};
use crate::model::slow_manifold::SlowFlow;
use crate::model::DrrParams;
use crate::numerics::series::{decimate, pick};
use crate::paper::cycle_period::CyclePeriod;
use crate::solver::{self, Method};
use serde::Serialize;

/// A state of the cycle, located in time from the catastrophe t_c (the 3D v maximum).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StatePoint {
    /// t_c − t (> 0 before the catastrophe).
    pub time_before_tc: f64,
    /// u.
    pub u: f64,
    /// v.
    pub v: f64,
    /// v/γ.
    pub v_over_gamma: f64,
    /// θ.
    pub theta: f64,
}

/// Largest differences between the 3D stick and the 2D flow at equal times.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StickDeviation {
    /// Compared from the start to the 3D flow's upward crossing of v = 1, at every 3D step end.
    pub samples: usize,
    /// max |ln v₃ − ln v₂|.
    pub max_abs_ln_v: f64,
    /// max |u₃ − u₂|.
    pub max_abs_u: f64,
    /// max |θ₃ − θ₂|.
    pub max_abs_theta: f64,
    /// max |ln v₃ − ln v₂| · γ² (γ-independent if the deviation is O(1/γ²)).
    pub max_abs_ln_v_times_gamma2: f64,
}

/// The method of the 2D slow flow, whatever the scene's.
pub const SLOW_FLOW_METHOD: Method = Method::Radau5;

/// How the 2D flow was integrated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlowIntegration {
    /// The integrator ([`SLOW_FLOW_METHOD`], in the arc parameter s with dt/ds = 1/(1 + v)).
    pub method: Method,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (t, u, θ).
    pub atol: f64,
    /// Steps taken.
    pub steps: u64,
    /// Bound on the time left after the last step (added to t_c(2D)); null without blow-up.
    pub tail: Option<f64>,
}

/// v/γ of the 2D and 3D flows near the catastrophe (the paper's Fig. 3a); times t − t_c.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig3a {
    /// 3D: t − t_c (from the start through the slip to v = 1).
    pub t_3d: Vec<f64>,
    /// 3D: v/γ.
    pub v_over_gamma_3d: Vec<f64>,
    /// 2D: t − t_c (from the start until v reaches 10 v_max of the 3D cycle).
    pub t_2d: Vec<f64>,
    /// 2D: v/γ.
    pub v_over_gamma_2d: Vec<f64>,
}

/// The "manifold" part of the asymptotics section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ManifoldReport {
    /// Where the 2D flow starts: the 3D cycle's v minimum.
    pub start: StatePoint,
    /// t_c(2D) − t_c: the 2D blow-up time minus the 3D v maximum; null if the 2D flow did not
    /// blow up within two periods.
    pub blow_up_offset: Option<f64>,
    /// t − t_c where the 2D integration ended (at the blow-up, or two periods after the start).
    pub followed_until: f64,
    /// 2D: time from its upward crossing of v = 1 to its blow-up.
    pub t0_2d: Option<f64>,
    /// 3D: time from its upward crossing of v = 1 to its v maximum.
    pub t0_3d: f64,
    /// 2D against 3D along the stick.
    pub stick_deviation: StickDeviation,
    /// The |ln v − ln v_S(u, θ)| threshold that defines leaving S (option departure_offset).
    pub departure_offset: f64,
    /// First point of the rise where the 3D flow is farther than `departure_offset` from S
    /// (interpolated between step ends).
    pub leaves_manifold: Option<StatePoint>,
    /// First point of the rise where |ln v₃ − ln v₂| at equal times exceeds `departure_offset`.
    pub flows_split: Option<StatePoint>,
    /// The 2D integration.
    pub integration: SlowIntegration,
    /// Figure data.
    pub fig3a: Fig3a,
    /// The 2D flow's samples (t − t_c, u, θ, ln v), kept for the matching figure.
    #[serde(skip)]
    pub slow_samples: Vec<[f64; 4]>,
}

fn point(gamma: f64, s: f64, u: f64, w: f64, theta: f64) -> StatePoint {
    let v = w.exp();
    StatePoint { time_before_tc: -s, u, v, v_over_gamma: v / gamma, theta }
}

/// The first k in `range` where `offset(k)` exceeds `threshold`, with the crossing
/// interpolated linearly from k − 1.
fn first_exceeding(
    orbit: &CyclePeriod,
    gamma: f64,
    range: std::ops::Range<usize>,
    threshold: f64,
    offset: &dyn Fn(usize) -> Option<f64>,
) -> Option<StatePoint> {
    let mut prev: Option<(usize, f64)> = None;
    for k in range {
        let d = offset(k)?;
        if d > threshold {
            let Some((j, dj)) = prev else {
                return Some(point(gamma, orbit.s[k], orbit.u[k], orbit.w[k], orbit.theta[k]));
            };
            let a = ((threshold - dj) / (d - dj)).clamp(0.0, 1.0);
            let lerp = |x: &[f64]| x[j] + a * (x[k] - x[j]);
            return Some(point(
                gamma,
                lerp(&orbit.s),
                lerp(&orbit.u),
                lerp(&orbit.w),
                lerp(&orbit.theta),
            ));
        }
        prev = Some((k, d));
    }
    None
}

/// The manifold analysis of one cycle.
pub fn analyse(
    orbit: &CyclePeriod,
    params: &DrrParams,
    options: &AsymptoticsOptions,
) -> Result<ManifoldReport, AnalysisError> {
    let gamma = params.gamma;
    let flow = SlowFlow::new(*params);
    let (rtol, atol) = (options.rtol, options.rtol * 1e-2);
    let y0 = [orbit.s[0], orbit.u[0], orbit.theta[0]];
    let mut integ = solver::build_default(
        SLOW_FLOW_METHOD,
        flow,
        0.0,
        &y0,
        &Options::new(rtol, Tolerance::Scalar(atol)),
    )?;
    let probes = &orbit.s[..=orbit.peak];
    let run: SlowRun = slow_run::run(integ.as_mut(), &flow, 2.0 * orbit.period, probes)?;

    let diff = |k: usize| {
        run.probes[k].map(|p| [orbit.u[k] - p[0], orbit.theta[k] - p[1], orbit.w[k] - p[2]])
    };
    let mut dev = StickDeviation {
        samples: 0,
        max_abs_ln_v: 0.0,
        max_abs_u: 0.0,
        max_abs_theta: 0.0,
        max_abs_ln_v_times_gamma2: 0.0,
    };
    for k in 0..=orbit.up {
        if let Some(d) = diff(k) {
            dev.samples += 1;
            dev.max_abs_u = dev.max_abs_u.max(d[0].abs());
            dev.max_abs_theta = dev.max_abs_theta.max(d[1].abs());
            dev.max_abs_ln_v = dev.max_abs_ln_v.max(d[2].abs());
        }
    }
    dev.max_abs_ln_v_times_gamma2 = dev.max_abs_ln_v * gamma * gamma;

    let off_manifold =
        |k: usize| flow.w(orbit.u[k], orbit.theta[k]).map(|ws| (orbit.w[k] - ws).abs());
    let leaves_manifold =
        first_exceeding(orbit, gamma, 0..orbit.peak + 1, options.departure_offset, &off_manifold);
    let flows_split =
        first_exceeding(orbit, gamma, 0..orbit.peak + 1, options.departure_offset, &|k| {
            Some(diff(k).map_or(f64::INFINITY, |d| d[2].abs()))
        });

    let v_max = orbit.w[orbit.peak].exp();
    let idx3: Vec<usize> = (0..=orbit.down).collect();
    let t3: Vec<f64> = pick(&orbit.s, &idx3);
    let y3: Vec<f64> = idx3.iter().map(|&k| orbit.w[k].exp() / gamma).collect();
    let keep3 = decimate(&t3, &[&y3], options.series_points);
    let end2 = run
        .samples
        .iter()
        .position(|x| x[3].exp() > 10.0 * v_max)
        .map_or(run.samples.len(), |i| i + 1);
    let t2: Vec<f64> = run.samples[..end2].iter().map(|x| x[0]).collect();
    let y2: Vec<f64> = run.samples[..end2].iter().map(|x| x[3].exp() / gamma).collect();
    let keep2 = decimate(&t2, &[&y2], options.series_points);

    Ok(ManifoldReport {
        start: point(gamma, orbit.s[0], orbit.u[0], orbit.w[0], orbit.theta[0]),
        blow_up_offset: run.t_c,
        followed_until: run.samples.last().map_or(orbit.s[0], |x| x[0]),
        t0_2d: run.t_c.zip(run.t_up).map(|(c, up)| c - up),
        t0_3d: -orbit.s[orbit.up],
        stick_deviation: dev,
        departure_offset: options.departure_offset,
        leaves_manifold,
        flows_split,
        integration: SlowIntegration {
            method: SLOW_FLOW_METHOD,
            rtol,
            atol,
            steps: run.steps,
            tail: run.tail,
        },
        fig3a: Fig3a {
            t_3d: pick(&t3, &keep3),
            v_over_gamma_3d: pick(&y3, &keep3),
            t_2d: pick(&t2, &keep2),
            v_over_gamma_2d: pick(&y2, &keep2),
        },
        slow_samples: run.samples,
    })
}
