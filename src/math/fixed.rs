//! Integer arithmetic for the `fixed-point` build (cores without an FPU:
//! ARMv6-M, RP2040), where an `f32` operation is a library call of 60–110
//! instructions and a plain `i64` product one of ~40.
//!
//! - [`mul64`]: the exact 64-bit product of two `i32` from four 16 × 16
//!   products (one `MULS` each on a Cortex-M0+); [`mul_shr`] rounds it
//!   down by a shift.
//! - [`mul_q30`]: the product of two Q30 numbers of magnitude ≤ 1 (unit
//!   quaternions, rotation matrices), exactly rounded, in 32-bit arithmetic.
//! - [`Coef`]: a constant multiplier with a 14-bit mantissa and a shift
//!   (relative precision 2⁻¹⁴), applied in two 32-bit products — for the
//!   error model's small coefficients (scale factors, misalignments,
//!   noise levels, Gauss–Markov constants), whose own accuracy is a few
//!   percent at best.
//! - [`scaled_f32`] / [`to_fixed`]: conversions with power-of-two scales,
//!   the scaling done on the exponent bits (no float multiply).
//! - [`atan2_q29`]: CORDIC arctangent for the Euler angles of `output()`.
//!
//! Everything here is exact integer arithmetic: the same inputs give the same
//! bits on every platform.
//!
//! **Out of line in the `fixed-point` build.** The products ([`mul64_parts`],
//! [`mul_shr`], [`mul_q30`], [`mul_q`]), the conversions ([`scaled_f32`], [`to_fixed`])
//! and [`bit_len`] are `#[inline(never)]` there (inlined otherwise): inlined
//! at their ~80 call sites they were 9.2 KiB of the RP2040 image's flash;
//! a call costs the worst-case device tick ≈ 6 % more instructions
//! (largest UDD 20 944 → 22 221, GA 13 735 → 14 486 under QEMU), far inside
//! the RP2040's 62 500 cycles.

/// The exact product `a · b` ([`mul64_parts`] on 32-bit targets, the
/// native product — the same value — on 64-bit hosts).
#[inline(always)]
pub fn mul64(a: i32, b: i32) -> i64 {
    // Fork by word size: ARMv6-M has no 32 × 32 → 64 multiply (a library call).
    if cfg!(target_pointer_width = "64") {
        i64::from(a) * i64::from(b)
    } else {
        mul64_parts(a, b)
    }
}

/// The exact product `a · b` from four 16 × 16 products (one `MULS` each on
/// ARMv6-M, where a plain `i64` product is a library call).
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
pub fn mul64_parts(a: i32, b: i32) -> i64 {
    let al = (a & 0xFFFF) as u32;
    let ah = a >> 16;
    let bl = (b & 0xFFFF) as u32;
    let bh = b >> 16;
    // al·bh and ah·bl: |·| ≤ 65535 · 32768 < 2³¹; ah·bh ≤ 2³⁰; al·bl < 2³².
    let mid = i64::from(al as i32 * bh) + i64::from(ah * bl as i32);
    (i64::from(ah * bh) << 32) + (mid << 16) + i64::from(al * bl)
}

/// `a · b / 2^s` rounded to nearest (half up), 1 ≤ `s` ≤ 62; the result must
/// fit an `i32`.
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
pub fn mul_shr(a: i32, b: i32, s: u32) -> i32 {
    ((mul64(a, b) + (1i64 << (s - 1))) >> s) as i32
}

/// `a · b / 2³⁰` rounded to nearest, in 32-bit arithmetic (four `MULS`),
/// for any `a`, `b` whose product is below 2⁶⁰ in magnitude (Q30 numbers of
/// magnitude ≤ 1, e.g. unit quaternions, times anything up to 2³⁰). The
/// cross terms are summed at 2⁻¹² of the result's LSB, so the result is
/// the correctly rounded one except within 1e-3 LSB of a tie (never off by
/// more than 1).
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
pub fn mul_q30(a: i32, b: i32) -> i32 {
    let al = (a & 0xFFFF) as u32;
    let ah = a >> 16;
    let bl = (b & 0xFFFF) as u32;
    let bh = b >> 16;
    // |al·bh|, |ah·bl| < 2³¹ for any i32: each fits, a quarter of each
    // cannot overflow the sum.
    let t =
        ((al as i32 * bh) >> 2) + ((ah * bl as i32) >> 2) + ((al * bl) >> 18) as i32 + (1 << 11);
    ((ah * bh) << 2) + (t >> 12)
}

