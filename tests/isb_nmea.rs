//! The IMX-5's NMEA face through the core: `$ASCE` as the release parses
//! it, every sentence it prints, their epochs, persistence and stops, and
//! NMEA and ISB interleaved whole on one line (`src/isb/asce.rs`,
//! `src/isb/nmea_out.rs`, `src/isb/nmea_stream.rs`; `docs/isb.md` "NMEA").

use imu_emu::device::{Device, Level, Pin};
use imu_emu::isb::did;
use imu_emu::isb::message::{self};
use imu_emu::isb::nav_sets::{GpsPos, Ins1, Ins2};
use imu_emu::isb::nmea::checksum;
use imu_emu::isb::Isb;
use imu_emu::Instant;

mod common;
use common::isb::{get, imx5, IsbFlash as Flash};
use common::xorshift::XorShift;

/// What came out of the line, split into whole ISB packets and whole
/// sentences (a cut message fails the split).
#[derive(Debug, Clone, PartialEq)]
enum Out {
    Isb { did: u8, payload: Vec<u8> },
    Nmea(String),
}

struct Bench {
    dev: Device<Flash, Isb>,
    now: u64,
    ticks: u64,
    raw: Vec<u8>,
}

fn sentence(body: &str) -> Vec<u8> {
    format!("${body}*{:02X}\r\n", checksum(body.as_bytes())).into_bytes()
}

impl Bench {
    fn new() -> Self {
        Self::with_flash(Flash::new())
    }

    fn with_flash(flash: Flash) -> Self {
        let dev = imx5(11, flash);
        Bench {
            dev,
            now: 0,
            ticks: 0,
            raw: Vec::new(),
        }
    }

    fn power_cycle(self) -> Self {
        Self::with_flash(self.dev.into_flash())
    }

    /// Output since the last call, split and checked (every sentence's
    /// checksum, upper-case hex, CR LF).
    fn take(&mut self) -> Vec<(u64, Out)> {
        let mut buf = [0u8; 4096];
        loop {
            let n = self.dev.poll_tx(&mut buf);
            while self.dev.poll_event().is_some() {}
            if n == 0 {
                break;
            }
            self.raw.extend_from_slice(&buf[..n]);
        }
        let raw = std::mem::take(&mut self.raw);
        split(&raw).into_iter().map(|o| (self.ticks, o)).collect()
    }

    fn send(&mut self, bytes: &[u8]) -> Vec<Out> {
        self.dev.on_rx(bytes, Instant(self.now));
        self.take().into_iter().map(|(_, o)| o).collect()
    }

    /// Runs `n` ticks; what came out, with the tick it came out at.
    fn run(&mut self, n: u64) -> Vec<(u64, Out)> {
        let period = self.dev.tick_period_ns();
        let mut out = Vec::new();
        for _ in 0..n {
            self.ticks += 1;
            self.now = self.ticks * period;
            self.dev.on_tick(Instant(self.now));
            out.extend(self.take());
        }
        out
    }
}

fn split(raw: &[u8]) -> Vec<Out> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < raw.len() {
        match raw[i] {
            0xEF => {
                let size = usize::from(u16::from_le_bytes([raw[i + 4], raw[i + 5]]));
                let end = i + 8 + size;
                assert!(end <= raw.len(), "a cut ISB packet");
                out.push(Out::Isb {
                    did: raw[i + 3],
                    payload: raw[i + 6..i + 6 + size].to_vec(),
                });
                i = end;
            }
            b'$' => {
                let end = raw[i..]
                    .windows(2)
                    .position(|w| w == b"\r\n")
                    .expect("a sentence ends with CR LF")
                    + i
                    + 2;
                let s = std::str::from_utf8(&raw[i..end]).unwrap().to_owned();
                let star = s.rfind('*').unwrap();
                let sum = checksum(&s.as_bytes()[1..star]);
                assert_eq!(&s[star + 1..star + 3], format!("{sum:02X}"), "{s}");
                assert_eq!(star + 5, s.len(), "{s}");
                out.push(Out::Nmea(s[..star].to_owned()));
                i = end;
            }
            b => panic!("byte {b:#04x} starts no message"),
        }
    }
    out
}

