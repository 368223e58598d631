//! `imu-emu --protocol isb` end to end: the emulated IMX-5 over TCP and a
//! pty, driven as the Inertial Sense command-line tool drives a real one
//! (`docs/protocol-facts.md` "ISB"; docs/isb.md).

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::time::{Duration, Instant};

use imu_emu::isb::did;

use imu_emu::isb::nav_sets::{ins_status, GpsPos, GpsSat, GpsVel, Ins1, Ins2};
use imu_emu::isb::sets::{flash, hdw_status, DevInfo, Imu, Pimu, SysParams};
use support::{free_port, hex, isb_get, isb_packet, isb_packet_of, isb_set, Conn, Control, Emu};

fn isb(args: &[&str]) -> Emu {
    let mut all = vec!["--protocol", "isb"];
    all.extend_from_slice(args);
    Emu::tcp(&all)
}

/// The vendor tool's connection sequence with its timing: `$INFO` and its
/// stray footer, GET DEV_INFO answered well inside the tool's 10 ms, the
/// SYS_PARAMS / FLASH_CONFIG checksum handshake, unanswered GETs of 121
/// and 123, `$STPC`, then DEV_INFO every 2 s and IMU on device time.
#[test]
fn the_vendor_tools_connection_sequence_with_its_deadlines() {
    let emu = isb(&[]);
    let mut c = emu.connect();
    c.send(b"$INFO*0E\r\n*56\r\n");
    let mut line = Vec::new();
    loop {
        let b = c.read_bytes(1)[0];
        line.push(b);
        if b == b'\n' {
            break;
        }
    }
    assert!(
        line.starts_with(b"$INFO,"),
        "{}",
        String::from_utf8_lossy(&line)
    );
    let mut trips = Vec::new();
    for _ in 0..20 {
        let t0 = Instant::now();
        c.send(&hex("ef 49 03 00 08 00 01 00 00 00 00 00 00 00 44 43"));
        let p = isb_packet(&mut c);
        trips.push(t0.elapsed());
        assert_eq!((p.flags, p.did, p.payload.len()), (4, 1, 84));
        assert!(DevInfo::decode(&p.payload.try_into().unwrap()).accepted_by_sdk());
    }
    // The device answers at its next tick (about 1 ms on a quiet host);
    // what exceeds that is the host's scheduling (up to 22 ms seen on a
    // 2-core VM at a load of 10 while other suites ran). So the median is
    // held inside the tool's ~10 ms and the worst is reported.
    trips.sort();
    eprintln!(
        "DEV_INFO round trip: median {:?}, worst {:?} of 20",
        trips[10], trips[19]
    );
    assert!(trips[10] < Duration::from_millis(10), "{trips:?}");
    c.send(&isb_get(did::SYS_PARAMS, 0));
    let sp = SysParams::decode(&isb_packet(&mut c).payload.try_into().unwrap());
    c.send(&isb_get(did::FLASH_CONFIG, 0));
    let fc = isb_packet(&mut c).payload;
    assert_eq!(
        sp.flash_cfg_checksum,
        u32::from_le_bytes(fc[4..8].try_into().unwrap())
    );
    c.send(&isb_get(121, 0));
    c.send(&isb_get(123, 0));
    c.send(b"$STPC*14\r\n");
    c.send(&isb_get(did::DEV_INFO, 2000));
    c.send(&isb_get(did::IMU, 1));
    // The first packets answer the GETs; then IMU every 4 ms of device
    // time, DEV_INFO every 2 s, nothing for 121/123.
    let first = isb_packet(&mut c);
    assert_eq!(first.did, did::DEV_INFO);
    let mut imu_times = Vec::new();
    let mut dev_infos = 0;
    while imu_times.len() < 751 {
        let p = isb_packet(&mut c);
        match p.did {
            did::IMU => imu_times.push(Imu::decode(&p.payload.try_into().unwrap()).time),
            did::DEV_INFO => dev_infos += 1,
            d => panic!("unexpected DID {d}"),
        }
    }
    for w in imu_times.windows(2).skip(1) {
        let dt = w[1] - w[0];
        assert!((dt - 0.004).abs() < 1e-9, "{dt}");
    }
    assert!((1..=2).contains(&dev_infos), "{dev_infos}");
}

