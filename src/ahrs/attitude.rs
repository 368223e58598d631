//! Attitude propagation (ICD Appendix C): quaternion integration of the
//! bias-compensated carrier-axis rates with the Earth rate removed, plus a
//! slow tilt correction from the accelerometers.
//!
//! Per tick (dt = 1/internal rate):
//!
//! ```text
//! ω_k = (gyro − bias)·π/180 − Q* ⊗ Ω_enu ⊗ Q  +  k_p · (f × û)    [rad/s, body]
//! a   = ½(ω_{k−1} + ω_k)·dt + (1/12)(ω_{k−1} × ω_k)·dt²
//! Q  ← Q ⊗ (cos|a|/2, sin(|a|/2)·a/|a|)     (4th-order series)
//! ```
//!
//! The rotation vector `a` over the tick interval [t_{k−1}, t_k] is the
//! trapezoid of the two rate samples plus the two-sample coning term, so the
//! attitude after tick k is the attitude *at* t_k (no half-tick lead), and
//! coning motion does not drift.
//!
//! - `Ω_enu` is the Earth rate assumed by the AHRS (default latitude,
//!   relative heading 0 = north; see [`super::alignment`]);
//! - `û` is the estimated up axis in the body (row 3 of C.1) and `f` the
//!   measured specific force: the cross product rotates the estimate towards
//!   the measured gravity with a time constant of 1/k_p = [`TILT_TIME_CONSTANT_S`]
//!   (a Mahony-style proportional correction). It acts only while
//!   0.9 g < |f| < 1.1 g, and never on heading (f × û is horizontal);
//! - the heading is free (no magnetometer): relative, 0 at the end of
//!   alignment.
//!
//! The AHRS runs on the sensor data before the FIR (the FIR of 5.6 filters
//! the *transmitted* signals), so orientation is not delayed by it.
//!
//! [`AttitudeFixed`] is the same filter in integers for the `fixed-point`
//! build, at the full tick rate (the attitude tests' bounds hold for both
//! builds).

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use crate::math::rotation::{
    canonical, cross, euler_from_quat, quat_rotate_inv, Quat, QuatIntegrator, Vec3, QUAT_IDENTITY,
};

/// Time constant of the accelerometer tilt correction, s.
pub const TILT_TIME_CONSTANT_S: f32 = 10.0;

const DEG: f32 = core::f32::consts::PI / 180.0;
const RAD: f32 = 180.0 / core::f32::consts::PI;

/// The attitude filter.
#[derive(Debug, Clone, PartialEq)]
pub struct Attitude {
    q: QuatIntegrator,
    earth_enu: Vec3,
    dt: f32,
    kp: f32,
    /// ω of the previous tick, rad/s (`None` after a reset).
    prev: Option<Vec3>,
}

impl Attitude {
    /// Starts at `q` with ticks of `dt` and the assumed Earth rate
    /// `earth_enu` (rad/s).
    pub fn new(q: Quat, earth_enu: Vec3, dt: f32) -> Self {
        Attitude {
            q: QuatIntegrator::new(q),
            earth_enu,
            dt,
            kp: 1.0 / TILT_TIME_CONSTANT_S,
            prev: None,
        }
    }

    /// Level, heading 0.
    pub fn level(earth_enu: Vec3, dt: f32) -> Self {
        Attitude::new(QUAT_IDENTITY, earth_enu, dt)
    }

    /// Sets the attitude at the time of the last rate sample seen (the
    /// previous rate is kept, so the next tick integrates its full interval).
    pub fn set(&mut self, q: Quat) {
        self.q.set(q);
    }

    /// Records a rate sample (°/s) without integrating it — while the chain
    /// aligns, so that the first tick after alignment has its interval's
    /// first sample.
    pub fn note_rate(&mut self, gyro_dps: &Vec3) {
        self.prev = Some([gyro_dps[0] * DEG, gyro_dps[1] * DEG, gyro_dps[2] * DEG]);
    }

