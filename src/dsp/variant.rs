//! The output variant accumulator of ICD 5.3.6 (Output_Variant, and
//! Average_Output_Data which forces the average).
//!
//! Every tick adds the FIR-filtered gyro/acc/aux-acc and the cascade-filtered
//! channels; at an output tick [`VariantAccumulator::take`] gives, over the
//! interval since the previous output:
//!
//! - **Instant**: the last tick's values, at every interval ("the exact
//!   values as measured at that instant"): a point sample of the FIR's
//!   output. Below the FIR's band (2·f_c > the output rate) it aliases the
//!   band's noise into the output's band, as a real unit's does
//!   (docs/sensors.md "Decimation").
//! - **Average**: the mean of the interval's ticks ("if the IMU's data rate is
//!   500 Hz, … the mean of four values"; at the internal rate it is instant).
//! - **Incremental**: the angle increment Δθ and the velocity increment Δv
//!   over the interval, *divided by the interval* (5.3.6: "between the two
//!   data messages, divided by the time step of data output"), so the fields
//!   keep their °/s and g units (Table 5.15's "deg·KG"/"g·s·KA" describe Δθ
//!   and Δv before that division;
//!   [`crate::chain::SignalChain::output_interval`] gives them back). Δθ is the rotation vector over the interval with the
//!   two-sample coning correction `½ Σ α_{k−1} × Δα_k`; Δv carries the
//!   rotation compensation `½ α × υ` and the sculling correction
//!   `½ Σ (α_{k−1} × Δυ_k + υ_{k−1} × Δα_k)`, expressed in the body frame at
//!   the start of the interval. Without rotation it equals the average.
//!
//! The cascade-filtered channels (UDD 0x2D, 0x91, 0x92) are rates and
//! accelerations by definition (Table 5.15: deg/s, g), so they are instant in
//! the Instant variant and averaged otherwise.
//!
//! Sums are taken of the differences from the interval's first sample, which
//! keeps f32 rounding at the level of the signal's variation, not its size.
//!
//! The `fixed-point` build uses [`VariantFixed`]: exact integer sums, the
//! same formulas (within an output LSB of an f64 evaluation at any interval
//! length, pinned by a unit test), a few dozen 32-bit products a tick and no
//! floating point but one division per output.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::fir::CHANNELS;
use crate::math::rotation::{cross, Vec3};

/// What an output carries over its interval (ICD 5.3.6; the KERNEL's
/// Output_Variant and Average_Output_Data map onto it in
/// [`crate::kernel::config::output_variant`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OutputVariant {
    /// Instant values (KERNEL Output_Variant 0).
    #[default]
    Instant,
    /// The mean over the output interval (1).
    Average,
    /// Δθ/T and Δv/T over the output interval (2).
    Incremental,
}

/// What [`VariantAccumulator::take`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VariantOutput {
    /// Gyro, acc, aux acc per the variant (°/s, g).
    pub main: [f32; CHANNELS],
    /// Cascade-filtered channels (°/s, g).
    pub filtered: [f32; CHANNELS],
    /// Ticks in the interval.
    pub ticks: u32,
}

/// The accumulator (module doc).
#[derive(Debug, Clone)]
pub struct VariantAccumulator {
    variant: OutputVariant,
    dt: f32,
    n: u32,
    first: [f32; CHANNELS],
    first_f: [f32; CHANNELS],
    sum: [f32; CHANNELS],
    sum_f: [f32; CHANNELS],
    last: [f32; CHANNELS],
    last_f: [f32; CHANNELS],
    /// Σ Δα (rad), coning term (rad).
    alpha: Vec3,
    coning: Vec3,
    /// Σ Δυ (g·s) per accelerometer, sculling term.
    upsilon: [Vec3; 2],
    sculling: [Vec3; 2],
}

const DEG: f32 = core::f32::consts::PI / 180.0;

