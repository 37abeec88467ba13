//! `stickslip run`'s QDYN glue: a QDYN input file read as a scene
//! ([`stickslip::scene::qdyn_input`]), and the `--qdyn-output` sink
//! ([`stickslip::series_file::qdyn`]).

use std::path::Path;
use stickslip::analysis::time_series::SeriesSink;
use stickslip::scene::qdyn_input::{self, QdynOutputIntervals};
use stickslip::scene::Scene;
use stickslip::series_file::qdyn::{QdynColumns, QdynOutputSink};

/// The scene text of the file at `path`: a QDYN input file's mapped scene (named after the
/// file's stem), any other file's text unchanged. The error (exit 2) names the line and field.
pub fn scene_text(path: Option<&Path>, text: String) -> Result<String, String> {
    read(path, text).map(|(scene, _)| scene)
}

/// [`scene_text`] with the QDYN output intervals of a QDYN input file (None for a scene).
pub fn read(
    path: Option<&Path>,
    text: String,
) -> Result<(String, Option<QdynOutputIntervals>), String> {
    match path {
        Some(p) if qdyn_input::is_qdyn_input(p, &text) => {
            let name = p.file_stem().map_or("qdyn".into(), |s| s.to_string_lossy().into_owned());
            let input = qdyn_input::read(&text, &p.display().to_string(), &name)
                .map_err(|e| e.to_string())?;
            Ok((input.scene, Some(input.output)))
        }
        _ => Ok((text, None)),
    }
}

/// The `--qdyn-output DIR` sink for `scene`, thinned by a qdyn.in's `intervals`; the error
/// (exit 2) names what the scene lacks or why DIR cannot be written. A large expected size is
/// announced on stderr.
pub fn sink(
    scene: &Scene,
    dir: &Path,
    intervals: Option<QdynOutputIntervals>,
) -> Result<Box<dyn SeriesSink>, String> {
    let named = |e: String| format!("--qdyn-output {}: {e}", dir.display());
    let columns = QdynColumns::for_scene(scene).map_err(named)?;
    let Some(series) = &scene.analyses.time_series else {
        return Err(named(format!("scene {} has no \"time_series\" analysis; add {{\"time_series\": {{\"t_max\": T}}}} to its analyses", scene.name)));
    };
    let announce = Box::new(|message: &str| eprintln!("stickslip: {message}"));
    let sink = QdynOutputSink::create(dir, columns, intervals, series.t_max, announce)
        .map_err(|e| named(format!("cannot create the files: {e}")))?;
    Ok(Box::new(sink))
}
