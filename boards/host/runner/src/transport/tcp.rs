//! TCP transport: the device's UART on a listening socket.
//!
//! One client at a time; a new connection replaces (closes) the old one and
//! the device keeps its state. As on a real line, what the device sends
//! while no client is connected is dropped, and so is what a client did not
//! take before it went: a new client starts with the live stream (possibly
//! mid-frame: resynchronise on `AA 55`). A client that closes its sending side
//! (`shutdown(SHUT_WR)`) keeps receiving the stream, as on a real line; it
//! is dropped when a write to it fails or the socket reports a hang-up, or
//! once the device has sent it nothing for [`HALF_CLOSED_QUIET`]: only
//! sending tells a peer that closed from one that half-closed, so a closed
//! client of an idle device would otherwise hold its descriptor (and, under
//! EMFILE, keep the control socket from accepting) for ever.
//! `accept()` failing for lack of resources (EMFILE, …) is transient: the
//! listener pauses briefly and the message is rate-limited
//! ([`super::AcceptGuard`]). Output the client does not take at once (a
//! slow reader) waits in the bounded backlog. The device powers on when the
//! first client connects (unless `--power-on now`), so that client still
//! sees the AutoStart announcement.

use std::io::{self, Read};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::os::fd::AsFd;

use nix::poll::{PollFd, PollFlags};

use super::{is_transient_accept_error, AcceptGuard, Transport};
use crate::backlog::Backlog;

/// How long a client that closed its sending side is kept while the
/// device sends it nothing (host time).
pub const HALF_CLOSED_QUIET: std::time::Duration = std::time::Duration::from_secs(1);

/// A listening socket with at most one client.
#[derive(Debug)]
pub struct TcpTransport {
    listener: TcpListener,
    local: SocketAddr,
    client: Option<(TcpStream, SocketAddr)>,
    /// The client closed its sending side: it is no longer read.
    read_closed: bool,
    /// Since when a client that closed its sending side was sent nothing.
    quiet_since: std::time::Instant,
    /// Input held back ([`Transport::hold_input`]).
    hold: bool,
    /// The last [`Transport::wait`] saw the client's socket hang up.
    hung_up: bool,
    accept: AcceptGuard,
    backlog: Backlog,
    /// The next wait polls the listener (its accept back-off is over).
    poll_listener: bool,
    /// A connection may be waiting: the last wait saw the listener
    /// readable, or no wait ran since the last `receive`. Otherwise
    /// `receive` makes no `accept` call (one syscall less a pass).
    listener_ready: bool,
    /// The client may have sent bytes or closed: as above, for `read`.
    client_ready: bool,
}

impl TcpTransport {
    /// Binds `addr` (`host:port`; port 0 picks a free port).
    pub fn bind(addr: &str) -> anyhow::Result<Self> {
        let listener =
            TcpListener::bind(addr).map_err(|e| crate::error::bind_error(e, "--tcp", addr))?;
        listener.set_nonblocking(true)?;
        let local = listener.local_addr()?;
        Ok(TcpTransport {
            listener,
            local,
            client: None,
            read_closed: false,
            quiet_since: std::time::Instant::now(),
            hold: false,
            hung_up: false,
            accept: AcceptGuard::new("tcp"),
            backlog: Backlog::default(),
            poll_listener: true,
            listener_ready: true,
            client_ready: true,
        })
    }

    /// The bound address (the real port when 0 was asked for).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// Failed `accept()` calls so far (EMFILE and the like: transient).
    pub fn accept_failures(&self) -> u64 {
        self.accept.failures()
    }

    fn accept_all(&mut self) -> anyhow::Result<()> {
        while self.accept.ready() {
            match self.listener.accept() {
                Ok((stream, peer)) => {
                    stream.set_nonblocking(true)?;
                    // Small frames should leave at once, like bytes on a wire.
                    stream.set_nodelay(true)?;
                    if let Some((_, old)) = self.client.replace((stream, peer)) {
                        if self.read_closed {
                            // It closed its side (end of file) and nothing
                            // written since failed: most likely gone for
                            // good, which TCP cannot tell from a half-close.
                            eprintln!(
                                "imu-emu: client {old} left; client {peer} connected to {}",
                                self.local
                            );
                        } else {
                            eprintln!("imu-emu: client {old} replaced by {peer}");
                        }
                    } else {
                        eprintln!("imu-emu: client {peer} connected to {}", self.local);
                    }
                    // What the old client did not take is not the new one's.
                    self.backlog.clear();
                    self.client_ready = true;
                    self.read_closed = false;
                    self.hung_up = false;
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if is_transient_accept_error(&e) => self.accept.failed(&e),
                Err(e) => return Err(anyhow::Error::new(e).context("tcp accept")),
            }
        }
        Ok(())
    }

    fn drop_client(&mut self, why: &str) {
        if let Some((_, peer)) = self.client.take() {
            eprintln!("imu-emu: client {peer} {why}; output is dropped until a client connects");
        }
        self.backlog.clear();
        self.read_closed = false;
        self.hung_up = false;
    }
}

impl Transport for TcpTransport {
    fn describe(&self) -> String {
        format!("tcp {}", self.local)
    }

