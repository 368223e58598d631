//! Output fields — the building blocks shared by the fixed formats (ICD
//! Tables 5.5–5.12) and the UDD types (Table 5.15). A format is a list of
//! fields; a UDD type is one field. Scaling and saturation live here, once.

use crate::model::Product;
use crate::sensor::Sample;

/// LSB per deg/s of the high-resolution rate fields (Tables 5.7–5.12: deg/s·10⁵).
pub(crate) const RATE_HR_SCALE: u32 = 100_000;
/// LSB per g of the high-resolution acceleration fields (Tables 5.7–5.12: g·10⁶).
pub(crate) const ACC_HR_SCALE: u32 = 1_000_000;
/// LSB per degree of the 16-bit angles (Tables 5.5, 5.9: deg·100).
pub(crate) const ANGLE_SCALE: u32 = 100;
/// LSB per degree of the 32-bit angles (Table 5.10: deg·1000).
pub(crate) const ANGLE_HR_SCALE: u32 = 1000;
/// LSB per unit of the quaternion components (Table 5.9: ·10⁴).
pub(crate) const QUAT_SCALE: u32 = 10_000;
/// LSB per °C of the temperature (Tables 5.5–5.12, UDD 0x52: °C·10).
pub(crate) const TEMPERATURE_SCALE: u32 = 10;
/// LSB per volt of the supply voltage (UDD 0x50: VDC·100).
pub(crate) const VOLTAGE_SCALE: u32 = 100;

/// Everything an output frame can carry at one output instant.
#[derive(Debug, Clone, Copy)]
pub struct OutputCtx<'a> {
    /// The measured (and processed) data.
    pub sample: &'a Sample,
    /// The product (KG/KA scale factors, Table 5.6).
    pub product: &'a Product,
    /// 2 kHz computation counter (Tables 5.7, 5.10, note 3), wrapping.
    pub counter: u16,
    /// Unit Status Word (5.4, Table 5.26).
    pub usw: u16,
    /// Extended Unit Status Word (Table 5.27).
    pub usw_ext: u16,
    /// GAm/GAAm time flags (0x0001 1PPS since last frame, 0x0008 no 1PPS > 1 s).
    pub time_flags: u16,
    /// Second fraction, ns (5.2.3.1).
    pub second_fraction_ns: u32,
    /// IMU time, ns since power-on (UDD 0x02).
    pub imu_time_ns: u64,
}

/// One field of an output payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// Heading u16, pitch i16, roll i16 in deg·100 (Tables 5.5, 5.9; UDD 0x07).
    Euler,
    /// Heading, pitch, roll as 32-bit deg·1000 (Table 5.10; UDD 0x08).
    EulerHr,
    /// q0..q3 as i16 ·10⁴ (Table 5.9; UDD 0x09).
    Quat,
    /// Gyro X/Y/Z as i16 deg/s·KG (Table 5.5; UDD 0x20).
    Gyro,
    /// Gyro X/Y/Z as i32 deg/s·10⁵ (Tables 5.7–5.12; UDD 0x21).
    GyroHr,
    /// Accel X/Y/Z as i16 g·KA (Table 5.5; UDD 0x22).
    Acc,
    /// Accel X/Y/Z as i32 g·10⁶ (Tables 5.7–5.12; UDD 0x23).
    AccHr,
    /// Aux accel X/Y/Z as i32 g·10⁶ (Tables 5.11, 5.12; UDD 0x2F).
    AuxAccHr,
    /// Bias-compensated, cascade-filtered gyro, i32 deg/s·10⁵ (UDD 0x2D).
    GyroBiasCompHr,
    /// Estimated gyro bias, i32 deg/s·10⁵ (UDD 0x2E).
    GyroBiasHr,
    /// Cascade-filtered low-g accel, i32 g·10⁶ (UDD 0x91).
    FilteredAccHr,
    /// Cascade-filtered high-g accel, i32 g·10⁶ (UDD 0x92).
    FilteredAuxAccHr,
    /// `n` zero bytes (reserved fields, magnetometer "always 0").
    Zero(u8),
    /// Unit Status Word, u16 (5.4; UDD 0x53).
    Usw,
    /// Extended USW, u16 (Table 5.27; UDD 0x5B).
    UswExt,
    /// 2 kHz counter, u16.
    Counter,
    /// Temperature, i16 °C·10 (UDD 0x52).
    Temperature,
    /// Time flags, u16 (Table 5.8 note 2).
    TimeFlags,
    /// Second fraction, u32 ns (5.2.3.1; UDD 0x05).
    SecondFraction,
    /// IMU time, u64 ns since power-on (UDD 0x02).
    ImuTime,
    /// Supply voltage, u16 VDC·100 (UDD 0x50).
    SupplyVoltage,
}

