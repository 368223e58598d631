//! The ISB personality through the core: the emulated IMX-5 driven with
//! bytes, ticks and pin edges exactly as a board drives it, answers read
//! back with the ISB packet decoder (`src/isb/device.rs`; `docs/isb.md`).

use imu_emu::device::{Device, Level, Pin};
use imu_emu::earth;
use imu_emu::isb::did;
use imu_emu::isb::ins::{self, NavFaults};
use imu_emu::isb::message::{self, GetRequest};
use imu_emu::isb::nav;
use imu_emu::isb::nav_sets::{
    hdw_nav, ins_status, rmc_nav, sat_status, Barometer, GpsPos, GpsSat, GpsSatSv, ImuMag, Ins1,
    Ins2, Ins4, Magnetometer, PimuMag, SysSensors,
};
use imu_emu::isb::packet::{self, Decoder};
use imu_emu::isb::sets::{
    dev_info, flash, hdw_status, imu_status, rmc, sys_cmd, sys_params, DevInfo, Imu, Pimu, Rmc,
    StrobeInTime, SysParams, SystemCommand,
};
use imu_emu::isb::Isb;
use imu_emu::sensor::Motion;
use imu_emu::Instant;

mod common;
use common::isb::{get, imx5, IsbFlash as Flash};

/// A received packet.
#[derive(Debug, Clone, PartialEq)]
struct Pkt {
    flags: u8,
    did: u8,
    payload: Vec<u8>,
    /// Device tick count when it was drained.
    tick: u64,
}

struct Bench {
    dev: Device<Flash, Isb>,
    now: u64,
    ticks: u64,
    reader: Decoder<4096>,
    /// Every byte the device sent, for the NMEA reply checks.
    raw: Vec<u8>,
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

fn set(did: u8, offset: u16, data: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 512];
    let n = message::encode_set(did, offset, data, &mut out).unwrap();
    out[..n].to_vec()
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
            reader: Decoder::new(),
            raw: Vec::new(),
        }
    }

    fn power_cycle(self) -> Self {
        let flash = self.dev.into_flash();
        Self::with_flash(flash)
    }

    fn send(&mut self, bytes: &[u8]) -> Vec<Pkt> {
        self.dev.on_rx(bytes, Instant(self.now));
        self.drain()
    }

    fn drain(&mut self) -> Vec<Pkt> {
        let mut buf = [0u8; 4096];
        let mut out = Vec::new();
        loop {
            let n = self.dev.poll_tx(&mut buf);
            while self.dev.poll_event().is_some() {}
            if n == 0 {
                break;
            }
            self.raw.extend_from_slice(&buf[..n]);
            let mut input = &buf[..n];
            while let Some(p) = self.reader.next_packet(&mut input) {
                out.push(Pkt {
                    flags: p.flags,
                    did: p.did,
                    payload: p.payload.to_vec(),
                    tick: self.ticks,
                });
            }
        }
        out
    }

    fn run_ticks(&mut self, n: u64) -> Vec<Pkt> {
        let period = self.dev.tick_period_ns();
        let mut out = Vec::new();
        for _ in 0..n {
            self.ticks += 1;
            self.now = self.ticks * period;
            self.dev.on_tick(Instant(self.now));
            out.extend(self.drain());
        }
        out
    }

    fn get_once(&mut self, did: u8) -> Vec<u8> {
        let r = self.send(&get(did, 0));
        assert_eq!(r.len(), 1, "{r:?}");
        assert_eq!((r[0].flags, r[0].did), (4, did));
        r[0].payload.clone()
    }

    fn sys_params(&mut self) -> SysParams {
        let p = self.get_once(did::SYS_PARAMS);
        SysParams::decode(&p.try_into().unwrap())
    }

    fn flash_config(&mut self) -> Vec<u8> {
        self.get_once(did::FLASH_CONFIG)
    }
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}

/// The vendor command-line tool's connection sequence as captured
/// (`docs/protocol-facts.md` "ISB"): `$INFO` with a stray footer, GET
/// DEV_INFO twice, SYS_PARAMS and FLASH_CONFIG with the checksums in step,
/// GET 121 and 123 unanswered, `$STPC`, bootloader probes ignored, DEV_INFO
/// every 2 s — every reply exact and at once.
#[test]
fn the_vendor_tools_connection_sequence() {
    let mut b = Bench::new();
    assert!(b.send(b"$INFO*0E\r\n*56\r\n").is_empty());
    let info = String::from_utf8(b.raw.clone()).unwrap();
    assert!(info.starts_with("$INFO,"), "{info}");
    assert!(info.ends_with("\r\n"), "{info}");
    let star = info.rfind('*').unwrap();
    let sum = u8::from_str_radix(&info[star + 1..star + 3], 16).unwrap();
    assert_eq!(info[1..star].bytes().fold(0, |a, c| a ^ c), sum, "{info}");
    assert!(info.contains(",10000011,"), "serial from the seed: {info}");

    let vector = hex("ef 49 03 00 08 00 01 00 00 00 00 00 00 00 44 43");
    for _ in 0..2 {
        let r = b.send(&vector);
        assert_eq!(r.len(), 1);
        // Whole, at offset 0, without the offset flag.
        assert_eq!((r[0].flags, r[0].did, r[0].payload.len()), (0x04, 1, 84));
        let d = DevInfo::decode(&r[0].payload.clone().try_into().unwrap());
        assert!(d.accepted_by_sdk(), "{d:?}");
        assert_eq!(d.hardware_type, dev_info::HARDWARE_TYPE_IMX);
        assert_eq!(d.protocol_ver, [2, 1, 0, 0]);
        // The IMX-5 firmware released with SDK 2.7.1, not the protocol.
        assert_eq!(d.firmware_ver, [2, 7, 1, 0]);
        assert_eq!(d.serial_number, 10_000_011);
    }
    for _ in 0..2 {
        let sp = b.sys_params();
        let fc = b.flash_config();
        assert_eq!(fc.len(), 288);
        assert_eq!(sp.flash_cfg_checksum, u32_at(&fc, 4));
        assert_ne!(sp.flash_cfg_checksum, 0xFFFF_FFFF);
    }
    assert!(b.send(&get(121, 0)).is_empty());
    assert!(b.send(&get(123, 0)).is_empty());
    assert!(b.send(b"$STPC*14\r\n").is_empty());
    // Bootloader probes and an Intel-HEX line: ignored, never echoed.
    let before = b.raw.len();
    assert!(b
        .send(b"UUUUUUUUUU\n\n\n\n\n:020000041000EA\r\n")
        .is_empty());
    assert_eq!(b.raw.len(), before);
    // DEV_INFO every 2000 ms: one now, then one every 4000 ticks at 2 kHz.
    let r = b.send(&get(did::DEV_INFO, 2000));
    assert_eq!(r.len(), 1);
    let r = b.run_ticks(12_000);
    let ticks: Vec<u64> = r.iter().map(|p| p.tick).collect();
    assert_eq!(ticks, [4000, 8000, 12_000]);
    // The tool re-sends its GET every second: no second stream, no extra
    // packet, the phase kept.
    b.send(&get(did::DEV_INFO, 2000));
    b.run_ticks(2000);
    b.send(&get(did::DEV_INFO, 2000));
    let r = b.run_ticks(2000);
    assert_eq!(r.iter().map(|p| p.tick).collect::<Vec<_>>(), [16_000]);
}

/// IMU with period multiple 1 streams every `startupNavDtMs` (4 ms by
/// default): 250 packets a second, time stepping by exactly 4 ms, a unit
/// at rest reading −g on its down axis (forward-right-down body frame).
#[test]
fn imu_streams_every_nav_period_with_exact_time() {
    let mut b = Bench::new();
    b.run_ticks(100);
    let r = b.send(&hex("ef 49 03 00 08 00 3a 00 00 00 00 00 01 00 7e 0d"));
    assert_eq!(r.len(), 1, "one packet at once");
    // Whole, without the offset flag: the last whole navigation period,
    // which ended at tick 96 (on the 4 ms grid).
    assert_eq!(
        (r[0].flags, r[0].did, r[0].payload.len()),
        (4, did::IMU, 36)
    );
    let imu = Imu::decode(&r[0].payload.clone().try_into().unwrap());
    assert_eq!(imu.time, 0.048);
    assert!((imu.acc[2] + 9.81).abs() < 0.1, "{:?}", imu.acc);
    let r = b.run_ticks(2000);
    assert_eq!(r.len(), 250);
    let imus: Vec<Imu> = r
        .iter()
        .map(|p| {
            assert_eq!((p.flags, p.did), (0x04, did::IMU));
            Imu::decode(&p.payload.clone().try_into().unwrap())
        })
        .collect();
    for (k, (p, imu)) in r.iter().zip(&imus).enumerate() {
        // On the grid: 104, 112, …
        assert_eq!(p.tick, 96 + 8 * (k as u64 + 1));
        assert_eq!(imu.time, (p.tick * 500_000) as f64 / 1e9, "{k}");
        assert_eq!(imu.status, imu_status::ALL_OK);
        assert!((imu.acc[2] + 9.81).abs() < 0.05, "{:?}", imu.acc);
        assert!(imu.acc[0].abs() < 0.05 && imu.acc[1].abs() < 0.05);
        assert!(imu.pqr.iter().all(|w| w.abs() < 0.01), "{:?}", imu.pqr);
    }
    // STOP_DID_BROADCAST of IMU: no reply, no more IMU.
    assert!(b.send(&hex("ef 49 07 3a 00 00 79 d1")).is_empty());
    assert!(b.run_ticks(100).is_empty());
}

/// PIMU with period multiple 2: Δθ and Δv over exactly 8 ms (dt 0.008) in
/// every packet; under a constant rotation of 90 °/s about the unit's z
/// (up) axis the down-axis Δθ is −90 °/s × dt (errors off).
#[test]
fn pimu_integrates_exactly_its_period() {
    let mut b = Bench::new();
    *b.dev.chain_mut().errors_mut() = imu_emu::sensor::ErrorModel::default();
    b.dev.chain_mut().set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [0.0, 0.0, 90.0],
    });
    b.run_ticks(10);
    // The reply at once covers the last whole navigation period (ticks
    // 0..8): dt = startupNavDtMs, time on the grid.
    let once = b.send(&get(did::PIMU, 2));
    let first = Pimu::decode(&once[0].payload.clone().try_into().unwrap());
    assert_eq!((first.dt, first.time), (0.004, 0.004));
    let r = b.run_ticks(4000);
    assert_eq!(r.len(), 250);
    let mut total = 0.0f64;
    for (k, p) in r.iter().enumerate() {
        // The stream starts where the reply ended (tick 8): 24, 40, …
        assert_eq!(p.tick, 8 + 16 * (k as u64 + 1));
        let pimu = Pimu::decode(&p.payload.clone().try_into().unwrap());
        assert_eq!(pimu.dt, 0.008, "{k}");
        assert_eq!(pimu.time, (p.tick * 500_000) as f64 / 1e9);
        // 90 °/s plus the Earth rate's vertical part (about 1e-4 rad/s).
        let want = -(90f64.to_radians() * 0.008);
        assert!(
            (f64::from(pimu.theta[2]) - want).abs() < 2e-6,
            "{k}: {:?}",
            pimu.theta
        );
        total += f64::from(pimu.theta[2]);
        // Δv: −g × dt on the down axis.
        assert!((f64::from(pimu.vel[2]) + 9.8106 * 0.008).abs() < 2e-4);
    }
    // Windows tile time: 2 s of rotation in all.
    assert!((total + 90f64.to_radians() * 2.0).abs() < 5e-4, "{total}");
}

