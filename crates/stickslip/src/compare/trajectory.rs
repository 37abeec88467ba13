//! A user's trajectory against the reference: the events first, aligned on each event, then
//! the state between events in phase.
//!
//! The reference is Radau5 at rtol = min(1e-12, tolerance/100) through the re-basing clock
//! ([`super::reference`]), started from the user's first sample with the scene's parameters.
//! Rodas5P at a 10 times tighter rtol (an independent method, run more accurately) is
//! processed the same way; the difference between the two, per compared quantity, is the
//! reference's stated accuracy. Where a quantity's accuracy is not below tolerance/10, no
//! verdict is given.
//!
//! Events (slip episodes, v ≥ 1; [`super::sampled`]) are located on the user's samples and on
//! the reference's own steps, and matched in order (both start from the same state). Each
//! event k gives a shift s_k between the reference's and the user's v maximum. The user's
//! sample at t is compared with the reference at t + s_k, k the event whose peak is nearest:
//! the reference's events are located again on those shifted sample times (the interpolation
//! between samples is then common to both), and the state between events (v < 1, where no
//! slip's steepness can swamp it) is compared at the same time from the same event's peak.

use super::error::CompareError;
use super::input::Trajectory;
use super::quantity::within;
use super::reference::{reference_recurrence, reference_states, reference_steps};
use super::sampled::{sampled_events, SampledEvent};
use super::scale::first_sample_fits;
use crate::model::Drr;
use crate::scene::{Method, Scene};
use serde::Serialize;
use std::collections::BTreeMap;

/// The per-event quantities compared: the peak time from the first sample, the recurrence
/// (peak to previous peak: the period), the rise time (start to peak), ln v_max and the slip.
pub const EVENT_QUANTITIES: [&str; 5] =
    ["peak_time", "recurrence", "rise_time", "ln_v_max", "slip"];
/// The state quantities compared between events.
pub const STATE_QUANTITIES: [&str; 3] = ["u", "ln_v", "theta"];

/// Agreement or not within the tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every deviation is within the tolerance.
    Agrees,
    /// Some deviation exceeds the tolerance (or the event counts differ).
    Disagrees,
}

/// One quantity of one event, the user's against the reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantityDeviation {
    /// One of [`EVENT_QUANTITIES`].
    pub quantity: String,
    /// Event number (1 = the first complete event).
    pub event: usize,
    /// The user's value.
    pub user: f64,
    /// The reference's value.
    pub reference: f64,
    /// Relative difference (|Δ| / |reference|), absolute for ln v_max.
    pub deviation: f64,
}

/// The worst deviation of the state between events (compared in phase).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateDeviation {
    /// "u", "ln_v" or "theta".
    pub quantity: String,
    /// The user's sample time.
    pub t: f64,
    /// Where the sample is in the file.
    pub at: String,
    /// The event it is aligned on (0: no event compared, at equal times).
    pub event: usize,
    /// Time from that event's v maximum (negative before it).
    pub phase: f64,
    /// The user's value.
    pub user: f64,
    /// The reference's value at the same phase.
    pub reference: f64,
    /// |Δu|/max(|u|, 1), |Δ ln v| or |Δθ|/max(|θ|, 1).
    pub deviation: f64,
}

/// The reference integration and its own accuracy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceInfo {
    /// Method, tolerances, time bookkeeping and accuracy estimate, in words.
    pub method: String,
    /// Its relative (and absolute) tolerance.
    pub rtol: f64,
    /// The check run's (Rodas5P) tolerance.
    pub check_rtol: f64,
    /// Per compared quantity ([`EVENT_QUANTITIES`], [`STATE_QUANTITIES`]), the largest
    /// difference between the reference and the check run, in the measure of the deviations:
    /// an estimate of the reference's own error.
    pub accuracy: BTreeMap<String, f64>,
    /// Re-bases of its clock.
    pub rebases: u64,
}

