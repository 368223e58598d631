//! The cascade filter of ICD 5.8 (Figure 5.1): Filter1², Filter2² and
//! Filter3, each bypassed or active per the `Filter` mask (Table 5.24:
//! 0x01 Filter1², 0x02 Filter2², 0x04 Filter3).
//!
//! ```text
//! Filter_i(s) = (s² + 2ζ1i ωi s + ωi²) / (s² + 2ζ2i ωi s + ωi²)     i = 1, 2
//! Filter_3(s) = 1 / (τ s + 1)
//! ```
//!
//! **Discretisation: bilinear transform pre-warped at the section's own
//! frequency** (ωi for Filter1/2, 1/τ for Filter3):
//! `s = K (1 − z⁻¹)/(1 + z⁻¹)` with `K = ω / tan(ω T / 2)`. The digital
//! response then equals the analog one *exactly* at ω (the notch/peak
//! frequency keeps its place and its gain ζ1/ζ2) and at DC (gain 1); at any
//! other frequency it equals the analog response at the warped frequency:
//! `H_d(e^{jωT}) = H_a(j · K · tan(ωT/2))`.
//! The bilinear map is stable for every stable analog section and has no
//! aliasing; it was chosen over impulse invariance (aliases, wrong DC gain
//! for these biquads) and matched-z (zeros misplaced for the notch shapes).
//! `tests/signal_cascade.rs` checks the implementation against the analog
//! transfer functions at several frequencies (module doc there states the
//! tolerance) and exactly against the warped-frequency identity.
//!
//! Guards: a section whose ω is at or beyond 0.9 × Nyquist is designed at
//! 0.9 × Nyquist (the bilinear pre-warp diverges at Nyquist); a denominator
//! damping below 1e-3 is raised to 1e-3 (ζ2 = 0 would put the poles on the
//! unit circle: an undamped oscillator). The sections run in f32 in a
//! DC-exact form ([`Section`]), or in integers in the `fixed-point` build
//! ([`CascadeFixed`]: the same sections with Q26/Q29 coefficients).
//!
//! **Design precision: `f32`** ([`crate::math::tanf`], f32 throughout),
//! at configure time. It was f64
//! (`tan`), which linked ≈ 5 KiB of soft-double code into the firmware
//! images for no accuracy the stored coefficients keep: they are `f32`
//! (or Q26/Q29 rounded from those `f32` values). The design is written in
//! t = tan(ωT/2) = ω/K, i.e. D(s) divided by K², so no term is of order K²
//! (1.6e7 at ω = 1 rad/s, 2 kHz) and the pole terms come out as `−2 + …`,
//! `1 − …` with the small part computed in relative precision: a1, a2 are
//! within a few f32 ulps of the f64 design, far inside the tolerances of
//! `tests/signal_cascade.rs` (5e-5 at each ω, 0.1 dB / 1° to 50 Hz),
//! which are unchanged.
//!
//! State: the cascade's input history plus each section's w (a section's
//! input history is the previous one's output history, rebuilt exactly;
//! see [`Cascade`]), 11 values a channel; the float channel loop is
//! specialised per Filter mask, the integer one tests the mask at run time
//! (flash: [`CascadeFixed::process`]).

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::fir::CHANNELS;

/// The channels run section by section (not on ARM): the first eight, two
/// whole four-lane vectors; the ninth (aux Z) runs on its own, or not at
/// all for a unit without the aux accelerometer (see
/// [`Cascade::set_aux_live`]).
const AUX_FIRST: usize = 8;
use crate::math::fixed::{mul64, mul_q};
use crate::math::tanf;
use libm::{cos, sin};

/// Parameters of one second-order section: ζ1 (numerator), ζ2
/// (denominator), ω (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrder {
    /// ζ1i, numerator damping (Filt*_Dzeta1).
    pub zeta_num: f32,
    /// ζ2i, denominator damping (Filt*_Dzeta2).
    pub zeta_den: f32,
    /// ωi, rad/s (Filt*_W).
    pub omega: f32,
}

