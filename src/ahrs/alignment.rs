//! Initial alignment (ICD 5.3.1, 5.7): gyro bias estimation accounting for
//! the Earth's rotation, and levelling from the accelerometers.
//!
//! During alignment every tick adds the carrier-axis gyro and accelerometer
//! samples (before the FIR: the AHRS runs on the sensor data, the FIR shapes
//! only the transmitted signals). The gyro is also averaged into 10 ms
//! blocks (the 100 Hz rate of the emulated AHRS), which feed both tests:
//!
//! - **ZUPT off — averaging.** The bias is the mean gyro over the whole
//!   alignment minus the Earth rate; it is *accepted* if, on every axis, the
//!   standard deviation of the 10 ms block means is at most
//!   Align_Gyro_STD_Threshold (°/s), otherwise *rejected*: USW-extended
//!   bit 1 is set and the bias stays zero. The statistic sees motion and
//!   vibration up to ≈ 50 Hz and the sensor noise at 100 Hz
//!   (σ = N·√100 Hz: 0.04 °/s for an ARW of 0.24 °/√h), not the 2 kHz noise.
//! - **ZUPT on — Kalman filter.** A scalar Kalman filter per axis on the
//!   10 ms block means, with the AHRS tuning parameters of Table 5.24:
//!   initial σ Gyro_Bias_RMS, measurement σ Gyro_Noise_RMS, random-walk
//!   density Gyro_Bias_Drift (all °/s). Vibration only slows its
//!   convergence; the bias is accepted when its final σ is at most the
//!   threshold (which at any sensible setting it is).
//!
//! **Earth rate.** The KERNEL has no magnetometer: heading is relative, 0 at
//! the end of alignment. For the Earth-rate correction the emulated AHRS
//! assumes that relative heading 0 is north, at the default latitude
//! ([`crate::sensor::motion::DEFAULT_LATITUDE_DEG`]). The levelled attitude
//! with heading 0 gives the Earth rate in the carrier axes, which is
//! subtracted from the mean. Whatever the true heading, a static unit then
//! stays exactly static (the attitude propagation subtracts the same
//! assumed Earth rate); only under rotation does a heading other than 0
//! misplace the horizontal Earth rate (at most 2Ω cos φ ≈ 0.006 °/s).
//!
//! **Levelling.** Pitch and roll from the mean specific force `f` (C.1 row
//! 3 is the up axis in the object frame): `θ = asin(f_y/|f|)`,
//! `γ = atan2(−f_x, f_z)`; heading 0.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use crate::math::rotation::{quat_from_euler, quat_rotate_inv, Quat, Vec3};
use crate::math::{asinf, atan2f};
use libm::sqrtf;

const RAD: f32 = 180.0 / core::f32::consts::PI;

/// Alignment parameters (Table 5.24: ZUPT, Align_Gyro_STD_Threshold and the
/// AHRS tuning rows).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignConfig {
    /// ZUPT: `false` averaging + STD threshold, `true` Kalman filter.
    pub zupt: bool,
    /// Align_Gyro_STD_Threshold, °/s.
    pub std_threshold_dps: f32,
    /// Gyro_Noise_RMS, °/s (Kalman measurement σ).
    pub gyro_noise_rms: f32,
    /// Gyro_Bias_RMS, °/s (Kalman initial σ).
    pub gyro_bias_rms: f32,
    /// Gyro_Bias_Drift, °/s/√s (Kalman random-walk density).
    pub gyro_bias_drift: f32,
}

impl Default for AlignConfig {
    fn default() -> Self {
        AlignConfig {
            zupt: false,
            std_threshold_dps: 0.05,
            gyro_noise_rms: 0.1,
            gyro_bias_rms: 0.1,
            gyro_bias_drift: 0.001,
        }
    }
}

/// The outcome of an alignment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignResult {
    /// Estimated gyro bias, carrier axes, °/s (zero when rejected).
    pub bias_dps: Vec3,
    /// Whether the bias estimate was accepted (USW-extended bit 1 clear).
    pub accepted: bool,
    /// Per-axis STD of the 10 ms gyro block means, °/s.
    pub std_dps: Vec3,
    /// Levelled attitude (heading 0).
    pub attitude: Quat,
}

