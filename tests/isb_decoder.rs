//! The ISB packet decoder (`docs/protocol-facts.md` "ISB"): any chunking gives the same
//! packets, a bad checksum or size is dropped silently and the scan resumes
//! on the next byte, so garbage never hides a good packet.

use imu_emu::isb::packet::{encode, Decoder, MAX_PACKET};
use proptest::prelude::*;

type Pkt = (u8, u8, Vec<u8>);

/// Feeds `bytes` in chunks of the given sizes (1 when they run out).
fn packets(bytes: &[u8], chunks: &[usize]) -> Vec<Pkt> {
    let mut d = Decoder::<MAX_PACKET>::new();
    let mut out = Vec::new();
    let mut sizes = chunks.iter().copied().chain(std::iter::repeat(1));
    let mut rest = bytes;
    while !rest.is_empty() {
        let (mut input, tail) = rest.split_at(sizes.next().unwrap_or(1).clamp(1, rest.len()));
        rest = tail;
        while let Some(p) = d.next_packet(&mut input) {
            out.push((p.flags, p.did, p.payload.to_vec()));
        }
    }
    out
}

fn wire(p: &Pkt) -> Vec<u8> {
    let mut out = vec![0u8; p.2.len() + 8];
    let n = encode(p.0, p.1, &p.2, &mut out).unwrap();
    out.truncate(n);
    out
}

fn arb_packet() -> impl Strategy<Value = Pkt> {
    (
        1u8..9,
        any::<u8>(),
        prop::collection::vec(any::<u8>(), 0..300),
    )
}

proptest! {
    #[test]
    fn any_chunking_gives_the_same_packets(
        ps in prop::collection::vec(arb_packet(), 1..6),
        chunks in prop::collection::vec(1usize..3000, 0..40),
    ) {
        let bytes: Vec<u8> = ps.iter().flat_map(wire).collect();
        prop_assert_eq!(&packets(&bytes, &[1]), &ps);
        prop_assert_eq!(&packets(&bytes, &[bytes.len()]), &ps);
        prop_assert_eq!(&packets(&bytes, &chunks), &ps);
    }

    #[test]
    fn a_corrupted_packet_is_dropped_and_the_next_one_found(
        p in arb_packet(),
        q in arb_packet(),
        at in any::<prop::sample::Index>(),
        flip in 1u8..=255,
    ) {
        let mut bad = wire(&p);
        let i = at.index(bad.len());
        bad[i] ^= flip;
        let mut bytes = bad;
        bytes.extend(wire(&q));
        // A corrupted size may make the bad candidate reach past `q`: it is
        // resolved once that many bytes have come (here idle-line zeros).
        bytes.extend(std::iter::repeat_n(0u8, MAX_PACKET));
        let got = packets(&bytes, &[7]);
        // Whatever the corruption, the good packet is the last one found.
        prop_assert_eq!(got.last(), Some(&q));
    }
}

#[test]
fn a_size_past_the_largest_packet_is_dropped() {
    let good = (4u8, 58u8, vec![1, 2, 3]);
    let mut bytes = vec![0xEF, 0x49, 0x04, 0x3A, 0xF9, 0x07]; // 2041 + 8 > 2048
    bytes.extend(wire(&good));
    assert_eq!(packets(&bytes, &[5]), vec![good]);
}
