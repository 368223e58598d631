//! The host runner under abuse, round two (issue 22): what a hostile or
//! broken peer does to the real `imu-emu` binary — a serial port that
//! hangs up, control answers longer than a socket buffer, command bursts
//! faster than the line, a client tool given absurd timeouts or a peer
//! that sends no data, an idle client's close under EMFILE.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::time::Duration;

use support::{free_port, Emu, TIMEOUT};

/// Sends `lines` in one write to a control socket at `addr`, then reads
/// back, after a pause in which the runner executes them all, exactly one
/// answer line per line (events skipped); panics after [`TIMEOUT`].
fn answers_to(addr: &str, lines: &str) -> Vec<String> {
    let s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(TIMEOUT)).unwrap();
    let mut w = s.try_clone().unwrap();
    w.write_all(lines.as_bytes()).unwrap();
    // Let the runner execute everything before anything is read: the
    // answers pile up in its output queue, not in the test's socket.
    std::thread::sleep(Duration::from_millis(300));
    let want = lines.split_inclusive('\n').count();
    let mut r = BufReader::new(s);
    let mut got = Vec::new();
    while got.len() < want {
        let mut l = String::new();
        match r.read_line(&mut l) {
            Ok(0) => break,
            Ok(_) if l.starts_with("event ") => {}
            Ok(_) => got.push(l.trim_end_matches('\n').to_owned()),
            Err(e) => panic!("after {} answers of {want}: {e}", got.len()),
        }
    }
    got
}

/// Issue 22 item 2: 1 000 `help` lines in one write (each answer ≈ 520
/// bytes, half a megabyte in all, far beyond the 64 KiB output queue)
/// get 1 000 whole answers, in order; so do 40 `devices` lines of a
/// 100-device run (≈ 3 KB each). A full queue holds back the next command
/// instead of dropping an answer.
#[test]
fn every_control_line_gets_its_whole_answer_however_long() {
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = Emu::tcp(&["--control", &addr, "--power-on", "now"]);
    let help = answers_to(&addr, "help\n");
    assert!(help[0].starts_with("ok commands: help |"), "{help:?}");
    assert!(help[0].len() > 400, "{}", help[0].len());
    let got = answers_to(&addr, &"help\n".repeat(1000));
    assert_eq!(got.len(), 1000);
    assert!(got.iter().all(|l| *l == help[0]), "an answer differs");
    drop(emu);

    let addr = format!("127.0.0.1:{}", free_port());
    let _fleet = Emu::tcp(&["--count", "100", "--control", &addr]);
    let devices = answers_to(&addr, "devices\n");
    assert!(devices[0].starts_with("ok count=100 dev0=tcp:127.0.0.1:"));
    assert!(devices[0].contains(" dev99=tcp:127.0.0.1:"));
    let got = answers_to(&addr, &"devices\n".repeat(40));
    assert_eq!(got.len(), 40);
    assert!(got.iter().all(|l| *l == devices[0]), "an answer differs");
}

/// Minor items of issue 22: a blank line is answered (`error empty
/// line`, one answer per line), and a device number is canonical
/// decimal (`dev +1`, `dev 01` are refused, `dev 0` and `dev 10` taken).
#[test]
fn blank_lines_are_answered_and_device_numbers_are_canonical() {
    let addr = format!("127.0.0.1:{}", free_port());
    let _emu = Emu::tcp(&["--count", "11", "--control", &addr]);
    let got = answers_to(
        &addr,
        "\n  \r\ndev +1 status\ndev 01 status\ndev 1 status\ndev 10 status\ndev 0 status\n",
    );
    assert_eq!(got.len(), 7, "{got:?}");
    assert_eq!(got[0], "error empty line");
    assert_eq!(got[1], "error empty line");
    assert_eq!(got[2], "error not a device number: +1");
    assert_eq!(got[3], "error not a device number: 01");
    for a in &got[4..] {
        assert_eq!(a, "ok mode=off", "{got:?}");
    }
}
