//! The vehicle the IMU rides on: one navigation truth per unit, below the
//! signal chain (docs/motion.md).
//!
//! ```text
//! motion sources (built-in motions, manoeuvre script, full-state rows,
//! rate/force rows integrated)
//!        │  each gives the vehicle at device time t
//!        ▼
//! VehicleState: lat, lon, h (WGS84), v_NED, q_nb, ω_ib^b, f^b, T
//!        │  ω and f are what a perfect IMU on the vehicle measures
//!        ▼
//! Truth (housing axes, °/s and g) ──► the signal chain, as before
//! ```
//!
//! Frames and conventions (docs/motion.md, "Frames"):
//! - navigation frame: local NED (north, east, down) on the WGS84
//!   ellipsoid; positions geodetic (latitude, longitude, height above the
//!   ellipsoid);
//! - body frame: forward, right, down (FRD); attitude `q_nb` rotates body
//!   vectors into NED (`v_n = q ⊗ v_b ⊗ q*`), scalar first, q0 ≥ 0; Euler
//!   angles roll φ, pitch θ, yaw ψ in the z-y-x order
//!   (`C_nb = Rz(ψ) Ry(θ) Rx(φ)`);
//! - the IMU housing (the KERNEL's axes, ICD 5.2 notes: X lateral, Y
//!   longitudinal, Z up) is mounted with X along body right, Y along body
//!   forward, Z along body up ([`body_to_housing`]); the chain's
//!   [`crate::sensor::TruthFrame`] and Alignment_Angles apply to it as to
//!   every other truth;
//! - the measurement: `ω_ib^b = ω_nb^b + C_bn (ω_ie^n + ω_en^n)` and
//!   `f^b = C_bn (v̇^n + (2ω_ie^n + ω_en^n) × v^n − γ^n)` with WGS84 normal
//!   gravity γ along down ([`wgs84`]).
//!
//! Everything is `f64` (a position needs it: docs/motion.md, "Precision")
//! and runs where the state is made: the host's sources once a tick; the
//! built-in motions' state is derived only when read
//! ([`builtin_state`]), so a firmware tick does no `f64` work.

// Numeric code indexes parallel arrays (axes) by one index.
#![allow(clippy::needless_range_loop)]

pub mod fullstate;

#[path = "script.rs"]
mod script_all;
facade! {
    /// Manoeuvre scripts: the parser and the player a board runs; the
    /// limits a script is checked against stay inside.
    pub mod script = script_all {
        is_script, Manoeuvre, Manoeuvres, Script, ScriptError, ScriptErrorKind, Segment, Start,
    }
}

internal! {
    mod strapdown;
    mod wgs84;
}

pub use fullstate::{FullStateLayout, FullStateRow, RowError};
pub use script::{Manoeuvre, Manoeuvres, Script, ScriptError, Segment, Start};
pub use strapdown::Strapdown;

use crate::sensor::motion::{Motion, Truth};

pub use crate::math::double::{Q4, V3};
// The rotations the models use, from the crate's maths.
#[cfg(feature = "internals")]
pub use crate::math::double::{
    add, body_rate_of_euler, cross, euler_from_quat, quat_conj, quat_from_euler, quat_from_rotvec,
    quat_mul, quat_normalize, rotate, rotate_inv, rotvec_from_quat, scale, wrap_pi,
};
#[cfg(not(feature = "internals"))]
pub(crate) use crate::math::double::{
    add, body_rate_of_euler, cross, euler_from_quat, quat_conj, quat_from_euler, quat_from_rotvec,
    quat_mul, quat_normalize, rotate, rotate_inv, rotvec_from_quat, scale, wrap_pi,
};

/// g in m/s² as the ICD defines it (Table 5.5 note 1): the unit of the
/// specific force handed to the chain.
pub const G_ICD: f64 = 9.8106;

/// Longitude of the built-in site, degrees east: the Newlyn Tidal
/// Observatory, Cornwall (5° 32.5′ W; its latitude is
/// [`crate::sensor::motion::DEFAULT_LATITUDE_DEG`], docs/motion.md "The
/// built-in site").
pub const DEFAULT_LONGITUDE_DEG: f64 = -5.541_667;