    /// Turns the tilt correction on or off (tests of pure integration).
    pub fn set_tilt_correction(&mut self, on: bool) {
        self.kp = if on { 1.0 / TILT_TIME_CONSTANT_S } else { 0.0 };
    }

    /// The attitude quaternion (object → ENU), q0 ≥ 0 (the C.6 form).
    pub fn quat(&self) -> Quat {
        canonical(&self.q.get())
    }

    /// Heading (0..360), pitch, roll in degrees (C.7).
    pub fn euler_deg(&self) -> Vec3 {
        let e = euler_from_quat(&self.q.get());
        [e[0] * RAD, e[1] * RAD, e[2] * RAD]
    }

    /// One tick with bias-compensated rates (°/s) and specific force (g),
    /// both in carrier axes.
    #[inline]
    pub fn update(&mut self, gyro_dps: &Vec3, acc_g: &Vec3) {
        let q = &self.q.get();
        let we = quat_rotate_inv(q, &self.earth_enu);
        let mut w = [
            gyro_dps[0] * DEG - we[0],
            gyro_dps[1] * DEG - we[1],
            gyro_dps[2] * DEG - we[2],
        ];
        let f2 = acc_g[0] * acc_g[0] + acc_g[1] * acc_g[1] + acc_g[2] * acc_g[2];
        if self.kp > 0.0 && f2 > 0.81 && f2 < 1.21 {
            // Estimated up axis in the body: row 3 of (C.4) at t_{k−1},
            // carried to t_k (dû/dt = −ω × û) so that a turning body does
            // not read its own rotation as a tilt error.
            let u0 = [
                2.0 * (q[1] * q[3] - q[0] * q[2]),
                2.0 * (q[2] * q[3] + q[0] * q[1]),
                q[0] * q[0] - q[1] * q[1] - q[2] * q[2] + q[3] * q[3],
            ];
            let d = cross(&w, &u0);
            let u = [
                u0[0] - d[0] * self.dt,
                u0[1] - d[1] * self.dt,
                u0[2] - d[2] * self.dt,
            ];
            let e = cross(acc_g, &u);
            for i in 0..3 {
                w[i] += self.kp * e[i];
            }
        }
        // The first sample ever only opens the first interval.
        let Some(p) = self.prev.replace(w) else {
            return;
        };
        let h = 0.5 * self.dt;
        let c = cross(&p, &w);
        let k = self.dt * self.dt * (1.0 / 12.0);
        let a = [
            (p[0] + w[0]) * h + c[0] * k,
            (p[1] + w[1]) * h + c[1] * k,
            (p[2] + w[2]) * h + c[2] * k,
        ];
        self.q.rotate(&a);
    }
}

// ----- fixed point (the `fixed-point` build) -----

use crate::math::fixed::{mul64, mul_q30, mul_shr, Coef};
use crate::math::rotation::{euler_deg_q30, quat_rotate_inv_q30, up_in_body_q30, QuatFixed};
use crate::math::units::{ACC_BITS, GYRO_BITS};

/// [`Attitude`] in integers, for the `fixed-point` build: the same
/// algorithm (trapezoid + two-sample coning rotation vector, Earth rate
/// removed, Mahony tilt correction) on rates in Q36 radians per tick and a
/// Q62 quaternion ([`QuatFixed`]).
///
/// Inputs: gyro in °/s·2^[`GYRO_BITS`], specific force in g·2^[`ACC_BITS`]
/// (the fixed-point sensor scale), carrier axes. The bias set by
/// [`AttitudeFixed::set_bias`] is subtracted in Q36 per tick, finer than the
/// gyro's own LSB, so a static unit stays put to ~1e-4° over minutes (the
/// residual is the rounding of three Q36 terms, ≤ 2e-11 rad per tick).
#[derive(Debug, Clone, PartialEq)]
pub struct AttitudeFixed {
    q: QuatFixed,
    /// ENU Earth rate × dt, Q50 rad.
    earth_tick: [i32; 3],
    /// Gyro unit → Q36 rad per tick, Q30.
    gyro_k: i32,
    /// Gyro bias, Q36 rad per tick.
    bias_tick: [i32; 3],
    /// k_p·dt from the Q29 tilt error to Q36 rad per tick (zero: off).
    tilt_k: Coef,
    tilt_on: bool,
    prev: [i32; 3],
    has_prev: bool,
}

