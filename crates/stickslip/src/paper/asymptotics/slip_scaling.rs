//! Slip scaling: the fast system in T = γt, V = v/γ with the predicted shifts
//! c_u = ε/ξ, c_θ = −(1+ε) (the paper's eqs. UV and cut), tested two ways.
//!
//! - Across the γ scan: u and θ at the v maximum should move by c_u and c_θ per unit ln γ;
//!   fitted as a + b ln γ and as a + b ln γ + d ln ln γ (the singular limit gives
//!   ln v_max ≈ ln γ + ln ln γ + ln(ε/ξ), so ln ln γ terms are expected). The slip half-width × γ
//!   and its large-γ limit, extrapolated as a + b (ln γ)^(−p) with a free exponent (fits in
//!   fixed powers of 1/ln γ were tried and are unstable: their limits range over 2.07 … 2.26
//!   with the fit window).
//! - On the scene's own cycle: the fast system started from the 3D state where v/γ first
//!   reaches `fast_start` must reproduce the slip (V_max and the half-width) up to the −1 it
//!   neglects in du/dt, at most 1/v_start of du/dt.

use super::scan::ScanValues;
use super::AsymptoticsOptions;
use crate::analysis::AnalysisError;
use crate::integrate::{Integrator, Options, SolverError, Task, Tolerance};
use crate::model::fast_slip::{shifts, FastSlip};
use crate::model::DrrParams;
use crate::numerics::events::{self, Knot};
use crate::numerics::fit::{least_squares, power_limit, Fit, PowerLimit};
use crate::numerics::series::{decimate, pick};
use crate::paper::cycle_period::CyclePeriod;
use crate::solver::{self, Method};
use serde::Serialize;

/// Fits of a quantity at the v maximum against ln γ.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShiftFit {
    /// The predicted slope per unit ln γ (c_u or c_θ).
    pub predicted_slope: f64,
    /// a + b ln γ.
    pub linear: Option<Fit>,
    /// a + b ln γ + d ln ln γ.
    pub with_ln_ln: Option<Fit>,
}

/// Slip half-width × γ across the scan and its large-γ limit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HalfWidthLimit {
    /// Largest γ of the scan with a half-width.
    pub largest_gamma: Option<f64>,
    /// Half-width × γ there.
    pub at_largest_gamma: Option<f64>,
    /// a + b (ln γ)^(−p) with a free exponent p, over the fit points: the limit is a.
    pub fit: Option<PowerLimit>,
    /// The largest change of the limit when the fit drops its smallest or its largest γ.
    pub limit_uncertainty: Option<f64>,
}

/// The fast system against the 3D slip of the scene's cycle.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FastCheck {
    /// v/γ at the start (the first step end of the rise with v/γ ≥ fast_start).
    pub start_v_over_gamma: f64,
    /// t_c − t at the start.
    pub start_time_before_tc: f64,
    /// Bound on the relative size of the neglected drive: 1/v at the start.
    pub neglected_drive: f64,
    /// V_max = v_max/γ of the 3D cycle.
    pub v_max_over_gamma_3d: f64,
    /// V_max of the fast system.
    pub v_max_fast: f64,
    /// Half-width × γ of the 3D cycle (its slip_half_width × γ).
    pub half_width_times_gamma_3d: Option<f64>,
    /// Relative spread of the 3D v_max and half-width over the converged cycles (their
    /// numerical uncertainty).
    pub spread_3d: [f64; 2],
    /// Half-width in T of the fast system.
    pub half_width_fast: Option<f64>,
    /// U and Θ (shifted u and θ) at the fast system's V maximum, and the 3D values mapped.
    pub u_theta_at_v_max_fast: [f64; 2],
    /// The 3D cycle's (u − c_u ln γ, θ − c_θ ln γ) at its v maximum.
    pub u_theta_at_v_max_3d: [f64; 2],
    /// Fast-system steps.
    pub steps: u64,
    /// Figure data (the paper's Fig. 4): T = γ(t − t_c) and V = v/γ.
    pub fig4: Fig4,
}

/// The slip in fast units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig4 {
    /// 3D: T.
    pub t_3d: Vec<f64>,
    /// 3D: V.
    pub v_3d: Vec<f64>,
    /// Fast system: T.
    pub t_fast: Vec<f64>,
    /// Fast system: V.
    pub v_fast: Vec<f64>,
}

