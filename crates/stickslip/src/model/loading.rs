//! The load-point history of a laboratory run: piecewise-constant load-point velocity
//! V_lp(t), with its jumps (velocity steps, holds, reloads) at known times.
//!
//! Convention (rsfmodel's): V_lp(t) is the velocity of the last segment whose start is ≤ t,
//! so a step at t_j takes effect at t_j. The load-point displacement x_lp(t) = ∫₀ᵗ V_lp is
//! continuous and piecewise linear, 0 at the first segment's start.

use serde::Serialize;

/// One segment: from `t_start` (to the next segment's start) the load point moves at
/// `velocity` (0: a hold).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Segment {
    /// Start time (s).
    pub t_start: f64,
    /// Load-point velocity (µm/s), ≥ 0.
    pub velocity: f64,
}

/// A load-point history: segments with increasing starts, ending at `t_end`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Loading {
    /// The segments, by strictly increasing `t_start`.
    pub segments: Vec<Segment>,
    /// End of the last segment (s).
    pub t_end: f64,
}

/// Why a load-point history is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LoadingError {
    /// No segment.
    #[error("no segment: give at least one {{\"t_start\", \"velocity\"}}")]
    Empty,
    /// A value is not finite or out of range.
    #[error("segment {index}: {message}")]
    Bad {
        /// The segment's index.
        index: usize,
        /// What is wrong and the fix.
        message: String,
    },
}

impl Loading {
    /// A checked history: starts finite and strictly increasing, velocities finite and ≥ 0,
    /// `t_end` after the last start.
    pub fn new(segments: Vec<Segment>, t_end: f64) -> Result<Self, LoadingError> {
        if segments.is_empty() {
            return Err(LoadingError::Empty);
        }
        for (index, s) in segments.iter().enumerate() {
            let bad = |message: String| LoadingError::Bad { index, message };
            if !s.t_start.is_finite() {
                return Err(bad(format!("t_start {} is not a finite number", s.t_start)));
            }
            if !(s.velocity.is_finite() && s.velocity >= 0.0) {
                return Err(bad(format!(
                    "velocity {} must be finite and ≥ 0 (0 is a hold)",
                    s.velocity
                )));
            }
            if index > 0 && s.t_start <= segments[index - 1].t_start {
                return Err(bad(format!(
                    "t_start {} must be after the previous segment's {}",
                    s.t_start,
                    segments[index - 1].t_start
                )));
            }
        }
        let last = segments[segments.len() - 1].t_start;
        if !(t_end.is_finite() && t_end > last) {
            let index = segments.len() - 1;
            let message = format!("the end time {t_end} must be after the last start {last}");
            return Err(LoadingError::Bad { index, message });
        }
        Ok(Self { segments, t_end })
    }

    /// The history from a sampled load-point displacement (time, x_lp) with strictly
    /// increasing times: between samples the load point moves at the constant velocity of
    /// the chord; consecutive chords of equal velocity are merged into one segment.
    pub fn from_displacement(samples: &[(f64, f64)]) -> Result<Self, LoadingError> {
        if samples.len() < 2 {
            return Err(LoadingError::Empty);
        }
        let mut segments: Vec<Segment> = Vec::new();
        for (index, w) in samples.windows(2).enumerate() {
            let ((t0, x0), (t1, x1)) = (w[0], w[1]);
            if !(t0.is_finite() && t1.is_finite() && x0.is_finite() && x1.is_finite()) {
                let message = format!("sample ({t1}, {x1}) is not finite");
                return Err(LoadingError::Bad { index: index + 1, message });
            }
            if t1 <= t0 {
                let message = format!("time {t1} must be after the previous sample's {t0}");
                return Err(LoadingError::Bad { index: index + 1, message });
            }
            let velocity = (x1 - x0) / (t1 - t0);
            if velocity < 0.0 {
                let message = format!(
                    "the load point moves backwards ({x0} → {x1}); only forward loading and holds are supported"
                );
                return Err(LoadingError::Bad { index: index + 1, message });
            }
            if segments.last().is_none_or(|s| s.velocity != velocity) {
                segments.push(Segment { t_start: t0, velocity });
            }
        }
        Self::new(segments, samples[samples.len() - 1].0)
    }

    /// Start of the history (the first segment's start).
    pub fn t_start(&self) -> f64 {
        self.segments[0].t_start
    }

    /// End of segment `j` (the next start, or `t_end`).
    pub fn segment_end(&self, j: usize) -> f64 {
        self.segments.get(j + 1).map_or(self.t_end, |s| s.t_start)
    }

    /// Load-point displacement at the start of each segment (0 at the first).
    pub fn start_displacements(&self) -> Vec<f64> {
        let mut x = Vec::with_capacity(self.segments.len());
        let mut acc = 0.0;
        for (j, s) in self.segments.iter().enumerate() {
            x.push(acc);
            acc += s.velocity * (self.segment_end(j) - s.t_start);
        }
        x
    }

    /// Load-point displacement x_lp at each of `times` (non-decreasing; 0 at the first
    /// segment's start; times before it are taken in the first segment).
    pub fn displacements_at(&self, times: &[f64]) -> Vec<f64> {
        let starts = self.start_displacements();
        let mut j = 0;
        times
            .iter()
            .map(|&t| {
                while j + 1 < self.segments.len() && self.segments[j + 1].t_start <= t {
                    j += 1;
                }
                let s = &self.segments[j];
                starts[j] + s.velocity * (t - s.t_start)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn displacement_samples_become_merged_segments() {
        let l =
            Loading::from_displacement(&[(0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (3.0, 12.0)]).unwrap();
        assert_eq!(l.segments.len(), 2);
        assert_eq!(l.segments[1], Segment { t_start: 2.0, velocity: 10.0 });
        assert_eq!(l.t_end, 3.0);
        assert_eq!(l.start_displacements(), vec![0.0, 2.0]);
    }

    #[test]
    fn rejects_unordered_and_negative() {
        let s = |t_start, velocity| Segment { t_start, velocity };
        assert!(Loading::new(vec![s(0.0, 1.0), s(0.0, 2.0)], 3.0).is_err());
        assert!(Loading::new(vec![s(0.0, -1.0)], 3.0).is_err());
        assert!(Loading::new(vec![s(0.0, 1.0)], 0.0).is_err());
        assert!(Loading::from_displacement(&[(0.0, 1.0), (1.0, 0.0)]).is_err());
    }
}