const Q36: f64 = 68_719_476_736.0;

/// The largest rotation of one tick about an axis the fixed-point AHRS
/// carries, Q36 rad: 2³¹ − 2²⁷, 0.0293 rad (3357 °/s at 2 kHz). A faster
/// axis is read at this rate (the attitude lags; no ISB output reads it,
/// docs/sensors.md "Fixed point"). The margin keeps the coning term
/// (|p × w| < 1.76·2⁶²) and a = ½(p + w) + p × w/12 within their integers.
pub const TICK_ROTATION_MAX: i32 = ((1i64 << 31) - (1 << 27)) as i32;

impl AttitudeFixed {
    /// Starts at `q` with ticks of `dt` and the assumed Earth rate
    /// `earth_enu` (rad/s).
    pub fn new(q: Quat, earth_enu: Vec3, dt: f32) -> Self {
        let dt64 = f64::from(dt);
        let e = |w: f32| libm::round(f64::from(w) * dt64 * 1_125_899_906_842_624.0) as i32; // 2⁵⁰
        let gyro_k =
            core::f64::consts::PI / 180.0 * dt64 * Q36 / crate::math::exp2i(GYRO_BITS as i32);
        AttitudeFixed {
            q: QuatFixed::from_f32(&q),
            earth_tick: earth_enu.map(e),
            gyro_k: libm::round(gyro_k * 1_073_741_824.0) as i32,
            bias_tick: [0; 3],
            tilt_k: Coef::new(f64::from(1.0 / TILT_TIME_CONSTANT_S) * dt64 * 128.0),
            tilt_on: true,
            prev: [0; 3],
            has_prev: false,
        }
    }

    /// [`Attitude::set`].
    pub fn set(&mut self, q: Quat) {
        self.q = QuatFixed::from_f32(&q);
    }

    /// [`AttitudeFixed::set`] from a Q30 quaternion (no float arithmetic).
    pub fn set_q30(&mut self, q: crate::math::rotation::QuatQ30) {
        self.q = QuatFixed::from_q30(q);
    }

    /// The gyro bias to subtract, °/s (carrier axes): one `f32` product per
    /// axis.
    pub fn set_bias(&mut self, bias_dps: &Vec3, dt: f32) {
        // π/180 · 2³⁶ · dt: Q36 radians per tick per °/s.
        let k = 1.199_381_1e9_f32 * dt;
        self.bias_tick = bias_dps.map(|b| crate::math::fixed::to_fixed(b * k, 0));
    }

    /// A gyro sample's rotation in one tick, Q36 rad, clamped to
    /// ±[`TICK_ROTATION_MAX`] (the product in `i64`: at 2 kHz the `i32`
    /// holds 3581 °/s, the gyro up to 4096).
    #[inline(always)]
    fn tick_rotation(&self, g: i32) -> i32 {
        let r = (mul64(g, self.gyro_k) + (1 << 29)) >> 30;
        r.clamp(-i64::from(TICK_ROTATION_MAX), i64::from(TICK_ROTATION_MAX)) as i32
    }

    /// [`Attitude::note_rate`] (gyro scaled).
    pub fn note_rate(&mut self, gyro: &[i32; 3]) {
        self.prev = gyro.map(|g| self.tick_rotation(g));
        self.has_prev = true;
    }

    /// [`Attitude::set_tilt_correction`].
    pub fn set_tilt_correction(&mut self, on: bool) {
        self.tilt_on = on;
    }