    fn prepare_wait(&mut self) -> anyhow::Result<()> {
        self.poll_listener = self.accept.ready();
        if self.read_closed
            && self.backlog.is_empty()
            && self.quiet_since.elapsed() >= HALF_CLOSED_QUIET
        {
            self.drop_client(&format!(
                "closed its sending side and was sent nothing for {} s: closed",
                HALF_CLOSED_QUIET.as_secs()
            ));
        }
        Ok(())
    }

    fn interest<'a>(&'a self, fds: &mut Vec<PollFd<'a>>) {
        if self.poll_listener {
            fds.push(PollFd::new(self.listener.as_fd(), PollFlags::POLLIN));
        }
        if let Some((stream, _)) = &self.client {
            // A half-closed client stays readable (end of file) for ever:
            // only its output and hang-ups matter then.
            let read = !(self.read_closed || self.hold);
            let ev = super::peer_interest(read, !self.backlog.is_empty());
            fds.push(PollFd::new(stream.as_fd(), ev));
        }
    }

    fn polled(&mut self, revents: &[PollFlags]) {
        let (listener, client) = if self.poll_listener {
            (revents.first().copied(), revents.get(1).copied())
        } else {
            (None, revents.first().copied())
        };
        let gone = PollFlags::POLLHUP | PollFlags::POLLERR;
        let readable = PollFlags::POLLIN | gone;
        // Level-triggered: a listener not polled (backing off) is not
        // accepted from; what is not seen now is seen at the next wait.
        self.listener_ready = listener.is_some_and(|r| r.intersects(readable));
        // A wait that held input back did not ask for it, so seeing
        // nothing says nothing: the next receive reads (else the rest of a
        // command cut by the line-rate pacing waited a pass longer, one
        // that ran up to 128 ms of ticks and so let the device abandon the
        // command's first part).
        self.client_ready = self.hold || client.is_some_and(|r| r.intersects(readable));
        if client.is_some_and(|r| r.intersects(gone)) {
            self.hung_up = true;
        }
    }

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        let had = self.client.as_ref().map(|(_, p)| *p);
        if std::mem::replace(&mut self.listener_ready, true) {
            self.accept_all()?;
        }
        if self.client.as_ref().map(|(_, p)| *p) != had {
            // A new client: hand it what was queued meanwhile.
            self.flush()?;
        }
        if self.hung_up {
            self.drop_client("disconnected");
        }
        let mut buf = [0u8; 4096];
        let mut got = 0;
        let ready = std::mem::replace(&mut self.client_ready, true);
        while let Some((stream, peer)) = &mut self.client {
            if self.read_closed || !ready {
                break;
            }
            let want = (max - got).min(buf.len());
            if want == 0 {
                break;
            }
            match stream.read(&mut buf[..want]) {
                Ok(0) => {
                    // Closed or half-closed: TCP cannot tell which until a
                    // write fails, so no warning (a client that leaves is
                    // the common case); `-v` says it.
                    tracing::info!(
                        "client {peer} closed its sending side; output goes on until the \
                         connection fails or another client connects"
                    );
                    self.read_closed = true;
                    self.quiet_since = std::time::Instant::now();
                }
                Ok(n) => {
                    got += n;
                    sink(&buf[..n]);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => self.drop_client(&format!("dropped: {e}")),
            }
        }
        Ok(())
    }