/// The "slip_scaling" part of the asymptotics section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlipScalingReport {
    /// c_u = ε/ξ.
    pub c_u: f64,
    /// c_θ = −(1+ε).
    pub c_theta: f64,
    /// Fits use the scan points with γ ≥ this.
    pub fit_min_gamma: f64,
    /// u at the v maximum against ln γ.
    pub u_at_v_max: ShiftFit,
    /// θ at the v maximum against ln γ.
    pub theta_at_v_max: ShiftFit,
    /// Half-width × γ.
    pub half_width: HalfWidthLimit,
    /// The fast system on the scene's slip (f = ln v only).
    pub fast_system: Option<FastCheck>,
    /// Why `fast_system` is null, if it is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fast_system_note: Option<String>,
}

fn shift_fit(
    points: &[(f64, ScanValues)],
    predicted_slope: f64,
    get: fn(&ScanValues) -> f64,
) -> ShiftFit {
    let l: Vec<f64> = points.iter().map(|(g, _)| g.ln()).collect();
    let y: Vec<f64> = points.iter().map(|(_, v)| get(v)).collect();
    ShiftFit {
        predicted_slope,
        linear: least_squares("a + b ln γ", &l, &y, &[&|_| 1.0, &|l| l]),
        with_ln_ln: least_squares(
            "a + b ln γ + d ln ln γ",
            &l,
            &y,
            &[&|_| 1.0, &|l| l, &|l: f64| l.ln()],
        ),
    }
}

fn half_width_limit(points: &[(f64, ScanValues)]) -> HalfWidthLimit {
    let with: Vec<(f64, f64)> =
        points.iter().filter_map(|(g, v)| v.half_width_times_gamma.map(|h| (g.ln(), h))).collect();
    let fit_of = |p: &[(f64, f64)]| {
        let (l, y): (Vec<f64>, Vec<f64>) = p.iter().copied().unzip();
        power_limit("a + b (ln γ)^(−p)", &l, &y)
    };
    let fit = fit_of(&with);
    let n = with.len();
    let limit_uncertainty = fit.as_ref().and_then(|f| {
        let a = fit_of(&with[1..])?.limit;
        let b = fit_of(&with[..n - 1])?.limit;
        Some((a - f.limit).abs().max((b - f.limit).abs()))
    });
    HalfWidthLimit {
        largest_gamma: with.last().map(|(l, _)| l.exp()),
        at_largest_gamma: with.last().map(|(_, h)| *h),
        fit,
        limit_uncertainty,
    }
}

/// Bisection inside the last step for a sign change of g(dense(t, k)).
fn bisect(
    integ: &mut dyn Integrator,
    (mut a, mut b): (f64, f64),
    k: u32,
    g: &dyn Fn(&[f64]) -> f64,
) -> Result<f64, SolverError> {
    let ga = g(integ.dense(a, k)?) > 0.0;
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if (g(integ.dense(m, k)?) > 0.0) == ga {
            a = m;
        } else {
            b = m;
        }
    }
    Ok(0.5 * (a + b))
}

