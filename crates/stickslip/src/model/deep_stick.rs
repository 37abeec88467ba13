//! Sticks deeper than double precision: v is zero in every sum, and the exact solution is known.
//!
//! After a far-off start (v = 1e30 launches the block to u ≈ v/γ) or far from threshold, an
//! arrest can drop ln v to a floor −(ξu + θ) far below [`ARREST_RATE_HELD_BELOW`] (−500; at
//! v = 1e30, γ = 1e8, ξ = 0.2 the floor is near −2e21), and the stick that follows lasts
//! ~u time units (1e22). There v < 1e-217, so in double precision du/dt = v − 1 = −1, the state
//! law's v-terms vanish, and ln v stays on the slow manifold −(ξu + θ) (its distance to it
//! relaxes at a rate above 1e217 γ²). The solution to the point where ln v comes back up to
//! [`STICK_EXIT`] = −50 is then exact to double precision in closed form:
//!
//! ```text
//! u(t) = u0 − t,   θ(t) = θ0 (slip law),   θ(t) = θ0 + (1+ε) ln(1 + t e^(−θ0/(1+ε))) (ageing, PRZ),
//! ```
//!
//! and integrating it step by step (steps of at most the model's max step, over 1e22 time
//! units) is neither possible nor more accurate. What the closed form leaves out is v itself:
//! ∫v dt over the rest of the stick, ≤ e^(−50)/ξ ≈ 2e-22/ξ in u (and as little in θ), below
//! the spacing of doubles at |u| ≳ 1e-5/ξ. The integration resumes at ln v = −50 rather than
//! at the hold: a restarted integrator's first steps on the manifold at −500, where the
//! round-off of G times the rate 1e217γ² dominates f, do not grow (Rodas5P, extrapolation). Only the logarithmic friction law has such a
//! floor (the power law's f(v) stays bounded as v → 0; the asinh law reaches v = 0).
//!
//! Reference: the slow manifold and its stick, ../shared/paper (section on the relaxation
//! oscillation); the state laws' v → 0 limits, docs/state-laws.md.

use super::drr::{Drr, ARREST_RATE_HELD_BELOW, THETA, U, W};
use super::friction::Friction;
use super::state_law::StateLaw;

/// A stick below the hold, crossed in closed form ([`Drr::deep_stick`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeepStick {
    /// ln v on the slow manifold at the start: −(ξu0 + θ0).
    pub floor: f64,
    /// The lowest ln v of the stick and when (after its start) it is reached. Under the slip
    /// law ln v = −(ξ(u0 − t) + θ0) only rises: the floor at t = 0. Under ageing and PRZ,
    /// d ln v/dt = ξ − (1+ε) e^(−θ/(1+ε)): ln v keeps falling while θ < θ* = (1+ε) ln((1+ε)/ξ)
    /// and is lowest where θ reaches θ*, at t* = (1+ε)/ξ − e^(θ0/(1+ε)) (e^(θ/(1+ε)) grows by
    /// t). This minimum is a function of the orbit (ξu + ξe^(θ/(1+ε)) is constant on the stick),
    /// whereas the floor at the start depends on where the integrator's step crossed the hold
    /// (measured: ageing, γ = 1e8, ξ = 0.7, ε = 10: floor −500.0 … −500.3 from cycle to cycle,
    /// lowest ln v ≈ −605).
    pub lowest: (f64, f64),
    /// Time until ln v comes back up to [`STICK_EXIT`].
    pub duration: f64,
    /// The state there (on the slow manifold, ln v = [`STICK_EXIT`]).
    pub exit: [f64; 3],
}

/// ln v where the integration resumes after a stick crossed in closed form: v = 2e-22, still
/// below every sum's resolution (see the module documentation).
pub const STICK_EXIT: f64 = -50.0;

/// How close ln v must be to the floor (relative) for the arrest to count as settled.
const SETTLED: f64 = 1e-6;

