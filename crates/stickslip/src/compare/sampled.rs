//! Events located on samples: the same rules for a user's samples and for the reference
//! evaluated at the same (per-event shifted) times, so the interpolation between samples is
//! common to both.
//!
//! An event is a slip episode, v ≥ 1: it starts at an upward crossing of v = 1 and ends at
//! the next downward crossing. Crossings are located by linear interpolation in ln v, the v
//! maximum by the parabola through the largest sample and its neighbours, and the slip
//! ∫v dt = Δ(u + t) (du/dt = v − 1) by linear interpolation of u + t in ln v at the two
//! crossings.
//!
//! The peak's time is the vertex of the parabola of ln v in t; its value, ln v_max, the maximum
//! of the cubic of ln v in θ through the four samples around it, where θ is strictly monotonic
//! over them (it falls through every peak the laws make): the value then does not depend on
//! the samples' times,
//! which a file may print with too few digits to place samples 1e-5 apart within a step
//! (QDYN's 14 digits at t ~ 1e8 s: a quarter of a step at a peak, 5e-6 in ln v_max), while θ
//! is printed to far below a step's change (7 digits of a 1 % change).

/// Largest |Δ ln v| between the two samples around an upward crossing of v = 1 for it to be
/// located by interpolation.
pub const MAX_EVENT_JUMP: f64 = 0.5;
/// Largest drop of ln v from the sampled maximum to its neighbours for the parabola through
/// the three to locate the v maximum.
pub const MAX_PEAK_DROP: f64 = 0.1;

/// One complete event (slip episode), located on samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledEvent {
    /// Upward crossing of v = 1.
    pub start: f64,
    /// Time of the v maximum.
    pub peak: f64,
    /// Downward crossing of v = 1.
    pub end: f64,
    /// ln v_max.
    pub ln_v_max: f64,
    /// ∫v dt from `start` to `end`.
    pub slip: f64,
}

/// Why the events of a sampled trajectory cannot be located: the samples around one are too
/// far apart; the message names the samples and the spacing needed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SamplingError {
    /// ln v jumps too far across an upward crossing of v = 1.
    #[error(
        "{from}–{to}: ln v jumps from {:.3} to {:.3} across the {event}; sampled too coarsely to locate it \
         (|Δ ln v| ≤ {max} is needed between the samples around each event's start)",
        ln_v[0],
        ln_v[1],
        max = MAX_EVENT_JUMP
    )]
    Event {
        /// The sample before the event.
        from: String,
        /// The sample after it.
        to: String,
        /// ln v at the two samples.
        ln_v: [f64; 2],
        /// The event: "upward crossing of v = 1".
        event: &'static str,
    },
    /// The samples either side of an event's v maximum are too far below it.
    #[error(
        "{at}: the v maximum of event {event} (ln v = {ln_v:.3}) is sampled too coarsely to locate it \
         (ln v must be within {max} of the maximum at the samples either side)",
        max = MAX_PEAK_DROP
    )]
    Peak {
        /// The sample at the maximum.
        at: String,
        /// The event (1-based).
        event: usize,
        /// ln v there.
        ln_v: f64,
    },
}

/// The fraction of the way from sample i to i + 1 at which w crosses `level`.
fn fraction(w: &[f64], i: usize, level: f64) -> f64 {
    (level - w[i]) / (w[i + 1] - w[i])
}

/// The vertex (abscissa, value) of the parabola through (x, y) at three points, or the middle
/// point where the parabola does not open downwards.
fn vertex(x: [f64; 3], y: [f64; 3]) -> (f64, f64) {
    let d1 = (y[1] - y[0]) / (x[1] - x[0]);
    let d2 = (y[2] - y[1]) / (x[2] - x[1]);
    let c = (d2 - d1) / (x[2] - x[0]);
    if c < 0.0 {
        let xp = 0.5 * (x[0] + x[1]) - d1 / (2.0 * c);
        (xp, y[0] + (xp - x[0]) * (d1 + c * (xp - x[1])))
    } else {
        (x[1], y[1])
    }
}

