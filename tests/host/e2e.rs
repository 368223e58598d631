//! End-to-end tests of what is particular to the `imu-emu` host runner: the
//! pty, client replacement, the backlog. The protocol itself is tested by
//! the conformance suite (tests/conformance), which runs the same cases
//! against this binary and against the QEMU firmware.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::thread::sleep;
use std::time::{Duration, Instant};

use support::{
    ack_of, assert_rate, command, device_times, frame, hex, read_ram, save, save_flash, sum16,
    Conn, Control, DeviceClock, Emu,
};

const GET_DEV_INFO: u8 = 0x12;
const GA: u8 = 0x8F;
const STOP: u8 = 0xFE;
const COMMIT_BAUD_RATE: u8 = 0xC2;

const DATA_RATE: u16 = 0x0012;
const AUTO_START: u16 = 0x03A9;

const GA_FRAME_LEN: usize = 40;

#[test]
fn the_test_helpers_build_the_icd_vectors() {
    assert_eq!(command(GET_DEV_INFO), hex("AA 55 00 00 07 00 12 19 00"));
    assert_eq!(command(GA), hex("AA 55 00 00 07 00 8F 96 00"));
    assert_eq!(command(STOP), hex("AA 55 00 00 07 00 FE 05 01"));
    assert_eq!(command(COMMIT_BAUD_RATE), hex("AA 55 00 00 07 00 C2 C9 00"));
    assert_eq!(
        read_ram(0x028F, 1),
        hex("AA 55 00 00 0C 00 B1 FF 8F 02 01 00 4E 02")
    );
    assert_eq!(
        read_ram(DATA_RATE, 2),
        hex("AA 55 00 00 0C 00 B1 FF 12 00 02 00 D0 01")
    );
    assert_eq!(
        save_flash(DATA_RATE, &2000u16.to_le_bytes()),
        hex("AA 55 00 00 0E 00 B2 FF 12 00 02 00 D0 07 AA 02")
    );
    assert_eq!(frame(1, 0xB1, &[0x93]), hex("AA 55 01 B1 07 00 93 4C 01"));
    assert_eq!(
        ack_of(GA, &command(GA)),
        hex("AA 55 01 8F 08 00 96 00 2E 01")
    );
}

/// Sends GetDevInfo and checks the 174-byte reply.
fn get_dev_info_round_trip(c: &mut Conn) {
    c.send(&command(GET_DEV_INFO));
    let f = c.frame();
    assert_eq!(f.bytes.len(), 174, "{:02X?}", f.bytes);
    assert_eq!(&f.bytes[..6], &[0xAA, 0x55, 0x01, 0x12, 0xAC, 0x00]);
    let sum = sum16(&f.bytes[2..172]);
    assert_eq!(&f.bytes[172..], &sum.to_le_bytes());
    assert_eq!(f.payload().len(), 166);
    assert_ne!(f.payload()[49], 0, "IMU_type");
    assert_eq!(c.bad, 0);
}

/// Starts GA streaming; returns after the acknowledgement.
fn start_ga(c: &mut Conn) {
    let cmd = command(GA);
    c.send(&cmd);
    let ack = c.frame();
    assert_eq!(ack.bytes, ack_of(GA, &cmd));
    assert_eq!(
        ack.bytes,
        [0xAA, 0x55, 0x01, 0x8F, 0x08, 0x00, 0x96, 0x00, 0x2E, 0x01]
    );
}

/// The next frame, which must be a GA frame.
fn ga_frame(c: &mut Conn) -> support::Frame {
    let f = c.frame();
    assert_eq!(f.id(), GA, "{:02X?}", f.bytes);
    assert_eq!(f.msg_type(), 1);
    assert_eq!(f.bytes.len(), GA_FRAME_LEN);
    assert_eq!(&f.bytes[4..6], &[0x26, 0x00]);
    f
}

fn flash_file(dir: &tempfile::TempDir) -> String {
    dir.path().join("flash.bin").to_str().unwrap().to_owned()
}

#[test]
fn a_new_connection_replaces_the_old_and_the_device_keeps_streaming() {
    let emu = Emu::tcp(&[]);
    let mut c = emu.connect();
    start_ga(&mut c);
    for _ in 0..5 {
        ga_frame(&mut c);
    }
    drop(c);
    sleep(Duration::from_millis(100));

    let mut c = emu.connect();
    // Measured on the 2 kHz counter: the stream goes on at 100 Hz, without
    // a gap, for (at least) 0.5 s of device time on each client.
    let clock = DeviceClock::Counter(24);
    let stamps = device_times(&mut c, GA, 51, clock);
    assert_rate("GA after reconnecting", &stamps, clock, 100);

    // A third client replaces the second one while it is still open.
    let mut third = emu.connect();
    let stamps = device_times(&mut third, GA, 26, clock);
    assert_rate("GA on the third client", &stamps, clock, 100);
    drop(c);
}

/// The device powers on when the first client connects (`--power-on`
/// default), so a client connecting late still sees the AutoStart
/// announcement first, then the stream.
#[test]
fn auto_start_output_is_seen_by_a_late_first_client() {
    let dir = tempfile::tempdir().unwrap();
    let flash = flash_file(&dir);
    let mut emu = Emu::tcp(&["--flash", &flash]);
    let mut c = emu.connect();
    save(&mut c, AUTO_START, &[GA]);
    drop(c);
    assert!(emu.terminate().success());
    drop(emu);

    let emu = Emu::tcp(&["--flash", &flash]);
    sleep(Duration::from_millis(300));
    let mut c = emu.connect();
    assert_eq!(c.read_bytes(10), hex("AA 55 01 00 08 00 00 00 09 00"));
    for _ in 0..10 {
        ga_frame(&mut c);
    }
    assert_eq!((c.bad, c.skipped), (0, 0));
}

