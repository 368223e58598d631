//! The error-state Kalman filter of the IMX-5's INS: 15 error states
//! about the nominal state of [`super::mech`], a covariance in `f32`
//! (900 bytes; the M4F has a single-precision FPU), propagated from the
//! navigation periods accumulated since the last propagation, and scalar
//! (sequential) measurement updates. States, equations, noise figures and
//! where each comes from: `docs/navigation.md` "The filter".
//!
//! | index | state | unit |
//! |---|---|---|
//! | [`POS`] 0–2 | position error, north, east, down | m |
//! | [`VEL`] 3–5 | velocity error, NED | m/s |
//! | [`ATT`] 6–8 | attitude error φ, NED axes (`C_true = (I + [φ×]) C_est`) | rad |
//! | [`BG`] 9–11 | gyro bias error, body axes | rad/s |
//! | [`BA`] 12–14 | accelerometer bias error, body axes | m/s² |
//!
//! Errors are truth − estimate. Continuous dynamics (Groves 2013, §14.2,
//! local-navigation-frame form, the small terms in position left out):
//!
//! ```text
//! δṙ = δv
//! δv̇ = −[fⁿ×] φ − C δb_a + (2γ/R) δr_D ê_D + w_a
//! φ̇  = −[ω_in×] φ − C δb_g + w_g
//! δḃ_g = w_bg,  δḃ_a = w_ba  (random walks)
//! ```
//!
//! No heap, no panic: fixed-size arrays, indices in range by
//! construction; a degenerate innovation variance skips the update.

// Matrix code indexes rows and columns by one index.
#![allow(clippy::needless_range_loop)]

use libm::sqrtf;

/// Number of error states.
pub const N: usize = 15;
/// Index of the position error (north, east, down).
pub const POS: usize = 0;
/// Index of the velocity error.
pub(crate) const VEL: usize = 3;
/// Index of the attitude error.
pub(crate) const ATT: usize = 6;
/// Index of the gyro bias error.
pub(crate) const BG: usize = 9;
/// Index of the accelerometer bias error.
pub(crate) const BA: usize = 12;

/// The process noise of the filter, per second (spectral densities).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProcessNoise {
    /// Velocity random walk, (m/s)²/s: the accelerometer's white noise.
    pub vel: f32,
    /// Angle random walk, rad²/s: the gyro's white noise.
    pub att: f32,
    /// Gyro bias random walk, (rad/s)²/s.
    pub bg: f32,
    /// Accelerometer bias random walk, (m/s²)²/s.
    pub ba: f32,
}

/// A result of one scalar update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Update {
    /// Applied; the normalised innovation (residual / √S).
    Applied(f32),
    /// Refused by the gate (|residual| > gate·√S); the normalised
    /// innovation.
    Gated(f32),
    /// The innovation variance was not positive and finite: skipped.
    Degenerate,
}

/// The covariance and the error-state estimate of the current update
/// batch.
#[derive(Debug, Clone)]
pub struct Filter {
    /// Covariance of the error state.
    pub p: [[f32; N]; N],
    /// Error state estimated by the updates since the last
    /// [`Filter::take_correction`].
    dx: [f32; N],
}

/// What the propagation of an interval needs from the mechanisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Length, s.
    pub dt: f32,
    /// Mean specific force, NED, m/s².
    pub f_n: [f32; 3],
    /// Attitude (body → NED) at the interval's end, rows of C.
    pub c_nb: [[f32; 3]; 3],
    /// ω_in (Earth plus transport rate), NED, rad/s.
    pub w_in: [f32; 3],
    /// 2γ/R, 1/s²: the vertical channel's gravity gradient.
    pub grav_grad: f32,
}

impl Filter {
    /// A filter with a diagonal covariance of these standard deviations.
    pub fn new(sigma: &[f32; N]) -> Self {
        let mut p = [[0.0; N]; N];
        for (i, s) in sigma.iter().enumerate() {
            p[i][i] = s * s;
        }
        Filter { p, dx: [0.0; N] }
    }

    /// The standard deviation of state `i`.
    pub(crate) fn sigma(&self, i: usize) -> f32 {
        sqrtf(self.p[i % N][i % N].max(0.0))
    }

    /// Resets the covariance of states `i..i+3` to `sigma` (uncorrelated
    /// with the rest): a state set from a measurement.
    pub(crate) fn reset3(&mut self, i: usize, sigma: [f32; 3]) {
        for (k, s) in sigma.iter().enumerate() {
            self.reset1(i + k, *s);
        }
    }

    /// Resets the covariance of state `i` to `sigma`, uncorrelated.
    pub(crate) fn reset1(&mut self, i: usize, sigma: f32) {
        let r = i % N;
        for j in 0..N {
            self.p[r][j] = 0.0;
            self.p[j][r] = 0.0;
        }
        self.p[r][r] = sigma * sigma;
        self.dx[r] = 0.0;
    }

