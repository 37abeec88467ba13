//! The scene's `solver` block, one for every kind of model, and the one rule for what runs
//! without it: [`DEFAULT_METHOD`] at its model's default rtol ([`SolverDefaults`]: the
//! spring-slider's [`DEFAULT_RTOL`], the laboratory's [`LAB_DEFAULT_RTOL`]), for a scene with
//! no `solver` block and for each key a block leaves out. The report's `solver.chosen_by` says
//! which applied and why.

use super::{finite, positive, SceneError};
use crate::solver::{Method, SolverSpec};
use serde::{Deserialize, Serialize};

/// A scene's `solver` block as written (every kind of model).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSolver {
    #[serde(default)]
    method: Option<String>,
    #[serde(default)]
    rtol: Option<f64>,
    #[serde(default)]
    atol: Option<RawAtol>,
    #[serde(default)]
    table: Option<String>,
    #[serde(default)]
    explicit_table: Option<String>,
    #[serde(default)]
    max_steps: Option<u64>,
}

/// `solver.atol`: one number, or one per component of the state.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub(super) enum RawAtol {
    Scalar(f64),
    PerComponent(Vec<f64>),
}

/// What runs for a kind of model without a `solver` block, or for what a block leaves out,
/// and why (the report's `solver.chosen_by`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverDefaults {
    /// The method: [`DEFAULT_METHOD`] for every model.
    pub method: Method,
    /// The relative tolerance that meets the model's accuracy bounds.
    pub rtol: f64,
    /// Why, with the measurement that says so.
    pub chosen_by: &'static str,
}

/// The spring-slider's defaults: [`DEFAULT_METHOD`] at [`DEFAULT_RTOL`].
pub const SPRING_SLIDER_DEFAULTS: SolverDefaults =
    SolverDefaults { method: DEFAULT_METHOD, rtol: DEFAULT_RTOL, chosen_by: CHOSEN_BY_DEFAULT };

/// The laboratory model's defaults: [`DEFAULT_METHOD`] at [`LAB_DEFAULT_RTOL`].
pub const LAB_DEFAULTS: SolverDefaults = SolverDefaults {
    method: DEFAULT_METHOD,
    rtol: LAB_DEFAULT_RTOL,
    chosen_by: LAB_CHOSEN_BY_DEFAULT,
};

/// The method of a scene without a `solver` block (or without `solver.method`).
///
/// Measured on the 12 QDYN spring-block cases written in the field's units (slip and ageing
/// law × k/k_c = 0.9, 0.5, 0.2 × η = 5e-8, 1e-3; docs/from-qdyn.md, "What the defaults give"),
/// against data/reference/quasi_dynamic_cycles.json: radau5 at rtol 1e-10 gives the period
/// within 9.6e-12 and v_max within 3.4e-10 for 3.08 G instructions (whole `stickslip run` per
/// case, cachegrind), where the former default, cvode-bdf at rtol 1e-8, gave 1.2e-7 and 8e-7
/// for 4.15 G. Extrapolation at rtol 1e-10 is cheaper there (1.33 G) but does not finish the
/// γ continuation of data/scenes/fig1c-extended.json in 300 s (radau5: 3.8 s). Since the cycle
/// analysis stops once the orbit is settled (issue #36), radau5 at 1e-10 costs 1.79 G on the
/// 12 (period within 3.8e-11, v_max within 4.5e-10): 0.43× the former default.
pub const DEFAULT_METHOD: Method = Method::Radau5;

/// The relative tolerance of a spring-slider scene without a `solver` block (or without
/// `solver.rtol`); see [`DEFAULT_METHOD`].
pub const DEFAULT_RTOL: f64 = 1e-10;