/// The largest value of the cubic through (x, y) at four points between `range`'s two
/// abscissas (golden-section search: the cubic has one maximum there, around the largest
/// sample).
fn cubic_maximum(x: [f64; 4], y: [f64; 4], range: [f64; 2]) -> f64 {
    let p = |s: f64| -> f64 {
        (0..4)
            .map(|i| {
                let l: f64 =
                    (0..4).filter(|&m| m != i).map(|m| (s - x[m]) / (x[i] - x[m])).product();
                y[i] * l
            })
            .sum()
    };
    let (mut a, mut b) = (range[0], range[1]);
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (p(c), p(d));
    for _ in 0..80 {
        if fc > fd {
            (b, d, fd) = (d, c, fc);
            c = b - r * (b - a);
            fc = p(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + r * (b - a);
            fd = p(d);
        }
    }
    fc.max(fd).max(y.into_iter().fold(f64::NEG_INFINITY, f64::max))
}

/// The complete events (v ≥ 1 from an upward to a downward crossing of v = 1, both inside
/// the samples) of a sampled trajectory: times `t`, states (u, w = ln v, θ). `origin(i)`
/// names sample i for messages. The end of an event may be sampled coarsely (the slip
/// Δ(u + t) barely changes across it); its start and its maximum may not.
pub fn sampled_events(
    t: &[f64],
    states: &[[f64; 3]],
    origin: &dyn Fn(usize) -> String,
) -> Result<Vec<SampledEvent>, SamplingError> {
    let w: Vec<f64> = states.iter().map(|y| y[1]).collect();
    let (u, theta) = (|k: usize| states[k][0], |k: usize| states[k][2]);
    let n = t.len();
    let mut events = Vec::new();
    let mut i = 0;
    while i + 1 < n {
        if !(w[i] < 0.0 && w[i + 1] >= 0.0) {
            i += 1;
            continue;
        }
        let Some(down) = (i + 1..n - 1).find(|&j| w[j] >= 0.0 && w[j + 1] < 0.0) else {
            break;
        };
        if (w[i + 1] - w[i]).abs() > MAX_EVENT_JUMP {
            return Err(SamplingError::Event {
                from: origin(i),
                to: origin(i + 1),
                ln_v: [w[i], w[i + 1]],
                event: "upward crossing of v = 1",
            });
        }
        let a = fraction(&w, i, 0.0);
        let start = t[i] + a * (t[i + 1] - t[i]);
        let j = (i + 1..=down).max_by(|&x, &y| w[x].total_cmp(&w[y])).expect("a non-empty range");
        if w[j] - w[j - 1] > MAX_PEAK_DROP || w[j] - w[j + 1] > MAX_PEAK_DROP {
            return Err(SamplingError::Peak { at: origin(j), event: events.len() + 1, ln_v: w[j] });
        }
        // The parabola through the three samples around the maximum in t for its time; its
        // value from θ (where monotonic) by the cubic through the four samples around the
        // interval it lies in (the largest and its larger neighbour).
        let around = [j - 1, j, j + 1];
        let (peak, ln_v_max_in_t) = vertex(around.map(|k| t[k]), around.map(|k| w[k]));
        let first = if w[j + 1] > w[j - 1] { j - 1 } else { j.saturating_sub(2) };
        let four = [first, first + 1, first + 2, first + 3];
        let th = four.map(theta);
        let monotonic = th.windows(2).all(|p| p[0] < p[1]) || th.windows(2).all(|p| p[0] > p[1]);
        let ln_v_max = if monotonic && j >= 2 && first + 3 < n {
            cubic_maximum(th, four.map(|k| w[k]), [theta(j - 1), theta(j + 1)])
        } else {
            ln_v_max_in_t
        };
        let b = fraction(&w, down, 0.0);
        let end = t[down] + b * (t[down + 1] - t[down]);
        // u + t, whose rate is v, at the two crossings.
        let s = |k: usize, f: f64| (u(k) + t[k]) + f * ((u(k + 1) + t[k + 1]) - (u(k) + t[k]));
        events.push(SampledEvent { start, peak, end, ln_v_max, slip: s(down, b) - s(i, a) });
        i = down + 1;
    }
    Ok(events)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth pulse ln v = 3 − (t − 5)², sampled finely: crossings at 5 ± √3, the maximum
    /// at 5 with ln v 3, and the slip ∫v dt with u = −t + ∫v (so u + t = ∫v).
    #[test]
    fn a_sampled_pulse() {
        let t: Vec<f64> = (0..=10_000).map(|i| i as f64 * 1e-3).collect();
        let w: Vec<f64> = t.iter().map(|t| 3.0 - (t - 5.0) * (t - 5.0)).collect();
        // ∫ e^w dt by the trapezoid rule on a finer grid, as u + t.
        let mut integral = vec![0.0; t.len()];
        for k in 1..t.len() {
            let fine = 20;
            let h = (t[k] - t[k - 1]) / fine as f64;
            let f = |s: f64| (3.0 - (s - 5.0) * (s - 5.0)).exp();
            integral[k] = integral[k - 1]
                + (0..fine)
                    .map(|m| {
                        let a = t[k - 1] + m as f64 * h;
                        0.5 * h * (f(a) + f(a + h))
                    })
                    .sum::<f64>();
        }
        let u: Vec<f64> = t.iter().zip(&integral).map(|(t, i)| i - t).collect();
        let origin = |i: usize| format!("index {i}");
        // θ falling through the peak (as it does in a slip), then flat (θ not monotonic).
        let states = |theta: &dyn Fn(f64) -> f64| -> Vec<[f64; 3]> {
            (0..t.len()).map(|i| [u[i], w[i], theta(t[i])]).collect()
        };
        let falling = states(&|t| -t);
        let flat = states(&|_| 0.0);
        let e = sampled_events(&t, &falling, &origin).unwrap();
        assert_eq!(e.len(), 1);
        let r3 = 3f64.sqrt();
        assert!((e[0].start - (5.0 - r3)).abs() < 1e-6, "{:?}", e[0]);
        assert!((e[0].end - (5.0 + r3)).abs() < 1e-6, "{:?}", e[0]);
        assert!((e[0].peak - 5.0).abs() < 1e-9 && (e[0].ln_v_max - 3.0).abs() < 1e-9);
        // ∫ e^(3 − x²) dx over |x| ≤ √3 = e³·√π·erf(√3), erf(√3) = 0.9856941215645704.
        let exact = 3f64.exp() * std::f64::consts::PI.sqrt() * 0.985_694_121_564_570_4;
        assert!((e[0].slip - exact).abs() < 1e-6 * exact, "{} {exact}", e[0].slip);
        // ln v_max does not depend on the samples' times where θ is monotonic: with the
        // times near the peak off by a quarter of a step it is unchanged, while the
        // parabola in t (θ flat) moves.
        let mut noisy = t.clone();
        noisy[4999] += 2.5e-4;
        let in_theta = sampled_events(&noisy, &falling, &origin).unwrap()[0].ln_v_max;
        let in_t = sampled_events(&noisy, &flat, &origin).unwrap()[0].ln_v_max;
        assert!((in_theta - 3.0).abs() < 1e-9, "{in_theta}");
        assert!((in_t - 3.0).abs() > 1e-8, "{in_t}");
        // Cut before the end: the event is incomplete and not returned.
        assert!(sampled_events(&t[..6000], &falling[..6000], &origin).unwrap().is_empty());
        // Every 500th sample: the start jumps too far in ln v.
        let pick: Vec<usize> = (0..t.len()).step_by(500).collect();
        let t_sub: Vec<f64> = pick.iter().map(|&i| t[i]).collect();
        let y_sub: Vec<[f64; 3]> = pick.iter().map(|&i| falling[i]).collect();
        let e = sampled_events(&t_sub, &y_sub, &origin).unwrap_err();
        assert!(matches!(e, SamplingError::Event { .. }), "{e}");
    }
}