/// The cascade's configuration (the Filter mask and its parameters).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CascadeConfig {
    /// 0x01 Filter1², 0x02 Filter2², 0x04 Filter3.
    pub mask: u8,
    /// Filter1 (ζ11, ζ21, ω1).
    pub filt1: SecondOrder,
    /// Filter2 (ζ12, ζ22, ω2).
    pub filt2: SecondOrder,
    /// τ of Filter3, s.
    pub tau: f32,
}

impl Default for CascadeConfig {
    /// All off, with the parameter table's defaults.
    fn default() -> Self {
        CascadeConfig {
            mask: 0,
            filt1: SecondOrder {
                zeta_num: 0.1,
                zeta_den: 0.7,
                omega: 314.159_27,
            },
            filt2: SecondOrder {
                zeta_num: 0.1,
                zeta_den: 0.7,
                omega: 628.318_5,
            },
            tau: 0.01,
        }
    }
}

/// One discrete section in the *DC-exact* form
///
/// ```text
/// H(z) = 1 + g · (1 − z⁻ᵏ) / (1 + a1 z⁻¹ + a2 z⁻²)      k = 2 (Filter1/2), 1 (Filter3)
/// ```
///
/// which is the bilinear image of `H(s) = 1 + (N(s) − D(s))/D(s)`: for the
/// biquads N − D = 2(ζ1 − ζ2)ωs, whose bilinear image has the exact factor
/// (1 − z⁻²); for Filter3, H − 1 = −τs/(τs + 1) gives (1 − z⁻¹). The zero at
/// DC is exact in any precision, so the DC gain is exactly 1 even in f32 with
/// poles close to z = 1 (a low ω at 2 kHz), where the plain
/// `(b0 + b1 z⁻¹ + b2 z⁻²)/A(z)` form with f32 coefficients is off by 1e-4.
/// It also costs 3 multiplications instead of 5.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Section {
    /// g.
    pub g: f32,
    /// a1.
    pub a1: f32,
    /// a2 (0 for Filter3).
    pub a2: f32,
    /// Filter3 (k = 1) rather than Filter1/2 (k = 2).
    pub first_order: bool,
}

/// Largest ωT/2 a section is designed at (0.9 × Nyquist; module doc).
const MAX_WARP: f32 = 0.9 * core::f32::consts::FRAC_PI_2;

impl Section {
    /// Filter1/Filter2 discretised at `rate_hz` (module doc). In `f32`, in
    /// the well-conditioned form of the module doc ("Design precision").
    pub fn second_order(p: &SecondOrder, rate_hz: f32) -> Section {
        let half = (p.omega / (2.0 * rate_hz)).clamp(1e-9, MAX_WARP);
        // t = ω/K: D(s) of the bilinear map divided by K² is
        // (1 + 2ζ2 t + t²) + 2(t² − 1) z⁻¹ + (1 − 2ζ2 t + t²) z⁻².
        let t = tanf(half);
        let zn = p.zeta_num.max(0.0);
        let zd = p.zeta_den.max(1e-3);
        let d0 = 1.0 + 2.0 * zd * t + t * t;
        Section {
            g: 2.0 * (zn - zd) * t / d0,
            // −2 + … and 1 − …: the small terms carry the pole positions.
            a1: -2.0 + 4.0 * t * (zd + t) / d0,
            a2: 1.0 - 4.0 * zd * t / d0,
            first_order: false,
        }
    }

    /// Filter3 discretised at `rate_hz` (pre-warped at 1/τ).
    pub fn first_order(tau: f32, rate_hz: f32) -> Section {
        let tau = tau.max(1e-9);
        let half = (1.0 / (2.0 * tau * rate_hz)).clamp(1e-9, MAX_WARP);
        // 1/(τ' s + 1), τ' = 1/ωc (= τ unless clamped), K τ' = 1/t.
        let t = tanf(half);
        Section {
            g: -1.0 / (1.0 + t),
            a1: -1.0 + 2.0 * t / (1.0 + t),
            a2: 0.0,
            first_order: true,
        }
    }

