//! The report of a lab scene (docs/lab.md).

use crate::analysis::lab::{LabOutcome, LabSolver};
use crate::model::{LabParams, Loading};
use serde::Serialize;

/// The rows of a lab run, column by column names.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabSeries {
    /// t (s), x_lp (µm), delta (µm), mu, v (µm/s), theta_1 (s), ….
    pub columns: Vec<&'static str>,
    /// One row per output time (or per step).
    pub rows: Vec<Vec<f64>>,
}

/// The report's `solver`: method, rtol and atol as used, and `chosen_by`, why (the scene's
/// block, or the defaults and why; `scene::LAB_DEFAULTS`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabSolverSection {
    /// The solver as used.
    #[serde(flatten)]
    pub solver: LabSolver,
    /// Why this solver runs.
    pub chosen_by: String,
}

/// The report of one lab scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabReport {
    /// stickslip version.
    pub stickslip_version: &'static str,
    /// SUNDIALS version linked at run time.
    pub sundials_version: String,
    /// Scene name.
    pub name: String,
    /// The scene as given.
    pub scene: serde_json::Value,
    /// The model's parameters as used.
    pub params: LabParams,
    /// k_c = (b − a)/D_c with one state variable (friction per µm), else None.
    pub critical_stiffness: Option<f64>,
    /// The load-point history as used (segments and end).
    pub loading: Loading,
    /// The solver, and why it runs.
    pub solver: LabSolverSection,
    /// Events and the numbers read off the record.
    #[serde(flatten)]
    pub outcome: LabOutcome,
    /// The rows.
    pub series: LabSeries,
}

impl LabReport {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }

    /// A few lines for the terminal.
    pub fn summary(&self) -> String {
        let o = &self.outcome;
        let mut s = format!(
            "{}: lab model, {} state variable(s), {} segment(s), t = {} … {} s; {} steps ({})\n",
            self.name,
            self.params.states.len(),
            self.loading.segments.len(),
            self.loading.t_start(),
            o.t_end,
            o.steps,
            self.solver.solver.method
        );
        for v in &o.velocity_steps {
            s += &format!(
                "  velocity step {} → {} µm/s at t = {} s: a − b = {:.6e} measured, {:.6e} model\n",
                v.v_before, v.v_after, v.t, v.a_minus_b_measured, v.a_minus_b_model
            );
        }
        for h in &o.holds {
            match h.delta_mu_peak {
                Some(d) => {
                    s += &format!(
                        "  hold of {} s at t = {} s: Δμ_peak = {d:.6e}\n",
                        h.t_hold, h.t_start
                    )
                }
                None => {
                    s += &format!(
                        "  hold of {} s at t = {} s: no reload peak\n",
                        h.t_hold, h.t_start
                    )
                }
            }
        }
        if let Some(beta) = o.healing_rate {
            s += &format!("  healing rate β = dΔμ_peak/dlog10(t_hold) = {beta:.6e}\n");
        }
        if !o.v_maxima.is_empty() {
            let top = o.v_maxima.iter().map(|m| m.v).fold(0.0, f64::max);
            s += &format!("  {} maxima of V, the largest {top:.6e} µm/s\n", o.v_maxima.len());
        }
        if let Some(b) = o.blow_up {
            s += &format!("  finite-time blow-up: V → ∞ at t = {:.12} s\n", b.t);
        }
        s
    }
}
