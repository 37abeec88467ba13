//! `stickslip reproduce` and `stickslip noise-curves`: the paper's figures and claims.

use super::progress::Progress;
use super::{worker_threads, Failure};
use std::path::PathBuf;
use stickslip::analysis::noise::report as noise_report;
use stickslip::paper::claims::Verdict;
use stickslip::report;

/// Runs `stickslip reproduce`: the paper's figures, reports and claims in `out`.
pub fn reproduce_command(
    out: PathBuf,
    threads: Option<usize>,
    reduced: bool,
) -> Result<(), Failure> {
    let progress = Progress::new("reproduce", "runs");
    let summary = crate::reproduce::run(&out, worker_threads(threads), reduced, &progress);
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

/// Runs `stickslip noise-curves`: the correlation-time curves of noise reports in one file.
pub fn noise_curves_command(out: PathBuf, reports: Vec<PathBuf>) -> Result<(), Failure> {
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
