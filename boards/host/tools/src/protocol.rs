//! The protocol a unit speaks (`--protocol`, or detected in a capture):
//! the one choice the program, the runner and the tools share, in the
//! lowest module so that none of them imports another for it. What differs
//! between the protocols is not matches on this enum but a trait per side:
//! the tools' [`crate::client::tool_protocol::ToolProtocol`] (a host
//! reading a line or a capture) and the runner's
//! `imu_emu_runner::protocol::HostProtocol` (serving a unit).

use imu_emu::isb::packet::{Decoder as IsbDecoder, MAX_PACKET};
use imu_emu::kernel::frame::Decoder as KernelDecoder;

/// Largest KERNEL frame [`Protocol::detect`] decodes.
const KERNEL_FRAME_CAP: usize = 4096;

/// The emulated device's protocol (`--protocol`); the KERNEL by default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Protocol {
    /// Inertial Labs KERNEL (ICD rev 1.42).
    #[default]
    Kernel,
    /// Inertial Sense IMX-5 over ISB (protocol 2.1).
    Isb,
}

impl Protocol {
    /// Its `--protocol` value (`kernel`, `isb`), as the web view's JSON
    /// names it too.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Kernel => "kernel",
            Protocol::Isb => "isb",
        }
    }

    /// The protocol whose frames or packets `head` (the start of a
    /// capture) holds more of, KERNEL on a tie, or `None` when it holds
    /// neither: whole frames by the core's decoders, their checksums
    /// included.
    pub fn detect(head: &[u8]) -> Option<Protocol> {
        let mut k = Box::new(KernelDecoder::<KERNEL_FRAME_CAP>::new());
        let mut input = head;
        let mut frames = 0usize;
        while k.next_frame(&mut input).is_some() {
            frames += 1;
        }
        let mut i = Box::new(IsbDecoder::<MAX_PACKET>::new());
        let mut input = head;
        let mut packets = 0usize;
        while i.next_packet(&mut input).is_some() {
            packets += 1;
        }
        match (frames, packets) {
            (0, 0) => None,
            (f, p) if p > f => Some(Protocol::Isb),
            _ => Some(Protocol::Kernel),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum as _;

    #[test]
    fn a_capture_is_of_the_protocol_it_holds_more_of() {
        let mut kernel = [0u8; 64];
        let n = imu_emu::kernel::frame::encode(1, 0x01, &[0; 10], &mut kernel).unwrap();
        assert_eq!(Protocol::detect(&kernel[..n]), Some(Protocol::Kernel));
        let mut isb = [0u8; 64];
        let m = imu_emu::isb::message::encode_get(
            &imu_emu::isb::message::GetRequest {
                did: 1,
                size: 0,
                offset: 0,
                period: 0,
            },
            &mut isb,
        )
        .unwrap();
        assert_eq!(Protocol::detect(&isb[..m]), Some(Protocol::Isb));
        assert_eq!(Protocol::detect(b"time,gyro_x\n1,2\n"), None);
    }

    #[test]
    fn names_are_the_command_line_values() {
        for p in Protocol::value_variants() {
            let v = p.to_possible_value().unwrap();
            assert_eq!(v.get_name(), p.name());
        }
    }
}
