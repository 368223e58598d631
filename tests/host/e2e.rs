//! End-to-end tests of what is particular to the `imu-emu` host runner: the
//! pty, client replacement, the backlog. The protocol itself is tested by
//! the conformance suite (tests/conformance), which runs the same cases
//! against this binary and against the QEMU firmware.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::thread::sleep;
use std::time::Duration;

use support::{
    ack_of, command, count_for, frame, hex, read_ram, save, save_flash, sum16, Conn, Emu,
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
    let (frames, _) = count_for(&mut c, GA, Duration::from_secs(1));
    assert!(frames >= 50, "{frames} GA frames in 1 s after reconnecting");

    // A third client replaces the second one while it is still open.
    let mut third = emu.connect();
    let (frames, _) = count_for(&mut third, GA, Duration::from_millis(500));
    assert!(
        frames >= 25,
        "{frames} GA frames in 0.5 s on the third client"
    );
    drop(c);
}

#[test]
fn auto_start_output_waits_in_the_backlog_for_the_first_client() {
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
