//! The IMX-5's INS as a navigation filter (`src/isb/ins/`,
//! `docs/navigation.md`): a flight flown by a manoeuvre script, the unit's
//! own emulated IMU integrated by the filter, aided by its receiver,
//! barometer and magnetometer; read back as bytes (INS_1/INS_2, INL2_*).

use imu_emu::device::Device;
use imu_emu::isb::did;
use imu_emu::isb::ins::NavFaults;
use imu_emu::isb::nav;
use imu_emu::isb::nav_sets::{ins_status, Inl2NedSigma, Inl2States, Ins1, Ins2};
use imu_emu::isb::packet::Decoder;
use imu_emu::isb::Isb;
use imu_emu::math::double::{rotate, V3};
use imu_emu::sensor::profile::SensorProfile;
use imu_emu::sensor::profiles::IMX5_PROFILE;
use imu_emu::vehicle::{Manoeuvres, VehicleState};
use imu_emu::Instant;

mod common;
use common::isb::{flight, get, IsbFlash as Flash, CONSUMER};

/// The outage: from here, 60 s.
const OUTAGE_AT_S: f64 = 330.0;
const OUTAGE_S: f64 = 60.0;

struct Run {
    dev: Device<Flash, Isb>,
    script: Manoeuvres,
    ticks: u64,
    reader: Decoder<4096>,
}

impl Run {
    fn new(profile: &'static SensorProfile, seed: u64) -> Self {
        let (dev, script) = flight(profile, seed);
        Run {
            dev,
            script,
            ticks: 0,
            reader: Decoder::new(),
        }
    }

    fn t(&self) -> f64 {
        self.ticks as f64 * self.dev.tick_period_ns() as f64 * 1e-9
    }

    fn truth(&mut self) -> VehicleState {
        let t = self.t();
        self.script.at(t)
    }

    /// Packets (DID, payload) of `n` ticks of flight.
    fn fly(&mut self, n: u64) -> Vec<(u8, Vec<u8>)> {
        let period = self.dev.tick_period_ns();
        let mut out = Vec::new();
        let mut buf = [0u8; 4096];
        for _ in 0..n {
            self.ticks += 1;
            let t = self.t();
            let s = self.script.at(t);
            self.dev.chain_mut().set_vehicle(s, s.truth());
            self.dev.on_tick(Instant(self.ticks * period));
            loop {
                let k = self.dev.poll_tx(&mut buf);
                if k == 0 {
                    break;
                }
                let mut input = &buf[..k];
                while let Some(p) = self.reader.next_packet(&mut input) {
                    out.push((p.did, p.payload.to_vec()));
                }
            }
        }
        out
    }

    fn fly_s(&mut self, s: f64) -> Vec<(u8, Vec<u8>)> {
        self.fly((s * 2000.0).round() as u64)
    }

    fn send(&mut self, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        let now = Instant(self.ticks * self.dev.tick_period_ns());
        self.dev.on_rx(bytes, now);
        self.fly(0);
        let mut buf = [0u8; 4096];
        let mut out = Vec::new();
        loop {
            let k = self.dev.poll_tx(&mut buf);
            if k == 0 {
                break;
            }
            let mut input = &buf[..k];
            while let Some(p) = self.reader.next_packet(&mut input) {
                out.push((p.did, p.payload.to_vec()));
            }
        }
        out
    }

    fn ins2(&mut self) -> Ins2 {
        let r = self.send(&get(did::INS_2, 0));
        Ins2::decode(&r[0].1.clone().try_into().unwrap())
    }

    /// INS position error now, NED, m.
    fn error(&mut self) -> V3 {
        let i = self.ins2();
        let t = self.truth();
        let truth = [t.lat_rad.to_degrees(), t.lon_rad.to_degrees(), t.height_m];
        let (m, n) = imu_emu::vehicle::wgs84::radii(t.lat_rad);
        [
            (i.lla[0] - truth[0]).to_radians() * m,
            (i.lla[1] - truth[1]).to_radians() * n * t.lat_rad.cos(),
            -(i.lla[2] - truth[2]),
        ]
    }

