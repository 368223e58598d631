//! The sensor error model: per sensor and axis, parameters named after the
//! Allan-variance terms a datasheet gives ([`super::profile`]), and the
//! per-tick engine that applies them.
//!
//! For each axis *i* of a sensor triad (gyro °/s, accelerometers g):
//!
//! ```text
//! x        = Σ_j M_ij · truth_j  +  g_i · force_i        (g-sensitivity: gyro only)
//! measured = sat( quant( lpf( x + n_i·x·|x|/range  +  b_i + f_i(t) + r_i(t)  +  σ_i · w_i ) ) )
//! M        = I + diag(scale_factor + temp_scale·ΔT) + misalignment (off-diagonal)
//! b_i      = bias (turn-on) + temp_bias · ΔT,   ΔT = T − 25 °C
//! f_i(t)   = flicker bias (bias instability B), r_i(t) = rate random walk K
//! σ_i      = noise_density · √f_s             (white noise per tick)
//! lpf      = the sensor's −3 dB bandwidth, first order, DC gain 1
//!            (super::bandwidth; none when the profile gives none)
//! ```
//!
//! **Allan mapping.** White noise of density N (unit/√Hz) has the Allan
//! deviation `σ(τ) = N/√τ`; so ARW [°/√h] = 60 · N [°/s/√Hz] and VRW
//! [m/s/√h] = 60 · 9.8106 · N [g/√Hz]. Rate random walk: `σ(τ) = K·√(τ/3)`.
//! A datasheet's bias instability B is the flat floor of the Allan plot
//! divided by 0.6643 = √(2 ln 2/π) (IEEE 952): flicker noise of one-sided
//! PSD `S(f) = B²/(π f)` has the flat Allan variance `(2 ln 2/π) B²`.
//!
//! **Flicker.** One Gauss–Markov process makes a bump in the Allan plot,
//! not a floor (read by the datasheet rule it gave 0.81 of B). The bias
//! instability is realised as flicker: a sum of [`FLICKER_TERMS`]
//! Gauss–Markov processes with corner times `T_k = 10^k s`, k = 0…5, one a
//! decade, each of variance `q² = B² · ln 10 / π`. Lorentzians of equal
//! variance, one per ln-interval `ln r`, sum to `S(f) ≈ q²/(f ln r)` between
//! the corners, which is the flicker PSD above. The Allan floor of the sum
//! is flat within ±2 % for τ from 3 s to 3·10⁴ s (the decades a datasheet's
//! Allan plot shows after the white-noise slope; below 3 s the white noise
//! dominates every built-in profile) and falls off outside it. Term k is
//! advanced every `D_k = 16·8^k` ticks (≥ 125 steps per corner time at
//! 2 kHz) by its exact discrete step `x ← a·x + q·√(1−a²)·u`,
//! `a = e^(−D_k·dt/T_k)`, `u` a unit-variance 16-bit uniform (the sum of
//! many steps is Gaussian); term k runs at ticks ≡ k (mod 16) and the
//! random walk (`r ← r + K·√(16·dt)·u`) at ticks ≡ 8, so **a tick advances
//! at most one of them**: the cost per tick is one test of the tick count,
//! and on one tick in 16 (or fewer) three products and two random draws —
//! less than the single Gauss–Markov process it replaces, which ran every
//! tick.
//!
//! The turn-on bias, scale factors, misalignments and the signs of the
//! temperature coefficients, non-linearity and g-sensitivity are
//! *realised* values: [`ErrorModel::from_profile`] draws them once from
//! the seed with the profile's spread, so a seed is one particular unit.
//! The host may overwrite any of them through
//! [`crate::chain::SignalChain::errors_mut`].
//!
//! [`TriadEngineFixed`] is the same engine in integers for the `fixed-point`
//! build (same random draws; `tests/signal_noise.rs` pins its Allan
//! deviation and its sample-by-sample agreement with [`TriadEngine`]). It
//! clamps each entry of M − I to ±¼ and truth to ±2³⁰ of its scale.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::bandwidth::{SensorLowPass, SensorLowPassFixed};
use super::profile::{SensorProfile, SensorSpec};
use super::rng::Rng;
use crate::math::fixed::{mul64, Coef, Recip};
use crate::math::rotation::{Mat3, Vec3};
use crate::math::{ACC_BITS, RATE_TRUTH_LIMIT, TRUTH_LIMIT};
use libm::sqrtf;

pub use super::profile::{arw_to_density, vrw_to_density};

/// Reference temperature of the temperature coefficients, °C.
pub(crate) const REFERENCE_TEMPERATURE_C: f32 = 25.0;

