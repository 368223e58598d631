//! Truth: what a perfect IMU would measure — the motion sources.
//!
//! A [`MotionSource`] yields, once per internal tick, the inertial angular
//! rate (what a perfect gyro measures, Earth rotation included) and the
//! specific force (what a perfect accelerometer measures) in the axes of the
//! IMU housing or of the carrier (see [`TruthFrame`]). The built-in sources
//! are the variants of [`Motion`]; a host plugs anything else (a trajectory
//! file player) through the trait, or pushes one [`Truth`] per tick with
//! [`Motion::Sample`].
//!
//! Physics (ICD 5.2 notes, 5.7):
//! - gravity: the specific force at rest is +1 g straight up, g = 9.8106 m/s²
//!   (the ICD's g); accelerometers output in g, so the built-ins never need
//!   the number itself;
//! - Earth rate Ω = 15.041 °/h; in the local ENU frame at latitude φ it is
//!   `Ω · (0, cos φ, sin φ)`. Transport rate is zero (the built-ins rotate
//!   and vibrate in place);
//! - the default site is latitude [`DEFAULT_LATITUDE_DEG`] = 50.1° N
//!   (Newlyn, Cornwall, where normal gravity is the ICD's g), heading 0
//!   (the housing's y axis points north), level, z up.
//!
//! [`BuiltinMotionFixed`] plays the same motions in integers for the
//! `fixed-point` build ([`TruthFixed`]); a unit test pins its agreement with
//! [`BuiltinMotion`].

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use crate::math::rotation::{
    canonical, quat_from_euler, quat_mul, quat_rotate_inv, Quat, QuatIntegrator, Vec3,
    QUAT_IDENTITY,
};
use crate::math::{cosf, sinf};
use crate::time::Instant;

/// Earth rotation rate, °/h (sidereal, 15.041 °/h).
pub(crate) const EARTH_RATE_DEG_PER_H: f32 = 15.041;
/// Earth rotation rate, rad/s.
pub(crate) const EARTH_RATE_RAD_S: f32 = EARTH_RATE_DEG_PER_H / 3600.0 * DEG;
/// Latitude of the default site, degrees north: the Newlyn Tidal
/// Observatory, Cornwall (50° 06.1′ N, docs/motion.md "The built-in
/// site"), where WGS84 normal gravity equals the ICD's g a few metres above
/// the pier, so the built-ins' +1 g at rest is physics there.
pub const DEFAULT_LATITUDE_DEG: f32 = 50.101_67;

const DEG: f32 = core::f32::consts::PI / 180.0;
const RAD: f32 = 180.0 / core::f32::consts::PI;

/// One tick of truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Inertial angular rate as a perfect gyro measures it, °/s.
    pub rate_dps: Vec3,
    /// Specific force as a perfect accelerometer measures it, g (at rest:
    /// +1 g along up).
    pub specific_force_g: Vec3,
    /// Sensor temperature, °C, if the source knows it (a trajectory file);
    /// `None` lets the temperature model decide.
    pub temperature_c: Option<f32>,
}

/// Largest angular rate handed to the sensor model, °/s: 8192, beyond every
/// gyro range (the IMX-5's ±4000 °/s included, so its over-range flag sees
/// a rate beyond it). The fixed-point build's truth stops at ±4095 °/s
/// (`RATE_TRUTH_LIMIT`, still beyond the IMX-5's range, so the flag sees
/// it; docs/sensors.md "Fixed point").
pub(crate) const TRUTH_RATE_LIMIT_DPS: f32 = 8192.0;
/// Largest specific force handed to the sensor model, g: 128, beyond every
/// accelerometer range.
pub(crate) const TRUTH_FORCE_LIMIT_G: f32 = 128.0;

impl Truth {
    /// The truth as the sensor model takes it: each rate clamped to
    /// ±[`TRUTH_RATE_LIMIT_DPS`], each specific force to
    /// ±[`TRUTH_FORCE_LIMIT_G`] — still beyond every range, so the axes
    /// saturate and the USW range bits (ICD Table 5.26, bits 10–12) are set
    /// as on a real sensor — and NaN read as 0 (as the fixed-point
    /// [`TruthFixed::from_truth`]). Without it an infinite or huge input
    /// (a trajectory value of 3.5e38) turns into NaN in the mounting and
    /// misalignment products (∞·0, ∞ − ∞), which read as 0 with no flag.
    pub fn bounded(&self) -> Truth {
        let c = |v: f32, lim: f32| if v.is_nan() { 0.0 } else { v.clamp(-lim, lim) };
        Truth {
            rate_dps: self.rate_dps.map(|v| c(v, TRUTH_RATE_LIMIT_DPS)),
            specific_force_g: self.specific_force_g.map(|v| c(v, TRUTH_FORCE_LIMIT_G)),
            temperature_c: self.temperature_c,
        }
    }

    /// At rest, level, z up, at the default latitude and heading 0.
    pub fn at_rest() -> Truth {
        let (w, f) = earth_and_gravity(&QUAT_IDENTITY, &earth_enu(DEFAULT_LATITUDE_DEG));
        Truth {
            rate_dps: w,
            specific_force_g: f,
            temperature_c: None,
        }
    }
}

/// Which axes the truth is given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TruthFrame {
    /// The IMU housing (sensor axes): the motion is what the unit itself
    /// does, as on a lab bench. Alignment_Angles then change what the device
    /// reports — a unit lying level with angles `0 0 180` reports AccZ = −1 g
    /// and roll 180°, as a real one does. The default.
    #[default]
    Sensor,
    /// The carrier: the motion is the vehicle's, and the unit is mounted in
    /// it as Alignment_Angles say (sensor axes = Mᵀ · carrier axes), so the
    /// device's carrier-axis output reproduces the motion.
    Carrier,
}

