//! Serial-port transport (`--serial DEV`): the device's UART on a real
//! serial port (a USB-RS-422 adapter on a HIL rig), through the
//! `serialport` crate.
//!
//! The port is opened raw 8N1 at the device's line rate and follows it:
//! every rate change of the device (power-on Baud_Rate, CommitBaudRate,
//! ICD 5.3.9) sets the port's rate, so the bytes really leave at that rate
//! (the runner's pacing models the same rate). A serial line has no
//! notion of a client: it counts as always connected, and the device
//! powers on at start. Output the port does not take at once waits in the
//! bounded backlog.
//!
//! **Hang-up**: when the port hangs up (the far end of a pty closed, a USB
//! adapter unplugged: `POLLHUP`/`POLLERR`, `EIO`, `ENXIO`, `ENODEV` on a
//! read or write) the transport says so once on stderr, closes the port
//! and tries to open the same path again every [`REOPEN_INTERVAL`],
//! without spinning (nothing of the port is polled meanwhile); the device
//! keeps running and its output is dropped, as with no client on a TCP
//! port. When the path opens again (the adapter re-enumerated, a symlink
//! now points at another port) the port is set to the device's line rate
//! and serves the device again; that is said once too.

use std::fs::File;
use std::io::{self, Read};
use std::os::fd::AsFd;
use std::os::unix::fs::OpenOptionsExt as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context as _;
use nix::fcntl::OFlag;
use nix::poll::{PollFd, PollFlags};
use nix::sys::termios::{self, SetArg};
use serialport::{SerialPort as _, TTYPort};

use super::Transport;
use crate::backlog::Backlog;

/// How often a hung-up port's path is tried again (host time).
pub const REOPEN_INTERVAL: Duration = Duration::from_millis(250);

/// The open port: the `serialport` handle configures it (raw 8N1,
/// exclusive, any rate), a second descriptor opened before it
/// (nonblocking) carries the bytes and is polled.
struct Open {
    port: TTYPort,
    io: File,
}

/// A serial port as the device's UART (see the module docs).
pub struct SerialTransport {
    /// `None` while the port is hung up.
    open: Option<Open>,
    path: PathBuf,
    bps: u32,
    backlog: Backlog,
    /// When the path of a hung-up port was last tried.
    tried_at: std::time::Instant,
    /// Input held back ([`Transport::hold_input`]).
    hold: bool,
}

impl std::fmt::Debug for SerialTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialTransport")
            .field("path", &self.path)
            .field("bps", &self.bps)
            .finish()
    }
}

impl SerialTransport {
    /// Opens `path` raw 8N1 at `bps`.
    pub fn open(path: &Path, bps: u32) -> anyhow::Result<Self> {
        let mut t = SerialTransport {
            open: None,
            path: path.to_owned(),
            bps,
            backlog: Backlog::default(),
            tried_at: std::time::Instant::now(),
            hold: false,
        };
        t.open_port()?;
        Ok(t)
    }

    /// Opens the path at the current rate.
    fn open_port(&mut self) -> anyhow::Result<()> {
        let (path, bps) = (&self.path, self.bps);
        let cannot = |e: &dyn std::fmt::Display| {
            anyhow::anyhow!("--serial {}: cannot open: {e}", path.display())
        };
        let io = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags((OFlag::O_NOCTTY | OFlag::O_NONBLOCK).bits())
            .open(path)
            .map_err(|e| cannot(&e))?;
        let port = serialport::new(path.to_string_lossy(), bps)
            .timeout(Duration::ZERO)
            .open_native()
            .map_err(|e| cannot(&e))?;
        tracing::info!("serial port {} opened at {bps} bit/s", path.display());
        self.open = Some(Open { port, io });
        self.set_rate(bps)
    }

    /// Whether the port is hung up (and waiting to be re-opened).
    pub fn hung_up(&self) -> bool {
        self.open.is_none()
    }

    /// Closes a port that hung up (`why`), once; the path is tried again
    /// from [`REOPEN_INTERVAL`] on.
    fn hang_up(&mut self, why: &str) {
        if self.open.take().is_some() {
            eprintln!(
                "imu-emu: --serial {}: the port hung up ({why}); output is dropped and the \
                 port is opened again when it comes back",
                self.path.display()
            );
            self.backlog.clear();
            self.tried_at = std::time::Instant::now();
        }
    }

