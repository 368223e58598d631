//! Pseudo-terminal transport: the device's UART as a serial port.
//!
//! The runner opens a pty pair, puts the slave in raw mode (8N1, no echo,
//! no line editing) and keeps the slave open itself, so the master never
//! sees `EIO`/hang-up when a client closes the port; clients open the slave
//! path (printed on stdout, optionally symlinked at `--link PATH`).
//!
//! The emulated line rate is also written to the slave's termios speed
//! (nearest standard `Bxxx` value) on every rate change, for clients that
//! look at it; a pty moves bytes at memory speed whatever the speed says,
//! so the runner's pacing is what models the line. Output the slave's
//! input queue cannot take (no reader, or a slow one) waits in the bounded
//! backlog.

use std::fs::File;
use std::io::{self, Read};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context as _;
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::poll::{PollFd, PollFlags};
use nix::sys::termios::{self, BaudRate, SetArg};

use super::{poll_fds, Transport};
use crate::backlog::Backlog;

/// A pty pair whose slave is the emulated serial port.
#[derive(Debug)]
pub struct PtyTransport {
    master: File,
    /// Held open so the master never sees a hang-up.
    slave: OwnedFd,
    slave_path: PathBuf,
    link: Option<LinkGuard>,
    backlog: Backlog,
}

impl PtyTransport {
    /// Opens a pty pair in raw mode at `bps`; with `link`, symlinks the
    /// slave there (an existing symlink is replaced).
    pub fn open(bps: u32, link: Option<&Path>) -> anyhow::Result<Self> {
        let pty = nix::pty::openpty(None, None).context("openpty")?;
        let slave_path = nix::unistd::ttyname(&pty.slave).context("ttyname of the pty slave")?;

        let mut t = termios::tcgetattr(&pty.slave).context("tcgetattr")?;
        termios::cfmakeraw(&mut t);
        termios::cfsetspeed(&mut t, nearest_baud(bps)).context("cfsetspeed")?;
        termios::tcsetattr(&pty.slave, SetArg::TCSANOW, &t).context("tcsetattr")?;

        let flags = OFlag::from_bits_truncate(fcntl(&pty.master, FcntlArg::F_GETFL)?);
        fcntl(&pty.master, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK))
            .context("making the pty master nonblocking")?;

        let link = link
            .map(|p| LinkGuard::create(p, &slave_path))
            .transpose()?;
        Ok(PtyTransport {
            master: File::from(pty.master),
            slave: pty.slave,
            slave_path,
            link,
            backlog: Backlog::default(),
        })
    }

    /// The slave's path (`/dev/pts/N`).
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// The symlink made for `--link`, if any.
    pub fn link_path(&self) -> Option<&Path> {
        self.link.as_ref().map(|l| l.path.as_path())
    }
}

impl Transport for PtyTransport {
    fn describe(&self) -> String {
        format!("pty {}", self.slave_path.display())
    }

    fn wait(&mut self, timeout: Duration) -> anyhow::Result<()> {
        let mut ev = PollFlags::POLLIN;
        if !self.backlog.is_empty() {
            ev |= PollFlags::POLLOUT;
        }
        let mut fds = [PollFd::new(self.master.as_fd(), ev)];
        poll_fds(&mut fds, timeout)
    }

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        let mut buf = [0u8; 4096];
        let mut got = 0;
        loop {
            let want = (max - got).min(buf.len());
            if want == 0 {
                return Ok(());
            }
            match self.master.read(&mut buf[..want]) {
                Ok(0) => return Ok(()),
                Ok(n) => {
                    got += n;
                    sink(&buf[..n]);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                // Cannot happen while the slave is held open; be tolerant.
                Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => return Ok(()),
                Err(e) => return Err(anyhow::Error::new(e).context("reading the pty master")),
            }
        }
    }

    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.backlog.push(bytes);
        Ok(())
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        match self.backlog.write_to(&mut self.master) {
            Ok(_) => Ok(()),
            Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => Ok(()),
            Err(e) => Err(anyhow::Error::new(e).context("writing the pty master")),
        }
    }

    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        let mut t = termios::tcgetattr(&self.slave).context("tcgetattr")?;
        termios::cfsetspeed(&mut t, nearest_baud(bps)).context("cfsetspeed")?;
        termios::tcsetattr(&self.slave, SetArg::TCSANOW, &t).context("tcsetattr")?;
        Ok(())
    }

    fn backlog_len(&self) -> usize {
        self.backlog.len()
    }
}