/// A source of truth, called once per internal tick.
///
/// Object safe, so a host can pass `&mut dyn MotionSource` to
/// [`crate::chain::SignalChain::tick_with`] (a CSV trajectory player needs
/// `std` and lives in the host crate).
pub trait MotionSource {
    /// Truth at `now` (the tick's time); `dt` is the tick period, s. Called
    /// exactly once per tick, in time order.
    fn next(&mut self, now: Instant, dt: f32) -> Truth;

    /// The true attitude (housing or carrier → ENU, Appendix C convention)
    /// at the last [`MotionSource::next`], if the source knows it.
    fn attitude(&self) -> Option<Quat> {
        None
    }
}

/// The built-in motions. Every variant is at a fixed site (latitude, deg N)
/// and starts level at `heading_deg` (clockwise from north, Appendix C).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// At rest: gravity and Earth rate only.
    Static {
        /// Latitude, degrees north.
        lat_deg: f32,
        /// Heading, degrees clockwise from north.
        heading_deg: f32,
    },
    /// A constant angular rate relative to the local level frame, in body
    /// axes (the body spins about a body-fixed axis through the IMU).
    ConstantRotation {
        /// Latitude, degrees north.
        lat_deg: f32,
        /// Initial heading, degrees.
        heading_deg: f32,
        /// Body-axis rate relative to the level frame, °/s.
        rate_dps: Vec3,
    },
    /// Sinusoidal vibration at one frequency: linear (added to the specific
    /// force) and angular (a body-axis rate `rate_amp · sin 2πft`, the
    /// attitude oscillating about the start attitude).
    Vibration {
        /// Latitude, degrees north.
        lat_deg: f32,
        /// Heading, degrees.
        heading_deg: f32,
        /// Frequency, Hz.
        freq_hz: f32,
        /// Linear acceleration amplitude per body axis, g.
        acc_amp_g: Vec3,
        /// Angular rate amplitude per body axis, °/s.
        rate_amp_dps: Vec3,
    },
    /// Classic coning: the body's z axis sweeps a cone of `half_angle_deg`
    /// about the vertical at `freq_hz` — attitude
    /// `Q(t) = Q_heading ⊗ (cos α/2, sin α/2 · cos Ωt, sin α/2 · sin Ωt, 0)`,
    /// body rate `ω = 2 Q* ⊗ Q̇`. The rotation is about the IMU's origin, so
    /// the specific force is gravity only.
    Coning {
        /// Latitude, degrees north.
        lat_deg: f32,
        /// Heading of the cone's base frame, degrees.
        heading_deg: f32,
        /// Cone half angle α, degrees.
        half_angle_deg: f32,
        /// Coning frequency Ω/2π, Hz.
        freq_hz: f32,
    },
    /// A truth sample held until the next `set_motion`: a host replaying a
    /// trajectory pushes one per tick.
    Sample(Truth),
}

impl Default for Motion {
    /// Static, level, z up, heading 0, [`DEFAULT_LATITUDE_DEG`].
    fn default() -> Self {
        Motion::Static {
            lat_deg: DEFAULT_LATITUDE_DEG,
            heading_deg: 0.0,
        }
    }
}

/// Earth rate in ENU at latitude `lat_deg`, rad/s.
pub(crate) fn earth_enu(lat_deg: f32) -> Vec3 {
    let lat = lat_deg * DEG;
    [
        0.0,
        EARTH_RATE_RAD_S * cosf(lat),
        EARTH_RATE_RAD_S * sinf(lat),
    ]
}

/// Earth rate (°/s) and gravity's specific force (g) in the body axes of
/// attitude `q`.
fn earth_and_gravity(q: &Quat, earth: &Vec3) -> (Vec3, Vec3) {
    let w = quat_rotate_inv(q, earth);
    let f = quat_rotate_inv(q, &[0.0, 0.0, 1.0]);
    ([w[0] * RAD, w[1] * RAD, w[2] * RAD], f)
}

/// A unit phasor `(cos φ, sin φ)` advanced by a fixed step without
/// trigonometry (re-normalised every step so it never drifts off the circle).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Phasor {
    c: f32,
    s: f32,
    step_c: f32,
    step_s: f32,
}

impl Phasor {
    fn new(step: f32) -> Self {
        Phasor {
            c: 1.0,
            s: 0.0,
            step_c: cosf(step),
            step_s: sinf(step),
        }
    }
    /// The angular rate the phasor actually turns at, rad/s.
    fn rate(&self, dt: f32) -> f32 {
        crate::math::atan2f(self.step_s, self.step_c) / dt
    }

    #[inline]
    fn advance(&mut self) {
        let c = self.c * self.step_c - self.s * self.step_s;
        let s = self.s * self.step_c + self.c * self.step_s;
        let k = 1.5 - 0.5 * (c * c + s * s);
        self.c = c * k;
        self.s = s * k;
    }
}

/// π/180 · 10⁻⁹: the rotation, rad, of 1 °/s over 1 ns, as the sum of two
/// `f32` (computed at compile time).
const DEG_NS: f64 = core::f64::consts::PI / 180.0 * 1e-9;
const DEG_NS_HI: f32 = DEG_NS as f32;
const DEG_NS_LO: f32 = (DEG_NS - DEG_NS_HI as f64) as f32;

