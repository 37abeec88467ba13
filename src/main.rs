//! The `stickslip` command line. Subcommands are thin: parse, call the library, print.
//! Exit codes: 0 success, 1 failed computation, 2 bad input, 3 `compare`: disagrees, 4 `run`:
//! the cycle analysis did not converge within its limits (the report is still written).

use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use stickslip::analysis::claims::Verdict;
use stickslip::analysis::noise::report as noise_report;
use stickslip::analysis::time_series::{SeriesSink, TeeSink};
use stickslip::sundials;
use stickslip::{compare, engine, report, scene, sweep};
use stickslip_cli::robertson_examples::{self as robertson, ExampleRun};
use stickslip_cli::stress;

use stickslip_cli::cli::progress::Progress;
use stickslip_cli::cli::{self, qdyn, Failure};

#[derive(Parser)]
#[command(
    name = "stickslip",
    version,
    about = "Very stiff stick-slip dynamics with Debian's SUNDIALS"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// `stickslip run`'s arguments.
#[derive(clap::Args)]
struct RunArgs {
    /// Scene file (JSON, see docs/scenes.md).
    scene: Option<PathBuf>,
    /// Print the JSON report to stdout instead of the summary.
    #[arg(long)]
    json: bool,
    /// Write the JSON report to FILE (atomically).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Worker threads for ensembles (the "noise" analysis; default: all cores). Results do
    /// not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Write the "time_series" analysis's rows to FILE as they are computed: CSV if FILE
    /// ends in .csv, otherwise a structured NumPy .npy array (np.load reads it). Repeat it
    /// for several files from one run (e.g. --series a.csv --series a.npy).
    #[arg(long, value_name = "FILE")]
    series: Vec<PathBuf>,
    /// Lab scenes: draw friction against load-point displacement to FILE (SVG).
    #[arg(long, value_name = "FILE.svg")]
    figure: Option<PathBuf>,
    /// Print the scene (JSON) instead of running it: a QDYN input file's mapped scene.
    #[arg(long)]
    print_scene: bool,
    /// Write QDYN's output files (output_ot_0, output_vmax, output_ox) of the
    /// "time_series" analysis in DIR (created if needed), in QDYN's format and SI units.
    #[arg(long, value_name = "DIR")]
    qdyn_output: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (default: the built-in earthquake scene, γ = 1e8) and print a summary.
    Run(RunArgs),
    /// Replay SUNDIALS' Robertson examples (cvRoberts_dns, ark_robertson_root) through the
    /// safe wrappers and print them as the C programs do, with solver statistics.
    Robertson,
    /// Cross-check: run a scene with several methods and compare the cycle, or compare a
    /// user's trajectory (CSV t,u,v,theta or JSON; per cycle) or report against a reference
    /// (exit 0 agrees, 3 disagrees).
    Compare {
        /// Scene file (its model and initial state; its tolerances for --methods).
        scene: PathBuf,
        /// Comma-separated methods, e.g. cvode-bdf,arkode-dirk,radau5.
        #[arg(long, value_delimiter = ',', conflicts_with = "against")]
        methods: Vec<scene::Method>,
        /// A user's trajectory or report to check against the reference.
        #[arg(long, value_name = "FILE")]
        against: Option<PathBuf>,
        /// Tolerance for --against (relative for durations, u, θ and report values; absolute in
        /// ln v). Exit 0 if the file agrees within it, 3 if it disagrees: see docs/compare.md.
        #[arg(long, default_value_t = 1e-4)]
        tolerance: f64,
        /// The reference's method for a report given to --against (default: the scene's),
        /// e.g. radau5; it runs at min(the scene's rtol, tolerance/100).
        #[arg(long, value_name = "METHOD", requires = "against")]
        reference_method: Option<scene::Method>,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Sweep scene parameters: one JSON line per point (parallel, resumable, shardable).
    Sweep {
        /// Scene file (model given as gamma/xi/epsilon).
        scene: PathBuf,
        /// NAME=START:STOP:COUNT[:log] for gamma, xi, epsilon, radiation_damping or alpha; repeat for a grid.
        #[arg(long = "param", required = true, value_name = "NAME=START:STOP:COUNT[:log]")]
        params: Vec<sweep::Axis>,
        /// Output file (JSON Lines).
        #[arg(long)]
        out: PathBuf,
        /// Continue a killed sweep: keep the rows in --out and run only the missing points.
        #[arg(long)]
        resume: bool,
        /// K/N: run only the points with index % N == K − 1 (for cluster job arrays).
        #[arg(long, value_name = "K/N")]
        shard: Option<sweep::Shard>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Merge sweep outputs (e.g. shards) into one file sorted by point index.
    Merge {
        /// Output file.
        #[arg(long)]
        out: PathBuf,
        /// Expected number of points: missing indices are listed (exit 1).
        #[arg(long)]
        total: Option<usize>,
        /// Input files.
        inputs: Vec<PathBuf>,
    },
    /// Run the numerical stress grid (γ, ξ, ε, tolerances, far-off starts, every method).
    /// Exit 1 if any cell panics, reports a non-finite number or methods disagree.
    Stress {
        /// The small grid (runs in CI); same as `--grid quick`.
        #[arg(long, conflicts_with = "grid")]
        quick: bool,
        /// Which grid: quick, full (the default) or physical (every stiff method over the
        /// unstable regime, γ = 10 … 1e12, ε/ξ up to 25).
        #[arg(long, value_enum)]
        grid: Option<stress::Grid>,
        /// Print the counts and defects as JSON.
        #[arg(long)]
        json: bool,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Also write the full table of outcomes (per γ and method, per start) as Markdown.
        #[arg(long, value_name = "FILE.md")]
        table: Option<PathBuf>,
        /// Known failures (one cell key a line, as printed): the run fails on any other
        /// failure, and on a known one that no longer fails (update the file). Without it, any
        /// failure fails the run.
        #[arg(long, value_name = "FILE")]
        known: Option<PathBuf>,
        /// Only these methods' cells (comma-separated, e.g. arkode-dirk,radau5); default: all.
        #[arg(long, value_delimiter = ',')]
        methods: Vec<scene::Method>,
    },
    /// Remake the paper's figures (SVG), their JSON reports and a summary of its claims
    /// against ours (summary.md, summary.html) in DIR.
    Reproduce {
        /// Output directory (created if needed).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Fewer points per curve (a quick check; the tests use it).
        #[arg(long)]
        reduced: bool,
    },
    /// Collect the correlation-time curves of noise reports (e.g. DRR, saddle-node, van der
    /// Pol) into one JSON document for one figure.
    NoiseCurves {
        /// Output file (JSON).
        #[arg(long)]
        out: PathBuf,
        /// Reports written by `stickslip run SCENE --out REPORT`.
        reports: Vec<PathBuf>,
    },
    /// Fit a lab scene's model to a friction record (a, b_i, D_c,i, k, μ0 and a trend), by
    /// Levenberg–Marquardt with CVODES' sensitivities (docs/lab.md).
    Fit(cli::fit::FitArgs),
    /// Print the SUNDIALS version linked at run time.
    Version,
}

fn print_stats(run: &ExampleRun) {
    let s = &run.stats;
    println!(
        "  steps {} (attempted {}), RHS evals {} (+{} explicit, +{} for FD Jacobians), Jacobian evals {},\n  \
         linear setups {}, error-test fails {}, Newton iterations {} (convergence fails {}), root evals {},\n  \
         last step {:e}, last order {}, t + h = t warnings {}",
        s.steps,
        s.step_attempts,
        s.rhs_evals,
        s.rhs_evals_explicit,
        s.rhs_evals_jacobian,
        s.jac_evals,
        s.lin_setups,
        s.err_test_fails,
        s.nonlin_iters,
        s.nonlin_conv_fails,
        s.root_evals,
        s.last_step,
        s.last_order,
        s.step_underflow_warnings
    );
}

fn robertson_command() -> Result<(), Failure> {
    println!("SUNDIALS {} (linked at run time)\n", sundials::version());
    let cvode = robertson::cvode_example().map_err(|e| Failure(1, e.to_string()))?;
    println!(
        "cvRoberts_dns through stickslip's CVODE wrapper (BDF, rtol 1e-4, analytic Jacobian):"
    );
    for line in robertson::format_cvode_rows(&cvode.rows) {
        println!("{line}");
    }
    print_stats(&cvode);
    let arkode = robertson::arkode_example().map_err(|e| Failure(1, e.to_string()))?;
    println!(
        "\nark_robertson_root through stickslip's ARKStep wrapper (DIRK SDIRK_5_3_4, rtol 1e-4):"
    );
    for line in robertson::format_arkode_rows(&arkode.rows) {
        println!("{line}");
    }
    print_stats(&arkode);
    Ok(())
}

/// A failed run of the scene `name`: exit code 2 when an option does not fit the computed
/// orbit (bad input, the field named), 1 otherwise.
fn failed(name: &str, error: engine::EngineError) -> Failure {
    Failure(if error.is_bad_input() { 2 } else { 1 }, format!("scene {name}: {error}"))
}

const EARTHQUAKE: &str = include_str!("../data/scenes/earthquake.json");

fn run_command(args: RunArgs) -> Result<(), Failure> {
    let RunArgs { scene: path, json, out, threads, series, figure, print_scene, qdyn_output } =
        args;
    let (text, source) = match &path {
        Some(p) => (read_scene_text(p)?, p.display().to_string()),
        None => (EARTHQUAKE.to_string(), "<built-in earthquake>".to_string()),
    };
    let text = qdyn::scene_text(path.as_deref(), text).map_err(|e| Failure(2, e))?;
    if print_scene {
        println!("{text}");
        return Ok(());
    }
    let scene = scene::parse_any(&text, &source).map_err(|e| Failure(2, e.to_string()))?;
    let echo: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Failure(2, e.to_string()))?;
    let progress = Progress::new("noise", "realisations");
    let update = |d, t| progress.update(d, t);
    let threads = worker_threads(threads);
    let mut not_converged = None;
    let (report_json, summary, ensembles) = match &scene {
        scene::AnyScene::Lab(_) if qdyn_output.is_some() => {
            return Err(Failure(2, "--qdyn-output: a lab scene has no QDYN output (QDYN's files hold a fault's slip history); use --series".into()));
        }
        scene::AnyScene::Lab(scene) => return run_lab(scene, echo, json, out, &series, figure),
        _ if figure.is_some() => {
            return Err(Failure(2, "--figure: only lab scenes (\"model\": {\"kind\": \"lab\"}) draw a figure here; `stickslip reproduce` draws the paper's".into()));
        }
        scene::AnyScene::Drr(scene) => {
            for warning in &scene.warnings {
                eprintln!("stickslip: warning: {warning}");
            }
            let report = if series.is_empty() && qdyn_output.is_none() {
                engine::run_with(scene, echo, threads, &update)
                    .map_err(|e| failed(&scene.name, e))?
            } else {
                let qdyn = qdyn_output.as_deref().map(|d| qdyn::sink(scene, d)).transpose();
                let qdyn = qdyn.map_err(|e| Failure(2, e))?;
                run_writing_series(scene, echo, threads, &update, &series, qdyn)?
            };
            not_converged = report.cycle.as_ref().and_then(|c| unconverged(&scene.name, c));
            (report.to_json(), report.summary(), scene.analyses.noise.is_some())
        }
        scene::AnyScene::Other(_) if !series.is_empty() || qdyn_output.is_some() => {
            return Err(Failure(
                2,
                "--series: this scene has no \"time_series\" analysis (only DRR scenes have one); \
                 add {\"time_series\": {\"t_max\": T}} to its analyses"
                    .into(),
            ));
        }
        scene::AnyScene::Other(scene) => {
            let report = engine::run_other(scene, echo, threads, &update)
                .map_err(|e| failed(&scene.name, e))?;
            (report.to_json(), report.summary(), true)
        }
    };
    if ensembles {
        progress.finish();
    }
    if let Some(file) = &out {
        report::write_atomic(file, &report_json)
            .map_err(|e| Failure(1, format!("cannot write {}: {e}", file.display())))?;
    }
    if json {
        println!("{report_json}");
    } else {
        print!("{summary}");
        if let Some(file) = &out {
            println!("report written to {}", file.display());
        }
    }
    match not_converged {
        Some(message) => Err(Failure(4, message)),
        None => Ok(()),
    }
}

/// Runs a lab scene: report, optional series files (through staging files, as for DRR
/// scenes) and optional figure.
fn run_lab(
    scene: &scene::lab::LabScene,
    echo: serde_json::Value,
    json: bool,
    out: Option<PathBuf>,
    series: &[PathBuf],
    figure: Option<PathBuf>,
) -> Result<(), Failure> {
    let report = with_series_files(series, None, |sink| {
        engine::lab::run(scene, echo, sink)
            .map_err(|e| Failure(1, format!("scene {}: {e}", scene.name)))
    })?;
    if let Some(file) = &figure {
        stickslip_cli::figure::lab::friction_against_displacement(&report)
            .write(file)
            .map_err(|e| Failure(1, format!("--figure: {e}")))?;
    }
    let report_json = report.to_json();
    if let Some(file) = &out {
        report::write_atomic(file, &report_json)
            .map_err(|e| Failure(1, format!("cannot write {}: {e}", file.display())))?;
    }
    if json {
        println!("{report_json}");
    } else {
        print!("{}", report.summary());
    }
    Ok(())
}

/// The exit-4 message of a cycle analysis that stopped at a limit before converging: which
/// limit, and what to raise.
fn unconverged(name: &str, c: &stickslip::analysis::cycle::CycleReport) -> Option<String> {
    if c.status != stickslip::analysis::cycle::CycleStatus::NotConverged {
        return None;
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

/// Runs a DRR scene streaming its "time_series" rows to each of `files` (CSV or .npy by its
/// suffix) through [`with_series_files`].
fn run_writing_series(
    scene: &scene::Scene,
    echo: serde_json::Value,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    files: &[PathBuf],
    qdyn: Option<Box<dyn SeriesSink>>,
) -> Result<report::Report, Failure> {
    if scene.analyses.time_series.is_none() {
        let mut named: Vec<String> =
            files.iter().map(|f| format!("--series {}", f.display())).collect();
        if qdyn.is_some() {
            named.push("--qdyn-output".into());
        }
        let named = named.join(", ");
        return Err(Failure(
            2,
            format!(
                "{named}: scene {} has no \"time_series\" analysis; add {{\"time_series\": {{\"t_max\": T}}}} to its analyses",
                scene.name
            ),
        ));
    }
    with_series_files(files, qdyn, |sink| {
        engine::run_with_series(scene, echo, threads, progress, sink)
            .map_err(|e| failed(&scene.name, e))
    })
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

/// Largest scene file accepted: scenes are a few hundred bytes; a huge file is a mistake, and
/// reading it whole would only exhaust memory.
const MAX_SCENE_BYTES: u64 = 16 << 20;

fn read_scene_text(path: &std::path::Path) -> Result<String, Failure> {
    let cannot =
        |e: std::io::Error| Failure(2, format!("cannot read scene {}: {e}", path.display()));
    let size = std::fs::metadata(path).map_err(cannot)?.len();
    if size > MAX_SCENE_BYTES {
        return Err(Failure(2, format!("scene {}: the file has {size} bytes; a scene is at most {MAX_SCENE_BYTES} bytes (is this the right file?)", path.display())));
    }
    std::fs::read_to_string(path).map_err(cannot)
}

fn read_scene(path: &std::path::Path) -> Result<scene::Scene, Failure> {
    let text = read_scene_text(path)?;
    scene::parse(&text, &path.display().to_string()).map_err(|e| Failure(2, e.to_string()))
}

fn print_json(value: &impl serde::Serialize) {
    println!("{}", serde_json::to_string_pretty(value).expect("serialisable"));
}

fn compare_command(
    path: PathBuf,
    methods: Vec<scene::Method>,
    against: Option<PathBuf>,
    tolerance: f64,
    reference_method: Option<scene::Method>,
    json: bool,
) -> Result<(), Failure> {
    let scene = read_scene(&path)?;
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Failure(2, format!("--tolerance {tolerance} must be a finite number > 0")));
    }
    match against {
        Some(file) => compare_against(&scene, &file, tolerance, reference_method, json),
        None => compare_methods(&scene, &methods, json),
    }
}

/// `compare --against FILE`: a user's trajectory or report against our reference (exit 3 if
/// it disagrees).
fn compare_against(
    scene: &scene::Scene,
    file: &std::path::Path,
    tolerance: f64,
    reference_method: Option<scene::Method>,
    json: bool,
) -> Result<(), Failure> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| Failure(2, format!("cannot read {}: {e}", file.display())))?;
    let data = compare::read_user_data(&text)
        .map_err(|e| Failure(2, format!("{}: {e}", file.display())))?;
    let verdict = match data {
        compare::UserData::Trajectory(t) => {
            if reference_method.is_some() {
                return Err(Failure(
                    2,
                    "--reference-method applies to a report; a trajectory's reference is \
                     radau5 checked by rodas5p (docs/compare.md)"
                        .into(),
                ));
            }
            let c = compare::against_trajectory(scene, &t, tolerance).map_err(|e| match e {
                e @ (compare::CompareError::Input(_)
                | compare::CompareError::UnresolvedReference(_)) => {
                    Failure(2, format!("{}: {e}", file.display()))
                }
                other => Failure(1, other.to_string()),
            })?;
            if json {
                print_json(&c);
            } else {
                print_trajectory_comparison(&c);
            }
            c.verdict
        }
        compare::UserData::Report(r) => {
            let c = compare::against_report(scene, &r, tolerance, reference_method)
                .map_err(|e| Failure(1, e.to_string()))?;
            if json {
                print_json(&c);
            } else {
                let r = &c.reference;
                println!(
                    "reference: {} at rtol {:.0e}, checked by {} at rtol {:.0e}",
                    r.method, r.rtol, r.check_method, r.check_rtol
                );
                for row in &c.rows {
                    let flag = if row.beyond_tolerance { "  BEYOND TOLERANCE" } else { "" };
                    println!(
                        "{:<16} yours {:<22} ours {:<22} {:.1e} (ours ±{:.0e}){flag}",
                        row.quantity,
                        row.user,
                        row.reference,
                        row.deviation,
                        row.reference_accuracy
                    );
                }
            }
            c.verdict
        }
    };
    if !json {
        println!(
            "verdict: {} (tolerance {tolerance:.1e})",
            if verdict == compare::Verdict::Agrees { "agrees" } else { "disagrees" }
        );
    }
    match verdict {
        compare::Verdict::Agrees => Ok(()),
        compare::Verdict::Disagrees => Err(Failure(
            3,
            format!(
                "{} disagrees with the reference beyond the tolerance {tolerance:e}",
                file.display()
            ),
        )),
    }
}

