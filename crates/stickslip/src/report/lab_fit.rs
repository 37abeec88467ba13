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
    /// The method that integrated the model and its tolerances (the scene's `solver`).
    pub solver: LabSolver,
    /// How the sensitivities were integrated: "cvodes" (CVODES' forward sensitivities, for
    /// cvode-bdf and cvode-adams) or "one-system" (the state and its sensitivity equations
    /// as one system, by the method).
    pub sensitivities: &'static str,
    /// What the fit found.
    #[serde(flatten)]
    pub outcome: FitOutcome,
}

impl FitReport {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }

    /// The record beside the fit as CSV (`stickslip fit --series`): columns
    /// `t,mu_measured,mu_fitted,residual`, the residual being μ_fitted − μ_measured (the
    /// fit's r_i, trend included), every number in the shortest form that reads back exactly.
    pub fn series_csv(&self) -> String {
        let s = &self.outcome.series;
        let mut csv = String::from("t,mu_measured,mu_fitted,residual\n");
        for ((t, data), fit) in s.t.iter().zip(&s.mu_data).zip(&s.mu_fit) {
            csv += &format!("{t:?},{data:?},{fit:?},{:?}\n", fit - data);
        }
        csv
    }

    /// A few lines for the terminal.
    pub fn summary(&self) -> String {
        let o = &self.outcome;
        let mut s = format!(
            "{}: fit of {} samples of {} ({} loading, {} rtol {:e}): {}, {} evaluations, residual rms {:.3e}\n",
            self.scene,
            o.samples,
            self.data,
            self.loading,
            self.solver.method,
            self.solver.rtol,
            if o.converged {
                "converged".to_string()
            } else {
                format!("NOT converged ({})", o.termination.name())
            },
            o.evaluations,
            o.residual_rms
        );
        if let Some(why) = &o.stopped {
            s += &format!("  stopped: {why}; the values are the best point reached\n");
        }
        for p in &o.parameters {
            s += &format!(
                "  {:6} = {:.6e} ± {:.2e} {:12} (start {:.4e})\n",
                p.name, p.value, p.standard_error, p.unit, p.initial
            );
        }
        let d = &o.a_minus_b;
        s += &format!(
            "  a − b  = {:.6e} ± {:.2e}              (start {:.4e})\n",
            d.value, d.standard_error, d.initial
        );
        s += &format!("  lag-1 autocorrelation of the residuals {:.3}\n", o.lag1_autocorrelation);
        for w in &o.warnings {
            s += &format!("  warning: {w}\n");
        }
        s
    }
}
