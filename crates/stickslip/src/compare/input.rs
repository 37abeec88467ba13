//! Reading a user's trajectory (CSV or JSON columns) or report (JSON with a `cycle` object),
//! and the errors of every reader (QDYN's files too, [`super::qdyn`]). Every error names where
//! (file line, or JSON path), the column and the value. Which reader a file needs is decided
//! in [`super::user_data`].

use super::quantity::Quantity;
use serde::de::IgnoredAny;
use serde::Deserialize;

/// A user's trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Times (increasing).
    pub t: Vec<f64>,
    /// States (u, v, θ).
    pub y: Vec<[f64; 3]>,
    /// Where each sample comes from, for messages: "line 17" (CSV) or "index 16" (JSON).
    pub origin: Vec<String>,
    /// Whether u was computed from the scene's force balance (a QDYN file) rather than given:
    /// it is then not compared between events, since it only repeats v and θ.
    pub u_from_force_balance: bool,
}

/// The `cycle` keys of a user's report: the keys of our own report's `cycle` section
/// (docs/reports.md). The compared ones must be numbers (or null); the others are accepted
/// and ignored; any other key is an error.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserCycle {
    /// Time between upward crossings of v = 1.
    pub period: Option<f64>,
    /// From the upward crossing of v = 1 to the v maximum.
    pub t0: Option<f64>,
    /// Full width of v(t) at half its maximum.
    pub slip_half_width: Option<f64>,
    /// ln v_max.
    pub ln_v_max: Option<f64>,
    /// ln v_min.
    pub ln_v_min: Option<f64>,
    /// u at the v maximum.
    pub u_at_v_max: Option<f64>,
    /// θ at the v maximum.
    pub theta_at_v_max: Option<f64>,
    /// Slip per event.
    pub slip: Option<f64>,
    #[serde(default, rename = "v_max")]
    _v_max: Option<IgnoredAny>,
    #[serde(default, rename = "v_min")]
    _v_min: Option<IgnoredAny>,
    #[serde(default, rename = "u_min")]
    _u_min: Option<IgnoredAny>,
    #[serde(default, rename = "u_max")]
    _u_max: Option<IgnoredAny>,
    #[serde(default, rename = "theta_min")]
    _theta_min: Option<IgnoredAny>,
    #[serde(default, rename = "theta_max")]
    _theta_max: Option<IgnoredAny>,
    #[serde(default, rename = "slip_duration")]
    _slip_duration: Option<IgnoredAny>,
    #[serde(default, rename = "steps")]
    _steps: Option<IgnoredAny>,
    #[serde(default, rename = "status")]
    _status: Option<IgnoredAny>,
    #[serde(default, rename = "converged")]
    _converged: Option<IgnoredAny>,
    #[serde(default, rename = "cycles_per_period")]
    _cycles_per_period: Option<IgnoredAny>,
    #[serde(default, rename = "spread")]
    _spread: Option<IgnoredAny>,
    #[serde(default, rename = "error_estimate")]
    _error_estimate: Option<IgnoredAny>,
    #[serde(default, rename = "stopped_by")]
    _stopped_by: Option<IgnoredAny>,
    #[serde(default, rename = "orbit")]
    _orbit: Option<IgnoredAny>,
    #[serde(default, rename = "orbit_period")]
    _orbit_period: Option<IgnoredAny>,
    #[serde(default, rename = "last_cycles")]
    _last_cycles: Option<IgnoredAny>,
    #[serde(default, rename = "cycles_used")]
    _cycles_used: Option<IgnoredAny>,
    #[serde(default, rename = "cycles_computed")]
    _cycles_computed: Option<IgnoredAny>,
    #[serde(default, rename = "time_integrated")]
    _time_integrated: Option<IgnoredAny>,
    #[serde(default, rename = "deep_sticks")]
    _deep_sticks: Option<IgnoredAny>,
    #[serde(default, rename = "convergence_rule")]
    _convergence_rule: Option<IgnoredAny>,
    #[serde(default, rename = "tolerance")]
    _tolerance: Option<IgnoredAny>,
    #[serde(default, rename = "steps_per_cycle")]
    _steps_per_cycle: Option<IgnoredAny>,
    #[serde(default, rename = "trajectory")]
    _trajectory: Option<IgnoredAny>,
}

impl UserCycle {
    /// The value the user gave for a compared quantity.
    pub fn get(&self, quantity: Quantity) -> Option<f64> {
        match quantity {
            Quantity::Period => self.period,
            Quantity::T0 => self.t0,
            Quantity::SlipHalfWidth => self.slip_half_width,
            Quantity::LnVMax => self.ln_v_max,
            Quantity::LnVMin => self.ln_v_min,
            Quantity::UAtVMax => self.u_at_v_max,
            Quantity::ThetaAtVMax => self.theta_at_v_max,
            Quantity::Slip => self.slip,
        }
    }
}

