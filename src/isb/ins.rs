//! The IMX-5's navigation side: its INS — a strapdown mechanisation of
//! the unit's own emulated IMU ([`mech`]) corrected by an error-state
//! Kalman filter ([`filter`]) with the GNSS receiver, the barometer and
//! the magnetometer, through the phases and status of [`status`] — and the
//! emulated aiding sensors it reads: the GNSS receiver (the truth plus
//! first-order Gauss–Markov errors, `x ← a·x + σ·√(1−a²)·w`, `a =
//! e^(−Δt/τ)`, stepped every [`STEP_MS`] from the unit's own seed), the
//! magnetometer and the barometer (white noise drawn from the seed and the
//! sample's tick, independent of what else is asked for). The navigation
//! data sets are built from the filter's state. Figures and decisions:
//! `docs/navigation.md`, `docs/isb.md` "Navigation".

pub mod filter;
pub mod mech;
pub(crate) mod status;

use core::cell::Cell;

use libm::{atan2, exp, log, pow, sqrt};

use super::nav::{
    ecef_of, lla_plus_ned, ned_from_ref, quat_e2n, GpsTime, NavTruth, DEFAULT_GPS_S_AT_ZERO,
    LEAP_SECONDS,
};
use super::nav_sets::{
    gps_status, hdw_nav, sat_status, Barometer, GpsPos, GpsSat, GpsSatSv, GpsVel, Inl2NedSigma,
    Inl2States, Ins1, Ins2, Ins3, Ins4, InsHeader, Magnetometer, MAX_NUM_SATELLITES,
};
use crate::earth::{declination_deg, geoid_undulation_m, FieldMemo};
use crate::math::double::{
    euler_from_quat, quat_from_euler, quat_mul, quat_normalize as normalize, rotate, rotate_inv, V3,
};
use crate::sensor::profile::SensorProfile;
use crate::sensor::rng::Rng;
use crate::vehicle::wgs84;
use filter::{Filter, Interval, ProcessNoise, Update, ATT, BA, BG, N, POS, VEL};
use mech::{Increment, Nominal};
pub use status::Phase;

/// The receiver error models' step, ms.
pub(crate) const STEP_MS: u32 = 20;
/// Coarse alignment after power-on (solution "aligning" until then): the
/// accelerometers and magnetometer are averaged over it, s.
pub(crate) const ALIGN_S: f64 = 5.0;
/// GNSS time to first fix from a cold start (no `lastLla`), s: a u-blox
/// class receiver's cold-start TTFF.
pub(crate) const COLD_START_S: f64 = 30.0;
/// GNSS time to first fix from a warm start (`lastLla` and its week saved
/// by an earlier NAV: position and time known), s.
pub(crate) const WARM_START_S: f64 = 10.0;
/// `lastLla` is rewritten when the INS has moved this far from it and
/// `lastLlaUpdateDistance` is 0 (its factory value), m.
pub(crate) const LAST_LLA_DEFAULT_DISTANCE_M: f64 = 1000.0;
/// The covariance is propagated at least this often, s (the mechanisation
/// runs every navigation period; the covariance needs less).
pub(crate) const PROPAGATE_S: f64 = 0.020;

/// One Gauss–Markov figure: standard deviation and correlation time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Gm {
    /// Standard deviation.
    pub sigma: f64,
    /// Correlation time, s.
    pub tau_s: f64,
}

/// GNSS position error, north/east, m (1σ per axis: hAcc ≈ 1.4 m).
pub(crate) const GNSS_POS_H: Gm = Gm {
    sigma: 1.0,
    tau_s: 30.0,
};
/// GNSS position error, down, m.
pub(crate) const GNSS_POS_V: Gm = Gm {
    sigma: 1.5,
    tau_s: 30.0,
};
/// GNSS velocity error per NED axis, m/s.
pub(crate) const GNSS_VEL: Gm = Gm {
    sigma: 0.05,
    tau_s: 1.0,
};
/// Magnetometer noise, normalized units (1σ per axis: 0.2 % of the local
/// field).
pub(crate) const MAG_NOISE: f64 = 0.002;
/// Barometer noise, kPa (1σ: 2 Pa ≈ 0.17 m).
pub(crate) const BARO_NOISE_KPA: f64 = 0.002;
/// Relative humidity the barometer reports, %.
pub(crate) const HUMIDITY: f32 = 40.0;
/// Satellites the receiver uses with a fix.
pub(crate) const SATS: u8 = 12;
/// Reported accuracies and DOP with a fix.
pub(crate) const H_ACC_M: f32 = 1.4;
/// Vertical accuracy, m.
pub(crate) const V_ACC_M: f32 = 1.5;
/// Speed accuracy, m/s.
pub(crate) const S_ACC_MPS: f32 = 0.09;
/// Position DOP.
pub(crate) const P_DOP: f32 = 1.2;
/// Mean C/N0, dBHz.
pub(crate) const CNO_MEAN: f32 = 42.0;
/// The GPS satellites (PRNs) of the constellation model: the [`SATS`]
/// GPS1_SAT lists while the receiver has a fix (`docs/isb.md` "GPS1_SAT").
pub const SAT_PRNS: [u8; SATS as usize] = [2, 5, 7, 9, 13, 15, 18, 20, 24, 27, 29, 30];
/// Their elevations, degrees (all above a receiver's 10° mask).
pub(crate) const SAT_ELEV_DEG: [i8; SATS as usize] = [15, 72, 38, 22, 63, 46, 30, 80, 55, 25, 41, 58];
/// Azimuths: the seed's bearing of the first satellite plus this spacing
/// per satellite, degrees.
pub(crate) const SAT_AZIM_STEP_DEG: i16 = 30;
/// Largest C/N0 spread of a satellite from [`CNO_MEAN`], dBHz (drawn from
/// the seed in ± pairs, so the mean is exactly [`CNO_MEAN`]).
pub(crate) const SAT_CNO_SPREAD: i32 = 4;
/// `gps_sat_sv_t.status` of a satellite in the solution: carrier locked,
/// used, healthy.
pub(crate) const SAT_STATUS_USED: u16 =
    sat_status::QUALITY_CARRIER_LOCKED | sat_status::USED_IN_SOLUTION | sat_status::HEALTH_GOOD;

/// A magnetic disturbance adds this field (normalized units, NED).
pub(crate) const MAG_DISTURBANCE: [f64; 3] = [0.6, -0.4, 0.3];

/// The filter's measurement noise (1σ) of the barometer's height, m: the
/// emulated barometer's 2 Pa noise is 0.17 m; the rest allows for the
/// height an ISA barometer misreads in weather the model does not have.
pub(crate) const BARO_SIGMA_M: f32 = 0.5;
/// The filter's measurement noise (1σ) of a magnetometer heading, rad (1°:
/// the emulated magnetometer's noise over the horizontal field at mid
/// latitudes is 0.3°, plus residual calibration).
pub(crate) const MAG_HEADING_SIGMA: f32 = 0.017_45;
/// While no GNSS fix was ever had (AHRS), the filter assumes the unit's
/// mean velocity is zero with this 1σ (a pseudo-measurement at each
/// receiver epoch), m/s: what levels an AHRS's attitude.
pub(crate) const AHRS_VEL_SIGMA: f32 = 0.5;
/// A magnetometer sample whose magnitude differs from the one learnt in
/// alignment by more than this fraction is interference (not fused).
pub(crate) const MAG_NORM_TOLERANCE: f64 = 0.10;
/// … or whose dip angle differs by more than this, rad (5°).
pub(crate) const MAG_DIP_TOLERANCE: f64 = 0.087;
/// A magnetometer heading whose residual exceeds this many standard
/// deviations of its prediction is not fused.
pub(crate) const MAG_GATE: f32 = 5.0;
/// With a heading σ above [`status::HDG_COARSE_RAD`] and the GNSS
/// horizontal speed above this, the heading is set from the course over
/// ground (single antenna: heading needs motion), m/s.
pub(crate) const GPS_HEADING_MIN_SPEED: f64 = 5.0;
/// The declination is evaluated again after this long, s (at 250 m/s that
/// is 2.5 km, where the declination changes by well under 0.1°).
pub(crate) const DECLINATION_EVERY_S: f64 = 10.0;
/// The heading σ after it was set from the course over ground, rad (5°).
pub(crate) const GPS_HEADING_SIGMA: f32 = 0.087;
/// `sysCfgBits`: no magnetometer fusion (`SYS_CFG_BITS_DISABLE_MAGNETOMETER_FUSION`).
pub(crate) const SYS_CFG_NO_MAG_FUSION: u32 = 0x1000;
/// `sysCfgBits`: no barometer fusion.
pub(crate) const SYS_CFG_NO_BARO_FUSION: u32 = 0x2000;
/// `sysCfgBits`: no GPS1 fusion.
pub(crate) const SYS_CFG_NO_GPS1_FUSION: u32 = 0x4000;

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
    /// `lastLlaWeek`: 0 when no position was ever saved.
    pub last_lla_week: u32,
    /// `lastLlaUpdateDistance`, m.
    pub last_lla_update_distance: f32,
    /// `sysCfgBits` (the fusion switches, [`SYS_CFG_NO_MAG_FUSION`] …).
    pub sys_cfg_bits: u32,
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

