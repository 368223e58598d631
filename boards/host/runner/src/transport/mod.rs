//! Where the emulated UART's bytes go: a TCP port, a pseudo-terminal or a
//! real serial port.
//!
//! Both transports are nonblocking and driven by the single-threaded
//! [`crate::runner`] loop: it waits in [`Transport::wait`] (a `ppoll` on the
//! transport's descriptors with a timeout up to the next tick deadline),
//! takes host → device bytes with [`Transport::receive`], and hands paced
//! device → host bytes to [`Transport::send`]. Output the peer cannot take
//! right now is kept in a bounded [`crate::backlog::Backlog`]; output while
//! no client is connected is dropped, as on a real line.

use std::time::Duration;

pub mod pty;
pub mod serial;
pub mod tcp;

pub use pty::PtyTransport;
pub use serial::SerialTransport;
pub use tcp::TcpTransport;

/// A byte pipe between the device's UART and the host side.
pub trait Transport {
    /// Where the transport listens, as printed on the first stdout line
    /// after `listening on ` (`tcp 127.0.0.1:7000`, `pty /dev/pts/5`).
    fn describe(&self) -> String;

    /// Blocks until input may be readable, queued output may be writable,
    /// a signal arrives, or `timeout` passes (sub-millisecond precision):
    /// one `ppoll` over the descriptors [`Transport::interest`] names.
    fn wait(&mut self, timeout: Duration) -> anyhow::Result<()> {
        self.prepare_wait()?;
        let revents = {
            let mut fds = Vec::with_capacity(2);
            self.interest(&mut fds);
            poll_fds(&mut fds, timeout)?;
            revents(&fds)
        };
        self.polled(&revents);
        Ok(())
    }

    /// The first step of a wait, which may be shared with other
    /// transports in one `ppoll` (the many-device mode, [`crate::fleet`]):
    /// notes what changed since the last wait (a pty opened or closed, a
    /// listener's back-off over).
    fn prepare_wait(&mut self) -> anyhow::Result<()> {
        Ok(())
    }

    /// Appends the descriptors to wait on and the events of interest
    /// (none: the transport only waits for the timeout).
    fn interest<'a>(&'a self, fds: &mut Vec<nix::poll::PollFd<'a>>);

    /// What the `ppoll` saw on the descriptors [`Transport::interest`]
    /// appended, in the same order. A transport may skip its `accept` and
    /// `read` calls in [`Transport::receive`] when it saw nothing readable
    /// (level-triggered: what is not seen now is seen at the next wait).
    fn polled(&mut self, revents: &[nix::poll::PollFlags]);

    /// Accepts pending connections and reads what is available, at most
    /// `max` bytes (the runner bounds its work per pass: a flood must not
    /// starve the ticks), handing each received chunk to `sink`. Never
    /// blocks.
    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()>;

    /// Queues device output in the bounded backlog; [`Transport::flush`]
    /// writes it (the runner flushes once a pass, so the bytes of a batch
    /// of ticks go out in one write). Never blocks.
    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()>;

    /// Whether input is held back (the runner paces what it reads at the
    /// line rate, [`crate::runner`]): while held, a wait does not wake for
    /// input (it would at once, for ever, with input pending), only for
    /// output room, hang-ups and its timeout. Not held at first.
    fn hold_input(&mut self, hold: bool);

    /// Writes backlog bytes the peer takes now. Never blocks.
    fn flush(&mut self) -> anyhow::Result<()>;

    /// The emulated line rate changed to `bps` (bit/s).
    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()>;

    /// Bytes waiting in the backlog.
    fn backlog_len(&self) -> usize;

    /// Bytes the backlog dropped so far because the client did not read
    /// them in time (`status backlog-dropped=`).
    fn backlog_dropped(&self) -> u64;

    /// Whether a client is connected (a TCP client accepted, the pty's
    /// slave open), as of the last [`Transport::wait`],
    /// [`Transport::receive`] or [`Transport::poll_client`]. While none is,
    /// [`Transport::send`] drops the bytes, as a real line loses what
    /// nobody reads.
    fn connected(&self) -> bool;

