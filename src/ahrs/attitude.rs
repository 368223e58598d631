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

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::rotation::{
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
