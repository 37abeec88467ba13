#!/usr/bin/env bash
# The test suite: installs missing Debian packages, checks the style gates (cargo fmt --check,
# clippy with -D warnings over every target, cargo doc with -D warnings; missing_docs is
# warned by Cargo.toml's [lints], so an undocumented public item fails clippy), then runs
# every default test.
set -euo pipefail
cd "$(dirname "$0")/.."
STICKSLIP_WITH_PYTHON=1 bash tools/deps.sh
# Style gates first (seconds when the tree is clean): formatting, lints, the API docs.
cargo fmt --check || { echo "tools/test.sh: run cargo fmt" >&2; exit 1; }
cargo clippy --release --all-targets --quiet -- -D warnings
RUSTDOCFLAGS='-D warnings' cargo doc --no-deps --quiet
cargo test --release "$@"
# The user's examples: the library guide's (docs/library.md), every stiff method on a user's
# system and CVODES' sensitivities against an exact solution, and the README's Rust lines
# (examples/readme.rs, from the repository's root).
cargo run --release --quiet --example own_system
cargo run --release --quiet --example sensitivities
cargo run --release --quiet --example readme
# The work–precision runner (a maintenance tool in tools/work_precision/, docs/README.md;
# docs/work-precision.md) still runs: one small cell, nothing written.
cargo run --release --quiet --example work_precision -- --smoke
# The Python package (docs/python.md): a fresh venv of its own, `pip install ./python` (maturin
# builds the extension against the same SUNDIALS), then its pytest suite (which compares with
# the CLI built above and with scipy) and the examples, headless.
venv="${STICKSLIP_VENV:-${CARGO_TARGET_DIR:-target}/venv}"
rm -rf "$venv"
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --upgrade pip
"$venv/bin/pip" install --quiet ./python pytest scipy numpy matplotlib
"$venv/bin/python" -m pytest -q python/tests
for example in examples/python/*.py; do
    MPLBACKEND=Agg "$venv/bin/python" "$example" "${CARGO_TARGET_DIR:-target}/python-figures"
done
# The instruction-count guard (docs/benchmarks.md): fails if a benchmark case runs more than 3 %
# more instructions than benches/instructions/baseline.txt records (skipped in tools/debian.sh's
# chroot and wherever the toolchain differs from the baseline's).
bash tools/instructions.sh
