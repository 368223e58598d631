//! The ISB personality through the core: the emulated IMX-5 driven with
//! bytes, ticks and pin edges exactly as a board drives it, answers read
//! back with the ISB packet decoder (`src/isb/device.rs`; `docs/isb.md`).

use imu_emu::device::{Device, Level, Pin, PowerOn};
use imu_emu::isb::did;
use imu_emu::isb::message::{self, GetRequest};
use imu_emu::isb::packet::{self, Decoder};
use imu_emu::isb::sets::{
    dev_info, flash, hdw_status, imu_status, rmc, sys_params, DevInfo, Imu, Pimu, Rmc,
    StrobeInTime, SysParams, SystemCommand,
};
use imu_emu::isb::Isb;
use imu_emu::sensor::Motion;
use imu_emu::{Instant, Product, RamNor};

type Flash = RamNor<16384>;

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

fn get(did: u8, period: u16) -> Vec<u8> {
    let req = GetRequest {
        did: u16::from(did),
        size: 0,
        offset: 0,
        period,
    };
    let mut out = [0u8; 64];
    let n = message::encode_get(&req, &mut out).unwrap();
    out[..n].to_vec()
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
        let dev = Device::<Flash, Isb>::new(
            PowerOn {
                product: Product::imx5(),
                boot: None,
                seed: 11,
            },
            flash,
            Instant::ZERO,
        );
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
    // Whole, without the offset flag, the last tick's sample.
    assert_eq!(
        (r[0].flags, r[0].did, r[0].payload.len()),
        (4, did::IMU, 36)
    );
    let imu = Imu::decode(&r[0].payload.clone().try_into().unwrap());
    assert_eq!(imu.time, 0.05);
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
        assert_eq!(p.tick, 100 + 8 * (k as u64 + 1));
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
    b.send(&get(did::PIMU, 2));
    let r = b.run_ticks(4000);
    assert_eq!(r.len(), 250);
    let mut total = 0.0f64;
    for (k, p) in r.iter().enumerate() {
        assert_eq!(p.tick, 10 + 16 * (k as u64 + 1));
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
    assert!(b.send(&get(2, 0)).is_empty(), "SYS_FAULT: not served");
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
        rate_dps: [3000.0, 0.0, 0.0],
    });
    b.send(&get(did::IMU, 1));
    let r = b.run_ticks(16);
    let imu = Imu::decode(&r[1].payload.clone().try_into().unwrap());
    assert_ne!(imu.status & imu_status::SATURATION_GYR, 0);
    let sp = b.sys_params();
    assert_ne!(sp.hdw_status & hdw_status::SATURATION_GYR, 0);
    assert_eq!(sys_params::SIZE, 64);
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