/// Gauss–Markov terms of the flicker bias (module doc "Flicker").
pub(crate) const FLICKER_TERMS: usize = 6;
/// Corner (correlation) time of flicker term k, s: 10^k.
pub const FLICKER_CORNERS_S: [f32; FLICKER_TERMS] = [1.0, 10.0, 100.0, 1e3, 1e4, 1e5];
/// Ticks between the steps of flicker term k: 16·8^k.
pub(crate) const FLICKER_PERIOD_TICKS: [u32; FLICKER_TERMS] = [16, 128, 1024, 8192, 65_536, 524_288];
/// Ticks between the steps of the rate random walk.
pub(crate) const RANDOM_WALK_PERIOD_TICKS: u32 = 16;
/// The tick (mod 16) of the random walk's step.
const RANDOM_WALK_PHASE: u32 = 8;
/// σ of each flicker term / B: √(ln 10 / π).
pub(crate) const FLICKER_SIGMA_PER_BIAS_INSTABILITY: f32 = 0.856_105;

/// Error parameters of one axis, in the sensor's output unit (°/s for a
/// gyro, g for an accelerometer).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisErrors {
    /// White-noise density, unit/√Hz: the angle random walk of a gyro
    /// (ARW °/√h = 60 × this) or the velocity random walk of an
    /// accelerometer (VRW m/s/√h = 60 × 9.8106 × this).
    pub noise_density: f32,
    /// Bias instability B (the Allan floor / 0.6643), unit: flicker.
    pub bias_instability: f32,
    /// Rate random walk K, unit/√s.
    pub rate_random_walk: f32,
    /// Turn-on bias (this power-on's constant offset), unit.
    pub bias: f32,
    /// Scale-factor error, fraction (1e-4 = 100 ppm).
    pub scale_factor: f32,
    /// Non-linearity: the error at full scale of the x·|x|/range term,
    /// fraction of full scale (signed).
    pub nonlinearity: f32,
    /// Sensitivity to the specific force along this axis, unit/g (gyro).
    pub g_sensitivity: f32,
    /// Bias temperature coefficient, unit/°C about 25 °C.
    pub temp_bias: f32,
    /// Scale-factor temperature coefficient, 1/°C about 25 °C.
    pub temp_scale: f32,
}

/// Error parameters of one sensor triad.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SensorErrors {
    /// X, Y, Z.
    pub axes: [AxisErrors; 3],
    /// Misalignment / non-orthogonality, rad: `misalignment[i][j]` (i ≠ j) is
    /// how much of the true axis *j* the sensor axis *i* picks up. The
    /// diagonal is ignored (that is the scale factor).
    pub misalignment: Mat3,
    /// Measurement range ±, unit (saturation); ≤ 0 keeps the engine's.
    pub range: f32,
    /// Quantisation step of the output, unit (0 = none).
    pub resolution: f32,
    /// The sensor's −3 dB bandwidth, Hz: a first-order low-pass of the
    /// output, noise included, before quantisation and saturation
    /// ([`super::bandwidth`]); 0, or at or above the internal rate's
    /// Nyquist frequency: none.
    pub bandwidth_hz: f32,
}

/// Error parameters of the whole unit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorModel {
    /// Gyroscopes, °/s.
    pub gyro: SensorErrors,
    /// Main accelerometers, g.
    pub acc: SensorErrors,
    /// Aux (high-g) accelerometers, g (ignored without one).
    pub aux: SensorErrors,
}

impl SensorErrors {
    /// One unit drawn from `spec`: per axis the turn-on bias and scale
    /// factor (Gaussian) and the signs of the temperature coefficients,
    /// then the misalignments, then the signs of the non-linearity and
    /// g-sensitivity (last, so that a seed draws the same unit as before
    /// these terms existed).
    pub(crate) fn draw(spec: &SensorSpec, rng: &mut Rng) -> Self {
        let mut s = SensorErrors {
            range: spec.range,
            resolution: spec.resolution,
            bandwidth_hz: spec.bandwidth_hz,
            ..SensorErrors::default()
        };
        for a in s.axes.iter_mut() {
            *a = AxisErrors {
                noise_density: spec.noise_density,
                bias_instability: spec.bias_instability,
                rate_random_walk: spec.rate_random_walk,
                bias: spec.turn_on_bias_sigma * rng.gaussian(),
                scale_factor: spec.scale_factor_sigma * rng.gaussian(),
                nonlinearity: 0.0,
                g_sensitivity: 0.0,
                temp_bias: spec.temp_bias * sign(rng.next_u32()),
                temp_scale: spec.temp_scale * sign(rng.next_u32()),
            };
        }
        for (i, row) in s.misalignment.iter_mut().enumerate() {
            for (j, m) in row.iter_mut().enumerate() {
                *m = if i == j {
                    0.0
                } else {
                    spec.misalignment_sigma * rng.gaussian()
                };
            }
        }
        // Only when the profile has the terms: no draw otherwise.
        if spec.nonlinearity != 0.0 || spec.g_sensitivity != 0.0 {
            for a in s.axes.iter_mut() {
                let u = rng.next_u32();
                a.nonlinearity = spec.nonlinearity * sign(u);
                a.g_sensitivity = spec.g_sensitivity * sign(u >> 1);
            }
        }
        s
    }
}

