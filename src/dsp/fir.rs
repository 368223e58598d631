//! The FIR low-pass of ICD 5.6 (Table 5.29): linear phase, order N, group
//! delay exactly N/2 samples.
//!
//! | LPF_Bandwidth code | −3 dB | order at 2 kHz | order at 4 kHz (K201) | delay |
//! |---|---|---|---|---|
//! | 0 | 16 Hz | 192 | — | 48 ms |
//! | 1 | 33 Hz | 96 | — | 24 ms |
//! | 2 | 66 Hz | 48 | 96 | 12 ms |
//! | 3 | 131 Hz | 24 | 48 | 6 ms |
//! | 4 | 262 Hz | 12 | 24 | 3 ms |
//! | 0xFF | off | — | — | 0 |
//!
//! **Design.** Windowed sinc with a Blackman window over each stage's taps
//! (`w[n] = 0.42 − 0.5 cos(2π(n+1)/(N+2)) + 0.08 cos(4π(n+1)/(N+2))`, so no tap
//! is zero), normalised to unit DC gain. The sinc cutoff is chosen per design
//! so that the −3 dB point of the whole filter falls exactly on the Table 5.29
//! bandwidth (found by bisection offline; `tests/signal_fir.rs` measures it).
//! Coefficients are computed at compile time by `const fn` (own Taylor
//! sine/cosine in f64): no run-time cost, they live in flash. Every stage is
//! symmetric, so the phase is exactly linear and the group delay is N/2
//! samples = N/(2·f_s), Table 5.29's delay
//! (`docs/protocol-facts.md`). The stop band beyond
//! 3.2× the bandwidth is at least 64 dB down.
//!
//! **Two-stage (interpolated) structure for the long orders.** Orders 192
//! (16 Hz) and 96 at 2 kHz (33 Hz; and 96 at 4 kHz, the same normalised
//! design) are realised as `H(z) = P(z) · G(z^L)`: a short pre-filter P
//! (order 16, cutoff 0.05·f_s) followed by a prototype G whose taps are L
//! samples apart (order 44 with L = 4 for 16 Hz: 16 + 4·44 = 192; order 40
//! with L = 2 for 33 Hz: 16 + 2·40 = 96). The product of two symmetric
//! filters is a symmetric FIR of exactly order N — the same kind of filter,
//! delay N/2 — built from 32 (30) pre-added multiply-adds per channel instead
//! of 97 (49). P is the same for both, so it runs on every tick whatever the
//! design and its output history is always ready: switching designs never
//! needs a refill. (P is skipped while the design reads none of it — one
//! stage, or off — keeping the input rows that leave the input ring in P's
//! ring instead, and the skipped outputs are computed from them, by the
//! same function on the same rows, when a two-stage design starts: the
//! output is bit for bit the same, a factory tick ~10 ns cheaper on a host.)
//!
//! **Structure.** Nine channels (gyro, acc, aux acc × 3) are filtered in one
//! pass over channel-interleaved histories; symmetric taps are pre-added
//! (`h[k]·(x[k] + x[N−k])`), halving the multiplications. The input history
//! (49 samples) serves the one-stage designs (orders ≤ 48) and P; the history
//! of P's output (177 samples) serves G. Both always hold the real past of the
//! signal, so reconfiguring keeps the filter running on it.
//!
//! **Memory.** Each history is a single ring (8 136 bytes for both, 9
//! channels of `f32`/`i32`): a window of the ring is at most two contiguous
//! segments, so the pairs (oldest + k·L, newest − k·L) fall in at most three
//! runs in which both rows advance without wrapping (`Window`); each run is
//! a pair of slice iterators (chunks of L rows for the strided stage), so
//! the inner loop is the one a contiguous window would have and the pairs are
//! summed in the same order — the float output is bit for bit the one of the
//! doubled rings this replaced (16 272 bytes; every sample was written at `i`
//! and `i + ring`), for 50–240 more instructions a tick on a Cortex-M4F (the
//! runs' set-up, most for the strided stage; the cascade's new layout wins
//! more than that back). The stage runs out of line (`run_f32`): inlined into the
//! chain, the compiler addressed each row from the chain's base at offsets
//! beyond the `VLDR` range (one extra instruction per load). The 226 rows
//! are the minimum for these designs: the order-192 filter needs 193 samples
//! of state in any realisation, and the order-48 designs 49 of the input.
//!
//! **Fixed point** ([`FirBankFixed`]) for cores without an FPU: samples are
//! `i32` (the chain scales gyro by 2¹⁷ per °/s and accelerometers by 2²⁰ per g),
//! coefficients Q15 rounded to nearest with each stage's centre tap adjusted
//! so its taps sum to exactly 2¹⁵ (unit DC gain, exact). Each pre-added pair
//! `s = x[k] + x[N−k]` is split `s = hi·2¹⁵ + lo` (0 ≤ lo < 2¹⁵) and both halves
//! are multiplied by the coefficient in 32-bit — one-cycle `MULS` on a
//! Cortex-M0+ — into two `i32` accumulators that cannot overflow (|s| < 2³⁰ and
//! a stage's coefficients' absolute sum is < 1.1 · 2¹⁵). The result
//! `acc_hi + ((acc_lo + 2¹⁴) >> 15)` is the stage's Σ h·x rounded to nearest,
//! exactly. The difference from the float path is bounded by
//! [`FirDesign::fixed_error_gain`] × max|x| + 2 LSB (rounding of the input, of
//! P's output and of the output), pinned by a parity test.
//! The fixed-point stage has two out-of-line copies, one for taps one row
//! apart and one for both strides of the two-stage designs (the stride a
//! run-time value there, the rows indexed one pair at a time): the
//! `fixed-point` build is for small flash, and a copy per stride in runs
//! cost 2.8 KiB more (the float stage keeps one per stride).

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

