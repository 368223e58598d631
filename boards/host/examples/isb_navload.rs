//! Whole-process measurement client for the IMX-5's navigation outputs
//! (docs/performance.md "Navigation filter"): connects to one or more
//! running `imu-emu --protocol isb` devices (`--tcp`, or the ports of
//! `--count N`), raises each line to 3 Mbaud (FLASH_CONFIG `ser0BaudRate`,
//! then `$SRST`), and streams every navigation data set at its source
//! period: INS_1..INS_4, INL2_STATES, INL2_NED_SIGMA (4 ms), GPS1_POS,
//! GPS1_VEL (200 ms), GPS1_SAT (1 s), MAGNETOMETER (10 ms), BAROMETER
//! (8 ms); one thread a device.
//!
//! Every nav-period packet's own time field must step by exactly the
//! navigation period (4 ms) from the previous packet of its DID — none
//! missed, none repeated (the step at the first fix, when the time fields
//! switch from time since boot to GPS time, is skipped) — or it counts a
//! miss.
//!
//! ```text
//! isb_navload ADDR[,ADDR…] SECONDS
//! ```
//!
//! Prints one line: `devices`, `packets`, `missed`, `wall_s`, `factor`
//! (device seconds of INS_2 per wall second, the mean over the devices).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use imu_emu::isb::did;
use imu_emu::isb::message::{encode_get, encode_set, GetRequest};
use imu_emu::isb::packet::Decoder;
use imu_emu::isb::sets::flash;

fn get(did: u8, period: u16) -> Vec<u8> {
    let req = GetRequest {
        did: u16::from(did),
        size: 0,
        offset: 0,
        period,
    };
    let mut out = [0u8; 64];
    let n = encode_get(&req, &mut out).unwrap();
    out[..n].to_vec()
}

const NAV_PERIOD: [u8; 6] = [
    did::INS_1,
    did::INS_2,
    did::INS_3,
    did::INS_4,
    did::INL2_STATES,
    did::INL2_NED_SIGMA,
];

/// A nav-period packet's time, s (its own time field).
fn time_of(d: u8, p: &[u8]) -> Option<f64> {
    let f64_at = |o: usize| f64::from_le_bytes(p.get(o..o + 8)?.try_into().ok()?).into();
    match d {
        did::INS_1 | did::INS_2 | did::INS_3 | did::INS_4 => f64_at(4),
        did::INL2_STATES => f64_at(0),
        did::INL2_NED_SIGMA => {
            Some(f64::from(u32::from_le_bytes(p.get(0..4)?.try_into().ok()?)) / 1e3)
        }
        _ => None,
    }
}

/// (packets, missed, device seconds) of one device over `secs`.
fn run(addr: &str, secs: f64) -> (u64, u64, f64) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_nodelay(true).ok();
    let mut out = [0u8; 64];
    let n = encode_set(
        did::FLASH_CONFIG,
        flash::SER0_BAUD_RATE as u16,
        &3_000_000u32.to_le_bytes(),
        &mut out,
    )
    .unwrap();
    s.write_all(&out[..n]).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    s.write_all(b"$SRST*06\r\n").unwrap();
    std::thread::sleep(Duration::from_millis(300));
    for d in NAV_PERIOD {
        s.write_all(&get(d, 1)).unwrap();
    }
    for d in [
        did::GPS1_POS,
        did::GPS1_VEL,
        did::GPS1_SAT,
        did::MAGNETOMETER,
        did::BAROMETER,
    ] {
        s.write_all(&get(d, 1)).unwrap();
    }
    s.set_read_timeout(Some(Duration::from_millis(100))).ok();
    let mut dec = Decoder::<4096>::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut last = [None::<f64>; 6];
    let (mut packets, mut missed, mut ins2) = (0u64, 0u64, 0u64);
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < secs {
        let k = match s.read(&mut buf) {
            Ok(0) => break,
            Ok(k) => k,
            Err(_) => continue,
        };
        let mut input = &buf[..k];
        while let Some(p) = dec.next_packet(&mut input) {
            if p.flags != 4 {
                continue;
            }
            packets += 1;
            let Some(i) = NAV_PERIOD.iter().position(|&d| d == p.did) else {
                continue;
            };
            if p.did == did::INS_2 {
                ins2 += 1;
            }
            let Some(t) = time_of(p.did, p.payload) else {
                continue;
            };
            if let Some(prev) = last[i] {
                let step = t - prev;
                // The switch to GPS time at the first fix: a jump of
                // about the time of week; anything else must be 4 ms.
                if (step - 0.004).abs() > 1e-6 && step.abs() < 1000.0 {
                    missed += 1;
                }
            }
            last[i] = Some(t);
        }
    }
    (packets, missed, ins2 as f64 * 0.004)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let addrs: Vec<String> = args[1].split(',').map(str::to_owned).collect();
    let secs: f64 = args[2].parse().unwrap();
    let t0 = Instant::now();
    let handles: Vec<_> = addrs
        .iter()
        .cloned()
        .map(|a| std::thread::spawn(move || run(&a, secs)))
        .collect();
    let res: Vec<(u64, u64, f64)> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    let wall = t0.elapsed().as_secs_f64();
    let packets: u64 = res.iter().map(|r| r.0).sum();
    let missed: u64 = res.iter().map(|r| r.1).sum();
    let factor = res.iter().map(|r| r.2).sum::<f64>() / res.len() as f64 / secs;
    println!(
        "devices={} packets={packets} missed={missed} wall_s={wall:.1} factor={factor:.1}",
        res.len()
    );
}
