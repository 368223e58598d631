//! The fuzz targets' bodies: each takes the raw
//! fuzzer input and panics on a broken invariant, never merely on bad
//! input. Kept in a library so the `fuzz_targets/*.rs` stay one line
//! and a crash input can be replayed from a unit test or a debugger.
//!
//! * [`kernel_frame`] — the KERNEL frame decoder (ICD Table 5.2).
//! * [`isb_packet`] — the ISB packet decoder.
//! * [`device`] — the whole KERNEL device for several models, driven by a
//!   script decoded from the input.
//! * [`isb_device`] — the whole ISB device (the emulated IMX-5), driven by
//!   a script decoded from the input.
//! * [`store`] — the parameter store with power cuts at arbitrary
//!   program/erase steps.
//! * [`feed`] — the live motion feed decoder (text rows and binary
//!   samples) and the per-device track.
//! * [`web_request`] — the host's web view: raw bytes on one connection
//!   through its HTTP server loop to its routes.
//! * [`control_line`] — the host's control grammar, line by line.
//!
//! One module per target (`kernel_frame.rs`, `isb_packet.rs`,
//! `device.rs`, `isb_device.rs`, `store.rs`, `feed.rs`, `web_request.rs`,
//! `control_line.rs`); `script.rs` holds what they
//! share (the script reader, the scanners' chunking invariance).

// The invariants lean on the core's debug assertions and overflow checks
// too: refuse a build without them (see Cargo.toml's release profile).
#[cfg(not(debug_assertions))]
compile_error!("build the fuzz targets with debug assertions (fuzz/Cargo.toml release profile)");

mod control_line;
mod device;
mod feed;
mod isb_device;
mod isb_packet;
mod kernel_frame;
mod script;
mod store;
mod web_request;

pub use control_line::control_line;
pub use device::device;
pub use feed::feed;
pub use isb_device::isb_device;
pub use isb_packet::isb_packet;
pub use kernel_frame::kernel_frame;
pub use script::Cursor;
pub use store::store;
pub use web_request::web_request;
