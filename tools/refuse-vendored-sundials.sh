#!/usr/bin/env bash
# Stands in for `cmake` during the build (see .cargo/config.toml): sundials-sys falls back to
# building its vendored SUNDIALS with cmake when it cannot use the system one. stickslip never
# uses a vendored SUNDIALS, so that fallback must fail, loudly and with the fix.
cat >&2 <<'MSG'

stickslip build: the system SUNDIALS was not usable, so sundials-sys tried to build its
vendored copy. stickslip links Debian's SUNDIALS only.
  fix: apt-get install -y libsundials-dev libclang-dev   (or: bash tools/deps.sh)

MSG
exit 1