/// PIMU over TCP: dt is its period on device time in every packet, and a
/// reconnect while streaming keeps the stream (the device keeps its state;
/// what was sent meanwhile is gone, as on a real line).
#[test]
fn pimu_streams_and_survives_a_reconnect() {
    let emu = isb(&[]);
    let mut c = emu.connect();
    c.send(&isb_get(did::PIMU, 5));
    // The GET's own reply comes at once (its time is the request's); the
    // stream then runs on its period.
    let first = isb_packet_of(&mut c, did::PIMU);
    assert_eq!(first.payload.len(), 40);
    let mut last: Option<f64> = None;
    for _ in 0..50 {
        let p = Pimu::decode(&isb_packet_of(&mut c, did::PIMU).payload.try_into().unwrap());
        if let Some(t) = last {
            assert!((p.time - t - 0.02f64).abs() < 1e-9);
            assert_eq!(p.dt, 0.02);
        }
        last = Some(p.time);
    }
    drop(c);
    std::thread::sleep(Duration::from_millis(100));
    let mut c = emu.connect();
    let p = Pimu::decode(&isb_packet_of(&mut c, did::PIMU).payload.try_into().unwrap());
    let q = Pimu::decode(&isb_packet_of(&mut c, did::PIMU).payload.try_into().unwrap());
    assert!((q.time - p.time - 0.02).abs() < 1e-9);
    assert_eq!(q.dt, 0.02);
}

