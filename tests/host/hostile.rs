//! The runner under abuse, round three, through the real binary: the web
//! view's HTTP server within its limits (huge and overflowing
//! `Content-Length`, oversized heads, slow and non-reading clients, more
//! connections than it serves, descriptor exhaustion, a POST to a device
//! that is off, `HEAD`, the `Host` check's case), lockstep samples far
//! ahead of the host clock, far-future feed rows, `motion file` of what
//! is not a regular file, NaN and inf lever arms of the IMX's
//! FLASH_CONFIG, and the rate limit of the feed's silence messages.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::{Read as _, Write as _};
use std::net::{SocketAddr, TcpStream, UdpSocket};
use std::process::Command;
use std::time::{Duration, Instant};

use imu_emu::feed::OWN_DEVICE;
use imu_emu::isb::did;
use imu_emu::isb::nav_sets::{GpsPos, Ins1, Ins2};
use imu_emu::isb::sets::flash;
use support::{
    command, feed_sample as sample, free_port, isb_get, isb_packet, isb_set, Conn, Control, Emu,
    TIMEOUT,
};

const GA: u8 = 0x8F;
/// The web server's connection limit (`boards/host/runner/src/web/server.rs`).
const MAX_CONNECTIONS: usize = 32;

/// The value of `key=` in a status line.
fn word<'a>(status: &'a str, key: &str) -> &'a str {
    status
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {status}"))
}

/// The stdout line starting with `prefix` among the first `n` after the
/// first, without the prefix.
fn line_after(emu: &Emu, n: usize, prefix: &str) -> String {
    emu.more_lines(n)
        .into_iter()
        .find_map(|l| l.strip_prefix(prefix).map(str::to_owned))
        .unwrap_or_else(|| panic!("no {prefix:?} line"))
}

/// A unit with a web view (and a control socket): (emulator, web
/// address, control address).
fn web_unit(extra: &[&str]) -> (Emu, SocketAddr, String) {
    let ctl = format!("127.0.0.1:{}", free_port());
    let mut args = vec!["--model", "K110", "--web", "127.0.0.1:0", "--control", &ctl];
    args.extend_from_slice(extra);
    let emu = Emu::tcp(&args);
    let web = line_after(&emu, 2, "web on http://");
    let web: SocketAddr = web.trim_end_matches('/').parse().unwrap();
    (emu, web, ctl)
}

/// Sends `request` on a new connection and reads the answer until the
/// server closes or `limit` passes: (status code or 0, whole answer).
fn http(web: SocketAddr, request: &[u8], limit: Duration) -> (u16, String) {
    let mut s = TcpStream::connect(web).unwrap();
    s.set_read_timeout(Some(limit)).unwrap();
    let _ = s.write_all(request);
    read_answer(&mut s, limit)
}

/// Reads one answer (head and `Content-Length` body) from `s` within
/// `limit`.
fn read_answer(s: &mut TcpStream, limit: Duration) -> (u16, String) {
    let end = Instant::now() + limit;
    let mut raw = Vec::new();
    let mut buf = [0u8; 8192];
    loop {
        let text = String::from_utf8_lossy(&raw).into_owned();
        if let Some((head, body)) = text.split_once("\r\n\r\n") {
            let len: usize = head
                .lines()
                .find_map(|l| {
                    l.to_ascii_lowercase()
                        .strip_prefix("content-length:")
                        .map(|v| v.trim().parse().unwrap())
                })
                .unwrap_or(0);
            if body.len() >= len {
                let code = head
                    .split_whitespace()
                    .nth(1)
                    .and_then(|c| c.parse().ok())
                    .unwrap_or(0);
                return (code, text);
            }
        }
        let left = end.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return (0, text);
        }
        s.set_read_timeout(Some(left)).unwrap();
        match s.read(&mut buf) {
            Ok(0) => {
                let code = text
                    .split_whitespace()
                    .nth(1)
                    .and_then(|c| c.parse().ok())
                    .unwrap_or(0);
                return (code, text);
            }
            Ok(n) => raw.extend_from_slice(&buf[..n]),
            Err(_) => return (0, text),
        }
    }
}

