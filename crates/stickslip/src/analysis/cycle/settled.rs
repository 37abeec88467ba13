//! Settled cycles and the error of the reported values.
//!
//! The convergence rule ([`super::periodicity`]) says when consecutive cycles agree within the
//! rule's tolerance; the first cycles it accepts can still carry the transient (measured:
//! radau5 at rtol 1e-10 on a quasi-dynamic case, cycle 2 of the accepted window off by
//! 2.6e-7 in v_max while cycles 3 onward agree to 1.5e-10). This module decides when the
//! transient has decayed below the cycle-to-cycle noise of the integration, and estimates the
//! error of the mean over the settled window.
//!
//! Model of the per-cycle sequence of a quantity: x_k = x_∞ + A ρ^k + noise_k, with ρ the
//! leading Floquet multiplier's modulus. The differences d_k = x_k − x_{k−1} that stand
//! clearly above the noise (|d_k| > [`CLEAN`] × noise) give ρ (the largest of the last three
//! ratios |d_k / d_{k−1}| below 1 of such pairs) and the transient's size at the last of them,
//! c: |x_c − x_∞| ≈ |d_c| ρ/(1 − ρ); at the window's first cycle j it is |d_c| ρ^{j−c+1}/(1 − ρ).
//! A clean difference followed by one within the noise bounds ρ by their ratio; with neither,
//! ρ is taken as [`RHO_UNKNOWN`], and with no clean difference at all d_1 as the clean level
//! (the transient was below it from the first cycle on). The noise is half the range of the
//! window plus the integration's error floor.
//!
//! The floor: an integration error common to every cycle is invisible in their scatter, so a
//! floor proportional to the tolerance is added: [`TIME_FLOOR`]·rtol·|x| for times and the
//! slip, [`LN_V_FLOOR`]·(rtol·|ln v| + atol) on ln v (relative on v). Measured on the 12
//! quasi-dynamic cases of issue #28 (data/reference/quasi_dynamic_cycles.json) with radau5 at
//! rtol 1e-10 and ln v weighed relative to its size: the period's error is up to
//! 1.6·rtol·|period| and ln v_max's up to 19·(rtol·|ln v_max|) (v_max off by 1.2e-8 relative,
//! a global error of the integration), so the factors leave margins of 6 and 2.6. The engine
//! now weighs ln v absolutely at rtol/10 (v_max within 3.4e-10); the floor is kept for
//! integrations weighed by size. They hold for the one-step
//! methods; CVODE BDF's error at rtol 1e-10 is larger (the period up to ~200·rtol, issue #28):
//! compare two methods (`stickslip compare`) when that matters.
//!
//! The window is settled when, for the period, v_max and the slip, the transient at its first
//! cycle is below [`TRANSIENT_SHARE`] of the noise the integration can resolve: the window's
//! own half range plus [`TIME_FLOOR`]·rtol·|x| for all three (v_max relative), so the run
//! stops once the transient is below the floor, after as few cycles as the contraction allows
//! (issue #36: a super-stable orbit stops on its third cycle). The cycle before the window is
//! left out of that noise, since the difference into the window may be the transient itself.
//! The error estimate of each value is the transient bound plus the noise, here with the cycle
//! before the window in the range (a window of one cycle then has a measured scatter) and the
//! floors above.

use super::{CycleValues, MainValues};

/// A difference is "clean" (the transient, not the noise) above this many noise levels.
const CLEAN: f64 = 3.0;
/// The contraction assumed when no two consecutive differences stand above the noise.
const RHO_UNKNOWN: f64 = 0.5;
/// The largest contraction used (a slower one is treated as this, i.e. 20 cycles per e-fold
/// of the bound's 1/(1 − ρ)).
const RHO_MAX: f64 = 0.95;
/// Settled when the transient left in the window is below this share of the noise.
const TRANSIENT_SHARE: f64 = 0.3;
/// The integration's error floor on times and the slip, in units of rtol·|x|.
const TIME_FLOOR: f64 = 10.0;
/// The integration's error floor on ln v, in units of rtol·|ln v| + atol.
const LN_V_FLOOR: f64 = 50.0;

/// The first cycle whose scatter counts for the window `closed[start..]`: the cycle before
/// the window as well, so that a window of one cycle has a measured scatter, but never
/// `closed[0]`.
fn scatter_start(start: usize) -> usize {
    start.saturating_sub(1).max(1)
}

