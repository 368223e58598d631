//! Target `isb_packet`: the ISB packet decoder.

use imu_emu::isb;

use crate::script::chunking_invariant;

/// ISB packet decoder: chunking invariance, and every packet re-encodes
/// ([`isb::packet::encode`]) to exactly its bytes.
pub fn isb_packet(data: &[u8]) {
    use isb::packet::{encode, Isb, MAX_PACKET, OVERHEAD, PREAMBLE};
    for raw in chunking_invariant::<Isb, MAX_PACKET>(data) {
        let n = raw.len();
        assert!((OVERHEAD..=MAX_PACKET).contains(&n));
        assert_eq!(raw[..2], PREAMBLE);
        assert_eq!(usize::from(u16::from_le_bytes([raw[4], raw[5]])), n - 8);
        let mut out = vec![0u8; n];
        assert_eq!(encode(raw[2], raw[3], &raw[6..n - 2], &mut out), Some(n));
        assert_eq!(out, raw, "re-encode differs");
        let mut d = isb::packet::Decoder::<MAX_PACKET>::new();
        let mut input = &raw[..];
        let p = d.next_packet(&mut input).expect("a packet decodes again");
        assert_eq!(
            (p.flags, p.did, p.payload),
            (raw[2], raw[3], &raw[6..n - 2])
        );
    }
}
