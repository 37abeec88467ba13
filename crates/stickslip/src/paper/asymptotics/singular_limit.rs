//! The singular-limit picture (issue 5): creep along v ≈ 1/u, quasi-static runaway, an
//! inertial half-oscillation of frequency γ and quick healing. It predicts
//!
//! - period ≈ (2ε/ξ) ln γ + O(ln ln γ): the slip moves u by ≈ 2 v_max/γ ≈ (2ε/ξ) ln γ, which the
//!   stick (u' ≈ −1) must take back; so the paper's "≈ 5 per decade" is a finite-γ slope
//!   tending to 2ε ln 10/ξ;
//! - v_max ≈ (ε/ξ) γ ln γ, i.e. ln v_max ≈ ln γ + ln ln γ + ln(ε/ξ);
//! - slip half-width × γ → 2π/3 (the full width at half maximum of a half-sine of frequency γ);
//! - t0, u_min and θ_max independent of γ (the stick ends where the reduced 2D flow, started at
//!   a γ-independent landing point, blows up).
//!
//! Each is measured across the γ scan, with the finite-γ corrections as observed.

use super::scan::ScanValues;
use crate::model::DrrParams;
use crate::numerics::fit::{least_squares, Fit};
use serde::Serialize;

/// The slope of the period between two neighbouring scan points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LocalSlope {
    /// Lower γ.
    pub from_gamma: f64,
    /// Upper γ.
    pub to_gamma: f64,
    /// ΔP / Δlog₁₀ γ.
    pub per_decade: f64,
}

/// Growth of the period with γ.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodGrowth {
    /// 2ε/ξ per unit ln γ.
    pub predicted_slope_per_ln_gamma: f64,
    /// 2ε ln 10/ξ per decade.
    pub predicted_slope_per_decade: f64,
    /// a + b ln γ.
    pub linear: Option<Fit>,
    /// a + b ln γ + d ln ln γ.
    pub with_ln_ln: Option<Fit>,
    /// Slopes between neighbouring scan points.
    pub local_slopes: Vec<LocalSlope>,
}

/// ln v_max against its prediction at one γ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LnVMax {
    /// γ.
    pub gamma: f64,
    /// ln v_max of the cycle.
    pub ours: f64,
    /// ln γ + ln ln γ + ln(ε/ξ).
    pub predicted: f64,
    /// ours − predicted.
    pub difference: f64,
}

/// A quantity predicted to be γ-independent.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Invariant {
    /// "t0", "u_min" or "theta_max".
    pub quantity: &'static str,
    /// (γ, value) across the scan.
    pub values: Vec<[f64; 2]>,
    /// |Δvalue|/|value| per decade between the two largest γ of the scan.
    pub relative_change_per_decade: Option<f64>,
}

/// The "singular_limit" part of the asymptotics section.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SingularLimitReport {
    /// Period growth.
    pub period: PeriodGrowth,
    /// ln v_max per γ.
    pub ln_v_max: Vec<LnVMax>,
    /// Half-width × γ limit predicted: 2π/3.
    pub half_width_predicted_limit: f64,
    /// t0, u_min, θ_max across γ.
    pub invariants: Vec<Invariant>,
}

/// The singular-limit analysis over all periodic scan points (`all`, increasing γ) and the
/// fit points (γ ≥ fit_min_gamma, `fit`).
pub fn analyse(
    all: &[(f64, ScanValues)],
    fit: &[(f64, ScanValues)],
    params: &DrrParams,
) -> SingularLimitReport {
    let (xi, e) = (params.xi, params.epsilon);
    let l: Vec<f64> = fit.iter().map(|(g, _)| g.ln()).collect();
    let p: Vec<f64> = fit.iter().map(|(_, v)| v.period).collect();
    let local_slopes = all
        .windows(2)
        .map(|w| LocalSlope {
            from_gamma: w[0].0,
            to_gamma: w[1].0,
            per_decade: (w[1].1.period - w[0].1.period) / (w[1].0 / w[0].0).log10(),
        })
        .collect();
    let ln_v_max = all
        .iter()
        .filter(|(g, _)| *g > std::f64::consts::E)
        .map(|(g, v)| {
            let predicted = g.ln() + g.ln().ln() + (e / xi).ln();
            LnVMax { gamma: *g, ours: v.ln_v_max, predicted, difference: v.ln_v_max - predicted }
        })
        .collect();
    let invariant = |quantity: &'static str, get: fn(&ScanValues) -> f64| {
        let values: Vec<[f64; 2]> = all.iter().map(|(g, v)| [*g, get(v)]).collect();
        let relative_change_per_decade = values.windows(2).last().map(|w| {
            let (a, b) = (w[0][1], w[1][1]);
            (b - a).abs() / b.abs().max(f64::MIN_POSITIVE) / (w[1][0] / w[0][0]).log10()
        });
        Invariant { quantity, values, relative_change_per_decade }
    };
    SingularLimitReport {
        period: PeriodGrowth {
            predicted_slope_per_ln_gamma: 2.0 * e / xi,
            predicted_slope_per_decade: 2.0 * e * std::f64::consts::LN_10 / xi,
            linear: least_squares("a + b ln γ", &l, &p, &[&|_| 1.0, &|l| l]),
            with_ln_ln: least_squares(
                "a + b ln γ + d ln ln γ",
                &l,
                &p,
                &[&|_| 1.0, &|l| l, &|l: f64| l.ln()],
            ),
            local_slopes,
        },
        ln_v_max,
        half_width_predicted_limit: 2.0 * std::f64::consts::PI / 3.0,
        invariants: vec![
            invariant("t0", |v| v.t0),
            invariant("u_min", |v| v.extremes.u_min),
            invariant("theta_max", |v| v.extremes.theta_max),
        ],
    }
}
