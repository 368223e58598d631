//! The live motion feed (`--motion-feed`) through the real
//! binary: text rows and binary samples over TCP and UDP move the gyros
//! the GA frames report; bad samples are counted by reason; a silent feed
//! is reported as a sensor fault (KERNEL USW bit 1, IMX IMU status) and
//! cleared by the next sample; lockstep gives the same bytes for the same
//! feed and seed; `--count` takes a feed per device or one shared feed.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::Write as _;
use std::net::{SocketAddr, TcpStream, UdpSocket};
use std::time::{Duration, Instant};

use imu_emu::feed::OWN_DEVICE;
use imu_emu::isb::did;
use imu_emu::isb::sets::{imu_status, Imu};
use support::{
    command, feed_sample as sample, free_port, isb_get, isb_packet_of, Conn, Control, Emu, TIMEOUT,
};

const GA: u8 = 0x8F;
/// USW bit 1: communication failure of internal sensors (ICD Table 5.26).
const USW_SENSOR_COMM: u16 = 1 << 1;

fn i32_at(p: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(p[at..at + 4].try_into().unwrap())
}

/// GA (Table 5.7): gyro X, Y, Z in 1e-5 °/s at 0, 4, 8; USW at 26.
fn gyro(p: &[u8]) -> [f64; 3] {
    [0, 4, 8].map(|i| f64::from(i32_at(p, i)) * 1e-5)
}

fn usw(p: &[u8]) -> u16 {
    u16::from_le_bytes([p[26], p[27]])
}

/// The `feed on …` address among the stdout lines after the first.
fn feed_addrs(emu: &Emu, lines: usize) -> Vec<String> {
    emu.more_lines(lines)
        .into_iter()
        .filter_map(|l| l.strip_prefix("feed on ").map(str::to_owned))
        .collect()
}

fn start_ga(c: &mut Conn) {
    c.send(&command(GA));
    c.frame_with_id(GA);
}

/// GA frames until one satisfies `ok` (panics after [`TIMEOUT`]).
fn ga_until(c: &mut Conn, what: &str, ok: impl Fn(&[u8]) -> bool) -> Vec<u8> {
    let end = Instant::now() + TIMEOUT;
    let mut last = Vec::new();
    while let Some(f) = c.frame_before(end) {
        if f.id() == GA {
            if ok(f.payload()) {
                return f.payload().to_vec();
            }
            last = f.payload().to_vec();
        }
    }
    panic!("no GA frame with {what}; last gyro {:?}", gyro(&last));
}

fn near(a: f64, b: f64) -> bool {
    (a - b).abs() < 0.5
}

/// The value of `key=` in a status line.
fn word<'a>(status: &'a str, key: &str) -> &'a str {
    status
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {status}"))
}

fn start(extra: &[&str]) -> (Emu, Conn, Control, String) {
    let ctl = format!("127.0.0.1:{}", free_port());
    let mut args = vec!["--tcp", "127.0.0.1:0", "--control", &ctl, "--seed", "7"];
    args.extend_from_slice(extra);
    let emu = Emu::start(&args);
    let feed = feed_addrs(&emu, 2).pop().expect("a feed line");
    let c = emu.connect();
    let control = Control::connect(&ctl);
    (emu, c, control, feed)
}

