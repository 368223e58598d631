//! Cumulative integrals since power-on, from which any output stream takes
//! its own window by differences — whatever its period, without an
//! accumulator of its own in the chain (the KERNEL's variants, the IMX's IMU
//! and PIMU).
//!
//! **What is integrated.** Every tick adds the *pre-FIR measurement* in
//! carrier axes (after the mounting rotation, before any filter), with the
//! gyro bias estimate *not* removed — what an IMU's own raw integration of
//! its sensors gives; a stream that wants the bias out subtracts
//! `bias × window length`. Only the gyro and the main accelerometer are
//! integrated.
//!
//! **Representation.** The samples are integers at the fixed-point sensor
//! scale ([`RATE_BITS`], [`FORCE_BITS`]: 2¹⁹ per °/s, 2²³ per g; the float
//! chain rounds its `f32` measurement to that grid, ≤ 1e-6 °/s, 6e-8 g), so
//! every sum is integer arithmetic, wrapping: a window computed at hour 10
//! is as exact as one computed at power-on (no `f32` accumulator loses the
//! small increments to a large total; the uncorrected Δθ and Δv are the
//! same bits). Per tick, with ω_k and f_k the
//! samples and Θ, V their running sums (all `i64`):
//!
//! ```text
//! Θ_n = Σ_{k≤n} ω_k          V_n = Σ_{k≤n} f_k                  (exact)
//! C_n = Σ_{k≤n} ⟦Θ_{k−1} × ω_k⟧
//! S_n = Σ_{k≤n} ⟦Θ_{k−1} × f_k⟧ + ⟦V_{k−1} × ω_k⟧
//! ```
//!
//! where ⟦x⟧ is each product term `a·b` divided by 2^[`CROSS_SHIFT`] and
//! rounded, modulo 2⁶⁴ (computed exactly from two 32 × 32-bit products).
//! For a window (a, b] — snapshots at its two ends — the in-window sums
//! Σ (Θ_{k−1} − Θ_a) × ω_k and Σ ((Θ_{k−1} − Θ_a) × f_k + (V_{k−1} − V_a)
//! × ω_k) are `C_b − C_a − ⟦Θ_a × (Θ_b − Θ_a)⟧` and `S_b − S_a − ⟦Θ_a ×
//! (V_b − V_a)⟧ − ⟦V_a × (Θ_b − Θ_a)⟧` (integer identities: the wrapping
//! cancels; each rounding adds at most ½ LSB, so the error grows with the
//! window's length, never with the time since power-on: at most 1.1e-9 rad
//! and 7.4e-8 m/s over a one-hour window at 2 kHz). [`window`] turns them into
//! the coning-corrected Δθ and the rotation- and sculling-corrected Δv of
//! [`crate::dsp::variant`]'s incremental output (the same formulas,
//! expressed in the body frame at the window's start):
//!
//! ```text
//! Δθ = α + ½ Σ α_{k−1} × Δα_k
//! Δv = υ + ½ α × υ + ½ Σ (α_{k−1} × Δυ_k + υ_{k−1} × Δα_k)
//! ```
//!
//! **Range.** Θ wraps after ≥ 2³³ ticks at the full ±2000 °/s scale (49
//! days at 2 kHz, 24 at 4 kHz); a window must not contain that wrap. The
//! in-window cross sums hold ±2⁶³ units (2⁸³ product units): at 2 kHz,
//! 2 679 rad² of Σ α × Δα and 9.4e4 rad·m/s of sculling sum — a full-scale
//! rotation about two axes at once with 40 g for 2 s (1 s at 4 kHz).
//!
//! **Cost.** Per tick: 6 `i64` additions and 36 32 × 32 → 64-bit products
//! (18 product terms), 6 `i64` sums; [`window`] (in `f64`) runs only when a
//! stream asks. Only a chain that keeps them pays: the chain's type says
//! so ([`Integrate`]: `SignalChain<Integrals>`; the default
//! `SignalChain<NoIntegrals>`, the KERNEL's, has no storage and no code for
//! them).

