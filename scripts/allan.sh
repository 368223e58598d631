#!/usr/bin/env bash
# The Allan figures of every built-in sensor profile (docs/sensors.md
# "Configured vs measured"): `imu-emu allan` runs each unit in process for
# HOURS of device time (100 by default: the run the datasheet reading
# needs, docs/sensors.md) at 100 Hz, prints every axis's fitted ARW/VRW,
# bias instability (and the datasheet reading min/0.6643) and rate random
# walk beside the profile's, and draws the K110's, the K120's and the
# IMX-5's plots. JOBS units run at a time (1 by default).
# Usage: [JOBS=2] scripts/allan.sh [HOURS] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
hours="${1:-100}"
out="${2:-target/allan}"
jobs="${JOBS:-1}"
mkdir -p "$out"
cargo build --release --quiet -p imu-emu-host
# A copy: a later build must not swap the binary under a long batch.
cp "${CARGO_TARGET_DIR:-target}/release/imu-emu" "$out/imu-emu"
unit() {
  local m="$1" plot=()
  case "$m" in
    K110 | K120 | IMX-5) plot=(--png "$out/allan-$m.png" --svg "$out/allan-$m.svg") ;;
  esac
  "$out/imu-emu" allan --model "$m" --hours "$hours" "${plot[@]}" >"$out/allan-$m.txt"
}
export -f unit
export out hours
models=(K100 K102 K108 K110 K110M K120 K201 K210 K220 IMX-5)
printf '%s\n' "${models[@]}" | xargs -P "$jobs" -I{} bash -c 'unit {}'
for m in "${models[@]}"; do cat "$out/allan-$m.txt"; done
