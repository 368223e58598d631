//! The IMX-5's navigation side: the INS and GNSS error models, the INS
//! phases after power-on, the magnetometer and the barometer, and the
//! navigation data sets built from the truth ([`super::nav::truth_of`]).
//! Figures and decisions: `docs/isb.md` "Navigation".
//!
//! Errors are first-order Gauss–Markov processes per axis (`x ← a·x +
//! σ·√(1−a²)·w`, `a = e^(−Δt/τ)`), stepped every [`STEP_MS`] from the
//! unit's own seed, so they are correlated in time as a filter's are and the
//! same seed gives the same errors whatever is streamed. Sensor noise of
//! the magnetometer and barometer is white, drawn from the seed and the
//! sample's tick (independent of what else is asked for).

use libm::{exp, log, pow, sqrt};

use super::nav::{ecef_of, lla_plus_ned, ned_from_ref, quat_e2n, GpsTime, NavTruth, LEAP_SECONDS};
use super::nav_sets::{
    gps_status, hdw_nav, ins_status, sat_status, Barometer, GpsPos, GpsSat, GpsSatSv, GpsVel, Ins1,
    Ins2, Ins3, Ins4, InsHeader, Magnetometer, MAX_NUM_SATELLITES,
};
use crate::earth::geoid_undulation_m;
use crate::math::double::{
    euler_from_quat, quat_from_euler, quat_mul, quat_normalize as normalize, rotate, rotate_inv,
};
use crate::sensor::rng::Rng;

/// The error models' step, ms.
pub const STEP_MS: u32 = 20;
/// Attitude alignment after power-on (solution "aligning" until then), s.
pub const ALIGN_S: f64 = 5.0;
/// GNSS time to first fix from a cold start, s (a u-blox class receiver's
/// cold-start TTFF).
pub const COLD_START_S: f64 = 30.0;
/// Dead reckoning longer than this reports "NAV, high variance", s.
pub const HIGH_VARIANCE_AFTER_S: f64 = 10.0;
/// Time constant with which the dead-reckoning error shrinks once the fix
/// is back, s.
pub const RECOVERY_TAU_S: f64 = 5.0;

/// One Gauss–Markov figure: standard deviation and correlation time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gm {
    /// Standard deviation.
    pub sigma: f64,
    /// Correlation time, s.
    pub tau_s: f64,
}

