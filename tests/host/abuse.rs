//! The host runner under abuse: what a hostile or broken local
//! client does to the real `imu-emu` binary, and what the binary must do
//! about it — keep the device's ticks on time, keep its memory bounded,
//! keep running, refuse what is unsafe with one clear line.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::{BufRead, BufReader, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use support::{command, free_port, save, Conn, Control, Emu, Frame, TIMEOUT};

const GA: u8 = 0x8F;
const DATA_RATE: u16 = 0x0012;
const BAUD_RATE: u16 = 0x03B2;
/// Baud_Rate code of 2 000 000 bit/s (ICD Table 5.24).
const BAUD_2M: u8 = 0x0B;
/// USW bits 10–12: X/Y/Z angular rate out of range (ICD Table 5.26).
const USW_RATE_RANGE: u16 = 7 << 10;

fn u16_at(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([p[i], p[i + 1]])
}

fn i32_at(p: &[u8], i: usize) -> i32 {
    i32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]])
}

/// A free local port.
/// The GA 2 kHz counter (Table 5.7, payload offset 24).
fn counter(f: &Frame) -> u16 {
    assert_eq!(f.id(), GA, "{:02X?}", f.bytes);
    u16_at(f.payload(), 24)
}

/// Starts GA and returns the first GA data frame (the acknowledgement
/// skipped).
fn start_ga(c: &mut Conn) -> Frame {
    c.send(&command(GA));
    let ack = c.frame_with_id(GA);
    assert_eq!(ack.msg_type(), 1);
    assert_eq!(ack.payload(), &command(GA)[7..9]);
    c.frame_with_id(GA)
}

/// Reads GA frames until `done()` holds (checked between frames), then
/// `extra` more; asserts the 2 kHz counter steps by exactly `step` from
/// each frame to the next. Returns the number of frames.
fn ga_without_gaps(
    c: &mut Conn,
    first: &Frame,
    step: u16,
    extra: usize,
    limit: Duration,
    done: &mut dyn FnMut() -> bool,
) -> usize {
    let end = Instant::now() + limit;
    let mut last = counter(first);
    let mut n = 0;
    let mut after = None;
    while after.is_none_or(|k| k < extra) {
        let f = c
            .frame_before(end)
            .unwrap_or_else(|| panic!("GA stream stopped after {n} frames"));
        let k = counter(&f);
        assert_eq!(
            k,
            last.wrapping_add(step),
            "frame lost or repeated after {n} frames"
        );
        last = k;
        n += 1;
        match after.as_mut() {
            Some(k) => *k += 1,
            None if done() => after = Some(0),
            None => {}
        }
    }
    assert_eq!((c.bad, c.skipped), (0, 0), "torn or garbled frames");
    n
}

