//! Parameter sweeps: one JSON object per point (JSON Lines), parallel over cores, resumable
//! after a kill, and shardable across machines with a merge step.
//!
//! A point's row holds its index, its parameters and the scene's requested report sections
//! (the keys of `stickslip run`), or the error that ended it. Rows carry no wall time, so a
//! sweep's rows do not depend on scheduling: a killed and resumed sweep yields exactly the rows
//! of an uninterrupted one. Rows are appended as points finish (one write per line); `merge`
//! sorts them by index and checks that none is missing.

use crate::analysis::continuation::Parameter;
use crate::scene::{self, AnalysisKind};
use crate::{engine, parallel};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;

/// A scene parameter a sweep can set: one that continuation follows too, or the power-law
/// exponent α, which only sweeps set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum SweepParameter {
    /// ε, ξ, γ or η ([`Parameter`]): the scene field `model.NAME`.
    Continued(Parameter),
    /// The power-law friction exponent α: the scene field `model.friction.power.alpha`.
    Alpha,
}

impl SweepParameter {
    /// Every parameter a sweep can set, in the order the errors list them.
    pub fn all() -> impl Iterator<Item = Self> {
        Parameter::ALL.into_iter().map(Self::Continued).chain([Self::Alpha])
    }

    /// The parameter by its scene name (`--param NAME=…`, the rows' `params`).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::all().find(|p| p.name() == name)
    }

    /// The scene name: [`Parameter::name`], or "alpha".
    pub fn name(self) -> &'static str {
        match self {
            Self::Continued(p) => p.name(),
            Self::Alpha => "alpha",
        }
    }

    /// The keys of its scene field, from the scene's root.
    pub fn path(self) -> Vec<&'static str> {
        match self {
            Self::Continued(_) => vec!["model", self.name()],
            Self::Alpha => vec!["model", "friction", "power", self.name()],
        }
    }
}

/// The scene names of every [`SweepParameter`], as the errors list them.
fn parameter_names() -> String {
    SweepParameter::all().map(SweepParameter::name).collect::<Vec<_>>().join(", ")
}

/// One swept parameter: `NAME=START:STOP:COUNT[:log]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The parameter.
    pub parameter: SweepParameter,
    /// The values, in order.
    pub values: Vec<f64>,
}

/// The usage of `--param`, quoted by the errors that reject one.
const AXIS_USAGE: &str =
    "expected NAME=START:STOP:COUNT[:log], e.g. epsilon=0.71:1.2:51 or gamma=1e1:1e8:71:log";

/// Why a sweep's arguments or base scene are refused; each message names the argument
/// (`--param`, `--shard`) or the scene field at fault and the fix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SweepError {
    /// `--param` is not `NAME=START:STOP:COUNT[:log]`.
    #[error("--param {spec:?}: {usage}", usage = AXIS_USAGE)]
    AxisSyntax {
        /// The argument as given.
        spec: String,
    },
    /// `--param` names a parameter that cannot be swept.
    #[error("--param {spec:?}: unknown parameter {name:?}; use one of {}", parameter_names())]
    UnknownParameter {
        /// The argument as given.
        spec: String,
        /// The parameter's name.
        name: String,
    },
    /// The fourth part of `--param` is not `log`.
    #[error("--param {spec:?}: {word:?} is not \"log\"; {usage}", usage = AXIS_USAGE)]
    NotLog {
        /// The argument as given.
        spec: String,
        /// The fourth part.
        word: String,
    },
    /// START or STOP is not a finite number.
    #[error("--param {spec:?}: {value:?} is not a finite number")]
    NotFinite {
        /// The argument as given.
        spec: String,
        /// The part that is not a finite number.
        value: String,
    },
    /// COUNT is not an integer ≥ 1.
    #[error("--param {spec:?}: COUNT {count:?} must be an integer ≥ 1")]
    BadCount {
        /// The argument as given.
        spec: String,
        /// The COUNT part.
        count: String,
    },
    /// A log axis with START or STOP ≤ 0.
    #[error("--param {spec:?}: a log axis needs START and STOP > 0")]
    LogNotPositive {
        /// The argument as given.
        spec: String,
    },
    /// `--shard` is not `K/N`.
    #[error("--shard {spec:?}: expected K/N, e.g. 3/8")]
    ShardSyntax {
        /// The argument as given.
        spec: String,
    },
    /// K or N of `--shard` is not an integer.
    #[error("--shard {spec:?}: {part} is not an integer")]
    ShardNotInteger {
        /// The argument as given.
        spec: String,
        /// "K" or "N".
        part: &'static str,
    },
    /// `--shard` outside 1 ≤ K ≤ N.
    #[error("--shard {spec:?}: need 1 ≤ K ≤ N")]
    ShardRange {
        /// The argument as given.
        spec: String,
    },
    /// The base scene's model is dimensional.
    #[error("sweeps set {}: give the scene's model as gamma, xi, epsilon, not dimensional", Parameter::ALL.map(Parameter::name).join("/"))]
    Dimensional,
    /// `--param alpha` on a scene without power-law friction.
    #[error("--param alpha needs a scene with \"friction\": {{\"power\": {{\"alpha\": ...}}}}")]
    AlphaWithoutPower,
    /// The base scene asks for the noise analysis.
    #[error("sweeps do not run the \"noise\" analysis (its ensembles use every core for one point); remove it, or run `stickslip run` per parameter set")]
    Noise,
}

