//! Matching the stick and the slip (the paper's section "matching slow and fast solutions"):
//! the curves θ(u) = c e^{εu} − K(1 + εu) fitted to the 3D cycle where 1 ≪ v and the cycle is
//! on S, before and after the catastrophe; their residuals; the finite-time condition c < 0
//! and the blow-up time ∫ e^{−Φ(u)} du it predicts; the zero-acceleration line (ours, derived,
//! beside the paper's printed formula), the adiabatic limit θ = −ξu − ln γ, and the data of
//! the paper's Fig. 3b.
//!
//! Zero acceleration. On S with u' = v (the matching regime), v = e^{−(ξu+θ)} gives
//! dv/dt = −v (ξ u' + θ') = −v² [ξ + εθ + (1+ε)ξu], so the line is εθ = −(1+ε)ξu − ξ. The
//! paper prints εθ = (1+ε)u − ξ (eq. acc0) after the bracket [ξ − εθ − (1+ε)u], which differ
//! from each other and from the derivation; both are reported and tested on the cycle.
//! θ is extremal on S where εθ + (1+ε)ξu = 0 (dθ/dt = v[εθ + (1+ε)ξu]).

use super::AsymptoticsOptions;
use crate::model::slow_manifold::{matching_k, matching_theta, phi, SlowFlow};
use crate::model::DrrParams;
use crate::numerics::series::{decimate, pick};
use crate::paper::cycle_period::CyclePeriod;
use serde::Serialize;

/// A straight line θ = intercept + slope·u in the (u, θ) plane.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Line {
    /// The equation, in words.
    pub equation: String,
    /// θ at u = 0.
    pub intercept: f64,
    /// dθ/du.
    pub slope: f64,
}

impl Line {
    fn at(&self, u: f64) -> f64 {
        self.intercept + self.slope * u
    }
}

/// One fitted branch of the matching curve: the contiguous stretch of the cycle with v ≥
/// matching_v_min on S (before: from the rise's crossing of matching_v_min to where the cycle
/// leaves S; after: from where the descent is back on S to its crossing of matching_v_min).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Branch {
    /// The fitted constant c (least squares in θ over the window).
    pub c: f64,
    /// Samples of the 3D cycle in the window.
    pub points: usize,
    /// u range of the window.
    pub u_range: [f64; 2],
    /// v range of the window.
    pub v_range: [f64; 2],
    /// t_c − t range of the window.
    pub time_before_tc_range: [f64; 2],
    /// RMS of θ₃ − θ_match(u₃) over the window.
    pub residual_rms: f64,
    /// Largest |θ₃ − θ_match(u₃)| over the window.
    pub residual_max: f64,
}

/// The blow-up of the matching solution u' = e^{Φ(u)} with the fitted c of the branch before
/// the catastrophe, started at the window's first sample.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PredictedBlowUp {
    /// t_c − t at the start (the window's first sample).
    pub from_time_before_tc: f64,
    /// u at the start.
    pub u_start: f64,
    /// ∫_{u_start}^∞ e^{−Φ(u)} du (adaptive Simpson).
    pub integral: f64,
    /// Predicted blow-up time minus the 3D v maximum t_c.
    pub offset_from_tc: f64,
}

/// Distances (θ − line(u)) of the cycle's two θ extrema from a line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExtremaDistance {
    /// Which line.
    pub line: String,
    /// At the θ maximum.
    pub at_theta_max: f64,
    /// At the θ minimum.
    pub at_theta_min: f64,
}

/// The (u, θ) plane of the paper's Fig. 3b.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig3b {
    /// The 3D cycle: u.
    pub cycle_u: Vec<f64>,
    /// The 3D cycle: θ.
    pub cycle_theta: Vec<f64>,
    /// The 2D flow on S from the start to its blow-up (cut where θ leaves the plot): u.
    pub slow_u: Vec<f64>,
    /// The 2D flow: θ.
    pub slow_theta: Vec<f64>,
    /// Matching curve with c before the catastrophe: u.
    pub before_u: Vec<f64>,
    /// Matching curve before: θ.
    pub before_theta: Vec<f64>,
    /// Matching curve with c after the catastrophe: u.
    pub after_u: Vec<f64>,
    /// Matching curve after: θ.
    pub after_theta: Vec<f64>,
    /// The u interval [u_min, u_max] of the cycle, to draw the lines of `lines`.
    pub u_span: [f64; 2],
}

