//! The one check of the engine against a reference table under data/reference
//! (tests/reference.rs, tests/reference_ageing.rs, tests/reference_far.rs).

use stickslip::analysis::cycle::CycleValues;
use stickslip::{engine, scene};

/// A cycle quantity that a reference table lists.
#[derive(Debug, Clone, Copy)]
pub enum Quantity {
    /// The period.
    Period,
    /// The time from v = 1 to the v maximum (a located event).
    T0,
    /// The slip half-width times γ (a Hermite-located event).
    HalfWidthTimesGamma,
    /// ln v_max.
    LnVMax,
}

impl Quantity {
    /// The table's key for it.
    fn key(self) -> &'static str {
        match self {
            Quantity::Period => "period",
            Quantity::T0 => "t0",
            Quantity::HalfWidthTimesGamma => "slip_half_width_times_gamma",
            Quantity::LnVMax => "ln_v_max",
        }
    }

    /// Its value in a cycle at stiffness `gamma`.
    fn of(self, v: &CycleValues, gamma: f64) -> f64 {
        match self {
            Quantity::Period => v.main.period,
            Quantity::T0 => v.main.t0,
            Quantity::HalfWidthTimesGamma => v.main.slip_half_width.unwrap() * gamma,
            Quantity::LnVMax => v.main.ln_v_max,
        }
    }
}

/// The bounds of a rtol 1e-10 run on the slip and ageing laws' tables (tests/reference.rs,
/// tests/reference_ageing.rs). Global error measured on the slip law's: worst 3.9e-8
/// (period), 5.2e-8 (t0), 1.7e-6 (half-width·γ, a Hermite-located event), 1.2e-7 (ln v_max,
/// at γ = 10).
pub const BOUNDS: [(Quantity, f64); 4] = [
    (Quantity::Period, 2e-7),
    (Quantity::T0, 2e-7),
    (Quantity::HalfWidthTimesGamma, 1e-5),
    (Quantity::LnVMax, 5e-7),
];

/// A reference table and what its rows promise.
pub struct Table {
    /// File name under data/reference.
    pub file: &'static str,
    /// The number of rows it has.
    pub rows: usize,
    /// The state law every row names, put into each scene (None: the scene default, slip).
    pub state_law: Option<&'static str>,
    /// Bound on the two reference integrators' relative disagreement on the period in a row
    /// that is checked (rows marked `"agrees": false` are skipped).
    pub agreement: f64,
}

/// The solver settings a check runs the cycle analysis with.
pub struct Run<'a> {
    /// The method's scene name.
    pub method: &'a str,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (None: the scene default, rtol/100).
    pub atol: Option<f64>,
}

/// Runs the cycle analysis with `run` on every row of `table` and compares each of `keys`
/// (quantity, bound on the relative deviation) with the row's reference; collects every
/// failure (typed error, no cycle, deviation beyond its bound) and fails once with all of
/// them.
pub fn check_against_table(table: &Table, keys: &[(Quantity, f64)], run: &Run) {
    let path = format!("{}/data/reference/{}", env!("CARGO_MANIFEST_DIR"), table.file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let parsed: serde_json::Value = serde_json::from_str(&text).unwrap();
    let rows = parsed["rows"].as_array().unwrap();
    assert_eq!(rows.len(), table.rows, "{path}");
    let mut worst = vec![0.0f64; keys.len()];
    let (mut failures, mut checked) = (Vec::new(), 0);
    for row in rows.iter().filter(|row| row["agrees"] != false) {
        checked += 1;
        let gamma = row["gamma"].as_f64().unwrap();
        match cycle_of(table, row, run) {
            Ok(v) => compare(row, keys, &v, gamma, &mut worst, &mut failures),
            Err(failure) => failures.push(failure),
        }
    }
    let worst: Vec<String> = worst.iter().map(|w| format!("{w:.1e}")).collect();
    let names: Vec<&str> = keys.iter().map(|(q, _)| q.key()).collect();
    eprintln!(
        "{} rtol {:e}: {checked} rows of {}; worst relative deviations ({}): {}",
        run.method,
        run.rtol,
        table.file,
        names.join(", "),
        worst.join(", ")
    );
    assert!(checked > 0, "{}: no row to check", table.file);
    assert!(
        failures.is_empty(),
        "{} at rtol {:e}: {} failures of {checked} rows:\n{}",
        run.method,
        run.rtol,
        failures.len(),
        failures.join("\n")
    );
}

/// The cycle that `run` finds at a row's parameters, or why there is none.
fn cycle_of(table: &Table, row: &serde_json::Value, run: &Run) -> Result<CycleValues, String> {
    let (gamma, xi, epsilon) = (
        row["gamma"].as_f64().unwrap(),
        row["xi"].as_f64().unwrap(),
        row["epsilon"].as_f64().unwrap(),
    );
    let point = format!("ξ={xi} ε={epsilon} γ={gamma:e}");
    let agreement = row["relative_agreement"]["period"].as_f64().unwrap();
    assert!(
        agreement < table.agreement,
        "{point}: the two reference integrators disagree by {agreement}"
    );
    let law = match table.state_law {
        Some(law) => {
            assert_eq!(row["state_law"], law, "{point}");
            format!(r#", "state_law": "{law}""#)
        }
        None => String::new(),
    };
    let atol = run.atol.map(|a| format!(r#", "atol": {a:e}"#)).unwrap_or_default();
    let text = format!(
        r#"{{"name": "ref", "model": {{"gamma": {gamma:e}, "xi": {xi}, "epsilon": {epsilon}{law}}},
            "solver": {{"method": "{}", "rtol": {:e}{atol}}}, "analyses": ["cycle"]}}"#,
        run.method, run.rtol
    );
    let s = scene::parse(&text, "reference").unwrap();
    let report = engine::run(&s, engine::RunOptions::default())
        .map_err(|e| format!("{point}: {e} [{e:?}]"))?;
    let c = report.cycle.unwrap();
    c.values.ok_or_else(|| format!("{point}: {:?} after {} cycles", c.status, c.cycles_computed))
}

/// Compares the cycle `v` with a row's reference on `keys`, raising `worst` and recording
/// each deviation beyond its bound in `failures`.
fn compare(
    row: &serde_json::Value,
    keys: &[(Quantity, f64)],
    v: &CycleValues,
    gamma: f64,
    worst: &mut [f64],
    failures: &mut Vec<String>,
) {
    let point = format!("ξ={} ε={} γ={gamma:e}", row["xi"], row["epsilon"]);
    for (k, &(quantity, bound)) in keys.iter().enumerate() {
        let ours = quantity.of(v, gamma);
        let reference = row["reference"][quantity.key()].as_f64().unwrap();
        let rel = (ours - reference).abs() / reference.abs();
        worst[k] = worst[k].max(rel);
        if rel.is_nan() || rel >= bound {
            failures.push(format!(
                "{point}: {} = {ours} vs reference {reference} ({rel:.1e} ≥ {bound:.0e})",
                quantity.key()
            ));
        }
    }
}