/// The start times of the receiver, s: to the first fix from a cold and
/// from a warm start (configurable: `Isb::set_start_times`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartTimes {
    /// Cold start (no saved position), s.
    pub cold_s: f64,
    /// Warm start (a position saved by an earlier NAV), s.
    pub warm_s: f64,
}

impl Default for StartTimes {
    fn default() -> Self {
        StartTimes {
            cold_s: COLD_START_S,
            warm_s: WARM_START_S,
        }
    }
}

/// A receiver fix: the antenna's position (deg, deg, m) and NED velocity
/// (m/s).
pub(crate) type Fix = ([f64; 3], [f64; 3]);

/// What the receiver reports of a fix (GPS1_POS): the antenna's position
/// (deg, deg, m above the ellipsoid), NED velocity (m/s), ECEF position
/// (m) and height above mean sea level (EGM96, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GnssReport {
    /// Latitude °, longitude °, height m.
    pub lla: [f64; 3],
    /// NED velocity, m/s.
    pub v: [f64; 3],
    /// ECEF, m.
    pub ecef: [f64; 3],
    /// Height above mean sea level, m.
    pub h_msl: f32,
}

/// What a [`GnssReport`] is made of, compared exactly
/// ([`NavState::gps_report`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct ReportKey {
    pos: [f64; 3],
    v: [f64; 3],
    q: [f64; 4],
    err_pos: [f64; 3],
    err_vel: [f64; 3],
    ant: [f32; 3],
}

impl ReportKey {
    /// The key of a report of `truth` with the receiver's errors `err`
    /// (position, velocity) and `cfg`'s antenna offset.
    fn of(truth: &NavTruth, cfg: &NavConfig, err: &([f64; 3], [f64; 3])) -> Self {
        ReportKey {
            pos: [truth.lat_deg, truth.lon_deg, truth.h_m],
            v: truth.v_ned,
            q: if cfg.gps1_ant_offset == [0.0; 3] {
                [0.0; 4]
            } else {
                truth.q_nb
            },
            err_pos: err.0,
            err_vel: err.1,
            ant: cfg.gps1_ant_offset,
        }
    }
}

/// What the aiding sensors read at a navigation step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aiding {
    /// The magnetometer's reading, body axes (what MAGNETOMETER reports).
    pub mag: [f32; 3],
    /// The barometer's pressure, kPa (what BAROMETER reports).
    pub pressure_kpa: f32,
    /// Decimal year of the GPS date (for the declination).
    pub year: f64,
}

/// The navigation state of one unit (module doc).
#[derive(Debug, Clone)]
pub struct NavState {
    rng: Rng,
    seed: u64,
    /// Seconds since boot at the last receiver-model step.
    t_s: f64,
    faults: NavFaults,
    fixed: bool,
    ever_fixed: bool,
    /// Seconds since boot when the current outage began.
    outage_at: Option<f64>,
    gnss_pos: [f64; 3],
    gnss_vel: [f64; 3],
    baro_frozen: Option<f32>,
    /// The date the magnetic field is read at, decimal year (UTC).
    year: f64,
    /// The main field at the truth, remembered ([`FieldMemo`]).
    field: FieldMemo,
    /// The receiver models' step and its [`gm_step`] coefficients
    /// (horizontal position, vertical position, velocity): the step is
    /// fixed, so they are computed once.
    gm: (f64, [(f64, f64); 3]),
    start: StartTimes,
    warm: bool,
    // --- the INS ---
    phase: Phase,
    /// Seconds since boot at the last navigation step.
    nav_t: f64,
    nom: Nominal,
    kf: Filter,
    q: ProcessNoise,
    /// Initial 1σ of the biases (the profile's turn-on biases), rad/s and
    /// m/s².
    bg0: f32,
    ba0: f32,
    /// Alignment sums: Δv and magnetometer readings, and their count.
    align_dv: V3,
    align_mag: V3,
    align_n: u32,
    /// Since the last covariance propagation: time, Σ Δv in NED.
    prop_dt: f64,
    prop_dv_n: V3,
    /// Index of the last receiver epoch (aiding instant).
    gnss_epoch: u64,
    /// The magnetometer field learnt in alignment: magnitude, dip (rad).
    mag_ref: Option<(f64, f64)>,
    mag_ok: bool,
    mag_aiding: bool,
    /// A magnetometer recalibration runs (`insStatus` MAG_RECALIBRATING).
    mag_recal: bool,
    gps_heading: bool,
    /// A GNSS update entered the solution in the last period.
    gps_step: bool,
    declination: f64,
    /// Seconds since boot when the declination was last evaluated.
    declination_at: f64,
    /// The position to save as `lastLla` (taken by the device).
    save_lla: Option<[f64; 3]>,
    saved_lla: Option<[f64; 3]>,
    /// A covariance propagation is due ([`NavState::work`]).
    prop_due: bool,
    /// The last navigation period, s.
    period_s: f64,
    /// The receiver epoch's work still to do ([`NavState::work`]).
    epoch: Option<Epoch>,
    /// The last receiver report and what it was made of
    /// ([`NavState::gps_report`]).
    report: Cell<Option<(ReportKey, GnssReport)>>,
    /// A GNSS update entered the state since the last period's start
    /// (shown as [`NavState::gps_step`] from the next period).
    gps_step_next: bool,
}

/// What a receiver epoch's aiding is read from: the readings themselves,
/// or the truth and the tick to read them of (on the ticks of
/// [`NavState::work`]).
#[derive(Debug, Clone, Copy)]
enum Input {
    /// The fix and the barometer and magnetometer readings.
    Read(Option<Fix>, Aiding),
    /// The truth at the epoch, its tick, the decimal year of its date.
    Truth(NavTruth, u64, f64),
}

/// The steps of a receiver epoch's work, in order (`docs/navigation.md`
/// "Firmware cost"): each a share of the tick budget, seven at most (the
/// ticks of a navigation period between its grid ticks).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
enum Stage {
    /// The covariance to the epoch.
    Propagate,
    /// The receiver's fix and the GNSS position updates.
    Fix,
    /// The GNSS velocity updates and their correction.
    GnssVel,
    /// The barometer's height (the AHRS's zero velocity).
    Baro,
    /// The declination, every [`DECLINATION_EVERY_S`].
    Declination,
    /// The magnetometer read and fused, the epoch's correction.
    MagUpdate,
    /// The receiver's report of the epoch ([`NavState::gps_report`]), of
    /// the fix [`Stage::Fix`] read, made ready for the GPS data sets (also
    /// with the filter off).
    Report,
    Done,
}