/// The "matching" part of the asymptotics section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MatchingReport {
    /// K = (1+ε)ξ/ε².
    pub k: f64,
    /// Window: v ≥ this (1 ≪ v).
    pub window_v_min: f64,
    /// Window: |ln v − ln v_S(u, θ)| ≤ this (on S).
    pub window_manifold_tolerance: f64,
    /// Branch fitted on the rise (before the catastrophe).
    pub before: Option<Branch>,
    /// Branch fitted after the v maximum.
    pub after: Option<Branch>,
    /// Largest v at which the descent after the v maximum is back on S (null if it never is
    /// before v = 1): the after-branch exists only if this reaches window_v_min.
    pub descent_on_manifold_v_max: Option<f64>,
    /// Blow-up predicted from the branch before (f = ln v only: Φ is ln v on the curve).
    pub predicted_blow_up: Option<PredictedBlowUp>,
    /// Lines of Fig. 3b: zero acceleration (derived; the same for every friction law), the
    /// paper's printed zero-acceleration line, the line of θ extrema on S, and the adiabatic
    /// limit v = γ on S, θ = −ξu − f(γ).
    pub lines: Vec<Line>,
    /// The cycle's θ maximum (u, θ).
    pub theta_max_point: [f64; 2],
    /// The cycle's θ minimum (u, θ).
    pub theta_min_point: [f64; 2],
    /// θ range of the cycle (θ_max − θ_min), the scale for the distances below.
    pub theta_range: f64,
    /// Distances of the θ extrema from each line.
    pub extrema_distances: Vec<ExtremaDistance>,
    /// Figure data.
    pub fig3b: Fig3b,
}

/// Indices of the lines in `MatchingReport::lines`.
pub const ZERO_ACCELERATION: usize = 0;
/// The paper's printed zero-acceleration line.
pub const PAPER_ZERO_ACCELERATION: usize = 1;
/// The line of θ extrema on S.
pub const THETA_EXTREMA: usize = 2;
/// The adiabatic limit.
pub const ADIABATIC: usize = 3;

fn fit_branch(orbit: &CyclePeriod, params: &DrrParams, idx: &[usize]) -> Option<Branch> {
    if idx.is_empty() {
        return None;
    }
    let (xi, e) = (params.xi, params.epsilon);
    let k = matching_k(xi, e);
    let (mut num, mut den) = (0.0, 0.0);
    for &i in idx {
        let ex = (e * orbit.u[i]).exp();
        num += (orbit.theta[i] + k * (1.0 + e * orbit.u[i])) * ex;
        den += ex * ex;
    }
    let c = num / den;
    let res: Vec<f64> =
        idx.iter().map(|&i| orbit.theta[i] - matching_theta(xi, e, c, orbit.u[i])).collect();
    let range = |f: &dyn Fn(usize) -> f64| {
        idx.iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &i| [lo.min(f(i)), hi.max(f(i))])
    };
    Some(Branch {
        c,
        points: idx.len(),
        u_range: range(&|i| orbit.u[i]),
        v_range: range(&|i| orbit.w[i].exp()),
        time_before_tc_range: range(&|i| -orbit.s[i]),
        residual_rms: (res.iter().map(|r| r * r).sum::<f64>() / res.len() as f64).sqrt(),
        residual_max: res.iter().fold(0.0, |m, r| m.max(r.abs())),
    })
}

/// ∫_a^b f by adaptive Simpson to an absolute tolerance (or the arithmetic's resolution on
/// each interval, whichever is larger); None if f is not finite or 1e7 intervals do not
/// suffice.
fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> Option<f64> {
    let rule = |a: f64, fa: f64, b: f64, fb: f64| {
        let m = 0.5 * (a + b);
        let fm = f(m);
        (m, fm, (b - a) / 6.0 * (fa + 4.0 * fm + fb))
    };
    let (fa, fb) = (f(a), f(b));
    let (m, fm, whole) = rule(a, fa, b, fb);
    let mut stack = vec![(a, fa, b, fb, m, fm, whole, tol)];
    let (mut total, mut intervals) = (0.0, 0u32);
    while let Some((a, fa, b, fb, m, fm, whole, tol)) = stack.pop() {
        intervals += 1;
        let (lm, flm, left) = rule(a, fa, m, fm);
        let (rm, frm, right) = rule(m, fm, b, fb);
        let delta = left + right - whole;
        if !delta.is_finite() || intervals > 10_000_000 {
            return None;
        }
        // Converged, or at the resolution of the arithmetic (|delta| is then rounding).
        let rounding = 64.0 * f64::EPSILON * (left.abs() + right.abs());
        if delta.abs() <= (15.0 * tol).max(rounding) {
            total += left + right + delta / 15.0;
        } else {
            stack.push((a, fa, m, fm, lm, flm, left, 0.5 * tol));
            stack.push((m, fm, b, fb, rm, frm, right, 0.5 * tol));
        }
    }
    Some(total)
}

