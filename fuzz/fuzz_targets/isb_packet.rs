//! Fuzz target `isb_packet`: see `imu_emu_fuzz::isb_packet` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::isb_packet(data));
