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
# The instruction-count guard (docs/benchmarks.md): fails if a benchmark case runs more than 3 %
# more instructions than benches/instructions/baseline.txt records (skipped in tools/debian.sh's
# chroot and wherever the toolchain differs from the baseline's).
bash tools/instructions.sh
