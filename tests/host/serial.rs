//! End-to-end tests of `--serial DEV`: the emulator on a real
//! tty — here the slave of a pty pair the test opens, the test playing the
//! far end of the cable on the master — whose rate follows the device's.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::fs::File;
use std::time::Duration;

use nix::sys::termios::{self, BaudRate};
use support::{command, pty_pair as pair, read_ram, save, Conn, Emu, Master};

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

/// Opens the emulator's pty as a raw serial port (reads time out after
/// 0.1 s); returns the client and a handle to set its speed.
fn open_raw(path: &std::path::Path) -> (Conn, File) {
    use nix::sys::termios::{SetArg, SpecialCharacterIndices as Cc};
    use std::os::unix::fs::OpenOptionsExt;
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(nix::fcntl::OFlag::O_NOCTTY.bits())
        .open(path)
        .unwrap();
    let mut t = termios::tcgetattr(&f).unwrap();
    termios::cfmakeraw(&mut t);
    t.control_chars[Cc::VMIN as usize] = 0;
    t.control_chars[Cc::VTIME as usize] = 1;
    termios::tcsetattr(&f, SetArg::TCSANOW, &t).unwrap();
    let handle = f.try_clone().unwrap();
    (Conn::new(Box::new(f)), handle)
}

fn set_speed(f: &File, b: BaudRate) {
    let mut t = termios::tcgetattr(f).unwrap();
    termios::cfsetspeed(&mut t, b).unwrap();
    termios::tcsetattr(f, termios::SetArg::TCSANOW, &t).unwrap();
}

/// A driver that sends CommitBaudRate but leaves its port at the old rate
/// gets garbage both ways, as on the bench (and a warning is logged once);
/// once it sets its port to the new rate, the line works again.
#[test]
fn a_baud_mismatch_on_the_pty_garbles_both_ways_until_the_client_follows() {
    let emu = Emu::start(&["--pty"]);
    let (mut c, port) = open_raw(&emu.pty_path());
    c.send(&command(0x12));
    assert_eq!(c.frame_with_id(0x12).bytes.len(), 174);
    save(&mut c, 0x03B2, &[8]); // 230400
    c.send(&command(0xC2));
    std::thread::sleep(Duration::from_millis(100));
    // The device now runs at 230400, the port still at 115200: the
    // request reaches the device garbled and nothing valid comes back.
    c.send(&command(0x12));
    let deadline = std::time::Instant::now() + Duration::from_millis(400);
    assert!(c.frame_before(deadline).is_none());
    // The client follows: the line works.
    set_speed(&port, BaudRate::B230400);
    std::thread::sleep(Duration::from_millis(100));
    c.drain_for(Duration::from_millis(50));
    c.send(&command(0x12));
    assert_eq!(c.frame_with_id(0x12).bytes.len(), 174);
    // Garbled both ways: set the port wrong again while a stream runs; the
    // bytes still arrive, no frame is valid.
    c.send(&command(0x8F));
    c.frame_with_id(0x8F);
    set_speed(&port, BaudRate::B9600);
    std::thread::sleep(Duration::from_millis(100));
    c.drain_for(Duration::from_millis(50));
    let before = c.received;
    let deadline = std::time::Instant::now() + Duration::from_millis(300);
    assert!(c.frame_before(deadline).is_none());
    assert!(c.received > before);
    let log = emu.log_with("the client's port is at 9600 bit/s");
    let warnings: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("the client's port is at"))
        .collect();
    assert_eq!(warnings.len(), 2, "{log}");
    assert!(warnings[0].contains(
        "the client's port is at 115200 bit/s, the device's line at 230400 bit/s: bytes are \
         garbled both ways as on a real line (did the driver follow CommitBaudRate?)"
    ));
    assert!(warnings[1].contains("the client's port is at 9600 bit/s"));
}

/// `--link` at the link of a running emulator is refused (exit status 2,
/// one line), not stolen: the first emulator keeps its port.
#[test]
fn a_link_to_a_live_pty_is_refused_not_stolen() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("kernel");
    let first = Emu::start(&["--pty", "--link", link.to_str().unwrap()]);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["--pty", "--link", link.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        format!(
            "imu-emu: --link {}: points at {}, a live pty (another imu-emu?); choose another \
             path or stop that program\n",
            link.display(),
            first.pty_path().display()
        )
    );
    assert_eq!(std::fs::read_link(&link).unwrap(), first.pty_path());
}

/// A client that sets its port's speed with serialport-rs (as the
/// project's own client does: termios2, `BOTHER` and the integer rate,
/// which the classic `CBAUD` bits cannot say) at 9 600 bit/s against an
/// IMX-5 whose pty runs at 921 600: the runner reads the speed with
/// `TCGETS2`, warns once naming both rates, and the request reaches the
/// device garbled (no answer); set to 921 600 the same way, the line
/// matches again and the device answers.
#[test]
fn a_termios2_client_at_the_wrong_rate_is_warned_naming_both_rates() {
    use serialport::SerialPort as _;
    use std::os::unix::fs::OpenOptionsExt as _;
    let emu = Emu::start(&["--protocol", "isb", "--pty"]);
    let port = serialport::new(emu.pty_path().to_string_lossy(), 9600)
        .timeout(Duration::from_millis(100))
        .open_native()
        .unwrap();
    // serialport-rs set the speed as termios2 does: BOTHER, not B9600
    // (read on another descriptor of the same tty: the settings are the
    // tty's).
    let tty = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(nix::fcntl::OFlag::O_NOCTTY.bits())
        .open(emu.pty_path())
        .unwrap();
    let t = termios::tcgetattr(&tty).unwrap();
    drop(tty);
    let cbaud = t.control_flags.bits() & nix::libc::CBAUD;
    assert_eq!(cbaud, nix::libc::BOTHER, "serialport-rs sets BOTHER");
    let mut handle = port.try_clone_native().unwrap();
    let mut c = Conn::new(Box::new(port));
    let warning = "the client's port is at 9600 bit/s, the device's line at 921600 bit/s: \
                   bytes are garbled both ways as on a real line";
    let log = emu.log_with(warning);
    assert!(log.contains(warning), "{log}");
    // DEV_INFO requested at the wrong rate: garbled, unanswered.
    c.send(&support::isb_get(imu_emu::isb::did::DEV_INFO, 0));
    assert_eq!(c.drain_for(Duration::from_millis(300)), 0);
    handle.set_baud_rate(921_600).unwrap();
    let again = "the client's port matches the line rate again (921600 bit/s)";
    let log = emu.log_with(again);
    assert!(log.contains(again), "{log}");
    c.send(&support::isb_get(imu_emu::isb::did::DEV_INFO, 0));
    let p = support::isb_packet(&mut c);
    assert_eq!((p.did, p.payload.len()), (imu_emu::isb::did::DEV_INFO, 84));
    assert_eq!(log.matches("the client's port is at").count(), 1, "{log}");
}
