//! The Earth's fields at a place: the geoid undulation (ellipsoid height −
//! MSL height) and the main magnetic field. Physics, not protocol: any
//! personality that reports an MSL height or a magnetometer reads them here.
//!
//! - the geoid: EGM96 on a stored 2° grid, bilinear ([`geoid`],
//!   [`egm96`]);
//! - the field: the World Magnetic Model 2025 ([`wmm`], [`wmm2025`]).
//!
//! Sources, resolution, errors and validity: docs/earth.md.

pub(crate) mod egm96;
pub(crate) mod geoid;
pub(crate) mod wmm;
pub(crate) mod wmm2025;

use core::cell::Cell;

use libm::{atan2, floor, round, sqrt};

/// Geoid undulation N (m) at `lat_deg`, `lon_deg`: MSL height = ellipsoid
/// height − N. EGM96 ([`geoid::undulation_m`]).
pub fn geoid_undulation_m(lat_deg: f64, lon_deg: f64) -> f64 {
    geoid::undulation_m(lat_deg, lon_deg)
}

/// The main field at a place and date, north, east, down, in nT (WMM2025,
/// [`wmm::field_ned_nt`]). `h_m` is the height above the WGS84 ellipsoid;
/// `year` a decimal year (2026.5 is mid-2026), clamped to 2025.0–2030.0.
pub fn magnetic_field_ned_nt(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> [f64; 3] {
    wmm::field_ned_nt(lat_deg, lon_deg, h_m, year)
}

/// Magnetic declination (degrees east of true north) at a place and date.
pub fn declination_deg(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> f64 {
    let f = magnetic_field_ned_nt(lat_deg, lon_deg, h_m, year);
    atan2(f[1], f[0]).to_degrees()
}

/// Magnetic inclination (degrees, positive down) at a place and date.
pub fn inclination_deg(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> f64 {
    let f = magnetic_field_ned_nt(lat_deg, lon_deg, h_m, year);
    atan2(f[2], sqrt(f[0] * f[0] + f[1] * f[1])).to_degrees()
}

/// The field's grid in latitude and longitude, steps a degree (0.001°:
/// 111 m, where the main field changes by under 2 nT). Steps per unit, so
/// the key is a multiplication (a division costs several times as much in
/// soft double precision).
const MEMO_PER_DEG: f64 = 1e3;
/// The field's grid in height, steps a metre (10 m: under 0.3 nT).
const MEMO_PER_M: f64 = 0.1;
/// The field's grid in time, steps a year (0.001 year: 9 h, under 0.2 nT
/// of secular variation).
const MEMO_PER_YEAR: f64 = 1e3;

/// The main field evaluated on a fine grid of place and date and
/// remembered: one synthesis costs about a thousand floating-point
/// operations (docs/performance.md), and a unit reads the field at every
/// magnetometer output while it moves metres. The value is that of the
/// grid point nearest the place and date — a function of them alone, so
/// the same truth gives the same bytes whatever else was asked for — and
/// the grid (0.001°, 10 m, 0.001 year) is finer than anything the model
/// resolves (docs/earth.md).
#[derive(Debug, Clone, Default)]
pub struct FieldMemo {
    last: Cell<Option<([i64; 4], [f64; 3])>>,
}

impl FieldMemo {
    /// A memo with nothing remembered.
    pub const fn new() -> Self {
        FieldMemo {
            last: Cell::new(None),
        }
    }

    /// [`magnetic_field_ned_nt`] at the grid point nearest the place and
    /// date, north, east, down, nT.
    pub fn field_ned_nt(&self, lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> [f64; 3] {
        // Non-finite values key as 0 or the largest integer; the synthesis
        // sanitises and clamps what they give back.
        let q = |v: f64, per: f64| round(v * per) as i64;
        let key = [
            q(lat_deg, MEMO_PER_DEG),
            q(lon_deg, MEMO_PER_DEG),
            q(h_m, MEMO_PER_M),
            q(year, MEMO_PER_YEAR),
        ];
        if let Some((k, f)) = self.last.get() {
            if k == key {
                return f;
            }
        }
        let at = |k: i64, per: f64| k as f64 / per;
        let f = magnetic_field_ned_nt(
            at(key[0], MEMO_PER_DEG),
            at(key[1], MEMO_PER_DEG),
            at(key[2], MEMO_PER_M),
            at(key[3], MEMO_PER_YEAR),
        );
        self.last.set(Some((key, f)));
        f
    }
}

/// Seconds in a day.
const DAY_S: i64 = 86_400;

/// The decimal year of a UTC Unix time (s): the year plus the fraction of
/// it elapsed (2026-07-02 12:00 is 2026.5), as the WMM counts dates.
pub fn decimal_year_of_unix_s(unix_s: i64) -> f64 {
    let days = unix_s.div_euclid(DAY_S);
    let secs = unix_s.rem_euclid(DAY_S);
    let year = year_of_days(days);
    let start = days_of_jan1(year);
    let len = days_of_jan1(year + 1) - start;
    year as f64 + ((days - start) * DAY_S + secs) as f64 / (len * DAY_S) as f64
}

/// Days from 1970-01-01 to 1 January of `year` (proleptic Gregorian).
fn days_of_jan1(year: i64) -> i64 {
    let y = year - 1;
    365 * (year - 1970) + (y.div_euclid(4) - y.div_euclid(100) + y.div_euclid(400))
        - (1969 / 4 - 1969 / 100 + 1969 / 400)
}

/// The year that day `days` (since 1970-01-01) falls in.
fn year_of_days(days: i64) -> i64 {
    // An estimate within a year of the truth, then corrected.
    let mut y = 1970 + floor(days as f64 / 365.2425) as i64;
    while days_of_jan1(y) > days {
        y -= 1;
    }
    while days_of_jan1(y + 1) <= days {
        y += 1;
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_years() {
        // 2025-01-01, 2026-01-01, 2026-07-02 12:00 (mid 2026), 2028-07-02 00:00 (mid leap year)
        assert_eq!(decimal_year_of_unix_s(1_735_689_600), 2025.0);
        assert_eq!(decimal_year_of_unix_s(1_767_225_600), 2026.0);
        assert_eq!(
            decimal_year_of_unix_s(1_767_225_600 + 182 * 86_400 + 43_200),
            2026.5
        );
        assert_eq!(decimal_year_of_unix_s(1_830_297_600 + 183 * 86_400), 2028.5);
        assert_eq!(decimal_year_of_unix_s(0), 1970.0);
        assert!(decimal_year_of_unix_s(-1) < 1970.0);
        assert!(decimal_year_of_unix_s(i64::MAX).is_finite());
        assert!(decimal_year_of_unix_s(i64::MIN).is_finite());
    }
}