impl Drr {
    /// The stick ahead of `y` when it lies wholly below the hold: ln v has settled on a floor
    /// −(ξu + θ) < −500 (logarithmic friction only). None otherwise. Asked after every step:
    /// the test that rules a stick out is inlined into the caller, the rest is not.
    #[inline]
    pub fn deep_stick(&self, y: &[f64; 3]) -> Option<DeepStick> {
        if self.params().friction != Friction::Log || y[W] >= ARREST_RATE_HELD_BELOW {
            return None;
        }
        self.deep_stick_below_hold(y)
    }

    /// [`Drr::deep_stick`] for ln v below the hold under logarithmic friction.
    #[inline(never)]
    fn deep_stick_below_hold(&self, y: &[f64; 3]) -> Option<DeepStick> {
        let p = self.params();
        let floor = -(p.xi * y[U] + y[THETA]);
        let settled = (y[W] - floor).abs() <= SETTLED * floor.abs();
        if !(floor < ARREST_RATE_HELD_BELOW && settled && floor.is_finite()) {
            return None;
        }
        let c = 1.0 + p.epsilon;
        let theta = |t: f64| at_rest(p.state_law, y[THETA], c, t);
        // ln v = −(ξ(u0 − t) + θ(t)) rises to the exit: the root of the concave, eventually
        // decreasing F(t) = ξ(u0 − t) + θ(t) + exit, with F(0) = exit − floor > 0.
        let excess = |t: f64| p.xi * (y[U] - t) + theta(t) + STICK_EXIT;
        let mut hi = (STICK_EXIT - floor) / p.xi;
        while excess(hi) > 0.0 {
            hi *= 2.0;
            if !hi.is_finite() {
                return None;
            }
        }
        let mut lo = 0.0;
        for _ in 0..2100 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if excess(mid) > 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let theta_exit = theta(hi);
        let u_exit = -(theta_exit + STICK_EXIT) / p.xi;
        let theta_star = c * (c / p.xi).ln();
        let lowest = match p.state_law {
            StateLaw::Ageing | StateLaw::Prz if y[THETA] < theta_star => {
                let t_star = (c / p.xi - (y[THETA] / c).exp()).clamp(0.0, hi);
                ((-(p.xi * (y[U] - t_star) + theta_star)).min(floor), t_star)
            }
            _ => (floor, 0.0),
        };
        Some(DeepStick { floor, lowest, duration: hi, exit: [u_exit, STICK_EXIT, theta_exit] })
    }
}

