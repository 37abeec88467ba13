//! One period of a converged limit cycle, re-ordered for the asymptotic and Lyapunov
//! analyses: from the v minimum in the stick, through the rise (v = 1 upward), the slip peak
//! t_c and the slip, back to the v minimum. Times are relative to the peak (s = t − t_c).
//!
//! Built from the cycle analysis' trajectory (every accepted step plus the located events), so
//! the v minimum and the v maximum are samples: at both, dv/dt = −γ²G = 0, i.e. the state lies
//! on the slow manifold to the solver's accuracy.

use crate::analysis::cycle::{CycleReport, CycleStatus};
use crate::analysis::AnalysisError;

/// One period of the cycle analysis' last recorded cycle, from v minimum to v minimum (not the
/// shooting's corrected orbit, nor the noise analysis's settled orbit); samples in time order
/// (non-decreasing: in the slip arrest at γ ≳ 1e7 steps of 1e-17 fall below the recorded
/// clock's resolution and neighbours can share a time).
#[derive(Debug, Clone, PartialEq)]
pub struct CyclePeriod {
    /// Period of the recorded cycle.
    pub period: f64,
    /// t − t_c of each sample (t_c: the v maximum).
    pub s: Vec<f64>,
    /// u.
    pub u: Vec<f64>,
    /// w = ln v.
    pub w: Vec<f64>,
    /// θ.
    pub theta: Vec<f64>,
    /// Index of the v maximum (s = 0).
    pub peak: usize,
    /// Index of the upward crossing of v = 1 before the peak (the cycle's end event).
    pub up: usize,
    /// Index of the first sample after the peak with v < 1 (end of the slip).
    pub down: usize,
}

impl CyclePeriod {
    /// The last recorded cycle of a periodic cycle analysis; [`AnalysisError::NoLimitCycle`]
    /// says why there is none.
    pub fn from_cycle(cycle: &CycleReport) -> Result<Self, AnalysisError> {
        let none = |reason: String| AnalysisError::NoLimitCycle { reason };
        if cycle.status != CycleStatus::Periodic {
            return Err(none(format!(
                "the cycle analysis found no period-1 limit cycle (status {:?})",
                cycle.status
            )));
        }
        let tr = cycle
            .trajectory
            .last()
            .ok_or_else(|| none("the cycle analysis recorded no trajectory".into()))?;
        let n = tr.t.len();
        if n < 8 || tr.v.iter().any(|&v| !(v > 0.0 && v.is_finite())) {
            return Err(none(format!(
                "the recorded cycle has {n} samples or a velocity that is not positive and finite"
            )));
        }
        let period = tr.t[n - 1];
        let argmax = (0..n).fold(0, |b, i| if tr.v[i] > tr.v[b] { i } else { b });
        let argmin = (0..n).fold(0, |b, i| if tr.v[i] < tr.v[b] { i } else { b });
        if argmin <= argmax {
            return Err(none(
                "the v minimum does not follow the slip in the recorded cycle".into(),
            ));
        }
        // From the v minimum to the end of the cycle, then the start of the cycle (one period
        // later) up to the v minimum; t = 0 and t = period are the same state. Times from the
        // peak are differences of the recorded times (the period is added only to the stick's
        // part, far from the peak, so the slip keeps the recorded resolution).
        let t_peak = tr.t[argmax];
        let order: Vec<(usize, f64)> = (argmin..n)
            .map(|i| (i, (tr.t[i] - period) - t_peak))
            .chain((1..=argmin).map(|i| (i, tr.t[i] - t_peak)))
            .collect();
        let s: Vec<f64> = order.iter().map(|&(_, s)| s).collect();
        let u: Vec<f64> = order.iter().map(|&(i, _)| tr.u[i]).collect();
        let w: Vec<f64> = order.iter().map(|&(i, _)| tr.v[i].ln()).collect();
        let theta: Vec<f64> = order.iter().map(|&(i, _)| tr.theta[i]).collect();
        let peak = n - argmin + argmax - 1;
        // The cycle ends at its upward crossing of v = 1 (a located event, t = period).
        let up = n - 1 - argmin;
        let down = (peak..s.len())
            .find(|&k| w[k] < 0.0)
            .ok_or_else(|| none("no downward crossing of v = 1 after the peak".into()))?;
        Ok(CyclePeriod { period, s, u, w, theta, peak, up, down })
    }

    /// [`CyclePeriod::from_cycle`] of the scene's cycle analysis, if it ran one.
    pub fn of_scene(cycle: Option<&CycleReport>) -> Result<Self, AnalysisError> {
        let none = AnalysisError::NoLimitCycle { reason: "the scene ran no cycle analysis".into() };
        cycle.ok_or(none).and_then(Self::from_cycle)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.s.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// The state (u, w, θ) of sample k.
    pub fn state(&self, k: usize) -> [f64; 3] {
        [self.u[k], self.w[k], self.theta[k]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::cycle::TrajectoryCycle;

    fn report(tr: TrajectoryCycle) -> CycleReport {
        CycleReport {
            status: CycleStatus::Periodic,
            converged: true,
            cycles_per_period: Some(1),
            values: None,
            error_estimate: None,
            spread: None,
            orbit: vec![],
            orbit_period: None,
            last_cycles: vec![],
            cycles_used: 1,
            cycles_computed: 2,
            time_integrated: 1.0,
            stopped_by: None,
            deep_sticks: 0,
            fixed_point_escapes: 0,
            convergence_rule: String::new(),
            tolerance: 1e-7,
            steps_per_cycle: None,
            trajectory: vec![tr],
        }
    }

    #[test]
    fn reorders_from_the_v_minimum_with_times_from_the_peak() {
        // A caricature: v = 1 at t = 0, peak at 1, back below 1 at 2, minimum at 5, period 10.
        let t = vec![0.0, 0.5, 1.0, 1.5, 2.0, 5.0, 8.0, 10.0];
        let v = vec![1.0, 10.0, 100.0, 10.0, 0.5, 0.1, 0.3, 1.0];
        let tr = TrajectoryCycle { t: t.clone(), u: t.clone(), v, theta: vec![0.0; 8] };
        let o = CyclePeriod::from_cycle(&report(tr)).unwrap();
        assert_eq!(o.s, vec![-6.0, -3.0, -1.0, -0.5, 0.0, 0.5, 1.0, 4.0]);
        assert_eq!((o.peak, o.up, o.down), (4, 2, 6));
        assert_eq!(o.w[0], 0.1f64.ln());
        assert_eq!(o.u[3], 0.5);
    }
}