/// `a · b` exactly, as `p + e` (Dekker's product with Veltkamp's split: no
/// `f64`, no fused multiply-add; |a|, |b| < 1e34).
fn two_prod(a: f32, b: f32) -> (f32, f32) {
    let split = |x: f32| {
        let c = 4097.0 * x; // 2¹² + 1
        let h = c - (c - x);
        (h, x - h)
    };
    let p = a * b;
    let ((ah, al), (bh, bl)) = (split(a), split(b));
    (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
}

/// One tick's rotation, rad, at `rate_dps` (°/s) for ticks of `dt` s, as
/// `hi + lo` (each `f32`, |lo| ≤ ½ ulp(hi)), to ~2⁻⁴⁵ relative: the tick
/// taken as a whole number of nanoseconds (the device's tick period,
/// `1e9 / rate`: 500 000 ns at 2 kHz), not the `f32` `dt` (0.0005 is
/// 2.4e-11 s off in `f32`). `rate · DEG · dt` in `f32` is off by up to
/// ~1e-7 of itself, a rate error of ~2e-8 rad/s at 10 °/s that an
/// integration of the reported rate turns into 1 m in 10 minutes
/// (docs/motion.md, "Precision"). In `f32` only, once (the M4F has no
/// double-precision FPU). A step beyond 0.1 rad (the integrator's large
/// rotations), a tick beyond 2²⁴ ns or a non-finite rate keep the plain
/// product (`lo` = 0).
fn tick_angle(rate_dps: &Vec3, dt: f32) -> (Vec3, Vec3) {
    let ns = libm::roundf(dt * 1e9);
    let mut hi = [0.0; 3];
    let mut lo = [0.0; 3];
    for i in 0..3 {
        let plain = rate_dps[i] * DEG * dt;
        let (p, e) = two_prod(rate_dps[i], ns);
        let (h, l) = two_prod(p, DEG_NS_HI);
        let l = l + (e * DEG_NS_HI + p * DEG_NS_LO);
        let s = h + l;
        let r = l - (s - h);
        let exact = s.is_finite() && r.is_finite() && ns <= 16_777_216.0;
        (hi[i], lo[i]) = if exact && plain.abs() < 0.1 {
            (s, r)
        } else {
            (plain, 0.0)
        };
    }
    (hi, lo)
}

/// One tick's angle: `hi + (lo + carry)` rounded to `f32`, what the
/// rounding left carried to the next tick (Fast2Sum: exact, as
/// |lo + carry| ≤ ulp(hi)), so the angles sum to the exact rotation and
/// the attitude turns at the rate reported.
#[inline]
fn carried(hi: &Vec3, lo: &Vec3, carry: &mut Vec3) -> Vec3 {
    core::array::from_fn(|i| {
        let t = lo[i] + carry[i];
        let a = hi[i] + t;
        carry[i] = t - (a - hi[i]);
        a
    })
}

/// The per-motion state of [`BuiltinMotion`].
#[derive(Debug, Clone, PartialEq)]
enum State {
    /// Static: the truth and the attitude never change.
    Static { truth: Truth, base: Quat },
    /// Sample: the truth is in the [`Motion`].
    Sample,
    /// Constant rotation: the attitude and one tick's rotation as the
    /// `f32` pair `hi + lo` ([`tick_angle`]), the part of `lo` not yet
    /// applied carried in `carry` (docs/motion.md, "Precision").
    Rotation {
        q: QuatIntegrator,
        hi: Vec3,
        lo: Vec3,
        carry: Vec3,
    },
    /// Vibration: the attitude and the phase (half-tick steps).
    Vibration { q: QuatIntegrator, phasor: Phasor },
    /// Coning: the base (heading) attitude, the phase, sin α/2, cos α/2 and
    /// the phasor's actual rate (rad/s) — computed once, so a tick needs no
    /// trigonometry; the attitude is base ⊗ cone(phase).
    Coning {
        base: Quat,
        phasor: Phasor,
        sa: f32,
        ca: f32,
        rate: f32,
    },
}

/// A [`Motion`] with its running state: the built-in [`MotionSource`].
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltinMotion {
    motion: Motion,
    earth: Vec3,
    dt: f32,
    started: bool,
    /// [`BuiltinMotion::static_and_bounded`].
    static_bounded: bool,
    state: State,
}

/// Latitude and heading of a motion's site, degrees (a replayed sample:
/// [`DEFAULT_LATITUDE_DEG`], heading 0).
pub(crate) fn site(motion: &Motion) -> (f32, f32) {
    match *motion {
        Motion::Static {
            lat_deg,
            heading_deg,
        }
        | Motion::ConstantRotation {
            lat_deg,
            heading_deg,
            ..
        }
        | Motion::Vibration {
            lat_deg,
            heading_deg,
            ..
        }
        | Motion::Coning {
            lat_deg,
            heading_deg,
            ..
        } => (lat_deg, heading_deg),
        Motion::Sample(_) => (DEFAULT_LATITUDE_DEG, 0.0),
    }
}

/// The coning quaternion at phase (cos, sin) for sin α/2, cos α/2.
fn cone(sa: f32, ca: f32, c: f32, s: f32) -> Quat {
    [ca, sa * c, sa * s, 0.0]
}

impl BuiltinMotion {
    /// Prepares `motion` for ticks of `dt` seconds.
    pub fn new(motion: Motion, dt: f32) -> Self {
        let (lat, heading) = site(&motion);
        let earth = earth_enu(lat);
        let base = quat_from_euler(heading * DEG, 0.0, 0.0);
        let state = match motion {
            Motion::Static { .. } => {
                let (w, f) = earth_and_gravity(&base, &earth);
                State::Static {
                    truth: Truth {
                        rate_dps: w,
                        specific_force_g: f,
                        temperature_c: None,
                    },
                    base,
                }
            }
            Motion::Sample(_) => State::Sample,
            Motion::ConstantRotation { rate_dps, .. } => {
                let (hi, lo) = tick_angle(&rate_dps, dt);
                State::Rotation {
                    q: QuatIntegrator::new(base),
                    hi,
                    lo,
                    carry: [0.0; 3],
                }
            }
            // Vibration samples the rate at mid-tick: two half steps a tick.
            Motion::Vibration { freq_hz, .. } => State::Vibration {
                q: QuatIntegrator::new(base),
                phasor: Phasor::new(core::f32::consts::PI * freq_hz * dt),
            },
            Motion::Coning {
                half_angle_deg,
                freq_hz,
                ..
            } => {
                let phasor = Phasor::new(core::f32::consts::TAU * freq_hz * dt);
                State::Coning {
                    base,
                    phasor,
                    sa: sinf(0.5 * half_angle_deg * DEG),
                    ca: cosf(0.5 * half_angle_deg * DEG),
                    // The phasor's actual step (its f32 step differs from
                    // 2πf·dt in the last bits): keeps the rate consistent
                    // with the attitude.
                    rate: phasor.rate(dt),
                }
            }
        };
        BuiltinMotion {
            motion,
            earth,
            dt,
            started: false,
            static_bounded: static_bounded(&state),
            state,
        }
    }

    /// The motion this source plays.
    pub fn motion(&self) -> &Motion {
        &self.motion
    }

    /// The truth of the last tick ([`MotionSource::next`]; before the first,
    /// of the initial state), without advancing.
    pub fn truth_now(&self) -> Truth {
        self.current()
    }

    /// Truth at the current state without advancing.
    fn current(&self) -> Truth {
        match (&self.state, self.motion) {
            (State::Static { truth, .. }, _) => *truth,
            (_, Motion::Sample(t)) => t,
            (State::Rotation { q, .. }, Motion::ConstantRotation { rate_dps, .. }) => {
                self.with_body_rate(&q.get(), rate_dps, [0.0; 3])
            }
            (
                State::Vibration { q, phasor },
                Motion::Vibration {
                    acc_amp_g,
                    rate_amp_dps,
                    ..
                },
            ) => {
                let s = phasor.s;
                self.with_body_rate(
                    &q.get(),
                    [
                        rate_amp_dps[0] * s,
                        rate_amp_dps[1] * s,
                        rate_amp_dps[2] * s,
                    ],
                    [acc_amp_g[0] * s, acc_amp_g[1] * s, acc_amp_g[2] * s],
                )
            }
            (
                State::Coning {
                    base,
                    phasor,
                    sa,
                    ca,
                    rate,
                },
                _,
            ) => {
                let om = *rate;
                let (c, s) = (phasor.c, phasor.s);
                let qc = cone(*sa, *ca, c, s);
                let sa = *sa;
                let qdot = [0.0, -sa * om * s, sa * om * c, 0.0];
                let w = quat_mul(&[qc[0], -qc[1], -qc[2], -qc[3]], &qdot);
                self.with_body_rate(
                    &quat_mul(base, &qc),
                    [2.0 * w[1] * RAD, 2.0 * w[2] * RAD, 2.0 * w[3] * RAD],
                    [0.0; 3],
                )
            }
            _ => Truth::at_rest(),
        }
    }

    fn with_body_rate(&self, q: &Quat, rate_dps: Vec3, lin_acc_g: Vec3) -> Truth {
        let (w, f) = earth_and_gravity(q, &self.earth);
        Truth {
            rate_dps: [w[0] + rate_dps[0], w[1] + rate_dps[1], w[2] + rate_dps[2]],
            specific_force_g: [
                f[0] + lin_acc_g[0],
                f[1] + lin_acc_g[1],
                f[2] + lin_acc_g[2],
            ],
            temperature_c: None,
        }
    }

    /// Moves the state on by one tick.
    fn advance(&mut self) {
        let dt = self.dt;
        match (&mut self.state, self.motion) {
            (State::Rotation { q, hi, lo, carry }, _) => q.rotate(&carried(hi, lo, carry)),
            (State::Vibration { q, phasor }, Motion::Vibration { rate_amp_dps, .. }) => {
                // Rate at mid-tick (second-order accurate attitude).
                phasor.advance();
                let s = phasor.s * DEG * dt;
                let a = [
                    rate_amp_dps[0] * s,
                    rate_amp_dps[1] * s,
                    rate_amp_dps[2] * s,
                ];
                q.rotate(&a);
                phasor.advance();
            }
            (State::Coning { phasor, .. }, _) => phasor.advance(),
            _ => {}
        }
    }
}

impl BuiltinMotion {
    /// The motion is static and its (constant) truth is already what
    /// [`Truth::bounded`] makes of it, bit for bit, so a chain may skip the
    /// bounding.
    #[inline(always)]
    pub fn static_and_bounded(&self) -> bool {
        self.static_bounded
    }
}

/// Whether `state` is static with a truth [`Truth::bounded`] leaves the
/// same, bit for bit.
fn static_bounded(state: &State) -> bool {
    let bits = |t: &Truth| {
        (
            t.rate_dps.map(f32::to_bits),
            t.specific_force_g.map(f32::to_bits),
            t.temperature_c.map(f32::to_bits),
        )
    };
    match state {
        State::Static { truth, .. } => bits(truth) == bits(&truth.bounded()),
        _ => false,
    }
}

impl MotionSource for BuiltinMotion {
    fn next(&mut self, _now: Instant, _dt: f32) -> Truth {
        // A static motion has nothing to advance and its truth in place
        // (without the matches on a copy of the motion below).
        if let State::Static { truth, .. } = &self.state {
            self.started = true;
            return *truth;
        }
        if self.started {
            self.advance();
        }
        self.started = true;
        self.current()
    }

    fn attitude(&self) -> Option<Quat> {
        match &self.state {
            State::Sample => None,
            State::Static { base, .. } => Some(canonical(base)),
            State::Rotation { q, .. } | State::Vibration { q, .. } => Some(canonical(&q.get())),
            State::Coning {
                base,
                phasor,
                sa,
                ca,
                ..
            } => Some(canonical(&quat_mul(
                base,
                &cone(*sa, *ca, phasor.c, phasor.s),
            ))),
        }
    }
}

// ----- fixed point (the `fixed-point` build) -----

use crate::math::fixed::{mul_q30, mul_shr, to_fixed};
use crate::math::rotation::{quat_rotate_inv_q30, up_in_body_q30, QuatFixed, QuatQ30};
use crate::math::units::{ACC_BITS, GYRO_BITS, RATE_TRUTH_LIMIT, TRUTH_LIMIT};

/// One tick of truth in integers: rates in °/s·2^[`GYRO_BITS`] (clamped
/// to ±[`RATE_TRUTH_LIMIT`]), specific force in g·2^[`ACC_BITS`]
/// (clamped to ±[`TRUTH_LIMIT`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthFixed {
    /// Inertial angular rate, scaled.
    pub rate: [i32; 3],
    /// Specific force, scaled.
    pub force: [i32; 3],
    /// Sensor temperature, °C, if the source knows it.
    pub temperature_c: Option<f32>,
}

