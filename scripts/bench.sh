#!/usr/bin/env bash
# The performance figures of the docs/performance.md in one
# command: the criterion benches (short measurement times) and the
# whole-process figures of the release `imu-emu` measured by
# `boards/host/examples/loadgen.rs`; prints a Markdown table and the
# machine it ran on.
#
#   scripts/bench.sh            # everything (a few minutes)
#   SECS=3 scripts/bench.sh     # shorter whole-process runs
#
# Uses CARGO_TARGET_DIR if set. Needs two free cores for honest figures
# (the emulator and the client each take one).
set -euo pipefail
cd "$(dirname "$0")/.."
target=${CARGO_TARGET_DIR:-target}
secs=${SECS:-5}
log=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$log"' EXIT

short=(--warm-up-time 1 --measurement-time 3)
echo "== cargo bench (decode, tick)" >&2
cargo bench -q -p imu-emu --bench decode -- kernel_decode "${short[@]}" >"$log/decode.txt" 2>&1
cargo bench -q -p imu-emu --bench tick -- device_tick "${short[@]}" >"$log/tick.txt" 2>&1
echo "== release build" >&2
cargo build -q --release -p imu-emu-host --bin imu-emu --example loadgen
emu=$target/release/imu-emu
loadgen=$target/release/examples/loadgen

# The middle estimate of criterion's `time:` or `thrpt:` line of bench $1.
estimate() {
    awk -v name="$1" -v key="$2" '
        $0 == name || index($0, name " ") == 1 { found = 1 }
        found && index($0, key ":") { sub(/.*\[/, ""); split($0, a, " "); print a[3] " " a[4]; exit }
    ' "$3"
}

# Starts imu-emu with the given options (N devices with --count N); sets
# $pid, $addr (the first device's address) and $addrs (all, comma-separated).
start() {
    local n=1
    [ "${1:-}" = --count ] && n=$2
    "$emu" --model K110 --tcp 127.0.0.1:0 "$@" >"$log/emu.out" 2>"$log/emu.err" &
    pid=$!
    for _ in $(seq 50); do
        if [ "$(grep -c '^listening on tcp' "$log/emu.out" || true)" -ge "$n" ]; then
            addrs=$(grep -o '127\.0\.0\.1:[0-9]*' "$log/emu.out" | head -"$n" | paste -sd,)
            addr=${addrs%%,*}
            return
        fi
        sleep 0.1
    done
    echo "imu-emu did not start" >&2
    exit 1
}

field() { tr ' ' '\n' <<<"$2" | sed -n "s/^$1=//p"; }

echo "== --speed max" >&2
start --speed max
max=$("$loadgen" "$addr" "$secs")
kill "$pid"; wait "$pid" 2>/dev/null || true
start --speed max
max_f=$("$loadgen" "$addr" "$secs" --filters)
kill "$pid"; wait "$pid" 2>/dev/null || true

echo "== real time (10 s)" >&2
start
rt=$("$loadgen" "$addr" 10 --pid "$pid")
kill "$pid"; wait "$pid" 2>/dev/null || true

echo "== real time, GA at 100 Hz (10 s)" >&2
start
rt100=$("$loadgen" "$addr" 10 --pid "$pid" --rate 100)
kill "$pid"; wait "$pid" 2>/dev/null || true

echo "== real time over a pty (10 s)" >&2
"$emu" --model K110 --pty >"$log/emu.out" 2>"$log/emu.err" &
pid=$!
for _ in $(seq 50); do grep -q '^listening on pty' "$log/emu.out" && break; sleep 0.1; done
pty=$(sed -n 's/^listening on pty //p' "$log/emu.out")
rt_pty=$("$loadgen" "$pty" 10 --pid "$pid")
kill "$pid"; wait "$pid" 2>/dev/null || true

echo "== 50 devices in one process, real time (10 s)" >&2
start --count 50
many=$("$loadgen" "$addrs" 10 --pid "$pid")
kill "$pid"; wait "$pid" 2>/dev/null || true

cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')
cat <<EOF
Ran on $(nproc) cores ($cpu), load average $(cut -d' ' -f1-3 /proc/loadavg) before the run, $(date -u +%Y-%m-%d).

| what | target | measured | how |
|---|---|---|---|
| KERNEL framing | ≥ 3 GB/s | $(estimate kernel_decode/framing_64MiB thrpt "$log/decode.txt") | \`cargo bench --bench decode\`: 64 MiB stream (every format, real UDD configs, ~2 % garbage, 1 frame in 200 corrupted) in 64 KiB reads |
| KERNEL typed decode (framing + every value) | ≥ 1 GB/s | $(estimate kernel_decode/typed_64MiB thrpt "$log/decode.txt") | same stream, \`kernel::decode\` |
| \`Device::on_tick\` + frame, GA at 2 kHz | — | $(estimate device_tick/GA time "$log/tick.txt") | \`cargo bench --bench tick\` (K120, 2 Mbaud, \`poll_tx\` included) |
| \`Device::on_tick\` + frame, Calibrated HR | — | $(estimate "device_tick/Calibrated HR" time "$log/tick.txt") | same |
| \`Device::on_tick\` + frame, worst case | — | $(estimate device_tick/worst time "$log/tick.txt") | K120, LPF 16 Hz, all cascade filters, incremental, mounting, largest UDD at 1 kHz on 2 Mbaud |
| \`--speed max\`, GA at 2 kHz, factory settings | ≥ 3 000× | $(field factor "$max")× | release \`imu-emu --speed max\` over TCP, \`loadgen\` checking every counter step for ${secs} s |
| \`--speed max\`, GA at 2 kHz, LPF 16 Hz + all cascade filters | ≥ 2 000× | $(field factor "$max_f")× | same, \`--filters\` |
| real time, GA at 2 kHz over TCP: CPU | ≤ 2 % of a core | $(field cpu_pct "$rt") % | \`/proc/PID/stat\` utime + stime over 10 s |
| real time, GA at 100 Hz over TCP: CPU | ≤ 2 % of a core | $(field cpu_pct "$rt100") % | same, \`loadgen --rate 100\` |
| real time, GA at 2 kHz over a pty: CPU; lateness p50 / p99 / p99.9 (max) | ≤ 2 % of a core; p99.9 ≤ 1 ms | $(field cpu_pct "$rt_pty") %; $(field late_p50_us "$rt_pty") / $(field late_p99_us "$rt_pty") / $(field late_p999_us "$rt_pty") µs ($(field late_max_us "$rt_pty") µs) | same, \`loadgen\` on the pty (raw, following the device to 2 Mbaud) |
| real time: lateness against the wire time, p50 / p99 / p99.9 (max) | p99.9 ≤ 1 ms | $(field late_p50_us "$rt") / $(field late_p99_us "$rt") / $(field late_p999_us "$rt") µs ($(field late_max_us "$rt") µs) | \`loadgen\`: arrival − (counter × 500 µs + 200 µs on the line), aligned on the earliest frame |
| 50 KERNELs in one process (\`--count 50\`), GA at 2 kHz at 2 Mbaud, real time | every counter step, p99.9 ≤ 1 ms | $(field frames "$many") frames, every step checked; CPU $(field cpu_pct "$many") % of a core; lateness $(field late_p50_us "$many") / $(field late_p99_us "$many") / $(field late_p999_us "$many") µs ($(field late_max_us "$many") µs) | \`loadgen\` over the 50 ports in one thread, 10 s |
EOF