    fn set_gps(&mut self, on: bool) {
        self.dev.personality_mut().set_nav_faults(NavFaults {
            gps_off: !on,
            ..NavFaults::default()
        });
    }
}

fn horiz(e: &V3) -> f64 {
    e[0].hypot(e[1])
}

fn sigma(r: &mut Run) -> Inl2NedSigma {
    let p = r.send(&get(did::INL2_NED_SIGMA, 0));
    Inl2NedSigma::decode(&p[0].1.clone().try_into().unwrap())
}

/// What one outage of the flight gave.
#[derive(Debug)]
#[allow(dead_code)] // read through Debug
struct Outage {
    /// Horizontal error at the outage's start, its end, and 60 s after
    /// the fix is back, m.
    before: f64,
    drift: f64,
    after: f64,
    /// The expected drift (`expected_drift`), m.
    expected: f64,
    /// The filter's own horizontal position σ at the outage's end, m.
    sigma_end: f64,
}

/// The flight with its outage.
fn outage_flight(profile: &'static SensorProfile, seed: u64) -> Outage {
    let mut r = Run::new(profile, seed);
    r.fly_s(OUTAGE_AT_S);
    let before = horiz(&r.error());
    let s0 = sigma(&mut r);
    r.set_gps(false);
    r.fly_s(OUTAGE_S);
    let drift = horiz(&r.error());
    let s1 = sigma(&mut r);
    let sp = ins_status::dead_reckoning(r.ins2().header.ins_status);
    assert!(sp, "dead reckoning at the outage's end");
    r.set_gps(true);
    r.fly_s(60.0);
    let after = horiz(&r.error());
    let h = |v: [f32; 3]| f64::from(v[0]).hypot(f64::from(v[1]));
    Outage {
        before,
        drift,
        after,
        expected: expected_drift(profile, &s0, OUTAGE_S),
        sigma_end: h(s1.std_pos_ned),
    }
}