/// INS position error while GPS-aided, north/east, m (1σ per axis).
pub const INS_POS_H: Gm = Gm {
    sigma: 0.7,
    tau_s: 60.0,
};
/// INS position error, down, m.
pub const INS_POS_V: Gm = Gm {
    sigma: 1.0,
    tau_s: 60.0,
};
/// INS velocity error per NED axis, m/s.
pub const INS_VEL: Gm = Gm {
    sigma: 0.03,
    tau_s: 10.0,
};
/// INS roll and pitch error, rad (0.1°).
pub const INS_TILT: Gm = Gm {
    sigma: 0.001_745,
    tau_s: 100.0,
};
/// INS heading error, rad (0.3°).
pub const INS_HEADING: Gm = Gm {
    sigma: 0.005_236,
    tau_s: 100.0,
};
/// GNSS position error, north/east, m (1σ per axis: hAcc ≈ 1.4 m).
pub const GNSS_POS_H: Gm = Gm {
    sigma: 1.0,
    tau_s: 30.0,
};
/// GNSS position error, down, m.
pub const GNSS_POS_V: Gm = Gm {
    sigma: 1.5,
    tau_s: 30.0,
};
/// GNSS velocity error per NED axis, m/s.
pub const GNSS_VEL: Gm = Gm {
    sigma: 0.05,
    tau_s: 1.0,
};
/// Acceleration error driving the dead reckoning during an outage, per
/// horizontal axis, m/s² (1σ, drawn at the outage's start: 0.1° tilt × g
/// plus accelerometer bias).
pub const DR_ACCEL_H: f64 = 0.02;
/// The same, down (the barometer holds the vertical), m/s².
pub const DR_ACCEL_V: f64 = 0.005;
/// Magnetometer noise, normalized units (1σ per axis).
pub const MAG_NOISE: f64 = 0.002;
/// Barometer noise, kPa (1σ: 2 Pa ≈ 0.17 m).
pub const BARO_NOISE_KPA: f64 = 0.002;
/// Relative humidity the barometer reports, %.
pub const HUMIDITY: f32 = 40.0;
/// Satellites the receiver uses with a fix.
pub const SATS: u8 = 12;
/// Reported accuracies and DOP with a fix.
pub const H_ACC_M: f32 = 1.4;
/// Vertical accuracy, m.
pub const V_ACC_M: f32 = 1.5;
/// Speed accuracy, m/s.
pub const S_ACC_MPS: f32 = 0.09;
/// Position DOP.
pub const P_DOP: f32 = 1.2;
/// Mean C/N0, dBHz.
pub const CNO_MEAN: f32 = 42.0;
/// The GPS satellites (PRNs) of the constellation model: the [`SATS`]
/// GPS1_SAT lists while the receiver has a fix (`docs/isb.md` "GPS1_SAT").
pub const SAT_PRNS: [u8; SATS as usize] = [2, 5, 7, 9, 13, 15, 18, 20, 24, 27, 29, 30];
/// Their elevations, degrees (all above a receiver's 10° mask).
pub const SAT_ELEV_DEG: [i8; SATS as usize] = [15, 72, 38, 22, 63, 46, 30, 80, 55, 25, 41, 58];
/// Azimuths: the seed's bearing of the first satellite plus this spacing
/// per satellite, degrees.
pub const SAT_AZIM_STEP_DEG: i16 = 30;
/// Largest C/N0 spread of a satellite from [`CNO_MEAN`], dBHz (drawn from
/// the seed in ± pairs, so the mean is exactly [`CNO_MEAN`]).
pub const SAT_CNO_SPREAD: i32 = 4;
/// `gps_sat_sv_t.status` of a satellite in the solution: carrier locked,
/// used, healthy.
pub const SAT_STATUS_USED: u16 =
    sat_status::QUALITY_CARRIER_LOCKED | sat_status::USED_IN_SOLUTION | sat_status::HEALTH_GOOD;

/// A magnetic disturbance adds this field (normalized units, NED).
pub const MAG_DISTURBANCE: [f64; 3] = [0.6, -0.4, 0.3];

/// Faults injected from outside (the host's control socket).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NavFaults {
    /// The GNSS receiver has no fix (antenna cut, jammed…).
    pub gps_off: bool,
    /// A magnetic disturbance near the unit.
    pub mag_disturbed: bool,
    /// The barometer has failed (its reading freezes).
    pub baro_failed: bool,
}

/// FLASH_CONFIG fields the navigation uses.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavConfig {
    /// `refLla`: origin of INS_1.ned.
    pub ref_lla: [f64; 3],
    /// `lastLla`: what the INS reports before its first fix.
    pub last_lla: [f64; 3],
    /// `insRotation`, rad (sensor → output frame).
    pub ins_rotation: [f32; 3],
    /// `insOffset`, m (output frame).
    pub ins_offset: [f32; 3],
    /// `gps1AntOffset`, m (sensor frame).
    pub gps1_ant_offset: [f32; 3],
}

/// What the INS reports: position, velocity, attitude of its output point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    /// deg, deg, m (ellipsoid).
    pub lla: [f64; 3],
    /// NED velocity, m/s.
    pub v_ned: [f64; 3],
    /// Output frame → NED.
    pub q_nb: [f64; 4],
}

/// The navigation state of one unit (module doc).
#[derive(Debug, Clone)]
pub struct NavState {
    rng: Rng,
    seed: u64,
    /// Seconds since boot at the last step.
    t_s: f64,
    faults: NavFaults,
    fixed: bool,
    ever_fixed: bool,
    /// Seconds since boot when the current outage began.
    outage_at: Option<f64>,
    ins_pos: [f64; 3],
    ins_vel: [f64; 3],
    ins_att: [f64; 3],
    gnss_pos: [f64; 3],
    gnss_vel: [f64; 3],
    dr_acc: [f64; 3],
    dr_vel: [f64; 3],
    dr_pos: [f64; 3],
    baro_frozen: Option<f32>,
}