fn sign(bits: u32) -> f32 {
    if bits & 1 == 0 {
        1.0
    } else {
        -1.0
    }
}

impl ErrorModel {
    /// A perfect unit: no error of any kind (tests of the filters and the
    /// attitude use it). Ranges ≤ 0: the engines keep their own.
    pub const IDEAL: ErrorModel = ErrorModel {
        gyro: SENSOR_IDEAL,
        acc: SENSOR_IDEAL,
        aux: SENSOR_IDEAL,
    };

    /// One unit drawn from `profile` (gyro, acc, aux in that order).
    pub fn from_profile(profile: &SensorProfile, rng: &mut Rng) -> Self {
        ErrorModel {
            gyro: SensorErrors::draw(&profile.gyro, rng),
            acc: SensorErrors::draw(&profile.acc, rng),
            aux: SensorErrors::draw(&profile.aux, rng),
        }
    }
}

const AXIS_IDEAL: AxisErrors = AxisErrors {
    noise_density: 0.0,
    bias_instability: 0.0,
    rate_random_walk: 0.0,
    bias: 0.0,
    scale_factor: 0.0,
    nonlinearity: 0.0,
    g_sensitivity: 0.0,
    temp_bias: 0.0,
    temp_scale: 0.0,
};
const SENSOR_IDEAL: SensorErrors = SensorErrors {
    axes: [AXIS_IDEAL; 3],
    misalignment: [[0.0; 3]; 3],
    range: 0.0,
    resolution: 0.0,
    bandwidth_hz: 0.0,
};

/// √3 / 32768: a 16-bit signed uniform scaled to unit variance.
const UNIFORM16_SCALE: f32 = 1.732_050_8 / 32_768.0;

/// Three 16-bit signed uniforms from two draws (the same in both engines).
#[inline(always)]
fn uniforms(rng: &mut Rng) -> [i32; 3] {
    let u = rng.next_u32();
    let u2 = rng.next_u32();
    [
        i32::from(u as u16 as i16),
        i32::from((u >> 16) as u16 as i16),
        i32::from(u2 as u16 as i16),
    ]
}

/// Which slow process steps at tick `phase` (module doc): `Some(k)` for
/// flicker term k, `Some(FLICKER_TERMS)` for the random walk.
#[inline(always)]
fn slow_step(phase: u32) -> Option<usize> {
    let r = phase & 15;
    if (r as usize) < FLICKER_TERMS {
        let k = r as usize;
        (phase & (FLICKER_PERIOD_TICKS[k] - 1) == r).then_some(k)
    } else if r == RANDOM_WALK_PHASE {
        Some(FLICKER_TERMS)
    } else {
        None
    }
}

/// The decay of flicker term k per step, `e^(−D_k·dt/T_k)`.
fn flicker_decay(k: usize, dt: f64) -> f64 {
    libm::exp(-f64::from(FLICKER_PERIOD_TICKS[k]) * dt / f64::from(FLICKER_CORNERS_S[k]))
}

/// The per-tick engine of one triad: the model's parameters turned into
/// coefficients, and the slow (flicker, random-walk) state.
#[derive(Debug, Clone, PartialEq)]
pub struct TriadEngine {
    m: Mat3,
    identity_m: bool,
    bias: Vec3,
    /// Flicker terms per axis.
    flicker: [[f32; FLICKER_TERMS]; 3],
    /// Rate random walk per axis.
    walk: Vec3,
    /// Σ flicker + walk (updated when one of them steps).
    slow: Vec3,
    flicker_a: [f32; FLICKER_TERMS],
    flicker_b: [[f32; FLICKER_TERMS]; 3],
    walk_b: Vec3,
    sigma: Vec3,
    g_sens: Vec3,
    nonlin: Vec3,
    quant: f32,
    inv_quant: f32,
    /// Any slow process, white noise, g-sensitivity or non-linearity.
    noisy: bool,
    slow_on: bool,
    coupled: bool,
    phase: u32,
    range: f32,
    /// The sensor's bandwidth ([`super::bandwidth`]).
    lpf: SensorLowPass,
}

