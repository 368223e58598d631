//! The numeric core of the chain in integers (`fixed-point` feature, cores
//! without an FPU): the same items, with the same signatures, as
//! `float.rs`, on `i32` samples ([`super`] doc, "Fixed point"). [`super`]
//! picks one of the two, in one place.

use super::{measure_sensors, triad, ChainConfig, Outputs, AUX_RANGE_G, EARTH_ASSUMED, RAD};
use crate::ahrs::alignment::{level_from, AlignConfig, AlignResult, Alignment};
use crate::ahrs::attitude::AttitudeFixed;
use crate::ahrs::mounting::{Mounting, MountingFixed};
use crate::dsp::cascade::CascadeFixed;
use crate::dsp::fir::{FirBankFixed, CHANNELS};
use crate::dsp::integrals::{FORCE_BITS, RATE_BITS};
use crate::dsp::variant::VariantFixed;
use crate::math::fixed::{scaled_f32, to_fixed};
use crate::math::rotation::{euler_deg_q30, level_q30, quat_rotate_inv_q30, Quat, Vec3};
use crate::math::units::{ACC_BITS, GYRO_BITS, TRUTH_LIMIT};
use crate::model::Product;
use crate::sensor::errors::{ErrorModel, TriadEngineFixed};
use crate::sensor::motion::{
    BuiltinMotionFixed, Motion, Truth as TruthF32, TruthFixed, TruthFrame,
};
use crate::sensor::rng::Rng;
use crate::time::Instant;

// The measurement is integrated as it is.
const _: () = assert!(RATE_BITS == GYRO_BITS && FORCE_BITS == ACC_BITS);

/// The FIR bank of this build.
pub(crate) type Fir = FirBankFixed;
/// The attitude filter of this build.
pub type Attitude = AttitudeFixed;
/// The truth the core measures (scaled integers).
pub(crate) type Truth = TruthFixed;
/// One measurement (gyro, acc, aux acc), sensor axes, °/s·2^GYRO_BITS and
/// g·2^ACC_BITS.
pub(crate) type Sensor = [[i32; 3]; 3];
/// A carrier-axes triad at the measurement's scale.
pub(crate) type Triad = [i32; 3];

/// The core (module doc).
#[derive(Debug, Clone)]
pub(crate) struct Core {
    pub engines: [TriadEngineFixed; 3],
    pub motion: BuiltinMotionFixed,
    pub mounting: MountingFixed,
    pub cascade: CascadeFixed,
    pub variant: VariantFixed,
    pub attitude: AttitudeFixed,
    /// Sensor axes whose temperature terms are still to be updated (one a
    /// tick, [`super`] doc).
    temp_pending: u8,
    /// The gyro bias in FIR units (°/s·2¹⁷), for the filtered gyro.
    bias_fir: [i32; 3],
}

/// [`EARTH_ASSUMED`] in °/s·2^(GYRO_BITS + 8) (the fixed-point motion's unit).
fn earth_assumed_fixed() -> [i32; 3] {
    EARTH_ASSUMED.map(|w| to_fixed(w * RAD, GYRO_BITS + 8))
}

/// FIR units (°/s·2¹⁷, g·2²⁰) of a fixed-point measurement, rounded.
#[inline(never)]
fn fir_units(s: &Sensor) -> [i32; CHANNELS] {
    let r = |x: i32, k: u32| (x >> k) + ((x >> (k - 1)) & 1);
    let (g, a) = (GYRO_BITS - 17, ACC_BITS - 20);
    [
        r(s[0][0], g),
        r(s[0][1], g),
        r(s[0][2], g),
        r(s[1][0], a),
        r(s[1][1], a),
        r(s[1][2], a),
        r(s[2][0], a),
        r(s[2][1], a),
        r(s[2][2], a),
    ]
}

/// A measurement (gyro, acc, aux acc) as a FIR input row, in FIR units.
pub(crate) fn fir_row(t: &[Vec3; 3]) -> [i32; CHANNELS] {
    fir_units(&[
        t[0].map(|v| to_fixed(v, GYRO_BITS)),
        t[1].map(|v| to_fixed(v, ACC_BITS)),
        t[2].map(|v| to_fixed(v, ACC_BITS)),
    ])
}

/// The FIR input of a measurement.
#[inline(always)]
pub(crate) fn fir_input(s: &Sensor) -> [i32; CHANNELS] {
    fir_units(s)
}

/// The FIR's newest input row (FIR units: the last good measurement) as a
/// measurement.
#[inline]
pub(crate) fn frozen(x: &[i32; CHANNELS]) -> Sensor {
    let (g, a) = (GYRO_BITS - 17, ACC_BITS - 20);
    [
        triad(x, 0).map(|v| v << g),
        triad(x, 1).map(|v| v << a),
        triad(x, 2).map(|v| v << a),
    ]
}