use crate::math::rotation::Vec3;
use crate::math::G;

/// Fraction bits of the integrated gyro samples: 2¹⁹ per °/s.
pub(crate) const RATE_BITS: u32 = 19;
/// Fraction bits of the integrated accelerometer samples: 2²³ per g.
pub(crate) const FORCE_BITS: u32 = 23;

/// Each cross-product term is divided by 2^CROSS_SHIFT (rounded) before it
/// is summed (module doc).
pub(crate) const CROSS_SHIFT: u32 = 20;

/// The cumulative integrals at one moment (a snapshot; module doc for the
/// quantities). Keep two of them and pass them to [`window`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Integrals {
    /// Samples (ticks) integrated.
    pub samples: u64,
    /// Θ: Σ ω_k, °/s·2^[`RATE_BITS`] per tick (× tick period = angle).
    pub theta: [i64; 3],
    /// V: Σ f_k, g·2^[`FORCE_BITS`] per tick.
    pub vel: [i64; 3],
    /// C: Σ ⟦Θ_{k−1} × ω_k⟧.
    pub coning: [i64; 3],
    /// S: Σ ⟦Θ_{k−1} × f_k⟧ + ⟦V_{k−1} × ω_k⟧.
    pub sculling: [i64; 3],
}

/// ⟦a·b⟧: `a·b / 2^CROSS_SHIFT` rounded (half up), modulo 2⁶⁴, exact for any
/// `a` (from the halves of `a`: the high one's product is a multiple of
/// 2³², so only the low one's is rounded).
#[inline(always)]
fn term(a: i64, b: i32) -> i64 {
    let hi = (a >> 32) as i32;
    let lo = a as u32;
    let p_hi = i64::from(hi) * i64::from(b);
    let p_lo = i64::from(lo) * i64::from(b);
    p_hi.wrapping_shl(32 - CROSS_SHIFT)
        .wrapping_add((p_lo + (1 << (CROSS_SHIFT - 1))) >> CROSS_SHIFT)
}

/// ⟦a × b⟧ (each of the six products), wrapping.
#[inline(always)]
fn cross_terms(a: &[i64; 3], b: &[i32; 3]) -> [i64; 3] {
    [
        term(a[1], b[2]).wrapping_sub(term(a[2], b[1])),
        term(a[2], b[0]).wrapping_sub(term(a[0], b[2])),
        term(a[0], b[1]).wrapping_sub(term(a[1], b[0])),
    ]
}

/// ⟦a·b⟧ of two `i64`s (the window's end correction), the same rounding.
fn term_wide(a: i64, b: i64) -> i64 {
    let p = i128::from(a) * i128::from(b);
    ((p + (1 << (CROSS_SHIFT - 1))) >> CROSS_SHIFT) as i64
}

/// ⟦a × b⟧ of two `i64` vectors, wrapping.
fn cross_terms_wide(a: &[i64; 3], b: &[i64; 3]) -> [i64; 3] {
    [
        term_wide(a[1], b[2]).wrapping_sub(term_wide(a[2], b[1])),
        term_wide(a[2], b[0]).wrapping_sub(term_wide(a[0], b[2])),
        term_wide(a[0], b[1]).wrapping_sub(term_wide(a[1], b[0])),
    ]
}

/// `a × b` of two `i64` vectors, exact.
fn cross_exact(a: &[i64; 3], b: &[i64; 3]) -> [i128; 3] {
    let m = |x: i64, y: i64| i128::from(x) * i128::from(y);
    [
        m(a[1], b[2]) - m(a[2], b[1]),
        m(a[2], b[0]) - m(a[0], b[2]),
        m(a[0], b[1]) - m(a[1], b[0]),
    ]
}

