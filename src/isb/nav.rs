//! The navigation truth the IMX-5's INS and GNSS outputs start from, and
//! the frames, quaternions and GPS time they are written in (Inertial
//! Sense SDK 2.7.1 conventions: `docs/protocol-facts.md` "ISB navigation
//! (SDK 2.7.1)").
//!
//! [`truth_of`] is the one place the truth is read: the unit's vehicle
//! ([`crate::vehicle`]), whatever its source.

use libm::{cos, sincos, sqrt};

use crate::chain::SignalChain;
use crate::dsp::integrals::Integrate;
use crate::math::double::quat_from_euler;

/// Longitude of the built-in site (Newlyn), degrees east: the vehicle's
/// ([`crate::vehicle::DEFAULT_LONGITUDE_DEG`], docs/motion.md "The
/// built-in site").
pub const DEFAULT_LON_DEG: f64 = crate::vehicle::DEFAULT_LONGITUDE_DEG;
/// Height of the built-in site above the WGS84 ellipsoid, m: where WGS84
/// normal gravity is the ICD's g at its latitude (the vehicle computes it,
/// [`crate::vehicle::wgs84::height_of_gravity`]; a unit test pins this
/// copy to it), 8.9 m above EGM96 mean sea level.
pub const DEFAULT_HEIGHT_M: f64 = 62.494_064;

/// WGS84 semi-major axis, m.
pub(crate) const WGS84_A: f64 = 6_378_137.0;
/// WGS84 first eccentricity squared.
pub(crate) const WGS84_E2: f64 = 0.006_694_379_990_141;
/// The SDK's flat-earth radius for INS_1.ned (111 120 m per degree).
pub(crate) const NED_RADIUS_M: f64 = 6_366_707.019_5;
/// Seconds in a GPS week.
pub(crate) const WEEK_S: u64 = 604_800;
pub(crate) use crate::time::{GPS_EPOCH_UNIX_S, LEAP_SECONDS};
/// GPS time at device instant 0 when a board sets none: 2026-01-01
/// 00:00:00 UTC (Unix 1 767 225 600) as GPS seconds (+18 leap seconds).
pub(crate) const DEFAULT_GPS_S_AT_ZERO: u64 = 1_767_225_600 - GPS_EPOCH_UNIX_S + LEAP_SECONDS as u64;

/// What the navigation outputs are built from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavTruth {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Height above the WGS84 ellipsoid, m.
    pub h_m: f64,
    /// Velocity, north, east, down, m/s.
    pub v_ned: [f64; 3],
    /// Attitude: rotating a body (forward, right, down) vector by it gives
    /// NED (W, X, Y, Z; Hamilton).
    pub q_nb: [f64; 4],
}

/// The navigation truth of `chain` now: the unit's vehicle
/// ([`SignalChain::vehicle`]: a board's vehicle source — manoeuvre script,
/// full-state rows, live feed — or the built-in motion's state at the
/// built-in site, the one both personalities share: docs/motion.md "The
/// built-in site"). Its body frame (forward, right, down) is the IMX's.
pub fn truth_of<I: Integrate>(chain: &SignalChain<I>) -> NavTruth {
    let v = match chain.vehicle_source() {
        Some(v) => *v,
        None => chain.vehicle(),
    };
    NavTruth {
        lat_deg: v.lat_rad.to_degrees(),
        lon_deg: v.lon_rad.to_degrees(),
        h_m: v.height_m,
        v_ned: v.vel_ned,
        q_nb: v.q_nb,
    }
}

/// qe2n: the NED frame's attitude in ECEF (roll 0, pitch −(lat + 90°), yaw
/// lon).
pub fn quat_e2n(lat_deg: f64, lon_deg: f64) -> [f64; 4] {
    quat_from_euler(0.0, -(lat_deg + 90.0).to_radians(), lon_deg.to_radians())
}

/// WGS84 latitude (deg), longitude (deg), height (m) → ECEF (m).
pub fn ecef_of(lla: &[f64; 3]) -> [f64; 3] {
    // One argument reduction for a sine and its cosine (soft double
    // precision on the M4F).
    let ((sl, cl), (so, co)) = (sincos(lla[0].to_radians()), sincos(lla[1].to_radians()));
    let n = WGS84_A / sqrt(1.0 - WGS84_E2 * sl * sl);
    [
        (n + lla[2]) * cl * co,
        (n + lla[2]) * cl * so,
        (n * (1.0 - WGS84_E2) + lla[2]) * sl,
    ]
}

/// A small NED displacement (m) added to a position (deg, deg, m), with
/// the WGS84 radii of curvature.
pub(crate) fn lla_plus_ned(lla: &[f64; 3], d: &[f64; 3]) -> [f64; 3] {
    let (sl, cl) = sincos(lla[0].to_radians());
    let s2 = sl * sl;
    let rn = WGS84_A / sqrt(1.0 - WGS84_E2 * s2);
    let rm = rn * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * s2);
    [
        lla[0] + (d[0] / (rm + lla[2])).to_degrees(),
        lla[1] + (d[1] / ((rn + lla[2]) * cl)).to_degrees(),
        lla[2] - d[2],
    ]
}

