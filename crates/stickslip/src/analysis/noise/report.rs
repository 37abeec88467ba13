//! The noise section's summary, and the correlation-time curves of several reports
//! in one document.

use super::NoiseReport;
use serde::Serialize;

impl NoiseReport {
    /// A readable summary for the terminal.
    pub fn summary(&self) -> String {
        let st = &self.settings;
        let mut s = format!(
            "noise ({}): {} realisations, amplitudes {:?}, τ = {:.4e}, h = τ/{}, aligned on {}\n",
            self.model,
            st.realisations,
            st.amplitudes,
            st.correlation_time,
            st.steps_per_correlation_time,
            match st.alignment {
                super::options::Alignment::OwnEvent => "each realisation's own event",
                super::options::Alignment::Deterministic => "the deterministic event",
            }
        );
        s += &format!(
            "  event ({}): t_c = {:.9}, realisations' t_c − t_c: mean {:+.3e}, std {:.3e} (linear response {})\n",
            st.event,
            self.deterministic.event_time,
            self.events.mean_shift,
            self.events.std,
            self.events.std_linear_response.map_or("-".into(), |v| format!("{v:.3e}"))
        );
        if let Some(l) = &self.events.linearity {
            s += &format!(
                "  linearised event time {}: event function's own-frame deviation {:.3} over the linear spread (limit {}); its fluctuation's correlation time {}\n",
                if l.valid { "valid" } else { "NOT valid (the own-event linear response does not apply; compare on \"alignment\": \"deterministic\")" },
                l.own_frame_deviation,
                super::EVENT_LINEARITY_LIMIT,
                l.event_function_correlation_time.map_or("-".into(), |v| format!("{v:.3e}"))
            );
        }
        let f = |v: Option<f64>| v.map_or("      -".to_string(), |v| format!("{v:8.4}"));
        s += &format!(
            "  correlation time of {} (half-height width of Γ; ensemble / linear response):\n",
            self.correlation_variable
        );
        let step = (self.correlation_time.len() / 8).max(1);
        for p in self.correlation_time.iter().step_by(step) {
            s += &format!(
                "    t_c − t = {:9.4}: τ = {} / {}\n",
                p.t_before_event,
                f(p.tau),
                f(p.tau_linear_response)
            );
        }
        if let Some(g) = &self.growth {
            s += &format!(
                "  growth over (t_f − t0, t_f), t_f = t_c − {}: v ×{:.3}, σ_v ×{:.3} (ratio {:.3}, log10 {:+.2}; linear response σ_v ×{})\n",
                g.t_f_before_event,
                g.v_growth,
                g.sigma_v_growth,
                g.ratio,
                g.log10_ratio,
                g.sigma_v_growth_linear_response.map_or("-".into(), |v| format!("{v:.3}"))
            );
        }
        for a in &self.agreement {
            s += &format!(
                "  {}: σ ensemble vs linear response: max |rel. diff| {:.3} (standard error {:.3}), beyond 4 s.e. at {} of the reported times\n",
                a.name,
                a.sigma_max_relative_difference,
                a.sigma_standard_error,
                a.sigma_disagree_at.len()
            );
        }
        s
    }
}

/// One model's correlation-time curve in a combined report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Curve {
    /// The report's file.
    pub source: String,
    /// Scene name.
    pub name: String,
    /// "drr", "saddle_node" or "van_der_pol".
    pub model: String,
    /// The observable (u for the DRR, x otherwise).
    pub variable: String,
    /// "own_event" or "deterministic".
    pub alignment: String,
    /// The report's `noise.correlation_time`.
    pub correlation_time: serde_json::Value,
}

/// The correlation-time curves of several reports (e.g. DRR, saddle-node, van der Pol) in one
/// JSON document for one figure. Each input is (file name, report JSON); an error names the
/// file whose report has no noise section.
pub fn combine(reports: &[(String, serde_json::Value)]) -> Result<Vec<Curve>, String> {
    reports
        .iter()
        .map(|(source, r)| {
            let noise = r
                .get("noise")
                .filter(|n| n.is_object())
                .ok_or_else(|| format!("{source}: the report has no \"noise\" section"))?;
            let text = |v: &serde_json::Value| v.as_str().unwrap_or("").to_string();
            Ok(Curve {
                source: source.clone(),
                name: text(&r["name"]),
                model: text(&noise["model"]),
                variable: text(&noise["correlation_variable"]),
                alignment: text(&noise["settings"]["alignment"]),
                correlation_time: noise["correlation_time"].clone(),
            })
        })
        .collect()
}