impl Integrals {
    /// Adds one tick: gyro `w` (°/s·2^[`RATE_BITS`]) and specific force `f`
    /// (g·2^[`FORCE_BITS`]), carrier axes.
    #[inline]
    pub fn add(&mut self, w: &[i32; 3], f: &[i32; 3]) {
        let c = cross_terms(&self.theta, w);
        let s1 = cross_terms(&self.theta, f);
        let s2 = cross_terms(&self.vel, w);
        for i in 0..3 {
            self.coning[i] = self.coning[i].wrapping_add(c[i]);
            self.sculling[i] = self.sculling[i].wrapping_add(s1[i]).wrapping_add(s2[i]);
            self.theta[i] = self.theta[i].wrapping_add(i64::from(w[i]));
            self.vel[i] = self.vel[i].wrapping_add(i64::from(f[i]));
        }
        self.samples = self.samples.wrapping_add(1);
    }
}

/// What a [`crate::chain::SignalChain`] keeps of the integrals: nothing
/// ([`NoIntegrals`]) or all of them ([`Integrals`]). Chosen by the chain's
/// type, so a chain without them has neither the storage nor the per-tick
/// code.
pub trait Integrate: Clone + core::fmt::Debug + Default {
    /// Whether [`Integrate::add`] does anything (the chain skips computing
    /// its inputs otherwise).
    const ON: bool;
    /// Adds one tick (see [`Integrals::add`]).
    fn add(&mut self, w: &[i32; 3], f: &[i32; 3]);
}

/// No integrals: zero-sized, [`Integrate::add`] does nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NoIntegrals;

impl Integrate for NoIntegrals {
    const ON: bool = false;
    #[inline(always)]
    fn add(&mut self, _w: &[i32; 3], _f: &[i32; 3]) {}
}

impl Integrate for Integrals {
    const ON: bool = true;
    #[inline(always)]
    fn add(&mut self, w: &[i32; 3], f: &[i32; 3]) {
        Integrals::add(self, w, f);
    }
}

/// One window of the integrals, in SI units, body frame at its start.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Increment {
    /// Samples in the window.
    pub samples: u64,
    /// Coning-corrected angle increment Δθ, rad.
    pub dtheta_rad: [f64; 3],
    /// Rotation- and sculling-corrected velocity increment Δv, m/s.
    pub dv_mps: [f64; 3],
    /// Δθ without the coning correction (Σ ω dt), rad.
    pub dtheta_raw_rad: [f64; 3],
    /// Δv without corrections (Σ f dt), m/s.
    pub dv_raw_mps: [f64; 3],
}

fn sub3(a: &[i64; 3], b: &[i64; 3]) -> [i64; 3] {
    [
        a[0].wrapping_sub(b[0]),
        a[1].wrapping_sub(b[1]),
        a[2].wrapping_sub(b[2]),
    ]
}

/// The window from snapshot `start` to snapshot `end` (taken later) of a
/// chain ticking at `rate_hz` (its internal rate): Δθ and Δv with the
/// coning, rotation and sculling corrections (module doc), in rad and m/s
/// (g = [`G`]).
pub fn window(start: &Integrals, end: &Integrals, rate_hz: u32) -> Increment {
    let dt_s = 1.0 / f64::from(rate_hz);
    let kt = dt_s * (core::f64::consts::PI / 180.0) / f64::from(1u32 << RATE_BITS);
    let kv = dt_s * f64::from(G) / f64::from(1u32 << FORCE_BITS);
    let kx = f64::from(1u32 << CROSS_SHIFT);
    let dth = sub3(&end.theta, &start.theta);
    let dvl = sub3(&end.vel, &start.vel);
    let a_th = cross_terms_wide(&start.theta, &dth);
    let a_tv = cross_terms_wide(&start.theta, &dvl);
    let a_vt = cross_terms_wide(&start.vel, &dth);
    let rot = cross_exact(&dth, &dvl);
    let mut out = Increment {
        samples: end.samples.wrapping_sub(start.samples),
        ..Increment::default()
    };
    for i in 0..3 {
        let c = end.coning[i]
            .wrapping_sub(start.coning[i])
            .wrapping_sub(a_th[i]);
        let s = end.sculling[i]
            .wrapping_sub(start.sculling[i])
            .wrapping_sub(a_tv[i])
            .wrapping_sub(a_vt[i]);
        let alpha = dth[i] as f64 * kt;
        let ups = dvl[i] as f64 * kv;
        out.dtheta_raw_rad[i] = alpha;
        out.dv_raw_mps[i] = ups;
        out.dtheta_rad[i] = alpha + 0.5 * c as f64 * kx * kt * kt;
        // ½ α × υ + ½ (sculling sum).
        out.dv_mps[i] = ups + 0.5 * (rot[i] as f64 + s as f64 * kx) * kt * kv;
    }
    out
}

