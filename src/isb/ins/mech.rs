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

use libm::{cos, sin, sqrt};

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
        // The latitude's sine and cosine once a period (soft double
        // precision on the M4F): the radii, the Earth and transport rates
        // and gravity from them (the formulas of `vehicle::wgs84`).
        let (sl, cl) = (sin(self.lat), cos(self.lat));
        let s2 = sl * sl;
        let w = sqrt(1.0 - wgs84::E2 * s2);
        let (rm, rn) = (wgs84::A * (1.0 - wgs84::E2) / (w * w * w), wgs84::A / w);
        let wie = [wgs84::OMEGA_IE * cl, 0.0, -wgs84::OMEGA_IE * sl];
        let (nh, mh) = (rn + self.h, rm + self.h);
        let wen = [self.v[1] / nh, -self.v[0] / mh, -self.v[1] * sl / (cl * nh)];
        let win = add(&wie, &wen);
        let dth = add(&inc.dtheta, &scale(&self.bg, -dt));
        let dv = add(&inc.dv, &scale(&self.ba, -dt));
        let q0 = self.q;
        let dv_n = rotate(&q0, &dv);
        let body = rotvec_quat(&dth);
        let nav = rotvec_quat(&scale(&win, -dt));
        self.q = quat_normalize(&quat_mul(&nav, &quat_mul(&q0, &body)));
        let cor = cross(&add(&scale(&wie, 2.0), &wen), &self.v);
        let h = self.h;
        let g = wgs84::GAMMA_E * (1.0 + wgs84::K * s2) / w
            * (1.0 - 2.0 / wgs84::A * (1.0 + wgs84::F + wgs84::M - 2.0 * wgs84::F * s2) * h
                + 3.0 * h * h / (wgs84::A * wgs84::A));
        let v0 = self.v;
        let v1 = [
            v0[0] + dv_n[0] - cor[0] * dt,
            v0[1] + dv_n[1] - cor[1] * dt,
            v0[2] + dv_n[2] + (g - cor[2]) * dt,
        ];
        let vm = scale(&add(&v0, &v1), 0.5);
        // The move with the radii of the period's start, the new
        // latitude's cosine to first order (the period moves it by
        // ≈ 1e-5 rad at most: a relative error under 1e-10).
        let d = scale(&vm, dt);
        let dlat = d[0] / mh;
        self.lat += dlat;
        self.lon = wrap_pi(self.lon + d[1] / (nh * (cl - sl * dlat)));
        self.h -= d[2];
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

/// [`quat_from_rotvec`] without a square root, sine or cosine for the
/// angles a navigation period turns (θ < 0.2 rad): their series in
/// `x = (θ/2)²`, to terms below 1e-17 (soft double precision on the M4F).
fn rotvec_quat(a: &V3) -> Q4 {
    let t2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    if t2.is_nan() || t2 >= 0.04 {
        return quat_from_rotvec(a);
    }
    let x = 0.25 * t2;
    // cos(θ/2) and sin(θ/2)/θ, Horner.
    let c =
        1.0 - x / 2.0 * (1.0 - x / 12.0 * (1.0 - x / 30.0 * (1.0 - x / 56.0 * (1.0 - x / 90.0))));
    let k = 0.5 * (1.0 - x / 6.0 * (1.0 - x / 20.0 * (1.0 - x / 42.0 * (1.0 - x / 72.0))));
    [c, a[0] * k, a[1] * k, a[2] * k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::VehicleState;

    /// What a perfect IMU at rest measures (Earth rate, normal gravity)
    /// keeps the mechanisation at rest: 10 minutes at 250 Hz move it less
    /// than a centimetre.
    #[test]
    fn the_series_rotation_is_the_trigonometric_one() {
        for a in [
            [0.0; 3],
            [1e-7, -2e-7, 3e-7],
            [0.05, -0.1, 0.02],
            [0.11, 0.1, -0.09],
        ] {
            let (s, t) = (rotvec_quat(&a), quat_from_rotvec(&a));
            for k in 0..4 {
                assert!((s[k] - t[k]).abs() < 1e-15, "{a:?}: {s:?} {t:?}");
            }
        }
    }

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