/// FLASH_CONFIG written with an offset: the ACK echoes flags, DID, size and
/// offset; the checksum is recomputed and SYS_PARAMS follows it; "flash
/// write pending" until the next tick, "system reset required" until a
/// power cycle, which applies the new period.
#[test]
fn flash_config_set_read_back_persist_and_apply_after_reset() {
    let mut b = Bench::new();
    let r = b.send(&set(
        did::FLASH_CONFIG,
        flash::STARTUP_NAV_DT_MS as u16,
        &8u32.to_le_bytes(),
    ));
    assert_eq!(r.len(), 1);
    assert_eq!((r[0].flags, r[0].did), (0x01, 0));
    assert_eq!(
        r[0].payload,
        [0x25, 12, 0, 0, 12, 4, 0, flash::STARTUP_NAV_DT_MS as u8, 0]
    );
    let fc = b.flash_config();
    assert_eq!(u32_at(&fc, flash::STARTUP_NAV_DT_MS), 8);
    assert_eq!(u32_at(&fc, 4), flash::checksum(&fc));
    let sp = b.sys_params();
    assert_eq!(sp.flash_cfg_checksum, u32_at(&fc, 4));
    assert_ne!(sp.hdw_status & hdw_status::FLASH_WRITE_PENDING, 0);
    assert_ne!(sp.hdw_status & hdw_status::SYSTEM_RESET_REQUIRED, 0);
    assert_eq!(sp.nav_output_period_ms, 4, "applies after a reset");
    b.run_ticks(1);
    let sp = b.sys_params();
    assert_eq!(sp.hdw_status & hdw_status::FLASH_WRITE_PENDING, 0);
    // The vendor SDK vector: startupImuDtMs = 2 at offset 12.
    let r = b.send(&hex("ef 49 25 0c 06 00 0c 00 02 00 00 00 7d b5"));
    assert_eq!(r[0].payload, [0x25, 12, 0, 0, 12, 4, 0, 12, 0]);
    b.run_ticks(1);

    let mut b = b.power_cycle();
    let sp = b.sys_params();
    assert_eq!(sp.nav_output_period_ms, 8);
    assert_eq!(sp.imu_sample_period_ms, 2);
    assert_eq!(sp.hdw_status & hdw_status::SYSTEM_RESET_REQUIRED, 0);
    assert_eq!(sp.flash_cfg_checksum, u32_at(&b.flash_config(), 4));
    b.send(&get(did::IMU, 1));
    let r = b.run_ticks(160);
    assert_eq!(r.len(), 10, "every 8 ms");
}

/// Writes the SDK rules refuse: the read-only `size` word (NACK), a SET
/// leaving under 4 bytes of room (no reply), and DIDs ≥ 132 and 95 (NACK);
/// nothing changes.
#[test]
fn refused_sets_change_nothing() {
    let mut b = Bench::new();
    let before = b.flash_config();
    let r = b.send(&set(did::FLASH_CONFIG, 0, &[1, 2, 0, 0]));
    assert_eq!((r[0].flags & 0x0F, r[0].payload[4]), (2, did::FLASH_CONFIG));
    assert!(b.send(&set(did::FLASH_CONFIG, 286, &[1, 2])).is_empty());
    for d in [132u8, 95] {
        let r = b.send(&set(d, 0, &[1, 2, 3, 4]));
        assert_eq!(r[0].flags, 2, "DID {d}");
    }
    assert_eq!(b.flash_config(), before);
}

/// `$PERS` saves the running streams; after `$SRST` they resume unasked,
/// `$STPC` stops them, and they resume again after a power cycle.
#[test]
fn persistent_streams_resume_after_a_software_reset_and_a_power_cycle() {
    let mut b = Bench::new();
    b.send(&get(did::IMU, 1));
    b.send(&get(did::DEV_INFO, 2000));
    assert!(b.send(b"$PERS*14\r\n").is_empty());
    b.send(b"$SRST*06\r\n");
    b.run_ticks(1);
    assert_eq!(b.dev.personality().streams().collect::<Vec<_>>(), [58, 1]);
    let r = b.run_ticks(80);
    assert_eq!(r.iter().filter(|p| p.did == did::IMU).count(), 10);
    assert!(b.send(b"$STPC*14\r\n").is_empty());
    assert!(b.run_ticks(80).is_empty());
    let mut b = b.power_cycle();
    let r = b.run_ticks(80);
    assert_eq!(r.iter().filter(|p| p.did == did::IMU).count(), 10);
}

/// More streams running than the flash image has persistent slots
/// (`MAX_STREAMS`): `$PERS` saves the first ten, and they resume after a
/// reset (found by the `isb_device` fuzz target: the save indexed past its
/// buffer).
#[test]
fn persist_saves_the_first_ten_of_more_running_streams() {
    use imu_emu::isb::device::{MAX_RUNNING, MAX_STREAMS};
    let mut b = Bench::new();
    let dids: Vec<u8> = did::DATA_SETS
        .iter()
        .map(|d| d.did)
        .filter(|&d| d != did::FLASH_CONFIG && d != did::SYS_CMD && d != did::RMC)
        .collect();
    for &d in &dids {
        b.send(&get(d, 1000));
    }
    let running: Vec<u8> = b.dev.personality().streams().collect();
    assert!(running.len() > MAX_STREAMS && running.len() <= MAX_RUNNING);
    assert!(b.send(b"$PERS*14\r\n").is_empty());
    b.send(b"$SRST*06\r\n");
    b.run_ticks(1);
    let resumed: Vec<u8> = b.dev.personality().streams().collect();
    assert_eq!(resumed, running[..MAX_STREAMS]);
}

/// SYS_CMD: save persistent messages (the SDK's vector) and a software
/// reset, each only with `invCommand == !command`.
#[test]
fn system_commands_need_their_inverse() {
    let mut b = Bench::new();
    b.send(&get(did::PIMU, 1));
    let r = b.send(&hex("ef 49 05 07 08 00 01 00 00 00 fe ff ff ff 48 9a"));
    assert_eq!(r[0].flags, 1);
    let bad = SystemCommand {
        command: 99,
        inv_command: 99,
    };
    b.send(&set(did::SYS_CMD, 0, &bad.encode()));
    b.run_ticks(2);
    assert_eq!(b.dev.personality().streams().count(), 1, "no reset");
    b.send(&b"$STPB*15\r\n"[..]);
    b.send(&set(did::SYS_CMD, 0, &SystemCommand::new(99).encode()));
    b.run_ticks(1);
    assert_eq!(
        b.dev.personality().streams().collect::<Vec<_>>(),
        [did::PIMU],
        "the reset restarted the persistent PIMU"
    );
}

/// RMC: the bits start and stop the streams they stand for, read back, and
/// the page's PPD preset is ACKed as the SDK's vector shows; stop-all is
/// ACKed with the SDK's bytes.
#[test]
fn rmc_bits_and_stop_all() {
    let mut b = Bench::new();
    let on = Rmc {
        bits: rmc::BITS_IMU | rmc::BITS_PIMU,
        options: 0,
    };
    let r = b.send(&set(did::RMC, 0, &on.encode()));
    assert_eq!(r[0].flags, 1);
    let r = Rmc::decode(&b.get_once(did::RMC).try_into().unwrap());
    assert_eq!(r.bits, rmc::BITS_IMU | rmc::BITS_PIMU);
    // Started in the order of the data set table: PIMU, then IMU.
    let r = b.run_ticks(8);
    assert_eq!(r.iter().map(|p| p.did).collect::<Vec<_>>(), [3, 58]);
    let ppd = hex("ef 49 05 09 0c 00 e2 3c 35 01 90 00 00 c0 00 01 00 00 f7 b0");
    let r = b.send(&ppd);
    let ack = hex("ef 49 01 00 09 00 05 09 00 00 09 0c 00 00 00 65 41");
    assert_eq!(r[0].payload, ack[6..15]);
    let r = b.send(&hex("ef 49 06 00 00 00 3e 1f"));
    let ack = hex("ef 49 01 00 09 00 06 00 00 00 00 00 00 00 00 48 a5");
    assert_eq!(r[0].payload, ack[6..15]);
    assert!(b.run_ticks(40).is_empty());
}

/// GET replies: NACK for DID ≥ 132 and 95 (the SDK's bytes), silence for an
/// in-range DID not served, NACK for a GET whose payload is not 8 bytes,
/// and a partial GET answered with the offset flag.
#[test]
fn get_rules() {
    let mut b = Bench::new();
    let nack = hex("ef 49 02 00 09 00 03 00 00 00 00 00 00 00 00 46 97");
    for d in [132u16, 200, 95] {
        let req = GetRequest {
            did: d,
            size: 0,
            offset: 0,
            period: 0,
        };
        let mut out = [0u8; 32];
        let n = message::encode_get(&req, &mut out).unwrap();
        let r = b.send(&out[..n]);
        assert_eq!(r.len(), 1);
        assert_eq!(
            (r[0].flags, r[0].payload.clone()),
            (2, nack[6..15].to_vec())
        );
    }
    assert!(b.send(&get(14, 0)).is_empty(), "GPS2_POS: not served");
    let mut out = [0u8; 32];
    let n = packet::encode(3, 0, &[1, 0, 0, 0], &mut out).unwrap();
    assert_eq!(b.send(&out[..n])[0].flags, 2);
    let req = GetRequest {
        did: u16::from(did::FLASH_CONFIG),
        size: 8,
        offset: 12,
        period: 0,
    };
    let n = message::encode_get(&req, &mut out).unwrap();
    let r = b.send(&out[..n]);
    assert_eq!((r[0].flags, r[0].did), (0x24, did::FLASH_CONFIG));
    assert_eq!(r[0].payload, [12, 0, 1, 0, 0, 0, 4, 0, 0, 0]);
}

/// Malformed input (the ISB classes of the catalogue): a bad checksum, a
/// short header cut short, an oversize size field, an offset past the
/// struct, an unknown type — each gets its documented reaction, and the
/// next good packet is answered.
#[test]
fn malformed_packets_resync_on_the_next_good_one() {
    let mut b = Bench::new();
    let good = get(did::DEV_INFO, 0);
    let mut bad_sum = good.clone();
    *bad_sum.last_mut().unwrap() ^= 0xFF;
    let oversize = [0xEF, 0x49, 0x04, 0x01, 0xFF, 0xFF];
    let past = set(did::RMC, 40, &[1, 2, 3, 4]);
    let mut unknown = [0u8; 16];
    let n = packet::encode(0x0B, 1, &[], &mut unknown).unwrap();
    let cases: [&[u8]; 5] = [&bad_sum, &good[..4], &oversize, &past, &unknown[..n]];
    for junk in cases {
        let mut input = junk.to_vec();
        input.extend_from_slice(&good);
        let r = b.send(&input);
        // A header cut short swallows the next bytes until it fails its
        // checksum; the idle timeout then drops it.
        let r = if r.is_empty() {
            b.run_ticks(201);
            b.send(&good)
        } else {
            r
        };
        assert_eq!(r.len(), 1, "{junk:02x?}: {r:?}");
        assert_eq!(r[0].did, did::DEV_INFO, "{junk:02x?}");
    }
}