/// Runs `imu-emu` with `args` to completion (5 s at most: a refusal must
/// not hang), returning its output.
fn run(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn imu-emu");
    let end = Instant::now() + TIMEOUT;
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > end {
            child.kill().unwrap();
            let out = child.wait_with_output().unwrap();
            panic!(
                "imu-emu {args:?} still running after {TIMEOUT:?}; stdout {:?}, stderr {:?}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

/// Asserts that `out` is a refusal: status `code`, nothing on stdout
/// (nothing listened), exactly one line on stderr containing `needle`.
fn refused(out: &Output, code: i32, needle: &str) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "{err}");
    assert!(
        out.stdout.is_empty(),
        "listened anyway: {:?}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert_eq!(err.lines().count(), 1, "one line expected: {err:?}");
    assert!(err.starts_with("imu-emu: "), "{err:?}");
    assert!(err.contains(needle), "{needle:?} not in {err:?}");
    err
}

/// The resident-set figures of process `pid`, kB: (VmRSS, VmHWM).
fn rss_kb(pid: u32) -> (u64, u64) {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let field = |name: &str| -> u64 {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .unwrap_or_else(|| panic!("{name} in /proc/{pid}/status"))
    };
    (field("VmRSS:"), field("VmHWM:"))
}

/// A burst of one million short control lines (`pps`) while GA streams at
/// 2 kHz on a 2 Mbit/s line: every line is answered `ok` (exactly one
/// million answers) and no frame is lost or torn — the 2 kHz counter steps
/// by exactly 1 from each frame to the next for the whole burst. (The old
/// O(n²) line buffer froze the device loop for tens of seconds.)
#[test]
fn a_burst_of_a_million_control_lines_does_not_stall_the_ticks() {
    const LINES: usize = 1_000_000;
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let emu = Emu::tcp(&["--model", "K110", "--control", &addr]);
    let mut c = emu.connect();
    save(&mut c, DATA_RATE, &2000u16.to_le_bytes());
    save(&mut c, BAUD_RATE, &[BAUD_2M]);
    c.send(&command(0xC2)); // CommitBaudRate
    let first = start_ga(&mut c);

    let ctl = TcpStream::connect(&addr).unwrap();
    let mut w = ctl.try_clone().unwrap();
    let writer = std::thread::spawn(move || {
        w.write_all(&b"pps\n".repeat(LINES)).unwrap();
    });
    let r = ctl.try_clone().unwrap();
    r.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut ok = 0usize;
        let mut other = Vec::new();
        let mut lines = BufReader::new(r).lines();
        while ok + other.len() < LINES {
            match lines.next() {
                Some(Ok(l)) if l == "ok" => ok += 1,
                Some(Ok(l)) => other.push(l),
                _ => break,
            }
        }
        tx.send(()).unwrap();
        (ok, other)
    });
    let frames = ga_without_gaps(
        &mut c,
        &first,
        1,
        2000,
        Duration::from_secs(120),
        &mut || rx.try_recv().is_ok(),
    );
    writer.join().unwrap();
    let (ok, other) = reader.join().unwrap();
    assert_eq!(
        ok,
        LINES,
        "answers other than ok: {:?}",
        &other[..other.len().min(5)]
    );
    assert!(other.is_empty());
    eprintln!("{LINES} control lines answered during {frames} GA frames at 2 kHz");
    assert!(
        emu.stderr().lines().all(|l| !l.contains("dropped")),
        "{}",
        emu.stderr()
    );
}

/// 64 MiB on the control socket without a newline: the emulator's memory
/// stays small (its peak resident set grows by less than 8 MiB), the line
/// is answered once with an error naming the limit, and after a newline
/// the socket answers the next command.
#[test]
fn a_line_without_a_newline_does_not_grow_memory() {
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let emu = Emu::tcp(&["--model", "K110", "--control", &addr]);
    let _uart = emu.connect(); // powers the device on
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    assert_eq!(ctl.cmd("pps"), "ok");
    let (_, hwm0) = rss_kb(emu.pid());

    let mut w = TcpStream::connect(&addr).unwrap(); // replaces `ctl`
    w.set_read_timeout(Some(TIMEOUT)).unwrap();
    let chunk = vec![b'x'; 1 << 20];
    for _ in 0..64 {
        w.write_all(&chunk).unwrap();
    }
    w.write_all(b"\npps\n").unwrap();
    let mut r = BufReader::new(w.try_clone().unwrap());
    let mut line = String::new();
    r.read_line(&mut line).unwrap();
    assert_eq!(line, "error line longer than 256 bytes\n");
    line.clear();
    r.read_line(&mut line).unwrap();
    assert_eq!(line, "ok\n");

    let (rss, hwm) = rss_kb(emu.pid());
    assert!(
        hwm < hwm0 + 8 * 1024,
        "peak resident set {hwm0} kB before, {hwm} kB after 64 MiB (now {rss} kB)"
    );
    // A line just over the limit is refused, one at the limit is parsed.
    let long = format!("pps{}\n", " ".repeat(254));
    w.write_all(long.as_bytes()).unwrap();
    line.clear();
    r.read_line(&mut line).unwrap();
    assert_eq!(line, "error line longer than 256 bytes\n");
    let at_limit = format!("pps{}\n", " ".repeat(253));
    w.write_all(at_limit.as_bytes()).unwrap();
    line.clear();
    r.read_line(&mut line).unwrap();
    assert_eq!(line, "ok\n");
}