impl TriadEngine {
    /// An engine with saturation at ±`range` (°/s or g).
    pub fn new(range: f32) -> Self {
        TriadEngine {
            m: crate::math::rotation::MAT3_IDENTITY,
            identity_m: true,
            bias: [0.0; 3],
            flicker: [[0.0; FLICKER_TERMS]; 3],
            walk: [0.0; 3],
            slow: [0.0; 3],
            flicker_a: [0.0; FLICKER_TERMS],
            flicker_b: [[0.0; FLICKER_TERMS]; 3],
            walk_b: [0.0; 3],
            sigma: [0.0; 3],
            g_sens: [0.0; 3],
            nonlin: [0.0; 3],
            quant: 0.0,
            inv_quant: 0.0,
            noisy: false,
            slow_on: false,
            coupled: false,
            phase: 0,
            range,
            lpf: SensorLowPass::OFF,
        }
    }

    /// Recomputes every coefficient from `e` for ticks of `dt` (exp and
    /// square roots: call when the parameters change, not per tick), then
    /// applies `temp_c`. The slow state is kept (it is the physical bias).
    pub fn configure(&mut self, e: &SensorErrors, temp_c: f32, dt: f32) {
        if e.range > 0.0 {
            self.range = e.range;
        }
        let mut slow_on = false;
        let mut noisy = false;
        let mut coupled = false;
        for k in 0..FLICKER_TERMS {
            self.flicker_a[k] = flicker_decay(k, f64::from(dt)) as f32;
        }
        for i in 0..3 {
            let a = &e.axes[i];
            self.sigma[i] = a.noise_density / sqrtf(dt);
            let q = FLICKER_SIGMA_PER_BIAS_INSTABILITY * a.bias_instability.max(0.0);
            for k in 0..FLICKER_TERMS {
                let ak = self.flicker_a[k];
                self.flicker_b[i][k] = q * sqrtf((1.0 - ak * ak).max(0.0)) * UNIFORM16_SCALE;
            }
            if q == 0.0 {
                self.flicker[i] = [0.0; FLICKER_TERMS];
            }
            self.walk_b[i] = a.rate_random_walk.max(0.0)
                * sqrtf(RANDOM_WALK_PERIOD_TICKS as f32 * dt)
                * UNIFORM16_SCALE;
            if self.walk_b[i] == 0.0 {
                self.walk[i] = 0.0;
            }
            self.g_sens[i] = a.g_sensitivity;
            self.nonlin[i] = if self.range > 0.0 {
                a.nonlinearity / self.range
            } else {
                0.0
            };
            slow_on |= q != 0.0 || self.walk_b[i] != 0.0;
            coupled |= a.g_sensitivity != 0.0 || a.nonlinearity != 0.0;
            noisy |= self.sigma[i] != 0.0;
        }
        self.resum();
        self.quant = e.resolution.max(0.0);
        self.inv_quant = if self.quant > 0.0 {
            1.0 / self.quant
        } else {
            0.0
        };
        self.slow_on = slow_on;
        self.lpf.configure(e.bandwidth_hz, dt);
        // The filter's path is the noisy one (the ideal path adds the bias
        // alone).
        self.noisy = noisy || slow_on || coupled || self.quant > 0.0 || self.lpf.is_on();
        self.coupled = coupled;
        self.set_temperature(e, temp_c);
    }

    fn resum(&mut self) {
        for i in 0..3 {
            self.slow[i] = self.flicker[i].iter().sum::<f32>() + self.walk[i];
        }
    }

    /// Applies the temperature-dependent terms at `temp_c` (cheap: a few
    /// multiplications).
    pub fn set_temperature(&mut self, e: &SensorErrors, temp_c: f32) {
        let dtemp = temp_c - REFERENCE_TEMPERATURE_C;
        // The misalignment off the diagonal, the scale on it.
        self.m = e.misalignment;
        for (i, a) in e.axes.iter().enumerate() {
            self.m[i][i] = 1.0 + a.scale_factor + a.temp_scale * dtemp;
            self.bias[i] = a.bias + a.temp_bias * dtemp;
        }
        self.identity_m = self.m == crate::math::rotation::MAT3_IDENTITY;
    }

    /// Starts the flicker terms in their stationary distribution (at
    /// power-on a unit's slow bias is already somewhere; the random walk
    /// starts at 0): one Gaussian per axis and term.
    pub fn randomize_slow(&mut self, e: &SensorErrors, rng: &mut Rng) {
        for i in 0..3 {
            let q = FLICKER_SIGMA_PER_BIAS_INSTABILITY * e.axes[i].bias_instability.max(0.0);
            for k in 0..FLICKER_TERMS {
                self.flicker[i][k] = if q > 0.0 { q * rng.gaussian() } else { 0.0 };
            }
            self.walk[i] = 0.0;
        }
        self.resum();
    }

