//! The scene's `analyses` list: one table of (name, options it takes, parser), [`TABLE`].
//! Every analysis parses and validates its own options where they are used; the table only
//! dispatches by name, and the messages that list the analyses are built from it.

use super::{finite, Analyses, ContinuationOptions, RawAnalysis, SceneError};
use crate::analysis::continuation::Parameter;
use crate::analysis::cycle::CycleOptions;
use crate::analysis::noise::options::{self as noise_options, NoiseOptions};
use crate::analysis::shooting::ShootingOptions;
use crate::analysis::time_series::TimeSeriesOptions;
use crate::analysis::InvalidOption;
use crate::model::ModelKind;
use crate::paper::asymptotics::AsymptoticsOptions;
use crate::paper::lyapunov::LyapunovOptions;
use serde::Deserialize;
use serde_json::Value;

/// What follows an analysis's name in the scene.
enum Takes {
    /// The bare name only, e.g. `"hopf"`.
    Nothing,
    /// The bare name or `{name: {...}}`; the bare name means `{}`.
    Optional,
    /// `{name: form}` only; `missing` is the message for the bare name.
    Required { form: &'static str, missing: &'static str },
}

/// Where an analysis's options come from: the entry's field (`analyses[i]`), the model it
/// runs on and the scene's error constructor.
struct Entry<'a> {
    /// `analyses[i]`.
    field: String,
    /// (kind, dimension, γ² for the DRR), for the noise options.
    model: (ModelKind, usize, Option<f64>),
    /// The scene's error constructor.
    err: &'a dyn Fn(&str, String) -> SceneError,
}

impl Entry<'_> {
    /// The error at `field` (relative to the entry, e.g. `trajectory.cycles`).
    fn error(&self, field: &str, message: String) -> SceneError {
        (self.err)(&format!("{}.{field}", self.field), message)
    }

    /// An option error of the analysis `name`, at its path below the entry.
    fn invalid(&self, name: &str, e: InvalidOption) -> SceneError {
        (self.err)(&e.path_below(&format!("{}.{name}", self.field)), e.message)
    }
}

/// The kind of an analysis a scene can ask for; [`AnalysisKind::name`] is its name in the scene,
/// the report and error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AnalysisKind {
    /// "hopf": the linear stability of the steady state.
    Hopf,
    /// "paper": the paper's values against hopf and cycle.
    Paper,
    /// "cycle": the limit cycle.
    Cycle,
    /// "trajectory": the cycles found by "cycle", sampled.
    Trajectory,
    /// "asymptotics": matched asymptotics against the numerics.
    Asymptotics,
    /// "lyapunov": Lyapunov exponents along the cycle.
    Lyapunov,
    /// "shooting": the periodic orbit by shooting.
    Shooting,
    /// "continuation": the periodic orbit followed in a parameter.
    Continuation,
    /// "noise": an ensemble of noisy runs.
    Noise,
    /// "time_series": a run from t = 0 to t_max.
    TimeSeries,
}

impl AnalysisKind {
    /// Its name in the scene, the report and the messages, e.g. "time_series".
    pub fn name(self) -> &'static str {
        match self {
            AnalysisKind::Hopf => "hopf",
            AnalysisKind::Paper => "paper",
            AnalysisKind::Cycle => "cycle",
            AnalysisKind::Trajectory => "trajectory",
            AnalysisKind::Asymptotics => "asymptotics",
            AnalysisKind::Lyapunov => "lyapunov",
            AnalysisKind::Shooting => "shooting",
            AnalysisKind::Continuation => "continuation",
            AnalysisKind::Noise => "noise",
            AnalysisKind::TimeSeries => "time_series",
        }
    }
}