/// A user's trajectory against the reference (the `--json` object; docs/compare.md).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryComparison {
    /// "agrees" or "disagrees".
    pub verdict: Verdict,
    /// Tolerance: relative for durations, the slip, u and θ (u, θ against max(|value|, 1));
    /// absolute for ln v.
    pub tolerance: f64,
    /// Samples in the file.
    pub samples: usize,
    /// Complete events in the user's trajectory, in the reference over the same span, and
    /// compared (those in both).
    pub events: [usize; 3],
    /// The reference and its accuracy.
    pub reference: ReferenceInfo,
    /// Where the event counts differ: the mean recurrence of the file's events and of the
    /// reference's (integrated past the file's end if needed; null if either has fewer than
    /// two events).
    pub recurrence: Option<MeanRecurrence>,
    /// The event with the largest relative recurrence (period) deviation (null with fewer
    /// than two events).
    pub period_error: Option<QuantityDeviation>,
    /// Per quantity, the worst event.
    pub worst_per_quantity: Vec<QuantityDeviation>,
    /// Every event's quantities.
    pub per_event: Vec<QuantityDeviation>,
    /// Samples compared between events (v < 1).
    pub state_samples: usize,
    /// The worst state deviation between events, in phase.
    pub worst_state: Option<StateDeviation>,
    /// Largest state deviation per quantity (u, ln_v, theta), in phase.
    pub max_state_deviation: StateMaxima,
    /// Why the verdict is "disagrees", in words (empty when it agrees).
    pub reasons: Vec<String>,
}

/// The mean time between events, the file's and the reference's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeanRecurrence {
    /// The file's: (last peak − first peak)/(events − 1).
    pub user: f64,
    /// The reference's: over its events in the file's span, or its first three upward
    /// crossings of v = 1 where the span holds fewer than two.
    pub reference: f64,
}

/// The mean recurrences where the file has two events or more (see [`MeanRecurrence`]).
fn mean_recurrence(
    drr: Drr,
    start: f64,
    y0: [f64; 3],
    user: &[SampledEvent],
    own: &[SampledEvent],
    rtol: f64,
) -> Result<Option<MeanRecurrence>, CompareError> {
    let mean = |e: &[SampledEvent]| {
        (e.len() >= 2).then(|| (e[e.len() - 1].peak - e[0].peak) / (e.len() - 1) as f64)
    };
    let Some(user) = mean(user) else { return Ok(None) };
    let reference = match mean(own) {
        Some(r) => Some(r),
        None => reference_recurrence(drr, Method::Radau5, rtol, start, y0, 3)?,
    };
    Ok(reference.map(|reference| MeanRecurrence { user, reference }))
}

/// Largest state deviation per component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StateMaxima {
    /// |Δu|/max(|u|, 1) (null where u is computed from the force balance: not compared).
    pub u: Option<f64>,
    /// |Δ ln v|.
    pub ln_v: f64,
    /// |Δθ|/max(|θ|, 1).
    pub theta: f64,
}

/// Deviations of (u, w, θ) in the measure of [`StateDeviation::deviation`].
fn state_deviation(user: &[f64; 3], reference: &[f64; 3]) -> [f64; 3] {
    [
        (user[0] - reference[0]).abs() / reference[0].abs().max(1.0),
        (user[1] - reference[1]).abs(),
        (user[2] - reference[2]).abs() / reference[2].abs().max(1.0),
    ]
}

/// One reference method processed against the user's samples.
struct Side {
    /// Its events on its own steps.
    own: Vec<SampledEvent>,
    /// The compared events, located on the user's sample times shifted per event.
    aligned: Vec<SampledEvent>,
    /// Its state at each user sample's time shifted by its event's shift.
    in_phase: Vec<[f64; 3]>,
    /// Re-bases of the in-phase run's clock.
    rebases: u64,
}

/// For each sample, the compared event (index < `n`) whose user peak is nearest (times and
/// peaks increase, so the anchors do too: one sweep).
fn anchors(t: &[f64], user: &[SampledEvent], n: usize) -> Vec<Option<usize>> {
    let mut k = 0;
    t.iter()
        .map(|&t| {
            if n == 0 {
                return None;
            }
            while k + 1 < n && (user[k + 1].peak - t).abs() < (user[k].peak - t).abs() {
                k += 1;
            }
            Some(k)
        })
        .collect()
}