/// Parses `NAME=START:STOP:COUNT[:log]`; the error says what is wrong.
pub fn parse_axis(spec: &str) -> Result<Axis, SweepError> {
    let (name, range) =
        spec.split_once('=').ok_or_else(|| SweepError::AxisSyntax { spec: spec.into() })?;
    let parameter = SweepParameter::from_name(name)
        .ok_or_else(|| SweepError::UnknownParameter { spec: spec.into(), name: name.into() })?;
    let parts: Vec<&str> = range.split(':').collect();
    let log = match parts.get(3) {
        None => false,
        Some(&"log") => true,
        Some(other) => return Err(SweepError::NotLog { spec: spec.into(), word: (*other).into() }),
    };
    if parts.len() < 3 || parts.len() > 4 {
        return Err(SweepError::AxisSyntax { spec: spec.into() });
    }
    let number = |s: &str| {
        s.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| SweepError::NotFinite { spec: spec.into(), value: s.into() })
    };
    let (start, stop) = (number(parts[0])?, number(parts[1])?);
    let count: usize = parts[2]
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| SweepError::BadCount { spec: spec.into(), count: parts[2].into() })?;
    if log && (start <= 0.0 || stop <= 0.0) {
        return Err(SweepError::LogNotPositive { spec: spec.into() });
    }
    let values = (0..count)
        .map(|i| {
            let f = if count == 1 { 0.0 } else { i as f64 / (count - 1) as f64 };
            if log {
                10f64.powf(start.log10() + f * (stop.log10() - start.log10()))
            } else {
                start + f * (stop - start)
            }
        })
        .collect();
    Ok(Axis { parameter, values })
}

impl std::str::FromStr for Axis {
    type Err = SweepError;

    /// As [`parse_axis`] (clap parses `--param` with it).
    fn from_str(spec: &str) -> Result<Self, SweepError> {
        parse_axis(spec)
    }
}

/// One point of a sweep: the value of each swept parameter.
pub type Point = BTreeMap<SweepParameter, f64>;

/// The points of the grid (the cartesian product of the axes, first axis slowest).
pub fn points(axes: &[Axis]) -> Vec<Point> {
    let mut points = vec![BTreeMap::new()];
    for axis in axes {
        points = points
            .into_iter()
            .flat_map(|p| {
                axis.values.iter().map(move |&v| {
                    let mut q = p.clone();
                    q.insert(axis.parameter, v);
                    q
                })
            })
            .collect();
    }
    points
}

/// One row of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Index of the point in the full grid.
    pub index: usize,
    /// The swept parameters.
    pub params: BTreeMap<String, f64>,
    /// The requested report sections (hopf, cycle, paper, physical, shooting, continuation), or null on error.
    pub report: Option<serde_json::Value>,
    /// The error that ended the point, if any (exit-code-1 cases of `stickslip run`).
    pub error: Option<String>,
}

/// `K/N`: this process runs the points with index % N == K − 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number.
    pub k: usize,
    /// Number of shards.
    pub n: usize,
}