/// STROBE_IN_TIME: with its stream on, every rising EXTRIG edge sends one,
/// counting edges, time of week in ms since power-on.
#[test]
fn strobe_in_time_on_extrig_edges() {
    let mut b = Bench::new();
    b.send(&get(did::STROBE_IN_TIME, 1));
    b.run_ticks(2000);
    b.dev.on_pin(Pin::Extrig, Level::High, Instant(b.now));
    b.dev.on_pin(Pin::Extrig, Level::Low, Instant(b.now + 10));
    let r = b.drain();
    assert_eq!(r.len(), 1);
    let s = StrobeInTime::decode(&r[0].payload.clone().try_into().unwrap());
    assert_eq!((s.count, s.time_of_week_ms), (1, 1000));
    b.run_ticks(20);
    b.dev.on_pin(Pin::Extrig, Level::High, Instant(b.now));
    let s = StrobeInTime::decode(&b.drain()[0].payload.clone().try_into().unwrap());
    assert_eq!((s.count, s.time_of_week_ms), (2, 1010));
}

/// Saturation from the chain reaches the IMU status and SYS_PARAMS
/// hdwStatus, like the KERNEL's USW range bits.
#[test]
fn saturation_reaches_the_status_words() {
    let mut b = Bench::new();
    b.dev.chain_mut().set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        // Beyond the IMX-5's ±4000 °/s (the fixed-point build's truth
        // stops at ±4095 °/s, beyond it too).
        rate_dps: [5000.0, 0.0, 0.0],
    });
    b.send(&get(did::IMU, 1));
    let r = b.run_ticks(16);
    let imu = Imu::decode(&r[1].payload.clone().try_into().unwrap());
    assert_ne!(imu.status & imu_status::SATURATION_GYR, 0);
    let sp = b.sys_params();
    assert_ne!(sp.hdw_status & hdw_status::SATURATION_GYR, 0);
    assert_eq!(sys_params::SIZE, 64);
}

/// The IMX-5's ±4000 °/s in both builds (docs/sensors.md "Fixed point"):
/// spun at 3000 and 3900 °/s about each axis (errors off), the IMU's rate
/// and the PIMU's Δθ/dt read the rate; at 4500 °/s both read the range,
/// 4000 °/s, with the saturation bit, as the float build does.
#[test]
fn imu_and_pimu_read_up_to_4000_dps_and_saturate_beyond() {
    for axis in 0..3 {
        for dps in [3000.0f32, 3900.0, -3900.0, 4500.0] {
            let mut b = Bench::new();
            *b.dev.chain_mut().errors_mut() = imu_emu::sensor::ErrorModel::default();
            let mut rate_dps = [0.0; 3];
            rate_dps[axis] = dps;
            b.dev.chain_mut().set_motion(Motion::ConstantRotation {
                lat_deg: 45.0,
                heading_deg: 0.0,
                rate_dps,
            });
            b.run_ticks(400);
            let want = f64::from(dps.abs().min(4000.0));
            let sat = dps.abs() > 4000.0;
            let norm = |v: [f32; 3]| v.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt();
            let r = b.send(&get(did::IMU, 0));
            let imu = Imu::decode(&r[0].payload.clone().try_into().unwrap());
            let got = norm(imu.pqr).to_degrees();
            assert!((got - want).abs() < 0.05, "IMU, axis {axis}, {dps}: {got}");
            assert_eq!(imu.status & imu_status::SATURATION_GYR != 0, sat);
            let r = b.send(&get(did::PIMU, 0));
            let pimu = Pimu::decode(&r[0].payload.clone().try_into().unwrap());
            let got = norm(pimu.theta).to_degrees() / f64::from(pimu.dt);
            assert!((got - want).abs() < 0.05, "PIMU, axis {axis}, {dps}: {got}");
            assert_eq!(pimu.status & imu_status::SATURATION_GYR != 0, sat);
        }
    }
}

/// The chain's injected faults reach the ISB status words: a sensor
/// communication failure clears the IMU's axis-OK bits and raises the
/// critical-fault bit of hdwStatus; over-temperature sets its bit.
#[test]
fn injected_faults_reach_the_status_words() {
    let mut b = Bench::new();
    b.dev.chain_mut().faults_mut().sensor_comm = true;
    b.dev.chain_mut().faults_mut().temperature_c = Some(99.0);
    b.run_ticks(1);
    let imu = Imu::decode(&b.get_once(did::IMU).try_into().unwrap());
    assert_eq!(imu.status & imu_status::ALL_OK, 0);
    let sp = b.sys_params();
    assert_ne!(sp.hdw_status & hdw_status::FAULT_SYS_CRITICAL, 0);
    assert_ne!(sp.hdw_status & hdw_status::ERR_TEMPERATURE, 0);
    assert_eq!(sp.imu_temp, 99.0);
    *b.dev.chain_mut().faults_mut() = Default::default();
    b.run_ticks(1);
    let imu = Imu::decode(&b.get_once(did::IMU).try_into().unwrap());
    assert_eq!(imu.status, imu_status::ALL_OK);
}

/// BIT: writing a command runs the test at once; the result follows the
/// chain's gyro BIT fault.
#[test]
fn bit_runs_on_command() {
    use imu_emu::isb::sets::{bit, Bit};
    let mut b = Bench::new();
    let r = b.send(&set(did::BIT, 0, &[bit::CMD_BASIC_MOVING, 0, 0, 0]));
    assert_eq!(r[0].flags, 1);
    let res = Bit::decode(&b.get_once(did::BIT).try_into().unwrap());
    assert_eq!((res.state, res.last_command), (bit::STATE_DONE, 3));
    assert_eq!(res.hdw_bit_status, bit::HDW_PASSED_NO_GPS);
    assert_ne!(b.sys_params().hdw_status & hdw_status::BIT_PASSED, 0);
    b.dev.chain_mut().faults_mut().gyro_bit = true;
    // A write of the command byte alone (the others are the result,
    // read-only: a SET changing them would be refused).
    let r = b.send(&set(did::BIT, 0, &[bit::CMD_FULL_STATIONARY]));
    assert_eq!(r[0].flags, 1);
    let res = Bit::decode(&b.get_once(did::BIT).try_into().unwrap());
    assert_eq!(res.hdw_bit_status, bit::HDW_FAULT_NOISE_PQR);
    assert_eq!(
        b.sys_params().hdw_status & hdw_status::BIT_MASK,
        hdw_status::BIT_FAILED
    );
}

/// The line starts at `ser0BaudRate` (921 600 by default) and follows a
/// new value after a software reset, not before.
#[test]
fn the_line_follows_ser0_baud_rate_after_a_reset() {
    let mut b = Bench::new();
    assert_eq!(b.dev.line_rate(), 921_600);
    b.send(&set(
        did::FLASH_CONFIG,
        flash::SER0_BAUD_RATE as u16,
        &230_400u32.to_le_bytes(),
    ));
    b.run_ticks(2);
    assert_eq!(b.dev.line_rate(), 921_600, "applies after a reset");
    assert_ne!(
        b.sys_params().hdw_status & hdw_status::SYSTEM_RESET_REQUIRED,
        0
    );
    b.send(b"$SRST*06\r\n");
    b.run_ticks(1);
    assert_eq!(b.dev.line_rate(), 230_400);
    assert_eq!(
        b.sys_params().hdw_status & hdw_status::SYSTEM_RESET_REQUIRED,
        0
    );
}

/// A FLASH_CONFIG write and a software reset in one write (both within
/// one tick, as a client sends them back to back, or as a host that fell
/// behind reads them): the acknowledged write is saved before the reset,
/// not lost with the RAM copy the reset discards — by `$SRST` and by
/// SYS_CMD alike, and it survives a power cycle.
#[test]
fn a_flash_config_write_and_a_reset_in_one_write_keep_the_write() {
    let resets = [
        b"$SRST*06\r\n".to_vec(),
        set(
            did::SYS_CMD,
            0,
            &SystemCommand::new(sys_cmd::SOFTWARE_RESET).encode(),
        ),
    ];
    for reset in resets {
        let mut b = Bench::new();
        let mut bytes = set(
            did::FLASH_CONFIG,
            flash::SER0_BAUD_RATE as u16,
            &230_400u32.to_le_bytes(),
        );
        bytes.extend_from_slice(&reset);
        b.send(&bytes);
        b.run_ticks(1);
        assert_eq!(b.dev.line_rate(), 230_400);
        let b = b.power_cycle();
        assert_eq!(b.dev.line_rate(), 230_400, "saved");
    }
}

/// IMU_RAW streams every `startupImuDtMs` (1 ms by default) multiple.
#[test]
fn imu_raw_streams_every_imu_period() {
    let mut b = Bench::new();
    b.send(&get(did::IMU_RAW, 3));
    let r = b.run_ticks(600);
    assert_eq!(r.len(), 100, "every 3 ms");
    assert!(r
        .iter()
        .all(|p| p.did == did::IMU_RAW && p.payload.len() == 36));
}

/// FLASH_CONFIG's `key` names the defaults it was made from: one written
/// with another key is replaced by the factory defaults at the next boot
/// (docs/isb-data-sets.md), with the persistent streams.
#[test]
fn a_changed_key_restores_the_factory_defaults_at_boot() {
    let mut b = Bench::new();
    b.send(&set(
        did::FLASH_CONFIG,
        flash::STARTUP_NAV_DT_MS as u16,
        &8u32.to_le_bytes(),
    ));
    b.send(&set(
        did::FLASH_CONFIG,
        flash::KEY as u16,
        &7u32.to_le_bytes(),
    ));
    b.run_ticks(1);
    assert_eq!(u32_at(&b.flash_config(), flash::KEY), 7);
    let mut b = b.power_cycle();
    let fc = b.flash_config();
    assert_eq!(u32_at(&fc, flash::KEY), flash::FACTORY_KEY);
    assert_eq!(u32_at(&fc, flash::STARTUP_NAV_DT_MS), 4);
}

/// The vendor tool's `-factoryReset`: SYS_CMD 1122334455 (unlock) then
/// 1357924680 back to back restores the FLASH_CONFIG defaults, saves them
/// and resets; without the unlock right before it, it does nothing.
#[test]
fn the_factory_reset_pair_restores_the_defaults_and_resets() {
    let mut b = Bench::new();
    let factory = b.flash_config();
    b.send(&set(
        did::FLASH_CONFIG,
        flash::STARTUP_NAV_DT_MS as u16,
        &8u32.to_le_bytes(),
    ));
    b.run_ticks(1);
    let changed = b.flash_config();
    assert_ne!(changed, factory);
    // The factory reset alone, or with another command between: nothing.
    for code in [
        sys_cmd::MANF_FACTORY_RESET,
        sys_cmd::MANF_UNLOCK,
        sys_cmd::ZERO_MOTION,
        sys_cmd::MANF_FACTORY_RESET,
    ] {
        b.send(&set(did::SYS_CMD, 0, &SystemCommand::new(code).encode()));
    }
    b.run_ticks(2);
    assert_eq!(b.flash_config(), changed);
    // The pair as the tool sends it ({1122334455, 3172632840} then
    // {1357924680, 2937042615}), back to back: each ACKed, then the reset.
    b.send(&get(did::IMU, 1));
    let both = hex("ef 49 05 07 08 00 f7 76 e5 42 08 89 1a bd 48 e6 \
         ef 49 05 07 08 00 48 49 f0 50 b7 b6 0f af 48 da");
    let r = b.send(&both);
    assert_eq!(r.iter().filter(|p| p.flags == 1).count(), 2, "{r:?}");
    b.run_ticks(1);
    assert_eq!(b.flash_config(), factory, "defaults in RAM");
    assert!(b.dev.personality().streams().next().is_none(), "it reset");
    let mut b = b.power_cycle();
    assert_eq!(b.flash_config(), factory, "and in flash");
}

// ---- navigation (docs/isb.md "Navigation") -------------------------------

fn ins2_of(p: &Pkt) -> Ins2 {
    Ins2::decode(&p.payload.clone().try_into().unwrap())
}