impl TruthFixed {
    /// `t` scaled and clamped (rounded to nearest; NaN reads 0).
    pub fn from_truth(t: &Truth) -> Self {
        TruthFixed {
            rate: t
                .rate_dps
                .map(|v| to_fixed(v, GYRO_BITS).clamp(-RATE_TRUTH_LIMIT, RATE_TRUTH_LIMIT)),
            force: t
                .specific_force_g
                .map(|v| to_fixed(v, ACC_BITS).clamp(-TRUTH_LIMIT, TRUTH_LIMIT)),
            temperature_c: t.temperature_c,
        }
    }
}

/// `x / 2^s` rounded to nearest (half up), s ≥ 1.
#[inline(always)]
fn rshr(x: i32, s: u32) -> i32 {
    (x >> s) + ((x >> (s - 1)) & 1)
}

/// Earth rate (°/s·2^GYRO_BITS) and gravity (g·2^ACC_BITS) in the body
/// axes of Q30 attitude `q`; `earth` is the ENU Earth rate in
/// °/s·2^(GYRO_BITS + 8).
#[inline]
fn earth_and_gravity_fixed(q: &QuatQ30, earth: &[i32; 3]) -> ([i32; 3], [i32; 3]) {
    let w = quat_rotate_inv_q30(q, earth);
    let f = up_in_body_q30(q);
    (w.map(|v| rshr(v, 8)), f.map(|v| rshr(v, 30 - ACC_BITS)))
}