/// `x · k` rounded to the nearest integer, halves away from zero, computed
/// exactly: the f32 is split into its 24-bit mantissa and exponent and the
/// mantissa multiplied by the integer scale in 64 bits (one `UMULL` on a
/// Cortex-M4), so no float arithmetic runs (the M4F's FPU is single
/// precision; f64 would be software) and the result is the same on every
/// platform. NaN gives 0; ±∞ and huge values give a magnitude beyond any
/// field, which the callers saturate. (The field writers' saturating forms
/// take one exact `f64` product on hosts instead: the same results.)
pub fn scale_round(x: f32, k: u32) -> i64 {
    if x.is_infinite() {
        return if x < 0.0 { i64::MIN } else { i64::MAX };
    }
    let magnitude = scaled_magnitude(x, k).min(1 << 62) as i64;
    if x.is_sign_negative() {
        -magnitude
    } else {
        magnitude
    }
}

/// `|x| · k` rounded half up, exactly ([`scale_round`]'s magnitude): NaN
/// gives 0, ∞ and products of 2^62 or more give at least 2^62.
// Out of line in the `fixed-point` build (RP2040 flash, like the helpers
// of `math::fixed`): 0.6 KiB less for a call per output value.
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
fn scaled_magnitude(x: f32, k: u32) -> u64 {
    let bits = x.to_bits();
    let exp = (bits >> 23) & 0xFF;
    let frac = bits & 0x7F_FFFF;
    if exp == 0xFF {
        return if frac != 0 { 0 } else { 1 << 62 };
    }
    // |x| = m · 2^(biased − 150) exactly (subnormals: biased 1, no
    // implicit bit).
    let (m, biased) = if exp == 0 {
        (frac, 1)
    } else {
        (frac | 0x80_0000, exp)
    };
    let p = u64::from(m) * u64::from(k); // < 2^56
    if biased <= 150 {
        // Right by s = 150 − biased, rounding half up:
        // (p + 2^(s−1)) >> s = ((p >> (s−1)) + 1) >> 1.
        match 150 - biased {
            0 => p,
            s @ 1..=60 => ((p >> (s - 1)) + 1) >> 1,
            _ => 0,
        }
    } else {
        match biased - 150 {
            e @ 1..=6 => p << e,
            _ => 1 << 62,
        }
    }
}

/// [`scaled_magnitude`] on the FPU when the single-precision product
/// decides it, else `None`. `a = fl(|x|·k)` is within half an ulp of the
/// exact product (`k < 2^24` is exact in f32), and half an ulp is at most
/// `a · 2^-24`; below 2^23 the fraction `f = a − ⌊a⌋` is exact. If `f` is
/// farther than that from ½, the exact product lies on the same side of the
/// half-integer and rounds like `a`; otherwise the integer path decides.
#[cfg(not(feature = "fixed-point"))]
#[inline(always)]
fn fast_magnitude(x: f32, k: u32) -> Option<u32> {
    if k >= 1 << 24 {
        return None;
    }
    let a = x.abs() * k as f32;
    if a < 8_388_608.0 {
        let n = a as u32;
        let f = a - n as f32;
        if (f - 0.5).abs() > a * (1.0 / 16_777_216.0) {
            return Some(n + u32::from(f > 0.5));
        }
    }
    None
}

/// Without an FPU (`fixed-point`) float products are library calls: the
/// integer path always.
#[cfg(feature = "fixed-point")]
#[inline(always)]
fn fast_magnitude(_x: f32, _k: u32) -> Option<u32> {
    None
}

/// Scales below this take [`sat_signed`]'s `f64` path on hosts.
const F64_SCALE_LIMIT: u32 = 1 << 28;

