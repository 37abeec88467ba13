//! Whether the non-trivial multipliers from the variational equations (the eigenvalues of
//! DP, the product of the section Jacobians) are resolved, judged against central
//! differences of the Poincaré map itself.
//!
//! The check runs when the trivial multiplier's error exceeds
//! [`ShootingSettings::multiplier_check_above`](super::ShootingSettings): then the variational
//! integration is suspect (measured: CVODE at γ ≥ 1e8 and Radau5 under the ageing law at 1e12
//! give errors ≈ 1 and non-trivial multipliers of −0.96 … −100 or 574 … 3e5 where the true
//! ones are ≤ 0.06). The map is differenced at two step sizes per unknown, h and h/10 with
//! h = 1e7·rtol·(1 + |x_j|): the map's noise is ~10·rtol (the Newton tolerance; measured
//! ~1e-9 at rtol 1e-10), so the smaller step's noise error is ~1e-5 and the larger's ~1e-6.
//! The two estimates' multipliers differ by `differences_spread`, the estimate of their error.
//! Then:
//! - spread > [`RESOLVED`] → the multipliers are unresolved: no number, stability unknown;
//! - else DP's multipliers within max(RESOLVED, 2·spread) of the differences' → DP's
//!   numbers, checked (uncertainty: the larger of the two distances);
//! - else the differences' multipliers (step h/10) replace DP's (uncertainty: the spread).

use super::{Multiplier, ShootingSettings};
use crate::analysis::period_map::Return;
use crate::analysis::AnalysisError;
use crate::integrate::Integrator;
use crate::model::drr::{Drr, THETA, U};
use nalgebra::Matrix2;
use serde::Serialize;

/// The largest spread between the two difference estimates' multipliers (absolute) for which
/// they count as resolved: enough for a stability verdict unless |μ| is within 1e-3 of 1.
pub const RESOLVED: f64 = 1e-3;

/// Where an orbit's non-trivial multipliers come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MultiplierSource {
    /// DP, unchecked (the trivial multiplier passed its bound).
    SectionJacobian,
    /// DP, confirmed by the map's central differences.
    SectionJacobianChecked,
    /// The map's central differences (DP disagreed with them beyond their spread).
    MapDifferences,
    /// Neither is resolved: no multipliers, stability unknown.
    Unresolved,
}

/// The comparison with the map's central differences.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MultiplierCheck {
    /// The two steps, relative to 1 + |x_j| of each unknown (u, θ).
    pub relative_steps: [f64; 2],
    /// Largest |μ(h) − μ(h/10)| between the two difference estimates (by decreasing modulus).
    pub differences_spread: f64,
    /// Largest |μ_DP − μ(h/10)|.
    pub section_jacobian_difference: f64,
}

/// The outcome: the non-trivial multipliers to report (None: unresolved), where they come
/// from, the check (if it ran) and why they are not DP's (if they are not).
#[derive(Debug, Clone, PartialEq)]
pub struct Checked {
    /// Non-trivial multipliers by decreasing modulus; None when unresolved.
    pub multipliers: Option<Vec<Multiplier>>,
    /// The matrix they are the eigenvalues of (DP or the differences).
    pub jacobian: Option<Matrix2<f64>>,
    /// Their source.
    pub source: MultiplierSource,
    /// The comparison, when it ran.
    pub check: Option<MultiplierCheck>,
    /// Why the multipliers are not DP's, when they are not.
    pub note: Option<String>,
}

/// The eigenvalues of a 2×2 map, by decreasing modulus.
pub fn eigenvalues(m: &Matrix2<f64>) -> Vec<Multiplier> {
    let mut mu: Vec<Multiplier> = m
        .complex_eigenvalues()
        .iter()
        .map(|z| Multiplier { re: z.re, im: z.im, modulus: z.norm() })
        .collect();
    mu.sort_by(|a, b| b.modulus.total_cmp(&a.modulus));
    mu
}

/// Largest pairwise distance between two multiplier lists (same order); ∞ if one is not finite.
fn distance(a: &[Multiplier], b: &[Multiplier]) -> f64 {
    let mut d = 0.0f64;
    for (p, q) in a.iter().zip(b) {
        let pq = (p.re - q.re).hypot(p.im - q.im);
        if !pq.is_finite() {
            return f64::INFINITY;
        }
        d = d.max(pq);
    }
    d
}

/// The map's Jacobian by central differences at steps `rel`·(1 + |x_j|), over `count` returns.
fn differences(
    integ: &mut dyn Integrator,
    drr: &Drr,
    x: [f64; 2],
    count: usize,
    settings: &ShootingSettings,
    rel: f64,
) -> Result<Matrix2<f64>, AnalysisError> {
    let mut m = Matrix2::zeros();
    for j in 0..2 {
        let h = rel * (1.0 + x[j].abs());
        let end = |integ: &mut dyn Integrator, sign: f64| -> Result<[f64; 3], AnalysisError> {
            let mut xs = x;
            xs[j] += sign * h;
            Ok(super::returns(integ, drr, xs, count, &settings.limits)?[count - 1].end)
        };
        let (plus, minus) = (end(integ, 1.0)?, end(integ, -1.0)?);
        for (i, k) in [U, THETA].into_iter().enumerate() {
            m[(i, j)] = (plus[k] - minus[k]) / (2.0 * h);
        }
    }
    Ok(m)
}