#[test]
fn a_tcp_feed_moves_the_gyros_and_bad_samples_are_counted_by_reason() {
    let (_emu, mut c, mut ctl, feed) = start(&["--motion-feed", "127.0.0.1:0"]);
    let addr: SocketAddr = feed.strip_prefix("tcp ").unwrap().parse().unwrap();
    start_ga(&mut c);
    let status = ctl.cmd("status");
    assert_eq!(word(&status, "feed-samples"), "0");
    assert_eq!(word(&status, "feed-age-ms"), "never");
    let mut f = TcpStream::connect(addr).unwrap();
    f.write_all(b"time,wx,wy,wz,fx,fy,fz\n0.0, 100, 0, 0, 0, 0, 1\n")
        .unwrap();
    ga_until(&mut c, "X = 100 °/s", |p| near(gyro(p)[0], 100.0));
    // A binary sample, then garbage, a bad checksum, a sample going back.
    f.write_all(&sample(OWN_DEVICE, 0.01, [0.0, -50.0, 0.0]))
        .unwrap();
    let p = ga_until(&mut c, "Y = -50 °/s", |p| near(gyro(p)[1], -50.0));
    assert!(near(gyro(&p)[0], 0.0), "{:?}", gyro(&p));
    let mut bad = sample(OWN_DEVICE, 0.02, [1.0, 0.0, 0.0]);
    bad[20] ^= 0xFF;
    f.write_all(b"garbage\n").unwrap();
    f.write_all(&bad).unwrap();
    // After a bad frame the decoder skips to a line end or a sync.
    f.write_all(b"\n0.005,0,0,0,0,0,1\n0.03,9000,0,0,0,0,1\n")
        .unwrap();
    f.write_all(&sample(7, 0.04, [0.0, 0.0, 0.0])).unwrap();
    f.write_all(b"0.05, 0, 0, 20, 0, 0, 1, 30\n").unwrap();
    ga_until(&mut c, "Z = 20 °/s", |p| near(gyro(p)[2], 20.0));
    let s = ctl.cmd("status");
    assert_eq!(word(&s, "feed-clock"), "realtime");
    assert_eq!(word(&s, "feed-samples"), "3");
    assert_eq!(word(&s, "feed-rejected"), "5");
    for (why, n) in [
        ("malformed", "1"),
        ("checksum", "1"),
        ("non-increasing", "1"),
        ("out-of-range", "1"),
        ("wrong-device", "1"),
    ] {
        assert_eq!(word(&s, &format!("feed-rejected-{why}")), n, "{s}");
    }
    assert_eq!(word(&s, "feed-lost"), "0");
}

#[test]
fn a_silent_feed_is_a_usw_sensor_fault_until_samples_return() {
    let (_emu, mut c, mut ctl, feed) =
        start(&["--motion-feed", "udp:127.0.0.1:0", "--feed-timeout", "0.05"]);
    let addr: SocketAddr = feed.strip_prefix("udp ").unwrap().parse().unwrap();
    start_ga(&mut c);
    // Before the first sample: no fault.
    let p = ga_until(&mut c, "a frame", |_| true);
    assert_eq!(usw(&p) & USW_SENSOR_COMM, 0);
    let u = UdpSocket::bind("127.0.0.1:0").unwrap();
    u.send_to(b"0, 30, 0, 0, 0, 0, 1", addr).unwrap();
    ga_until(&mut c, "X = 30 °/s", |p| near(gyro(p)[0], 30.0));
    // Silence: the fault, and the last sample still holds.
    let p = ga_until(&mut c, "USW bit 1", |p| usw(p) & USW_SENSOR_COMM != 0);
    assert!(near(gyro(&p)[0], 30.0), "{:?}", gyro(&p));
    let s = ctl.cmd("status");
    assert_eq!(word(&s, "feed-lost"), "1");
    assert!(word(&s, "feed-age-ms").parse::<u64>().unwrap() >= 50, "{s}");
    u.send_to(&sample(0, 1.0, [0.0, 0.0, -30.0]), addr).unwrap();
    // The first clear frame may average the held and the new sample
    // (decimation averages the output interval): the next carries it.
    ga_until(&mut c, "USW bit 1 clear", |p| usw(p) & USW_SENSOR_COMM == 0);
    let p = ga_until(&mut c, "Z = -30 °/s", |p| near(gyro(p)[2], -30.0));
    assert_eq!(usw(&p) & USW_SENSOR_COMM, 0);
}

