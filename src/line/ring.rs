//! The TX ring and the line model of the device shell (see [`Line`]).

use super::pacer::{byte_time_ps, wire_ns};
use crate::time::Instant;

/// Device TX queue (the UART buffer): frames that do not fit are dropped
/// whole, as a device whose line is too slow would.
pub const TX_CAP: usize = 2048;

/// The storage of the TX queue: [`TX_CAP`] bytes and, after them, room for
/// the largest frame the personality writes in one piece
/// ([`TxBuffer::MAX_FRAME`]). A personality chooses it
/// (`crate::personality::Personality::TxBuffer`) as
/// `[u8; TX_CAP + its largest frame]`, so the line is sized by the protocol
/// it carries and names none. (A type, not a `const` of the personality:
/// stable Rust cannot size an array from a generic parameter's constant.)
pub trait TxBuffer: Sized {
    /// The buffer zeroed.
    const EMPTY: Self;
    /// The largest frame the queue takes in one piece: the buffer's length
    /// less [`TX_CAP`] (a buffer no longer than [`TX_CAP`] does not compile).
    const MAX_FRAME: usize;
    /// The bytes.
    fn bytes(&self) -> &[u8];
    /// The bytes, mutably.
    fn bytes_mut(&mut self) -> &mut [u8];
}

impl<const N: usize> TxBuffer for [u8; N] {
    const EMPTY: Self = [0; N];
    const MAX_FRAME: usize = {
        assert!(N > TX_CAP, "a TX buffer holds TX_CAP bytes and one frame");
        N - TX_CAP
    };

    #[inline(always)]
    fn bytes(&self) -> &[u8] {
        self
    }

    #[inline(always)]
    fn bytes_mut(&mut self) -> &mut [u8] {
        self
    }
}

/// The UART transmit queue: [`TX_CAP`] bytes (what [`TxRing::free`]
/// counts) in a buffer [`TxBuffer::MAX_FRAME`] bytes longer, so that a frame
/// is always written in place in one piece ([`TxRing::push_frame`]): one
/// that starts near the end runs on past [`TX_CAP`], that point becomes the
/// end of the ring until the reader has passed it, and the next frame
/// starts at 0.
struct TxRing<B: TxBuffer> {
    buf: B,
    head: usize,
    len: usize,
    /// Where the bytes wrap to 0: [`TX_CAP`], or the end of a frame that ran
    /// past it (until the reader passes it).
    end: usize,
}

impl<B: TxBuffer> TxRing<B> {
    const fn new() -> Self {
        TxRing {
            buf: B::EMPTY,
            head: 0,
            len: 0,
            end: TX_CAP,
        }
    }

    fn free(&self) -> usize {
        TX_CAP - self.len
    }

    fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.end = TX_CAP;
    }

    /// Appends an `n`-byte frame that `fill` writes in place (the caller
    /// checked [`TxRing::free`]); nothing is queued if `fill` returns
    /// `false` or the frame is longer than [`TxBuffer::MAX_FRAME`].
    ///
    /// The tail is always below [`TX_CAP`]; written after the reader's
    /// bytes it may run into the extra bytes, written before them (wrapped)
    /// it ends at or below `head − (end − TX_CAP)` since at most [`TX_CAP`]
    /// bytes are queued, so it never meets them.
    fn push_frame(&mut self, n: usize, fill: impl FnOnce(&mut [u8]) -> bool) -> bool {
        if n > self.free().min(B::MAX_FRAME) {
            return false;
        }
        let mut tail = self.head + self.len;
        if tail >= self.end {
            tail -= self.end;
        }
        let Some(f) = self.buf.bytes_mut().get_mut(tail..tail + n) else {
            return false;
        };
        if !fill(f) {
            return false;
        }
        if tail + n >= TX_CAP {
            self.end = tail + n;
        }
        self.len += n;
        true
    }

    /// Moves up to `out.len()` bytes out.
    fn pop(&mut self, out: &mut [u8]) -> usize {
        let n = out.len().min(self.len);
        let first = n.min(self.end - self.head);
        let buf = self.buf.bytes();
        out[..first].copy_from_slice(&buf[self.head..self.head + first]);
        out[first..n].copy_from_slice(&buf[..n - first]);
        self.head += n;
        if self.head >= self.end {
            self.head -= self.end;
            self.end = TX_CAP;
        }
        self.len -= n;
        n
    }
}

