//! What passes between a board and the device, below both the shell
//! ([`crate::device`]) and the personalities ([`crate::kernel`],
//! [`crate::isb`]): input pins and their levels, the events the device asks
//! a board to act on, and the device's operating mode.

use crate::time::Instant;

/// Logic level of an input pin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Low.
    Low,
    /// High.
    High,
}

/// Input pins of the connector (KERNEL ICD Table 4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pin {
    /// 1PPS input (pin 3); a rising edge marks the second.
    Pps,
    /// External trigger input (pin 8).
    Extrig,
}

/// Operating mode (KERNEL ICD 5.1, 5.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Waiting for commands.
    Idle,
    /// Initial alignment before a stream with orientation (5.3.1).
    Aligning,
    /// Streaming.
    Continuous,
    /// Entered by BOOT at power-on; answers nothing until power cycle.
    FirmwareUpdate,
}

/// Something the board must act on, from [`crate::device::Device::poll_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// Set the UART to this line rate (bit/s) now. Every byte queued before
    /// the switch has already been handed out by
    /// [`crate::device::Device::poll_tx`]; bytes after it are held back
    /// until this event is taken. Raised at power-on and on a rate change
    /// (KERNEL CommitBaudRate, 5.3.9).
    LineRate(u32),
    /// Drive the TOV output (ICD 4.1.4) to `level` at time `at` (which may
    /// lie in the future: the falling edge comes when the frame's last bit
    /// has left the line).
    Tov {
        /// New pin level.
        level: Level,
        /// When.
        at: Instant,
    },
}
