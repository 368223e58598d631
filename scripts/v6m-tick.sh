#!/usr/bin/env bash
# Instructions per Device::on_tick for the ARMv6-M fixed-point build
# (scripts/v6m-tick: a bare probe image run on QEMU mps2-an386). Prints one
# line per load: load, worst of 40 ticks, mean (instructions, ±40):
#   0 the empty measurement, 1 K110 factory (no output), 2 GA at 2000 Hz,
#   3 the largest K110 UDD (145 B) at 1000 Hz, 4 the same with LPF 16 Hz;
# and line 9: size_of the signal chain without and with integrals (bytes).
set -euo pipefail
cd "$(dirname "$0")/v6m-tick"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/imu-emu/target}/v6m-tick"
cargo build --release --quiet
timeout 120 qemu-system-arm -M mps2-an386 -nographic -icount shift=0 \
  -semihosting-config enable=on,target=native \
  -kernel "$CARGO_TARGET_DIR/thumbv6m-none-eabi/release/v6m-tick"
