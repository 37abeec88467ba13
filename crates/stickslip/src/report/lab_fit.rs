//! The report of `stickslip fit` (docs/lab.md): the fitted parameters with their standard
//! errors and correlations, and how the fit went.

use crate::analysis::lab::LabSolver;
use crate::analysis::lab_fit::FitOutcome;
use serde::Serialize;

/// The report of one fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitReport {
    /// stickslip version.
    pub stickslip_version: &'static str,
    /// SUNDIALS version linked at run time.
    pub sundials_version: String,
    /// The scene's name.
    pub scene: String,
    /// The record fitted (its path).
    pub data: String,
    /// Where the load-point history came from: "scene" or "data" (the record's x_lp column).
    pub loading: &'static str,
    /// The integration's tolerances (CVODES BDF with sensitivities).
    pub solver: LabSolver,
    /// What the fit found.
    #[serde(flatten)]
    pub outcome: FitOutcome,
}

impl FitReport {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }

    /// A few lines for the terminal.
    pub fn summary(&self) -> String {
        let o = &self.outcome;
        let mut s = format!(
            "{}: fit of {} samples of {} ({} loading): {}, {} evaluations, residual rms {:.3e}\n",
            self.scene,
            o.samples,
            self.data,
            self.loading,
            if o.converged {
                "converged".to_string()
            } else {
                format!("NOT converged ({})", o.termination)
            },
            o.evaluations,
            o.residual_rms
        );
        for p in &o.parameters {
            s += &format!(
                "  {:6} = {:.6e} ± {:.2e}   (start {:.4e})\n",
                p.name, p.value, p.standard_error, p.initial
            );
        }
        s += &format!("  lag-1 autocorrelation of the residuals {:.3}\n", o.lag1_autocorrelation);
        for w in &o.warnings {
            s += &format!("  warning: {w}\n");
        }
        s
    }
}