/// A receiver epoch in progress.
#[derive(Debug, Clone, Copy)]
struct Epoch {
    input: Input,
    cfg: NavConfig,
    stage: Stage,
    /// The fix (resolved at [`Stage::Fix`]) and the receiver's errors
    /// (position, velocity) it was made with (its report's key).
    fix: Option<Fix>,
    err: ([f64; 3], [f64; 3]),
    /// Fusing the fix: the antenna's lever arm in NED, the ground speed,
    /// the heading σ before the updates, whether it began NAV.
    ant: V3,
    speed: f64,
    hdg_sigma: f32,
    first: bool,
    /// The magnetometer's reading (resolved at [`Stage::MagUpdate`]).
    mag: [f32; 3],
    year: f64,
}

/// One Gauss–Markov step with `a = e^(−Δt/τ)` and `b = σ·√(1 − a²)`.
fn gm_step(x: &mut f64, (a, b): (f64, f64), w: f64) {
    *x = a * *x + b * w;
}

/// `(a, b)` of [`gm_step`] for `g` over `dt`.
fn gm_coefficients(g: &Gm, dt: f64) -> (f64, f64) {
    let a = exp(-dt / g.tau_s);
    (a, g.sigma * sqrt(1.0 - a * a))
}

/// The filter's process noise and initial bias σ of `profile`
/// (`docs/navigation.md` "Noise"): the white noise of each sensor as its
/// random walk; its bias instability B as a bias random walk reaching B in
/// [`BIAS_WALK_S`] (plus the profile's rate random walk); the turn-on
/// biases as the initial bias σ.
pub(crate) fn noise_of(profile: &SensorProfile) -> (ProcessNoise, f32, f32) {
    let g = crate::math::G;
    let d2r = core::f32::consts::PI / 180.0;
    let (gy, ac) = (&profile.gyro, &profile.acc);
    let arw = gy.noise_density * d2r;
    let vrw = ac.noise_density * g;
    let bi_g = gy.bias_instability * d2r;
    let bi_a = ac.bias_instability * g;
    let rrw_g = gy.rate_random_walk * d2r;
    let rrw_a = ac.rate_random_walk * g;
    // Temperature: the bias moves with the sensor's warm-up (temp_bias per
    // °C over the self-heating): folded into the walk's size.
    let heat = profile.temperature.self_heating_c.abs().max(1.0);
    let drift_g = bi_g + gy.temp_bias * d2r * heat;
    let drift_a = bi_a + ac.temp_bias * g * heat;
    (
        ProcessNoise {
            vel: vrw * vrw,
            att: arw * arw,
            bg: drift_g * drift_g / BIAS_WALK_S + rrw_g * rrw_g,
            ba: drift_a * drift_a / BIAS_WALK_S + rrw_a * rrw_a,
        },
        gy.turn_on_bias_sigma * d2r,
        ac.turn_on_bias_sigma * g,
    )
}

/// The index of the receiver epoch a time `t_s` falls in (`gps_dt_s`
/// apart).
fn epoch_of(t_s: f64, gps_dt_s: f64) -> u64 {
    (t_s / gps_dt_s.max(1e-3) + 1e-6) as u64
}

/// The time over which the bias random walk of [`noise_of`] reaches the
/// profile's bias instability (plus temperature drift), s.
pub(crate) const BIAS_WALK_S: f32 = 100.0;

impl NavState {
    /// Power-on state for `seed` (receiver errors drawn at their steady
    /// state), with the IMX-5's profile until [`NavState::set_profile`].
    pub fn new(seed: u64) -> Self {
        let mut rng = Rng::new(seed ^ 0x4E41_5600);
        let mut draw = |g: &Gm| g.sigma * f64::from(rng.gaussian());
        let h3 = |d: &mut dyn FnMut(&Gm) -> f64, h: &Gm, v: &Gm| [d(h), d(h), d(v)];
        let gnss_pos = h3(&mut draw, &GNSS_POS_H, &GNSS_POS_V);
        let gnss_vel = h3(&mut draw, &GNSS_VEL, &GNSS_VEL);
        let (q, bg0, ba0) = noise_of(&crate::sensor::profiles::IMX5_PROFILE);
        NavState {
            rng,
            seed,
            t_s: 0.0,
            faults: NavFaults::default(),
            fixed: false,
            ever_fixed: false,
            outage_at: None,
            gnss_pos,
            gnss_vel,
            baro_frozen: None,
            year: GpsTime::of_ns(DEFAULT_GPS_S_AT_ZERO * 1_000_000_000).decimal_year(),
            field: FieldMemo::new(),
            gm: (-1.0, [(0.0, 0.0); 3]),
            start: StartTimes::default(),
            warm: false,
            phase: Phase::Aligning,
            nav_t: 0.0,
            nom: Nominal::at(&[0.0; 3]),
            kf: Filter::new(&[0.0; N]),
            q,
            bg0,
            ba0,
            align_dv: [0.0; 3],
            align_mag: [0.0; 3],
            align_n: 0,
            prop_dt: 0.0,
            prop_dv_n: [0.0; 3],
            gnss_epoch: 0,
            mag_ref: None,
            mag_ok: false,
            mag_aiding: false,
            mag_recal: false,
            gps_heading: false,
            gps_step: false,
            declination: 0.0,
            declination_at: 0.0,
            save_lla: None,
            saved_lla: None,
            prop_due: false,
            period_s: 0.0,
            epoch: None,
            gps_step_next: false,
            report: Cell::new(None),
        }
    }

    /// Sets the date the magnetometer reads the field at (decimal year,
    /// UTC: [`GpsTime::decimal_year`] of the unit's GPS clock).
    pub(crate) fn set_year(&mut self, year: f64) {
        self.year = year;
    }

    /// The sensor profile the filter is tuned for (the unit's own).
    pub(crate) fn set_profile(&mut self, profile: &SensorProfile) {
        let (q, bg0, ba0) = noise_of(profile);
        self.q = q;
        self.bg0 = bg0;
        self.ba0 = ba0;
    }

    /// Boots the INS from FLASH_CONFIG: at `lastLla`; a warm start if an
    /// earlier NAV saved it (`lastLlaWeek` ≠ 0), else cold.
    pub fn boot(&mut self, cfg: &NavConfig, start: StartTimes) {
        self.start = start;
        self.warm = cfg.last_lla_week != 0;
        self.nom = Nominal::at(&cfg.last_lla);
        if self.warm {
            self.saved_lla = Some(cfg.last_lla);
        }
    }

    /// Whether the navigation filter runs (from power-on it does). Off,
    /// the INS reports no solution (`insStatus` solution 0, `lastLla`, at
    /// rest, level, facing north: [`NavState::solution`]) and computes
    /// nothing of its own but the receiver's report of each epoch, made
    /// ready on the ticks before it as with the filter ([`Stage::Report`]:
    /// the firmware's tick budget); the aiding sensors' models (GNSS receiver,
    /// magnetometer, barometer) and their data sets run as before. What an
    /// image serves whose processor cannot afford the filter
    /// (`docs/navigation.md` "Firmware cost": the RP2040). On again, the
    /// INS starts aligning.
    pub(crate) fn set_enabled(&mut self, on: bool) {
        match (on, self.phase) {
            (false, _) => {
                self.phase = Phase::Off;
                self.epoch = None;
                self.prop_due = false;
            }
            // An epoch begun with the filter off was for the report only.
            (true, Phase::Off) => {
                self.phase = Phase::Aligning;
                self.epoch = None;
            }
            _ => {}
        }
    }

    /// The receiver's time to first fix for this power-on, s.
    pub(crate) fn ttff_s(&self) -> f64 {
        if self.warm {
            self.start.warm_s
        } else {
            self.start.cold_s
        }
    }

    /// Whether this power-on is a warm start.
    pub fn warm_start(&self) -> bool {
        self.warm
    }

    /// The faults in force.
    pub(crate) fn faults(&self) -> NavFaults {
        self.faults
    }

