//! The Inertial Sense ISB protocol, the second device personality
//! (the Inertial Sense ISB protocol page, protocol 2.1; the facts the code uses
//! are in `docs/protocol-facts.md` "ISB").
//!
//! So far the wire layer: [`packet`] (header, checksum, encoding, the
//! streaming decoder). The device behind it (data sets, GET/SET, RMC
//! streaming) is not built yet.

pub mod packet;
