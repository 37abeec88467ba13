//! QDYN's `output_ot_*` as a user's trajectory: read as QDYN writes it (its header, nine
//! whitespace-separated Fortran `E` columns in SI units), then turned into the scene's
//! dimensionless (t, u, v, θ) with the scene's own mapping ([`crate::model::scales`]):
//! t/(D_c/v0), V/v0, θ = (b/a) ln(v0 Θ/D_c), and u from the force balance,
//! u = −(Φ(v, θ) + η v)/ξ (QDYN's spring-block is quasi-dynamic), not from slip − t, whose
//! origin QDYN sets at its own t = 0.
//!
//! The τ column checks the mapping: at each sample it must equal the scene's σμ(V, Θ) to the
//! file's printed digits, so a file made with other friction parameters (a, b, μ*, V*, the
//! law), or in other units, is refused at once ([`SceneMismatch::Stress`]).

use super::input::{check_times, InputError, Trajectory, MAX_SAMPLES};
use super::scale::SceneMismatch;
use crate::model::scales::dimensionless_friction;
use crate::model::Drr;
use crate::scene::Scene;

/// The first header line of QDYN's `output_ot_*` files.
pub const OT_FIRST_LINE: &str = "# macroscopic values:";

/// The largest relative difference between the file's τ and the scene's σμ at the file's V
/// and Θ: QDYN prints 7 significant digits (`E15.7`), so V, Θ and τ are each within 5e-8.
pub const STRESS_MISMATCH: f64 = 1e-5;

/// The columns of QDYN's `output_ot_*` that the comparison reads, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct QdynOutput {
    /// t (s).
    pub t: Vec<f64>,
    /// V (m/s).
    pub v: Vec<f64>,
    /// Θ (s).
    pub state: Vec<f64>,
    /// τ (Pa).
    pub tau: Vec<f64>,
    /// The file line of each sample ("line 17").
    pub origin: Vec<String>,
    /// The file line of a last row left out because it repeats the row before it at a later
    /// time: QDYN writes its last state again at t = TMAX when its solver stops there.
    pub repeated_last: Option<String>,
}

/// Whether `text` is a QDYN `output_ot_*` file (its first line is QDYN's header).
pub fn is_qdyn_output(text: &str) -> bool {
    text.lines().next().is_some_and(|l| l.trim() == OT_FIRST_LINE)
}

/// A Fortran `E` field: `0.1234567E+02`, or `0.1234567-100` beyond two exponent digits.
fn fortran_number(cell: &str) -> Option<f64> {
    cell.parse().ok().or_else(|| {
        let split = cell.rfind(['+', '-']).filter(|&i| i > 0)?;
        format!("{}E{}", &cell[..split], &cell[split..]).parse().ok()
    })
}

/// Reads an `output_ot_*` file: `#` header lines, then rows of nine columns
/// (t, pot, pot_rate, V, Θ, τ, dtau_dt, slip, σ).
pub fn read_qdyn_output(text: &str) -> Result<QdynOutput, InputError> {
    const NAMES: [&str; 9] =
        ["t", "pot", "pot_rate", "V", "theta", "tau", "dtau_dt", "slip", "sigma"];
    let mut out = QdynOutput {
        t: vec![],
        v: vec![],
        state: vec![],
        tau: vec![],
        origin: vec![],
        repeated_last: None,
    };
    let mut rows: [Option<Vec<&str>>; 2] = [None, None];
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split_whitespace().collect();
        let value = |k: usize| -> Result<f64, InputError> {
            let column = NAMES[k];
            let cell = cells.get(k).ok_or(InputError::MissingCell {
                line: n + 1,
                column,
                cells: cells.len(),
                header: NAMES.len(),
            })?;
            fortran_number(cell).ok_or_else(|| InputError::CsvNotNumber {
                line: n + 1,
                column,
                cell: (*cell).into(),
            })
        };
        if out.t.len() == MAX_SAMPLES {
            return Err(InputError::TooManySamples { line: n + 1 });
        }
        let at = format!("line {}", n + 1);
        let positive = |k: usize| -> Result<f64, InputError> {
            let x = value(k)?;
            if x.is_finite() && x > 0.0 {
                return Ok(x);
            }
            Err(InputError::NotPositive { at: at.clone(), column: NAMES[k], value: x })
        };
        out.t.push(value(0)?);
        out.v.push(positive(3)?);
        out.state.push(positive(4)?);
        out.tau.push(value(5)?);
        out.origin.push(at);
        rows = [rows[1].take(), Some(cells)];
    }
    if let [Some(before), Some(last)] = &rows {
        if before[1..] == last[1..] && out.t.len() > 2 {
            out.repeated_last = out.origin.pop();
            for column in [&mut out.t, &mut out.v, &mut out.state, &mut out.tau] {
                column.pop();
            }
        }
    }
    check_times(&out.t, &out.origin)?;
    Ok(out)
}

