//! Periodic orbits by Newton shooting on the Poincaré section v = 1 (upward), with their
//! Floquet multipliers, and period doubling.
//!
//! Unknowns: the section point (u, θ) (w = 0). One Newton iteration integrates the state and
//! its variational equations over one return ([`period_map`]) and solves
//! (DP − I) δ = −(P(x) − x) with the linearised Poincaré map DP; a step that does not reduce
//! the residual is halved (up to 8 times). The orbit's Floquet multipliers are the
//! eigenvalues of the monodromy matrix Φ(T); one of them is 1 (the flow direction), and how
//! close the computed one comes is reported as a check of the whole computation. When that
//! check fails (error above [`MULTIPLIER_CHECK_ABOVE`]), the non-trivial multipliers are
//! checked against central differences of the map and replaced or withheld (module `check`):
//! unresolved multipliers are never reported, and their stability is unknown (null).
//!
//! A real multiplier below −1 means the period-1 orbit has lost stability by period doubling.
//! The doubled orbit is then sought by the same Newton iteration on P∘P, from the period-1
//! orbit displaced along the flip eigenvector; it is reported only if it differs from the
//! period-1 orbit.
//!
//! Reference: R. Seydel, *Practical Bifurcation and Stability Analysis*, 3rd ed., Springer
//! 2010, §7.3 (shooting) and §7.4 (Floquet multipliers).

mod check;
mod options;

pub use check::{MultiplierCheck, MultiplierSource};
pub use options::ShootingOptions;

use super::period_map::{self, Limits, Return};
use super::AnalysisError;
use crate::integrate::Integrator;
use crate::model::drr::{Drr, THETA, U, W};
use nalgebra::{Matrix2, Matrix3};
use serde::Serialize;

/// How shooting runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShootingSettings {
    /// Converged when max_i |P(x)_i − x_i| / max_i |x_i − x*_i| ≤ tolerance (x*: the fixed
    /// point, which lies on the section).
    pub tolerance: f64,
    /// Newton iterations before giving up.
    pub max_iterations: usize,
    /// Plain iterations of the map at most, before Newton (while they contract fast or the
    /// oscillation grows away from the fixed point).
    pub max_warmup: usize,
    /// Limits of each return.
    pub limits: Limits,
    /// Above this trivial multiplier error the non-trivial multipliers are checked against
    /// central differences of the map (module `check`).
    pub multiplier_check_above: f64,
}

impl ShootingSettings {
    /// Defaults for an integration at `rtol` with absolute tolerance `atol_w` on w: tolerance
    /// 10·rtol within [1e-12, 1e-4], 30 Newton iterations after at most 500 plain ones, returns within t = 1e5 and 1e6 steps.
    pub fn defaults(rtol: f64, atol_w: f64) -> Self {
        Self {
            tolerance: (10.0 * rtol).clamp(1e-12, 1e-4),
            max_iterations: 30,
            max_warmup: 500,
            limits: Limits { w_tolerance: (rtol, atol_w), max_time: 1e5, max_steps: 1_000_000 },
            multiplier_check_above: MULTIPLIER_CHECK_ABOVE,
        }
    }
}

/// The default bound on the trivial multiplier's error above which the non-trivial multipliers
/// are checked against the map's central differences. The cancellation in the fixed-time
/// monodromy alone gives errors up to 3.7e-2 at γ = 1e8 (Radau5, rtol 1e-10: slip, ageing,
/// PRZ laws), where DP agrees with the differences; a failed variational integration gives
/// ≈ 1 (CVODE at γ ≥ 1e8, Radau5 under the ageing law at 1e12).
pub const MULTIPLIER_CHECK_ABOVE: f64 = 5e-2;

/// A Floquet multiplier μ (complex).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Multiplier {
    /// Re μ.
    pub re: f64,
    /// Im μ.
    pub im: f64,
    /// |μ|.
    pub modulus: f64,
}

