#!/usr/bin/env bash
# Live motion feed figures (docs/feed.md "Figures"): starts a release
# `imu-emu` (K110, real time) with a feed and a control socket on free
# loopback ports, runs boards/host/examples/feedbench.rs against it
# (delay from a sample's arrival to the first GA frame carrying it at a
# 2 kHz feed, p50/p99/max, split into the design part and the host's
# scheduling; binary and text throughput) and stops it. The load average
# is printed before and after: the delay's tail is the machine's.
#
#   scripts/feed-bench.sh [--rate HZ] [--lpf CODE] [--steps N] [--burst N]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -q --release -p imu-emu-host --bin imu-emu --example feedbench
target="${CARGO_TARGET_DIR:-target}"
out=$(mktemp)
"$target/release/imu-emu" --tcp 127.0.0.1:0 --control 127.0.0.1:0 \
  --motion-feed 127.0.0.1:0 --power-on now --feed-timeout 10 >"$out" 2>/dev/null &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null; rm -f "$out"' EXIT
for _ in $(seq 100); do [[ $(wc -l <"$out") -ge 3 ]] && break; sleep 0.05; done
uart=$(sed -n 's/^listening on tcp //p' "$out")
control=$(sed -n 's/^control on tcp //p' "$out")
feed=$(sed -n 's/^feed on tcp //p' "$out")
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) ($(nproc) CPUs)"
"$target/release/examples/feedbench" "$uart" "$control" "$feed" "$@"
echo "load average after:  $(cut -d' ' -f1-3 /proc/loadavg)"