fn gm_step(x: &mut f64, g: &Gm, dt: f64, w: f64) {
    let a = exp(-dt / g.tau_s);
    *x = a * *x + g.sigma * sqrt(1.0 - a * a) * w;
}

impl NavState {
    /// Power-on state for `seed` (errors drawn at their steady state).
    pub fn new(seed: u64) -> Self {
        let mut rng = Rng::new(seed ^ 0x4E41_5600);
        let mut draw = |g: &Gm| g.sigma * f64::from(rng.gaussian());
        let h3 = |d: &mut dyn FnMut(&Gm) -> f64, h: &Gm, v: &Gm| [d(h), d(h), d(v)];
        let ins_pos = h3(&mut draw, &INS_POS_H, &INS_POS_V);
        let ins_vel = h3(&mut draw, &INS_VEL, &INS_VEL);
        let ins_att = h3(&mut draw, &INS_TILT, &INS_HEADING);
        let gnss_pos = h3(&mut draw, &GNSS_POS_H, &GNSS_POS_V);
        let gnss_vel = h3(&mut draw, &GNSS_VEL, &GNSS_VEL);
        NavState {
            rng,
            seed,
            t_s: 0.0,
            faults: NavFaults::default(),
            fixed: false,
            ever_fixed: false,
            outage_at: None,
            ins_pos,
            ins_vel,
            ins_att,
            gnss_pos,
            gnss_vel,
            dr_acc: [0.0; 3],
            dr_vel: [0.0; 3],
            dr_pos: [0.0; 3],
            baro_frozen: None,
        }
    }

    /// The faults in force.
    pub fn faults(&self) -> NavFaults {
        self.faults
    }

    /// Sets the injected faults (they act from the next step).
    pub fn set_faults(&mut self, f: NavFaults) {
        self.faults = f;
    }

    /// Whether the receiver has a fix now.
    pub fn has_fix(&self) -> bool {
        self.fixed
    }

    /// Whether GPS time is known (a fix was had since power-on).
    pub fn gps_time_valid(&self) -> bool {
        self.ever_fixed
    }

    /// Advances the models to `t_s` seconds since boot at `truth` (called
    /// every [`STEP_MS`]).
    pub fn step(&mut self, t_s: f64, truth: &NavTruth) {
        let dt = (t_s - self.t_s).max(0.0);
        self.t_s = t_s;
        let was_fixed = self.fixed;
        self.fixed = !self.faults.gps_off && t_s >= COLD_START_S;
        self.ever_fixed |= self.fixed;
        let mut w = [0.0f64; 15];
        for x in w.iter_mut() {
            *x = f64::from(self.rng.gaussian());
        }
        for k in 0..3 {
            let (ph, pv) = (&INS_POS_H, &INS_POS_V);
            gm_step(&mut self.ins_pos[k], if k < 2 { ph } else { pv }, dt, w[k]);
            gm_step(&mut self.ins_vel[k], &INS_VEL, dt, w[3 + k]);
            let att = if k < 2 { &INS_TILT } else { &INS_HEADING };
            gm_step(&mut self.ins_att[k], att, dt, w[6 + k]);
            let gp = if k < 2 { &GNSS_POS_H } else { &GNSS_POS_V };
            gm_step(&mut self.gnss_pos[k], gp, dt, w[9 + k]);
            gm_step(&mut self.gnss_vel[k], &GNSS_VEL, dt, w[12 + k]);
        }
        let navigating = self.ever_fixed && t_s >= ALIGN_S;
        if navigating && !self.fixed {
            if was_fixed || self.outage_at.is_none() {
                self.outage_at = Some(t_s);
                let h = [DR_ACCEL_H, DR_ACCEL_H, DR_ACCEL_V];
                for (a, s) in self.dr_acc.iter_mut().zip(h) {
                    *a = s * f64::from(self.rng.gaussian());
                }
            }
            // Dead reckoning: the acceleration error integrates twice.
            for k in 0..3 {
                self.dr_vel[k] += self.dr_acc[k] * dt;
                self.dr_pos[k] += self.dr_vel[k] * dt;
            }
        } else {
            self.outage_at = None;
            let a = exp(-dt / RECOVERY_TAU_S);
            for k in 0..3 {
                self.dr_vel[k] *= a;
                self.dr_pos[k] *= a;
            }
        }
        // A failed barometer keeps its last good reading.
        if !self.faults.baro_failed || self.baro_frozen.is_none() {
            self.baro_frozen =
                Some(isa_kpa(truth.h_m - geoid_undulation_m(truth.lat_deg, truth.lon_deg)) as f32);
        }
    }