    /// Takes a pending connection (TCP) or notices that the pty was
    /// opened, without reading anything; whether a client is connected.
    /// Never blocks. (The device powers on when this first says yes.)
    fn poll_client(&mut self) -> anyhow::Result<bool>;
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

/// The events each descriptor of a finished `ppoll` reported.
pub(crate) fn revents(fds: &[nix::poll::PollFd<'_>]) -> Vec<nix::poll::PollFlags> {
    fds.iter()
        .map(|f| f.revents().unwrap_or(nix::poll::PollFlags::empty()))
        .collect()
}

/// How long a listener is left alone after `accept()` failed for lack of
/// resources (EMFILE, ENFILE, ENOBUFS, ENOMEM): the pending connection stays
/// queued and the listener stays readable, so retrying at once would spin.
pub const ACCEPT_BACKOFF: Duration = Duration::from_millis(100);

/// What a connected peer's descriptor is polled for: input unless input
/// is held back ([`Transport::hold_input`]: the device's line rate is the
/// limit) or unwanted, output while a backlog waits for the peer.
pub fn peer_interest(read: bool, backlog_pending: bool) -> nix::poll::PollFlags {
    use nix::poll::PollFlags;
    let mut ev = if read {
        PollFlags::POLLIN
    } else {
        PollFlags::empty()
    };
    if backlog_pending {
        ev |= PollFlags::POLLOUT;
    }
    ev
}

/// At most one message a second about failing `accept()` calls.
pub const ACCEPT_REPORT_INTERVAL: Duration = Duration::from_secs(1);

/// Whether an `accept()` error is transient: the listener stays usable and
/// a later call may succeed (resources exhausted, or a connection that was
/// reset or aborted before it was taken).
pub fn is_transient_accept_error(e: &std::io::Error) -> bool {
    use nix::errno::Errno;
    matches!(
        e.kind(),
        std::io::ErrorKind::ConnectionAborted
            | std::io::ErrorKind::ConnectionReset
            | std::io::ErrorKind::Interrupted
    ) || matches!(
        e.raw_os_error().map(Errno::from_raw),
        Some(
            Errno::EMFILE
                | Errno::ENFILE
                | Errno::ENOBUFS
                | Errno::ENOMEM
                | Errno::EPROTO
                | Errno::EPERM
                | Errno::ENETDOWN
                | Errno::ENOPROTOOPT
                | Errno::EHOSTDOWN
                | Errno::ENONET
                | Errno::EHOSTUNREACH
                | Errno::EOPNOTSUPP
                | Errno::ENETUNREACH
        )
    )
}

/// What a listener does about transient `accept()` failures: it pauses for
/// [`ACCEPT_BACKOFF`] (so a full descriptor table does not turn the loop
/// into a busy spin) and reports on stderr at most once per
/// [`ACCEPT_REPORT_INTERVAL`], with the number of failures since the last
/// report. The process keeps running and serving the current client.
#[derive(Debug)]
pub struct AcceptGuard {
    what: &'static str,
    paused_until: Option<std::time::Instant>,
    last_report: Option<std::time::Instant>,
    failures: u64,
}

impl AcceptGuard {
    /// A guard for the listener named `what` in messages (`tcp`, `control`).
    pub fn new(what: &'static str) -> Self {
        AcceptGuard {
            what,
            paused_until: None,
            last_report: None,
            failures: 0,
        }
    }

    /// Whether the listener may be polled and accepted from now.
    pub fn ready(&mut self) -> bool {
        match self.paused_until {
            Some(t) if std::time::Instant::now() < t => false,
            _ => {
                self.paused_until = None;
                true
            }
        }
    }

    /// Whether the listener is backing off now (not to be polled).
    pub fn paused(&self) -> bool {
        self.paused_until
            .is_some_and(|t| std::time::Instant::now() < t)
    }

    /// Failed `accept()` calls so far.
    pub fn failures(&self) -> u64 {
        self.failures
    }

    /// Notes a transient failure `e`: pauses the listener and reports, at
    /// most once per [`ACCEPT_REPORT_INTERVAL`].
    pub fn failed(&mut self, e: &std::io::Error) {
        let now = std::time::Instant::now();
        self.failures += 1;
        self.paused_until = Some(now + ACCEPT_BACKOFF);
        let due = self
            .last_report
            .is_none_or(|t| now.duration_since(t) >= ACCEPT_REPORT_INTERVAL);
        if due {
            eprintln!(
                "imu-emu: {} accept failed: {e} ({} failures so far; retrying, \
                 the current client is still served)",
                self.what, self.failures
            );
            self.last_report = Some(now);
        }
    }
}

/// A rate limit of repeated messages (a token bucket): a burst of
/// [`LogLimit::BURST`], then one every [`LogLimit::EVERY`]; what it holds
/// back is counted and named by the next message let through.
#[derive(Debug, Clone)]
pub struct LogLimit {
    tokens: u32,
    refilled: std::time::Instant,
    held: u64,
}

impl Default for LogLimit {
    fn default() -> Self {
        LogLimit {
            tokens: Self::BURST,
            refilled: std::time::Instant::now(),
            held: 0,
        }
    }
}

impl LogLimit {
    /// Messages let through at once.
    pub const BURST: u32 = 4;
    /// Then one per this.
    pub const EVERY: Duration = Duration::from_secs(10);

    /// `Some(held back since the last one)` if this message may go out.
    pub fn allow(&mut self) -> Option<u64> {
        let now = std::time::Instant::now();
        while self.tokens < Self::BURST && now.duration_since(self.refilled) >= Self::EVERY {
            self.tokens += 1;
            self.refilled += Self::EVERY;
        }
        if self.tokens == Self::BURST {
            self.refilled = now;
        }
        if self.tokens == 0 {
            self.held += 1;
            return None;
        }
        self.tokens -= 1;
        Some(std::mem::take(&mut self.held))
    }
}