/// Largest order (Table 5.29).
pub const MAX_ORDER: usize = 192;
/// Input samples kept: the longest one-stage design (order 48) + 1.
pub(crate) const RING: usize = 49;
/// Pre-filter outputs kept: the longest span of a two-stage prototype
/// (4 × 44) + 1.
pub(crate) const MID_RING: usize = 177;
/// Channels filtered together: gyro X/Y/Z, acc X/Y/Z, aux acc X/Y/Z.
pub const CHANNELS: usize = 9;

/// One symmetric FIR stage.
#[derive(Debug, PartialEq)]
pub struct Stage {
    /// Order (taps − 1), even.
    pub order: usize,
    /// Sinc cutoff as a fraction of the stage's own sample rate.
    pub fc_norm: f64,
    /// Taps 0..=order/2 (the rest mirror them), unit DC gain.
    pub half: &'static [f32],
    /// The same taps in Q15, summing (mirrored) to exactly 32768.
    pub half_q15: &'static [i32],
}

impl Stage {
    /// Tap `n` (0..=order), float.
    pub fn tap(&self, n: usize) -> f32 {
        let h = self.order / 2;
        self.half[if n <= h { n } else { self.order - n }]
    }
    /// Tap `n` (0..=order), Q15.
    pub fn tap_q15(&self, n: usize) -> i32 {
        let h = self.order / 2;
        self.half_q15[if n <= h { n } else { self.order - n }]
    }
    /// Σ |taps|.
    pub fn l1(&self) -> f32 {
        (0..=self.order).map(|n| self.tap(n).abs()).sum()
    }
}

/// One FIR design of Table 5.29.
#[derive(Debug, PartialEq)]
pub struct FirDesign {
    /// Filter order N of the whole filter (N + 1 taps).
    pub order: usize,
    /// −3 dB bandwidth, Hz (Table 5.29).
    pub bandwidth_hz: f32,
    /// Sample rate the design is for, Hz.
    pub rate_hz: u32,
    /// The stage run on the input (`stride` 1) or, for the two-stage
    /// designs, the prototype G run on [`PRE`]'s output with taps `stride`
    /// samples apart.
    pub stage: Stage,
    /// 1 = one stage; L > 1 = `PRE(z) · G(z^L)`.
    pub stride: usize,
}

impl FirDesign {
    /// Group delay, samples (N/2, exact).
    pub const fn delay_samples(&self) -> usize {
        self.order / 2
    }

    /// Group delay, seconds (Table 5.29).
    pub fn delay_s(&self) -> f32 {
        self.order as f32 / (2.0 * self.rate_hz as f32)
    }

    /// Tap `n` (0..=N) of the whole impulse response, float (for a
    /// two-stage design the convolution of the stages).
    pub fn tap(&self, n: usize) -> f32 {
        self.tap_with(n, Stage::tap, |s, k| s.tap(k))
    }

    /// Tap `n` of the whole impulse response as the fixed-point path
    /// realises it (Q15 stages), as a fraction.
    pub fn tap_fixed(&self, n: usize) -> f32 {
        self.tap_with(
            n,
            |s, k| s.tap_q15(k) as f32 / 32768.0,
            |s, k| s.tap_q15(k) as f32 / 32768.0,
        )
    }

    fn tap_with(
        &self,
        n: usize,
        pre: impl Fn(&Stage, usize) -> f32,
        main: impl Fn(&Stage, usize) -> f32,
    ) -> f32 {
        if self.stride == 1 {
            return main(&self.stage, n);
        }
        let mut acc = 0.0;
        for k in 0..=PRE.order.min(n) {
            let m = n - k;
            if m.is_multiple_of(self.stride) && m / self.stride <= self.stage.order {
                acc += pre(&PRE, k) * main(&self.stage, m / self.stride);
            }
        }
        acc
    }

    /// Σ over all taps of |h − h_fixed|: bounds the fixed-point coefficient
    /// error (multiply by max|x|).
    pub fn fixed_error_gain(&self) -> f32 {
        (0..=self.order)
            .map(|n| (self.tap(n) - self.tap_fixed(n)).abs())
            .sum()
    }
}

// ----- compile-time design -----

const PI: f64 = core::f64::consts::PI;
const TAU: f64 = core::f64::consts::TAU;

