//! # imu-emu — the emulator core
//!
//! A sans-IO, `no_std`, allocation-free emulator of the Inertial Labs KERNEL
//! IMU family (the KERNEL Interface Control Document rev 1.42, "the ICD")
//! and of an Inertial Sense IMX-5 speaking the ISB protocol (protocol
//! 2.1.0.0, as the vendor's SDK 2.7.1 speaks it): one device shell, two
//! protocol personalities. Boards hand the core bytes, ticks, pin edges
//! and time; the core hands back bytes and events. It never reads a clock
//! or a port. `ARCHITECTURE.md` in the repository explains the layers.
//!
//! ## The whole API a board or a unit test needs
//!
//! | name | what |
//! |---|---|
//! | [`Device`] | the emulated unit: a [`Shell`] carrying one [`Personality`] ([`Kernel`] by default) |
//! | [`PowerOn`], [`Product`] | what is fixed at power-on: the product (model + ranges, ICD 3.2.2), BOOT, seed |
//! | [`Device::on_rx`], [`Device::on_tick`], [`Device::on_pin`] | bytes in, one internal-rate tick, a pin edge ([`Pin`], [`Level`]) |
//! | [`Device::poll_tx`], [`Device::poll_event`] | bytes out, board actions ([`Event`]: line rate, TOV) |
//! | [`Device::power_cycle_with`], [`Device::mode`] ([`Mode`]), [`Device::ticks_to_next_output`] | power, state, when to wake |
//! | [`Device::chain_mut`] ([`SignalChain`]) | motion ([`Motion`]), error model, faults ([`Faults`]) |
//! | [`Instant`] | time, ns on the board's clock |
//! | [`RamNor`] | a NOR flash in RAM for tests and hosts (any `embedded-storage` `NorFlash` works) |
//!
//! ```
//! use imu_emu::{Device, Instant, Product, RamNor};
//! let product = Product::parse("K110").unwrap();
//! let mut dev = Device::power_on(product, RamNor::<8192>::new(), Instant::ZERO);
//! // GetDevInfo (ICD 5.3.3)
//! dev.on_rx(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x12, 0x19, 0x00], Instant::ZERO);
//! let mut out = [0u8; 256];
//! let n = dev.poll_tx(&mut out);
//! assert_eq!(n, 8 + 166); // header, type, id, length, 166-byte payload, checksum
//! ```
//!
//! ## Internal modules
//!
//! The modules below are public so that tests, benchmarks and tools can
//! reach the stages and the protocol codecs (e.g. [`kernel::frame`] to
//! decode what the device sends, [`isb::packet`]); they are the product's
//! insides, documented but not a stable interface. Protocol-free: [`chain`],
//! [`sensor`], [`dsp`], [`ahrs`], [`math`], [`store`], [`nor`], [`line`](mod@line),
//! [`framing`], [`time`]; the shell: [`device`], [`personality`]; the
//! personalities: [`kernel`], [`isb`] (packets, messages, NMEA,
//! data sets, the IMX-5 personality).
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod ahrs;
pub mod chain;
pub mod device;
pub mod dsp;
pub mod earth;
pub mod feed;
pub mod framing;
pub mod io;
pub mod isb;
pub mod kernel;
pub mod line;
pub mod math;
pub mod model;
pub mod nor;
pub mod personality;
pub mod schedule;
pub mod sensor;
pub mod store;
pub mod time;
pub mod vehicle;

pub use chain::{Faults, SignalChain};
pub use device::{Device, PowerOn, Shell};
pub use io::{Event, Level, Mode, Pin};
pub use kernel::Kernel;
pub use model::Product;
pub use nor::RamNor;
pub use personality::Personality;
pub use sensor::Motion;
pub use time::Instant;