/// A unit phasor (cos φ, sin φ) in Q30 turned by a fixed step, re-normalised
/// every step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PhasorFixed {
    c: i32,
    s: i32,
    step_c: i32,
    step_s: i32,
}

impl PhasorFixed {
    fn new(step: f64) -> Self {
        let (sn, cs) = crate::math::sincos(step);
        PhasorFixed {
            c: 1 << 30,
            s: 0,
            step_c: libm::round(cs * 1_073_741_824.0) as i32,
            step_s: libm::round(sn * 1_073_741_824.0) as i32,
        }
    }

    /// The angular rate the phasor actually turns at, rad/s.
    fn rate(&self, dt: f32) -> f64 {
        libm::atan2(f64::from(self.step_s), f64::from(self.step_c)) / f64::from(dt)
    }

    #[inline]
    fn advance(&mut self) {
        let m = mul_q30;
        let c = m(self.c, self.step_c) - m(self.s, self.step_s);
        let s = m(self.s, self.step_c) + m(self.c, self.step_s);
        // k = 1.5 − 0.5 (c² + s²), Q30.
        let k = (3 << 29) - ((m(c, c) + m(s, s)) >> 1);
        self.c = m(c, k);
        self.s = m(s, k);
    }
}

/// The per-motion state of [`BuiltinMotionFixed`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum FixedKind {
    /// Static and Sample: the truth never changes but for the dither of
    /// its rate; the (Q30) attitude. `floor` is the rate rounded down,
    /// `frac` the rest in 2⁻³² of its unit and `acc` their running sum: the
    /// rate is `floor + 1` at the ticks where `acc` wraps, so its mean is
    /// the exact rate (docs/motion.md, "Precision"). A sample's `frac` is
    /// 0 (its truth is new every tick).
    Constant {
        truth: TruthFixed,
        base: QuatQ30,
        floor: [i32; 3],
        frac: [u32; 3],
        acc: [u32; 3],
    },
    /// Constant rotation: the attitude, the rotation of one tick (Q36 rad;
    /// of half a tick if `halves`) rounded down, its fraction and running
    /// sum (dithered as `Constant`'s rate) and the body rate (scaled).
    Rotation {
        q: QuatFixed,
        step: [i32; 3],
        frac: [u32; 3],
        acc: [u32; 3],
        rate: [i32; 3],
        halves: bool,
    },
    /// Vibration: the attitude, the phase, one tick's rotation at unit
    /// phase (Q36 rad), rate and acceleration amplitudes (scaled).
    Vibration {
        q: QuatFixed,
        phasor: PhasorFixed,
        step: [i32; 3],
        rate: [i32; 3],
        acc: [i32; 3],
    },
    /// Coning: the base attitude, the phase, cos α/2 and sin α/2 (Q30); the
    /// body rate is (−A sin φ, A cos φ, B) with A = 2Ω·cos·sin,
    /// B = −2Ω·sin² (scaled).
    Coning {
        base: QuatQ30,
        phasor: PhasorFixed,
        cs: [i32; 2],
        a: i32,
        b: i32,
    },
}

/// [`BuiltinMotion`] in integers, for the `fixed-point` build: the same
/// motions, integrated in Q62 ([`QuatFixed`]) with integer phasors, so a
/// tick needs no floating point. The truth agrees with the float source to
/// the scaling's resolution (and the phasor's Q30 step).
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltinMotionFixed {
    motion: Motion,
    /// ENU Earth rate, °/s·2^(GYRO_BITS + 8).
    earth: [i32; 3],
    started: bool,
    kind: FixedKind,
}

