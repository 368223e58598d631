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
//! truth is measured in). `f64`: a position needs it, and the attitude
//! too (a navigation period turns it by about an `f32` ulp of a
//! quaternion component: the rounding would be a drift of the order of
//! the IMX-5's gyro bias instability).
//!
//! The Earth's terms of the position (the latitude's sine and cosine, the
//! radii, gravity: [`Earth`]) are what the soft double precision of the
//! firmware makes dear; they are computed at an anchor
//! ([`Nominal::refresh`], at each covariance propagation, on a tick of its
//! own) and carried from it to the current position to first order: the
//! anchor is at most [`ANCHOR_LAT_RAD`] and [`ANCHOR_H_M`] away (else it
//! is moved first), where the terms left out are below 10⁻⁸ of each
//! (`docs/navigation.md` "Firmware cost").

use libm::{cos, sin, sqrt};

use crate::math::double::{
    add, quat_from_rotvec, quat_mul, quat_normalize, scale, wrap_pi, Q4, V3,
};

/// The anchor of [`Earth`] is moved to the position when the latitude is
/// further from it than this, rad (64 m; a propagation interval at 250 m/s
/// moves 5 m).
pub(crate) const ANCHOR_LAT_RAD: f64 = 1e-5;
/// … or the height, m.
pub(crate) const ANCHOR_H_M: f64 = 10.0;

/// The Earth's terms at an anchor position (WGS84, the formulas of
/// [`wgs84`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Earth {
    /// The anchor: latitude, rad, and height, m.
    pub lat: f64,
    /// Height of the anchor, m.
    pub h: f64,
    /// sin and cos of the latitude.
    pub sin_lat: f64,
    /// cos of the latitude.
    pub cos_lat: f64,
    /// Meridian radius of curvature M, m.
    pub rm: f64,
    /// Prime-vertical radius of curvature N, m.
    pub rn: f64,
    /// Normal gravity, m/s².
    pub g: f64,
    /// Its vertical gradient dγ/dh, 1/s².
    pub dg_dh: f64,
}

impl Earth {
    /// At latitude `lat` (rad), height `h` (m).
    pub(crate) fn at(lat: f64, h: f64) -> Earth {
        let (sl, cl) = (sin(lat), cos(lat));
        let s2 = sl * sl;
        let w = sqrt(1.0 - wgs84::E2 * s2);
        let g0 = wgs84::GAMMA_E * (1.0 + wgs84::K * s2) / w;
        let k1 = 2.0 / wgs84::A * (1.0 + wgs84::F + wgs84::M - 2.0 * wgs84::F * s2);
        let a2 = wgs84::A * wgs84::A;
        Earth {
            lat,
            h,
            sin_lat: sl,
            cos_lat: cl,
            rm: wgs84::A * (1.0 - wgs84::E2) / (w * w * w),
            rn: wgs84::A / w,
            g: g0 * (1.0 - k1 * h + 3.0 * h * h / a2),
            dg_dh: g0 * (-k1 + 6.0 * h / a2),
        }
    }

    /// Whether a position (`lat` rad, `h` m) is near enough the anchor.
    fn near(&self, lat: f64, h: f64) -> bool {
        (lat - self.lat).abs() <= ANCHOR_LAT_RAD && (h - self.h).abs() <= ANCHOR_H_M
    }
}
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
    /// The Earth's terms at an anchor near the position (module doc).
    pub earth: Earth,
}

impl Nominal {
    /// At `lla` (deg, deg, m), at rest, level, facing north, no bias.
    pub fn at(lla: &[f64; 3]) -> Self {
        let (lat, h) = (lla[0].to_radians(), lla[2]);
        Nominal {
            lat,
            lon: lla[1].to_radians(),
            h,
            v: [0.0; 3],
            q: [1.0, 0.0, 0.0, 0.0],
            bg: [0.0; 3],
            ba: [0.0; 3],
            earth: Earth::at(lat, h),
        }
    }

    /// Moves the anchor of `Nominal::earth` to the position, and scales
    /// the attitude back to unit length (the periods since the last call
    /// left it within 10⁻⁹ of one: `turn`).
    pub(crate) fn refresh(&mut self) {
        self.earth = Earth::at(self.lat, self.h);
        self.q = quat_normalize(&self.q);
    }

    /// The Earth's terms, the anchor moved first if the position left it
    /// (a jump: the first fix, a large correction).
    fn earth(&mut self) -> Earth {
        if !self.earth.near(self.lat, self.h) {
            self.refresh();
        }
        self.earth
    }

    /// sin and cos of the latitude, carried from the anchor to first order
    /// (the second-order term is below 5·10⁻¹¹).
    fn sin_cos_lat(&self, e: &Earth) -> (f64, f64) {
        let d = self.lat - e.lat;
        (e.sin_lat + e.cos_lat * d, e.cos_lat - e.sin_lat * d)
    }

