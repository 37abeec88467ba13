//! Ensembles of realisations in parallel over cores ([`crate::parallel`], one Rodas5P per
//! realisation). Realisation i draws from the random stream (seed, i) and writes only its own
//! slot; reductions run afterwards in index order. Results are therefore bit-identical for any
//! number of threads.

use super::models::{EventKind, NoiseModel};
use super::rng::Rng;
use super::scheme::{self, Path, SchemeSettings, Start};
use crate::analysis::AnalysisError;
use crate::integrate::{ErrorKind, OdeSystem, Stats};
use crate::parallel;

/// One realisation's results: event time, samples, solver statistics, noise nodes.
type Realisation = (f64, Vec<f64>, Stats, usize);

/// What each realisation records: its observables at given times relative to its own event
/// (or at fixed times), after the run.
#[derive(Debug, Clone)]
pub struct Sampling<'a> {
    /// Grid s_k; realisation r is read at t_ref(r) + s_k.
    pub s: &'a [f64],
    /// None: t_ref = the realisation's own event; Some(t): the fixed time t.
    pub fixed_reference: Option<f64>,
}

/// An ensemble's raw results.
#[derive(Debug, Clone, Default)]
pub struct EnsembleData {
    /// Number of realisations.
    pub realisations: usize,
    /// Event time of each realisation.
    pub event_times: Vec<f64>,
    /// Observables at the grid, realisation-major: `[r][observable][k]`.
    pub samples: Vec<f64>,
    /// Rodas5P's statistics summed over realisations.
    pub stats: Stats,
    /// Noise nodes summed over realisations.
    pub nodes: u64,
}

/// The fixed inputs of an ensemble.
#[derive(Debug, Clone)]
pub struct EnsembleSpec<'a> {
    /// The model with its amplitudes.
    pub model: &'a NoiseModel,
    /// Common deterministic start.
    pub start: &'a Start,
    /// The scheme.
    pub scheme: &'a SchemeSettings,
    /// The event (None: run to `record_until`).
    pub event: Option<EventKind>,
    /// Record at least until this time (for fixed-time sampling).
    pub record_until: f64,
    /// Give up on a realisation without an event at this time.
    pub t_max: f64,
    /// Seed of the random streams.
    pub seed: u64,
}

/// Reads realisation `path`'s observables at the sampling times into `out` ([observable][k]).
fn sample(
    model: &NoiseModel,
    path: &Path,
    sampling: &Sampling<'_>,
    out: &mut [f64],
) -> Result<(), AnalysisError> {
    let reference = sampling.fixed_reference.unwrap_or(path.t_event);
    let k_n = sampling.s.len();
    let mut x = vec![0.0; model.dim()];
    for (k, s) in sampling.s.iter().enumerate() {
        let t = reference + s;
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = path.value(t, i).ok_or_else(|| {
                let (a, b) = path.span();
                AnalysisError::Failed {
                    analysis: "noise",
                    t: path.t_event,
                    state: vec![],
                    message: format!(
                        "the time t_ref + s = {t:e} (t_ref = {reference:e}, s = {s:e}) is outside the realisation's recorded span \
                         [{a:e}, {b:e}]: the event moved too far from the deterministic one (lower the amplitudes or raise \
                         start_before_event)"
                    ),
                }
            })?;
        }
        for (o, (_, obs)) in model.observables().iter().enumerate() {
            out[o * k_n + k] = obs.value(&x);
        }
    }
    Ok(())
}

/// How the realisations are run: on `threads` threads, `progress(done, total)` after each, and
/// a realisation not yet begun when `stop()` returns true fails with
/// [`AnalysisError::Stopped`] (a realisation takes milliseconds).
#[derive(Clone, Copy)]
pub struct Workers<'a> {
    /// Worker threads.
    pub threads: usize,
    /// Called with (done, total) after each realisation.
    pub progress: &'a (dyn Fn(usize, usize) + Sync),
    /// True once the caller wants the ensemble stopped.
    pub stop: &'a (dyn Fn() -> bool + Sync),
}

/// Runs `count` realisations with `workers`. On failures, the error of the lowest failing
/// index (the same whatever the scheduling), with the index in its message.
pub fn run(
    spec: &EnsembleSpec<'_>,
    sampling: &Sampling<'_>,
    count: usize,
    workers: Workers<'_>,
) -> Result<EnsembleData, AnalysisError> {
    let Workers { threads, progress, stop } = workers;
    let per = spec.model.observables().len() * sampling.s.len();
    let realisation = |i: usize| -> Result<Realisation, AnalysisError> {
        if stop() {
            return Err(AnalysisError::Stopped);
        }
        let mut path = Path::default();
        let mut rng = Rng::for_realisation(spec.seed, i as u64);
        let outcome = scheme::realisation(
            spec.model,
            spec.start,
            spec.scheme,
            spec.event,
            spec.record_until,
            spec.t_max,
            &mut rng,
            &mut path,
        )
        .and_then(|()| {
            let mut out = vec![0.0; per];
            sample(spec.model, &path, sampling, &mut out)?;
            Ok(out)
        });
        match outcome {
            Ok(out) => Ok((path.t_event, out, path.stats, path.nodes())),
            Err(mut e) => {
                let hint = if matches!(&e, AnalysisError::Solver(s) if s.kind == ErrorKind::ErrorTestFailures)
                {
                    " (an absolute tolerance below what a noise-driven stiff component allows? loosen atol)"
                } else {
                    ""
                };
                if let Some(message) = e.message_mut() {
                    *message = format!("realisation {i}: {message}{hint}");
                }
                Err(e)
            }
        }
    };
    let mut data = EnsembleData {
        realisations: count,
        samples: Vec::with_capacity(count * per),
        ..Default::default()
    };
    for (t, out, stats, nodes) in parallel::try_map(count, threads, progress, realisation)? {
        data.event_times.push(t);
        data.nodes += nodes as u64;
        data.samples.extend_from_slice(&out);
        data.stats.accumulate(&stats);
    }
    Ok(data)
}