/// `a · b / 2^S` rounded to nearest, in 32-bit arithmetic, for
/// 19 ≤ S ≤ 32: [`mul_q30`] at another binary point (the result must fit an
/// `i32`; within 1 of the correctly rounded value).
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
pub fn mul_q<const S: u32>(a: i32, b: i32) -> i32 {
    let al = (a & 0xFFFF) as u32;
    let ah = a >> 16;
    let bl = (b & 0xFFFF) as u32;
    let bh = b >> 16;
    let t = ((al as i32 * bh) >> 2) + ((ah * bl as i32) >> 2) + ((al * bl) >> 18) as i32;
    ((ah * bh) << (32 - S)) + ((t + (1 << (S - 19))) >> (S - 18))
}

/// A constant multiplier `m · 2⁻ⁿ` with |m| < 2¹⁴ (relative precision
/// 2⁻¹⁴ ≈ 6e-5), 0 ≤ n ≤ 46; magnitudes below 2⁻³³ are 0, above 2¹⁴
/// saturate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Coef {
    m: i16,
    n: u8,
}

impl Coef {
    /// Zero.
    pub const ZERO: Coef = Coef { m: 0, n: 0 };

    /// The nearest representable multiplier to `c`.
    pub fn new(c: f64) -> Coef {
        if c.is_nan() || c == 0.0 {
            return Coef::ZERO;
        }
        let mut n = 0u8;
        let mut v = c.abs();
        if v >= 16_383.5 {
            let m = 16_383i16;
            return Coef {
                m: if c < 0.0 { -m } else { m },
                n: 0,
            };
        }
        while v < 8_192.0 && n < 46 {
            v *= 2.0;
            n += 1;
        }
        let r = libm::round(v);
        if r < 1.0 {
            return Coef::ZERO;
        }
        // Rounding may reach 2¹⁴: halve (keeps |m| < 2¹⁴).
        let (r, n) = if r >= 16_384.0 {
            (8_192.0, n - 1)
        } else {
            (r, n)
        };
        let m = r as i16;
        Coef {
            m: if c < 0.0 { -m } else { m },
            n,
        }
    }

    /// The multiplier `v · 2^−frac` (to 14 significant bits; `frac` ≤ 46,
    /// and |v| < 2^(frac + 14)).
    pub fn from_fixed(v: i32, frac: u32) -> Coef {
        if v == 0 {
            return Coef::ZERO;
        }
        let mag = v.unsigned_abs();
        let bits = 32 - mag.leading_zeros();
        let (m, n) = if bits <= 14 {
            (mag, frac)
        } else {
            let s = bits - 14;
            let r = (mag + (1 << (s - 1))) >> s;
            if r >= 1 << 14 {
                (r >> 1, frac - s - 1)
            } else {
                (r, frac - s)
            }
        };
        let m = m as i16;
        Coef {
            m: if v < 0 { -m } else { m },
            n: n as u8,
        }
    }

    /// The nearest representable multiplier to `c` from its bits (no float
    /// arithmetic: the significand's top 14 bits, rounded; |c| < 2¹³).
    pub fn from_f32(c: f32) -> Coef {
        let bits = c.to_bits();
        let exp = ((bits >> 23) & 0xFF) as i32;
        if exp == 0 || exp == 0xFF {
            return Coef::ZERO;
        }
        // |c| = M·2^(exp − 150), M = 1.f in 24 bits; keep 14 of them.
        let m = (bits & 0x7F_FFFF) | 0x80_0000;
        let mut r = (m + (1 << 9)) >> 10;
        let mut n = 150 - exp - 10;
        if r >= 1 << 14 {
            r >>= 1;
            n -= 1;
        }
        if n > 46 {
            return Coef::ZERO;
        }
        if n < 0 {
            return Coef {
                m: if bits >> 31 != 0 { -16_383 } else { 16_383 },
                n: 0,
            };
        }
        let r = r as i16;
        Coef {
            m: if bits >> 31 != 0 { -r } else { r },
            n: n as u8,
        }
    }