    /// The dead-reckoning position error now, NED, m.
    pub fn dead_reckoning_error(&self) -> [f64; 3] {
        self.dr_pos
    }

    /// `insStatus` now (module doc, `docs/isb.md`).
    pub fn ins_status(&self) -> u32 {
        use ins_status::*;
        let t = self.t_s;
        let mag = if self.faults.mag_disturbed {
            MAG_INTERFERENCE_OR_BAD_CAL
        } else {
            MAG_AIDING_HEADING
        };
        let hdg = if self.faults.mag_disturbed {
            HDG_ALIGN_COARSE
        } else {
            HDG_ALIGN_FINE
        };
        if t < ALIGN_S {
            return SOLUTION_ALIGNING << SOLUTION_SHIFT;
        }
        if !self.ever_fixed {
            return (SOLUTION_AHRS << SOLUTION_SHIFT) | hdg | mag;
        }
        let mut s = hdg | mag | NAV_MODE;
        if self.fixed {
            s |= VEL_ALIGN_FINE | POS_ALIGN_FINE | GPS_AIDING_POS | GPS_AIDING_VEL;
            s |= SOLUTION_NAV << SOLUTION_SHIFT;
            s |= GPS_NAV_FIX_3D << GPS_NAV_FIX_SHIFT;
        } else {
            let since = self.outage_at.map_or(0.0, |a| t - a);
            if since < HIGH_VARIANCE_AFTER_S {
                s |= VEL_ALIGN_FINE | POS_ALIGN_FINE | (SOLUTION_NAV << SOLUTION_SHIFT);
            } else {
                s |= VEL_ALIGN_COARSE
                    | POS_ALIGN_COARSE
                    | (SOLUTION_NAV_HIGH_VARIANCE << SOLUTION_SHIFT);
            }
        }
        s
    }

    /// The navigation bits of `hdwStatus` now.
    pub fn hdw_bits(&self) -> u32 {
        let mut h = 0;
        if self.fixed {
            h |= hdw_nav::GPS_SATELLITE_RX_VALID | hdw_nav::GPS_PPS_TIMESYNC;
        }
        if self.ever_fixed {
            h |= hdw_nav::GPS_TIME_OF_WEEK_VALID;
        }
        if self.faults.baro_failed {
            h |= hdw_nav::SATURATION_BARO;
        }
        h
    }

    /// The INS solution for `truth` (before alignment: level, facing
    /// north, at rest; before the first fix: at `lastLla`).
    pub fn solution(&self, truth: &NavTruth, cfg: &NavConfig) -> Solution {
        let e = self.ins_att;
        let err = [1.0, e[0] / 2.0, e[1] / 2.0, e[2] / 2.0];
        let [r, p, y] = cfg.ins_rotation.map(f64::from);
        let q_rot = quat_from_euler(r, p, y);
        let q_nb = normalize(&quat_mul(&quat_mul(&err, &truth.q_nb), &q_rot));
        if self.t_s < ALIGN_S {
            return Solution {
                lla: cfg.last_lla,
                v_ned: [0.0; 3],
                q_nb: [1.0, 0.0, 0.0, 0.0],
            };
        }
        if !self.ever_fixed {
            return Solution {
                lla: cfg.last_lla,
                v_ned: [0.0; 3],
                q_nb,
            };
        }
        let lever = rotate(&(q_nb), &cfg.ins_offset.map(f64::from));
        let mut d = [0.0; 3];
        let mut v = [0.0; 3];
        for k in 0..3 {
            d[k] = lever[k] + self.ins_pos[k] + self.dr_pos[k];
            v[k] = truth.v_ned[k] + self.ins_vel[k] + self.dr_vel[k];
        }
        Solution {
            lla: lla_plus_ned(&[truth.lat_deg, truth.lon_deg, truth.h_m], &d),
            v_ned: v,
            q_nb,
        }
    }

