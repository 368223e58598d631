//! Streaming decoder properties (ICD Table 5.2): chunking invariance,
//! bounded buffer, resync after garbage.

use imu_emu::kernel::frame::{encode, Decoder};
use proptest::prelude::*;

type D = Decoder<265>;

fn decode_chunked(bytes: &[u8], chunks: &[usize]) -> Vec<(u8, u8, Vec<u8>)> {
    let mut d = D::new();
    let mut out = Vec::new();
    let mut rest = bytes;
    let mut i = 0;
    while !rest.is_empty() {
        let n = chunks.get(i).copied().unwrap_or(1).clamp(1, rest.len());
        i += 1;
        let mut input = &rest[..n];
        rest = &rest[n..];
        while let Some(f) = d.next_frame(&mut input) {
            out.push((f.msg_type, f.id, f.payload.to_vec()));
        }
        assert!(input.is_empty());
    }
    out
}

fn frame(ty: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; payload.len() + 8];
    let n = encode(ty, id, payload, &mut out).unwrap();
    out.truncate(n);
    out
}

prop_compose! {
    fn arb_frame()(ty in 0u8..2, id: u8, payload in prop::collection::vec(any::<u8>(), 0..257)) -> (u8, u8, Vec<u8>) {
        (ty, id, payload)
    }
}

proptest! {
    #[test]
    fn any_chunking_gives_the_same_frames(
        frames in prop::collection::vec(arb_frame(), 1..6),
        chunks in prop::collection::vec(1usize..4096, 0..40),
    ) {
        let mut bytes = Vec::new();
        for (t, i, p) in &frames {
            bytes.extend(frame(*t, *i, p));
        }
        let one = decode_chunked(&bytes, &[1]);
        let all = decode_chunked(&bytes, &[bytes.len()]);
        let random = decode_chunked(&bytes, &chunks);
        prop_assert_eq!(&one, &frames);
        prop_assert_eq!(&all, &frames);
        prop_assert_eq!(&random, &frames);
    }

    #[test]
    fn garbage_never_hides_a_good_frame_that_follows_it(
        garbage in prop::collection::vec(any::<u8>(), 0..600),
        payload in prop::collection::vec(any::<u8>(), 1..40),
        chunks in prop::collection::vec(1usize..64, 0..40),
    ) {
        // Garbage, then a long idle gap is not needed: 265 bytes of padding
        // guarantee any candidate started in the garbage has been resolved.
        let good = frame(0, 0, &payload);
        let mut bytes = garbage.clone();
        bytes.extend(std::iter::repeat_n(0u8, 265));
        bytes.extend(&good);
        let frames = decode_chunked(&bytes, &chunks);
        prop_assert_eq!(frames.last(), Some(&(0u8, 0u8, payload.clone())));
        // Same frames with any chunking.
        prop_assert_eq!(decode_chunked(&bytes, &[1]), frames);
    }
}

#[test]
fn a_frame_larger_than_the_buffer_is_dropped_and_the_next_found() {
    let mut bytes = vec![0xAA, 0x55, 0x00, 0x00, 0x10, 0x01]; // len 272 > 265-2
    bytes.extend(frame(0, 0, &[0x1A]));
    assert_eq!(decode_chunked(&bytes, &[3]), vec![(0, 0, vec![0x1A])]);
}

#[test]
fn length_below_6_is_dropped() {
    let mut bytes = vec![0xAA, 0x55, 0x00, 0x00, 0x05, 0x00];
    bytes.extend(frame(0, 0, &[0xFE]));
    assert_eq!(decode_chunked(&bytes, &[1]), vec![(0, 0, vec![0xFE])]);
}