fn lines(out: &[(u64, Out)], prefix: &str) -> Vec<(u64, Vec<String>)> {
    out.iter()
        .filter_map(|(t, o)| match o {
            Out::Nmea(s) if s.starts_with(prefix) => {
                Some((*t, s.split(',').map(str::to_owned).collect()))
            }
            _ => None,
        })
        .collect()
}

fn isb_of(out: &[(u64, Out)], d: u8) -> Vec<Vec<u8>> {
    out.iter()
        .filter_map(|(_, o)| match o {
            Out::Isb { did, payload } if *did == d => Some(payload.clone()),
            _ => None,
        })
        .collect()
}

/// Seconds of `hhmmss.sss`.
fn secs(t: &str) -> f64 {
    let h: f64 = t[0..2].parse().unwrap();
    let m: f64 = t[2..4].parse().unwrap();
    let s: f64 = t[4..].parse().unwrap();
    h * 3600.0 + m * 60.0 + s
}

/// `ddmm.mmmmm` / `dddmm.mmmmm` with its hemisphere, degrees.
fn degrees(v: &str, hemi: &str) -> f64 {
    let dot = v.find('.').unwrap();
    let d: f64 = v[..dot - 2].parse().unwrap();
    let m: f64 = v[dot - 2..].parse().unwrap();
    let x = d + m / 60.0;
    if hemi == "S" || hemi == "W" {
        -x
    } else {
        x
    }
}

/// Until the first fix (the cold start is 30 s), then the GNSS sentences
/// at period 5 of the 200 ms receiver epoch: each exactly once a second,
/// on the whole GPS second, all of one epoch in ID order (GGA, GLL, GSA,
/// RMC, ZDA, GSV, VTG), with the very position, time and status GPS1_POS
/// streamed beside them carries.
#[test]
fn gnss_sentences_on_whole_gps_seconds_agree_with_gps1_pos() {
    let mut b = Bench::new();
    b.run(62_000);
    let r = b.send(&sentence(
        "ASCE,0,GNGGA,5,GNGLL,5,GNGSA,5,GNRMC,5,GNZDA,5,GPGSV,1,GNVTG,5",
    ));
    assert!(r.is_empty(), "no reply to a set: {r:?}");
    b.send(&get(did::GPS1_POS, 1));
    let out = b.run(2000 * 4);
    let gga = lines(&out, "$GNGGA");
    assert_eq!(gga.len(), 4);
    let pos: Vec<GpsPos> = isb_of(&out, did::GPS1_POS)
        .into_iter()
        .map(|p| GpsPos::decode(&p.try_into().unwrap()))
        .collect();
    for (t, f) in &gga {
        let s = secs(&f[1]);
        assert_eq!(s.fract(), 0.0, "{f:?}");
        // The GPS1_POS of that epoch (its UTC = tow − leapS).
        let p = pos
            .iter()
            .find(|p| {
                let utc = (p.time_of_week_ms / 1000 - u32::from(p.leap_s)) % 86_400;
                f64::from(utc) == s && p.time_of_week_ms % 1000 == 0
            })
            .unwrap_or_else(|| panic!("no GPS1_POS at {f:?} (tick {t})"));
        assert!((degrees(&f[2], &f[3]) - p.lla[0]).abs() < 1e-7, "{f:?}");
        assert!((degrees(&f[4], &f[5]) - p.lla[1]).abs() < 1e-7, "{f:?}");
        assert_eq!(f[6], "1");
        assert_eq!(f[7], format!("{:02}", p.status & 0xFF));
        assert_eq!(f[8], format!("{:.2}", p.p_dop));
        assert_eq!(f[9], format!("{:.2}", p.h_msl));
        assert_eq!(f[11], format!("{:.2}", p.lla[2] - f64::from(p.h_msl)));
    }
    for w in gga.windows(2) {
        assert_eq!(secs(&w[1].1[1]) - secs(&w[0].1[1]), 1.0);
        assert_eq!(w[1].0 - w[0].0, 2000, "one device second apart");
    }
    // One epoch's sentences in ID order, in one tick.
    let order: Vec<String> = out
        .iter()
        .filter(|(t, _)| *t == gga[1].0)
        .filter_map(|(_, o)| match o {
            Out::Nmea(s) => Some(s[..6].to_owned()),
            _ => None,
        })
        .collect();
    assert_eq!(
        order,
        [
            "$GNGGA", "$GNGLL", "$GNGSA", "$GNRMC", "$GNZDA", "$GPGSV", "$GPGSV", "$GPGSV",
            "$GNVTG"
        ]
    );
    let rmc = lines(&out, "$GNRMC");
    let zda = lines(&out, "$GNZDA");
    assert_eq!((rmc.len(), zda.len()), (4, 4));
    assert_eq!(rmc[0].1[2], "A");
    assert_eq!(secs(&rmc[0].1[1]), secs(&gga[0].1[1]));
    // 2026-01-01 + 31 s: the date in RMC and ZDA.
    assert_eq!(rmc[0].1[9], "010126");
    assert_eq!(&zda[0].1[2..5], ["01", "01", "2026"]);
    // GSV: 12 GPS satellites in three sentences.
    let gsv = lines(&out, "$GPGSV");
    assert_eq!(gsv.len(), 12);
    assert_eq!(&gsv[0].1[1..4], ["3", "1", "12"]);
    let gsa = lines(&out, "$GNGSA");
    assert_eq!(&gsa[0].1[1..4], ["A", "03", "02"]);
    assert_eq!(lines(&out, "$GNVTG")[0].1[9], "A");
}

