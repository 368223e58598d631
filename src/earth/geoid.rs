//! The geoid undulation from the stored EGM96 grid ([`super::egm96`]):
//! bilinear interpolation between the four grid points around a place.
//! Resolution and error: docs/earth.md "Geoid".

use libm::{floor, fmod};

use super::egm96::{COLS, ROWS, STEP_DEG, UNDULATION_M};

/// EGM96 undulation N (m) at `lat_deg`, `lon_deg`, bilinear in the 2° grid.
/// Latitude is clamped to ±90°, longitude wraps; a non-finite coordinate
/// gives 0 (the ellipsoid), never NaN.
pub(crate) fn undulation_m(lat_deg: f64, lon_deg: f64) -> f64 {
    if !lat_deg.is_finite() || !lon_deg.is_finite() {
        return 0.0;
    }
    let y = (lat_deg.clamp(-90.0, 90.0) + 90.0) / STEP_DEG;
    // fmod keeps the sign of the dividend: shift a negative remainder up.
    let mut x = fmod(lon_deg + 180.0, 360.0);
    if x < 0.0 {
        x += 360.0;
    }
    let x = x / STEP_DEG;
    // Indices clamped: the last row pairs with itself at the north pole.
    let i = (floor(y) as usize).min(ROWS - 2);
    let j = (floor(x) as usize).min(COLS - 1);
    let (fy, fx) = (y - i as f64, x - j as f64);
    let j1 = (j + 1) % COLS;
    let at = |r: usize, c: usize| f64::from(UNDULATION_M[r][c]);
    let south = at(i, j) * (1.0 - fx) + at(i, j1) * fx;
    let north = at(i + 1, j) * (1.0 - fx) + at(i + 1, j1) * fx;
    south * (1.0 - fy) + north * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid nodes read back exactly, across the date line too.
    #[test]
    fn nodes_read_back_and_longitude_wraps() {
        let n = f64::from(UNDULATION_M[45][0]);
        assert_eq!(undulation_m(0.0, -180.0), n);
        assert_eq!(undulation_m(0.0, 180.0), n);
        assert_eq!(undulation_m(0.0, 540.0), n);
        assert_eq!(undulation_m(90.0, 10.0), f64::from(UNDULATION_M[90][95]));
        assert_eq!(undulation_m(-90.0, 0.0), f64::from(UNDULATION_M[0][90]));
    }

    /// Absurd input never indexes out of the grid nor gives NaN.
    #[test]
    fn absurd_input_is_finite() {
        for (la, lo) in [
            (f64::NAN, 0.0),
            (0.0, f64::INFINITY),
            (1e300, -1e300),
            (-91.0, 359.999_999_999),
            (90.0, -0.0),
            (f64::MAX, f64::MIN),
        ] {
            let n = undulation_m(la, lo);
            assert!(n.is_finite() && n.abs() < 110.0, "{la} {lo}: {n}");
        }
        assert_eq!(undulation_m(f64::NAN, 0.0), 0.0);
    }
}
