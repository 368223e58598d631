//! The WGS84 Earth model the vehicle truth is computed in: the defining
//! and derived constants, normal gravity, the radii of curvature and the
//! Earth and transport rates in the local NED frame.
//!
//! Source of every constant: NIMA TR8350.2, "Department of Defense World
//! Geodetic System 1984", third edition, amendment 1 (3 January 2000):
//! Table 3.1 (defining parameters a, 1/f, ω, GM), Table 3.3 (derived
//! geometric constants: e²), Table 3.4 (derived physical constants: γe,
//! γp, k, m), and equations (4-1) (Somigliana's closed formula for normal
//! gravity on the ellipsoid) and (4-3) (its Taylor series in height above
//! the ellipsoid). The table is copied into `docs/motion.md`.
//!
//! All in `f64`: a latitude in `f32` resolves 0.5 m at best and a height in
//! `f32` 1 m at 10 km, too coarse for a navigation truth (docs/motion.md,
//! "Precision").

// The constants as TR8350.2 prints them.
#![allow(clippy::excessive_precision)]

use libm::{cos, sin, sqrt};

/// Semi-major axis a, m (TR8350.2 Table 3.1).
pub(crate) const A: f64 = 6_378_137.0;
/// Reciprocal of the flattening 1/f (TR8350.2 Table 3.1).
pub(crate) const INV_F: f64 = 298.257_223_563;
/// Flattening f.
pub(crate) const F: f64 = 1.0 / INV_F;
/// Angular velocity of the Earth ω, rad/s (TR8350.2 Table 3.1).
pub(crate) const OMEGA_IE: f64 = 7.292_115e-5;
/// Earth's gravitational constant GM (atmosphere included), m³/s²
/// (TR8350.2 Table 3.1).
pub const GM: f64 = 3.986_004_418e14;
/// First eccentricity squared e² (TR8350.2 Table 3.3).
pub(crate) const E2: f64 = 6.694_379_990_14e-3;
/// Normal gravity at the equator γe, m/s² (TR8350.2 Table 3.4).
pub(crate) const GAMMA_E: f64 = 9.780_325_335_9;
/// Normal gravity at the poles γp, m/s² (TR8350.2 Table 3.4).
pub const GAMMA_P: f64 = 9.832_184_937_8;
/// Normal gravity formula constant k = (b γp − a γe) / (a γe) (TR8350.2
/// Table 3.4).
pub(crate) const K: f64 = 0.001_931_852_652_41;
/// m = ω² a² b / GM (TR8350.2 Table 3.4).
pub(crate) const M: f64 = 0.003_449_786_506_84;

/// Normal gravity γ at geodetic latitude `lat` (rad) and height `h` (m)
/// above the ellipsoid, m/s²: Somigliana's formula on the ellipsoid
/// (TR8350.2 eq. 4-1) and the second-order series in height (eq. 4-3):
/// `γh = γ [1 − 2/a (1 + f + m − 2 f sin²φ) h + 3 h²/a²]`.
///
/// The magnitude of the normal gravity vector, taken along the ellipsoidal
/// normal (the NED down axis); the small deflection of the normal gravity
/// vector above the ellipsoid (< 1e-6 rad below 10 km) is neglected.
pub(crate) fn normal_gravity(lat: f64, h: f64) -> f64 {
    let s2 = sin(lat) * sin(lat);
    let g0 = GAMMA_E * (1.0 + K * s2) / sqrt(1.0 - E2 * s2);
    g0 * (1.0 - 2.0 / A * (1.0 + F + M - 2.0 * F * s2) * h + 3.0 * h * h / (A * A))
}

/// The radii of curvature at latitude `lat` (rad): meridian M and prime
/// vertical N, m.
pub fn radii(lat: f64) -> (f64, f64) {
    let s2 = sin(lat) * sin(lat);
    let w = sqrt(1.0 - E2 * s2);
    (A * (1.0 - E2) / (w * w * w), A / w)
}

