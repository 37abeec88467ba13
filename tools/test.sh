#!/usr/bin/env bash
# The test suite: installs missing Debian packages, then runs every default test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/deps.sh
cargo test --release "$@"
# The library guide's example (docs/library.md): every stiff method on a user's system.
cargo run --release --quiet --example own_system