/// sin and cos of `x` by range reduction and Taylor series (|error| < 1e-15).
const fn sin_cos(x: f64) -> (f64, f64) {
    let k = x / TAU;
    let k = if k >= 0.0 {
        (k + 0.5) as i64
    } else {
        (k - 0.5) as i64
    };
    let r = x - k as f64 * TAU;
    let mut s = 0.0;
    let mut c = 0.0;
    let mut term_s = r;
    let mut term_c = 1.0;
    let mut n = 0;
    while n < 30 {
        s += term_s;
        c += term_c;
        let a = (2 * n + 2) as f64;
        let b = (2 * n + 3) as f64;
        term_s = -term_s * r * r / (a * b);
        term_c = -term_c * r * r / ((2 * n + 1) as f64 * a);
        n += 1;
    }
    (s, c)
}

/// Half of a Blackman-windowed sinc of order `order`, cutoff `fc` (fraction of
/// the sample rate), unit DC gain.
const fn design_half<const H: usize>(order: usize, fc: f64) -> [f64; H] {
    let mut h = [0.0; H];
    let mut sum = 0.0;
    let mut n = 0;
    while n < H {
        let m = n as f64 - order as f64 / 2.0;
        let x = (n + 1) as f64 / (order + 2) as f64;
        let w = 0.42 - 0.5 * sin_cos(TAU * x).1 + 0.08 * sin_cos(2.0 * TAU * x).1;
        let s = if n == order / 2 {
            2.0 * fc
        } else {
            sin_cos(TAU * fc * m).0 / (PI * m)
        };
        h[n] = w * s;
        sum += if n == order / 2 { h[n] } else { 2.0 * h[n] };
        n += 1;
    }
    let mut n = 0;
    while n < H {
        h[n] /= sum;
        n += 1;
    }
    h
}

const fn to_f32<const H: usize>(h: [f64; H]) -> [f32; H] {
    let mut o = [0.0f32; H];
    let mut n = 0;
    while n < H {
        o[n] = h[n] as f32;
        n += 1;
    }
    o
}

/// Q15, rounded to nearest; the centre tap takes up the rounding so the
/// mirrored sum is exactly 32768.
const fn to_q15<const H: usize>(h: [f64; H]) -> [i32; H] {
    let mut o = [0i32; H];
    let mut sum = 0i32;
    let mut n = 0;
    while n < H {
        let v = h[n] * 32768.0;
        o[n] = if v >= 0.0 {
            (v + 0.5) as i32
        } else {
            (v - 0.5) as i32
        };
        sum += if n + 1 == H { o[n] } else { 2 * o[n] };
        n += 1;
    }
    o[H - 1] += 32768 - sum;
    o
}

macro_rules! stage {
    ($h:literal, $order:literal, $fc:literal) => {{
        const D: [f64; $h] = design_half::<$h>($order, $fc);
        const F: [f32; $h] = to_f32(D);
        const Q: [i32; $h] = to_q15(D);
        Stage {
            order: $order,
            fc_norm: $fc,
            half: &F,
            half_q15: &Q,
        }
    }};
}

macro_rules! designs {
    ($( $name:ident, $order:literal, $bw:literal, $rate:literal, $stride:literal, [$h:literal, $sorder:literal, $fc:literal]; )*) => {
        $(
            #[doc = concat!("Order ", stringify!($order), ", ", stringify!($bw), " Hz at ", stringify!($rate), " Hz.")]
            pub static $name: FirDesign = FirDesign {
                order: $order,
                bandwidth_hz: $bw,
                rate_hz: $rate,
                stage: stage!($h, $sorder, $fc),
                stride: $stride,
            };
        )*
    };
}

/// The pre-filter P of the two-stage designs: order 16, cutoff 0.05·f_s.
pub(crate) static PRE: Stage = stage!(9, 16, 0.05);

designs! {
    FIR_16HZ_2K, 192, 16.0, 2000, 4, [23, 44, 0.04248138727458818];
    FIR_33HZ_2K, 96, 33.0, 2000, 2, [21, 40, 0.04550790936390805];
    FIR_66HZ_2K, 48, 66.0, 2000, 1, [25, 48, 0.042826545562041594];
    FIR_131HZ_2K, 24, 131.0, 2000, 1, [13, 24, 0.08459574257503238];
    FIR_262HZ_2K, 12, 262.0, 2000, 1, [7, 12, 0.1671063788343958];
    FIR_66HZ_4K, 96, 66.0, 4000, 2, [21, 40, 0.04550790936390805];
    FIR_131HZ_4K, 48, 131.0, 4000, 1, [25, 48, 0.042548959277471196];
    FIR_262HZ_4K, 24, 262.0, 4000, 1, [13, 24, 0.08459574257503238];
}

/// Every design, for tests and documentation.
pub static DESIGNS: [&FirDesign; 8] = [
    &FIR_16HZ_2K,
    &FIR_33HZ_2K,
    &FIR_66HZ_2K,
    &FIR_131HZ_2K,
    &FIR_262HZ_2K,
    &FIR_66HZ_4K,
    &FIR_131HZ_4K,
    &FIR_262HZ_4K,
];