    /// The section's frequency response at `f_hz` for `rate_hz`: (re, im),
    /// from the coefficients as stored.
    pub fn response(&self, f_hz: f64, rate_hz: f64) -> (f64, f64) {
        let w = core::f64::consts::TAU * f_hz / rate_hz;
        // z⁻¹ = e^{−jw}
        let (c1, s1) = (cos(w), -sin(w));
        let (c2, s2) = (cos(2.0 * w), -sin(2.0 * w));
        let (g, a1, a2) = (f64::from(self.g), f64::from(self.a1), f64::from(self.a2));
        let num = if self.first_order {
            (g * (1.0 - c1), -g * s1)
        } else {
            (g * (1.0 - c2), -g * s2)
        };
        let den = (1.0 + a1 * c1 + a2 * c2, a1 * s1 + a2 * s2);
        let d = den.0 * den.0 + den.1 * den.1;
        (
            1.0 + (num.0 * den.0 + num.1 * den.1) / d,
            (num.1 * den.0 - num.0 * den.1) / d,
        )
    }
}

/// Most sections: Filter1 twice, Filter2 twice, Filter3.
pub(crate) const MAX_SECTIONS: usize = 5;

/// Slots of the per-channel state ([`Cascade`]): the cascade's input one
/// and two ticks ago, then w[n−1], w[n−2] of Filter1 (twice) and Filter2
/// (twice), then w[n−1] of Filter3.
const STATE: usize = 11;

/// The cascade over [`CHANNELS`] channels.
///
/// **State.** A section's input history is the previous section's output
/// history, y = u + w, so only the cascade's input history and each
/// section's w are kept: the next section's u[n−1], u[n−2] are rebuilt as
/// u[n−1] + w[n−1], u[n−2] + w[n−2] — the same additions, on the same
/// operands, that produced them, so bit for bit the values a per-section
/// history would hold, in 11 values per channel instead of 20. The channel
/// loop is specialised per Filter mask (sections at fixed places, the
/// coefficients in registers).
#[derive(Debug, Clone)]
pub struct Cascade {
    sections: [Section; MAX_SECTIONS],
    n: usize,
    mask: u8,
    /// Slot (see [`STATE`]) × channel, laid out by [`at`].
    state: [f32; STATE * CHANNELS],
    /// Whether the aux channels are filtered ([`Cascade::set_aux_live`]).
    aux_live: bool,
}

/// Slot-major (each slot's nine channels contiguous: the section-by-section
/// loop vectorises) except on ARM, where the channel-by-channel loop reads a
/// channel's slots at small fixed offsets.
// Fork by architecture: SIMD lanes on hosts, registers on ARM; bit-identical results.
const SLOT_MAJOR: bool = !cfg!(target_arch = "arm");

/// Index of slot `k`, channel `c` in [`Cascade`]'s state.
#[inline(always)]
const fn at(k: usize, c: usize) -> usize {
    if SLOT_MAJOR {
        k * CHANNELS + c
    } else {
        c * STATE + k
    }
}

/// One Filter1/2 section on sample `u` of channel `c`: `p` = its input
/// history (u[n−1], u[n−2]) on entry, the next section's on return; its
/// w[n−1], w[n−2] are slots `k`, `k + 1`.
#[inline(always)]
fn second_f32(
    st: &mut [f32; STATE * CHANNELS],
    k: usize,
    c: usize,
    s: &Section,
    u: f32,
    p: &mut [f32; 2],
    last: bool,
) -> f32 {
    let (w1, w2) = (st[at(k, c)], st[at(k + 1, c)]);
    let wn = s.g * (u - p[1]) - s.a1 * w1 - s.a2 * w2;
    st[at(k, c)] = wn;
    st[at(k + 1, c)] = w1;
    if !last {
        p[0] += w1;
        p[1] += w2;
    }
    u + wn
}

/// `second_f32` for the first `N` channels at once, in whole-row loops
/// (slots `K`, `K + 1`; `p0`, `p1` the input history rows).
#[inline(always)]
fn rows<const K: usize, const N: usize>(
    st: &mut [f32; STATE * CHANNELS],
    f: &Section,
    x: &mut [f32; CHANNELS],
    p0: &mut [f32; CHANNELS],
    p1: &mut [f32; CHANNELS],
    last: bool,
) {
    let mut wn = [0.0f32; CHANNELS];
    for c in 0..N {
        wn[c] = f.g * (x[c] - p1[c]) - f.a1 * st[at(K, c)] - f.a2 * st[at(K + 1, c)];
    }
    if !last {
        for c in 0..N {
            p0[c] += st[at(K, c)];
            p1[c] += st[at(K + 1, c)];
        }
    }
    for c in 0..N {
        st[at(K + 1, c)] = st[at(K, c)];
        st[at(K, c)] = wn[c];
        x[c] += wn[c];
    }
}