impl BuiltinMotionFixed {
    /// Prepares `motion` for ticks of `dt` seconds (float, once).
    pub fn new(motion: Motion, dt: f32) -> Self {
        // Set-up in float (once); only the per-tick work is integer.
        let (lat, heading) = site(&motion);
        let earth_f = earth_enu(lat);
        let base_f = quat_from_euler(heading * DEG, 0.0, 0.0);
        let earth = earth_f.map(|w| to_fixed(w * RAD, GYRO_BITS + 8).clamp(-(1 << 29), 1 << 29));
        let base = base_f.map(crate::math::rotation::q30);
        let tick_rad = |v: f32| {
            let x = f64::from(v) * core::f64::consts::PI / 180.0 * f64::from(dt);
            libm::round(x * 68_719_476_736.0).clamp(-2e9, 2e9) as i32 // 2³⁶
        };
        let lim = |v: f32, bits: u32| {
            let l = if bits == GYRO_BITS {
                RATE_TRUTH_LIMIT
            } else {
                TRUTH_LIMIT
            };
            to_fixed(v, bits).clamp(-l, l)
        };
        let q = QuatFixed::from_f32(&base_f);
        let kind = match motion {
            Motion::Static { .. } => {
                let (w, f) = earth_and_gravity(&base_f, &earth_f);
                let truth = TruthFixed::from_truth(&Truth {
                    rate_dps: w,
                    specific_force_g: f,
                    temperature_c: None,
                });
                // The Earth rate rounded to 2⁻¹⁹ °/s would hold an error of
                // up to half a unit for ever (an integration of a unit at
                // rest then drifts up to 6 m in 10 minutes): dithered
                // instead, exact on average.
                let scale = crate::math::exp2i(GYRO_BITS as i32);
                let (floor, frac) = dither_parts(w.map(|v| f64::from(v) * scale));
                FixedKind::Constant {
                    truth: TruthFixed {
                        rate: floor,
                        ..truth
                    },
                    base,
                    floor,
                    frac,
                    acc: [1 << 31; 3],
                }
            }
            Motion::Sample(t) => {
                let truth = TruthFixed::from_truth(&t);
                FixedKind::Constant {
                    truth,
                    base,
                    floor: truth.rate,
                    frac: [0; 3],
                    acc: [0; 3],
                }
            }
            Motion::ConstantRotation { rate_dps, .. } => {
                // The tick's rotation at the rate reported (scaled, so the
                // two agree exactly), over the tick in whole nanoseconds,
                // in Q36 with its fraction dithered: rounded to Q36 alone
                // it is up to 7e-12 rad a tick off (1.5e-8 rad/s at 2 kHz,
                // 2 m in 10 minutes of an integration; docs/motion.md,
                // "Precision").
                let rate = rate_dps.map(|v| lim(v, GYRO_BITS));
                let tick_s = libm::round(f64::from(dt) * 1e9) * 1e-9;
                let k = core::f64::consts::PI / 180.0
                    * tick_s
                    * crate::math::exp2i(36 - GYRO_BITS as i32);
                // The step is a Q36 i32: a tick's rotation beyond 0.029 rad
                // (3335 °/s at 2 kHz, up to RATE_TRUTH_LIMIT's 0.036) turns
                // in two dithered half-tick steps.
                let exact = rate.map(|r| f64::from(r) * k);
                let halves = exact.iter().any(|x| x.abs() > 2e9);
                let h = if halves { 0.5 } else { 1.0 };
                let (step, frac) = dither_parts(exact.map(|x| (x * h).clamp(-2e9, 2e9)));
                FixedKind::Rotation {
                    q,
                    step,
                    frac,
                    acc: [1 << 31; 3],
                    rate,
                    halves,
                }
            }
            Motion::Vibration {
                freq_hz,
                acc_amp_g,
                rate_amp_dps,
                ..
            } => FixedKind::Vibration {
                q,
                // Half-tick steps, as the float source.
                phasor: PhasorFixed::new(
                    core::f64::consts::PI * f64::from(freq_hz) * f64::from(dt),
                ),
                step: rate_amp_dps.map(tick_rad),
                rate: rate_amp_dps.map(|v| lim(v, GYRO_BITS)),
                acc: acc_amp_g.map(|v| lim(v, ACC_BITS)),
            },
            Motion::Coning {
                half_angle_deg,
                freq_hz,
                ..
            } => {
                let phasor =
                    PhasorFixed::new(core::f64::consts::TAU * f64::from(freq_hz) * f64::from(dt));
                let half = 0.5 * f64::from(half_angle_deg) * core::f64::consts::PI / 180.0;
                let (sa, ca) = crate::math::sincos(half);
                let om = phasor.rate(dt);
                let scale = crate::math::exp2i(GYRO_BITS as i32) * 180.0 / core::f64::consts::PI;
                let c = |v: f64| libm::round(v * scale).clamp(-1.0e9, 1.0e9) as i32;
                FixedKind::Coning {
                    base,
                    phasor,
                    cs: [
                        libm::round(ca * 1_073_741_824.0) as i32,
                        libm::round(sa * 1_073_741_824.0) as i32,
                    ],
                    a: c(2.0 * om * ca * sa),
                    b: c(-2.0 * om * sa * sa),
                }
            }
        };
        BuiltinMotionFixed {
            motion,
            earth,
            started: false,
            kind,
        }
    }

    /// The motion this source plays.
    pub fn motion(&self) -> &Motion {
        &self.motion
    }

    /// The truth of the last tick ([`BuiltinMotionFixed::step`]; before the
    /// first, of the initial state) in physical units, without advancing.
    pub fn truth_now(&self) -> Truth {
        let t = self.current();
        let k = |v: i32, bits: u32| crate::math::fixed::scaled_f32(v, bits);
        Truth {
            rate_dps: t.rate.map(|v| k(v, GYRO_BITS)),
            specific_force_g: t.force.map(|v| k(v, ACC_BITS)),
            temperature_c: t.temperature_c,
        }
    }

    /// Truth of the next tick (the first call gives the initial state).
    #[inline]
    pub fn step(&mut self) -> TruthFixed {
        if self.started {
            self.advance();
        }
        self.started = true;
        self.current()
    }

