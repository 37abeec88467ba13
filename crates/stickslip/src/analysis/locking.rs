//! The response of a periodically loaded spring-block to its forcing, judged from its event
//! catalogue: whether the events lock onto the forcing, and at which ratio.
//!
//! A forced system has no period of its own to report (the unforced cycle analysis does not
//! apply). What it has is its events' times against the forcing's. The response is **locked
//! p:q** when it repeats itself every q forcing periods with p events in each repetition:
//! then t_{i+p} − t_i = q·T for every event i, and the events' phases (t_i mod T)/T take p
//! values, repeated. p/q is the mean number of events per forcing period (1:3 is one event
//! every three periods, 3:1 three events in each period).
//!
//! The criterion, over the **judged window** (the second half of the catalogue; the first is
//! taken as the transient): the smallest p ≤ [`MAX_EVENTS_PER_REPETITION`] for which every
//! difference t_{i+p} − t_i of peak times in the window is the same whole number q ≥ 1 of
//! forcing periods to within [`TOLERANCE`]·T, with at least p + 1 such differences (each of the
//! p events of a repetition seen to recur at least once more). Where no p passes, the response
//! is reported as not locked, with the smallest mismatch found; its mean number of events per
//! forcing period is reported either way.

use crate::analysis::time_series::Event;
use crate::model::{PeriodicLoading, PhysicalScales};
use serde::Serialize;

/// The largest number p of events per repetition that the criterion tries.
pub const MAX_EVENTS_PER_REPETITION: usize = 12;

/// The largest mismatch |t_{i+p} − t_i − qT| accepted, relative to T.
pub const TOLERANCE: f64 = 1e-3;

/// The forcing in the input's units, with dimensional input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhysicalForcing {
    /// A_per (stress units).
    pub amplitude: f64,
    /// T_per (time units).
    pub period: f64,
}

/// The "forcing" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ForcingReport {
    /// a_per = A_per/(aσ): the amplitude in units of A.
    pub amplitude: f64,
    /// The forcing period in units of D_c/v0.
    pub period: f64,
    /// The same in the input's units, with dimensional input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub physical: Option<PhysicalForcing>,
    /// Events in the catalogue (the report's `events`).
    pub events: usize,
    /// Events judged: the second half of the catalogue.
    pub window_events: usize,
    /// The mean number of events per forcing period over the window (null with fewer than
    /// two events in it).
    pub events_per_period: Option<f64>,
    /// Whether the events lock onto the forcing by the criterion (module documentation).
    pub locked: bool,
    /// p: events per repetition, when locked.
    pub lock_events: Option<usize>,
    /// q: forcing periods per repetition, when locked.
    pub lock_periods: Option<u64>,
    /// The phases (t_peak mod T)/T in [0, 1) of the last p events of the window, when locked.
    pub phases: Vec<f64>,
    /// The largest |t_{i+p} − t_i − qT|/T over the window for the locking found, or when not
    /// locked the smallest such value over the p tried (null where no p could be tried).
    pub mismatch: Option<f64>,
    /// The criterion's tolerance on `mismatch` ([`TOLERANCE`]).
    pub tolerance: f64,
    /// The finding in words.
    pub statement: String,
}