impl Cascade {
    /// The cascade of `cfg` at `rate_hz`, in steady state for input `x`.
    pub fn new(cfg: &CascadeConfig, rate_hz: u32, x: &[f32; CHANNELS]) -> Self {
        let mut c = Cascade {
            sections: [Section::default(); MAX_SECTIONS],
            n: 0,
            mask: 0,
            state: [0.0; STATE * CHANNELS],
            aux_live: true,
        };
        c.configure(cfg, rate_hz, x);
        c
    }

    /// Whether the aux accelerometer's channels (the last three) are live;
    /// off (a unit without one), [`Cascade::process`]
    /// leaves the last channel as it is (the chain reports zeros for the
    /// aux channels).
    pub fn set_aux_live(&mut self, live: bool) {
        self.aux_live = live;
    }

    /// Re-designs the sections and puts them in steady state for input `x`
    /// (no start-up transient).
    pub fn configure(&mut self, cfg: &CascadeConfig, rate_hz: u32, x: &[f32; CHANNELS]) {
        let fs = rate_hz as f32;
        self.n = 0;
        let mut push = |s: Section| {
            self.sections[self.n] = s;
            self.n += 1;
        };
        if cfg.mask & 0x01 != 0 {
            let s = Section::second_order(&cfg.filt1, fs);
            push(s);
            push(s);
        }
        if cfg.mask & 0x02 != 0 {
            let s = Section::second_order(&cfg.filt2, fs);
            push(s);
            push(s);
        }
        if cfg.mask & 0x04 != 0 {
            push(Section::first_order(cfg.tau, fs));
        }
        self.mask = cfg.mask & 0x07;
        self.reset(x);
    }

    /// The active sections, in order.
    pub fn sections(&self) -> &[Section] {
        &self.sections[..self.n]
    }

    /// Steady state for a constant input `x` (every section has DC gain 1).
    pub fn reset(&mut self, x: &[f32; CHANNELS]) {
        self.state = [0.0; STATE * CHANNELS];
        for (c, &v) in x.iter().enumerate() {
            self.state[at(0, c)] = v;
            self.state[at(1, c)] = v;
        }
    }

    /// Filters one sample per channel in place.
    #[inline]
    pub fn process(&mut self, x: &mut [f32; CHANNELS]) {
        match self.mask {
            1 => self.run::<1>(x),
            2 => self.run::<2>(x),
            3 => self.run::<3>(x),
            4 => self.run::<4>(x),
            5 => self.run::<5>(x),
            6 => self.run::<6>(x),
            7 => self.run::<7>(x),
            _ => {}
        }
    }

    /// [`Cascade::process`] for Filter mask `M`: channel by channel on ARM
    /// (no SIMD: a channel's state stays in registers through the sections),
    /// section by section elsewhere (the channels vectorise). The same
    /// operations on the same operands: bit-identical (a unit test pins it).
    #[inline(always)]
    fn run<const M: u8>(&mut self, x: &mut [f32; CHANNELS]) {
        // Fork by architecture, as `SLOT_MAJOR`.
        if cfg!(target_arch = "arm") {
            self.run_by_channel::<M>(x)
        } else {
            // The first eight channels section by section (two whole
            // four-lane vectors), the ninth on its own: its arithmetic is
            // the same in either order (`both_loop_orders_are_bit_identical`).
            self.run_by_section::<M, AUX_FIRST>(x);
            if !self.aux_live {
                return;
            }
            self.run_channels::<M>(x, AUX_FIRST)
        }
    }