/// `|x| · k` (see [`scale_round`]) with the sign of `x`, saturated at
/// `-lo_limit` and `hi_limit`, on a host (a double-precision FPU): one
/// `f64` product, `+ 0.5`, truncation. Exact for 2 ≤ `k <` 2^28: the product
/// of the 24-bit mantissa and `k` has at most 52 significant bits, so it
/// is exact, and so is the sum when `|x|·k ≥ ¼` (at most 53 bits); below
/// ¼ the sum is below ¾ whatever its rounding and truncates to 0, as it
/// should. NaN truncates to 0 and ∞ or a huge product to `i64::MAX`
/// (Rust's saturating casts), which the limits then clip: the same
/// results as the integer path, which larger scales take
/// (`scale_round_is_exact`, `the_f64_path_is_the_integer_path`).
/// Firmware takes the integer path (with the M4F's `f32` fast path) for
/// every scale.
#[inline(always)]
fn sat_signed(x: f32, k: u32, lo_limit: u32, hi_limit: u32) -> i32 {
    // Scales 0 and 1 too: the integer path saturates every |x| ≥ 2^30,
    // which for them is not beyond every field.
    // Fork: no f64 FPU on firmware; the f64 path measured M4F on_tick 5 080 → 20 040 (largest UDD).
    if cfg!(target_os = "none") || !(2..F64_SCALE_LIMIT).contains(&k) {
        return sat_signed_int(x, k, lo_limit, hi_limit);
    }
    let m = (f64::from(x.abs()) * f64::from(k) + 0.5) as i64;
    // Without a branch on the sign (a noisy value's sign is random): all
    // ones for a negative `x`, the limit of its sign, then a conditional
    // negation (−2^31 wraps to itself: i32::MIN).
    let neg = (x.to_bits() as i32) >> 31;
    let limit = hi_limit ^ ((hi_limit ^ lo_limit) & neg as u32);
    let r = m.min(i64::from(limit)) as i32;
    (r ^ neg).wrapping_sub(neg)
}

/// `|x| · k` (see [`scale_round`]) with the sign of `x`, saturated at
/// `-lo_limit` and `hi_limit`: the callers' saturation without 64-bit
/// signed compares, by [`fast_magnitude`] and [`scaled_magnitude`]
/// (on firmware for every scale; on hosts for the scales beyond the
/// `f64` path).
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline(always))]
fn sat_signed_int(x: f32, k: u32, lo_limit: u32, hi_limit: u32) -> i32 {
    // Zero and subnormals (|x·k| < 2^-94) round to 0 (most often an
    // output the model does not have).
    if x.to_bits() & 0x7F80_0000 == 0 {
        return 0;
    }
    let m = match fast_magnitude(x, k) {
        Some(m) => m,
        None => scaled_magnitude(x, k).min(1 << 31) as u32,
    };
    if x.is_sign_negative() {
        // −2^31 wraps to itself: i32::MIN.
        (m.min(lo_limit) as i32).wrapping_neg()
    } else {
        m.min(hi_limit) as i32
    }
}

/// `x · k`, rounded (see [`scale_round`]), saturated at the i32 limits.
pub(crate) fn sat_i32(x: f32, k: u32) -> i32 {
    sat_signed(x, k, 1 << 31, i32::MAX as u32)
}

/// `x · k`, rounded (see [`scale_round`]), saturated at the i16 limits.
pub(crate) fn sat_i16(x: f32, k: u32) -> i16 {
    sat_signed(x, k, 1 << 15, i16::MAX as u32) as i16
}

/// `x · k`, rounded (see [`scale_round`]), saturated at the u16 limits.
pub(crate) fn sat_u16(x: f32, k: u32) -> u16 {
    sat_signed(x, k, 0, u32::from(u16::MAX)) as u16
}

/// Heading in [0, 360) degrees (the f32 remainder is exact).
fn heading_0_360(h: f32) -> f32 {
    let h = crate::math::rotation::small_rem(h, 360.0);
    if h < 0.0 {
        h + 360.0
    } else {
        h
    }
}