impl VariantAccumulator {
    /// An empty accumulator for ticks of `dt` seconds whose empty-interval
    /// output (main and filtered) is `last`.
    pub fn new(variant: OutputVariant, dt: f32, last: &[f32; CHANNELS]) -> Self {
        VariantAccumulator {
            variant,
            dt,
            n: 0,
            first: [0.0; CHANNELS],
            first_f: [0.0; CHANNELS],
            sum: [0.0; CHANNELS],
            sum_f: [0.0; CHANNELS],
            last: *last,
            last_f: *last,
            alpha: [0.0; 3],
            coning: [0.0; 3],
            upsilon: [[0.0; 3]; 2],
            sculling: [[0.0; 3]; 2],
        }
    }

    /// The variant.
    pub fn variant(&self) -> OutputVariant {
        self.variant
    }

    /// The last tick's FIR output.
    pub fn last(&self) -> [f32; CHANNELS] {
        self.last
    }

    /// Starts a new interval (keeps the last values for an empty interval).
    pub fn reset(&mut self) {
        self.n = 0;
        self.sum = [0.0; CHANNELS];
        self.sum_f = [0.0; CHANNELS];
        self.alpha = [0.0; 3];
        self.coning = [0.0; 3];
        self.upsilon = [[0.0; 3]; 2];
        self.sculling = [[0.0; 3]; 2];
    }

    /// Adds one tick: `main` = FIR outputs, `filtered` = cascade outputs.
    #[inline]
    pub fn add(&mut self, main: &[f32; CHANNELS], filtered: &[f32; CHANNELS]) {
        self.last = *main;
        self.last_f = *filtered;
        // Saturating: an interval no output ends (output stopped) may run
        // past 2^32 ticks (24.8 days at 2 kHz) without a panic.
        if self.variant == OutputVariant::Instant {
            self.n = self.n.saturating_add(1);
            return;
        }
        if self.n == 0 {
            self.first = *main;
            self.first_f = *filtered;
        } else {
            for c in 0..CHANNELS {
                self.sum[c] += main[c] - self.first[c];
                self.sum_f[c] += filtered[c] - self.first_f[c];
            }
        }
        self.n = self.n.saturating_add(1);
        if self.variant == OutputVariant::Incremental {
            let k = self.dt * DEG;
            let da = [main[0] * k, main[1] * k, main[2] * k];
            let a0 = self.alpha;
            let c = cross(&a0, &da);
            for (i, ci) in c.iter().enumerate() {
                self.coning[i] += 0.5 * ci;
            }
            for s in 0..2 {
                let b = 3 + 3 * s;
                let dv = [
                    main[b] * self.dt,
                    main[b + 1] * self.dt,
                    main[b + 2] * self.dt,
                ];
                let u0 = self.upsilon[s];
                let t1 = cross(&a0, &dv);
                let t2 = cross(&u0, &da);
                for i in 0..3 {
                    self.sculling[s][i] += 0.5 * (t1[i] + t2[i]);
                    self.upsilon[s][i] += dv[i];
                }
            }
            for i in 0..3 {
                self.alpha[i] += da[i];
            }
        }
    }

    /// The interval's output per the variant; starts a new interval.
    pub fn take(&mut self) -> VariantOutput {
        let n = self.n;
        let mut out = VariantOutput {
            main: self.last,
            filtered: self.last_f,
            ticks: n.max(1),
        };
        if n > 0 && self.variant != OutputVariant::Instant {
            let inv = 1.0 / n as f32;
            for c in 0..CHANNELS {
                out.main[c] = self.first[c] + self.sum[c] * inv;
                out.filtered[c] = self.first_f[c] + self.sum_f[c] * inv;
            }
            if self.variant == OutputVariant::Incremental {
                let t = n as f32 * self.dt;
                let k = 1.0 / (t * DEG);
                for i in 0..3 {
                    out.main[i] = (self.alpha[i] + self.coning[i]) * k;
                }
                for s in 0..2 {
                    let b = 3 + 3 * s;
                    let rot = cross(&self.alpha, &self.upsilon[s]);
                    for i in 0..3 {
                        out.main[b + i] =
                            (self.upsilon[s][i] + 0.5 * rot[i] + self.sculling[s][i]) / t;
                    }
                }
            }
        }
        self.reset();
        out
    }
}