/// The summary of a trajectory comparison.
fn print_trajectory_comparison(c: &compare::TrajectoryComparison) {
    println!(
        "{} samples; complete events: {} yours, {} the reference's, {} compared",
        c.samples, c.events[0], c.events[1], c.events[2]
    );
    let r = &c.reference;
    let accuracy: Vec<String> = r.accuracy.iter().map(|(q, a)| format!("{q} {a:.1e}")).collect();
    println!(
        "reference: radau5, rtol {:.0e}, re-based {} times; its own accuracy (against rodas5p at rtol {:.0e}): {}",
        r.rtol,
        r.rebases,
        r.check_rtol,
        accuracy.join(", ")
    );
    for q in &c.worst_per_quantity {
        println!(
            "{:<12} worst at event {:<4} yours {:<22} reference {:<22} {:.2e}",
            q.quantity, q.event, q.user, q.reference, q.deviation
        );
    }
    let m = &c.max_state_deviation;
    println!(
        "state between events ({} samples, in phase): max deviation u {:.2e}, ln v {:.2e}, θ {:.2e}",
        c.state_samples, m.u, m.ln_v, m.theta
    );
    if let Some(w) = &c.worst_state {
        println!(
            "worst: {} at t = {} ({}, {} from the peak of event {}): yours {}, reference {}",
            w.quantity, w.t, w.at, w.phase, w.event, w.user, w.reference
        );
    }
    for reason in &c.reasons {
        println!("DISAGREES: {reason}");
    }
}