    /// Sets the injected faults (they act from the next step).
    pub(crate) fn set_faults(&mut self, f: NavFaults) {
        self.faults = f;
    }

    /// Whether the receiver has a fix now.
    pub fn has_fix(&self) -> bool {
        self.fixed
    }

    /// Whether GPS time is known (a fix was had since power-on).
    pub(crate) fn gps_time_valid(&self) -> bool {
        self.ever_fixed
    }

    /// The INS phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The filter's nominal state (position, velocity, attitude of the IMU,
    /// estimated biases).
    pub fn nominal(&self) -> &Nominal {
        &self.nom
    }

    /// The filter's covariance.
    pub fn filter(&self) -> &Filter {
        &self.kf
    }

    /// A position to save as `lastLla` now (the INS moved far enough from
    /// the saved one, or none was saved), taken once.
    pub(crate) fn take_last_lla(&mut self) -> Option<[f64; 3]> {
        self.save_lla.take()
    }

    /// Advances the receiver, barometer and fault models to `t_s` seconds
    /// since boot at `truth` (called every [`STEP_MS`]).
    pub fn step(&mut self, t_s: f64, truth: &NavTruth) {
        let dt = (t_s - self.t_s).max(0.0);
        self.t_s = t_s;
        let was_fixed = self.fixed;
        self.fixed = !self.faults.gps_off && t_s >= self.ttff_s();
        self.ever_fixed |= self.fixed;
        let mut w = [0.0f64; 6];
        for x in w.iter_mut() {
            *x = f64::from(self.rng.gaussian());
        }
        // The step is fixed, but `dt` is a difference of seconds since
        // boot that rounds differently from step to step: the coefficients
        // (an `exp` and a `sqrt` each, soft double precision on the
        // firmware) are computed again only when it changes by more than
        // a nanosecond (their relative change then is under 10⁻¹⁰).
        let same_step = (self.gm.0 - dt).abs() <= 1e-9;
        if !same_step {
            self.gm = (
                dt,
                [
                    gm_coefficients(&GNSS_POS_H, dt),
                    gm_coefficients(&GNSS_POS_V, dt),
                    gm_coefficients(&GNSS_VEL, dt),
                ],
            );
        }
        let c = self.gm.1;
        for k in 0..3 {
            gm_step(&mut self.gnss_pos[k], c[if k < 2 { 0 } else { 1 }], w[k]);
            gm_step(&mut self.gnss_vel[k], c[2], w[3 + k]);
        }
        if self.phase == Phase::Nav && !self.fixed {
            if was_fixed || self.outage_at.is_none() {
                self.outage_at = Some(t_s);
            }
        } else {
            self.outage_at = None;
        }
        // A failed barometer keeps the reading it had when it failed.
        if !self.faults.baro_failed {
            self.baro_frozen = None;
        } else if self.baro_frozen.is_none() {
            self.baro_frozen =
                Some(isa_kpa(truth.h_m - geoid_undulation_m(truth.lat_deg, truth.lon_deg)) as f32);
        }
    }

    /// Seconds since the current GNSS outage began (in NAV), if in one.
    pub fn outage_s(&self) -> Option<f64> {
        self.outage_at.map(|a| self.t_s - a)
    }

    /// Whether the navigation period ending `t_s` is the last before a
    /// receiver epoch (`gps_dt_s` apart): the aiding
    /// [`NavState::navigate`] then wants (the epoch's work is done over
    /// the next period, its correction enters the state as that period
    /// ends, on the epoch).
    pub fn epoch_due(&self, t_s: f64, gps_dt_s: f64) -> bool {
        epoch_of(self.epoch_t(t_s, self.period_s), gps_dt_s) != self.gnss_epoch
    }

    /// The time of the epoch a period ending `t_s` (of `dt`) reads the
    /// aiding for: the end of the next period, but in alignment (which
    /// only sums) its own end.
    fn epoch_t(&self, t_s: f64, dt: f64) -> f64 {
        if self.phase == Phase::Aligning {
            t_s
        } else {
            t_s + dt
        }
    }

    /// One navigation period ending `t_s` seconds since boot: the
    /// mechanisation of the unit's IMU increment `inc`, then, at each
    /// receiver epoch ([`NavState::epoch_due`]), the aiding
    /// (`docs/navigation.md` "Phases"): `aiding` is the receiver's fix (the
    /// antenna's position and NED velocity) and the barometer and
    /// magnetometer, given at epochs only (reading them costs: the
    /// firmware's tick budget).
    pub fn navigate(
        &mut self,
        t_s: f64,
        inc: &Increment,
        gps_dt_s: f64,
        aiding: Option<(Option<Fix>, Aiding)>,
        cfg: &NavConfig,
    ) {
        self.begin(
            t_s,
            inc,
            gps_dt_s,
            aiding.map(|(f, a)| (Input::Read(f, a), cfg)),
        );
    }

    /// [`NavState::navigate`] with the epoch's aiding read by the INS
    /// itself, from the truth `truth` at tick `tick` (the date `year`),
    /// on the ticks of [`NavState::work`]: what the device does, so that
    /// no tick carries a whole epoch (the firmware's tick budget). The
    /// configuration `cfg` comes with the epoch: the INS reads nothing of
    /// it between epochs (its parse on every period was a tick's margin on
    /// the M4F).
    pub(crate) fn navigate_truth(
        &mut self,
        t_s: f64,
        inc: &Increment,
        gps_dt_s: f64,
        epoch: Option<(NavTruth, u64, f64, &NavConfig)>,
    ) {
        self.begin(
            t_s,
            inc,
            gps_dt_s,
            epoch.map(|(t, k, y, cfg)| (Input::Truth(t, k, y), cfg)),
        );
    }

    /// One navigation period: the last period's work finished (and its
    /// correction in the state), the mechanisation; the covariance
    /// propagation and the epoch's aiding left to [`NavState::work`].
    fn begin(
        &mut self,
        t_s: f64,
        inc: &Increment,
        gps_dt_s: f64,
        input: Option<(Input, &NavConfig)>,
    ) {
        while self.work() {}
        self.nav_t = t_s;
        self.gps_step = core::mem::take(&mut self.gps_step_next);
        self.mag_aiding &= self.mag_ok;
        if inc.dt.is_nan() || inc.dt <= 0.0 {
            return;
        }
        self.period_s = inc.dt;
        // The epoch at the end of the next period: its aiding is read now
        // and fused on the ticks of that period.
        let epoch = epoch_of(self.epoch_t(t_s, inc.dt), gps_dt_s);
        let due = epoch != self.gnss_epoch;
        self.gnss_epoch = epoch;
        let input = if due { input } else { None };
        if self.phase == Phase::Aligning {
            let aid = input.map(|(i, cfg)| match i {
                Input::Read(_, a) => (a, cfg),
                Input::Truth(truth, tick, year) => (
                    Aiding {
                        mag: self.magnetometer(&truth, tick),
                        pressure_kpa: 0.0,
                        year,
                    },
                    cfg,
                ),
            });
            self.align(t_s, inc, aid);
            return;
        }
        // The filter off, the epoch's work is the receiver's report alone
        // ([`Stage::Report`]), made ready ahead of the epoch all the same.
        if self.phase != Phase::Off {
            let dv_n = self.nom.mechanise(inc);
            self.prop_dt += inc.dt;
            self.prop_dv_n = [0, 1, 2].map(|k| self.prop_dv_n[k] + dv_n[k]);
            self.prop_due = self.prop_dt >= PROPAGATE_S - 1e-9;
        }
        // Every aiding source enters at the receiver's epochs, so the state
        // steps only there (GPS_UPDATE_IN_SOLUTION marks those with a fix,
        // on the next period's outputs); between them the position is the
        // integral of the velocity.
        self.epoch = input.map(|(input, cfg)| {
            let (fix, aid) = match input {
                Input::Read(f, a) => (f, a),
                Input::Truth(_, _, year) => (
                    None,
                    Aiding {
                        mag: [0.0; 3],
                        pressure_kpa: 0.0,
                        year,
                    },
                ),
            };
            Epoch {
                input,
                cfg: *cfg,
                stage: Stage::Propagate,
                fix,
                err: ([0.0; 3], [0.0; 3]),
                ant: [0.0; 3],
                speed: 0.0,
                hdg_sigma: 0.0,
                first: false,
                mag: aid.mag,
                year: aid.year,
            }
        });
    }