/// What [`Line::push_frame`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Queued {
    /// The frame is queued; its last bit leaves the line at this time.
    Yes(Instant),
    /// No room in the queue: dropped whole (and counted).
    Full,
    /// Not sent (the frame writer refused, or the frame is too long).
    No,
}

impl Queued {
    /// When the queued frame's last bit leaves the line, if it was queued.
    pub(crate) fn end(self) -> Option<Instant> {
        match self {
            Queued::Yes(end) => Some(end),
            _ => None,
        }
    }
}

/// The device's serial line: the TX queue, the line rate, when the UART
/// will have sent everything queued (assuming it sends back to back at the
/// current rate), and a rate switch waiting for the bytes queued before it.
/// `B` is the queue's storage, chosen by the personality ([`TxBuffer`]).
pub struct Line<B: TxBuffer> {
    tx: TxRing<B>,
    dropped: u32,
    rate: u32,
    /// Time one byte occupies the line at `rate`, ps.
    byte_time_ps: u64,
    /// When the UART will have sent everything queued so far.
    free_at: Instant,
    /// Line-rate switch waiting for the bytes queued before it: (rate, bytes).
    switch: Option<(u32, usize)>,
}

impl<B: TxBuffer> Line<B> {
    /// An empty line at 115 200 bit/s, idle from `now`.
    pub(crate) const fn new(now: Instant) -> Self {
        Line {
            tx: TxRing::new(),
            dropped: 0,
            rate: 115_200,
            byte_time_ps: byte_time_ps(115_200),
            free_at: now,
            switch: None,
        }
    }

    /// Power-on: the queue empties, no switch pending, idle from `now`.
    /// (The drop count is kept: it counts over the board's whole run.)
    pub(crate) fn reset(&mut self, now: Instant) {
        self.tx.clear();
        self.switch = None;
        self.free_at = now;
    }

    /// Queues an `n`-byte frame that `fill` writes in place (`false`: send
    /// nothing); a frame that does not fit is dropped whole and counted.
    /// `now` is the device's latest time (the line cannot have started
    /// before it).
    pub(crate) fn push_frame(
        &mut self,
        n: usize,
        now: Instant,
        fill: impl FnOnce(&mut [u8]) -> bool,
    ) -> Queued {
        if self.tx.free() < n {
            self.dropped = self.dropped.wrapping_add(1);
            return Queued::Full;
        }
        if !self.tx.push_frame(n, fill) {
            return Queued::No;
        }
        let start = self.free_at.max(now);
        self.free_at = start.plus_nanos(wire_ns(n, self.byte_time_ps));
        Queued::Yes(self.free_at)
    }

    /// Bytes free in the queue.
    pub fn free(&self) -> usize {
        self.tx.free()
    }

    /// Bytes queued.
    pub(crate) fn len(&self) -> usize {
        self.tx.len
    }

    /// Whether nothing is queued.
    pub(crate) fn is_empty(&self) -> bool {
        self.tx.len == 0
    }

    /// Frames dropped because the queue was full.
    pub(crate) fn dropped(&self) -> u32 {
        self.dropped
    }

    /// The line rate the device runs at, bit/s.
    pub(crate) fn rate(&self) -> u32 {
        self.rate
    }

