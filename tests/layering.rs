//! Layering inside each crate. Cargo's dependency graph enforces the arrows between the
//! workspace's crates (stickslip-ode → stickslip → the `stickslip` command and python/); this
//! test guards what Cargo cannot: inside one crate, every top-level module of its src/ may use
//! only the modules listed for it below, and the graph has no cycle. A new `crate::…` path that
//! crosses a layer fails here, naming the file and the line.
//!
//! The graph is read from the source text: every `crate::name` and `crate::{a, b}` outside
//! comments, in each file of a top-level module (src/name.rs or src/name/).

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// A crate's modules, each with the modules it may use.
type Table = &'static [(&'static str, &'static [&'static str])];

/// What each top-level module may use, per crate (its src/ folder from the workspace root), in
/// the order of the data flow (scene → model → integrator → analysis → report/figure). A
/// module missing here fails the test: place it.
const CRATES: &[(&str, Table)] = &[
    (
        "crates/ode/src",
        &[
            // The methods' names and dense-output orders, which the integrators report.
            ("method", &[]),
            ("integrate", &["method"]),
            ("sundials", &["integrate", "method"]),
            ("solver", &["integrate", "method", "sundials"]),
            // SUNDIALS' Robertson problem and its examples replayed through the wrappers.
            ("robertson", &["integrate", "sundials"]),
        ],
    ),
    (
        // integrate and sundials are stickslip-ode's, re-exported at the crate root; solver
        // re-exports stickslip-ode's and adds a scene's solver settings.
        "crates/stickslip/src",
        &[
            ("parallel", &[]),
            ("solver", &[]),
            ("model", &["integrate"]),
            // The numerics the analyses share (events, finite checks, fits, figure series).
            ("numerics", &["integrate"]),
            ("analysis", &["integrate", "model", "numerics", "parallel", "solver", "sundials"]),
            // The paper's claims tested: its quoted values, asymptotics and lyapunov.
            ("paper", &["analysis", "integrate", "model", "numerics", "solver", "sundials"]),
            ("scene", &["analysis", "model", "numerics", "paper", "solver", "sundials"]),
            ("report", &["analysis", "integrate", "model", "numerics", "paper", "scene"]),
            // The time-series files (CSV, .npy, QDYN's output files): sinks for the analysis's
            // rows, an output layer; QDYN's files take their physical units from the scene.
            ("series_file", &["analysis", "model", "scene"]),
            (
                "engine",
                &[
                    "analysis",
                    "integrate",
                    "model",
                    "numerics",
                    "paper",
                    "report",
                    "scene",
                    "series_file",
                    "solver",
                    "sundials",
                ],
            ),
            ("compare", &["engine", "integrate", "model", "report", "scene"]),
            ("sweep", &["analysis", "engine", "parallel", "report", "scene"]),
        ],
    ),
    (
        "src",
        &[
            ("figure", &[]),
            ("stress", &[]),
            ("reproduce", &["figure"]),
            ("cli", &["figure", "reproduce", "stress"]),
        ],
    ),
];

