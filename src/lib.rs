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
//! ## The public API
//!
//! **The board API**: what a board (a firmware image, the host runner, a
//! unit test of host software) drives the emulated unit with.
//!
//! | name | what |
//! |---|---|
//! | [`Device`] | the emulated unit: a [`Shell`] carrying one [`Personality`] ([`Kernel`], [`isb::Isb`]) |
//! | [`PowerOn`], [`Product`] ([`Model`]) | what is fixed at power-on: the unit and its ranges, BOOT, seed |
//! | [`Device::on_rx`], [`Device::on_tick`], [`Device::on_pin`] | bytes in, one internal-rate tick, a pin edge ([`Pin`], [`Level`]) |
//! | [`Device::poll_tx`], [`Device::poll_event`] | bytes out, board actions ([`Event`]: line rate, TOV) |
//! | [`Device::power_cycle_with`], [`Device::mode`] ([`Mode`]), [`Device::ticks_to_next_output`] | power, state, when to wake |
//! | [`schedule`] | ticks on deadlines, the line pump, RX, events ([`Pacer`]: input at the line rate) |
//! | [`Device::chain_mut`] ([`SignalChain`], [`ChainConfig`], [`Faults`]) | motion ([`Motion`], [`vehicle`], [`feed`]), the sensors' description ([`sensor`]), faults |
//! | [`Instant`] ([`time`]), [`store`], [`RamNor`] ([`nor`]) | time, ns on the board's clock; the power-fail-safe image store; a NOR flash in RAM (any `embedded-storage` `NorFlash` works) |
//!
//! **The codec façades**: what a host tool needs to speak each protocol —
//! [`kernel`] ([`kernel::frame`], [`kernel::command`], [`kernel::params`],
//! [`kernel::decode`], [`kernel::formats`], [`kernel::rate`],
//! [`kernel::model`]) and [`isb`] ([`isb::packet`], [`isb::message`],
//! [`isb::did`], [`isb::sets`], [`isb::layout`], [`isb::nmea`]);
//! [`framing`] is the scanner trait both decoders implement. Some of them
//! (`params`, `message`, `nmea`, `sets`) re-export only what a host tool
//! uses of a module whose other items are the personality's.
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
//! ## The insides
//!
//! The stages (the signal chain, the sensor error engines, the filters,
//! the AHRS), the maths, the Earth's fields, the line and each protocol's
//! own modules are crate-private. The crate's own tests, benches and fuzz
//! targets reach them with the `internals` feature, which makes them public
//! modules (and the façades whole, and adds the few accessors only they
//! read, such as `SignalChain::output` and `Isb::nav`); they are not an
//! interface. `ARCHITECTURE.md` "The public API"
//! lists it and counts it.
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Without `internals`, what only the crate's tests, benches and fuzz
// targets reach of its insides is unused; the dead-code lint is run with
// it (`cargo clippy --all-targets`, which builds the tests). The public
// docs name the insides they rest on: those links resolve in the docs of
// the insides (`cargo doc --features internals`). Clippy's advice to
// change the signatures of what is not exported is heeded in that build,
// where they are (`wrong_self_convention` spares exported methods).
#![cfg_attr(
    not(feature = "internals"),
    allow(
        dead_code,
        unused_imports,
        rustdoc::private_intra_doc_links,
        clippy::wrong_self_convention
    )
)]

#[cfg(test)]
extern crate std;

/// Declares modules that are the crate's insides: public with the
/// `internals` feature (the crate's own tests, benches and fuzz targets
/// turn it on), crate-private without.
macro_rules! internal {
    ($(mod $name:ident;)*) => {$(
        #[cfg(feature = "internals")] pub mod $name;
        #[cfg(not(feature = "internals"))] pub(crate) mod $name;
    )*};
}

/// Declares a codec façade: `pub mod $name` re-exports the listed items
/// of the crate-private module `$inner` (declared beside it, from the
/// file `$name.rs`). Inside the crate, and outside it with `internals`,
/// `$name::` names every item of `$inner`, so the crate and its tests keep
/// one path for each item whether or not it is in the public API.
macro_rules! facade {
    ($(#[$attr:meta])* pub mod $name:ident = $inner:ident { $($list:tt)* }) => {
        $(#[$attr])* pub mod $name {
            pub use super::$inner::{$($list)*};
            // (Unused when the list names every public item.)
            #[cfg(feature = "internals")]
            #[allow(unused_imports)]
            pub use super::$inner::*;
            #[cfg(not(feature = "internals"))]
            pub(crate) use super::$inner::*;
        }
    };
}

// The board API.
pub mod device;
pub mod feed;
pub mod io;
pub mod model;
pub mod nor;
pub mod personality;
pub mod schedule;
pub mod store;
pub mod time;
// What a board feeds the chain: the vehicle, the sensors' description.
pub mod sensor;
pub mod vehicle;
// The protocols' codec façades and personalities.
pub mod framing;
pub mod isb;
pub mod kernel;

internal! {
    mod ahrs;
    mod chain;
    mod dsp;
    mod earth;
    mod line;
    mod math;
}

pub use chain::{ChainConfig, Faults, Health, SignalChain};
pub use device::{Device, PowerOn, Shell};
pub use dsp::OutputVariant;
pub use io::{Event, Level, Mode, Pin};
pub use kernel::Kernel;
pub use line::Pacer;
pub use math::rotation::{euler_from_quat, Quat};
pub use math::G;
pub use model::{Model, Product};
pub use nor::RamNor;
pub use personality::Personality;
pub use sensor::Motion;
pub use time::Instant;