/// A carrier-axes measurement in the integrals' units: gyro °/s and
/// force g (`f32`, the float chain) rounded to 2^[`RATE_BITS`] and
/// 2^[`FORCE_BITS`], saturated to the `i32` range.
#[inline]
pub fn quantize(w: &Vec3, f: &Vec3) -> ([i32; 3], [i32; 3]) {
    let q = |v: f32, s: f32| {
        let x = v * s;
        // `as` saturates (NaN gives 0); half away from zero.
        (x + if x < 0.0 { -0.5 } else { 0.5 }) as i32
    };
    let (sw, sf) = ((1u32 << RATE_BITS) as f32, (1u32 << FORCE_BITS) as f32);
    (
        [q(w[0], sw), q(w[1], sw), q(w[2], sw)],
        [q(f[0], sf), q(f[1], sf), q(f[2], sf)],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window does not depend on what came before it: after "hours" (a
    /// large arbitrary state) the uncorrected increments are the same bits
    /// as from a fresh start, the corrections differ by the rounding of
    /// the cross terms only (≤ 1 unit a tick for the coning sum, ≤ 2 for
    /// the sculling sum, plus the end corrections).
    #[test]
    fn windows_do_not_depend_on_the_history() {
        let mut fresh = Integrals::default();
        let mut old = Integrals {
            samples: 72_000_000,
            theta: [(1 << 62) + 5, -(1 << 61), 123_456_789_012_345],
            vel: [1 << 62, -987_654_321_098, 42],
            coning: [i64::MAX - 3, i64::MIN / 3, 7],
            sculling: [-(1 << 60), 1 << 50, i64::MIN + 1],
        };
        let (a0, b0) = (fresh, old);
        let n = 1000;
        for k in 0..n {
            let w = [1_000_000 * (k % 7 - 3), -300_000 * k, 50_000_000];
            let f = [k * 1000, 8_388_608, -5 * k];
            fresh.add(&w, &f);
            old.add(&w, &f);
        }
        let (x, y) = (window(&a0, &fresh, 2000), window(&b0, &old, 2000));
        assert_eq!(y.samples, 1000);
        assert_eq!(
            (x.dtheta_raw_rad, x.dv_raw_mps),
            (y.dtheta_raw_rad, y.dv_raw_mps)
        );
        let kt = 5e-4 * core::f64::consts::PI / 180.0 / f64::from(1u32 << RATE_BITS);
        let kv = 5e-4 * f64::from(G) / f64::from(1u32 << FORCE_BITS);
        let unit_c = 0.5 * f64::from(1u32 << CROSS_SHIFT) * kt * kt;
        let unit_s = 0.5 * f64::from(1u32 << CROSS_SHIFT) * kt * kv;
        for i in 0..3 {
            let dc = (x.dtheta_rad[i] - y.dtheta_rad[i]).abs();
            let ds = (x.dv_mps[i] - y.dv_mps[i]).abs();
            assert!(dc <= (f64::from(n) + 2.0) * unit_c, "{i}: {dc}");
            assert!(ds <= (2.0 * f64::from(n) + 4.0) * unit_s, "{i}: {ds}");
        }
    }
}