/// PINS1, PINS2 and PPIMU on the navigation period (period 2 = 8 ms of
/// device time, `startupNavDtMs` 4 ms), printing the INS_1 / INS_2 / PIMU
/// bytes of the same instant to the release's precisions.
#[test]
fn pins_and_ppimu_on_the_navigation_period_agree_with_isb() {
    let mut b = Bench::new();
    b.run(62_000);
    b.send(&sentence("ASCE,0,PINS1,2,PINS2,2,PPIMU,2"));
    b.send(&get(did::INS_1, 2));
    b.send(&get(did::INS_2, 2));
    let out = b.run(400);
    let p1 = lines(&out, "$PINS1");
    let p2 = lines(&out, "$PINS2");
    let pp = lines(&out, "$PPIMU");
    assert_eq!((p1.len(), p2.len(), pp.len()), (25, 25, 25));
    for w in p1.windows(2) {
        let dt: f64 = w[1].1[1].parse::<f64>().unwrap() - w[0].1[1].parse::<f64>().unwrap();
        assert!((dt - 0.008).abs() < 1e-6, "{dt}");
        assert_eq!(w[1].0 - w[0].0, 16);
    }
    let ins1: Vec<Ins1> = isb_of(&out, did::INS_1)
        .into_iter()
        .map(|p| Ins1::decode(&p.try_into().unwrap()))
        .collect();
    let last = &p1.last().unwrap().1;
    let i = ins1
        .iter()
        .find(|i| format!("{:.3}", i.header.time_of_week) == last[1])
        .expect("INS_1 of the same instant");
    assert_eq!(last[2], i.header.week.to_string());
    assert_eq!(last[3], i.header.ins_status.to_string());
    assert_eq!(last[4], i.header.hdw_status.to_string());
    assert_eq!(last[7], format!("{:.4}", i.theta[2]));
    assert_eq!(last[11], format!("{:.8}", i.lla[0]));
    assert_eq!(last[13], format!("{:.3}", i.lla[2]));
    let ins2: Vec<Ins2> = isb_of(&out, did::INS_2)
        .into_iter()
        .map(|p| Ins2::decode(&p.try_into().unwrap()))
        .collect();
    let last = &p2.last().unwrap().1;
    let i = ins2
        .iter()
        .find(|i| format!("{:.3}", i.header.time_of_week) == last[1])
        .unwrap();
    assert_eq!(last[5], format!("{:.4}", i.qn2b[0]));
    // PPIMU: one navigation period's increments, dt 0.004, at rest Δv
    // down ≈ −g·dt.
    let f = &pp.last().unwrap().1;
    assert_eq!(f[8], "0.004");
    let dvz: f64 = f[7].parse().unwrap();
    assert!((dvz + 9.80665 * 0.004).abs() < 2e-3, "{f:?}");
}

