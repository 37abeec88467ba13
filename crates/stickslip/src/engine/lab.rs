//! A lab scene's run (through [`super::run`]): the lab analysis, its rows to a sink and into
//! the report; and the fit of the scene's model to a friction record.

use crate::analysis::lab::{self, LabRunError};
use crate::analysis::lab_fit::{
    self, ColumnNames, FitError, FitLimits, FitParameter, FitSettings, FrictionRecord,
    SensitivityRoute,
};
use crate::analysis::time_series::SeriesSink;
use crate::model::Loading;
use crate::report::lab::{LabReport, LabSeries, LabSolverSection};
use crate::report::lab_fit::FitReport;
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

/// Runs `scene` ([`super::run`]), handing each row to `sink` too (begin, rows, finish);
/// `echo` is the scene as given.
pub(super) fn run(
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
        solver: LabSolverSection {
            solver: scene.solver.clone(),
            chosen_by: scene.solver_chosen_by.clone(),
        },
        outcome,
        series: LabSeries { columns, rows },
    })
}

/// Where a fit takes the load-point history from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitLoading {
    /// The scene's `loading`.
    Scene,
    /// The record's load-point displacement column (chords between samples).
    Data,
}

/// Fits `scene`'s lab model to `record` (`stickslip fit`): the scene gives the starting
/// values, the solver and (with [`FitLoading::Scene`]) the loading; `data` names the record
/// in the report; `limits` caps the work.
pub fn fit(
    scene: &LabScene,
    record: &FrictionRecord,
    data: &str,
    params: Vec<FitParameter>,
    loading: FitLoading,
    limits: FitLimits,
) -> Result<FitReport, FitError> {
    let history = match loading {
        FitLoading::Scene => scene.loading.clone(),
        FitLoading::Data => {
            let x = record.x_lp.as_ref().ok_or_else(|| {
                FitError::BadInput("--loading data needs the record's load-point displacement: name its column with --columns x_lp=NAME".into())
            })?;
            let samples: Vec<(f64, f64)> =
                record.t.iter().copied().zip(x.iter().copied()).collect();
            Loading::from_displacement(&samples).map_err(|e| {
                FitError::BadInput(format!("the record's x_lp column: {e}; a measured displacement is noisy: give the scene a loading with the record's velocities (e.g. from a line fitted to each part, as data/scenes/lab-basalt-b819.json does) and use --loading scene"))
            })?
        }
    };
    let steady = scene.params.steady_state(history.segments[0].velocity);
    if scene.initial.iter().zip(&steady).any(|(a, b)| (a - b).abs() > 1e-12 * (1.0 + b.abs())) {
        return Err(FitError::BadInput(
            "a fit starts at steady sliding at the first segment's velocity: give \"initial\": \"steady\" in the scene".into(),
        ));
    }
    let route = SensitivityRoute::for_method(scene.solver.method).map_err(FitError::BadInput)?;
    let settings = FitSettings { params, solver: scene.solver.clone(), limits };
    let outcome = lab_fit::fit(&scene.params, &history, record, &settings)?;
    Ok(FitReport {
        stickslip_version: env!("CARGO_PKG_VERSION"),
        sundials_version: sundials::version(),
        scene: scene.name.clone(),
        data: data.to_string(),
        loading: match loading {
            FitLoading::Scene => "scene",
            FitLoading::Data => "data",
        },
        solver: scene.solver.clone(),
        sensitivities: route.name(),
        outcome,
    })
}

/// [`fit`] from what a user types: `params` as `a,b_1,d_c_1,…`, `columns` as
/// `t=NAME,mu=NAME,x_lp=NAME` (empty: the names t, mu, x_lp), the record read from `data`.
/// Used by `stickslip fit` and Python's `stickslip.fit`.
pub fn fit_file(
    scene: &LabScene,
    data: &std::path::Path,
    params: &str,
    columns: &str,
    loading: FitLoading,
    limits: FitLimits,
) -> Result<FitReport, FitError> {
    let n = scene.params.states.len();
    let params = params
        .split(',')
        .map(|p| FitParameter::parse(p.trim(), n))
        .collect::<Result<Vec<_>, _>>()
        .map_err(FitError::BadInput)?;
    let names = ColumnNames::parse(columns).map_err(FitError::BadInput)?;
    let record = FrictionRecord::read(data, &names, loading == FitLoading::Data)
        .map_err(|e| FitError::BadInput(format!("--data: {e}")))?;
    fit(scene, &record, &data.display().to_string(), params, loading, limits)
}