/// A periodic orbit found by shooting.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodicOrbit {
    /// The orbit's point on the section: (u, v = 1, θ).
    pub section_point: [f64; 3],
    /// Period (for a doubled orbit, the full period: two returns).
    pub period: f64,
    /// Returns to the section per period (1, or 2 for a doubled orbit).
    pub returns_per_period: usize,
    /// Times of the returns (each from one crossing of the section to the next).
    pub return_times: Vec<f64>,
    /// Time from the section to the first v maximum.
    pub t0: f64,
    /// Largest v over the period.
    pub v_max: f64,
    /// ln v_max.
    pub ln_v_max: f64,
    /// Smallest ln v over the period.
    pub ln_v_min: f64,
    /// u at the (first) v maximum.
    pub u_at_v_max: f64,
    /// θ at the (first) v maximum.
    pub theta_at_v_max: f64,
    /// Floquet multipliers: first the trivial one, the eigenvalue closest to 1 of the
    /// fixed-time monodromy matrix Φ(T) (a check: it loses accuracy roughly in proportion to γ,
    /// measured |μ − 1| ≈ 1e-7 at γ = 1e3, 1e-5 at 1e5, 3e-2 at 1e8 with Radau5 at rtol
    /// 1e-10, because Φ(T) is the product of factors as large as dy/dt in the slip); then the
    /// non-trivial ones, the eigenvalues of the linearised Poincaré map (the product of the
    /// section maps, free of that cancellation; or the map's central differences, see
    /// `multipliers_source`), by decreasing modulus; none when they are unresolved.
    pub multipliers: Vec<Multiplier>,
    /// |μ_trivial − 1|: the check that the flow direction is reproduced.
    pub trivial_multiplier_error: f64,
    /// Whether every non-trivial multiplier lies inside the unit circle (by more than their
    /// uncertainty, when they were checked); None (null) when unknown: the multipliers are
    /// unresolved, or within their uncertainty of the unit circle.
    pub stable: Option<bool>,
    /// Where the non-trivial multipliers come from (`section_jacobian`,
    /// `section_jacobian_checked`, `map_differences`, `unresolved`).
    pub multipliers_source: MultiplierSource,
    /// The check against the map's central differences, when it ran.
    pub multipliers_check: Option<MultiplierCheck>,
    /// Why the multipliers are not DP's, or the stability is unknown (null otherwise).
    pub multipliers_note: Option<String>,
    /// The matrix whose eigenvalues are the non-trivial multipliers (DP or the differences).
    #[serde(skip)]
    pub map_jacobian: Option<Matrix2<f64>>,
    /// Iterations used (plain warm-up iterations of the map, then Newton's).
    pub newton_iterations: usize,
    /// Final residual max_i |P(x)_i − x_i| / max_i |x_i − x*_i|.
    pub residual: f64,
    /// Integrator steps of the final evaluation (one period).
    pub steps_per_period: u64,
}

impl PeriodicOrbit {
    /// The non-trivial multipliers.
    pub fn nontrivial(&self) -> &[Multiplier] {
        &self.multipliers[1..]
    }

    /// The largest non-trivial multiplier that is real and negative (the one that can flip).
    pub fn negative_real_multiplier(&self) -> Option<f64> {
        self.nontrivial()
            .iter()
            .find(|m| m.im.abs() <= 1e-9 * m.modulus && m.re < 0.0)
            .map(|m| m.re)
    }
}

/// One Newton iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Iteration {
    /// Residual before the step.
    pub residual: f64,
    /// Return time at the iterate.
    pub period: f64,
    /// Step halvings needed.
    pub halvings: u32,
}

/// Period doubling of the period-1 orbit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodDoubling {
    /// The real multiplier below −1.
    pub multiplier: f64,
    /// The doubled orbit, if found.
    pub doubled: Option<PeriodicOrbit>,
    /// What happened in the search for it.
    pub note: String,
}