/// θ after `t` at rest (v = 0 in double precision) from θ0, with c = 1 + ε.
fn at_rest(law: StateLaw, theta0: f64, c: f64, t: f64) -> f64 {
    match law {
        // dθ/dt = −c v x → 0, and without healing −c v → 0.
        StateLaw::Slip | StateLaw::NoHealing => theta0,
        // dθ/dt = c e^(−θ/c) (PRZ's v²-term vanishes too): e^(θ/c) grows by t, i.e.
        // θ = θ0 + c ln(1 + t e^(−θ0/c)) = θ0 + c softplus(ln t − θ0/c), which stays finite
        // where e^(−θ0/c) overflows.
        StateLaw::Ageing | StateLaw::Prz if t > 0.0 => {
            let l = t.ln() - theta0 / c;
            theta0 + c * (l.max(0.0) + (-l.abs()).exp().ln_1p())
        }
        StateLaw::Ageing | StateLaw::Prz => theta0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DrrParams;

    fn drr(law: StateLaw, friction: Friction) -> Drr {
        Drr::new(DrrParams { state_law: law, ..DrrParams::new(1e8, 2.0, 5.0, friction) })
    }

    #[test]
    fn slip_law_stick_is_the_plate_catching_up() {
        // ξu + θ = 1000: the floor is ln v = −1000, and ln v = −(ξ(u0 − t) + θ0) reaches −50
        // after (1000 − 50)/ξ.
        let stick = drr(StateLaw::Slip, Friction::Log)
            .deep_stick(&[1e3, -1e3, -1e3])
            .expect("a deep stick");
        assert_eq!(stick.floor, -1e3);
        assert!((stick.duration - 475.0).abs() < 1e-12, "{stick:?}");
        assert!(
            (stick.exit[U] - 525.0).abs() < 1e-12
                && stick.exit[W] == STICK_EXIT
                && stick.exit[THETA] == -1e3,
            "{stick:?}"
        );
    }

    #[test]
    fn ageing_and_prz_sticks_follow_their_healing_law() {
        for law in [StateLaw::Ageing, StateLaw::Prz] {
            let d = drr(law, Friction::Log);
            let (u, theta0) = (510.0, -20.0);
            let y = [u, -(2.0 * u + theta0), theta0];
            let stick = d.deep_stick(&y).expect("a deep stick");
            // RK4 on dθ/dt = (1+ε) e^(−θ/(1+ε)) (v = 0) over the stick's duration.
            let c = 6.0;
            let (n, mut theta) = (200_000, y[THETA]);
            let h = stick.duration / n as f64;
            let f = |th: f64| c * (-th / c).exp();
            for _ in 0..n {
                let k1 = f(theta);
                let k2 = f(theta + 0.5 * h * k1);
                let k3 = f(theta + 0.5 * h * k2);
                let k4 = f(theta + h * k3);
                theta += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            }
            assert!(
                (stick.exit[THETA] - theta).abs() < 1e-9 * theta.abs().max(1.0),
                "{law:?}: {} vs {theta}",
                stick.exit[THETA]
            );
            // The exit is on the slow manifold at ln v = −50, and u fell by the duration.
            assert!(
                (2.0 * stick.exit[U] + stick.exit[THETA] + STICK_EXIT).abs() < 1e-9,
                "{stick:?}"
            );
            assert!((y[U] - stick.duration - stick.exit[U]).abs() < 1e-9 * y[U], "{stick:?}");
        }
    }

    #[test]
    fn the_lowest_ln_v_of_a_healing_stick_lies_below_its_start() {
        // Slip law: ln v only rises from the floor.
        let stick = drr(StateLaw::Slip, Friction::Log)
            .deep_stick(&[1e3, -1e3, -1e3])
            .expect("a deep stick");
        assert_eq!(stick.lowest, (-1e3, 0.0));
        for law in [StateLaw::Ageing, StateLaw::Prz] {
            let d = drr(law, Friction::Log);
            // ξ = 2, 1 + ε = 6: θ0 = −20 heals faster than ξ until θ* = 6 ln 3.
            let (u, theta0) = (510.0, -20.0);
            let y = [u, -(2.0 * u + theta0), theta0];
            let stick = d.deep_stick(&y).expect("a deep stick");
            // ln v = −(ξ(u0 − t) + θ(t)) on a fine grid of the stick.
            let n = 2_000_000;
            let (mut best, mut at) = (f64::INFINITY, 0.0);
            for i in 0..=n {
                let t = stick.duration * i as f64 / n as f64;
                let w = -(2.0 * (u - t) + at_rest(law, theta0, 6.0, t));
                if w < best {
                    (best, at) = (w, t);
                }
            }
            assert!(stick.lowest.0 < stick.floor - 1.0, "{stick:?}");
            assert!(
                (stick.lowest.0 - best).abs() < 1e-9 * best.abs(),
                "{law:?}: {:?} vs {best}",
                stick.lowest
            );
            assert!((stick.lowest.1 - at).abs() < 1e-3, "{law:?}: {:?} vs t = {at}", stick.lowest);
            assert!((stick.lowest.1 - (3.0 - (-20.0f64 / 6.0).exp())).abs() < 1e-12);
        }
    }

    #[test]
    fn only_a_settled_log_friction_stick_below_the_hold_is_crossed() {
        let log = drr(StateLaw::Slip, Friction::Log);
        assert!(log.deep_stick(&[1e3, -900.0, -1e3]).is_none(), "still falling to its floor −1000");
        assert!(log.deep_stick(&[100.0, -150.0, -50.0]).is_none(), "floor −150 is above the hold");
        let power = drr(StateLaw::Slip, Friction::Power { alpha: 0.3 });
        assert!(power.deep_stick(&[1e3, -1e3, -1e3]).is_none(), "no floor under the power law");
    }
}