    /// The multiplier's value.
    pub fn value(self) -> f64 {
        f64::from(self.m) / crate::math::exp2i(self.n as i32)
    }

    /// `x · c` rounded to nearest, for any `x` (the result must fit).
    #[inline(always)]
    pub fn apply(self, x: i32) -> i32 {
        let m = i32::from(self.m);
        // x·m / 2¹⁵ in two products: |x >> 15| ≤ 2¹⁶, |m| < 2¹⁴.
        let t = (x >> 15) * m + (((x & 0x7FFF) * m + (1 << 14)) >> 15);
        let n = u32::from(self.n);
        if n > 15 {
            let s = n - 15;
            (t + (1 << (s - 1))) >> s
        } else {
            t << (15 - n)
        }
    }

    /// `x · c` rounded to nearest for |x| < 2¹⁷ (one product: |x · m| < 2³¹).
    #[inline(always)]
    pub fn apply_small(self, x: i32) -> i32 {
        let p = x * i32::from(self.m);
        match u32::from(self.n) {
            0 => p,
            n @ 1..=31 => (p + (1 << (n - 1))) >> n,
            _ => 0,
        }
    }
}

/// `x · 2⁻ᵏ` as `f32`: `x` rounded to 24 significant bits exactly as
/// `x as f32` does (to nearest, ties to even), the scaling exact (on the
/// exponent; k ≤ 100 keeps it normal). Built from the bits: ARMv6-M's
/// library conversion costs ~70 instructions with its `CLZ` emulation.
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline)]
pub fn scaled_f32(x: i32, k: u32) -> f32 {
    if x == 0 {
        return 0.0;
    }
    let sign = (x as u32) & 0x8000_0000;
    let m = x.unsigned_abs();
    let e = bit_len(m) - 1;
    let (mant, e) = if e <= 23 {
        (m << (23 - e), e)
    } else {
        let s = e - 23;
        let mut mant = m >> s;
        let rem = m & ((1 << s) - 1);
        let half = 1 << (s - 1);
        if rem > half || (rem == half && mant & 1 == 1) {
            mant += 1;
        }
        if mant == 1 << 24 {
            (mant >> 1, e + 1)
        } else {
            (mant, e)
        }
    };
    f32::from_bits(sign | ((e + 127 - k) << 23) | (mant & 0x7F_FFFF))
}

/// [`scaled_f32`] of an `i64`.
#[inline]
pub fn scaled_f32_i64(x: i64, k: u32) -> f32 {
    if x == 0 {
        return 0.0;
    }
    f32::from_bits((x as f32).to_bits() - (k << 23))
}

/// `v · 2ᵏ` rounded to nearest (half away from zero), saturated to the `i32`
/// range; NaN gives 0.
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline)]
pub fn to_fixed(v: f32, k: u32) -> i32 {
    let bits = v.to_bits();
    let exp = (bits >> 23) & 0xFF;
    if exp == 0 || exp == 0xFF {
        // Zero, subnormal (rounds to 0), infinity or NaN.
        return if exp == 0xFF && bits & 0x7F_FFFF == 0 {
            if v > 0.0 {
                i32::MAX
            } else {
                i32::MIN
            }
        } else {
            0
        };
    }
    if exp + k >= 0xFF {
        return if v > 0.0 { i32::MAX } else { i32::MIN };
    }
    let w = f32::from_bits(bits + (k << 23));
    (w + 0.5f32.copysign(w)) as i32
}

/// The number of significant bits of `x` (0 for 0): a few compares, where
/// `leading_zeros` is a library call on ARMv6-M (no `CLZ`).
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
pub fn bit_len(x: u32) -> u32 {
    let (mut x, mut n) = (x, 0);
    if x >= 1 << 16 {
        x >>= 16;
        n += 16;
    }
    if x >= 1 << 8 {
        x >>= 8;
        n += 8;
    }
    if x >= 1 << 4 {
        x >>= 4;
        n += 4;
    }
    if x >= 1 << 2 {
        x >>= 2;
        n += 2;
    }
    if x >= 1 << 1 {
        x >>= 1;
        n += 1;
    }
    n + x
}

