//! KERNEL framing (ICD Table 5.2, Table 5.3; `docs/protocol-facts.md`
//! "KERNEL framing").
//!
//! `AA 55 | type | id | len u16 LE | payload | sum u16 LE`, where
//! `len = payload_len + 6` and `sum` is the wrapping 16-bit sum of every byte
//! from `type` through the last payload byte.

use crate::framing::{Framing, Scanner};

/// The two header bytes.
pub const HEADER: [u8; 2] = [0xAA, 0x55];
/// Bytes a frame adds around its payload (header 2, type, id, len 2, sum 2).
pub const OVERHEAD: usize = 8;
/// Smallest valid value of the length field (empty payload).
pub const MIN_LEN_FIELD: u16 = 6;
/// Message type of host → device commands (Table 5.2).
pub const TYPE_COMMAND: u8 = 0x00;
/// Message type of everything the device sends (Table 5.2).
pub const TYPE_DATA: u8 = 0x01;

/// Wrapping 16-bit sum of `bytes` (Table 5.2 "Checksum").
///
/// A word at a time: a word's even and odd bytes are added in its 16-bit
/// lanes (folded before a lane can carry) — on 64-bit hosts four lanes of
/// a `u64`, eight bytes a step, on the 32-bit firmware two lanes of a
/// `u32` (no 64-bit arithmetic on a Cortex-M); a third to a sixth of the
/// instructions of a byte loop. (The [`Decoder`] checks the frames it
/// finds in its input in 64-byte blocks instead: `sum_from_header`.)
pub fn checksum(bytes: &[u8]) -> u16 {
    // Fork by word size: 64-bit arithmetic is two instructions a step on a Cortex-M.
    if cfg!(target_pointer_width = "64") {
        checksum_u64(bytes)
    } else {
        checksum_u32(bytes)
    }
}

/// [`checksum`] in the 16-bit lanes of a `u32`: folded every 128 words.
fn checksum_u32(bytes: &[u8]) -> u16 {
    let mut total = 0u32;
    for block in bytes.chunks(512) {
        let words = block.chunks_exact(4);
        for &b in words.remainder() {
            total = total.wrapping_add(u32::from(b));
        }
        let mut lanes = 0u32;
        for w in words {
            let w = u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
            lanes += (w & 0x00FF_00FF) + ((w >> 8) & 0x00FF_00FF);
        }
        total = total.wrapping_add((lanes & 0xFFFF) + (lanes >> 16));
    }
    total as u16
}

/// [`checksum`] in the 16-bit lanes of `u64`s, the even bytes in one,
/// the odd in the other (folded every 128 words: a lane takes at most 255
/// a word, two lanes summed 510), the tail (< 8 bytes) a byte at a time.
fn checksum_u64(bytes: &[u8]) -> u16 {
    const EVEN: u64 = 0x00FF_00FF_00FF_00FF;
    let mut total = 0u64;
    for block in bytes.chunks(1024) {
        let words = block.chunks_exact(8);
        for &b in words.remainder() {
            total += u64::from(b);
        }
        let (mut even, mut odd) = (0u64, 0u64);
        for w in words {
            // One 8-byte load (`w` is 8 bytes long).
            let w = w.first_chunk::<8>().map_or(0, |a| u64::from_le_bytes(*a));
            even += w & EVEN;
            odd += (w >> 8) & EVEN;
        }
        let lanes = even + odd;
        total +=
            (lanes & 0xFFFF) + ((lanes >> 16) & 0xFFFF) + ((lanes >> 32) & 0xFFFF) + (lanes >> 48);
    }
    total as u16
}

/// 64 bytes `0xFF` then 64 bytes `0`: the 64 bytes from `64 - n` keep the
/// first `n` bytes of a block ([`sum_from_header`]).
static KEEP: [u8; 128] = {
    let mut m = [0u8; 128];
    let mut i = 0;
    while i < 64 {
        m[i] = 0xFF;
        i += 1;
    }
    m
};