    /// [`Cascade::run`] section by section.
    #[inline(always)]
    fn run_by_section<const M: u8, const N: usize>(&mut self, x: &mut [f32; CHANNELS]) {
        let s = &self.sections;
        let f1 = s[0];
        let f2 = s[if M & 1 != 0 { 2 } else { 0 }];
        let f3 = s[self.n.saturating_sub(1)];
        let st = &mut self.state;
        // The input history rows, then the same arithmetic as `second_f32`
        // in whole-row loops (contiguous on hosts: they vectorise).
        let (mut p0, mut p1) = ([0.0f32; CHANNELS], [0.0f32; CHANNELS]);
        for c in 0..N {
            p0[c] = st[at(0, c)];
            p1[c] = st[at(1, c)];
            st[at(1, c)] = p0[c];
            st[at(0, c)] = x[c];
        }
        if M & 1 != 0 {
            rows::<2, N>(st, &f1, x, &mut p0, &mut p1, false);
            rows::<4, N>(st, &f1, x, &mut p0, &mut p1, M & 6 == 0);
        }
        if M & 2 != 0 {
            rows::<6, N>(st, &f2, x, &mut p0, &mut p1, false);
            rows::<8, N>(st, &f2, x, &mut p0, &mut p1, M & 4 == 0);
        }
        if M & 4 != 0 {
            for c in 0..N {
                let u = x[c];
                let wn = f3.g * (u - p0[c]) - f3.a1 * st[at(10, c)];
                st[at(10, c)] = wn;
                x[c] = u + wn;
            }
        }
    }

    /// [`Cascade::run`] channel by channel.
    #[inline(always)]
    fn run_by_channel<const M: u8>(&mut self, x: &mut [f32; CHANNELS]) {
        self.run_channels::<M>(x, 0)
    }

    /// [`Cascade::run_by_channel`] for the channels from `from` on.
    #[inline(always)]
    fn run_channels<const M: u8>(&mut self, x: &mut [f32; CHANNELS], from: usize) {
        let s = &self.sections;
        let f1 = s[0];
        let f2 = s[if M & 1 != 0 { 2 } else { 0 }];
        let f3 = s[self.n.saturating_sub(1)];
        let st = &mut self.state;
        for c in from..CHANNELS {
            let mut u = x[c];
            let mut p = [st[at(0, c)], st[at(1, c)]];
            st[at(1, c)] = st[at(0, c)];
            st[at(0, c)] = u;
            if M & 1 != 0 {
                u = second_f32(st, 2, c, &f1, u, &mut p, false);
                u = second_f32(st, 4, c, &f1, u, &mut p, M & 6 == 0);
            }
            if M & 2 != 0 {
                u = second_f32(st, 6, c, &f2, u, &mut p, false);
                u = second_f32(st, 8, c, &f2, u, &mut p, M & 4 == 0);
            }
            if M & 4 != 0 {
                let wn = f3.g * (u - p[0]) - f3.a1 * st[at(10, c)];
                st[at(10, c)] = wn;
                u += wn;
            }
            x[c] = u;
        }
    }

    /// The whole cascade's response at `f_hz`: (re, im).
    pub fn response(&self, f_hz: f64, rate_hz: f64) -> (f64, f64) {
        let mut acc = (1.0, 0.0);
        for s in self.sections() {
            let r = s.response(f_hz, rate_hz);
            acc = (acc.0 * r.0 - acc.1 * r.1, acc.0 * r.1 + acc.1 * r.0);
        }
        acc
    }
}

#[cfg(test)]
mod order_tests {
    use super::*;

    /// Section by section and channel by channel give the same bits.
    #[test]
    fn both_loop_orders_are_bit_identical() {
        let d = CascadeConfig::default();
        for mask in 0..8u8 {
            let cfg = CascadeConfig { mask, ..d };
            let x0 = [0.5f32, -1.0, 3.0, 0.0, 0.1, 1.0, -0.2, 0.3, 9.0];
            let mut a = Cascade::new(&cfg, 2000, &x0);
            let mut b = a.clone();
            // `process`: eight channels section by section, the ninth alone.
            let mut c = a.clone();
            let mut s = 0x2545_F491u32;
            for _ in 0..5000 {
                let mut x = x0;
                for v in x.iter_mut() {
                    s ^= s << 13;
                    s ^= s >> 17;
                    s ^= s << 5;
                    *v += (s as f32 / u32::MAX as f32) - 0.5;
                }
                let mut y = x;
                let mut z = x;
                c.process(&mut z);
                match mask {
                    1 => (
                        a.run_by_section::<1, CHANNELS>(&mut x),
                        b.run_by_channel::<1>(&mut y),
                    ),
                    2 => (
                        a.run_by_section::<2, CHANNELS>(&mut x),
                        b.run_by_channel::<2>(&mut y),
                    ),
                    3 => (
                        a.run_by_section::<3, CHANNELS>(&mut x),
                        b.run_by_channel::<3>(&mut y),
                    ),
                    4 => (
                        a.run_by_section::<4, CHANNELS>(&mut x),
                        b.run_by_channel::<4>(&mut y),
                    ),
                    5 => (
                        a.run_by_section::<5, CHANNELS>(&mut x),
                        b.run_by_channel::<5>(&mut y),
                    ),
                    6 => (
                        a.run_by_section::<6, CHANNELS>(&mut x),
                        b.run_by_channel::<6>(&mut y),
                    ),
                    7 => (
                        a.run_by_section::<7, CHANNELS>(&mut x),
                        b.run_by_channel::<7>(&mut y),
                    ),
                    _ => ((), ()),
                };
                assert_eq!(x.map(f32::to_bits), y.map(f32::to_bits), "mask {mask}");
                assert_eq!(x.map(f32::to_bits), z.map(f32::to_bits), "mask {mask}");
            }
            assert_eq!(a.state, b.state);
            assert_eq!(a.state, c.state);
        }
    }
}