/// A low-pass bandwidth of the FIR (Table 5.29's −3 dB points), protocol
/// neutral: a personality maps its own parameter onto it (the KERNEL's
/// LPF_Bandwidth codes: [`crate::kernel::config::lpf_bandwidth`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Bandwidth {
    /// 16 Hz (order 192 at 2 kHz).
    Hz16,
    /// 33 Hz (order 96 at 2 kHz).
    Hz33,
    /// 66 Hz (order 48 at 2 kHz, 96 at 4 kHz).
    Hz66,
    /// 131 Hz (order 24 at 2 kHz, 48 at 4 kHz).
    Hz131,
    /// 262 Hz (order 12 at 2 kHz, 24 at 4 kHz): the power-on bandwidth.
    #[default]
    Hz262,
    /// No filter (delay 0).
    Off,
}

impl Bandwidth {
    /// The −3 dB bandwidth, Hz (`None` = off).
    pub const fn hz(self) -> Option<f32> {
        match self {
            Bandwidth::Hz16 => Some(16.0),
            Bandwidth::Hz33 => Some(33.0),
            Bandwidth::Hz66 => Some(66.0),
            Bandwidth::Hz131 => Some(131.0),
            Bandwidth::Hz262 => Some(262.0),
            Bandwidth::Off => None,
        }
    }
}

/// The design of `bandwidth` at `internal_rate_hz`; `None` = filter off
/// ([`Bandwidth::Off`], or a bandwidth the rate has no design for: 16 and
/// 33 Hz at 4 kHz).
pub fn design(bandwidth: Bandwidth, internal_rate_hz: u32) -> Option<&'static FirDesign> {
    use Bandwidth::*;
    match (internal_rate_hz, bandwidth) {
        (4000, Hz66) => Some(&FIR_66HZ_4K),
        (4000, Hz131) => Some(&FIR_131HZ_4K),
        (4000, Hz262) => Some(&FIR_262HZ_4K),
        (4000, _) => None,
        (_, Hz16) => Some(&FIR_16HZ_2K),
        (_, Hz33) => Some(&FIR_33HZ_2K),
        (_, Hz66) => Some(&FIR_66HZ_2K),
        (_, Hz131) => Some(&FIR_131HZ_2K),
        (_, Hz262) => Some(&FIR_262HZ_2K),
        (_, Off) => None,
    }
}

/// Where the rows of one symmetric stage lie in a ring: the newest row is
/// `end`, the oldest `start` = `end` − 2·h·L (cyclically), the centre row
/// `start` + h·L; pair k (k = 0..h) is (`start` + k·L, `end` − k·L). The
/// a-index wraps from pair `ka` on, the b-index from pair `kb` on, so the
/// pairs fall in at most three runs in which both are contiguous slices.
#[derive(Clone, Copy)]
struct Window {
    len: usize,
    l: usize,
    start: usize,
    end: usize,
    centre: usize,
    ka: usize,
    kb: usize,
}

impl Window {
    /// A window of `h` pairs `l` rows apart ending at `end` in a ring of
    /// `len` rows (2·h·l < `len`; inlined: `l` is a constant except in
    /// [`run_i32_strided`]).
    #[inline(always)]
    fn new(len: usize, end: usize, h: usize, l: usize) -> Self {
        let span = 2 * h * l;
        let start = if end >= span {
            end - span
        } else {
            end + len - span
        };
        let c = start + h * l;
        let centre = if c >= len { c - len } else { c };
        let ka = if start + (h - 1) * l < len {
            h
        } else {
            (len - start).div_ceil(l)
        };
        let kb = if (h - 1) * l <= end { h } else { end / l + 1 };
        Window {
            len,
            l,
            start,
            end,
            centre,
            ka,
            kb,
        }
    }

    /// Calls `f(a, b, h_k)` for the pairs in order k = 0, 1, …
    #[inline(always)]
    fn pairs<T, H>(
        &self,
        ring: &[[T; CHANNELS]],
        coefs: &[H],
        mut f: impl FnMut(&[T; CHANNELS], &[T; CHANNELS], &H),
    ) {
        let l = self.l;
        let (k1, k2) = if self.ka <= self.kb {
            (self.ka, self.kb)
        } else {
            (self.kb, self.ka)
        };
        for (k0, k1) in [(0, k1), (k1, k2), (k2, coefs.len())] {
            if k0 >= k1 {
                continue;
            }
            let a0 = self.start + k0 * l - if k0 >= self.ka { self.len } else { 0 };
            let b0 = if k0 >= self.kb {
                self.end + self.len - k0 * l
            } else {
                self.end - k0 * l
            };
            let coefs = &coefs[k0..k1];
            if l == 1 {
                // By index over three slices of the run's length (the
                // bounds checks fold; zipped iterators, one of them
                // reversed, stepped each one).
                let n = coefs.len();
                let a = &ring[a0..a0 + n];
                let b = &ring[b0 + 1 - n..=b0];
                for j in 0..n {
                    f(&a[j], &b[n - 1 - j], &coefs[j]);
                }
            } else {
                // All but the last pair as whole chunks of L rows: rows
                // a0 + jL start the chunks from a0, rows b0 − jL end the
                // chunks counted back from b0 (the last pair's chunk may
                // cross the end of the ring, so it is taken by index).
                let n = k1 - k0;
                let a = ring[a0..a0 + (n - 1) * l].chunks_exact(l);
                let b = ring[b0 + 1 - (n - 1) * l..=b0].rchunks_exact(l);
                for ((a, b), h) in a.zip(b).zip(coefs) {
                    f(&a[0], &b[l - 1], h);
                }
                f(
                    &ring[a0 + (n - 1) * l],
                    &ring[b0 - (n - 1) * l],
                    &coefs[n - 1],
                );
            }
        }
    }
}