/// Period 0 sends once and turns the ID off; `$ASCE*14` reads the table
/// back as the release writes it; a bad checksum changes nothing; unknown
/// names and out-of-range IDs are dropped and counted; `PSTRB` goes out
/// on a strobe (numeric 13 only), `INFO` on its 1 ms source.
#[test]
fn one_shots_the_table_reply_and_bad_requests() {
    let mut b = Bench::new();
    b.run(10);
    b.send(&sentence("ASCE,0,PINS1,0,PIMU,25"));
    let out = b.run(1000);
    assert_eq!(lines(&out, "$PINS1").len(), 1);
    assert_eq!(lines(&out, "$PIMU").len(), 5, "every 25 × 4 ms");
    let r = b.send(b"$ASCE*14\r\n");
    assert_eq!(r, [Out::Nmea("$ASCE,0,1,25".into())]);
    // A wrong checksum: dropped, nothing changes.
    assert!(b.send(b"$ASCE,0,PINS1,1*00\r\n").is_empty());
    assert_eq!(b.send(b"$ASCE*14\r\n"), [Out::Nmea("$ASCE,0,1,25".into())]);
    b.send(&sentence("ASCE,0,PSTRB,1,BOGUS,1,20,1,13,1,14,1000"));
    assert_eq!(b.dev.personality().asce_rejected(), 3);
    assert_eq!(
        b.send(b"$ASCE*14\r\n"),
        [Out::Nmea("$ASCE,0,1,25,13,1,14,232".into())],
        "1000 is stored as a byte"
    );
    b.dev.on_pin(Pin::Extrig, Level::High, Instant(b.now));
    let out = b.take();
    let s = lines(&out, "$PSTRB");
    assert_eq!(s.len(), 1);
    assert_eq!(&s[0].1[1..], ["0", "505", "0", "1"]);
    let out = b.run(232 * 2);
    let info = lines(&out, "$INFO");
    assert_eq!(info.len(), 1);
    assert_eq!(info[0].1[1], "10000011");
}

/// `$ASCE` with the persistent option outlives a power cycle (as `$PERS`
/// does); `$STPB` and the ISB stop packet stop NMEA with everything else;
/// stop then `$PERS` clears what was saved.
#[test]
fn persistence_stops_and_interleaving_with_isb() {
    let mut b = Bench::new();
    b.send(&sentence("ASCE,512,PINS2,25"));
    b.send(&get(did::IMU, 1));
    let out = b.run(800);
    assert_eq!(lines(&out, "$PINS2").len(), 4);
    assert_eq!(isb_of(&out, did::IMU).len(), 100);
    let mut b = b.power_cycle();
    let out = b.run(800);
    assert_eq!(lines(&out, "$PINS2").len(), 4, "persistent");
    assert!(isb_of(&out, did::IMU).is_empty(), "not saved");
    b.send(b"$STPB*15\r\n");
    assert!(b.run(400).is_empty());
    let mut b = b.power_cycle();
    assert_eq!(lines(&b.run(800), "$PINS2").len(), 4, "stop leaves flash");
    b.send(b"$STPC*14\r\n$PERS*14\r\n");
    let mut b = b.power_cycle();
    assert!(b.run(400).is_empty(), "cleared by stop + $PERS");
}

