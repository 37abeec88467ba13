#!/usr/bin/env bash
# Checks a Debian release from scratch, as a new user would: builds a clean minbase root
# filesystem with debootstrap, clones this repository's HEAD into it, runs the README's two
# commands (tools/run.sh, tools/test.sh) inside, and reports the linked SUNDIALS version, the
# earthquake period and step count, the test summary (cargo and the Python package's pytest,
# which tools/test.sh runs in a fresh venv with Debian's python3), the earthquake period as
# `import stickslip` prints it, and ldd of the binary.
#
#   usage (as root): bash tools/debian.sh 12|13 [ROOTFS_DIR]
#
# ROOTFS_DIR defaults to /var/tmp/stickslip-debian-<codename>; an existing one made by this
# script is deleted first. The host's Rust toolchain (~/.cargo, ~/.rustup) is bind-mounted.
# Output: the full logs in ROOTFS_DIR/check/, the summary on stdout. Exit status: that of the
# first failing command.
set -euo pipefail

case "${1:-}" in
    12) codename=bookworm ;;
    13) codename=trixie ;;
    *) echo "usage: bash tools/debian.sh 12|13 [ROOTFS_DIR]" >&2; exit 2 ;;
esac
[ "$(id -u)" -eq 0 ] || { echo "tools/debian.sh: needs root (debootstrap, chroot, mounts)" >&2; exit 2; }
repo="$(cd "$(dirname "$0")/.." && pwd)"
root="${2:-/var/tmp/stickslip-debian-$codename}"
mirror="${DEBIAN_MIRROR:-http://deb.debian.org/debian}"
cargo_home="${CARGO_HOME:-$HOME/.cargo}"
rustup_home="${RUSTUP_HOME:-$HOME/.rustup}"
[ -x "$cargo_home/bin/cargo" ] || { echo "tools/debian.sh: no Rust toolchain in $cargo_home (install one with rustup)" >&2; exit 2; }

start=$(date +%s)
stamp() { echo "[$(( $(date +%s) - start )) s] $*" >&2; }

if [ -e "$root" ]; then
    [ -f "$root/.stickslip-debian-check" ] || { echo "tools/debian.sh: $root exists and was not made by this script" >&2; exit 2; }
    if grep -q " $root/" /proc/mounts; then echo "tools/debian.sh: something is still mounted under $root" >&2; exit 2; fi
    rm -rf "$root"
fi
command -v debootstrap >/dev/null || { stamp "installing debootstrap"; apt-get install -y -qq debootstrap >/dev/null; }

stamp "debootstrap --variant=minbase $codename $root"
mkdir -p "$root"
touch "$root/.stickslip-debian-check"
debootstrap --variant=minbase "$codename" "$root" "$mirror" > "$root.debootstrap.log" 2>&1 \
    || { tail -20 "$root.debootstrap.log" >&2; exit 1; }
mv "$root.debootstrap.log" "$root/debootstrap.log"
cp /etc/resolv.conf "$root/etc/resolv.conf"
# The host's network setup comes along: its resolver above and the local CA certificates it
# trusts (a TLS-inspecting proxy's, where there is one), which ca-certificates adds to the
# chroot's bundle; pip inside is pointed at that bundle (PIP_CERT below).
if compgen -G "/usr/local/share/ca-certificates/*.crt" >/dev/null; then
    mkdir -p "$root/usr/local/share/ca-certificates"
    cp /usr/local/share/ca-certificates/*.crt "$root/usr/local/share/ca-certificates/"
fi

stamp "cloning HEAD of $repo"
git clone --quiet --no-hardlinks "$repo" "$root/src/stickslip"
git -C "$root/src/stickslip" log --oneline -1 >&2

mounted=()
cleanup() {
    for (( i=${#mounted[@]}-1; i>=0; i-- )); do umount "${mounted[i]}" || umount -l "${mounted[i]}"; done
}
trap cleanup EXIT
bind() {
    mkdir -p "$root$2"
    mount --bind "$1" "$root$2"
    mounted+=("$root$2")
}
bind /proc /proc
bind /sys /sys
bind /dev /dev
bind /dev/pts /dev/pts
bind "$cargo_home" /opt/cargo
bind "$rustup_home" /opt/rustup

mkdir -p "$root/check"
inside() {
    chroot "$root" /usr/bin/env -i HOME=/root PATH=/opt/cargo/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
        CARGO_HOME=/opt/cargo RUSTUP_HOME=/opt/rustup CARGO_TARGET_DIR=/root/target LANG=C.UTF-8 STICKSLIP_INSTRUCTION_GUARD=0 \
        PIP_CERT=/etc/ssl/certs/ca-certificates.crt \
        /bin/bash -c "cd /src/stickslip && $1"
}

stamp "bash tools/run.sh (installs the Debian packages, builds, runs the earthquake scene)"
status=0
inside "bash tools/run.sh" > "$root/check/run.log" 2> "$root/check/run.err" || status=$?
stamp "bash tools/test.sh"
if [ $status -eq 0 ]; then
    # ca-certificates (installed by tools/run.sh) bundles the copied local certificates.
    inside "update-ca-certificates" > "$root/check/ca.log" 2>&1 || status=$?
fi
if [ $status -eq 0 ]; then
    inside "bash tools/test.sh" > "$root/check/test.log" 2>&1 || status=$?
fi
stamp "done (status $status)"

echo "== Debian $1 ($codename), $(( $(date +%s) - start )) s in all; logs in $root/check/"
if [ -s "$root/check/run.log" ]; then
    inside "/root/target/release/stickslip version" || true
    grep -E "^solver|^  period" "$root/check/run.log" || true
fi
[ -s "$root/check/test.log" ] && {
    passed=$(grep -Eo "test result: [a-zA-Z]+\. [0-9]+ passed; [0-9]+ failed; [0-9]+ ignored" "$root/check/test.log" |
        awk '{p+=$4; f+=$6; i+=$8} END {print p " passed, " f " failed, " i " ignored in " NR " test binaries"}')
    echo "tests: $passed"
    grep -E "^test .* FAILED|^failures:" "$root/check/test.log" || true
    echo "python tests (pytest): $(grep -E "^[0-9]+ (passed|failed)|^=+ .*(passed|failed)" "$root/check/test.log" | tail -1)"
}
if [ -x "$root/root/target/venv/bin/python" ]; then
    echo "python: $(inside "/root/target/venv/bin/python --version") prints the earthquake period" \
        "$(inside "/root/target/venv/bin/python -c \"import stickslip; print(stickslip.run('data/scenes/earthquake.json')['cycle']['period'])\"" || true)"
fi
if [ -x "$root/root/target/release/stickslip" ]; then
    echo "ldd target/release/stickslip | grep -E 'sundials|mpi':"
    inside "ldd /root/target/release/stickslip" | grep -E "sundials|libmpi" || true
fi
[ $status -eq 0 ] || { echo "FAILED (status $status); last lines:"; tail -30 "$root/check/run.err" "$root/check/test.log" 2>/dev/null; }
exit $status