/// Standard termios speeds with their rates.
const BAUDS: &[(u32, BaudRate)] = &[
    (1200, BaudRate::B1200),
    (2400, BaudRate::B2400),
    (4800, BaudRate::B4800),
    (9600, BaudRate::B9600),
    (19_200, BaudRate::B19200),
    (38_400, BaudRate::B38400),
    (57_600, BaudRate::B57600),
    (115_200, BaudRate::B115200),
    (230_400, BaudRate::B230400),
    (460_800, BaudRate::B460800),
    (500_000, BaudRate::B500000),
    (921_600, BaudRate::B921600),
    (1_000_000, BaudRate::B1000000),
    (1_500_000, BaudRate::B1500000),
    (2_000_000, BaudRate::B2000000),
    (2_500_000, BaudRate::B2500000),
    (3_000_000, BaudRate::B3000000),
    (3_500_000, BaudRate::B3500000),
    (4_000_000, BaudRate::B4000000),
];

/// The standard termios speed nearest to `bps` (14400 → B9600 or B19200,
/// 375000 → B460800, …).
pub fn nearest_baud(bps: u32) -> BaudRate {
    BAUDS
        .iter()
        .min_by_key(|(r, _)| r.abs_diff(bps))
        .map(|&(_, b)| b)
        .unwrap_or(BaudRate::B115200)
}

/// The `--link` symlink; removed on drop if it still points at the slave.
#[derive(Debug)]
struct LinkGuard {
    path: PathBuf,
    target: PathBuf,
}

impl LinkGuard {
    fn create(path: &Path, target: &Path) -> anyhow::Result<Self> {
        match std::fs::symlink_metadata(path) {
            Ok(m) if m.file_type().is_symlink() => std::fs::remove_file(path)
                .with_context(|| format!("replacing symlink {}", path.display()))?,
            Ok(_) => anyhow::bail!("--link {}: exists and is not a symlink", path.display()),
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(anyhow::Error::new(e).context(format!("{}", path.display()))),
        }
        std::os::unix::fs::symlink(target, path)
            .with_context(|| format!("symlinking {} -> {}", path.display(), target.display()))?;
        Ok(LinkGuard {
            path: path.to_owned(),
            target: target.to_owned(),
        })
    }
}

impl Drop for LinkGuard {
    fn drop(&mut self) {
        if std::fs::read_link(&self.path).is_ok_and(|t| t == self.target) {
            if let Err(e) = std::fs::remove_file(&self.path) {
                eprintln!("imu-emu: removing {}: {e}", self.path.display());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn nearest_standard_speeds() {
        assert_eq!(nearest_baud(4800), BaudRate::B4800);
        assert_eq!(nearest_baud(115_200), BaudRate::B115200);
        assert_eq!(nearest_baud(375_000), BaudRate::B460800);
        assert_eq!(nearest_baud(1_843_200), BaudRate::B2000000);
        assert_eq!(nearest_baud(3_686_400), BaudRate::B3500000);
    }

    #[test]
    fn bytes_cross_the_pair_and_the_link_is_managed() {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("kernel");
        std::os::unix::fs::symlink("/nonexistent", &link).unwrap();
        let mut t = PtyTransport::open(115_200, Some(&link)).unwrap();
        assert_eq!(std::fs::read_link(&link).unwrap(), t.slave_path());

        let mut client = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&link)
            .unwrap();
        client.write_all(&[0xAA, 0x55, 0x00]).unwrap();
        let mut got = vec![];
        for _ in 0..100 {
            t.wait(Duration::from_millis(10)).unwrap();
            t.receive(usize::MAX, &mut |b| got.extend_from_slice(b))
                .unwrap();
            if got.len() == 3 {
                break;
            }
        }
        assert_eq!(got, [0xAA, 0x55, 0x00]); // raw: no echo, no translation

        t.send(&[1, 2, 0x0A, 0x0D]).unwrap();
        t.flush().unwrap();
        let mut b = [0u8; 4];
        client.read_exact(&mut b).unwrap();
        assert_eq!(b, [1, 2, 0x0A, 0x0D]);

        t.set_line_rate(4800).unwrap();
        let tio = termios::tcgetattr(&client).unwrap();
        assert_eq!(termios::cfgetospeed(&tio), BaudRate::B4800);

        // The client closing does not disturb the master.
        drop(client);
        t.send(&[3]).unwrap();
        t.flush().unwrap();
        t.receive(usize::MAX, &mut |_| {}).unwrap();

        drop(t);
        assert!(std::fs::symlink_metadata(&link).is_err());
    }
}
