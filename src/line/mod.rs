//! The serial line as the device shell models it: the UART transmit queue
//! and the wire time of what it holds at the current line rate (ICD 4.1.1:
//! 10 bit times a byte, start + 8 data + stop). Protocol-free: a
//! personality hands it whole frames, it hands the board bytes.

mod ring;

pub use ring::{Line, Queued, MAX_FRAME, TX_CAP};
