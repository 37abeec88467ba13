#!/usr/bin/env bash
# The instruction-count guard (docs/benchmarks.md, "Instruction counts"): counts the
# instructions of fixed runs under valgrind (cachegrind, no cache simulation: the "I refs"
# total, the same on every run of the same binary) and compares each with
# benches/instructions/baseline.txt.
#
#   bash tools/instructions.sh                    # check: fail if a case > 1.03 × its baseline
#   bash tools/instructions.sh --update "reason"  # measure and rewrite the baseline, appending
#                                                 # the one-line reason to its history
#   bash tools/instructions.sh --case NAME        # check one case only
#
# The check fails (exit 1) when a case's count exceeds 1.03 × its baseline, when a case has no
# baseline, or when the baseline file lacks a reason line for its last update. A commit that
# makes a case slower on purpose therefore updates the baseline in the same commit, with its
# reason (--update refuses an empty one). Counts depend on the toolchain and libm, so the
# baseline records rustc, glibc and valgrind; on another combination the check says so and
# skips (regenerate the baseline there). STICKSLIP_INSTRUCTION_GUARD=0 skips it too (the
# Debian 13 chroot of tools/debian.sh sets it).
set -euo pipefail
cd "$(dirname "$0")/.."

baseline=benches/instructions/baseline.txt
limit=1.03
mode=check
reason=""
only=""
case "${1:-}" in
    --update)
        mode=update
        reason="${2:-}"
        if [ -z "${reason// /}" ]; then
            echo "instructions.sh: --update needs a one-line reason, e.g. --update \"noise: stage solves unrefined (issue #30)\"" >&2
            exit 2
        fi
        case "$reason" in *$'\n'*) echo "instructions.sh: the reason must be one line" >&2; exit 2;; esac
        ;;
    --case) only="${2:-}" ;;
    "") ;;
    *) echo "instructions.sh: unknown argument '$1' (give nothing, --update \"reason\" or --case NAME)" >&2; exit 2 ;;
esac

if [ "${STICKSLIP_INSTRUCTION_GUARD:-1}" = 0 ]; then
    echo "instructions.sh: skipped (STICKSLIP_INSTRUCTION_GUARD=0)"
    exit 0
fi
if ! command -v valgrind >/dev/null; then
    STICKSLIP_WITH_VALGRIND=1 bash tools/deps.sh
fi

environment="rustc $(rustc --version | cut -d' ' -f2), glibc $(ldd --version | head -n1 | awk '{print $NF}'), $(valgrind --version)"
if [ "$mode" = check ]; then
    [ -f "$baseline" ] || { echo "instructions.sh: no $baseline; create it with --update \"reason\"" >&2; exit 1; }
    recorded=$(sed -n 's/^# environment: //p' "$baseline")
    if [ "$recorded" != "$environment" ]; then
        echo "instructions.sh: skipped: the baseline was measured with '$recorded', this host has '$environment' (counts are not comparable; regenerate the baseline on this host with --update)"
        exit 0
    fi
    last=$(grep '^# update ' "$baseline" | tail -n 1 || true)
    if ! [[ "$last" =~ ^#\ update\ [^:]+:\ *[^[:space:]].* ]]; then
        echo "instructions.sh: FAIL: $baseline has no reason line ('# update <date> <commit>: <reason>') for its last update" >&2
        exit 1
    fi
fi

cargo build --release --quiet --bin stickslip --example instructions
bin=${CARGO_TARGET_DIR:-target}/release/stickslip
ex=${CARGO_TARGET_DIR:-target}/release/examples/instructions
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# name | command (run from the repository root; one thread wherever threads are chosen)
cases=(
    "earthquake|$bin run data/scenes/earthquake.json --out $out/report.json"
    "earthquake-radau5|$bin run benches/instructions/earthquake-radau5.json --out $out/report.json"
    "fig1c-short|$bin run benches/instructions/fig1c-short.json --out $out/report.json"
    "noise-drr-20|$bin run benches/instructions/noise-drr-20.json --threads 1 --out $out/report.json"
    "quasi-dynamic|$bin run data/scenes/quasi-dynamic.json --out $out/report.json"
    "hires-radau5|$ex hires-radau5"
    "hires-rodas5p|$ex hires-rodas5p"
    "orego-radau5|$ex orego-radau5"
    "orego-rodas5p|$ex orego-rodas5p"
)

# Instructions of one command (valgrind's "I refs" total).
count() {
    local log="$out/valgrind.log"
    if ! valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null $1 >"$out/stdout" 2>"$log"; then
        echo "instructions.sh: the case failed: $1" >&2
        cat "$out/stdout" "$log" >&2
        exit 1
    fi
    sed -n 's/.*I *refs: *//p' "$log" | tr -d ','
}

if [ -n "$only" ] && ! printf '%s\n' "${cases[@]}" | grep -q "^$only|"; then
    echo "instructions.sh: unknown case '$only'" >&2
    exit 2
fi
status=0
lines=()
for entry in "${cases[@]}"; do
    name=${entry%%|*}
    command=${entry#*|}
    [ -n "$only" ] && [ "$name" != "$only" ] && continue
    n=$(count "$command")
    lines+=("$name $n")
    if [ "$mode" = check ]; then
        base=$(awk -v c="$name" '$1 == c { print $2 }' "$baseline")
        if [ -z "$base" ]; then
            echo "FAIL $name: $n instructions, no baseline (add it with --update \"reason\")"
            status=1
            continue
        fi
        verdict=$(awk -v n="$n" -v b="$base" -v l="$limit" 'BEGIN {
            r = n / b; printf "%s %.4f", (n > l * b) ? "FAIL" : "ok", r }')
        read -r word ratio <<<"$verdict"
        if [ "$word" = FAIL ]; then
            echo "FAIL $name: $n instructions, $ratio × the baseline $base (limit $limit): a slowdown; if it is meant, update the baseline in the same commit: bash tools/instructions.sh --update \"<reason>\""
            status=1
        else
            echo "ok   $name: $n instructions, $ratio × the baseline $base"
        fi
    else
        echo "$name $n"
    fi
done

if [ "$mode" = update ]; then
    history=""
    [ -f "$baseline" ] && history=$(grep '^# update ' "$baseline" || true)
    commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
    {
        echo "# Instruction counts of tools/instructions.sh's cases (valgrind cachegrind, I refs)."
        echo "# The check fails when a case exceeds $limit × its count here. Regenerate with"
        echo "# bash tools/instructions.sh --update \"<one-line reason>\" (docs/benchmarks.md)."
        echo "# environment: $environment"
        [ -n "$history" ] && echo "$history"
        echo "# update $(date -u +%Y-%m-%d) $commit: $reason"
        printf '%s\n' "${lines[@]}"
    } >"$baseline.new"
    mv "$baseline.new" "$baseline"
    echo "instructions.sh: wrote $baseline"
fi
exit $status