impl std::fmt::Display for AnalysisKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One analysis a scene can ask for.
struct Analysis {
    /// Its kind (and so its scene name).
    kind: AnalysisKind,
    /// What follows the name.
    takes: Takes,
    /// Records the analysis and its options (`Value::Null` when it takes none; an object
    /// when they are optional) in [`Analyses`].
    parse: fn(&mut Analyses, Value, &Entry) -> Result<(), SceneError>,
}

/// Every analysis, in the order the messages list them.
const TABLE: [Analysis; 10] = [
    Analysis { kind: AnalysisKind::Hopf, takes: Takes::Nothing, parse: hopf },
    Analysis { kind: AnalysisKind::Paper, takes: Takes::Nothing, parse: paper },
    Analysis { kind: AnalysisKind::Cycle, takes: Takes::Optional, parse: cycle },
    Analysis {
        kind: AnalysisKind::Trajectory,
        takes: Takes::Required {
            form: "{\"cycles\": N}",
            missing: "\"trajectory\" needs a sampling spec: {\"trajectory\": {\"cycles\": N}}",
        },
        parse: trajectory,
    },
    Analysis { kind: AnalysisKind::Asymptotics, takes: Takes::Optional, parse: asymptotics },
    Analysis { kind: AnalysisKind::Lyapunov, takes: Takes::Optional, parse: lyapunov },
    Analysis { kind: AnalysisKind::Shooting, takes: Takes::Optional, parse: shooting },
    Analysis {
        kind: AnalysisKind::Continuation,
        takes: Takes::Required {
            form: "{\"parameter\": \"epsilon\"|\"xi\"|\"gamma\"|\"radiation_damping\", \
                   \"to\": X, \"points\": N}",
            missing: "\"continuation\" needs {\"parameter\": \"epsilon\", \"to\": 1.2, \
                      \"points\": 51}",
        },
        parse: continuation,
    },
    Analysis {
        kind: AnalysisKind::Noise,
        takes: Takes::Required {
            form: "{\"amplitudes\": [...]}",
            missing: "\"noise\" needs its amplitudes: {\"noise\": {\"amplitudes\": [...]}} \
                      (docs/noise.md)",
        },
        parse: noise,
    },
    Analysis {
        kind: AnalysisKind::TimeSeries,
        takes: Takes::Required {
            form: "{\"t_max\": T}",
            missing: "\"time_series\" needs its length: {\"time_series\": {\"t_max\": T}} \
                      (T in the scene's time unit; docs/scenes.md)",
        },
        parse: time_series,
    },
];

/// The name of every analysis a scene can ask for.
pub fn analysis_names() -> impl Iterator<Item = &'static str> {
    TABLE.iter().map(|a| a.kind.name())
}

/// How each analysis is written, for the messages: `"hopf", "cycle", {"cycle": {...}}, …`.
fn forms() -> String {
    let form = |a: &Analysis| match a.takes {
        Takes::Nothing => format!("\"{}\"", a.kind.name()),
        Takes::Optional => format!("\"{0}\", {{\"{0}\": {{...}}}}", a.kind.name()),
        Takes::Required { form, .. } => format!("{{\"{}\": {form}}}", a.kind.name()),
    };
    TABLE.iter().map(form).collect::<Vec<_>>().join(", ")
}

