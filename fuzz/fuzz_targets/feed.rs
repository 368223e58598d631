//! Fuzz target `feed`: see `imu_emu_fuzz::feed` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::feed(data));