/// The running alignment. Its parameters ([`AlignConfig`]) are passed to
/// [`Alignment::add`] and [`Alignment::finish`] rather than kept (the chain
/// holds them in its configuration).
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    rate_hz: u16,
    block_len: u8,
    in_block: u8,
    block_sum: Vec3,
    n_blocks: u32,
    blk_first: Vec3,
    blk_sum: Vec3,
    blk_sum2: Vec3,
    n: u32,
    g_first: Vec3,
    g_sum: Vec3,
    a_first: Vec3,
    a_sum: Vec3,
    kf_b: Vec3,
    kf_p: Vec3,
}

impl Alignment {
    /// A fresh alignment for ticks at `rate_hz` (≤ 25 500 Hz).
    pub(crate) fn new(cfg: &AlignConfig, rate_hz: u32) -> Self {
        let block_len = (rate_hz / 100).clamp(1, 255);
        let p0 = cfg.gyro_bias_rms * cfg.gyro_bias_rms;
        Alignment {
            rate_hz: rate_hz.min(25_500) as u16,
            block_len: block_len as u8,
            in_block: 0,
            block_sum: [0.0; 3],
            n_blocks: 0,
            blk_first: [0.0; 3],
            blk_sum: [0.0; 3],
            blk_sum2: [0.0; 3],
            n: 0,
            g_first: [0.0; 3],
            g_sum: [0.0; 3],
            a_first: [0.0; 3],
            a_sum: [0.0; 3],
            kf_b: [0.0; 3],
            kf_p: [p0; 3],
        }
    }

    /// Ticks added so far.
    pub(crate) fn ticks(&self) -> u32 {
        self.n
    }

    /// Adds one tick of carrier-axis gyro (°/s) and specific force (g).
    #[inline]
    pub fn add(&mut self, gyro: &Vec3, acc: &Vec3, cfg: &AlignConfig) {
        if self.n == 0 {
            self.g_first = *gyro;
            self.a_first = *acc;
        }
        self.n += 1;
        for i in 0..3 {
            self.g_sum[i] += gyro[i] - self.g_first[i];
            self.a_sum[i] += acc[i] - self.a_first[i];
            self.block_sum[i] += gyro[i] - self.g_first[i];
        }
        self.in_block += 1;
        if self.in_block == self.block_len {
            let inv = 1.0 / self.block_len as f32;
            let m = [
                self.block_sum[0] * inv,
                self.block_sum[1] * inv,
                self.block_sum[2] * inv,
            ];
            self.add_block(&m, cfg);
            self.in_block = 0;
            self.block_sum = [0.0; 3];
        }
    }

    /// One 10 ms block mean (relative to the first gyro sample).
    fn add_block(&mut self, m: &Vec3, cfg: &AlignConfig) {
        if self.n_blocks == 0 {
            self.blk_first = *m;
        }
        self.n_blocks += 1;
        let block_dt = f32::from(self.block_len) / f32::from(self.rate_hz);
        let q = cfg.gyro_bias_drift * cfg.gyro_bias_drift * block_dt;
        let r = (cfg.gyro_noise_rms * cfg.gyro_noise_rms).max(1e-12);
        for i in 0..3 {
            let d = m[i] - self.blk_first[i];
            self.blk_sum[i] += d;
            self.blk_sum2[i] += d * d;
            // Kalman filter on the bias (relative to the first sample).
            let p = self.kf_p[i] + q;
            let k = p / (p + r);
            self.kf_b[i] += k * (m[i] - self.kf_b[i]);
            self.kf_p[i] = (1.0 - k) * p;
        }
    }

    /// The mean specific force so far, carrier axes, g.
    pub(crate) fn mean_force(&self) -> Vec3 {
        let inv = if self.n > 0 { 1.0 / self.n as f32 } else { 0.0 };
        [
            self.a_first[0] + self.a_sum[0] * inv,
            self.a_first[1] + self.a_sum[1] * inv,
            self.a_first[2] + self.a_sum[2] * inv,
        ]
    }

    /// The levelled attitude from the mean specific force so far (heading 0).
    pub fn level(&self) -> Quat {
        level_from(&self.mean_force())
    }

