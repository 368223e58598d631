//! The one random source of the signal chain: xoshiro128++ seeded through
//! SplitMix64, and a cheap Gaussian.
//!
//! Everything random in the emulator (noise, bias walks, the turn-on draws of
//! the error model) comes from this generator, so a seed replays a run bit
//! for bit on every platform: the generator uses only 32-bit integer
//! operations (no multiply — cheap on a Cortex-M0+), and the Gaussian is built
//! from integers with a single conversion to `f32`.
//!
//! The Gaussian is Irwin–Hall with four 16-bit uniforms: mean 0, variance 1
//! exactly, excess kurtosis −0.3 and tails cut at ±2√3 ≈ ±3.46σ. Allan
//! variances and standard deviations depend only on the variance, so this is
//! what the noise model needs, at a fraction of the cost of Box–Muller.

/// xoshiro128++ (Blackman & Vigna), 128-bit state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rng {
    s: [u32; 4],
}

/// √3 / 65536: scales the centred sum of four 16-bit uniforms to unit variance.
pub(crate) const IRWIN_HALL_SCALE: f32 = 1.732_050_8 / 65_536.0;

impl Rng {
    /// A generator whose state is derived from `seed` with SplitMix64 (so
    /// nearby seeds give unrelated streams; the all-zero state cannot occur).
    pub fn new(seed: u64) -> Self {
        let mut x = seed;
        let mut next = || {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        let a = next();
        let b = next();
        let mut s = [a as u32, (a >> 32) as u32, b as u32, (b >> 32) as u32];
        if s == [0; 4] {
            s[0] = 1;
        }
        Rng { s }
    }

    /// The next 32 random bits.
    #[cfg_attr(feature = "fixed-point", inline(never))]
    #[cfg_attr(not(feature = "fixed-point"), inline)]
    pub fn next_u32(&mut self) -> u32 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(7).wrapping_add(s[0]);
        let t = s[1] << 9;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(11);
        result
    }

    /// A uniform number in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// A standard normal deviate (Irwin–Hall of order 4, see the module doc).
    #[inline]
    pub fn gaussian(&mut self) -> f32 {
        self.gaussian_sum() as f32 * IRWIN_HALL_SCALE
    }

    /// The integer behind [`Rng::gaussian`]: the centred sum of four 16-bit
    /// uniforms, in −131 070 ..= 131 070 (standard deviation
    /// 65 536/√3 ≈ 37 837). The fixed-point error model scales it with one
    /// integer product.
    #[cfg_attr(feature = "fixed-point", inline(never))]
    #[cfg_attr(not(feature = "fixed-point"), inline)]
    pub fn gaussian_sum(&mut self) -> i32 {
        let a = self.next_u32();
        let b = self.next_u32();
        let sum = (a & 0xFFFF) as i32 + (a >> 16) as i32 + (b & 0xFFFF) as i32 + (b >> 16) as i32;
        // Each half is uniform on 0..=65535 with mean 32767.5; the sum of
        // four has mean 131070 and variance 4 · (65536² − 1)/12.
        sum - 131_070
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_stream_different_seed_different_stream() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        let mut c = Rng::new(8);
        let va: [u32; 8] = core::array::from_fn(|_| a.next_u32());
        let vb: [u32; 8] = core::array::from_fn(|_| b.next_u32());
        let vc: [u32; 8] = core::array::from_fn(|_| c.next_u32());
        assert_eq!(va, vb);
        assert_ne!(va, vc);
    }

    #[test]
    fn gaussian_has_unit_variance_and_zero_mean() {
        let mut r = Rng::new(1);
        let n = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let g = f64::from(r.gaussian());
            s += g;
            s2 += g * g;
        }
        let mean = s / f64::from(n);
        let var = s2 / f64::from(n) - mean * mean;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.01, "var {var}");
    }

    #[test]
    fn pinned_first_outputs() {
        // Pins the stream (computed independently from the SplitMix64 and
        // xoshiro128++ definitions): a change here changes every emulated
        // byte stream.
        let mut r = Rng::new(0);
        let v: [u32; 3] = core::array::from_fn(|_| r.next_u32());
        assert_eq!(v, [0x4653_daa3, 0x7392_2b58, 0xb82b_4add]);
    }
}
