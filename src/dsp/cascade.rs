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
//! unit circle: an undamped oscillator). Coefficients are computed in f64
//! at configure time; the sections run in f32 in a DC-exact form
//! ([`Section`]).
//! Both paths (float and fixed-point FIR) use this float cascade.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::fir::CHANNELS;
use libm::{cos, sin, tan};

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

const MAX_WARP: f64 = 0.9 * core::f64::consts::FRAC_PI_2;

impl Section {
    /// Filter1/Filter2 discretised at `rate_hz` (module doc).
    pub fn second_order(p: &SecondOrder, rate_hz: f64) -> Section {
        let t = 1.0 / rate_hz;
        let half = (f64::from(p.omega) * t / 2.0).clamp(1e-9, MAX_WARP);
        let w = 2.0 * half / t;
        let k = w / tan(half);
        let zn = f64::from(p.zeta_num).max(0.0);
        let zd = f64::from(p.zeta_den).max(1e-3);
        let (k2, w2) = (k * k, w * w);
        let d0 = k2 + 2.0 * zd * w * k + w2;
        let d1 = 2.0 * (w2 - k2);
        let d2 = k2 - 2.0 * zd * w * k + w2;
        Section {
            g: (2.0 * (zn - zd) * w * k / d0) as f32,
            a1: (d1 / d0) as f32,
            a2: (d2 / d0) as f32,
            first_order: false,
        }
    }

