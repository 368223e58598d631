//! The World Magnetic Model's main field at a place and date: spherical
//! harmonic synthesis to degree 12 of the WMM2025 coefficients
//! ([`super::wmm2025`]), following the WMM2025 technical report §1.2
//! (NOAA NCEI / BGS): geodetic → geocentric spherical coordinates
//! (eq. 7–8), the coefficients at the date (eq. 9), the field in
//! geocentric axes from Schmidt semi-normalised associated Legendre
//! functions (eq. 10–12), rotated back to the geodetic NED frame (eq. 17).
//!
//! Written here rather than taken from a crate: the one `no_std` WMM2025
//! crate found (`world_magnetic_model` 0.2) works behind `uom` quantities
//! and a `time::Date` (a day's resolution) and refuses heights outside
//! −1…850 km; docs/earth.md says more. In `f32` (docs/earth.md: in `f64`
//! a synthesis costs six ticks of the Cortex-M4F).

use libm::{cosf, sinf, sqrtf};

use super::wmm2025::{Coef, COEFS, EPOCH, N_MAX, RADIUS_M, VALID_UNTIL};

/// WGS84 semi-major axis, m.
const A: f32 = 6_378_137.0;
/// WGS84 first eccentricity squared (f = 1/298.257223563).
const E2: f32 = 0.006_694_38;
/// Lowest and highest height the synthesis takes, m: the model is
/// specified from 1 km below the ellipsoid to 850 km above; beyond, the
/// height is clamped (a far height only weakens the field).
const H_MIN_M: f64 = -10_000.0;
const H_MAX_M: f64 = 1_000_000.0;
/// The Schmidt semi-normalisation factors S(n, m) =
/// √((2 − δ₀ₘ)(n − m)!/(n + m)!) that turn the Gauss-normalised P_n^m of
/// the recursion into the model's, by their recursion S(n, 0) =
/// S(n−1, 0)(2n − 1)/n, S(n, m) = S(n, m−1)√((n − m + 1)(1 + δ₁ₘ)/(n + m)),
/// written out: 90 square roots a synthesis cost more than the rest on a
/// soft-float MCU (a unit test computes them again, bit for bit).
#[rustfmt::skip]
const SCHMIDT: [[f32; N_MAX + 1]; N_MAX + 1] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.5, 1.7320508, 0.8660254, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [2.5, 3.0618622, 1.9364917, 0.7905694, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [4.375, 5.533986, 3.913119, 2.09165, 0.73951, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [7.875, 10.166581, 7.685213, 4.7062125, 2.21853, 0.70156074, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [14.4375, 18.903124, 14.944232, 9.962822, 5.456862, 2.3268137, 0.67169327, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [26.8125, 35.469604, 28.96081, 20.478386, 12.348931, 6.1744657, 2.4218247, 0.64725983, 0.0, 0.0, 0.0, 0.0, 0.0],
    [50.273438, 67.03125, 56.082367, 41.419575, 26.73622, 14.830586, 6.865227, 2.5068266, 0.62670666, 0.0, 0.0, 0.0, 0.0],
    [94.96094, 127.403465, 108.65004, 82.98284, 56.37574, 33.69095, 17.39793, 7.533525, 2.5839777, 0.6090494, 0.0, 0.0, 0.0],
    [180.42578, 243.28607, 210.69193, 165.28033, 116.87085, 73.91562, 41.320084, 20.043186, 8.182596, 2.6547847, 0.5936279, 0.0, 0.0],
    [344.44922, 466.38644, 409.04797, 327.96802, 239.51396, 158.4236, 94.117645, 49.60435, 22.760038, 8.814925, 2.7203448, 0.5799795, 0.0],
    [660.19434, 897.02747, 795.1299, 649.2208, 486.91562, 334.02136, 208.2989, 117.05388, 58.52694, 25.543251, 9.43247, 2.781484, 0.56776804],
];

/// Latitudes closer to a pole than this are moved to it, degrees: the
/// east component's 1/cos φ' has no limit at the pole itself (the report's
/// special case), and 10⁻⁴° (11 m) keeps cos φ' well above `f32`'s
/// resolution of the latitude.
const POLE_GUARD_DEG: f64 = 1e-4;

/// The main field north, east, down (nT) at geodetic `lat_deg`,
/// `lon_deg`, height `h_m` above the WGS84 ellipsoid, at decimal year
/// `year`. The date is clamped to the model's validity (2025.0–2030.0:
/// the secular variation is linear and meant for those five years only);
/// a non-finite input reads as latitude 0, longitude 0, height 0 or the
/// epoch, so the result is always finite.
pub(crate) fn field_ned_nt(lat_deg: f64, lon_deg: f64, h_m: f64, year: f64) -> [f64; 3] {
    let finite_or = |v: f64, d: f64| if v.is_finite() { v } else { d };
    let lat_deg = finite_or(lat_deg, 0.0).clamp(-90.0 + POLE_GUARD_DEG, 90.0 - POLE_GUARD_DEG);
    let lon = finite_or(lon_deg, 0.0).to_radians() as f32;
    let h = finite_or(h_m, 0.0).clamp(H_MIN_M, H_MAX_M) as f32;
    let dt = (finite_or(year, EPOCH).clamp(EPOCH, VALID_UNTIL) - EPOCH) as f32;

    // Geodetic → geocentric spherical (eq. 7–8): radius r, and the sine
    // and cosine of the geocentric latitude φ' as z/r and p/r.
    let lat = lat_deg.to_radians() as f32;
    let (s, c) = (sinf(lat), cosf(lat));
    let rc = A / sqrtf(1.0 - E2 * s * s);
    let p = (rc + h) * c;
    let z = (rc * (1.0 - E2) + h) * s;
    let r = sqrtf(p * p + z * z);
    let (sc, cc) = (z / r, p / r);

    // Schmidt semi-normalised P_n^m(sin φ') and dP/dθ: the recursion in
    // the colatitude θ (cos θ = sin φ') for the Gauss-normalised
    // functions, then the Schmidt factors.
    let mut pn = [[0.0f32; N_MAX + 1]; N_MAX + 1];
    let mut dp = [[0.0f32; N_MAX + 1]; N_MAX + 1];
    pn[0][0] = 1.0;
    for n in 1..=N_MAX {
        for m in 0..=n {
            if n == m {
                pn[n][m] = cc * pn[n - 1][m - 1];
                dp[n][m] = cc * dp[n - 1][m - 1] + sc * pn[n - 1][m - 1];
            } else {
                let (k, p2, d2) = if n > 1 {
                    let k = ((n - 1) * (n - 1) - m * m) as f32 / ((2 * n - 1) * (2 * n - 3)) as f32;
                    (k, pn[n - 2][m], dp[n - 2][m])
                } else {
                    (0.0, 0.0, 0.0)
                };
                pn[n][m] = sc * pn[n - 1][m] - k * p2;
                dp[n][m] = sc * dp[n - 1][m] - cc * pn[n - 1][m] - k * d2;
            }
        }
    }
    // cos mλ, sin mλ by the angle-sum recursion.
    let mut cm = [0.0f32; N_MAX + 1];
    let mut sm = [0.0f32; N_MAX + 1];
    cm[0] = 1.0;
    let (sl, cl) = (sinf(lon), cosf(lon));
    for m in 1..=N_MAX {
        cm[m] = cm[m - 1] * cl - sm[m - 1] * sl;
        sm[m] = sm[m - 1] * cl + cm[m - 1] * sl;
    }

    // Field in geocentric axes (eq. 10–12); dp is d/dθ = −d/dφ'.
    let ratio = RADIUS_M / r;
    let (mut bt, mut bp, mut br) = (0.0f32, 0.0f32, 0.0f32);
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
        let k = SCHMIDT[nu][mu];
        let (p, d) = (k * pn[nu][mu], k * dp[nu][mu]);
        let t1 = g * cm[mu] + hc * sm[mu];
        let t2 = g * sm[mu] - hc * cm[mu];
        bt -= ar * t1 * d;
        bp += ar * f32::from(m) * t2 * p;
        br += ar * f32::from(n + 1) * t1 * p;
    }
    // X' north, Y' east, Z' down in the geocentric frame.
    let (xp, yp, zp) = (-bt, bp / cc, -br);

    // Back to geodetic NED (eq. 17), ψ = φ' − φ.
    let (sp, cp) = (sc * c - cc * s, cc * c + sc * s);
    [xp * cp - zp * sp, yp, xp * sp + zp * cp].map(f64::from)
}

#[cfg(test)]
mod tests {
    use super::*;

    use libm::sqrt;

    #[test]
    fn the_schmidt_factors_are_their_recursion() {
        let mut s = [[0.0f64; N_MAX + 1]; N_MAX + 1];
        s[0][0] = 1.0;
        for n in 1..=N_MAX {
            s[n][0] = s[n - 1][0] * (2 * n - 1) as f64 / n as f64;
            for m in 1..=n {
                let j = if m == 1 { 2.0 } else { 1.0 };
                s[n][m] = s[n][m - 1] * sqrt((n - m + 1) as f64 * j / (n + m) as f64);
            }
        }
        for n in 0..=N_MAX {
            for m in 0..=N_MAX {
                assert_eq!(
                    (s[n][m] as f32).to_bits(),
                    SCHMIDT[n][m].to_bits(),
                    "{n} {m}"
                );
            }
        }
    }
}
