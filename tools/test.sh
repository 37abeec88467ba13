#!/usr/bin/env bash
# The test suite: installs missing Debian packages, then runs every default test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/deps.sh
cargo test --release "$@"
# The library guide's example (docs/library.md): every stiff method on a user's system.
cargo run --release --quiet --example own_system
# The work–precision runner (docs/work-precision.md) still runs: one small cell, nothing written.
cargo run --release --quiet --example work_precision -- --smoke