/// The Rust files of a top-level module.
fn files_of(src: &Path, module: &str) -> Vec<PathBuf> {
    let file = src.join(format!("{module}.rs"));
    let mut out = if file.is_file() { vec![file] } else { Vec::new() };
    let mut dirs = vec![src.join(module)];
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = fs::read_dir(&dir) else { continue };
        for path in entries.map(|e| e.expect("a readable src/ entry").path()) {
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The top-level modules named by `crate::` paths on one line of code (comments removed).
fn crate_paths(line: &str) -> Vec<String> {
    let code = line.split("//").next().unwrap_or("");
    let ident = |s: &str| {
        s.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect::<String>()
    };
    let mut out = Vec::new();
    for (i, _) in code.match_indices("crate::") {
        if code[..i].ends_with('$')
            || code[..i].ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_')
        {
            continue;
        }
        let rest = &code[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let inner = group.split('}').next().unwrap_or("");
            out.extend(inner.split(',').map(|p| ident(p.trim())).filter(|p| !p.is_empty()));
        } else {
            out.push(ident(rest));
        }
    }
    out
}

/// Module → (used module → the first place it is used).
fn graph(src: &Path) -> BTreeMap<String, BTreeMap<String, String>> {
    let mut modules: Vec<String> = fs::read_dir(src)
        .expect("src/ is readable")
        .map(|e| e.expect("a readable src/ entry").path())
        .filter(|p| p.is_dir() || p.extension().is_some_and(|e| e == "rs"))
        .map(|p| p.file_stem().expect("a file name").to_string_lossy().into_owned())
        .filter(|m| m != "lib" && m != "main")
        .collect();
    modules.sort();
    modules.dedup();
    let mut out = BTreeMap::new();
    for module in modules {
        let mut uses = BTreeMap::new();
        for file in files_of(src, &module) {
            let text = fs::read_to_string(&file).expect("a readable source file");
            for (n, line) in text.lines().enumerate() {
                for used in crate_paths(line) {
                    if used != module {
                        uses.entry(used).or_insert_with(|| {
                            format!(
                                "{}:{}",
                                file.strip_prefix(src.parent().unwrap_or(src))
                                    .unwrap_or(&file)
                                    .display(),
                                n + 1
                            )
                        });
                    }
                }
            }
        }
        out.insert(module, uses);
    }
    out
}

/// Every crate's src/ folder with its table.
fn crates() -> impl Iterator<Item = (PathBuf, Table)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    CRATES.iter().map(move |(dir, table)| (root.join(dir), *table))
}

#[test]
fn crate_paths_are_read_from_code_only() {
    assert_eq!(crate_paths("use crate::integrate::{Options, Stats};"), ["integrate"]);
    assert_eq!(crate_paths("use crate::{engine, parallel};"), ["engine", "parallel"]);
    assert_eq!(crate_paths("    let x = crate::model::drr::W; // crate::engine"), ["model"]);
    assert!(crate_paths("/// see [`crate::engine::run`]").is_empty());
    assert!(crate_paths("$crate::foo!()").is_empty());
    assert!(crate_paths("use stickslip::engine;").is_empty());
}

#[test]
fn every_module_uses_only_the_layers_before_it() {
    let mut errors = Vec::new();
    for (src, table) in crates() {
        let allowed: BTreeMap<&str, BTreeSet<&str>> =
            table.iter().map(|(m, a)| (*m, a.iter().copied().collect())).collect();
        for (module, uses) in graph(&src) {
            let Some(ok) = allowed.get(module.as_str()) else {
                errors.push(format!("{}/{module}: a new top-level module; add it to tests/layering.rs's CRATES at its place in the data flow", src.display()));
                continue;
            };
            for (used, place) in uses {
                if !ok.contains(used.as_str()) {
                    errors.push(format!(
                        "{place}: `{module}` uses `crate::{used}`, which its layer may not"
                    ));
                }
            }
        }
    }
    assert!(errors.is_empty(), "layering broken:\n{}", errors.join("\n"));
}

#[test]
fn analyses_never_import_scene_engine_or_report() {
    let library = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/stickslip/src");
    let uses = &graph(&library)["analysis"];
    for forbidden in ["engine", "scene", "report"] {
        assert!(
            !uses.contains_key(forbidden),
            "{}: analysis imports crate::{forbidden}",
            uses[forbidden]
        );
    }
}

#[test]
fn the_module_graph_has_no_cycle() {
    // Depth-first search with colours: a grey node met again closes a cycle.
    fn visit<'a>(
        g: &'a BTreeMap<String, BTreeMap<String, String>>,
        m: &'a str,
        grey: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
    ) -> Result<(), String> {
        if done.contains(m) {
            return Ok(());
        }
        if let Some(i) = grey.iter().position(|&x| x == m) {
            return Err(format!("{} → {m}", grey[i..].join(" → ")));
        }
        grey.push(m);
        for used in g.get(m).map(|u| u.keys()).into_iter().flatten() {
            visit(g, used, grey, done)?;
        }
        grey.pop();
        done.insert(m);
        Ok(())
    }
    for (src, _) in crates() {
        let g = graph(&src);
        let mut done = BTreeSet::new();
        for m in g.keys() {
            if let Err(cycle) = visit(&g, m, &mut Vec::new(), &mut done) {
                panic!("{}: the module graph has a cycle: {cycle}", src.display());
            }
        }
    }
}
