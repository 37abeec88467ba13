//! The scene's `solver` block, and the one rule for what runs without it: [`DEFAULT_METHOD`] at
//! [`DEFAULT_RTOL`], atol = rtol·1e-2, for a scene with no `solver` block and for each key a
//! block leaves out. The report's `solver.chosen_by` says which applied and why.

use super::{finite, positive, RawAtol, RawSolver, SceneError};
use crate::solver::{Method, SolverSpec};

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

/// The relative tolerance of a scene without a `solver` block (or without `solver.rtol`); see
/// [`DEFAULT_METHOD`].
pub const DEFAULT_RTOL: f64 = 1e-10;

/// The absolute tolerance a scene without `solver.atol` gets: rtol times this.
const DEFAULT_ATOL_OVER_RTOL: f64 = 1e-2;

/// The report's `solver.chosen_by` for a scene without a `solver` block: what ran and why.
pub const CHOSEN_BY_DEFAULT: &str = "default: no solver block; radau5 at rtol 1e-10 meets \
    period 1e-9 and v_max 1e-8 on the 12 QDYN spring-block cases for 0.43x the instructions \
    of cvode-bdf at rtol 1e-8 (docs/from-qdyn.md, \"What the defaults give\")";

/// The report's `solver.chosen_by` for a scene whose `solver` block sets method and rtol.
pub const CHOSEN_BY_SCENE: &str = "scene: its solver block";

/// The solver of a scene's `solver` block (None: no block), with the defaults for what it
/// leaves out, and the report's `solver.chosen_by` that says so.
pub(super) fn parse(
    raw: Option<&RawSolver>,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(SolverSpec, String), SceneError> {
    let method = match raw.and_then(|r| r.method.as_deref()) {
        None => DEFAULT_METHOD,
        Some(name) => name.parse::<Method>().map_err(|e| err("solver.method", e.to_string()))?,
    };
    let rtol = positive(
        "solver.rtol",
        raw.and_then(|r| r.rtol).unwrap_or(DEFAULT_RTOL),
        "e.g. 1e-10",
        err,
    )?;
    let atol = match raw.and_then(|r| r.atol.clone()) {
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
    let table = raw.and_then(|r| r.table.clone());
    let explicit_table = raw.and_then(|r| r.explicit_table.clone());
    if let Err(e) =
        crate::solver::check_table_names(method, table.as_deref(), explicit_table.as_deref())
    {
        let (field, message) = e.setting().unwrap_or(("table", e.to_string()));
        return Err(err(&format!("solver.{field}"), message));
    }
    if raw.and_then(|r| r.max_steps).is_some() {
        return Err(err(
            "solver.max_steps",
            "set the step budget with {\"cycle\": {\"max_steps\": N}}".into(),
        ));
    }
    let spec = SolverSpec { method, rtol, atol, table, explicit_table };
    Ok((spec, chosen_by(raw)))
}

/// Which of method and rtol the scene set, and which came from the defaults.
fn chosen_by(raw: Option<&RawSolver>) -> String {
    let Some(raw) = raw else { return CHOSEN_BY_DEFAULT.into() };
    let defaulted: Vec<String> = [
        raw.method.is_none().then(|| format!("method {}", DEFAULT_METHOD.name())),
        raw.rtol.is_none().then(|| format!("rtol {DEFAULT_RTOL:e}")),
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
        parse(raw.as_ref(), &err).unwrap()
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
