//! End-to-end tests of `--serial DEV` (issue 11): the emulator on a real
//! tty — here the slave of a pty pair the test opens, the test playing the
//! far end of the cable on the master — whose rate follows the device's.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::time::Duration;

use nix::poll::{PollFd, PollFlags, PollTimeout};
use nix::sys::termios::{self, BaudRate};
use support::{command, read_ram, save, Conn, Emu};

/// The pty master as the far end of the line: reads time out after 20 ms.
struct Master(File);

impl Read for Master {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let mut fds = [PollFd::new(self.0.as_fd(), PollFlags::POLLIN)];
        nix::poll::poll(&mut fds, PollTimeout::from(20u8)).map_err(std::io::Error::from)?;
        if fds[0]
            .revents()
            .is_some_and(|r| r.intersects(PollFlags::POLLIN))
        {
            self.0.read(buf)
        } else {
            Err(std::io::ErrorKind::WouldBlock.into())
        }
    }
}

impl Write for Master {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn pair() -> (OwnedFd, OwnedFd, String) {
    let pty = nix::pty::openpty(None, None).unwrap();
    let path = nix::unistd::ttyname(&pty.slave).unwrap();
    (pty.master, pty.slave, path.to_str().unwrap().to_owned())
}

#[test]
fn the_device_on_a_serial_port_answers_and_its_rate_follows_commit_baud_rate() {
    let (master, slave, path) = pair();
    let emu = Emu::start(&["--serial", &path]);
    assert_eq!(emu.listening, format!("serial {path}"));
    let speed = || termios::cfgetospeed(&termios::tcgetattr(&slave).unwrap());
    // Opened at the power-on line rate.
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(speed(), BaudRate::B115200);
    let mut c = Conn::new(Box::new(Master(File::from(master))));
    c.send(&command(0x12));
    let info = c.frame_with_id(0x12);
    assert_eq!(info.bytes.len(), 174);
    // Baud_Rate 460800 (code 9), CommitBaudRate: the port follows.
    save(&mut c, 0x03B2, &[9]);
    c.send(&command(0xC2));
    c.send(&read_ram(0x03B2, 1));
    assert_eq!(c.frame_with_id(0xB1).payload(), &[9]);
    assert_eq!(speed(), BaudRate::B460800);
    assert_eq!(c.bad, 0);
    drop(emu);
}
