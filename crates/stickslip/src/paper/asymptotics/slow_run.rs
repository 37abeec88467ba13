//! Integrates the 2D slow flow (in its arc parameter, see [`crate::model::slow_manifold`]) from
//! a point of S to its finite-time blow-up, locating the upward crossing of v = 1 and
//! evaluating the flow at given times (the 3D samples) from the integrator's dense output.

use crate::analysis::AnalysisError;
use crate::integrate::{Integrator, SolverError, Task};
use crate::model::slow_manifold::{SlowFlow, T, THETA, U};

/// The outcome of one run of the 2D flow.
#[derive(Debug, Clone, PartialEq)]
pub struct SlowRun {
    /// Samples (t, u, θ, ln v): every step end plus three dense-output points inside each step.
    pub samples: Vec<[f64; 4]>,
    /// Time of the first upward crossing of v = 1 (None if v started above 1 or never reached it).
    pub t_up: Option<f64>,
    /// The blow-up time t_c (None if v did not blow up within `max_time`).
    pub t_c: Option<f64>,
    /// The bound on ∫ dt left after the last step, added to t_c.
    pub tail: Option<f64>,
    /// The state (u, θ, ln v) at each probe time (None past the blow-up or the end).
    pub probes: Vec<Option<[f64; 3]>>,
    /// Integrator steps.
    pub steps: u64,
}

fn w_of(flow: &SlowFlow, y: &[f64]) -> f64 {
    flow.w(y[U], y[THETA]).unwrap_or(f64::NAN)
}

/// Finds s in [a, b] (inside the last step) where `g(dense(s))` changes sign, by bisection.
fn bisect(
    integ: &mut dyn Integrator,
    (mut a, mut b): (f64, f64),
    g: &dyn Fn(&[f64]) -> f64,
) -> Result<f64, SolverError> {
    let mut ga = g(integ.dense(a, 0)?);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let gm = g(integ.dense(m, 0)?);
        if (gm > 0.0) == (ga > 0.0) {
            a = m;
            ga = gm;
        } else {
            b = m;
        }
    }
    Ok(0.5 * (a + b))
}

