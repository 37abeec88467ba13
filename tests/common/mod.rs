//! Helpers shared by the library's and the command's tests: the reference tables' check
//! ([`reference`]), a scene run through the library ([`run_scene`], [`run_scene_file`]) and
//! through the CLI ([`cli_run`], [`compare_cli`]). The integrators' test problems are
//! crates/ode/tests/common's.
#![allow(dead_code)]

pub mod reference;

/// The text of the shipped scene data/scenes/`name`.
pub fn scene_file_text(name: &str) -> String {
    let path = format!("{}/data/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The report of the scene `text` (JSON) through the library, as `stickslip run` computes it:
/// `scene::parse`, then `engine::run` with the text echoed; panics with the error's message.
pub fn run_scene(text: &str) -> stickslip::report::Report {
    let s = stickslip::scene::parse(text, "test").unwrap_or_else(|e| panic!("{e}"));
    stickslip::engine::run(
        &s,
        stickslip::engine::RunOptions::echoing(serde_json::from_str(text).unwrap()),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// [`run_scene`] on the shipped scene data/scenes/`name`.
pub fn run_scene_file(name: &str) -> stickslip::report::Report {
    run_scene(&scene_file_text(name))
}

/// `stickslip run FILE` with `extra` options, FILE a temporary copy of the scene `text` named
/// after `tag` (unique per test process, removed afterwards): the process's output.
pub fn cli_run(text: &str, tag: &str, extra: &[&str]) -> std::process::Output {
    let path =
        std::env::temp_dir().join(format!("stickslip-test-{}-{tag}.json", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("run")
        .arg(&path)
        .args(extra)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&path);
    out
}

/// `stickslip compare SCENE --against FILE` with `extra` options: (exit code, stdout, stderr).
pub fn compare_cli(
    scene: &std::path::Path,
    file: &std::path::Path,
    extra: &[&str],
) -> (Option<i32>, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args(["compare", scene.to_str().unwrap(), "--against", file.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