/// `$PERS` of DEV_INFO and SYS_CMD streams, `$SRST`: they resume, and
/// the first `$STPB` stops them (with NMEA ones beside them).
#[test]
fn the_first_stpb_after_pers_and_a_reset_stops_everything() {
    let mut b = Bench::new();
    b.send(&get(did::DEV_INFO, 1000));
    b.send(&get(did::SYS_CMD, 1000));
    b.send(&sentence("ASCE,0,PINS2,25"));
    b.send(b"$PERS*14\r\n");
    b.send(b"$SRST*06\r\n");
    let out = b.run(4000);
    assert_eq!(isb_of(&out, did::DEV_INFO).len(), 2);
    assert_eq!(isb_of(&out, did::SYS_CMD).len(), 2);
    assert_eq!(lines(&out, "$PINS2").len(), 20);
    assert!(b.send(b"$STPB*15\r\n").is_empty());
    assert!(b.run(5000).is_empty());
}

/// Host DATA (packet type 4) is applied as SET_DATA and answered with
/// nothing (no ACK, no NACK): here FLASH_CONFIG `magDeclination`, which
/// RMC then prints as the magnetic variation.
#[test]
fn host_data_packets_apply_as_set_data_without_an_ack() {
    use imu_emu::isb::packet::{self, FLAG_OFFSET};
    use imu_emu::isb::sets::flash;
    let mut b = Bench::new();
    let mut payload = (flash::MAG_DECLINATION as u16).to_le_bytes().to_vec();
    payload.extend(0.2059f32.to_le_bytes());
    let mut out = [0u8; 64];
    let n = packet::encode(4 | FLAG_OFFSET, did::FLASH_CONFIG, &payload, &mut out).unwrap();
    assert!(b.send(&out[..n]).is_empty(), "no ACK");
    // A DATA the device refuses (a read-only set) gets no NACK either.
    let n = packet::encode(4, did::INS_1, &[0xFF; 8], &mut out).unwrap();
    assert!(b.send(&out[..n]).is_empty(), "no NACK");
    let r = b.send(&get(did::FLASH_CONFIG, 0));
    let Out::Isb { payload, .. } = &r[0] else {
        panic!("{r:?}")
    };
    let at = flash::MAG_DECLINATION;
    assert_eq!(payload[at..at + 4], 0.2059f32.to_le_bytes());
    b.run(62_000);
    b.send(&sentence("ASCE,0,GNRMC,0"));
    let rmc = lines(&b.run(400), "$GNRMC");
    assert_eq!(&rmc[0].1[10..], ["011.8", "E"]);
}

/// One-shot GETs of INS, MAGNETOMETER and BAROMETER are stamped on their
/// output grid, as IMU and PIMU are (a GET between two navigation periods
/// reads the last one's time, not "now").
#[test]
fn one_shot_gets_are_stamped_on_their_grid() {
    use imu_emu::isb::nav_sets::{Barometer, Magnetometer};
    use imu_emu::isb::sets::Imu;
    let mut b = Bench::new();
    b.run(62_003);
    let one = |b: &mut Bench, d: u8| match &b.send(&get(d, 0))[0] {
        Out::Isb { payload, .. } => payload.clone(),
        o => panic!("{o:?}"),
    };
    let imu = Imu::decode(&one(&mut b, did::IMU).try_into().unwrap());
    let ins = Ins2::decode(&one(&mut b, did::INS_2).try_into().unwrap());
    let pos = GpsPos::decode(&one(&mut b, did::GPS1_POS).try_into().unwrap());
    let mag = Magnetometer::decode(&one(&mut b, did::MAGNETOMETER).try_into().unwrap());
    let bar = Barometer::decode(&one(&mut b, did::BAROMETER).try_into().unwrap());
    // Tick 62 003 is 31.0015 s: the 4 ms grid's 31.000, 10 ms 31.000, 8 ms 31.000.
    assert_eq!(imu.time, 31.0);
    assert!((ins.header.time_of_week - pos.tow_offset - 31.0).abs() < 1e-6);
    assert_eq!((mag.time, bar.time), (31.0, 31.0));
}