/// Element by element within `tol`.
fn close(a: &[f64], b: &[f64], tol: f64) {
    assert!(
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < tol),
        "{a:?} vs {b:?}"
    );
}

fn of_did(r: &[Pkt], d: u8) -> Vec<Pkt> {
    r.iter().filter(|p| p.did == d).cloned().collect()
}

/// After power-on the INS aligns (5 s), runs as an AHRS until the
/// receiver's cold-start fix (30 s), then navigates (the SDK's healthy
/// word at rest, 0x200 added on the outputs of a GNSS epoch): insStatus through
/// those phases, INS_2 every 4 ms and GPS1_POS every 200 ms by their own
/// time fields, GPS time once known (week 2399 for the default epoch),
/// `towOffset` tying the IMU's time since boot to the time of week.
#[test]
fn ins_phases_gps_time_and_periods() {
    let mut b = Bench::new();
    b.send(&get(did::INS_2, 1));
    b.send(&get(did::GPS1_POS, 1));
    let r = b.run_ticks(2000);
    let ins = of_did(&r, did::INS_2);
    assert_eq!(ins.len(), 250);
    let first = ins2_of(&ins[0]);
    assert_eq!(ins_status::solution(first.header.ins_status), 1, "aligning");
    assert_eq!((first.header.week, first.qn2b), (0, [1.0, 0.0, 0.0, 0.0]));
    // Before GPS time: time since boot.
    assert_eq!(first.header.time_of_week, ins[0].tick as f64 / 2000.0);
    let r = b.run_ticks(10_000);
    let s = ins2_of(of_did(&r, did::INS_2).last().unwrap())
        .header
        .ins_status;
    assert_eq!(ins_status::solution(s), ins_status::SOLUTION_AHRS);
    assert_eq!(s & ins_status::NAV_MODE, 0);
    let r = b.run_ticks(50_000);
    let gps = of_did(&r, did::GPS1_POS);
    let fixes: Vec<GpsPos> = gps
        .iter()
        .map(|p| GpsPos::decode(&p.payload.clone().try_into().unwrap()))
        .filter(|g| g.status != 0)
        .collect();
    assert!(!fixes.is_empty());
    for w in fixes.windows(2) {
        assert_eq!(w[1].time_of_week_ms - w[0].time_of_week_ms, 200);
        assert_eq!(w[1].time_of_week_ms % 200, 0);
    }
    let g = fixes.last().unwrap();
    assert_eq!(g.status, 0x1001_030C);
    assert_eq!((g.week, g.leap_s, g.sats_used), (2399, 18, 12));
    let ins = of_did(&r, did::INS_2);
    let last = ins2_of(ins.last().unwrap());
    assert_eq!(
        last.header.ins_status & !ins_status::GPS_UPDATE_IN_SOLUTION,
        0x0103_5970,
        "{:#x}",
        last.header.ins_status
    );
    assert_eq!(last.header.week, 2399);
    let since_boot = ins.last().unwrap().tick as f64 / 2000.0;
    assert!((last.header.time_of_week - (g.tow_offset + since_boot)).abs() < 1e-6);
    for w in ins.windows(2) {
        let (a, c) = (ins2_of(&w[0]), ins2_of(&w[1]));
        if a.header.week == c.header.week && a.header.week != 0 {
            assert!((c.header.time_of_week - a.header.time_of_week - 0.004).abs() < 1e-6);
        }
    }
    // SYS_PARAMS carries the same words.
    let sp = b.sys_params();
    assert_eq!(
        sp.ins_status & !ins_status::GPS_UPDATE_IN_SOLUTION,
        0x0103_5970
    );
    assert_ne!(sp.hdw_status & hdw_nav::GPS_TIME_OF_WEEK_VALID, 0);
}

/// INS_1's NED offset agrees with its LLA and `refLla`; INS_4's ECEF with
/// INS_2's LLA; qe2b with qe2n ⊗ qn2b; GPS1_POS with the INS within the
/// stated errors (σ 1 m / 1.5 m receiver, 0.7 m / 1 m INS).
#[test]
fn the_navigation_data_sets_agree() {
    let mut b = Bench::new();
    // 0.1° south and east of the built-in site (Newlyn).
    let site_lat = f64::from(imu_emu::sensor::motion::DEFAULT_LATITUDE_DEG);
    let reference = [
        site_lat - 0.1,
        imu_emu::vehicle::DEFAULT_LONGITUDE_DEG + 0.1,
        40.0,
    ];
    let mut ref_lla = Vec::new();
    for v in reference {
        ref_lla.extend_from_slice(&v.to_le_bytes());
    }
    let r = b.send(&set(did::FLASH_CONFIG, flash::REF_LLA as u16, &ref_lla));
    assert_eq!(r[0].flags, 1);
    b.run_ticks(62_000);
    let one = |b: &mut Bench, d| b.get_once(d);
    let i1 = Ins1::decode(&one(&mut b, did::INS_1).try_into().unwrap());
    let i2 = Ins2::decode(&one(&mut b, did::INS_2).try_into().unwrap());
    let i4 = Ins4::decode(&one(&mut b, did::INS_4).try_into().unwrap());
    let g = GpsPos::decode(&one(&mut b, did::GPS1_POS).try_into().unwrap());
    let want = nav::ned_from_ref(&i1.lla, &reference);
    close(&i1.ned.map(f64::from), &want, 0.01);
    assert!((f64::from(i1.ned[0]) - 0.1f64.to_radians() * 6_366_707.019_5).abs() < 5.0);
    assert_eq!(i1.lla, i2.lla);
    close(&i4.ecef, &nav::ecef_of(&i2.lla), 1e-6);
    let q = imu_emu::math::double::quat_mul(
        &nav::quat_e2n(i2.lla[0], i2.lla[1]),
        &i2.qn2b.map(f64::from),
    );
    close(&i4.qe2b.map(f64::from), &q, 1e-6);
    // Euler of INS_1 = the quaternion of INS_2.
    let e = imu_emu::math::double::euler_from_quat(&i2.qn2b.map(f64::from));
    close(&i1.theta.map(f64::from), &e, 1e-5);
    // GPS vs INS: within 4σ of the two errors combined.
    let d = nav::ned_from_ref(&g.lla, &i2.lla);
    assert!(d[0].hypot(d[1]) < 4.0 * 1.22 * 2f64.sqrt(), "{d:?}");
    assert!(d[2].abs() < 4.0 * 1.8, "{d:?}");
    assert_eq!(g.ecef, nav::ecef_of(&g.lla));
    // The truth: the built-in site, level; heading error ≤ 4σ (0.3°).
    assert!((i2.lla[0] - site_lat).abs() < 1e-4);
}

/// `fault gps off` (Isb::set_nav_faults): the fix drops, insStatus says
/// dead reckoning (fix 0, GPS aiding clear) while the filter integrates the
/// unit's own IMU: its position σ (INL2_NED_SIGMA) grows, and once it is
/// no longer fine the solution reads "high variance"; once the fix is back
/// the filter converges (σ back under a metre, the error with it) and the
/// status is NAV again. Faults outlast a reset.
#[test]
fn a_gps_outage_and_its_recovery() {
    use imu_emu::isb::nav_sets::Inl2NedSigma;
    let mut b = Bench::new();
    b.run_ticks(64_000);
    assert!(b.dev.personality().nav().has_fix());
    let sigma = |b: &mut Bench| {
        let s = Inl2NedSigma::decode(&b.get_once(did::INL2_NED_SIGMA).try_into().unwrap());
        f64::from(s.std_pos_ned[0].max(s.std_pos_ned[1]))
    };
    let error = |b: &mut Bench| {
        let i = Ins2::decode(&b.get_once(did::INS_2).try_into().unwrap());
        let t = nav::truth_of(b.dev.chain());
        let d = nav::ned_from_ref(&i.lla, &[t.lat_deg, t.lon_deg, t.h_m]);
        d[0].hypot(d[1])
    };
    let aided = sigma(&mut b);
    assert!(aided < 1.0, "{aided}");
    b.dev.personality_mut().set_nav_faults(NavFaults {
        gps_off: true,
        ..NavFaults::default()
    });
    b.run_ticks(4000);
    let sp = b.sys_params();
    assert!(
        ins_status::dead_reckoning(sp.ins_status),
        "{:#x}",
        sp.ins_status
    );
    assert_eq!(sp.ins_status & ins_status::GPS_NAV_FIX_MASK, 0);
    assert_eq!(sp.hdw_status & hdw_nav::GPS_SATELLITE_RX_VALID, 0);
    let g = GpsPos::decode(&b.get_once(did::GPS1_POS).try_into().unwrap());
    assert_eq!(g.status, 0);
    let s2 = sigma(&mut b);
    let mut high_at = None;
    for k in 0..60 {
        b.run_ticks(2000);
        let sp = b.sys_params();
        if ins_status::solution(sp.ins_status) == 4 && high_at.is_none() {
            high_at = Some(k);
        }
    }
    let s62 = sigma(&mut b);
    let e62 = error(&mut b);
    eprintln!("σ {aided} → {s2} → {s62}; error {e62}; high variance after {high_at:?} s");
    assert!(s62 > 5.0 && s62 > 10.0 * s2, "{s2} {s62}");
    assert!(high_at.is_some(), "high variance once σ > 5 m");
    assert!(
        e62 < 3.0 * s62,
        "the error within the filter's σ: {e62} vs {s62}"
    );
    b.dev.personality_mut().set_nav_faults(NavFaults::default());
    b.run_ticks(40_000);
    let sp = b.sys_params();
    assert_eq!(
        sp.ins_status & !ins_status::GPS_UPDATE_IN_SOLUTION,
        0x0103_5970,
        "{:#x}",
        sp.ins_status
    );
    assert!(sigma(&mut b) < 1.0);
    let back = error(&mut b);
    assert!(back < 4.0, "{back}");
}