/// A user's report: other top-level keys (a whole stickslip report) are ignored.
#[derive(Debug, Clone, Deserialize)]
pub(super) struct UserReport {
    pub(super) cycle: UserCycle,
}

/// The largest user file read (bytes): with [`MAX_SAMPLES`], it bounds the comparison's
/// memory whatever the file.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

/// The most samples a trajectory may have.
pub const MAX_SAMPLES: usize = 2_000_000;

/// Why a user's file cannot be read; each message says where (file line for CSV, index or
/// JSON path for JSON), the column and the value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputError {
    /// The file starts like JSON but is not.
    #[error("invalid JSON: {0}")]
    Json(String),
    /// A report whose `cycle` object does not match docs/reports.md.
    #[error("report: {path}: {message} (the keys of docs/reports.md's cycle section)")]
    ReportKey {
        /// The JSON path, e.g. cycle.period.
        path: String,
        /// What is wrong there.
        message: String,
    },
    /// A report's `cycle` with none of the compared keys.
    #[error("report: cycle has none of the compared keys {} (all absent or null)", Quantity::ALL.map(Quantity::name).join(", "))]
    NoComparedKey,
    /// A JSON trajectory lacks one of the columns.
    #[error("JSON trajectory: missing array \"{column}\" (need t, u, v, theta; or a report with \"cycle\")")]
    MissingArray {
        /// The column.
        column: &'static str,
    },
    /// A JSON trajectory entry that is not a number.
    #[error("JSON trajectory: {column}[{index}] = {value} is not a number")]
    JsonNotNumber {
        /// The column.
        column: &'static str,
        /// The index in it.
        index: usize,
        /// The entry, as JSON.
        value: String,
    },
    /// A JSON trajectory's columns differ in length.
    #[error("JSON trajectory: t, u, v and theta must have the same length (they have {}, {}, {}, {})", lengths[0], lengths[1], lengths[2], lengths[3])]
    LengthMismatch {
        /// The lengths of t, u, v and theta.
        lengths: [usize; 4],
    },
    /// A CSV file without a header (only blank or comment lines).
    #[error("empty file")]
    Empty,
    /// A CSV header without one of the columns.
    #[error("CSV header {header:?} lacks column \"{column}\" (need t,u,v,theta)")]
    MissingColumn {
        /// The header line.
        header: String,
        /// The column.
        column: &'static str,
    },
    /// A CSV line with too few cells.
    #[error("line {line}: column {column} is missing ({cells} columns, header has {header})")]
    MissingCell {
        /// The file line (1-based).
        line: usize,
        /// The column.
        column: &'static str,
        /// The cells on the line.
        cells: usize,
        /// The columns of the header.
        header: usize,
    },
    /// A CSV cell that is not a number.
    #[error("line {line}: column {column} = {cell:?} is not a number")]
    CsvNotNumber {
        /// The file line (1-based).
        line: usize,
        /// The column.
        column: &'static str,
        /// The cell, trimmed.
        cell: String,
    },
    /// Fewer than two samples.
    #[error("a trajectory needs at least two samples (it has {0})")]
    TooFewSamples(usize),
    /// More than [`MAX_SAMPLES`] samples.
    #[error("line {line}: more than {max} samples; compare a shorter stretch, or every k-th sample (the events need |Δ ln v| ≤ 0.5 at their start and samples within 0.1 of ln v_max)", max = MAX_SAMPLES)]
    TooManySamples {
        /// The file line of the first sample beyond the limit.
        line: usize,
    },
    /// A QDYN column that must be positive.
    #[error("{at}: column {column} = {value} must be finite and > 0")]
    NotPositive {
        /// Where the sample is.
        at: String,
        /// The column (QDYN's name).
        column: &'static str,
        /// The value.
        value: f64,
    },
    /// QDYN's `output_ox`: snapshots of the fault, not a time series.
    #[error("this is QDYN's output_ox: snapshots of the whole fault every NTOUT_OX steps ({rows} rows here), not a time series; give output_ot_0 from the same run (its time series, a row every NTOUT_OT steps), or output_vmax")]
    QdynSnapshots {
        /// The data rows in the file.
        rows: usize,
    },
    /// QDYN's `output_vmax` of a fault with several elements.
    #[error("{at}: ivmax = {ivmax}: this output_vmax follows the velocity maximum over several fault elements, so it is not a spring-block's time series; compare a spring-block's (MESHDIM = 0) output_ot_0 or output_vmax")]
    QdynElements {
        /// Where the row is.
        at: String,
        /// The element of the maximum.
        ivmax: f64,
    },
    /// A time that is not finite.
    #[error("{at}: column t = {t} must be finite")]
    TimeNotFinite {
        /// Where the sample is ("line 17", "index 16").
        at: String,
        /// The time.
        t: f64,
    },
    /// A time not greater than the previous one.
    #[error("{at}: column t = {t} must be greater than the previous sample's t = {previous} (times must increase)")]
    TimeNotIncreasing {
        /// Where the sample is.
        at: String,
        /// The time.
        t: f64,
        /// The previous sample's time.
        previous: f64,
    },
    /// u or theta not finite.
    #[error("{at}: column {column} = {value} must be finite")]
    NotFinite {
        /// Where the sample is.
        at: String,
        /// The column: u or theta.
        column: &'static str,
        /// The value.
        value: f64,
    },
    /// v not finite and positive.
    #[error("{at}: column v = {value} must be finite and > 0")]
    VelocityNotPositive {
        /// Where the sample is.
        at: String,
        /// The value.
        value: f64,
    },
}