/// [`bit_len`] of a `u64`.
#[inline(always)]
pub fn bit_len64(x: u64) -> u32 {
    let hi = (x >> 32) as u32;
    if hi != 0 {
        32 + bit_len(hi)
    } else {
        bit_len(x as u32)
    }
}

/// ⌊a · b / 2³²⌋ for `u32`, from below: at most 2 less than the exact
/// value (the cross terms are shifted separately; written out exactly,
/// LLVM turns the expression back into a 64-bit product — a library call
/// on ARMv6-M).
#[inline(always)]
pub fn mulhi_u32_low(a: u32, b: u32) -> u32 {
    let (al, ah) = (a & 0xFFFF, a >> 16);
    let (bl, bh) = (b & 0xFFFF, b >> 16);
    ah * bh + ((ah * bl) >> 16) + ((al * bh) >> 16)
}

/// The exact product `a · b` of two `u32` (four 16 × 16 products on 32-bit
/// targets, the native product on 64-bit hosts).
#[inline(always)]
pub fn mulu64(a: u32, b: u32) -> u64 {
    // Fork by word size, as in `mul64`.
    if cfg!(target_pointer_width = "64") {
        u64::from(a) * u64::from(b)
    } else {
        mulu64_parts(a, b)
    }
}

/// [`mulu64`]'s 32-bit path.
#[inline(always)]
pub fn mulu64_parts(a: u32, b: u32) -> u64 {
    let (al, ah) = (a & 0xFFFF, a >> 16);
    let (bl, bh) = (b & 0xFFFF, b >> 16);
    let mid = u64::from(al * bh) + u64::from(ah * bl);
    (u64::from(ah * bh) << 32) + (mid << 16) + u64::from(al * bl)
}

/// Division by a fixed `n` through its reciprocal: one software division
/// when made, then a few 32 × 32 products per quotient (ARMv6-M has no
/// divide instruction; a library `i64 / u32` costs ~250 instructions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Recip {
    n: u32,
    /// ⌊(2³² − 1)/n⌋.
    r: u32,
}

impl Recip {
    /// The reciprocal of `n` ≥ 1.
    pub fn new(n: u32) -> Self {
        let n = n.max(1);
        Recip { n, r: u32::MAX / n }
    }

    /// `x / n` rounded to nearest (half away from zero), saturated to
    /// `i32`.
    pub fn div_round(&self, x: i64) -> i32 {
        let n = self.n;
        let ax = x.unsigned_abs() + u64::from(n / 2);
        let q = if n == 1 {
            ax
        } else if n > 0xFFFF || ax >> 31 >= u64::from(n) {
            // Outside the fast path's range (or a quotient beyond i32).
            ax / u64::from(n)
        } else {
            // ax < 2³¹·n: ax = a1·2³² + a0 with a1 < n/2. Two estimates
            // from below with r ≤ 2³²/n (a1·r < 2³¹), then a few
            // corrections; everything in 32-bit products.
            let (a1, a0) = ((ax >> 32) as u32, ax as u32);
            let mut q = a1 * self.r + mulhi_u32_low(a0, self.r);
            // rem < (a1 + 5)·n < 2³²
            let mut rem = (ax - mulu64(q, n)) as u32;
            let d = mulhi_u32_low(rem, self.r);
            q += d;
            rem -= d * n;
            while rem >= n {
                q += 1;
                rem -= n;
            }
            u64::from(q)
        };
        let q = q.min(i32::MAX as u64) as i32;
        if x < 0 {
            -q
        } else {
            q
        }
    }
}

