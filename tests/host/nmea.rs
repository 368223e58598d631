//! The emulated IMX-5's NMEA read by real NMEA consumers: Debian's `gpsd`
//! on the emulator's pty (`gpspipe -w`), through the binary
//! (`docs/isb.md` "NMEA"; README "ISB").

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::process::{Child, Command, Stdio};
use std::time::Duration;

use imu_emu::isb::did;
use imu_emu::isb::ins::SAT_PRNS;
use imu_emu::isb::nmea::checksum;
use imu_emu::isb::sets::flash;
use support::{free_port, isb_packet, isb_set, Conn, Emu};

fn sentence(body: &str) -> Vec<u8> {
    format!("${body}*{:02X}\r\n", checksum(body.as_bytes())).into_bytes()
}

/// Whether `prog` runs; in CI (`CI=true`) its absence fails the test
/// loudly, elsewhere it is reported and the test returns.
fn have(prog: &str) -> bool {
    let ok = Command::new(prog)
        .arg("-V")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok();
    if !ok {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "{prog} is not installed (apt-get install gpsd gpsd-clients): CI must run this test"
        );
        eprintln!("NOT RUN: {prog} is not installed (apt-get install gpsd gpsd-clients)");
    }
    ok
}

/// Kills the gpsd it holds (by its pid) when dropped.
struct Gpsd(Child);

