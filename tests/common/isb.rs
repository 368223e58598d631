//! The ISB test bench's shared setup: an emulated IMX-5 on the core
//! device, a GET_DATA request, and the INS flight of the GPS-outage test
//! (`tests/isb_ins.rs`) and of `boards/host/examples/nav_outage.rs`, which
//! includes this file by path.
#![allow(dead_code)]

use imu_emu::device::{Device, PowerOn};
use imu_emu::isb::message::{self, GetRequest};
use imu_emu::isb::Isb;
use imu_emu::sensor::profile::{arw_to_density, vrw_to_density, SensorProfile};
use imu_emu::sensor::profiles::IMX5_PROFILE;
use imu_emu::vehicle::{Manoeuvres, Script};
use imu_emu::{Instant, Product, RamNor};

/// The flash of an emulated IMX-5 (room for the ISB image twice).
pub type IsbFlash = RamNor<16384>;

/// An IMX-5 powered on at instant 0 with `flash` and `seed`.
pub fn imx5(seed: u64, flash: IsbFlash) -> Device<IsbFlash, Isb> {
    Device::<IsbFlash, Isb>::new(
        PowerOn {
            product: Product::imx5(),
            boot: None,
            seed,
        },
        flash,
        Instant::ZERO,
    )
}

/// A GET_DATA of the whole set `did`, every `period` source periods (0:
/// once).
pub fn get(did: u8, period: u16) -> Vec<u8> {
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

/// A consumer-grade MEMS IMU (a phone-class part): gyro ARW 0.6 °/√h and
/// bias instability 36 °/h, accelerometer VRW 0.1 m/s/√h and bias
/// instability 1 mg; the rest as the IMX-5's.
pub static CONSUMER: SensorProfile = {
    let mut p = IMX5_PROFILE;
    p.gyro.noise_density = arw_to_density(0.6);
    p.gyro.bias_instability = 36.0 / 3600.0;
    p.acc.noise_density = vrw_to_density(0.1);
    p.acc.bias_instability = 1e-3;
    p
};

/// The flight: still for 60 s (alignment, first fix, bias settling), a
/// take-off run, turns, a climb and descent, then straight and level
/// (where the outage falls), 7 minutes.
pub const FLIGHT: &str = "start 45.5 7.25 300 30 0; hold 60; accel 2 15; hold 20; \
    coord-turn 3 30; hold 20; climb 5 20; hold 10; descend 5 20; hold 10; \
    coord-turn -3 30; hold 20; accel 1 5; hold 150";

/// An IMX-5 with sensors of `profile` at the start of [`FLIGHT`] (powered
/// on there), and the flight's script.
pub fn flight(profile: &'static SensorProfile, seed: u64) -> (Device<IsbFlash, Isb>, Manoeuvres) {
    let mut dev = imx5(seed, IsbFlash::new());
    dev.chain_mut().set_profile(Some(profile));
    let mut script = Manoeuvres::new(Script::parse(FLIGHT).unwrap());
    let s = script.at(0.0);
    dev.chain_mut().set_vehicle(s, s.truth());
    dev.power_cycle(Instant::ZERO);
    (dev, script)
}