fn get(web: SocketAddr, path: &str) -> (u16, String) {
    http(
        web,
        format!("GET {path} HTTP/1.1\r\nHost: {web}\r\nConnection: close\r\n\r\n").as_bytes(),
        TIMEOUT,
    )
}

/// The resident set of process `pid`, kB.
fn rss_kb(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap()
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

/// A huge or overflowing `Content-Length` (from a foreign `Host` too) is
/// answered with an HTTP error and never allocated: the process and its
/// web port live on. (The old server aborted the process on the first and
/// closed the web port for good on the second.)
#[test]
fn huge_and_overflowing_content_lengths_are_refused_and_the_web_view_lives() {
    let (mut emu, web, _) = web_unit(&[]);
    for len in [
        "1000000000000",
        "18446744073709551615",
        "99999999999999999999",
    ] {
        for host in ["evil.example", &web.to_string()] {
            let req = format!(
                "POST /api/command HTTP/1.1\r\nHost: {host}\r\nX-Imu-Emu: 1\r\n\
                 Content-Length: {len}\r\n\r\n"
            );
            let (code, answer) = http(web, req.as_bytes(), TIMEOUT);
            assert!((400..500).contains(&code), "{len}: {answer:?}");
            assert!(emu.running(), "exited: {}", emu.stderr());
            assert_eq!(get(web, "/api/devices").0, 200, "{len}");
        }
    }
    let pid = emu.pid();
    assert!(rss_kb(pid) < 200_000, "{} kB", rss_kb(pid));
}

/// A head beyond 8 KiB or 32 headers gets 431; `HEAD` is answered like
/// `GET` without a body; the `Host` check ignores case.
#[test]
fn oversized_heads_are_refused_head_is_answered_and_host_ignores_case() {
    let (_emu, web, _) = web_unit(&[]);
    let many: String = (0..40).map(|i| format!("X-{i}: y\r\n")).collect();
    let req = format!("GET / HTTP/1.1\r\nHost: {web}\r\n{many}\r\n");
    assert_eq!(http(web, req.as_bytes(), TIMEOUT).0, 431);
    let long = "a".repeat(20_000);
    let req = format!("GET / HTTP/1.1\r\nHost: {web}\r\nX-Long: {long}\r\n\r\n");
    assert_eq!(http(web, req.as_bytes(), TIMEOUT).0, 431);
    let (code, page) = get(web, "/");
    assert_eq!(code, 200);
    let body_len = page.split_once("\r\n\r\n").unwrap().1.len();
    let mut s = TcpStream::connect(web).unwrap();
    write!(
        s,
        "HEAD / HTTP/1.1\r\nHost: {web}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut raw = String::new();
    s.set_read_timeout(Some(TIMEOUT)).unwrap();
    s.read_to_string(&mut raw).unwrap();
    assert!(raw.starts_with("HTTP/1.1 200 "), "{raw}");
    assert!(
        raw.contains(&format!("Content-Length: {body_len}\r\n")),
        "{raw}"
    );
    assert!(raw.ends_with("\r\n\r\n"), "HEAD sent a body: {raw}");
    let upper = format!("LOCALHOST:{}", web.port());
    let req = format!("GET /api/devices HTTP/1.1\r\nHost: {upper}\r\nConnection: close\r\n\r\n");
    assert_eq!(http(web, req.as_bytes(), TIMEOUT).0, 200);
}

/// A client that announces a body and never sends it, and one that
/// pipelines requests without reading the answers, delay nobody else and
/// do not grow the process (the old server served one request at a time
/// and buffered the non-reader's answers: 565 MB).
#[test]
fn a_silent_body_and_a_non_reading_pipeliner_delay_no_one() {
    let (emu, web, _) = web_unit(&[]);
    let mut silent = TcpStream::connect(web).unwrap();
    write!(
        silent,
        "POST /api/command HTTP/1.1\r\nHost: {web}\r\nX-Imu-Emu: 1\r\nContent-Length: 200\r\n\r\n"
    )
    .unwrap();
    let mut pipeliner = TcpStream::connect(web).unwrap();
    let one = format!("GET / HTTP/1.1\r\nHost: {web}\r\n\r\n");
    let burst = one.repeat(2000);
    pipeliner
        .set_write_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let start = Instant::now();
    let mut sent = 0usize;
    while start.elapsed() < Duration::from_secs(3) {
        if let Ok(n) = pipeliner.write(burst.as_bytes()) {
            sent += n;
        }
        // Meanwhile the others are answered at once.
        let t = Instant::now();
        assert_eq!(get(web, "/api/devices").0, 200);
        assert!(
            t.elapsed() < Duration::from_secs(2),
            "a request took {:?} beside the slow clients",
            t.elapsed()
        );
    }
    assert!(sent > 0);
    let kb = rss_kb(emu.pid());
    assert!(kb < 100_000, "{kb} kB with a non-reading client");
    drop((silent, pipeliner));
}

/// Beyond 32 connections at once the next gets 503 (not a wait); once
/// the idle ones go, requests are served again.
#[test]
fn connections_beyond_the_limit_get_503_and_the_port_stays_open() {
    let (_emu, web, _) = web_unit(&[]);
    let idle: Vec<TcpStream> = (0..MAX_CONNECTIONS)
        .map(|_| TcpStream::connect(web).unwrap())
        .collect();
    // The accept thread has taken them all (each holds its slot).
    std::thread::sleep(Duration::from_millis(300));
    let (code, answer) = get(web, "/api/devices");
    assert_eq!(code, 503, "{answer}");
    assert!(answer.contains("Retry-After: 1"), "{answer}");
    drop(idle);
    let end = Instant::now() + TIMEOUT;
    loop {
        let (code, _) = get(web, "/api/devices");
        if code == 200 {
            break;
        }
        assert!(
            Instant::now() < end,
            "still {code} after the idle ones left"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// EMFILE on the web port is transient, reported at most once a second:
/// once descriptors are free the web view answers again (the old server's
/// accept thread ended on the first failure).
#[test]
fn emfile_on_the_web_port_is_transient() {
    assert!(
        Command::new("prlimit").arg("--version").output().is_ok(),
        "prlimit (util-linux) is needed"
    );
    let (mut emu, web, _) = web_unit(&[]);
    assert_eq!(get(web, "/api/devices").0, 200);
    // (Its connection's thread closes its end first.)
    std::thread::sleep(Duration::from_millis(300));
    let pid = emu.pid();
    let lowest_free = support::lowest_free_fd(pid);
    let st = Command::new("prlimit")
        .args([
            "--pid",
            &pid.to_string(),
            // The soft limit only, so that it can be raised again.
            &format!("--nofile={lowest_free}:"),
        ])
        .status()
        .unwrap();
    assert!(st.success());
    let queued = TcpStream::connect(web).unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    let err = emu.stderr();
    let n = err
        .lines()
        .filter(|l| l.contains("web accept failed"))
        .count();
    assert!((1..=4).contains(&n), "{n} messages in 2.5 s:\n{err}");
    drop(queued);
    let st = Command::new("prlimit")
        .args(["--pid", &pid.to_string(), "--nofile=1024:"])
        .status()
        .unwrap();
    assert!(st.success());
    let end = Instant::now() + TIMEOUT;
    while get(web, "/api/devices").0 != 200 {
        assert!(Instant::now() < end, "the web port stayed closed");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(emu.running());
}

/// A POST while the device is off waits for its own answer (503 after
/// 2 s) without holding the web view: a GET meanwhile is answered at
/// once (the old server held every request for those 2 s).
#[test]
fn a_post_while_the_device_is_off_holds_only_itself() {
    let (_emu, web, _) = web_unit(&[]);
    let post = std::thread::spawn(move || {
        http(
            web,
            format!(
                "POST /api/command HTTP/1.1\r\nHost: {web}\r\nX-Imu-Emu: 1\r\n\
                 Content-Length: 6\r\nConnection: close\r\n\r\nstatus"
            )
            .as_bytes(),
            TIMEOUT,
        )
    });
    std::thread::sleep(Duration::from_millis(200));
    let t = Instant::now();
    assert_eq!(get(web, "/api/devices").0, 200);
    let took = t.elapsed();
    let (code, answer) = post.join().unwrap();
    assert_eq!(code, 503, "{answer}");
    assert!(took < Duration::from_millis(1500), "GET waited {took:?}");
}

/// `motion file` of a FIFO, `/dev/zero` or a directory is refused at once
/// (control socket and web view) and the device goes on; the old runner
/// blocked on the FIFO and read `/dev/zero` until memory ran out.
#[test]
fn motion_file_of_what_is_not_a_regular_file_is_refused_at_once() {
    let (emu, web, ctl) = web_unit(&[]);
    let mut c = emu.connect();
    c.send(&command(GA));
    c.frame_with_id(GA);
    let mut ctl = Control::connect(&ctl);
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo");
    let st = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(st.success());
    let fifo = fifo.to_str().unwrap().to_owned();
    let d = dir.path().to_str().unwrap().to_owned();
    for (path, what) in [
        (fifo.as_str(), "a FIFO"),
        ("/dev/zero", "a character device"),
        (d.as_str(), "a directory"),
    ] {
        let t = Instant::now();
        let a = ctl.cmd(&format!("motion file {path}"));
        assert!(a.starts_with("error ") && a.contains(what), "{a}");
        assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
        let body = format!("motion file {path}");
        let req = format!(
            "POST /api/command HTTP/1.1\r\nHost: {web}\r\nX-Imu-Emu: 1\r\nContent-Length: {}\r\n\
             Connection: close\r\n\r\n{body}",
            body.len()
        );
        let (code, answer) = http(web, req.as_bytes(), TIMEOUT);
        assert_eq!(code, 422, "{answer}");
        assert!(answer.contains(what), "{answer}");
    }
    // The device loop went on: frames still come, memory stayed small.
    c.drain_for(Duration::from_millis(50));
    assert!(c.frame_before(Instant::now() + TIMEOUT).is_some());
    assert!(rss_kb(emu.pid()) < 200_000);
}

/// A unit with a control socket and `args`, its UART client connected
/// and the device on: (emulator, UART, control).
fn unit(args: &[&str]) -> (Emu, Conn, Control) {
    let ctl = format!("127.0.0.1:{}", free_port());
    let mut all = vec!["--control", &ctl];
    all.extend_from_slice(args);
    let emu = Emu::tcp(&all);
    let c = emu.connect();
    let mut ctl = Control::connect(&ctl);
    ctl.wait_powered();
    (emu, c, ctl)
}

/// A K110 with a motion feed on `feed` (`127.0.0.1:0`, `udp:…`) and
/// `args`: (emulator, UART, control, the feed's address).
fn feed_unit(feed: &str, args: &[&str]) -> (Emu, Conn, Control, SocketAddr) {
    let mut all = vec!["--model", "K110", "--motion-feed", feed];
    all.extend_from_slice(args);
    let (emu, c, ctl) = unit(&all);
    let addr = line_after(&emu, 2, "feed on ");
    let addr = addr.split_once(' ').unwrap().1.parse().unwrap();
    (emu, c, ctl, addr)
}

/// A lockstep unit at `speed` with a TCP feed: (emulator, UART, control,
/// feed).
fn lockstep_unit(speed: &str) -> (Emu, Conn, Control, TcpStream) {
    let (emu, c, ctl, feed) = feed_unit("127.0.0.1:0", &["--lockstep", "--speed", speed]);
    let f = TcpStream::connect(feed).unwrap();
    (emu, c, ctl, f)
}

/// The GA 2 kHz counter (Table 5.7, payload offset 24).
fn counter(p: &[u8]) -> u16 {
    u16::from_le_bytes([p[24], p[25]])
}

/// `--lockstep --speed 1`: a row 5 s ahead of the host clock is reached
/// tick by tick as the host clock goes — GA frames keep coming, their
/// counter advancing — and the control socket answers meanwhile; a row
/// 10⁶ s ahead is refused (`too-far-ahead`, counted) and the feed goes
/// on. (The old runner slept the whole lead: no frame, no answer.)
#[test]
fn a_lockstep_sample_ahead_of_the_host_clock_never_silences_the_unit() {
    let (_emu, mut c, mut ctl, mut f) = lockstep_unit("1");
    ctl.wait_powered();
    c.send(&command(GA));
    // Rows at the host's pace for 0.5 s.
    let t0 = Instant::now();
    let mut t = 0.0;
    while t < 0.5 {
        t = t0.elapsed().as_secs_f64();
        f.write_all(&sample(OWN_DEVICE, t, [0.0; 3])).unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    c.frame_with_id(GA);
    // One row 10⁶ s ahead: refused at once.
    f.write_all(&sample(OWN_DEVICE, t + 1e6, [0.0; 3])).unwrap();
    let end = Instant::now() + TIMEOUT;
    loop {
        let s = ctl.cmd("status");
        if s.contains("feed-rejected-too-far-ahead=1") {
            break;
        }
        assert!(Instant::now() < end, "{s}");
    }
    // One row 5 s ahead: device time follows the host clock towards it.
    f.write_all(&sample(OWN_DEVICE, t + 5.0, [0.0; 3])).unwrap();
    c.drain_for(Duration::from_millis(100));
    let first = counter(c.frame_with_id(GA).payload());
    let t1 = Instant::now();
    std::thread::sleep(Duration::from_millis(1000));
    let a = Instant::now();
    assert!(ctl.cmd("status").starts_with("ok "));
    assert!(
        a.elapsed() < Duration::from_millis(1500),
        "{:?}",
        a.elapsed()
    );
    let last = loop {
        let n = counter(c.frame_with_id(GA).payload());
        if t1.elapsed() >= Duration::from_millis(1500) {
            break n;
        }
    };
    let ticks = last.wrapping_sub(first);
    // About 1.5 s of 2 kHz ticks (the host clock), never the whole lead
    // (10 000 ticks).
    assert!((1000..=7000).contains(&ticks), "{ticks} ticks");
}

/// A far-future row (Unix time) in real time locks the feed only until a
/// new connection or a power cycle starts a new timeline; in lockstep at
/// `--speed max` it is refused (`too-far-ahead`) instead of running
/// 1.8·10⁹ s of ticks.
#[test]
fn a_far_future_row_does_not_lock_the_feed() {
    // Real time over TCP: a new connection.
    let (emu, _c, mut ctl, feed) = feed_unit("127.0.0.1:0", &[]);
    let samples = |ctl: &mut Control, n: &str| {
        let end = Instant::now() + TIMEOUT;
        loop {
            let s = ctl.cmd("status");
            if word(&s, "feed-samples") == n {
                return s;
            }
            assert!(Instant::now() < end, "feed-samples not {n}: {s}");
            std::thread::sleep(Duration::from_millis(5));
        }
    };
    let mut f = TcpStream::connect(feed).unwrap();
    f.write_all(b"1700000000.0, 0, 0, 0, 0, 0, 1\n1.0, 0, 0, 0, 0, 0, 1\n")
        .unwrap();
    let s = samples(&mut ctl, "1");
    let end = Instant::now() + TIMEOUT;
    let mut s = s;
    while !s.contains("feed-rejected-non-increasing=1") {
        assert!(Instant::now() < end, "{s}");
        s = ctl.cmd("status");
    }
    drop(f);
    let mut f = TcpStream::connect(feed).unwrap();
    f.write_all(b"2.0, 0, 0, 0, 0, 0, 1\n3.0, 0, 0, 0, 0, 0, 1\n")
        .unwrap();
    samples(&mut ctl, "3");
    // A power cycle too (the same connection).
    f.write_all(b"1700000000.0, 0, 0, 0, 0, 0, 1\n").unwrap();
    samples(&mut ctl, "4");
    assert_eq!(ctl.cmd("power-cycle"), "ok");
    f.write_all(b"4.0, 0, 0, 0, 0, 0, 1\n").unwrap();
    samples(&mut ctl, "5");
    drop(emu);

    // UDP: a power cycle.
    let (emu, _c, mut ctl, feed) = feed_unit("udp:127.0.0.1:0", &[]);
    let u = UdpSocket::bind("127.0.0.1:0").unwrap();
    u.send_to(b"1700000000.0, 0, 0, 0, 0, 0, 1\n", feed)
        .unwrap();
    samples(&mut ctl, "1");
    u.send_to(b"1.0, 0, 0, 0, 0, 0, 1\n", feed).unwrap();
    let end = Instant::now() + TIMEOUT;
    while !ctl.cmd("status").contains("feed-rejected-non-increasing=1") {
        assert!(Instant::now() < end);
    }
    assert_eq!(ctl.cmd("power-cycle"), "ok");
    u.send_to(b"2.0, 0, 0, 0, 0, 0, 1\n", feed).unwrap();
    samples(&mut ctl, "2");
    drop(emu);

    // Lockstep at --speed max: refused, and the next row is taken.
    let (_emu, mut c, mut ctl, mut f) = lockstep_unit("max");
    ctl.wait_powered();
    c.send(&command(GA));
    f.write_all(
        b"0.001, 0, 0, 0, 0, 0, 1\n1700000000.0, 0, 0, 0, 0, 0, 1\n0.002, 0, 0, 0, 0, 0, 1\n",
    )
    .unwrap();
    let s = samples(&mut ctl, "2");
    assert!(s.contains("feed-rejected-too-far-ahead=1"), "{s}");
    let t = Instant::now();
    assert!(ctl.cmd("status").starts_with("ok "));
    assert!(t.elapsed() < Duration::from_secs(1));
}

/// A jittery feeder (silent past the timeout, then back, over and over)
/// gets at most a burst of `silent` / `back` messages, then one per 10 s
/// naming how many were held back (the old runner logged every change:
/// 36 000 lines in 5 minutes of a fleet).
#[test]
fn feed_silence_messages_are_rate_limited() {
    let (emu, _c, _ctl, feed) = feed_unit("127.0.0.1:0", &["--feed-timeout", "0.01"]);
    let mut f = TcpStream::connect(feed).unwrap();
    let t0 = Instant::now();
    let mut t = 0.0;
    while t0.elapsed() < Duration::from_secs(2) {
        t += 0.05;
        f.write_all(format!("{t}, 0, 0, 0, 0, 0, 1\n").as_bytes())
            .unwrap();
        std::thread::sleep(Duration::from_millis(50));
    }
    let err = emu.stderr();
    let n = err
        .lines()
        .filter(|l| l.contains("motion feed silent") || l.contains("motion feed back"))
        .count();
    assert!((2..=4).contains(&n), "{n} lines:\n{err}");
}

/// NaN, inf and out-of-range lever arms (`insOffset`, `gps1AntOffset`)
/// and `insRotation` are NACKed as `refLla` is; after the first fix no
/// INS or GPS output carries a NaN or an infinity.
#[test]
fn nan_and_inf_lever_arms_are_refused_and_no_nan_reaches_an_output() {
    let (_emu, mut c, _ctl) = unit(&[
        "--protocol",
        "isb",
        "--speed",
        "20",
        "--gps-time",
        "2026-03-01T12:00:00Z",
    ]);
    let bad = |x: f32| {
        [x, 0.0, 0.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect::<Vec<u8>>()
    };
    for off in [
        flash::INS_OFFSET,
        flash::GPS1_ANT_OFFSET,
        flash::INS_ROTATION,
    ] {
        for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e6] {
            c.send(&isb_set(did::FLASH_CONFIG, off as u16, &bad(x)));
            let p = isb_packet(&mut c);
            assert_eq!(p.flags, 2, "offset {off} value {x}: not a NACK");
        }
        // One component alone, as a vendor tool may write it.
        c.send(&isb_set(
            did::FLASH_CONFIG,
            off as u16 + 8,
            &f32::NAN.to_le_bytes(),
        ));
        assert_eq!(isb_packet(&mut c).flags, 2, "offset {off} + 8");
    }
    c.send(&isb_set(
        did::FLASH_CONFIG,
        flash::INS_OFFSET as u16,
        &bad(1.5),
    ));
    assert_eq!(isb_packet(&mut c).flags, 1, "a sane lever arm is taken");
    c.send(&isb_get(did::GPS1_POS, 1));
    c.send(&isb_get(did::INS_1, 25));
    c.send(&isb_get(did::INS_2, 25));
    let mut fixes = 0;
    let mut checked = 0;
    let end = Instant::now() + Duration::from_secs(30);
    while fixes < 10 {
        assert!(Instant::now() < end, "no fix");
        let p = isb_packet(&mut c);
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match p.did {
            did::GPS1_POS => {
                let g = GpsPos::decode(&p.payload.try_into().unwrap());
                assert!(finite(&g.lla) && finite(&g.ecef), "{g:?}");
                if g.status != 0 {
                    fixes += 1;
                }
            }
            did::INS_1 => {
                let i = Ins1::decode(&p.payload.try_into().unwrap());
                assert!(finite(&i.lla), "{i:?}");
                assert!(i.ned.iter().chain(&i.uvw).all(|x| x.is_finite()), "{i:?}");
                checked += 1;
            }
            did::INS_2 => {
                let i = Ins2::decode(&p.payload.try_into().unwrap());
                assert!(finite(&i.lla), "{i:?}");
                assert!(i.qn2b.iter().all(|x| x.is_finite()), "{i:?}");
                checked += 1;
            }
            _ => {}
        }
    }
    assert!(checked > 10);
}

/// A fleet's shared feed: a new connection starts a new timeline for
/// every device, so a far-future sample sent once does not lock any of
/// them.
#[test]
fn a_new_connection_to_a_shared_feed_starts_every_devices_timeline() {
    let ctl = format!("127.0.0.1:{}", free_port());
    let emu = Emu::start(&[
        "--count",
        "2",
        "--tcp",
        "127.0.0.1:0",
        "--control",
        &ctl,
        "--power-on",
        "now",
        "--motion-feed",
        "127.0.0.1:0",
        "--feed-shared",
    ]);
    let feed: SocketAddr = line_after(&emu, 3, "feed on tcp ").parse().unwrap();
    let mut c = Control::connect(&ctl);
    let wait = |c: &mut Control, k: u16, key: &str, value: &str| {
        let end = Instant::now() + TIMEOUT;
        loop {
            let s = c.cmd(&format!("dev {k} status"));
            if s.split_whitespace().any(|w| w == format!("{key}={value}")) {
                return;
            }
            assert!(Instant::now() < end, "dev {k}: no {key}={value} in {s}");
            std::thread::sleep(Duration::from_millis(5));
        }
    };
    let mut f = TcpStream::connect(feed).unwrap();
    for k in 0..2 {
        f.write_all(&sample(k, 1.7e9, [0.0; 3])).unwrap();
        f.write_all(&sample(k, 1.0, [0.0; 3])).unwrap();
    }
    for k in 0..2 {
        wait(&mut c, k, "feed-rejected-non-increasing", "1");
    }
    drop(f);
    let mut f = TcpStream::connect(feed).unwrap();
    for k in 0..2 {
        f.write_all(&sample(k, 2.0, [0.0; 3])).unwrap();
    }
    for k in 0..2 {
        wait(&mut c, k, "feed-samples", "2");
    }
}
