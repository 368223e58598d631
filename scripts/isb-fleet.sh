#!/usr/bin/env bash
# The IMX-5 navigation figures of docs/performance.md ("Navigation
# filter"): a fleet of N IMX-5 units in real time with every navigation
# stream on, and one unit at --speed max; the release `imu-emu` served
# to boards/host/examples/isb_navload.rs, which checks every nav-period
# packet's own time field (a step of exactly 4 ms, none missed, none
# repeated) and reads the emulator's own drop counts over its control
# socket. Prints one line a run and the machine's load before and after.
#
#   scripts/isb-fleet.sh                  # 50 units, 30 s, then --speed max 10 s
#   COUNT=50 SECS=60 RUNS=3 scripts/isb-fleet.sh
#   PIN=1 scripts/isb-fleet.sh            # emulator on CPU 0, client on CPU 1
#   MAX=0 scripts/isb-fleet.sh            # the fleet only
#
# Uses CARGO_TARGET_DIR if set. The emulator and the client each take most
# of a core at --speed max: state the machine's load with the figures.
set -euo pipefail
cd "$(dirname "$0")/.."
target=${CARGO_TARGET_DIR:-target}
count=${COUNT:-50}
secs=${SECS:-30}
runs=${RUNS:-1}
max_secs=${MAX_SECS:-10}
log=$(mktemp -d)
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$log"' EXIT

cargo build -q --release -p imu-emu-host --bin imu-emu --example isb_navload
emu=$target/release/imu-emu
client=$target/release/examples/isb_navload
emu_pin=()
client_pin=()
if [ "${PIN:-0}" = 1 ]; then
    emu_pin=(taskset -c 0)
    client_pin=(taskset -c 1)
fi

# Starts `imu-emu --protocol isb` with N units and the given options; sets
# $pid, $addrs (every unit's address, comma-separated) and $control.
start() {
    local n=$1
    shift
    "${emu_pin[@]}" "$emu" --protocol isb --count "$n" --tcp 127.0.0.1:0 \
        --control 127.0.0.1:0 --gps-time 2026-03-13T15:27:00Z "$@" \
        >"$log/emu.out" 2>"$log/emu.err" &
    pid=$!
    for _ in $(seq 100); do
        if grep -q '^control on tcp' "$log/emu.out"; then
            addrs=$(grep '^listening on tcp' "$log/emu.out" | grep -o '127\.0\.0\.1:[0-9]*' | paste -sd,)
            control=$(grep '^control on tcp' "$log/emu.out" | grep -o '127\.0\.0\.1:[0-9]*')
            return
        fi
        sleep 0.1
    done
    echo "imu-emu did not start" >&2
    exit 1
}

stop() {
    kill "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
    pid=
}

echo "commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src boards || echo ' (with local changes)'); $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
for r in $(seq "$runs"); do
    echo "fleet $r: load before: $(cut -d' ' -f1-3 /proc/loadavg)"
    start "$count"
    "${client_pin[@]}" "$client" "$addrs" "$secs" --pid "$pid" --control "$control" --list 20
    stop
    echo "fleet $r: load after: $(cut -d' ' -f1-3 /proc/loadavg)"
done
if [ "$max_secs" != 0 ] && [ "${MAX:-1}" != 0 ]; then
    echo "speed max: load before: $(cut -d' ' -f1-3 /proc/loadavg)"
    start 1 --speed max
    "${client_pin[@]}" "$client" "$addrs" "$max_secs" --pid "$pid" --control "$control" --list 20
    stop
    echo "speed max: load after: $(cut -d' ' -f1-3 /proc/loadavg)"
fi