    /// Position as latitude °, longitude °, height m.
    pub(crate) fn lla(&self) -> [f64; 3] {
        [self.lat.to_degrees(), self.lon.to_degrees(), self.h]
    }

    /// Moves on by one period `inc` (module doc); returns the specific
    /// force's velocity increment in NED (m/s) over the period, which the
    /// covariance propagation needs.
    pub fn mechanise(&mut self, inc: &Increment) -> V3 {
        let dt = inc.dt;
        if dt <= 0.0 {
            return [0.0; 3];
        }
        // The Earth's terms from the anchor (module doc).
        let e = self.earth();
        let (sl, cl) = self.sin_cos_lat(&e);
        let (nh, mh) = (e.rn + self.h, e.rm + self.h);
        // The rates in `f32`: what they turn and accelerate in a period
        // (10⁻⁷ rad, 10⁻⁴ m/s) needs their relative precision only.
        let (s32, c32, dt32) = (sl as f32, cl as f32, dt as f32);
        let v32 = self.v.map(|x| x as f32);
        let om = wgs84::OMEGA_IE as f32;
        let wie = [om * c32, 0.0, -om * s32];
        let wen = [
            v32[1] / nh as f32,
            -v32[0] / mh as f32,
            -v32[1] * s32 / (c32 * nh as f32),
        ];
        let q0 = self.q;
        let dth = [0, 1, 2].map(|k| inc.dtheta[k] as f32 - self.bg[k] as f32 * dt32);
        let nav = [0, 1, 2].map(|k| -0.5 * (wie[k] + wen[k]) * dt32);
        self.q = match turn(&q0, &dth, &nav) {
            Some(dq) => [0, 1, 2, 3].map(|k| q0[k] + f64::from(dq[k])),
            None => {
                let body = quat_from_rotvec(&dth.map(f64::from));
                let nav = quat_from_rotvec(&nav.map(|x| 2.0 * f64::from(x)));
                quat_normalize(&quat_mul(&nav, &quat_mul(&q0, &body)))
            }
        };
        let dv = add(&inc.dv, &scale(&self.ba, -dt));
        let dv_n = rotate_by(&q0, &dv);
        let w = [0, 1, 2].map(|j| 2.0 * wie[j] + wen[j]);
        let cor = crate::math::rotation::cross(&w, &v32).map(|c| f64::from(c * dt32));
        let g = e.g + e.dg_dh * (self.h - e.h);
        let v0 = self.v;
        let v1 = [
            v0[0] + dv_n[0] - cor[0],
            v0[1] + dv_n[1] - cor[1],
            v0[2] + dv_n[2] + g * dt - cor[2],
        ];
        // The move with the radii of the period's start, the new
        // latitude's cosine to first order (the period moves it by
        // ≈ 1e-5 rad at most: a relative error under 1e-10).
        let d = [0, 1, 2].map(|k| (v0[k] + v1[k]) * (0.5 * dt));
        let dlat = d[0] / mh;
        self.lat += dlat;
        self.lon = wrap_pi(self.lon + d[1] / (nh * (cl - sl * dlat)));
        self.h -= d[2];
        self.v = v1;
        dv_n
    }

    /// Moves the position by a small NED displacement `d` (m).
    pub(crate) fn move_ned(&mut self, d: &V3) {
        let e = self.earth();
        let (_, cl) = self.sin_cos_lat(&e);
        let dlat = d[0] / (e.rm + self.h);
        self.lon = wrap_pi(self.lon + d[1] / ((e.rn + self.h) * cl));
        self.lat += dlat;
        self.h -= d[2];
    }

    /// Adds an estimated error state `dx` (position NED m, velocity m/s,
    /// attitude rad in NED, gyro bias rad/s, accelerometer bias m/s²):
    /// the truth is the estimate plus the error.
    pub(crate) fn correct(&mut self, dx: &[f32; super::filter::N]) {
        let g = |i: usize| [0, 1, 2].map(|k| f64::from(dx[i + k]));
        self.move_ned(&g(super::filter::POS));
        self.v = add(&self.v, &g(super::filter::VEL));
        let phi = g(super::filter::ATT);
        self.q = quat_normalize(&quat_mul(&rotvec_quat(&phi), &self.q));
        self.bg = add(&self.bg, &g(super::filter::BG));
        self.ba = add(&self.ba, &g(super::filter::BA));
    }
}

/// `v` rotated by the unit quaternion `q` (`q ⊗ v ⊗ q*`) as `v + w t + u ×
/// t`, `t = 2 u × v` (`u` the vector part): half the double operations of
/// the matrix form (soft double precision on the M4F), the same rotation.
fn rotate_by(q: &Q4, v: &V3) -> V3 {
    let (w, u) = (q[0], [q[1], q[2], q[3]]);
    let x = |a: &V3, b: &V3| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = x(&u, v).map(|c| 2.0 * c);
    let ut = x(&u, &t);
    [0, 1, 2].map(|k| v[k] + w * t[k] + ut[k])
}

