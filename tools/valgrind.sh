#!/usr/bin/env bash
# Runs the SUNDIALS wrapper tests under valgrind memcheck; fails if any bytes are definitely
# (or indirectly) lost or memory errors occur.
set -euo pipefail
cd "$(dirname "$0")/.."
STICKSLIP_WITH_VALGRIND=1 bash tools/deps.sh
status=0
for test in wrappers sundials_examples cvodes_sensitivities; do
    binary=$(cargo test -p stickslip-ode --test "$test" --no-run --message-format=json 2>/dev/null \
        | grep '"kind":\["test"\]' | grep -o '"executable":"[^"]*"' | tail -n 1 | cut -d'"' -f4)
    [ -n "$binary" ] || { echo "valgrind.sh: no test binary for $test" >&2; exit 1; }
    echo "== valgrind memcheck: $test ($binary)"
    valgrind --quiet --leak-check=full --show-leak-kinds=definite,indirect \
        --errors-for-leak-kinds=definite,indirect --error-exitcode=3 \
        "$binary" --test-threads=1 -q || status=$?
done
exit $status