/// INS_1.ned: the SDK's flat-earth offset of `lla` from `ref_lla`.
pub fn ned_from_ref(lla: &[f64; 3], ref_lla: &[f64; 3]) -> [f64; 3] {
    [
        (lla[0] - ref_lla[0]).to_radians() * NED_RADIUS_M,
        (lla[1] - ref_lla[1]).to_radians() * NED_RADIUS_M * cos(ref_lla[0].to_radians()),
        -(lla[2] - ref_lla[2]),
    ]
}

/// GPS time as week and time of week, from GPS nanoseconds since the GPS
/// epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpsTime {
    /// Whole weeks since 1980-01-06.
    pub week: u32,
    /// Nanoseconds since the start of the week.
    pub tow_ns: u64,
}

impl GpsTime {
    /// Of `ns` GPS nanoseconds since the epoch.
    pub const fn of_ns(ns: u64) -> Self {
        let week_ns = WEEK_S * 1_000_000_000;
        GpsTime {
            week: (ns / week_ns) as u32,
            tow_ns: ns % week_ns,
        }
    }
    /// Time of week, s.
    pub(crate) fn tow_s(&self) -> f64 {
        self.tow_ns as f64 / 1e9
    }
    /// Time of week, ms (truncated: the epoch of the ms it falls in).
    pub(crate) const fn tow_ms(&self) -> u32 {
        (self.tow_ns / 1_000_000) as u32
    }
    /// The UTC date as a decimal year (GPS − [`LEAP_SECONDS`]): what the
    /// magnetic field model is read at.
    pub fn decimal_year(&self) -> f64 {
        let gps_s = u64::from(self.week) * WEEK_S + self.tow_ns / 1_000_000_000;
        let unix_s = gps_s + GPS_EPOCH_UNIX_S - u64::from(LEAP_SECONDS);
        crate::earth::decimal_year_of_unix_s(unix_s as i64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::double::{dcm_from_quat, euler_from_quat, quat_from_dcm, rotate};

    /// The site constants are the vehicle's built-in site.
    #[test]
    fn the_built_in_site_is_the_vehicles() {
        use crate::sensor::motion::DEFAULT_LATITUDE_DEG;
        use crate::vehicle::{wgs84::height_of_gravity, G_ICD};
        let lat = f64::from(DEFAULT_LATITUDE_DEG).to_radians();
        assert!((height_of_gravity(lat, G_ICD) - DEFAULT_HEIGHT_M).abs() < 1e-6);
        assert_eq!(DEFAULT_LON_DEG, -5.541_667);
    }

    #[test]
    fn the_sdk_frame_rules() {
        // Level, yaw 30°: body X → NED (0.866, 0.5, 0).
        let q = quat_from_euler(0.0, 0.0, 30f64.to_radians());
        let v = rotate(&q, &[1.0, 0.0, 0.0]);
        assert!((v[0] - 0.866_025).abs() < 1e-6 && (v[1] - 0.5).abs() < 1e-9);
        let e = [0.1, -0.2, 2.5];
        let back = euler_from_quat(&quat_from_euler(e[0], e[1], e[2]));
        for k in 0..3 {
            assert!((back[k] - e[k]).abs() < 1e-12, "{back:?}");
        }
        assert!((quat_from_dcm(&dcm_from_quat(&q))[3] - q[3]).abs() < 1e-12);
        // ECEF of 0°, 0°, 0 m and of the pole.
        assert_eq!(ecef_of(&[0.0, 0.0, 0.0]), [WGS84_A, 0.0, 0.0]);
        assert!((ecef_of(&[90.0, 0.0, 0.0])[2] - 6_356_752.314).abs() < 1e-3);
        // qe2n maps NED down to −(ECEF position direction) at 0°, 0°.
        let down = rotate(&quat_e2n(0.0, 0.0), &[0.0, 0.0, 1.0]);
        assert!((down[0] + 1.0).abs() < 1e-12, "{down:?}");
        // Flat-earth NED: 111 120 m a degree.
        let n = ned_from_ref(&[46.0, 0.0, 10.0], &[45.0, 0.0, 0.0]);
        assert!((n[0] - 111_120.0).abs() < 0.01 && n[2] == -10.0);
        // GPS time: 2026-01-01 00:00:00 UTC is week 2399.
        let t = GpsTime::of_ns(DEFAULT_GPS_S_AT_ZERO * 1_000_000_000);
        assert_eq!(t.week, 2399);
        assert_eq!(t.tow_ms(), (4 * 86_400 + 18) * 1000);
    }
}
