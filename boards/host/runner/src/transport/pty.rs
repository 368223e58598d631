//! Pseudo-terminal transport: the device's UART as a serial port.
//!
//! The runner opens a pty pair and puts the slave in raw mode (8N1, no
//! echo, no line editing); clients open the slave path (printed on stdout,
//! optionally symlinked at `--link PATH`). The runner does not keep the
//! slave open itself, so the master tells whether a client has it open: it
//! reports a hang-up (`POLLHUP`) exactly while nobody does. As on a real
//! line, what the device sends while the port is closed is dropped, and
//! what a client left unread when it closed the port is flushed: the next
//! client starts with the live stream. The raw settings stay with the pty
//! between opens.
//!
//! The emulated line rate is written to the slave's termios speed (nearest
//! standard `Bxxx` value) while no client has the port open, so a client
//! that opens it finds the device's rate; a pty moves bytes at memory speed
//! whatever the speed says, so the runner's pacing is what models the line.
//! Output the slave's input queue cannot take (a slow reader) waits in the
//! bounded backlog.
//!
//! **Baud mismatch**: while a client has the port open its termios speed
//! is its own (a rate change of the device, CommitBaudRate, does not touch
//! it, as a real UART's rate does not follow the far end). The runner
//! reads it every [`SPEED_CHECK`] — with `TCGETS2` (termios2, through
//! `rustix`), so the integer speed of a client that set an arbitrary one
//! (`BOTHER`, as serialport-rs does for every rate on Linux) is read as
//! well as a classic `Bxxx` speed; when it differs from the device's line
//! rate, the bytes in both directions are garbled as a UART at the wrong
//! rate reads them ([`crate::uart::resample`]: wrong bits, framing errors
//! read as `0x00`) and a warning naming both rates is logged once per
//! mismatch.

use std::fs::File;
use std::io::{self, Read};
use std::os::fd::AsFd;
use std::os::unix::fs::OpenOptionsExt as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context as _;
use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::poll::{PollFd, PollFlags, PollTimeout};
use nix::sys::termios::{self, BaudRate, FlushArg, SetArg};

use super::Transport;
use crate::backlog::Backlog;

/// A pty pair whose slave is the emulated serial port.
#[derive(Debug)]
pub struct PtyTransport {
    master: File,
    slave_path: PathBuf,
    link: Option<LinkGuard>,
    /// Whether a client has the slave open (as of the last check).
    open: bool,
    backlog: Backlog,
    /// The device's line rate, bit/s.
    bps: u32,
    /// The client's termios speed when it differs from the device's, as
    /// of the last check.
    mismatch: Option<u32>,
    /// When the client's speed was last read (host time).
    checked_at: Option<std::time::Instant>,
    /// The last wait saw the master hang up (or none ran yet): look at
    /// the client again before trusting `open`.
    recheck: bool,
    /// The master may have input: the last wait saw it readable, or no
    /// wait ran since the last `receive`. Otherwise `receive` does not
    /// read (one syscall less a pass).
    readable: bool,
    /// Input held back ([`Transport::hold_input`]).
    hold: bool,
}

/// How often the client's termios speed is read while it has the port
/// open.
pub const SPEED_CHECK: Duration = Duration::from_millis(20);

impl PtyTransport {
    /// Opens a pty pair in raw mode at `bps`; with `link`, symlinks the
    /// slave there (an existing symlink is replaced, unless it points at a
    /// live pty: another emulator's port is refused, not stolen).
    pub fn open(bps: u32, link: Option<&Path>) -> anyhow::Result<Self> {
        let pty = nix::pty::openpty(None, None).context("openpty")?;
        let slave_path = nix::unistd::ttyname(&pty.slave).context("ttyname of the pty slave")?;

        let mut t = termios::tcgetattr(&pty.slave).context("tcgetattr")?;
        termios::cfmakeraw(&mut t);
        termios::cfsetspeed(&mut t, nearest_baud(bps)).context("cfsetspeed")?;
        termios::tcsetattr(&pty.slave, SetArg::TCSANOW, &t).context("tcsetattr")?;
        // Closed: from now on the master's hang-up says "no client".
        drop(pty.slave);

        let flags = OFlag::from_bits_truncate(fcntl(&pty.master, FcntlArg::F_GETFL)?);
        fcntl(&pty.master, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK))
            .context("making the pty master nonblocking")?;

