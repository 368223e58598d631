//! `f32` trigonometry in `f32` arithmetic only, and the few `f64`
//! functions the fixed-point build's configuration maths needs
//! ([`exp2i`], [`sincos`]) without libm's large-argument machinery.
//!
//! libm's `sinf`/`cosf`/`tanf`/`asinf` evaluate their kernels in `f64`
//! (and `rem_pio2f` reduces in `f64`), which on a single-precision FPU
//! (Cortex-M4F) or none (RP2040) links ≈ 7 KiB of libm plus the soft-double
//! routines and costs hundreds of instructions a call. These are the Cephes
//! single-precision algorithms instead: a three-part Cody–Waite reduction
//! by π/2 (exact products for |x| < 2¹³·π/2; beyond that the result degrades
//! to some bounded value, but no caller comes near: the arguments are
//! angles of a turn or two) and minimax polynomials on [−π/4, π/4].
//!
//! Accuracy against the correctly rounded value (libm's `f64` functions on a
//! dense grid, the tests below): `sin`, `cos` ≤ 2 ulp (absolute 6e-8 near
//! the zeros), `tan` ≤ 3 ulp, `atan2` ≤ 4 ulp, `asin` ≤ 3 ulp — the
//! error model, attitude and filter design all run with tolerances orders
//! of magnitude wider. Like libm, the results are the same bits on every
//! platform (plain IEEE `f32` operations, no fused multiply-add).

// The Cephes coefficients as published (they round to the same f32).
#![allow(clippy::excessive_precision)]

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// π/2 in three parts: `DP1 + DP2 + DP3`; `DP1` and `DP2` have few enough
/// significant bits that `k·DP1` and `k·DP2` are exact for |k| < 2¹³.
const DP1: f32 = 1.570_312_5;
const DP2: f32 = 4.837_512_969_970_703_125e-4;
const DP3: f32 = 7.549_789_954_891_88e-8;

/// `x = k·π/2 + r` with |r| ≤ π/4 (slightly more when rounding ties): the
/// quadrant `k mod 4` and `r`. Non-finite `x` gives a NaN `r`.
fn reduce(x: f32) -> (u32, f32) {
    if x.abs() <= FRAC_PI_4 {
        return (0, x);
    }
    let k = round_half_away(x * core::f32::consts::FRAC_2_PI);
    // Beyond 2¹³·π/2 the reduction loses bits; the clamp keeps the kernels
    // (and so every result) bounded however large `x` is.
    let r = (((x - k * DP1) - k * DP2) - k * DP3).clamp(-0.8, 0.8);
    // `k` as an integer modulo 4 (saturating casts keep huge `x` defined).
    (k as i32 as u32 & 3, r)
}

/// `x` rounded to an integer, halves away from zero (|x| < 2²³ exact).
fn round_half_away(x: f32) -> f32 {
    if x.abs() >= 8_388_608.0 || x.is_nan() {
        return x;
    }
    let t = (x.abs() + 0.5) as i32 as f32;
    if x < 0.0 {
        -t
    } else {
        t
    }
}

/// sin r for |r| ≤ π/4.
fn sin_kernel(r: f32) -> f32 {
    let z = r * r;
    ((-1.951_529_589_1e-4 * z + 8.332_160_873_6e-3) * z - 1.666_665_461_1e-1) * z * r + r
}

/// cos r for |r| ≤ π/4.
fn cos_kernel(r: f32) -> f32 {
    let z = r * r;
    ((2.443_315_711_809_948e-5 * z - 1.388_731_625_493_765e-3) * z + 4.166_664_568_298_827e-2)
        * z
        * z
        - 0.5 * z
        + 1.0
}

/// sin x.
pub fn sinf(x: f32) -> f32 {
    sincosf(x).0
}

/// cos x.
pub fn cosf(x: f32) -> f32 {
    sincosf(x).1
}

