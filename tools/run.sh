#!/usr/bin/env bash
# The main job: installs missing Debian packages, builds stickslip in release mode and runs it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/deps.sh
cargo run --release --quiet -- run "$@"
