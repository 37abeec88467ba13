#!/usr/bin/env bash
# The Slurm recipe of docs/slurm.md on a real (one-node) Slurm cluster: installs Debian's
# slurm-wlm and munge when missing, starts munged, slurmctld and slurmd on localhost with a generated
# munge key and a minimal slurm.conf in a temporary directory (no systemd), submits the
# files tools/slurm-sweep.sbatch (a job array of 4 `sweep --shard` tasks) and
# tools/slurm-submit.sh (the array, then `merge --total` once every task succeeded) from a
# directory holding the earthquake scene as scene.json, and compares the merged rows with an
# unsharded sweep of the same grid, row for row. Exits non-zero on any difference or failure;
# stops the daemons it started (trap on exit). Needs root (daemons, apt-get).
#
#   usage: bash tools/slurm.sh            (about 30 s on 2 cores, after the build)
#
# Environment: STICKSLIP_SLURM_KEEP=1 keeps the temporary directory (logs, conf, rows).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
cd "$repo"
[ "$(id -u)" -eq 0 ] || { echo "tools/slurm.sh: needs root (it starts munged, slurmctld, slurmd)" >&2; exit 2; }

start=$(date +%s)
stamp() { echo "[$(( $(date +%s) - start )) s] $*" >&2; }

# Debian's packages, when missing (as tools/deps.sh does for the build).
bash tools/deps.sh
missing=()
for p in slurm-wlm munge; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    stamp "installing Debian packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    # policy-rc.d 101: the packages' maintainer scripts must not start their own daemons.
    policy=/usr/sbin/policy-rc.d
    had_policy=0
    [ -e "$policy" ] && had_policy=1
    [ $had_policy = 1 ] || { printf '#!/bin/sh\nexit 101\n' > "$policy"; chmod +x "$policy"; }
    status=0
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null || status=$?
    [ $had_policy = 1 ] || rm -f "$policy"
    [ $status -eq 0 ] || exit $status
fi

stamp "cargo build --release"
cargo build --release --quiet
export PATH="$repo/target/release:$PATH"

dir=$(mktemp -d /tmp/stickslip-slurm.XXXXXX)
chmod 755 "$dir"  # munged wants its socket reachable by every user
pids=()
cleanup() {
    local status=$?
    for (( i=${#pids[@]}-1; i>=0; i-- )); do
        kill "${pids[i]}" 2>/dev/null || true
    done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
    done
    if [ $status -ne 0 ]; then
        for log in "$dir"/*.log "$dir"/work/*.log; do
            [ -s "$log" ] && { echo "== $log (last lines)" >&2; tail -n 15 "$log" >&2; }
        done
    fi
    if [ "${STICKSLIP_SLURM_KEEP:-0}" = 1 ]; then echo "kept $dir" >&2; else rm -rf "$dir"; fi
    exit $status
}
trap cleanup EXIT

# A free TCP port at or above $1 (the cluster must not meet another Slurm on this machine).
free_port() {
    local port=$1
    while (echo > "/dev/tcp/127.0.0.1/$port") 2>/dev/null; do port=$((port + 1)); done
    echo "$port"
}
# Waits up to $1 seconds for the command "${@:2}" to succeed.
wait_for() {
    local seconds=$1
    shift
    for _ in $(seq $((seconds * 10))); do "$@" >/dev/null 2>&1 && return 0; sleep 0.1; done
    echo "tools/slurm.sh: timed out after $seconds s waiting for: $*" >&2
    return 1
}

stamp "munged (generated key) in $dir"
mkdir -p "$dir/munge" "$dir/munge-key" "$dir/spool/ctld" "$dir/spool/d" "$dir/work"
chmod 755 "$dir/munge"
chmod 700 "$dir/munge-key"
dd if=/dev/urandom of="$dir/munge-key/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge-key/munge.key"
socket="$dir/munge/munge.socket"
munged --force --key-file="$dir/munge-key/munge.key" --socket="$socket" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/munged.log" \
    --seed-file="$dir/munge-key/munged.seed"
wait_for 10 test -s "$dir/munge/munged.pid"
pids+=("$(cat "$dir/munge/munged.pid")")
wait_for 10 munge --socket="$socket" -n

node=$(hostname -s)
cpus=$(nproc)
ctld_port=$(free_port 16817)
slurmd_port=$(free_port $((ctld_port + 1)))
export SLURM_CONF="$dir/slurm.conf"
cat > "$SLURM_CONF" <<EOF
# A one-node cluster for tools/slurm.sh: no accounting, no cgroups, no systemd.
ClusterName=stickslip
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/spool/ctld
SlurmdSpoolDir=$dir/spool/d
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerParameters=kill_invalid_depend
ReturnToService=2
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF

stamp "slurmctld and slurmd (ports $ctld_port, $slurmd_port)"
slurmctld -D -i -f "$SLURM_CONF" > "$dir/slurmctld.out" 2>&1 &
pids+=($!)
wait_for 30 scontrol ping
slurmd -D -f "$SLURM_CONF" -N "$node" > "$dir/slurmd.out" 2>&1 &
pids+=($!)
node_idle() { sinfo -h -n "$node" -o %T | grep -qx idle; }
wait_for 60 node_idle

# The recipe, as docs/slurm.md shows it, from a directory holding scene.json.
work="$dir/work"
cp tools/slurm-sweep.sbatch tools/slurm-submit.sh "$work/"
cp data/scenes/earthquake.json "$work/scene.json"
stamp "bash slurm-submit.sh (the job array of 4 shards, then the merge)"
(cd "$work" && timeout 300 bash slurm-submit.sh)
[ -s "$work/all.jsonl" ] || { echo "tools/slurm.sh: the merge wrote no all.jsonl" >&2; exit 1; }

# The same grid in one unsharded sweep, outside Slurm.
param=$(grep -o -- '--param [^ ]*' tools/slurm-sweep.sbatch | cut -d' ' -f2)
total=$(grep -o -- '--total [0-9]*' tools/slurm-submit.sh | cut -d' ' -f2)
stamp "unsharded sweep --param $param (reference)"
(cd "$work" && stickslip sweep scene.json --param "$param" --out unsharded.jsonl >/dev/null)
# Rows are in completion order; sort them by index (each line starts {"index":N,).
sort -t: -k2,2n "$work/unsharded.jsonl" > "$work/unsharded-sorted.jsonl"

rows=$(wc -l < "$work/all.jsonl")
reference=$(wc -l < "$work/unsharded-sorted.jsonl")
differ=$( (diff "$work/all.jsonl" "$work/unsharded-sorted.jsonl" || true) | grep -c '^<' || true)
echo "slurm: $rows merged rows from 4 array tasks, $reference unsharded rows (--total $total), $differ rows differ"
if [ "$rows" -ne "$total" ] || [ "$reference" -ne "$total" ] || [ "$differ" -ne 0 ]; then
    diff "$work/all.jsonl" "$work/unsharded-sorted.jsonl" | head -c 2000 >&2 || true
    echo "tools/slurm.sh: FAILED: the merged rows differ from the unsharded sweep" >&2
    exit 1
fi
stamp "done: merged rows equal the unsharded sweep's, row for row"