    #[inline]
    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        // A real line loses what nobody reads.
        if self.client.is_some() {
            self.backlog.push(bytes);
            // Only a half-closed client's quiet time is ever read: no
            // clock read per frame otherwise (`--speed max` sends millions).
            if self.read_closed && !bytes.is_empty() {
                self.quiet_since = std::time::Instant::now();
            }
        }
        Ok(())
    }

    fn hold_input(&mut self, hold: bool) {
        self.hold = hold;
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        if let Some((stream, _)) = &mut self.client {
            if let Err(e) = self.backlog.write_to(stream) {
                self.drop_client(&format!("dropped: {e}"));
            }
        }
        Ok(())
    }

    fn set_line_rate(&mut self, _bps: u32) -> anyhow::Result<()> {
        // TCP has no line rate; pacing alone models it.
        Ok(())
    }

    fn backlog_len(&self) -> usize {
        self.backlog.len()
    }

    fn backlog_dropped(&self) -> u64 {
        self.backlog.dropped()
    }

    fn connected(&self) -> bool {
        self.client.is_some()
    }

    fn poll_client(&mut self) -> anyhow::Result<bool> {
        if std::mem::replace(&mut self.listener_ready, true) {
            self.accept_all()?;
        }
        Ok(self.client.is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backlog::DEFAULT_CAPACITY;
    use std::io::Write as _;
    use std::time::Duration;

    fn received(t: &mut TcpTransport) -> Vec<u8> {
        let mut got = Vec::new();
        t.receive(4096, &mut |b| got.extend_from_slice(b)).unwrap();
        got
    }

    #[test]
    fn input_after_a_wait_that_saw_nothing_is_read_after_the_next_wait() {
        let mut t = TcpTransport::bind("127.0.0.1:0").unwrap();
        let mut c = TcpStream::connect(t.local_addr()).unwrap();
        c.write_all(b"abc").unwrap();
        // The wait sees the connection (and, level-triggered, later the
        // input): accepted and read.
        let mut got = Vec::new();
        for _ in 0..50 {
            t.wait(Duration::from_millis(100)).unwrap();
            got.extend(received(&mut t));
            if got.len() == 3 {
                break;
            }
        }
        assert!(t.connected());
        assert_eq!(got, b"abc");
        // A wait that sees nothing: the next receive reads nothing, not
        // even what arrived since; the wait after it sees the bytes.
        t.wait(Duration::ZERO).unwrap();
        c.write_all(b"x").unwrap();
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(received(&mut t), b"");
        t.wait(Duration::from_millis(500)).unwrap();
        assert_eq!(received(&mut t), b"x");
        // Without a wait in between, receive reads what is there.
        c.write_all(b"yz").unwrap();
        let mut got = Vec::new();
        for _ in 0..200 {
            got.extend(received(&mut t));
            if got.len() >= 2 {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        assert_eq!(got, b"yz");
    }

    #[test]
    fn a_replacing_client_is_accepted_at_the_wait_that_sees_it() {
        let mut t = TcpTransport::bind("127.0.0.1:0").unwrap();
        let _a = TcpStream::connect(t.local_addr()).unwrap();
        assert!(t.poll_client().unwrap());
        let first = t.client.as_ref().unwrap().1;
        t.wait(Duration::ZERO).unwrap();
        let mut b = TcpStream::connect(t.local_addr()).unwrap();
        b.write_all(b"hi").unwrap();
        t.wait(Duration::from_millis(500)).unwrap();
        let got = received(&mut t);
        assert_ne!(t.client.as_ref().unwrap().1, first, "not replaced");
        // The new client's first bytes may come with this receive or the
        // next wait's.
        let got = if got.is_empty() {
            t.wait(Duration::from_millis(500)).unwrap();
            received(&mut t)
        } else {
            got
        };
        assert_eq!(got, b"hi");
    }

    /// Output a client does not read fills the kernel's buffers, then the
    /// 64 KiB backlog, then is dropped oldest first and counted
    /// (`status backlog-dropped=`): every byte sent is read, waiting or
    /// counted as dropped, none twice.
    #[test]
    fn what_a_client_does_not_read_in_time_is_counted_as_dropped() {
        let mut t = TcpTransport::bind("127.0.0.1:0").unwrap();
        let mut c = TcpStream::connect(t.local_addr()).unwrap();
        assert!(t.poll_client().unwrap());
        let chunk: Vec<u8> = (0..=255u8).cycle().take(64 * 1024).collect();
        let mut sent = 0u64;
        // Far more than the loopback socket's buffers take.
        while t.backlog_dropped() == 0 && sent < 1 << 30 {
            t.send(&chunk).unwrap();
            t.flush().unwrap();
            sent += chunk.len() as u64;
        }
        assert!(t.backlog_dropped() > 0);
        assert_eq!(t.backlog_len(), DEFAULT_CAPACITY);
        c.set_nonblocking(true).unwrap();
        let mut read = 0u64;
        let mut buf = vec![0u8; 1 << 16];
        loop {
            t.flush().unwrap();
            match c.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => read += n as u64,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if t.backlog_len() == 0 {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => panic!("{e}"),
            }
        }
        assert_eq!(t.backlog_len(), 0);
        assert_eq!(read + t.backlog_dropped(), sent);
    }

    /// Input held back ([`Transport::hold_input`]) is read at the first
    /// receive after a wait, though that wait did not ask for it: the rest
    /// of a command the line-rate pacing cut must reach the device at the
    /// next pass, not a pass later.
    #[test]
    fn held_input_is_read_after_the_next_wait() {
        let mut t = TcpTransport::bind("127.0.0.1:0").unwrap();
        let mut c = TcpStream::connect(t.local_addr()).unwrap();
        assert!(t.poll_client().unwrap());
        c.write_all(b"abcdef").unwrap();
        std::thread::sleep(Duration::from_millis(20));
        let mut got = Vec::new();
        t.receive(2, &mut |b| got.extend_from_slice(b)).unwrap();
        assert_eq!(got, b"ab");
        t.hold_input(true);
        t.wait(Duration::from_millis(1)).unwrap();
        t.hold_input(false);
        assert_eq!(received(&mut t), b"cdef");
    }
}
