//! The numeric core of the chain in `f32` (FPU cores): sensor engines, the
//! built-in motion, mounting, cascade, accumulator and attitude. The same
//! items, with the same signatures, as `fixed.rs` (the `fixed-point` build);
//! [`super`] picks one of the two, in one place.

use super::{measure_sensors, triad, ChainConfig, Outputs, AUX_RANGE_G, EARTH_ASSUMED, RAD};
use crate::ahrs::alignment::{level_from, AlignConfig, AlignResult, Alignment};
use crate::ahrs::attitude::Attitude as AttitudeFilter;
use crate::ahrs::mounting::Mounting;
use crate::dsp::cascade::Cascade;
use crate::dsp::fir::{FirBank, CHANNELS};
use crate::dsp::integrals;
use crate::dsp::variant::VariantAccumulator;
use crate::math::rotation::{canonical, euler_from_quat, Quat, Vec3};
use crate::model::Product;
use crate::sensor::errors::{ErrorModel, TriadEngine};
use crate::sensor::motion::{BuiltinMotion, Motion, MotionSource, Truth as TruthF32, TruthFrame};
use crate::sensor::rng::Rng;
use crate::time::Instant;

/// The FIR bank of this build.
pub(crate) type Fir = FirBank;
/// The attitude filter of this build.
pub type Attitude = AttitudeFilter;
/// The truth the core measures.
pub(crate) type Truth = TruthF32;
/// One measurement (gyro, acc, aux acc), sensor axes, as a FIR row.
pub(crate) type Sensor = [f32; CHANNELS];
/// A carrier-axes triad (°/s or g).
pub(crate) type Triad = Vec3;

/// The core (module doc).
#[derive(Debug, Clone)]
pub(crate) struct Core {
    pub engines: [TriadEngine; 3],
    pub motion: BuiltinMotion,
    pub mounting: Mounting,
    pub cascade: Cascade,
    pub variant: VariantAccumulator,
    pub attitude: Attitude,
}

#[inline(always)]
fn pack(s: &[Vec3; 3]) -> Sensor {
    [
        s[0][0], s[0][1], s[0][2], s[1][0], s[1][1], s[1][2], s[2][0], s[2][1], s[2][2],
    ]
}

/// A measurement (gyro, acc, aux acc) as a FIR input row.
#[inline]
pub(crate) fn fir_row(t: &[Vec3; 3]) -> Sensor {
    pack(t)
}

/// The FIR input of a measurement.
#[inline(always)]
pub(crate) fn fir_input(s: &Sensor) -> Sensor {
    *s
}

/// The FIR's newest input row (the last measurement) as a measurement.
#[inline(always)]
pub(crate) fn frozen(last_input: &Sensor) -> Sensor {
    *last_input
}

/// The last measurement of the FIR's newest input row, °/s and g.
#[inline]
pub(crate) fn sensor_of(x: &Sensor) -> [Vec3; 3] {
    [triad(x, 0), triad(x, 1), triad(x, 2)]
}

/// A truth sample of an external source.
#[inline(always)]
pub fn truth_of(t: &TruthF32) -> Truth {
    *t
}

/// The truth clamped to what the sensor model can take (±8192 °/s,
/// ±128 g: [`TruthF32::bounded`]), so a value beyond `f32` saturates the
/// sensor instead of turning into NaN.
#[inline(always)]
pub(crate) fn bounded(t: &Truth) -> Truth {
    t.bounded()
}

/// Gyro and force in the units of [`crate::dsp::integrals`].
#[inline(always)]
pub(crate) fn integral_units(g: &Triad, a: &Triad) -> ([i32; 3], [i32; 3]) {
    integrals::quantize(g, a)
}

/// A carrier triad as °/s (gyro) or g (acc) for the alignment.
#[inline(always)]
pub(crate) fn gyro_dps(g: &Triad) -> Vec3 {
    *g
}

/// See [`gyro_dps`].
#[inline(always)]
pub(crate) fn acc_g(a: &Triad) -> Vec3 {
    *a
}

/// The levelled orientation of a running alignment: (quaternion, Euler
/// angles in degrees).
pub(crate) fn aligning_orientation(al: &Alignment) -> (Quat, Vec3) {
    let q = al.level();
    let e = euler_from_quat(&q);
    (canonical(&q), [e[0] * RAD, e[1] * RAD, e[2] * RAD])
}

impl Core {
    /// The core at power-on (or a placeholder) measuring `t0`.
    pub(crate) fn new(product: &Product, cfg: &ChainConfig, t0: &[Vec3; 3], dt: f32) -> Self {
        let x = fir_row(t0);
        #[allow(unused_mut)]
        let mut core = Core {
            engines: [
                TriadEngine::new(product.gyro_range_dps as f32),
                TriadEngine::new(product.accel_range_g as f32),
                TriadEngine::new(AUX_RANGE_G),
            ],
            motion: BuiltinMotion::new(Motion::default(), dt),
            mounting: Mounting::from_angles_deg(cfg.alignment_angles_deg),
            cascade: Cascade::new(&cfg.cascade, cfg.internal_rate_hz, &x),
            variant: VariantAccumulator::new(cfg.output_variant, dt, &x),
            attitude: Attitude::new(level_from(&t0[1]), EARTH_ASSUMED, dt),
        };
        // A unit without the aux accelerometer does not filter its (zero)
        // channels; no output reads them (`Core::take`).
        core.cascade.set_aux_live(product.model.aux_accel);
        core
    }

