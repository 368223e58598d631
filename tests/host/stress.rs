//! The host runner under abuse, round two: what a hostile or
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

/// 1 000 `help` lines in one write (each answer ≈ 520
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

/// Smaller cases: a blank line is answered (`error empty
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

/// Runs `imu-emu ARGS…` to its end, killed (and the test failed) after
/// `limit`.
fn run_for(args: &[&str], limit: Duration) -> std::process::Output {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + limit;
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!(
                "imu-emu {args:?} still running after {limit:?}; stderr: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

/// `client --timeout` takes a finite time in (0, 3600]
/// seconds; NaN (which panicked), infinities and absurd values (which
/// waited for ever) are usage errors, exit status 2, one line naming the
/// option.
#[test]
fn client_timeouts_that_are_not_a_time_are_usage_errors() {
    for bad in ["nan", "NaN", "inf", "-inf", "1e300", "3601", "0", "-1", "x"] {
        let o = run_for(
            &[
                "client",
                "--tcp",
                "127.0.0.1:1",
                &format!("--timeout={bad}"),
                "info",
            ],
            TIMEOUT,
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "--timeout {bad}: {err}");
        assert!(err.contains("--timeout"), "--timeout {bad}: {err}");
        assert!(!err.contains("panicked"), "--timeout {bad}: {err}");
    }
}

/// `client record --frames 10` against a peer that
/// sends only valid frames that are not data (an acknowledgement, every
/// 20 ms, for ever) ends after `--timeout` with one line saying no data
/// frame came (it used to wait for ever).
#[test]
fn client_record_times_out_when_only_non_data_frames_come() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let peer = {
        let stop = std::sync::Arc::clone(&stop);
        std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            let ack = support::hex("aa 55 01 8f 08 00 96 00 2e 01");
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                if s.write_all(&ack).is_err() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        })
    };
    let t0 = std::time::Instant::now();
    let o = run_for(
        &[
            "client",
            "--tcp",
            &addr,
            "--timeout",
            "0.5",
            "record",
            "--frames",
            "10",
        ],
        Duration::from_secs(10),
    );
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    peer.join().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(
        err,
        format!(
            "imu-emu: --tcp {addr}: no data frame within 500ms after 0 rows (is a stream \
             running? --format GA starts one)\n"
        )
    );
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
}