    /// Ends the alignment: the outcome, with the Earth rate at `earth_enu`
    /// (rad/s, ENU) removed from the bias.
    pub fn finish(&self, earth_enu: &Vec3, cfg: &AlignConfig) -> AlignResult {
        let attitude = self.level();
        let w = quat_rotate_inv(&attitude, earth_enu);
        self.finish_at(attitude, [w[0] * RAD, w[1] * RAD, w[2] * RAD], cfg)
    }

    /// [`Alignment::finish`] with the levelled `attitude` and the Earth rate
    /// in its body axes (°/s) given (the fixed-point chain computes both in
    /// integers).
    pub(crate) fn finish_at(&self, attitude: Quat, earth_dps: Vec3, cfg: &AlignConfig) -> AlignResult {
        let nb = self.n_blocks as f32;
        let mut std = [0.0; 3];
        if self.n_blocks >= 2 {
            for (i, s) in std.iter_mut().enumerate() {
                let var = (self.blk_sum2[i] - self.blk_sum[i] * self.blk_sum[i] / nb) / (nb - 1.0);
                *s = sqrtf(var.max(0.0));
            }
        }
        let (estimate, accepted) = if self.n_blocks < 2 {
            ([0.0; 3], false)
        } else if cfg.zupt {
            let sigma = self.kf_p.iter().fold(0.0f32, |a, &p| a.max(p));
            (self.kf_b, sqrtf(sigma) <= cfg.std_threshold_dps)
        } else {
            let inv = 1.0 / self.n as f32;
            let mean = [
                self.g_sum[0] * inv,
                self.g_sum[1] * inv,
                self.g_sum[2] * inv,
            ];
            let ok = std.iter().all(|&s| s <= cfg.std_threshold_dps);
            (mean, ok)
        };
        let bias_dps = if accepted {
            [
                self.g_first[0] + estimate[0] - earth_dps[0],
                self.g_first[1] + estimate[1] - earth_dps[1],
                self.g_first[2] + estimate[2] - earth_dps[2],
            ]
        } else {
            [0.0; 3]
        };
        AlignResult {
            bias_dps,
            accepted,
            std_dps: std,
            attitude,
        }
    }
}

/// The heading-0 attitude whose up axis is along the specific force `f`.
pub(crate) fn level_from(f: &Vec3) -> Quat {
    let n = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if n < 1e-6 {
        return crate::math::rotation::QUAT_IDENTITY;
    }
    let pitch = asinf((f[1] / n).clamp(-1.0, 1.0));
    let roll = atan2f(-f[0], f[2]);
    quat_from_euler(0.0, pitch, roll)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rotation::level_q30;

    /// Levelling in integers agrees with the float levelling.
    #[test]
    fn fixed_point_levelling_matches_float() {
        for f in [
            [0.0f32, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.1, -0.2, 0.97],
            [-0.5, 0.5, -0.7],
            [0.01, 0.999, 0.01],
        ] {
            // f64 reference: pitch asin(f_y/|f|), roll atan2(−f_x, f_z).
            let g = f.map(f64::from);
            let n = libm::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
            let (p, r) = (libm::asin(g[1] / n) / 2.0, libm::atan2(-g[0], g[2]) / 2.0);
            let (cp, sp, cr, sr) = (libm::cos(p), libm::sin(p), libm::cos(r), libm::sin(r));
            let reference = [cp * cr, sp * cr, cp * sr, sp * sr];
            let angle = |q: [f64; 4]| {
                let d = [
                    reference[0] * q[1] - reference[1] * q[0] - reference[2] * q[3]
                        + reference[3] * q[2],
                    reference[0] * q[2] + reference[1] * q[3]
                        - reference[2] * q[0]
                        - reference[3] * q[1],
                    reference[0] * q[3] - reference[1] * q[2] + reference[2] * q[1]
                        - reference[3] * q[0],
                ];
                2.0 * libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
            };
            let q = level_q30(&f.map(|x| (x * (1u32 << 23) as f32) as i32));
            let qf = level_from(&f);
            let e = angle(q.map(|x| f64::from(x) / f64::from(1u32 << 30)));
            assert!(e < 1e-6, "{f:?}: fixed {e} rad");
            // The float levelling (asin near ±90°) is the coarser one.
            assert!(angle(qf.map(f64::from)) < 1e-4, "{f:?}");
        }
        assert_eq!(level_q30(&[0, 0, 0]), [1 << 30, 0, 0, 0]);
    }
}