impl Window {
    /// [`Self::pairs`] in the same order, one pair at a time with the rows
    /// indexed and wrapped: one copy of `f`'s body where [`Self::pairs`]
    /// has two for strides above 1 (the strided fixed-point stage, module
    /// doc).
    #[inline(always)]
    fn pairs_by_index<T, H>(
        &self,
        ring: &[[T; CHANNELS]],
        coefs: &[H],
        mut f: impl FnMut(&[T; CHANNELS], &[T; CHANNELS], &H),
    ) {
        let (mut a, mut b) = (self.start, self.end);
        for h in coefs {
            f(&ring[a], &ring[b], h);
            a += self.l;
            if a >= self.len {
                a -= self.len;
            }
            b = if b >= self.l {
                b - self.l
            } else {
                b + self.len - self.l
            };
        }
    }
}

/// Runs `$body` once for each channel index `$c` in 0..[`CHANNELS`],
/// written out: the per-pair multiply-accumulate is the FIR's inner loop,
/// and unrolled the accumulators stay in registers across the pairs (a size-
/// optimised build would keep a counted loop over memory, ~3× the
/// instructions).
macro_rules! each_channel {
    ($c:ident => $body:expr) => {
        each_channel!(@ $c => $body; 0 1 2 3 4 5 6 7 8)
    };
    (@ $c:ident => $body:expr; $($i:literal)*) => {{
        const _: () = assert!(CHANNELS == 9);
        $({
            let $c = $i;
            $body;
        })*
    }};
}

/// One symmetric stage with taps `L` rows apart over the ring `ring` whose
/// newest row is `end`, float.
///
/// Not inlined: called with the ring as an argument, the compiler addresses
/// the rows from the slice pointer with small offsets (inlined into the
/// chain it re-derives every row from the chain's base with offsets beyond
/// the VLDR range: one extra instruction per load).
///
/// Channels `N` and beyond are not filtered (they read 0): `N` <
/// [`CHANNELS`] only for a unit without the aux accelerometer
/// (`FirBank::set_aux_live`).
// Fork by architecture: inlined on ARM, a row load takes one more instruction.
#[cfg_attr(target_arch = "arm", inline(never))]
#[cfg_attr(not(target_arch = "arm"), inline(always))]
fn run_f32<const L: usize, const N: usize>(
    ring: &[[f32; CHANNELS]],
    end: usize,
    st: &Stage,
) -> [f32; CHANNELS] {
    // Every stage has taps; no `expect`, whose panic would bring `&str`
    // formatting into the firmware (0.7 KiB on the RP2040).
    let Some((centre, coefs)) = st.half.split_last() else {
        return [0.0f32; CHANNELS];
    };
    let w = Window::new(ring.len(), end, coefs.len(), L);
    let mid = &ring[w.centre];
    let mut acc = [0.0f32; CHANNELS];
    each_channel!(c => if c < N { acc[c] = centre * mid[c] });
    w.pairs(ring, coefs, |a, b, &h| {
        each_channel!(c => if c < N { acc[c] += h * (a[c] + b[c]) });
    });
    acc
}

/// The channels a unit without the aux accelerometer filters: the
/// first eight, two whole four-lane vectors (the aux X and Y channels
/// among them, on zeros); the last, aux Z, is left out.
const AUX_FIRST: usize = 8;

/// [`run_f32`] with taps one row apart (the pre-filter, the one-stage
/// designs), every channel or (`live` false) those before the aux
/// accelerometer's.
#[inline(always)]
fn run_f32_1(ring: &[[f32; CHANNELS]], end: usize, st: &Stage, live: bool) -> [f32; CHANNELS] {
    if !live {
        return run_f32::<1, AUX_FIRST>(ring, end, st);
    }
    run_f32::<1, CHANNELS>(ring, end, st)
}

/// [`run_f32`] for the two-stage designs' prototypes (stride 2 or 4), the
/// channels as [`run_f32_1`].
#[inline(always)]
fn run_f32_strided(
    ring: &[[f32; CHANNELS]],
    end: usize,
    st: &Stage,
    stride: usize,
    live: bool,
) -> [f32; CHANNELS] {
    if !live {
        return if stride == 2 {
            run_f32::<2, AUX_FIRST>(ring, end, st)
        } else {
            run_f32::<4, AUX_FIRST>(ring, end, st)
        };
    }
    if stride == 2 {
        run_f32::<2, CHANNELS>(ring, end, st)
    } else {
        run_f32::<4, CHANNELS>(ring, end, st)
    }
}

