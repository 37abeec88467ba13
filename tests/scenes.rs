//! Scene validation: bad input names the field and the fix; the CLI exits 2 and writes nothing.

use std::process::Command;
use stickslip::scene;

fn scene_with(model: &str, rest: &str) -> String {
    format!(r#"{{"name": "t", "model": {model}, "analyses": ["hopf"]{rest}}}"#)
}

fn error_of(text: &str) -> scene::SceneError {
    scene::parse(text, "test").expect_err("the scene must be rejected")
}

#[test]
fn the_shipped_scenes_are_valid() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes");
    let mut count = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        scene::parse_any(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
        count += 1;
    }
    assert!(count >= 4);
}

#[test]
fn cycle_and_shooting_options_name_the_field_and_what_is_valid() {
    let model = r#""model": {"gamma": 10, "xi": 0.7, "epsilon": 1}"#;
    let with =
        |analysis: &str| format!(r#"{{"name": "t", {model}, "analyses": ["hopf", {analysis}]}}"#);
    let cases = [
        (with(r#"{"cycle": {"tolerance": 0.5}}"#), "analyses[1].cycle.tolerance", "(0, 0.1]"),
        (with(r#"{"cycle": {"max_time": 0.5}}"#), "analyses[1].cycle.max_time", "≥ 1"),
        (with(r#"{"cycle": {"settle": 0}}"#), "analyses[1].cycle.settle", "between 1 and 1000"),
        (
            with(r#"{"cycle": {"max_cycles": 0}}"#),
            "analyses[1].cycle.max_cycles",
            "between 1 and 10000000",
        ),
        (with(r#"{"cycle": {"max_steps": 0}}"#), "analyses[1].cycle.max_steps", "between 1 and"),
        (
            with(r#"{"cycle": {"tolerence": 1e-7}}"#),
            "analyses[1].cycle",
            "unknown field `tolerence`",
        ),
        (with(r#"{"shooting": {"tolerance": 0}}"#), "analyses[1].shooting.tolerance", "(0, 0.1]"),
        (
            with(r#"{"shooting": {"max_iterations": 1001}}"#),
            "analyses[1].shooting.max_iterations",
            "between 1 and 1000",
        ),
        (
            with(r#"{"shooting": {"iterations": 3}}"#),
            "analyses[1].shooting",
            "unknown field `iterations`",
        ),
    ];
    for (text, field, hint) in cases {
        let e = error_of(&text);
        assert_eq!(e.field, field, "{e}");
        assert!(e.message.contains(hint), "{e} should mention {hint}");
    }
    let ok = scene::parse(&with(r#"{"cycle": {"tolerance": 1e-6, "settle": 4}}"#), "test").unwrap();
    let cycle = ok.analyses.cycle.unwrap();
    let settings = cycle.settings(1e-10, 1e-12);
    assert_eq!(
        (settings.tolerance, settings.settle, settings.max_cycles),
        (1e-6, 4, 1000),
        "given, given, default"
    );
}

#[test]
fn domain_errors_name_the_field_and_what_is_valid() {
    let cases = [
        (scene_with(r#"{"gamma": -1, "xi": 0.7, "epsilon": 0.7}"#, ""), "model.gamma", "> 0"),
        (scene_with(r#"{"gamma": 0, "xi": 0.7, "epsilon": 0.7}"#, ""), "model.gamma", "> 0"),
        (scene_with(r#"{"gamma": 10, "xi": 0, "epsilon": 0.7}"#, ""), "model.xi", "> 0"),
        (
            scene_with(
                r#"{"gamma": 10, "xi": 0.7, "epsilon": 0.7, "friction": {"power": {"alpha": -0.3}}}"#,
                "",
            ),
            "model.friction.power.alpha",
            "> 0",
        ),
        (scene_with(r#"{"gamma": 10, "xi": 0.7}"#, ""), "model", "epsilon"),
        (
            scene_with(r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#, r#", "solver": {"rtol": 0}"#),
            "solver.rtol",
            "> 0",
        ),
        (
            scene_with(
                r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#,
                r#", "solver": {"rtol": -1e-8}"#,
            ),
            "solver.rtol",
            "> 0",
        ),
        (
            scene_with(
                r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#,
                r#", "solver": {"method": "rk4"}"#,
            ),
            "solver.method",
            "cvode-bdf",
        ),
        (
            scene_with(
                r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#,
                r#", "solver": {"atol": [1e-9, 1e-9]}"#,
            ),
            "solver.atol",
            "three",
        ),
        (
            scene_with(
                r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#,
                r#", "solver": {"method": "arkode-dirk", "table": "NOPE"}"#,
            ),
            "solver.table",
            "SDIRK_5_3_4",
        ),
        (
            scene_with(r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#, r#", "initial": {"v": -1}"#),
            "initial.v",
            "> 0",
        ),
        (
            scene_with(
                r#"{"gamma": 10, "xi": 0.7, "epsilon": 1, "dimensional": {"k":1,"mass":1,"a_sigma": 1,"b_sigma": 2,"d_c":1,"v0":1}}"#,
                "",
            ),
            "model",
            "not both",
        ),
    ];
    for (text, field, hint) in cases {
        let e = error_of(&text);
        assert_eq!(e.field, field, "{e}");
        assert!(e.message.contains(hint), "{e} should mention {hint}");
    }
}

#[test]
fn unknown_keys_and_wrong_types_name_the_path() {
    let e = error_of(&scene_with(r#"{"gama": 10, "xi": 0.7, "epsilon": 1}"#, ""));
    assert!(e.field.starts_with("model") && e.message.contains("gama"), "{e}");
    let e = error_of(&scene_with(r#"{"gamma": "big", "xi": 0.7, "epsilon": 1}"#, ""));
    assert_eq!(e.field, "model.gamma", "{e}");
    let e = error_of(
        r#"{"name": "t", "model": {"gamma": 10, "xi": 0.7, "epsilon": 1}, "analyses": ["hopf"], "extra": 1}"#,
    );
    assert!(e.message.contains("extra"), "{e}");
    let e = error_of(
        &scene_with(r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#, "")
            .replace("\"hopf\"", "\"fourier\""),
    );
    assert!(e.message.contains("unknown analysis") && e.message.contains("cycle"), "{e}");
    // JSON has no NaN or infinity: both are syntax or range errors, never a silent value.
    assert!(
        scene::parse(&scene_with(r#"{"gamma": NaN, "xi": 0.7, "epsilon": 1}"#, ""), "t").is_err()
    );
    let e = error_of(&scene_with(r#"{"gamma": 1e999, "xi": 0.7, "epsilon": 1}"#, ""));
    assert!(e.message.contains("out of range") || e.message.contains("finite"), "{e}");
    // An empty key at the top level (found by cargo-fuzz): the error still names a field.
    let e = error_of(r#"{"": 1, "name": "t"}"#);
    assert_eq!(e.field, "(document)", "{e}");
    assert!(e.message.contains("unknown field"), "{e}");
}

/// The smallest entry of the analysis `name`: the bare name, or the least options it needs.
/// A new analysis that needs options fails `every_analysis_parses_from_its_minimal_form`
/// until it gets a line here.
fn minimal_entry(name: &str) -> String {
    match name {
        "trajectory" => r#"{"trajectory": {"cycles": 1}}"#.into(),
        "continuation" => r#"{"continuation": {"parameter": "xi", "to": 0.8, "points": 2}}"#.into(),
        "noise" => r#"{"noise": {"amplitudes": [0, 1e-3, 0]}}"#.into(),
        "time_series" => r#"{"time_series": {"t_max": 10}}"#.into(),
        bare => format!("\"{bare}\""),
    }
}

/// What the analysis `name` works on, when it needs another's results.
fn needs(name: &str) -> &'static [&'static str] {
    match name {
        "paper" => &["\"hopf\"", "\"cycle\""],
        "trajectory" | "asymptotics" | "lyapunov" => &["\"cycle\""],
        _ => &[],
    }
}

#[test]
fn every_analysis_parses_from_its_minimal_form() {
    let names: Vec<&str> = scene::analysis_names().collect();
    let distinct: std::collections::BTreeSet<&str> = names.iter().copied().collect();
    assert_eq!(distinct.len(), names.len(), "a name twice: {names:?}");
    let parse = |entries: &[String]| {
        let text = format!(
            r#"{{"name": "t", "model": {{"gamma": 10, "xi": 0.7, "epsilon": 1}}, "analyses": [{}]}}"#,
            entries.join(", ")
        );
        scene::parse(&text, "test").map(|s| s.analyses)
    };
    for name in names {
        let base: Vec<String> = needs(name).iter().map(|n| n.to_string()).collect();
        let with: Vec<String> = base.iter().cloned().chain([minimal_entry(name)]).collect();
        let asked = parse(&with).unwrap_or_else(|e| panic!("{name}: {e}"));
        let without = if base.is_empty() { Ok(scene::Analyses::default()) } else { parse(&base) };
        assert_ne!(Ok(asked), without, "{name} changed nothing");
    }
}

#[test]
fn an_unknown_analysis_is_refused_naming_every_analysis() {
    let e = error_of(
        &scene_with(r#"{"gamma": 10, "xi": 0.7, "epsilon": 1}"#, "")
            .replace("\"hopf\"", "\"hopf\", \"fourier\""),
    );
    assert_eq!(e.field, "analyses[1]", "{e}");
    assert!(e.message.starts_with("unknown analysis \"fourier\"; use one of "), "{e}");
    for name in scene::analysis_names() {
        assert!(e.message.contains(&format!("\"{name}\"")), "{name} missing: {e}");
    }
}

#[test]
fn dimensional_input_converts_to_gamma_xi_epsilon() {
    let text = scene_with(
        r#"{"dimensional": {"k": 4.0, "mass": 1.0, "a_sigma": 2.0, "b_sigma": 5.0, "d_c": 3.0, "v0": 0.5}}"#,
        "",
    );
    let s = scene::parse(&text, "t").unwrap();
    assert!((s.params.gamma - 6.0 * 2.0).abs() < 1e-12); // (D_c/v0)·√(k/M)
    assert!((s.params.xi - 6.0).abs() < 1e-12); // k·D_c/A
    assert!((s.params.epsilon - 1.5).abs() < 1e-12); // (B − A)/A
    assert_eq!(s.units.unwrap().time_scale, 6.0); // D_c/v0
}

#[test]
fn default_start_is_on_the_slow_manifold() {
    for friction in [r#""log""#, r#""asinh""#, r#"{"power": {"alpha": 0.31}}"#] {
        let text = scene_with(
            &format!(r#"{{"gamma": 1e8, "xi": 0.8, "epsilon": 1, "friction": {friction}}}"#),
            "",
        );
        let s = scene::parse(&text, "t").unwrap();
        let drr = stickslip::model::Drr::new(s.params);
        assert!(
            drr.manifold_offset(&s.initial).abs() < 1e-15,
            "{friction}: G = {}",
            drr.manifold_offset(&s.initial)
        );
        assert!((s.initial[1] - 0.5f64.ln()).abs() < 1e-15);
    }
}

#[test]
fn cli_exit_codes_and_nothing_written_on_bad_input() {
    let exe = env!("CARGO_BIN_EXE_stickslip");
    let dir = std::env::temp_dir().join(format!("stickslip-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(&bad, scene_with(r#"{"gamma": -5, "xi": 0.7, "epsilon": 1}"#, "")).unwrap();
    let out = dir.join("report.json");
    let run = Command::new(exe)
        .args(["run", bad.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("model.gamma"), "{stderr}");
    assert!(!out.exists(), "no report on bad input");
    let missing = Command::new(exe).args(["run", "/no/such/scene.json"]).output().unwrap();
    assert_eq!(missing.status.code(), Some(2));
    let malformed = dir.join("malformed.json");
    std::fs::write(&malformed, "{\"name\": ").unwrap();
    assert_eq!(
        Command::new(exe)
            .args(["run", malformed.to_str().unwrap()])
            .output()
            .unwrap()
            .status
            .code(),
        Some(2)
    );
    // Deep nesting (serde_json's recursion limit) and a huge file: exit 2 with a message, no panic.
    let deep = dir.join("deep.json");
    std::fs::write(
        &deep,
        format!(
            "{{\"name\": \"t\", \"analyses\": {}{}}}",
            "[".repeat(100_000),
            "]".repeat(100_000)
        ),
    )
    .unwrap();
    let run = Command::new(exe).args(["run", deep.to_str().unwrap()]).output().unwrap();
    assert_eq!(run.status.code(), Some(2), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(String::from_utf8_lossy(&run.stderr).contains("recursion limit"));
    let huge = dir.join("huge.json");
    std::fs::write(&huge, " ".repeat(17 << 20)).unwrap();
    let run = Command::new(exe).args(["run", huge.to_str().unwrap()]).output().unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&run.stderr).contains("at most"),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::remove_file(&huge).unwrap();

    // A computation that fails: a non-stiff method on a stiff case with a small step budget.
    let stiff = dir.join("stiff.json");
    std::fs::write(
        &stiff,
        r#"{"name": "t", "model": {"gamma": 1e5, "xi": 0.8, "epsilon": 1}, "solver": {"method": "arkode-erk"},
            "analyses": [{"cycle": {"max_steps": 20000}}]}"#,
    )
    .unwrap();
    let run = Command::new(exe)
        .args(["run", stiff.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("at t =") && stderr.contains("state"), "{stderr}");
    assert!(!out.exists());

    let good = dir.join("good.json");
    std::fs::write(&good, scene_with(r#"{"gamma": 10, "xi": 0.8, "epsilon": 1}"#, "")).unwrap();
    let run = Command::new(exe)
        .args(["run", good.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert!(report["hopf"]["epsilon_c"].is_number());
    assert!(report.get("cycle").is_none(), "only what the scene asks for");
    std::fs::remove_dir_all(&dir).ok();
}

/// `--out` onto a path that is not a regular file (a FIFO here, `/dev/null` in practice) writes
/// into it instead of renaming a temporary file over it, and `--out` through a symbolic link
/// replaces the file it points to, not the link.
#[test]
fn reports_are_written_through_fifos_and_symbolic_links() {
    use std::os::unix::fs::FileTypeExt;
    let dir = std::env::temp_dir().join(format!("stickslip-write-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("pipe");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    stickslip::report::write_atomic(&fifo, "through the pipe\n").unwrap();
    // Checked before joining: a replaced FIFO would leave the reader waiting for ever.
    assert!(
        std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(),
        "the FIFO was replaced"
    );
    assert_eq!(reader.join().unwrap(), "through the pipe\n");

    let target = dir.join("report.json");
    let link = dir.join("latest.json");
    std::fs::write(&target, "old").unwrap();
    std::os::unix::fs::symlink(&target, &link).unwrap();
    stickslip::report::write_atomic(&link, "new").unwrap();
    assert!(
        std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(),
        "the link was replaced"
    );
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    std::fs::remove_dir_all(&dir).unwrap();
}
