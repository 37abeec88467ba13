#!/usr/bin/env bash
# Installs what stickslip needs on Debian 12 or 13, idempotently, also on a minbase system:
# Debian's SUNDIALS (headers and shared libraries; on 13 it pulls in the OpenMPI headers its
# MPI-enabled build needs), libclang (bindgen reads the SUNDIALS headers), a C compiler
# (linking, and the SUN_COMM_NULL shim on 13), pkg-config (finds MPI) and the CA certificates
# cargo needs to download crates; with STICKSLIP_WITH_PYTHON=1 also python3 and python3-venv
# (the Python package's tests). Needs root (or sudo) only when something is missing. Also
# checks for a Rust toolchain.
set -euo pipefail

packages=(libsundials-dev libclang-dev gcc libc6-dev pkg-config ca-certificates)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${STICKSLIP_WITH_VALGRIND:-0}" = 1 ] && ! command -v valgrind >/dev/null; then
    missing+=(valgrind)
fi
# The Python package's tests (tools/test.sh): Debian's python3 with venv (pip comes with it).
if [ "${STICKSLIP_WITH_PYTHON:-0}" = 1 ]; then
    for p in python3 python3-venv; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
fi

if [ ${#missing[@]} -gt 0 ]; then
    echo "stickslip: installing Debian packages: ${missing[*]}" >&2
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null; then
    echo "stickslip: no Rust toolchain (cargo) on PATH; install one with rustup (https://rustup.rs)" >&2
    exit 1
fi
for tool in fmt clippy; do
    cargo "$tool" --version >/dev/null 2>&1 || {
        echo "stickslip: cargo $tool is missing (the test command runs it); install it with: rustup component add ${tool/fmt/rustfmt}" >&2
        exit 1
    }
done
