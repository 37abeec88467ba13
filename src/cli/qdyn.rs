//! `stickslip run`'s QDYN glue: a QDYN input file read as a scene
//! ([`stickslip::scene::qdyn_input`]), and the `--qdyn-output` sink
//! ([`stickslip::series_file::qdyn`]).

use std::path::Path;
use stickslip::analysis::time_series::SeriesSink;
use stickslip::scene::{qdyn_input, Scene};
use stickslip::series_file::qdyn::{QdynColumns, QdynOutputSink};

/// The scene text of the file at `path`: a QDYN input file's mapped scene (named after the
/// file's stem), any other file's text unchanged. The error (exit 2) names the line and field.
pub fn scene_text(path: Option<&Path>, text: String) -> Result<String, String> {
    match path {
        Some(p) if qdyn_input::is_qdyn_input(p, &text) => {
            let name = p.file_stem().map_or("qdyn".into(), |s| s.to_string_lossy().into_owned());
            qdyn_input::to_scene(&text, &p.display().to_string(), &name).map_err(|e| e.to_string())
        }
        _ => Ok(text),
    }
}

/// The `--qdyn-output DIR` sink for `scene`; the error (exit 2) names what the scene lacks or
/// why DIR cannot be written.
pub fn sink(scene: &Scene, dir: &Path) -> Result<Box<dyn SeriesSink>, String> {
    let named = |e: String| format!("--qdyn-output {}: {e}", dir.display());
    let columns = QdynColumns::for_scene(scene).map_err(named)?;
    if scene.analyses.time_series.is_none() {
        return Err(named(format!("scene {} has no \"time_series\" analysis; add {{\"time_series\": {{\"t_max\": T}}}} to its analyses", scene.name)));
    }
    let sink = QdynOutputSink::create(dir, columns)
        .map_err(|e| named(format!("cannot create the files: {e}")))?;
    Ok(Box::new(sink))
}
