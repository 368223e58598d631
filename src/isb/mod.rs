//! The Inertial Sense ISB protocol, the second device personality
//! (`shared/spec/isb-protocol.txt`, facts in NOTES.md "ISB").
//!
//! So far the wire layer: [`packet`] (header, checksum, encoding, the
//! streaming decoder). The device behind it (data sets, GET/SET, RMC
//! streaming) is not built yet.

pub mod packet;