/// One instant of the vehicle: where it is, how it moves, and what a
/// perfect IMU on it measures (module doc for the frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleState {
    /// Device time of the state, s.
    pub time_s: f64,
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad, in (−π, π].
    pub lon_rad: f64,
    /// Height above the WGS84 ellipsoid, m.
    pub height_m: f64,
    /// Velocity over the ground, NED, m/s.
    pub vel_ned: V3,
    /// Attitude, body (FRD) → NED, scalar first, q0 ≥ 0.
    pub q_nb: Q4,
    /// Inertial angular rate ω_ib^b, body axes, rad/s.
    pub rate_ib_b: V3,
    /// Specific force f^b, body axes, m/s².
    pub force_b: V3,
    /// Sensor temperature, °C, if the source sets it (`None`: the chain's
    /// temperature model decides).
    pub temperature_c: Option<f32>,
}

/// What a state's time derivatives are, for [`measure`]: the NED velocity's
/// rate of change and the body rate relative to NED.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion6 {
    /// d/dt of the NED velocity components, m/s².
    pub acc_ned: V3,
    /// Body rate relative to the NED frame, body axes, rad/s.
    pub rate_nb_b: V3,
}

impl VehicleState {
    /// A vehicle at rest in NED at (`lat`, `lon`, `height`), level at
    /// heading `yaw` (rad), with its measurement filled in.
    pub fn at_rest(lat_rad: f64, lon_rad: f64, height_m: f64, yaw_rad: f64) -> Self {
        let mut s = VehicleState {
            time_s: 0.0,
            lat_rad,
            lon_rad,
            height_m,
            vel_ned: [0.0; 3],
            q_nb: quat_from_euler(0.0, 0.0, yaw_rad),
            rate_ib_b: [0.0; 3],
            force_b: [0.0; 3],
            temperature_c: None,
        };
        s.measure(&Motion6 {
            acc_ned: [0.0; 3],
            rate_nb_b: [0.0; 3],
        });
        s
    }

    /// Fills in [`VehicleState::rate_ib_b`] and [`VehicleState::force_b`]
    /// from the state and its derivatives `m` (module doc: Earth rate,
    /// transport rate, Coriolis, normal gravity).
    pub fn measure(&mut self, m: &Motion6) {
        let (w, f) = measure(self, m);
        self.rate_ib_b = w;
        self.force_b = f;
    }

    /// Roll, pitch, yaw, rad (yaw in (−π, π]).
    pub fn euler_rad(&self) -> V3 {
        euler_from_quat(&self.q_nb)
    }

    /// The truth the chain takes: ω in °/s and f in g (the ICD's g), in the
    /// IMU housing's axes ([`body_to_housing`]), and the temperature.
    pub fn truth(&self) -> Truth {
        let w = body_to_housing(&self.rate_ib_b);
        let f = body_to_housing(&self.force_b);
        Truth {
            rate_dps: w.map(|x| x.to_degrees() as f32),
            specific_force_g: f.map(|x| (x / G_ICD) as f32),
            temperature_c: self.temperature_c,
        }
    }
}

/// What a perfect IMU measures on a vehicle in state `s` (position,
/// velocity, attitude) moving as `m` says: (ω_ib^b rad/s, f^b m/s²).
pub fn measure(s: &VehicleState, m: &Motion6) -> (V3, V3) {
    let wie = wgs84::earth_rate_ned(s.lat_rad);
    let wen = wgs84::transport_rate_ned(s.lat_rad, s.height_m, &s.vel_ned);
    let win = add(&wie, &wen);
    let w = add(&m.rate_nb_b, &rotate_inv(&s.q_nb, &win));
    let cor = cross(&add(&scale(&wie, 2.0), &wen), &s.vel_ned);
    let g = wgs84::normal_gravity(s.lat_rad, s.height_m);
    let f_n = [
        m.acc_ned[0] + cor[0],
        m.acc_ned[1] + cor[1],
        m.acc_ned[2] + cor[2] - g,
    ];
    (w, rotate_inv(&s.q_nb, &f_n))
}

/// A body (FRD) vector in the IMU housing's axes (X right, Y forward, Z
/// up). Its own inverse.
pub fn body_to_housing(v: &V3) -> V3 {
    [v[1], v[0], -v[2]]
}

/// A housing vector in body axes ([`body_to_housing`] is its own inverse).
pub fn housing_to_body(v: &V3) -> V3 {
    body_to_housing(v)
}

/// [`wgs84::height_of_gravity`] at
/// [`crate::sensor::motion::DEFAULT_LATITUDE_DEG`] and the ICD's g, m
/// (bit for bit: `the_default_site_height_is_the_solved_one`).
pub const DEFAULT_SITE_HEIGHT_M: f64 = f64::from_bits(0x404f_3f3d_7f72_7bd1);

