//! Locating events inside the last step from the integrator's dense output, and between
//! stored step ends by cubic Hermite interpolation.

use crate::integrate::{Clock, Integrator, SolverError};

/// The state (its first three components) at the end of the step the clock just took to local
/// time `t`, and its time derivative from the integrator's dense output.
pub fn step_end(clock: &mut Clock<'_>, t: f64) -> Result<([f64; 3], [f64; 3]), SolverError> {
    let y = clock.state();
    let y = [y[0], y[1], y[2]];
    let d = clock.integrator().dense(t, 1)?;
    Ok((y, [d[0], d[1], d[2]]))
}

/// Finds t in [a, b] (inside the integrator's last step) where component `index` of the k-th
/// derivative of the interpolant equals `level`, given that it changes sign across [a, b].
/// Illinois (modified regula falsi), to a few ulps of t.
pub fn refine(
    integ: &mut dyn Integrator,
    (a, b): (f64, f64),
    k: u32,
    index: usize,
    level: f64,
) -> Result<f64, SolverError> {
    let mut phi = |t: f64| -> Result<f64, SolverError> { Ok(integ.dense(t, k)?[index] - level) };
    let (mut ta, mut tb) = (a, b);
    let (mut fa, mut fb) = (phi(ta)?, phi(tb)?);
    if fa == 0.0 {
        return Ok(ta);
    }
    if fb == 0.0 || fa.signum() == fb.signum() {
        return Ok(tb);
    }
    let mut side = 0i8;
    for _ in 0..200 {
        let width = tb - ta;
        if width.abs() <= 4.0 * f64::EPSILON * ta.abs().max(tb.abs()) + f64::MIN_POSITIVE {
            break;
        }
        let mut t = tb - fb * width / (fb - fa);
        // Keep the secant point strictly inside; fall back to bisection if it is not.
        if !(t > ta.min(tb) && t < ta.max(tb)) {
            t = 0.5 * (ta + tb);
        }
        let f = phi(t)?;
        if f == 0.0 {
            return Ok(t);
        }
        if f.signum() == fb.signum() {
            tb = t;
            fb = f;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            ta = t;
            fa = f;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    Ok(if fa.abs() < fb.abs() { ta } else { tb })
}

/// A point (t, x, dx/dt) of a scalar signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knot {
    /// Time.
    pub t: f64,
    /// Value.
    pub x: f64,
    /// Time derivative.
    pub dx: f64,
}

/// The cubic Hermite interpolant between two knots, evaluated at t.
pub fn hermite(a: Knot, b: Knot, t: f64) -> f64 {
    let h = b.t - a.t;
    let s = (t - a.t) / h;
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * a.x
        + (s3 - 2.0 * s2 + s) * h * a.dx
        + (-2.0 * s3 + 3.0 * s2) * b.x
        + (s3 - s2) * h * b.dx
}

/// The last upward crossing of `level` in `knots`, located on the cubic Hermite
/// interpolant by bisection; None if there is none.
pub fn last_upward_crossing(knots: &[Knot], level: f64) -> Option<f64> {
    let i = knots.windows(2).rposition(|k| k[0].x < level && k[1].x >= level)?;
    let (a, b) = (knots[i], knots[i + 1]);
    let (mut lo, mut hi) = (a.t, b.t);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if hermite(a, b, mid) < level {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_is_exact_for_cubics() {
        let f = |t: f64| t * t * t - 2.0 * t + 0.5;
        let df = |t: f64| 3.0 * t * t - 2.0;
        let (a, b) =
            (Knot { t: 0.3, x: f(0.3), dx: df(0.3) }, Knot { t: 1.7, x: f(1.7), dx: df(1.7) });
        for t in [0.3, 0.8, 1.1, 1.7] {
            assert!((hermite(a, b, t) - f(t)).abs() < 1e-14);
        }
    }

    #[test]
    fn last_upward_crossing_of_a_sampled_sine() {
        let knots: Vec<Knot> = (0..40)
            .map(|i| {
                let t = -1.0 + 0.1 * i as f64;
                Knot { t, x: t.sin(), dx: t.cos() }
            })
            .collect();
        let t = last_upward_crossing(&knots, 0.5).unwrap();
        assert!((t - 0.5f64.asin()).abs() < 1e-6, "{t}");
        assert!(last_upward_crossing(&knots, 2.0).is_none());
    }
}