/// What a period turns the attitude `q` by, `q⁺ − q` with `q⁺ = q(2u) ⊗ q
/// ⊗ q(θ)` (θ the body's rotation vector, `u` half the navigation frame's),
/// in `f32`: the change is at most 0.1 of `q`, so `f32`'s relative
/// precision of it is 10⁻⁸ of the turn (a scale-factor error of 0.06 ppm),
/// while `q` itself stays `f64`. The half-angle series ([`rotvec_quat`])
/// less their 1, so nothing small is lost against it. `None` for a turn of
/// 0.2 rad or more (or NaN): the caller turns in `f64`.
fn turn(q: &Q4, theta: &[f32; 3], u: &[f32; 3]) -> Option<[f32; 4]> {
    use crate::math::rotation::quat_mul as mul;
    let t2 = theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2];
    let u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    if !(t2 < 0.04 && u2 < 1e-4) {
        return None;
    }
    // cos(θ/2) − 1 and sin(θ/2)/θ in x = (θ/2)².
    let x = 0.25 * t2;
    let cm1 = -0.5 * x * (1.0 - x * (1.0 / 12.0) * (1.0 - x * (1.0 / 30.0)));
    let k = 0.5 * (1.0 - x * (1.0 / 6.0) * (1.0 - x * (1.0 / 20.0)));
    let p = q.map(|x| x as f32);
    // q ⊗ q(θ) − q = (c − 1) q + q ⊗ (0, k θ)
    let b = mul(&p, &[0.0, k * theta[0], k * theta[1], k * theta[2]]);
    let d1 = [0, 1, 2, 3].map(|i| cm1 * p[i] + b[i]);
    // q(2u) ⊗ X − X = (cos|u| − 1) X + (0, u) ⊗ X, X = q + d1 (|u| < 10⁻²:
    // the next terms are below 10⁻⁹ of it)
    let x1 = [0, 1, 2, 3].map(|i| p[i] + d1[i]);
    let n = mul(&[0.0, u[0], u[1], u[2]], &x1);
    let ncm1 = -0.5 * u2;
    Some([0, 1, 2, 3].map(|i| d1[i] + ncm1 * x1[i] + n[i]))
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
    // cos(θ/2) and sin(θ/2)/θ, Horner (the reciprocals are constants: no
    // division in soft double precision).
    let c = 1.0
        - x * 0.5
            * (1.0
                - x * (1.0 / 12.0)
                    * (1.0
                        - x * (1.0 / 30.0) * (1.0 - x * (1.0 / 56.0) * (1.0 - x * (1.0 / 90.0)))));
    let k = 0.5
        * (1.0
            - x * (1.0 / 6.0)
                * (1.0 - x * (1.0 / 20.0) * (1.0 - x * (1.0 / 42.0) * (1.0 - x * (1.0 / 72.0)))));
    [c, a[0] * k, a[1] * k, a[2] * k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::double::rotate;
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

    /// What [`turn`] adds in `f32` is the `f64` product's change to
    /// within `f32`'s precision of the change (not of the quaternion).
    #[test]
    fn the_f32_turn_is_the_f64_one() {
        let q = quat_normalize(&[0.7, -0.3, 0.5, 0.4]);
        for (th, u) in [
            ([1e-7, -2e-7, 3e-7], [1e-7, 0.0, -1.5e-7]),
            ([0.004, -0.001, 0.002], [2e-7, 0.0, -1e-7]),
            ([0.11, 0.1, -0.09], [1e-6, 3e-7, -2e-6]),
        ] {
            let th32 = th.map(|x: f64| x as f32);
            let u32_ = u.map(|x: f64| x as f32);
            let dq = turn(&q, &th32, &u32_).unwrap();
            let body = quat_from_rotvec(&th32.map(f64::from));
            let nav = quat_from_rotvec(&u32_.map(|x| 2.0 * f64::from(x)));
            let want = quat_mul(&nav, &quat_mul(&q, &body));
            let size = (th32.iter().map(|x| x * x).sum::<f32>()).sqrt() as f64;
            for k in 0..4 {
                let got = q[k] + f64::from(dq[k]);
                assert!(
                    (got - want[k]).abs() < 2e-7 * size + 1e-12,
                    "{th:?}: {k} {got} {}",
                    want[k]
                );
            }
        }
        assert!(turn(&q, &[0.3, 0.0, 0.0], &[0.0; 3]).is_none());
        assert!(turn(&q, &[f32::NAN, 0.0, 0.0], &[0.0; 3]).is_none());
    }

    #[test]
    fn the_quaternion_rotation_is_the_matrix_one() {
        let q = quat_normalize(&[0.7, -0.3, 0.5, 0.4]);
        let v = [0.01, -0.02, -0.0392];
        let (a, b) = (rotate_by(&q, &v), rotate(&q, &v));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-17, "{a:?} {b:?}");
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
