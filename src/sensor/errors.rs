//! The sensor error model: per sensor and axis, parameters named after the
//! Allan-variance terms a datasheet gives, and the per-tick engine that
//! applies them.
//!
//! For each axis *i* of a sensor triad (gyro °/s, accelerometers g):
//!
//! ```text
//! measured = sat( Σ_j M_ij · truth_j  +  b_i + x_i(t)  +  σ_i · w_i )
//! M        = I + diag(scale_factor + temp_scale·ΔT) + misalignment (off-diagonal)
//! b_i      = bias (turn-on) + temp_bias · ΔT,   ΔT = T − 25 °C
//! x_i(t)   = first-order Gauss–Markov bias, σ_GM and correlation time T_c
//! σ_i      = noise_density · √f_s             (white noise per tick)
//! ```
//!
//! **Allan mapping.** White noise of density N (unit/√Hz) has the Allan
//! deviation `σ(τ) = N/√τ`; so ARW [°/√h] = 60 · N [°/s/√Hz] and VRW
//! [m/s/√h] = 60 · 9.8106 · N [g/√Hz]. A Gauss–Markov process of variance
//! σ_GM² and correlation time T_c has an Allan deviation that peaks at
//! τ ≈ 1.89 T_c with the value 0.6174 σ_GM; a datasheet's bias instability B
//! is read off the floor of the Allan plot as σ_min / 0.6643 (the flicker
//! constant √(2 ln 2/π)). The model sets `σ_GM = 1.0760 · B` so that the
//! Allan deviation of the bias term peaks at exactly 0.6643 · B: the plot of
//! a static run shows the datasheet's floor where the datasheet has it.
//!
//! The turn-on bias, scale factors and misalignments are *realised* values:
//! [`ErrorModel::for_product`] draws them once from the seed with the model's
//! spread ([`ErrorSpec`]), so a seed is one particular unit. The host may
//! overwrite any of them through [`crate::chain::SignalChain::errors_mut`].
//!
//! [`TriadEngineFixed`] is the same engine in integers for the `fixed-point`
//! build (same random draws; `tests/signal_noise.rs` pins its Allan
//! deviation and its sample-by-sample agreement with [`TriadEngine`]). It
//! clamps each entry of M − I to ±¼ and truth to ±2³⁰ of its scale.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::rng::Rng;
use crate::math::fixed::Coef;
use crate::math::rotation::{Mat3, Vec3};
use crate::model::{Product, SensorGrade};
use libm::{expf, sqrtf};

/// σ_GM / B: makes the Gauss–Markov Allan peak equal 0.6643 · B (module doc).
pub const GM_SIGMA_PER_BIAS_INSTABILITY: f32 = 1.076;
/// Reference temperature of the temperature coefficients, °C.
pub const REFERENCE_TEMPERATURE_C: f32 = 25.0;

/// Error parameters of one axis, in the sensor's output unit (°/s for a
/// gyro, g for an accelerometer).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisErrors {
    /// White-noise density, unit/√Hz: the angle random walk of a gyro
    /// (ARW °/√h = 60 × this) or the velocity random walk of an
    /// accelerometer (VRW m/s/√h = 60 × 9.8106 × this).
    pub noise_density: f32,
    /// Bias instability B (the Allan floor / 0.6643), unit.
    pub bias_instability: f32,
    /// Correlation time of the Gauss–Markov bias, s (≤ 0 disables it).
    pub bias_corr_time_s: f32,
    /// Turn-on bias (this power-on's constant offset), unit.
    pub bias: f32,
    /// Scale-factor error, fraction (1e-4 = 100 ppm).
    pub scale_factor: f32,
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

/// Datasheet-style spread of a sensor class, from which
/// [`ErrorModel::for_product`] draws one unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSpec {
    /// White-noise density, unit/√Hz.
    pub noise_density: f32,
    /// Bias instability, unit.
    pub bias_instability: f32,
    /// Gauss–Markov correlation time, s.
    pub bias_corr_time_s: f32,
    /// 1σ of the turn-on bias, unit.
    pub turn_on_bias_sigma: f32,
    /// 1σ of the scale-factor error, fraction.
    pub scale_factor_sigma: f32,
    /// 1σ of each misalignment angle, rad.
    pub misalignment_sigma: f32,
    /// Bias temperature coefficient, unit/°C (signs drawn per axis).
    pub temp_bias: f32,
    /// Scale-factor temperature coefficient, 1/°C (signs drawn per axis).
    pub temp_scale: f32,
}