/// Heading `h` degrees as the field integer `h · k` (see [`scale_round`])
/// in [0, 360·k): the heading of the Euler fields (Tables 5.5, 5.9, 5.10,
/// UDD 0x07, 0x08) is 0 up to below 360. A heading just below 360 (or a
/// tiny negative one, which `+ 360` rounds to 360.0 in `f32`) rounds to
/// 360·k, which is 0: wrapped in the integers, where the wrap is exact.
pub(crate) fn heading_code(h: f32, k: u32) -> u32 {
    let full = 360 * k;
    let n = sat_signed(heading_0_360(h), k, 0, full) as u32;
    if n >= full {
        n - full
    } else {
        n
    }
}

/// Three [`sat_i32`] values (the saturation inlined: one call a triad;
/// in line, where the fixed formats' writers fold `out`'s length).
#[inline(always)]
fn put3_i32(out: &mut [u8], v: &[f32; 3], k: u32) {
    for (c, &x) in out.chunks_exact_mut(4).zip(v) {
        c.copy_from_slice(&sat_signed(x, k, 1 << 31, i32::MAX as u32).to_le_bytes());
    }
}

/// Three [`sat_i16`] values (the saturation inlined: one call a triad;
/// in line, as [`put3_i32`]).
#[inline(always)]
fn put3_i16(out: &mut [u8], v: &[f32; 3], k: u32) {
    for (c, &x) in out.chunks_exact_mut(2).zip(v) {
        let y = sat_signed(x, k, 1 << 15, i16::MAX as u32) as i16;
        c.copy_from_slice(&y.to_le_bytes());
    }
}

impl Field {
    /// Size in bytes (Table 5.15 "Size"; out of line in the `fixed-point`
    /// build, RP2040 flash).
    #[cfg_attr(feature = "fixed-point", inline(never))]
    #[cfg_attr(not(feature = "fixed-point"), inline(always))]
    pub const fn size(self) -> usize {
        match self {
            Field::Euler => 6,
            Field::EulerHr => 12,
            Field::Quat => 8,
            Field::Gyro | Field::Acc => 6,
            Field::GyroHr
            | Field::AccHr
            | Field::AuxAccHr
            | Field::GyroBiasCompHr
            | Field::GyroBiasHr
            | Field::FilteredAccHr
            | Field::FilteredAuxAccHr => 12,
            Field::Zero(n) => n as usize,
            Field::Usw
            | Field::UswExt
            | Field::Counter
            | Field::Temperature
            | Field::TimeFlags
            | Field::SupplyVoltage => 2,
            Field::SecondFraction => 4,
            Field::ImuTime => 8,
        }
    }

    /// Whether the field carries the orientation ([`Sample::euler`],
    /// [`Sample::quat`]).
    pub const fn is_attitude(self) -> bool {
        matches!(self, Field::Euler | Field::EulerHr | Field::Quat)
    }

    /// Writes the field into `out[..self.size()]`; returns the size, or 0
    /// if `out` is too short (nothing written).
    pub fn write(self, ctx: &OutputCtx<'_>, out: &mut [u8]) -> usize {
        let n = self.size();
        match out.get_mut(..n) {
            Some(out) => {
                self.write_exact(ctx, out);
                n
            }
            None => 0,
        }
    }

    /// Writes the field into `out`, which is [`Field::size`] bytes long.
    fn write_exact(self, ctx: &OutputCtx<'_>, out: &mut [u8]) {
        self.write_exact_inline(ctx, out)
    }

    /// [`Field::write`] inlined: with a constant field (the fixed formats'
    /// writers, [`crate::kernel::formats`]) the dispatch and the scales
    /// fold away.
    #[inline(always)]
    pub(crate) fn write_inline(self, ctx: &OutputCtx<'_>, out: &mut [u8]) -> Option<usize> {
        let n = self.size();
        self.write_exact_inline(ctx, out.get_mut(..n)?);
        Some(n)
    }