/// [`run_i32`] with taps one row apart (the pre-filter, the one-stage
/// designs).
#[inline(never)]
fn run_i32_1(ring: &[[i32; CHANNELS]], end: usize, st: &Stage) -> [i32; CHANNELS] {
    run_i32(ring, end, st, 1)
}

/// [`run_i32`] for the two-stage designs' prototypes, stride 2 or 4: one
/// copy for both strides (the `fixed-point` build is for small flash: a
/// copy per stride was 1.9 KiB more; module doc).
#[inline(never)]
fn run_i32_strided(
    ring: &[[i32; CHANNELS]],
    end: usize,
    st: &Stage,
    stride: usize,
) -> [i32; CHANNELS] {
    run_i32(ring, end, st, if stride == 2 { 2 } else { 4 })
}

/// [`run_i32_strided`] for the bank (every channel, always).
#[inline(always)]
fn run_i32_strided_all(
    ring: &[[i32; CHANNELS]],
    end: usize,
    st: &Stage,
    stride: usize,
    _live: bool,
) -> [i32; CHANNELS] {
    run_i32_strided(ring, end, st, stride)
}

/// One symmetric stage with taps `l` rows apart, fixed point (module doc),
/// rounded to nearest (out of line through [`run_i32_1`] and
/// [`run_i32_strided`], like [`run_f32`]).
#[inline(always)]
fn run_i32(ring: &[[i32; CHANNELS]], end: usize, st: &Stage, l: usize) -> [i32; CHANNELS] {
    // Every stage has taps; no `expect`, whose panic would bring `&str`
    // formatting into the firmware (0.7 KiB on the RP2040).
    let Some((centre, coefs)) = st.half_q15.split_last() else {
        return [0i32; CHANNELS];
    };
    let w = Window::new(ring.len(), end, coefs.len(), l);
    let mid = &ring[w.centre];
    let mut acc_hi = [0i32; CHANNELS];
    let mut acc_lo = [1i32 << 14; CHANNELS];
    for c in 0..CHANNELS {
        let s = mid[c];
        acc_hi[c] += centre * (s >> 15);
        acc_lo[c] += centre * (s & 0x7FFF);
    }
    // A closure per call (one shared by reference is compiled out of line:
    // a call per pair, the accumulators in memory).
    macro_rules! mac {
        () => {
            |a: &[i32; CHANNELS], b: &[i32; CHANNELS], &h: &i32| {
                each_channel!(c => {
                    let s = a[c] + b[c];
                    acc_hi[c] += h * (s >> 15);
                    acc_lo[c] += h * (s & 0x7FFF);
                });
            }
        };
    }
    if l == 1 {
        w.pairs(ring, coefs, mac!());
    } else {
        w.pairs_by_index(ring, coefs, mac!());
    }
    let mut y = [0i32; CHANNELS];
    for c in 0..CHANNELS {
        y[c] = acc_hi[c] + (acc_lo[c] >> 15);
    }
    y
}