    /// The current slow bias (flicker + random walk).
    pub fn slow_bias(&self) -> Vec3 {
        self.slow
    }

    /// Saturation level (°/s or g).
    pub fn range(&self) -> f32 {
        self.range
    }

    /// Advances the slow process due at this tick, if any.
    #[inline(always)]
    fn step_slow(&mut self, rng: &mut Rng) {
        self.phase = self.phase.wrapping_add(1);
        let Some(k) = slow_step(self.phase) else {
            return;
        };
        let u = uniforms(rng);
        for i in 0..3 {
            let w = u[i] as f32;
            if k < FLICKER_TERMS {
                let x = &mut self.flicker[i][k];
                *x = self.flicker_a[k] * *x + self.flicker_b[i][k] * w;
            } else {
                self.walk[i] += self.walk_b[i] * w;
            }
        }
        self.resum();
    }

    /// One tick: measures `truth` (with `force`, the specific force in g
    /// along the same axes, for the g-sensitivity); returns the
    /// measurement and a mask of the axes beyond the range (bit i = axis
    /// i), which are clipped.
    #[inline]
    pub fn measure(&mut self, truth: &Vec3, force: &Vec3, rng: &mut Rng) -> (Vec3, u8) {
        let mut y = if self.identity_m {
            *truth
        } else {
            crate::math::rotation::mat_vec(&self.m, truth)
        };
        if self.noisy {
            if self.slow_on {
                self.step_slow(rng);
            }
            if self.coupled {
                for i in 0..3 {
                    y[i] += self.g_sens[i] * force[i] + self.nonlin[i] * y[i] * y[i].abs();
                }
            }
            for i in 0..3 {
                y[i] += self.bias[i] + self.slow[i] + self.sigma[i] * rng.gaussian();
            }
            // The sensor's own response, then its output word: resolution
            // and range (docs/sensors.md "Bandwidth").
            if self.lpf.is_on() {
                self.lpf.apply(&mut y);
            }
            if self.quant > 0.0 {
                for v in y.iter_mut() {
                    *v = libm::roundf(*v * self.inv_quant) * self.quant;
                }
            }
        } else {
            for i in 0..3 {
                y[i] += self.bias[i];
            }
        }
        let over = saturate(&mut y, self.range);
        (y, over)
    }
}

/// An entry of M − I for the fixed-point engine: clamped to ±¼ (NaN → 0).
fn delta(x: f32) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        f64::from(x.clamp(-0.25, 0.25))
    }
}

/// [`TriadEngine`] in integers, for the `fixed-point` build: the same
/// model and the same random draws, on measurements scaled by 2^`bits`
/// ([`GYRO_BITS`](crate::math::GYRO_BITS), [`ACC_BITS`]).
///
/// - M − I as [`Coef`]s (14-bit mantissas: a 300 ppm scale factor is kept to
///   0.02 ppm); the temperature terms (scale factor and bias) are set one
///   axis at a time ([`TriadEngineFixed::set_axis_temperature`]: two `f32`
///   products), so the chain spreads a temperature step over nine ticks
///   instead of spending a few thousand soft-float instructions in one;
/// - white noise: the integer Irwin–Hall sum ([`Rng::gaussian_sum`]) times
///   one [`Coef`] (σ·√3/65536);
/// - flicker: `x ← x − ε_k·x + b_k·u` on states with `slow_shift` extra
///   fraction bits (per axis, so that 16 σ fill 2²⁶; a step's decay ε_k ≈
///   1/125 of the state is then thousands of LSB and rounds without bias),
///   `u` the same 16-bit uniform as the float engine; the random walk on a
///   state with `walk_shift` fraction bits (its 10⁶ s excursion fills 2²⁸);
/// - g-sensitivity: one [`Coef`] times the force; non-linearity: one
///   [`Coef`] times `x·|x|/2³¹` (an exact 64-bit product); resolution: a
///   rounded division by the step ([`Recip`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TriadEngineFixed {
    /// M − I.
    m: [[Coef; 3]; 3],
    identity_m: bool,
    noisy: bool,
    slow_on: bool,
    coupled: bool,
    bits: u8,
    slow_shift: [u8; 3],
    walk_shift: [u8; 3],
    /// Bias now, scaled.
    bias: [i32; 3],
    flicker: [[i32; FLICKER_TERMS]; 3],
    walk: [i32; 3],
    /// Σ flicker and walk at the measurement's scale.
    slow: [i32; 3],
    flicker_decay: [Coef; FLICKER_TERMS],
    flicker_drive: [[Coef; FLICKER_TERMS]; 3],
    walk_drive: [Coef; 3],
    sigma: [Coef; 3],
    g_sens: [Coef; 3],
    nonlin: [Coef; 3],
    quant: Option<(Recip, i32)>,
    phase: u32,
    range: i32,
    /// The sensor's bandwidth ([`super::bandwidth`]).
    lpf: SensorLowPassFixed,
}