/// BIT runs at start-up as the release's does (DID_BIT filled, hdwStatus
/// BIT passed) unless `sysCfgBits` has
/// `SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP`; GPS1_POS, GPS1_VEL and
/// hdwStatus agree on PPS time sync once the receiver has its fix.
#[test]
fn bit_at_start_up_and_pps_flags_in_step() {
    use imu_emu::isb::nav_sets::{gps_status, hdw_nav, GpsVel};
    use imu_emu::isb::sets::{bit, flash, hdw_status, Bit, SysParams};
    let mut b = Bench::new();
    let one = |b: &mut Bench, d: u8| match &b.send(&get(d, 0))[0] {
        Out::Isb { payload, .. } => payload.clone(),
        o => panic!("{o:?}"),
    };
    let r = Bit::decode(&one(&mut b, did::BIT).try_into().unwrap());
    assert_eq!(
        (r.state, r.last_command, r.hdw_bit_status),
        (
            bit::STATE_DONE,
            bit::CMD_BASIC_MOVING,
            bit::HDW_PASSED_NO_GPS
        )
    );
    let sp = SysParams::decode(&one(&mut b, did::SYS_PARAMS).try_into().unwrap());
    assert_eq!(sp.hdw_status & hdw_status::BIT_MASK, hdw_status::BIT_PASSED);
    b.run(62_000);
    let sp = SysParams::decode(&one(&mut b, did::SYS_PARAMS).try_into().unwrap());
    let pos = GpsPos::decode(&one(&mut b, did::GPS1_POS).try_into().unwrap());
    let vel = GpsVel::decode(&one(&mut b, did::GPS1_VEL).try_into().unwrap());
    assert_ne!(sp.hdw_status & hdw_nav::GPS_PPS_TIMESYNC, 0);
    assert_ne!(pos.status & gps_status::TIME_PPS_SYNC, 0);
    assert_eq!(vel.status, pos.status);
    // Disabled: no BIT at the next boot.
    let bits = flash::SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP.to_le_bytes();
    let mut out = [0u8; 64];
    let n = message::encode_set(
        did::FLASH_CONFIG,
        flash::SYS_CFG_BITS as u16,
        &bits,
        &mut out,
    )
    .unwrap();
    b.send(&out[..n]);
    b.run(10);
    let mut b = b.power_cycle();
    let r = Bit::decode(&one(&mut b, did::BIT).try_into().unwrap());
    assert_eq!(r.state, bit::STATE_OFF);
    let sp = SysParams::decode(&one(&mut b, did::SYS_PARAMS).try_into().unwrap());
    assert_eq!(sp.hdw_status & hdw_status::BIT_MASK, 0);
}

/// Malformed `$ASCE` with valid checksums — random fields of digits,
/// names, signs, `0x`, underscores, empty fields, up to the receive limit —
/// never crash the device; every request leaves a table the `$ASCE*14`
/// reply reads back as `$ASCE,0` and ascending `id,period` pairs of IDs
/// 0…19, and every sentence it then sends is whole.
#[test]
fn malformed_asce_never_crashes() {
    const WORDS: [&str; 16] = [
        "",
        "0",
        "7",
        "19",
        "20",
        "255",
        "300",
        "-1",
        "0x2FF",
        "3857",
        "99999999999999999999",
        "PINS1",
        "GxGSV_5_1",
        "GNGGA",
        "PSTRB",
        "G?RMC",
    ];
    let mut b = Bench::new();
    let mut r = XorShift(0x5EED_0028);
    for round in 0..400 {
        let mut body = String::from("ASCE");
        for _ in 0..r.below(50) {
            body.push(',');
            body.push_str(WORDS[r.below(WORDS.len() as u32) as usize]);
        }
        body.truncate(190);
        b.send(&sentence(&body));
        b.run(20);
        let reply = b.send(b"$ASCE*14\r\n");
        let Some(Out::Nmea(t)) = reply
            .iter()
            .find(|o| matches!(o, Out::Nmea(s) if s.starts_with("$ASCE")))
        else {
            panic!("round {round}: no table reply to {body}: {reply:?}")
        };
        let f: Vec<u32> = t.split(',').skip(2).map(|x| x.parse().unwrap()).collect();
        assert_eq!(&t[..7], "$ASCE,0", "round {round}");
        for p in f.chunks(2) {
            assert!(p[0] < 20 && (1..=255).contains(&p[1]), "round {round}: {t}");
        }
        if round % 50 == 49 {
            b.send(b"$STPB*15\r\n");
        }
    }
}

