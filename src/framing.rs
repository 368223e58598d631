//! The streaming packet scanner both wire protocols share: KERNEL frames
//! ([`crate::kernel::frame`], ICD Table 5.2) and ISB packets
//! ([`crate::isb::packet`], the ISB protocol page). Each protocol says, in a
//! [`Framing`], what its two preamble bytes are, how long a packet is from
//! its first bytes, and whether a complete packet's check bytes are right;
//! [`Scanner`] does the rest the same way for both.
//!
//! Bytes may arrive in any chunking: the scanner only decides about a
//! candidate packet once it holds all of it, so the packets found depend on
//! the byte sequence alone. A candidate is dropped one byte at a time — its
//! first byte is skipped and the scan restarts right after it — when its
//! second byte is not the second preamble byte, its length is invalid or
//! larger than the buffer, or its check fails; so the next good packet right
//! after a bad one (or inside its bytes) is found. The buffer is bounded
//! (`CAP` bytes, the largest packet accepted); nothing is allocated.

use core::marker::PhantomData;

/// What a wire protocol tells the [`Scanner`].
pub trait Framing {
    /// The two bytes every packet starts with.
    const PREAMBLE: [u8; 2];
    /// Bytes from the start of a packet needed to know its length.
    const HEADER_LEN: usize;
    /// Total packet length from its first [`Framing::HEADER_LEN`] bytes, or
    /// `None` if the header is invalid.
    fn total_len(header: &[u8]) -> Option<usize>;
    /// Whether a complete candidate packet's check bytes are right.
    fn check(packet: &[u8]) -> bool;
    /// [`Framing::check`] of the candidate packet of `total` bytes at the
    /// start of `avail`, which holds all of it and possibly bytes after it
    /// (the rest of the input), which a faster check may read and ignore.
    #[inline]
    fn check_in(avail: &[u8], total: usize) -> bool {
        avail.get(..total).is_some_and(Self::check)
    }
}

/// Streaming packet scanner with a bounded buffer of `CAP` bytes (module
/// doc).
#[derive(Debug, Clone)]
pub struct Scanner<F: Framing, const CAP: usize> {
    buf: [u8; CAP],
    /// Valid bytes are `buf[start..end]`.
    start: usize,
    end: usize,
    /// Total length of a packet just returned, to skip next time.
    consumed: usize,
    /// Count of candidates dropped (bad length, check, abandoned).
    errors: u32,
    framing: PhantomData<F>,
}

impl<F: Framing, const CAP: usize> Default for Scanner<F, CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<F: Framing, const CAP: usize> Scanner<F, CAP> {
    /// An empty scanner.
    pub const fn new() -> Self {
        Scanner {
            buf: [0; CAP],
            start: 0,
            end: 0,
            consumed: 0,
            errors: 0,
            framing: PhantomData,
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

    /// Drops the current candidate (e.g. a packet cut short, detected by an
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
    /// returns the next complete, valid packet (all its bytes), if any.
    /// Call in a loop until it returns `None`; then all of `input` has been
    /// taken. (Each protocol adds a typed reader on top: `next_frame`,
    /// `next_packet`.)
    ///
    /// While no bytes of a candidate are held, packets are
    /// found in `input` itself and returned borrowing it (no copy); only a
    /// candidate cut at the end of `input` is kept in the buffer, and only
    /// the bytes it needs are added to it from the next input, so that the
    /// scan is back in place once it is decided. The packets found are the
    /// same either way.
    #[inline(always)]
    pub fn next_raw<'r, 's: 'r, 'i: 'r>(&'s mut self, input: &mut &'i [u8]) -> Option<&'r [u8]> {
        self.skip_consumed();
        loop {
            if self.start == self.end {
                // Nothing held: scan the input in place.
                let bytes: &'i [u8] = input;
                match scan::<F>(bytes, CAP, &mut self.errors) {
                    Scan::Found { at, total } => {
                        *input = &bytes[at + total..];
                        return Some(&bytes[at..at + total]);
                    }
                    Scan::NeedMore { at } => {
                        // What is left is a candidate shorter than CAP.
                        let rest = &bytes[at..];
                        let n = rest.len().min(CAP);
                        self.buf[..n].copy_from_slice(&rest[..n]);
                        self.start = 0;
                        self.end = n;
                        *input = &rest[n..];
                    }
                }
            }
            match scan::<F>(&self.buf[self.start..self.end], CAP, &mut self.errors) {
                Scan::Found { at, total } => {
                    self.start += at;
                    self.consumed = total;
                    return Some(&self.buf[self.start..self.start + total]);
                }
                Scan::NeedMore { at } => self.start += at,
            }
            if input.is_empty() {
                return None;
            }
            if self.start == self.end {
                continue;
            }
            // Compact and take as many bytes as the held candidate needs.
            if self.start > 0 {
                self.buf.copy_within(self.start..self.end, 0);
                self.end -= self.start;
                self.start = 0;
            }
            let room = CAP - self.end;
            let room = room.min(self.wanted());
            let n = room.min(input.len());
            self.buf[self.end..self.end + n].copy_from_slice(&input[..n]);
            self.end += n;
            *input = &input[n..];
        }
    }

    /// Bytes the held candidate needs before it can be decided: up to its
    /// header, then up to its length (at least one).
    fn wanted(&self) -> usize {
        let held = &self.buf[self.start..self.end];
        let need = match held.get(..F::HEADER_LEN) {
            None => F::HEADER_LEN,
            Some(header) => F::total_len(header).unwrap_or(0),
        };
        need.saturating_sub(held.len()).max(1)
    }
}

/// The first `b` in `bytes` (`memchr`).
#[inline]
fn find_byte(b: u8, bytes: &[u8]) -> Option<usize> {
    // Back-to-back packets: the next one starts right here (no call).
    if bytes.first() == Some(&b) {
        return Some(0);
    }
    memchr::memchr(b, bytes)
}

/// What [`scan`] found in a byte slice.
enum Scan {
    /// A complete valid packet of `total` bytes at `at`.
    Found { at: usize, total: usize },
    /// No complete packet: the bytes before `at` are garbage or dropped
    /// candidates; from `at` on, an incomplete candidate (or nothing).
    NeedMore { at: usize },
}

/// Skips garbage and bad candidates in `avail` (each dropped candidate
/// counted in `errors`) up to the first complete valid packet of at most
/// `cap` bytes.
#[inline(always)]
fn scan<F: Framing>(avail: &[u8], cap: usize, errors: &mut u32) -> Scan {
    let mut at = 0;
    loop {
        let rest = &avail[at..];
        match find_byte(F::PREAMBLE[0], rest) {
            None => return Scan::NeedMore { at: avail.len() },
            Some(i) => at += i,
        }
        let cand = &avail[at..];
        if cand.len() < 2 {
            return Scan::NeedMore { at };
        }
        if cand[1] != F::PREAMBLE[1] {
            at += 1;
            *errors = errors.wrapping_add(1);
            continue;
        }
        if cand.len() < F::HEADER_LEN {
            return Scan::NeedMore { at };
        }
        let total = match F::total_len(&cand[..F::HEADER_LEN]) {
            Some(t) if t <= cap => t,
            _ => {
                at += 1;
                *errors = errors.wrapping_add(1);
                continue;
            }
        };
        if cand.len() < total {
            return Scan::NeedMore { at };
        }
        if !F::check_in(cand, total) {
            at += 1;
            *errors = errors.wrapping_add(1);
            continue;
        }
        return Scan::Found { at, total };
    }
}