/// A JSON trajectory: `{"t": [...], "u": [...], "v": [...], "theta": [...]}`.
pub(super) fn read_json_trajectory(json: &serde_json::Value) -> Result<Trajectory, InputError> {
    let column = |column: &'static str| -> Result<Vec<f64>, InputError> {
        json.get(column)
            .and_then(|c| c.as_array())
            .ok_or(InputError::MissingArray { column })?
            .iter()
            .enumerate()
            .map(|(index, x)| {
                x.as_f64().ok_or_else(|| InputError::JsonNotNumber {
                    column,
                    index,
                    value: x.to_string(),
                })
            })
            .collect()
    };
    let (t, u, v, theta) = (column("t")?, column("u")?, column("v")?, column("theta")?);
    if [u.len(), v.len(), theta.len()].iter().any(|&n| n != t.len()) {
        return Err(InputError::LengthMismatch {
            lengths: [t.len(), u.len(), v.len(), theta.len()],
        });
    }
    if t.len() > MAX_SAMPLES {
        return Err(InputError::TooManySamples { line: 1 });
    }
    let y = (0..t.len()).map(|i| [u[i], v[i], theta[i]]).collect();
    let origin = (0..u.len()).map(|i| format!("index {i}")).collect();
    Ok(Trajectory { t, y, origin, u_from_force_balance: false })
}

/// A CSV trajectory: a header naming t, u, v, theta (any order), then one sample per line.
pub(super) fn read_csv(text: &str) -> Result<Trajectory, InputError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (_, header) = lines.next().ok_or(InputError::Empty)?;
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_lowercase()).collect();
    let index = |column: &'static str| {
        names
            .iter()
            .position(|n| n == column)
            .ok_or_else(|| InputError::MissingColumn { header: header.into(), column })
    };
    let cols =
        [("t", index("t")?), ("u", index("u")?), ("v", index("v")?), ("theta", index("theta")?)];
    let mut trajectory = Trajectory {
        t: Vec::new(),
        y: Vec::new(),
        origin: Vec::new(),
        u_from_force_balance: false,
    };
    for (n, line) in lines {
        if trajectory.t.len() == MAX_SAMPLES {
            return Err(InputError::TooManySamples { line: n + 1 });
        }
        let cells: Vec<&str> = line.split(',').collect();
        let value = |(column, c): (&'static str, usize)| -> Result<f64, InputError> {
            let cell = cells.get(c).ok_or(InputError::MissingCell {
                line: n + 1,
                column,
                cells: cells.len(),
                header: names.len(),
            })?;
            cell.trim().parse::<f64>().map_err(|_| InputError::CsvNotNumber {
                line: n + 1,
                column,
                cell: cell.trim().into(),
            })
        };
        trajectory.t.push(value(cols[0])?);
        trajectory.y.push([value(cols[1])?, value(cols[2])?, value(cols[3])?]);
        trajectory.origin.push(format!("line {}", n + 1));
    }
    Ok(trajectory)
}

/// At least two samples, times finite and increasing.
pub(super) fn check_times(t: &[f64], origin: &[String]) -> Result<(), InputError> {
    if t.len() < 2 {
        return Err(InputError::TooFewSamples(t.len()));
    }
    for (i, &ti) in t.iter().enumerate() {
        if !ti.is_finite() {
            return Err(InputError::TimeNotFinite { at: origin[i].clone(), t: ti });
        }
        if i > 0 && ti <= t[i - 1] {
            return Err(InputError::TimeNotIncreasing {
                at: origin[i].clone(),
                t: ti,
                previous: t[i - 1],
            });
        }
    }
    Ok(())
}

/// At least two samples, times finite and increasing, u and θ finite, v finite and > 0.
pub(super) fn check(trajectory: Trajectory) -> Result<Trajectory, InputError> {
    check_times(&trajectory.t, &trajectory.origin)?;
    let names = ["u", "v", "theta"];
    for (i, y) in trajectory.y.iter().enumerate() {
        let at = &trajectory.origin[i];
        for k in [0, 2] {
            if !y[k].is_finite() {
                return Err(InputError::NotFinite {
                    at: at.clone(),
                    column: names[k],
                    value: y[k],
                });
            }
        }
        if !(y[1].is_finite() && y[1] > 0.0) {
            return Err(InputError::VelocityNotPositive { at: at.clone(), value: y[1] });
        }
    }
    Ok(trajectory)
}