    fn with_body(&self, q: &QuatQ30, rate: [i32; 3], acc: [i32; 3]) -> TruthFixed {
        let (w, f) = earth_and_gravity_fixed(q, &self.earth);
        let add = |a: i32, b: i32, l: i32| a.saturating_add(b).clamp(-l, l);
        let (r, t) = (RATE_TRUTH_LIMIT, TRUTH_LIMIT);
        TruthFixed {
            rate: [
                add(w[0], rate[0], r),
                add(w[1], rate[1], r),
                add(w[2], rate[2], r),
            ],
            force: [
                add(f[0], acc[0], t),
                add(f[1], acc[1], t),
                add(f[2], acc[2], t),
            ],
            temperature_c: None,
        }
    }

    #[inline]
    fn current(&self) -> TruthFixed {
        match &self.kind {
            FixedKind::Constant { truth, .. } => *truth,
            FixedKind::Rotation { q, rate, .. } => self.with_body(&q.get(), *rate, [0; 3]),
            FixedKind::Vibration {
                q,
                phasor,
                rate,
                acc,
                ..
            } => {
                let s = phasor.s;
                self.with_body(
                    &q.get(),
                    rate.map(|r| mul_q30(r, s)),
                    acc.map(|a| mul_q30(a, s)),
                )
            }
            FixedKind::Coning {
                base,
                phasor,
                cs,
                a,
                b,
            } => {
                let (c, s) = (phasor.c, phasor.s);
                self.with_body(
                    &cone_fixed(base, phasor, cs),
                    [-mul_q30(*a, s), mul_q30(*a, c), *b],
                    [0; 3],
                )
            }
        }
    }

    #[inline]
    fn advance(&mut self) {
        match &mut self.kind {
            FixedKind::Constant {
                truth,
                floor,
                frac,
                acc,
                ..
            } => {
                truth.rate = dither(floor, frac, acc);
            }
            FixedKind::Rotation {
                q,
                step,
                frac,
                acc,
                halves,
                ..
            } => {
                q.rotate(&dither(step, frac, acc));
                if *halves {
                    q.rotate(&dither(step, frac, acc));
                }
            }
            FixedKind::Vibration {
                q, phasor, step, ..
            } => {
                // Rate at mid-tick (second-order accurate attitude).
                phasor.advance();
                let s = phasor.s;
                q.rotate(&step.map(|a| mul_shr(a, s, 30)));
                phasor.advance();
            }
            FixedKind::Coning { phasor, .. } => phasor.advance(),
        }
    }

    /// The true attitude at the last tick (Appendix C convention, q0 ≥ 0).
    pub fn attitude(&self) -> Option<Quat> {
        let f = |q: QuatQ30| canonical(&q.map(|v| crate::math::fixed::scaled_f32(v, 30)));
        match &self.kind {
            FixedKind::Constant { .. } if matches!(self.motion, Motion::Sample(_)) => None,
            FixedKind::Constant { base, .. } => Some(f(*base)),
            FixedKind::Rotation { q, .. } | FixedKind::Vibration { q, .. } => {
                Some(canonical(&q.to_f32()))
            }
            FixedKind::Coning {
                base, phasor, cs, ..
            } => Some(f(cone_fixed(base, phasor, cs))),
        }
    }
}

/// `exact` (in units) as its floor and the rest in 2⁻³² units, for
/// [`dither`].
fn dither_parts(exact: [f64; 3]) -> ([i32; 3], [u32; 3]) {
    let floor = exact.map(|x| libm::floor(x) as i32);
    let frac = core::array::from_fn(|i| {
        let r = exact[i] - f64::from(floor[i]);
        libm::round(r * 4_294_967_296.0).min(4_294_967_295.0) as u32
    });
    (floor, frac)
}

/// One tick's value of a dithered constant: `floor + 1` where the running
/// sum `acc` of `frac` wraps, else `floor` — exact on average.
#[inline]
fn dither(floor: &[i32; 3], frac: &[u32; 3], acc: &mut [u32; 3]) -> [i32; 3] {
    core::array::from_fn(|i| {
        let (a, carry) = acc[i].overflowing_add(frac[i]);
        acc[i] = a;
        floor[i] + i32::from(carry)
    })
}

