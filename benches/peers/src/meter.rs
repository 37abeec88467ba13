//! The cycle measurement of the work-precision benchmark, written on what a peer crate offers:
//! its accepted step ends and its dense output inside the last step.
//!
//! - An upward crossing of v = 1 is a sign change of w from < 0 to ≥ 0 between step ends,
//!   located on the crate's interpolant by the Illinois method (as stickslip's engine does on
//!   its integrators' dense output).
//! - A maximum of v is a sign change of the model's dw/dt from > 0 to ≤ 0 between step ends,
//!   located as a root of dw/dt along the interpolant (dw/dt = f_w(y(t)), the model's
//!   right-hand side at the interpolated state; inside a slip it is well conditioned).
//!   stickslip's engine instead uses the derivative of its integrators' interpolant.
//! - A cycle runs from one upward crossing to the next; its t0 is the time from the crossing to
//!   its highest maximum of v with v > 1, its ln v_max the value there.

use crate::model::{Drr, W};

/// The means over the measured cycles.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// Mean period.
    pub period: f64,
    /// Mean time from the upward crossing of v = 1 to the v maximum.
    pub t0: f64,
    /// Mean ln v_max.
    pub ln_v_max: f64,
}

/// Collects crossings and maxima from successive step ends.
pub struct Meter {
    drr: Drr,
    prev: Option<(f64, [f64; 3], f64)>,
    crossings: Vec<f64>,
    maxima: Vec<(f64, f64)>,
}

/// The root of g in [a, b] (g(a) and g(b) of opposite signs, or g(b) = 0) by the Illinois
/// method, to the resolution of t.
fn illinois(
    mut g: impl FnMut(f64) -> Result<f64, String>,
    (mut a, mut b): (f64, f64),
    (mut ga, mut gb): (f64, f64),
) -> Result<f64, String> {
    let mut side = 0;
    for _ in 0..200 {
        if gb == 0.0 {
            return Ok(b);
        }
        if ga == 0.0 {
            return Ok(a);
        }
        let mut t = b - gb * (b - a) / (gb - ga);
        if !(t > a.min(b) && t < a.max(b)) {
            t = 0.5 * (a + b);
        }
        if (b - a).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs()) {
            return Ok(t);
        }
        let gt = g(t)?;
        if (gt > 0.0) == (gb > 0.0) {
            b = t;
            gb = gt;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            a = t;
            ga = gt;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
    }
    Ok(0.5 * (a + b))
}

impl Meter {
    /// A meter for the model `drr`.
    pub fn new(drr: Drr) -> Self {
        Self { drr, prev: None, crossings: Vec::new(), maxima: Vec::new() }
    }

    /// One accepted step ending at (t, y); `dense(s)` is the crate's interpolant at s inside
    /// the step. The first call gives the initial point (no step).
    pub fn step(
        &mut self,
        t: f64,
        y: [f64; 3],
        mut dense: impl FnMut(f64) -> Result<[f64; 3], String>,
    ) -> Result<(), String> {
        if y.iter().any(|v| !v.is_finite()) {
            return Err(format!("non-finite state {y:?} at t = {t}"));
        }
        let dw = self.drr.dw(&y);
        if let Some((a, ya, dwa)) = self.prev {
            if ya[W] < 0.0 && y[W] >= 0.0 {
                let c = illinois(|s| dense(s).map(|z| z[W]), (a, t), (ya[W], y[W]))?;
                self.crossings.push(c);
            }
            if dwa > 0.0 && dw <= 0.0 && ya[W].max(y[W]) > 0.0 {
                let drr = self.drr;
                let p = illinois(|s| dense(s).map(|z| drr.dw(&z)), (a, t), (dwa, dw))?;
                let wp = dense(p)?[W];
                if wp > 0.0 {
                    self.maxima.push((p, wp));
                }
            }
        }
        self.prev = Some((t, y, dw));
        Ok(())
    }

    /// The means over the first `cycles` complete cycles.
    pub fn finish(&self, cycles: usize) -> Result<Measured, String> {
        if self.crossings.len() < cycles + 1 {
            return Err(format!(
                "only {} upward crossings of v = 1 before the end time ({} needed for {cycles} cycles)",
                self.crossings.len(),
                cycles + 1
            ));
        }
        let (mut period, mut t0, mut ln_v_max) = (0.0, 0.0, 0.0);
        for k in 0..cycles {
            let (c0, c1) = (self.crossings[k], self.crossings[k + 1]);
            let peak = self
                .maxima
                .iter()
                .filter(|(t, _)| *t >= c0 && *t < c1)
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .ok_or_else(|| format!("cycle {k} ({c0} to {c1}) has no maximum of v above 1"))?;
            period += c1 - c0;
            t0 += peak.0 - c0;
            ln_v_max += peak.1;
        }
        let n = cycles as f64;
        Ok(Measured { period: period / n, t0: t0 / n, ln_v_max: ln_v_max / n })
    }
}