/// The fast system on the scene's cycle; [`AnalysisError::NotApplicable`] when it cannot be
/// started or finds no peak (a note in the report).
fn fast_check(
    orbit: &CyclePeriod,
    params: &DrrParams,
    options: &AsymptoticsOptions,
    half_width_3d: Option<f64>,
    spread_3d: [f64; 2],
) -> Result<FastCheck, AnalysisError> {
    let not_applicable = |reason: String| AnalysisError::NotApplicable { reason };
    let Some(fast) = FastSlip::new(params) else {
        return Err(not_applicable(format!(
            "the fast system needs f = ln v; this scene's friction is {}",
            params.friction.label()
        )));
    };
    let gamma = params.gamma;
    let level = (options.fast_start * gamma).ln();
    let Some(k0) = (orbit.up..orbit.peak).find(|&k| orbit.w[k] >= level) else {
        return Err(not_applicable(format!(
            "the rise has no step end with v/γ ≥ {} before the peak",
            options.fast_start
        )));
    };
    let z0 = fast.to_fast(gamma, &orbit.state(k0));
    let t0 = gamma * orbit.s[k0];
    let mut integ = solver::build_default(
        Method::Radau5,
        fast,
        t0,
        &z0,
        &Options::new(options.rtol, Tolerance::Scalar(options.rtol * 1e-2)),
    )?;
    let mut d0 = [0.0; 3];
    crate::integrate::OdeSystem::rhs(&fast, t0, &z0, &mut d0);
    let mut knots = vec![Knot { t: t0, x: z0[1], dx: d0[1] }];
    let (mut prev_t, mut prev_d) = (t0, d0[1]);
    let mut peak: Option<(f64, [f64; 3])> = None;
    let mut half_fall = None;
    let mut steps = 0;
    while t0 + 200.0 > prev_t {
        let step = integ.advance(prev_t + 1e3, Task::OneStep)?;
        steps += 1;
        let z = integ.state().to_vec();
        let d = integ.dense(step.t, 1)?[1];
        knots.push(Knot { t: step.t, x: z[1], dx: d });
        if peak.is_none() && prev_d > 0.0 && d <= 0.0 {
            let tp = bisect(integ.as_mut(), (prev_t, step.t), 1, &|x| x[1])?;
            let zp = integ.dense(tp, 0)?;
            peak = Some((tp, [zp[0], zp[1], zp[2]]));
        }
        if let Some((tp, zp)) = peak {
            let half = zp[1] - std::f64::consts::LN_2;
            if half_fall.is_none() && z[1] < half {
                let a = prev_t.max(tp);
                half_fall = Some(bisect(integ.as_mut(), (a, step.t), 0, &|x| x[1] - half)?);
            }
            if z[1] < zp[1] - 20f64.ln() {
                break;
            }
        }
        prev_t = step.t;
        prev_d = d;
    }
    let Some((_, zp)) = peak else {
        return Err(not_applicable("the fast system reached no V maximum within T = 200".into()));
    };
    // The rising half-maximum crossing, located between stored step ends (the peak was
    // unknown then) on the cubic Hermite interpolant of W, as the cycle analysis does.
    let half = zp[1] - std::f64::consts::LN_2;
    let half_rise = events::last_upward_crossing(&knots, half);
    let (cu, ct) = shifts(params.xi, params.epsilon);
    let l = gamma.ln();
    let idx3: Vec<usize> = (k0..=orbit.down).collect();
    let t3: Vec<f64> = idx3.iter().map(|&k| gamma * orbit.s[k]).collect();
    let v3: Vec<f64> = idx3.iter().map(|&k| orbit.w[k].exp() / gamma).collect();
    let keep3 = decimate(&t3, &[&v3], options.series_points);
    let tf: Vec<f64> = knots.iter().map(|k| k.t).collect();
    let vf: Vec<f64> = knots.iter().map(|k| k.x.exp()).collect();
    let keepf = decimate(&tf, &[&vf], options.series_points);
    Ok(FastCheck {
        start_v_over_gamma: orbit.w[k0].exp() / gamma,
        start_time_before_tc: -orbit.s[k0],
        neglected_drive: (-orbit.w[k0]).exp(),
        v_max_over_gamma_3d: orbit.w[orbit.peak].exp() / gamma,
        v_max_fast: zp[1].exp(),
        half_width_times_gamma_3d: half_width_3d,
        spread_3d,
        half_width_fast: half_rise.zip(half_fall).map(|(r, f)| f - r),
        u_theta_at_v_max_fast: [zp[0], zp[2]],
        u_theta_at_v_max_3d: [orbit.u[orbit.peak] - cu * l, orbit.theta[orbit.peak] - ct * l],
        steps,
        fig4: Fig4 {
            t_3d: pick(&t3, &keep3),
            v_3d: pick(&v3, &keep3),
            t_fast: pick(&tf, &keepf),
            v_fast: pick(&vf, &keepf),
        },
    })
}

/// The slip-scaling analysis: fits over the scan's periodic points with γ ≥ fit_min_gamma
/// (increasing γ), and the fast system on the scene's cycle (if there is one); `half_width_3d`
/// and `spread_3d` (relative spreads of v_max and the half-width) come from the scene's cycle.
pub fn analyse(
    points: &[(f64, ScanValues)],
    orbit: Option<&CyclePeriod>,
    params: &DrrParams,
    options: &AsymptoticsOptions,
    half_width_3d: Option<f64>,
    spread_3d: [f64; 2],
) -> Result<SlipScalingReport, AnalysisError> {
    let (c_u, c_theta) = shifts(params.xi, params.epsilon);
    let (fast_system, fast_system_note) = match orbit {
        Some(o) => match fast_check(o, params, options, half_width_3d, spread_3d) {
            Ok(f) => (Some(f), None),
            Err(why) => (None, Some(why.into_note()?)),
        },
        None => (None, Some("no periodic cycle of the scene".into())),
    };
    Ok(SlipScalingReport {
        c_u,
        c_theta,
        fit_min_gamma: options.fit_min_gamma,
        u_at_v_max: shift_fit(points, c_u, |v| v.extremes.u_at_v_max),
        theta_at_v_max: shift_fit(points, c_theta, |v| v.extremes.theta_at_v_max),
        half_width: half_width_limit(points),
        fast_system,
        fast_system_note,
    })
}