// ----- fixed point (the `fixed-point` build) -----

use crate::math::fixed::{cross_i64, mul64, norm3, scale_i64, Recip};

/// What [`VariantFixed::take`] returns, in the FIR's fixed-point units
/// (gyro °/s·2¹⁷, accelerometers g·2²⁰).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VariantOutputFixed {
    /// Gyro, acc, aux acc per the variant.
    pub main: [i32; CHANNELS],
    /// Cascade-filtered channels.
    pub filtered: [i32; CHANNELS],
    /// Ticks in the interval.
    pub ticks: u32,
}

/// [`VariantAccumulator`] in integers, for the `fixed-point` build.
///
/// A "unit" is one FIR unit for one tick (gyro: 2⁻¹⁷ °/s × dt = G rad,
/// G = dt·π/180/2¹⁷; accelerometers 2⁻²⁰ g × dt). With A = Σ gyro and
/// U = Σ acc over the interval (exact `i64` sums) and n ticks, the float
/// accumulator's formulas become, in output units:
///
/// ```text
/// average       = Σ/n
/// incremental   gyro = (A + ½G·C)/n,   C = Σ α_{k−1} × Δα_k
///               acc  = (U + ½G·(A × U + S))/n,   S = Σ (α_{k−1} × Δυ_k + υ_{k−1} × Δα_k)
/// ```
///
/// C and S are sums of exact 32 × 32 → 64 cross products in block floating
/// point: α_{k−1} and υ_{k−1} enter as `i32` after a right shift s that
/// grows by one each time the tick count doubles (s = ⌊log₂(k−1)⌋ − 1), the
/// products enter the `i64` sums shifted by s too, and the sums are
/// rescaled (÷4, rounded) when s grows: a full-scale input cannot overflow
/// at any interval length, and the corrections keep ~30 significant bits.
/// The means divide by a reciprocal ([`Recip`]). One `f32` division per
/// output (½G/n), otherwise integers.
#[derive(Debug, Clone)]
pub struct VariantFixed {
    variant: OutputVariant,
    /// The block exponent s (LSB of C and S: 2^2s units²).
    shift: u8,
    /// ½·G.
    half_g: f32,
    n: u32,
    last: [i32; CHANNELS],
    last_f: [i32; CHANNELS],
    sum: [i64; CHANNELS],
    sum_f: [i64; CHANNELS],
    coning: [i64; 3],
    sculling: [[i64; 3]; 2],
}

/// `x / 2^s` rounded to nearest (half up) for 0 ≤ s < 32, in 32-bit
/// operations (a variable 64-bit shift is a library call on ARMv6-M).
#[inline(always)]
fn shr64(x: i64, s: u32) -> i64 {
    if s == 0 {
        return x;
    }
    let half = (x as u32 >> (s - 1)) & 1;
    let lo = x as u32;
    let hi = (x >> 32) as i32;
    let nlo = (lo >> s) | ((hi as u32) << (32 - s));
    let nhi = hi >> s;
    ((i64::from(nhi) << 32) | i64::from(nlo)) + i64::from(half)
}

