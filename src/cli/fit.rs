//! `stickslip fit SCENE --data FILE --params a,b_1,d_c_1[,k,mu0,trend]`: the lab model fitted
//! to a friction record.

use super::Failure;
use std::path::PathBuf;
use stickslip::analysis::lab_fit::{FitError, FitLimits};
use stickslip::engine::lab::{self, FitLoading};
use stickslip::scene::{self, AnyScene};

/// `stickslip fit`'s arguments.
#[derive(clap::Args)]
pub struct FitArgs {
    /// A lab scene (`"model": {"kind": "lab"}`): the starting values, the tolerances and the
    /// load-point history, in the record's time origin.
    pub scene: PathBuf,
    /// The friction record: a header line of column names, then rows (tab, comma or blank
    /// separated).
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,
    /// The parameters to fit, comma-separated: a, b_1 … b_n, d_c_1 … d_c_n, k, mu0, trend.
    #[arg(long, value_name = "LIST")]
    pub params: String,
    /// The record's columns by header name, e.g. t=Time(s),x_lp=Displ(microns),mu=Friction
    /// (default names t, mu, x_lp).
    #[arg(long, value_name = "KEY=NAME,...", default_value = "")]
    pub columns: String,
    /// Where the load-point history comes from: the scene's "loading", or the record's x_lp
    /// column (the chords between samples).
    #[arg(long, value_enum, default_value_t = LoadingSource::Scene)]
    pub loading: LoadingSource,
    /// Print the JSON report instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON report to FILE (atomically).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Draw the record, the fit and the residuals to FILE (SVG).
    #[arg(long, value_name = "FILE.svg")]
    pub figure: Option<PathBuf>,
    /// Write t, μ measured, μ fitted and the residual (μ fitted − μ measured) to FILE (CSV).
    #[arg(long, value_name = "FILE.csv")]
    pub series: Option<PathBuf>,
    /// Stop after N model evaluations (the report then holds the best point reached, exit 4).
    #[arg(long, value_name = "N", default_value_t = FitLimits::default().max_evaluations)]
    pub max_evaluations: usize,
    /// Stop after S seconds of wall time (the report then holds the best point reached, exit 4).
    #[arg(long, value_name = "S", default_value_t = FitLimits::default().max_time.as_secs_f64())]
    pub max_time: f64,
}

/// The `--loading` choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LoadingSource {
    /// The scene's loading.
    Scene,
    /// The record's load-point displacement.
    Data,
}

/// Runs `stickslip fit`.
pub fn command(args: FitArgs) -> Result<(), Failure> {
    let bad = |m: String| Failure(2, m);
    let source = args.scene.display().to_string();
    let text = std::fs::read_to_string(&args.scene)
        .map_err(|e| bad(format!("cannot read scene {source}: {e}")))?;
    let AnyScene::Lab(scene) = scene::parse_any(&text, &source).map_err(|e| bad(e.to_string()))?
    else {
        return Err(bad(format!("scene {source}: fit takes a lab scene (\"model\": {{\"kind\": \"lab\", ...}}, docs/lab.md)")));
    };
    let loading = match args.loading {
        LoadingSource::Scene => FitLoading::Scene,
        LoadingSource::Data => FitLoading::Data,
    };
    if !(args.max_time.is_finite() && args.max_time > 0.0) {
        return Err(bad(format!(
            "--max-time {}: give a positive number of seconds",
            args.max_time
        )));
    }
    let limits = FitLimits {
        max_evaluations: args.max_evaluations,
        max_time: std::time::Duration::from_secs_f64(args.max_time),
        ..FitLimits::default()
    };
    let report = lab::fit_file(&scene, &args.data, &args.params, &args.columns, loading, limits)
        .map_err(|e| match e {
            FitError::BadInput(m) => bad(m),
            FitError::Stopped(m) => Failure(4, format!("fit of scene {}: {m}", scene.name)),
            other => Failure(1, format!("fit of scene {}: {other}", scene.name)),
        })?;
    if let Some(file) = &args.figure {
        crate::figure::fit::data_fit_and_residuals(&scene.name, &report.outcome)
            .write(file)
            .map_err(|e| Failure(1, format!("--figure: {e}")))?;
    }
    if let Some(file) = &args.series {
        stickslip::report::write_atomic(file, &report.series_csv())
            .map_err(|e| Failure(1, format!("--series: cannot write {}: {e}", file.display())))?;
    }
    super::deliver_report(&report.to_json(), &report.summary(), args.json, args.out.as_deref())?;
    match &report.outcome.stopped {
        Some(why) => Err(Failure(
            4,
            format!(
                "fit of scene {}: stopped: {why} (the report holds the best point reached)",
                scene.name
            ),
        )),
        None => Ok(()),
    }
}
