//! The sensor's own −3 dB bandwidth (a profile's `bandwidth_hz`,
//! docs/sensors.md "Bandwidth"): a first-order low-pass per axis at the
//! chain's internal rate, applied by the error engines to the sensor's
//! output (noise included) before the chain's FIR (ICD 5.6).
//!
//! **Order.** First order: a MEMS datasheet's "−3 dB bandwidth" is the
//! corner of the sensor's (mostly single-pole) response, and one pole is
//! the model that adds nothing the datasheet does not give (no Q, no second
//! corner).
//!
//! **Discretisation.** Bilinear with prewarp: `K = tan(π·f_c/f_s)`,
//! `b = K/(1+K)`, and
//!
//! ```text
//! y[n] = y[n−1] + b·(x[n] + x[n−1] − 2·y[n−1])
//! ```
//!
//! which is `H(z) = b·(1 + z⁻¹)/(1 − (1 − 2b)·z⁻¹)`: −3 dB exactly at
//! `f_c` for any `f_c` below Nyquist (exact pole mapping puts it 10 % off
//! at the IMX-5's 539 Hz at 2 kHz), a zero at Nyquist, and a DC gain of
//! exactly 1 in this form (a constant input is a fixed point of the step),
//! so the white-noise density at DC, what an Allan plot reads, is
//! unchanged. The filter is off for `f_c` ≤ 0 (a profile's "not given")
//! and for `f_c` ≥ f_s/2 (beyond what the internal rate can represent).
//! The first sample primes the state (no power-on transient from zero).
//!
//! **Fixed point** ([`SensorLowPassFixed`]): the same step on a state with
//! [`STATE_BITS`] fraction bits and `b = m·2^−s` with a [`COEF_BITS`]-bit
//! mantissa (as precise as the float build's `f32`, so the two agree to the
//! output's LSB; `b` at least 2^−15, so a bandwidth below ≈ f_s·2⁻¹⁵/π,
//! 0.019 Hz at 2 kHz, is raised to it), the product rounded to nearest.
//! A constant input converges to within 1/(4b) ≤ 2¹³ state units (¼ LSB
//! of the output) and stays there (the step rounds to 0), so the output
//! equals the input exactly: DC gain 1, no bias from rounding. (The `f32`
//! step stalls within ulp(y)/(4·min(b, 1 − b)) of a constant, 1e-5 of it
//! at 1 Hz and 2 kHz: the float build's rounding, unbiased on noise.) The
//! input is any `i32` (the IMX-5's ±4000 °/s is 0.98·2³¹ at
//! `GYRO_BITS`): every intermediate fits an `i64` for |x| ≤ 2³¹ (bounds
//! at [`SensorLowPassFixed::apply`]).

// The three axes' states are parallel arrays indexed by one index.
#![allow(clippy::needless_range_loop)]

/// Fraction bits of the fixed-point filter's state.
pub const STATE_BITS: u32 = 15;
/// Bits of the fixed-point coefficient's mantissa: `b = m·2^−s`,
/// 2²⁹ ≤ m < 2³⁰ (as precise as the float build's `f32`).
pub const COEF_BITS: u32 = 30;
/// The smallest fixed-point coefficient, 2^−15: a constant then settles
/// within ¼ LSB (module doc).
const MIN_SHIFT: u32 = COEF_BITS + 15;

/// The filter's coefficient `b = K/(1+K)`, `K = tan(π·f_c·dt)`, for a
/// bandwidth of `bandwidth_hz` at ticks of `dt` s; `None` (no filter) for a
/// bandwidth ≤ 0, NaN, or at or above the Nyquist frequency 1/(2·dt).
pub fn coefficient(bandwidth_hz: f32, dt: f32) -> Option<f64> {
    let x = f64::from(bandwidth_hz) * f64::from(dt);
    if !(x > 0.0 && x < 0.5) {
        return None;
    }
    let k = libm::tan(core::f64::consts::PI * x);
    Some(k / (1.0 + k))
}

