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

use imu_emu::device::{Device, PowerOn};
use imu_emu::isb::did;
use imu_emu::isb::ins::NavFaults;
use imu_emu::isb::message::{encode_get, GetRequest};
use imu_emu::isb::nav_sets::Ins2;
use imu_emu::isb::packet::Decoder;
use imu_emu::isb::Isb;
use imu_emu::sensor::profile::{arw_to_density, vrw_to_density, SensorProfile};
use imu_emu::sensor::profiles::IMX5_PROFILE;
use imu_emu::vehicle::{wgs84, Manoeuvres, Script};
use imu_emu::{Instant, Product, RamNor};

/// The consumer-grade profile of `tests/isb_ins.rs`.
static CONSUMER: SensorProfile = {
    let mut p = IMX5_PROFILE;
    p.gyro.noise_density = arw_to_density(0.6);
    p.gyro.bias_instability = 36.0 / 3600.0;
    p.acc.noise_density = vrw_to_density(0.1);
    p.acc.bias_instability = 1e-3;
    p
};

const FLIGHT: &str = "start 45.5 7.25 300 30 0; hold 60; accel 2 15; hold 20; \
    coord-turn 3 30; hold 20; climb 5 20; hold 10; descend 5 20; hold 10; \
    coord-turn -3 30; hold 20; accel 1 5; hold 150";
const OUTAGE: (u64, u64) = (330, 390);
const END_S: u64 = 450;

/// Horizontal INS error each second of the flight, m.
fn errors(profile: &'static SensorProfile) -> Vec<f64> {
    let mut dev = Device::<RamNor<16384>, Isb>::new(
        PowerOn {
            product: Product::imx5(),
            boot: None,
            seed: 11,
        },
        RamNor::new(),
        Instant::ZERO,
    );
    dev.chain_mut().set_profile(Some(profile));
    let mut script = Manoeuvres::new(Script::parse(FLIGHT).unwrap());
    let s = script.at(0.0);
    dev.chain_mut().set_vehicle(s, s.truth());
    dev.power_cycle(Instant::ZERO);
    let period = dev.tick_period_ns();
    let per_s = 1_000_000_000 / period;
    let mut get = [0u8; 32];
    let n = encode_get(
        &GetRequest {
            did: u16::from(did::INS_2),
            size: 0,
            offset: 0,
            period: 0,
        },
        &mut get,
    )
    .unwrap();
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
        dev.on_rx(&get[..n], Instant(tick * period));
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