/// Where a built-in [`Motion`] stands: its latitude, the height where
/// WGS84 normal gravity is the ICD's g ([`wgs84::height_of_gravity`]) and
/// the level attitude at its heading. Fixed for a motion, so the chain
/// keeps it ([`Site::of`] when the motion is chosen) instead of solving
/// for the height and turning the heading each time the vehicle is read
/// (about 100 000 instructions of soft double precision on the M4F).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Site {
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Height above the ellipsoid, m.
    pub height_m: f64,
    /// Level at the site's heading, body (FRD) → NED.
    pub level: Q4,
}

impl Site {
    /// The site of `motion` (its latitude and heading,
    /// [`DEFAULT_LONGITUDE_DEG`]).
    pub fn of(motion: &Motion) -> Site {
        let (lat_deg, heading_deg) = crate::sensor::motion::site(motion);
        let lat = f64::from(lat_deg).to_radians();
        // Every power-on starts at the default site: its height is a
        // constant (the solution's own bits, checked by a test) rather
        // than a solve in soft double precision on each reset.
        let height_m = if lat_deg == crate::sensor::motion::DEFAULT_LATITUDE_DEG {
            DEFAULT_SITE_HEIGHT_M
        } else {
            wgs84::height_of_gravity(lat, G_ICD)
        };
        Site {
            lat_rad: lat,
            height_m,
            level: quat_from_euler(0.0, 0.0, f64::from(heading_deg).to_radians()),
        }
    }

    /// A placeholder (the equator, height 0, facing north), for a chain
    /// not yet powered on.
    pub const fn placeholder() -> Site {
        Site {
            lat_rad: 0.0,
            height_m: 0.0,
            level: [1.0, 0.0, 0.0, 0.0],
        }
    }
}

/// The state of a built-in motion at `time_s`: its `site` ([`Site::of`]
/// the motion: latitude, [`DEFAULT_LONGITUDE_DEG`], the height where WGS84
/// normal gravity is the ICD's g), at rest, with the attitude the motion
/// reports (housing → ENU, Appendix C; `None`: level at the site's
/// heading) and its truth as the measurement (housing axes, °/s and g).
/// The built-ins rotate and vibrate in place (docs/motion.md).
pub fn builtin_state(
    site: &Site,
    attitude: Option<crate::math::rotation::Quat>,
    truth: &Truth,
    time_s: f64,
) -> VehicleState {
    let q_nb = match attitude {
        Some(q) => housing_enu_to_body_ned(&q.map(f64::from)),
        None => site.level,
    };
    let w = housing_to_body(&truth.rate_dps.map(|x| f64::from(x).to_radians()));
    let f = housing_to_body(&truth.specific_force_g.map(|x| f64::from(x) * G_ICD));
    VehicleState {
        time_s,
        lat_rad: site.lat_rad,
        lon_rad: DEFAULT_LONGITUDE_DEG.to_radians(),
        height_m: site.height_m,
        vel_ned: [0.0; 3],
        q_nb,
        rate_ib_b: w,
        force_b: f,
        temperature_c: truth.temperature_c,
    }
}