/// `compare --methods a,b,…`: the scene's cycle by several methods.
fn compare_methods(
    scene: &scene::Scene,
    methods: &[scene::Method],
    json: bool,
) -> Result<(), Failure> {
    if methods.is_empty() {
        return Err(Failure(2, "give --methods a,b,... or --against FILE".into()));
    }
    let c = compare::methods(scene, methods);
    if json {
        print_json(&c);
    } else {
        for ((m, status), (_, time)) in c.runs.iter().zip(&c.wall_time_s) {
            println!("{m:<12} {status} ({})", time.map_or("-".into(), |t| format!("{:.3} s", t)));
        }
        for row in &c.rows {
            let values: Vec<String> = row
                .values
                .iter()
                .map(|(m, v)| format!("{m}={}", v.map_or("-".into(), |v| format!("{v:.12}"))))
                .collect();
            let flag = if row.outliers.is_empty() {
                String::new()
            } else {
                format!("  OUTLIERS: {}", row.outliers.join(", "))
            };
            println!(
                "{:<16} spread {:<9} (allowed {:.0e}) {}{flag}",
                row.quantity,
                row.spread.map_or("-".into(), |s| format!("{s:.1e}")),
                row.allowed,
                values.join("  ")
            );
        }
    }
    Ok(())
}