/// The scene's dimensionless trajectory of a QDYN output (see the module docs). Fails when
/// the scene has no physical scales or friction level, is inertial, or when a sample's τ is
/// not the scene's σμ at its V and Θ.
pub fn to_trajectory(scene: &Scene, q: &QdynOutput) -> Result<Trajectory, SceneMismatch> {
    let scales = scene.scales.ok_or(SceneMismatch::NotPhysical)?;
    let params = scene.params;
    if params.inertia {
        return Err(SceneMismatch::Inertial);
    }
    let friction = params.friction;
    scales.friction_level(&friction).ok_or(SceneMismatch::NoFrictionLevel)?;
    let drr = Drr::new(params);
    let mut trajectory =
        Trajectory { t: vec![], y: vec![], origin: q.origin.clone(), u_from_force_balance: true };
    for i in 0..q.t.len() {
        let (t, v) = (q.t[i] / scales.time_scale(), q.v[i] / scales.v0);
        let theta = scales.theta_from_state(q.state[i]);
        let w = v.ln();
        let tau = scales.shear_stress(&friction, dimensionless_friction(&params, theta, w));
        if let Some(tau) = tau.filter(|&s| v > 0.0 && s.is_finite()) {
            if (tau - q.tau[i]).abs() > STRESS_MISMATCH * tau.abs() {
                return Err(SceneMismatch::Stress {
                    at: q.origin[i].clone(),
                    v: q.v[i],
                    state: q.state[i],
                    file: q.tau[i],
                    scene: tau,
                });
            }
        }
        let u = -drr.strength(&[0.0, w, theta]).value / params.xi;
        trajectory.t.push(t);
        trajectory.y.push([u, v, theta]);
    }
    Ok(trajectory)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fortran_fields_parse_with_and_without_the_exponent_letter() {
        assert_eq!(fortran_number("0.5000000E-09"), Some(5e-10));
        assert_eq!(fortran_number("-0.1000000E+08"), Some(-1e7));
        assert_eq!(fortran_number("0.1234567-100"), Some(0.1234567e-100));
        assert_eq!(fortran_number("0.1234567+123"), Some(0.1234567e123));
        assert_eq!(fortran_number("-0.5"), Some(-0.5));
        assert_eq!(fortran_number("x1"), None);
        assert_eq!(fortran_number("-"), None);
    }

    #[test]
    fn an_output_file_is_recognised_and_read() {
        let text = "# macroscopic values:\n# 1=t, 2=pot, 3=pot_rate\n# values at selected point:\n\
                    # 4=V, 5=theta, 6=tau, 7=dtau_dt, 8=slip, 9=sigma\n    \
                    0.00000000000000E+00  0.0000000E+00  0.6000000E-07  0.5000000E-09  \
                    0.1000000E+06  0.5932128E+07  0.0000000E+00  0.0000000E+00  0.1000000E+08\n    \
                    0.10000000000000E+01  0.0000000E+00  0.6000000E-07  0.5000001E-09  \
                    0.1000000E+06  0.5932128E+07  0.0000000E+00  0.5000000E-09  0.1000000E+08\n";
        assert!(is_qdyn_output(text));
        assert!(!is_qdyn_output("t,u,v,theta\n0,0,1,0\n"));
        let q = read_qdyn_output(text).unwrap();
        assert_eq!((q.t[0], q.v[0], q.state[0], q.tau[0]), (0.0, 5e-10, 1e5, 5.932128e6));
        assert_eq!(
            (q.origin[0].as_str(), q.t.len(), q.repeated_last.as_deref()),
            ("line 5", 2, None)
        );
        // QDYN's last row at TMAX repeating the row before is left out.
        let row = |t: &str| {
            format!("{t}  0.1E+00  0.1E+00  0.5E-09  0.1E+06  0.5E+07  0.0E+00  0.0E+00  0.1E+08\n")
        };
        let text =
            format!("{OT_FIRST_LINE}\n{}{}{}", row("0.0E+00"), row("0.1E+01"), row("0.2E+01"));
        let q = read_qdyn_output(&text).unwrap();
        assert_eq!((q.t.len(), q.repeated_last.as_deref()), (2, Some("line 4")));
        let short = read_qdyn_output("# macroscopic values:\n 0.0 0.0 0.0 1e-9\n").unwrap_err();
        assert!(short.to_string().contains("line 2: column theta is missing"), "{short}");
    }
}
