//! The emulated serial line: what a byte costs on the wire and how fast the
//! boards may hand the device's output to their UART ([`Pacer`]).
//!
//! 10 bit times per byte (1 start, 8 data, no parity, 1 stop: ICD Table 4.3, Table 5.1). Shared by
//! every board so the line is modelled once.

mod pacer;

pub use pacer::{byte_time_ps, wire_ns, Pacer, BITS_PER_BYTE, BURST_NS, MIN_BURST_BYTES};