/// FLASH_CONFIG set and read back with the checksum in step, persisted in
/// `--flash FILE` and applied after a restart; `$PERS` streams resume after
/// `$SRST` and after a restart.
#[test]
fn flash_config_and_persistent_streams_survive_a_restart() {
    let dir = std::env::temp_dir().join(format!("imu-emu-isb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("imx.flash");
    let _ = std::fs::remove_file(&file);
    let path = file.to_str().unwrap();
    {
        let emu = isb(&["--flash", path]);
        let mut c = emu.connect();
        c.send(&isb_set(
            did::FLASH_CONFIG,
            flash::STARTUP_NAV_DT_MS as u16,
            &2u32.to_le_bytes(),
        ));
        let ack = isb_packet(&mut c);
        assert_eq!(ack.flags, 1);
        assert_eq!(ack.payload, [0x25, 12, 0, 0, 12, 4, 0, 16, 0]);
        c.send(&isb_get(did::FLASH_CONFIG, 0));
        let fc = isb_packet_of(&mut c, did::FLASH_CONFIG).payload;
        assert_eq!(u32::from_le_bytes(fc[16..20].try_into().unwrap()), 2);
        c.send(&isb_get(did::SYS_PARAMS, 0));
        let sp = SysParams::decode(
            &isb_packet_of(&mut c, did::SYS_PARAMS)
                .payload
                .try_into()
                .unwrap(),
        );
        assert_eq!(sp.flash_cfg_checksum, flash::checksum(&fc));
        assert_ne!(sp.hdw_status & hdw_status::SYSTEM_RESET_REQUIRED, 0);
        c.send(&isb_get(did::IMU, 1));
        c.send(b"$PERS*14\r\n");
        c.send(b"$SRST*06\r\n");
        // After the reset the IMU stream resumes at the new 2 ms period.
        let mut times = Vec::new();
        while times.len() < 20 {
            let p = isb_packet_of(&mut c, did::IMU);
            times.push(Imu::decode(&p.payload.try_into().unwrap()).time);
        }
        let t = &times[10..];
        for w in t.windows(2) {
            assert!((w[1] - w[0] - 0.002).abs() < 1e-9, "{t:?}");
        }
    }
    let emu = isb(&["--flash", path]);
    let mut c = emu.connect();
    let a = Imu::decode(&isb_packet_of(&mut c, did::IMU).payload.try_into().unwrap());
    let b = Imu::decode(&isb_packet_of(&mut c, did::IMU).payload.try_into().unwrap());
    assert!((b.time - a.time - 0.002).abs() < 1e-9);
    c.send(b"$STPC*14\r\n");
    std::thread::sleep(Duration::from_millis(50));
    c.drain_for(Duration::from_millis(50));
    let n = c.drain_for(Duration::from_millis(100));
    assert_eq!(n, 0, "$STPC stops the persistent stream");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Over a pty too: GET DEV_INFO is answered at the line's 921 600 bit/s.
#[test]
fn dev_info_over_a_pty() {
    let emu = Emu::start(&["--protocol", "isb", "--pty"]);
    let mut c = Conn::serial(&emu.pty_path());
    c.send(&isb_get(did::DEV_INFO, 0));
    let p = isb_packet(&mut c);
    assert_eq!((p.flags, p.did, p.payload.len()), (4, 1, 84));
    let log = emu.log_with("921600 bit/s");
    assert!(log.contains("921600 bit/s"), "{log}");
}

/// GPS1_POS and INS_1 over a pty at `--speed 20` from `--gps-time`: the
/// fix after the cold start carries GPS week 2400 (2026-01-04 is a
/// Sunday, the first of week 2400), INS_1 navigates with its NED offset
/// from the default `refLla` (0, 0, 0): north ≈ 50.1° × 111 120 m (the
/// built-in site, Newlyn).
#[test]
fn navigation_over_a_pty() {
    let emu = Emu::start(&[
        "--protocol",
        "isb",
        "--pty",
        "--power-on",
        "now",
        "--speed",
        "20",
        "--gps-time",
        "2026-01-04",
    ]);
    let mut c = Conn::serial(&emu.pty_path());
    c.send(&isb_get(did::GPS1_POS, 5));
    let g = loop {
        let g = GpsPos::decode(
            &isb_packet_of(&mut c, did::GPS1_POS)
                .payload
                .try_into()
                .unwrap(),
        );
        if g.status != 0 {
            break g;
        }
    };
    assert_eq!((g.week, g.status), (2400, 0x1001_030C));
    // Midnight + 18 leap seconds + the 30 s cold start (within a second).
    assert!((48_000..49_200).contains(&g.time_of_week_ms), "{g:?}");
    c.send(&isb_get(did::INS_1, 0));
    let i = Ins1::decode(
        &isb_packet_of(&mut c, did::INS_1)
            .payload
            .try_into()
            .unwrap(),
    );
    // NAV from the first fix: solution 3, GPS-aided, 3D fix.
    let want = ins_status::NAV_MODE
        | ins_status::GPS_AIDING_POS
        | ins_status::GPS_AIDING_VEL
        | (1 << ins_status::GPS_NAV_FIX_SHIFT);
    assert_eq!(
        i.header.ins_status & want,
        want,
        "{:#x}",
        i.header.ins_status
    );
    assert_eq!(ins_status::solution(i.header.ins_status), 3);
    assert!((f64::from(i.ned[0]) - 50.10167f64.to_radians() * 6_366_707.019_5).abs() < 10.0);
}

/// The INS_2 and GPS1_POS of `--gps-time` over TCP at `--speed 20`: no
/// fix for the 30 s cold start, then GPS1_POS every 200 ms of GPS time
/// (week 2408 for 2026-03-01), INS_2 every 100 ms by its own time fields
/// and NAV status; `fault gps off` on the control socket drops the fix and
/// INS_2 reports dead reckoning; `fault gps on` brings both back.
#[test]
fn ins_2_and_gps1_pos_over_tcp_with_an_outage() {
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = isb(&[
        "--control",
        &addr,
        "--speed",
        "20",
        "--gps-time",
        "2026-03-01T12:00:00Z",
    ]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    c.send(&isb_get(did::GPS1_POS, 1));
    c.send(&isb_get(did::INS_2, 25));
    let pos = |p: support::IsbPacket| GpsPos::decode(&p.payload.try_into().unwrap());
    let ins = |p: support::IsbPacket| Ins2::decode(&p.payload.try_into().unwrap());
    // Until the fix: status 0, week 0 (GPS time unknown).
    let mut fixes = Vec::new();
    let mut ins2 = Vec::new();
    for _ in 0..2000 {
        let p = isb_packet(&mut c);
        match p.did {
            did::GPS1_POS => {
                let g = pos(p);
                if g.status != 0 {
                    fixes.push(g);
                }
            }
            did::INS_2 => ins2.push(ins(p)),
            d => panic!("unexpected DID {d}"),
        }
        if fixes.len() == 20 {
            break;
        }
    }
    assert_eq!(fixes.len(), 20, "a fix after the cold start");
    for w in fixes.windows(2) {
        assert_eq!(w[1].time_of_week_ms - w[0].time_of_week_ms, 200);
    }
    let g = fixes[0];
    assert_eq!((g.week, g.status, g.leap_s), (2408, 0x1001_030C, 18));
    // 12:00:00 UTC on a Sunday + 18 s + the 30 s cold start.
    assert!(
        (43_248_000..43_251_000).contains(&g.time_of_week_ms),
        "{g:?}"
    );
    let navigating: Vec<&Ins2> = ins2.iter().filter(|i| i.header.week == 2408).collect();
    assert!(navigating.len() > 5);
    for w in navigating.windows(2) {
        assert!((w[1].header.time_of_week - w[0].header.time_of_week - 0.1).abs() < 1e-6);
    }
    let last = navigating.last().unwrap();
    // The SDK's healthy word at rest (0x200 marks a GNSS epoch's output).
    assert_eq!(
        last.header.ins_status & !ins_status::GPS_UPDATE_IN_SOLUTION,
        0x0103_5970,
        "{:#x}",
        last.header.ins_status
    );
    // The navigation-period grid sits on GPS time: whole 4 ms steps of a
    // GPS second (the epoch is a whole second, so 1PPS edges fall on GPS
    // seconds).
    let steps = last.header.time_of_week * 250.0;
    assert!(
        (steps - steps.round()).abs() < 1e-6,
        "{}",
        last.header.time_of_week
    );
    assert!((last.lla[0] - 50.10167).abs() < 1e-4);

    assert!(ctl.cmd("fault gps off").starts_with("ok"));
    let mut dr = None;
    for _ in 0..200 {
        let p = isb_packet(&mut c);
        if p.did == did::INS_2 {
            let i = ins(p);
            if ins_status::dead_reckoning(i.header.ins_status) {
                dr = Some(i);
                break;
            }
        }
    }
    let dr = dr.expect("dead reckoning after the outage");
    assert_eq!(dr.header.ins_status & ins_status::GPS_NAV_FIX_MASK, 0);
    assert!(ctl.cmd("fault gps on").starts_with("ok"));
    let mut back = false;
    for _ in 0..200 {
        let p = isb_packet(&mut c);
        if p.did == did::INS_2
            && ins(p).header.ins_status & !ins_status::GPS_UPDATE_IN_SOLUTION == 0x0103_5970
        {
            back = true;
            break;
        }
    }
    assert!(back, "NAV again once the fix is back");
    assert!(ctl.cmd("fault mag on").starts_with("ok"));
}

/// The vendor tool's `-presetINS` bytes (RMC {0x8000000000000402, 0x100})
/// over TCP: INS_2 every 4 ms and GPS1_POS every 200 ms by their own time
/// fields; `$PERS` then `$SRST`: both resume unasked after the reset.
#[test]
fn the_ins_preset_persists_across_a_reset() {
    let emu = isb(&["--speed", "5"]);
    let mut c = emu.connect();
    c.send(&hex(
        "ef 49 05 09 0c 00 02 04 00 00 00 00 00 80 00 01 00 00 d9 ed",
    ));
    let ack = isb_packet(&mut c);
    assert_eq!((ack.flags, ack.payload[1]), (1, did::RMC));
    let collect = |c: &mut Conn| {
        let (mut ins, mut gps) = (Vec::new(), Vec::new());
        while gps.len() < 4 {
            let p = isb_packet(c);
            match p.did {
                did::INS_2 => ins.push(Ins2::decode(&p.payload.try_into().unwrap())),
                did::GPS1_POS => gps.push(GpsPos::decode(&p.payload.try_into().unwrap())),
                d => panic!("unexpected DID {d}"),
            }
        }
        (ins, gps)
    };
    let check = |ins: &[Ins2], gps: &[GpsPos]| {
        for w in ins.windows(2) {
            assert!((w[1].header.time_of_week - w[0].header.time_of_week - 0.004).abs() < 1e-9);
        }
        for w in gps.windows(2) {
            assert_eq!(w[1].time_of_week_ms - w[0].time_of_week_ms, 200);
        }
        assert!(ins.len() >= 100, "{}", ins.len());
    };
    let (ins, gps) = collect(&mut c);
    check(&ins, &gps);
    c.send(b"$PERS*14\r\n");
    c.send(b"$SRST*06\r\n");
    // After the reset time since boot starts again.
    let mut ins = Vec::new();
    loop {
        let p = isb_packet(&mut c);
        if p.did == did::INS_2 {
            let i = Ins2::decode(&p.payload.try_into().unwrap());
            if i.header.time_of_week < 0.1 {
                ins.push(i);
                break;
            }
        }
    }
    let (more, gps) = collect(&mut c);
    ins.extend(more);
    check(&ins, &gps);
}

/// A manoeuvre script (`--motion`): heading north at 50 m/s from 45.5° N,
/// 7.25° E, 300 m. Once the fix is there INS_1 moves north at 50 m/s by its
/// own time fields and positions, reads yaw 0° (the IMX's body is the
/// vehicle's: docs/isb.md) and the velocity (50, 0, 0) in its body axes;
/// GPS1_VEL's ECEF speed is 50 m/s within the receiver's error.
#[test]
fn a_manoeuvre_script_moves_the_ins() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("north.txt");
    std::fs::write(&path, "start 45.5 7.25 300 0 50\nhold 1000\n").unwrap();
    let emu = isb(&["--motion", path.to_str().unwrap(), "--speed", "20"]);
    let mut c = emu.connect();
    c.send(&isb_get(did::INS_1, 250));
    c.send(&isb_get(did::GPS1_VEL, 5));
    let mut ins = Vec::new();
    let mut vel = None;
    while ins.len() < 4 || vel.is_none() {
        let p = isb_packet(&mut c);
        match p.did {
            did::INS_1 => {
                // NAV and GPS-aided (moving: heading from GPS too).
                let i = Ins1::decode(&p.payload.try_into().unwrap());
                let s = i.header.ins_status;
                let aided = ins_status::NAV_MODE | ins_status::GPS_AIDING_POS;
                if s & aided == aided && ins_status::solution(s) == 3 {
                    ins.push(i);
                }
            }
            did::GPS1_VEL => {
                let v = GpsVel::decode(&p.payload.try_into().unwrap());
                if v.status != 0 {
                    vel = Some(v);
                }
            }
            d => panic!("unexpected DID {d}"),
        }
    }
    for w in ins.windows(2) {
        let dt = w[1].header.time_of_week - w[0].header.time_of_week;
        assert!((dt - 1.0).abs() < 1e-6, "{dt}");
        // 50 m a second north: 50 / 111 120 m a degree (within the INS's
        // velocity error and the Earth's curvature at 45°).
        let dlat = (w[1].lla[0] - w[0].lla[0]) * 111_132.0;
        assert!((dlat - 50.0).abs() < 1.5, "{dlat}");
        assert!((w[1].lla[1] - 7.25).abs() < 1e-4);
    }
    let i = ins.last().unwrap();
    let yaw = f64::from(i.theta[2]).to_degrees();
    assert!(yaw.abs() < 1.5, "{:?}", i.theta);
    assert!(
        (i.uvw[0] - 50.0).abs() < 0.5 && i.uvw[1].abs() < 0.5,
        "{:?}",
        i.uvw
    );
    let v = vel.unwrap().vel.map(f64::from);
    let speed = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    assert!((speed - 50.0).abs() < 0.5, "{speed}");
}

/// GPS1_SAT over TCP at `--speed 20` (the real binary, its control
/// socket): no satellites during the 30 s cold start, then the 12 used
/// satellites every 1 s of GPS time; `fault gps off` empties the list.
#[test]
fn gps1_sat_over_tcp_with_an_outage() {
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = isb(&["--control", &addr, "--speed", "20"]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    c.send(&isb_get(did::GPS1_SAT, 1));
    let sat =
        |c: &mut Conn| GpsSat::decode(&isb_packet_of(c, did::GPS1_SAT).payload.try_into().unwrap());
    let first = sat(&mut c);
    assert_eq!(first.num_sats, 0, "no fix at power-on");
    let mut fixed = Vec::new();
    for _ in 0..60 {
        let s = sat(&mut c);
        if s.num_sats > 0 {
            fixed.push(s);
            if fixed.len() == 3 {
                break;
            }
        }
    }
    assert_eq!(fixed.len(), 3, "satellites after the cold start");
    for w in fixed.windows(2) {
        assert_eq!(w[1].time_of_week_ms - w[0].time_of_week_ms, 1000);
    }
    assert_eq!(fixed[2].num_sats, 12);
    assert!(ctl.cmd("fault gps off").starts_with("ok"));
    let mut empty = false;
    for _ in 0..5 {
        if sat(&mut c).num_sats == 0 {
            empty = true;
            break;
        }
    }
    assert!(empty, "no satellites during the outage");
}

/// `status` counts ISB packets as it counts KERNEL frames: one GET of
/// DEV_INFO with period 0 is one packet sent, and the bytes sent are the
/// bytes the client received (the link had followed ISB output with the
/// KERNEL's framing: 0 frames).
#[test]
fn status_counts_isb_packets() {
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = isb(&["--control", &addr]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    c.send(&isb_get(did::DEV_INFO, 0));
    let p = isb_packet(&mut c);
    assert_eq!(p.did, did::DEV_INFO);
    // Nothing else comes: a GET with period 0 sends once.
    let len = p.payload.len() + imu_emu::isb::packet::OVERHEAD;
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(300))
        .is_none());
    assert_eq!(c.received, len);
    let s = ctl.cmd("status");
    let field = |k: &str| {
        s.split(' ')
            .find_map(|kv| kv.strip_prefix(k)?.strip_prefix('='))
            .unwrap_or_else(|| panic!("no {k} in {s}"))
            .to_owned()
    };
    assert_eq!(field("frames-sent"), "1", "{s}");
    assert_eq!(field("bytes-sent"), len.to_string(), "{s}");
}

/// The flight of the end-to-end tests: 45 s at rest (alignment, the cold
/// start's fix at 30 s), then north at 20 m/s.
const FLIGHT: &str = "start 45.5 7.25 300 0 0\nhold 45\naccel 2 10\nhold 10000\n";

fn ins1_of(c: &mut Conn) -> Ins1 {
    Ins1::decode(&isb_packet_of(c, did::INS_1).payload.try_into().unwrap())
}

/// A manoeuvre script flown by the real binary (`--motion`, `--speed 20`),
/// INS_1 every second, the control socket's `fault gps` and `power-cycle`:
/// NAV from the cold start's fix (30 s); moving north at 20 m/s, a 20 s
/// outage is dead reckoning whose positions still advance 20 m a second by
/// their own time fields; GPS aiding is back with the fix; a power cycle
/// after NAV is a warm start: the saved `lastLla` from the alignment on,
/// NAV 10 s after power-on instead of 30 s.
fn flight_with_an_outage_and_a_power_cycle(c: &mut Conn, ctl: &mut Control) {
    use ins_status::{GPS_AIDING_POS, NAV_MODE};
    c.send(&isb_get(did::INS_1, 250));
    // NAV, then moving.
    let i = loop {
        let i = ins1_of(c);
        assert!(i.header.time_of_week < 1e5 || i.header.week != 0);
        if i.header.ins_status & NAV_MODE != 0 && i.uvw[0] > 19.5 {
            break i;
        }
    };
    assert_ne!(i.header.ins_status & GPS_AIDING_POS, 0, "{i:?}");
    assert!(ctl.cmd("fault gps off").starts_with("ok"));
    let mut dr = Vec::new();
    while dr.len() < 20 {
        let i = ins1_of(c);
        if ins_status::dead_reckoning(i.header.ins_status) {
            dr.push(i);
        }
    }
    for w in dr.windows(2) {
        let dt = w[1].header.time_of_week - w[0].header.time_of_week;
        assert!((dt - 1.0).abs() < 1e-6, "{dt}");
        let north = (w[1].lla[0] - w[0].lla[0]) * 111_132.0;
        assert!((north - 20.0).abs() < 1.0, "{north}");
    }
    assert!(ctl.cmd("fault gps on").starts_with("ok"));
    let back = (0..5).any(|_| ins1_of(c).header.ins_status & GPS_AIDING_POS != 0);
    assert!(back, "GPS aiding again once the fix is back");
    assert_eq!(ctl.cmd("power-cycle"), "ok");
    c.send(&isb_get(did::INS_1, 250));
    // Time since boot until GPS time is known again.
    let first = loop {
        let i = ins1_of(c);
        if i.header.week == 0 && i.header.time_of_week > 5.5 {
            break i;
        }
    };
    assert!((first.lla[0] - 45.5).abs() < 0.02, "lastLla: {first:?}");
    assert_eq!(first.header.ins_status & NAV_MODE, 0);
    // Time since boot runs until the fix (10 s), NAV from the receiver's
    // next epoch: the output after it.
    let mut since_boot = first.header.time_of_week;
    let nav = loop {
        let i = ins1_of(c);
        if i.header.ins_status & NAV_MODE != 0 {
            break i;
        }
        if i.header.week == 0 {
            since_boot = i.header.time_of_week;
        }
    };
    assert!((9.0..10.5).contains(&since_boot), "{since_boot}");
    assert_ne!(nav.header.week, 0);
    assert!((nav.lla[0] - 45.5).abs() < 0.05, "{nav:?}");
}

#[test]
fn a_flight_with_an_outage_and_a_warm_power_cycle_over_tcp() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.txt");
    std::fs::write(&path, FLIGHT).unwrap();
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = isb(&[
        "--motion",
        path.to_str().unwrap(),
        "--control",
        &addr,
        "--speed",
        "20",
    ]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    flight_with_an_outage_and_a_power_cycle(&mut c, &mut ctl);
}

#[test]
fn a_flight_with_an_outage_and_a_warm_power_cycle_over_a_pty() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.txt");
    std::fs::write(&path, FLIGHT).unwrap();
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = Emu::start(&[
        "--protocol",
        "isb",
        "--pty",
        "--power-on",
        "now",
        "--motion",
        path.to_str().unwrap(),
        "--control",
        &addr,
        "--speed",
        "20",
    ]);
    let mut c = Conn::serial(&emu.pty_path());
    let mut ctl = Control::connect(&addr);
    flight_with_an_outage_and_a_power_cycle(&mut c, &mut ctl);
}

/// SYS_FAULT, GPS1_VERSION, PORT_MONITOR, MAG_CAL, GPS1_SIG and IMU3_RAW
/// through the binary over TCP (`docs/isb-data-sets.md`): each one-shot
/// GET is one whole DATA packet of the release's size (32, 220, 223, 12,
/// 708, 84 bytes)
/// with the fields a real IMX-5.0 reports; a MAG_CAL recalibration command
/// is ACKed and reads running, does not progress while the unit rests, and
/// completes when the unit is turned on the control socket (`motion
/// rotate`: a whole turn in heading, then one about a horizontal axis);
/// GPS1_SIG lists the signals of the satellites GPS1_SAT lists once the
/// receiver has its fix; RTOS_INFO is the unit's task table.
#[test]
fn status_version_calibration_signal_and_triple_imu_sets_over_tcp() {
    use imu_emu::isb::aux_sets::{mag_cal_state, GpsSig, Imu3, MagCal, PortMonitor};
    let addr = format!("127.0.0.1:{}", free_port());
    let emu = isb(&["--control", &addr, "--speed", "20"]);
    let mut c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    let once = |c: &mut Conn, d: u8| {
        c.send(&isb_get(d, 0));
        let p = isb_packet_of(c, d);
        assert_eq!(p.flags, 4, "whole, no offset flag");
        p.payload
    };
    let f = once(&mut c, did::SYS_FAULT);
    assert_eq!(f, [0u8; 32]);
    let v = once(&mut c, did::GPS1_VERSION);
    assert_eq!(v.len(), 220);
    assert!(v.starts_with(b"EXT CORE 1.00"));
    assert_eq!(&v[30..39], b"00190000\0");
    assert!(v[40 + 3 * 30..].starts_with(b"MOD=ZED-F9P\0"));
    // PORT_MONITOR: the line's bytes so far (three 16-byte GETs in, the
    // two replies out before its own).
    let out_so_far = c.received;
    let pm = once(&mut c, did::PORT_MONITOR);
    let pm = PortMonitor::decode(&pm.try_into().unwrap());
    assert_eq!((pm.active_ports, pm.port[0].port_info), (1, 0x10));
    assert_eq!(pm.port[0].tx_bytes as usize, out_so_far);
    assert_eq!(pm.port[0].rx_bytes, 3 * 16);
    let i3 = once(&mut c, did::IMU3_RAW);
    let i3 = Imu3::decode(&i3.try_into().unwrap());
    assert_eq!(i3.imu[0], i3.imu[2]);
    // At rest, level: about 1 g down in each IMU.
    assert!((i3.imu[1].acc[2] + 9.8).abs() < 0.2, "{i3:?}");
    let m = MagCal::decode(&once(&mut c, did::MAG_CAL).try_into().unwrap());
    assert_eq!((m.state, m.progress), (0, 0.0));
    c.send(&isb_set(did::MAG_CAL, 0, &1u32.to_le_bytes()));
    let ack = isb_packet(&mut c);
    assert_eq!((ack.flags, ack.payload[4]), (1, did::MAG_CAL));
    let m = MagCal::decode(&once(&mut c, did::MAG_CAL).try_into().unwrap());
    assert_eq!(m.state, mag_cal_state::RECAL_RUNNING);
    assert!((0.0..100.0).contains(&m.progress), "{m:?}");
    // GPS1_SIG: empty before the fix, then the 12 satellites' signals.
    c.send(&isb_get(did::GPS1_SIG, 1));
    let sig =
        |c: &mut Conn| GpsSig::decode(&isb_packet_of(c, did::GPS1_SIG).payload.try_into().unwrap());
    assert_eq!(sig(&mut c).num_sigs, 0, "no fix at power-on");
    let mut s = sig(&mut c);
    for _ in 0..60 {
        if s.num_sigs > 0 {
            break;
        }
        s = sig(&mut c);
    }
    assert_eq!(s.num_sigs, 12);
    c.send(&isb_get(did::GPS1_SAT, 0));
    let sat = GpsSat::decode(
        &isb_packet_of(&mut c, did::GPS1_SAT)
            .payload
            .try_into()
            .unwrap(),
    );
    for (g, v) in s.sig.iter().zip(&sat.sat).take(12) {
        assert_eq!((g.gnss_id, g.sv_id, g.cno), (v.gnss_id, v.sv_id, v.cno));
        assert_eq!((g.sig_id, g.quality, g.status), (0, 7, 5));
    }
    // At rest through the receiver's cold start: still running, hardly
    // any progress.
    let m = MagCal::decode(&once(&mut c, did::MAG_CAL).try_into().unwrap());
    assert_eq!(m.state, mag_cal_state::RECAL_RUNNING);
    assert!(m.progress < 10.0, "{m:?}");
    let cal =
        |c: &mut Conn| MagCal::decode(&isb_packet_of(c, did::MAG_CAL).payload.try_into().unwrap());
    // 36 °/s in heading for 11 s (MAG_CAL every 100 ms): one axis of two.
    assert!(ctl.cmd("motion rotate 0 0 36").starts_with("ok"));
    c.send(&isb_get(did::MAG_CAL, 100));
    let mut m = cal(&mut c);
    for _ in 0..110 {
        m = cal(&mut c);
    }
    assert_eq!(m.state, mag_cal_state::RECAL_RUNNING);
    assert!(m.progress > 50.0 && m.progress < 100.0, "{m:?}");
    // Then about a horizontal axis: done within the turn.
    assert!(ctl.cmd("motion rotate 36 0 0").starts_with("ok"));
    for _ in 0..150 {
        m = cal(&mut c);
        if m.state != mag_cal_state::RECAL_RUNNING {
            break;
        }
    }
    assert_eq!(
        (m.state, m.progress),
        (mag_cal_state::RECAL_COMPLETE, 100.0)
    );
    c.send(&isb_get(did::MAG_CAL, 0));
    let r = once(&mut c, did::RTOS_INFO);
    assert_eq!(r.len(), 372);
    assert_eq!(&r[12..19], b"SAMPLE\0");
    assert_eq!(&r[12 + 60..16 + 60], b"NAV\0");
}

/// CAN_CONFIG written over TCP is kept in `--flash FILE`: after a restart
/// (a power cycle) it reads back byte for byte; a fresh unit reads the
/// factory settings (every message off, 500 kbit/s).
#[test]
fn can_config_survives_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("imx.flash");
    let path = file.to_str().unwrap();
    let mut want = vec![0u8; 168];
    want[162..164].copy_from_slice(&500u16.to_le_bytes());
    {
        let emu = isb(&["--flash", path]);
        let mut c = emu.connect();
        c.send(&isb_get(did::CAN_CONFIG, 0));
        assert_eq!(isb_packet_of(&mut c, did::CAN_CONFIG).payload, want);
        // INS time every 5 periods at 0x100, 1 Mbit/s.
        c.send(&isb_set(did::CAN_CONFIG, 0, &5u16.to_le_bytes()));
        assert_eq!(isb_packet(&mut c).flags, 1);
        c.send(&isb_set(did::CAN_CONFIG, 54, &0x100u32.to_le_bytes()));
        assert_eq!(isb_packet(&mut c).flags, 1);
        c.send(&isb_set(did::CAN_CONFIG, 162, &1000u16.to_le_bytes()));
        assert_eq!(isb_packet(&mut c).flags, 1);
        std::thread::sleep(Duration::from_millis(100));
    }
    want[0..2].copy_from_slice(&5u16.to_le_bytes());
    want[54..58].copy_from_slice(&0x100u32.to_le_bytes());
    want[162..164].copy_from_slice(&1000u16.to_le_bytes());
    let emu = isb(&["--flash", path]);
    let mut c = emu.connect();
    c.send(&isb_get(did::CAN_CONFIG, 0));
    assert_eq!(isb_packet_of(&mut c, did::CAN_CONFIG).payload, want);
}