    /// The attitude quaternion (object → ENU), q0 ≥ 0 (the C.6 form).
    pub fn quat(&self) -> Quat {
        canonical(&self.q.to_f32())
    }

    /// Heading (0..360), pitch, roll in degrees (C.7), by CORDIC.
    pub fn euler_deg(&self) -> Vec3 {
        euler_deg_q30(&self.q.get())
    }

    /// [`Attitude::update`] on scaled rates (bias not yet removed) and
    /// specific force, carrier axes.
    #[inline]
    pub fn update(&mut self, gyro: &[i32; 3], acc: &[i32; 3]) {
        let q = self.q.get();
        let we = quat_rotate_inv_q30(&q, &self.earth_tick);
        let mut w = [0i32; 3];
        for i in 0..3 {
            // Q50 → Q36.
            let we36 = (we[i] + (1 << 13)) >> 14;
            w[i] = self
                .tick_rotation(gyro[i])
                .saturating_sub(self.bias_tick[i])
                .saturating_sub(we36);
        }
        // Tilt: |f| between 0.9 and 1.1 g (each component within 1.1 g
        // first, so the squares fit).
        const G11: i32 = (1.1 * (1u32 << ACC_BITS) as f32) as i32;
        if self.tilt_on && acc.iter().all(|a| a.unsigned_abs() <= G11 as u32) {
            let f = acc.map(|a| a << (29 - ACC_BITS)); // Q29
            let f2 = mul_q30(f[0], f[0]) + mul_q30(f[1], f[1]) + mul_q30(f[2], f[2]); // Q28
            if f2 > (0.81 * (1u32 << 28) as f32) as i32 && f2 < (1.21 * (1u32 << 28) as f32) as i32
            {
                // Up axis at t_{k−1}, carried to t_k: u = u0 − (w·dt) × u0.
                let u0 = up_in_body_q30(&q);
                let d = [
                    mul_shr(w[1], u0[2], 36) - mul_shr(w[2], u0[1], 36),
                    mul_shr(w[2], u0[0], 36) - mul_shr(w[0], u0[2], 36),
                    mul_shr(w[0], u0[1], 36) - mul_shr(w[1], u0[0], 36),
                ];
                let u = [u0[0] - d[0], u0[1] - d[1], u0[2] - d[2]];
                // e = f × u, Q29.
                let e = [
                    mul_q30(f[1], u[2]) - mul_q30(f[2], u[1]),
                    mul_q30(f[2], u[0]) - mul_q30(f[0], u[2]),
                    mul_q30(f[0], u[1]) - mul_q30(f[1], u[0]),
                ];
                for i in 0..3 {
                    w[i] = w[i].saturating_add(self.tilt_k.apply(e[i]));
                }
            }
        }
        let w = w.map(|x| x.clamp(-TICK_ROTATION_MAX, TICK_ROTATION_MAX));
        // The first sample ever only opens the first interval.
        if !self.has_prev {
            self.prev = w;
            self.has_prev = true;
            return;
        }
        let p = self.prev;
        self.prev = w;
        // a = ½(p + w) + (1/12) p × w, Q36.
        let c = [
            mul64(p[1], w[2]) - mul64(p[2], w[1]),
            mul64(p[2], w[0]) - mul64(p[0], w[2]),
            mul64(p[0], w[1]) - mul64(p[1], w[0]),
        ];
        let mut a = [0i32; 3];
        for i in 0..3 {
            let half = ((i64::from(p[i]) + i64::from(w[i]) + 1) >> 1) as i32;
            // c is Q72; /12 and → Q36.
            let ci = ((c[i] >> 34) as i32 + 2) >> 2; // Q36 (c/2³⁶, rounded)
            a[i] = half + mul_shr(ci, 357_913_941, 32); // ·2³²/12
        }
        self.q.rotate(&a);
    }
}