    /// Whether an I/O error means the port is gone.
    fn is_hang_up(e: &io::Error) -> bool {
        use nix::errno::Errno;
        matches!(
            e.raw_os_error().map(Errno::from_raw),
            Some(Errno::EIO | Errno::ENXIO | Errno::ENODEV | Errno::EBADF)
        )
    }

    /// The port's rate now, bit/s.
    pub fn rate(&self) -> u32 {
        self.bps
    }

    /// Sets the port's rate: any rate through `serialport`; a standard one
    /// also as the termios `Bxxx` speed, so that `cfgetospeed`/`stty` on
    /// the port read it back.
    fn set_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        self.bps = bps;
        let Some(o) = self.open.as_mut() else {
            // Set when the port is opened again.
            return Ok(());
        };
        o.port
            .set_baud_rate(bps)
            .with_context(|| format!("--serial {}: setting {bps} bit/s", self.path.display()))?;
        let standard = super::pty::nearest_baud(bps);
        if super::pty::baud_bps(standard) == Some(bps) {
            let mut t = termios::tcgetattr(&o.io).context("tcgetattr")?;
            termios::cfsetspeed(&mut t, standard).context("cfsetspeed")?;
            termios::tcsetattr(&o.io, SetArg::TCSANOW, &t).context("tcsetattr")?;
        }
        Ok(())
    }
}

impl Transport for SerialTransport {
    fn describe(&self) -> String {
        format!("serial {}", self.path.display())
    }

    fn prepare_wait(&mut self) -> anyhow::Result<()> {
        if self.open.is_none() && self.tried_at.elapsed() >= REOPEN_INTERVAL {
            self.tried_at = std::time::Instant::now();
            if self.open_port().is_ok() {
                eprintln!(
                    "imu-emu: --serial {}: the port is back, at {} bit/s",
                    self.path.display(),
                    self.bps
                );
            }
        }
        Ok(())
    }

    fn interest<'a>(&'a self, fds: &mut Vec<PollFd<'a>>) {
        // A hung-up port is not polled (it would report POLLHUP at once,
        // for ever): the wait is the runner's timeout.
        if let Some(o) = &self.open {
            let ev = super::peer_interest(!self.hold, !self.backlog.is_empty());
            fds.push(PollFd::new(o.io.as_fd(), ev));
        }
    }

    fn polled(&mut self, revents: &[PollFlags]) {
        let gone = PollFlags::POLLHUP | PollFlags::POLLERR | PollFlags::POLLNVAL;
        if revents.first().is_some_and(|r| r.intersects(gone)) {
            self.hang_up("the far end closed or the adapter was unplugged");
        }
    }

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        let mut buf = [0u8; 4096];
        let mut got = 0;
        while let Some(o) = self.open.as_mut() {
            let want = (max - got).min(buf.len());
            if want == 0 {
                return Ok(());
            }
            match o.io.read(&mut buf[..want]) {
                Ok(0) => return Ok(()),
                Ok(n) => {
                    got += n;
                    sink(&buf[..n]);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if Self::is_hang_up(&e) => self.hang_up(&format!("read: {e}")),
                Err(e) => {
                    return Err(
                        anyhow::Error::new(e).context(format!("reading {}", self.path.display()))
                    )
                }
            }
        }
        Ok(())
    }

    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        // A hung-up line loses what nobody reads.
        if self.open.is_some() {
            self.backlog.push(bytes);
        }
        Ok(())
    }

    fn hold_input(&mut self, hold: bool) {
        self.hold = hold;
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        let Some(o) = self.open.as_mut() else {
            return Ok(());
        };
        match self.backlog.write_to(&mut o.io) {
            Ok(_) => Ok(()),
            Err(e) if Self::is_hang_up(&e) => {
                self.hang_up(&format!("write: {e}"));
                Ok(())
            }
            Err(e) => {
                Err(anyhow::Error::new(e).context(format!("writing {}", self.path.display())))
            }
        }
    }

    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        // What is queued leaves at the old rate (the core switches after
        // it): wait for the port to take it, up to a second.
        let start = std::time::Instant::now();
        self.flush()?;
        while !self.backlog.is_empty() && start.elapsed() < Duration::from_secs(1) {
            std::thread::sleep(Duration::from_millis(1));
            self.flush()?;
        }
        self.set_rate(bps)
    }

    fn backlog_len(&self) -> usize {
        self.backlog.len()
    }

    fn backlog_dropped(&self) -> u64 {
        self.backlog.dropped()
    }

    fn connected(&self) -> bool {
        self.open.is_some()
    }

    fn poll_client(&mut self) -> anyhow::Result<bool> {
        Ok(true)
    }
}
