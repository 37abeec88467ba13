//! `stickslip run`: a scene (DRR, other models, lab, or a QDYN input file) to its report,
//! series files, QDYN output files and figure.

use super::progress::Progress;
use super::qdyn;
use super::{deliver_report, failed, read_scene_text, worker_threads, Failure};
use std::path::{Path, PathBuf};
use stickslip::analysis::time_series::{SeriesSink, TeeSink};
use stickslip::{engine, report, scene};

/// `stickslip run`'s arguments.
#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene file (JSON, see docs/scenes.md).
    pub scene: Option<PathBuf>,
    /// Print the JSON report to stdout instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON report to FILE (atomically).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Worker threads for ensembles (the "noise" analysis; default: all cores). Results do
    /// not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the "time_series" analysis's rows to FILE as they are computed: CSV if FILE
    /// ends in .csv, otherwise a structured NumPy .npy array (np.load reads it). Repeat it
    /// for several files from one run (e.g. --series a.csv --series a.npy).
    #[arg(long, value_name = "FILE")]
    pub series: Vec<PathBuf>,
    /// Lab scenes: draw friction against load-point displacement to FILE (SVG).
    #[arg(long, value_name = "FILE.svg")]
    pub figure: Option<PathBuf>,
    /// Print the scene (JSON) instead of running it: a QDYN input file's mapped scene.
    #[arg(long)]
    pub print_scene: bool,
    /// Write QDYN's output files (output_ot_0, output_vmax, output_ox) of the
    /// "time_series" analysis in DIR (created if needed), in QDYN's format and SI units.
    #[arg(long, value_name = "DIR")]
    pub qdyn_output: Option<PathBuf>,
}

/// The built-in scene of `stickslip run` without a file.
const EARTHQUAKE: &str = include_str!("../../data/scenes/earthquake.json");

/// Runs `stickslip run`.
pub fn run_command(args: RunArgs) -> Result<(), Failure> {
    let RunArgs { scene: path, json, out, threads, series, figure, print_scene, qdyn_output } =
        args;
    let (text, source) = match &path {
        Some(p) => (read_scene_text(p)?, p.display().to_string()),
        None => (EARTHQUAKE.to_string(), "<built-in earthquake>".to_string()),
    };
    let (text, intervals) = qdyn::read(path.as_deref(), text).map_err(|e| Failure(2, e))?;
    if print_scene {
        println!("{text}");
        return Ok(());
    }
    let scene = scene::parse_any(&text, &source).map_err(|e| Failure(2, e.to_string()))?;
    let echo: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Failure(2, e.to_string()))?;
    let qdyn = match &scene {
        scene::AnyScene::Lab(_) if qdyn_output.is_some() => {
            return Err(Failure(2, "--qdyn-output: a lab scene has no QDYN output (QDYN's files hold a fault's slip history); use --series".into()));
        }
        scene::AnyScene::Lab(_) => None,
        _ if figure.is_some() => {
            return Err(Failure(2, "--figure: only lab scenes (\"model\": {\"kind\": \"lab\"}) draw a figure here; `stickslip reproduce` draws the paper's".into()));
        }
        scene::AnyScene::Drr(scene) => {
            for warning in &scene.warnings {
                eprintln!("stickslip: warning: {warning}");
            }
            if scene.analyses.time_series.is_none() {
                refuse_series_files(&scene.name, &series, qdyn_output.is_some())?;
            }
            let qdyn = qdyn_output.as_deref().map(|d| qdyn::sink(scene, d, intervals)).transpose();
            qdyn.map_err(|e| Failure(2, e))?
        }
        scene::AnyScene::Other(_) if !series.is_empty() || qdyn_output.is_some() => {
            return Err(Failure(
                2,
                "--series: this scene has no \"time_series\" analysis (only DRR scenes have one); \
                 add {\"time_series\": {\"t_max\": T}} to its analyses"
                    .into(),
            ));
        }
        scene::AnyScene::Other(_) => None,
    };
    let ensembles = match &scene {
        scene::AnyScene::Drr(s) => s.analyses.noise.is_some(),
        scene::AnyScene::Other(_) => true,
        scene::AnyScene::Lab(_) => false,
    };
    let progress = Progress::new("noise", "realisations");
    let update = |d, t| progress.update(d, t);
    let threads = worker_threads(threads);
    let report = with_series_files(&series, qdyn, |sink| {
        let options =
            engine::RunOptions::echoing(echo).threads(threads).progress(&update).series(sink);
        engine::run(&scene, options).map_err(|e| failed(scene.name(), e))
    })?;
    if ensembles {
        progress.finish();
    }
    if let (report::AnyReport::Lab(report), Some(file)) = (&report, &figure) {
        crate::figure::lab::friction_against_displacement(report)
            .write(file)
            .map_err(|e| Failure(1, format!("--figure: {e}")))?;
    }
    deliver_report(&report.to_json(), &report.summary(), json, out.as_deref())?;
    let not_converged = match (&scene, &report) {
        (scene::AnyScene::Drr(s), report::AnyReport::Drr(r)) => {
            r.cycle.as_ref().and_then(|c| unconverged(s, c))
        }
        _ => None,
    };
    match not_converged {
        Some(message) => Err(Failure(4, message)),
        None => Ok(()),
    }
}

