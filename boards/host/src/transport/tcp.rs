//! TCP transport: the device's UART on a listening socket.
//!
//! One client at a time; a new connection replaces (closes) the old one and
//! the device keeps its state. While no client is connected — and whenever
//! the client does not keep up — output goes into the bounded backlog, which
//! is delivered first to the next client (so a client connecting right after
//! start still sees the AutoStart announcement).

use std::io::{self, Read};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::os::fd::AsFd;
use std::time::Duration;

use anyhow::Context as _;
use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags};

use super::{poll_fds, Transport};
use crate::backlog::Backlog;

/// A listening socket with at most one client.
#[derive(Debug)]
pub struct TcpTransport {
    listener: TcpListener,
    local: SocketAddr,
    client: Option<(TcpStream, SocketAddr)>,
    backlog: Backlog,
    /// A connection may be waiting: the last `wait` saw the listener
    /// readable (or no `wait` ran since the last accept). Otherwise
    /// `receive` makes no `accept` call: one syscall less a pass.
    listener_ready: bool,
    /// The client may have sent bytes (or closed): as above, for `read`.
    client_ready: bool,
}

impl TcpTransport {
    /// Binds `addr` (`host:port`; port 0 picks a free port).
    pub fn bind(addr: &str) -> anyhow::Result<Self> {
        let listener = TcpListener::bind(addr).with_context(|| format!("binding tcp {addr}"))?;
        listener.set_nonblocking(true)?;
        let local = listener.local_addr()?;
        Ok(TcpTransport {
            listener,
            local,
            client: None,
            backlog: Backlog::default(),
            listener_ready: true,
            client_ready: true,
        })
    }

    /// The bound address (the real port when 0 was asked for).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    fn accept_all(&mut self) -> anyhow::Result<()> {
        loop {
            match self.listener.accept() {
                Ok((stream, peer)) => {
                    stream.set_nonblocking(true)?;
                    // Small frames should leave at once, like bytes on a wire.
                    stream.set_nodelay(true)?;
                    self.client_ready = true;
                    if let Some((_, old)) = self.client.replace((stream, peer)) {
                        eprintln!("imu-emu: client {old} replaced by {peer}");
                    } else {
                        eprintln!("imu-emu: client {peer} connected");
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if is_transient_accept_error(&e) => {
                    eprintln!("imu-emu: accept: {e}");
                    return Ok(());
                }
                Err(e) => return Err(anyhow::Error::new(e).context("accept")),
            }
        }
    }

    fn drop_client(&mut self, why: &str) {
        if let Some((_, peer)) = self.client.take() {
            eprintln!("imu-emu: client {peer} {why}");
        }
    }
}

/// Whether the last poll saw `fd` readable, hung up or in error.
fn readable(fd: &PollFd<'_>) -> bool {
    fd.revents()
        .is_some_and(|r| r.intersects(PollFlags::POLLIN | PollFlags::POLLHUP | PollFlags::POLLERR))
}

fn is_transient_accept_error(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::ConnectionAborted
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::Interrupted
    ) || matches!(
        e.raw_os_error().map(Errno::from_raw),
        Some(Errno::EMFILE | Errno::ENFILE | Errno::ENOBUFS | Errno::ENOMEM)
    )
}

impl Transport for TcpTransport {
    fn describe(&self) -> String {
        format!("tcp {}", self.local)
    }

    fn wait(&mut self, timeout: Duration) -> anyhow::Result<()> {
        let mut fds = vec![PollFd::new(self.listener.as_fd(), PollFlags::POLLIN)];
        if let Some((stream, _)) = &self.client {
            let mut ev = PollFlags::POLLIN;
            if !self.backlog.is_empty() {
                ev |= PollFlags::POLLOUT;
            }
            fds.push(PollFd::new(stream.as_fd(), ev));
        }
        poll_fds(&mut fds, timeout)?;
        // Level-triggered: what is not seen now is seen at the next wait.
        self.listener_ready = fds.first().is_some_and(readable);
        self.client_ready = fds.get(1).is_some_and(readable);
        Ok(())
    }

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        let had = self.client.as_ref().map(|(_, p)| *p);
        if self.listener_ready {
            self.accept_all()?;
            self.listener_ready = false;
        }
        if self.client.as_ref().map(|(_, p)| *p) != had {
            // A new client: hand it what was queued meanwhile.
            self.flush()?;
        }
        let mut buf = [0u8; 4096];
        let mut got = 0;
        while self.client_ready {
            let Some((stream, _)) = &mut self.client else {
                break;
            };
            let want = (max - got).min(buf.len());
            if want == 0 {
                break;
            }
            match stream.read(&mut buf[..want]) {
                Ok(0) => self.drop_client("disconnected"),
                Ok(n) => {
                    got += n;
                    sink(&buf[..n]);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    self.client_ready = false;
                    break;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => self.drop_client(&format!("dropped: {e}")),
            }
        }
        Ok(())
    }

    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.backlog.push(bytes);
        Ok(())
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
}
