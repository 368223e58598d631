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

/// A serial port as the device's UART: the `serialport` handle configures
/// it (raw 8N1, exclusive, any rate), a second descriptor opened before it
/// (nonblocking) carries the bytes and is polled.
pub struct SerialTransport {
    port: TTYPort,
    io: File,
    path: PathBuf,
    bps: u32,
    backlog: Backlog,
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
        let mut t = SerialTransport {
            port,
            io,
            path: path.to_owned(),
            bps,
            backlog: Backlog::default(),
        };
        t.set_rate(bps)?;
        Ok(t)
    }

    /// The port's rate now, bit/s.
    pub fn rate(&self) -> u32 {
        self.bps
    }

    /// Sets the port's rate: any rate through `serialport`; a standard one
    /// also as the termios `Bxxx` speed, so that `cfgetospeed`/`stty` on
    /// the port read it back.
    fn set_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        self.port
            .set_baud_rate(bps)
            .with_context(|| format!("--serial {}: setting {bps} bit/s", self.path.display()))?;
        let standard = super::pty::nearest_baud(bps);
        if super::pty::baud_bps(standard) == Some(bps) {
            let mut t = termios::tcgetattr(&self.io).context("tcgetattr")?;
            termios::cfsetspeed(&mut t, standard).context("cfsetspeed")?;
            termios::tcsetattr(&self.io, SetArg::TCSANOW, &t).context("tcsetattr")?;
        }
        self.bps = bps;
        Ok(())
    }
}

impl Transport for SerialTransport {
    fn describe(&self) -> String {
        format!("serial {}", self.path.display())
    }

    fn interest<'a>(&'a self, fds: &mut Vec<PollFd<'a>>) {
        let mut ev = PollFlags::POLLIN;
        if !self.backlog.is_empty() {
            ev |= PollFlags::POLLOUT;
        }
        fds.push(PollFd::new(self.io.as_fd(), ev));
    }

    fn polled(&mut self, _revents: &[PollFlags]) {}

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        let mut buf = [0u8; 4096];
        let mut got = 0;
        loop {
            let want = (max - got).min(buf.len());
            if want == 0 {
                return Ok(());
            }
            match self.io.read(&mut buf[..want]) {
                Ok(0) => return Ok(()),
                Ok(n) => {
                    got += n;
                    sink(&buf[..n]);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                // A pty's far end closed: nothing to read.
                Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => return Ok(()),
                Err(e) => {
                    return Err(
                        anyhow::Error::new(e).context(format!("reading {}", self.path.display()))
                    )
                }
            }
        }
    }

    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.backlog.push(bytes);
        Ok(())
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        match self.backlog.write_to(&mut self.io) {
            Ok(_) => Ok(()),
            Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => Ok(()),
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

    fn connected(&self) -> bool {
        true
    }

    fn poll_client(&mut self) -> anyhow::Result<bool> {
        Ok(true)
    }
}