/// GPS1_SAT every 1 s by its own `timeOfWeekMs` (on the receiver's
/// 200 ms epochs): no satellites before the cold-start fix, then the 12
/// GPS1_POS counts as used (numSats = satsUsed, mean C/N0 = cnoMean, each
/// above 10° elevation, "used in solution"), the same constellation at
/// every epoch; none during `fault gps off`.
#[test]
fn gps1_sat_follows_the_fix() {
    let mut b = Bench::new();
    b.send(&get(did::GPS1_SAT, 1));
    let r = b.run_ticks(64_000);
    let sats: Vec<GpsSat> = of_did(&r, did::GPS1_SAT)
        .iter()
        .map(|p| GpsSat::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert_eq!(sats.len(), 32);
    assert_eq!(sats[0].num_sats, 0, "no fix yet");
    assert!(sats[0].sat.iter().all(|s| *s == GpsSatSv::default()));
    let fixed: Vec<&GpsSat> = sats.iter().filter(|s| s.num_sats > 0).collect();
    assert!(fixed.len() >= 2, "{}", fixed.len());
    for w in fixed.windows(2) {
        assert_eq!(w[1].time_of_week_ms - w[0].time_of_week_ms, 1000);
        assert_eq!(w[1].time_of_week_ms % 200, 0);
        assert_eq!(w[1].sat, w[0].sat, "a fixed constellation");
    }
    let s = b.get_once(did::GPS1_SAT);
    let g = GpsPos::decode(&b.get_once(did::GPS1_POS).try_into().unwrap());
    let s = GpsSat::decode(&s.try_into().unwrap());
    assert_eq!(s.time_of_week_ms, g.time_of_week_ms);
    assert_eq!(s.num_sats, u32::from(g.sats_used));
    let used = &s.sat[..s.num_sats as usize];
    let mean = used.iter().map(|v| f32::from(v.cno)).sum::<f32>() / used.len() as f32;
    assert_eq!(mean, g.cno_mean);
    let mut azims: Vec<i16> = used.iter().map(|v| v.azim).collect();
    azims.sort_unstable();
    azims.dedup();
    assert_eq!(azims.len(), used.len());
    for v in used {
        // GPS, carrier locked (7), used in solution (0x8), healthy (0x10).
        assert_eq!((v.gnss_id, v.status), (1, 0x001F));
        assert_ne!(v.status & sat_status::USED_IN_SOLUTION, 0);
        assert!(v.elev > 10 && (-180..=180).contains(&v.azim), "{v:?}");
        assert!((f32::from(v.cno) - g.cno_mean).abs() <= 4.0, "{v:?}");
    }
    assert!(s.sat[used.len()..]
        .iter()
        .all(|v| *v == GpsSatSv::default()));
    b.dev.personality_mut().set_nav_faults(NavFaults {
        gps_off: true,
        ..NavFaults::default()
    });
    let r = b.run_ticks(4000);
    for p in of_did(&r, did::GPS1_SAT) {
        let s = GpsSat::decode(&p.payload.try_into().unwrap());
        assert_eq!(s.num_sats, 0);
        assert!(s.sat.iter().all(|v| *v == GpsSatSv::default()));
    }
    let s = GpsSat::decode(&b.get_once(did::GPS1_SAT).try_into().unwrap());
    assert_eq!(s.num_sats, 0);
}

/// MAGNETOMETER every 10 ms and BAROMETER every 8 ms by their time fields;
/// the field is the World Magnetic Model's at the site and the GPS date —
/// unit length, its declination and inclination the model's (mean of the
/// minute's samples, level and facing north) — the pressure the ISA's at
/// the site's MSL height (ellipsoid height − EGM96 undulation); a magnetic
/// disturbance (refused by the filter: interference, no magnetometer
/// aiding) and a barometer failure reach insStatus / hdwStatus.
#[test]
fn magnetometer_and_barometer() {
    let mut b = Bench::new();
    b.send(&get(did::MAGNETOMETER, 1));
    b.send(&get(did::BAROMETER, 1));
    let r = b.run_ticks(12_000);
    let mags: Vec<Magnetometer> = of_did(&r, did::MAGNETOMETER)
        .iter()
        .map(|p| Magnetometer::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    let baros: Vec<Barometer> = of_did(&r, did::BAROMETER)
        .iter()
        .map(|p| Barometer::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert_eq!((mags.len(), baros.len()), (600, 750));
    for w in mags.windows(2) {
        assert!((w[1].time - w[0].time - 0.010).abs() < 1e-9);
    }
    for w in baros.windows(2) {
        assert!((w[1].time - w[0].time - 0.008).abs() < 1e-9);
    }
    let m = mags.last().unwrap().mag.map(f64::from);
    let n = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
    assert!((n - 1.0).abs() < 0.01, "{m:?}");
    // Level, facing north: body forward, right, down are north, east, down.
    let mean = [0, 1, 2].map(|k| mags.iter().map(|s| f64::from(s.mag[k])).sum::<f64>() / 600.0);
    let t = nav::truth_of(b.dev.chain());
    // The default GPS clock starts 2026-01-01; the minute run is 2026.0.
    let (decl, incl) = (
        earth::declination_deg(t.lat_deg, t.lon_deg, t.h_m, 2026.0),
        earth::inclination_deg(t.lat_deg, t.lon_deg, t.h_m, 2026.0),
    );
    let got_decl = mean[1].atan2(mean[0]).to_degrees();
    let got_incl = mean[2].atan2(mean[0].hypot(mean[1])).to_degrees();
    assert!((got_decl - decl).abs() < 0.1, "{got_decl} vs WMM {decl}");
    assert!((got_incl - incl).abs() < 0.1, "{got_incl} vs WMM {incl}");
    // The site's MSL height: its ellipsoid height less the undulation.
    let msl = t.h_m - earth::geoid_undulation_m(t.lat_deg, t.lon_deg);
    let p = baros.last().unwrap();
    assert!(
        (f64::from(p.bar) - ins::isa_kpa(msl)).abs() < 0.01,
        "{p:?} at {msl} m MSL"
    );
    // mslBar is the SDK's baro2msl of the pressure (an exponential
    // atmosphere, which near sea level agrees with the ISA: the site's
    // 8.9 m MSL within the noise).
    let sdk = -8434.668 * (f64::from(p.bar) / 101.325).ln();
    assert!((f64::from(p.msl_bar) - sdk).abs() < 0.01, "{p:?}");
    assert!((sdk - msl).abs() < 1.0, "{sdk} vs {msl} m MSL");
    b.dev.personality_mut().set_nav_faults(NavFaults {
        mag_disturbed: true,
        baro_failed: true,
        ..NavFaults::default()
    });
    // The filter refuses the disturbed field at its next magnetometer
    // update (at the receiver's epochs, 200 ms): unlike the field learnt
    // in alignment.
    b.run_ticks(420);
    let sp = b.sys_params();
    assert_ne!(sp.ins_status & ins_status::MAG_INTERFERENCE_OR_BAD_CAL, 0);
    assert_eq!(sp.ins_status & ins_status::MAG_AIDING_HEADING, 0);
    assert_ne!(sp.hdw_status & hdw_nav::SATURATION_BARO, 0);
    let r = b.run_ticks(400);
    let frozen: Vec<f32> = of_did(&r, did::BAROMETER)
        .iter()
        .map(|p| Barometer::decode(&p.payload.clone().try_into().unwrap()).bar)
        .collect();
    assert!(frozen.windows(2).all(|w| w[0] == w[1]), "{frozen:?}");
}

/// The RMC presets of SDK 2.7.1: INS (INS_2 and GPS1_POS at their source
/// periods) and PPD (INS_2 every 100 ms, PIMU every 4 ms, MAGNETOMETER,
/// BAROMETER, GPS1_POS, GPS1_VEL at theirs); persistent with `$PERS`.
#[test]
fn rmc_presets_and_persistent_navigation_streams() {
    let mut b = Bench::new();
    let rmc_set = |b: &mut Bench, bits: u64| {
        let r = b.send(&set(did::RMC, 0, &Rmc { bits, options: 0 }.encode()));
        assert_eq!(r[0].flags, 1);
    };
    rmc_set(&mut b, rmc_nav::PRESET_INS);
    let r = b.run_ticks(2000);
    assert_eq!(of_did(&r, did::INS_2).len(), 250);
    assert_eq!(of_did(&r, did::GPS1_POS).len(), 5);
    rmc_set(&mut b, rmc_nav::PRESET_PPD);
    let r = b.run_ticks(2000);
    let count = |d| of_did(&r, d).len();
    assert_eq!(
        [
            count(did::INS_2),
            count(did::PIMU),
            count(did::MAGNETOMETER),
            count(did::BAROMETER),
            count(did::GPS1_POS),
            count(did::GPS1_VEL),
            count(did::IMU)
        ],
        [10, 250, 100, 125, 5, 5, 0]
    );
    b.send(b"$PERS*14\r\n");
    let mut b = b.power_cycle();
    let r = b.run_ticks(2000);
    assert_eq!(of_did(&r, did::INS_2).len(), 10);
    assert_eq!(of_did(&r, did::BAROMETER).len(), 125);
}

/// Bad input: writes to the read-only navigation sets are NACKed; an
/// absurd `refLla` or `startupGPSDtMs` is NACKed and changes nothing; a
/// GET window past the end gives the whole set.
#[test]
fn bad_navigation_input() {
    let mut b = Bench::new();
    let nav_dids = [
        did::INS_1,
        did::INS_2,
        did::INS_3,
        did::INS_4,
        did::GPS1_POS,
        did::GPS1_VEL,
        did::GPS1_SAT,
        did::MAGNETOMETER,
        did::BAROMETER,
        did::SYS_SENSORS,
        did::IMU_MAG,
        did::PIMU_MAG,
    ];
    for d in nav_dids {
        let size = did::lookup(u16::from(d)).unwrap().size;
        // Read-only: a SET changing bytes is NACKed, at any offset.
        for off in [0u16, 4, size - 4] {
            let r = b.send(&set(d, off, &[0xFF; 4]));
            assert_eq!(r[0].flags, 2, "DID {d} @{off}");
        }
        // A part: the offset flag and exactly those bytes; a window past
        // the end: the whole set without it.
        for (sz, off, flags, len) in [
            (4u16, 4u16, 0x24, 6),
            (size, 8, 4, size),
            (4, size, 4, size),
        ] {
            let req = GetRequest {
                did: u16::from(d),
                size: sz,
                offset: off,
                period: 0,
            };
            let mut out = [0u8; 64];
            let n = message::encode_get(&req, &mut out).unwrap();
            let r = b.send(&out[..n]);
            assert_eq!(
                (r[0].flags, r[0].payload.len()),
                (flags, usize::from(len)),
                "DID {d} size {sz} offset {off}"
            );
        }
    }
    let before = b.flash_config();
    for (off, v) in [
        (flash::REF_LLA, 91f64.to_le_bytes().to_vec()),
        (flash::REF_LLA + 16, f64::NAN.to_le_bytes().to_vec()),
        (flash::STARTUP_GPS_DT_MS, 50u32.to_le_bytes().to_vec()),
    ] {
        let r = b.send(&set(did::FLASH_CONFIG, off as u16, &v));
        assert_eq!(r[0].flags, 2, "offset {off}");
    }
    assert_eq!(b.flash_config(), before);
    let req = GetRequest {
        did: u16::from(did::INS_1),
        size: 200,
        offset: 70,
        period: 0,
    };
    let mut out = [0u8; 64];
    let n = message::encode_get(&req, &mut out).unwrap();
    let r = b.send(&out[..n]);
    assert_eq!((r[0].flags, r[0].payload.len()), (4, 80));
}

/// PIMU_MAG every 2 navigation periods: the PIMU part is the same window
/// PIMU gives (dt 8 ms, on the grid), the magnetometer part carries the
/// same time; IMU_MAG the same with an IMU; SYS_SENSORS at once with the
/// measurement at rest (−g down), the ISA pressure and a unit field; the
/// RMC bits of IMU_MAG and PIMU_MAG start them.
#[test]
fn imu_mag_pimu_mag_and_sys_sensors() {
    let mut b = Bench::new();
    b.run_ticks(10);
    b.send(&get(did::PIMU_MAG, 2));
    let r = b.run_ticks(400);
    let ps: Vec<PimuMag> = of_did(&r, did::PIMU_MAG)
        .iter()
        .map(|p| PimuMag::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert_eq!(ps.len(), 25);
    for (p, pkt) in ps.iter().zip(of_did(&r, did::PIMU_MAG)) {
        assert_eq!(p.pimu.dt, 0.008);
        assert_eq!(p.pimu.time, pkt.tick as f64 / 2000.0);
        assert_eq!(p.mag.time, p.pimu.time);
        assert!((p.pimu.vel[2] + 9.8106 * 0.008).abs() < 2e-3, "{p:?}");
    }
    let s = SysSensors::decode(&b.get_once(did::SYS_SENSORS).try_into().unwrap());
    assert!((s.acc[2] + 9.81).abs() < 0.1, "{s:?}");
    let t = nav::truth_of(b.dev.chain());
    let msl = t.h_m - earth::geoid_undulation_m(t.lat_deg, t.lon_deg);
    assert!((f64::from(s.bar) - ins::isa_kpa(msl)).abs() < 0.01);
    assert!((f64::from(s.msl_bar) + 8434.668 * (f64::from(s.bar) / 101.325).ln()).abs() < 0.01);
    let m = s.mag.map(f64::from);
    assert!(((m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt() - 1.0).abs() < 0.01);
    let r = b.send(&set(
        did::RMC,
        0,
        &Rmc {
            bits: rmc_nav::BITS_IMU_MAG,
            options: 0,
        }
        .encode(),
    ));
    assert_eq!(r[0].flags, 1);
    let r = b.run_ticks(80);
    let im = of_did(&r, did::IMU_MAG);
    assert_eq!(im.len(), 10);
    let i = ImuMag::decode(&im[0].payload.clone().try_into().unwrap());
    assert_eq!((i.imu.time, i.mag.time), (i.imu.time, i.imu.time));
    assert!((i.imu.acc[2] + 9.81).abs() < 0.1);
}

/// FLASH_CONFIG navigation fields take effect: `gps1AntOffset` 10 m up
/// (sensor z is down) raises GPS1_POS by 10 m against the INS; a yaw of
/// 90° in `insRotation` turns INS_1's yaw by 90°; a strobe after the fix
/// carries GPS week and time of week.
#[test]
fn navigation_flash_config_fields_take_effect() {
    let mut b = Bench::new();
    b.run_ticks(62_000);
    let yaw0 = Ins1::decode(&b.get_once(did::INS_1).try_into().unwrap()).theta[2];
    let mut ant = Vec::new();
    for v in [0f32, 0.0, -10.0] {
        ant.extend_from_slice(&v.to_le_bytes());
    }
    b.send(&set(did::FLASH_CONFIG, flash::GPS1_ANT_OFFSET as u16, &ant));
    let mut rot = Vec::new();
    for v in [0f32, 0.0, std::f32::consts::FRAC_PI_2] {
        rot.extend_from_slice(&v.to_le_bytes());
    }
    b.send(&set(did::FLASH_CONFIG, flash::INS_ROTATION as u16, &rot));
    b.run_ticks(1);
    let i1 = Ins1::decode(&b.get_once(did::INS_1).try_into().unwrap());
    let g = GpsPos::decode(&b.get_once(did::GPS1_POS).try_into().unwrap());
    let up = g.lla[2] - i1.lla[2];
    assert!((up - 10.0).abs() < 4.0 * 1.8, "{up}");
    let turned = (i1.theta[2] - yaw0).rem_euclid(std::f32::consts::TAU);
    assert!(
        (turned - std::f32::consts::FRAC_PI_2).abs() < 0.01,
        "{turned}"
    );
    b.send(&get(did::STROBE_IN_TIME, 1));
    b.dev.on_pin(Pin::Extrig, Level::High, Instant(b.now));
    let r = b.drain();
    let s = StrobeInTime::decode(&r[0].payload.clone().try_into().unwrap());
    assert_eq!(s.week, 2399);
    assert!(s.time_of_week_ms > 4 * 86_400_000);
}

/// An IMX-5 on a scripted vehicle (`imu_emu::vehicle`, the board's source
/// set before each tick as the host runner does): its IMU reads the
/// forward acceleration on its x axis (the IMX body frame is the
/// vehicle's, forward-right-down), and once navigating its INS_2 reports
/// the vehicle's position, heading and body velocity within the INS error
/// model's bounds.
#[test]
fn the_ins_reports_the_vehicle_it_rides_on() {
    use imu_emu::vehicle::{Manoeuvres, Script};
    let script = "start 45.5 7.25 300 90 10; hold 40; accel 2 5; hold 100";
    let mut m = Manoeuvres::new(Script::parse(script).unwrap());
    let mut b = Bench::new();
    let period = b.dev.tick_period_ns();
    let mut step = |b: &mut Bench, n: u64| {
        let mut out = Vec::new();
        for _ in 0..n {
            let t = (b.ticks + 1) as f64 * period as f64 * 1e-9;
            let s = m.at(t);
            b.dev.chain_mut().set_vehicle(s, s.truth());
            out.extend(b.run_ticks(1));
        }
        out
    };
    step(&mut b, 80_000); // 40 s: aligned, GPS fix, navigating
    b.send(&get(did::IMU, 1));
    let r = step(&mut b, 4_000); // 2 s into `accel 2 5`
    let imu: Vec<Imu> = of_did(&r, did::IMU)
        .iter()
        .map(|p| Imu::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    let last = imu.last().unwrap();
    // Forward: +2 m/s² on x; right: ~0; down: −g.
    assert!((f64::from(last.acc[0]) - 2.0).abs() < 0.05, "{last:?}");
    assert!(f64::from(last.acc[1]).abs() < 0.05, "{last:?}");
    assert!((f64::from(last.acc[2]) + 9.8).abs() < 0.05, "{last:?}");
    let i2 = Ins2::decode(&b.get_once(did::INS_2).try_into().unwrap());
    let truth = m.at(b.ticks as f64 * period as f64 * 1e-9);
    assert_eq!(
        i2.header.ins_status & ins_status::NAV_MODE,
        ins_status::NAV_MODE,
        "{:#x}",
        i2.header.ins_status
    );
    // Position within a few metres (σ 0.7 m / 1 m), body velocity along x.
    let d = nav::ned_from_ref(
        &i2.lla,
        &[
            truth.lat_rad.to_degrees(),
            truth.lon_rad.to_degrees(),
            truth.height_m,
        ],
    );
    assert!(d[0].hypot(d[1]) < 5.0 && d[2].abs() < 5.0, "{d:?}");
    let speed = (truth.vel_ned[0].powi(2) + truth.vel_ned[1].powi(2)).sqrt();
    assert!(
        (f64::from(i2.uvw[0]) - speed).abs() < 0.5,
        "{i2:?} vs {speed}"
    );
    assert!(f64::from(i2.uvw[1]).abs() < 0.5, "{i2:?}");
    // Heading east (90°) within a degree.
    let e = imu_emu::math::double::euler_from_quat(&i2.qn2b.map(f64::from));
    assert!((e[2].to_degrees() - 90.0).abs() < 1.0, "{e:?}");
}

/// The magnetometer reads the WMM2025 field where the vehicle is and when
/// the unit's GPS clock says: at 80° N 0° E (the report's first test
/// place, where the declination moves half a degree a year) on
/// 2029-07-02 12:00 UTC (2029.5), level and facing north, the mean of 4 s
/// of samples has the model's declination and inclination of that date,
/// not of the default 2026.
#[test]
fn the_magnetometer_reads_the_field_at_the_vehicle_and_the_gps_date() {
    use imu_emu::vehicle::{Manoeuvres, Script};
    let mut m = Manoeuvres::new(Script::parse("start 80 0 0 0 0; hold 100").unwrap());
    let mut b = Bench::new();
    // GPS time at device instant 0: 2029-07-02 12:00 UTC (+18 leap s).
    let unix_s: u64 = 1_877_688_000;
    b.dev
        .personality_mut()
        .set_gps_time((unix_s - imu_emu::time::GPS_EPOCH_UNIX_S + 18) * 1_000_000_000);
    let period = b.dev.tick_period_ns();
    b.send(&get(did::MAGNETOMETER, 1));
    let mut mags = Vec::new();
    for _ in 0..8_000 {
        let s = m.at((b.ticks + 1) as f64 * period as f64 * 1e-9);
        b.dev.chain_mut().set_vehicle(s, s.truth());
        for p in of_did(&b.run_ticks(1), did::MAGNETOMETER) {
            mags.push(Magnetometer::decode(&p.payload.clone().try_into().unwrap()));
        }
    }
    assert_eq!(mags.len(), 400);
    let n = mags.len() as f64;
    let mean = [0, 1, 2].map(|k| mags.iter().map(|s| f64::from(s.mag[k])).sum::<f64>() / n);
    let decl = mean[1].atan2(mean[0]).to_degrees();
    let incl = mean[2].atan2(mean[0].hypot(mean[1])).to_degrees();
    let year = 2029.5;
    let (want_d, want_i) = (
        earth::declination_deg(80.0, 0.0, 0.0, year),
        earth::inclination_deg(80.0, 0.0, 0.0, year),
    );
    assert!((decl - want_d).abs() < 0.25, "D {decl} vs WMM {want_d}");
    assert!((incl - want_i).abs() < 0.05, "I {incl} vs WMM {want_i}");
    // The default date's declination is more than a degree away.
    let d_2026 = earth::declination_deg(80.0, 0.0, 0.0, 2026.0);
    assert!((want_d - d_2026).abs() > 1.0, "{want_d} vs {d_2026}");
}

// ----- SYS_FAULT, GPS1_VERSION, MAG_CAL, GPS1_SIG, IMU3_RAW -----

use imu_emu::isb::aux_sets::{
    gps_sig, gps_version, imu3, mag_cal, mag_cal_state, sys_fault, GpsSig, GpsSigSv, GpsVersion,
    Imu3, MagCal,
};

/// A NUL-padded string field as text.
fn text(b: &[u8]) -> &str {
    let n = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    std::str::from_utf8(&b[..n]).unwrap()
}

/// SYS_FAULT: one whole 32-byte `system_fault_t`, all zeros on a unit
/// that never faulted; read-only (a SET changing it is refused).
#[test]
fn sys_fault_reads_a_healthy_unit() {
    let mut b = Bench::new();
    let p = b.get_once(did::SYS_FAULT);
    assert_eq!(p.len(), sys_fault::SIZE);
    assert_eq!(p.len(), 32);
    assert!(p.iter().all(|&x| x == 0), "{p:?}");
    let r = b.send(&set(did::SYS_FAULT, 0, &[1, 0, 0, 0]));
    assert_eq!((r[0].flags, r[0].payload[4]), (2, did::SYS_FAULT), "NACK");
    assert!(b.get_once(did::SYS_FAULT).iter().all(|&x| x == 0));
}

/// GPS1_VERSION: one whole 220-byte `gps_version_t`: swVersion[30] @0,
/// hwVersion[10] @30, six 30-byte extensions @40, NUL padded.
#[test]
fn gps1_version_strings() {
    let mut b = Bench::new();
    let p = b.get_once(did::GPS1_VERSION);
    assert_eq!(p.len(), 220);
    assert_eq!(gps_version::SIZE, 220);
    assert_eq!(text(&p[0..30]), "EXT CORE 1.00 (emulated)");
    assert_eq!(text(&p[30..40]), "00190000");
    let ext: Vec<&str> = (0..6).map(|k| text(&p[40 + 30 * k..70 + 30 * k])).collect();
    assert_eq!(
        ext,
        [
            "ROM BASE 0x118B2060",
            "FWVER=HPG 1.32",
            "PROTVER=27.31",
            "MOD=ZED-F9P",
            "GPS;GLO;GAL;BDS",
            "SBAS;QZSS"
        ]
    );
    let v = GpsVersion::decode(&p.try_into().unwrap());
    assert_eq!(&v.hw_version[..8], b"00190000");
}

fn mag_cal_now(b: &mut Bench) -> MagCal {
    let p = b.get_once(did::MAG_CAL);
    assert_eq!(p.len(), 12);
    MagCal::decode(&p.try_into().unwrap())
}

/// The unit turning at 36 °/s about its up (`[0, 0, 36]`) or right
/// (`[36, 0, 0]`) axis, or at rest.
fn turn(b: &mut Bench, rate_dps: [f32; 3]) {
    b.dev.chain_mut().set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps,
    });
}

/// `insStatus` MAG_RECALIBRATING and `hdwStatus` MAG_RECAL_COMPLETE now.
fn recal_bits(b: &mut Bench) -> (bool, bool) {
    let p = b.sys_params();
    (
        p.ins_status & 0x0040_0000 != 0,
        p.hdw_status & 0x0000_4000 != 0,
    )
}

/// MAG_CAL (12 B: state u32 @0, progress f32 @4, declination f32 @8): idle
/// reads state 0; the multi-axis command (cltool `-magRecal`) is ACKed and
/// starts a recalibration: state 200, `insStatus` MAG_RECALIBRATING, and a
/// progress that follows how far the field has turned in the body frame —
/// a unit at rest stays near 0 for 30 s, a whole turn in heading (10 s at
/// 36 °/s) covers one axis, a whole turn about a horizontal axis the
/// second: then state 201 at 100 %, MAG_RECALIBRATING cleared,
/// `hdwStatus` MAG_RECAL_COMPLETE raised. Single-axis needs the heading
/// turn only; abort (101) ends one; the declination is FLASH_CONFIG's
/// `magDeclination`; progress is read-only.
#[test]
fn mag_cal_recalibration_follows_the_turns_the_unit_makes() {
    let mut b = Bench::new();
    let m = mag_cal_now(&mut b);
    assert_eq!((m.state, m.progress, m.declination), (0, 0.0, 0.0));
    assert_eq!(recal_bits(&mut b), (false, false));
    // magDeclination 0.2 rad.
    let r = b.send(&set(
        did::FLASH_CONFIG,
        flash::MAG_DECLINATION as u16,
        &0.2f32.to_le_bytes(),
    ));
    assert_eq!(r[0].flags, 1, "ACK");
    let r = b.send(&set(
        did::MAG_CAL,
        0,
        &mag_cal_state::MULTI_AXIS.to_le_bytes(),
    ));
    assert_eq!((r[0].flags, r[0].payload[4]), (1, did::MAG_CAL), "ACK");
    let m = mag_cal_now(&mut b);
    assert_eq!((m.state, m.progress), (mag_cal_state::RECAL_RUNNING, 0.0));
    assert_eq!(m.declination, 0.2);
    assert_eq!(recal_bits(&mut b), (true, false));
    // 30 s at rest (2000 ticks a second): the field does not turn.
    b.run_ticks(60_000);
    let m = mag_cal_now(&mut b);
    assert_eq!(m.state, 200);
    assert!(m.progress > 0.0 && m.progress < 10.0, "{}", m.progress);
    // A whole turn in heading: one axis of two.
    turn(&mut b, [0.0, 0.0, 36.0]);
    b.run_ticks(22_000);
    let m = mag_cal_now(&mut b);
    assert_eq!(m.state, 200);
    assert!(m.progress > 50.0 && m.progress < 100.0, "{}", m.progress);
    assert_eq!(recal_bits(&mut b), (true, false));
    // A whole turn about a horizontal axis: done.
    turn(&mut b, [36.0, 0.0, 0.0]);
    b.run_ticks(22_000);
    let m = mag_cal_now(&mut b);
    assert_eq!(
        (m.state, m.progress),
        (mag_cal_state::RECAL_COMPLETE, 100.0)
    );
    assert_eq!(recal_bits(&mut b), (false, true));
    // progress is the device's.
    let r = b.send(&set(did::MAG_CAL, mag_cal::PROGRESS as u16, &[0; 8]));
    assert_eq!(r[0].flags, 2, "NACK");
    // Single-axis: the heading turn alone completes it.
    turn(&mut b, [0.0, 0.0, 0.0]);
    b.send(&set(
        did::MAG_CAL,
        0,
        &mag_cal_state::SINGLE_AXIS.to_le_bytes(),
    ));
    assert_eq!(mag_cal_now(&mut b).state, 200);
    assert_eq!(recal_bits(&mut b), (true, false));
    turn(&mut b, [0.0, 0.0, 36.0]);
    b.run_ticks(22_000);
    assert_eq!(mag_cal_now(&mut b).state, 201);
    // Abort ends a running one: nothing raised.
    b.send(&set(
        did::MAG_CAL,
        0,
        &mag_cal_state::SINGLE_AXIS.to_le_bytes(),
    ));
    b.send(&set(did::MAG_CAL, 0, &mag_cal_state::ABORT.to_le_bytes()));
    let m = mag_cal_now(&mut b);
    assert_eq!((m.state, m.progress), (mag_cal_state::DO_NOTHING, 0.0));
    assert_eq!(recal_bits(&mut b), (false, false));
}

/// GPS1_SIG (708 B: timeOfWeekMs, numSigs, 100 × 7-byte `gps_sig_sv_t`):
/// one L1 C/A signal (sigId 0) for each satellite GPS1_SAT lists, with
/// its constellation, number and C/N0, quality 7, healthy and used (5);
/// the same epoch; streamed every 1 s; none without a fix.
#[test]
fn gps1_sig_lists_the_signals_of_gps1_sat() {
    let mut b = Bench::new();
    let p = b.get_once(did::GPS1_SIG);
    assert_eq!(p.len(), 708);
    assert_eq!(le_u32(&p, gps_sig::NUM_SIGS), 0, "no fix yet");
    b.send(&get(did::GPS1_SIG, 1));
    let r = b.run_ticks(64_000);
    let sigs: Vec<GpsSig> = of_did(&r, did::GPS1_SIG)
        .iter()
        .map(|p| GpsSig::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert_eq!(sigs.len(), 32, "every 1 s");
    let fixed: Vec<&GpsSig> = sigs.iter().filter(|s| s.num_sigs > 0).collect();
    assert!(fixed.len() >= 2);
    for w in fixed.windows(2) {
        assert_eq!(w[1].time_of_week_ms - w[0].time_of_week_ms, 1000);
    }
    let sat = GpsSat::decode(&b.get_once(did::GPS1_SAT).try_into().unwrap());
    let sig = GpsSig::decode(&b.get_once(did::GPS1_SIG).try_into().unwrap());
    assert_eq!(sig.time_of_week_ms, sat.time_of_week_ms);
    assert_eq!(sig.num_sigs, sat.num_sats);
    assert_eq!(sig.num_sigs, 12);
    for (g, s) in sig.sig.iter().zip(&sat.sat).take(12) {
        assert_eq!(
            *g,
            GpsSigSv {
                gnss_id: s.gnss_id,
                sv_id: s.sv_id,
                sig_id: 0,
                cno: s.cno,
                quality: 7,
                status: 0x0005,
            }
        );
    }
    assert!(sig.sig[12..].iter().all(|v| *v == GpsSigSv::default()));
    b.dev.personality_mut().set_nav_faults(NavFaults {
        gps_off: true,
        ..NavFaults::default()
    });
    b.run_ticks(4000);
    let sig = GpsSig::decode(&b.get_once(did::GPS1_SIG).try_into().unwrap());
    assert_eq!(sig.num_sigs, 0);
}

fn le_u32(b: &[u8], i: usize) -> u32 {
    u32_at(b, i)
}

/// IMU3_RAW (84 B: time f64, status u32, 3 × {pqr, acc}): a one-shot GET
/// reads what IMU_RAW reads at the same instant in each of the three
/// IMUs (the chain's one sensor); streamed every `startupImuDtMs` ×
/// period; its RMC bit 0x100_0000_0000 streams it too.
#[test]
fn imu3_raw_is_the_chains_sensor_three_times() {
    let mut b = Bench::new();
    b.dev.chain_mut().set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [5.7, -11.5, 17.2],
    });
    b.run_ticks(100);
    let raw = Imu::decode(&b.get_once(did::IMU_RAW).try_into().unwrap());
    let p = b.get_once(did::IMU3_RAW);
    assert_eq!(p.len(), 84);
    assert_eq!(imu3::SIZE, 84);
    let i3 = Imu3::decode(&p.try_into().unwrap());
    assert_eq!((i3.time, i3.status), (raw.time, raw.status));
    for imu in i3.imu {
        assert_eq!((imu.pqr, imu.acc), (raw.pqr, raw.acc));
    }
    // |ω| of the rotation (5.7, −11.5, 17.2) °/s = 0.374 rad/s.
    for imu in i3.imu {
        let n = imu
            .pqr
            .iter()
            .map(|w| f64::from(*w).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((n - 0.374).abs() < 0.005, "{i3:?}");
    }
    b.send(&get(did::IMU3_RAW, 3));
    let r = b.run_ticks(600);
    assert_eq!(r.len(), 100, "every 3 ms");
    assert!(r
        .iter()
        .all(|p| p.did == did::IMU3_RAW && p.payload.len() == 84));
    b.send(&hex("ef 49 06 00 00 00 3e 1f"));
    let bits = 0x100_0000_0000u64;
    let mut rmc_set = bits.to_le_bytes().to_vec();
    rmc_set.extend_from_slice(&0u32.to_le_bytes());
    b.send(&set(did::RMC, 0, &rmc_set));
    let r = b.run_ticks(20);
    assert!(
        !r.is_empty() && r.iter().all(|p| p.did == did::IMU3_RAW),
        "{r:?}"
    );
}

/// What cltool's `-magRecal` sends (`docs/protocol-facts.md`): GET
/// DID_MAG_CAL with period 100, then SET_DATA of `state`: MAG_CAL streams
/// every 100 ms (1 ms source), the ACK comes, and the stream shows the
/// recalibration running with its progress rising while the unit turns
/// (11 s in heading, 11 s about a horizontal axis), then done.
#[test]
fn cltools_mag_recal_sequence_is_answered() {
    let mut b = Bench::new();
    b.send(&get(did::MAG_CAL, 100));
    let r = b.run_ticks(2000);
    let cals = of_did(&r, did::MAG_CAL);
    assert_eq!(cals.len(), 10, "every 100 ms");
    assert!(cals.iter().all(|p| p.payload.len() == 12));
    let r = b.send(&set(did::MAG_CAL, 0, &1u32.to_le_bytes()));
    assert_eq!((r[0].flags, r[0].payload[4]), (1, did::MAG_CAL));
    turn(&mut b, [0.0, 0.0, 36.0]);
    let mut r = b.run_ticks(22_000);
    turn(&mut b, [36.0, 0.0, 0.0]);
    r.extend(b.run_ticks(22_000));
    let cals: Vec<MagCal> = of_did(&r, did::MAG_CAL)
        .iter()
        .map(|p| MagCal::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert_eq!(cals.len(), 220);
    assert!(cals.windows(2).all(|w| w[1].progress >= w[0].progress));
    assert_eq!(cals[0].state, mag_cal_state::RECAL_RUNNING);
    assert!(
        cals[50].progress > 25.0 && cals[50].progress < 50.0,
        "half the first turn: {:?}",
        cals[50]
    );
    assert_eq!(cals[219].state, mag_cal_state::RECAL_COMPLETE);
}

/// PORT_MONITOR (223 B: 6 × 37-byte `port_monitor_set_t`, then u8
/// activePorts @222): port 0 is the serial line (portInfo 0x10: UART,
/// index 0), the only active one; txBytes / rxBytes count every byte sent
/// and received since power-on (exactly what went over the line before
/// the reply), the per-second rates the last whole second's bytes, and
/// rxChecksumErrors the packets dropped for a bad checksum.
#[test]
fn port_monitor_counts_the_lines_bytes() {
    use imu_emu::isb::aux_sets::{port_monitor, PortMonitor};
    let mut b = Bench::new();
    let mut rx = 0usize;
    let pm = |b: &mut Bench, rx: &mut usize| {
        let q = get(did::PORT_MONITOR, 0);
        *rx += q.len();
        let before = b.raw.len();
        let r = b.send(&q);
        assert_eq!((r.len(), r[0].did), (1, did::PORT_MONITOR));
        assert_eq!(r[0].payload.len(), port_monitor::SIZE);
        (
            PortMonitor::decode(&r[0].payload.clone().try_into().unwrap()),
            before,
        )
    };
    let (m, sent) = pm(&mut b, &mut rx);
    assert_eq!(m.active_ports, 1);
    assert_eq!(m.port[0].port_info, 0x10);
    assert_eq!(
        (m.port[0].tx_bytes as usize, m.port[0].rx_bytes as usize),
        (sent, rx)
    );
    assert!(m.port[1..].iter().all(|p| *p == Default::default()));
    // IMU every 4 ms: 250 packets of 44 bytes a second.
    let q = get(did::IMU, 1);
    rx += q.len();
    b.send(&q);
    b.run_ticks(2 * 2000 + 100);
    let (m, sent) = pm(&mut b, &mut rx);
    assert_eq!(m.port[0].tx_bytes as usize, sent);
    assert_eq!(m.port[0].rx_bytes as usize, rx);
    assert_eq!(m.port[0].tx_bytes_per_sec, 250 * 44);
    assert_eq!(m.port[0].rx_bytes_per_sec, 0);
    assert_eq!(m.port[0].tx_data_drops, 0);
    // A packet with a bad checksum.
    let mut bad = get(did::DEV_INFO, 0);
    let n = bad.len();
    bad[n - 1] ^= 0xFF;
    rx += bad.len();
    b.send(&bad);
    let (m, _) = pm(&mut b, &mut rx);
    assert_eq!(m.port[0].rx_checksum_errors, 1);
    assert_eq!(m.port[0].rx_bytes as usize, rx);
}

// ----- RTOS_INFO, CAN_CONFIG -----

/// RTOS_INFO (38, 372 B: heap words, then six 60-byte `rtos_task_t`):
/// served with the task names and the periods and last-run times of the
/// emulated unit's work — sample on the IMU grid (`startupImuDtMs` 1 ms),
/// nav on the navigation period (4 ms), comm on the 1 ms grid of its
/// streams, maint on the aiding models' 20 ms step (half a navigation
/// period after the grid), idle and timer names only; heap, CPU and stack
/// figures 0 (not measured). 1.2345 s after power-on, byte for byte. The
/// vendor tool's companion SYS_CMD 4 (enable RTOS statistics) is ACKed,
/// and a stream of period 1000 sends every 1 s.
#[test]
fn rtos_info_is_the_units_own_task_table() {
    use imu_emu::isb::rtos::{rtos_info, rtos_task};
    let mut b = Bench::new();
    b.run_ticks(2469);
    let p = b.get_once(did::RTOS_INFO);
    let mut want = vec![0u8; 372];
    let tasks: [(&[u8], u32, u32); 6] = [
        (b"SAMPLE", 1, 1_234_000),
        (b"NAV", 4, 1_232_000),
        (b"COMM", 1, 1_234_000),
        (b"MAINT", 20, 1_222_000),
        (b"IDLE", 0, 0),
        (b"TIMER", 0, 0),
    ];
    for (k, (name, period, start)) in tasks.iter().enumerate() {
        let at = rtos_info::TASK + k * rtos_task::SIZE;
        want[at..at + name.len()].copy_from_slice(name);
        want[at + 20..at + 24].copy_from_slice(&period.to_le_bytes());
        want[at + 44..at + 48].copy_from_slice(&start.to_le_bytes());
    }
    assert_eq!(p, want);
    assert_eq!(&p[12..24], b"SAMPLE\0\0\0\0\0\0");
    // SYS_CMD 4 (cltool `-did DID_RTOS_INFO`): ACKed.
    let mut cmd = 4u32.to_le_bytes().to_vec();
    cmd.extend((!4u32).to_le_bytes());
    let r = b.send(&set(did::SYS_CMD, 0, &cmd));
    assert_eq!((r[0].flags, r[0].payload[4]), (1, did::SYS_CMD), "ACK");
    b.send(&get(did::RTOS_INFO, 1000));
    let r = b.run_ticks(6000);
    let s = of_did(&r, did::RTOS_INFO);
    assert_eq!(s.len(), 3, "every 1 s");
    assert!(s.windows(2).all(|w| w[1].tick - w[0].tick == 2000));
}

/// CAN_CONFIG (90, 168 B, packed: u16 period multiples ×27 @0, u32
/// transmit addresses ×27 @54, u16 `can_baudrate_kbps` @162, u32
/// `can_receive_address` @164): factory settings (every message off,
/// 500 kbit/s), a SET_DATA ACKed, read back, written to flash ("flash
/// write pending" until the next tick) and still there after a power
/// cycle; a host DATA packet writes it too, unanswered.
#[test]
fn can_config_is_set_read_back_and_kept_in_flash() {
    use imu_emu::isb::packet::{self, FLAG_OFFSET};
    let mut b = Bench::new();
    let mut factory = vec![0u8; 168];
    factory[162..164].copy_from_slice(&500u16.to_le_bytes());
    assert_eq!(b.get_once(did::CAN_CONFIG), factory);
    // 250 kbit/s, receive address 0x123.
    let mut v = 250u16.to_le_bytes().to_vec();
    v.extend(0x123u32.to_le_bytes());
    let r = b.send(&set(did::CAN_CONFIG, 162, &v));
    assert_eq!((r[0].flags, r[0].payload[4]), (1, did::CAN_CONFIG), "ACK");
    assert_ne!(b.sys_params().hdw_status & 0x8000, 0, "flash write pending");
    b.run_ticks(1);
    assert_eq!(b.sys_params().hdw_status & 0x8000, 0, "written");
    // Host DATA: INS time every 10 periods at address 0x1F0 (message 0).
    let mut payload = 0u16.to_le_bytes().to_vec();
    payload.extend(10u16.to_le_bytes());
    let mut out = [0u8; 64];
    let n = packet::encode(4 | FLAG_OFFSET, did::CAN_CONFIG, &payload, &mut out).unwrap();
    assert!(b.send(&out[..n]).is_empty(), "no ACK");
    let mut payload = 54u16.to_le_bytes().to_vec();
    payload.extend(0x1F0u32.to_le_bytes());
    let n = packet::encode(4 | FLAG_OFFSET, did::CAN_CONFIG, &payload, &mut out).unwrap();
    assert!(b.send(&out[..n]).is_empty(), "no ACK");
    b.run_ticks(1);
    let mut want = factory.clone();
    want[0..2].copy_from_slice(&10u16.to_le_bytes());
    want[54..58].copy_from_slice(&0x1F0u32.to_le_bytes());
    want[162..168].copy_from_slice(&v);
    assert_eq!(b.get_once(did::CAN_CONFIG), want);
    let mut b = b.power_cycle();
    assert_eq!(b.get_once(did::CAN_CONFIG), want, "kept over a power cycle");
    // FLASH_CONFIG's own save keeps it too.
    b.send(&set(
        did::FLASH_CONFIG,
        flash::MAG_DECLINATION as u16,
        &0.1f32.to_le_bytes(),
    ));
    b.run_ticks(1);
    let mut b = b.power_cycle();
    assert_eq!(b.get_once(did::CAN_CONFIG), want);
}

/// A unit with the navigation filter off (as the RP2040 image runs it),
/// its receiver's first fix 6 s after power-on.
fn without_the_filter() -> Bench {
    let mut b = Bench::new();
    b.dev.personality_mut().set_start_times(ins::StartTimes {
        cold_s: 6.0,
        warm_s: 6.0,
    });
    b.dev.personality_mut().set_navigation(false);
    b.dev.power_cycle(Instant(b.now));
    b
}

/// The navigation filter off (what the RP2040 image serves: its tick cannot
/// afford the filter): every INS_2 says so — solution OFF, not NAV — and
/// reports `lastLla`, level, at rest, also after a power cycle, while the
/// receiver's fix still reaches GPS1_POS.
#[test]
fn without_the_navigation_filter_the_ins_reports_no_solution() {
    let mut b = without_the_filter();
    let last_lla: Vec<f64> = (0..3)
        .map(|k| {
            let off = flash::LAST_LLA + 8 * k;
            f64::from_le_bytes(b.flash_config()[off..off + 8].try_into().unwrap())
        })
        .collect();
    b.send(&get(did::INS_2, 1));
    b.send(&get(did::GPS1_POS, 1));
    let out = b.run_ticks(14_000);
    let ins: Vec<Ins2> = out
        .iter()
        .filter(|p| p.did == did::INS_2)
        .map(|p| Ins2::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert!(ins.len() > 1_700, "{}", ins.len());
    for i in &ins {
        let s = i.header.ins_status;
        assert_eq!(
            (s & ins_status::SOLUTION_MASK) >> ins_status::SOLUTION_SHIFT,
            ins_status::SOLUTION_OFF
        );
        assert_eq!(s & ins_status::NAV_MODE, 0);
        assert_eq!(i.lla.to_vec(), last_lla);
        assert_eq!((i.qn2b, i.uvw), ([1.0, 0.0, 0.0, 0.0], [0.0; 3]));
    }
    let pos: Vec<GpsPos> = out
        .iter()
        .filter(|p| p.did == did::GPS1_POS)
        .map(|p| GpsPos::decode(&p.payload.clone().try_into().unwrap()))
        .collect();
    assert_ne!(
        pos.last().unwrap().status & imu_emu::isb::nav_sets::gps_status::FIX_OK,
        0
    );
    assert_eq!(b.dev.personality().nav().phase(), ins::Phase::Off);
}

/// With the navigation filter off (the RP2040 image) the receiver's report
/// of an epoch is made ready on the ticks before it, as with the filter
/// (`docs/navigation.md` "Firmware cost"): every GPS1_POS with a fix
/// carries exactly the report computed directly from the receiver's fix at
/// its tick (ECEF, ellipsoid and MSL heights, bit for bit), and the stream's
/// bytes are the ones the unit sent when the report was made on the epoch's
/// own tick (their digest recorded then).
#[test]
fn without_the_navigation_filter_gps1_pos_carries_the_receivers_report() {
    let mut b = without_the_filter();
    b.send(&get(did::GPS1_POS, 1));
    let cfg = ins::NavConfig::default();
    // FNV-1a over every GPS1_POS payload, in order.
    let mut digest = 0xcbf2_9ce4_8422_2325u64;
    let (mut sent, mut fixed) = (0, 0);
    for _ in 0..20_000 {
        for p in b.run_ticks(1) {
            if p.did != did::GPS1_POS {
                continue;
            }
            sent += 1;
            for &x in &p.payload {
                digest = (digest ^ u64::from(x)).wrapping_mul(0x100_0000_01b3);
            }
            let pos = GpsPos::decode(&p.payload.clone().try_into().unwrap());
            let nav = b.dev.personality().nav();
            let Some((lla, _)) = nav.gnss(&nav::truth_of(b.dev.chain()), &cfg) else {
                assert_eq!(pos.status, 0, "no fix, no position");
                continue;
            };
            fixed += 1;
            let bits = |v: [f64; 3]| v.map(f64::to_bits);
            assert_eq!(bits(pos.lla), bits(lla));
            assert_eq!(bits(pos.ecef), bits(nav::ecef_of(&lla)));
            let msl = (lla[2] - earth::geoid_undulation_m(lla[0], lla[1])) as f32;
            assert_eq!(pos.h_msl.to_bits(), msl.to_bits());
        }
    }
    assert_eq!((sent, fixed), (50, 20));
    assert_eq!(digest, 0x01a0_e6c2_226f_741d, "GPS1_POS's bytes changed");
}
