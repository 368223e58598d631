//! A bounded byte backlog: device output that left the (emulated) UART but
//! that the connected client could not take yet — a TCP client or pty
//! reader that is slower than the line. (Output while no client is
//! connected is not kept: the transports drop it, as a real line would.)
//!
//! When full, the oldest bytes are dropped first, so a slow client sees the
//! most recent output (and must resynchronise on `AA 55`).

use std::collections::VecDeque;
use std::io::{self, Write};

/// Default capacity: 64 KiB.
pub const DEFAULT_CAPACITY: usize = 64 * 1024;

/// Bounded FIFO of bytes that drops its oldest bytes when full.
#[derive(Debug)]
pub struct Backlog {
    buf: VecDeque<u8>,
    cap: usize,
    dropped: u64,
}

/// Outcome of [`Backlog::write_to`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flush {
    /// Everything was written; the backlog is empty.
    Done,
    /// The writer would block; bytes remain queued.
    Blocked,
}

impl Default for Backlog {
    fn default() -> Self {
        Self::new(DEFAULT_CAPACITY)
    }
}

impl Backlog {
    /// An empty backlog holding at most `cap` bytes (at least 1).
    pub fn new(cap: usize) -> Self {
        let cap = cap.max(1);
        Backlog {
            buf: VecDeque::with_capacity(cap.min(DEFAULT_CAPACITY)),
            cap,
            dropped: 0,
        }
    }

    /// Queued bytes.
    pub fn len(&self) -> usize {
        self.buf.len()
    }

    /// Whether nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// Bytes dropped so far because the backlog was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Drops everything queued (the client it was for went away); not
    /// counted in [`Backlog::dropped`].
    pub fn clear(&mut self) {
        self.buf.clear();
    }

    /// Appends `bytes`, dropping the oldest queued bytes if the capacity
    /// would be exceeded.
    pub fn push(&mut self, bytes: &[u8]) {
        let bytes = if bytes.len() > self.cap {
            let skip = bytes.len() - self.cap;
            self.dropped += skip as u64;
            &bytes[skip..]
        } else {
            bytes
        };
        let excess = (self.buf.len() + bytes.len()).saturating_sub(self.cap);
        if excess > 0 {
            self.buf.drain(..excess);
            self.dropped += excess as u64;
        }
        self.buf.extend(bytes);
    }

    /// Writes queued bytes to `w` (a nonblocking socket or pty master) until
    /// the backlog is empty or `w` would block. Other errors are returned;
    /// bytes not written stay queued.
    pub fn write_to<W: Write>(&mut self, w: &mut W) -> io::Result<Flush> {
        while !self.buf.is_empty() {
            let (front, _) = self.buf.as_slices();
            match w.write(front) {
                Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
                Ok(n) => {
                    self.buf.drain(..n);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(Flush::Blocked),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(Flush::Done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A writer taking at most `room` bytes, then blocking.
    struct Slow {
        got: Vec<u8>,
        room: usize,
    }

    impl Write for Slow {
        fn write(&mut self, b: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::ErrorKind::WouldBlock.into());
            }
            let n = b.len().min(self.room);
            self.room -= n;
            self.got.extend_from_slice(&b[..n]);
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn drops_oldest_bytes_first() {
        let mut b = Backlog::new(4);
        b.push(&[1, 2, 3]);
        b.push(&[4, 5]);
        assert_eq!(b.len(), 4);
        assert_eq!(b.dropped(), 1);
        b.push(&[6, 7, 8, 9, 10, 11]);
        assert_eq!(b.dropped(), 7);
        let mut w = Slow {
            got: vec![],
            room: 100,
        };
        assert_eq!(b.write_to(&mut w).unwrap(), Flush::Done);
        assert_eq!(w.got, [8, 9, 10, 11]);
    }

    #[test]
    fn keeps_what_a_blocked_writer_did_not_take() {
        let mut b = Backlog::new(64);
        b.push(b"hello world");
        let mut w = Slow {
            got: vec![],
            room: 5,
        };
        assert_eq!(b.write_to(&mut w).unwrap(), Flush::Blocked);
        assert_eq!(w.got, b"hello");
        w.room = 100;
        assert_eq!(b.write_to(&mut w).unwrap(), Flush::Done);
        assert_eq!(w.got, b"hello world");
        assert!(b.is_empty());
    }
}
