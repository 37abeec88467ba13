#!/usr/bin/env bash
# The test suite: installs missing Debian packages, then runs every default test.
set -euo pipefail
cd "$(dirname "$0")/.."
STICKSLIP_WITH_PYTHON=1 bash tools/deps.sh
cargo test --release "$@"
# The library guide's example (docs/library.md): every stiff method on a user's system.
cargo run --release --quiet --example own_system
# The work–precision runner (docs/work-precision.md) still runs: one small cell, nothing written.
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
