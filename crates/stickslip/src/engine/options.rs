//! How [`super::run`] carries a scene out: the scene as given (echoed in the report), the
//! worker threads of ensembles, where the time-series rows go, a flag to stop the run from
//! another thread, and where the progress of an ensemble goes. None of them changes a number
//! of the report.

use super::Cancel;
use crate::analysis::time_series::SeriesSink;

/// A progress sink: `progress(done, total)` after each unit of long work (an ensemble's
/// realisations). Called from the worker threads, so it is `Sync`.
pub type ProgressSink<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// The options of [`super::run`]. `RunOptions::default()` echoes nothing (the report's
/// `scene` is null), uses every core, keeps no rows, cannot be stopped and reports no
/// progress; the builder methods set each of these.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// The scene as given (its JSON), echoed as the report's `scene`; `Value::Null` by
    /// default.
    pub echo: serde_json::Value,
    /// Worker threads for ensembles (the "noise" analysis); None: every core. Results do not
    /// depend on it.
    pub threads: Option<usize>,
    /// Where the "time_series" rows go as they are computed (a file of
    /// [`crate::series_file`], or a [`crate::analysis::time_series::SeriesCollector`] to keep
    /// them in memory); None: nowhere (the report's `time_series` and `events` are the same
    /// either way). Nothing is written to it when the scene asks for no time series.
    pub series: Option<&'a mut dyn SeriesSink>,
    /// Stops the run from another thread: every integration fails at its next step once it is
    /// set, the analyses not begun are skipped, and the run returns
    /// [`super::RunError::Cancelled`] (the rows written to `series` are then incomplete).
    pub cancel: Option<&'a Cancel>,
    /// Called after each realisation of an ensemble with (done, total).
    pub progress: Option<ProgressSink<'a>>,
}

impl<'a> RunOptions<'a> {
    /// The options that echo `scene` (the scene as given) in the report.
    pub fn echoing(scene: serde_json::Value) -> Self {
        Self { echo: scene, ..Self::default() }
    }

    /// With `threads` worker threads for ensembles.
    pub fn threads(self, threads: usize) -> Self {
        Self { threads: Some(threads), ..self }
    }

    /// Streaming the "time_series" rows to `series`.
    pub fn series(self, series: &'a mut dyn SeriesSink) -> Self {
        Self { series: Some(series), ..self }
    }

    /// Stopped once `cancel` is set.
    pub fn cancel(self, cancel: &'a Cancel) -> Self {
        Self { cancel: Some(cancel), ..self }
    }

    /// Reporting an ensemble's progress to `progress`.
    pub fn progress(self, progress: ProgressSink<'a>) -> Self {
        Self { progress: Some(progress), ..self }
    }

    /// The worker threads: the ones asked for, or every core.
    pub(super) fn worker_threads(&self) -> usize {
        self.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
    }
}
