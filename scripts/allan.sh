#!/usr/bin/env bash
# The Allan figures of every built-in sensor profile (docs/sensors.md):
# `imu-emu allan` runs each unit in process for HOURS of device time (24 by
# default) at 100 Hz, prints its fitted ARW/VRW, bias instability and rate
# random walk beside the profile's, and draws the K110's and the IMX-5's
# plots. Usage: scripts/allan.sh [HOURS] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
hours="${1:-24}"
out="${2:-target/allan}"
mkdir -p "$out"
cargo build --release --quiet -p imu-emu-host
bin="${CARGO_TARGET_DIR:-target}/release/imu-emu"
for m in K100 K102 K108 K110 K110M K120 K201 K210 K220 IMX-5; do
  plot=()
  if [ "$m" = K110 ] || [ "$m" = IMX-5 ]; then
    plot=(--png "$out/allan-$m.png" --svg "$out/allan-$m.svg")
  fi
  "$bin" allan --model "$m" --hours "$hours" "${plot[@]}" | tee "$out/allan-$m.txt"
done
