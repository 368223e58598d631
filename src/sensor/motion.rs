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
//! - the default site is latitude [`DEFAULT_LATITUDE_DEG`] = 45° N, heading 0
//!   (the housing's y axis points north), level, z up.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use crate::ahrs::rotation::{
    canonical, quat_from_euler, quat_mul, quat_rotate_inv, Quat, QuatIntegrator, Vec3,
    QUAT_IDENTITY,
};
use crate::time::Instant;
use libm::{cosf, sinf};

/// g in m/s², as the ICD defines it (Table 5.5 note 1).
pub const G: f32 = 9.8106;
/// Earth rotation rate, °/h (sidereal, 15.041 °/h).
pub const EARTH_RATE_DEG_PER_H: f32 = 15.041;
/// Earth rotation rate, rad/s.
pub const EARTH_RATE_RAD_S: f32 = EARTH_RATE_DEG_PER_H / 3600.0 * DEG;
/// Latitude of the default site, degrees north. 45° gives the Earth rate
/// equal horizontal and vertical parts, so both show in the gyros.
pub const DEFAULT_LATITUDE_DEG: f32 = 45.0;

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

impl Truth {
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
pub fn earth_enu(lat_deg: f32) -> Vec3 {
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
        libm::atan2f(self.step_s, self.step_c) / dt
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

/// A [`Motion`] with its running state: the built-in [`MotionSource`].
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltinMotion {
    motion: Motion,
    earth: Vec3,
    base: Quat,
    q: QuatIntegrator,
    /// Phase of the vibration/coning; for vibration at half-tick steps.
    phasor: Phasor,
    dt: f32,
    started: bool,
    static_truth: Truth,
    /// Coning: sin α/2, cos α/2 and the phasor's actual rate (rad/s) —
    /// computed once, so a tick needs no trigonometry.
    cone_s: f32,
    cone_c: f32,
    cone_rate: f32,
}

impl BuiltinMotion {
    /// Prepares `motion` for ticks of `dt` seconds.
    pub fn new(motion: Motion, dt: f32) -> Self {
        let (lat, heading) = match motion {
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
        };
        let earth = earth_enu(lat);
        let base = quat_from_euler(heading * DEG, 0.0, 0.0);
        let step = match motion {
            // Vibration samples the rate at mid-tick: two half steps a tick.
            Motion::Vibration { freq_hz, .. } => core::f32::consts::PI * freq_hz * dt,
            Motion::Coning { freq_hz, .. } => core::f32::consts::TAU * freq_hz * dt,
            _ => 0.0,
        };
        let (w, f) = earth_and_gravity(&base, &earth);
        let mut m = BuiltinMotion {
            motion,
            earth,
            base,
            q: QuatIntegrator::new(base),
            phasor: Phasor::new(step),
            dt,
            started: false,
            static_truth: Truth {
                rate_dps: w,
                specific_force_g: f,
                temperature_c: None,
            },
            cone_s: 0.0,
            cone_c: 1.0,
            cone_rate: 0.0,
        };
        if let Motion::Coning { half_angle_deg, .. } = motion {
            m.cone_s = sinf(0.5 * half_angle_deg * DEG);
            m.cone_c = cosf(0.5 * half_angle_deg * DEG);
            // The phasor's actual step (its f32 step differs from 2πf·dt in
            // the last bits): keeps the rate consistent with the attitude.
            m.cone_rate = m.phasor.rate(dt);
            m.q = QuatIntegrator::new(quat_mul(&base, &m.cone(1.0, 0.0)));
        }
        m
    }

    /// The coning quaternion at phase (cos, sin).
    fn cone(&self, c: f32, s: f32) -> Quat {
        [self.cone_c, self.cone_s * c, self.cone_s * s, 0.0]
    }

    /// The motion this source plays.
    pub fn motion(&self) -> &Motion {
        &self.motion
    }

    /// Truth at the current state without advancing.
    fn current(&self) -> Truth {
        match self.motion {
            Motion::Static { .. } => self.static_truth,
            Motion::Sample(t) => t,
            Motion::ConstantRotation { rate_dps, .. } => self.with_body_rate(rate_dps, [0.0; 3]),
            Motion::Vibration {
                acc_amp_g,
                rate_amp_dps,
                ..
            } => {
                let s = self.phasor.s;
                self.with_body_rate(
                    [
                        rate_amp_dps[0] * s,
                        rate_amp_dps[1] * s,
                        rate_amp_dps[2] * s,
                    ],
                    [acc_amp_g[0] * s, acc_amp_g[1] * s, acc_amp_g[2] * s],
                )
            }
            Motion::Coning { .. } => {
                let om = self.cone_rate;
                let (c, s) = (self.phasor.c, self.phasor.s);
                let qc = self.cone(c, s);
                let sa = self.cone_s;
                let qdot = [0.0, -sa * om * s, sa * om * c, 0.0];
                let w = quat_mul(&[qc[0], -qc[1], -qc[2], -qc[3]], &qdot);
                self.with_body_rate(
                    [2.0 * w[1] * RAD, 2.0 * w[2] * RAD, 2.0 * w[3] * RAD],
                    [0.0; 3],
                )
            }
        }
    }

    fn with_body_rate(&self, rate_dps: Vec3, lin_acc_g: Vec3) -> Truth {
        let (w, f) = earth_and_gravity(&self.q.get(), &self.earth);
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
        match self.motion {
            Motion::Static { .. } | Motion::Sample(_) => {}
            Motion::ConstantRotation { rate_dps, .. } => {
                let a = [
                    rate_dps[0] * DEG * dt,
                    rate_dps[1] * DEG * dt,
                    rate_dps[2] * DEG * dt,
                ];
                self.q.rotate(&a);
            }
            Motion::Vibration { rate_amp_dps, .. } => {
                // Rate at mid-tick (second-order accurate attitude).
                self.phasor.advance();
                let s = self.phasor.s * DEG * dt;
                let a = [
                    rate_amp_dps[0] * s,
                    rate_amp_dps[1] * s,
                    rate_amp_dps[2] * s,
                ];
                self.q.rotate(&a);
                self.phasor.advance();
            }
            Motion::Coning { .. } => {
                self.phasor.advance();
                let qc = self.cone(self.phasor.c, self.phasor.s);
                self.q.set(quat_mul(&self.base, &qc));
            }
        }
    }
}

impl MotionSource for BuiltinMotion {
    fn next(&mut self, _now: Instant, _dt: f32) -> Truth {
        if self.started {
            self.advance();
        }
        self.started = true;
        self.current()
    }

    fn attitude(&self) -> Option<Quat> {
        match self.motion {
            Motion::Sample(_) => None,
            _ => Some(canonical(&self.q.get())),
        }
    }
}