macro_rules! bank {
    ($name:ident, $t:ty, $run1:expr, $strided:ident, $doc:literal) => {
        #[doc = $doc]
        #[derive(Debug, Clone)]
        pub struct $name {
            raw: [[$t; CHANNELS]; RING],
            raw_pos: usize,
            mid: [[$t; CHANNELS]; MID_RING],
            mid_pos: usize,
            design: Option<&'static FirDesign>,
            /// Ticks (at most [`MID_RING`]) since the pre-filter last ran
            /// (see [`Self::push`]).
            lag: usize,
            /// Whether the aux channels are filtered
            /// ([`Self::set_aux_live`]).
            aux_live: bool,
        }

        impl $name {
            /// A bank whose history is all `x` (the steady state of input `x`).
            pub fn new(design: Option<&'static FirDesign>, x: &[$t; CHANNELS]) -> Self {
                $name {
                    raw: [*x; RING],
                    raw_pos: 0,
                    mid: [*x; MID_RING],
                    mid_pos: 0,
                    design,
                    lag: 0,
                    aux_live: true,
                }
            }

            /// Whether the aux accelerometer's channels (the last three)
            /// are live. A unit without one turns them off after
            /// [`Self::reset`]: the last channel is then not filtered and
            /// reads 0 (the first eight make two whole four-lane vectors;
            /// the chain reports zeros for the aux channels anyway). The
            /// float bank only: the fixed-point bank filters every channel.
            pub fn set_aux_live(&mut self, live: bool) {
                self.aux_live = live;
            }

            /// Whether every channel is filtered.
            #[inline(always)]
            fn live(&self) -> bool {
                self.aux_live
            }

            /// [`Self::new`] in place (no second bank on the stack).
            pub fn reset(&mut self, design: Option<&'static FirDesign>, x: &[$t; CHANNELS]) {
                self.fill(x);
                self.raw_pos = 0;
                self.mid_pos = 0;
                self.design = design;
            }

            /// Switches to `design`, keeping the histories.
            pub fn set_design(&mut self, design: Option<&'static FirDesign>) {
                self.design = design;
                if !Self::pre_unused(design) {
                    self.catch_up();
                }
            }

            /// The current design (`None` = off).
            pub fn design(&self) -> Option<&'static FirDesign> {
                self.design
            }

            /// The newest input row (the last sample pushed).
            pub fn last_input(&self) -> [$t; CHANNELS] {
                self.raw[if self.raw_pos == 0 {
                    RING - 1
                } else {
                    self.raw_pos - 1
                }]
            }

            /// Fills the histories with `x`.
            pub fn fill(&mut self, x: &[$t; CHANNELS]) {
                self.raw.fill(*x);
                self.mid.fill(*x);
                self.lag = 0;
            }

            /// Whether `design` reads no pre-filter output (one stage, or
            /// off).
            #[inline(always)]
            fn pre_unused(design: Option<&'static FirDesign>) -> bool {
                design.is_none_or(|d| d.stride == 1)
            }

            /// The pre-filter outputs of the last
            /// [`Self::push`]es that skipped it (`lag` of them), computed
            /// now by the same function on the same input rows, so the
            /// history of its output is bit for bit the one of a
            /// pre-filter run on every tick.
            ///
            /// While it is skipped, each push moves the input row leaving
            /// the input ring into the output ring's slot of that tick: the
            /// two rings then hold the last `lag + RING` input rows, and a
            /// pre-filter output needs its tick's row and the
            /// [`PRE`]`.order` before it (`lag` ≤ [`MID_RING`] = 177,
            /// so at most 193 rows, of up to 226). Slots older than `lag`
            /// hold outputs of the pre-filter (or of [`Self::fill`]).
            #[cold]
            #[inline(never)]
            fn catch_up(&mut self) {
                const SPAN: usize = PRE.order;
                const W: usize = SPAN + 1;
                let n = self.lag;
                if n == 0 {
                    return;
                }
                let len = n + SPAN;
                // The input row `age` pushes before the newest.
                let row = |s: &Self, age: usize| {
                    if age < RING {
                        s.raw[(s.raw_pos + RING - 1 - age) % RING]
                    } else {
                        s.mid[(s.mid_pos + MID_RING - 1 - (age - RING)) % MID_RING]
                    }
                };
                // A window of the W rows one output reads, as a ring: the
                // oldest SPAN first, then one row in per output. The outputs
                // go oldest first into the slots whose input rows (RING
                // older than the output's own, SPAN < RING) no later output
                // reads: in place, with 0.6 KiB of stack.
                let mut win = [[<$t>::default(); CHANNELS]; W];
                for (i, slot) in win[..SPAN].iter_mut().enumerate() {
                    *slot = row(self, len - 1 - i);
                }
                for j in 0..n {
                    let age = n - 1 - j;
                    let end = (SPAN + j) % W;
                    win[end] = row(self, age);
                    let m = $run1(&win, end, &PRE, self.live());
                    self.mid[(self.mid_pos + MID_RING - 1 - age) % MID_RING] = m;
                }
                self.lag = 0;
            }

            /// [`Self::push`] without the pre-filter (a design that reads
            /// none of it): the input row leaving the ring is
            /// kept in the pre-filter's slot of this tick instead, and
            /// [`Self::catch_up`] computes the skipped outputs when a
            /// two-stage design needs them.
            #[inline(always)]
            fn push_skipping_pre(&mut self, x: &[$t; CHANNELS]) -> [$t; CHANNELS] {
                let p = self.raw_pos;
                let q = self.mid_pos;
                self.mid[q] = self.raw[p];
                self.lag = (self.lag + 1).min(MID_RING);
                self.raw[p] = *x;
                self.raw_pos = if p + 1 == RING { 0 } else { p + 1 };
                self.mid_pos = if q + 1 == MID_RING { 0 } else { q + 1 };
                match self.design {
                    Some(d) => $run1(&self.raw, p, &d.stage, self.live()),
                    None => *x,
                }
            }

            /// Pushes one sample per channel and returns the filtered output.
            #[inline]
            pub fn push(&mut self, x: &[$t; CHANNELS]) -> [$t; CHANNELS] {
                // A design that reads no pre-filter output skips it
                // ([`Self::push_skipping_pre`]).
                if Self::pre_unused(self.design) {
                    return self.push_skipping_pre(x);
                } else if self.lag > 0 {
                    self.catch_up();
                }
                let p = self.raw_pos;
                self.raw[p] = *x;
                self.raw_pos = if p + 1 == RING { 0 } else { p + 1 };
                // The pre-filter runs on every tick.
                let m = $run1(&self.raw, p, &PRE, self.live());
                let q = self.mid_pos;
                self.mid[q] = m;
                self.mid_pos = if q + 1 == MID_RING { 0 } else { q + 1 };
                match self.design {
                    None => *x,
                    Some(d) if d.stride == 1 => $run1(&self.raw, p, &d.stage, self.live()),
                    Some(d) => $strided(&self.mid, q, &d.stage, d.stride, self.live()),
                }
            }
        }
    };
}

