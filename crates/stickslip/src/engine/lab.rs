//! Runs a lab scene: the lab analysis, its rows to a sink and into the report.

use crate::analysis::lab::{self, LabRunError};
use crate::analysis::time_series::SeriesSink;
use crate::report::lab::{LabReport, LabSeries};
use crate::scene::lab::LabScene;
use crate::sundials;

/// Why a lab scene failed: the run's typed error, or the sink's.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// The run failed.
    #[error(transparent)]
    Run(#[from] LabRunError),
    /// Writing a row failed.
    #[error("cannot write the series: {0}")]
    Sink(std::io::Error),
}

/// Runs `scene`, handing each row to `sink` too (begin, rows, finish); `echo` is the scene as
/// given.
pub fn run(
    scene: &LabScene,
    echo: serde_json::Value,
    sink: &mut dyn SeriesSink,
) -> Result<LabReport, LabError> {
    let n = scene.params.states.len();
    let columns: Vec<&'static str> = lab::COLUMNS[..5 + n].to_vec();
    sink.begin(&columns).map_err(LabError::Sink)?;
    let mut rows = Vec::new();
    let mut sink_error = None;
    let outcome = lab::run(
        &scene.params,
        &scene.loading,
        &scene.initial,
        &scene.solver,
        &scene.output,
        &mut |r| {
            if sink_error.is_none() {
                sink_error = sink.row(r).err();
            }
            rows.push(r.to_vec());
        },
    )?;
    if let Some(e) = sink_error {
        return Err(LabError::Sink(e));
    }
    sink.finish().map_err(LabError::Sink)?;
    Ok(LabReport {
        stickslip_version: env!("CARGO_PKG_VERSION"),
        sundials_version: sundials::version(),
        name: scene.name.clone(),
        scene: echo,
        params: scene.params.clone(),
        critical_stiffness: scene.params.critical_stiffness(),
        loading: scene.loading.clone(),
        solver: scene.solver.clone(),
        outcome,
        series: LabSeries { columns, rows },
    })
}