/// With the descriptor table full (once the first client is served, the
/// process's descriptor limit is lowered to its lowest free descriptor
/// with `prlimit --pid`), a second UART client and a control client make
/// `accept()` fail with EMFILE: the process keeps running, the current
/// client keeps its stream without a gap, the message is rate-limited (at
/// most once a second per listener), and once a descriptor is free the
/// control client is served.
#[test]
fn accept_failing_with_emfile_is_transient_and_rate_limited() {
    if Command::new("prlimit").arg("--version").output().is_err() {
        eprintln!("prlimit (util-linux) not installed: skipped");
        return;
    }
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let mut emu = Emu::tcp(&["--model", "K110", "--control", &addr]);
    let mut c = emu.connect();
    let first = start_ga(&mut c);
    let pid = emu.pid();
    let lowest_free = support::lowest_free_fd(pid);
    let limit = format!("--nofile={lowest_free}:{lowest_free}");
    let st = Command::new("prlimit")
        .args(["--pid", &pid.to_string(), &limit])
        .status()
        .unwrap();
    assert!(st.success(), "prlimit --pid {pid} {limit}");
    // Queued by the kernel, but the emulator cannot take them.
    let ctl = TcpStream::connect(&addr).unwrap();
    let second = TcpStream::connect(emu.addr()).unwrap();
    let t0 = Instant::now();
    let window = Duration::from_millis(2500);
    ga_without_gaps(&mut c, &first, 20, 0, TIMEOUT, &mut || {
        t0.elapsed() >= window
    });
    assert!(emu.running(), "exited: {}", emu.stderr());
    let err = emu.stderr();
    let failures = |what: &str| {
        err.lines()
            .filter(|l| l.contains(&format!("{what} accept failed")))
            .count()
    };
    for what in ["tcp", "control"] {
        let n = failures(what);
        assert!(
            (1..=3).contains(&n),
            "{n} {what} accept messages in 2.5 s:\n{err}"
        );
    }
    assert!(err.contains("Too many open files"), "{err}");

    // Free the descriptors: the queued UART client (already closed) and
    // then the control client are accepted.
    drop(second);
    drop(c);
    let mut ctl = {
        ctl.set_read_timeout(Some(TIMEOUT)).unwrap();
        let mut w = ctl.try_clone().unwrap();
        w.write_all(b"pps\n").unwrap();
        BufReader::new(ctl)
    };
    let mut line = String::new();
    ctl.read_line(&mut line).unwrap();
    assert_eq!(line, "ok\n");
    assert!(emu.running());
}

/// `--tcp` and `--control` on a non-loopback address are refused (exit
/// status 2, one line naming `--allow-remote`, nothing listens).
#[test]
fn non_loopback_addresses_are_refused_without_allow_remote() {
    for args in [
        &["--tcp", "0.0.0.0:0"][..],
        &["--tcp", "[::]:0"],
        &["--tcp", "127.0.0.1:0", "--control", "0.0.0.0:0"],
        &["--tcp", "127.0.0.1:0", "--control", "[::]:0"],
    ] {
        let out = run(args, &[]);
        let err = refused(&out, 2, "--allow-remote");
        assert!(err.contains("not a loopback address"), "{err}");
    }
    // Loopback in any spelling is fine without the flag.
    let emu = Emu::start(&["--tcp", "localhost:0"]);
    assert!(emu.stderr().lines().all(|l| !l.contains("WARNING")));
}