/// Judges the catalogue `events` (peak times from the start, dimensionless) against `loading`.
pub fn analyse(
    events: &[Event],
    loading: &PeriodicLoading,
    scales: Option<&PhysicalScales>,
) -> ForcingReport {
    let period = loading.period;
    let peaks: Vec<f64> = events.iter().map(|e| e.values.t_peak).collect();
    let window = &peaks[peaks.len() / 2..];
    let events_per_period = (window.len() >= 2)
        .then(|| (window.len() - 1) as f64 * period / (window[window.len() - 1] - window[0]));
    let mut best: Option<(usize, u64, f64)> = None;
    let mut found = None;
    for p in 1..=MAX_EVENTS_PER_REPETITION {
        if window.len() < 2 * p + 1 {
            break;
        }
        let Some((q, mismatch)) = repetition(window, p, period) else { continue };
        if best.is_none_or(|(.., m)| mismatch < m) {
            best = Some((p, q, mismatch));
        }
        if mismatch <= TOLERANCE {
            found = Some((p, q, mismatch));
            break;
        }
    }
    let physical = scales.map(|s| PhysicalForcing {
        amplitude: loading.amplitude * s.a_sigma,
        period: s.time(period),
    });
    let statement = match (found, best) {
        (Some((p, q, m)), _) => format!(
            "locked {p}:{q}: {p} event(s) every {q} forcing period(s) ({:.6} per period) over the last {} events, t_(i+{p}) − t_i = {q}·T within {m:.1e}·T (criterion {TOLERANCE:e}·T)",
            p as f64 / q as f64,
            window.len()
        ),
        (None, Some((p, q, m))) => format!(
            "not locked: over the last {} events no p ≤ {} gives t_(i+p) − t_i = q·T within {TOLERANCE:e}·T (closest {p}:{q}, off by {m:.1e}·T); {} events per forcing period on average",
            window.len(),
            MAX_EVENTS_PER_REPETITION.min((window.len().max(1) - 1) / 2),
            events_per_period.map_or("—".to_string(), |r| format!("{r:.6}"))
        ),
        (None, None) => format!(
            "not judged: {} events in the catalogue, {} in the judged half; the criterion needs at least 3 there (raise time_series.t_max)",
            events.len(),
            window.len()
        ),
    };
    let phases = found.map_or_else(Vec::new, |(p, ..)| {
        window[window.len() - p..].iter().map(|t| loading.phase(*t)).collect()
    });
    ForcingReport {
        amplitude: loading.amplitude,
        period,
        physical,
        events: events.len(),
        window_events: window.len(),
        events_per_period,
        locked: found.is_some(),
        lock_events: found.map(|(p, ..)| p),
        lock_periods: found.map(|(_, q, _)| q),
        phases,
        mismatch: found.or(best).map(|(.., m)| m),
        tolerance: TOLERANCE,
        statement,
    }
}

/// For p events per repetition: the common whole number q ≥ 1 of periods of the differences
/// t_{i+p} − t_i in `peaks` and their largest mismatch |Δ − qT|/T, if they share one q.
fn repetition(peaks: &[f64], p: usize, period: f64) -> Option<(u64, f64)> {
    let mut q = None;
    let mut mismatch = 0.0f64;
    for i in 0..peaks.len() - p {
        let cycles = (peaks[i + p] - peaks[i]) / period;
        let whole = cycles.round();
        if whole < 1.0 || q.is_some_and(|q| q != whole) {
            return None;
        }
        q = Some(whole);
        mismatch = mismatch.max((cycles - whole).abs());
    }
    q.map(|q| (q as u64, mismatch))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::time_series::EventValues;

    fn catalogue(peaks: &[f64]) -> Vec<Event> {
        peaks
            .iter()
            .map(|&t| Event {
                values: EventValues {
                    t_start: t,
                    t_peak: t,
                    t_end: t,
                    v_max: 1.0,
                    slip: 1.0,
                    duration: 0.0,
                    stress_drop: 0.0,
                    recurrence: None,
                },
                physical: None,
                started_before_run: false,
            })
            .collect()
    }

    const LOADING: PeriodicLoading = PeriodicLoading { amplitude: 0.4, period: 2.0 };

    #[test]
    fn one_event_every_three_periods_is_locked_1_3() {
        let peaks: Vec<f64> = (0..20).map(|i| 0.3 + 6.0 * i as f64).collect();
        let r = analyse(&catalogue(&peaks), &LOADING, None);
        assert!(r.locked, "{}", r.statement);
        assert_eq!((r.lock_events, r.lock_periods), (Some(1), Some(3)));
        assert!((r.phases[0] - 0.15).abs() < 1e-12, "{:?}", r.phases);
    }

    #[test]
    fn two_events_in_each_period_at_two_phases_is_locked_2_1() {
        let peaks: Vec<f64> =
            (0..30).map(|i| 2.0 * (i / 2) as f64 + if i % 2 == 0 { 0.2 } else { 1.5 }).collect();
        let r = analyse(&catalogue(&peaks), &LOADING, None);
        assert!(r.locked, "{}", r.statement);
        assert_eq!((r.lock_events, r.lock_periods), (Some(2), Some(1)));
        assert!((r.events_per_period.unwrap() - 2.0).abs() < 0.1);
    }

    #[test]
    fn an_incommensurate_recurrence_is_not_locked() {
        let peaks: Vec<f64> = (0..40).map(|i| 2.0 * std::f64::consts::SQRT_2 * i as f64).collect();
        let r = analyse(&catalogue(&peaks), &LOADING, None);
        assert!(!r.locked, "{}", r.statement);
        assert!(r.statement.starts_with("not locked"), "{}", r.statement);
        assert!(r.mismatch.unwrap() > TOLERANCE);
    }

    #[test]
    fn too_few_events_are_not_judged() {
        let r = analyse(&catalogue(&[1.0, 5.0]), &LOADING, None);
        assert!(!r.locked && r.statement.starts_with("not judged"), "{}", r.statement);
    }
}