/// `client decode` streams its input: decoding
/// `/dev/zero` (endless) keeps the process's resident memory small
/// (under 32 MiB after 1.5 s at GB/s; reading it whole grew without
/// bound).
#[test]
fn client_decode_streams_its_input_in_bounded_memory() {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["client", "decode", "/dev/zero", "--out", "/dev/null"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let status = std::fs::read_to_string(format!("/proc/{}/status", child.id()));
    let _ = child.kill();
    let _ = child.wait();
    let status = status.expect("still running");
    let kb = |key: &str| -> u64 {
        status
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no {key} in {status}"))
    };
    assert!(kb("VmHWM:") < 32 * 1024, "peak RSS {} kB", kb("VmHWM:"));
}

/// under `ulimit -n 6` a UART client that connects and
/// closes without sending holds the last descriptor; the emulator notices
/// the close while the device is idle (a client that closed its sending
/// side and is sent nothing for a second is closed), so the control
/// socket, whose accept failed with EMFILE meanwhile, then answers.
#[test]
fn a_closed_idle_client_frees_its_descriptor_for_the_control_socket() {
    let addr = format!("127.0.0.1:{}", free_port());
    let mut cmd = std::process::Command::new("bash");
    cmd.args([
        "-c",
        &format!(
            "ulimit -n 6; exec {} --tcp 127.0.0.1:0 --control {addr}",
            env!("CARGO_BIN_EXE_imu-emu")
        ),
    ]);
    let mut emu = Emu::start_command(cmd);
    let uart = TcpStream::connect(emu.addr()).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    drop(uart);
    let ctl = TcpStream::connect(&addr).unwrap();
    ctl.set_read_timeout(Some(TIMEOUT)).unwrap();
    let mut w = ctl.try_clone().unwrap();
    w.write_all(b"status\n").unwrap();
    let mut line = String::new();
    BufReader::new(ctl).read_line(&mut line).unwrap();
    assert!(line.starts_with("ok mode=idle "), "{line:?}");
    assert!(emu.running());
    emu.log_with("control accept failed");
    let err = emu.log_with("was sent nothing for 1 s: closed");
    assert!(err.contains("control accept failed"), "{err}");
    assert!(err.contains("was sent nothing for 1 s: closed"), "{err}");
}

/// CPU time (user + system) the process `pid` used so far, in clock
/// ticks (`/proc/PID/stat` fields 14 and 15).
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    // The fields after the command name, which is in parentheses.
    let rest = &stat[stat.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = rest.split(' ').collect();
    f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap()
}

/// A pty pair: the master (the far end of the cable), the slave and the
/// slave's path.
fn pty_pair() -> (std::fs::File, std::os::fd::OwnedFd, String) {
    let (master, slave, path) = support::pty_pair();
    (std::fs::File::from(master), slave, path)
}

/// GetDevInfo sent every 200 ms until its answer (174 bytes) comes, for
/// at most [`TIMEOUT`].
fn dev_info_answered(c: &mut support::Conn) -> bool {
    let end = std::time::Instant::now() + TIMEOUT;
    while std::time::Instant::now() < end {
        c.send(&support::command(0x12));
        let until = std::time::Instant::now() + Duration::from_millis(200);
        while let Some(f) = c.frame_before(until) {
            if f.id() == 0x12 {
                return f.bytes.len() == 174;
            }
        }
    }
    false
}

/// `--serial` says the device powers on
/// at start (not "when a client connects"); when the port hangs up (the
/// pty's master closed) the emulator says so once, does not spin (under
/// 0.2 s of CPU in 1 s; it used to take a whole core) and keeps running;
/// when the path opens again (here a symlink now pointing at another
/// pty) the device answers there.
#[test]
fn a_hung_up_serial_port_is_waited_on_and_opened_again() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyUSB0");
    let (master, slave, path) = pty_pair();
    std::os::unix::fs::symlink(&path, &link).unwrap();
    let mut emu = Emu::start(&["--serial", link.to_str().unwrap()]);
    let mut c = support::Conn::new(Box::new(support::Master(master)));
    assert!(dev_info_answered(&mut c));
    // Unplugged: the port hangs up and its node goes (so that the
    // emulator does not open a pty of another test that got its number).
    drop(c);
    drop(slave);
    std::fs::remove_file(&link).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let before = cpu_ticks(emu.pid());
    std::thread::sleep(Duration::from_secs(1));
    let used = cpu_ticks(emu.pid()) - before;
    let hz: u64 = String::from_utf8(
        std::process::Command::new("getconf")
            .arg("CLK_TCK")
            .output()
            .unwrap()
            .stdout,
    )
    .unwrap()
    .trim()
    .parse()
    .unwrap();
    assert!(
        used * 5 < hz,
        "{used} ticks of CPU in 1 s after the hang-up"
    );
    assert!(emu.running());
    // The port comes back (an adapter re-enumerated): a new pty behind
    // the same path.
    let (master, _slave, path) = pty_pair();
    std::os::unix::fs::symlink(&path, &link).unwrap();
    let mut c = support::Conn::new(Box::new(support::Master(master)));
    assert!(dev_info_answered(&mut c), "{}", emu.stderr());
    let err = emu.log_with("the port is back");
    assert_eq!(err.matches("the port hung up").count(), 1, "{err}");
    assert_eq!(err.matches("the port is back").count(), 1, "{err}");
    assert!(!err.contains("when a client connects"), "{err}");
}

/// How a burst reaches the emulator.
#[derive(Debug, Clone, Copy)]
enum Via {
    Tcp,
    Pty,
    Serial,
}

/// Commands in the burst.
const BURST: usize = 5000;

/// One command whose reply is shorter than itself, and a test of whether
/// a received reply is its reply: KERNEL ReadRAM of Data_Rate (14 bytes,
/// answered by 10), ISB GET of 4 bytes of DEV_INFO (16 bytes, answered by
/// a 14-byte DATA packet).
fn short_reply_command(isb: bool) -> Vec<u8> {
    if isb {
        let req = imu_emu::isb::message::GetRequest {
            did: u16::from(imu_emu::isb::did::DEV_INFO),
            size: 4,
            offset: 0,
            period: 0,
        };
        let mut out = [0u8; 32];
        let n = imu_emu::isb::message::encode_get(&req, &mut out).unwrap();
        out[..n].to_vec()
    } else {
        support::read_ram(0x0012, 2)
    }
}