        let link = link
            .map(|p| LinkGuard::create(p, &slave_path))
            .transpose()?;
        Ok(PtyTransport {
            master: File::from(pty.master),
            slave_path,
            link,
            open: false,
            backlog: Backlog::default(),
            bps,
            mismatch: None,
            checked_at: None,
            recheck: true,
            readable: true,
            hold: false,
        })
    }

    /// The client's termios speed when it differs from the device's line
    /// rate (as of the last check), bit/s.
    pub fn mismatch(&self) -> Option<u32> {
        self.mismatch
    }

    /// Reads the client's termios speed (at most every [`SPEED_CHECK`])
    /// and notes a mismatch with the device's rate, warning once.
    fn check_speed(&mut self) -> anyhow::Result<()> {
        let now = std::time::Instant::now();
        if self
            .checked_at
            .is_some_and(|t| now.duration_since(t) < SPEED_CHECK)
        {
            return Ok(());
        }
        self.checked_at = Some(now);
        let slave = self.open_slave()?;
        let client = client_speed(&slave)?;
        // The device's rate as the runner wrote it (the nearest standard
        // speed), or exactly (a termios2 client that set the very rate).
        let device = baud_bps(nearest_baud(self.bps));
        let mismatch =
            (client != 0 && client != self.bps && Some(client) != device).then_some(client);
        if mismatch != self.mismatch {
            match mismatch {
                Some(c) => tracing::warn!(
                    "{}: the client's port is at {c} bit/s, the device's line at {} bit/s: \
                     bytes are garbled both ways as on a real line (did the driver follow \
                     CommitBaudRate?)",
                    self.slave_path.display(),
                    self.bps
                ),
                None if self.mismatch.is_some() => tracing::warn!(
                    "{}: the client's port matches the line rate again ({} bit/s)",
                    self.slave_path.display(),
                    self.bps
                ),
                None => {}
            }
            self.mismatch = mismatch;
        }
        Ok(())
    }

    /// Writes the device's line rate into the slave's termios.
    fn write_speed(&self) -> anyhow::Result<()> {
        let slave = self.open_slave()?;
        let mut t = termios::tcgetattr(&slave).context("tcgetattr")?;
        termios::cfsetspeed(&mut t, nearest_baud(self.bps)).context("cfsetspeed")?;
        termios::tcsetattr(&slave, SetArg::TCSANOW, &t).context("tcsetattr")?;
        Ok(())
    }

    /// The slave's path (`/dev/pts/N`).
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// The symlink made for `--link`, if any.
    pub fn link_path(&self) -> Option<&Path> {
        self.link.as_ref().map(|l| l.path.as_path())
    }

    /// Opens the slave for the runner's own use (termios, flushing): no
    /// controlling terminal, never blocking.
    fn open_slave(&self) -> anyhow::Result<File> {
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags((OFlag::O_NOCTTY | OFlag::O_NONBLOCK).bits())
            .open(&self.slave_path)
            .with_context(|| format!("opening {}", self.slave_path.display()))
    }

    /// Whether a client has the slave open now (the master reports no
    /// hang-up); notes opens and closes. On a close the bytes the client
    /// left unread and the backlog are dropped.
    fn check_client(&mut self) -> anyhow::Result<bool> {
        let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::empty())];
        match nix::poll::poll(&mut fds, PollTimeout::ZERO) {
            Ok(_) | Err(nix::errno::Errno::EINTR) => {}
            Err(e) => return Err(anyhow::Error::new(e).context("poll of the pty master")),
        }
        let hung_up = fds[0]
            .revents()
            .is_some_and(|r| r.contains(PollFlags::POLLHUP));
        let open = !hung_up;
        if open != self.open {
            self.open = open;
            if open {
                eprintln!("imu-emu: {} opened", self.slave_path.display());
            } else {
                eprintln!(
                    "imu-emu: {} closed; output is dropped until it is opened again",
                    self.slave_path.display()
                );
                self.backlog.clear();
                let slave = self.open_slave()?;
                termios::tcflush(&slave, FlushArg::TCIFLUSH).context("flushing the pty")?;
                drop(slave);
                // The next client finds the device's rate.
                self.mismatch = None;
                self.write_speed()?;
                // Closing it again restores the hang-up.
            }
        }
        if open {
            self.check_speed()?;
        }
        Ok(open)
    }
}

