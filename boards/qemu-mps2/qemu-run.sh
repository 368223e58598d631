#!/bin/sh
# The cargo runner of this board (`cargo run --release -- [ARGS]`), also
# usable by hand: qemu-run.sh ELF [model=K110] [seed=N] [flash=FILE] [boot=high|low|float]
#
# Boots the firmware in QEMU's mps2-an386 with
#   UART0 (the KERNEL protocol, or ISB in the `isb` image) on tcp 127.0.0.1:${IMU_EMU_PORT:-7000}
#     QEMU waits for the first client before the firmware starts, so the
#     client sees everything from power-on (e.g. the AutoStart message);
#   UART1 (the pin bridge) on tcp 127.0.0.1:${IMU_EMU_BRIDGE_PORT:-7001};
#   both sockets with nodelay=on (TCP_NODELAY), so a reply leaves when the
#   firmware writes it, as on a wire (without it Nagle holds small writes
#   back ~40 ms).
# IMU_EMU_QEMU_ARGS adds QEMU options (e.g. "-icount shift=0").
# Ctrl-C stops QEMU; with flash=FILE the next run is a power cycle.
set -eu
elf="$1"
shift
port="${IMU_EMU_PORT:-7000}"
bridge="${IMU_EMU_BRIDGE_PORT:-7001}"
semi="enable=on,target=native"
for a in "$@"; do
    # QEMU option values escape commas by doubling them.
    semi="$semi,arg=$(printf '%s' "$a" | sed 's/,/,,/g')"
done
echo "imu-emu on QEMU mps2-an386: device UART (KERNEL, or ISB with --features isb) on tcp 127.0.0.1:$port (waiting for a client), pin bridge on tcp 127.0.0.1:$bridge" >&2
# shellcheck disable=SC2086 # IMU_EMU_QEMU_ARGS is a list of options
exec qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic -monitor none \
    -serial "tcp:127.0.0.1:$port,server=on,wait=on,nodelay=on" \
    -serial "tcp:127.0.0.1:$bridge,server=on,wait=off,nodelay=on" \
    -semihosting-config "$semi" ${IMU_EMU_QEMU_ARGS:-} \
    -kernel "$elf"