/// With `--allow-remote` the same addresses are accepted, with one loud
/// warning per remote listener on stderr; the device answers on them.
#[test]
fn allow_remote_accepts_with_a_loud_warning() {
    let port = free_port();
    let control = format!("0.0.0.0:{port}");
    let emu = Emu::start(&[
        "--tcp",
        "0.0.0.0:0",
        "--control",
        &control,
        "--allow-remote",
    ]);
    let at: std::net::SocketAddr = emu.listening.strip_prefix("tcp ").unwrap().parse().unwrap();
    assert!(at.ip().is_unspecified(), "{at}");
    let mut c = Conn::tcp(([127, 0, 0, 1], at.port()).into());
    start_ga(&mut c);
    let mut ctl = Control::connect(&format!("127.0.0.1:{port}"));
    assert_eq!(ctl.cmd("pps"), "ok");
    let err = emu.log_with(&format!("--control {control}"));
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains("WARNING")).collect();
    assert_eq!(warnings.len(), 2, "{err}");
    assert!(warnings[0].contains("--tcp 0.0.0.0:0") && warnings[0].contains("network"));
    assert!(warnings[1].contains(&format!("--control {control}")));
}

/// `--flash` on a FIFO, `/dev/null`, `/dev/full` or a directory is refused
/// at once with one line (no hang, nothing listens).
#[test]
fn flash_on_something_other_than_a_regular_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::S_IRWXU).unwrap();
    for (path, what) in [
        (fifo.to_str().unwrap(), "a FIFO"),
        ("/dev/null", "a character device"),
        ("/dev/full", "a character device"),
    ] {
        let out = run(&["--tcp", "127.0.0.1:0", "--flash", path], &[]);
        let err = refused(&out, 2, "not a regular file");
        assert!(err.contains(what) && err.contains(path), "{err}");
    }
    let out = run(
        &[
            "--tcp",
            "127.0.0.1:0",
            "--flash",
            dir.path().to_str().unwrap(),
        ],
        &[],
    );
    refused(&out, 1, "--flash");
}

/// A second emulator on the same flash file is refused (the file is locked
/// while the first runs); once the first stopped, the file is free again.
#[test]
fn a_second_emulator_on_the_same_flash_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let flash = dir.path().join("flash.bin");
    let flash = flash.to_str().unwrap();
    let mut first = Emu::tcp(&["--flash", flash]);
    let out = run(&["--tcp", "127.0.0.1:0", "--flash", flash], &[]);
    let err = refused(&out, 1, "in use by another process");
    assert!(err.contains(flash), "{err}");
    assert!(first.running());
    assert!(first.terminate().success());
    drop(first);
    let emu = Emu::tcp(&["--flash", flash]);
    drop(emu);
}

/// A client that half-closes its sending side keeps receiving the stream,
/// as on a real line: GA frames keep coming, without a gap, for a second.
#[test]
fn a_half_closed_client_keeps_receiving_the_stream() {
    let emu = Emu::tcp(&["--model", "K110", "-v"]);
    let s = TcpStream::connect(emu.addr()).unwrap();
    let half = s.try_clone().unwrap();
    let mut c = Conn::from_tcp(s);
    let first = start_ga(&mut c);
    half.shutdown(Shutdown::Write).unwrap();
    let t0 = Instant::now();
    let n = ga_without_gaps(&mut c, &first, 20, 0, TIMEOUT, &mut || {
        t0.elapsed() >= Duration::from_secs(1)
    });
    assert!(n >= 90, "{n} GA frames in 1 s after the half-close");
    let log = emu.log_with("closed its sending side");
    assert!(log.contains("closed its sending side"), "{log}");
}