/// Runs `method` at `rtol` from the user's first sample and aligns it on the user's events.
fn side(
    drr: Drr,
    method: Method,
    rtol: f64,
    user: &Trajectory,
    y0: [f64; 3],
    user_events: &[SampledEvent],
) -> Result<Side, CompareError> {
    let (start, last) = (user.t[0], *user.t.last().expect("two samples"));
    let (fine, states) = reference_steps(drr, method, rtol, start, y0, last, user_events.len())?;
    let origin = |i: usize| format!("reference at t = {}", fine[i]);
    let own = sampled_events(&fine, &states, &origin).map_err(CompareError::UnresolvedReference)?;
    let n = own.len().min(user_events.len());
    let anchor = anchors(&user.t, user_events, n);
    // The states at the user's times shifted per event, and the events located on them.
    let align = |shift: &[f64]| -> Result<Side, CompareError> {
        let targets: Vec<f64> =
            user.t.iter().zip(&anchor).map(|(t, a)| a.map_or(*t, |k| t + shift[k])).collect();
        let (in_phase, rebases) = reference_states(drr, method, rtol, start, y0, &targets)?;
        let aligned = (0..n)
            .map(|k| {
                // The samples anchored on event k: a contiguous range, the anchors increasing.
                let first = anchor.partition_point(|a| a.is_some_and(|a| a < k));
                let window: Vec<usize> =
                    (first..user.t.len()).take_while(|&i| anchor[i] == Some(k)).collect();
                let times: Vec<f64> = window.iter().map(|&i| targets[i]).collect();
                let states: Vec<[f64; 3]> = window.iter().map(|&i| in_phase[i]).collect();
                let located = sampled_events(&times, &states, &|k| user.origin[window[k]].clone());
                // Where the reference cannot be located on the user's times (far off the
                // user's event), on its own steps.
                located
                    .ok()
                    .and_then(|e| {
                        e.into_iter().min_by(|a, b| {
                            (a.peak - own[k].peak).abs().total_cmp(&(b.peak - own[k].peak).abs())
                        })
                    })
                    .unwrap_or(own[k])
            })
            .collect();
        Ok(Side { own: own.clone(), aligned, in_phase, rebases })
    };
    // First from the peaks on the reference's own steps, whose parabola may be off by far more
    // than the reference's error where its steps are coarse (4.7e-8 at a first event: 2.5e-7
    // in ln v where it falls fast after the peak); then corrected so that the peak located on
    // the shifted times is the user's, shifted: the samples then sit at the same phase of
    // both events, and the interpolation's bias is common to both.
    let shift: Vec<f64> = (0..n).map(|k| own[k].peak - user_events[k].peak).collect();
    let first = align(&shift)?.aligned;
    let shift: Vec<f64> = (0..n).map(|k| first[k].peak - user_events[k].peak).collect();
    align(&shift)
}

/// The compared quantities of event k (see [`EVENT_QUANTITIES`]): (name, value, relative).
fn event_quantities(
    events: &[SampledEvent],
    k: usize,
    start: f64,
) -> Vec<(&'static str, f64, bool)> {
    let e = events[k];
    let mut q = vec![("peak_time", e.peak - start, true)];
    if k > 0 {
        q.push(("recurrence", e.peak - events[k - 1].peak, true));
    }
    q.extend([
        ("rise_time", e.peak - e.start, true),
        ("ln_v_max", e.ln_v_max, false),
        ("slip", e.slip, true),
    ]);
    q
}

fn deviation(user: f64, reference: f64, relative: bool) -> f64 {
    let d = (user - reference).abs();
    if relative {
        d / reference.abs().max(f64::MIN_POSITIVE)
    } else {
        d
    }
}