/// ∫_{u0}^∞ e^{−Φ(u)} du: the time the matching solution u' = e^{Φ(u)} takes from u0 to its
/// blow-up. None if c > 0 (Φ eventually decreases: no blow-up) or the quadrature fails. For
/// c ≤ 0, Φ increases monotonically and the integral converges (for c = 0 too:
/// u' = e^{(ξ/ε)u + K}).
pub fn blow_up_integral(xi: f64, epsilon: f64, c: f64, u0: f64) -> Option<f64> {
    if c > 0.0 {
        return None;
    }
    let p0 = phi(xi, epsilon, c, u0);
    let f = |u: f64| (-(phi(xi, epsilon, c, u) - p0)).exp();
    let mut span = 1.0;
    while phi(xi, epsilon, c, u0 + span) - p0 < 700.0 {
        span *= 2.0;
    }
    // First a coarse estimate (the integrand is at most 1 and decreasing) for the tolerance.
    let scale = simpson(&f, u0, u0 + span, 1e-6 * span)?;
    Some((-p0).exp() * simpson(&f, u0, u0 + span, 1e-14 * scale)?)
}

/// The matching analysis of one cycle. `slow_samples` are the 2D flow's (t − t_c, u, θ, ln v).
pub fn analyse(
    orbit: &CyclePeriod,
    params: &DrrParams,
    options: &AsymptoticsOptions,
    slow_samples: &[[f64; 4]],
) -> MatchingReport {
    let (xi, e, gamma) = (params.xi, params.epsilon, params.gamma);
    let flow = SlowFlow::new(*params);
    let ln_v_min = options.matching_v_min.ln();
    let on_manifold = |k: usize| {
        flow.w(orbit.u[k], orbit.theta[k])
            .is_some_and(|ws| (orbit.w[k] - ws).abs() <= options.manifold_tolerance)
    };
    // Before: the stretch of the rise from v = matching_v_min to where the cycle first leaves S.
    // After: the stretch of the descent on S that ends where v falls below matching_v_min. (The
    // v maximum itself lies on S, dv/dt = 0, but not in the matching regime.)
    let before_idx: Vec<usize> = (orbit.up..=orbit.peak)
        .skip_while(|&k| orbit.w[k] < ln_v_min)
        .take_while(|&k| on_manifold(k))
        .collect();
    let end = (orbit.peak..orbit.down).find(|&k| orbit.w[k] < ln_v_min).unwrap_or(orbit.down);
    let mut after_idx: Vec<usize> =
        (orbit.peak + 1..end).rev().take_while(|&k| on_manifold(k)).collect();
    after_idx.reverse();
    // The descent's last stretch on S before v = 1 (the v maximum itself is on S too).
    let descent_on_manifold_v_max = (orbit.peak + 1..orbit.down)
        .rev()
        .take_while(|&k| on_manifold(k))
        .map(|k| orbit.w[k].exp())
        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))));
    let before = fit_branch(orbit, params, &before_idx);
    let after = fit_branch(orbit, params, &after_idx);
    // Φ(u) = ln v on the matching curve holds for f = ln v only.
    let log_law = params.friction == crate::model::Friction::Log;
    let predicted_blow_up = before.as_ref().filter(|_| log_law).and_then(|b| {
        let first = before_idx[0];
        blow_up_integral(xi, e, b.c, orbit.u[first]).map(|integral| PredictedBlowUp {
            from_time_before_tc: -orbit.s[first],
            u_start: orbit.u[first],
            integral,
            offset_from_tc: orbit.s[first] + integral,
        })
    });
    let lines = vec![
        Line { equation: "zero acceleration on S (derived, v ≫ 1): εθ = −(1+ε)ξu − ξ".into(), intercept: -xi / e, slope: -(1.0 + e) * xi / e },
        Line { equation: "zero acceleration as printed in the paper (eq. acc0): εθ = (1+ε)u − ξ".into(), intercept: -xi / e, slope: (1.0 + e) / e },
        Line { equation: "θ extremal on S: εθ = −(1+ε)ξu".into(), intercept: 0.0, slope: -(1.0 + e) * xi / e },
        Line { equation: "adiabatic limit (eq. limitadiab): v = γ on S, θ = −ξu − f(γ) (= −ξu − ln γ for f = ln v)".into(), intercept: -params.friction.eval(gamma.ln()).0, slope: -xi },
    ];
    let n = orbit.len();
    let imax = (0..n).fold(0, |b, i| if orbit.theta[i] > orbit.theta[b] { i } else { b });
    let imin = (0..n).fold(0, |b, i| if orbit.theta[i] < orbit.theta[b] { i } else { b });
    let theta_max_point = [orbit.u[imax], orbit.theta[imax]];
    let theta_min_point = [orbit.u[imin], orbit.theta[imin]];
    let extrema_distances = lines
        .iter()
        .map(|l| ExtremaDistance {
            line: l.equation.clone(),
            at_theta_max: theta_max_point[1] - l.at(theta_max_point[0]),
            at_theta_min: theta_min_point[1] - l.at(theta_min_point[0]),
        })
        .collect();

    // Figure 3b.
    let (u_lo, u_hi) =
        orbit.u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &u| (a.min(u), b.max(u)));
    let theta_range = orbit.theta[imax] - orbit.theta[imin];
    let (th_lo, th_hi) =
        (orbit.theta[imin] - 0.5 * theta_range, orbit.theta[imax] + 0.5 * theta_range);
    let keep = decimate(&orbit.u, &[&orbit.theta], options.series_points);
    let curve = |c: Option<f64>| -> (Vec<f64>, Vec<f64>) {
        let Some(c) = c else { return (vec![], vec![]) };
        let m = options.series_points.min(400);
        let du = u_hi - u_lo;
        (0..m)
            .map(|i| u_lo - 0.1 * du + 1.2 * du * i as f64 / (m - 1) as f64)
            .map(|u| (u, matching_theta(xi, e, c, u)))
            .filter(|(_, th)| (th_lo..=th_hi).contains(th))
            .unzip()
    };
    let (before_u, before_theta) = curve(before.as_ref().map(|b| b.c));
    let (after_u, after_theta) = curve(after.as_ref().map(|b| b.c));
    let slow: Vec<&[f64; 4]> = slow_samples
        .iter()
        .take_while(|x| (th_lo..=th_hi).contains(&x[2]) && x[1] <= u_hi + 0.1 * (u_hi - u_lo))
        .collect();
    let su: Vec<f64> = slow.iter().map(|x| x[1]).collect();
    let sth: Vec<f64> = slow.iter().map(|x| x[2]).collect();
    let keep_slow = decimate(&su, &[&sth], options.series_points);
    MatchingReport {
        k: matching_k(xi, e),
        window_v_min: options.matching_v_min,
        window_manifold_tolerance: options.manifold_tolerance,
        before,
        after,
        descent_on_manifold_v_max,
        predicted_blow_up,
        lines,
        theta_max_point,
        theta_min_point,
        theta_range,
        extrema_distances,
        fig3b: Fig3b {
            cycle_u: pick(&orbit.u, &keep),
            cycle_theta: pick(&orbit.theta, &keep),
            slow_u: pick(&su, &keep_slow),
            slow_theta: pick(&sth, &keep_slow),
            before_u,
            before_theta,
            after_u,
            after_theta,
            u_span: [u_lo, u_hi],
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blow_up_integral_matches_closed_forms() {
        // c = 0: ∫ e^{−(a u + K)} du from u0 = e^{−(a u0 + K)}/a, a = ξ/ε.
        let (xi, e) = (0.7, 0.72);
        let (a, k) = (xi / e, matching_k(xi, e));
        let u0 = 0.3;
        let exact = (-(a * u0 + k)).exp() / a;
        let got = blow_up_integral(xi, e, 0.0, u0).unwrap();
        assert!((got - exact).abs() < 1e-12 * exact, "{got} vs {exact}");
        // c < 0 against a fine trapezoid sum; c > 0 has no blow-up.
        let c = -0.4;
        let h = 1e-6;
        let mut sum = 0.0;
        let mut u = u0;
        while u < u0 + 20.0 {
            sum += 0.5 * h * ((-phi(xi, e, c, u)).exp() + (-phi(xi, e, c, u + h)).exp());
            u += h;
        }
        let got = blow_up_integral(xi, e, c, u0).unwrap();
        assert!((got - sum).abs() < 1e-9 * sum, "{got} vs {sum}");
        assert!(blow_up_integral(xi, e, 0.1, u0).is_none());
    }
}
