//! The `stickslip` command line. Subcommands are thin: parse, call the library, print.
//! Exit codes: 0 success, 1 failed computation, 2 bad input, 3 `compare`: disagrees, 4 `run`:
//! the cycle analysis did not converge within its limits (the report is still written).

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use stickslip::sundials;
use stickslip::{scene, sweep};
use stickslip_cli::stress;

use stickslip_cli::cli::{self, Failure};

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

#[derive(Subcommand)]
enum Command {
    /// Run a scene (default: the built-in earthquake scene, γ = 1e8) and print a summary.
    Run(cli::run::RunArgs),
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Run(args) => cli::run::run_command(args),
        Command::Fit(args) => cli::fit::command(args),
        Command::Robertson => cli::robertson::robertson_command(),
        Command::Stress { quick, grid, json, threads, table, known, methods } => {
            let grid = if quick { stress::Grid::Quick } else { grid.unwrap_or(stress::Grid::Full) };
            cli::stress::stress_command(grid, &methods, json, threads, table, known)
        }
        Command::Sweep { scene, params, out, resume, shard, threads } => {
            cli::sweep::sweep_command(scene, params, out, resume, shard, threads)
        }
        Command::Merge { out, total, inputs } => cli::sweep::merge_command(out, total, inputs),
        Command::Compare { scene, methods, against, tolerance, reference_method, json } => {
            cli::compare::compare_command(
                scene,
                methods,
                against,
                tolerance,
                reference_method,
                json,
            )
        }
        Command::Reproduce { out, threads, reduced } => {
            cli::reproduce::reproduce_command(out, threads, reduced)
        }
        Command::NoiseCurves { out, reports } => cli::reproduce::noise_curves_command(out, reports),
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
