//! Fuzz target `store`: see `imu_emu_fuzz::store` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::store(data));
