//! The Earth's fields at a place: the geoid undulation (ellipsoid height −
//! MSL height) and the main magnetic field. Physics, not protocol: any
//! personality that reports an MSL height or a magnetometer reads them here.
//!
//! Placeholder models until the published ones are embedded: the geoid is
//! the ellipsoid (undulation 0) and the field a centred axial dipole of
//! unit direction (declination 0).

use libm::{atan2, cos, sin, sqrt};

/// Geoid undulation N (m) at `lat_deg`, `lon_deg`: MSL height = ellipsoid
/// height − N.
pub fn geoid_undulation_m(lat_deg: f64, lon_deg: f64) -> f64 {
    let _ = (lat_deg, lon_deg);
    0.0
}

/// The main magnetic field at a place and date, north, east, down, in nT.
/// `year` is a decimal year (2026.5 is mid-2026).
pub fn magnetic_field_ned_nt(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> [f64; 3] {
    let _ = (lon_deg, h_m, year);
    let lat = lat_deg.to_radians();
    let (h, z) = (cos(lat), 2.0 * sin(lat));
    let n = sqrt(h * h + z * z);
    // A centred axial dipole scaled to a typical 50 000 nT.
    [50_000.0 * h / n, 0.0, 50_000.0 * z / n]
}

/// Magnetic declination (degrees east of true north) at a place and date.
pub fn declination_deg(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> f64 {
    let f = magnetic_field_ned_nt(lat_deg, lon_deg, h_m, year);
    atan2(f[1], f[0]).to_degrees()
}
