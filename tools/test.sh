#!/usr/bin/env bash
# The test suite: installs missing Debian packages, then runs every default test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/deps.sh
cargo test --release "$@"