impl Transport for PtyTransport {
    fn describe(&self) -> String {
        format!("pty {}", self.slave_path.display())
    }

    fn prepare_wait(&mut self) -> anyhow::Result<()> {
        if self.open && !self.recheck {
            // Open as of the last wait, which would have seen a hang-up.
            return self.check_speed();
        }
        self.recheck = false;
        self.check_client()?;
        Ok(())
    }

    fn interest<'a>(&'a self, fds: &mut Vec<PollFd<'a>>) {
        if !self.open {
            // The master's hang-up would end every poll at once: sleep
            // instead (a signal still wakes it), looking again afterwards.
            return;
        }
        let ev = super::peer_interest(!self.hold, !self.backlog.is_empty());
        fds.push(PollFd::new(self.master.as_fd(), ev));
    }

    fn polled(&mut self, revents: &[PollFlags]) {
        // Polled only while open; level-triggered, as the TCP transport.
        let r = revents.first().copied().unwrap_or(PollFlags::empty());
        self.readable = !self.open || r.intersects(PollFlags::POLLIN | PollFlags::POLLERR);
        if r.intersects(PollFlags::POLLHUP | PollFlags::POLLERR) {
            self.recheck = true;
            self.readable = true;
        }
    }

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        if !std::mem::replace(&mut self.readable, true) {
            // Open as of the last wait, and nothing to read then.
            return Ok(());
        }
        self.recheck = false;
        self.check_client()?;
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
                    match self.mismatch {
                        // Sent at the client's rate, read at the device's.
                        Some(c) => sink(&crate::uart::resample(&buf[..n], c, self.bps)),
                        None => sink(&buf[..n]),
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                // No client has the slave open.
                Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => return Ok(()),
                Err(e) => return Err(anyhow::Error::new(e).context("reading the pty master")),
            }
        }
    }

    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        // A real line loses what nobody reads.
        if self.open {
            match self.mismatch {
                // Sent at the device's rate, read at the client's.
                Some(c) => self
                    .backlog
                    .push(&crate::uart::resample(bytes, self.bps, c)),
                None => self.backlog.push(bytes),
            }
        }
        Ok(())
    }

    fn hold_input(&mut self, hold: bool) {
        self.hold = hold;
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        if !self.open {
            return Ok(());
        }
        match self.backlog.write_to(&mut self.master) {
            Ok(_) => Ok(()),
            Err(e) if e.raw_os_error() == Some(nix::errno::Errno::EIO as i32) => Ok(()),
            Err(e) => Err(anyhow::Error::new(e).context("writing the pty master")),
        }
    }

    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        self.bps = bps;
        if self.open {
            // The client's port keeps its own speed: look at it again now.
            self.checked_at = None;
            self.check_speed()
        } else {
            self.write_speed()
        }
    }

    fn backlog_len(&self) -> usize {
        self.backlog.len()
    }

    fn backlog_dropped(&self) -> u64 {
        self.backlog.dropped()
    }

    fn connected(&self) -> bool {
        self.open
    }

    fn poll_client(&mut self) -> anyhow::Result<bool> {
        self.check_client()
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

/// The output speed a client set on the tty `fd`, bit/s: read with
/// `TCGETS2`, whose `c_ospeed` holds the integer rate both for a classic
/// `Bxxx` speed (the kernel fills it in) and for an arbitrary one
/// (`BOTHER`, which the `CBAUD` bits and `cfgetospeed` cannot express).
/// 0 is B0 (hang up), no rate.
pub fn client_speed(fd: impl std::os::fd::AsFd) -> anyhow::Result<u32> {
    Ok(rustix::termios::tcgetattr(fd)
        .context("tcgetattr (TCGETS2)")?
        .output_speed())
}

/// The rate of a standard termios speed, bit/s (`None` for one not in the
/// table).
pub fn baud_bps(b: BaudRate) -> Option<u32> {
    BAUDS.iter().find(|&&(_, x)| x == b).map(|&(r, _)| r)
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
            Ok(m) if m.file_type().is_symlink() => {
                // A pty slave exists only while its master is open: a link
                // to one that exists belongs to a running emulator (or
                // another program): refuse rather than steal it.
                if let Ok(old) = std::fs::read_link(path) {
                    if old.starts_with("/dev/pts") && old.exists() {
                        return Err(anyhow::Error::new(crate::error::UsageError(format!(
                            "--link {}: points at {}, a live pty (another imu-emu?); \
                             choose another path or stop that program",
                            path.display(),
                            old.display()
                        ))));
                    }
                }
                std::fs::remove_file(path)
                    .with_context(|| format!("replacing symlink {}", path.display()))?
            }
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

        // A rate change while the client has the port open leaves the
        // client's speed alone (a baud mismatch): the mismatch is
        // noted and bytes are garbled both ways until the client follows.
        t.set_line_rate(4800).unwrap();
        let mut tio = termios::tcgetattr(&client).unwrap();
        assert_eq!(termios::cfgetospeed(&tio), BaudRate::B115200);
        assert_eq!(t.mismatch(), Some(115_200));
        t.send(&[0x55]).unwrap();
        t.flush().unwrap();
        let mut g = [0u8; 1];
        client.read_exact(&mut g).unwrap();
        assert_eq!(g[0], crate::uart::resample(&[0x55], 4800, 115_200)[0]);
        termios::cfsetspeed(&mut tio, BaudRate::B4800).unwrap();
        termios::tcsetattr(&client, SetArg::TCSANOW, &tio).unwrap();
        std::thread::sleep(SPEED_CHECK);
        t.receive(usize::MAX, &mut |_| {}).unwrap();
        assert_eq!(t.mismatch(), None);
        // An arbitrary speed set through termios2 (BOTHER) is read too.
        let mut t2 = rustix::termios::tcgetattr(&client).unwrap();
        t2.set_speed(250_000).unwrap();
        rustix::termios::tcsetattr(&client, rustix::termios::OptionalActions::Now, &t2).unwrap();
        assert_eq!(client_speed(&client).unwrap(), 250_000);
        std::thread::sleep(SPEED_CHECK);
        t.receive(usize::MAX, &mut |_| {}).unwrap();
        assert_eq!(t.mismatch(), Some(250_000));
        termios::tcsetattr(&client, SetArg::TCSANOW, &tio).unwrap();
        std::thread::sleep(SPEED_CHECK);
        t.receive(usize::MAX, &mut |_| {}).unwrap();
        assert_eq!(t.mismatch(), None);

        // The client closing does not disturb the master; what is sent
        // while the port is closed is dropped, and so is what the client
        // left unread.
        t.send(&[5, 6]).unwrap();
        t.flush().unwrap();
        drop(client);
        t.receive(usize::MAX, &mut |_| {}).unwrap();
        assert!(!t.connected());
        t.send(&[3]).unwrap();
        t.flush().unwrap();
        assert_eq!(t.backlog_len(), 0);
        let mut client = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&link)
            .unwrap();
        assert!(t.poll_client().unwrap());
        t.send(&[4]).unwrap();
        t.flush().unwrap();
        let mut b = [0u8; 8];
        assert_eq!(client.read(&mut b).unwrap(), 1);
        assert_eq!(b[0], 4);
        drop(client);

        drop(t);
        assert!(std::fs::symlink_metadata(&link).is_err());
    }
}