/// A port in use is one line with the hint `--tcp 127.0.0.1:0`, never a
/// backtrace, whatever RUST_BACKTRACE says; the same for `--control`.
#[test]
fn a_port_in_use_is_one_line_with_a_hint() {
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    for bt in ["0", "1", "full"] {
        let out = run(
            &["--tcp", &addr],
            &[("RUST_BACKTRACE", bt), ("RUST_LIB_BACKTRACE", bt)],
        );
        let err = refused(&out, 1, "hint: --tcp 127.0.0.1:0");
        assert!(err.contains(&addr) && err.contains("in use"), "{err}");
        let out = run(
            &["--tcp", "127.0.0.1:0", "--control", &addr],
            &[("RUST_BACKTRACE", bt)],
        );
        refused(&out, 1, "hint: --control 127.0.0.1:0");
    }
    let out = run(&["--tcp", "7000"], &[("RUST_BACKTRACE", "1")]);
    refused(&out, 2, "expected HOST:PORT");
}

/// `motion rotate 1e6 0 0` on the control socket: the GA frames read X at
/// the gyro's range (450 °/s on a G450) with USW bit 10 set — not all-zero
/// axes with USW 0 — and the accelerometers keep reading.
#[test]
fn a_rotation_of_1e6_deg_s_saturates_on_the_wire() {
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let emu = Emu::tcp(&["--model", "KERNEL-110-G450-A40", "--control", &addr]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    start_ga(&mut c);
    ctl.wait_powered();
    assert_eq!(ctl.cmd("motion rotate 1e6 0 0"), "ok");
    c.drain_for(Duration::from_millis(100));
    for _ in 0..20 {
        let f = c.frame_with_id(GA);
        let p = f.payload();
        // Gyro ×1e5 (Table 5.7): +450 °/s after the FIR's unit gain.
        assert!(
            (i32_at(p, 0) - 45_000_000).abs() < 100,
            "gyro X {}",
            i32_at(p, 0)
        );
        assert_eq!(
            u16_at(p, 26) & USW_RATE_RANGE,
            1 << 10,
            "USW {:#06x}",
            u16_at(p, 26)
        );
    }
    assert_eq!(ctl.cmd("motion static"), "ok");
    c.drain_for(Duration::from_millis(100));
    let f = c.frame_with_id(GA);
    assert_eq!(u16_at(f.payload(), 26) & USW_RATE_RANGE, 0);
}

/// A trajectory value of 3.5e38 deg/s (beyond `f32`): X saturates at the
/// range (2000 °/s on a G2000) with USW bit 10, Z keeps its 1 g.
#[test]
fn a_trajectory_value_beyond_f32_saturates_on_the_wire() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.csv");
    std::fs::write(&path, "0,3.5e38,0,0,0,0,1\n1,3.5e38,0,0,0,0,1\n").unwrap();
    let emu = Emu::tcp(&["--model", "K110", "--trajectory", path.to_str().unwrap()]);
    let mut c = emu.connect();
    start_ga(&mut c);
    c.drain_for(Duration::from_millis(100));
    let f = c.frame_with_id(GA);
    let p = f.payload();
    assert!(
        (i32_at(p, 0) - 200_000_000).abs() < 100,
        "gyro X {}",
        i32_at(p, 0)
    );
    assert_eq!(u16_at(p, 26) & USW_RATE_RANGE, 1 << 10);
    // Accelerations ×1e6 g: Z ≈ 1 g.
    assert!(
        (i32_at(p, 20) - 1_000_000).abs() < 20_000,
        "acc Z {}",
        i32_at(p, 20)
    );
}

