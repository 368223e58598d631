//! Target `kernel_frame`: the KERNEL frame decoder (ICD Table 5.2).

use imu_emu::kernel::RX_FRAME_CAP;
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::{self, Decoder as KernelDecoder};

use crate::script::chunking_invariant;

/// KERNEL frame decoder: chunking invariance, and every frame it emits
/// re-encodes ([`frame::encode`]) to exactly its bytes, with a valid
/// header, length field and checksum.
pub fn kernel_frame(data: &[u8]) {
    for raw in chunking_invariant::<frame::Kernel, RX_FRAME_CAP>(data) {
        let n = raw.len();
        assert!((frame::OVERHEAD..=RX_FRAME_CAP).contains(&n));
        assert_eq!(raw[..2], frame::HEADER);
        assert_eq!(usize::from(u16::from_le_bytes([raw[4], raw[5]])), n - 2);
        let mut out = vec![0u8; n];
        let m = frame::encode(raw[2], raw[3], &raw[6..n - 2], &mut out);
        assert_eq!(m, Some(n));
        assert_eq!(out, raw, "re-encode differs");
        // The typed decoder agrees with the raw one.
        let mut d = KernelDecoder::<RX_FRAME_CAP>::new();
        let mut input = &raw[..];
        let f = d.next_frame(&mut input).expect("a frame decodes again");
        assert_eq!(
            (f.msg_type, f.id, f.payload),
            (raw[2], raw[3], &raw[6..n - 2])
        );
        // A command payload parses and, when it does, re-encodes the same.
        if let Ok(cmd) = Command::parse(f.payload) {
            let mut again = [0u8; 300];
            if let Some(k) = cmd.encode(&mut again) {
                if f.msg_type == frame::TYPE_COMMAND && f.id == 0 {
                    assert_eq!(&again[..k], &raw[..], "command re-encode");
                }
            }
        }
    }
}