    /// Propagates the covariance over `iv` with `q` (module doc):
    /// `P ← Φ P Φᵀ + Q Δt`, `Φ = I + F Δt`.
    pub fn propagate(&mut self, iv: &Interval, q: &ProcessNoise) {
        let dt = iv.dt;
        if dt <= 0.0 || !dt.is_finite() {
            return;
        }
        let mut phi = [[0.0f32; N]; N];
        for (i, row) in phi.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        let f = iv.f_n;
        let w = iv.w_in;
        for k in 0..3 {
            phi[POS + k][VEL + k] = dt;
            for j in 0..3 {
                phi[VEL + k][BA + j] = -iv.c_nb[k][j] * dt;
                phi[ATT + k][BG + j] = -iv.c_nb[k][j] * dt;
            }
        }
        // −[f×] and −[ω×].
        let skew = |v: [f32; 3]| [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
        let (sf, sw) = (skew(f), skew(w));
        for k in 0..3 {
            for j in 0..3 {
                phi[VEL + k][ATT + j] = -sf[k][j] * dt;
                phi[ATT + k][ATT + j] -= sw[k][j] * dt;
            }
        }
        phi[VEL + 2][POS + 2] = iv.grav_grad * dt;
        // Φ's non-zeros by row (at most 8: the diagonal, two of a skew
        // matrix or one gradient, three of C); A = Φ P, then the upper
        // triangle of P = A Φᵀ (symmetric), each through them only.
        let mut nz = [[(0usize, 0.0f32); 8]; N];
        let mut len = [0usize; N];
        for (i, row) in phi.iter().enumerate() {
            for (k, &x) in row.iter().enumerate() {
                if x != 0.0 && len[i] < 8 {
                    nz[i][len[i]] = (k, x);
                    len[i] += 1;
                }
            }
        }
        let mut a = [[0.0f32; N]; N];
        for (i, ai) in a.iter_mut().enumerate() {
            for &(k, x) in &nz[i][..len[i]] {
                for (aij, pkj) in ai.iter_mut().zip(&self.p[k]) {
                    *aij += x * pkj;
                }
            }
        }
        let mut p = [[0.0f32; N]; N];
        for i in 0..N {
            for j in i..N {
                let mut s = 0.0;
                for &(k, x) in &nz[j][..len[j]] {
                    s += a[i][k] * x;
                }
                p[i][j] = s;
                p[j][i] = s;
            }
        }
        for k in 0..3 {
            p[VEL + k][VEL + k] += q.vel * dt;
            p[ATT + k][ATT + k] += q.att * dt;
            p[BG + k][BG + k] += q.bg * dt;
            p[BA + k][BA + k] += q.ba * dt;
        }
        self.p = p;
        self.condition();
    }

    /// Symmetric, with a non-negative diagonal (f32 round-off).
    fn condition(&mut self) {
        for i in 0..N {
            if self.p[i][i].is_nan() || self.p[i][i] < 1e-20 {
                self.p[i][i] = 1e-20;
            }
            for j in 0..i {
                let m = 0.5 * (self.p[i][j] + self.p[j][i]);
                self.p[i][j] = m;
                self.p[j][i] = m;
            }
        }
    }

    /// One scalar measurement: `residual` = measured − predicted by the
    /// nominal state, sensitivity `h` (pairs of state index and
    /// coefficient), variance `r`; refused when `|residual − h·δx| >
    /// gate·√S` (`gate` ≤ 0: never).
    pub fn update(&mut self, h: &[(usize, f32)], residual: f32, r: f32, gate: f32) -> Update {
        let mut ph = [0.0f32; N];
        for (i, v) in ph.iter_mut().enumerate() {
            *v = h.iter().map(|&(k, c)| self.p[i][k % N] * c).sum();
        }
        let s: f32 = h.iter().map(|&(k, c)| c * ph[k % N]).sum::<f32>() + r;
        if !(s > 0.0 && s.is_finite() && residual.is_finite()) {
            return Update::Degenerate;
        }
        let y = residual - h.iter().map(|&(k, c)| c * self.dx[k % N]).sum::<f32>();
        let norm = y / sqrtf(s);
        if gate > 0.0 && norm.abs() > gate {
            return Update::Gated(norm);
        }
        for i in 0..N {
            let k = ph[i] / s;
            self.dx[i] += k * y;
            for j in 0..N {
                self.p[i][j] -= k * ph[j];
            }
        }
        self.condition();
        Update::Applied(norm)
    }

    /// The error state estimated since the last call (to add to the
    /// nominal state); the estimate restarts at zero.
    pub fn take_correction(&mut self) -> [f32; N] {
        core::mem::replace(&mut self.dx, [0.0; N])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A direct measurement of a state: the variance falls to
    /// P·R/(P+R), the estimate moves by the gain.
    #[test]
    fn a_scalar_update_is_the_textbook_one() {
        let mut f = Filter::new(&[2.0; N]);
        let u = f.update(&[(POS, 1.0)], 1.0, 4.0, 0.0);
        assert_eq!(u, Update::Applied(1.0 / 8f32.sqrt()));
        assert!((f.p[POS][POS] - 2.0).abs() < 1e-6);
        assert!((f.take_correction()[POS] - 0.5).abs() < 1e-6);
        assert_eq!(f.take_correction()[POS], 0.0);
        assert!(matches!(
            f.update(&[(POS, 1.0)], 100.0, 4.0, 5.0),
            Update::Gated(_)
        ));
        assert_eq!(
            f.update(&[(POS, 1.0)], f32::NAN, 4.0, 0.0),
            Update::Degenerate
        );
    }

    /// Free inertial: a velocity uncertainty grows the position's as σ_v·t.
    #[test]
    fn propagation_integrates_velocity_into_position() {
        let mut s = [0.0; N];
        s[VEL] = 1.0;
        let mut f = Filter::new(&s);
        let iv = Interval {
            dt: 0.02,
            f_n: [0.0, 0.0, -9.8],
            c_nb: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            w_in: [0.0; 3],
            grav_grad: 0.0,
        };
        let q = ProcessNoise {
            vel: 0.0,
            att: 0.0,
            bg: 0.0,
            ba: 0.0,
        };
        for _ in 0..500 {
            f.propagate(&iv, &q);
        }
        assert!((f.sigma(POS) - 10.0).abs() < 0.01, "{}", f.sigma(POS));
    }
}
