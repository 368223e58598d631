#!/usr/bin/env bash
# Instructions per Device::on_tick of a navigating IMX-5 on the firmware
# targets (scripts/nav-tick: a bare probe image run on QEMU mps2-an386 under
# -icount shift=0; its doc says what it streams and prints).
#   scripts/nav-tick.sh          # thumbv7em-none-eabihf: the M4F images
#   scripts/nav-tick.sh v6m      # thumbv6m-none-eabi, fixed point: the RP2040's core
#   scripts/nav-tick.sh v6m-off  # the same, the navigation filter off (the RP2040 image)
set -euo pipefail
cd "$(dirname "$0")/nav-tick"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/imu-emu/target}/nav-tick"
if [[ ${1:-} == v6m* ]]; then
  target=thumbv6m-none-eabi
  features=fixed-point
  [[ ${1:-} == v6m-off ]] && features=fixed-point,nav-off
  cargo build --release --quiet --target $target --features $features
else
  target=thumbv7em-none-eabihf
  cargo build --release --quiet --target $target
fi
timeout 600 qemu-system-arm -M mps2-an386 -nographic -icount shift=0 \
  -semihosting-config enable=on,target=native \
  -kernel "$CARGO_TARGET_DIR/$target/release/nav-tick"
