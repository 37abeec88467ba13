//! The documentation cannot point at files that moved: every relative Markdown link in the
//! repository's Markdown (README.md, docs/, data/, tests/, benches/, python/, examples/,
//! tools/) resolves to an existing file or folder, and so does every repository path to Rust
//! source that the prose names (`crates/ode/src/solver.rs`, `src/figure/`, …).

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every Markdown file under `dir`, build output and nested workspaces' targets skipped.
fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy();
        if path.is_dir() {
            if name != "target" && !name.starts_with('.') {
                markdown_files(&path, out);
            }
        } else if name.ends_with(".md") {
            out.push(path);
        }
    }
}

fn all_markdown() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    for dir in ["docs", "data", "tests", "benches", "python", "examples", "tools"] {
        markdown_files(&root().join(dir), &mut files);
    }
    assert!(files.len() > 20, "{files:?}");
    files
}

/// The text outside fenced code blocks and inline code spans, line by line (a span never
/// crosses a line here).
fn prose(markdown: &str) -> Vec<(usize, String)> {
    let mut fenced = false;
    let mut lines = Vec::new();
    for (i, line) in markdown.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            let kept: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
            lines.push((i + 1, kept));
        }
    }
    lines
}

/// The targets of the inline links `[text](target)` and `![alt](target)` on `line`.
fn link_targets(line: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        let end = after.find(')').unwrap_or(after.len());
        targets.push(after[..end].split_whitespace().next().unwrap_or("").to_string());
        rest = &after[end..];
    }
    targets
}

fn is_external(target: &str) -> bool {
    target.is_empty()
        || target.starts_with('#')
        || target.contains("://")
        || target.starts_with("mailto:")
}

#[test]
fn every_relative_markdown_link_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in all_markdown() {
        let text = std::fs::read_to_string(&file).unwrap();
        let dir = file.parent().unwrap();
        for (line_number, line) in prose(&text) {
            for target in link_targets(&line) {
                if is_external(&target) {
                    continue;
                }
                checked += 1;
                let path = target.split('#').next().unwrap();
                if !dir.join(path).exists() {
                    let shown = file.strip_prefix(root()).unwrap().display().to_string();
                    broken.push(format!("{shown}:{line_number}: ({target})"));
                }
            }
        }
    }
    assert!(broken.is_empty(), "links to nothing (fix the path):\n{}", broken.join("\n"));
    assert!(checked > 50, "only {checked} links found: is the parser still finding them?");
}

/// The repository paths to Rust source on `line`: words that start with `src/`, `crates/`,
/// `tests/`, `benches/`, `examples/` or `tools/` (after an optional run of `../`) and end in
/// `.rs` or `/`.
fn source_paths(line: &str) -> Vec<String> {
    let is_path_char = |c: char| c.is_ascii_alphanumeric() || "_-./".contains(c);
    line.split(|c: char| !is_path_char(c))
        .map(|w| w.trim_end_matches('.'))
        .filter(|w| {
            let bare = w.trim_start_matches("../");
            ["src/", "crates/", "tests/", "benches/", "examples/", "tools/"]
                .iter()
                .any(|p| bare.starts_with(p))
                && (w.ends_with(".rs") || w.ends_with('/'))
        })
        .map(str::to_string)
        .collect()
}

#[test]
fn every_source_path_named_in_the_docs_exists() {
    let mut missing = Vec::new();
    let mut checked = 0;
    for file in all_markdown() {
        let text = std::fs::read_to_string(&file).unwrap();
        let dir = file.parent().unwrap();
        // In code spans too: `crates/ode/src/solver.rs` is the usual way to name a file.
        for (line_number, line) in text.lines().enumerate() {
            for path in source_paths(line) {
                checked += 1;
                // Relative to the repository root, or (with ../) to the Markdown file.
                let found = if path.starts_with("../") {
                    dir.join(&path).exists()
                } else {
                    root().join(&path).exists()
                };
                if !found {
                    let shown = file.strip_prefix(root()).unwrap().display().to_string();
                    missing.push(format!("{shown}:{}: {path}", line_number + 1));
                }
            }
        }
    }
    assert!(missing.is_empty(), "paths to nothing (fix the path):\n{}", missing.join("\n"));
    assert!(checked > 50, "only {checked} paths found: is the scan still finding them?");
}
