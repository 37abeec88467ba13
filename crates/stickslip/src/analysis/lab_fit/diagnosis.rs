//! What a fit says about its model beyond the numbers: a failure at the starting values
//! explained (a finite-time blow-up, with what to change), and fitted values that contradict
//! the physics or the start (b < 0, a − b of the other sign).

use super::{AMinusB, FitError, FittedParameter, SensitivityError};
use crate::analysis::lab::{self, LabSolver, Output};
use crate::model::{LabParams, Loading};

/// The fit's error when the model cannot be integrated at the starting values: a finite-time
/// blow-up (found by an ordinary run of the scene, as `stickslip run` does) said as such with
/// what to change; otherwise the solver's failure.
pub fn at_start(
    start: &LabParams,
    loading: &Loading,
    solver: &LabSolver,
    source: SensitivityError,
) -> FitError {
    let y0 = start.steady_state(loading.segments[0].velocity);
    let run = lab::run(start, loading, &y0, solver, &Output::Times(vec![]), &mut |_| {});
    let Ok(outcome) = run else {
        return FitError::Solver { stage: "starting", source: Box::new(source) };
    };
    let Some(blow_up) = outcome.blow_up else {
        return FitError::Solver { stage: "starting", source: Box::new(source) };
    };
    let segments = loading.segments.len();
    let j = loading.segments.iter().rposition(|s| s.t_start <= blow_up.t_start).unwrap_or(0);
    let change = match start.critical_stiffness() {
        Some(kc) if start.k < kc => format!(
            "k = {:e} friction/µm is below the critical stiffness k_c = (b − a)/D_c = {kc:e}: start with k above k_c (e.g. {:e}), a closer to b, or a larger D_c",
            start.k,
            2.0 * kc
        ),
        _ => format!(
            "start nearer the record: a closer to b (a − b = {:e} now), a larger D_c or a stiffer k",
            start.a_minus_b()
        ),
    };
    FitError::BlowUp(format!(
        "the model at the starting values blows up in finite time: V → ∞ at t = {} s, in segment {} of {segments} (V_lp = {} µm/s), as `stickslip run` on the scene shows; a fit cannot start there: {change}",
        blow_up.t,
        j + 1,
        loading.segments[j].velocity
    ))
}

/// Warnings on fitted values: a negative b_i, and a − b whose sign differs from the start's.
pub fn sign_warnings(parameters: &[FittedParameter], a_minus_b: &AMinusB) -> Vec<String> {
    let mut warnings: Vec<String> = parameters
        .iter()
        .filter(|p| p.name.starts_with("b_") && p.value < 0.0)
        .map(|p| {
            format!(
                "{} = {:e} < 0: a state variable whose healing lowers the friction; the record does not support this law with this many state variables (fix {} in the scene, change the law, or check the loading)",
                p.name, p.value, p.name
            )
        })
        .collect();
    let (start, end) = (a_minus_b.initial, a_minus_b.value);
    if start * end < 0.0 {
        let kind = |v: f64| if v < 0.0 { "velocity weakening" } else { "velocity strengthening" };
        warnings.push(format!(
            "a − b changed sign: {start:e} at the start ({}), {end:e} ± {:.1e} fitted ({}); check it against the record's steady-state friction at each velocity",
            kind(start),
            a_minus_b.standard_error,
            kind(end)
        ));
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parameter(name: &str, value: f64) -> FittedParameter {
        FittedParameter { name: name.into(), value, standard_error: 1e-4, initial: 0.01, unit: "" }
    }

    /// A negative b and a flipped a − b are flagged; a plain fit is not.
    #[test]
    fn negative_b_and_a_flipped_a_minus_b_are_flagged() {
        let d = |initial, value| AMinusB { value, standard_error: 1e-4, initial };
        assert!(sign_warnings(
            &[parameter("a", 0.01), parameter("b_1", 0.012)],
            &d(-0.001, -0.002)
        )
        .is_empty());
        let w = sign_warnings(&[parameter("a", 0.01), parameter("b_1", -0.002)], &d(-0.001, 0.012));
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].contains("b_1") && w[0].contains("< 0"), "{w:?}");
        assert!(w[1].contains("changed sign") && w[1].contains("velocity strengthening"), "{w:?}");
    }
}