/// The 1σ horizontal drift of straight and level dead reckoning over `t`
/// s (`docs/navigation.md` "Drift"), from the profile and from what the
/// filter knew at the outage's start (`s0`): a tilt error θ and an
/// accelerometer bias error δa give ½·(g·θ + δa)·t²; a gyro bias error δω
/// tilts the platform at δω, ⅙·g·δω·t³; the bias instability B of the
/// profile adds its own change over the outage (½·B_a·t², ⅙·g·B_g·t³);
/// the velocity error δv gives δv·t.
fn expected_drift(p: &SensorProfile, s0: &Inl2NedSigma, t: f64) -> f64 {
    let g = 9.81;
    let h = |v: [f32; 3]| f64::from(v[0]).hypot(f64::from(v[1]));
    let ba = f64::from(p.acc.bias_instability) * g;
    let bg = f64::from(p.gyro.bias_instability).to_radians();
    let t2 = 0.5 * t * t;
    let t3 = g * t * t * t / 6.0;
    let terms = [
        g * h(s0.std_att_ned) * t2,
        h(s0.std_acc_bias) * t2,
        h(s0.std_gyr_bias) * t3,
        ba * t2,
        bg * t3,
        h(s0.std_vel_ned) * t,
    ];
    terms.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The same 60 s outage of the same flight: the consumer-grade unit drifts
/// clearly more (over 3×) than the IMX-5; each drift is within 3 of its
/// expected 1σ drift (`expected_drift`: the profile's figures and the
/// filter's σ at the outage's start) and within 3 of the filter's own
/// position σ at the outage's end; the error shrinks back under 3 m within
/// 60 s of the fix's return.
#[test]
fn a_gps_outage_drifts_as_the_profile_says_and_recovers() {
    let imx = outage_flight(&IMX5_PROFILE, 11);
    let con = outage_flight(&CONSUMER, 11);
    eprintln!("IMX-5 {imx:?}\nconsumer {con:?}");
    assert!(con.drift > 3.0 * imx.drift, "{con:?} vs {imx:?}");
    for o in [&imx, &con] {
        assert!(o.before < 3.0, "{o:?}");
        assert!(o.drift < 3.0 * o.expected, "{o:?}");
        assert!(o.drift < 3.0 * o.sigma_end, "{o:?}");
        assert!(o.after < 3.0, "{o:?}");
    }
}

fn ins1(p: &[u8]) -> Ins1 {
    Ins1::decode(&p.to_vec().try_into().unwrap())
}

/// Every INS_1 of the navigation period, through a coordinated turn with
/// the fix: the change of position between two outputs is the mean of
/// their velocities (body velocity rotated by the Euler attitude) times the
/// period, to 2 mm/s, except on the outputs that carry
/// GPS_UPDATE_IN_SOLUTION (a GNSS update stepped the state), where the
/// step stays under 0.3 m.
#[test]
fn the_position_is_the_integral_of_the_velocity() {
    let mut r = Run::new(&IMX5_PROFILE, 7);
    r.fly_s(120.0);
    r.send(&get(did::INS_1, 1));
    let out = r.fly_s(10.0);
    let ins: Vec<Ins1> = out
        .iter()
        .filter(|p| p.0 == did::INS_1)
        .map(|p| ins1(&p.1))
        .collect();
    assert_eq!(ins.len(), 2500);
    let v_ned = |i: &Ins1| {
        let e = i.theta.map(f64::from);
        let q = imu_emu::math::double::quat_from_euler(e[0], e[1], e[2]);
        rotate(&q, &i.uvw.map(f64::from))
    };
    let (mut worst, mut steps, mut worst_step) = (0.0f64, 0, 0.0f64);
    for w in ins.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let dt = b.header.time_of_week - a.header.time_of_week;
        assert!((dt - 0.004).abs() < 1e-6, "{dt}");
        let lat = a.lla[0].to_radians();
        let (m, n) = imu_emu::vehicle::wgs84::radii(lat);
        let d = [
            (b.lla[0] - a.lla[0]).to_radians() * (m + a.lla[2]),
            (b.lla[1] - a.lla[1]).to_radians() * (n + a.lla[2]) * lat.cos(),
            -(b.lla[2] - a.lla[2]),
        ];
        let (va, vb) = (v_ned(a), v_ned(b));
        let miss = (0..3)
            .map(|k| (d[k] / dt - 0.5 * (va[k] + vb[k])).abs())
            .fold(0.0, f64::max);
        if b.header.ins_status & ins_status::GPS_UPDATE_IN_SOLUTION != 0 {
            steps += 1;
            worst_step = worst_step.max(miss * dt);
        } else {
            worst = worst.max(miss);
        }
    }
    eprintln!("worst {worst} m/s; {steps} GNSS steps, the largest {worst_step} m");
    assert_eq!(steps, 50, "one a GNSS epoch (200 ms)");
    assert!(worst < 0.002, "{worst} m/s");
    assert!(worst_step < 0.3, "{worst_step} m");
}