/// The emulator behind `via` speaking `isb` or KERNEL in real time (the
/// burst takes its line time: 6 s at 115 200 bit/s, 0.9 s at 921 600), a
/// reader of its replies and a writer for the burst; and what must live
/// as long as the line.
fn line_to(
    via: Via,
    isb: bool,
) -> (
    Emu,
    support::Conn,
    Box<dyn Write + Send>,
    Option<std::os::fd::OwnedFd>,
) {
    let mut args = vec![];
    if isb {
        args.extend(["--protocol", "isb"]);
    }
    match via {
        Via::Tcp => {
            let emu = Emu::tcp(&args);
            let s = TcpStream::connect(emu.addr()).unwrap();
            let w = s.try_clone().unwrap();
            (emu, support::Conn::from_tcp(s), Box::new(w), None)
        }
        Via::Pty => {
            args.push("--pty");
            let emu = Emu::start(&args);
            let c = support::Conn::serial(&emu.pty_path());
            // The client's port at the device's rate (or bytes garble).
            let f = std::fs::OpenOptions::new()
                .write(true)
                .open(emu.pty_path())
                .unwrap();
            let rate = if isb {
                nix::sys::termios::BaudRate::B921600
            } else {
                nix::sys::termios::BaudRate::B115200
            };
            // Again once the device is on: its power-on writes its line
            // rate into the port's termios (a read-modify-write that may
            // undo `Conn::serial`'s reads that time out).
            std::thread::sleep(Duration::from_millis(300));
            use nix::sys::termios::SpecialCharacterIndices as Cc;
            let mut t = nix::sys::termios::tcgetattr(&f).unwrap();
            t.control_chars[Cc::VMIN as usize] = 0;
            t.control_chars[Cc::VTIME as usize] = 1;
            nix::sys::termios::cfsetspeed(&mut t, rate).unwrap();
            nix::sys::termios::tcsetattr(&f, nix::sys::termios::SetArg::TCSANOW, &t).unwrap();
            (emu, c, Box::new(f), None)
        }
        Via::Serial => {
            let (master, slave, path) = pty_pair();
            args.extend(["--serial", path.as_str()]);
            let emu = Emu::start(&args);
            let w = master.try_clone().unwrap();
            let c = support::Conn::new(Box::new(support::Master(master)));
            (emu, c, Box::new(w), Some(slave))
        }
    }
}

/// [`BURST`] commands in one write, far faster than the
/// line carries them, each get their reply (the device's input is paced
/// at the line rate whatever the transport delivers at once, so the
/// replies, each shorter than its command, always fit the line). Before,
/// 5 000 ReadRAM got 237 replies.
fn a_burst_gets_every_reply(via: Via, isb: bool) {
    let (emu, mut c, mut w, _keep) = line_to(via, isb);
    let cmd = short_reply_command(isb);
    // The device is on (a pty or TCP client powers it on) and answers.
    std::thread::sleep(Duration::from_millis(200));
    let burst = cmd.repeat(BURST);
    let writer = std::thread::spawn(move || w.write_all(&burst).map(|()| w));
    let mut replies = 0;
    while replies < BURST {
        if isb {
            let p = support::isb_packet(&mut c);
            if p.did == imu_emu::isb::did::DEV_INFO {
                assert!(p.raw.len() < cmd.len(), "{} bytes", p.raw.len());
                replies += 1;
            }
        } else {
            let end = std::time::Instant::now() + TIMEOUT;
            match c.frame_before(end) {
                Some(f) if f.id() == 0xB1 => {
                    assert_eq!(f.payload(), 100u16.to_le_bytes());
                    replies += 1;
                }
                Some(f) => panic!("{:02X?}", f.bytes),
                None => break,
            }
        }
    }
    // (The writer may still be blocked if replies are missing: not
    // joined then.)
    assert_eq!(replies, BURST, "{via:?} isb={isb}: {}", emu.stderr());
    let _w = writer.join().unwrap().unwrap();
    assert!(!emu.stderr().contains("overflowed"), "{}", emu.stderr());
}

#[test]
fn a_kernel_burst_over_tcp_gets_every_reply() {
    a_burst_gets_every_reply(Via::Tcp, false);
}

#[test]
fn a_kernel_burst_over_a_pty_gets_every_reply() {
    a_burst_gets_every_reply(Via::Pty, false);
}

