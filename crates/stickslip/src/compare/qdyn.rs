//! QDYN's output files as a user's trajectory: `output_ot_*`, or a spring-block's
//! `output_vmax` (its one element: the same rows), read as QDYN writes them (their header,
//! whitespace-separated Fortran `E` columns in SI units), then turned into the scene's
//! dimensionless (t, u, v, θ) with the scene's own mapping ([`crate::model::scales`]):
//! t/(D_c/v0), V/v0, θ = (b/a) ln(v0 Θ/D_c), and u from the force balance,
//! u = −(Φ(v, θ) + η v)/ξ (QDYN's spring-block is quasi-dynamic), not from slip − t, whose
//! origin QDYN sets at its own t = 0. `output_ox` (snapshots of the fault) is named and refused.
//!
//! QDYN prints t with 14 significant digits (`E24.14`), so late in a long run its fastest steps
//! (2e-5 s at t ~ 1e8 s, where a printed digit is 1e-5 s) print the same time twice or more.
//! Such a run of rows is merged into one: the middle one (the earlier of the two middle ones
//! for an even count) is kept, as the row whose true time is nearest the printed one (the
//! printed t is each row's time rounded, and the rows' true times increase across it).
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
/// The first header line of QDYN's `output_vmax`.
pub const VMAX_FIRST_LINE: &str = "# values at max(V) location:";
/// How each snapshot of QDYN's `output_ox` starts.
pub const OX_HEADER_START: &str = "# t x y z";

/// Which of QDYN's output files a text is, recognised by its first line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QdynFile {
    /// `output_ot_*`: the time series at a selected point (nine columns).
    Ot,
    /// `output_vmax`: the time series at the location of the velocity maximum (eight
    /// columns); for a spring-block, its one element.
    Vmax,
    /// `output_ox`: snapshots of the whole fault every NTOUT_OX steps (refused: not a time
    /// series).
    Ox,
}

impl QdynFile {
    /// The kind of QDYN output `text` is (None: not one of QDYN's output files).
    pub fn recognise(text: &str) -> Option<QdynFile> {
        let first = text.lines().next()?.trim();
        if first == OT_FIRST_LINE {
            Some(QdynFile::Ot)
        } else if first == VMAX_FIRST_LINE {
            Some(QdynFile::Vmax)
        } else if first.starts_with(OX_HEADER_START) {
            Some(QdynFile::Ox)
        } else {
            None
        }
    }

    /// A time series' columns (QDYN's names) and where t, V, Θ and τ are among them; None
    /// for `output_ox`, snapshots of the fault rather than a time series.
    fn layout(self) -> Option<(&'static [&'static str], [usize; 4])> {
        match self {
            QdynFile::Ot => Some((
                &["t", "pot", "pot_rate", "V", "theta", "tau", "dtau_dt", "slip", "sigma"],
                [0, 3, 4, 5],
            )),
            QdynFile::Vmax => Some((
                &["t", "ivmax", "v", "theta", "tau", "dtau_dt", "slip", "sigma"],
                [0, 2, 3, 4],
            )),
            QdynFile::Ox => None,
        }
    }
}

/// The largest relative difference between the file's τ and the scene's σμ at the file's V
/// and Θ: QDYN prints 7 significant digits (`E15.7`), so V, Θ and τ are each within 5e-8.
pub const STRESS_MISMATCH: f64 = 1e-5;

/// The columns of QDYN's time series that the comparison reads, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct QdynOutput {
    /// The file it was read from: `output_ot` or `output_vmax`.
    pub file: QdynFile,
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
    /// Rows left out because they print the same t as a neighbouring row (see the module
    /// docs: of each run of tied rows the middle one is kept).
    pub tied: TiedTimes,
}

/// The rows merged because they print the same time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TiedTimes {
    /// Rows left out.
    pub rows_left_out: usize,
    /// Runs of rows with one printed time.
    pub runs: usize,
    /// The file line of the first row of the first run.
    pub first: Option<String>,
}

/// A Fortran `E` field: `0.1234567E+02`, or `0.1234567-100` beyond two exponent digits.
fn fortran_number(cell: &str) -> Option<f64> {
    cell.parse().ok().or_else(|| {
        let split = cell.rfind(['+', '-']).filter(|&i| i > 0)?;
        format!("{}E{}", &cell[..split], &cell[split..]).parse().ok()
    })
}