/// d(radii)/d(lat) at `lat`: (dM/dφ, dN/dφ), m/rad — what the derivative of
/// the NED velocity of a position given in latitude, longitude and height
/// needs (the full-state interpolation).
pub(crate) fn radii_slope(lat: f64) -> (f64, f64) {
    let (s, c) = (sin(lat), cos(lat));
    let w2 = 1.0 - E2 * s * s;
    let w = sqrt(w2);
    let dm = 3.0 * A * (1.0 - E2) * E2 * s * c / (w2 * w2 * w);
    let dn = A * E2 * s * c / (w2 * w);
    (dm, dn)
}

/// The Earth's rate in the NED frame at latitude `lat`, rad/s:
/// `ω (cos φ, 0, −sin φ)`.
pub(crate) fn earth_rate_ned(lat: f64) -> [f64; 3] {
    [OMEGA_IE * cos(lat), 0.0, -OMEGA_IE * sin(lat)]
}

/// The transport rate (rotation of the NED frame over the ellipsoid) at
/// latitude `lat`, height `h` and NED velocity `v`, rad/s:
/// `(vE/(N+h), −vN/(M+h), −vE tan φ/(N+h))`.
pub(crate) fn transport_rate_ned(lat: f64, h: f64, v: &[f64; 3]) -> [f64; 3] {
    let (m, n) = radii(lat);
    let (s, c) = (sin(lat), cos(lat));
    [v[1] / (n + h), -v[0] / (m + h), -v[1] * s / (c * (n + h))]
}

/// The height above the ellipsoid at latitude `lat` where normal gravity
/// equals `g` (m/s²), m: the site of the built-in motions, whose specific
/// force at rest is exactly the ICD's 1 g (docs/motion.md, "The built-in
/// motions").
pub(crate) fn height_of_gravity(lat: f64, g: f64) -> f64 {
    // Newton on γ(h) − g; γ is nearly linear in h (three steps reach the
    // f64 resolution).
    let mut h = 0.0;
    for _ in 0..4 {
        let d = 1.0;
        let y = normal_gravity(lat, h) - g;
        let slope = (normal_gravity(lat, h + d) - normal_gravity(lat, h - d)) / (2.0 * d);
        h -= y / slope;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// TR8350.2 Table 3.4 / section 4: γ at the equator and the poles, and
    /// the derived constants agree with the defining ones.
    #[test]
    fn normal_gravity_matches_the_tabulated_values() {
        assert!((normal_gravity(0.0, 0.0) - GAMMA_E).abs() < 1e-12);
        let pole = core::f64::consts::FRAC_PI_2;
        assert!((normal_gravity(pole, 0.0) - GAMMA_P).abs() < 1e-9);
        // e² = f (2 − f) (TR8350.2 Table 3.3).
        assert!((E2 - F * (2.0 - F)).abs() < 1e-14);
        // Free-air gradient near −3.086e-6 s⁻² at mid latitudes.
        let lat = 45f64.to_radians();
        let grad = normal_gravity(lat, 1000.0) - normal_gravity(lat, 0.0);
        assert!((grad / 1000.0 + 3.086e-6).abs() < 2e-9, "{grad}");
    }

    #[test]
    fn the_built_in_site_height_gives_the_icd_g() {
        let lat = 45f64.to_radians();
        let h = height_of_gravity(lat, 9.8106);
        assert!((normal_gravity(lat, h) - 9.8106).abs() < 1e-12);
        assert!((-1500.0..-1400.0).contains(&h), "{h}");
    }

    #[test]
    fn radii_slopes_are_the_derivatives() {
        for deg in [-70.0f64, -10.0, 0.0, 33.0, 80.0] {
            let lat = deg.to_radians();
            let d = 1e-6;
            let (m1, n1) = radii(lat + d);
            let (m0, n0) = radii(lat - d);
            let (dm, dn) = radii_slope(lat);
            assert!((dm - (m1 - m0) / (2.0 * d)).abs() < 1e-3, "{deg}");
            assert!((dn - (n1 - n0) / (2.0 * d)).abs() < 1e-3, "{deg}");
        }
    }
}