/// `--threads`, or every core.
fn worker_threads(threads: Option<usize>) -> usize {
    threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

fn sweep_command(
    path: PathBuf,
    axes: Vec<sweep::Axis>,
    out: PathBuf,
    resume: bool,
    shard: Option<sweep::Shard>,
    threads: Option<usize>,
) -> Result<(), Failure> {
    let text = read_scene_text(&path)?;
    scene::parse(&text, &path.display().to_string()).map_err(|e| Failure(2, e.to_string()))?;
    let base: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Failure(2, e.to_string()))?;
    sweep::check_base(&base, &axes).map_err(|e| Failure(2, format!("{}: {e}", path.display())))?;
    let progress = Progress::new("sweep", "points");
    let ran = sweep::run(&base, &axes, &out, resume, shard, worker_threads(threads), &|d, t| {
        progress.update(d, t)
    })
    .map_err(|e| Failure(1, format!("cannot write {}: {e}", out.display())))?;
    let seconds = progress.finish();
    println!("sweep: {ran} points run into {} in {seconds:.1} s", out.display());
    Ok(())
}

fn merge_command(out: PathBuf, total: Option<usize>, inputs: Vec<PathBuf>) -> Result<(), Failure> {
    let paths: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    let (rows, missing) =
        sweep::merge(&paths, total).map_err(|e| Failure(2, format!("cannot read inputs: {e}")))?;
    let text: String = rows.iter().map(|line| format!("{line}\n")).collect();
    report::write_atomic(&out, &text)
        .map_err(|e| Failure(1, format!("cannot write {}: {e}", out.display())))?;
    println!("merge: {} rows into {}", rows.len(), out.display());
    if missing.is_empty() {
        Ok(())
    } else {
        Err(Failure(
            1,
            format!("{} points missing: {:?}", missing.len(), &missing[..missing.len().min(20)]),
        ))
    }
}