/// The "shooting" section of a report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShootingReport {
    /// Whether Newton converged.
    pub converged: bool,
    /// The periodic orbit (when converged).
    pub orbit: Option<PeriodicOrbit>,
    /// Why it did not converge.
    #[serde(serialize_with = "display")]
    pub failure: Option<NoOrbit>,
    /// The Newton iterations.
    pub iterations: Vec<Iteration>,
    /// Period doubling, when a multiplier is below −1.
    pub period_doubling: Option<PeriodDoubling>,
    /// Convergence tolerance.
    pub tolerance: f64,
}

/// Why Newton's iteration found no periodic orbit (its text is the report's `failure`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoOrbit {
    /// The iteration converged onto the fixed point (a trivial solution on the section).
    #[error("converged onto the fixed point (ln v range {amplitude:.3e} below the noise floor {floor:.1e})")]
    FixedPoint {
        /// The ln v range of the converged returns.
        amplitude: f64,
        /// The integration noise floor on ln v.
        floor: f64,
    },
    /// The iteration budget ran out.
    #[error("Newton did not converge in {iterations} iterations (residual {residual:.3e})")]
    MaxIterations {
        /// The budget (`max_iterations`).
        iterations: usize,
        /// The last residual.
        residual: f64,
    },
    /// DP − I is singular: a multiplier 1.
    #[error(
        "the linearised Poincaré map has a multiplier 1 (DP − I is singular): a bifurcation point"
    )]
    Singular,
    /// Eight halvings of the Newton step did not reduce the residual.
    #[error("Newton stalled at residual {residual:.3e} (no decrease after 8 step halvings)")]
    Stalled {
        /// The residual that did not decrease.
        residual: f64,
    },
}

/// The outcome of Newton's iteration: an orbit, or why not (integration failures are errors).
#[derive(Debug, Clone, PartialEq)]
pub struct Newton {
    /// The orbit, when converged.
    pub orbit: Result<PeriodicOrbit, NoOrbit>,
    /// The iterations.
    pub iterations: Vec<Iteration>,
}

/// Serialises why not as its text (the report's `failure`: a string or null).
fn display<S: serde::Serializer>(why: &Option<NoOrbit>, serializer: S) -> Result<S::Ok, S::Error> {
    match why {
        Some(why) => serializer.collect_str(why),
        None => serializer.serialize_none(),
    }
}

fn section(x: [f64; 2]) -> [f64; 3] {
    let mut y = [0.0; 3];
    y[U] = x[0];
    y[THETA] = x[1];
    y
}

/// The residual P(x) − x and its size relative to the distance of x from the fixed point
/// (which lies on the section and is a trivial solution: near it every small oscillation
/// has a small absolute residual).
fn residual(drr: &Drr, x: [f64; 2], end: &[f64; 3]) -> ([f64; 2], f64) {
    let fixed = drr.fixed_point();
    let r = [end[U] - x[0], end[THETA] - x[1]];
    let distance = (x[0] - fixed[U]).abs().max((x[1] - fixed[THETA]).abs());
    let scaled = r[0].abs().max(r[1].abs()) / distance;
    (r, if scaled.is_finite() { scaled } else { f64::INFINITY })
}

fn distance_from_fixed_point(drr: &Drr, x: [f64; 2]) -> f64 {
    let fixed = drr.fixed_point();
    (x[0] - fixed[U]).abs().max((x[1] - fixed[THETA]).abs())
}

/// `returns` successive returns from the section point x.
fn returns(
    integ: &mut dyn Integrator,
    drr: &Drr,
    x: [f64; 2],
    count: usize,
    limits: &Limits,
) -> Result<Vec<Return>, AnalysisError> {
    let mut out: Vec<Return> = Vec::with_capacity(count);
    let mut start = section(x);
    for _ in 0..count {
        let r = period_map::flow_to_section(integ, drr, start, true, limits)?;
        start = r.end;
        start[W] = 0.0;
        out.push(r);
    }
    Ok(out)
}

/// The linearised Poincaré map over the returns: the product of their section Jacobians.
fn map_jacobian(rs: &[Return]) -> Matrix2<f64> {
    rs.iter().fold(Matrix2::identity(), |acc, r| r.section_jacobian * acc)
}