/// `x · 2^lsb · k` rounded to nearest and saturated to `i32`, for an `f32`
/// factor `k` > 0: `x` is normalised to 31 bits and multiplied by the
/// 24-bit significand of `k` (relative precision 2⁻²⁴, like an `f32`
/// product), the exponents applied as one shift.
pub fn scale_i64(x: i64, lsb: i32, k: f32) -> i32 {
    if x == 0 || k.is_nan() || k <= 0.0 || !k.is_finite() {
        return 0;
    }
    let bits = k.to_bits();
    let m = ((bits & 0x7F_FFFF) | 0x80_0000) as i32;
    let e = ((bits >> 23) & 0xFF) as i32 - 150;
    let sx = bit_len64(x.unsigned_abs()).saturating_sub(31);
    let xs = (x >> sx) as i32;
    let p = mul64(xs, m);
    let t = sx as i32 + lsb + e;
    let v = if t >= 0 {
        if t > 62 || p.unsigned_abs() >> (62 - t) != 0 {
            if p < 0 {
                i64::MIN
            } else {
                i64::MAX
            }
        } else {
            p << t
        }
    } else if t < -62 {
        0
    } else {
        let s = (-t) as u32;
        (p + (1i64 << (s - 1))) >> s
    };
    v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

/// A triad of `i64` as `i32` after a common right shift (returned) that
/// brings every component within 2³⁰.
pub fn norm3(v: &[i64; 3]) -> ([i32; 3], u32) {
    let m = v[0].unsigned_abs() | v[1].unsigned_abs() | v[2].unsigned_abs();
    let s = bit_len64(m).saturating_sub(30);
    (
        [(v[0] >> s) as i32, (v[1] >> s) as i32, (v[2] >> s) as i32],
        s,
    )
}

/// The cross product `a × b` of two triads normalised by [`norm3`], exact
/// in `i64` (|·| < 2⁶¹), in units of 2^(shift a + shift b).
pub fn cross_i64(a: &[i32; 3], b: &[i32; 3]) -> [i64; 3] {
    [
        mul64(a[1], b[2]) - mul64(a[2], b[1]),
        mul64(a[2], b[0]) - mul64(a[0], b[2]),
        mul64(a[0], b[1]) - mul64(a[1], b[0]),
    ]
}

/// `x · 2^s` for `s` of either sign (right shifts round to nearest,
/// left shifts saturate).
pub fn shift_i64(x: i64, s: i32) -> i64 {
    if s >= 0 {
        if s > 62 || (x.unsigned_abs() >> (62 - s)) != 0 {
            if x == 0 {
                0
            } else if x < 0 {
                i64::MIN
            } else {
                i64::MAX
            }
        } else {
            x << s
        }
    } else if s < -62 {
        0
    } else {
        let r = (-s) as u32;
        (x >> r) + ((x >> (r - 1)) & 1)
    }
}

/// The CORDIC gain Π √(1 + 2⁻²ⁱ), i = 0…, in Q30.
pub const CORDIC_GAIN_Q30: i32 = 1_768_195_363;

/// atan(2⁻ⁱ) in Q29 radians, computed at compile time.
const ATAN_Q29: [i32; 30] = {
    let mut t = [0i32; 30];
    let mut i = 0;
    while i < 30 {
        // atan x = Σ (−1)ᵏ x²ᵏ⁺¹/(2k+1); atan 1 = π/4 directly.
        let a = if i == 0 {
            core::f64::consts::FRAC_PI_4
        } else {
            let x = 1.0 / (1u64 << i) as f64;
            let mut s = 0.0;
            let mut p = x;
            let mut k = 0;
            while k < 40 {
                let term = p / (2 * k + 1) as f64;
                s += if k % 2 == 0 { term } else { -term };
                p *= x * x;
                k += 1;
            }
            s
        };
        t[i] = (a * (1u64 << 29) as f64 + 0.5) as i32;
        i += 1;
    }
    t
};

/// π/2 in Q29.
const HALF_PI_Q29: i32 = 843_314_857;

/// `atan2(y, x)` in Q29 radians (−π … π) and `K·√(x² + y²)` (K =
/// [`CORDIC_GAIN_Q30`]/2³⁰ ≈ 1.6468), by 30 CORDIC vectoring steps;
/// |x|, |y| ≤ 2²⁹. Accurate to a few 1e-9 rad for inputs of ~2²⁸.
pub fn atan2_q29(y: i32, x: i32) -> (i32, i32) {
    // On an axis the angle is exact (a level attitude reads 0, not ±1e-9).
    if y == 0 {
        let m = mul_shr(x.abs(), CORDIC_GAIN_Q30, 30);
        return (if x >= 0 { 0 } else { 2 * HALF_PI_Q29 }, m);
    }
    if x == 0 {
        let m = mul_shr(y.abs(), CORDIC_GAIN_Q30, 30);
        return (if y > 0 { HALF_PI_Q29 } else { -HALF_PI_Q29 }, m);
    }
    // Into the right half-plane by ±π/2 (exact).
    let (mut x, mut y, mut z) = if x >= 0 {
        (x, y, 0)
    } else if y >= 0 {
        (y, -x, HALF_PI_Q29)
    } else {
        (-y, x, -HALF_PI_Q29)
    };
    for (i, &a) in ATAN_Q29.iter().enumerate() {
        let (dx, dy) = (y >> i, x >> i);
        if y > 0 {
            x += dx;
            y -= dy;
            z += a;
        } else {
            x -= dx;
            y += dy;
            z -= a;
        }
    }
    (z, x)
}

/// (sin z, cos z) in Q30 for an angle `z` in Q29 radians, |z| ≤ π/2, by 30
/// CORDIC rotation steps (within 1e-8).
pub fn sin_cos_q30(z: i32) -> (i32, i32) {
    // Start at 1/K so the rotations' gain brings the vector to unit length.
    let mut x: i32 = 652_032_874; // 2³⁰ / 1.6467602581
    let mut y: i32 = 0;
    let mut z = z;
    for (i, &a) in ATAN_Q29.iter().enumerate() {
        let (dx, dy) = (y >> i, x >> i);
        if z >= 0 {
            x -= dx;
            y += dy;
            z -= a;
        } else {
            x += dx;
            y -= dy;
            z += a;
        }
    }
    (y, x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_are_exact() {
        let vals = [
            0,
            1,
            -1,
            65_535,
            65_536,
            -65_536,
            1 << 30,
            -(1 << 30),
            i32::MAX,
            i32::MIN,
            123_456_789,
            -987_654_321,
            0x7FFF_0001,
        ];
        for &a in &vals {
            for &b in &vals {
                assert_eq!(mul64(a, b), i64::from(a) * i64::from(b), "{a} {b}");
                assert_eq!(mul64_parts(a, b), i64::from(a) * i64::from(b), "{a} {b}");
            }
        }
        let mut s = 0x1234_5678u32;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as i32
        };
        for _ in 0..100_000 {
            let (a, b) = (rnd(), rnd());
            assert_eq!(mul64(a, b), i64::from(a) * i64::from(b));
            assert_eq!(mul64_parts(a, b), i64::from(a) * i64::from(b));
            let (ua, ub) = (a as u32, b as u32);
            assert_eq!(mulu64_parts(ua, ub), u64::from(ua) * u64::from(ub));
            // Any magnitudes with |a·b| < 2⁶⁰: within 1 of the rounded
            // value, and equal to it except next to a tie.
            let (a, b) = (a >> 1 >> (a as u32 & 1), b >> 1);
            let (a, b) = (a.clamp(-(1 << 30) - 9999, 1 << 30), b);
            let p = i64::from(a) * i64::from(b);
            let exact = (p + (1 << 29)) >> 30;
            let got = i64::from(mul_q30(a, b));
            assert!((got - exact).abs() <= 1, "{a} {b}");
            let frac = (p & ((1 << 30) - 1)) as f64 / (1u64 << 30) as f64;
            assert!(got == exact || (frac - 0.5).abs() < 1e-3, "{a} {b}");
        }
        for _ in 0..10_000 {
            let (a, b) = (rnd(), rnd() >> 3);
            let exact = (i64::from(a) * i64::from(b) + (1 << 25)) >> 26;
            if exact.abs() < 1 << 30 {
                assert!((i64::from(mul_q::<26>(a, b)) - exact).abs() <= 1, "{a} {b}");
            }
            let exact = (i64::from(a) * i64::from(b >> 1) + (1 << 28)) >> 29;
            assert!(
                (i64::from(mul_q::<29>(a, b >> 1)) - exact).abs() <= 1,
                "{a} {b}"
            );
        }
        for (a, b) in [
            (1 << 30, 1 << 30),
            (-(1 << 30), 1 << 30),
            (-(1 << 30), -(1 << 30)),
            (-(1 << 30) - 1, -(1 << 30) - 1),
            (-(1 << 30) - 65_535, (1 << 30) + 65_535),
            (i32::MAX, 1 << 28),
            (i32::MIN, -(1 << 28)),
        ] {
            let exact = (i64::from(a) * i64::from(b) + (1 << 29)) >> 30;
            assert_eq!(i64::from(mul_q30(a, b)), exact, "{a} {b}");
        }
    }

    #[test]
    fn coefficients_are_within_their_precision() {
        for c in [
            1e-9, 3.3e-6, 0.001, -0.25, 0.5, 0.999, 1.0, 2.06, -7.5, 1234.5, 16_000.0,
        ] {
            let k = Coef::new(c);
            assert!((k.value() / c - 1.0).abs() < 1.3e-4, "{c}: {}", k.value());
            for x in [0, 1, -1, 1000, -131_070, 131_070, 99_999] {
                let exact = f64::from(x) * k.value();
                assert!(
                    (f64::from(k.apply_small(x)) - exact).abs() <= 0.5 + 1e-9,
                    "{c} {x}"
                );
            }
            if c.abs() <= 0.25 {
                for x in [i32::MAX, i32::MIN, 1 << 30, -123_456_789] {
                    let exact = f64::from(x) * k.value();
                    assert!((f64::from(k.apply(x)) - exact).abs() <= 1.0, "{c} {x}");
                }
            }
        }
        assert_eq!(Coef::new(0.0), Coef::ZERO);
        for c in [3e-4f32, -2.5e-4, 0.2499, 1.0, -7.25, 1e-9, 1234.5] {
            let k = Coef::from_f32(c);
            assert!((k.value() / f64::from(c) - 1.0).abs() < 1.3e-4, "{c}");
        }
        assert_eq!(Coef::from_f32(0.0), Coef::ZERO);
        for v in [1, -1, 12_345, -16_384, 1 << 30, -(1 << 30), 987_654_321] {
            let k = Coef::from_fixed(v, 32);
            let c = f64::from(v) / 4_294_967_296.0;
            assert!((k.value() / c - 1.0).abs() < 1.3e-4, "{v}");
        }
        assert_eq!(Coef::new(1e-12).apply(i32::MAX), 0);
    }

    #[test]
    fn reciprocal_division_is_exact() {
        let mut s = 0x9E37_79B9u32;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s
        };
        for n in (1..70_000u32)
            .step_by(7)
            .chain([1, 2, 3, 20, 4000, 65_535, 65_536, 1 << 20])
        {
            let r = Recip::new(n);
            for _ in 0..20 {
                let mean = (rnd() as i32) >> (rnd() % 31);
                let x = i64::from(mean) * i64::from(n) + i64::from(rnd() % n) - i64::from(n / 2);
                let h = i64::from(n / 2);
                let expect = if x >= 0 {
                    (x + h) / i64::from(n)
                } else {
                    (x - h) / i64::from(n)
                };
                let expect = expect.clamp(i64::from(i32::MIN) + 1, i64::from(i32::MAX));
                assert_eq!(i64::from(r.div_round(x)), expect, "{x} / {n}");
            }
        }
    }

    #[test]
    fn scaling_matches_float() {
        for (x, lsb, k) in [
            (123_456_789_012i64, 12, 1.7e-12f32),
            (-5, 0, 0.5),
            (1 << 40, -20, 3.0),
            (-987_654_321_987, 36, 2.3e-15),
            (i64::MAX, 0, 1.0),
        ] {
            let expect = (x as f64) * 2f64.powi(lsb) * f64::from(k);
            let got = f64::from(scale_i64(x, lsb, k));
            let expect = expect.clamp(f64::from(i32::MIN), f64::from(i32::MAX));
            assert!(
                (got - expect).abs() <= 0.5 + expect.abs() * 1.2e-7,
                "{x} {lsb} {k}: {got} {expect}"
            );
        }
        assert_eq!(shift_i64(5, -1), 3);
        assert_eq!(shift_i64(-5, -1), -2);
        assert_eq!(shift_i64(3, 2), 12);
        assert_eq!(shift_i64(1 << 62, 2), i64::MAX);
        let (v, s) = norm3(&[1 << 40, -(1 << 35), 7]);
        assert_eq!((v, s), ([1 << 29, -(1 << 24), 0], 11));
    }

    #[test]
    fn bit_tricks_match_the_library() {
        let mut s = 0xDEAD_BEEFu32;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s
        };
        for i in 0..200_000u32 {
            let x = match i % 4 {
                0 => rnd(),
                1 => rnd() >> (rnd() % 32),
                2 => i,
                _ => u32::MAX - i,
            };
            assert_eq!(bit_len(x), 32 - x.leading_zeros(), "{x}");
            let y = rnd();
            let exact = ((u64::from(x) * u64::from(y)) >> 32) as u32;
            let low = mulhi_u32_low(x, y);
            assert!(low <= exact && exact - low <= 2, "{x} {y}");
            let v = x as i32;
            assert_eq!(scaled_f32(v, 0).to_bits(), (v as f32).to_bits(), "{v}");
            assert_eq!(scaled_f32(v, 17), v as f32 / 131_072.0, "{v}");
        }
        for v in [
            i32::MIN,
            i32::MAX,
            16_777_217,
            16_777_219,
            -33_554_435,
            1,
            -1,
        ] {
            assert_eq!(scaled_f32(v, 0).to_bits(), (v as f32).to_bits(), "{v}");
        }
        assert_eq!(bit_len64(1 << 40), 41);
        assert_eq!(bit_len64(0), 0);
    }

    #[test]
    fn conversions_scale_exactly() {
        assert_eq!(scaled_f32(3, 1), 1.5);
        assert_eq!(scaled_f32(-(1 << 20), 20), -1.0);
        assert_eq!(scaled_f32(0, 7), 0.0);
        assert_eq!(scaled_f32_i64(-(1i64 << 40), 40), -1.0);
        assert_eq!(to_fixed(1.0, 23), 1 << 23);
        assert_eq!(to_fixed(-2.5, 0), -3);
        assert_eq!(to_fixed(2.5, 0), 3);
        assert_eq!(to_fixed(f32::NAN, 10), 0);
        assert_eq!(to_fixed(1e30, 10), i32::MAX);
        assert_eq!(to_fixed(-1e30, 0), i32::MIN);
        assert_eq!(to_fixed(f32::INFINITY, 0), i32::MAX);
        assert_eq!(to_fixed(1e-40, 10), 0);
        assert_eq!(to_fixed(0.1, 20), 104_858);
    }

    #[test]
    fn cordic_atan2_matches_libm() {
        let scale = f64::from(1u32 << 28);
        for i in 0..720 {
            let a = f64::from(i) * 0.5f64.to_radians() - core::f64::consts::PI;
            for r in [1.0, 0.3, 0.01] {
                let (x, y) = (
                    (libm::cos(a) * r * scale) as i32,
                    (libm::sin(a) * r * scale) as i32,
                );
                let (z, m) = atan2_q29(y, x);
                let expect = libm::atan2(f64::from(y), f64::from(x));
                let got = f64::from(z) / f64::from(1u32 << 29);
                let mut d = got - expect;
                if d > core::f64::consts::PI {
                    d -= core::f64::consts::TAU;
                }
                if d < -core::f64::consts::PI {
                    d += core::f64::consts::TAU;
                }
                assert!(d.abs() < 5e-8 / r, "{a} {r}: {got} vs {expect}");
                let mag = libm::hypot(f64::from(x), f64::from(y)) * f64::from(CORDIC_GAIN_Q30)
                    / f64::from(1u32 << 30);
                assert!((f64::from(m) - mag).abs() < 40.0, "{m} vs {mag}");
            }
        }
        assert_eq!(atan2_q29(0, 0).0, 0);
        for i in -90..=90 {
            let a = f64::from(i).to_radians();
            let (sn, cs) = sin_cos_q30((a * f64::from(1u32 << 29)) as i32);
            let k = f64::from(1u32 << 30);
            assert!((f64::from(sn) / k - libm::sin(a)).abs() < 2e-8, "{i}");
            assert!((f64::from(cs) / k - libm::cos(a)).abs() < 2e-8, "{i}");
        }
    }
}