/// DP's multipliers if the trivial multiplier's error is within the bound; otherwise checked
/// against the map's central differences (see the module docs).
pub fn check(
    integ: &mut dyn Integrator,
    drr: &Drr,
    x: [f64; 2],
    rs: &[Return],
    dp: &Matrix2<f64>,
    trivial_error: f64,
    settings: &ShootingSettings,
) -> Checked {
    let from_dp = eigenvalues(dp);
    let finite = from_dp.iter().all(|m| m.re.is_finite() && m.im.is_finite());
    if trivial_error <= settings.multiplier_check_above && finite {
        return Checked {
            multipliers: Some(from_dp),
            jacobian: Some(*dp),
            source: MultiplierSource::SectionJacobian,
            check: None,
            note: None,
        };
    }
    let why = if finite {
        format!(
            "the trivial multiplier's error {trivial_error:.2e} exceeds {:.0e}",
            settings.multiplier_check_above
        )
    } else {
        "DP is not finite".to_string()
    };
    let count = rs.len();
    let large = (1e7 * settings.limits.w_tolerance.0).clamp(1e-6, 1e-2);
    let steps = [large, 0.1 * large];
    let pair = differences(integ, drr, x, count, settings, steps[0])
        .and_then(|a| Ok((a, differences(integ, drr, x, count, settings, steps[1])?)));
    let (coarse, fine) = match pair {
        Ok(p) => p,
        Err(e) => {
            let note = format!("{why}, and the map's central differences failed: {e}");
            return Checked {
                multipliers: None,
                jacobian: None,
                source: MultiplierSource::Unresolved,
                check: None,
                note: Some(note),
            };
        }
    };
    judge(&why, steps, *dp, &coarse, fine)
}

/// The verdict from DP and the map's differences at the larger and the smaller step (module
/// docs); `why` says why the check ran.
fn judge(
    why: &str,
    steps: [f64; 2],
    dp: Matrix2<f64>,
    coarse: &Matrix2<f64>,
    fine: Matrix2<f64>,
) -> Checked {
    let from_dp = eigenvalues(&dp);
    let from_fine = eigenvalues(&fine);
    let spread = distance(&eigenvalues(coarse), &from_fine);
    let dp_difference = distance(&from_dp, &from_fine);
    let check = Some(MultiplierCheck {
        relative_steps: steps,
        differences_spread: spread,
        section_jacobian_difference: dp_difference,
    });
    if spread > RESOLVED {
        let note = format!(
            "{why}; the map's central differences at the two step sizes disagree by {spread:.2e} (> {RESOLVED:e}; DP's multipliers are {dp_difference:.2e} from the finer): the multipliers are unresolved and the stability unknown"
        );
        Checked {
            multipliers: None,
            jacobian: None,
            source: MultiplierSource::Unresolved,
            check,
            note: Some(note),
        }
    } else if dp_difference <= RESOLVED.max(2.0 * spread) {
        Checked {
            multipliers: Some(from_dp),
            jacobian: Some(dp),
            source: MultiplierSource::SectionJacobianChecked,
            check,
            note: None,
        }
    } else {
        let note = format!(
            "{why}; DP's multipliers are {dp_difference:.2e} from the map's central differences (spread {spread:.1e}): the differences' are reported"
        );
        Checked {
            multipliers: Some(from_fine),
            jacobian: Some(fine),
            source: MultiplierSource::MapDifferences,
            check,
            note: Some(note),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_pairs_by_position_and_flags_non_finite() {
        let m = |re: f64, im: f64| Multiplier { re, im, modulus: re.hypot(im) };
        assert_eq!(distance(&[m(0.5, 0.0), m(0.1, 0.0)], &[m(0.5, 0.0), m(0.1, 0.0)]), 0.0);
        assert!((distance(&[m(0.5, 0.0)], &[m(0.5, 0.3)]) - 0.3).abs() < 1e-15);
        assert_eq!(distance(&[m(f64::NAN, 0.0)], &[m(0.5, 0.0)]), f64::INFINITY);
        let e = eigenvalues(&Matrix2::new(0.1, 0.0, 0.0, -0.7));
        assert_eq!((e[0].re, e[1].re), (-0.7, 0.1));
    }

    #[test]
    fn judge_keeps_dp_replaces_it_or_withholds_the_multipliers() {
        let steps = [1e-3, 1e-4];
        let map = |mu: f64| Matrix2::new(mu, 0.0, 0.0, 1e-9);
        // DP within the resolution of the differences: DP's numbers, checked.
        let c = judge("why", steps, map(0.0544152), &map(0.054420), map(0.054418));
        assert_eq!(c.source, MultiplierSource::SectionJacobianChecked);
        assert_eq!(c.multipliers.unwrap()[0].re, 0.0544152);
        // DP far from resolved differences (CVODE, ageing, γ = 1e10): the differences'.
        let c = judge("why", steps, map(-0.96), &map(0.04440), map(0.04439));
        assert_eq!(c.source, MultiplierSource::MapDifferences);
        assert_eq!(c.multipliers.unwrap()[0].re, 0.04439);
        assert!(c.note.unwrap().contains("the differences' are reported"));
        // The differences disagree between their two steps: no number, whatever DP says.
        let c = judge("why", steps, map(0.05), &map(0.3), map(0.05));
        assert_eq!(
            (c.source, c.multipliers, c.jacobian),
            (MultiplierSource::Unresolved, None, None)
        );
        assert!(c.note.unwrap().contains("unresolved"));
    }
}