/// The eigenvalue of the fixed-time monodromy matrix closest to 1 (the trivial multiplier).
fn trivial_multiplier(monodromy: &Matrix3<f64>) -> Multiplier {
    let distance = |z: &nalgebra::Complex<f64>| (z.re - 1.0).hypot(z.im);
    let z = monodromy
        .complex_eigenvalues()
        .iter()
        .copied()
        .min_by(|a, b| distance(a).total_cmp(&distance(b)))
        .unwrap_or_default();
    Multiplier { re: z.re, im: z.im, modulus: z.norm() }
}

fn orbit_from(
    integ: &mut dyn Integrator,
    drr: &Drr,
    x: [f64; 2],
    rs: &[Return],
    newton: (usize, f64),
    settings: &ShootingSettings,
) -> PeriodicOrbit {
    let (iterations, residual) = newton;
    let monodromy = rs.iter().fold(Matrix3::identity(), |acc, r| r.fundamental * acc);
    let dp = map_jacobian(rs);
    let trivial = trivial_multiplier(&monodromy);
    let trivial_multiplier_error = (trivial.re - 1.0).hypot(trivial.im);
    let checked = check::check(integ, drr, x, rs, &dp, trivial_multiplier_error, settings);
    let (stable, mut note) = stability(&checked);
    if let Some(why) = &checked.note {
        note = Some(note.map_or(why.clone(), |n| format!("{why}; {n}")));
    }
    let mut mu = checked.multipliers.unwrap_or_default();
    mu.insert(0, trivial);
    let highest = rs.iter().max_by(|a, b| a.peak[W].total_cmp(&b.peak[W])).unwrap_or(&rs[0]);
    let ln_v_max = highest.peak[W];
    PeriodicOrbit {
        section_point: [x[0], 1.0, x[1]],
        period: rs.iter().map(|r| r.period).sum(),
        returns_per_period: rs.len(),
        return_times: rs.iter().map(|r| r.period).collect(),
        t0: rs[0].t_peak,
        v_max: ln_v_max.exp(),
        ln_v_max,
        ln_v_min: rs.iter().map(|r| r.ln_v_min).fold(f64::INFINITY, f64::min),
        u_at_v_max: rs[0].peak[U],
        theta_at_v_max: rs[0].peak[THETA],
        multipliers: mu,
        trivial_multiplier_error,
        stable,
        multipliers_source: checked.source,
        multipliers_check: checked.check,
        multipliers_note: note,
        map_jacobian: checked.jacobian,
        newton_iterations: iterations,
        residual,
        steps_per_period: rs.iter().map(|r| r.steps).sum(),
    }
}

/// The stability verdict from checked multipliers, and why it is unknown when it is: every
/// |μ| below 1 by more than the uncertainty → stable; one above 1 by more → unstable; else
/// unknown. The uncertainty is 0 for unchecked DP (as before the check existed), the larger
/// of the spread and DP's distance from the differences otherwise.
fn stability(checked: &check::Checked) -> (Option<bool>, Option<String>) {
    let Some(mu) = &checked.multipliers else { return (None, None) };
    let uncertainty = checked.check.map_or(0.0, |c| match checked.source {
        MultiplierSource::SectionJacobianChecked => {
            c.differences_spread.max(c.section_jacobian_difference)
        }
        _ => c.differences_spread,
    });
    let largest = mu.iter().map(|m| m.modulus).fold(0.0, f64::max);
    if largest + uncertainty < 1.0 {
        (Some(true), None)
    } else if largest - uncertainty > 1.0 {
        (Some(false), None)
    } else {
        (None, Some(format!("the largest |μ| = {largest:.6} is within its uncertainty {uncertainty:.1e} of 1: stability unknown")))
    }
}

