//! Streaming decoder properties (ICD Table 5.2): chunking invariance,
//! bounded buffer, resync after garbage, the same frames and dropped
//! candidates as a byte-at-a-time reference scanner.

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

/// The rules of Table 5.2 a byte at a time, for a whole stream: at each
/// `AA`, a candidate is a frame if its second byte is `55`, its length
/// field ≥ 6 with the frame at most `cap` bytes, and the 16-bit byte sum
/// of type through payload is its checksum field; then the scan goes on
/// after it, otherwise after the `AA` (a dropped candidate, counted). For
/// streams that end in `cap` zero bytes, so that every candidate is
/// complete.
fn reference(bytes: &[u8], cap: usize) -> (Vec<(u8, u8, Vec<u8>)>, u32) {
    let (mut frames, mut dropped, mut at) = (Vec::new(), 0u32, 0);
    while at < bytes.len() {
        let c = &bytes[at..];
        if c[0] != 0xAA {
            at += 1;
            continue;
        }
        let total = usize::from(u16::from_le_bytes([c[4], c[5]])) + 2;
        let good = c[1] == 0x55 && total >= 8 && total <= cap && {
            let sum = c[2..total - 2]
                .iter()
                .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)));
            sum == u16::from_le_bytes([c[total - 2], c[total - 1]])
        };
        if good {
            frames.push((c[2], c[3], c[6..total - 2].to_vec()));
            at += total;
        } else {
            dropped += 1;
            at += 1;
        }
    }
    (frames, dropped)
}

/// A piece of a test stream: a frame, changed or cut short, or garbage
/// rich in `AA` and `AA 55`.
#[derive(Debug, Clone)]
enum Piece {
    Frame(u8, u8, Vec<u8>),
    Flipped(u8, u8, Vec<u8>, usize, u8),
    Cut(u8, u8, Vec<u8>, usize),
    Garbage(Vec<u8>),
}

fn arb_piece() -> impl Strategy<Value = Piece> {
    let garbage = prop::collection::vec(prop_oneof![Just(0xAA), Just(0x55), any::<u8>()], 1..80);
    prop_oneof![
        4 => arb_frame().prop_map(|(t, i, p)| Piece::Frame(t, i, p)),
        1 => (arb_frame(), any::<usize>(), 1u8..=255)
            .prop_map(|((t, i, p), at, x)| Piece::Flipped(t, i, p, at, x)),
        1 => (arb_frame(), any::<usize>()).prop_map(|((t, i, p), n)| Piece::Cut(t, i, p, n)),
        1 => garbage.prop_map(Piece::Garbage),
    ]
}

proptest! {
    /// Good, corrupted and truncated frames between runs of garbage, in
    /// any chunking: the decoder (on hosts, its in-place scan and masked
    /// block checksum) finds the reference's frames and drops as many
    /// candidates.
    #[test]
    fn the_frames_are_those_of_a_byte_wise_scan(
        pieces in prop::collection::vec(arb_piece(), 1..24),
        chunks in prop::collection::vec(1usize..700, 0..40),
    ) {
        let mut bytes = Vec::new();
        for p in &pieces {
            match p {
                Piece::Frame(t, i, p) => bytes.extend(frame(*t, *i, p)),
                Piece::Flipped(t, i, p, at, x) => {
                    let mut f = frame(*t, *i, p);
                    let n = f.len();
                    f[at % n] ^= x;
                    bytes.extend(f);
                }
                Piece::Cut(t, i, p, n) => {
                    let f = frame(*t, *i, p);
                    bytes.extend(&f[..n % f.len()]);
                }
                Piece::Garbage(g) => bytes.extend(g),
            }
        }
        bytes.extend(std::iter::repeat_n(0u8, 265));
        let (want, dropped) = reference(&bytes, 265);
        for chunking in [&chunks[..], &[1], &[bytes.len()]] {
            let mut d = D::new();
            let mut got = Vec::new();
            let mut rest = &bytes[..];
            let mut i = 0;
            while !rest.is_empty() {
                let n = chunking.get(i).copied().unwrap_or(64).clamp(1, rest.len());
                i += 1;
                let mut input = &rest[..n];
                rest = &rest[n..];
                while let Some(f) = d.next_frame(&mut input) {
                    got.push((f.msg_type, f.id, f.payload.to_vec()));
                }
            }
            prop_assert_eq!(&got, &want);
            prop_assert_eq!(d.errors(), dropped);
            prop_assert!(!d.has_partial());
        }
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