/// The error of one quantity's mean over the window `closed[start..]`: (transient bound at the
/// window's first cycle, noise), with the noise half the range of `closed[scatter_from..]`
/// plus `floor(mean)`, the integration's error floor. `closed[0]` (from the start, not a full
/// cycle of the orbit) is never used.
fn quantity(
    closed: &[f64],
    start: usize,
    scatter_from: usize,
    floor: impl Fn(f64) -> f64,
) -> (f64, f64) {
    let window = &closed[start..];
    let (lo, hi) = closed[scatter_from..]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mean = window.iter().sum::<f64>() / window.len() as f64;
    let noise = 0.5 * (hi - lo) + floor(mean);
    let clean = CLEAN * noise;
    // Differences d_k = x_k − x_{k−1}, k ≥ 1: cycle 0 (the first complete one, with the
    // largest transient) takes part in the estimate of the decay, never in the mean.
    let d = |k: usize| closed[k] - closed[k - 1];
    let last_clean = (1..closed.len()).rev().find(|&k| d(k).abs() > clean);
    let ratios: Vec<f64> = (2..closed.len())
        .rev()
        .filter(|&k| d(k).abs() > clean && d(k - 1).abs() > clean)
        .map(|k| (d(k) / d(k - 1)).abs())
        // A growing pair is noise (an outlier cycle and the return from it): a transient that
        // grew would not have passed the convergence rule.
        .filter(|&r| r < 1.0)
        .take(3)
        .collect();
    let rho = if !ratios.is_empty() {
        ratios.iter().fold(0.0f64, |a, &r| a.max(r))
    } else {
        // A clean difference followed by one within the noise bounds the decay: |d_{c+1}| is
        // at most the clean level plus the noise of two cycles.
        match last_clean {
            Some(c) if c + 1 < closed.len() => (clean + 2.0 * noise) / d(c).abs(),
            _ => RHO_UNKNOWN,
        }
        .min(RHO_UNKNOWN)
    }
    .min(RHO_MAX);
    // With no clean difference the transient was below the clean level from cycle 1 on (a
    // jump inside the window is excluded by `settled`'s pairwise agreement).
    let (c, dc) = match last_clean {
        Some(c) => (c, d(c).abs()),
        None => (1, clean),
    };
    // Transient at cycle c: |d_c| ρ/(1 − ρ); at the window's first cycle it has decayed by
    // ρ^{start − c} (grown, if a clean difference lies inside the window).
    let at_c = dc * rho / (1.0 - rho);
    let transient = at_c * rho.powi(start as i32 - c as i32);
    (transient, noise)
}

/// How one reported quantity is read from a cycle, and its integration floor.
struct Quantity {
    get: fn(&CycleValues) -> f64,
    /// The floor for a mean value x, given the tolerance (rtol, atol) on w.
    floor: fn(f64, (f64, f64)) -> f64,
}

fn time_floor(x: f64, (rtol, _): (f64, f64)) -> f64 {
    TIME_FLOOR * rtol * x.abs()
}

fn ln_v_floor(x: f64, (rtol, atol): (f64, f64)) -> f64 {
    LN_V_FLOOR * (rtol * x.abs() + atol)
}

/// v = e^w: the floor on w, relative (0 for a v_min that underflowed to 0 in a deep stick).
fn v_floor(v: f64, tol: (f64, f64)) -> f64 {
    if v > 0.0 {
        v * ln_v_floor(v.ln(), tol)
    } else {
        0.0
    }
}

const PERIOD: Quantity = Quantity { get: |c| c.main.period, floor: time_floor };
const V_MAX: Quantity = Quantity { get: |c| c.main.v_max, floor: v_floor };
const SLIP: Quantity = Quantity { get: |c| c.main.slip, floor: time_floor };

/// (transient, noise) of `q` over the window `closed[start..]`.
fn of(q: &Quantity, closed: &[CycleValues], start: usize, w_tolerance: (f64, f64)) -> (f64, f64) {
    let x: Vec<f64> = closed.iter().map(q.get).collect();
    quantity(&x, start, scatter_start(start), |m| (q.floor)(m, w_tolerance))
}

/// The first cycle of the longest settled window (see the module doc) of at most `max_len`
/// cycles ending at the last one, for an integration with tolerance `w_tolerance` = (rtol,
/// atol) on w; None while no window is settled.
///
/// A super-stable orbit settles on its third cycle: the first (from the start) gives the
/// clean difference d_1, the second d_2 within the noise, which bounds the contraction ρ by
/// their ratio, and the window is the third cycle alone, whose transient is ρ² |d_1| at most.
pub(super) fn settled_start(
    closed: &[CycleValues],
    max_len: usize,
    w_tolerance: (f64, f64),
    tolerance: f64,
) -> Option<usize> {
    (super::last_window(closed, max_len)..closed.len())
        .find(|&start| settled(closed, start, w_tolerance, tolerance))
}