/// Runs the 2D flow from the integrator's current state (t, u, θ) at arc parameter s = its
/// t(). Stops at the blow-up — when v > 1e6 and the remaining time, bounded by
/// 1/(v · d ln v/ds) (d ln v/ds grows on the blow-up), is below 1e-16 of |t| — or after
/// `max_time` of t. `probe_times` must be increasing.
pub fn run(
    integ: &mut dyn Integrator,
    flow: &SlowFlow,
    max_time: f64,
    probe_times: &[f64],
) -> Result<SlowRun, AnalysisError> {
    let y = integ.state().to_vec();
    let t_start = y[T];
    let mut prev = (integ.t(), y);
    let mut out = SlowRun {
        samples: vec![],
        t_up: None,
        t_c: None,
        tail: None,
        probes: vec![None; probe_times.len()],
        steps: 0,
    };
    let w0 = w_of(flow, &prev.1);
    out.samples.push([prev.1[T], prev.1[U], prev.1[THETA], w0]);
    let mut next_probe =
        probe_times.iter().position(|&t| t >= t_start).unwrap_or(probe_times.len());
    loop {
        let step = integ.advance(prev.0 + 1e6, Task::OneStep)?;
        out.steps += 1;
        let y = integ.state().to_vec();
        let w = w_of(flow, &y);
        if !(w.is_finite() && y.iter().all(|x| x.is_finite())) {
            return Err(AnalysisError::Failed {
                analysis: "the 2D slow flow",
                t: y[T],
                state: y,
                message: "it left the slow manifold's domain (no v with f(v) = −(ξu + θ))".into(),
            });
        }
        let span = (prev.0, step.t);
        // Dense points inside the step, for figures.
        for k in 1..4 {
            let s = span.0 + (span.1 - span.0) * k as f64 / 4.0;
            let d = integ.dense(s, 0)?.to_vec();
            out.samples.push([d[T], d[U], d[THETA], w_of(flow, &d)]);
        }
        out.samples.push([y[T], y[U], y[THETA], w]);
        if out.t_up.is_none() && w_of(flow, &prev.1) < 0.0 && w >= 0.0 {
            let s = bisect(integ, span, &|d| w_of(flow, d))?;
            out.t_up = Some(integ.dense(s, 0)?[T]);
        }
        while next_probe < probe_times.len() && probe_times[next_probe] <= y[T] {
            let target = probe_times[next_probe];
            let s = bisect(integ, span, &|d| d[T] - target)?;
            let d = integ.dense(s, 0)?.to_vec();
            out.probes[next_probe] = Some([d[U], d[THETA], w_of(flow, &d)]);
            next_probe += 1;
        }
        // Blow-up: d ln v/ds from the flow, dt/ds = q; the tail ∫ q ds ≤ q/(d ln v/ds).
        let mut dy = [0.0; 3];
        crate::integrate::OdeSystem::rhs(flow, step.t, &y, &mut dy);
        let (_, vfp) = flow.params().friction.eval(w);
        let dw_ds = -(flow.params().xi * dy[U] + dy[THETA]) / vfp;
        if w > 1e6f64.ln() && dw_ds > 0.0 {
            let tail = dy[T] / dw_ds;
            if tail <= 1e-16 * y[T].abs().max(1.0) {
                out.t_c = Some(y[T] + tail);
                out.tail = Some(tail);
                return Ok(out);
            }
        }
        if y[T] - t_start > max_time {
            return Ok(out);
        }
        prev = (step.t, y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::{Options, Radau5, Tolerance};
    use crate::model::slow_manifold::{matching_c, phi};
    use crate::model::{DrrParams, Friction};

    fn flow() -> SlowFlow {
        SlowFlow::new(DrrParams::new(1e3, 0.7, 0.72, Friction::Log))
    }

    fn radau(y0: [f64; 3]) -> Radau5<SlowFlow> {
        Radau5::new(flow(), 0.0, &y0, &Options::new(1e-12, Tolerance::Scalar(1e-13))).unwrap()
    }

    /// ∫_u^∞ e^{−Φ} du by the trapezoid rule on a fine grid (the integrand decays
    /// double-exponentially).
    fn matching_time(c: f64, u0: f64) -> f64 {
        let (xi, e) = (0.7, 0.72);
        let h = 1e-5;
        let mut sum = 0.5 * (-phi(xi, e, c, u0)).exp();
        let mut u = u0 + h;
        loop {
            let f = (-phi(xi, e, c, u)).exp();
            sum += f;
            if f < 1e-30 {
                break;
            }
            u += h;
        }
        sum * h
    }

    #[test]
    fn blows_up_in_finite_time_when_c_is_negative_and_not_when_positive() {
        let (xi, e) = (0.7, 0.72);
        // Starts far out on S (v = e^9): the flow is the matching flow up to the −1 of du/dt.
        for c in [-0.05, -0.5, -3.0] {
            let u0: f64 = 2.0;
            let theta0 = crate::model::slow_manifold::matching_theta(xi, e, c, u0);
            let v0 = (-(xi * u0 + theta0)).exp();
            assert!(v0 > 10.0, "start with v ≫ 1 ({v0})");
            let run = run(&mut radau([0.0, u0, theta0]), &flow(), 100.0, &[]).unwrap();
            let t_c = run.t_c.expect("finite-time blow-up for c < 0");
            let predicted = matching_time(matching_c(xi, e, u0, theta0), u0);
            // The matching flow neglects the −1 in du/dt: relative error O(1/v0).
            // (plus the integration's absolute tolerance on t, 1e-13 per step)
            assert!(
                (t_c - predicted).abs() < 2.0 * predicted / v0 + 1e-11,
                "c = {c}: t_c {t_c} vs ∫e^−Φ {predicted} (v0 {v0})"
            );
        }
        // c > K e^{−εu} > 0 (c then grows, dc/dt = ε(c − K e^{−εu}) on the 2D flow): θ outruns
        // −ξu, v falls from e^{4.4} below 1 and there is no blow-up.
        let (u0, c) = (6.0, 0.05);
        assert!(c > crate::model::slow_manifold::matching_k(xi, e) * (-e * u0).exp());
        let theta0 = crate::model::slow_manifold::matching_theta(xi, e, c, u0);
        assert!(-(xi * u0 + theta0) > 4.0);
        let run = run(&mut radau([0.0, u0, theta0]), &flow(), 3.0, &[]).unwrap();
        assert!(run.t_c.is_none());
        assert!(run.samples.last().unwrap()[3] < 0.0, "v fell below 1");
    }

    #[test]
    fn probes_and_the_upward_crossing_follow_the_dense_output() {
        // Start below v = 1 on the stick of Fig. 1's cycle (its v minimum).
        let y0 = [0.0, 9.123245362467106, -3.841465412610634];
        let probes = [1.0, 5.0, 10.0];
        let r = run(&mut radau(y0), &flow(), 100.0, &probes).unwrap();
        let t_up = r.t_up.unwrap();
        let t_c = r.t_c.unwrap();
        assert!(t_up > 10.0 && t_c > t_up && t_c - t_up < 2.0, "t_up {t_up}, t_c {t_c}");
        // Each probe agrees with an independent integrator (CVODE BDF) on the same flow.
        let options = Options::new(1e-12, Tolerance::Scalar(1e-13));
        let settings = crate::sundials::CvodeSettings {
            method: crate::sundials::CvodeMethod::Bdf,
            stability_limit_detection: false,
        };
        let mut cvode =
            crate::sundials::Solver::cvode(flow(), settings, 0.0, &y0, &options).unwrap();
        let other = run(&mut cvode, &flow(), 100.0, &probes).unwrap();
        for (a, b) in r.probes.iter().zip(&other.probes) {
            let (a, b) = (a.unwrap(), b.unwrap());
            assert!(
                (0..3).all(|i| (a[i] - b[i]).abs() < 1e-8 * (1.0 + a[i].abs())),
                "{a:?} vs {b:?}"
            );
        }
        assert!((other.t_c.unwrap() - t_c).abs() < 1e-8 * t_c, "{} vs {t_c}", other.t_c.unwrap());
        assert!((other.t_up.unwrap() - t_up).abs() < 1e-8 * t_up);
    }
}