/// Sum of a 64-byte block's bytes (on x86-64, four SSE2 `PSADBW`).
#[inline(always)]
fn block_sum(block: &[u8; 64]) -> u32 {
    block.iter().map(|&b| u32::from(b)).sum()
}

/// The checksum field a frame starting at `avail[0]` (its header `AA 55`)
/// must have if its body — header through last payload byte — is
/// `avail[..n]` (Table 5.2: the 16-bit sum of `avail[2..n]`), or `None`
/// when fewer than 64 bytes follow the last whole 64-byte block of the
/// body. For the [`Scanner`], which finds frames in the input: no
/// byte loop and no loop at all for a body of up to 64 bytes — 64-byte
/// blocks summed whole, the last one with the bytes past the body masked
/// off (so it reads up to 63 bytes past the body, which the input holds:
/// the next frames), the header's `0xAA + 0x55` subtracted.
#[inline]
fn sum_from_header(avail: &[u8], n: usize) -> Option<u16> {
    let mut total = 0u32;
    let mut at = 0;
    while n - at > 64 {
        total = total.wrapping_add(block_sum(avail.get(at..)?.first_chunk::<64>()?));
        at += 64;
    }
    let last = avail.get(at..)?.first_chunk::<64>()?;
    let keep = KEEP.get(64 - (n - at)..)?.first_chunk::<64>()?;
    let mut masked = [0u8; 64];
    for ((m, &b), &k) in masked.iter_mut().zip(last).zip(keep) {
        *m = b & k;
    }
    total = total.wrapping_add(block_sum(&masked));
    Some((total as u16).wrapping_sub(u16::from(HEADER[0]) + u16::from(HEADER[1])))
}

/// A decoded frame borrowing the decoder's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Message type (0 command, 1 data).
    pub msg_type: u8,
    /// KERNEL data identifier (the command code or data format code).
    pub id: u8,
    /// The payload.
    pub payload: &'a [u8],
    /// The frame's checksum field (verified).
    pub checksum: u16,
}

/// Encodes a frame into `out`; returns its length, or `None` if `out` is too
/// small or the payload longer than the length field can express.
pub fn encode(msg_type: u8, id: u8, payload: &[u8], out: &mut [u8]) -> Option<usize> {
    let total = payload.len().checked_add(OVERHEAD)?;
    let len_field = u16::try_from(payload.len() + 6).ok()?;
    let out = out.get_mut(..total)?;
    out[0] = HEADER[0];
    out[1] = HEADER[1];
    out[2] = msg_type;
    out[3] = id;
    out[4..6].copy_from_slice(&len_field.to_le_bytes());
    out[6..6 + payload.len()].copy_from_slice(payload);
    let sum = checksum(&out[2..6 + payload.len()]);
    out[6 + payload.len()..].copy_from_slice(&sum.to_le_bytes());
    Some(total)
}

/// The KERNEL rules for the shared [`Scanner`]: header `AA 55`, length
/// field at bytes 4–5 (≥ 6), the 16-bit sum of type through payload.
#[derive(Debug, Clone, Copy)]
pub struct Kernel;

impl Framing for Kernel {
    const PREAMBLE: [u8; 2] = HEADER;
    const HEADER_LEN: usize = 6;

    #[inline]
    fn total_len(header: &[u8]) -> Option<usize> {
        let len_field = u16::from_le_bytes([header[4], header[5]]);
        (len_field >= MIN_LEN_FIELD).then_some(usize::from(len_field) + 2)
    }

    #[inline]
    fn check(packet: &[u8]) -> bool {
        let n = packet.len();
        checksum(&packet[2..n - 2]) == u16::from_le_bytes([packet[n - 2], packet[n - 1]])
    }

    /// The checksum summed in 64-byte blocks, the bytes of
    /// `avail` after the frame read and masked off; a frame too close to
    /// the end of `avail` for that, [`Kernel::check`].
    #[inline(always)]
    fn check_in(avail: &[u8], total: usize) -> bool {
        // Shorter than header and checksum: no frame (the scanner only
        // asks about candidates of 8 bytes or more).
        let Some(packet) = avail.get(..total).filter(|p| p.len() >= 4) else {
            return false;
        };
        match sum_from_header(avail, total - 2) {
            Some(sum) => sum == u16::from_le_bytes([packet[total - 2], packet[total - 1]]),
            None => Self::check(packet),
        }
    }
}

