//! # imu-emu-tools — the host side of a KERNEL or ISB line
//!
//! The tools of the `imu-emu` program that talk to a unit or read what
//! one sent, built on the core's codec façades only (framing, commands,
//! parameters, decoding, the unit model and the sensor profiles: no
//! device, chain or clock — a unit `allan` runs in process is run by the
//! program's runner) and on nothing of the runner (`imu-emu-runner` builds
//! on this crate, not the other way round):
//!
//! * [`protocol`] — the protocol choice ([`protocol::Protocol`]:
//!   `--protocol kernel|isb`), below every other module;
//! * [`error`] — [`error::UsageError`] (exit status 2), shared with the
//!   runner and the program;
//! * [`client`] — `imu-emu client …`: the host side of a KERNEL or ISB
//!   line (commands, record, decode, plot) and the decoders the runner's
//!   web view uses too; what differs between the protocols is one trait,
//!   [`client::tool_protocol::ToolProtocol`];
//! * [`allan`] — `imu-emu allan`: the Allan deviation of a unit run in
//!   process (by the [`allan::RunUnit`] it is handed) or of a recording ([`allan::input`]), its fit
//!   ([`allan::deviation`]) and its plot ([`allan::plot`]);
//! * [`plot`] — the one plot style (titled panels, labelled axes with
//!   units, legend; PNG or SVG; embedded font);
//! * [`profile_file`] — sensor profile files (`--sensor-profile`,
//!   `sensor-profile show|check`).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod allan;
pub mod client;
pub mod error;
pub mod plot;
pub mod profile_file;
pub mod protocol;