    /// [`Field::write_exact`]'s body.
    #[inline(always)]
    fn write_exact_inline(self, ctx: &OutputCtx<'_>, out: &mut [u8]) {
        let s = ctx.sample;
        // The triads first, through one call site of each writer (so
        // that it can be inlined once).
        let triad = match self {
            Field::Gyro => Some((&s.gyro, ctx.product.gyro().kg(), false)),
            Field::GyroHr => Some((&s.gyro, RATE_HR_SCALE, true)),
            Field::Acc => Some((&s.acc, ctx.product.accel().ka(), false)),
            Field::AccHr => Some((&s.acc, ACC_HR_SCALE, true)),
            Field::AuxAccHr => Some((&s.aux_acc, ACC_HR_SCALE, true)),
            Field::GyroBiasCompHr => Some((&s.gyro_filtered, RATE_HR_SCALE, true)),
            Field::GyroBiasHr => Some((&s.gyro_bias, RATE_HR_SCALE, true)),
            Field::FilteredAccHr => Some((&s.acc_filtered, ACC_HR_SCALE, true)),
            Field::FilteredAuxAccHr => Some((&s.aux_acc_filtered, ACC_HR_SCALE, true)),
            _ => None,
        };
        if let Some((v, k, wide)) = triad {
            if wide {
                put3_i32(out, v, k);
            } else {
                put3_i16(out, v, k);
            }
            return;
        }
        match self {
            Field::Euler => {
                out[0..2]
                    .copy_from_slice(&(heading_code(s.euler[0], ANGLE_SCALE) as u16).to_le_bytes());
                out[2..4].copy_from_slice(&sat_i16(s.euler[1], ANGLE_SCALE).to_le_bytes());
                out[4..6].copy_from_slice(&sat_i16(s.euler[2], ANGLE_SCALE).to_le_bytes());
            }
            Field::EulerHr => {
                out[0..4].copy_from_slice(
                    &(heading_code(s.euler[0], ANGLE_HR_SCALE) as i32).to_le_bytes(),
                );
                out[4..8].copy_from_slice(&sat_i32(s.euler[1], ANGLE_HR_SCALE).to_le_bytes());
                out[8..12].copy_from_slice(&sat_i32(s.euler[2], ANGLE_HR_SCALE).to_le_bytes());
            }
            Field::Quat => {
                for (c, q) in out.chunks_exact_mut(2).zip(s.quat) {
                    c.copy_from_slice(&sat_i16(q, QUAT_SCALE).to_le_bytes());
                }
            }
            Field::Zero(_) => out.fill(0),
            Field::Usw => out.copy_from_slice(&ctx.usw.to_le_bytes()),
            Field::UswExt => out.copy_from_slice(&ctx.usw_ext.to_le_bytes()),
            Field::Counter => out.copy_from_slice(&ctx.counter.to_le_bytes()),
            Field::Temperature => {
                out.copy_from_slice(&sat_i16(s.temperature, TEMPERATURE_SCALE).to_le_bytes())
            }
            Field::TimeFlags => out.copy_from_slice(&ctx.time_flags.to_le_bytes()),
            Field::SecondFraction => out.copy_from_slice(&ctx.second_fraction_ns.to_le_bytes()),
            Field::ImuTime => out.copy_from_slice(&ctx.imu_time_ns.to_le_bytes()),
            Field::SupplyVoltage => {
                out.copy_from_slice(&sat_u16(s.supply_voltage, VOLTAGE_SCALE).to_le_bytes())
            }
            // The triads, written above.
            _ => {}
        }
    }
}

/// Total size of a field list.
pub fn payload_len(fields: &[Field]) -> usize {
    fields.iter().map(|f| f.size()).sum()
}

/// Writes a field list into `out`; returns the bytes written, or `None` if
/// `out` is too short.
pub fn write_all(fields: &[Field], ctx: &OutputCtx<'_>, out: &mut [u8]) -> Option<usize> {
    let mut at = 0;
    for f in fields {
        // The writer in line, one dispatch a field (UDD).
        at += f.write_inline(ctx, out.get_mut(at..)?)?;
    }
    Some(at)
}

/// The scale factors of the 16-bit gyro and accelerometer fields, which
/// depend on the product's ranges (Table 5.6: KG, KA).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scales {
    /// KG: LSB per deg/s of [`Field::Gyro`].
    pub kg: u32,
    /// KA: LSB per g of [`Field::Acc`].
    pub ka: u32,
}

impl Scales {
    /// The scales `product` encodes with (Table 5.6).
    pub const fn of(product: &Product) -> Scales {
        Scales {
            kg: product.gyro().kg(),
            ka: product.accel().ka(),
        }
    }
}