/// The sensor low-pass of one triad in `f32` (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct SensorLowPass {
    /// `b`; 0 = off.
    b: f32,
    /// Output of the last tick.
    y: [f32; 3],
    /// Input of the last tick.
    x: [f32; 3],
    primed: bool,
}

impl SensorLowPass {
    /// No filter.
    pub const OFF: SensorLowPass = SensorLowPass {
        b: 0.0,
        y: [0.0; 3],
        x: [0.0; 3],
        primed: false,
    };

    /// Sets the bandwidth (module doc); a changed coefficient restarts the
    /// filter from its next input.
    pub fn configure(&mut self, bandwidth_hz: f32, dt: f32) {
        let b = coefficient(bandwidth_hz, dt).map_or(0.0, |b| b as f32);
        if b != self.b {
            *self = SensorLowPass {
                b,
                ..SensorLowPass::OFF
            };
        }
    }

    /// Whether the filter is on.
    #[inline(always)]
    pub fn is_on(&self) -> bool {
        self.b > 0.0
    }

    /// One tick: filters `v` in place.
    #[inline]
    pub fn apply(&mut self, v: &mut [f32; 3]) {
        if !self.primed {
            self.primed = true;
            self.x = *v;
            self.y = *v;
            return;
        }
        for i in 0..3 {
            let mut y = self.y[i] + self.b * (v[i] + self.x[i] - 2.0 * self.y[i]);
            // A non-finite input would stick in the state: restart there.
            if !y.is_finite() {
                y = 0.0;
            }
            self.x[i] = if v[i].is_finite() { v[i] } else { 0.0 };
            self.y[i] = y;
            v[i] = y;
        }
    }
}

/// [`SensorLowPass`] in integers, for the `fixed-point` build (module doc
/// "Fixed point").
#[derive(Debug, Clone, PartialEq)]
pub struct SensorLowPassFixed {
    /// The mantissa m of `b` (0 = off).
    m: i64,
    /// The exponent s of `b = m·2^−s`, 30 ..= 45.
    s: u32,
    /// Output of the last tick, with [`STATE_BITS`] fraction bits.
    y: [i64; 3],
    /// Input of the last tick (clamped).
    x: [i32; 3],
    primed: bool,
}

impl SensorLowPassFixed {
    /// No filter.
    pub const OFF: SensorLowPassFixed = SensorLowPassFixed {
        m: 0,
        s: COEF_BITS,
        y: [0; 3],
        x: [0; 3],
        primed: false,
    };

    /// [`SensorLowPass::configure`].
    pub fn configure(&mut self, bandwidth_hz: f32, dt: f32) {
        let (m, sh) = coefficient(bandwidth_hz, dt).map_or((0, COEF_BITS), mantissa);
        if (m, sh) != (self.m, self.s) {
            *self = SensorLowPassFixed {
                m,
                s: sh,
                ..SensorLowPassFixed::OFF
            };
        }
    }

    /// Whether the filter is on.
    #[inline(always)]
    pub fn is_on(&self) -> bool {
        self.m > 0
    }

    /// One tick: filters `v` (any scale) in place. Not inlined: the
    /// engine's common path (no filter: the KERNEL profiles) stays small.
    #[inline(never)]
    pub fn apply(&mut self, v: &mut [i32; 3]) {
        let xs = *v;
        if !self.primed {
            self.primed = true;
            self.x = xs;
            self.y = xs.map(|x| i64::from(x) << STATE_BITS);
            *v = xs;
            return;
        }
        let sh = self.s - 16;
        let half = 1i64 << (sh - 1);
        for i in 0..3 {
            // |x| ≤ 2^31 and |y| < 2·2^31 (the impulse response's absolute
            // sum is 2b < 2): in state units |x + x'| < 2^47 and |2y| <
            // 2^48, so |d| < 1.5·2^48; d·m as (d >> 16)·m < 1.5·2^62 plus
            // ((d mod 2^16)·m) >> 16 < 2^30, then shifted by s − 16.
            let d = ((i64::from(xs[i]) + i64::from(self.x[i])) << STATE_BITS) - 2 * self.y[i];
            let p = (d >> 16) * self.m + (((d & 0xFFFF) * self.m) >> 16);
            let y = self.y[i] + ((p + half) >> sh);
            self.y[i] = y;
            self.x[i] = xs[i];
            let out = (y + (1i64 << (STATE_BITS - 1))) >> STATE_BITS;
            v[i] = out.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
        }
    }
}