/// Plain iterations of the map while they halve the residual, then Newton's iteration for a periodic orbit through the section point near `x0` that returns
/// to it after `count` returns.
pub fn newton(
    integ: &mut dyn Integrator,
    drr: &Drr,
    x0: [f64; 2],
    count: usize,
    settings: &ShootingSettings,
) -> Result<Newton, AnalysisError> {
    let mut x = x0;
    let mut rs = returns(integ, drr, x, count, &settings.limits)?;
    let (mut r, mut res) = residual(drr, x, &rs[count - 1].end);
    let mut iterations = Vec::new();
    // Warm-up: plain iterations of the map while they contract fast (far from the orbit, e.g.
    // near the unstable fixed point, Newton's linear model can lead to a spurious tiny orbit).
    for _ in 0..settings.max_warmup {
        let trial = [rs[count - 1].end[U], rs[count - 1].end[THETA]];
        let trs = returns(integ, drr, trial, count, &settings.limits)?;
        let (tr, tres) = residual(drr, trial, &trs[count - 1].end);
        iterations.push(Iteration {
            residual: res,
            period: rs.iter().map(|ret| ret.period).sum(),
            halvings: 0,
        });
        // Fast contraction, or a small oscillation still growing away from the fixed point.
        let growing =
            distance_from_fixed_point(drr, trial) > 1.01 * distance_from_fixed_point(drr, x);
        let fast = tres < 0.5 * res || growing;
        (x, rs, r, res) = (trial, trs, tr, tres);
        if !fast || res <= settings.tolerance {
            break;
        }
    }
    let warmup = iterations.len();
    loop {
        if res <= settings.tolerance {
            let amplitude = rs.iter().map(|ret| ret.peak[W]).fold(0.0, f64::max)
                - rs.iter().map(|ret| ret.ln_v_min).fold(0.0, f64::min);
            let floor =
                1e-9f64.max(1e3 * (settings.limits.w_tolerance.0 + settings.limits.w_tolerance.1));
            if amplitude < floor {
                return Ok(Newton {
                    orbit: Err(NoOrbit::FixedPoint { amplitude, floor }),
                    iterations,
                });
            }
            let orbit = orbit_from(integ, drr, x, &rs, (iterations.len(), res), settings);
            return Ok(Newton { orbit: Ok(orbit), iterations });
        }
        if iterations.len() - warmup >= settings.max_iterations {
            let why = NoOrbit::MaxIterations { iterations: settings.max_iterations, residual: res };
            return Ok(Newton { orbit: Err(why), iterations });
        }
        let dp = map_jacobian(&rs);
        let Some(delta) =
            (dp - Matrix2::identity()).lu().solve(&nalgebra::Vector2::new(-r[0], -r[1]))
        else {
            return Ok(Newton { orbit: Err(NoOrbit::Singular), iterations });
        };
        let period: f64 = rs.iter().map(|ret| ret.period).sum();
        let mut lambda = 1.0;
        let mut halvings = 0;
        let accepted = loop {
            let trial = [x[0] + lambda * delta[0], x[1] + lambda * delta[1]];
            let outcome = returns(integ, drr, trial, count, &settings.limits);
            match outcome {
                Ok(trs) => {
                    let (tr, tres) = residual(drr, trial, &trs[count - 1].end);
                    if tres < res || halvings >= 8 {
                        break Some((trial, trs, tr, tres));
                    }
                }
                Err(e) if halvings >= 8 => return Err(e),
                Err(_) => {}
            }
            lambda *= 0.5;
            halvings += 1;
        };
        iterations.push(Iteration { residual: res, period, halvings });
        if let Some((trial, trs, tr, tres)) = accepted {
            if tres >= res {
                return Ok(Newton { orbit: Err(NoOrbit::Stalled { residual: res }), iterations });
            }
            (x, rs, r, res) = (trial, trs, tr, tres);
        }
    }
}

/// Reaches the section from `y0` (the first upward crossing of v = 1).
pub fn reach_section(
    integ: &mut dyn Integrator,
    drr: &Drr,
    y0: [f64; 3],
    limits: &Limits,
) -> Result<[f64; 2], AnalysisError> {
    let r = period_map::flow_to_section(integ, drr, y0, false, limits)?;
    Ok([r.end[U], r.end[THETA]])
}