/// The last measurement of the FIR's newest input row, °/s and g.
pub(crate) fn sensor_of(x: &[i32; CHANNELS]) -> [Vec3; 3] {
    [
        triad(x, 0).map(|v| scaled_f32(v, 17)),
        triad(x, 1).map(|v| scaled_f32(v, 20)),
        triad(x, 2).map(|v| scaled_f32(v, 20)),
    ]
}

/// A truth sample of an external source, scaled.
#[inline(always)]
pub fn truth_of(t: &TruthF32) -> Truth {
    TruthFixed::from_truth(t)
}

/// The fixed-point truth is bounded where it is made (its integer scale
/// holds ±4095 °/s, ±128 g): unchanged.
#[inline(always)]
pub(crate) fn bounded(t: &Truth) -> Truth {
    *t
}

/// Gyro and force in the units of [`crate::dsp::integrals`] (the
/// measurement's own).
#[inline(always)]
pub(crate) fn integral_units(g: &Triad, a: &Triad) -> ([i32; 3], [i32; 3]) {
    (*g, *a)
}

/// A carrier gyro triad in °/s for the alignment.
#[inline(always)]
pub(crate) fn gyro_dps(g: &Triad) -> Vec3 {
    g.map(|v| scaled_f32(v, GYRO_BITS))
}

/// A carrier acc triad in g for the alignment.
#[inline(always)]
pub(crate) fn acc_g(a: &Triad) -> Vec3 {
    a.map(|v| scaled_f32(v, ACC_BITS))
}

/// The levelled attitude (Q30) of an alignment's mean force, in integers.
fn aligning_level(al: &Alignment) -> crate::math::rotation::QuatQ30 {
    let f = al
        .mean_force()
        .map(|v| to_fixed(v, ACC_BITS).clamp(-TRUTH_LIMIT, TRUTH_LIMIT));
    level_q30(&f)
}

/// The levelled orientation of a running alignment: (quaternion, Euler
/// angles in degrees).
pub(crate) fn aligning_orientation(al: &Alignment) -> (Quat, Vec3) {
    let q = aligning_level(al);
    (q.map(|v| scaled_f32(v, 30)), euler_deg_q30(&q))
}

impl Core {
    /// The core at power-on (or a placeholder) measuring `t0`.
    pub(crate) fn new(product: &Product, cfg: &ChainConfig, t0: &[Vec3; 3], dt: f32) -> Self {
        let x = fir_row(t0);
        let mounting = Mounting::from_angles_deg(cfg.alignment_angles_deg);
        Core {
            engines: [
                TriadEngineFixed::new(product.gyro_range_dps as f32, GYRO_BITS),
                TriadEngineFixed::new(product.accel_range_g as f32, ACC_BITS),
                TriadEngineFixed::new(AUX_RANGE_G, ACC_BITS),
            ],
            motion: BuiltinMotionFixed::new(Motion::default(), dt),
            mounting: MountingFixed::new(&mounting),
            cascade: CascadeFixed::new(&cfg.cascade, cfg.internal_rate_hz, &x),
            variant: VariantFixed::new(cfg.output_variant, dt, &x),
            attitude: AttitudeFixed::new(level_from(&t0[1]), EARTH_ASSUMED, dt),
            temp_pending: 0,
            bias_fir: [0; 3],
        }
    }

    /// The error model was (re)configured: no temperature update pending.
    #[inline(always)]
    pub(crate) fn errors_configured(&mut self) {
        self.temp_pending = 0;
    }

    /// The temperature changed: update the nine axes, one a tick.
    #[inline(always)]
    pub(crate) fn temperature_changed(&mut self, _e: &ErrorModel, _t: f32) {
        self.temp_pending = 9;
    }

    /// Per tick: one axis's temperature terms (two soft-float products).
    #[inline]
    pub(crate) fn temperature_step(&mut self, e: &ErrorModel, t: f32) {
        if self.temp_pending > 0 {
            self.temp_pending -= 1;
            let k = usize::from(self.temp_pending);
            let (i_e, i) = (
                [2, 2, 2, 1, 1, 1, 0, 0, 0][k],
                [2, 1, 0, 2, 1, 0, 2, 1, 0][k],
            );
            let errs = [&e.gyro, &e.acc, &e.aux][i_e];
            self.engines[i_e].set_axis_temperature(errs, i, t);
        }
    }

    /// The built-in motion's truth at this tick.
    #[inline(always)]
    pub(crate) fn builtin_truth(&mut self, _now: Instant, _dt: f32) -> Truth {
        self.motion.step()
    }