fn stress_command(
    grid: stress::Grid,
    methods: &[scene::Method],
    json: bool,
    threads: Option<usize>,
    table: Option<PathBuf>,
    known: Option<PathBuf>,
) -> Result<(), Failure> {
    let known =
        match &known {
            Some(path) => Some(std::fs::read_to_string(path).map_err(|e| {
                Failure(2, format!("--known {}: cannot read it: {e}", path.display()))
            })?),
            None => None,
        };
    let mut cells = stress::grid(grid);
    if !methods.is_empty() {
        cells.retain(|cell| methods.contains(&cell.method));
    }
    let progress = Progress::new("stress", "cells");
    let (outcomes, summary) =
        stress::run(&cells, worker_threads(threads), &|d, t| progress.update(d, t));
    let seconds = progress.finish();
    if let Some(path) = table {
        let text = format!(
            "{} cells in {seconds:.0} s\n\n{}",
            cells.len(),
            stress::table(&cells, &outcomes, &summary)
        );
        report::write_atomic(&path, &text)
            .map_err(|e| Failure(1, format!("cannot write {}: {e}", path.display())))?;
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&summary).expect("serialisable"));
    } else {
        println!(
            "stress: {} cells in {seconds:.1} s: {} ok, typed errors {:?}, {} panics, {} nan, {} inconsistent",
            summary.cells, summary.ok, summary.typed_errors, summary.panics, summary.nan, summary.inconsistent
        );
        for (reason, (n, errors)) in &summary.limits {
            println!("  expected limit ({n} cells, {errors} typed errors): {reason}");
        }
        for f in &summary.failures {
            println!("  FAILURE {f}");
        }
        for d in &summary.defects {
            println!("  DEFECT {d}");
        }
        println!(
            "stress: physical region {} of {} cells converged, {} failed; below threshold {} failed; {} defects",
            summary.physical_ok,
            summary.physical,
            summary.physical_failures,
            summary.decay_failures,
            summary.defects.len()
        );
    }
    let mut problems = summary.defects.len();
    match &known {
        Some(text) => {
            let (new, fixed) = stress::against_known(&cells, &outcomes, text);
            // With --json, stdout holds only the JSON summary; the verdict goes to stderr.
            let say = |line: String| if json { eprintln!("{line}") } else { println!("{line}") };
            for k in &new {
                say(format!("  NEW FAILURE (not in the known-failures file) {k}"));
            }
            for k in &fixed {
                say(format!("  NOW PASSES (remove it from the known-failures file) {k}"));
            }
            say(format!(
                "stress: {} known failures, {} new failures, {} fixed",
                summary.failures.len() - new.len(),
                new.len(),
                fixed.len()
            ));
            problems += new.len() + fixed.len();
        }
        None => problems += summary.failures.len(),
    }
    if problems == 0 {
        Ok(())
    } else {
        Err(Failure(1, format!("{problems} problems in the stress grid (defects, failures not known, known failures fixed)")))
    }
}