    /// The receiver's position (of the antenna) and NED velocity, if it
    /// has a fix.
    pub fn gnss(&self, truth: &NavTruth, cfg: &NavConfig) -> Option<([f64; 3], [f64; 3])> {
        if !self.fixed {
            return None;
        }
        let ant = rotate(&(truth.q_nb), &cfg.gps1_ant_offset.map(f64::from));
        let mut d = [0.0; 3];
        let mut v = [0.0; 3];
        for k in 0..3 {
            d[k] = ant[k] + self.gnss_pos[k];
            v[k] = truth.v_ned[k] + self.gnss_vel[k];
        }
        Some((
            lla_plus_ned(&[truth.lat_deg, truth.lon_deg, truth.h_m], &d),
            v,
        ))
    }

    /// GPS1_SAT of a receiver epoch `t` (`docs/isb.md` "GPS1_SAT"): with a
    /// fix, the [`SATS`] satellites GPS1_POS counts as used, at fixed
    /// elevations ([`SAT_ELEV_DEG`]), azimuths [`SAT_AZIM_STEP_DEG`] apart
    /// from a bearing drawn from the seed, C/N0 [`CNO_MEAN`] ± a seed-drawn
    /// pair offset (mean exactly [`CNO_MEAN`]); without a fix (before the
    /// first, during an outage) no satellites.
    pub fn gps_sat(&self, t: &GpsTime) -> GpsSat {
        let mut sat = [GpsSatSv::default(); MAX_NUM_SATELLITES];
        let n = if self.fixed { usize::from(SATS) } else { 0 };
        let mut r = Rng::new(self.seed ^ 0x4753_4154);
        let base = (r.uniform() * 360.0) as i16;
        let mut spread = [0i32; SATS as usize / 2];
        for d in &mut spread {
            *d = (r.uniform() * (2 * SAT_CNO_SPREAD + 1) as f32) as i32 - SAT_CNO_SPREAD;
        }
        let half = spread.len();
        for (i, sv) in sat.iter_mut().take(n).enumerate() {
            let d = if i < half {
                spread[i]
            } else {
                -spread[i - half]
            };
            let azim = (base + SAT_AZIM_STEP_DEG * i as i16) % 360;
            *sv = GpsSatSv {
                gnss_id: 1,
                sv_id: SAT_PRNS[i],
                elev: SAT_ELEV_DEG[i],
                azim: if azim > 180 { azim - 360 } else { azim },
                cno: (CNO_MEAN as i32 + d) as u8,
                status: SAT_STATUS_USED,
            };
        }
        GpsSat {
            time_of_week_ms: t.tow_ms(),
            num_sats: n as u32,
            sat,
        }
    }

    /// White noise for sample `tick`, channel `ch`: the same whatever is
    /// streamed.
    fn noise(&self, tick: u64, ch: u64) -> f64 {
        let mut r = Rng::new(self.seed ^ tick.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ ch);
        f64::from(r.gaussian())
    }

    /// The magnetometer's reading (body axes, normalized units): the axial
    /// dipole's field direction at the truth latitude (declination 0,
    /// inclination `atan(2 tan lat)`), plus the disturbance, plus noise.
    pub fn magnetometer(&self, truth: &NavTruth, tick: u64) -> [f32; 3] {
        let lat = truth.lat_deg.to_radians();
        let (h, z) = (libm::cos(lat), 2.0 * libm::sin(lat));
        let n = sqrt(h * h + z * z);
        let mut f = [h / n, 0.0, z / n];
        if self.faults.mag_disturbed {
            for (x, d) in f.iter_mut().zip(MAG_DISTURBANCE) {
                *x += d;
            }
        }
        let b = rotate_inv(&(truth.q_nb), &f);
        [0, 1, 2].map(|k| (b[k] + MAG_NOISE * self.noise(tick, k as u64)) as f32)
    }