/// Whether the window `closed[start..]` is settled (see the module doc), for an integration
/// with tolerance `w_tolerance` = (rtol, atol) on w.
///
/// Every consecutive pair from the cycle before the window on (at least one pair) must also
/// agree under the convergence rule's `tolerance` ([`super::agree`]): a window that still
/// holds a jump of the transient (e.g. the last small oscillation before the relaxation
/// cycle) has a range, i.e. a "noise", that would hide it.
fn settled(closed: &[CycleValues], start: usize, w_tolerance: (f64, f64), tolerance: f64) -> bool {
    if start < 1 || closed.len() <= start {
        return false;
    }
    let scattered = &closed[scatter_start(start)..];
    if scattered.len() < 2 || !scattered.windows(2).all(|w| super::agree(&w[1], &w[0], tolerance)) {
        return false;
    }
    // The stop compares the transient with the window's own scatter (a difference into the
    // window may be the transient itself) plus the tightest floor, TIME_FLOOR·rtol·|x| for
    // every quantity (v_max relative).
    [PERIOD, V_MAX, SLIP].iter().all(|q| {
        let x: Vec<f64> = closed.iter().map(q.get).collect();
        let (transient, noise) = quantity(&x, start, start, |m| time_floor(m, w_tolerance));
        transient <= TRANSIENT_SHARE * noise
    })
}

/// The error estimate of the mean over `closed[start..]` (see the module doc).
pub(super) fn estimate(
    closed: &[CycleValues],
    start: usize,
    w_tolerance: (f64, f64),
) -> MainValues {
    let start = start.max(1);
    let err = |get: fn(&CycleValues) -> f64, floor: fn(f64, (f64, f64)) -> f64| {
        let (transient, noise) = of(&Quantity { get, floor }, closed, start, w_tolerance);
        transient + noise
    };
    let has_half_width = closed[start..].iter().all(|c| c.main.slip_half_width.is_some());
    MainValues {
        period: err(|c| c.main.period, time_floor),
        t0: err(|c| c.main.t0, time_floor),
        slip_half_width: has_half_width
            .then(|| err(|c| c.main.slip_half_width.unwrap_or(0.0), time_floor)),
        v_max: err(|c| c.main.v_max, v_floor),
        ln_v_max: err(|c| c.main.ln_v_max, ln_v_floor),
        v_min: err(|c| c.main.v_min, v_floor),
        ln_v_min: err(|c| c.main.ln_v_min, ln_v_floor),
        slip: err(|c| c.main.slip, time_floor),
        slip_duration: err(|c| c.main.slip_duration, time_floor),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x_k = 10 + A ρ^k + alternating noise of size s.
    fn sequence(n: usize, a: f64, rho: f64, s: f64) -> Vec<f64> {
        (0..n).map(|k| 10.0 + a * rho.powi(k as i32) + if k % 2 == 0 { s } else { -s }).collect()
    }

    #[test]
    fn a_geometric_transient_is_bounded_and_unsettled_until_below_the_noise() {
        // ρ = 0.2, A = 1, noise 1e-9: the transient ρ^k falls below 0.3e-9 after k ≈ 14.
        let x = sequence(12, 1.0, 0.2, 1e-9);
        let (transient, noise) = quantity(&x, 6, 6, |m| 1e-12 * m);
        let mean = x[6..].iter().sum::<f64>() / 6.0;
        assert!((mean - 10.0).abs() <= transient + noise, "{transient} {noise}");
        assert!(transient > TRANSIENT_SHARE * noise, "a visible transient is not settled");
        let x = sequence(24, 1.0, 0.2, 1e-9);
        let (transient, noise) = quantity(&x, 18, 18, |m| 1e-12 * m);
        assert!(transient <= TRANSIENT_SHARE * noise, "{transient} {noise}");
        let mean = x[18..].iter().sum::<f64>() / 6.0;
        assert!((mean - 10.0).abs() <= transient + noise);
    }

    #[test]
    fn a_window_holding_the_jump_to_the_cycle_is_not_settled() {
        // The last small oscillation (period 12.7) before the relaxation cycle (62.56), as at
        // γ = 1e12, ξ = 0.7, ε = 0.72: its range would pass for noise.
        let x = [8.9, 9.35, 10.16, 12.69, 62.137, 62.5552, 62.5552, 62.5552, 62.5552];
        let (transient, noise) = quantity(&x, 3, 3, |m| 1e-12 * m);
        assert!(noise > 20.0, "{noise}");
        let (transient_after, noise_after) = quantity(&x, 5, 5, |m| 1e-12 * m);
        assert!(transient_after > TRANSIENT_SHARE * noise_after, "62.137 is still transient");
        let _ = transient;
    }

    #[test]
    fn noise_alone_settles_after_the_assumed_decay() {
        let x = sequence(12, 0.0, 0.0, 1e-9);
        let (transient, noise) = quantity(&x, 6, 6, |m| 1e-12 * m);
        assert!(transient <= TRANSIENT_SHARE * noise && noise >= 1e-9, "{transient} {noise}");
        let (transient, noise) = quantity(&x, 2, 2, |m| 1e-12 * m);
        assert!(transient > TRANSIENT_SHARE * noise, "too soon for the assumed ρ = 0.5");
    }
}
