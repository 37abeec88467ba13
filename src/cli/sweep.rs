//! `stickslip sweep` and `stickslip merge`: parameter sweeps as JSON Lines.

use super::progress::Progress;
use super::{read_scene_text, worker_threads, Failure};
use std::path::PathBuf;
use stickslip::{report, scene, sweep};

/// Runs `stickslip sweep`: one JSON line per point in `out`.
pub fn sweep_command(
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

/// Runs `stickslip merge`: sweep outputs into one file sorted by point index.
pub fn merge_command(
    out: PathBuf,
    total: Option<usize>,
    inputs: Vec<PathBuf>,
) -> Result<(), Failure> {
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
