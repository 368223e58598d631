//! Fuzz target `web_request`: see `imu_emu_fuzz::web_request` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::web_request(data));
