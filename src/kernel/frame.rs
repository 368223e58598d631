//! KERNEL framing (ICD Table 5.2, Table 5.3; NOTES.md "framing").
//!
//! `AA 55 | type | id | len u16 LE | payload | sum u16 LE`, where
//! `len = payload_len + 6` and `sum` is the wrapping 16-bit sum of every byte
//! from `type` through the last payload byte.

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
/// Four bytes at a time: a word's even and odd bytes are added in the two
/// 16-bit lanes of a `u32` (folded every 128 words, before a lane can
/// carry), about a third of the instructions of a byte loop.
pub fn checksum(bytes: &[u8]) -> u16 {
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

/// Streaming frame decoder with a bounded buffer of `CAP` bytes; `CAP` is
/// the largest frame (payload + 8) it accepts.
///
/// Bytes may arrive in any chunking: the decoder only decides about a
/// candidate frame once it holds all of it, so the frames found depend on the
/// byte sequence alone. A candidate is dropped one byte at a time — its
/// first byte is skipped and the scan restarts right after it — when its
/// second byte is not `0x55`, its length field is < 6 or larger than `CAP`
/// allows, or its checksum is wrong; so the next good frame right after a bad
/// one (or inside its bytes) is found. [`Decoder::abandon`] drops a candidate
/// that was cut short (the device calls it after an idle gap).
#[derive(Debug, Clone)]
pub struct Decoder<const CAP: usize> {
    buf: [u8; CAP],
    /// Valid bytes are `buf[start..end]`.
    start: usize,
    end: usize,
    /// Total frame length of a candidate just returned, to skip next time.
    consumed: usize,
    /// Count of candidates dropped (bad length, checksum, abandoned).
    errors: u32,
}

impl<const CAP: usize> Default for Decoder<CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize> Decoder<CAP> {
    /// An empty decoder.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; CAP],
            start: 0,
            end: 0,
            consumed: 0,
            errors: 0,
        }
    }

    /// Number of dropped candidates so far (for diagnostics and tests).
    pub fn errors(&self) -> u32 {
        self.errors
    }

    /// Whether bytes of an incomplete candidate are held.
    pub fn has_partial(&self) -> bool {
        self.consumed == 0 && self.start < self.end
    }

    /// Drops the current candidate (e.g. a frame cut short, detected by an
    /// idle gap) and rescans the bytes after its first byte.
    pub fn abandon(&mut self) {
        self.skip_consumed();
        if self.start < self.end {
            self.start += 1;
            self.errors = self.errors.wrapping_add(1);
        }
    }

    fn skip_consumed(&mut self) {
        self.start += self.consumed;
        self.consumed = 0;
    }

    /// Feeds bytes from `input` (advancing it past what was taken) and
    /// returns the next complete, valid frame, if any. Call in a loop until
    /// it returns `None`; then all of `input` has been taken.
    pub fn next_frame<'s>(&'s mut self, input: &mut &[u8]) -> Option<Frame<'s>> {
        self.skip_consumed();
        loop {
            // Scan what is buffered.
            match self.scan() {
                Scan::Found(total) => {
                    self.consumed = total;
                    let b = &self.buf[self.start..self.start + total];
                    let plen = total - OVERHEAD;
                    return Some(Frame {
                        msg_type: b[2],
                        id: b[3],
                        payload: &b[6..6 + plen],
                        checksum: u16::from_le_bytes([b[6 + plen], b[7 + plen]]),
                    });
                }
                Scan::NeedMore => {}
            }
            if input.is_empty() {
                return None;
            }
            // Compact and take as many bytes as fit.
            if self.start > 0 {
                self.buf.copy_within(self.start..self.end, 0);
                self.end -= self.start;
                self.start = 0;
            }
            let room = CAP - self.end;
            let n = room.min(input.len());
            self.buf[self.end..self.end + n].copy_from_slice(&input[..n]);
            self.end += n;
            *input = &input[n..];
        }
    }

    /// Advances `start` past garbage and bad candidates; reports a complete
    /// valid frame at `start`, or that more bytes are needed.
    fn scan(&mut self) -> Scan {
        loop {
            let avail = &self.buf[self.start..self.end];
            match avail.iter().position(|&b| b == HEADER[0]) {
                None => {
                    self.start = self.end;
                    return Scan::NeedMore;
                }
                Some(0) => {}
                Some(i) => self.start += i,
            }
            let avail = &self.buf[self.start..self.end];
            if avail.len() < 2 {
                return Scan::NeedMore;
            }
            if avail[1] != HEADER[1] {
                self.drop_candidate();
                continue;
            }
            if avail.len() < 6 {
                return Scan::NeedMore;
            }
            let len_field = usize::from(u16::from_le_bytes([avail[4], avail[5]]));
            let total = len_field + 2;
            if len_field < usize::from(MIN_LEN_FIELD) || total > CAP {
                self.drop_candidate();
                continue;
            }
            if avail.len() < total {
                return Scan::NeedMore;
            }
            let sum = u16::from_le_bytes([avail[total - 2], avail[total - 1]]);
            if checksum(&avail[2..total - 2]) != sum {
                self.drop_candidate();
                continue;
            }
            return Scan::Found(total);
        }
    }

    fn drop_candidate(&mut self) {
        self.start += 1;
        self.errors = self.errors.wrapping_add(1);
    }
}

enum Scan {
    Found(usize),
    NeedMore,
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
