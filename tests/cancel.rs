//! Cancelling a run ([`engine::Cancel`]): the run stops at the next integrator step with
//! [`engine::RunError::Cancelled`], and a run never cancelled is the plain run.

use stickslip::analysis::time_series::SeriesSink;
use stickslip::engine::{self, Cancel, RunError, RunOptions};
use stickslip::{scene, sweep};

/// A time series of 40 time units in 4001 rows (CVODE's BDF takes ~2 steps per 10 rows).
const SERIES: &str = r#"{"name": "cancel", "model": {"gamma": 1e3, "xi": 0.7, "epsilon": 0.72},
    "solver": {"method": "cvode-bdf", "rtol": 1e-10, "atol": 1e-12},
    "analyses": ["hopf", {"time_series": {"t_max": 40, "points": 4001}}]}"#;

/// Counts the rows; cancels the run at row `at`.
struct CancelAt {
    cancel: Cancel,
    at: usize,
    rows: usize,
}

impl SeriesSink for CancelAt {
    fn begin(&mut self, _: &[&'static str]) -> std::io::Result<()> {
        Ok(())
    }
    fn row(&mut self, _: &[f64]) -> std::io::Result<()> {
        self.rows += 1;
        if self.rows == self.at {
            self.cancel.cancel();
        }
        Ok(())
    }
    fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn rows_until_cancelled_at(at: usize) -> (Result<(), RunError>, usize) {
    let s = scene::parse(SERIES, "test").unwrap();
    let cancel = Cancel::new();
    let mut sink = CancelAt { cancel: cancel.clone(), at, rows: 0 };
    let options = RunOptions::default().threads(1).series(&mut sink).cancel(&cancel);
    let outcome = engine::run(&s, options);
    (outcome.map(|_| ()), sink.rows)
}

#[test]
fn a_cancelled_run_stops_at_the_next_step_with_a_typed_error() {
    let (whole, all) = rows_until_cancelled_at(usize::MAX);
    assert!(whole.is_ok(), "{whole:?}");
    assert_eq!(all, 4001);
    let (cancelled, rows) = rows_until_cancelled_at(100);
    assert!(matches!(cancelled, Err(RunError::Cancelled)), "{cancelled:?}");
    // The rows of the step in progress at most (measured: 100, none after the cancel).
    assert!((100..110).contains(&rows), "{rows} rows written after cancelling at row 100");
}

#[test]
fn a_run_never_cancelled_is_the_plain_run() {
    let text = std::fs::read_to_string(format!(
        "{}/data/scenes/earthquake.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let s = scene::parse(&text, "earthquake").unwrap();
    let echo: serde_json::Value = serde_json::from_str(&text).unwrap();
    let plain = engine::run(&s, RunOptions::echoing(echo.clone()).threads(1)).unwrap();
    let cancel = Cancel::new();
    let cancellable =
        engine::run(&s, RunOptions::echoing(echo).threads(1).cancel(&cancel)).unwrap();
    let json = |r: &stickslip::report::Report| {
        let mut v = serde_json::to_value(r).unwrap();
        v.as_object_mut().unwrap().remove("wall_time_s");
        v
    };
    assert_eq!(json(&plain), json(&cancellable));
}

#[test]
fn a_cancelled_sweep_point_has_no_row() {
    let base: serde_json::Value = serde_json::from_str(SERIES).unwrap();
    let epsilon = sweep::SweepParameter::from_name("epsilon").unwrap();
    let params = [(epsilon, 0.8)].into_iter().collect();
    let cancel = Cancel::new();
    let row = sweep::run_point_cancellable(&base, 0, &params, &cancel);
    assert_eq!(row, Some(sweep::run_point(&base, 0, &params)));
    cancel.cancel();
    assert_eq!(sweep::run_point_cancellable(&base, 0, &params, &cancel), None);
}

/// A noise analysis stops between realisations: cancelled once 5 of 200 are done (from the
/// progress callback, on one thread), the run ends with `Cancelled` after at most the one
/// realisation that finds the flag set.
#[test]
fn a_cancelled_noise_analysis_stops_between_realisations() {
    let text = std::fs::read_to_string(format!(
        "{}/data/scenes/noise-drr.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut echo: serde_json::Value = serde_json::from_str(&text).unwrap();
    let noise = echo["analyses"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find_map(|a| a.get_mut("noise"))
        .expect("noise-drr.json has a noise analysis");
    noise["realisations"] = serde_json::json!(200);
    let s = scene::parse(&echo.to_string(), "noise").unwrap();
    let cancel = Cancel::new();
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let progress = |done: usize, _: usize| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if done == 5 {
            cancel.cancel();
        }
    };
    let options = RunOptions::echoing(echo).threads(1).progress(&progress).cancel(&cancel);
    let outcome = engine::run(&s, options);
    assert!(matches!(outcome, Err(RunError::Cancelled)), "{outcome:?}");
    let calls = calls.into_inner();
    assert!((5..=6).contains(&calls), "{calls} realisations reported after cancelling at 5");
}
