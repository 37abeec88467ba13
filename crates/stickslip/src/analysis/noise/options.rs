//! The scene's `{"noise": {...}}` options: parsing and validation (errors name the field and
//! the fix). Defaults that depend on the model are resolved in [`super::run`].

use crate::analysis::InvalidOption;
use crate::model::ModelKind;
use serde::{Deserialize, Serialize};

/// How ensemble statistics are aligned in time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Alignment {
    /// Each realisation is read at times relative to its own event t_c,i (default).
    OwnEvent,
    /// Every realisation is read at times relative to the deterministic event t_c.
    Deterministic,
}

/// Options of the noise analysis as given in a scene (None = default).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseOptions {
    /// Noise amplitudes, one per state component: DRR (η_u, η_v, η_θ), saddle-node (η_x),
    /// van der Pol (η_x, η_y). Required.
    pub amplitudes: Vec<f64>,
    /// OU correlation time τ (default: DRR 2.5/γ, the slip time; saddle-node 0.05/√μ0;
    /// van der Pol 2.5/β²).
    #[serde(default)]
    pub correlation_time: Option<f64>,
    /// Noise nodes per correlation time, τ/h (default 10).
    #[serde(default)]
    pub steps_per_correlation_time: Option<f64>,
    /// Number of realisations (default 1000).
    #[serde(default)]
    pub realisations: Option<usize>,
    /// Seed of the random streams (default 1).
    #[serde(default)]
    pub seed: Option<u64>,
    /// The realisations start on the deterministic orbit this long before its event (default:
    /// DRR min(6, 0.8·period); van der Pol 0.45·period; saddle-node from t = 0).
    #[serde(default)]
    pub start_before_event: Option<f64>,
    /// [from, to]: times before the event between which correlation times are reported
    /// (default: DRR [3, 30/γ]; others [0.9, 0.01]·start_before_event).
    #[serde(default)]
    pub window: Option<[f64; 2]>,
    /// "own_event" (default) or "deterministic".
    #[serde(default)]
    pub alignment: Option<Alignment>,
    /// Equally spaced grid times from the start to the event (default 1000; a fifth as many
    /// log-spaced ones are added towards the event).
    #[serde(default)]
    pub grid_points: Option<usize>,
    /// Times, log-spaced across the window, at which correlation times are reported
    /// (default 60).
    #[serde(default)]
    pub report_points: Option<usize>,
    /// Rodas5P's relative tolerance per realisation (default 1e-6).
    #[serde(default)]
    pub rtol: Option<f64>,
    /// Rodas5P's absolute tolerances per realisation, one per component (default: 1e-3 of the
    /// component's median linear-response σ, within [1e-14, 1e-6]; 1e-6 without it).
    #[serde(default)]
    pub atol: Option<Vec<f64>>,
    /// Compute the linear response (small-noise limit) too (default true).
    #[serde(default)]
    pub linear_response: Option<bool>,
    /// Times before the event at which Γ(t, t − t') is reported as a curve (default: DRR
    /// [2.3, 1, 30/γ], the paper's Fig. 6b; others the window's ends and its geometric middle).
    #[serde(default)]
    pub correlation_curves_at: Option<Vec<f64>>,
    /// Saddle-node only: the escape is the downward crossing of x = event_level < 0
    /// (default −1).
    #[serde(default)]
    pub event_level: Option<f64>,
}

/// Validates the options for a model with `dim` components; `gamma2` is γ² for the DRR (the
/// amplitudes must stay below it). The error names the field.
pub fn validate(
    o: &NoiseOptions,
    dim: usize,
    kind: ModelKind,
    gamma2: Option<f64>,
) -> Result<(), InvalidOption> {
    let bad = |field: &str, message: String| Err(InvalidOption::new(field, message));
    let names = match kind {
        ModelKind::Drr => "(η_u, η_v, η_θ)",
        ModelKind::SaddleNode => "(η_x)",
        ModelKind::VanDerPol => "(η_x, η_y)",
    };
    if o.amplitudes.len() != dim {
        return bad(
            "amplitudes",
            format!("has {} values; give {dim}, one per component {names}", o.amplitudes.len()),
        );
    }
    for (i, a) in o.amplitudes.iter().enumerate() {
        if !(a.is_finite() && *a >= 0.0) {
            return bad(&format!("amplitudes[{i}]"), format!("{a} must be a finite number ≥ 0"));
        }
        if let Some(g2) = gamma2 {
            if *a >= g2 {
                return bad(&format!("amplitudes[{i}]"), format!("{a:e} must be below γ² = {g2:e} (the paper's condition; a response of order one otherwise)"));
            }
        }
    }
    if o.amplitudes.iter().all(|a| *a == 0.0) {
        return bad("amplitudes", "are all zero; give at least one positive amplitude".into());
    }
    let positive = |field: &str, v: Option<f64>, hint: &str| -> Result<(), InvalidOption> {
        match v {
            Some(x) if !(x.is_finite() && x > 0.0) => {
                Err(InvalidOption::new(field, format!("{x} must be a finite number > 0 ({hint})")))
            }
            _ => Ok(()),
        }
    };
    positive("correlation_time", o.correlation_time, "the OU correlation time τ")?;
    positive("start_before_event", o.start_before_event, "a duration")?;
    if let Some(k) = o.steps_per_correlation_time {
        if !(k.is_finite() && (2.0..=1e4).contains(&k)) {
            return bad(
                "steps_per_correlation_time",
                format!("{k} must be between 2 and 1e4 (default 10)"),
            );
        }
    }
    if let Some(r) = o.realisations {
        if !(2..=10_000_000).contains(&r) {
            return bad("realisations", format!("{r} must be between 2 and 1e7"));
        }
    }
    if let Some([from, to]) = o.window {
        if !(from.is_finite() && to.is_finite() && from > to && to > 0.0) {
            return bad("window", format!("[{from}, {to}] must be [from, to] times before the event with from > to > 0, e.g. [3, 0.03]"));
        }
    }
    if let Some(g) = o.grid_points {
        if !(10..=20000).contains(&g) {
            return bad("grid_points", format!("{g} must be between 10 and 20000 (default 1000)"));
        }
    }
    if let Some(g) = o.report_points {
        if !(1..=1000).contains(&g) {
            return bad("report_points", format!("{g} must be between 1 and 1000 (default 60)"));
        }
    }
    if let Some(r) = o.rtol {
        if !(r.is_finite() && r > 0.0 && r < 0.1) {
            return bad("rtol", format!("{r} must be in (0, 0.1), e.g. 1e-6"));
        }
    }
    if let Some(a) = &o.atol {
        if a.len() != dim {
            return bad("atol", format!("has {} values; give {dim}, one per component", a.len()));
        }
        if let Some(i) = a.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            return bad(&format!("atol[{i}]"), format!("{} must be a finite number > 0", a[i]));
        }
    }
    if let Some(times) = &o.correlation_curves_at {
        if let Some(i) = times.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            return bad(
                &format!("correlation_curves_at[{i}]"),
                format!("{} must be a time before the event > 0", times[i]),
            );
        }
    }
    match (kind, o.event_level) {
        (ModelKind::SaddleNode, Some(l)) if !(l.is_finite() && l < 0.0) => {
            bad("event_level", format!("{l} must be < 0: the escape is a downward crossing below the stable branch x = √μ > 0"))
        }
        (ModelKind::SaddleNode, _) | (_, None) => Ok(()),
        (_, Some(_)) => bad("event_level", "only the saddle-node model takes an event level".into()),
    }
}