#[test]
fn a_kernel_burst_over_a_serial_port_gets_every_reply() {
    a_burst_gets_every_reply(Via::Serial, false);
}

#[test]
fn an_isb_burst_over_tcp_gets_every_reply() {
    a_burst_gets_every_reply(Via::Tcp, true);
}

#[test]
fn an_isb_burst_over_a_pty_gets_every_reply() {
    a_burst_gets_every_reply(Via::Pty, true);
}

#[test]
fn an_isb_burst_over_a_serial_port_gets_every_reply() {
    a_burst_gets_every_reply(Via::Serial, true);
}

/// saves that fail to reach the flash file (here every
/// write refused with EFBIG: `ulimit -f 0` on an existing image, as a
/// full disk refuses them) are said on stderr at most once a second, with
/// the count, not once per save.
#[test]
fn failed_flash_writes_are_reported_at_most_once_a_second() {
    let dir = tempfile::tempdir().unwrap();
    let flash = dir.path().join("imu.flash");
    std::fs::write(&flash, vec![0xFF; 8192]).unwrap();
    let mut cmd = std::process::Command::new("bash");
    cmd.args([
        "-c",
        &format!(
            "trap '' XFSZ; ulimit -f 0; exec {} --tcp 127.0.0.1:0 --flash {}",
            env!("CARGO_BIN_EXE_imu-emu"),
            flash.display()
        ),
    ]);
    let emu = Emu::start_command(cmd);
    let mut c = emu.connect();
    let t0 = std::time::Instant::now();
    for k in 0..20u16 {
        c.send(&support::save_flash(
            0x0012,
            &(100 + k % 2 * 100).to_le_bytes(),
        ));
        std::thread::sleep(Duration::from_millis(20));
    }
    c.send(&support::read_ram(0x0012, 2));
    c.frame_with_id(0xB1);
    let secs = t0.elapsed().as_secs() + 1;
    let err = emu.log_with("failed writes so far");
    let lines = err.lines().filter(|l| l.contains("File too large")).count();
    assert!(lines >= 1, "{err}");
    assert!(lines as u64 <= secs, "{lines} lines in {secs} s: {err}");
    assert!(err.contains("failed writes so far"), "{err}");
}

/// a `--count` start that fails (device 2's flash path
/// is a directory; device 2's port is taken) leaves none of the `FILE.K`
/// files it created; a file that was there before stays.
#[test]
fn a_fleet_start_that_fails_leaves_no_flash_files() {
    let dir = tempfile::tempdir().unwrap();
    let flash = dir.path().join("imu");
    let k = |n: usize| dir.path().join(format!("imu.{n}"));
    std::fs::create_dir(k(2)).unwrap();
    let o = run_for(
        &[
            "--count",
            "3",
            "--tcp",
            "127.0.0.1:0",
            "--flash",
            flash.to_str().unwrap(),
        ],
        TIMEOUT,
    );
    assert!(!o.status.success());
    assert!(!k(0).exists() && !k(1).exists(), "FILE.0/FILE.1 left");
    assert!(k(2).is_dir());
    std::fs::remove_dir(k(2)).unwrap();

    // The third port taken; device 0's file was there before.
    std::fs::write(k(0), vec![0xFF; 8192]).unwrap();
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let o = run_for(
        &[
            "--count",
            "3",
            "--tcp",
            &format!("127.0.0.1:{}", port - 2),
            "--flash",
            flash.to_str().unwrap(),
        ],
        TIMEOUT,
    );
    assert!(
        !o.status.success(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(k(0).exists(), "a file that was there before was removed");
    assert!(!k(1).exists() && !k(2).exists(), "FILE.1/FILE.2 left");
}

/// A documented decision: the control socket serves one
/// client; a new one replaces the previous one, whose connection is
/// closed (it reads end of file), and is answered.
#[test]
fn a_new_control_client_replaces_the_previous_one() {
    let addr = format!("127.0.0.1:{}", free_port());
    let _emu = Emu::tcp(&["--control", &addr]);
    let mut first = support::Control::connect(&addr);
    assert_eq!(first.cmd("devices").split(' ').next(), Some("ok"));
    let mut second = support::Control::connect(&addr);
    assert_eq!(second.cmd("devices").split(' ').next(), Some("ok"));
    assert_eq!(first.line(), "", "the first client was not closed");
}
