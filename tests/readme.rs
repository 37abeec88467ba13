//! The README's Slurm recipe is the one tools/slurm.sh runs: two of its code blocks are the
//! files tools/slurm-sweep.sbatch and tools/slurm-submit.sh, verbatim (indented by four
//! spaces).

/// Asserts that README.md has an indented code block equal to `file`: the block is found by
/// the file's first two lines (both files start with `#!/bin/bash`).
fn check(file: &str) {
    let root = env!("CARGO_MANIFEST_DIR");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    let text = std::fs::read_to_string(format!("{root}/{file}")).unwrap();
    let indented: Vec<String> = text.lines().map(|l| format!("    {l}")).collect();
    let lines: Vec<&str> = readme.lines().collect();
    let start = lines
        .windows(2)
        .position(|w| w[0] == indented[0] && w[1] == indented[1])
        .unwrap_or_else(|| panic!("README.md has no code block starting with {file}'s lines"));
    let block: Vec<&str> =
        lines[start..].iter().take_while(|l| l.starts_with("    ")).copied().collect();
    assert_eq!(block, indented, "README.md's block differs from {file}: copy the file into it");
}

#[test]
fn the_readme_shows_the_slurm_batch_script_verbatim() {
    check("tools/slurm-sweep.sbatch");
}

#[test]
fn the_readme_shows_the_slurm_submit_script_verbatim() {
    check("tools/slurm-submit.sh");
}
