//! The `stickslip` binary's commands, one module each, and what they share.

pub mod compare;
pub mod fit;
pub mod progress;
pub mod qdyn;
pub mod reproduce;
pub mod robertson;
pub mod run;
pub mod stress;
pub mod sweep;

use stickslip::{engine, scene};

/// A failed command and its exit code: 2 for bad input, 1 for a failed computation, 4 for a
/// cycle analysis that did not converge.
pub struct Failure(pub u8, pub String);

/// A failed run of the scene `name`: exit code 2 when an option does not fit the computed
/// orbit (bad input, the field named), 1 otherwise.
pub fn failed(name: &str, error: engine::RunError) -> Failure {
    Failure(if error.is_bad_input() { 2 } else { 1 }, format!("scene {name}: {error}"))
}

/// Largest scene file accepted: scenes are a few hundred bytes; a huge file is a mistake, and
/// reading it whole would only exhaust memory.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// A scene file's text (a bad path or a file over [`MAX_SCENE_BYTES`]: exit 2).
pub fn read_scene_text(path: &std::path::Path) -> Result<String, Failure> {
    let cannot =
        |e: std::io::Error| Failure(2, format!("cannot read scene {}: {e}", path.display()));
    let size = std::fs::metadata(path).map_err(cannot)?.len();
    if size > MAX_SCENE_BYTES {
        return Err(Failure(2, format!("scene {}: the file has {size} bytes; a scene is at most {MAX_SCENE_BYTES} bytes (is this the right file?)", path.display())));
    }
    std::fs::read_to_string(path).map_err(cannot)
}

/// A DRR scene file (or a QDYN input file, mapped: [`qdyn::scene_text`]), parsed and
/// validated (exit 2 naming the field).
pub fn read_scene(path: &std::path::Path) -> Result<scene::Scene, Failure> {
    let text = qdyn::scene_text(Some(path), read_scene_text(path)?).map_err(|e| Failure(2, e))?;
    scene::parse(&text, &path.display().to_string()).map_err(|e| Failure(2, e.to_string()))
}

/// Pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) {
    println!("{}", serde_json::to_string_pretty(value).expect("serialisable"));
}

/// `--threads`, or every core.
pub fn worker_threads(threads: Option<usize>) -> usize {
    threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// Writes a command's JSON report to `out` (atomically) if given, then prints it (`json`) or
/// the summary, naming the file written.
pub fn deliver_report(
    report_json: &str,
    summary: &str,
    json: bool,
    out: Option<&std::path::Path>,
) -> Result<(), Failure> {
    if let Some(file) = out {
        stickslip::report::write_atomic(file, report_json)
            .map_err(|e| Failure(1, format!("cannot write {}: {e}", file.display())))?;
    }
    if json {
        println!("{report_json}");
    } else {
        print!("{summary}");
        if let Some(file) = out {
            println!("report written to {}", file.display());
        }
    }
    Ok(())
}