#[test]
fn a_silent_feed_is_an_imx_imu_status_fault() {
    let (_emu, mut c, _ctl, feed) = start(&[
        "--protocol",
        "isb",
        "--motion-feed",
        "127.0.0.1:0",
        "--feed-timeout",
        "0.05",
    ]);
    let addr: SocketAddr = feed.strip_prefix("tcp ").unwrap().parse().unwrap();
    c.send(&isb_get(did::IMU, 1));
    let imu = |c: &mut Conn| Imu::decode(&isb_packet_of(c, did::IMU).payload.try_into().unwrap());
    let mut f = TcpStream::connect(addr).unwrap();
    f.write_all(b"0, 57.29578, 0, 0, 0, 0, 1\n").unwrap();
    let end = Instant::now() + TIMEOUT;
    // 1 rad/s about the housing's X (its right: the IMX body's Y, its
    // frame being forward-right-down), status all OK while samples are
    // fresh …
    loop {
        assert!(Instant::now() < end, "no IMU packet with 1 rad/s");
        let m = imu(&mut c);
        if (m.pqr[1] - 1.0).abs() < 0.01 {
            assert_eq!(m.status & imu_status::ALL_OK, imu_status::ALL_OK);
            break;
        }
    }
    // … and not OK once the feed is silent, the rate held.
    loop {
        assert!(Instant::now() < end, "no IMU packet with the fault");
        let m = imu(&mut c);
        if m.status & imu_status::ALL_OK == 0 {
            assert!((m.pqr[1] - 1.0).abs() < 0.01, "{m:?}");
            break;
        }
    }
    f.write_all(b"1, 0, 0, 0, 0, 0, 1\n").unwrap();
    loop {
        assert!(Instant::now() < end, "the fault did not clear");
        let m = imu(&mut c);
        // (A packet's window may straddle the change.)
        if m.status & imu_status::ALL_OK == imu_status::ALL_OK && m.pqr[1].abs() < 0.01 {
            break;
        }
    }
}