    /// One share of the navigation's pending work — the covariance
    /// propagation, then a receiver epoch's steps in order (reading the
    /// aiding, the GNSS position updates, the velocity updates, the
    /// barometer, the declination, the magnetometer) — on a tick between
    /// navigation periods; whatever is left when the next period begins
    /// is done then, so the result does not depend on how the work is
    /// spread. Returns whether there was any.
    pub(crate) fn work(&mut self) -> bool {
        if self.prop_due {
            self.prop_due = false;
            self.propagate();
            return true;
        }
        let Some(mut e) = self.epoch.take() else {
            return false;
        };
        loop {
            let stage = e.stage;
            e.stage = match stage {
                Stage::Propagate => Stage::Fix,
                Stage::Fix => Stage::GnssVel,
                Stage::GnssVel => Stage::Baro,
                Stage::Baro => Stage::Declination,
                Stage::Declination => Stage::MagUpdate,
                Stage::MagUpdate => Stage::Report,
                Stage::Report | Stage::Done => Stage::Done,
            };
            let busy = self.stage(&mut e, stage);
            if e.stage == Stage::Done {
                return true;
            }
            if busy {
                self.epoch = Some(e);
                return true;
            }
        }
    }

    /// One step of a receiver epoch; whether it had anything to do.
    fn stage(&mut self, e: &mut Epoch, stage: Stage) -> bool {
        let cfg = e.cfg;
        // The filter off, only the receiver's fix and report are made.
        let on = self.phase != Phase::Off;
        if !on && !matches!(stage, Stage::Fix | Stage::Report) {
            return false;
        }
        let mag_fusion = cfg.sys_cfg_bits & SYS_CFG_NO_MAG_FUSION == 0;
        let gps_fusion = on && cfg.sys_cfg_bits & SYS_CFG_NO_GPS1_FUSION == 0;
        match stage {
            Stage::Propagate => self.propagate(),
            Stage::Fix => {
                // The fix the report is made of too ([`Stage::Report`]):
                // one conversion a step (the firmware's tick budget).
                let mut read = false;
                if let Input::Truth(truth, _, _) = e.input {
                    e.fix = self.gnss(&truth, &cfg);
                    e.err = (self.gnss_pos, self.gnss_vel);
                    read = e.fix.is_some();
                }
                match e.fix {
                    Some(fix) if gps_fusion => {
                        self.fuse_gnss_pos(e, &fix);
                        true
                    }
                    _ => read,
                }
            }
            Stage::GnssVel => match e.fix {
                Some(fix) if gps_fusion => {
                    self.fuse_gnss_vel(e, &fix);
                    true
                }
                _ => false,
            },
            Stage::Baro => self.fuse_baro(e),
            Stage::Declination => {
                // The field model is dear (a spherical-harmonic sum) and the
                // declination changes slowly: evaluated every
                // DECLINATION_EVERY_S.
                if mag_fusion && self.nav_t - self.declination_at >= DECLINATION_EVERY_S {
                    let lla = self.nom.lla();
                    self.declination = declination_deg(lla[0], lla[1], lla[2], e.year).to_radians();
                    self.declination_at = self.nav_t;
                    true
                } else {
                    false
                }
            }
            Stage::MagUpdate => {
                if let Input::Truth(truth, tick, _) = e.input {
                    if mag_fusion && self.mag_ref.is_some() {
                        e.mag = self.magnetometer(&truth, tick);
                    }
                }
                self.fuse_mag(e);
                self.check_last_lla(&cfg);
                true
            }
            // The truth of a unit at a built-in site (every firmware
            // image's) does not move: the report made here, of the epoch's
            // fix, is the one the epoch's GPS data sets find. A moving
            // vehicle's is made again when they are sent.
            Stage::Report => match (e.input, e.fix) {
                (Input::Truth(truth, _, _), Some(fix)) => {
                    let key = ReportKey::of(&truth, &cfg, &e.err);
                    if self.report.get().is_some_and(|(k, _)| k == key) {
                        return false;
                    }
                    self.remember_report(key, fix);
                    true
                }
                _ => false,
            },
            Stage::Done => false,
        }
    }

    /// Coarse alignment: sums until [`ALIGN_S`] (the magnetometer at the
    /// receiver's epochs), then, at the first epoch from there, roll and
    /// pitch from the mean specific force, heading from the levelled mean
    /// magnetometer reading and the declination, the covariance from the
    /// profile.
    fn align(&mut self, t_s: f64, inc: &Increment, aid: Option<(Aiding, &NavConfig)>) {
        self.align_dv = [0, 1, 2].map(|k| self.align_dv[k] + inc.dv[k]);
        let Some((aid, cfg)) = aid else {
            return;
        };
        self.align_mag = [0, 1, 2].map(|k| self.align_mag[k] + f64::from(aid.mag[k]));
        self.align_n += 1;
        if t_s < ALIGN_S - 1e-9 {
            return;
        }
        let f = self.align_dv;
        let roll = atan2(f[1], -f[2]);
        let pitch = atan2(f[0], sqrt(f[1] * f[1] + f[2] * f[2]));
        let n = f64::from(self.align_n.max(1));
        let m = self.align_mag.map(|x| x / n);
        let lvl = rotate(&quat_from_euler(roll, pitch, 0.0), &m);
        let norm = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        let use_mag = cfg.sys_cfg_bits & SYS_CFG_NO_MAG_FUSION == 0 && norm > 0.0;
        let lla = self.nom.lla();
        self.declination = declination_deg(lla[0], lla[1], lla[2], aid.year).to_radians();
        self.declination_at = t_s;
        let yaw = if use_mag {
            self.mag_ref = Some((norm, libm::asin((lvl[2] / norm).clamp(-1.0, 1.0))));
            self.declination - atan2(lvl[1], lvl[0])
        } else {
            0.0
        };
        self.nom.q = quat_from_euler(roll, pitch, yaw);
        let tilt = (self.ba0 / 9.81).max(0.002);
        let hdg = if use_mag {
            3.0 * MAG_HEADING_SIGMA
        } else {
            core::f32::consts::PI
        };
        let mut s = [0.0f32; N];
        for k in 0..3 {
            s[POS + k] = 100.0;
            s[VEL + k] = AHRS_VEL_SIGMA;
            s[BG + k] = self.bg0;
            s[BA + k] = self.ba0;
        }
        s[ATT] = tilt;
        s[ATT + 1] = tilt;
        s[ATT + 2] = hdg;
        self.kf = Filter::new(&s);
        self.mag_ok = use_mag;
        self.phase = Phase::Ahrs;
    }

    /// The covariance over the periods since the last propagation;
    /// whether there were any.
    fn propagate(&mut self) -> bool {
        let dt = self.prop_dt;
        if dt <= 0.0 {
            return false;
        }
        let f_n = self.prop_dv_n.map(|x| (x / dt) as f32);
        // The Earth's terms at the position, on this tick rather than a
        // navigation period's (`mech`'s anchor).
        self.nom.refresh();
        let (e, v) = (self.nom.earth, self.nom.v);
        let (nh, mh) = (e.rn + self.nom.h, e.rm + self.nom.h);
        let w_in = [
            wgs84::OMEGA_IE * e.cos_lat + v[1] / nh,
            -v[0] / mh,
            -wgs84::OMEGA_IE * e.sin_lat - v[1] * e.sin_lat / (e.cos_lat * nh),
        ]
        .map(|x| x as f32);
        let iv = Interval {
            dt: dt as f32,
            f_n,
            // The same DCM as `math::double`'s, in the covariance's `f32`.
            c_nb: crate::math::rotation::dcm_from_quat(&self.nom.q.map(|x| x as f32)),
            w_in,
            grav_grad: (2.0 * e.g / wgs84::A) as f32,
        };
        self.kf.propagate(&iv, &self.q);
        self.prop_dt = 0.0;
        self.prop_dv_n = [0.0; 3];
        true
    }