    /// The barometer's pressure (kPa) at the truth's MSL height (ISA), with
    /// noise; frozen while it has failed.
    pub fn pressure_kpa(&self, truth: &NavTruth, tick: u64) -> f32 {
        match self.baro_frozen {
            Some(p) if self.faults.baro_failed => p,
            _ => {
                let p = isa_kpa(truth.h_m - geoid_undulation_m(truth.lat_deg, truth.lon_deg));
                (p + BARO_NOISE_KPA * self.noise(tick, 7)) as f32
            }
        }
    }
}

/// ISA pressure at `h` m above MSL, kPa (troposphere: 101.325 kPa, 15 °C,
/// −6.5 K/km).
pub fn isa_kpa(h: f64) -> f64 {
    101.325 * pow(1.0 - 2.255_77e-5 * h, 5.255_88)
}

/// Whether the navigation fields of a FLASH_CONFIG image are sane: `refLla`
/// and `lastLla` latitude within ±90°, longitude within ±360°, height within
/// −1 000…100 000 m, none NaN; `startupGPSDtMs` 200…60 000 ms; the lever
/// arms `insOffset` and `gps1AntOffset` within ±[`MAX_LEVER_ARM_M`] and
/// `insRotation` within ±2π rad on every axis (so none is NaN or infinite:
/// each goes into every INS and GPS position). A SET that would store
/// anything else is refused (NACK).
pub fn flash_nav_valid(image: &[u8]) -> bool {
    use super::sets::{flash, le};
    let within = |off: usize, limit: f32| {
        le::f32x3(image, off)
            .iter()
            .all(|x| (-limit..=limit).contains(x))
    };
    within(flash::INS_OFFSET, MAX_LEVER_ARM_M)
        && within(flash::GPS1_ANT_OFFSET, MAX_LEVER_ARM_M)
        && within(flash::INS_ROTATION, core::f32::consts::TAU)
        && flash_lla_valid(image)
}

/// The largest lever arm (`insOffset`, `gps1AntOffset`) a FLASH_CONFIG may
/// hold, m, per axis: beyond any vehicle an IMX rides on.
pub const MAX_LEVER_ARM_M: f32 = 100.0;

/// The positions and the GPS period of [`flash_nav_valid`].
fn flash_lla_valid(image: &[u8]) -> bool {
    use super::sets::{flash, le};
    let lla_ok = |off: usize| {
        let (lat, lon, h) = (
            le::f64(image, off),
            le::f64(image, off + 8),
            le::f64(image, off + 16),
        );
        (-90.0..=90.0).contains(&lat)
            && (-360.0..=360.0).contains(&lon)
            && (-1_000.0..=100_000.0).contains(&h)
    };
    let gps = le::u32(image, flash::STARTUP_GPS_DT_MS);
    lla_ok(flash::REF_LLA) && lla_ok(flash::LAST_LLA) && (200..=60_000).contains(&gps)
}

fn f32s<const N: usize>(v: [f64; N]) -> [f32; N] {
    v.map(|x| x as f32)
}

/// INS_1 of `s`.
pub fn ins1(h: &InsHeader, s: &Solution, cfg: &NavConfig) -> Ins1 {
    let uvw = rotate_inv(&s.q_nb, &s.v_ned);
    Ins1 {
        header: *h,
        theta: f32s(euler_from_quat(&s.q_nb)),
        uvw: f32s(uvw),
        lla: s.lla,
        ned: f32s(ned_from_ref(&s.lla, &cfg.ref_lla)),
    }
}

/// INS_2 of `s`.
pub fn ins2(h: &InsHeader, s: &Solution) -> Ins2 {
    Ins2 {
        header: *h,
        qn2b: f32s(s.q_nb),
        uvw: f32s(rotate_inv(&s.q_nb, &s.v_ned)),
        lla: s.lla,
    }
}

/// INS_3 of `s`: INS_2 plus the MSL height.
pub fn ins3(h: &InsHeader, s: &Solution) -> Ins3 {
    Ins3 {
        ins2: ins2(h, s),
        msl: (s.lla[2] - geoid_undulation_m(s.lla[0], s.lla[1])) as f32,
    }
}