/// Fraction bits of the fixed-point numerator gain g (|g| < 32).
const QG: u32 = 26;
/// Fraction bits of the fixed-point denominator coefficients (|a| < 2).
const QA: u32 = 29;

/// A [`Section`] in fixed point, for [`CascadeFixed`]: g in Q26, a1 and a2 in
/// Q29 (finer than the float path's `f32`, whose spacing near |a1| = 2 is
/// 2.4e-7).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SectionFixed {
    g: i32,
    a1: i32,
    a2: i32,
    first_order: bool,
}

impl SectionFixed {
    /// `s` rounded to the fixed-point formats (g clamped to ±32).
    pub fn from_float(s: &Section) -> Self {
        // x·2^bits is exact in f32 (a power-of-two scale), so rounding it in
        // f32 gives the same integer as in f64; beyond i32 it saturates.
        let q = |x: f32, bits: u32| (libm::roundf(x * (1u32 << bits) as f32) as i32).max(-i32::MAX);
        SectionFixed {
            g: q(s.g, QG),
            a1: q(s.a1, QA),
            a2: q(s.a2, QA),
            first_order: s.first_order,
        }
    }

    /// w[n] from the input u[n], u[n−k] and w[n−1], w[n−2], rounded and
    /// saturated. The products are 32-bit ([`mul_q`], four `MULS` each)
    /// while every term fits 2³⁰ — the normal case, checked on the operands
    /// — and exact 64-bit ([`mul64`]) otherwise.
    #[inline(always)]
    fn w(&self, u: i32, uk: i32, w1: i32, w2: i32, second: bool) -> i32 {
        const BIG: u32 = 1 << 29;
        let d = u.wrapping_sub(uk);
        let small = (u.unsigned_abs() | uk.unsigned_abs()) < BIG
            && (w1.unsigned_abs() | w2.unsigned_abs()) < BIG
            && self.g.unsigned_abs() < 1 << QG;
        if small {
            // |d| < 2³⁰, |g| < 1: |t| < 2³⁰; |a| < 2, |w| < 2²⁹: |r| < 2³¹.
            let t = mul_q::<QG>(self.g, d);
            let r = if second {
                mul_q::<QA>(self.a1, w1) + mul_q::<QA>(self.a2, w2)
            } else {
                mul_q::<QA>(self.a1, w1)
            };
            return t.saturating_sub(r);
        }
        self.w_wide(u, uk, w1, w2)
    }

    /// [`SectionFixed::w`] beyond 2²⁹: exact 64-bit products. Out of line
    /// and cold (a resonant cascade near full scale): one copy in flash
    /// instead of one per inlined section.
    #[cold]
    #[inline(never)]
    fn w_wide(&self, u: i32, uk: i32, w1: i32, w2: i32) -> i32 {
        let gd = match u.checked_sub(uk) {
            Some(d) => mul64(self.g, d),
            None => mul64(self.g, u) - mul64(self.g, uk),
        };
        let t = (gd + (1 << (QG - 1))) >> QG;
        let r = (mul64(self.a1, w1) + mul64(self.a2, w2) + (1 << (QA - 1))) >> QA;
        (t - r).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
    }
}