/// The coning attitude `base ⊗ (C, S cos φ, S sin φ, 0)`, Q30, for a base
/// rotation about z.
fn cone_fixed(base: &QuatQ30, phasor: &PhasorFixed, cs: &[i32; 2]) -> QuatQ30 {
    let m = mul_q30;
    let (x, y) = (m(cs[1], phasor.c), m(cs[1], phasor.s));
    let [b0, _, _, b3] = *base;
    [
        m(b0, cs[0]),
        m(b0, x) - m(b3, y),
        m(b0, y) + m(b3, x),
        m(b3, cs[0]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The float rotation's tick angles sum, over ten minutes at 2 kHz,
    /// to the exact rotation at the rate reported (in `f64`, over ticks of
    /// 500 000 ns) to 1e-12 of it; each rounded on its own, as before,
    /// they were off by up to ~1e-7 of it (here 1.1e-8 to 9.6e-8).
    #[test]
    fn the_float_rotation_tick_angles_sum_to_the_exact_rotation() {
        let rate = [3.3f32, -2.1, 10.7];
        let (hi, lo) = tick_angle(&rate, 0.0005);
        let mut carry = [0.0; 3];
        let mut sum = [0.0f64; 3];
        let ticks = 1_200_000;
        for _ in 0..ticks {
            let a = carried(&hi, &lo, &mut carry);
            for i in 0..3 {
                sum[i] += f64::from(a[i]);
            }
        }
        let mut worst_old = 0.0f64;
        for i in 0..3 {
            let exact = f64::from(rate[i]).to_radians() * 0.0005 * f64::from(ticks);
            let e = (sum[i] - exact).abs() / exact.abs();
            assert!(e < 1e-12, "axis {i}: {e}");
            let old = f64::from(rate[i] * DEG * 0.0005) * f64::from(ticks);
            worst_old = worst_old.max((old - exact).abs() / exact.abs());
        }
        assert!(worst_old > 1e-8, "{worst_old}");
    }

    /// The fixed-point rotation's attitude after ten minutes at 2 kHz is
    /// the exact rotation of the rate it reports (scaled back) to 2e-7 rad
    /// (4e-8 measured) — its Q36 tick angle dithered; rounded, as before,
    /// it was ~1.5e-5 rad off (1.2e-8 to 1.7e-8 rad/s on each axis).
    #[test]
    fn the_fixed_rotation_turns_at_the_rate_it_reports() {
        fixed_rotation_error([3.3, -2.1, 10.7], 1_200_000, 2e-7);
    }

    /// Beyond 0.029 rad a tick (3335 °/s at 2 kHz) the fixed-point
    /// rotation turns in two half-tick steps: at 3900 °/s (and at
    /// RATE_TRUTH_LIMIT on all axes) it still turns at the rate it reports.
    #[test]
    fn a_fast_fixed_rotation_turns_at_the_rate_it_reports() {
        fixed_rotation_error([3900.0, 0.0, -200.0], 20_000, 1e-6);
        fixed_rotation_error([-4095.0, 4095.0, 4095.0], 20_000, 1e-6);
    }

    /// The attitude error (rad) of a fixed-point constant rotation at
    /// `rate_dps` after `ticks` at 2 kHz against the exact rotation of the
    /// rate it reports, asserted below `tol`.
    fn fixed_rotation_error(rate_dps: Vec3, ticks: u64, tol: f64) {
        use crate::math::double;
        let m = Motion::ConstantRotation {
            lat_deg: 45.0,
            heading_deg: 30.0,
            rate_dps,
        };
        let mut fixed = BuiltinMotionFixed::new(m, 0.0005);
        for _ in 0..=ticks {
            fixed.step();
        }
        let FixedKind::Rotation { rate, .. } = fixed.kind else {
            panic!("not a rotation")
        };
        let t = ticks as f64 * 0.0005;
        let w = rate.map(|r| (f64::from(r) / f64::from(1u32 << GYRO_BITS)).to_radians() * t);
        let base = quat_from_euler(30.0 * DEG, 0.0, 0.0).map(f64::from);
        let want = double::quat_mul(&base, &double::quat_from_rotvec(&w));
        let q = fixed.attitude().unwrap().map(f64::from);
        let d = double::quat_mul(&double::quat_conj(&want), &q);
        let e = 2.0 * (d[1] * d[1] + d[2] * d[2] + d[3] * d[3]).sqrt();
        assert!(e < tol, "{rate_dps:?}: {e} rad");
    }

    /// The integer motions follow the float ones over 2 s at 2 kHz: truth
    /// within a few LSB of the fixed-point scale, attitude within 2e-6 rad —
    /// up to the phase of the oscillating motions, where the f32 phasor of
    /// the float source drifts (~3e-6 rad after 8000 half steps; the Q30
    /// one holds ~1e-10 a step), so their rates differ by a few 1e-6 of the
    /// amplitude (up to 2e-4 °/s for the 63 °/s coning) at the zero crossings.
    #[test]
    fn fixed_point_motions_match_float() {
        let dt = 0.0005;
        for m in [
            Motion::default(),
            Motion::Static {
                lat_deg: -30.0,
                heading_deg: 120.0,
            },
            Motion::ConstantRotation {
                lat_deg: 45.0,
                heading_deg: 10.0,
                rate_dps: [40.0, -25.0, 60.0],
            },
            Motion::Vibration {
                lat_deg: 45.0,
                heading_deg: 0.0,
                freq_hz: 7.0,
                acc_amp_g: [0.5, 0.5, 1.0],
                rate_amp_dps: [10.0, 10.0, 10.0],
            },
            Motion::Coning {
                lat_deg: 45.0,
                heading_deg: 10.0,
                half_angle_deg: 5.0,
                freq_hz: 2.0,
            },
            Motion::Sample(Truth {
                rate_dps: [1.0, -2.0, 3.0],
                specific_force_g: [0.1, 0.2, 0.9],
                temperature_c: Some(40.0),
            }),
        ] {
            let mut f = BuiltinMotion::new(m, dt);
            let mut q = BuiltinMotionFixed::new(m, dt);
            let (mut worst_w, mut worst_f, mut worst_q) = (0.0f32, 0.0f32, 0.0f32);
            for k in 0..4_000 {
                let a = f.next(Instant::from_nanos(0), dt);
                let b = q.step();
                for i in 0..3 {
                    let dw = (a.rate_dps[i] - b.rate[i] as f32 / (1u32 << GYRO_BITS) as f32).abs();
                    let df = (a.specific_force_g[i]
                        - b.force[i] as f32 / (1u32 << ACC_BITS) as f32)
                        .abs();
                    worst_w = worst_w.max(dw / a.rate_dps[i].abs().max(1.0));
                    worst_f = worst_f.max(df);
                }
                assert_eq!(a.temperature_c, b.temperature_c);
                if k % 100 == 0 {
                    match (f.attitude(), q.attitude()) {
                        (Some(x), Some(y)) => {
                            let d = quat_mul(&[x[0], -x[1], -x[2], -x[3]], &y);
                            worst_q =
                                worst_q.max(2.0 * (d[1] * d[1] + d[2] * d[2] + d[3] * d[3]).sqrt());
                        }
                        (None, None) => {}
                        other => panic!("{m:?}: {other:?}"),
                    }
                }
            }
            let oscillating = matches!(m, Motion::Vibration { .. } | Motion::Coning { .. });
            let (tw, tf) = if oscillating {
                (3e-4, 2e-5)
            } else {
                (2e-6, 2e-6)
            };
            assert!(worst_w < tw, "{m:?}: rate {worst_w}");
            assert!(worst_f < tf, "{m:?}: force {worst_f}");
            assert!(worst_q < 2e-6, "{m:?}: attitude {worst_q} rad");
        }
    }
}