/// Waits until `status` says `key=value`.
fn wait_status(ctl: &mut Control, key: &str, value: &str) -> String {
    let end = Instant::now() + TIMEOUT;
    loop {
        let s = ctl.cmd("status");
        if word(&s, key) == value {
            return s;
        }
        assert!(Instant::now() < end, "no {key}={value}: {s}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Every byte the UART sends until it is quiet (lockstep: device time
/// stays at the last sample's).
fn until_quiet(c: &mut Conn) -> Vec<u8> {
    let mut bytes = Vec::new();
    while let Some(f) = c.frame_before(Instant::now() + Duration::from_millis(300)) {
        bytes.extend(f.bytes);
    }
    bytes
}

/// A unit in lockstep at `--speed max` and its TCP feed's address.
fn start_lockstep() -> (Emu, Conn, Control, SocketAddr) {
    let (emu, c, ctl, feed) = start(&[
        "--motion-feed",
        "127.0.0.1:0",
        "--lockstep",
        "--speed",
        "max",
    ]);
    let addr = feed.strip_prefix("tcp ").unwrap().parse().unwrap();
    (emu, c, ctl, addr)
}

/// The number after `key=` in a reply.
fn num(reply: &str, key: &str) -> f64 {
    word(reply, key)
        .parse()
        .unwrap_or_else(|_| panic!("{key} not a number in {reply}"))
}

/// GA acc (Table 5.7): X, Y, Z in 1e-6 g at 12, 16, 20.
fn acc(p: &[u8]) -> [f64; 3] {
    [12, 16, 20].map(|i| f64::from(i32_at(p, i)) * 1e-6)
}

#[test]
fn a_lockstep_full_state_feed_moves_the_vehicle_truth_and_the_ga_frames() {
    let (_emu, mut c, mut ctl, addr) = start_lockstep();
    // The command is read as device time moves (its bytes are paced on
    // it): GA starts within the first samples.
    c.send(&command(GA));
    // 10 m/s north at 45° N, 300 m, pitched up 30° and yawing at 10 °/s
    // (level flight: the nose turns, the path does not), a row every
    // 10 ms for 0.5 s. The WGS84 meridian radius (NIMA TR8350.2 eq. 4-18)
    // turns the speed into degrees of latitude a second.
    let (a, e2) = (6_378_137.0, 6.694_379_990_14e-3);
    let s2 = 45f64.to_radians().sin().powi(2);
    let m = a * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5);
    let dlat = (10.0 / (m + 300.0)).to_degrees();
    let mut text = String::from("time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n");
    for k in 0..=50 {
        let t = f64::from(k) * 0.01;
        text.push_str(&format!(
            "{t:.2},{:.12},7,300,10,0,0,0,30,{:.3}\n",
            45.0 + dlat * t,
            10.0 * t
        ));
    }
    // Rejected and counted, device time does not move: a row short of
    // columns, a latitude beyond 89.9°.
    text.push_str("0.6,45,7,300\n0.61,95,7,300,10,0,0,0,30,6\n");
    let mut f = TcpStream::connect(addr).unwrap();
    f.write_all(text.as_bytes()).unwrap();
    let s = wait_status(&mut ctl, "feed-samples", "51");
    let s = if word(&s, "feed-rejected") == "2" {
        s
    } else {
        wait_status(&mut ctl, "feed-rejected", "2")
    };
    assert_eq!(word(&s, "feed-rejected-malformed"), "1", "{s}");
    assert_eq!(word(&s, "feed-rejected-out-of-range"), "1", "{s}");
    let bytes = until_quiet(&mut c);
    let t = ctl.cmd("truth");
    assert_eq!(word(&t, "source"), "feed", "{t}");
    assert!((num(&t, "time") - 0.5).abs() < 1e-3, "{t}");
    assert!((num(&t, "lat") - (45.0 + dlat * 0.5)).abs() < 1e-8, "{t}");
    assert!((num(&t, "lon") - 7.0).abs() < 1e-9, "{t}");
    assert!((num(&t, "height") - 300.0).abs() < 1e-3, "{t}");
    assert!((num(&t, "vn") - 10.0).abs() < 1e-3, "{t}");
    assert!(
        num(&t, "ve").abs() < 1e-3 && num(&t, "vd").abs() < 1e-3,
        "{t}"
    );
    assert!((num(&t, "pitch") - 30.0).abs() < 1e-3, "{t}");
    assert!((num(&t, "yaw") - 5.0).abs() < 1e-3, "{t}");
    assert!(ctl.cmd("status").contains(" truth-source=feed "));
    // Body FRD: ω = (−ψ' sin θ, 0, ψ' cos θ) = (−5, 0, 8.66) °/s; f = g
    // (sin θ, 0, −cos θ). Housing (X right, Y forward, Z up): gyro (0, −5,
    // −8.66) °/s, acc (0, 0.5, 0.866) × γ/g₀, γ = 9.8053 m/s² the normal
    // gravity there, g₀ = 9.8106 (ICD 5.2.1). Earth and transport rates
    // (< 0.003 °/s) are within the tolerance. Frames from 0.1 s on (the
    // filters settled), by their 2 kHz counters, averaged.
    let mut c = Conn::new(Box::new(std::io::Cursor::new(bytes)));
    assert_eq!(c.frame().id(), GA, "the ack");
    let (mut w, mut f, mut n) = ([0.0; 3], [0.0; 3], 0.0);
    while let Some(fr) = c.frame_before(Instant::now()) {
        let p = fr.payload();
        if fr.id() != GA || p.len() < 28 || u16::from_le_bytes([p[24], p[25]]) < 200 {
            continue;
        }
        for i in 0..3 {
            w[i] += gyro(p)[i];
            f[i] += acc(p)[i];
        }
        n += 1.0;
    }
    // 100 Hz: 40 frames (the first may be late by the command's line time).
    assert!(n >= 39.0, "{n} GA frames from 0.1 s to 0.5 s");
    let (w, f) = (w.map(|x| x / n), f.map(|x| x / n));
    let k = 9.8053 / 9.8106;
    for (got, want) in w.iter().zip([0.0, -5.0, -10.0 * 30f64.to_radians().cos()]) {
        assert!((got - want).abs() < 0.1, "gyro {w:?}");
    }
    for (got, want) in f.iter().zip([0.0, 0.5 * k, 30f64.to_radians().cos() * k]) {
        assert!((got - want).abs() < 0.003, "acc {f:?}");
    }
}

#[test]
fn real_time_full_state_rows_hold_the_newest_state_until_rates_take_over() {
    let (_emu, _c, mut ctl, feed) = start(&["--motion-feed", "127.0.0.1:0"]);
    let mut f = TcpStream::connect(feed.strip_prefix("tcp ").unwrap()).unwrap();
    f.write_all(
        b"time,lat,lon,height,vn,ve,vd,roll,pitch,yaw,wx,wy,wz,fx,fy,fz\n\
          0,45,7,300,10,0,0,0,0,0,0,0,20,0,0,-9.8\n\
          1,45.0001,7,300,10,0,0,0,0,90,0,0,20,0,0,-9.8\n",
    )
    .unwrap();
    let end = Instant::now() + TIMEOUT;
    let t = loop {
        let t = ctl.cmd("truth");
        if word(&t, "source") == "feed" && word(&t, "yaw") != "0.000000" {
            break t;
        }
        assert!(Instant::now() < end, "the second row did not apply: {t}");
        std::thread::sleep(Duration::from_millis(5));
    };
    // The newest row holds, with its own rates and forces.
    assert!((num(&t, "lat") - 45.0001).abs() < 1e-9, "{t}");
    assert!((num(&t, "vn") - 10.0).abs() < 1e-6, "{t}");
    assert!((num(&t, "yaw") - 90.0).abs() < 1e-6, "{t}");
    assert!((num(&t, "wz") - 20.0).abs() < 1e-6, "{t}");
    assert!((num(&t, "fz") + 9.8).abs() < 1e-6, "{t}");
    std::thread::sleep(Duration::from_millis(50));
    assert!((num(&ctl.cmd("truth"), "lat") - 45.0001).abs() < 1e-9);
    // A rate header, a rate row: rates and forces again.
    f.write_all(b"time,wx,wy,wz,fx,fy,fz\n2,0,0,5,0,0,1\n")
        .unwrap();
    wait_status(&mut ctl, "feed-samples", "3");
    let end = Instant::now() + TIMEOUT;
    while word(&ctl.cmd("truth"), "source") != "sample" {
        assert!(Instant::now() < end, "the rate row did not take over");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(word(&ctl.cmd("status"), "feed-rejected"), "0");
}

/// One lockstep run: GA started, then 400 samples 1 ms apart (a ramp of
/// X), all sent at once; every byte the UART sends until it is quiet.
fn lockstep_run() -> Vec<u8> {
    let (_emu, mut c, mut ctl, addr) = start_lockstep();
    c.send(&command(GA));
    // Device time stands still until the first sample: wait until the
    // command was taken (the monitor counts it) so it applies at time 0.
    let end = Instant::now() + TIMEOUT;
    // (`mode=off` until the runner noticed the client.)
    while !ctl.cmd("status").contains(" commands=1 ") {
        assert!(Instant::now() < end, "the GA command was not taken");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(word(&ctl.cmd("status"), "feed-clock"), "lockstep");
    let mut feed = TcpStream::connect(addr).unwrap();
    let mut all = Vec::new();
    for k in 0..=400 {
        all.extend(sample(
            OWN_DEVICE,
            k as f64 * 1e-3,
            [k as f32 * 0.1, 0.0, 0.0],
        ));
    }
    feed.write_all(&all).unwrap();
    let end = Instant::now() + TIMEOUT;
    while word(&ctl.cmd("status"), "feed-samples") != "401" {
        assert!(Instant::now() < end, "not every sample was taken");
        std::thread::sleep(Duration::from_millis(5));
    }
    // Device time is at 0.4 s and stays there: the line's last bytes are
    // out once nothing more comes.
    until_quiet(&mut c)
}

#[test]
fn lockstep_moves_device_time_with_the_samples_and_repeats_byte_for_byte() {
    let a = lockstep_run();
    let b = lockstep_run();
    assert_eq!(a, b, "two runs of one feed and seed differ");
    // The ack, then GA frames up to device time 0.4 s (the 2 kHz counter)
    // whose X follows the ramp (0.1 °/s a ms).
    let mut c = Conn::new(Box::new(std::io::Cursor::new(a)));
    let ack = c.frame();
    assert_eq!(ack.id(), GA);
    let mut last = None;
    while let Some(f) = c.frame_before(Instant::now()) {
        let p = f.payload();
        let counter = u16::from_le_bytes([p[24], p[25]]);
        let t_ms = f64::from(counter) / 2.0;
        assert!(
            (gyro(p)[0] - t_ms * 0.1).abs() < 1.0,
            "X {} at {t_ms} ms",
            gyro(p)[0]
        );
        last = Some(counter);
    }
    let last = last.expect("GA frames");
    assert!((790..=800).contains(&last), "last counter {last}");
}

#[test]
fn count_gives_each_device_its_own_feed_or_one_shared_feed() {
    for shared in [false, true] {
        let ctl = format!("127.0.0.1:{}", free_port());
        let mut args = vec![
            "--count",
            "2",
            "--tcp",
            "127.0.0.1:0",
            "--control",
            &ctl,
            "--motion-feed",
            "127.0.0.1:0",
        ];
        if shared {
            args.push("--feed-shared");
        }
        let emu = Emu::start(&args);
        let lines = emu.more_lines(if shared { 3 } else { 4 });
        let uart: SocketAddr = lines[0]
            .strip_prefix("listening on tcp ")
            .unwrap()
            .parse()
            .unwrap();
        let feeds = feed_addrs(&emu, lines.len());
        assert_eq!(feeds.len(), if shared { 1 } else { 2 }, "{lines:?}");
        let mut d0 = emu.connect();
        let mut d1 = Conn::tcp(uart);
        start_ga(&mut d0);
        start_ga(&mut d1);
        let tcp = |k: usize| TcpStream::connect(feeds[k].strip_prefix("tcp ").unwrap()).unwrap();
        if shared {
            let mut f = tcp(0);
            f.write_all(&sample(1, 0.0, [40.0, 0.0, 0.0])).unwrap();
            f.write_all(&sample(0, 0.0, [-40.0, 0.0, 0.0])).unwrap();
            // Names no device: not routed.
            f.write_all(b"0,1,1,1,0,0,1\n").unwrap();
            f.write_all(&sample(5, 0.0, [0.0; 3])).unwrap();
        } else {
            tcp(1)
                .write_all(&sample(OWN_DEVICE, 0.0, [40.0, 0.0, 0.0]))
                .unwrap();
            tcp(0).write_all(b"0, -40, 0, 0, 0, 0, 1\n").unwrap();
        }
        ga_until(&mut d1, "dev 1 X = 40", |p| near(gyro(p)[0], 40.0));
        ga_until(&mut d0, "dev 0 X = -40", |p| near(gyro(p)[0], -40.0));
        let mut c = Control::connect(&ctl);
        let s1 = c.cmd("dev 1 status");
        assert_eq!(word(&s1, "feed-samples"), "1", "{s1}");
        if shared {
            let d = c.cmd("devices");
            assert_eq!(word(&d, "feed-unrouted"), "2", "{d}");
        }
    }
}

#[test]
fn feed_options_are_checked() {
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&["--motion-feed", "10.1.2.3:9000"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--motion-feed"));
    assert_eq!(run(&["--lockstep"]).status.code(), Some(2));
    assert_eq!(
        run(&["--motion-feed", "127.0.0.1:0", "--feed-shared"])
            .status
            .code(),
        Some(2)
    );
    assert_eq!(
        run(&["--motion-feed", "127.0.0.1:0", "--feed-timeout", "0"])
            .status
            .code(),
        Some(2)
    );
}