/// The relative tolerance of a laboratory scene without a `solver` block (or without
/// `solver.rtol`), with [`DEFAULT_METHOD`]: it meets μ within 1e-10 and V, θ within 1e-8
/// (relative) of an independent reference on the 13 cases of data/reference/lab
/// (tests/lab_reference.rs): velocity steps up and down, two state variables, a stiff machine,
/// soft machines, a finite-time blow-up, slide-hold-slide under both laws, PRZ, Nagata and
/// inertia. The former lab default, cvode-bdf at rtol 1e-10, was 4.9e-8 off in μ and 8.3e-5
/// in V there (issue #44); CVODE needs rtol 1e-14 to meet the bounds.
pub const LAB_DEFAULT_RTOL: f64 = 1e-12;

/// The absolute tolerance a scene without `solver.atol` gets: rtol times this.
const DEFAULT_ATOL_OVER_RTOL: f64 = 1e-2;

/// The report's `solver.chosen_by` for a scene without a `solver` block: what ran and why.
pub const CHOSEN_BY_DEFAULT: &str = "default: no solver block; radau5 at rtol 1e-10 meets \
    period 1e-9 and v_max 1e-8 on the 12 QDYN spring-block cases for 0.43x the instructions \
    of cvode-bdf at rtol 1e-8 (docs/from-qdyn.md, \"What the defaults give\")";

/// The report's `solver.chosen_by` for a laboratory scene without a `solver` block.
pub const LAB_CHOSEN_BY_DEFAULT: &str = "default: no solver block; radau5 at rtol 1e-12 meets \
    mu 1e-10 and V, theta 1e-8 (relative) on the 13 lab reference cases, where cvode-bdf at \
    rtol 1e-10 does not (docs/lab.md, \"Running\")";

/// The report's `solver.chosen_by` for a scene whose `solver` block sets method and rtol.
pub const CHOSEN_BY_SCENE: &str = "scene: its solver block";

/// A scene's `solver` block read with its model's defaults for what it leaves out: the method
/// and rtol, the absolute tolerance as given (None: the model's default), the Butcher tables
/// checked against the method, and the report's `solver.chosen_by`. Each model turns it into
/// its own validated form ([`SolverBlock::spring_slider`], and the lab's in `scene::lab`).
#[derive(Debug, Clone)]
pub(super) struct SolverBlock {
    pub(super) method: Method,
    pub(super) rtol: f64,
    pub(super) atol: Option<RawAtol>,
    pub(super) table: Option<String>,
    pub(super) explicit_table: Option<String>,
    pub(super) max_steps: Option<u64>,
    pub(super) chosen_by: String,
}