    /// Adds the filter's estimate to the nominal state.
    fn correct(&mut self) {
        let dx = self.kf.take_correction();
        if dx.iter().all(|x| x.is_finite()) {
            self.nom.correct(&dx);
        }
    }

    /// A GNSS epoch's position: the first fix starts NAV (position and
    /// velocity set from it); after that, three scalar updates (position
    /// NED), the antenna's lever arm taken out.
    fn fuse_gnss_pos(&mut self, e: &mut Epoch, fix: &Fix) {
        let (lla, v) = fix;
        let ant = if e.cfg.gps1_ant_offset == [0.0; 3] {
            [0.0; 3]
        } else {
            rotate(&self.nom.q, &e.cfg.gps1_ant_offset.map(f64::from))
        };
        e.ant = ant;
        e.speed = libm::hypot(v[0], v[1]);
        e.hdg_sigma = self.kf.sigma(ATT + 2);
        e.first = self.phase != Phase::Nav;
        if e.first {
            // NAV from the first fix: position and velocity from it.
            self.nom = Nominal {
                lat: lla[0].to_radians(),
                lon: lla[1].to_radians(),
                h: lla[2],
                v: *v,
                ..self.nom
            };
            self.nom.move_ned(&ant.map(|x| -x));
            let (h, vv) = (H_ACC_M / core::f32::consts::SQRT_2, V_ACC_M);
            self.kf.reset3(POS, [h, h, vv]);
            let s = S_ACC_MPS;
            self.kf.reset3(VEL, [s, s, s]);
            // A magnetometer heading was taken with the declination at
            // `lastLla` (before the first fix the only position known); at
            // the fix's position the declination differs, and the heading
            // with it (a change the heading gate would refuse as an update).
            let p = self.nom.lla();
            let d = declination_deg(p[0], p[1], p[2], self.year).to_radians();
            if self.mag_ref.is_some() {
                let e = euler_from_quat(&self.nom.q);
                self.nom.q = quat_from_euler(e[0], e[1], e[2] + (d - self.declination));
            }
            self.declination = d;
            self.declination_at = self.nav_t;
            self.phase = Phase::Nav;
        } else {
            // The radii and the latitude's cosine of the mechanisation's
            // anchor (a few metres away: 10⁻⁸ of a residual of metres).
            let e = self.nom.earth;
            let p = self.nom.lla();
            let d = [
                (lla[0] - p[0]).to_radians() * (e.rm + p[2]) - ant[0],
                // Across ±180° the difference of longitudes wraps.
                crate::math::double::wrap_pi((lla[1] - p[1]).to_radians())
                    * (e.rn + p[2])
                    * e.cos_lat
                    - ant[1],
                -(lla[2] - p[2]) - ant[2],
            ];
            let h = H_ACC_M / core::f32::consts::SQRT_2;
            let r_pos = [h * h, h * h, V_ACC_M * V_ACC_M];
            for (k, (dk, r)) in d.iter().zip(r_pos).enumerate() {
                self.kf.update(&[(POS + k, 1.0)], *dk as f32, r, 0.0);
            }
        }
    }

    /// A GNSS epoch's velocity: three scalar updates (none at the fix
    /// that began NAV), the correction; the heading from the course over
    /// ground once moving, when nothing else has given one.
    fn fuse_gnss_vel(&mut self, e: &Epoch, fix: &Fix) {
        let v = &fix.1;
        if !e.first {
            let sv = S_ACC_MPS / 1.732;
            for (k, (vk, nk)) in v.iter().zip(self.nom.v).enumerate() {
                self.kf
                    .update(&[(VEL + k, 1.0)], (vk - nk) as f32, sv * sv, 0.0);
            }
            self.correct();
        }
        self.gps_step_next = true;
        if e.hdg_sigma > status::HDG_COARSE_RAD && e.speed > GPS_HEADING_MIN_SPEED {
            let a = euler_from_quat(&self.nom.q);
            let yaw = atan2(v[1], v[0]);
            self.nom.q = quat_from_euler(a[0], a[1], yaw);
            self.kf.reset1(ATT + 2, GPS_HEADING_SIGMA);
        }
        self.gps_heading = e.speed > GPS_HEADING_MIN_SPEED;
    }

    /// Before the first fix the AHRS's zero-velocity assumption; in NAV
    /// the barometer's height. Whether there was anything to do.
    fn fuse_baro(&mut self, e: &Epoch) -> bool {
        if self.phase == Phase::Ahrs {
            for k in 0..3 {
                let y = -self.nom.v[k] as f32;
                self.kf
                    .update(&[(VEL + k, 1.0)], y, AHRS_VEL_SIGMA * AHRS_VEL_SIGMA, 0.0);
            }
            return true;
        }
        if e.cfg.sys_cfg_bits & SYS_CFG_NO_BARO_FUSION != 0 || self.phase != Phase::Nav {
            return false;
        }
        let p = match e.input {
            Input::Read(_, a) => a.pressure_kpa,
            Input::Truth(truth, tick, _) => self.pressure_kpa(&truth, tick),
        };
        if p > 0.0 {
            let lla = self.nom.lla();
            // ISA's height in `f32` (the FPU): 3 mm of rounding against
            // the measurement's 0.5 m.
            let isa = (1.0 - libm::powf(p / 101.325, 1.0 / 5.255_88)) / 2.255_77e-5;
            let h = f64::from(isa) + geoid_undulation_m(lla[0], lla[1]);
            let y = (lla[2] - h) as f32;
            self.kf
                .update(&[(POS + 2, 1.0)], y, BARO_SIGMA_M * BARO_SIGMA_M, 5.0);
        }
        true
    }

    /// The magnetometer's heading, then the epoch's correction.
    fn fuse_mag(&mut self, e: &Epoch) {
        self.mag_ok = false;
        if e.cfg.sys_cfg_bits & SYS_CFG_NO_MAG_FUSION == 0 {
            if let Some(y) = self.mag_residual(&e.mag) {
                let r = MAG_HEADING_SIGMA * MAG_HEADING_SIGMA;
                match self.kf.update(&[(ATT + 2, 1.0)], y, r, MAG_GATE) {
                    Update::Applied(_) => {
                        self.mag_ok = true;
                        self.mag_aiding = true;
                    }
                    _ => self.mag_aiding = false,
                }
            } else {
                self.mag_aiding = false;
            }
        }
        self.correct();
    }