    /// Filter3 discretised at `rate_hz` (pre-warped at 1/τ).
    pub fn first_order(tau: f32, rate_hz: f64) -> Section {
        let t = 1.0 / rate_hz;
        let tau = f64::from(tau).max(1e-9);
        let half = (t / (2.0 * tau)).clamp(1e-9, MAX_WARP);
        let wc = 2.0 * half / t;
        let k = wc / tan(half);
        // 1/(τ' s + 1) with τ' = 1/wc (= τ unless clamped).
        let tk = k / wc;
        let d0 = tk + 1.0;
        Section {
            g: (-tk / d0) as f32,
            a1: ((1.0 - tk) / d0) as f32,
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
pub const MAX_SECTIONS: usize = 5;

/// The cascade over [`CHANNELS`] channels.
#[derive(Debug, Clone)]
pub struct Cascade {
    sections: [Section; MAX_SECTIONS],
    n: usize,
    /// Per section: u[n−1], u[n−2], w[n−1], w[n−2], each per channel.
    state: [[[f32; CHANNELS]; 4]; MAX_SECTIONS],
}

impl Cascade {
    /// The cascade of `cfg` at `rate_hz`, in steady state for input `x`.
    pub fn new(cfg: &CascadeConfig, rate_hz: u32, x: &[f32; CHANNELS]) -> Self {
        let mut c = Cascade {
            sections: [Section::default(); MAX_SECTIONS],
            n: 0,
            state: [[[0.0; CHANNELS]; 4]; MAX_SECTIONS],
        };
        c.configure(cfg, rate_hz, x);
        c
    }

    /// Re-designs the sections and puts them in steady state for input `x`
    /// (no start-up transient).
    pub fn configure(&mut self, cfg: &CascadeConfig, rate_hz: u32, x: &[f32; CHANNELS]) {
        let fs = f64::from(rate_hz);
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
        self.reset(x);
    }

    /// The active sections, in order.
    pub fn sections(&self) -> &[Section] {
        &self.sections[..self.n]
    }

    /// Steady state for a constant input `x` (every section has DC gain 1).
    pub fn reset(&mut self, x: &[f32; CHANNELS]) {
        for st in self.state[..self.n].iter_mut() {
            *st = [*x, *x, [0.0; CHANNELS], [0.0; CHANNELS]];
        }
    }

    /// Filters one sample per channel in place.
    #[inline]
    pub fn process(&mut self, x: &mut [f32; CHANNELS]) {
        for (s, st) in self.sections[..self.n].iter().zip(self.state.iter_mut()) {
            let [u1, u2, w1, w2] = st;
            if s.first_order {
                for c in 0..CHANNELS {
                    let u = x[c];
                    let w = s.g * (u - u1[c]) - s.a1 * w1[c];
                    u1[c] = u;
                    w1[c] = w;
                    x[c] = u + w;
                }
            } else {
                for c in 0..CHANNELS {
                    let u = x[c];
                    let w = s.g * (u - u2[c]) - s.a1 * w1[c] - s.a2 * w2[c];
                    u2[c] = u1[c];
                    u1[c] = u;
                    w2[c] = w1[c];
                    w1[c] = w;
                    x[c] = u + w;
                }
            }
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

/// Fraction bits of the fixed-point cascade's internal state `w`.
const W_FRAC: u32 = 4;
/// Fraction bits of the fixed-point coefficients.
const Q: u32 = 24;

/// A [`Section`] with Q24 coefficients, for [`CascadeFixed`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SectionFixed {
    g: i32,
    a1: i32,
    a2: i32,
    first_order: bool,
}

impl SectionFixed {
    /// `s` rounded to Q24 (|coefficients| < 2, so they fit with room).
    pub fn from_float(s: &Section) -> Self {
        let q = |x: f32| libm::round(f64::from(x) * f64::from(1u32 << Q)) as i32;
        SectionFixed {
            g: q(s.g),
            a1: q(s.a1),
            a2: q(s.a2),
            first_order: s.first_order,
        }
    }
}

/// The cascade in fixed point (the `fixed-point` build, for cores without an
/// FPU): the same DC-exact sections on `i32` samples (the FIR's scale), Q24
/// coefficients, the internal state `w` with 4 extra fraction bits in `i64`,
/// 64-bit products (|g·d| < 2⁵⁵, |a·w| < 2⁶¹: no overflow for |x| < 2²⁹ and
/// section gains below 16). An output beyond the `i32` range (a resonant
/// cascade driving a full-scale signal past 16384 °/s or 2048 g) saturates.
/// Constant input gives exactly the input back; the accuracy against an f64
/// evaluation (better than the f32 path's) is pinned by a parity test.
#[derive(Debug, Clone)]
pub struct CascadeFixed {
    sections: [SectionFixed; MAX_SECTIONS],
    n: usize,
    /// Per section, per channel: u[n−1], u[n−2] (i32) and w[n−1], w[n−2]
    /// (Q4, i64).
    u: [[[i32; 2]; CHANNELS]; MAX_SECTIONS],
    w: [[[i64; 2]; CHANNELS]; MAX_SECTIONS],
}

impl CascadeFixed {
    /// The cascade of `cfg` at `rate_hz`, in steady state for input `x`.
    pub fn new(cfg: &CascadeConfig, rate_hz: u32, x: &[i32; CHANNELS]) -> Self {
        let mut c = CascadeFixed {
            sections: [SectionFixed::default(); MAX_SECTIONS],
            n: 0,
            u: [[[0; 2]; CHANNELS]; MAX_SECTIONS],
            w: [[[0; 2]; CHANNELS]; MAX_SECTIONS],
        };
        c.configure(cfg, rate_hz, x);
        c
    }

    /// Re-designs (through the float design) and resets to steady state.
    pub fn configure(&mut self, cfg: &CascadeConfig, rate_hz: u32, x: &[i32; CHANNELS]) {
        let f = Cascade::new(cfg, rate_hz, &[0.0; CHANNELS]);
        self.n = f.sections().len();
        for (d, s) in self.sections.iter_mut().zip(f.sections()) {
            *d = SectionFixed::from_float(s);
        }
        self.reset(x);
    }

    /// Steady state for a constant input `x`.
    pub fn reset(&mut self, x: &[i32; CHANNELS]) {
        for k in 0..self.n {
            for c in 0..CHANNELS {
                self.u[k][c] = [x[c]; 2];
                self.w[k][c] = [0; 2];
            }
        }
    }

    /// Filters one sample per channel in place.
    #[inline]
    pub fn process(&mut self, x: &mut [i32; CHANNELS]) {
        const ROUND_Q: i64 = 1 << (Q - 1);
        const ROUND_W: i64 = 1 << (W_FRAC - 1);
        for k in 0..self.n {
            let s = self.sections[k];
            let (g, a1, a2) = (i64::from(s.g), i64::from(s.a1), i64::from(s.a2));
            for c in 0..CHANNELS {
                let u = x[c];
                let [u1, u2] = self.u[k][c];
                let [w1, w2] = self.w[k][c];
                let d = i64::from(u) - i64::from(if s.first_order { u1 } else { u2 });
                let w = if s.first_order {
                    ((g * d) >> (Q - W_FRAC)) - ((a1 * w1 + ROUND_Q) >> Q)
                } else {
                    ((g * d) >> (Q - W_FRAC)) - ((a1 * w1 + a2 * w2 + ROUND_Q) >> Q)
                };
                self.u[k][c] = [u, u1];
                self.w[k][c] = [w, w1];
                let y = i64::from(u) + ((w + ROUND_W) >> W_FRAC);
                x[c] = y.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
            }
        }
    }
}