/// Compares a user's trajectory with the reference of `scene`'s model, events first, then
/// the state between events in phase (see the module docs). Fails with
/// [`CompareError::InaccurateReference`] when the reference's own accuracy is not below
/// tolerance/10 for some compared quantity (its verdict would not mean anything).
pub fn against_trajectory(
    scene: &Scene,
    user: &Trajectory,
    tolerance: f64,
) -> Result<TrajectoryComparison, CompareError> {
    first_sample_fits(scene, user, tolerance)?;
    let drr = Drr::new(scene.params);
    let rtol = (tolerance / 100.0).min(1e-12);
    let check_rtol = rtol / 10.0;
    let start = user.t[0];
    let uw: Vec<[f64; 3]> = user.y.iter().map(|y| [y[0], y[1].ln(), y[2]]).collect();
    let y0 = uw[0];
    let user_events =
        sampled_events(&user.t, &uw, &|i| user.origin[i].clone()).map_err(CompareError::Input)?;
    let reference = side(drr, Method::Radau5, rtol, user, y0, &user_events)?;
    let check = side(drr, Method::Rodas5p, check_rtol, user, y0, &user_events)?;
    let n = reference.aligned.len();
    // Samples between events: the user's v < 1.
    let between: Vec<usize> = (0..user.t.len()).filter(|&i| uw[i][1] < 0.0).collect();
    // The reference's own accuracy per quantity: its difference from the check run.
    let mut accuracy: BTreeMap<String, f64> = BTreeMap::new();
    for k in 0..n.min(check.aligned.len()) {
        let ours = event_quantities(&reference.aligned, k, start);
        let theirs = event_quantities(&check.aligned, k, start);
        for ((name, r, relative), (_, c, _)) in ours.into_iter().zip(theirs) {
            let a = accuracy.entry(name.into()).or_insert(0.0);
            *a = a.max(deviation(c, r, relative));
        }
    }
    if check.aligned.len() != n {
        return Err(CompareError::InaccurateReference {
            quantities: vec![(
                format!("the event count ({n} against {} by the check run)", check.aligned.len()),
                f64::INFINITY,
            )],
            tolerance,
        });
    }
    // A u computed from the scene's own force balance (a QDYN file) is not compared: it only
    // repeats v and θ, their rounding amplified by 1/ξ.
    let compared = if user.u_from_force_balance { 1..3 } else { 0..3 };
    for &i in &between {
        let d = state_deviation(&check.in_phase[i], &reference.in_phase[i]);
        for k in compared.clone() {
            let a = accuracy.entry(STATE_QUANTITIES[k].into()).or_insert(0.0);
            *a = a.max(d[k]);
        }
    }
    let inaccurate: Vec<(String, f64)> = accuracy
        .iter()
        .filter(|(_, a)| !within(**a, tolerance / 10.0))
        .map(|(q, a)| (q.clone(), *a))
        .collect();
    // A quantity the reference does not resolve gives no reason either way; a disagreement in
    // one it resolves is still a verdict (a 1 % period error does not need ln v resolved to
    // 1e-5 right after an arrest). Without such a disagreement there is no verdict.
    let resolved = |name: &str| inaccurate.iter().all(|(q, _)| q != name);
    let reference_info = ReferenceInfo {
        method: format!(
            "radau5 through the re-basing clock, rtol {rtol:e}, atol {rtol:e}, from the first \
             sample; accuracy: its largest difference from rodas5p at rtol {check_rtol:e}, \
             processed the same way"
        ),
        rtol,
        check_rtol,
        accuracy,
        rebases: reference.rebases,
    };

    let mut reasons = Vec::new();
    let span = user.t.last().expect("two samples") - start;
    let own_count = reference.own.len();
    let mut recurrence = None;
    if user_events.len() != own_count {
        // One event more in one of them is only an edge effect if it ends within the
        // tolerance (of the span) of the file's end.
        let longer = if user_events.len() > own_count { &user_events } else { &reference.own };
        let at_the_edge = user_events.len().abs_diff(own_count) == 1
            && (user.t.last().expect("two samples") - longer[longer.len() - 1].end).abs()
                <= tolerance * span;
        if !at_the_edge {
            reasons.push(format!(
                "{} complete events against the reference's {} over the same span",
                user_events.len(),
                own_count
            ));
            recurrence = mean_recurrence(drr, start, y0, &user_events, &reference.own, rtol)?;
            if let Some(r) = &recurrence {
                reasons.push(format!(
                    "period: your events recur every {} (mean peak to peak), the reference's every {}: {:.3e} times its period (the t column in other units?)",
                    r.user, r.reference, r.user / r.reference
                ));
            }
        }
    }
    let mut per_event = Vec::new();
    for k in 0..n {
        let ours = event_quantities(&user_events, k, start);
        let theirs = event_quantities(&reference.aligned, k, start);
        for ((name, u, relative), (_, r, _)) in ours.into_iter().zip(theirs) {
            per_event.push(QuantityDeviation {
                quantity: name.into(),
                event: k + 1,
                user: u,
                reference: r,
                deviation: deviation(u, r, relative),
            });
        }
    }
    let worst = |name: &str| {
        per_event
            .iter()
            .filter(|q| q.quantity == name)
            .max_by(|a, b| a.deviation.total_cmp(&b.deviation))
            .cloned()
    };
    let worst_per_quantity: Vec<QuantityDeviation> =
        EVENT_QUANTITIES.iter().filter_map(|n| worst(n)).collect();
    for q in worst_per_quantity
        .iter()
        .filter(|q| resolved(&q.quantity) && !within(q.deviation, tolerance))
    {
        let what = match q.quantity.as_str() {
            "recurrence" => format!(
                "period error: the period differs by {:.2e} between events {} and {} (peak to peak)",
                q.deviation,
                q.event - 1,
                q.event
            ),
            name => format!("{name} differs by {:.2e} at event {}", q.deviation, q.event),
        };
        reasons.push(format!("{what} (yours {}, reference {})", q.user, q.reference));
    }
    // The state between events, in phase.
    let anchor = anchors(&user.t, &user_events, n);
    let mut maxima = [0.0f64; 3];
    let mut worst_state: Option<StateDeviation> = None;
    for &i in &between {
        let d = state_deviation(&uw[i], &reference.in_phase[i]);
        for k in compared.clone() {
            maxima[k] = maxima[k].max(d[k]);
            if !resolved(STATE_QUANTITIES[k]) {
                continue;
            }
            if worst_state.as_ref().is_none_or(|w| !within(d[k], w.deviation)) {
                worst_state = Some(StateDeviation {
                    quantity: STATE_QUANTITIES[k].into(),
                    t: user.t[i],
                    at: user.origin[i].clone(),
                    event: anchor[i].map_or(0, |e| e + 1),
                    phase: anchor[i].map_or(user.t[i] - start, |e| user.t[i] - user_events[e].peak),
                    user: uw[i][k],
                    reference: reference.in_phase[i][k],
                    deviation: d[k],
                });
            }
        }
    }
    if let Some(w) = worst_state.as_ref().filter(|w| !within(w.deviation, tolerance)) {
        reasons.push(format!(
            "state between events: {} = {} against the reference's {} ({:.2e}) at t = {} ({}, {} from the v maximum of event {})",
            w.quantity, w.user, w.reference, w.deviation, w.t, w.at, w.phase, w.event
        ));
    }
    if reasons.is_empty() && !inaccurate.is_empty() {
        return Err(CompareError::InaccurateReference { quantities: inaccurate, tolerance });
    }
    Ok(TrajectoryComparison {
        verdict: if reasons.is_empty() { Verdict::Agrees } else { Verdict::Disagrees },
        tolerance,
        samples: user.t.len(),
        events: [user_events.len(), own_count, n],
        reference: reference_info,
        recurrence,
        period_error: worst("recurrence"),
        worst_per_quantity,
        per_event,
        state_samples: between.len(),
        worst_state,
        max_state_deviation: StateMaxima {
            u: (!user.u_from_force_balance).then_some(maxima[0]),
            ln_v: maxima[1],
            theta: maxima[2],
        },
        reasons,
    })
}