/// Parses the scene's `analyses`; `model` is (kind, dimension, γ² for the DRR), for the
/// noise options.
pub(super) fn parse(
    raw: &[RawAnalysis],
    model: (ModelKind, usize, Option<f64>),
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<Analyses, SceneError> {
    let mut out = Analyses::default();
    if raw.is_empty() {
        return Err(err("analyses", format!("is empty; ask for at least one of {}", forms())));
    }
    for (i, raw_entry) in raw.iter().enumerate() {
        let entry = Entry { field: format!("analyses[{i}]"), model, err };
        let (name, options) = name_and_options(raw_entry, &entry)?;
        let Some(analysis) = TABLE.iter().find(|a| a.kind.name() == name) else {
            return Err(err(
                &entry.field,
                format!("unknown analysis \"{name}\"; use one of {}", forms()),
            ));
        };
        let options = options_for(analysis, options, &entry)?;
        (analysis.parse)(&mut out, options, &entry)?;
    }
    requirements(&out, err)?;
    Ok(out)
}

/// The entry's analysis name and its options, if any.
fn name_and_options<'r>(
    raw: &'r RawAnalysis,
    entry: &Entry,
) -> Result<(&'r str, Option<Value>), SceneError> {
    match raw {
        RawAnalysis::Name(n) => Ok((n, None)),
        RawAnalysis::WithOptions(map) if map.len() == 1 => {
            let (n, v) = map.iter().next().expect("one entry");
            Ok((n, Some(v.clone())))
        }
        RawAnalysis::WithOptions(_) => Err((entry.err)(
            &entry.field,
            format!("an object entry must have exactly one key; use one of {}", forms()),
        )),
    }
}

/// The options `analysis` is parsed from, as its [`Takes`] allows them.
fn options_for(
    analysis: &Analysis,
    options: Option<Value>,
    entry: &Entry,
) -> Result<Value, SceneError> {
    let name = analysis.kind.name();
    match (&analysis.takes, options) {
        (Takes::Nothing, None) => Ok(Value::Null),
        (Takes::Nothing, Some(_)) => {
            Err((entry.err)(&entry.field, format!("\"{name}\" takes no options")))
        }
        (Takes::Optional, None) => Ok(Value::Object(Default::default())),
        (Takes::Optional, Some(v)) if v.is_object() => Ok(v),
        (Takes::Optional, Some(_)) => Err(entry.error(name, "options must be an object".into())),
        (Takes::Required { missing, .. }, None) => {
            Err((entry.err)(&entry.field, (*missing).into()))
        }
        (Takes::Required { .. }, Some(v)) => Ok(v),
    }
}

/// The analyses that work on another's results need it.
fn requirements(
    out: &Analyses,
    err: &impl Fn(&str, String) -> SceneError,
) -> Result<(), SceneError> {
    if out.trajectory_cycles.is_some() && out.cycle.is_none() {
        return Err(err(
            "analyses",
            "\"trajectory\" records the cycles found by \"cycle\"; add \"cycle\"".into(),
        ));
    }
    for (asked, name) in [
        (out.asymptotics.is_some(), AnalysisKind::Asymptotics),
        (out.lyapunov.is_some(), AnalysisKind::Lyapunov),
    ] {
        if asked && out.cycle.is_none() {
            return Err(err(
                "analyses",
                format!("\"{name}\" works on the limit cycle found by \"cycle\"; add \"cycle\""),
            ));
        }
    }
    if out.paper && (out.cycle.is_none() || !out.hopf) {
        return Err(err(
            "analyses",
            "\"paper\" compares hopf and cycle results; add \"hopf\" and \"cycle\"".into(),
        ));
    }
    Ok(())
}

fn hopf(out: &mut Analyses, _: Value, _: &Entry) -> Result<(), SceneError> {
    out.hopf = true;
    Ok(())
}

fn paper(out: &mut Analyses, _: Value, _: &Entry) -> Result<(), SceneError> {
    out.paper = true;
    Ok(())
}

fn cycle(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    out.cycle =
        Some(CycleOptions::from_json(v).map_err(|e| entry.invalid(AnalysisKind::Cycle.name(), e))?);
    Ok(())
}

fn asymptotics(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    let o = AsymptoticsOptions::from_json(v)
        .map_err(|e| entry.invalid(AnalysisKind::Asymptotics.name(), e))?;
    out.asymptotics = Some(o);
    Ok(())
}

fn lyapunov(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    out.lyapunov = Some(
        LyapunovOptions::from_json(v)
            .map_err(|e| entry.invalid(AnalysisKind::Lyapunov.name(), e))?,
    );
    Ok(())
}