/// Aided and moving (the flight's first five minutes: take-off run,
/// turns, climb, descent), the filter's bias estimates (INL2_STATES, body
/// axes) converge toward the unit's drawn turn-on biases (the chain's
/// error model, housing axes, with the temperature term and the vertical
/// accelerometer's scale factor at 1 g): each within 3 of the filter's own σ
/// (INL2_NED_SIGMA; 4 for the horizontal accelerometers) plus the bias instability, and every σ well below the
/// turn-on σ it started from.
#[test]
fn estimated_biases_converge_toward_the_turn_on_biases() {
    let mut r = Run::new(&IMX5_PROFILE, 5);
    r.fly_s(300.0);
    let st = r.send(&get(did::INL2_STATES, 0));
    let st = Inl2States::decode(&st[0].1.clone().try_into().unwrap());
    let sg = r.send(&get(did::INL2_NED_SIGMA, 0));
    let sg = Inl2NedSigma::decode(&sg[0].1.clone().try_into().unwrap());
    // The bias each sensor has now: turn-on plus temperature coefficient ×
    // (T − 25 °C); on the vertical accelerometer (housing z, up, reading
    // +1 g in level flight) its scale-factor error × g reads as a bias too.
    let e = r.dev.chain().errors();
    let dtemp = f64::from(r.dev.chain().temperature()) - 25.0;
    let housing = |f: &dyn Fn(usize) -> f64| [f(0), f(1), f(2)];
    let g_true = imu_emu::vehicle::housing_to_body(&housing(&|k| {
        let a = &e.gyro.axes[k];
        (f64::from(a.bias) + f64::from(a.temp_bias) * dtemp).to_radians()
    }));
    let a_true = imu_emu::vehicle::housing_to_body(&housing(&|k| {
        let a = &e.acc.axes[k];
        let sf = if k == 2 {
            f64::from(a.scale_factor)
        } else {
            0.0
        };
        (f64::from(a.bias) + f64::from(a.temp_bias) * dtemp + sf) * 9.80665
    }));
    let p = &IMX5_PROFILE;
    let bi_g = f64::from(p.gyro.bias_instability).to_radians();
    let bi_a = f64::from(p.acc.bias_instability) * 9.80665;
    let (g0, a0) = (
        f64::from(p.gyro.turn_on_bias_sigma).to_radians(),
        f64::from(p.acc.turn_on_bias_sigma) * 9.80665,
    );
    for k in 0..3 {
        let (eg, ea) = (f64::from(st.bias_pqr[k]), f64::from(st.bias_acc[k]));
        let (sg_, sa) = (f64::from(sg.std_gyr_bias[k]), f64::from(sg.std_acc_bias[k]));
        eprintln!(
            "axis {k}: gyro {eg:.3e} vs {:.3e} (σ {sg_:.1e}); acc {ea:.3e} vs {:.3e} (σ {sa:.1e})",
            g_true[k], a_true[k]
        );
    }
    for k in 0..3 {
        let (eg, ea) = (f64::from(st.bias_pqr[k]), f64::from(st.bias_acc[k]));
        let (sg_, sa) = (f64::from(sg.std_gyr_bias[k]), f64::from(sg.std_acc_bias[k]));
        assert!((eg - g_true[k]).abs() < 3.0 * sg_ + bi_g, "gyro {k}");
        // The horizontal accelerometer biases are seen only through the
        // turns (a tilt error looks the same in level flight): after five
        // minutes they are the filter's weakest states, within 4 σ.
        let n_sigma = if k < 2 { 4.0 } else { 3.0 };
        assert!((ea - a_true[k]).abs() < n_sigma * sa + bi_a, "acc {k}");
        assert!(sg_ < 0.2 * g0 && sa < 0.5 * a0, "σ {sg_} {sa}");
    }
}

fn flash_lla(r: &mut Run) -> ([f64; 3], u32) {
    use imu_emu::isb::sets::flash;
    let b = r.send(&get(did::FLASH_CONFIG, 0))[0].1.clone();
    let f = |o: usize| f64::from_le_bytes(b[o..o + 8].try_into().unwrap());
    let week = u32::from_le_bytes(b[flash::LAST_LLA_WEEK..][..4].try_into().unwrap());
    let l = flash::LAST_LLA;
    ([f(l), f(l + 8), f(l + 16)], week)
}