/// α, υ of the ticks so far as `i32` at block exponent `s`.
#[inline(always)]
fn block(x: i64, s: u32) -> i32 {
    shr64(x, s).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

fn cross_shr(a: &[i32; 3], b: &[i32], s: u32) -> [i64; 3] {
    [
        shr64(mul64(a[1], b[2]) - mul64(a[2], b[1]), s),
        shr64(mul64(a[2], b[0]) - mul64(a[0], b[2]), s),
        shr64(mul64(a[0], b[1]) - mul64(a[1], b[0]), s),
    ]
}

fn triad64(x: &[i64; CHANNELS], b: usize) -> [i64; 3] {
    [x[b], x[b + 1], x[b + 2]]
}

impl VariantFixed {
    /// An empty accumulator for ticks of `dt` seconds whose empty-interval
    /// output (main and filtered) is `last`.
    pub fn new(variant: OutputVariant, dt: f32, last: &[i32; CHANNELS]) -> Self {
        VariantFixed {
            variant,
            shift: 0,
            half_g: 0.5 * dt * DEG / 131_072.0,
            n: 0,
            last: *last,
            last_f: *last,
            sum: [0; CHANNELS],
            sum_f: [0; CHANNELS],
            coning: [0; 3],
            sculling: [[0; 3]; 2],
        }
    }

    /// The variant.
    pub fn variant(&self) -> OutputVariant {
        self.variant
    }

    /// The last tick's FIR output.
    pub fn last(&self) -> [i32; CHANNELS] {
        self.last
    }

    /// Starts a new interval (keeps the last values for an empty interval).
    pub fn reset(&mut self) {
        self.n = 0;
        self.shift = 0;
        self.sum = [0; CHANNELS];
        self.sum_f = [0; CHANNELS];
        self.coning = [0; 3];
        self.sculling = [[0; 3]; 2];
    }

    /// Adds one tick: `main` = FIR outputs, `filtered` = cascade outputs.
    #[inline]
    pub fn add(&mut self, main: &[i32; CHANNELS], filtered: &[i32; CHANNELS]) {
        self.last = *main;
        self.last_f = *filtered;
        if self.variant == OutputVariant::Instant {
            self.n = self.n.saturating_add(1);
            return;
        }
        if self.variant == OutputVariant::Incremental {
            // α, υ before this tick at the block exponent: |Σ| < n·2^28.2
            // up to ±2048 °/s, s = ⌊log₂ n⌋ − 1 keeps them within 2^30
            // (up to the fixed-point truth's ±4095 °/s, n·2^29.2: `block`
            // saturates a partial sum beyond an i32; the products are
            // 64-bit either way).
            let s = u32::from(self.shift);
            let mut h = [0i32; CHANNELS];
            for c in 0..CHANNELS {
                h[c] = block(self.sum[c], s);
            }
            let alpha = [h[0], h[1], h[2]];
            let da = &main[0..3];
            let c = cross_shr(&alpha, da, s);
            for i in 0..3 {
                self.coning[i] = self.coning[i].wrapping_add(c[i]);
            }
            for k in 0..2 {
                let b = 3 + 3 * k;
                let ups = [h[b], h[b + 1], h[b + 2]];
                let t1 = cross_shr(&alpha, &main[b..b + 3], s);
                let t2 = cross_shr(&ups, da, s);
                for i in 0..3 {
                    self.sculling[k][i] = self.sculling[k][i].wrapping_add(t1[i] + t2[i]);
                }
            }
        }
        for c in 0..CHANNELS {
            self.sum[c] = self.sum[c].wrapping_add(i64::from(main[c]));
            self.sum_f[c] = self.sum_f[c].wrapping_add(i64::from(filtered[c]));
        }
        self.n = self.n.saturating_add(1);
        let n = self.n;
        if n >= 4 && n & (n - 1) == 0 && self.shift < 31 {
            // The tick count doubled: one more bit of block exponent; the
            // sums' LSB (2^2s) grows by 4.
            self.shift += 1;
            let r = |x: &mut i64| *x = (*x >> 2) + ((*x >> 1) & 1);
            self.coning.iter_mut().for_each(r);
            self.sculling.iter_mut().flatten().for_each(r);
        }
    }

    /// The interval's output per the variant; starts a new interval.
    pub fn take(&mut self) -> VariantOutputFixed {
        let n = self.n;
        let mut out = VariantOutputFixed {
            main: self.last,
            filtered: self.last_f,
            ticks: n.max(1),
        };
        if n > 0 && self.variant != OutputVariant::Instant {
            let r = Recip::new(n);
            for c in 0..CHANNELS {
                out.main[c] = r.div_round(self.sum[c]);
                out.filtered[c] = r.div_round(self.sum_f[c]);
            }
            if self.variant == OutputVariant::Incremental {
                // Corrections ½G·(…)/n, output units.
                let k = self.half_g / n as f32;
                let lsb = 2 * i32::from(self.shift);
                for i in 0..3 {
                    out.main[i] = out.main[i].saturating_add(scale_i64(self.coning[i], lsb, k));
                }
                let (a, sa) = norm3(&triad64(&self.sum, 0));
                for s in 0..2 {
                    let b = 3 + 3 * s;
                    let (u, su) = norm3(&triad64(&self.sum, b));
                    let rot = cross_i64(&a, &u);
                    for i in 0..3 {
                        let corr = scale_i64(rot[i], (sa + su) as i32, k)
                            .saturating_add(scale_i64(self.sculling[s][i], lsb, k));
                        out.main[b + i] = out.main[b + i].saturating_add(corr);
                    }
                }
            }
        }
        self.reset();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`VariantAccumulator`]'s formulas in f64: (main, filtered).
    fn reference(variant: OutputVariant, dt: f64, ys: &[[f64; CHANNELS]]) -> [f64; CHANNELS] {
        let n = ys.len() as f64;
        let last = *ys.last().unwrap();
        match variant {
            OutputVariant::Instant => last,
            OutputVariant::Average => {
                let mut m = [0.0; CHANNELS];
                for y in ys {
                    for c in 0..CHANNELS {
                        m[c] += y[c] / n;
                    }
                }
                m
            }
            OutputVariant::Incremental => {
                let deg = core::f64::consts::PI / 180.0;
                let cr = |a: &[f64; 3], b: &[f64; 3]| {
                    [
                        a[1] * b[2] - a[2] * b[1],
                        a[2] * b[0] - a[0] * b[2],
                        a[0] * b[1] - a[1] * b[0],
                    ]
                };
                let (mut al, mut con) = ([0.0; 3], [0.0; 3]);
                let (mut up, mut scu) = ([[0.0; 3]; 2], [[0.0; 3]; 2]);
                for y in ys {
                    let da = [y[0] * dt * deg, y[1] * dt * deg, y[2] * dt * deg];
                    let c = cr(&al, &da);
                    for s in 0..2 {
                        let b = 3 + 3 * s;
                        let dv = [y[b] * dt, y[b + 1] * dt, y[b + 2] * dt];
                        let t1 = cr(&al, &dv);
                        let t2 = cr(&up[s], &da);
                        for i in 0..3 {
                            scu[s][i] += 0.5 * (t1[i] + t2[i]);
                            up[s][i] += dv[i];
                        }
                    }
                    for i in 0..3 {
                        con[i] += 0.5 * c[i];
                        al[i] += da[i];
                    }
                }
                let t = n * dt;
                let mut m = [0.0; CHANNELS];
                for i in 0..3 {
                    m[i] = (al[i] + con[i]) / (t * deg);
                }
                for s in 0..2 {
                    let b = 3 + 3 * s;
                    let rot = cr(&al, &up[s]);
                    for i in 0..3 {
                        m[b + i] = (up[s][i] + 0.5 * rot[i] + scu[s][i]) / t;
                    }
                }
                m
            }
        }
    }

    /// Instant is the last tick's values at every interval length (ICD
    /// 5.3.6 "exact values as measured at that instant"), bit for bit, in
    /// both builds' accumulators; never the interval's mean.
    #[test]
    fn instant_is_the_last_ticks_sample_at_every_interval() {
        let mut f = VariantAccumulator::new(OutputVariant::Instant, 0.0005, &[0.0; CHANNELS]);
        let mut q = VariantFixed::new(OutputVariant::Instant, 0.0005, &[0; CHANNELS]);
        let mut k = 0u32;
        for n in [1u32, 2, 3, 5, 1, 4, 20, 2000] {
            let mut last = [0.0f32; CHANNELS];
            let mut last_q = [0i32; CHANNELS];
            for _ in 0..n {
                k += 1;
                last = core::array::from_fn(|c| libm::sinf((k * 7 + c as u32) as f32) * 100.0);
                last_q = last.map(|x| (x * 1000.0) as i32);
                f.add(&last, &[1.0; CHANNELS]);
                q.add(&last_q, &[1; CHANNELS]);
            }
            let out = f.take();
            assert_eq!(out.main.map(f32::to_bits), last.map(f32::to_bits), "n {n}");
            assert_eq!(out.filtered, [1.0; CHANNELS]);
            assert_eq!(out.ticks, n);
            let out = q.take();
            assert_eq!(out.main, last_q, "n {n}");
            assert_eq!(out.ticks, n);
        }
    }

    /// The fixed accumulator against the float formulas (in f64) on a
    /// tumbling, vibrating input, for intervals within one sub-interval and
    /// over several (folded) ones; and the float accumulator alike.
    #[test]
    fn fixed_point_matches_the_formulas_in_every_variant() {
        let dt = 0.0005f32;
        for variant in [
            OutputVariant::Instant,
            OutputVariant::Average,
            OutputVariant::Incremental,
        ] {
            for n in [1u32, 2, 3, 4, 5, 20, 255, 256, 257, 700, 2000, 5000, 40_000] {
                let mut f = VariantAccumulator::new(variant, dt, &[0.0; CHANNELS]);
                let mut q = VariantFixed::new(variant, dt, &[0; CHANNELS]);
                let mut ys = std::vec::Vec::new();
                for k in 0..n {
                    let t = k as f32 * dt;
                    let (s, c) = (libm::sinf(30.0 * t), libm::cosf(30.0 * t));
                    let v = [
                        300.0 * s,
                        300.0 * c,
                        50.0 + 20.0 * s,
                        2.0 * c,
                        -1.5 * s,
                        1.0 + 0.5 * c,
                        20.0 * s,
                        -30.0 * c,
                        5.0,
                    ];
                    let mut yq = [0i32; CHANNELS];
                    let mut yf = [0.0f32; CHANNELS];
                    let mut y64 = [0.0f64; CHANNELS];
                    for ch in 0..CHANNELS {
                        let scale = if ch < 3 { 131_072.0 } else { 1_048_576.0 };
                        yq[ch] = libm::roundf(v[ch] * scale) as i32;
                        yf[ch] = yq[ch] as f32 / scale;
                        y64[ch] = f64::from(yq[ch]) / f64::from(scale);
                    }
                    f.add(&yf, &yf);
                    q.add(&yq, &yq);
                    ys.push(y64);
                }
                let r = reference(variant, f64::from(dt), &ys);
                let a = f.take();
                let b = q.take();
                for ch in 0..CHANNELS {
                    let scale = if ch < 3 { 131_072.0 } else { 1_048_576.0 };
                    let y = f64::from(b.main[ch]) / scale;
                    // Fixed: within an output LSB (+ the f32 significand of
                    // the corrections' factor).
                    let tol = 1.5 / scale + 1e-7 * r[ch].abs();
                    assert!(
                        (r[ch] - y).abs() <= tol,
                        "{variant:?} n {n} ch {ch}: {} vs {y}",
                        r[ch]
                    );
                    // Float: its own f32 rounding.
                    let x = f64::from(a.main[ch]);
                    assert!(
                        (r[ch] - x).abs() <= 1e-5 * 300.0,
                        "{variant:?} n {n} ch {ch}: {} vs {x}",
                        r[ch]
                    );
                    if variant != OutputVariant::Incremental {
                        let yf = f64::from(b.filtered[ch]) / scale;
                        assert!((r[ch] - yf).abs() <= tol);
                    }
                }
                assert_eq!(a.ticks, b.ticks);
            }
        }
    }
}