/// A field's value decoded from the wire ([`Field::read`]), in the ICD's
/// units: each is the `f64` nearest to the transmitted integer divided by
/// the field's scale (exact enough that the integer is recovered by
/// multiplying back and rounding).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// Heading, pitch, roll in degrees ([`Field::Euler`],
    /// [`Field::EulerHr`]; heading as sent, 0 up to below 360).
    Angles([f64; 3]),
    /// Quaternion q0..q3 ([`Field::Quat`], Appendix C.3).
    Quat([f64; 4]),
    /// Angular rate X/Y/Z in deg/s ([`Field::Gyro`], [`Field::GyroHr`],
    /// [`Field::GyroBiasCompHr`], [`Field::GyroBiasHr`]).
    Rate([f64; 3]),
    /// Specific force X/Y/Z in g ([`Field::Acc`], [`Field::AccHr`],
    /// [`Field::AuxAccHr`], [`Field::FilteredAccHr`],
    /// [`Field::FilteredAuxAccHr`]; 1 g = 9.8106 m/s², ICD 5.2.1).
    Accel([f64; 3]),
    /// Reserved bytes ([`Field::Zero`]): nothing to report.
    Reserved,
    /// A 16-bit word as sent: [`Field::Usw`], [`Field::UswExt`] (bits of
    /// Tables 5.26, 5.27), [`Field::Counter`] (2 kHz ticks, wrapping),
    /// [`Field::TimeFlags`] (Table 5.8 note 2).
    Word(u16),
    /// Temperature in °C ([`Field::Temperature`]).
    Celsius(f64),
    /// A time in nanoseconds: [`Field::SecondFraction`] (since the last
    /// 1PPS, 5.2.3.1), [`Field::ImuTime`] (since power-on).
    Nanos(u64),
    /// Supply voltage in volts ([`Field::SupplyVoltage`]).
    Volts(f64),
}