#[test]
fn pty_with_link_answers_get_dev_info() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("kernel");
    let mut emu = Emu::start(&["--pty", "--link", link.to_str().unwrap()]);
    assert_eq!(std::fs::read_link(&link).unwrap(), emu.pty_path());
    let mut c = Conn::serial(&link);
    get_dev_info_round_trip(&mut c);

    // Closing and reopening the port works (the runner holds the slave).
    drop(c);
    let mut c = Conn::serial(&link);
    c.drain_for(Duration::from_millis(100));
    get_dev_info_round_trip(&mut c);
    drop(c);

    assert!(emu.terminate().success());
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "--link symlink left behind"
    );
}

/// The GA 2 kHz counter (Table 5.7, payload offset 24).
fn ga_counter(f: &support::Frame) -> u16 {
    u16::from_le_bytes([f.payload()[24], f.payload()[25]])
}

/// Saves AutoStart = GA in a fresh flash file and returns its path.
fn auto_start_flash(dir: &tempfile::TempDir) -> String {
    let flash = flash_file(dir);
    let mut emu = Emu::tcp(&["--flash", &flash]);
    let mut c = emu.connect();
    save(&mut c, AUTO_START, &[GA]);
    drop(c);
    assert!(emu.terminate().success());
    flash
}

/// `--power-on now`: the device powers on at start and a real line loses
/// what nobody reads — a client connecting 500 ms later gets no
/// announcement and no old frames: its first GA frame is from after it
/// connected (2 kHz counter at least 2000 × 0.5 s).
#[test]
fn power_on_now_loses_what_was_sent_before_the_client_connected() {
    let dir = tempfile::tempdir().unwrap();
    let flash = auto_start_flash(&dir);
    let emu = Emu::tcp(&["--flash", &flash, "--power-on", "now"]);
    sleep(Duration::from_millis(500));
    let mut c = emu.connect();
    let f = c.frame();
    assert_eq!(f.id(), GA, "{:02X?}", f.bytes);
    assert_eq!(f.bytes.len(), GA_FRAME_LEN);
    assert!(
        ga_counter(&f) >= 1000,
        "stale frame: counter {}",
        ga_counter(&f)
    );
}

/// After a client disconnects, what the device sends meanwhile is dropped:
/// the next client's first GA frame follows the gap in time (its counter
/// jumped by at least 2000 × 0.4 s while nobody was connected), frames
/// from the unconnected time never arrive.
#[test]
fn output_while_no_client_is_connected_is_dropped() {
    let emu = Emu::tcp(&[]);
    let mut c = emu.connect();
    start_ga(&mut c);
    let mut last = 0;
    for _ in 0..5 {
        last = ga_counter(&ga_frame(&mut c));
    }
    drop(c);
    let gone = Instant::now();
    sleep(Duration::from_millis(500));
    let mut c = emu.connect();
    let away = gone.elapsed();
    let first = ga_frame(&mut c);
    let jump = ga_counter(&first).wrapping_sub(last);
    assert!(
        jump >= 800,
        "counter jumped by {jump} only: stale frames ({away:?} away)"
    );
    // Then the live stream, without gaps.
    let mut k = ga_counter(&first);
    for _ in 0..20 {
        let n = ga_counter(&ga_frame(&mut c));
        assert_eq!(n, k.wrapping_add(20));
        k = n;
    }
}

/// Before the first client connects the device is off: the control socket
/// says so instead of applying commands; once a client connected, it works.
#[test]
fn the_control_socket_says_when_the_device_is_off() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    let emu = Emu::tcp(&["--control", &addr]);
    let mut ctl = Control::connect(&addr);
    assert_eq!(
        ctl.cmd("pps"),
        "error the device is off: it powers on when a client connects to the UART \
         (or use --power-on now)"
    );
    let mut c = emu.connect();
    get_dev_info_round_trip(&mut c);
    assert_eq!(ctl.cmd("pps"), "ok");
}

/// On a pty the device powers on when the port is first opened (so the
/// AutoStart announcement is seen), and what it sends while the port is
/// closed — or what the client left unread — is dropped.
#[test]
fn pty_powers_on_at_first_open_and_drops_output_while_closed() {
    let dir = tempfile::tempdir().unwrap();
    let flash = auto_start_flash(&dir);
    let emu = Emu::start(&["--pty", "--flash", &flash]);
    sleep(Duration::from_millis(300));
    let mut c = Conn::serial(&emu.pty_path());
    assert_eq!(c.read_bytes(10), hex("AA 55 01 00 08 00 00 00 09 00"));
    let mut last = 0;
    for _ in 0..5 {
        last = ga_counter(&ga_frame(&mut c));
    }
    // Leave some unread, then close for 0.5 s.
    sleep(Duration::from_millis(100));
    drop(c);
    sleep(Duration::from_millis(500));
    let mut c = Conn::serial(&emu.pty_path());
    let first = ga_frame(&mut c);
    let jump = ga_counter(&first).wrapping_sub(last);
    assert!(jump >= 800, "counter jumped by {jump} only: stale frames");
    assert_eq!(
        ga_counter(&ga_frame(&mut c)),
        ga_counter(&first).wrapping_add(20)
    );
}