/// INS_4 of `s`: ECEF.
pub fn ins4(h: &InsHeader, s: &Solution) -> Ins4 {
    let qe2n = quat_e2n(s.lla[0], s.lla[1]);
    Ins4 {
        header: *h,
        qe2b: f32s(quat_mul(&qe2n, &s.q_nb)),
        ve: f32s(rotate(&(qe2n), &s.v_ned)),
        ecef: ecef_of(&s.lla),
    }
}

/// GPS1_POS of a receiver epoch `t` (`fix`: position and NED velocity if
/// the receiver has one), `tow_offset` s.
pub fn gps_pos(t: &GpsTime, fix: Option<([f64; 3], [f64; 3])>, tow_offset: f64) -> GpsPos {
    match fix {
        Some((lla, _)) => GpsPos {
            week: t.week,
            time_of_week_ms: t.tow_ms(),
            status: u32::from(SATS)
                | (gps_status::FIX_3D << gps_status::FIX_SHIFT)
                | gps_status::FIX_OK,
            ecef: ecef_of(&lla),
            lla,
            h_msl: (lla[2] - geoid_undulation_m(lla[0], lla[1])) as f32,
            h_acc: H_ACC_M,
            v_acc: V_ACC_M,
            p_dop: P_DOP,
            cno_mean: CNO_MEAN,
            tow_offset,
            leap_s: LEAP_SECONDS,
            sats_used: SATS,
            cno_mean_sigma: 15,
            status2: 0,
        },
        // No fix: status 0 (no satellites, fix none), accuracies unknown.
        None => GpsPos {
            week: t.week,
            time_of_week_ms: t.tow_ms(),
            tow_offset,
            leap_s: LEAP_SECONDS,
            ..GpsPos::default()
        },
    }
}

/// GPS1_VEL of a receiver epoch (ECEF velocity).
pub fn gps_vel(t: &GpsTime, fix: Option<([f64; 3], [f64; 3])>) -> GpsVel {
    let p = gps_pos(t, fix, 0.0);
    match fix {
        Some((lla, v)) => GpsVel {
            time_of_week_ms: t.tow_ms(),
            vel: f32s(rotate(&(quat_e2n(lla[0], lla[1])), &v)),
            s_acc: S_ACC_MPS,
            status: p.status,
        },
        None => GpsVel {
            time_of_week_ms: t.tow_ms(),
            ..GpsVel::default()
        },
    }
}

/// MAGNETOMETER at `time` (s since boot).
pub fn magnetometer(time: f64, mag: [f32; 3]) -> Magnetometer {
    Magnetometer { time, mag }
}

/// BAROMETER at `time` (s since boot) for pressure `p` kPa and
/// temperature `temp` °C: `mslBar` by the SDK's `baro2msl`.
pub fn barometer(time: f64, p: f32, temp: f32) -> Barometer {
    Barometer {
        time,
        bar: p,
        msl_bar: (-8434.668 * log(f64::from(p) / 101.325)) as f32,
        bar_temp: temp,
        humidity: HUMIDITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GPS1_SAT is a function of the seed (and the fix) only: the same
    /// seed gives the same records, another seed another bearing; none
    /// before the fix.
    #[test]
    fn the_constellation_comes_from_the_seed() {
        let truth = NavTruth {
            lat_deg: 45.0,
            lon_deg: 0.0,
            h_m: 0.0,
            v_ned: [0.0; 3],
            q_nb: [1.0, 0.0, 0.0, 0.0],
        };
        let t = GpsTime {
            week: 2399,
            tow_ns: 1_000_000_000,
        };
        let fixed = |seed| {
            let mut n = NavState::new(seed);
            assert_eq!(n.gps_sat(&t).num_sats, 0);
            n.step(COLD_START_S + 1.0, &truth);
            n.gps_sat(&t)
        };
        let (a, b, c) = (fixed(11), fixed(11), fixed(12));
        assert_eq!(a, b);
        assert_eq!(a.num_sats, u32::from(SATS));
        assert_ne!(a.sat[0].azim, c.sat[0].azim);
        assert_eq!((a.time_of_week_ms, a.sat[0].sv_id), (1000, SAT_PRNS[0]));
    }
}