fn reproduce_command(out: PathBuf, threads: Option<usize>, reduced: bool) -> Result<(), Failure> {
    let progress = Progress::new("reproduce", "runs");
    let summary = stickslip_cli::reproduce::run(&out, worker_threads(threads), reduced, &progress);
    progress.finish();
    let summary = summary.map_err(|e| Failure(1, e.to_string()))?;
    for f in &summary.figures {
        match &f.error {
            None => println!("{:<5} {:>5.1} s  {}", f.id, f.seconds, f.output.files.join(", ")),
            Some(e) => println!("{:<5} FAILED: {e}", f.id),
        }
    }
    let rows: Vec<_> = summary.rows().collect();
    let count = |v: Verdict| rows.iter().filter(|r| r.verdict == v).count();
    println!(
        "claims: {} agree, {} roughly, {} disagree, {} hold, {} do not hold; not yet reproduced: {}",
        count(Verdict::Agrees),
        count(Verdict::Roughly),
        count(Verdict::Disagrees),
        count(Verdict::Holds),
        count(Verdict::DoesNotHold),
        if summary.pending.is_empty() { "none".to_string() } else { summary.pending.iter().map(|p| p.figure).collect::<Vec<_>>().join(", ") }
    );
    println!(
        "summary: {} and summary.html ({:.1} s)",
        out.join("summary.md").display(),
        summary.wall_time_s
    );
    let failed = summary.failed();
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Failure(
            1,
            format!(
                "{} figure(s) failed: {}",
                failed.len(),
                failed.iter().map(|f| f.id.as_str()).collect::<Vec<_>>().join(", ")
            ),
        ))
    }
}

