//! The Allan deviation and its fit (the module doc of [`super`]): the
//! phases of each channel, the overlapping estimator, the weighted least
//! squares of the noise terms, the warning for a record too short — what
//! the unit run, the recordings ([`super::input`]) and the plot
//! ([`super::plot`]) share, below all three.

use std::path::Path;

use anyhow::bail;
use imu_emu::sensor::profile::SensorProfile;

/// Flicker floor / B: √(2 ln 2/π) (IEEE 952).
pub const FLICKER_FLOOR: f64 = 0.664_282;

/// Phases kept per axis at most.
const KEEP: usize = 1 << 20;

pub use crate::client::decode::AXES;

/// Phases of the channels (the first `channels` of [`AXES`]), kept every
/// `stride` samples.
pub(crate) struct Phases {
    pub(crate) tau0: f64,
    stride: usize,
    /// Samples pushed.
    pub(crate) n: usize,
    acc: Vec<f64>,
    first: Option<Vec<f64>>,
    kept: Vec<Vec<f64>>,
}

impl Phases {
    pub(crate) fn new(tau0: f64, expected: usize, channels: usize) -> Self {
        let stride = expected.div_ceil(KEEP).max(1);
        let mut p = Phases {
            tau0,
            stride,
            n: 0,
            acc: vec![0.0; channels],
            first: None,
            kept: vec![Vec::new(); channels],
        };
        for k in &mut p.kept {
            k.reserve(expected / stride + 2);
            k.push(0.0);
        }
        p
    }

    /// One sample of every channel (`y.len()` = the `channels` it was
    /// made with).
    pub(crate) fn push(&mut self, y: &[f64]) {
        // Relative to the first sample: the phases stay small (the Allan
        // deviation ignores a constant).
        let y0 = self.first.get_or_insert_with(|| y.to_vec());
        for ((a, v), v0) in self.acc.iter_mut().zip(y).zip(y0.iter()) {
            *a += (v - v0) * self.tau0;
        }
        self.n += 1;
        if self.n.is_multiple_of(self.stride) {
            for (k, a) in self.kept.iter_mut().zip(&self.acc) {
                k.push(*a);
            }
        }
    }
}

/// One axis's Allan deviation: (τ s, σ, samples n/m) points.
#[derive(Debug, Clone)]
pub struct Curve {
    /// (τ, σ(τ), n/m).
    pub points: Vec<(f64, f64, f64)>,
}

pub(crate) fn curves(p: &Phases) -> Vec<Curve> {
    let kept = p.kept[0].len();
    let max_k = (kept.saturating_sub(1)) / 4;
    let mut ks: Vec<usize> = Vec::new();
    let mut e = 0.0f64;
    while 10f64.powf(e / 10.0) <= max_k as f64 {
        let k = 10f64.powf(e / 10.0).round() as usize;
        if ks.last() != Some(&k) {
            ks.push(k);
        }
        e += 1.0;
    }
    p.kept
        .iter()
        .map(|x| {
            let points = ks
                .iter()
                .map(|&k| {
                    let m = k * p.stride;
                    let tau = m as f64 * p.tau0;
                    let terms = x.len() - 2 * k;
                    let s: f64 = (0..terms)
                        .map(|i| {
                            let d = x[i + 2 * k] - 2.0 * x[i + k] + x[i];
                            d * d
                        })
                        .sum();
                    let var = s / (2.0 * tau * tau * terms as f64);
                    (tau, var.sqrt(), p.n as f64 / m as f64)
                })
                .collect();
            Curve { points }
        })
        .collect()
}

/// Fitted terms of one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// White-noise density, unit/√Hz.
    pub n: f64,
    /// Bias instability B = floor / 0.6643, unit.
    pub b: f64,
    /// Rate random walk, unit/√s.
    pub k: f64,
    /// The datasheet reading: min σ / 0.6643 over τ ≤ `tau_min_max`
    /// (where each estimate averages ≥ 100 intervals: the minimum of a
    /// noisier estimate reads low), unit.
    pub b_min: f64,
}

