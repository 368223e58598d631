//! Where the emulated UART's bytes go: a TCP port or a pseudo-terminal.
//!
//! Both transports are nonblocking and driven by the single-threaded
//! [`crate::runner`] loop: it waits in [`Transport::wait`] (a `ppoll` on the
//! transport's descriptors with a timeout up to the next tick deadline),
//! takes host → device bytes with [`Transport::receive`], and hands paced
//! device → host bytes to [`Transport::send`]. Output the peer cannot take
//! right now is kept in a bounded [`crate::backlog::Backlog`].

use std::time::Duration;

pub mod pty;
pub mod tcp;

pub use pty::PtyTransport;
pub use tcp::TcpTransport;

/// A byte pipe between the device's UART and the host side.
pub trait Transport {
    /// Where the transport listens, as printed on the first stdout line
    /// after `listening on ` (`tcp 127.0.0.1:7000`, `pty /dev/pts/5`).
    fn describe(&self) -> String;

    /// Blocks until input may be readable, queued output may be writable,
    /// a signal arrives, or `timeout` passes (sub-millisecond precision).
    fn wait(&mut self, timeout: Duration) -> anyhow::Result<()>;

    /// Accepts pending connections and reads what is available, at most
    /// `max` bytes (the runner bounds its work per pass: a flood must not
    /// starve the ticks), handing each received chunk to `sink`. Never
    /// blocks.
    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()>;

    /// Queues device output in the bounded backlog; [`Transport::flush`]
    /// writes it (the runner flushes once a pass, so the bytes of a batch
    /// of ticks go out in one write). Never blocks.
    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()>;

    /// Writes backlog bytes the peer takes now. Never blocks.
    fn flush(&mut self) -> anyhow::Result<()>;

    /// The emulated line rate changed to `bps` (bit/s).
    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()>;

    /// Bytes waiting in the backlog.
    fn backlog_len(&self) -> usize;
}

/// Converts a timeout into the `ppoll` time spec (rounded up to 1 µs so a
/// tiny positive timeout does not turn into a busy poll).
pub(crate) fn timespec(timeout: Duration) -> nix::sys::time::TimeSpec {
    let t = if timeout.is_zero() {
        timeout
    } else {
        timeout.max(Duration::from_micros(1))
    };
    nix::sys::time::TimeSpec::from_duration(t)
}

/// Runs `ppoll` over `fds`, treating `EINTR` (a signal) as a wakeup.
pub(crate) fn poll_fds(fds: &mut [nix::poll::PollFd<'_>], timeout: Duration) -> anyhow::Result<()> {
    match nix::poll::ppoll(fds, Some(timespec(timeout)), None) {
        Ok(_) | Err(nix::errno::Errno::EINTR) => Ok(()),
        Err(e) => Err(anyhow::Error::new(e).context("ppoll")),
    }
}
