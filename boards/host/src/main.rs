//! `imu-emu`: a virtual Inertial Labs KERNEL IMU on a TCP port or a pty.
//! See `imu-emu --help` and the `imu_emu_host` library docs.
#![forbid(unsafe_code)]

use clap::Parser as _;

fn main() -> anyhow::Result<()> {
    imu_emu_host::cli::run(imu_emu_host::cli::Args::parse())
}
