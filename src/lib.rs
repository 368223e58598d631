//! # imu-emu — the emulator core
//!
//! A sans-IO, `no_std`, allocation-free emulator of the Inertial Labs KERNEL
//! IMU family, implementing the KERNEL Interface Control Document rev 1.42
//! ("the ICD"). Boards hand the core bytes, ticks, pin edges and time; the
//! core hands back bytes and events. It never reads a clock or a port.
//!
//! The one entry point is [`device::Device`]:
//!
//! ```
//! use imu_emu::{device::Device, model::Product, nor::RamNor, time::Instant};
//! let product = Product::parse("K110").unwrap();
//! let mut dev = Device::power_on(product, RamNor::<8192>::new(), Instant::ZERO);
//! // GetDevInfo (ICD 5.3.3)
//! dev.on_rx(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x12, 0x19, 0x00], Instant::ZERO);
//! let mut out = [0u8; 256];
//! let n = dev.poll_tx(&mut out);
//! assert_eq!(n, 8 + 166); // header, type, id, length, 166-byte payload, checksum
//! ```
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod ahrs;
pub mod chain;
pub mod device;
pub mod dsp;
pub mod framing;
pub mod isb;
pub mod kernel;
pub mod line;
pub mod math;
pub mod model;
pub mod nor;
pub mod schedule;
pub mod sensor;
pub mod store;
pub mod time;