    /// The magnetometer's heading minus the estimate's, rad, if the
    /// reading looks like the field learnt in alignment. With the reading
    /// turned into NED (`m_n = C m`), the levelled reading is `m_n` turned
    /// back by the heading ψ about the vertical: its dip is `m_n`'s, and
    /// the measured heading `D − atan2(lvl_E, lvl_N)` less ψ is `D −
    /// atan2(m_n,E, m_n,N)`. In `f32` (the FPU; 10⁻⁷ rad against a 1°
    /// measurement).
    fn mag_residual(&self, mag: &[f32; 3]) -> Option<f32> {
        let (norm0, dip0) = self.mag_ref?;
        let c = crate::math::rotation::dcm_from_quat(&self.nom.q.map(|x| x as f32));
        let m = crate::math::rotation::mat_vec(&c, mag);
        let norm = libm::sqrtf(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if norm.is_nan()
            || norm <= 0.0
            || (f64::from(norm) / norm0 - 1.0).abs() > MAG_NORM_TOLERANCE
        {
            return None;
        }
        let dip = libm::asinf((m[2] / norm).clamp(-1.0, 1.0));
        if (f64::from(dip) - dip0).abs() > MAG_DIP_TOLERANCE {
            return None;
        }
        let y = self.declination as f32 - libm::atan2f(m[1], m[0]);
        Some(crate::math::double::wrap_pi(f64::from(y)) as f32)
    }

    /// `insStatus` now ([`status`]; MAG_RECALIBRATING while a
    /// recalibration runs, [`super::magcal`]).
    pub fn ins_status(&self) -> u32 {
        let s = status::ins_status(&status::Inputs {
            phase: self.phase,
            kf: &self.kf,
            fixed: self.fixed,
            mag_aiding: self.mag_aiding,
            mag_interference: self.mag_ref.is_some() && !self.mag_ok,
            gps_heading: self.gps_heading && self.fixed,
            gps_step: self.gps_step,
        });
        if self.mag_recal {
            s | super::magcal::INS_STATUS_MAG_RECALIBRATING
        } else {
            s
        }
    }

    /// Marks a magnetometer recalibration as running or not.
    pub(crate) fn set_mag_recalibrating(&mut self, on: bool) {
        self.mag_recal = on;
    }

    /// The magnetometer reading `m` (body axes) levelled with the INS's
    /// own roll and pitch: north-ish, east-ish, down components.
    pub(crate) fn mag_levelled(&self, m: &[f32; 3]) -> [f64; 3] {
        let e = euler_from_quat(&self.nom.q);
        rotate(&quat_from_euler(e[0], e[1], 0.0), &m.map(f64::from))
    }

    /// A recalibration's result: the field's magnitude and dip (rad) the
    /// magnetometer's readings are checked against from now on (what
    /// alignment learnt until then).
    pub(crate) fn set_mag_reference(&mut self, norm: f64, dip: f64) {
        if norm.is_finite() && norm > 0.0 && dip.is_finite() {
            self.mag_ref = Some((norm, dip));
        }
    }

    /// The navigation bits of `hdwStatus` now.
    pub(crate) fn hdw_bits(&self) -> u32 {
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

    /// The INS solution of the output point (`insRotation`, `insOffset`):
    /// the filter's state; while aligning level, facing north, at rest at
    /// `lastLla`; as an AHRS (position and velocity not estimated) the
    /// filter's attitude at `lastLla`, at rest.
    pub fn solution(&self, cfg: &NavConfig) -> Solution {
        // The usual insRotation is none: no trigonometry then.
        let q_nb = if cfg.ins_rotation == [0.0; 3] {
            self.nom.q
        } else {
            let [r, p, y] = cfg.ins_rotation.map(f64::from);
            normalize(&quat_mul(&self.nom.q, &quat_from_euler(r, p, y)))
        };
        match self.phase {
            Phase::Off | Phase::Aligning => Solution {
                lla: cfg.last_lla,
                v_ned: [0.0; 3],
                q_nb: [1.0, 0.0, 0.0, 0.0],
            },
            Phase::Ahrs => Solution {
                lla: cfg.last_lla,
                v_ned: [0.0; 3],
                q_nb,
            },
            Phase::Nav => {
                // The usual insOffset is none: no conversion then.
                let lla = if cfg.ins_offset == [0.0; 3] {
                    self.nom.lla()
                } else {
                    let lever = rotate(&q_nb, &cfg.ins_offset.map(f64::from));
                    lla_plus_ned(&self.nom.lla(), &lever)
                };
                Solution {
                    lla,
                    v_ned: self.nom.v,
                    q_nb,
                }
            }
        }
    }

    /// Asks for `lastLla` to be saved when in NAV with a fix and the INS
    /// has moved far enough from the saved one (`docs/navigation.md`
    /// "Warm start"); at each receiver epoch.
    fn check_last_lla(&mut self, cfg: &NavConfig) {
        if self.phase != Phase::Nav || !self.fixed {
            return;
        }
        let lla = self.nom.lla();
        let far = match self.saved_lla {
            None => true,
            Some(s) => {
                let d = ned_from_ref(&lla, &s);
                let limit = if cfg.last_lla_update_distance > 0.0 {
                    f64::from(cfg.last_lla_update_distance)
                } else {
                    LAST_LLA_DEFAULT_DISTANCE_M
                };
                sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > limit
            }
        };
        if far {
            self.saved_lla = Some(lla);
            self.save_lla = Some(lla);
        }
    }

    /// INL2_STATES now (`tow`: GPS time of week, s): the filter's state of
    /// the IMU (sensor frame), its biases, the declination and the dip it
    /// uses; no barometer bias is estimated (0).
    pub fn inl2_states(&self, tow: f64) -> Inl2States {
        let lla = self.nom.lla();
        let qe2n = quat_e2n(lla[0], lla[1]);
        Inl2States {
            time_of_week: tow,
            qe2b: f32s(quat_mul(&qe2n, &self.nom.q)),
            ve: f32s(rotate(&qe2n, &self.nom.v)),
            ecef: ecef_of(&lla),
            bias_pqr: f32s(self.nom.bg),
            bias_acc: f32s(self.nom.ba),
            bias_baro: 0.0,
            mag_dec: self.declination as f32,
            mag_inc: self.mag_ref.map_or(0.0, |(_, d)| d as f32),
        }
    }

    /// The filter's attitude 1σ as roll, pitch and heading, rad: the tilt
    /// σ (the rms of the north and east attitude errors' σ, whatever the
    /// heading) for roll and pitch, the down error's σ for heading.
    pub(crate) fn attitude_sigma_rad(&self) -> [f32; 3] {
        let (n, e, d) = (
            self.kf.sigma(ATT),
            self.kf.sigma(ATT + 1),
            self.kf.sigma(ATT + 2),
        );
        let tilt = libm::sqrtf((n * n + e * e) / 2.0);
        [tilt, tilt, d]
    }

    /// INL2_NED_SIGMA now (`tow_ms`: GPS time of week, ms): the square
    /// roots of the covariance's diagonal; the barometer bias and the
    /// declination are not estimated (0).
    pub fn inl2_ned_sigma(&self, tow_ms: u32) -> Inl2NedSigma {
        let s = |i: usize| [0, 1, 2].map(|k| self.kf.sigma(i + k));
        Inl2NedSigma {
            time_of_week_ms: tow_ms,
            std_pos_ned: s(POS),
            std_vel_ned: s(VEL),
            std_att_ned: s(ATT),
            std_acc_bias: s(BA),
            std_gyr_bias: s(BG),
            std_bar_bias: 0.0,
            std_mag_declination: 0.0,
        }
    }

    /// The receiver's report of its fix now ([`GnssReport`]), if it has
    /// one: remembered with everything it is made of (the truth's
    /// position, velocity and — with an antenna offset — attitude, the
    /// receiver's errors, the offset), so that a report asked for again of
    /// the same is not converted again (soft double precision on the
    /// firmware: `Stage::Report`).
    pub fn gps_report(&self, truth: &NavTruth, cfg: &NavConfig) -> Option<GnssReport> {
        if !self.fixed {
            return None;
        }
        let key = ReportKey::of(truth, cfg, &(self.gnss_pos, self.gnss_vel));
        if let Some((k, r)) = self.report.get() {
            if k == key {
                return Some(r);
            }
        }
        let fix = self.gnss(truth, cfg)?;
        Some(self.remember_report(key, fix))
    }

    /// The report of the fix `(lla, v)` (its ECEF position and MSL
    /// height), remembered as made of `key`.
    fn remember_report(&self, key: ReportKey, (lla, v): Fix) -> GnssReport {
        let r = GnssReport {
            lla,
            v,
            ecef: ecef_of(&lla),
            h_msl: (lla[2] - geoid_undulation_m(lla[0], lla[1])) as f32,
        };
        self.report.set(Some((key, r)));
        r
    }

    /// The receiver's position (of the antenna) and NED velocity, if it
    /// has a fix: the truth plus the receiver's errors.
    pub fn gnss(&self, truth: &NavTruth, cfg: &NavConfig) -> Option<([f64; 3], [f64; 3])> {
        if !self.fixed {
            return None;
        }
        // The usual antenna offset is none: no rotation then.
        let ant = if cfg.gps1_ant_offset == [0.0; 3] {
            [0.0; 3]
        } else {
            rotate(&(truth.q_nb), &cfg.gps1_ant_offset.map(f64::from))
        };
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
    pub(crate) fn gps_sat(&self, t: &GpsTime) -> GpsSat {
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

    /// The magnetometer's reading (body axes, normalized units): the
    /// World Magnetic Model's field at the truth position and the date set
    /// by [`NavState::set_year`], scaled to unit length (the IMX reports a
    /// calibrated field "normalized": `docs/isb.md` "Magnetometer"), plus
    /// the disturbance, rotated into body axes, plus noise.
    pub fn magnetometer(&self, truth: &NavTruth, tick: u64) -> [f32; 3] {
        let b = self
            .field
            .field_ned_nt(truth.lat_deg, truth.lon_deg, truth.h_m, self.year);
        let n = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        let mut f = if n > 0.0 { b.map(|x| x / n) } else { [0.0; 3] };
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

/// The MSL height of ISA pressure `p` kPa, m (the inverse of [`isa_kpa`]).
pub fn isa_height_m(p: f64) -> f64 {
    (1.0 - pow(p / 101.325, 1.0 / 5.255_88)) / 2.255_77e-5
}

/// A decimal year of GPS seconds since the GPS epoch (1980-01-06 =
/// 1980.014; 365.25-day years, within a day: what a field model's secular
/// variation needs).
pub(crate) fn decimal_year(gps_s: f64) -> f64 {
    1980.0 + 5.0 / 366.0 + gps_s / (365.25 * 86_400.0)
}

/// Whether the navigation fields of a FLASH_CONFIG image are sane: `refLla`
/// and `lastLla` latitude within ±90°, longitude within ±360°, height within
/// −1 000…100 000 m, none NaN; `startupGPSDtMs` 200…60 000 ms; the lever
/// arms `insOffset` and `gps1AntOffset` within ±[`MAX_LEVER_ARM_M`] and
/// `insRotation` within ±2π rad on every axis (so none is NaN or infinite:
/// each goes into every INS and GPS position). A SET that would store
/// anything else is refused (NACK).
pub(crate) fn flash_nav_valid(image: &[u8]) -> bool {
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
pub(crate) const MAX_LEVER_ARM_M: f32 = 100.0;

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
    Ins1 {
        header: *h,
        theta: f32s(euler_from_quat(&s.q_nb)),
        uvw: uvw(s),
        lla: s.lla,
        ned: f32s(ned_from_ref(&s.lla, &cfg.ref_lla)),
    }
}

/// The body-frame velocity of `s`, in `f32` (the FPU; the field is `f32`).
fn uvw(s: &Solution) -> [f32; 3] {
    let c = crate::math::rotation::dcm_from_quat(&f32s(s.q_nb));
    crate::math::rotation::mat_t_vec(&c, &f32s(s.v_ned))
}

/// INS_2 of `s`.
pub fn ins2(h: &InsHeader, s: &Solution) -> Ins2 {
    Ins2 {
        header: *h,
        qn2b: f32s(s.q_nb),
        uvw: uvw(s),
        lla: s.lla,
    }
}

/// INS_3 of `s`: INS_2 plus the MSL height.
pub(crate) fn ins3(h: &InsHeader, s: &Solution) -> Ins3 {
    Ins3 {
        ins2: ins2(h, s),
        msl: (s.lla[2] - geoid_undulation_m(s.lla[0], s.lla[1])) as f32,
    }
}

/// INS_4 of `s`: ECEF.
pub(crate) fn ins4(h: &InsHeader, s: &Solution) -> Ins4 {
    let qe2n = quat_e2n(s.lla[0], s.lla[1]);
    Ins4 {
        header: *h,
        qe2b: f32s(quat_mul(&qe2n, &s.q_nb)),
        ve: f32s(rotate(&(qe2n), &s.v_ned)),
        ecef: ecef_of(&s.lla),
    }
}

/// `gps_pos_t.status` with a fix: the satellites used, a 3D fix, time
/// synchronised by the PPS (as hdwStatus says with a fix).
const FIX_STATUS: u32 = SATS as u32
    | (gps_status::FIX_3D << gps_status::FIX_SHIFT)
    | gps_status::FIX_OK
    | gps_status::TIME_PPS_SYNC;

/// GPS1_POS of a receiver epoch `t` (`report`: the receiver's report if it
/// has a fix, [`NavState::gps_report`]), `tow_offset` s.
pub fn gps_pos(t: &GpsTime, report: Option<&GnssReport>, tow_offset: f64) -> GpsPos {
    match report {
        Some(r) => GpsPos {
            week: t.week,
            time_of_week_ms: t.tow_ms(),
            status: FIX_STATUS,
            ecef: r.ecef,
            lla: r.lla,
            h_msl: r.h_msl,
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
pub(crate) fn gps_vel(t: &GpsTime, fix: Option<([f64; 3], [f64; 3])>) -> GpsVel {
    match fix {
        Some((lla, v)) => GpsVel {
            time_of_week_ms: t.tow_ms(),
            vel: f32s(rotate(&(quat_e2n(lla[0], lla[1])), &v)),
            s_acc: S_ACC_MPS,
            status: FIX_STATUS,
        },
        None => GpsVel {
            time_of_week_ms: t.tow_ms(),
            ..GpsVel::default()
        },
    }
}

/// MAGNETOMETER at `time` (s since boot).
pub(crate) fn magnetometer(time: f64, mag: [f32; 3]) -> Magnetometer {
    Magnetometer { time, mag }
}

/// BAROMETER at `time` (s since boot) for pressure `p` kPa and
/// temperature `temp` °C: `mslBar` by the SDK's `baro2msl`.
pub(crate) fn barometer(time: f64, p: f32, temp: f32) -> Barometer {
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

    /// The truth of a unit at rest, level, facing north at `lla`.
    fn still_at(lla: [f64; 3]) -> NavTruth {
        NavTruth {
            lat_deg: lla[0],
            lon_deg: lla[1],
            h_m: lla[2],
            v_ned: [0.0; 3],
            q_nb: [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// With the filter off an epoch's steps make the receiver's report
    /// ready and nothing else; the filter turned on in the middle of one
    /// starts aligning, the epoch not fused.
    #[test]
    fn the_filter_off_epoch_makes_the_report_only() {
        let truth = still_at([45.5, 7.25, 300.0]);
        let cfg = NavConfig::default();
        let inc = Increment {
            dtheta: [0.0; 3],
            dv: [0.0; 3],
            dt: 0.004,
        };
        let mut n = NavState::new(3);
        n.set_enabled(false);
        n.step(COLD_START_S + 1.0, &truth);
        // The period ending 4 ms before the epoch at 40 s takes its truth.
        let t = 40.0 - 0.004;
        n.navigate_truth(t - 0.004, &inc, 0.2, None);
        assert!(n.epoch_due(t, 0.2));
        let mut off = n.clone();
        off.navigate_truth(t, &inc, 0.2, Some((truth, 0, 2026.9, &cfg)));
        // The fix, then its report: two steps.
        assert!(off.work() && off.work() && !off.work());
        assert_eq!(off.phase(), Phase::Off);
        let want = n.gps_report(&truth, &cfg);
        assert!(want.is_some());
        assert_eq!(off.report.get().map(|(_, r)| r), want);
        n.navigate_truth(t, &inc, 0.2, Some((truth, 0, 2026.9, &cfg)));
        assert!(n.work());
        n.set_enabled(true);
        assert!(!n.work());
        assert_eq!(n.phase(), Phase::Aligning);
    }

    /// GPS1_SAT is a function of the seed (and the fix) only: the same
    /// seed gives the same records, another seed another bearing; none
    /// before the fix.
    #[test]
    fn the_constellation_comes_from_the_seed() {
        let truth = still_at([45.0, 0.0, 0.0]);
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