/// One Filter1/2 section of [`CascadeFixed`] (as [`second_f32`]).
#[inline(always)]
fn second_fixed(s: &SectionFixed, u: i32, p: &mut [i32; 2], w: &mut [i32], last: bool) -> i32 {
    let (w1, w2) = (w[0], w[1]);
    let wn = s.w(u, p[1], w1, w2, true);
    w[0] = wn;
    w[1] = w1;
    if !last {
        p[0] = p[0].saturating_add(w1);
        p[1] = p[1].saturating_add(w2);
    }
    u.saturating_add(wn)
}

/// The cascade in fixed point (the `fixed-point` build, for cores without an
/// FPU): the same DC-exact sections and the same shared-history state
/// layout as [`Cascade`], on `i32` samples (the FIR's scale), g in Q26 and
/// a1, a2 in Q29, the state w in the samples' unit; products are exact
/// 32 × 32 → 64 ([`mul64`]: four 16-bit products, no library call). A signal
/// beyond the `i32` range (a resonant cascade driving a full-scale signal
/// past 16384 °/s or 2048 g) saturates. Constant input gives exactly the
/// input back; the accuracy against an f64 evaluation is pinned by a parity
/// test.
#[derive(Debug, Clone)]
pub struct CascadeFixed {
    sections: [SectionFixed; 3],
    mask: u8,
    /// Per channel: see [`STATE`] (the state w in Q2).
    state: [[i32; STATE]; CHANNELS],
}

impl CascadeFixed {
    /// The cascade of `cfg` at `rate_hz`, in steady state for input `x`.
    pub fn new(cfg: &CascadeConfig, rate_hz: u32, x: &[i32; CHANNELS]) -> Self {
        let mut c = CascadeFixed {
            sections: [SectionFixed::default(); 3],
            mask: 0,
            state: [[0; STATE]; CHANNELS],
        };
        c.configure(cfg, rate_hz, x);
        c
    }

    /// Re-designs (through the float design) and resets to steady state.
    pub fn configure(&mut self, cfg: &CascadeConfig, rate_hz: u32, x: &[i32; CHANNELS]) {
        let fs = rate_hz as f32;
        self.sections = [
            SectionFixed::from_float(&Section::second_order(&cfg.filt1, fs)),
            SectionFixed::from_float(&Section::second_order(&cfg.filt2, fs)),
            SectionFixed::from_float(&Section::first_order(cfg.tau, fs)),
        ];
        self.mask = cfg.mask & 0x07;
        self.reset(x);
    }

    /// Steady state for a constant input `x`.
    pub fn reset(&mut self, x: &[i32; CHANNELS]) {
        for (st, &v) in self.state.iter_mut().zip(x) {
            *st = [0; STATE];
            st[0] = v;
            st[1] = v;
        }
    }

    /// Filters one sample per channel in place. One loop for every Filter
    /// mask, the mask tested per channel (a few predictable branches), not
    /// one specialised copy per mask as in [`Cascade`]: on ARMv6-M each copy
    /// of the integer sections is 0.5–3 KiB of flash (12 KiB for all seven).
    pub fn process(&mut self, x: &mut [i32; CHANNELS]) {
        let m = self.mask;
        if m == 0 {
            return;
        }
        let [f1, f2, f3] = self.sections;
        for (xc, st) in x.iter_mut().zip(self.state.iter_mut()) {
            let mut u = *xc;
            let mut p = [st[0], st[1]];
            st[1] = st[0];
            st[0] = u;
            if m & 1 != 0 {
                u = second_fixed(&f1, u, &mut p, &mut st[2..4], false);
                u = second_fixed(&f1, u, &mut p, &mut st[4..6], m & 6 == 0);
            }
            if m & 2 != 0 {
                u = second_fixed(&f2, u, &mut p, &mut st[6..8], false);
                u = second_fixed(&f2, u, &mut p, &mut st[8..10], m & 4 == 0);
            }
            if m & 4 != 0 {
                let wn = f3.w(u, p[0], st[10], 0, false);
                st[10] = wn;
                u = u.saturating_add(wn);
            }
            *xc = u;
        }
    }
}