bank!(
    FirBank,
    f32,
    run_f32_1,
    run_f32_strided,
    "The float FIR over [`CHANNELS`] channels."
);
bank!(
    FirBankFixed,
    i32,
    |ring: &[[i32; CHANNELS]], end: usize, st: &Stage, _: bool| run_i32_1(ring, end, st),
    run_i32_strided_all,
    "The fixed-point FIR over [`CHANNELS`] channels (module doc); samples |x| < 2²⁹."
);

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of pseudo-random samples (xorshift), float and fixed.
    fn row(state: &mut u64) -> ([f32; CHANNELS], [i32; CHANNELS]) {
        let mut f = [0.0f32; CHANNELS];
        let mut i = [0i32; CHANNELS];
        for c in 0..CHANNELS {
            *state ^= *state << 13;
            *state ^= *state >> 7;
            *state ^= *state << 17;
            i[c] = (*state >> 40) as i32 - (1 << 23);
            f[c] = i[c] as f32 / 4096.0;
        }
        (f, i)
    }

    /// A bank that ran a one-stage design (or none) for `n` ticks and then
    /// switches to a two-stage one gives, tick for tick and bit for bit,
    /// what a bank that ran the two-stage design all along gives on the
    /// same input (the skipped pre-filter outputs are caught up): every
    /// count around the rings' lengths, float and fixed,
    /// both two-stage designs, several switches.
    #[test]
    fn a_two_stage_design_after_a_one_stage_one_sees_the_whole_history() {
        let counts = [
            0, 1, 2, 15, 16, 17, 32, 33, 47, 48, 49, 50, 64, 160, 176, 177, 178, 192, 193, 194,
            225, 226, 227, 300, 1000,
        ];
        for two in [&FIR_16HZ_2K, &FIR_33HZ_2K] {
            for one in [None, Some(&FIR_262HZ_2K), Some(&FIR_66HZ_2K)] {
                for &n in &counts {
                    let mut state = 0x9E37_79B9_7F4A_7C15u64 ^ n as u64;
                    let (f0, i0) = row(&mut state);
                    let (mut a, mut b) = (FirBank::new(one, &f0), FirBank::new(Some(two), &f0));
                    let (mut ai, mut bi) = (
                        FirBankFixed::new(one, &i0),
                        FirBankFixed::new(Some(two), &i0),
                    );
                    for round in 0..3 {
                        for _ in 0..n + round {
                            let (f, i) = row(&mut state);
                            a.push(&f);
                            b.push(&f);
                            ai.push(&i);
                            bi.push(&i);
                        }
                        a.set_design(Some(two));
                        ai.set_design(Some(two));
                        for t in 0..200 {
                            let (f, i) = row(&mut state);
                            let (ya, yb) = (a.push(&f), b.push(&f));
                            assert_eq!(
                                ya.map(f32::to_bits),
                                yb.map(f32::to_bits),
                                "{} after {n} ticks of {:?}, round {round}, tick {t}",
                                two.order,
                                one.map(|d| d.order)
                            );
                            assert_eq!(ai.push(&i), bi.push(&i), "fixed {n} {round} {t}");
                        }
                        a.set_design(one);
                        ai.set_design(one);
                    }
                }
            }
        }
    }

    #[test]
    fn const_sine_is_accurate() {
        for i in -100..100 {
            let x = i as f64 * 0.37;
            let (s, c) = sin_cos(x);
            assert!((s - libm::sin(x)).abs() < 1e-12, "{x}");
            assert!((c - libm::cos(x)).abs() < 1e-12, "{x}");
        }
    }

    #[test]
    fn q15_taps_sum_to_one_exactly_and_stages_compose_to_order_n() {
        for st in DESIGNS.iter().map(|d| &d.stage).chain([&PRE]) {
            let n = st.half_q15.len();
            let sum: i32 = st.half_q15[..n - 1].iter().sum::<i32>() * 2 + st.half_q15[n - 1];
            assert_eq!(sum, 32768);
            let fsum: f32 = st.half[..n - 1].iter().sum::<f32>() * 2.0 + st.half[n - 1];
            assert!((fsum - 1.0).abs() < 1e-6);
            assert_eq!(n, st.order / 2 + 1);
            assert!(
                st.l1() < 1.1,
                "L1 {}: the fixed-point accumulators rely on it",
                st.l1()
            );
        }
        for d in DESIGNS {
            let span = if d.stride == 1 {
                d.stage.order
            } else {
                PRE.order + d.stride * d.stage.order
            };
            assert_eq!(span, d.order);
            assert!(d.stride == 1 || d.stage.order * d.stride < MID_RING);
            // The bank runs strides 1, 2 and 4 (monomorphised).
            assert!(matches!(d.stride, 1 | 2 | 4));
            assert!(d.stride > 1 || d.order < RING);
            let sum: f32 = (0..=d.order).map(|n| d.tap(n)).sum();
            assert!((sum - 1.0).abs() < 1e-5);
            for n in 0..=d.order {
                let (a, b) = (d.tap(n), d.tap(d.order - n));
                assert!(
                    (a - b).abs() < 1e-7,
                    "symmetric: order {} n {n}: {a} {b}",
                    d.order
                );
            }
        }
    }
}