impl Drop for Gpsd {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// gpsd on the emulator's pty reports a 3-D fix at the truth position
/// (45° N, 0° E, the built-in site) within the GNSS error model (σ 1 m
/// per horizontal axis: 5 m), the UTC time of `--gps-time` from RMC/ZDA,
/// and the 12 satellites of GSV with their PRNs. The line is first set to
/// 115 200 bit/s (gpsd's speeds stop at 460 800) and the sentences made
/// persistent with `$ASCE` option 0x200, then the unit is reset: gpsd only
/// reads (`-b`), on a private control socket and port so tests run in
/// parallel.
#[test]
fn gpsd_reads_a_3d_fix_the_time_and_the_satellites() {
    if !have("gpsd") || !have("gpspipe") {
        return;
    }
    let emu = Emu::start(&[
        "--protocol",
        "isb",
        "--pty",
        "--power-on",
        "now",
        "--speed",
        "10",
        "--gps-time",
        "2026-01-04",
    ]);
    {
        let mut c = Conn::serial(&emu.pty_path());
        c.send(&isb_set(
            did::FLASH_CONFIG,
            flash::SER0_BAUD_RATE as u16,
            &115_200u32.to_le_bytes(),
        ));
        assert_eq!(isb_packet(&mut c).flags, 1, "ACK");
        c.send(&sentence(
            "ASCE,512,GNGGA,5,GNGLL,5,GNGSA,5,GNRMC,5,GNZDA,5,GPGSV,5,GNVTG,5",
        ));
        c.send(b"$SRST*06\r\n");
        std::thread::sleep(Duration::from_millis(200));
    }
    let dir = tempfile::tempdir().unwrap();
    let port = free_port();
    let _gpsd = Gpsd(
        Command::new("gpsd")
            .args(["-N", "-n", "-b", "-s", "115200", "-F"])
            .arg(dir.path().join("gpsd.sock"))
            .args(["-S", &port.to_string()])
            .arg(emu.pty_path())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn gpsd"),
    );
    // gpsd listens within a moment; gpspipe retries until it does.
    let mut reports = Vec::new();
    for _ in 0..50 {
        let out = Command::new("timeout")
            .args(["60", "gpspipe", "-w", "-n", "120"])
            .arg(format!("127.0.0.1:{port}"))
            .output()
            .expect("run gpspipe");
        reports = String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
            .collect::<Vec<_>>();
        if !reports.is_empty() {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let class = |c: &str| {
        reports
            .iter()
            .filter(|r| r["class"] == c)
            .cloned()
            .collect::<Vec<_>>()
    };
    let fixes: Vec<_> = class("TPV")
        .into_iter()
        .filter(|t| t["mode"] == 3)
        .collect();
    assert!(!fixes.is_empty(), "no 3-D fix in {reports:#?}");
    for t in &fixes {
        let (lat, lon) = (t["lat"].as_f64().unwrap(), t["lon"].as_f64().unwrap());
        // The built-in site (docs/motion.md), metres per degree there.
        let (lat0, lon0) = (
            f64::from(imu_emu::sensor::motion::DEFAULT_LATITUDE_DEG),
            imu_emu::vehicle::DEFAULT_LONGITUDE_DEG,
        );
        let north = (lat - lat0) * 111_200.0;
        let east = (lon - lon0) * 111_320.0 * lat0.to_radians().cos();
        assert!(north.hypot(east) < 5.0, "{t}");
        assert!(t["time"].as_str().unwrap().ends_with(".000Z"), "{t}");
    }
    // The UTC of `--gps-time` 2026-01-04 00:00:00 + the 30 s cold start,
    // once gpsd has its date from RMC/ZDA (its first fix may carry a
    // time of day only).
    let last = fixes.last().unwrap();
    assert!(
        last["time"]
            .as_str()
            .unwrap()
            .starts_with("2026-01-04T00:0"),
        "{last}"
    );
    let sky = class("SKY");
    let sats = sky
        .iter()
        .rev()
        .find_map(|s| s["satellites"].as_array().filter(|a| !a.is_empty()))
        .unwrap_or_else(|| panic!("no satellites in {sky:#?}"));
    let mut prns: Vec<u64> = sats.iter().map(|s| s["PRN"].as_u64().unwrap()).collect();
    prns.sort_unstable();
    let want: Vec<u64> = SAT_PRNS.iter().map(|&p| u64::from(p)).collect();
    assert_eq!(prns, want);
    assert!(sats.iter().all(|s| s["used"] == true), "{sats:?}");
}

/// `$PERS` of DEV_INFO and SYS_CMD streams, `$SRST`, then `$STPB`: the
/// persistent streams resume after the reset and the first `$STPB` stops
/// them (a reported defect: the first one was ignored).
#[test]
fn the_first_stpb_after_pers_and_a_reset_stops_the_streams() {
    let emu = Emu::tcp(&["--protocol", "isb"]);
    let mut c = emu.connect();
    c.send(&support::isb_get(did::DEV_INFO, 1000));
    c.send(&support::isb_get(did::SYS_CMD, 1000));
    std::thread::sleep(Duration::from_millis(300));
    c.send(b"$PERS*14\r\n");
    std::thread::sleep(Duration::from_millis(300));
    c.send(b"$SRST*06\r\n");
    std::thread::sleep(Duration::from_millis(1000));
    assert!(c.drain_for(Duration::from_millis(2500)) > 0, "resumed");
    c.send(b"$STPB*15\r\n");
    std::thread::sleep(Duration::from_millis(100));
    c.drain_for(Duration::from_millis(200));
    assert_eq!(c.drain_for(Duration::from_millis(2500)), 0, "stopped");
}

/// The reported `$STPB` defect ("after `$PERS` of DEV_INFO and SYS_CMD
/// streams and a reset, the first `$STPB` is ignored") through the real
/// path: the binary on a pty at 10× speed, the streams asked for as the
/// vendor tool asks (GET_DATA with a period: DEV_INFO every 100 ms,
/// SYS_CMD every 1 ms), saved with `$PERS`, then each way of resetting —
/// `$SRST`, SYS_CMD 99 three times 20 ms apart (the SDK's software
/// reset), a power cycle on the control socket, and `$SRST` with the
/// port closed and reopened (the `$STPB` is then the first write of the
/// new open), and `$SRST` with a stray `0xEF` byte right before the
/// `$STPB` (which the input classifier once took for a packet's start,
/// swallowing the `$`) — and one `$STPB` sent the moment the resumed
/// streams show: the line goes quiet (25 s of device time) and stays so.
#[test]
fn the_first_stpb_after_a_reset_silences_the_pty() {
    use support::{isb_get, Control};
    for reset in [
        "$SRST",
        "SYS_CMD 99",
        "power-cycle",
        "$SRST, reopen",
        "$SRST, stray 0xEF",
    ] {
        let addr = format!("127.0.0.1:{}", free_port());
        let emu = Emu::start(&[
            "--protocol",
            "isb",
            "--pty",
            "--power-on",
            "now",
            "--speed",
            "10",
            "--control",
            &addr,
        ]);
        let mut ctl = Control::connect(&addr);
        let mut c = Conn::serial(&emu.pty_path());
        c.send(&isb_get(did::DEV_INFO, 100));
        c.send(&isb_get(did::SYS_CMD, 1));
        std::thread::sleep(Duration::from_millis(200));
        c.send(b"$PERS*14\r\n");
        std::thread::sleep(Duration::from_millis(200));
        match reset {
            "SYS_CMD 99" => {
                let mut cmd = 99u32.to_le_bytes().to_vec();
                cmd.extend((!99u32).to_le_bytes());
                for _ in 0..3 {
                    c.send(&isb_set(did::SYS_CMD, 0, &cmd));
                    std::thread::sleep(Duration::from_millis(20));
                }
            }
            "power-cycle" => assert!(ctl.cmd("power-cycle").starts_with("ok")),
            _ => c.send(b"$SRST*06\r\n"),
        }
        if reset.ends_with("reopen") {
            drop(c);
            std::thread::sleep(Duration::from_millis(300));
            c = Conn::serial(&emu.pty_path());
        } else {
            std::thread::sleep(Duration::from_millis(300));
            c.drain_for(Duration::from_millis(100));
        }
        // The resumed streams' next byte, then at once one `$STPB`.
        assert_eq!(c.read_bytes(1).len(), 1, "{reset}: resumed");
        if reset.ends_with("0xEF") {
            c.send(b"\xEF$STPB*15\r\n");
        } else {
            c.send(b"$STPB*15\r\n");
        }
        std::thread::sleep(Duration::from_millis(100));
        c.drain_for(Duration::from_millis(200));
        assert_eq!(
            c.drain_for(Duration::from_millis(2500)),
            0,
            "{reset}: quiet after the first $STPB"
        );
    }
}

/// `strobe` on the control socket is a rising EXTRIG edge: the IMX-5
/// answers with STROBE_IN_TIME and, with ID 13 on, `$PSTRB` carrying the
/// same GPS week, time of week and count.
#[test]
fn a_strobe_on_the_control_socket_gives_strobe_in_time_and_pstrb() {
    use imu_emu::isb::nav_sets::GpsPos;
    use imu_emu::isb::sets::StrobeInTime;
    use support::{isb_get, isb_packet_of, Control};
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = Emu::tcp(&[
        "--protocol",
        "isb",
        "--control",
        &addr,
        "--speed",
        "20",
        "--gps-time",
        "2026-03-13T15:27:26Z",
    ]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    c.send(&isb_get(did::GPS1_POS, 1));
    while GpsPos::decode(
        &isb_packet_of(&mut c, did::GPS1_POS)
            .payload
            .try_into()
            .unwrap(),
    )
    .status
        == 0
    {}
    c.send(b"$STPC*14\r\n");
    c.send(&isb_get(did::STROBE_IN_TIME, 1));
    c.send(&sentence("ASCE,0,13,1"));
    std::thread::sleep(Duration::from_millis(300));
    c.drain_for(Duration::from_millis(300));
    assert!(ctl.cmd("strobe").starts_with("ok"));
    let p = isb_packet_of(&mut c, did::STROBE_IN_TIME);
    let s = StrobeInTime::decode(&p.payload.try_into().unwrap());
    let mut line = Vec::new();
    while !line.ends_with(b"\n") {
        line.extend(c.read_bytes(1));
    }
    let line = String::from_utf8(line).unwrap();
    assert_eq!(
        line,
        String::from_utf8(sentence(&format!(
            "PSTRB,{},{},{},{}",
            s.week, s.time_of_week_ms, s.pin, s.count
        )))
        .unwrap()
    );
    // 2026-03-13 is in GPS week 2409; the edge after the 30 s cold start.
    assert_eq!((s.week, s.count), (2409, 1));
}

/// `client --protocol isb record --nmea GNGGA,GNRMC --period 5`: one
/// `$ASCE`, then an NMEA log of whole sentences with valid checksums, GGA
/// and RMC of each whole GPS second in turn; `$STPC` at the end.
#[test]
fn client_records_an_nmea_log() {
    let emu = Emu::tcp(&["--protocol", "isb", "--speed", "5"]);
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.nmea");
    let out = Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["client", "--protocol", "isb", "--tcp"])
        .arg(emu.addr().to_string())
        .args([
            "record",
            "--nmea",
            "GNGGA,GNRMC",
            "--period",
            "5",
            "--frames",
            "6",
            "-o",
        ])
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = text.split_inclusive("\r\n").collect();
    assert_eq!(lines.len(), 6, "{text}");
    let mut seconds = Vec::new();
    for (k, l) in lines.iter().enumerate() {
        let star = l.rfind('*').unwrap();
        let sum = checksum(&l.as_bytes()[1..star]);
        assert_eq!(&l[star + 1..], format!("{sum:02X}\r\n"), "{l}");
        let f: Vec<&str> = l[..star].split(',').collect();
        assert_eq!(f[0], ["$GNGGA", "$GNRMC"][k % 2], "{text}");
        seconds.push(f[1][..6].to_owned());
    }
    // GGA and RMC of one second carry the same time; seconds follow on.
    for p in seconds.chunks(2) {
        assert_eq!(p[0], p[1]);
    }
    assert!(String::from_utf8_lossy(&out.stderr).contains("6 NMEA sentences recorded"));
}