/// Parses `K/N` with 1 ≤ K ≤ N.
pub fn parse_shard(spec: &str) -> Result<Shard, SweepError> {
    let (k, n) =
        spec.split_once('/').ok_or_else(|| SweepError::ShardSyntax { spec: spec.into() })?;
    let integer = |s: &str, part| {
        s.parse::<usize>().map_err(|_| SweepError::ShardNotInteger { spec: spec.into(), part })
    };
    let (k, n) = (integer(k, "K")?, integer(n, "N")?);
    if n == 0 || k == 0 || k > n {
        return Err(SweepError::ShardRange { spec: spec.into() });
    }
    Ok(Shard { k, n })
}

impl std::str::FromStr for Shard {
    type Err = SweepError;

    /// As [`parse_shard`] (clap parses `--shard` with it).
    fn from_str(spec: &str) -> Result<Self, SweepError> {
        parse_shard(spec)
    }
}

/// The scene JSON with the point's parameters set (each at its [`SweepParameter::path`]);
/// parsing it again re-validates everything and recomputes the default start on the slow
/// manifold.
fn scene_at(base: &serde_json::Value, point: &Point) -> serde_json::Value {
    let mut s = base.clone();
    for (parameter, &v) in point {
        let slot = parameter.path().into_iter().fold(&mut s, |node, key| &mut node[key]);
        *slot = serde_json::json!(v);
    }
    s
}

/// Checks that a scene can be swept over these axes; the error says why not.
pub fn check_base(base: &serde_json::Value, axes: &[Axis]) -> Result<(), SweepError> {
    if base["model"].get("dimensional").is_some() {
        return Err(SweepError::Dimensional);
    }
    let alpha = axes.iter().any(|a| a.parameter == SweepParameter::Alpha);
    if alpha && base["model"]["friction"].get("power").is_none() {
        return Err(SweepError::AlphaWithoutPower);
    }
    let analyses = base["analyses"].as_array().map(Vec::as_slice).unwrap_or_default();
    if analyses.iter().any(|a| a.get(AnalysisKind::Noise.name()).is_some()) {
        return Err(SweepError::Noise);
    }
    Ok(())
}

/// Runs one point: the scene with its parameters (validated as `stickslip run` would), the
/// requested report sections kept and the wall time dropped.
pub fn run_point(base: &serde_json::Value, index: usize, point: &Point) -> Row {
    let outcome = point_scene(base, point)
        .and_then(|s| engine::run(&s, engine::RunOptions::default()).map_err(|e| e.to_string()));
    row(index, point, outcome)
}

/// [`run_point`] that the caller can stop with `cancel` ([`engine::RunOptions::cancel`]):
/// `None` when it was cancelled.
pub fn run_point_cancellable(
    base: &serde_json::Value,
    index: usize,
    point: &Point,
    cancel: &engine::Cancel,
) -> Option<Row> {
    let outcome = match point_scene(base, point) {
        Err(e) => Err(e),
        Ok(s) => match engine::run(&s, engine::RunOptions::default().cancel(cancel)) {
            Err(engine::RunError::Cancelled) => return None,
            other => other.map_err(|e| e.to_string()),
        },
    };
    Some(row(index, point, outcome))
}

/// The scene of one point, validated as `stickslip run` would.
fn point_scene(base: &serde_json::Value, point: &Point) -> Result<crate::scene::Scene, String> {
    scene::parse(&scene_at(base, point).to_string(), "sweep point").map_err(|e| e.to_string())
}

/// The row of point `index`: the requested sections of its report, or its error.
fn row(index: usize, point: &Point, outcome: Result<crate::report::Report, String>) -> Row {
    let params = point.iter().map(|(p, &v)| (p.name().to_string(), v)).collect();
    match outcome {
        Ok(report) => {
            let mut json = serde_json::to_value(&report).expect("a report serialises");
            // The analyses' sections, and the cycle's values in physical units.
            let sections: serde_json::Map<String, serde_json::Value> = [
                AnalysisKind::Hopf.name(),
                AnalysisKind::Cycle.name(),
                AnalysisKind::Paper.name(),
                "physical",
                AnalysisKind::Shooting.name(),
                AnalysisKind::Continuation.name(),
                AnalysisKind::Asymptotics.name(),
                AnalysisKind::Lyapunov.name(),
            ]
            .into_iter()
            .filter_map(|k| json.get_mut(k).map(|v| (k.to_string(), v.take())))
            .collect();
            Row { index, params, report: Some(serde_json::Value::Object(sections)), error: None }
        }
        Err(e) => Row { index, params, report: None, error: Some(e) },
    }
}