fn q(v: f64, bits: u32) -> i32 {
    let x = libm::round(v * crate::math::exp2i(bits as i32));
    if x.is_nan() {
        0
    } else {
        x.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }
}

/// The largest shift k ≤ 24 with `s · 2^k ≤ 2^limit` (0 for s ≤ 0 or NaN).
fn shift_for(s: f64, limit: u32) -> u8 {
    if s.is_nan() || s <= 0.0 {
        return 0;
    }
    let mut k = 0u8;
    while k < 24 && s * crate::math::exp2i(i32::from(k) + 1) <= f64::from(1u32 << limit) {
        k += 1;
    }
    k
}

impl TriadEngineFixed {
    /// An engine with saturation at ±`range` (°/s or g) on measurements
    /// scaled by 2^`bits`.
    pub fn new(range: f32, bits: u32) -> Self {
        TriadEngineFixed {
            m: [[Coef::ZERO; 3]; 3],
            identity_m: true,
            noisy: false,
            slow_on: false,
            coupled: false,
            bits: bits as u8,
            slow_shift: [0; 3],
            walk_shift: [0; 3],
            bias: [0; 3],
            flicker: [[0; FLICKER_TERMS]; 3],
            walk: [0; 3],
            slow: [0; 3],
            flicker_decay: [Coef::ZERO; FLICKER_TERMS],
            flicker_drive: [[Coef::ZERO; FLICKER_TERMS]; 3],
            walk_drive: [Coef::ZERO; 3],
            sigma: [Coef::ZERO; 3],
            g_sens: [Coef::ZERO; 3],
            nonlin: [Coef::ZERO; 3],
            quant: None,
            phase: 0,
            range: q(f64::from(range), bits).max(0),
            lpf: SensorLowPassFixed::OFF,
        }
    }

    /// The scale exponent: measurements are in units of 2^−bits.
    pub fn bits(&self) -> u32 {
        u32::from(self.bits)
    }

    fn scale(&self) -> f64 {
        crate::math::exp2i(self.bits as i32)
    }

    /// σ of one flicker term of axis `a`, scaled.
    fn flicker_sigma(&self, a: &AxisErrors) -> f64 {
        f64::from(FLICKER_SIGMA_PER_BIAS_INSTABILITY)
            * f64::from(a.bias_instability.max(0.0))
            * self.scale()
    }

    /// The random walk's 10⁶ s excursion K·1000, scaled.
    fn walk_span(&self, a: &AxisErrors) -> f64 {
        f64::from(a.rate_random_walk.max(0.0)) * 1000.0 * self.scale()
    }