/// The spread of one model's sensors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorSpec {
    /// Gyroscopes (°/s).
    pub gyro: SensorSpec,
    /// Main accelerometers (g).
    pub acc: SensorSpec,
    /// Aux accelerometers (g).
    pub aux: SensorSpec,
}

/// ARW in °/√h → noise density in °/s/√Hz.
pub const fn arw_to_density(arw_deg_per_rt_h: f32) -> f32 {
    arw_deg_per_rt_h / 60.0
}

/// VRW in m/s/√h → noise density in g/√Hz.
pub const fn vrw_to_density(vrw_m_s_per_rt_h: f32) -> f32 {
    vrw_m_s_per_rt_h / 60.0 / crate::math::G
}

/// ICD 2.2: "non-orthogonality between axes … in the order of 0.01°".
const MISALIGN_SIGMA: f32 = 0.01 * core::f32::consts::PI / 180.0;

const fn gyro_spec(arw: f32, bias_inst_deg_h: f32) -> SensorSpec {
    SensorSpec {
        noise_density: arw_to_density(arw),
        bias_instability: bias_inst_deg_h / 3600.0,
        bias_corr_time_s: 100.0,
        turn_on_bias_sigma: 0.05,
        scale_factor_sigma: 300e-6,
        misalignment_sigma: MISALIGN_SIGMA,
        temp_bias: 1e-4,
        temp_scale: 10e-6,
    }
}

const fn acc_spec(vrw: f32, bias_inst_ug: f32) -> SensorSpec {
    SensorSpec {
        noise_density: vrw_to_density(vrw),
        bias_instability: bias_inst_ug * 1e-6,
        bias_corr_time_s: 100.0,
        turn_on_bias_sigma: 1e-3,
        scale_factor_sigma: 300e-6,
        misalignment_sigma: MISALIGN_SIGMA,
        temp_bias: 10e-6,
        temp_scale: 10e-6,
    }
}

/// The aux (±90 g) accelerometer of K120/K220.
const AUX_SPEC: SensorSpec = SensorSpec {
    noise_density: vrw_to_density(0.3),
    bias_instability: 200e-6,
    bias_corr_time_s: 100.0,
    turn_on_bias_sigma: 5e-3,
    scale_factor_sigma: 1000e-6,
    misalignment_sigma: MISALIGN_SIGMA,
    temp_bias: 100e-6,
    temp_scale: 20e-6,
};

impl ErrorSpec {
    /// The emulator's default spread for `product`'s model, by the grade
    /// its model row carries ([`SensorGrade`]). These are plausible values
    /// for tactical-grade MEMS IMUs of each class — not Inertial Labs
    /// datasheet figures; put your unit's datasheet here:
    ///
    /// | grade (models) | gyro ARW °/√h | gyro B °/h | acc VRW m/s/√h | acc B µg |
    /// |---|---|---|---|---|
    /// | Entry (K100, K102, K201) | 0.24 | 3 | 0.04 | 10 |
    /// | Mid (K108, K110, K110M, K120) | 0.2 | 2 | 0.03 | 7 |
    /// | High (K210, K220) | 0.1 | 1 | 0.02 | 5 |
    /// | aux (K120, K220) | — | — | 0.3 | 200 |
    ///
    /// All: T_c 100 s; turn-on bias 1σ 0.05 °/s, 1 mg (aux 5 mg); scale
    /// factor 1σ 300 ppm (aux 1000 ppm); misalignment 1σ 0.01° (ICD 2.2);
    /// temperature coefficients 1e-4 °/s/°C, 10 µg/°C (aux 100 µg/°C),
    /// 10 ppm/°C (aux 20 ppm/°C).
    pub fn for_product(product: &Product) -> ErrorSpec {
        let (gyro, acc) = match product.model.grade {
            SensorGrade::Entry => (gyro_spec(0.24, 3.0), acc_spec(0.04, 10.0)),
            SensorGrade::Mid => (gyro_spec(0.2, 2.0), acc_spec(0.03, 7.0)),
            SensorGrade::High => (gyro_spec(0.1, 1.0), acc_spec(0.02, 5.0)),
        };
        ErrorSpec {
            gyro,
            acc,
            aux: AUX_SPEC,
        }
    }
}

