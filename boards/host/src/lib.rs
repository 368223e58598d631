//! # imu-emu-host — the `imu-emu` program
//!
//! One program for the emulated IMUs and the tools around them: its
//! command line ([`cli`]) serves an Inertial Labs KERNEL or an Inertial
//! Sense IMX-5 (ISB) — one or a fleet — with the runner crate
//! (`imu_emu_runner`: transports, clocks, control, link faults, motion
//! feed, web view), and runs the client, the Allan tool and the sensor
//! profile commands of the tools crate (`imu_emu_tools`).
//!
//! * [`cli`] — the command line ([`cli::Args`]) and [`cli::run`], what
//!   `main` calls; serving one device or a fleet is `cli::serve`.
//! * [`isb_layouts`] — `imu-emu isb-layouts`: the ISB data set layouts
//!   from their one declaration each.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod cli;
pub mod isb_layouts;