/// Refuses `--series` files and `--qdyn-output` for a scene without a "time_series" analysis
/// (exit 2, naming them and the analysis to add).
fn refuse_series_files(name: &str, files: &[PathBuf], qdyn: bool) -> Result<(), Failure> {
    let mut named: Vec<String> =
        files.iter().map(|f| format!("--series {}", f.display())).collect();
    if qdyn {
        named.push("--qdyn-output".into());
    }
    if named.is_empty() {
        return Ok(());
    }
    let named = named.join(", ");
    Err(Failure(
        2,
        format!(
            "{named}: scene {name} has no \"time_series\" analysis; add {{\"time_series\": {{\"t_max\": T}}}} to its analyses"
        ),
    ))
}

/// The exit-4 message of a cycle analysis that stopped at a limit before converging: which
/// limit, and what to raise; or, for a start on the fixed point, that nothing happens.
fn unconverged(
    scene: &scene::Scene,
    c: &stickslip::analysis::cycle::CycleReport,
) -> Option<String> {
    if c.status != stickslip::analysis::cycle::CycleStatus::NotConverged {
        return None;
    }
    let name = &scene.name;
    if scene.loading.is_none() && stickslip::model::Drr::new(scene.params).at_rest(&scene.initial) {
        return Some(format!(
            "scene {name}: cycle: the run starts on the fixed point (v = 1, θ = {:e}: steady \
             sliding at the loading rate), where the state never changes, so no cycle forms; \
             perturb the start, e.g. \"initial\": {{\"v\": 0.5}} (with model.dimensional: \
             \"velocity\", half of v0) (exit code 4)",
            scene.initial[2]
        ));
    }
    let limit = c.stopped_by.unwrap_or("max_cycles");
    Some(format!(
        "scene {name}: cycle: NOT converged after {} cycles / t = {:e}: stopped by the limit \
         {limit}; raise it (e.g. {{\"cycle\": {{\"{limit}\": ...}}}}), or loosen \
         cycle.tolerance if the last cycles (cycle.last_cycles in the report) only scatter \
         (exit code 4)",
        c.cycles_computed, c.time_integrated
    ))
}

/// Where `--series FILE` streams its rows: a temporary file beside FILE (`.NAME.tmp-PID`, as
/// [`report::write_atomic`] names it), renamed to FILE when the run succeeds, so that a run
/// killed part way (Ctrl-C) leaves FILE as it was, never half-written; FILE itself when it
/// exists and is not a regular file (`/dev/stdout`, a FIFO). A symbolic link is followed.
fn series_staging(file: &Path) -> (PathBuf, PathBuf) {
    let file = match std::fs::canonicalize(file) {
        Ok(target) if file.is_symlink() => target,
        _ => file.to_path_buf(),
    };
    let special = std::fs::metadata(&file).is_ok_and(|m| !m.is_file() && !m.is_dir());
    let staging = match file.file_name() {
        Some(name) if !special => {
            file.with_file_name(format!(".{}.tmp-{}", name.to_string_lossy(), std::process::id()))
        }
        _ => file.clone(),
    };
    (staging, file)
}

/// Runs `run` with one sink that writes every row to each of `files` (CSV or .npy by its
/// suffix; none: rows are discarded) through temporary files ([`series_staging`]): renamed to
/// the files when `run` succeeds, removed when it fails; and to `extra` (QDYN's files).
fn with_series_files<R>(
    files: &[PathBuf],
    extra: Option<Box<dyn SeriesSink>>,
    run: impl FnOnce(&mut dyn SeriesSink) -> Result<R, Failure>,
) -> Result<R, Failure> {
    let staged: Vec<(PathBuf, PathBuf)> = files.iter().map(|f| series_staging(f)).collect();
    let remove_staging = |staged: &[(PathBuf, PathBuf)]| {
        for (staging, target) in staged {
            if staging != target {
                drop(std::fs::remove_file(staging));
            }
        }
    };
    let mut sinks = Vec::new();
    for ((staging, _), file) in staged.iter().zip(files) {
        match stickslip::series_file::create_as(staging, file) {
            Ok(sink) => sinks.push(sink),
            Err(e) => {
                drop(sinks);
                remove_staging(&staged);
                return Err(Failure(
                    2,
                    format!("--series {}: cannot create the file: {e}", file.display()),
                ));
            }
        }
    }
    sinks.extend(extra);
    let mut tee = TeeSink(sinks);
    let result = run(&mut tee);
    drop(tee);
    if result.is_err() {
        remove_staging(&staged);
    }
    let result = result?;
    for (i, (staging, target)) in staged.iter().enumerate() {
        if staging != target {
            if let Err(e) = std::fs::rename(staging, target) {
                remove_staging(&staged[i..]);
                return Err(Failure(
                    1,
                    format!("--series {}: cannot write it: {e}", files[i].display()),
                ));
            }
        }
    }
    Ok(result)
}