    /// Whether the built-in truth needs no [`bounded`] (which is the
    /// identity here: the fixed-point truth is clamped as it is made).
    #[inline(always)]
    pub(crate) fn builtin_truth_bounded(&self) -> bool {
        true
    }

    /// The sensors' measurement of `truth` (sensor axes) and the gyro (bits
    /// 0–2) and accelerometer (bits 3–5) axes beyond their range.
    #[inline(always)]
    pub(crate) fn measure(
        &mut self,
        truth: &Truth,
        frame: TruthFrame,
        has_aux: bool,
        rng: &mut Rng,
    ) -> (Sensor, u8) {
        measure_sensors(
            (truth.rate, truth.force),
            frame,
            |v| self.mounting.to_sensor(v),
            has_aux,
            [0; 3],
            |i, x, f| self.engines[i].measure(x, f, rng),
        )
    }

    /// Gyro and acc of a measurement in carrier axes.
    #[inline(always)]
    pub(crate) fn carrier(&self, s: &Sensor) -> (Triad, Triad) {
        (
            self.mounting.to_carrier(&s[0]),
            self.mounting.to_carrier(&s[1]),
        )
    }

    /// One attitude step on carrier gyro `g` and acc `a` (the bias is in
    /// the filter, [`Core::set_bias`]).
    #[inline(always)]
    pub(crate) fn run_attitude(&mut self, g: &Triad, a: &Triad, _bias: &Vec3) {
        self.attitude.update(g, a);
    }

    /// Ends the alignment `al`: its result, the attitude set from it
    /// (levelling and the Earth rate in integers, CORDIC: no soft-float
    /// trigonometry in this tick).
    pub(crate) fn finish_alignment(&mut self, al: &Alignment, cfg: &AlignConfig) -> AlignResult {
        let q = aligning_level(al);
        let w = quat_rotate_inv_q30(&q, &earth_assumed_fixed());
        let r = al.finish_at(
            q.map(|v| scaled_f32(v, 30)),
            w.map(|v| scaled_f32(v, GYRO_BITS + 8)),
            cfg,
        );
        self.attitude.set_q30(q);
        r
    }

    /// Levels the attitude at once from the last filtered accelerometer.
    pub(crate) fn level_now(&mut self) {
        let last = self.variant.last();
        let f = self.mounting.to_carrier(&triad(&last, 1));
        self.attitude.set_q30(level_q30(&f));
    }

    /// A new gyro bias estimate (°/s, carrier axes).
    pub(crate) fn set_bias(&mut self, b: &Vec3, dt: f32) {
        self.attitude.set_bias(b, dt);
        self.bias_fir = b.map(|v| to_fixed(v, 17));
    }

    /// A new configuration: cascade in the steady state of the last output,
    /// mounting, an empty accumulator.
    pub(crate) fn reconfigure(&mut self, cfg: &ChainConfig, dt: f32) {
        let last = self.variant.last();
        self.cascade
            .configure(&cfg.cascade, cfg.internal_rate_hz, &last);
        let mounting = Mounting::from_angles_deg(cfg.alignment_angles_deg);
        self.mounting = MountingFixed::new(&mounting);
        self.variant = VariantFixed::new(cfg.output_variant, dt, &last);
    }

    /// Chooses a built-in motion.
    pub(crate) fn set_motion(&mut self, m: Motion, dt: f32) {
        self.motion = BuiltinMotionFixed::new(m, dt);
    }

    /// The accumulated interval, carrier axes, in °/s and g, and its ticks;
    /// restarts the interval.
    #[inline]
    pub(crate) fn take(&mut self, _bias: &Vec3, has_aux: bool) -> (Outputs, u32) {
        let v = self.variant.take();
        let m = &self.mounting;
        let f = |x: &[i32; CHANNELS], i: usize, k: u32| {
            m.to_carrier(&triad(x, i)).map(|v| scaled_f32(v, k))
        };
        let b = self.bias_fir;
        let gf = m.to_carrier(&triad(&v.filtered, 0));
        let (aux, aux_f) = if has_aux {
            (f(&v.main, 2, 20), f(&v.filtered, 2, 20))
        } else {
            ([0.0; 3], [0.0; 3])
        };
        (
            Outputs {
                gyro: f(&v.main, 0, 17),
                acc: f(&v.main, 1, 20),
                gyro_f: [
                    scaled_f32(gf[0].saturating_sub(b[0]), 17),
                    scaled_f32(gf[1].saturating_sub(b[1]), 17),
                    scaled_f32(gf[2].saturating_sub(b[2]), 17),
                ],
                acc_f: f(&v.filtered, 1, 20),
                aux,
                aux_f,
            },
            v.ticks,
        )
    }
}