/// The flip eigenvector of the linearised Poincaré map `dp` (for a real multiplier μ < −1).
fn flip_direction(dp: &Matrix2<f64>, mu: f64) -> [f64; 2] {
    // (DP − μI) e = 0: e ⟂ the first row (or the second, whichever is larger).
    let a = dp - Matrix2::identity() * mu;
    let (p, q) = if a.row(0).norm() >= a.row(1).norm() {
        (a[(0, 0)], a[(0, 1)])
    } else {
        (a[(1, 0)], a[(1, 1)])
    };
    let n = p.hypot(q);
    if n > 0.0 {
        [-q / n, p / n]
    } else {
        [1.0, 0.0]
    }
}

/// Shooting from the integrator's scene start `y0`: reach the section, Newton, multipliers,
/// and the doubled orbit when the period-1 orbit has a multiplier below −1.
pub fn analyse(
    integ: &mut dyn Integrator,
    drr: &Drr,
    y0: [f64; 3],
    settings: &ShootingSettings,
) -> Result<ShootingReport, AnalysisError> {
    let x0 = reach_section(integ, drr, y0, &settings.limits)?;
    let result = newton(integ, drr, x0, 1, settings)?;
    let mut report = ShootingReport {
        converged: result.orbit.is_ok(),
        orbit: None,
        failure: None,
        iterations: result.iterations,
        period_doubling: None,
        tolerance: settings.tolerance,
    };
    match result.orbit {
        Ok(orbit) => {
            report.period_doubling = period_doubling(integ, drr, &orbit, settings)?;
            report.orbit = Some(orbit);
        }
        Err(why) => report.failure = Some(why),
    }
    Ok(report)
}

/// The flip multiplier of an orbit, if a non-trivial real one is below −1.
pub fn flip_multiplier(orbit: &PeriodicOrbit) -> Option<f64> {
    orbit.negative_real_multiplier().filter(|&mu| mu < -1.0)
}

fn period_doubling(
    integ: &mut dyn Integrator,
    drr: &Drr,
    orbit: &PeriodicOrbit,
    settings: &ShootingSettings,
) -> Result<Option<PeriodDoubling>, AnalysisError> {
    let (Some(mu), Some(dp)) = (flip_multiplier(orbit), orbit.map_jacobian) else {
        return Ok(None);
    };
    let x = [orbit.section_point[0], orbit.section_point[2]];
    let e = flip_direction(&dp, mu);
    let mut notes = Vec::new();
    for size in [1e-2, 1e-1] {
        for sign in [1.0, -1.0] {
            let scale = size * (1.0 + x[0].abs().max(x[1].abs()));
            let start = [x[0] + sign * scale * e[0], x[1] + sign * scale * e[1]];
            match newton(integ, drr, start, 2, settings).map(|n| n.orbit) {
                Ok(Ok(doubled)) => {
                    let p = [doubled.section_point[0], doubled.section_point[2]];
                    let distinct = (p[0] - x[0]).abs().max((p[1] - x[1]).abs())
                        > 1e3 * settings.tolerance * (1.0 + x[0].abs().max(x[1].abs()));
                    if distinct {
                        let note = format!(
                            "found from a displacement {:+e} along the flip eigenvector",
                            sign * scale
                        );
                        return Ok(Some(PeriodDoubling {
                            multiplier: mu,
                            doubled: Some(doubled),
                            note,
                        }));
                    }
                    notes.push(format!(
                        "displacement {:+e}: converged back to the period-1 orbit",
                        sign * scale
                    ));
                }
                Ok(Err(why)) => notes.push(format!("displacement {:+e}: {why}", sign * scale)),
                Err(failure) => notes.push(format!("displacement {:+e}: {failure}", sign * scale)),
            }
        }
    }
    Ok(Some(PeriodDoubling { multiplier: mu, doubled: None, note: notes.join("; ") }))
}
