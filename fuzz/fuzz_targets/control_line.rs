//! Fuzz target `control_line`: see `imu_emu_fuzz::control_line` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::control_line(data));