#[inline(always)]
fn i32_at<const N: usize>(b: &[u8; N], i: usize) -> i32 {
    i32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

#[inline(always)]
fn i16_at<const N: usize>(b: &[u8; N], i: usize) -> i16 {
    i16::from_le_bytes([b[i], b[i + 1]])
}

#[inline(always)]
fn u16_at<const N: usize>(b: &[u8; N], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

/// Three i32 values over `k`.
#[inline(always)]
fn get3_i32(b: &[u8; 12], k: u32) -> [f64; 3] {
    let k = f64::from(k);
    [
        f64::from(i32_at(b, 0)) / k,
        f64::from(i32_at(b, 4)) / k,
        f64::from(i32_at(b, 8)) / k,
    ]
}

/// Three i16 values over `k`.
#[inline(always)]
fn get3_i16(b: &[u8; 6], k: u32) -> [f64; 3] {
    let k = f64::from(k);
    [
        f64::from(i16_at(b, 0)) / k,
        f64::from(i16_at(b, 2)) / k,
        f64::from(i16_at(b, 4)) / k,
    ]
}

impl Field {
    /// Decodes the field from `bytes[..self.size()]` — the inverse of the
    /// writer, with the same scales (the constants above, `scales` for the
    /// 16-bit gyro and accelerometer); `None` if `bytes` is too short.
    // Each arm reads a fixed-size array: its offsets need no checks.
    #[inline(always)]
    pub fn read(self, scales: Scales, bytes: &[u8]) -> Option<Value> {
        Some(match self {
            Field::Euler => {
                let b = bytes.first_chunk::<6>()?;
                Value::Angles([
                    f64::from(u16_at(b, 0)) / f64::from(ANGLE_SCALE),
                    f64::from(i16_at(b, 2)) / f64::from(ANGLE_SCALE),
                    f64::from(i16_at(b, 4)) / f64::from(ANGLE_SCALE),
                ])
            }
            Field::EulerHr => Value::Angles(get3_i32(bytes.first_chunk()?, ANGLE_HR_SCALE)),
            Field::Quat => {
                let b = bytes.first_chunk::<8>()?;
                let k = f64::from(QUAT_SCALE);
                Value::Quat([
                    f64::from(i16_at(b, 0)) / k,
                    f64::from(i16_at(b, 2)) / k,
                    f64::from(i16_at(b, 4)) / k,
                    f64::from(i16_at(b, 6)) / k,
                ])
            }
            Field::Gyro => Value::Rate(get3_i16(bytes.first_chunk()?, scales.kg)),
            Field::Acc => Value::Accel(get3_i16(bytes.first_chunk()?, scales.ka)),
            Field::GyroHr | Field::GyroBiasCompHr | Field::GyroBiasHr => {
                Value::Rate(get3_i32(bytes.first_chunk()?, RATE_HR_SCALE))
            }
            Field::AccHr | Field::AuxAccHr | Field::FilteredAccHr | Field::FilteredAuxAccHr => {
                Value::Accel(get3_i32(bytes.first_chunk()?, ACC_HR_SCALE))
            }
            Field::Zero(n) => {
                bytes.get(..usize::from(n))?;
                Value::Reserved
            }
            Field::Usw | Field::UswExt | Field::Counter | Field::TimeFlags => {
                Value::Word(u16::from_le_bytes(*bytes.first_chunk()?))
            }
            Field::Temperature => Value::Celsius(
                f64::from(i16::from_le_bytes(*bytes.first_chunk()?)) / f64::from(TEMPERATURE_SCALE),
            ),
            Field::SecondFraction => {
                Value::Nanos(u64::from(u32::from_le_bytes(*bytes.first_chunk()?)))
            }
            Field::ImuTime => Value::Nanos(u64::from_le_bytes(*bytes.first_chunk()?)),
            Field::SupplyVoltage => Value::Volts(
                f64::from(u16::from_le_bytes(*bytes.first_chunk()?)) / f64::from(VOLTAGE_SCALE),
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Heading is sent in [0, 360) (docs/kernel.md): at the wrap, where a
    /// heading a hair below 360 or below 0 used to round to 360.00/360.000,
    /// both Euler fields write 0, and a heading just past the rounding
    /// boundary keeps its last step below 360.
    #[test]
    fn heading_at_the_wrap_reads_below_360() {
        let product = Product::parse("K110").unwrap();
        let sc = Scales::of(&product);
        // (heading, deg·100 sent, deg·1000 sent)
        let cases: [(f32, u32, u32); 11] = [
            (0.0, 0, 0),
            (-0.0, 0, 0),
            (-1e-7, 0, 0),
            (-0.0004, 0, 0),
            (-0.0006, 0, 359_999),
            (359.9996, 0, 0),
            (359.9994, 0, 359_999),
            (359.994, 35_999, 359_994),
            (360.0, 0, 0),
            (-360.0, 0, 0),
            (f32::NAN, 0, 0),
        ];
        for (h, lo, hr) in cases {
            let mut s = Sample::STATIC_LEVEL;
            s.euler = [h, 0.0, 0.0];
            let ctx = OutputCtx {
                sample: &s,
                product: &product,
                counter: 0,
                usw: 0,
                usw_ext: 0,
                time_flags: 0,
                second_fraction_ns: 0,
                imu_time_ns: 0,
            };
            let mut b = [0u8; 12];
            assert_eq!(Field::Euler.write(&ctx, &mut b), 6);
            assert_eq!(
                u32::from(u16::from_le_bytes([b[0], b[1]])),
                lo,
                "{h} deg·100"
            );
            let Some(Value::Angles(a)) = Field::Euler.read(sc, &b) else {
                panic!("Euler reads angles")
            };
            assert!((0.0..360.0).contains(&a[0]), "{h}: {}", a[0]);
            assert_eq!(Field::EulerHr.write(&ctx, &mut b), 12);
            assert_eq!(
                i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u32,
                hr,
                "{h} deg·1000"
            );
            let Some(Value::Angles(a)) = Field::EulerHr.read(sc, &b) else {
                panic!("EulerHr reads angles")
            };
            assert!((0.0..360.0).contains(&a[0]), "{h}: {}", a[0]);
        }
    }

    /// The reference: the exact product in f64 (a 24-bit mantissa times a
    /// scale below 2^20 is exact in f64), rounded half away from zero.
    fn reference(x: f32, k: u32) -> i64 {
        let p = f64::from(x) * f64::from(k);
        let r = if p >= 0.0 {
            (p + 0.5).floor()
        } else {
            -((-p + 0.5).floor())
        };
        r as i64
    }

    #[test]
    fn scale_round_is_exact() {
        let mut state = 0x1234_5678_9ABC_DEF0u64;
        let scales = [
            10, 20, 50, 100, 500, 1000, 2000, 4000, 10_000, 100_000, 1_000_000,
        ];
        for i in 0..200_000u32 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            // Mostly ordinary magnitudes, some ties and tiny numbers.
            let x = match i % 4 {
                0 => f32::from_bits((state >> 32) as u32) % 5000.0,
                1 => ((state >> 40) as i32 as f32) / 65536.0,
                2 => ((state >> 48) as i32 as f32 + 0.5) / 100.0,
                _ => f32::from_bits(((state >> 32) as u32) & 0x3FFF_FFFF) * 1e-3,
            };
            if !x.is_finite() {
                continue;
            }
            for &k in &scales {
                let r = reference(x, k);
                assert_eq!(scale_round(x, k), r, "{x:e} x {k}");
                // The saturating forms (their FPU fast path included).
                let clamp = |lo: i64, hi: i64| r.clamp(lo, hi);
                assert_eq!(
                    i64::from(sat_i32(x, k)),
                    clamp(i32::MIN.into(), i32::MAX.into())
                );
                assert_eq!(
                    i64::from(sat_i16(x, k)),
                    clamp(i16::MIN.into(), i16::MAX.into())
                );
                assert_eq!(i64::from(sat_u16(x, k)), clamp(0, u16::MAX.into()));
            }
        }
        assert_eq!(scale_round(0.5, 1), 1);
        assert_eq!(scale_round(-0.5, 1), -1);
        assert_eq!(scale_round(0.499_999_97, 1), 0);
        assert_eq!(scale_round(f32::NAN, 100), 0);
        assert_eq!(sat_i32(f32::INFINITY, 10), i32::MAX);
        assert_eq!(sat_i16(f32::NEG_INFINITY, 10), i16::MIN);
        assert_eq!(sat_i32(3.0e38, 1_000_000), i32::MAX);
        assert_eq!(sat_u16(-5.0, 100), 0);
        assert_eq!(sat_i32(1e-40, 1_000_000), 0);
    }

    /// The host's `f64` path of [`sat_signed`] gives the integer path's
    /// result for every exponent (subnormals, ∞ and NaN included), both
    /// signs, the mantissas next to the rounding ties, and every scale a
    /// field uses plus the largest the path takes.
    #[test]
    fn the_f64_path_is_the_integer_path() {
        let scales = [
            0,
            1,
            2,
            3,
            7,
            10,
            20,
            50,
            100,
            500,
            1000,
            2000,
            4000,
            10_000,
            100_000,
            1_000_000,
            (1 << 24) - 1,
            1 << 24,
            F64_SCALE_LIMIT - 1,
            F64_SCALE_LIMIT,
        ];
        let limits = [
            (1u32 << 31, i32::MAX as u32),
            (1 << 15, i16::MAX as u32),
            (0, u32::from(u16::MAX)),
        ];
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let check = |bits: u32| {
            let x = f32::from_bits(bits);
            for &k in &scales {
                for &(lo, hi) in &limits {
                    assert_eq!(
                        sat_signed(x, k, lo, hi),
                        sat_signed_int(x, k, lo, hi),
                        "{x:e} ({bits:#010x}) x {k}"
                    );
                }
            }
        };
        for exp in 0..=255u32 {
            for _ in 0..32 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let frac = (state >> 41) as u32;
                for sign in [0, 1u32 << 31] {
                    check(sign | exp << 23 | frac);
                    // Few low bits set or clear: products at or next to
                    // a half-integer.
                    check(sign | exp << 23 | (frac & 0x7F_F000));
                    check(sign | exp << 23 | (frac | 0xFFF));
                    check(sign | exp << 23 | (frac & 0x7F_F000).wrapping_sub(1) & 0x7F_FFFF);
                }
            }
        }
        // Exact ties and their neighbours for the scales of the fields.
        for &k in &scales[3..16] {
            for n in 0..20_000u32 {
                let x = (n as f32 + 0.5) / k as f32;
                for d in [-1i32, 0, 1] {
                    check(x.to_bits().wrapping_add(d as u32));
                    check((-x).to_bits().wrapping_add(d as u32));
                }
            }
        }
    }
}
