//! The README is one screen that leads to the docs, and what it and docs/slurm.md show is
//! what runs: README.md has at most 150 lines, gives the two commands and links the docs index,
//! which names every page in docs/; its Rust and Python lines are, verbatim, part of
//! examples/readme.rs and examples/python/readme.py (which tools/test.sh runs); the Slurm
//! recipe in docs/slurm.md is the two files tools/slurm.sh runs on a real cluster; and the
//! README's sample run has the step and cycle counts that `bash tools/run.sh` prints.

use std::path::Path;

fn read(path: &str) -> String {
    let full = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{}: {e}", full.display()))
}

/// The lines of every fenced code block of `markdown` opened with ```` ```lang ````.
fn fenced_blocks<'a>(markdown: &'a str, lang: &str) -> Vec<Vec<&'a str>> {
    let (mut blocks, mut current): (Vec<Vec<&str>>, Option<Vec<&str>>) = (Vec::new(), None);
    for line in markdown.lines() {
        match current.take() {
            Some(block) if line.trim_start().starts_with("```") => blocks.push(block),
            Some(mut block) => {
                block.push(line);
                current = Some(block);
            }
            None if line.trim() == format!("```{lang}") => current = Some(Vec::new()),
            None => {}
        }
    }
    assert!(current.is_none(), "an unclosed ```{lang} block");
    blocks
}

/// Asserts that `doc` has an indented code block equal to `file`: the block is found by the
/// file's first two lines (both Slurm files start with `#!/bin/bash`).
fn check_indented_block(doc: &str, file: &str) {
    let (markdown, text) = (read(doc), read(file));
    let indented: Vec<String> = text.lines().map(|l| format!("    {l}")).collect();
    let lines: Vec<&str> = markdown.lines().collect();
    let start = lines
        .windows(2)
        .position(|w| w[0] == indented[0] && w[1] == indented[1])
        .unwrap_or_else(|| panic!("{doc} has no code block starting with {file}'s lines"));
    let block: Vec<&str> =
        lines[start..].iter().take_while(|l| l.starts_with("    ")).copied().collect();
    assert_eq!(block, indented, "{doc}'s block differs from {file}: copy the file into it");
}

/// Asserts that README.md has exactly one ```` ```lang ```` block, of at most five lines, and
/// that `file` contains those lines in a row (indentation aside): the file is what runs.
fn check_snippet(lang: &str, file: &str) {
    let readme = read("README.md");
    let blocks = fenced_blocks(&readme, lang);
    assert_eq!(blocks.len(), 1, "README.md should show one ```{lang} block");
    let block = &blocks[0];
    assert!(!block.is_empty() && block.len() <= 5, "README.md's {lang}: 1 to 5 lines, {block:?}");
    let source = read(file);
    let lines: Vec<&str> = source.lines().map(str::trim).collect();
    let wanted: Vec<&str> = block.iter().map(|l| l.trim()).collect();
    assert!(
        lines.windows(wanted.len()).any(|w| w == wanted.as_slice()),
        "README.md's ```{lang} lines are not in {file}, in a row: copy them into it\n{wanted:#?}"
    );
}

#[test]
fn the_readme_is_one_screen_with_the_two_commands_and_the_docs_index() {
    let readme = read("README.md");
    let lines = readme.lines().count();
    assert!(lines <= 150, "README.md has {lines} lines: move details to docs/ (at most 150)");
    for command in ["bash tools/run.sh", "bash tools/test.sh"] {
        assert!(readme.contains(command), "README.md does not give `{command}`");
    }
    assert!(readme.contains("](docs/README.md)"), "README.md does not link docs/README.md");
}

#[test]
fn the_docs_index_names_every_page() {
    let index = read("docs/README.md");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs");
    let mut pages = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.ends_with(".md") && name != "README.md" {
            pages += 1;
            assert!(index.contains(&format!("]({name})")), "docs/README.md does not link {name}");
        }
    }
    assert!(pages >= 20, "only {pages} pages in docs/");
}

#[test]
fn the_readme_rust_lines_are_examples_readme() {
    check_snippet("rust", "examples/readme.rs");
}

#[test]
fn the_readme_python_lines_are_examples_python_readme() {
    check_snippet("python", "examples/python/readme.py");
}

#[test]
fn the_slurm_page_shows_the_batch_script_verbatim() {
    check_indented_block("docs/slurm.md", "tools/slurm-sweep.sbatch");
}

#[test]
fn the_slurm_page_shows_the_submit_script_verbatim() {
    check_indented_block("docs/slurm.md", "tools/slurm-submit.sh");
}

/// The README's "A first run" block: the indented lines after "`bash tools/run.sh` prints".
fn readme_sample_run() -> Vec<String> {
    let readme = read("README.md");
    let lines: Vec<&str> = readme.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.starts_with("`bash tools/run.sh` prints"))
        .expect("README.md introduces its sample run with \"`bash tools/run.sh` prints\"");
    lines[start + 1..]
        .iter()
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| l.starts_with("    "))
        .map(|l| l[4..].to_string())
        .collect()
}

/// The number after `label` in `text` ("… 18023 steps" with label " steps", digits before it;
/// "periodic after 3 cycles" with label "periodic after ", digits after it).
fn count(text: &str, label: &str, before: bool) -> Option<u64> {
    let at = text.find(label)?;
    let digits: String = if before {
        let head: Vec<char> = text[..at].chars().rev().take_while(char::is_ascii_digit).collect();
        head.into_iter().rev().collect()
    } else {
        text[at + label.len()..].chars().take_while(char::is_ascii_digit).collect()
    };
    digits.parse().ok()
}

#[test]
fn the_readme_sample_run_is_what_tools_run_sh_prints() {
    // tools/run.sh is `stickslip run` on the built-in earthquake scene.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("run")
        .output()
        .expect("stickslip runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let real = String::from_utf8(out.stdout).unwrap();
    let sample = readme_sample_run().join("\n");
    let line = |text: &str, start: &str| {
        text.lines().find(|l| l.starts_with(start)).map(str::to_string).unwrap_or_default()
    };
    let (sample_solver, real_solver) = (line(&sample, "solver "), line(&real, "solver "));
    let steps = |l: &str| count(l, " steps", true);
    assert!(steps(&real_solver).is_some(), "no step count in {real_solver:?}");
    assert_eq!(
        steps(&sample_solver),
        steps(&real_solver),
        "README.md's sample run shows another step count: copy `bash tools/run.sh`'s output \
         into it\nREADME: {sample_solver}\nreal:   {real_solver}"
    );
    let (sample_cycle, real_cycle) = (line(&sample, "cycle: "), line(&real, "cycle: "));
    let cycles = |l: &str| count(l, "periodic after ", false);
    assert!(cycles(&real_cycle).is_some(), "no cycle count in {real_cycle:?}");
    assert_eq!(
        cycles(&sample_cycle),
        cycles(&real_cycle),
        "README.md's sample run shows another cycle count: copy `bash tools/run.sh`'s output \
         into it\nREADME: {sample_cycle}\nreal:   {real_cycle}"
    );
}
