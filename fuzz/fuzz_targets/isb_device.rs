//! Fuzz target `isb_device`: see `imu_emu_fuzz::isb_device` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::isb_device(data));
