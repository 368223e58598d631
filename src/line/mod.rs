//! The emulated serial line, modelled once for every board and every
//! personality: what a byte costs on the wire (10 bit times: 1 start, 8
//! data, no parity, 1 stop — ICD Table 4.3, Table 5.1), the device's UART
//! transmit queue and when what it holds has left ([`Line`]), and how fast
//! a board may hand the device's output to its UART ([`Pacer`]).
//! Protocol-free: a personality hands it whole frames, it hands the board
//! bytes.

mod pacer;
mod ring;

pub use pacer::{byte_time_ps, wire_ns, Pacer, BITS_PER_BYTE, BURST_NS, MIN_BURST_BYTES};
pub use ring::{Line, Queued, TxBuffer, TX_CAP};
