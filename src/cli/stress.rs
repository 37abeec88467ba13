//! `stickslip stress`: the numerical stress grid.

use super::progress::Progress;
use super::{worker_threads, Failure};
use std::path::PathBuf;
use stickslip::{report, scene};

/// Runs `stickslip stress` over `grid` (only `methods`' cells if any are given).
pub fn stress_command(
    grid: crate::stress::Grid,
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
    let mut cells = crate::stress::grid(grid);
    if !methods.is_empty() {
        cells.retain(|cell| methods.contains(&cell.method));
    }
    let progress = Progress::new("stress", "cells");
    let (outcomes, summary) =
        crate::stress::run(&cells, worker_threads(threads), &|d, t| progress.update(d, t));
    let seconds = progress.finish();
    if let Some(path) = table {
        let text = format!(
            "{} cells in {seconds:.0} s\n\n{}",
            cells.len(),
            crate::stress::table(&cells, &outcomes, &summary)
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
            let (new, fixed) = crate::stress::against_known(&cells, &outcomes, text);
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
