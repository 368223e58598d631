//! The INS position error of the emulated IMX-5 through a 60 s GPS outage,
//! for two sensor profiles, as a CSV for `imu-emu client plot` (the
//! README's ISB picture; docs/navigation.md "Drift"): the flight of
//! `tests/isb_ins.rs` flown by the core device with the IMX-5's built-in
//! profile and with a consumer-grade one, the outage injected as the
//! control socket's `fault gps off` does, INS_2 read once a second as
//! bytes and compared with the vehicle's truth, from a minute after
//! power-on; the outage is from 330 s to 390 s.
//!
//! ```text
//! cargo run --release -p imu-emu-host --example nav_outage > outage.csv
//! imu-emu client plot outage.csv -o docs/ins-outage.png
//! ```

use imu_emu::isb::did;
use imu_emu::isb::ins::NavFaults;
use imu_emu::isb::nav_sets::Ins2;
use imu_emu::isb::packet::Decoder;
use imu_emu::sensor::profile::SensorProfile;
use imu_emu::sensor::profiles::IMX5_PROFILE;
use imu_emu::vehicle::wgs84;
use imu_emu::Instant;

// The flight and the consumer-grade profile of `tests/isb_ins.rs`.
#[path = "../../../tests/common/isb.rs"]
mod bench;
use bench::{flight, CONSUMER};

const OUTAGE: (u64, u64) = (330, 390);
const END_S: u64 = 450;

/// Horizontal INS error each second of the flight, m.
fn errors(profile: &'static SensorProfile) -> Vec<f64> {
    let (mut dev, mut script) = flight(profile, 11);
    let period = dev.tick_period_ns();
    let per_s = 1_000_000_000 / period;
    let get = bench::get(did::INS_2, 0);
    let mut dec = Decoder::<4096>::new();
    let mut buf = [0u8; 4096];
    let mut out = Vec::new();
    let mut tick = 0u64;
    for sec in 1..=END_S {
        let gps_off = (OUTAGE.0..OUTAGE.1).contains(&sec);
        dev.personality_mut().set_nav_faults(NavFaults {
            gps_off,
            ..NavFaults::default()
        });
        for _ in 0..per_s {
            tick += 1;
            let s = script.at(tick as f64 * period as f64 * 1e-9);
            dev.chain_mut().set_vehicle(s, s.truth());
            dev.on_tick(Instant(tick * period));
            while dev.poll_tx(&mut buf) > 0 {}
        }
        dev.on_rx(&get, Instant(tick * period));
        let k = dev.poll_tx(&mut buf);
        let mut input = &buf[..k];
        let p = dec.next_packet(&mut input).expect("INS_2");
        let i = Ins2::decode(&p.payload.try_into().unwrap());
        let t = script.at(tick as f64 * period as f64 * 1e-9);
        let (m, nr) = wgs84::radii(t.lat_rad);
        let dn = (i.lla[0].to_radians() - t.lat_rad) * m;
        let de = (i.lla[1].to_radians() - t.lon_rad) * nr * t.lat_rad.cos();
        out.push(dn.hypot(de));
    }
    out
}

fn main() {
    let a = errors(&IMX5_PROFILE);
    let b = errors(&CONSUMER);
    // From a minute after power-on: the INS navigates (before its first
    // fix it reports `lastLla`, not a position).
    println!("device_time_s,pos_err_IMX-5 profile,pos_err_consumer profile");
    for (k, (x, y)) in a.iter().zip(&b).enumerate().skip(59) {
        println!("{},{x:.3},{y:.3}", k + 1);
    }
}