/// Weighted least squares of the curve (module doc) over τ ≤ `tau_max`;
/// the datasheet reading over τ ≤ `tau_min_max`.
pub fn fit(c: &Curve, tau_max: f64, tau_min_max: f64) -> Fit {
    let pts: Vec<&(f64, f64, f64)> = c
        .points
        .iter()
        .filter(|p| p.0 <= tau_max && p.1 > 0.0)
        .collect();
    let mut on = [true; 3];
    let mut x = [0.0f64; 3];
    for _ in 0..3 {
        let idx: Vec<usize> = (0..3).filter(|&i| on[i]).collect();
        let n = idx.len();
        let mut a = vec![vec![0.0f64; n]; n];
        let mut b = vec![0.0f64; n];
        for &&(tau, sigma, dof) in &pts {
            let v = sigma * sigma;
            let f = [1.0 / tau, 1.0, tau / 3.0];
            let w = dof / (v * v);
            for (r, &i) in idx.iter().enumerate() {
                b[r] += w * f[i] * v;
                for (s, &j) in idx.iter().enumerate() {
                    a[r][s] += w * f[i] * f[j];
                }
            }
        }
        let sol = solve(a, b);
        x = [0.0; 3];
        for (r, &i) in idx.iter().enumerate() {
            x[i] = sol[r];
        }
        match (0..3).find(|&i| on[i] && x[i] < 0.0) {
            Some(i) => on[i] = false,
            None => break,
        }
    }
    let x = x.map(|v| v.max(0.0));
    let b_min = pts
        .iter()
        .filter(|p| p.0 <= tau_min_max)
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min)
        / FLICKER_FLOOR;
    Fit {
        n: x[0].sqrt(),
        b: x[1].sqrt() / FLICKER_FLOOR,
        k: x[2].sqrt(),
        b_min,
    }
}

/// Gaussian elimination with partial pivoting (n ≤ 3).
#[allow(clippy::needless_range_loop)] // rows and columns by index
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, p);
        b.swap(c, p);
        if a[c][c] == 0.0 {
            continue;
        }
        for r in c + 1..n {
            let k = a[r][c] / a[c][c];
            for j in c..n {
                a[r][j] -= k * a[c][j];
            }
            b[r] -= k * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|j| a[c][j] * x[j]).sum();
        x[c] = if a[c][c] == 0.0 {
            0.0
        } else {
            (b[c] - s) / a[c][c]
        };
    }
    x
}

/// What was analysed, for the report.
pub(crate) struct Source {
    /// Plot and report title.
    pub(crate) title: String,
    /// The profile to compare with, if known.
    pub(crate) profile: Option<SensorProfile>,
    /// The channels' phases.
    pub(crate) phases: Phases,
}

/// The warning for a run too short for the figures past the white noise:
/// on some axis the Allan deviation still falls at its longest τ (a
/// quarter of the run), so the floor (bias instability) and a rise (rate
/// random walk) lie beyond the data and those columns are upper bounds of
/// noise, not readings (docs/sensors.md "The datasheet reading": a floor
/// shows from about 100 times the τ where the white noise meets it, hours
/// for the built-in profiles). `None` when every curve turns.
pub fn too_short(cs: &[Curve], seconds: f64) -> Option<String> {
    let falling: Vec<&str> = cs
        .iter()
        .zip(AXES)
        .filter(|(c, _)| {
            let lowest = c
                .points
                .iter()
                .enumerate()
                .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
                .map(|(i, _)| i);
            c.points.len() < 2 || lowest == Some(c.points.len() - 1)
        })
        .map(|(_, ax)| ax)
        .collect();
    if falling.is_empty() {
        return None;
    }
    let longest = cs
        .first()
        .and_then(|c| c.points.last())
        .map_or(0.0, |p| p.0);
    Some(format!(
        "the record ({seconds:.1} s) is too short for bias instability and rate random walk: \
         the Allan deviation of {} still falls at its longest τ ({longest:.3} s), so their \
         figures below are upper bounds, not readings; only the white noise (ARW/VRW) is read",
        falling.join(" ")
    ))
}

/// A recording needs 100 samples or more.
pub(crate) fn enough(path: &Path, n: usize) -> anyhow::Result<()> {
    if n < 100 {
        bail!(
            "allan {}: {n} usable samples (need 100 or more)",
            path.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// White noise of known density: the fit reads it (and no floor).
    #[test]
    fn the_fit_reads_white_noise() {
        let mut rng = imu_emu::sensor::Rng::new(3);
        let n = 0.01;
        let rate = 100.0;
        let mut p = Phases::new(1.0 / rate, 200_000, 6);
        for _ in 0..200_000 {
            let w = f64::from(rng.gaussian()) * n * rate.sqrt();
            p.push(&[w, w, w, w, w, w]);
        }
        let c = curves(&p);
        let f = fit(&c[0], 200.0, 20.0);
        assert!((f.n / n - 1.0).abs() < 0.03, "{f:?}");
        assert!(f.b < 0.1 * n, "{f:?}");
    }
}