/// (sin x, cos x) from one reduction.
pub fn sincosf(x: f32) -> (f32, f32) {
    let (q, r) = reduce(x);
    let (s, c) = (sin_kernel(r), cos_kernel(r));
    match q {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// tan x.
pub fn tanf(x: f32) -> f32 {
    let (q, r) = reduce(x);
    let z = r * r;
    let t = if r.abs() < 1e-4 {
        r
    } else {
        (((((9.385_401_855_43e-3 * z + 3.119_922_326_97e-3) * z + 2.443_013_545_25e-2) * z
            + 5.341_128_070_05e-2)
            * z
            + 1.333_879_940_85e-1)
            * z
            + 3.333_315_685_48e-1)
            * z
            * r
            + r
    };
    if q & 1 == 1 {
        -1.0 / t
    } else {
        t
    }
}

/// atan t for 0 ≤ t ≤ 1 (NaN stays NaN).
fn atan_unit(t: f32) -> f32 {
    // tan(π/8): above it, atan t = π/4 + atan((t − 1)/(t + 1)).
    let (y0, t) = if t > 0.414_213_57 {
        (FRAC_PI_4, (t - 1.0) / (t + 1.0))
    } else {
        (0.0, t)
    };
    let z = t * t;
    y0 + (((8.053_744_495_38e-2 * z - 1.387_768_560_32e-1) * z + 1.997_771_064_78e-1) * z
        - 3.333_294_915_39e-1)
        * z
        * t
        + t
}

/// The four-quadrant arctangent of `y/x`, in [−π, π] (as libm's `atan2f`,
/// to an ulp, for the signs of zeros and for infinities).
pub fn atan2f(y: f32, x: f32) -> f32 {
    if x.is_nan() || y.is_nan() {
        return f32::NAN;
    }
    let (ax, ay) = (x.abs(), y.abs());
    // The angle from the positive x axis in [0, π/2], the ratio kept ≤ 1.
    let a = if ax == ay {
        if ax == 0.0 {
            0.0
        } else {
            FRAC_PI_4
        }
    } else if ay > ax {
        FRAC_PI_2 - atan_unit(ax / ay)
    } else {
        atan_unit(ay / ax)
    };
    let a = if x.is_sign_negative() { PI - a } else { a };
    if y.is_sign_negative() {
        -a
    } else {
        a
    }
}

/// asin x for |x| ≤ 1 (NaN outside).
pub fn asinf(x: f32) -> f32 {
    let a = x.abs();
    if a > 1.0 || x.is_nan() {
        return f32::NAN;
    }
    let (z, t, big) = if a > 0.5 {
        let z = 0.5 * (1.0 - a);
        (z, libm::sqrtf(z), true)
    } else {
        (a * a, a, false)
    };
    let p = ((((4.216_319_904_8e-2 * z + 2.418_131_104_9e-2) * z + 4.547_002_599_8e-2) * z
        + 7.495_300_268_6e-2)
        * z
        + 1.666_675_242_2e-1)
        * z
        * t
        + t;
    let r = if big { FRAC_PI_2 - (p + p) } else { p };
    if x < 0.0 {
        -r
    } else {
        r
    }
}

/// 2ⁿ exactly, from the exponent bits (no `pow`); `n` is clamped to the
/// normal range −1022 … 1023.
pub fn exp2i(n: i32) -> f64 {
    f64::from_bits(((n.clamp(-1022, 1023) + 1023) as u64) << 52)
}

/// (sin x, cos x) in `f64` for the fixed-point build's configuration
/// maths: fdlibm's kernels after a three-part Cody–Waite reduction by π/2
/// (fdlibm's medium-size path, accurate for |x| < 2¹⁹·π/2 — every caller
/// passes an angle of at most a turn), ≤ 1 ulp against libm. Unlike libm's
/// `sin`/`cos` it never needs `rem_pio2_large` (≈ 2.3 KiB on ARMv6-M).
/// Non-finite `x` gives NaNs; huge `x` bounded garbage.
pub fn sincos(x: f64) -> (f64, f64) {
    const PIO2_1: f64 = 1.570_796_326_734_125_6e0;
    const PIO2_1T: f64 = 6.077_100_506_506_192_6e-11;
    const PIO2_2: f64 = 6.077_100_506_303_966e-11;
    const PIO2_2T: f64 = 2.022_266_248_795_950_6e-21;
    let (q, r) = if x.abs() <= core::f64::consts::FRAC_PI_4 {
        (0, x)
    } else {
        let kf = x * core::f64::consts::FRAC_2_PI;
        let k = if kf.is_nan() {
            kf
        } else {
            let t = (kf.abs() + 0.5) as i64 as f64;
            if kf < 0.0 {
                -t
            } else {
                t
            }
        };
        let r = (x - k * PIO2_1) - k * PIO2_1T;
        let r = if (kf.abs() as u64) < (1 << 16) {
            r
        } else {
            // fdlibm's second step: 33 more bits of π/2.
            let t = x - k * PIO2_1;
            let w = k * PIO2_2;
            let t2 = t - w;
            let w = k * PIO2_2T - ((t - t2) - w);
            t2 - w
        };
        ((k as i64 & 3) as u32, r.clamp(-0.8, 0.8))
    };
    let z = r * r;
    let sn = r + r
        * z
        * (-1.666_666_666_666_663_2e-1
            + z * (8.333_333_333_322_49e-3
                + z * (-1.984_126_982_985_795e-4
                    + z * (2.755_731_370_707_006_8e-6
                        + z * (-2.505_076_025_340_686_3e-8 + z * 1.589_690_995_211_55e-10)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let cr = z
        * z
        * (4.166_666_666_666_66e-2
            + z * (-1.388_888_888_887_411e-3
                + z * (2.480_158_728_947_673e-5
                    + z * (-2.755_731_435_139_066_3e-7
                        + z * (2.087_572_321_298_175e-9 + z * -1.135_964_755_778_819_5e-11)))));
    let cs = w + (((1.0 - w) - hz) + cr);
    match q {
        0 => (sn, cs),
        1 => (cs, -sn),
        2 => (-sn, -cs),
        _ => (-cs, sn),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place of `exact` (rounded to f32).
    fn ulps(got: f32, exact: f64) -> f64 {
        let e = exact as f32;
        let ulp = if e == 0.0 {
            f64::from(f32::MIN_POSITIVE)
        } else {
            f64::from(f32::from_bits(e.abs().to_bits() + 1) - e.abs())
        };
        (f64::from(got) - exact).abs() / ulp
    }

    fn grid(lo: f32, hi: f32, n: u32) -> impl Iterator<Item = f32> {
        (0..=n).map(move |i| lo + (hi - lo) * (i as f32 / n as f32))
    }

    #[test]
    fn sin_cos_within_2_ulp_or_6e8_absolute() {
        let (mut worst_u, mut worst_a) = (0.0f64, 0.0f64);
        for x in grid(-30.0, 30.0, 400_000).chain(grid(-1e-3, 1e-3, 10_000)) {
            let (s, c) = sincosf(x);
            assert_eq!((s, c), (sinf(x), cosf(x)));
            for (got, exact) in [(s, libm::sin(f64::from(x))), (c, libm::cos(f64::from(x)))] {
                let abs = (f64::from(got) - exact).abs();
                worst_a = worst_a.max(abs);
                if exact.abs() > 1e-2 {
                    worst_u = worst_u.max(ulps(got, exact));
                }
            }
        }
        assert!(worst_u <= 2.0, "{worst_u} ulp");
        assert!(worst_a <= 1.2e-7, "{worst_a}");
        std::eprintln!("sin/cos: {worst_u} ulp, {worst_a:e} absolute");
        assert_eq!(sinf(0.0), 0.0);
        assert_eq!(cosf(0.0), 1.0);
        assert!(sinf(f32::NAN).is_nan() && cosf(f32::INFINITY).is_nan());
        // Huge arguments stay defined (bounded, no panic).
        for x in [1e10f32, -3e38, f32::MAX] {
            assert!(sinf(x).abs() <= 1.5 && cosf(x).abs() <= 1.5, "{x}");
        }
    }

    #[test]
    fn f64_sincos_within_1_ulp_and_exp2i_exact() {
        let (mut worst, mut worst_a) = (0.0f64, 0.0f64);
        for i in -400_000..=400_000 {
            let x = f64::from(i) * 2.5e-5 + 1e-9;
            let (s, c) = sincos(x);
            for (got, exact) in [(s, libm::sin(x)), (c, libm::cos(x))] {
                worst_a = worst_a.max((got - exact).abs());
                if exact.abs() > 1e-3 {
                    worst = worst.max((got - exact).abs() / (exact.abs() * f64::EPSILON));
                }
            }
        }
        std::eprintln!("f64 sincos: {worst} ulp, {worst_a:e} absolute");
        assert!(worst <= 1.0 && worst_a <= 2.3e-16, "{worst} {worst_a}");
        assert!(sincos(f64::NAN).0.is_nan() && sincos(f64::INFINITY).1.is_nan());
        for n in [-1022, -30, 0, 1, 26, 50, 1023] {
            assert_eq!(exp2i(n), libm::pow(2.0, f64::from(n)));
        }
    }

    #[test]
    fn tan_within_3_ulp() {
        let mut worst = 0.0f64;
        for x in grid(-1.5, 1.5, 300_000) {
            worst = worst.max(ulps(tanf(x), libm::tan(f64::from(x))));
        }
        assert!(worst <= 3.0, "{worst} ulp");
        std::eprintln!("tan: {worst} ulp");
    }

    #[test]
    fn atan2_within_4_ulp_and_libm_special_cases() {
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let a = -3.2 + 6.4 * f64::from(i) / 200_000.0;
            for r in [1e-3f64, 1.0, 7e3] {
                let (y, x) = ((a.sin() * r) as f32, (a.cos() * r) as f32);
                let exact = libm::atan2(f64::from(y), f64::from(x));
                worst = worst.max(ulps(atan2f(y, x), exact));
            }
        }
        assert!(worst <= 4.0, "{worst} ulp");
        std::eprintln!("atan2: {worst} ulp");
        for (y, x) in [
            (0.0f32, 0.0f32),
            (-0.0, 0.0),
            (0.0, -0.0),
            (-0.0, -0.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, -1.0),
            (-0.0, -1.0),
            (f32::INFINITY, f32::INFINITY),
            (f32::INFINITY, -f32::INFINITY),
            (-f32::INFINITY, 1.0),
            (1.0, f32::INFINITY),
            (1e-30, 1e30),
            (1e30, 1e-30),
        ] {
            let (got, want) = (atan2f(y, x), libm::atan2f(y, x));
            assert!(
                (got - want).abs() <= 2.5e-7,
                "atan2({y}, {x}): {got} vs {want}"
            );
            assert_eq!(
                got.is_sign_negative(),
                want.is_sign_negative(),
                "atan2({y}, {x})"
            );
        }
        assert!(atan2f(f32::NAN, 1.0).is_nan());
    }

    #[test]
    fn asin_within_3_ulp() {
        let mut worst = 0.0f64;
        for x in grid(-1.0, 1.0, 400_000) {
            worst = worst.max(ulps(asinf(x), libm::asin(f64::from(x))));
        }
        assert!(worst <= 3.0, "{worst} ulp");
        std::eprintln!("asin: {worst} ulp");
        assert_eq!(asinf(1.0), FRAC_PI_2);
        assert!(asinf(1.01).is_nan() && asinf(f32::NAN).is_nan());
    }
}