fn noise_curves_command(out: PathBuf, reports: Vec<PathBuf>) -> Result<(), Failure> {
    if reports.is_empty() {
        return Err(Failure(2, "give at least one report".into()));
    }
    let inputs = reports
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p)
                .map_err(|e| Failure(2, format!("cannot read {}: {e}", p.display())))?;
            let value = serde_json::from_str(&text)
                .map_err(|e| Failure(2, format!("{}: {e}", p.display())))?;
            Ok((p.display().to_string(), value))
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let curves = noise_report::combine(&inputs).map_err(|e| Failure(2, e))?;
    let text = serde_json::to_string_pretty(&serde_json::json!({ "curves": curves }))
        .expect("serialisable");
    report::write_atomic(&out, &text)
        .map_err(|e| Failure(1, format!("cannot write {}: {e}", out.display())))?;
    println!("noise-curves: {} curves into {}", curves.len(), out.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Run(args) => run_command(args),
        Command::Fit(args) => cli::fit::command(args),
        Command::Robertson => robertson_command(),
        Command::Stress { quick, grid, json, threads, table, known, methods } => {
            let grid = if quick { stress::Grid::Quick } else { grid.unwrap_or(stress::Grid::Full) };
            stress_command(grid, &methods, json, threads, table, known)
        }
        Command::Sweep { scene, params, out, resume, shard, threads } => {
            sweep_command(scene, params, out, resume, shard, threads)
        }
        Command::Merge { out, total, inputs } => merge_command(out, total, inputs),
        Command::Compare { scene, methods, against, tolerance, reference_method, json } => {
            compare_command(scene, methods, against, tolerance, reference_method, json)
        }
        Command::Reproduce { out, threads, reduced } => reproduce_command(out, threads, reduced),
        Command::NoiseCurves { out, reports } => noise_curves_command(out, reports),
        Command::Version => {
            println!(
                "stickslip {} with SUNDIALS {}",
                env!("CARGO_PKG_VERSION"),
                sundials::version()
            );
            Ok(())
        }
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure(code, message)) => {
            eprintln!("stickslip: {message}");
            ExitCode::from(code)
        }
    }
}