/// Reads the rows already in `path` (for --resume), dropping a trailing partial line left by
/// a kill and rewriting the file without it.
pub fn read_done(path: &Path) -> std::io::Result<Vec<Row>> {
    Ok(read_lines(path)?.into_iter().map(|(row, _)| row).collect())
}

/// The complete rows of a sweep output, each with its line as written (without the newline),
/// dropping a trailing partial line left by a kill and rewriting the file without it.
fn read_lines(path: &Path) -> std::io::Result<Vec<(Row, String)>> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e),
    };
    let mut rows = Vec::new();
    let mut good = 0;
    for line in text.split_inclusive('\n') {
        let complete = line.trim_end_matches('\n');
        match (line.ends_with('\n'), serde_json::from_str::<Row>(complete)) {
            (true, Ok(row)) => {
                good += line.len();
                rows.push((row, complete.to_string()));
            }
            _ => break,
        }
    }
    if good != text.len() {
        crate::report::write_atomic(path, &text[..good])?;
    }
    Ok(rows)
}

/// Runs the sweep into `out` (appending; with `resume`, skipping points already there).
/// Returns the number of points run now.
pub fn run(
    base: &serde_json::Value,
    axes: &[Axis],
    out: &Path,
    resume: bool,
    shard: Option<Shard>,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> std::io::Result<usize> {
    let done: std::collections::BTreeSet<usize> = if resume {
        read_done(out)?.into_iter().map(|r| r.index).collect()
    } else {
        std::fs::write(out, "")?;
        Default::default()
    };
    let todo: Vec<(usize, Point)> = points(axes)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| shard.is_none_or(|s| i % s.n == s.k - 1) && !done.contains(i))
        .collect();
    let file = Mutex::new(std::fs::OpenOptions::new().append(true).create(true).open(out)?);
    // Each row is written as soon as its point finishes (what --resume reads back).
    parallel::try_map(todo.len(), threads, progress, |i| {
        let (index, point) = &todo[i];
        let row = run_point(base, *index, point);
        let line = serde_json::to_string(&row).expect("a row serialises") + "\n";
        let mut f = file.lock().unwrap_or_else(|e| e.into_inner());
        f.write_all(line.as_bytes()).and_then(|_| f.flush())
    })?;
    Ok(todo.len())
}

/// Merges shard outputs: the rows' lines sorted by index, each exactly as the sweep wrote it
/// (parsing and printing a row again could change a number's last digit: serde_json's
/// default float parsing is not correctly rounded), duplicates dropped (they are identical),
/// and the missing indices of the full grid listed.
pub fn merge(inputs: &[&Path], total: Option<usize>) -> std::io::Result<(Vec<String>, Vec<usize>)> {
    let mut lines: BTreeMap<usize, String> = BTreeMap::new();
    for path in inputs {
        for (row, line) in read_lines(path)? {
            lines.entry(row.index).or_insert(line);
        }
    }
    let missing =
        total.map_or_else(Vec::new, |n| (0..n).filter(|i| !lines.contains_key(i)).collect());
    Ok((lines.into_values().collect(), missing))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each parameter's name parses back to it, and a point sets its scene field: α inside the
    /// power law, the others in the model.
    #[test]
    fn axes_set_their_scene_fields() {
        let base =
            serde_json::json!({"model": {"gamma": 10.0, "friction": {"power": {"alpha": 0.3}}}});
        for parameter in SweepParameter::all() {
            let axis = parse_axis(&format!("{}=0.5:0.6:2", parameter.name())).unwrap();
            assert_eq!(axis.parameter, parameter);
            assert_eq!(axis.values, [0.5, 0.6]);
            let scene = scene_at(&base, &points(&[axis])[1]);
            let path = format!("/{}", parameter.path().join("/"));
            assert_eq!(scene.pointer(&path), Some(&serde_json::json!(0.6)), "{path}");
        }
        let alpha = parse_axis("alpha=0.5:0.6:2").unwrap();
        assert_eq!(alpha.parameter, SweepParameter::Alpha);
        let no_power = serde_json::json!({"model": {"gamma": 10.0}});
        assert_eq!(check_base(&no_power, &[alpha]), Err(SweepError::AlphaWithoutPower));
        let e = parse_axis("mass=1:2:2").unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("unknown parameter \"mass\"; use one of epsilon, xi, gamma, radiation_damping, alpha"),
            "{text}"
        );
    }
}