impl SensorErrors {
    /// One unit drawn from `spec`.
    pub fn draw(spec: &SensorSpec, rng: &mut Rng) -> Self {
        let mut s = SensorErrors::default();
        for a in s.axes.iter_mut() {
            *a = AxisErrors {
                noise_density: spec.noise_density,
                bias_instability: spec.bias_instability,
                bias_corr_time_s: spec.bias_corr_time_s,
                bias: spec.turn_on_bias_sigma * rng.gaussian(),
                scale_factor: spec.scale_factor_sigma * rng.gaussian(),
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
    /// attitude use it).
    pub const IDEAL: ErrorModel = ErrorModel {
        gyro: SENSOR_IDEAL,
        acc: SENSOR_IDEAL,
        aux: SENSOR_IDEAL,
    };

    /// One unit of `product`'s model drawn from [`ErrorSpec::for_product`].
    pub fn for_product(product: &Product, rng: &mut Rng) -> Self {
        let spec = ErrorSpec::for_product(product);
        ErrorModel {
            gyro: SensorErrors::draw(&spec.gyro, rng),
            acc: SensorErrors::draw(&spec.acc, rng),
            aux: SensorErrors::draw(&spec.aux, rng),
        }
    }
}

const AXIS_IDEAL: AxisErrors = AxisErrors {
    noise_density: 0.0,
    bias_instability: 0.0,
    bias_corr_time_s: 0.0,
    bias: 0.0,
    scale_factor: 0.0,
    temp_bias: 0.0,
    temp_scale: 0.0,
};
const SENSOR_IDEAL: SensorErrors = SensorErrors {
    axes: [AXIS_IDEAL; 3],
    misalignment: [[0.0; 3]; 3],
};

/// The per-tick engine of one triad: the model's parameters turned into
/// coefficients, and the Gauss–Markov state.
#[derive(Debug, Clone, PartialEq)]
pub struct TriadEngine {
    m: Mat3,
    identity_m: bool,
    bias: Vec3,
    gm: Vec3,
    gm_a: Vec3,
    gm_b: Vec3,
    sigma: Vec3,
    noisy: bool,
    range: f32,
}

/// √3 / 32768: a 16-bit signed uniform scaled to unit variance.
const UNIFORM16_SCALE: f32 = 1.732_050_8 / 32_768.0;

impl TriadEngine {
    /// An engine with saturation at ±`range` (°/s or g).
    pub fn new(range: f32) -> Self {
        TriadEngine {
            m: crate::math::rotation::MAT3_IDENTITY,
            identity_m: true,
            bias: [0.0; 3],
            gm: [0.0; 3],
            gm_a: [0.0; 3],
            gm_b: [0.0; 3],
            sigma: [0.0; 3],
            noisy: false,
            range,
        }
    }

    /// Recomputes every coefficient from `e` for ticks of `dt` (exp and
    /// square roots: call when the parameters change, not per tick), then
    /// applies `temp_c`. The Gauss–Markov state is kept (it is the physical
    /// bias).
    pub fn configure(&mut self, e: &SensorErrors, temp_c: f32, dt: f32) {
        let mut noisy = false;
        for i in 0..3 {
            let a = &e.axes[i];
            self.sigma[i] = a.noise_density / sqrtf(dt);
            if a.bias_corr_time_s > 0.0 && a.bias_instability > 0.0 {
                let k = expf(-dt / a.bias_corr_time_s);
                self.gm_a[i] = k;
                self.gm_b[i] = GM_SIGMA_PER_BIAS_INSTABILITY
                    * a.bias_instability
                    * sqrtf((1.0 - k * k).max(0.0));
            } else {
                self.gm_a[i] = 0.0;
                self.gm_b[i] = 0.0;
                self.gm[i] = 0.0;
            }
            noisy |= self.sigma[i] != 0.0 || self.gm_b[i] != 0.0;
        }
        self.noisy = noisy;
        self.set_temperature(e, temp_c);
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

    /// Starts the Gauss–Markov biases in their stationary distribution (at
    /// power-on a unit's slow bias is already somewhere).
    pub fn randomize_gm(&mut self, e: &SensorErrors, rng: &mut Rng) {
        for i in 0..3 {
            let a = &e.axes[i];
            self.gm[i] = if a.bias_corr_time_s > 0.0 {
                GM_SIGMA_PER_BIAS_INSTABILITY * a.bias_instability * rng.gaussian()
            } else {
                0.0
            };
        }
    }

    /// The current Gauss–Markov bias.
    pub fn gm_bias(&self) -> Vec3 {
        self.gm
    }

    /// Saturation level (°/s or g).
    pub fn range(&self) -> f32 {
        self.range
    }

    /// One tick: measures `truth`; returns the measurement and a mask of the
    /// axes beyond the range (bit i = axis i), which are clipped.
    #[inline]
    pub fn measure(&mut self, truth: &Vec3, rng: &mut Rng) -> (Vec3, u8) {
        let mut y = if self.identity_m {
            *truth
        } else {
            crate::math::rotation::mat_vec(&self.m, truth)
        };
        if self.noisy {
            let u = rng.next_u32();
            let u2 = rng.next_u32();
            let inn = [
                (u as u16 as i16) as f32,
                ((u >> 16) as u16 as i16) as f32,
                (u2 as u16 as i16) as f32,
            ];
            for i in 0..3 {
                self.gm[i] = self.gm_a[i] * self.gm[i] + self.gm_b[i] * inn[i] * UNIFORM16_SCALE;
                y[i] += self.bias[i] + self.gm[i] + self.sigma[i] * rng.gaussian();
            }
        } else {
            for i in 0..3 {
                y[i] += self.bias[i];
            }
        }
        let mut over = 0u8;
        for (i, v) in y.iter_mut().enumerate() {
            if *v > self.range {
                *v = self.range;
                over |= 1 << i;
            } else if *v < -self.range {
                *v = -self.range;
                over |= 1 << i;
            } else if v.is_nan() {
                *v = 0.0;
            }
        }
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
/// ([`GYRO_BITS`](crate::math::GYRO_BITS), [`ACC_BITS`](crate::math::ACC_BITS)).
///
/// - M − I as [`Coef`]s (14-bit mantissas: a 300 ppm scale factor is kept to
///   0.02 ppm); the temperature terms (scale factor and bias) are set one
///   axis at a time ([`TriadEngineFixed::set_axis_temperature`]: two `f32`
///   products), so the chain spreads a temperature step over nine ticks
///   instead of spending a few thousand soft-float instructions in one;
/// - white noise: the integer Irwin–Hall sum ([`Rng::gaussian_sum`]) times
///   one [`Coef`] (σ·√3/65536);
/// - Gauss–Markov: `x ← x − ε·x + b·u` on a state with `gm_shift` extra
///   fraction bits (chosen per axis so that 16 σ fill 2³⁰: the decay term
///   ε·x, 5e-6·x at T_c = 100 s and 2 kHz, is then ~100 LSB and rounds
///   without bias), `u` the same 16-bit uniform as the float engine.
#[derive(Debug, Clone, PartialEq)]
pub struct TriadEngineFixed {
    /// M − I.
    m: [[Coef; 3]; 3],
    identity_m: bool,
    noisy: bool,
    bits: u8,
    gm_shift: [u8; 3],
    /// Bias now, scaled.
    bias: [i32; 3],
    gm: [i32; 3],
    gm_decay: [Coef; 3],
    gm_drive: [Coef; 3],
    sigma: [Coef; 3],
    range: i32,
}

fn q(v: f64, bits: u32) -> i32 {
    let x = libm::round(v * crate::math::exp2i(bits as i32));
    if x.is_nan() {
        0
    } else {
        x.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }
}

impl TriadEngineFixed {
    /// An engine with saturation at ±`range` (°/s or g) on measurements
    /// scaled by 2^`bits`.
    pub fn new(range: f32, bits: u32) -> Self {
        TriadEngineFixed {
            m: [[Coef::ZERO; 3]; 3],
            identity_m: true,
            noisy: false,
            bits: bits as u8,
            gm_shift: [0; 3],
            bias: [0; 3],
            gm: [0; 3],
            gm_decay: [Coef::ZERO; 3],
            gm_drive: [Coef::ZERO; 3],
            sigma: [Coef::ZERO; 3],
            range: q(f64::from(range), bits).max(0),
        }
    }

    /// The scale exponent: measurements are in units of 2^−bits.
    pub fn bits(&self) -> u32 {
        u32::from(self.bits)
    }

    fn gm_sigma(&self, a: &AxisErrors) -> f64 {
        f64::from(GM_SIGMA_PER_BIAS_INSTABILITY)
            * f64::from(a.bias_instability)
            * crate::math::exp2i(self.bits as i32)
    }

    /// Extra fraction bits of an axis's Gauss–Markov state: 16 σ ≈ 2³⁰.
    fn gm_shift_for(&self, a: &AxisErrors) -> u8 {
        let s = self.gm_sigma(a);
        if s.is_nan() || s <= 0.0 {
            return 0;
        }
        let mut k = 0u8;
        while k < 24 && s * crate::math::exp2i((k + 1) as i32) <= f64::from(1u32 << 26) {
            k += 1;
        }
        k
    }

    /// [`TriadEngine::configure`]: every coefficient from `e` for ticks of
    /// `dt` at `temp_c` (float, at configuration time). The Gauss–Markov
    /// state is kept (rescaled if its fraction bits change).
    pub fn configure(&mut self, e: &SensorErrors, temp_c: f32, dt: f32) {
        let scale = crate::math::exp2i(self.bits as i32);
        let dt = f64::from(dt);
        let mut noisy = false;
        for i in 0..3 {
            let a = &e.axes[i];
            let shift = self.gm_shift_for(a);
            let old = self.gm_shift[i];
            self.gm[i] = if shift >= old {
                self.gm[i].saturating_mul(1 << (shift - old))
            } else {
                self.gm[i] >> (old - shift)
            };
            self.gm_shift[i] = shift;
            let sigma = f64::from(a.noise_density) / libm::sqrt(dt) * scale;
            self.sigma[i] = Coef::new(sigma * f64::from(crate::sensor::rng::IRWIN_HALL_SCALE));
            if a.bias_corr_time_s > 0.0 && a.bias_instability > 0.0 {
                let k = libm::exp(-dt / f64::from(a.bias_corr_time_s));
                let g = self.gm_sigma(a) * crate::math::exp2i(shift as i32);
                self.gm_decay[i] = Coef::new(1.0 - k);
                // u is a 16-bit signed uniform: ×√3/32768 for unit variance.
                self.gm_drive[i] =
                    Coef::new(g * libm::sqrt((1.0 - k * k).max(0.0)) * 1.732_050_8 / 32_768.0);
            } else {
                self.gm_decay[i] = Coef::ZERO;
                self.gm_drive[i] = Coef::ZERO;
                self.gm[i] = 0;
            }
            noisy |= self.sigma[i] != Coef::ZERO || self.gm_drive[i] != Coef::ZERO;
            for j in 0..3 {
                if i != j {
                    self.m[i][j] = Coef::new(delta(e.misalignment[i][j]));
                }
            }
        }
        self.noisy = noisy;
        for i in 0..3 {
            self.set_axis_temperature(e, i, temp_c);
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
    /// [`TriadEngine::randomize_gm`]: the Gauss–Markov biases drawn from
    /// their stationary distribution (one Gaussian per axis, as the float
    /// engine draws).
    pub fn randomize_gm(&mut self, e: &SensorErrors, rng: &mut Rng) {
        for i in 0..3 {
            let a = &e.axes[i];
            let shift = self.gm_shift_for(a);
            self.gm_shift[i] = shift;
            self.gm[i] = if a.bias_corr_time_s > 0.0 {
                let g = self.gm_sigma(a) * crate::math::exp2i(shift as i32);
                let k = Coef::new(g * f64::from(crate::sensor::rng::IRWIN_HALL_SCALE));
                k.apply_small(rng.gaussian_sum())
            } else {
                0
            };
        }
    }

    /// The current Gauss–Markov bias, scaled.
    pub fn gm_bias(&self) -> [i32; 3] {
        let mut b = [0; 3];
        for i in 0..3 {
            b[i] = round_shr(self.gm[i], self.gm_shift[i]);
        }
        b
    }

    /// Saturation level, scaled.
    pub fn range(&self) -> i32 {
        self.range
    }

    /// One tick: measures `truth` (scaled, |·| ≤ [`TRUTH_LIMIT`](crate::math::TRUTH_LIMIT)); returns
    /// the measurement and a mask of the axes beyond the range (bit i =
    /// axis i), which are clipped.
    #[inline]
    pub fn measure(&mut self, truth: &[i32; 3], rng: &mut Rng) -> ([i32; 3], u8) {
        let x = truth;
        let mut y = *x;
        if !self.identity_m {
            for i in 0..3 {
                let r = &self.m[i];
                y[i] = x[i] + r[0].apply(x[0]) + r[1].apply(x[1]) + r[2].apply(x[2]);
            }
        }
        if self.noisy {
            let u = rng.next_u32();
            let u2 = rng.next_u32();
            let inn = [
                i32::from(u as u16 as i16),
                i32::from((u >> 16) as u16 as i16),
                i32::from(u2 as u16 as i16),
            ];
            for i in 0..3 {
                let g = self.gm[i];
                self.gm[i] = g
                    .saturating_sub(self.gm_decay[i].apply(g))
                    .saturating_add(self.gm_drive[i].apply_small(inn[i]));
                let e = self.bias[i]
                    .saturating_add(round_shr(self.gm[i], self.gm_shift[i]))
                    .saturating_add(self.sigma[i].apply_small(rng.gaussian_sum()));
                y[i] = y[i].saturating_add(e);
            }
        } else {
            for i in 0..3 {
                y[i] = y[i].saturating_add(self.bias[i]);
            }
        }
        let mut over = 0u8;
        for (i, v) in y.iter_mut().enumerate() {
            if *v > self.range {
                *v = self.range;
                over |= 1 << i;
            } else if *v < -self.range {
                *v = -self.range;
                over |= 1 << i;
            }
        }
        (y, over)
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