fn shooting(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    out.shooting = Some(ShootingOptions::from_json(v).map_err(|e| entry.invalid("shooting", e))?);
    Ok(())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTrajectory {
    cycles: usize,
}

fn trajectory(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    let t: RawTrajectory =
        serde_json::from_value(v).map_err(|e| entry.error("trajectory", e.to_string()))?;
    if t.cycles == 0 || t.cycles > 10_000 {
        return Err(
            entry.error("trajectory.cycles", format!("{} must be between 1 and 10000", t.cycles))
        );
    }
    out.trajectory_cycles = Some(t.cycles);
    Ok(())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContinuation {
    parameter: String,
    to: f64,
    points: usize,
    #[serde(default)]
    log: Option<bool>,
}

fn continuation(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    let c: RawContinuation =
        serde_json::from_value(v).map_err(|e| entry.error("continuation", e.to_string()))?;
    let parameter = Parameter::from_name(&c.parameter).ok_or_else(|| {
        let names = Parameter::quoted_names(Parameter::ALL);
        entry.error(
            "continuation.parameter",
            format!("\"{}\" cannot be continued; use one of {names}", c.parameter),
        )
    })?;
    let to = continuation_end(parameter, c.to, entry)?;
    if !(2..=100_000).contains(&c.points) {
        return Err(entry
            .error("continuation.points", format!("{} must be between 2 and 100000", c.points)));
    }
    let log = c.log.unwrap_or(parameter == Parameter::Gamma);
    let linear_only = match parameter {
        Parameter::Epsilon => Some("ε can be negative"),
        Parameter::Eta => Some("η can be 0"),
        Parameter::Xi | Parameter::Gamma => None,
    };
    if let (true, Some(why)) = (log, linear_only) {
        return Err(entry.error(
            "continuation.log",
            format!("{why}: continue it on a linear grid (\"log\": false)"),
        ));
    }
    out.continuation = Some(ContinuationOptions { parameter, to, points: c.points, log });
    Ok(())
}

/// The continuation's final value `to` of `parameter`, checked against its domain.
fn continuation_end(parameter: Parameter, to: f64, entry: &Entry) -> Result<f64, SceneError> {
    let field = format!("{}.continuation.to", entry.field);
    let to = finite(&field, to, &entry.err)?;
    let bad = |message: String| Err((entry.err)(&field, message));
    if parameter == Parameter::Eta && to < 0.0 {
        return bad(format!("{to} must be ≥ 0 for radiation_damping"));
    }
    if !matches!(parameter, Parameter::Epsilon | Parameter::Eta) && to <= 0.0 {
        return bad(format!("{to} must be > 0 for {}", parameter.name()));
    }
    if parameter == Parameter::Gamma && !(1e-100..=1e100).contains(&to) {
        return bad(format!("{to:e} is outside 1e-100 … 1e100"));
    }
    Ok(to)
}

fn noise(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    let o: NoiseOptions = serde_path_to_error::deserialize(v).map_err(|e| {
        let path = e.path().to_string();
        let sub = if path == "." { String::new() } else { format!(".{path}") };
        entry.error(&format!("noise{sub}"), e.into_inner().to_string())
    })?;
    let (kind, dim, gamma2) = entry.model;
    noise_options::validate(&o, dim, kind, gamma2)
        .map_err(|e| entry.invalid(AnalysisKind::Noise.name(), e))?;
    out.noise = Some(o);
    Ok(())
}

fn time_series(out: &mut Analyses, v: Value, entry: &Entry) -> Result<(), SceneError> {
    if !v.is_object() {
        return Err(entry.error(
            AnalysisKind::TimeSeries.name(),
            "options must be an object, e.g. {\"t_max\": 1000}".into(),
        ));
    }
    let o = TimeSeriesOptions::from_json(v)
        .map_err(|e| entry.invalid(AnalysisKind::TimeSeries.name(), e))?;
    out.time_series = Some(o);
    Ok(())
}
