#!/usr/bin/env bash
# Instructions and syscalls per frame of `imu-emu --speed max` (K110, GA
# at 2 kHz over TCP, read by `loadgen`): a comparison of two builds that
# needs no quiet machine (docs/performance.md, "Counting instead of
# timing").
#
#   scripts/speed-instr.sh BASE_BIN NEW_BIN [SECS]
#
# Each binary serves `loadgen ADDR SECS --at-once` and `loadgen ADDR
# 3×SECS --at-once` under `valgrind --tool=callgrind`; the instructions
# per frame (user space, the whole process) are the slope between the
# two runs: start-up, configuration and shutdown cancel out. Then one
# run of SECS under `strace -c -f` counts the syscalls per frame (all of
# the run's, start-up included: a few hundred in millions of frames).
# Prints one line a binary. Callgrind files (NAME.out; NAME.frames: the
# frames loadgen read, the device's ticks) are
# kept in $OUT (default: a temporary directory) for `callgrind_annotate`.
# Needs valgrind, strace and the release `boards/host/examples/loadgen.rs`
# (built here into CARGO_TARGET_DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { echo "usage: $0 BASE_BIN NEW_BIN [SECS]" >&2; exit 2; }
secs=${3:-2}
target=${CARGO_TARGET_DIR:-target}
cargo build -q --release -p imu-emu-host --example loadgen
loadgen=$target/release/examples/loadgen
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
echo "files in $out" >&2
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null || true' EXIT

# Runs `$1 ARGS…` (a wrapper and the emulator), waits for its address and
# sets $addr; $pid is the emulator's own process.
start() {
    local name=$1
    shift
    "$@" --model K110 --speed max --tcp 127.0.0.1:0 >"$out/$name.stdout" 2>"$out/$name.stderr" &
    pid=$!
    for _ in $(seq 300); do grep -q '^listening on tcp' "$out/$name.stdout" && break; sleep 0.1; done
    addr=$(grep -o '127\.0\.0\.1:[0-9]*' "$out/$name.stdout" | head -1)
    [ -n "$addr" ] || { echo "$* did not start" >&2; exit 1; }
}

# Frames `loadgen` read from $addr in $1 seconds.
read_frames() {
    "$loadgen" "$addr" "$1" --at-once | tr ' ' '\n' | sed -n 's/^frames=//p'
}

# Calls of function $1 in callgrind file $2 (names compressed as
# `fn=(id) name` on first use, `calls=N …` after each `cfn=(id)`).
calls() {
    awk -v name="$1" '
        match($0, /^c?fn=\([0-9]+\)/) {
            id = substr($0, 1, RLENGTH)
            sub(/^c?fn=/, "", id)
            if (substr($0, RLENGTH + 2) == name) want[id] = 1
            callee = ($0 ~ /^cfn=/) ? id : ""
            next
        }
        /^calls=/ && callee != "" && (callee in want) { split(substr($0, 7), a, " "); n += a[1] }
        { callee = "" }
        END { print n + 0 }
    ' "$2"
}

# Binary $1 under callgrind for $2 seconds of reading into $out/$3.out;
# prints "INSTR FRAMES". FRAMES are the device's ticks (`Device::on_tick`
# calls; GA at 2 kHz is a frame a tick), which unlike the frames `loadgen`
# read do not depend on what was in flight when it stopped (a round of
# 448 frames, or not); `loadgen`'s count if the symbol is not found.
instr() {
    start "$3" valgrind --tool=callgrind --callgrind-out-file="$out/$3.out" "$1"
    local frames ticks
    frames=$(read_frames "$2")
    kill "$pid"
    wait "$pid" || true
    pid=
    ticks=$(calls 'imu_emu::device::Device<F,P>::on_tick' "$out/$3.out")
    [ "$ticks" -gt 0 ] || ticks=$frames
    echo "$frames $ticks" >"$out/$3.frames"
    echo "$(sed -n 's/^totals: //p' "$out/$3.out") $ticks"
}

# Binary $1 under strace for $2 seconds; prints "SYSCALLS FRAMES".
syscalls() {
    start "$3" strace -c -f -o "$out/$3.strace" "$1"
    local tracer=$pid frames
    pid=$(pgrep -P "$tracer")
    frames=$(read_frames "$2")
    kill "$pid"
    wait "$tracer" || true
    pid=
    echo "$(awk '$NF == "total" { print $(NF - 2) }' "$out/$3.strace") $frames"
}

for which in base new; do
    if [ $which = base ]; then bin=$1; else bin=$2; fi
    read -r i1 f1 < <(instr "$bin" "$secs" "$which-short")
    read -r i2 f2 < <(instr "$bin" "$((3 * secs))" "$which-long")
    read -r sc fs < <(syscalls "$bin" "$secs" "$which-strace")
    awk -v w="$which" -v b="$bin" -v i1="$i1" -v f1="$f1" -v i2="$i2" -v f2="$f2" -v sc="$sc" -v fs="$fs" \
        'BEGIN { printf "%s instr_per_frame=%.1f syscalls_per_1000_frames=%.3f (%s; %d and %d ticks counted, %d frames under strace)\n",
                 w, (i2 - i1) / (f2 - f1), 1000 * sc / fs, b, f1, f2, fs }'
done
