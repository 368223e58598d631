//! The World Magnetic Model's main field at a place and date: spherical
//! harmonic synthesis to degree 12 of the WMM2025 coefficients
//! ([`super::wmm2025`]), following the WMM2025 technical report §1.2
//! (NOAA NCEI / BGS): geodetic → geocentric spherical coordinates
//! (eq. 7–8), the coefficients at the date (eq. 9), the field in
//! geocentric axes from Schmidt semi-normalised associated Legendre
//! functions (eq. 10–12), rotated back to the geodetic NED frame (eq. 17).
//!
//! Written here rather than taken from a crate: the one `no_std` WMM2025
//! crate found (`world_magnetic_model` 0.2) computes in `f32` behind `uom`
//! and `time` types, with a date to the day; docs/earth.md says more.

use libm::{asin, cos, sin, sqrt};

use super::wmm2025::{Coef, COEFS, EPOCH, N_MAX, RADIUS_M, VALID_UNTIL};

/// WGS84 semi-major axis, m.
const A: f64 = 6_378_137.0;
/// WGS84 first eccentricity squared (f = 1/298.257223563).
const E2: f64 = 0.006_694_379_990_141_3;
/// Lowest and highest height the synthesis takes, m: the model is
/// specified from 1 km below the ellipsoid to 850 km above; beyond, the
/// height is clamped (a far height only weakens the field).
const H_MIN_M: f64 = -10_000.0;
const H_MAX_M: f64 = 1_000_000.0;
/// Latitudes closer to a pole than this are moved to it, degrees: the
/// east component's 1/cos φ' has no limit at the pole itself (the report's
/// special case), and 10⁻⁷° is 1 cm.
const POLE_GUARD_DEG: f64 = 1e-7;

/// The main field north, east, down (nT) at geodetic `lat_deg`,
/// `lon_deg`, height `h_m` above the WGS84 ellipsoid, at decimal year
/// `year`. The date is clamped to the model's validity (2025.0–2030.0:
/// the secular variation is linear and meant for those five years only);
/// a non-finite input reads as latitude 0, longitude 0, height 0 or the
/// epoch, so the result is always finite.
pub fn field_ned_nt(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> [f64; 3] {
    let finite_or = |v: f64, d: f64| if v.is_finite() { v } else { d };
    let lat_deg = finite_or(lat_deg, 0.0).clamp(-90.0 + POLE_GUARD_DEG, 90.0 - POLE_GUARD_DEG);
    let lon = finite_or(lon_deg, 0.0).to_radians();
    let h = finite_or(h_m, 0.0).clamp(H_MIN_M, H_MAX_M);
    let dt = finite_or(year, EPOCH).clamp(EPOCH, VALID_UNTIL) - EPOCH;

    // Geodetic → geocentric spherical (eq. 7–8).
    let lat = lat_deg.to_radians();
    let (s, c) = (sin(lat), cos(lat));
    let rc = A / sqrt(1.0 - E2 * s * s);
    let p = (rc + h) * c;
    let z = (rc * (1.0 - E2) + h) * s;
    let r = sqrt(p * p + z * z);
    let lat_c = asin(z / r);
    let (sc, cc) = (sin(lat_c), cos(lat_c));

    // Schmidt semi-normalised P_n^m(sin φ') and dP/dφ', by the recursion
    // in the colatitude θ (cos θ = sin φ'), then the Schmidt factors.
    let mut pn = [[0.0f64; N_MAX + 1]; N_MAX + 1];
    let mut dp = [[0.0f64; N_MAX + 1]; N_MAX + 1];
    pn[0][0] = 1.0;
    for n in 1..=N_MAX {
        for m in 0..=n {
            if n == m {
                pn[n][m] = cc * pn[n - 1][m - 1];
                dp[n][m] = cc * dp[n - 1][m - 1] + sc * pn[n - 1][m - 1];
            } else {
                let k = if n > 1 {
                    ((n - 1) * (n - 1) - m * m) as f64 / ((2 * n - 1) * (2 * n - 3)) as f64
                } else {
                    0.0
                };
                let (p2, d2) = if n > 1 {
                    (pn[n - 2][m], dp[n - 2][m])
                } else {
                    (0.0, 0.0)
                };
                pn[n][m] = sc * pn[n - 1][m] - k * p2;
                dp[n][m] = sc * dp[n - 1][m] - cc * pn[n - 1][m] - k * d2;
            }
        }
    }
    let mut schmidt = [[0.0f64; N_MAX + 1]; N_MAX + 1];
    schmidt[0][0] = 1.0;
    for n in 1..=N_MAX {
        schmidt[n][0] = schmidt[n - 1][0] * (2 * n - 1) as f64 / n as f64;
        for m in 1..=n {
            let j = if m == 1 { 2.0 } else { 1.0 };
            schmidt[n][m] = schmidt[n][m - 1] * sqrt((n - m + 1) as f64 * j / (n + m) as f64);
        }
    }

    // cos mλ, sin mλ by the angle-sum recursion.
    let mut cm = [0.0f64; N_MAX + 1];
    let mut sm = [0.0f64; N_MAX + 1];
    cm[0] = 1.0;
    let (sl, cl) = (sin(lon), cos(lon));
    for m in 1..=N_MAX {
        cm[m] = cm[m - 1] * cl - sm[m - 1] * sl;
        sm[m] = sm[m - 1] * cl + cm[m - 1] * sl;
    }

    // Field in geocentric axes (eq. 10–12); dp is d/dθ = −d/dφ'.
    let ratio = RADIUS_M / r;
    let (mut bt, mut bp, mut br) = (0.0, 0.0, 0.0);
    let mut ar = ratio * ratio;
    let mut last_n = 0u8;
    for &Coef {
        n,
        m,
        g,
        h: hc,
        g_dot,
        h_dot,
    } in COEFS.iter()
    {
        if n != last_n {
            ar *= ratio;
            last_n = n;
        }
        let (nu, mu) = (usize::from(n), usize::from(m));
        let (g, hc) = (g + g_dot * dt, hc + h_dot * dt);
        let k = schmidt[nu][mu];
        let (p, d) = (k * pn[nu][mu], k * dp[nu][mu]);
        let t1 = g * cm[mu] + hc * sm[mu];
        let t2 = g * sm[mu] - hc * cm[mu];
        bt -= ar * t1 * d;
        bp += ar * f64::from(m) * t2 * p;
        br += ar * f64::from(n + 1) * t1 * p;
    }
    // X' north, Y' east, Z' down in the geocentric frame.
    let (xp, yp, zp) = (-bt, bp / cc, -br);

    // Back to geodetic NED (eq. 17).
    let psi = lat_c - lat;
    let (sp, cp) = (sin(psi), cos(psi));
    [xp * cp - zp * sp, yp, xp * sp + zp * cp]
}