    /// Sets the rate the device models from now on (wire time, and the
    /// rate a personality's rate rule reads).
    pub(crate) fn set_rate(&mut self, bps: u32) {
        self.rate = bps.max(1);
        self.byte_time_ps = byte_time_ps(self.rate);
    }

    /// Switches to `bps` after the bytes queued so far: the model's rate
    /// changes now, the board is told (an event) once it has taken those
    /// bytes.
    pub(crate) fn switch_rate_after_queued(&mut self, bps: u32) {
        self.set_rate(bps);
        self.switch = Some((self.rate, self.tx.len));
    }

    /// Moves up to `buf.len()` queued bytes into `buf`, stopping at a
    /// pending rate switch.
    pub(crate) fn pop(&mut self, buf: &mut [u8]) -> usize {
        let limit = match self.switch {
            Some((_, before)) => before,
            None => usize::MAX,
        };
        let want = buf.len().min(limit);
        let n = self.tx.pop(&mut buf[..want]);
        if let Some((_, before)) = self.switch.as_mut() {
            *before -= n;
        }
        n
    }

    /// The rate switch whose bytes have all been taken, if any (it is then
    /// no longer pending).
    pub(crate) fn take_due_switch(&mut self) -> Option<u32> {
        if let Some((rate, 0)) = self.switch {
            self.switch = None;
            return Some(rate);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest frame of the tests' queue.
    const MAX_FRAME: usize = 418;
    type Line = super::Line<[u8; TX_CAP + MAX_FRAME]>;

    #[test]
    fn wire_time_is_ten_bit_times_a_byte() {
        let mut l = Line::new(Instant::ZERO);
        l.set_rate(2_000_000);
        let end = l.push_frame(40, Instant::ZERO, |_| true).end();
        assert_eq!(end, Some(Instant::from_micros(200)));
        // Back to back: the next frame starts when the first has left.
        let end = l.push_frame(40, Instant::from_micros(100), |_| true).end();
        assert_eq!(end, Some(Instant::from_micros(400)));
    }

    #[test]
    fn a_frame_that_does_not_fit_is_dropped_whole_and_counted() {
        let mut l = Line::new(Instant::ZERO);
        for _ in 0..TX_CAP / 200 {
            assert!(l.push_frame(200, Instant::ZERO, |_| true).end().is_some());
        }
        assert_eq!(l.push_frame(200, Instant::ZERO, |_| true), Queued::Full);
        assert_eq!(l.dropped(), 1);
        assert_eq!(l.len(), TX_CAP / 200 * 200);
    }

    #[test]
    fn a_rate_switch_waits_for_the_bytes_queued_before_it() {
        let mut l = Line::new(Instant::ZERO);
        l.push_frame(10, Instant::ZERO, |f| {
            f.fill(7);
            true
        });
        l.switch_rate_after_queued(921_600);
        l.push_frame(5, Instant::ZERO, |_| true);
        let mut out = [0u8; 64];
        assert_eq!(l.pop(&mut out), 10);
        assert_eq!(l.pop(&mut out), 0, "held back until the switch is taken");
        assert_eq!(l.take_due_switch(), Some(921_600));
        assert_eq!(l.pop(&mut out), 5);
    }

    #[test]
    fn frames_wrap_in_one_piece() {
        let mut l = Line::new(Instant::ZERO);
        let mut out = [0u8; TX_CAP];
        let mut seq = 0u8;
        for _ in 0..50 {
            for _ in 0..3 {
                let s = seq;
                l.push_frame(MAX_FRAME, Instant::ZERO, |f| {
                    f.fill(s);
                    true
                });
                seq = seq.wrapping_add(1);
            }
            let n = l.pop(&mut out);
            assert_eq!(n, 3 * MAX_FRAME);
            for (k, chunk) in out[..n].chunks(MAX_FRAME).enumerate() {
                let want = seq.wrapping_sub(3).wrapping_add(k as u8);
                assert!(chunk.iter().all(|&b| b == want));
            }
        }
    }
}