/// A housing → ENU attitude (the built-in motions', Appendix C) as body
/// (FRD) → NED: `C_nb = P C_eh P` with P the swap of the first two axes
/// and the sign of the third (ENU ↔ NED and RFU ↔ FRD alike). P is the
/// half turn about (1, 1, 0)/√2, so on the quaternion it swaps X and Y and
/// negates Z: `(w, x, y, z) → (w, y, x, −z)` (normalised, w ≥ 0) — no
/// matrix and back (soft double precision on the firmware, where the
/// truth is read at every receiver step).
pub fn housing_enu_to_body_ned(q_eh: &Q4) -> Q4 {
    let [w, x, y, z] = *q_eh;
    quat_normalize(&[w, y, x, -z])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::double::{dcm_from_quat, quat_from_dcm};
    use crate::math::rotation::quat_from_euler as quat_from_euler_c;

    fn close(a: &V3, b: &V3, tol: f64) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
    }

    #[test]
    fn euler_round_trip() {
        for e in [[0.1, -0.2, 2.5], [-1.0, 0.7, -3.0], [0.0, 0.0, 0.0]] {
            let q = quat_from_euler(e[0], e[1], e[2]);
            assert!(close(&euler_from_quat(&q), &e, 1e-12), "{e:?}");
        }
    }

    #[test]
    fn rotvec_round_trip() {
        let a = [0.3, -1.2, 0.5];
        assert!(close(&rotvec_from_quat(&quat_from_rotvec(&a)), &a, 1e-12));
    }

    /// A level vehicle at rest measures −γ along body z and the Earth rate
    /// `Ω (cos φ, 0, −sin φ)` at heading 0.
    #[test]
    fn at_rest_measures_gravity_and_earth_rate() {
        let lat = 45f64.to_radians();
        let s = VehicleState::at_rest(lat, 0.3, 100.0, 0.0);
        let g = wgs84::normal_gravity(lat, 100.0);
        assert!(close(&s.force_b, &[0.0, 0.0, -g], 1e-12));
        assert!(close(&s.rate_ib_b, &wgs84::earth_rate_ned(lat), 1e-18));
        let t = s.truth();
        assert!((f64::from(t.specific_force_g[2]) - g / G_ICD).abs() < 1e-7);
    }

    /// The quaternion form of `P C P` is the matrix form.
    #[test]
    fn the_axes_swap_on_the_quaternion_is_the_matrix_one() {
        for e in [
            [0.3, -0.2, 2.0],
            [-1.2, 0.7, -2.9],
            [0.0, 0.0, 0.0],
            [3.0, 1.5, 0.1],
        ] {
            let q = quat_from_euler(e[0], e[1], e[2]);
            let c = dcm_from_quat(&q);
            let p = |i: usize| [1, 0, 2][i];
            let sgn = |i: usize| if i == 2 { -1.0 } else { 1.0 };
            let n: [V3; 3] =
                core::array::from_fn(|i| core::array::from_fn(|j| sgn(i) * sgn(j) * c[p(i)][p(j)]));
            let want = quat_from_dcm(&n);
            let got = housing_enu_to_body_ned(&q);
            for k in 0..4 {
                assert!((want[k] - got[k]).abs() < 1e-12, "{e:?}: {want:?} {got:?}");
            }
        }
    }

    /// The built-in motions' attitude maps to the same heading, pitch and
    /// roll in NED (heading 90°: the body's x points east).
    #[test]
    fn builtin_attitude_maps_to_ned() {
        let q = quat_from_euler_c(90f32.to_radians(), 0.0, 0.0).map(f64::from);
        let n = housing_enu_to_body_ned(&q);
        assert!(close(&rotate(&n, &[1.0, 0.0, 0.0]), &[0.0, 1.0, 0.0], 1e-7));
        assert!(close(&rotate(&n, &[0.0, 0.0, 1.0]), &[0.0, 0.0, 1.0], 1e-7));
        // Pitch up 10° (Appendix C pitch: the Y axis up) is pitch up in NED.
        let q = quat_from_euler_c(0.0, 10f32.to_radians(), 0.0).map(f64::from);
        let e = euler_from_quat(&housing_enu_to_body_ned(&q));
        assert!((e[1] - 10f64.to_radians()).abs() < 1e-6, "{e:?}");
    }

    /// The static built-in motion's truth is its state's measurement: the
    /// 1 g of the ICD is normal gravity at the site's height, and the Earth
    /// rate agrees to the f32 constant's precision.
    #[test]
    fn the_default_site_height_is_the_solved_one() {
        let lat = f64::from(crate::sensor::motion::DEFAULT_LATITUDE_DEG).to_radians();
        let h = wgs84::height_of_gravity(lat, G_ICD);
        assert_eq!(h.to_bits(), DEFAULT_SITE_HEIGHT_M.to_bits());
        assert_eq!(Site::of(&Motion::default()).height_m.to_bits(), h.to_bits());
    }

    #[test]
    fn builtin_static_is_self_consistent() {
        let m = Motion::Static {
            lat_deg: 45.0,
            heading_deg: 30.0,
        };
        let src = crate::sensor::motion::BuiltinMotion::new(m, 0.0005);
        let truth = src.truth_now();
        let s = builtin_state(
            &Site::of(&m),
            crate::sensor::MotionSource::attitude(&src),
            &truth,
            0.0,
        );
        let mut again = s;
        again.measure(&Motion6 {
            acc_ned: [0.0; 3],
            rate_nb_b: [0.0; 3],
        });
        assert!(close(&s.force_b, &again.force_b, 2e-6), "{s:?} {again:?}");
        assert!(
            close(&s.rate_ib_b, &again.rate_ib_b, 1e-9),
            "{s:?} {again:?}"
        );
        assert!((s.euler_rad()[2] - 30f64.to_radians()).abs() < 1e-6);
    }
}