/// `b` as (m, s), `b = m·2^−s`, 2²⁹ ≤ m < 2³⁰ (`b` clamped to
/// 2^−15 ..< 1).
fn mantissa(b: f64) -> (i64, u32) {
    let mut v = b.clamp(crate::math::exp2i(-15), 1.0);
    let mut s = 0u32;
    while v < f64::from(1u32 << (COEF_BITS - 1)) && s < MIN_SHIFT {
        v *= 2.0;
        s += 1;
    }
    let m = libm::round(v) as i64;
    // A mantissa rounded up to 2^30 (b within 2^−31 of 1: an f32
    // bandwidth cannot come that close to Nyquist): kept below it.
    (m.min((1 << COEF_BITS) - 1), s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_at_zero_and_at_or_above_nyquist() {
        let dt = 1.0 / 2000.0;
        assert_eq!(coefficient(0.0, dt), None);
        assert_eq!(coefficient(1000.0, dt), None);
        assert_eq!(coefficient(1500.0, dt), None);
        assert_eq!(coefficient(f32::NAN, dt), None);
        assert!(coefficient(999.0, dt).is_some());
    }

    #[test]
    fn a_constant_comes_out_exactly_in_both_builds() {
        let dt = 1.0 / 2000.0;
        for bw in [0.02f32, 1.0, 50.0, 416.0, 539.0, 999.0] {
            let mut f = SensorLowPass::OFF;
            let mut q = SensorLowPassFixed::OFF;
            f.configure(bw, dt);
            q.configure(bw, dt);
            assert!(f.is_on() && q.is_on());
            let mut a = [0.0f32; 3];
            let mut b = [0i32; 3];
            f.apply(&mut a);
            q.apply(&mut b);
            // A step, held: the output settles on the input exactly.
            for k in 0..2_000_000 {
                a = [1.25, -3.5, 1000.0];
                b = [1_234_567, -7, 1 << 30];
                f.apply(&mut a);
                q.apply(&mut b);
                if k > 100_000 && b == [1_234_567, -7, 1 << 30] {
                    break;
                }
            }
            // f32: the step stalls within ulp(y)/(4·min(b, 1 − b)) of the
            // input (module doc).
            let b_f = coefficient(bw, dt).unwrap() as f32;
            let m = b_f.min(1.0 - b_f);
            for (y, x) in a.iter().zip([1.25f32, -3.5, 1000.0]) {
                assert!((y - x).abs() <= f32::EPSILON * x.abs() / m, "{bw} Hz: {y}");
            }
            assert_eq!(b, [1_234_567, -7, 1 << 30], "{bw} Hz");
        }
    }

    #[test]
    fn extreme_inputs_stay_bounded() {
        let mut q = SensorLowPassFixed::OFF;
        q.configure(999.0, 1.0 / 2000.0);
        for k in 0..1000 {
            let s = if k % 2 == 0 { i32::MAX } else { i32::MIN };
            let mut v = [s, s.saturating_neg(), s];
            q.apply(&mut v);
            assert!(v.iter().all(|x| x.unsigned_abs() <= 1 << 31));
        }
        let mut f = SensorLowPass::OFF;
        f.configure(50.0, 1.0 / 2000.0);
        let mut v = [f32::NAN, f32::INFINITY, 1.0];
        f.apply(&mut v);
        let mut v = [f32::NAN, f32::INFINITY, 1.0];
        f.apply(&mut v);
        let mut v = [0.0; 3];
        f.apply(&mut v);
        assert!(v.iter().all(|x| x.is_finite()));
    }
}