    /// The error model was (re)configured.
    #[inline(always)]
    pub(crate) fn errors_configured(&mut self) {}

    /// The temperature changed to `t`: every axis at once.
    #[inline]
    pub(crate) fn temperature_changed(&mut self, e: &ErrorModel, t: f32) {
        let c = &mut self.engines;
        c[0].set_temperature(&e.gyro, t);
        c[1].set_temperature(&e.acc, t);
        c[2].set_temperature(&e.aux, t);
    }

    /// Per tick: nothing left to update.
    #[inline(always)]
    pub(crate) fn temperature_step(&mut self, _e: &ErrorModel, _t: f32) {}

    /// The built-in motion's truth at this tick.
    #[inline(always)]
    pub(crate) fn builtin_truth(&mut self, now: Instant, dt: f32) -> Truth {
        self.motion.next(now, dt)
    }

    /// The built-in motion's truth needs no [`bounded`] (static, within
    /// the bounds).
    #[inline(always)]
    pub(crate) fn builtin_truth_bounded(&self) -> bool {
        self.motion.static_and_bounded()
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
        let (m, over) = measure_sensors(
            (truth.rate_dps, truth.specific_force_g),
            frame,
            |v| self.mounting.to_sensor(v),
            has_aux,
            [0.0; 3],
            |i, x, f| self.engines[i].measure(x, f, rng),
        );
        (pack(&m), over)
    }

    /// Gyro and acc of a measurement in carrier axes.
    #[inline(always)]
    pub(crate) fn carrier(&self, s: &Sensor) -> (Triad, Triad) {
        (
            self.mounting.to_carrier(&triad(s, 0)),
            self.mounting.to_carrier(&triad(s, 1)),
        )
    }

    /// One attitude step on carrier gyro `g` and acc `a`, `bias` removed.
    #[inline(always)]
    pub(crate) fn run_attitude(&mut self, g: &Triad, a: &Triad, bias: &Vec3) {
        let g = [g[0] - bias[0], g[1] - bias[1], g[2] - bias[2]];
        self.attitude.update(&g, a);
    }

    /// Ends the alignment `al`: its result, the attitude set from it.
    pub(crate) fn finish_alignment(&mut self, al: &Alignment, cfg: &AlignConfig) -> AlignResult {
        let r = al.finish(&EARTH_ASSUMED, cfg);
        self.attitude.set(r.attitude);
        r
    }

    /// Levels the attitude at once from the last filtered accelerometer.
    pub(crate) fn level_now(&mut self) {
        let last = self.variant.last();
        let f = self.mounting.to_carrier(&triad(&last, 1));
        self.attitude.set(level_from(&f));
    }

    /// A new gyro bias estimate (°/s, carrier axes).
    #[inline(always)]
    pub(crate) fn set_bias(&mut self, _b: &Vec3, _dt: f32) {}

    /// A new configuration: mounting and an empty accumulator (the cascade
    /// is reconfigured by the caller).
    pub(crate) fn reconfigure(&mut self, cfg: &ChainConfig, dt: f32) {
        let last = self.variant.last();
        self.cascade
            .configure(&cfg.cascade, cfg.internal_rate_hz, &last);
        self.mounting = Mounting::from_angles_deg(cfg.alignment_angles_deg);
        self.variant = VariantAccumulator::new(cfg.output_variant, dt, &last);
    }

    /// Chooses a built-in motion.
    pub(crate) fn set_motion(&mut self, m: Motion, dt: f32) {
        self.motion = BuiltinMotion::new(m, dt);
    }

    /// The accumulated interval, carrier axes, in °/s and g, and its ticks;
    /// restarts the interval.
    #[inline]
    pub(crate) fn take(&mut self, bias: &Vec3, has_aux: bool) -> (Outputs, u32) {
        let v = self.variant.take();
        let m = &self.mounting;
        let b = bias;
        let gf = m.to_carrier(&triad(&v.filtered, 0));
        let (aux, aux_f) = if has_aux {
            (
                m.to_carrier(&triad(&v.main, 2)),
                m.to_carrier(&triad(&v.filtered, 2)),
            )
        } else {
            ([0.0; 3], [0.0; 3])
        };
        (
            Outputs {
                gyro: m.to_carrier(&triad(&v.main, 0)),
                acc: m.to_carrier(&triad(&v.main, 1)),
                gyro_f: [gf[0] - b[0], gf[1] - b[1], gf[2] - b[2]],
                acc_f: m.to_carrier(&triad(&v.filtered, 1)),
                aux,
                aux_f,
            },
            v.ticks,
        )
    }
}
