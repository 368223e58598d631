//! `imu-emu`: a virtual Inertial Labs KERNEL IMU on a TCP port or a pty.
//! See `imu-emu --help` and the `imu_emu_host` library docs.
//!
//! Errors are one line on stderr (never a backtrace, whatever
//! `RUST_BACKTRACE` says): exit status 2 for a bad argument, 1 otherwise.
#![forbid(unsafe_code)]

use std::process::ExitCode;

use clap::Parser as _;

fn main() -> ExitCode {
    imu_emu_host::cli::one_line_panics();
    match imu_emu_host::cli::run(imu_emu_host::cli::Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => ExitCode::from(imu_emu_host::cli::report(&e)),
    }
}
