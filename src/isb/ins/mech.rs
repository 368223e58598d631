//! The strapdown mechanisation of the IMX-5's navigation filter: the
//! nominal (whole) state — WGS84 position, NED velocity, attitude, the
//! estimated sensor biases — moved on by one navigation period of the
//! unit's own coning- and sculling-corrected increments (the Δθ, Δv PIMU
//! reports), and corrected by the error state the Kalman filter
//! ([`super::filter`]) estimates. Frames and equations:
//! `docs/navigation.md` "Mechanisation".
//!
//! Per period `Δt`, with the increments corrected for the estimated biases
//! (`Δθ' = Δθ − b_g Δt`, `Δv' = Δv − b_a Δt`):
//!
//! ```text
//! q⁺ = q(−ω_in Δt) ⊗ q ⊗ q(Δθ')                     attitude (body → NED)
//! v⁺ = v + C(q) Δv' + (γ·d − (2ω_ie + ω_en) × v) Δt   velocity, NED
//! φ, λ, h ← trapezoidal in v                         position, WGS84
//! ```
//!
//! with ω_ie the Earth rate, ω_en the transport rate and γ WGS84 normal
//! gravity ([`crate::vehicle::wgs84`]: the same Earth the vehicle's IMU
//! truth is measured in). `f64`: a position needs it.

use libm::cos;

use crate::math::double::{
    add, cross, quat_from_rotvec, quat_mul, quat_normalize, rotate, scale, wrap_pi, Q4, V3,
};
use crate::vehicle::wgs84;

/// One navigation period of the unit's IMU: coning-corrected Δθ (rad) and
/// rotation- and sculling-corrected Δv (m/s), body (forward, right, down)
/// axes at the period's start, over `dt` seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Increment {
    /// Δθ, rad.
    pub dtheta: V3,
    /// Δv, m/s (specific force integrated).
    pub dv: V3,
    /// The period, s.
    pub dt: f64,
}

/// The nominal state of the filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nominal {
    /// Geodetic latitude, rad.
    pub lat: f64,
    /// Longitude, rad.
    pub lon: f64,
    /// Height above the ellipsoid, m.
    pub h: f64,
    /// Velocity, NED, m/s.
    pub v: V3,
    /// Attitude, body → NED (W, X, Y, Z; Hamilton).
    pub q: Q4,
    /// Estimated gyro bias, body axes, rad/s.
    pub bg: V3,
    /// Estimated accelerometer bias, body axes, m/s².
    pub ba: V3,
}

impl Nominal {
    /// At `lla` (deg, deg, m), at rest, level, facing north, no bias.
    pub fn at(lla: &[f64; 3]) -> Self {
        Nominal {
            lat: lla[0].to_radians(),
            lon: lla[1].to_radians(),
            h: lla[2],
            v: [0.0; 3],
            q: [1.0, 0.0, 0.0, 0.0],
            bg: [0.0; 3],
            ba: [0.0; 3],
        }
    }

    /// Position as latitude °, longitude °, height m.
    pub fn lla(&self) -> [f64; 3] {
        [self.lat.to_degrees(), self.lon.to_degrees(), self.h]
    }

    /// Moves on by one period `inc` (module doc); returns the specific
    /// force in NED (m/s²) over the period, which the covariance
    /// propagation needs.
    pub fn mechanise(&mut self, inc: &Increment) -> V3 {
        let dt = inc.dt;
        if dt <= 0.0 {
            return [0.0; 3];
        }
        let wie = wgs84::earth_rate_ned(self.lat);
        let wen = wgs84::transport_rate_ned(self.lat, self.h, &self.v);
        let win = add(&wie, &wen);
        let dth = add(&inc.dtheta, &scale(&self.bg, -dt));
        let dv = add(&inc.dv, &scale(&self.ba, -dt));
        let q0 = self.q;
        let dv_n = rotate(&q0, &dv);
        let body = quat_from_rotvec(&dth);
        let nav = quat_from_rotvec(&scale(&win, -dt));
        self.q = quat_normalize(&quat_mul(&nav, &quat_mul(&q0, &body)));
        let cor = cross(&add(&scale(&wie, 2.0), &wen), &self.v);
        let g = wgs84::normal_gravity(self.lat, self.h);
        let v0 = self.v;
        let v1 = [
            v0[0] + dv_n[0] - cor[0] * dt,
            v0[1] + dv_n[1] - cor[1] * dt,
            v0[2] + dv_n[2] + (g - cor[2]) * dt,
        ];
        let vm = scale(&add(&v0, &v1), 0.5);
        self.move_ned(&scale(&vm, dt));
        self.v = v1;
        scale(&dv_n, 1.0 / dt)
    }

    /// Moves the position by a small NED displacement `d` (m).
    pub fn move_ned(&mut self, d: &V3) {
        let (m, n) = wgs84::radii(self.lat);
        self.lat += d[0] / (m + self.h);
        self.lon = wrap_pi(self.lon + d[1] / ((n + self.h) * cos(self.lat)));
        self.h -= d[2];
    }

    /// Adds an estimated error state `dx` (position NED m, velocity m/s,
    /// attitude rad in NED, gyro bias rad/s, accelerometer bias m/s²):
    /// the truth is the estimate plus the error.
    pub fn correct(&mut self, dx: &[f32; super::filter::N]) {
        let g = |i: usize| [0, 1, 2].map(|k| f64::from(dx[i + k]));
        self.move_ned(&g(super::filter::POS));
        self.v = add(&self.v, &g(super::filter::VEL));
        let phi = g(super::filter::ATT);
        self.q = quat_normalize(&quat_mul(&quat_from_rotvec(&phi), &self.q));
        self.bg = add(&self.bg, &g(super::filter::BG));
        self.ba = add(&self.ba, &g(super::filter::BA));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::VehicleState;

    /// What a perfect IMU at rest measures (Earth rate, normal gravity)
    /// keeps the mechanisation at rest: 10 minutes at 250 Hz move it less
    /// than a centimetre.
    #[test]
    fn rest_stays_at_rest() {
        let s = VehicleState::at_rest(0.7, 0.1, 50.0, 1.0);
        let mut n = Nominal::at(&[0.7f64.to_degrees(), 0.1f64.to_degrees(), 50.0]);
        n.q = s.q_nb;
        let dt = 0.004;
        let inc = Increment {
            dtheta: scale(&s.rate_ib_b, dt),
            dv: scale(&s.force_b, dt),
            dt,
        };
        for _ in 0..150_000 {
            n.mechanise(&inc);
        }
        let (m, _) = wgs84::radii(0.7);
        assert!((n.lat - 0.7).abs() * m < 0.01, "{n:?}");
        assert!((n.h - 50.0).abs() < 0.01, "{n:?}");
        assert!(n.v.iter().all(|v| v.abs() < 1e-4), "{n:?}");
    }
}