/// Reads a QDYN time series of the `kind` recognised ([`QdynFile::recognise`]): `#` header
/// lines, then rows of its columns (`output_ot_*`: t, pot, pot_rate, V, Θ, τ, dtau_dt, slip, σ;
/// `output_vmax`: t, ivmax, V, Θ, τ, dtau_dt, slip, σ). `output_ox` is refused
/// ([`InputError::QdynSnapshots`]), and so is an `output_vmax` whose maximum moves between
/// elements (not a spring-block). Rows that print the same time are merged (module docs). A
/// text whose first line is none of QDYN's headers is read as `output_ot_*`.
pub fn read_qdyn_output(text: &str) -> Result<QdynOutput, InputError> {
    let kind = QdynFile::recognise(text).unwrap_or(QdynFile::Ot);
    let Some((names, [ct, cv, cs, ctau])) = kind.layout() else {
        let rows = text.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#')).count();
        return Err(InputError::QdynSnapshots { rows });
    };
    let mut out = QdynOutput {
        file: kind,
        t: vec![],
        v: vec![],
        state: vec![],
        tau: vec![],
        origin: vec![],
        repeated_last: None,
        tied: TiedTimes::default(),
    };
    let mut rows: [Option<Vec<&str>>; 2] = [None, None];
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split_whitespace().collect();
        let value = |k: usize| -> Result<f64, InputError> {
            let column = names[k];
            let cell = cells.get(k).ok_or(InputError::MissingCell {
                line: n + 1,
                column,
                cells: cells.len(),
                header: names.len(),
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
        if kind == QdynFile::Vmax {
            let ivmax = value(1)?;
            if ivmax != 1.0 {
                return Err(InputError::QdynElements { at, ivmax });
            }
        }
        let positive = |k: usize| -> Result<f64, InputError> {
            let x = value(k)?;
            if x.is_finite() && x > 0.0 {
                return Ok(x);
            }
            Err(InputError::NotPositive { at: at.clone(), column: names[k], value: x })
        };
        out.t.push(value(ct)?);
        out.v.push(positive(cv)?);
        out.state.push(positive(cs)?);
        out.tau.push(value(ctau)?);
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
    merge_tied_times(&mut out);
    check_times(&out.t, &out.origin)?;
    Ok(out)
}

/// Keeps one row of each run of rows that print the same time: the middle one (the earlier
/// of the two middle ones for an even count), whose true time is nearest the printed one.
fn merge_tied_times(out: &mut QdynOutput) {
    let n = out.t.len();
    let mut keep = Vec::with_capacity(n);
    let mut i = 0;
    while i < n {
        let mut j = i + 1;
        while j < n && out.t[j] == out.t[i] {
            j += 1;
        }
        if j - i > 1 {
            out.tied.rows_left_out += j - i - 1;
            out.tied.runs += 1;
            out.tied.first.get_or_insert_with(|| out.origin[i].clone());
        }
        keep.push(i + (j - i - 1) / 2);
        i = j;
    }
    if keep.len() == n {
        return;
    }
    out.t = keep.iter().map(|&k| out.t[k]).collect();
    out.v = keep.iter().map(|&k| out.v[k]).collect();
    out.state = keep.iter().map(|&k| out.state[k]).collect();
    out.tau = keep.iter().map(|&k| out.tau[k]).collect();
    out.origin = keep.iter().map(|&k| std::mem::take(&mut out.origin[k])).collect();
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
        assert_eq!(QdynFile::recognise(text), Some(QdynFile::Ot));
        assert_eq!(QdynFile::recognise("t,u,v,theta\n0,0,1,0\n"), None);
        let q = read_qdyn_output(text).unwrap();
        assert_eq!((q.t[0], q.v[0], q.state[0], q.tau[0]), (0.0, 5e-10, 1e5, 5.932128e6));
        assert_eq!(
            (q.origin[0].as_str(), q.t.len(), q.repeated_last.as_deref()),
            ("line 5", 2, None)
        );
        assert_eq!(q.tied, TiedTimes::default());
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

    #[test]
    fn tied_times_keep_the_middle_row_and_are_counted() {
        // Times 0, 1, 1, 2, 2, 2, 3; V numbers the rows so the kept one shows.
        let row = |t: &str, v: usize| {
            format!(
                "{t}  0.1E+00  0.1E+00  0.{v}E-09  0.1E+06  0.5E+07  0.0E+00  0.0E+00  0.1E+08\n"
            )
        };
        let times = ["0.0E+00", "0.1E+01", "0.1E+01", "0.2E+01", "0.2E+01", "0.2E+01", "0.3E+01"];
        let rows: String = times.iter().enumerate().map(|(i, t)| row(t, i + 1)).collect();
        let q = read_qdyn_output(&format!("{OT_FIRST_LINE}\n{rows}")).unwrap();
        assert_eq!(q.t, [0.0, 1.0, 2.0, 3.0]);
        // Of the pair the earlier (row 2), of the three the middle (row 5).
        assert_eq!(q.v, [1e-10, 2e-10, 5e-10, 7e-10]);
        assert_eq!(q.origin, ["line 2", "line 3", "line 6", "line 8"]);
        let first = Some("line 3".to_string());
        assert_eq!(q.tied, TiedTimes { rows_left_out: 3, runs: 2, first });
        // A time that goes back is still refused.
        let back = format!("{OT_FIRST_LINE}\n{}{}", row("0.2E+01", 1), row("0.1E+01", 2));
        let e = read_qdyn_output(&back).unwrap_err();
        assert!(e.to_string().contains("line 3: column t = 1 must be greater"), "{e}");
    }

    #[test]
    fn output_vmax_is_read_and_output_ox_is_named() {
        let vmax = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/reference/qdyn_output/output_vmax"
        ))
        .unwrap();
        let q = read_qdyn_output(&vmax).unwrap();
        assert_eq!(q.file, QdynFile::Vmax);
        assert_eq!(
            (q.t[1], q.v[1], q.state[1], q.tau[1]),
            (0.076174138036644, 4.999999e-10, 1e5, 5.932128e6)
        );
        let other =
            vmax.replacen("              1  0.4999999E-09", "              2  0.4999999E-09", 1);
        let e = read_qdyn_output(&other).unwrap_err();
        assert!(e.to_string().contains("line 4: ivmax = 2"), "{e}");
        let ox = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/reference/qdyn_output/output_ox"
        ))
        .unwrap();
        let e = read_qdyn_output(&ox).unwrap_err();
        assert!(e.to_string().starts_with("this is QDYN's output_ox"), "{e}");
        assert!(e.to_string().contains("(2 rows here)"), "{e}");
    }
}