    /// [`TriadEngine::configure`]: every coefficient from `e` for ticks of
    /// `dt` at `temp_c` (float, at configuration time). The slow state is
    /// kept (rescaled if its fraction bits change).
    pub fn configure(&mut self, e: &SensorErrors, temp_c: f32, dt: f32) {
        if e.range > 0.0 {
            // Capped below the truth limits (±4095 °/s, ±128 g), so a
            // truth beyond the range is flagged (the IMX-5's ±4000 °/s
            // is within them).
            let limit = if self.bits() == ACC_BITS {
                TRUTH_LIMIT
            } else {
                RATE_TRUTH_LIMIT
            };
            self.range = q(f64::from(e.range), self.bits()).clamp(0, limit - 1);
        }
        let scale = self.scale();
        let dt = f64::from(dt);
        let (mut noisy, mut slow_on, mut coupled) = (false, false, false);
        for k in 0..FLICKER_TERMS {
            self.flicker_decay[k] = Coef::new(1.0 - flicker_decay(k, dt));
        }
        // u is a 16-bit signed uniform: ×√3/32768 for unit variance.
        let u16_scale = 1.732_050_8 / 32_768.0;
        for i in 0..3 {
            let a = &e.axes[i];
            let shift = shift_for(self.flicker_sigma(a), 26);
            let old = self.slow_shift[i];
            for x in self.flicker[i].iter_mut() {
                *x = rescale(*x, old, shift);
            }
            self.slow_shift[i] = shift;
            let g = self.flicker_sigma(a) * crate::math::exp2i(i32::from(shift));
            for k in 0..FLICKER_TERMS {
                let ak = flicker_decay(k, dt);
                self.flicker_drive[i][k] =
                    Coef::new(g * libm::sqrt((1.0 - ak * ak).max(0.0)) * u16_scale);
            }
            if g == 0.0 {
                self.flicker[i] = [0; FLICKER_TERMS];
            }
            let wshift = shift_for(self.walk_span(a), 28);
            self.walk[i] = rescale(self.walk[i], self.walk_shift[i], wshift);
            self.walk_shift[i] = wshift;
            let k_step = f64::from(a.rate_random_walk.max(0.0))
                * libm::sqrt(f64::from(RANDOM_WALK_PERIOD_TICKS) * dt)
                * scale
                * crate::math::exp2i(i32::from(wshift));
            self.walk_drive[i] = Coef::new(k_step * u16_scale);
            if self.walk_drive[i] == Coef::ZERO {
                self.walk[i] = 0;
            }
            let sigma = f64::from(a.noise_density) / libm::sqrt(dt) * scale;
            self.sigma[i] = Coef::new(sigma * f64::from(crate::sensor::rng::IRWIN_HALL_SCALE));
            // g-sensitivity: force at 2^ACC_BITS into this engine's scale.
            self.g_sens[i] = Coef::new(
                f64::from(a.g_sensitivity) * crate::math::exp2i(self.bits as i32 - ACC_BITS as i32),
            );
            // Non-linearity: nl/range · x·|x| = nl·2³¹/R_s · (x·|x| / 2³¹).
            let r_s = f64::from(self.range);
            self.nonlin[i] = if r_s > 0.0 {
                Coef::new(f64::from(a.nonlinearity) * 2_147_483_648.0 / r_s)
            } else {
                Coef::ZERO
            };
            slow_on |= self.flicker_drive[i].iter().any(|c| *c != Coef::ZERO)
                || self.walk_drive[i] != Coef::ZERO;
            coupled |= self.g_sens[i] != Coef::ZERO || self.nonlin[i] != Coef::ZERO;
            noisy |= self.sigma[i] != Coef::ZERO;
            for j in 0..3 {
                if i != j {
                    self.m[i][j] = Coef::new(delta(e.misalignment[i][j]));
                }
            }
        }
        self.resum();
        let step = q(f64::from(e.resolution.max(0.0)), self.bits());
        self.quant = (step > 1).then(|| (Recip::new(step as u32), step));
        self.slow_on = slow_on;
        self.coupled = coupled;
        self.lpf.configure(e.bandwidth_hz, dt as f32);
        self.noisy = noisy || slow_on || coupled || self.quant.is_some() || self.lpf.is_on();
        for i in 0..3 {
            self.set_axis_temperature(e, i, temp_c);
        }
    }

    fn resum(&mut self) {
        for i in 0..3 {
            let f = self.flicker[i]
                .iter()
                .fold(0i32, |s, x| s.saturating_add(*x));
            self.slow[i] = round_shr(f, self.slow_shift[i])
                .saturating_add(round_shr(self.walk[i], self.walk_shift[i]));
        }
    }

    /// The temperature terms of axis `i` at `temp_c`: scale factor
    /// `1 + sf + ts·ΔT` and bias `b + tb·ΔT` (two `f32` products, the same
    /// arithmetic as [`TriadEngine::set_temperature`]).
    pub fn set_axis_temperature(&mut self, e: &SensorErrors, i: usize, temp_c: f32) {
        let a = &e.axes[i];
        let dtemp = temp_c - REFERENCE_TEMPERATURE_C;
        self.m[i][i] = Coef::from_f32(delta(a.scale_factor + a.temp_scale * dtemp) as f32);
        self.bias[i] =
            crate::math::fixed::to_fixed(a.bias + a.temp_bias * dtemp, u32::from(self.bits));
        self.identity_m = self.m.iter().flatten().all(|c| *c == Coef::ZERO);
    }

    /// [`TriadEngine::randomize_slow`]: the flicker terms drawn from their
    /// stationary distribution (one Gaussian per axis and term, as the
    /// float engine draws), the random walk at 0.
    pub fn randomize_slow(&mut self, e: &SensorErrors, rng: &mut Rng) {
        for i in 0..3 {
            let a = &e.axes[i];
            let shift = shift_for(self.flicker_sigma(a), 26);
            self.slow_shift[i] = shift;
            let g = self.flicker_sigma(a) * crate::math::exp2i(i32::from(shift));
            let k = Coef::new(g * f64::from(crate::sensor::rng::IRWIN_HALL_SCALE));
            for x in self.flicker[i].iter_mut() {
                *x = if g > 0.0 {
                    k.apply_small(rng.gaussian_sum())
                } else {
                    0
                };
            }
            self.walk[i] = 0;
        }
        self.resum();
    }

