//! The paper's quoted values set beside ours, claim by claim. The paper's numbers are claims
//! to test: nothing is tuned to them, and the verdict says plainly where they do not hold.
//!
//! Reference: Pomeau & Le Berre, "Critical speed-up vs critical slow-down" (eq. tauc, eq. to,
//! the slip duration "about 2.5/γ", and the earthquake case τ = 28, i.e. 75 years).

use super::claims::{Claim, Source};
use crate::analysis::cycle::CycleValues;
use crate::analysis::hopf::HopfReport;
use crate::model::{DrrParams, Friction};

/// A claim of the paper with its verdict: agrees within 5 %, roughly within 20 %, else
/// disagrees.
pub fn claim(claim: &str, paper: f64, ours: f64, note: String) -> Claim {
    Claim::relative(claim, Source::Paper, paper, ours, 0.05, note)
}

/// The claims that one scene can test.
pub fn compare(params: &DrrParams, hopf: &HopfReport, cycle: Option<&CycleValues>) -> Vec<Claim> {
    let mut claims = vec![claim(
        "period at the Hopf threshold τ_c = 2π/√ξ",
        hopf.period_c_large_gamma,
        hopf.period_c,
        format!("2π/ω_c of the linearisation at this γ (ε_c = {:.9})", hopf.epsilon_c),
    )];
    if let Some(c) = cycle {
        claims.push(claim(
            "t0 ≅ 1: time from v = 1 to the v maximum",
            1.0,
            c.main.t0,
            "limit cycle, upward crossing of v = 1 to the v maximum".into(),
        ));
        if let Some(w) = c.main.slip_half_width {
            claims.push(claim(
                "slip lasts about 2.5/γ",
                2.5,
                w * params.gamma,
                "full width of v(t) at half its maximum, times γ".into(),
            ));
        }
        let earthquake = params.friction == Friction::Log
            && params.xi == 0.8
            && params.epsilon == 1.0
            && params.gamma == 1e8;
        if earthquake {
            claims.push(claim(
                "earthquake case (γ = 1e8, ξ = 0.8, ε = 1): period τ = 28 (75 years)",
                28.0,
                c.main.period,
                format!(
                    "limit-cycle period; {:.1} years with D_c/v0 = 2.7 years",
                    c.main.period * 2.7
                ),
            ));
        }
    }
    claims
}