/// A cold start (empty flash) fixes after 30 s; NAV saves `lastLla` (and
/// its week) to flash; a power cycle after NAV is a warm start: the INS
/// reports the saved position from its alignment on, and fixes after 10 s
/// (NAV from the receiver's next epoch).
/// The start times are configurable ([`Isb::set_start_times`]).
#[test]
fn a_power_cycle_after_nav_is_a_warm_start() {
    let mut r = Run::new(&IMX5_PROFILE, 3);
    let nav = |r: &mut Run| r.ins2().header.ins_status & ins_status::NAV_MODE != 0;
    assert_eq!(flash_lla(&mut r).1, 0, "nothing saved");
    r.fly_s(29.9);
    assert!(!nav(&mut r), "cold: no fix before 30 s");
    r.fly_s(0.3);
    assert!(nav(&mut r), "cold: NAV from the fix at 30 s");
    r.fly_s(1.0);
    let (lla, week) = flash_lla(&mut r);
    assert_eq!(week, 2399);
    let t = r.truth();
    let d = nav::ned_from_ref(
        &lla,
        &[t.lat_rad.to_degrees(), t.lon_rad.to_degrees(), t.height_m],
    );
    assert!(d[0].hypot(d[1]) < 5.0 && d[2].abs() < 5.0, "{d:?}");
    let now = Instant(r.ticks * r.dev.tick_period_ns());
    r.dev.power_cycle(now);
    r.fly_s(6.0);
    let i = r.ins2();
    assert_eq!(i.lla, lla, "the saved position before the fix");
    assert_eq!(i.header.ins_status & ins_status::NAV_MODE, 0);
    r.fly_s(3.9);
    assert!(!nav(&mut r), "warm: no fix before 10 s");
    // The fix at 10 s enters at the receiver's next epoch (200 ms).
    r.fly_s(0.4);
    assert!(nav(&mut r), "warm: NAV from the fix at 10 s");
    // Configured: a 2 s warm start.
    r.dev
        .personality_mut()
        .set_start_times(imu_emu::isb::ins::StartTimes {
            cold_s: 30.0,
            warm_s: 2.0,
        });
    let now = Instant(r.ticks * r.dev.tick_period_ns());
    r.dev.power_cycle(now);
    r.fly_s(5.3);
    assert!(nav(&mut r), "NAV right after the alignment");
}

/// A nav-period packet's own time, s: the INS header's time of week,
/// INL2_STATES' time of week, INL2_NED_SIGMA's in ms (their SDK 2.7.1
/// layouts, docs/isb-data-sets.md).
fn nav_time(d: u8, p: &[u8]) -> f64 {
    let f64_at = |o: usize| f64::from_le_bytes(p[o..o + 8].try_into().unwrap());
    match d {
        did::INL2_STATES => f64_at(0),
        did::INL2_NED_SIGMA => f64::from(u32::from_le_bytes(p[0..4].try_into().unwrap())) / 1e3,
        _ => f64_at(4),
    }
}

/// Streams of every navigation-period data set asked for between two
/// navigation periods start on the navigation grid and step by exactly
/// the period from their first packet (a client checking the period from
/// the packets' own times sees no step but 4 ms), and one-shot GETs read
/// the last period's time: the filter's state is the last navigation
/// step's, whichever data set carries it (INL2_STATES and INL2_NED_SIGMA
/// were stamped "now", half a millisecond off the grid).
#[test]
fn nav_streams_start_on_the_grid_and_step_by_the_period() {
    const NAV: [u8; 6] = [
        did::INS_1,
        did::INS_2,
        did::INS_3,
        did::INS_4,
        did::INL2_STATES,
        did::INL2_NED_SIGMA,
    ];
    let mut r = Run::new(&IMX5_PROFILE, 3);
    // 1.0015 s: between two 4 ms periods.
    r.fly(2003);
    for d in NAV {
        let p = r.send(&get(d, 0));
        assert_eq!(p.len(), 1, "{d}");
        assert!((nav_time(d, &p[0].1) - 1.0).abs() < 1e-9, "one-shot {d}");
    }
    // 1.003 s.
    r.fly(3);
    let mut got = Vec::new();
    for d in NAV {
        got.extend(r.send(&get(d, 1)));
    }
    got.extend(r.fly_s(2.0));
    for d in NAV {
        let t: Vec<f64> = got
            .iter()
            .filter(|(id, _)| *id == d)
            .map(|(_, p)| nav_time(d, p))
            .collect();
        assert!(t.len() >= 499, "{d}: {} packets", t.len());
        // The first packet answers at once with the last step's state.
        assert!((t[0] - 1.0).abs() < 1e-9, "{d}: first at {}", t[0]);
        for w in t.windows(2) {
            assert!(
                (w[1] - w[0] - 0.004).abs() < 1e-9,
                "{d}: {} -> {}",
                w[0],
                w[1]
            );
        }
    }
}