    /// The current slow bias (flicker + random walk), scaled.
    pub fn slow_bias(&self) -> [i32; 3] {
        self.slow
    }

    /// Saturation level, scaled.
    pub fn range(&self) -> i32 {
        self.range
    }

    /// Advances the slow process due at this tick, if any.
    #[inline(always)]
    fn step_slow(&mut self, rng: &mut Rng) {
        self.phase = self.phase.wrapping_add(1);
        let Some(k) = slow_step(self.phase) else {
            return;
        };
        let u = uniforms(rng);
        for i in 0..3 {
            if k < FLICKER_TERMS {
                let x = self.flicker[i][k];
                self.flicker[i][k] = x
                    .saturating_sub(self.flicker_decay[k].apply(x))
                    .saturating_add(self.flicker_drive[i][k].apply_small(u[i]));
            } else {
                self.walk[i] = self.walk[i].saturating_add(self.walk_drive[i].apply_small(u[i]));
            }
        }
        self.resum();
    }

    /// One tick: measures `truth` (scaled, any `i32`: M·truth is summed in
    /// `i64` and saturated; `force`
    /// the specific force at 2^[`ACC_BITS`] for the g-sensitivity); returns
    /// the measurement and a mask of the axes beyond the range (bit i =
    /// axis i), which are clipped.
    #[inline(always)]
    pub fn measure(&mut self, truth: &[i32; 3], force: &[i32; 3], rng: &mut Rng) -> ([i32; 3], u8) {
        let x = truth;
        let mut y = *x;
        if !self.identity_m {
            for i in 0..3 {
                let r = &self.m[i];
                // |M − I| ≤ ¼ an entry: |Σ| < 1.75·2³¹, an i64 (the IMX-5's
                // ±4000 °/s is 0.98·2³¹); saturated to the i32 (the range
                // then clips and flags it).
                let s = i64::from(x[i])
                    + i64::from(r[0].apply(x[0]))
                    + i64::from(r[1].apply(x[1]))
                    + i64::from(r[2].apply(x[2]));
                y[i] = s.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
            }
        }
        if self.noisy {
            if self.slow_on {
                self.step_slow(rng);
            }
            if self.coupled {
                for i in 0..3 {
                    let sq = (mul64(y[i], y[i].saturating_abs()) >> 31) as i32;
                    y[i] = y[i]
                        .saturating_add(self.g_sens[i].apply(force[i]))
                        .saturating_add(self.nonlin[i].apply(sq));
                }
            }
            for i in 0..3 {
                let e = self.bias[i]
                    .saturating_add(self.slow[i])
                    .saturating_add(self.sigma[i].apply_small(rng.gaussian_sum()));
                y[i] = y[i].saturating_add(e);
            }
            if self.lpf.is_on() {
                self.lpf.apply(&mut y);
            }
            if let Some((r, step)) = self.quant {
                for v in y.iter_mut() {
                    *v = r.div_round(i64::from(*v)).saturating_mul(step);
                }
            }
        } else {
            for i in 0..3 {
                y[i] = y[i].saturating_add(self.bias[i]);
            }
        }
        let over = saturate(&mut y, self.range);
        (y, over)
    }
}

/// Clips each axis of `y` to ±`range` (NaN → 0); the mask of the clipped
/// axes (bit i = axis i).
#[inline(always)]
fn saturate<T>(y: &mut [T; 3], range: T) -> u8
where
    T: Copy + Default + PartialOrd + core::ops::Neg<Output = T>,
{
    let mut over = 0u8;
    for (i, v) in y.iter_mut().enumerate() {
        if *v > range {
            *v = range;
            over |= 1 << i;
        } else if *v < -range {
            *v = -range;
            over |= 1 << i;
        } else if (*v).partial_cmp(&*v).is_none() {
            *v = T::default();
        }
    }
    over
}

/// A state with `old` fraction bits at `new` fraction bits.
fn rescale(x: i32, old: u8, new: u8) -> i32 {
    if new >= old {
        x.saturating_mul(1 << (new - old))
    } else {
        x >> (old - new)
    }
}

/// `x / 2^s` rounded to nearest (half up).
#[inline(always)]
fn round_shr(x: i32, s: u8) -> i32 {
    if s == 0 {
        x
    } else {
        (x >> s) + ((x >> (s - 1)) & 1)
    }
}