/// Streaming frame decoder with a bounded buffer of `CAP` bytes; `CAP` is
/// the largest frame (payload + 8) it accepts.
///
/// Bytes may arrive in any chunking (the [`crate::framing`] scanner): a
/// candidate is dropped one byte at a time — its first byte is skipped and
/// the scan restarts right after it — when its second byte is not `0x55`,
/// its length field is < 6 or larger than `CAP` allows, or its checksum is
/// wrong; so the next good frame right after a bad one (or inside its
/// bytes) is found. [`Scanner::abandon`] drops a candidate that was cut
/// short (the device calls it after an idle gap).
pub type Decoder<const CAP: usize> = Scanner<Kernel, CAP>;

impl<const CAP: usize> Scanner<Kernel, CAP> {
    /// Feeds bytes from `input` (advancing it past what was taken) and
    /// returns the next complete, valid frame, if any. Call in a loop until
    /// it returns `None`; then all of `input` has been taken.
    #[inline(always)]
    pub fn next_frame<'r, 's: 'r, 'i: 'r>(&'s mut self, input: &mut &'i [u8]) -> Option<Frame<'r>> {
        let b = self.next_raw(input)?;
        let n = b.len();
        Some(Frame {
            msg_type: b[2],
            id: b[3],
            payload: &b[6..n - 2],
            checksum: u16::from_le_bytes([b[n - 2], b[n - 1]]),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames<const C: usize>(d: &mut Decoder<C>, mut input: &[u8]) -> usize {
        let mut n = 0;
        while d.next_frame(&mut input).is_some() {
            n += 1;
        }
        n
    }

    #[test]
    fn both_checksums_are_the_byte_sum() {
        let bytes: std::vec::Vec<u8> = (0..3000u32).map(|i| (i * 151 + i / 7) as u8).collect();
        for n in (0..40).chain([511, 512, 513, 1023, 1024, 1025, 2047, 2048, 2049, 3000]) {
            for start in 0..3 {
                let b = &bytes[start..n.max(start)];
                let want = b.iter().fold(0u16, |s, &x| s.wrapping_add(u16::from(x)));
                assert_eq!(checksum_u32(b), want, "{n}");
                assert_eq!(checksum_u64(b), want, "{n}");
            }
        }
        let ff = [0xFFu8; 3000];
        let want = (3000u32 * 255) as u16;
        assert_eq!(checksum_u32(&ff), want);
        assert_eq!(checksum_u64(&ff), want);
    }

    /// The masked-block sum is the byte sum at every start
    /// alignment, every body length up to past two blocks and the fold
    /// limit, with no, few and many bytes after the body (`None` exactly
    /// when fewer than 64 bytes follow its last whole block).
    #[test]
    fn the_masked_block_sum_is_the_byte_sum() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut bytes = std::vec![0u8; 1400];
        for b in bytes.iter_mut() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            *b = x as u8;
        }
        for fill in [None, Some(0x00), Some(0xFF)] {
            let mut bytes = bytes.clone();
            if let Some(f) = fill {
                bytes.fill(f);
            }
            for start in 0..16 {
                bytes[start..start + 2].copy_from_slice(&HEADER);
                for n in (2..300).chain(1000..=1100) {
                    let body = &bytes[start..start + n];
                    let want = body[2..]
                        .iter()
                        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)));
                    let whole = (n - 1) / 64 * 64;
                    for after in [0, 1, 2, 31, 62, 63, 64, 65, 200] {
                        let avail = &bytes[start..start + n + after];
                        let got = sum_from_header(avail, n);
                        let room = avail.len() - whole >= 64;
                        assert_eq!(got, room.then_some(want), "{start} {n} {after}");
                    }
                }
                bytes[start..start + 2].copy_from_slice(&[0, 0]);
            }
        }
    }

    /// The check of a frame in place gives the byte-wise check's
    /// answer for good and corrupted frames (a payload, type or length byte
    /// changed, the checksum), at every distance from the end of the input.
    #[test]
    fn the_in_place_check_is_the_byte_wise_check() {
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut out = [0u8; 600];
        for round in 0..3000 {
            let len = (next() % 300) as usize;
            let payload: std::vec::Vec<u8> = (0..len).map(|_| next() as u8).collect();
            let n = encode(1, next() as u8, &payload, &mut out).unwrap();
            let mut stream = out[..n].to_vec();
            match round % 4 {
                0 => {}
                1 => {
                    let i = 2 + (next() as usize % (n - 2));
                    stream[i] ^= 1 << (next() % 8);
                }
                2 => stream[n - 1 - (next() as usize % 2)] ^= 0x80,
                _ => {
                    let i = 2 + (next() as usize % (n - 2));
                    stream[i] = stream[i].wrapping_add(1 + (next() % 255) as u8);
                }
            }
            let tail: std::vec::Vec<u8> = (0..130).map(|_| next() as u8).collect();
            stream.extend_from_slice(&tail);
            let want =
                checksum(&stream[2..n - 2]) == u16::from_le_bytes([stream[n - 2], stream[n - 1]]);
            assert_eq!(want, round % 4 == 0);
            for after in 0..=130 {
                let avail = &stream[..n + after];
                assert_eq!(Kernel::check_in(avail, n), want, "{round} {after}");
                assert_eq!(Kernel::check(&avail[..n]), want);
            }
        }
        // No panic on lengths no candidate has, or past the input.
        for total in 0..4 {
            assert!(!Kernel::check_in(&[0xAA, 0x55, 0, 0, 0, 0, 0, 0], total));
        }
        assert!(!Kernel::check_in(&[0xAA, 0x55, 0, 0], 9));
    }

    /// A frame cut between two inputs is completed in the buffer with only
    /// the bytes it lacks; the frames after it are found in the input in
    /// place (returned borrowing it), as before the cut.
    #[test]
    fn after_a_cut_frame_the_scan_is_back_in_the_input() {
        let mut stream = std::vec::Vec::new();
        let mut out = [0u8; 64];
        for i in 0..4u8 {
            let n = encode(1, 0x8F, &[i; 32], &mut out).unwrap();
            stream.extend_from_slice(&out[..n]);
        }
        let (first, second) = stream.split_at(20);
        let mut d = Decoder::<512>::new();
        let mut input = first;
        assert!(d.next_frame(&mut input).is_none());
        assert!(d.has_partial());
        let mut input = second;
        let f = d.next_frame(&mut input).unwrap();
        assert_eq!(f.payload, &[0; 32]);
        let inside = |p: &[u8]| second.as_ptr_range().contains(&p.as_ptr());
        assert!(!inside(f.payload));
        for i in 1..4 {
            let f = d.next_frame(&mut input).unwrap();
            assert_eq!(f.payload, &[i; 32]);
            assert!(inside(f.payload), "frame {i} copied");
        }
        assert!(d.next_frame(&mut input).is_none());
        assert!(input.is_empty() && !d.has_partial());
    }

    #[test]
    fn encode_matches_the_stop_command() {
        let mut out = [0u8; 16];
        let n = encode(0, 0, &[0xFE], &mut out).unwrap();
        assert_eq!(
            &out[..n],
            &[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0xFE, 0x05, 0x01]
        );
        assert_eq!(encode(0, 0, &[0; 9], &mut out), None);
    }

    #[test]
    fn a_header_byte_inside_a_bad_frame_is_rescanned() {
        // A bad frame whose payload contains a good Stop frame.
        let stop = [0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0xFE, 0x05, 0x01];
        let mut bad = std::vec![0xAA, 0x55, 0x00, 0x00, 0x0D, 0x00];
        bad.extend_from_slice(&stop);
        bad.extend_from_slice(&[0x00, 0x00]);
        let mut d = Decoder::<64>::new();
        assert_eq!(frames(&mut d, &bad), 1);
    }
}