/// Reads the `solver` block `raw` (None: no block) with `defaults` for what it leaves out.
pub(super) fn parse(
    raw: Option<&RawSolver>,
    defaults: &SolverDefaults,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<SolverBlock, SceneError> {
    let method = match raw.and_then(|r| r.method.as_deref()) {
        None => defaults.method,
        Some(name) => name.parse::<Method>().map_err(|e| err("solver.method", e.to_string()))?,
    };
    let rtol = positive(
        "solver.rtol",
        raw.and_then(|r| r.rtol).unwrap_or(defaults.rtol),
        &format!("e.g. {:e}", defaults.rtol),
        err,
    )?;
    let table = raw.and_then(|r| r.table.clone());
    let explicit_table = raw.and_then(|r| r.explicit_table.clone());
    if let Err(e) =
        crate::solver::check_table_names(method, table.as_deref(), explicit_table.as_deref())
    {
        let (field, message) = e.setting().unwrap_or(("table", e.to_string()));
        return Err(err(&format!("solver.{field}"), message));
    }
    Ok(SolverBlock {
        method,
        rtol,
        atol: raw.and_then(|r| r.atol.clone()),
        table,
        explicit_table,
        max_steps: raw.and_then(|r| r.max_steps),
        chosen_by: chosen_by(raw, defaults),
    })
}

impl SolverBlock {
    /// The spring-slider's solver: atol one number or three (for u, ln v, θ), by default
    /// rtol·1e-2; its step budget is the cycle analysis's.
    pub(super) fn spring_slider(
        self,
        err: &impl Fn(&str, String) -> SceneError,
    ) -> Result<(SolverSpec, String), SceneError> {
        let rtol = self.rtol;
        let atol = match self.atol {
            None => [rtol * DEFAULT_ATOL_OVER_RTOL; 3],
            Some(RawAtol::Scalar(a)) => [a; 3],
            Some(RawAtol::PerComponent(v)) => {
                let arr: [f64; 3] = v.clone().try_into().map_err(|_| {
                    err(
                        "solver.atol",
                        format!(
                            "{v:?} has {} values; give one number or three (for u, ln v, θ)",
                            v.len()
                        ),
                    )
                })?;
                arr
            }
        };
        for (i, a) in atol.iter().enumerate() {
            let a = finite(&format!("solver.atol[{i}]"), *a, err)?;
            if a < 0.0 {
                return Err(err(&format!("solver.atol[{i}]"), format!("{a} must be ≥ 0")));
            }
        }
        if self.max_steps.is_some() {
            return Err(err(
                "solver.max_steps",
                "set the step budget with {\"cycle\": {\"max_steps\": N}}".into(),
            ));
        }
        let spec = SolverSpec {
            method: self.method,
            rtol,
            atol,
            table: self.table,
            explicit_table: self.explicit_table,
        };
        Ok((spec, self.chosen_by))
    }
}

/// Which of method and rtol the scene set, and which came from `defaults`.
fn chosen_by(raw: Option<&RawSolver>, defaults: &SolverDefaults) -> String {
    let Some(raw) = raw else { return defaults.chosen_by.into() };
    let defaulted: Vec<String> = [
        raw.method.is_none().then(|| format!("method {}", defaults.method.name())),
        raw.rtol.is_none().then(|| format!("rtol {:e}", defaults.rtol)),
    ]
    .into_iter()
    .flatten()
    .collect();
    if defaulted.is_empty() {
        CHOSEN_BY_SCENE.into()
    } else {
        format!(
            "{CHOSEN_BY_SCENE}, with the default {} (docs/scenes.md, \"solver\")",
            defaulted.join(" and ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chosen(text: &str) -> (SolverSpec, String) {
        let raw: Option<RawSolver> = serde_json::from_str(text).unwrap();
        let err = |field: &str, message: String| SceneError {
            source_name: "t".into(),
            field: field.into(),
            message,
        };
        parse(raw.as_ref(), &SPRING_SLIDER_DEFAULTS, &err).unwrap().spring_slider(&err).unwrap()
    }

    #[test]
    fn no_block_runs_the_default_and_says_why() {
        let (spec, why) = chosen("null");
        assert_eq!((spec.method, spec.rtol, spec.atol), (Method::Radau5, 1e-10, [1e-12; 3]));
        assert_eq!(why, CHOSEN_BY_DEFAULT);
        // The reason names what runs.
        let runs = format!("{} at rtol {DEFAULT_RTOL:e}", DEFAULT_METHOD.name());
        assert!(why.contains(&runs), "{why}");
    }

    #[test]
    fn a_block_fills_what_it_leaves_out_and_says_which() {
        let (spec, why) = chosen(r#"{"method": "cvode-bdf", "rtol": 1e-8}"#);
        assert_eq!((spec.method, spec.atol), (Method::CvodeBdf, [1e-10; 3]));
        assert_eq!(why, CHOSEN_BY_SCENE);
        let (spec, why) = chosen(r#"{"method": "cvode-bdf"}"#);
        assert_eq!(spec.rtol, 1e-10);
        assert!(why.ends_with("with the default rtol 1e-10 (docs/scenes.md, \"solver\")"), "{why}");
        let (spec, why) = chosen(r#"{"atol": 1e-14}"#);
        assert_eq!((spec.method, spec.rtol, spec.atol), (Method::Radau5, 1e-10, [1e-14; 3]));
        let both =
            format!("the default method {} and rtol {DEFAULT_RTOL:e}", DEFAULT_METHOD.name());
        assert!(why.contains(&both), "{why}");
    }
}