/// `ticks_to_next_output` (when a board wakes) names the very tick the
/// next sentence goes out at: navigation-period and GNSS (GPS-second)
/// streams alike.
#[test]
fn the_next_output_is_the_next_sentence() {
    let mut b = Bench::new();
    b.run(62_001);
    for asce in ["ASCE,0,PINS2,25", "ASCE,0,PINS2,0,GNGGA,5"] {
        b.send(&sentence(asce));
        b.run(1);
        for _ in 0..3 {
            let k = b.dev.ticks_to_next_output().expect("streaming");
            let out = b.run(k);
            let firsts: Vec<u64> = out.iter().map(|(t, _)| *t).collect();
            assert!(!firsts.is_empty(), "{asce}: nothing after {k} ticks");
            assert!(
                firsts.iter().all(|&t| t == b.ticks),
                "{asce}: {firsts:?} {}",
                b.ticks
            );
        }
    }
}

/// DID 8 (NMEA_BCAST_PERIOD, `nmea_msgs_t`): a SET of options and
/// `{msgID, period}` pairs (ID 0 ends the list) sets the table as `$ASCE`
/// does, is ACKed, and a GET reads the table back in that form.
#[test]
fn nmea_bcast_period_sets_and_reads_the_table() {
    let mut b = Bench::new();
    let mut msgs = vec![0u8; 44];
    msgs[4..10].copy_from_slice(&[4, 2, 7, 1, 0, 9]);
    let mut out = [0u8; 128];
    let n = message::encode_set(8, 0, &msgs, &mut out).unwrap();
    let r = b.send(&out[..n]);
    assert!(matches!(&r[..], [Out::Isb { did: 0, .. }]), "an ACK: {r:?}");
    assert_eq!(
        b.send(b"$ASCE*14\r\n"),
        [Out::Nmea("$ASCE,0,4,2,7,1".into())]
    );
    let r = b.send(&get(8, 0));
    let Out::Isb { did: 8, payload } = &r[0] else {
        panic!("{r:?}")
    };
    assert_eq!(payload[..10], [0, 0, 0, 0, 4, 2, 7, 1, 0, 0]);
    assert_eq!(payload.len(), 44);
    assert_eq!(lines(&b.run(32), "$PINS1").len(), 2, "every 2 × 4 ms");
}

/// GPS1_RCVR_POS (DID 6): without RTK the receiver's solution is GPS1_POS,
/// byte for byte, at the same epoch; its RMC bit (0x400000) streams it.
#[test]
fn gps1_rcvr_pos_is_the_receivers_gps1_pos() {
    let mut b = Bench::new();
    b.run(62_000);
    let one = |b: &mut Bench, d: u8| match &b.send(&get(d, 0))[0] {
        Out::Isb { payload, .. } => payload.clone(),
        o => panic!("{o:?}"),
    };
    let (rcvr, pos) = (one(&mut b, 6), one(&mut b, did::GPS1_POS));
    assert_eq!(rcvr, pos);
    assert_ne!(GpsPos::decode(&rcvr.try_into().unwrap()).status, 0);
    let rmc = imu_emu::isb::sets::Rmc {
        bits: 0x40_0000,
        options: 0,
    }
    .encode();
    let mut out = [0u8; 64];
    let n = message::encode_set(did::RMC, 0, &rmc, &mut out).unwrap();
    b.send(&out[..n]);
    assert_eq!(isb_of(&b.run(2000), 6).len(), 5, "every 200 ms");
}
