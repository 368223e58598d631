//! Fuzz target `kernel_frame`: see `imu_emu_fuzz::kernel_frame` for the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| imu_emu_fuzz::kernel_frame(data));