/// Options that parse but do not go together are refused with one line:
/// a KERNEL model for the IMX-5, a pty link with TCP, a flash
/// "file" that cannot hold an image.
#[test]
fn options_that_do_not_go_together_are_refused() {
    let out = run(&["--protocol", "isb", "--model", "K120"], &[]);
    let err = refused(&out, 2, "--model K120 is a KERNEL model");
    assert_eq!(
        err,
        "imu-emu: --model K120 is a KERNEL model; --protocol isb emulates an IMX-5 (drop \
         --model)\n"
    );
    let out = run(
        &["--link", "/tmp/imu-emu-no-link", "--tcp", "127.0.0.1:0"],
        &[],
    );
    let err = refused(&out, 2, "--link");
    assert_eq!(
        err,
        "imu-emu: --link names the pty's slave: it goes with --pty, not with --tcp or --serial\n"
    );
    assert!(!std::path::Path::new("/tmp/imu-emu-no-link").exists());
    // The web view listens on loopback only, like the other sockets.
    let out = run(&["--tcp", "127.0.0.1:0", "--web", "0.0.0.0:0"], &[]);
    let err = refused(&out, 2, "--web 0.0.0.0:0: not a loopback address");
    assert!(err.ends_with("add --allow-remote to allow it\n"), "{err}");
    let out = run(&["--flash", "/proc/version", "--tcp", "127.0.0.1:0"], &[]);
    let err = refused(&out, 2, "--flash /proc/version");
    assert!(
        err.starts_with(
            "imu-emu: --flash /proc/version: cannot write the 8192-byte flash image there ("
        ) && err.ends_with("); give the path of an ordinary file on a writable disk\n"),
        "{err}"
    );
}

/// `--help` speaks to users: no source modules, --pps in device time.
#[test]
fn help_sends_nobody_to_the_source() {
    let out = run(&["--help"], &[]);
    assert!(out.status.success());
    let help = String::from_utf8(out.stdout).unwrap();
    assert!(!help.contains("module"), "{help}");
    assert!(
        help.contains(
            "Generate a 1PPS rising edge every second of device time (so it follows --speed)"
        ),
        "{help}"
    );
    assert!(
        help.contains("send `help` on it for every command"),
        "{help}"
    );
}

/// A client that connects, asks and leaves, then another: the log says the
/// first left and the second connected — no "still sending", no
/// "replaced" for a client already gone.
#[test]
fn a_client_that_leaves_is_logged_as_gone() {
    let emu = Emu::tcp(&["--model", "K110"]);
    let s = TcpStream::connect(emu.addr()).unwrap();
    let first_addr = s.local_addr().unwrap();
    let mut first = Conn::from_tcp(s);
    first.send(&support::command(0x12));
    let _ = first.frame_with_id(0x12);
    drop(first);
    std::thread::sleep(Duration::from_millis(200));
    let second = TcpStream::connect(emu.addr()).unwrap();
    let second_addr = second.local_addr().unwrap();
    let want = format!("client {first_addr} left; client {second_addr} connected to");
    let log = emu.log_with(&want);
    assert!(log.contains(&want), "{want:?} not in {log}");
    assert!(!log.contains("closed its sending side"), "{log}");
    assert!(!log.contains("replaced by"), "{log}");
}

/// Shell completions and the man page come from the command-line
/// definition: every option is there; bash accepts the script.
#[test]
fn completions_and_man_page_come_from_the_cli_definition() {
    let out = run(&["completions", "bash"], &[]);
    assert!(out.status.success());
    let script = String::from_utf8(out.stdout).unwrap();
    for word in [
        "_imu__emu()",
        "--protocol",
        "--allow-remote",
        "client",
        "record",
        "--did",
    ] {
        assert!(script.contains(word), "no {word} in the bash completions");
    }
    let mut bash = Command::new("bash")
        .arg("-n")
        .stdin(Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write as _;
    bash.stdin
        .take()
        .unwrap()
        .write_all(script.as_bytes())
        .unwrap();
    assert!(bash.wait().unwrap().success(), "bash -n refused the script");
    let out = run(&["man"], &[]);
    assert!(out.status.success());
    let man = String::from_utf8(out.stdout).unwrap();
    assert!(man.contains(".TH imu-emu 1"), "{}", &man[..200]);
    for word in ["\\-\\-protocol", "\\-\\-pps", "device time", "client"] {
        assert!(man.contains(word), "no {word} in the man page");
    }
}
