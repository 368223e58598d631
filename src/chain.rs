//! The signal chain: everything between the physics and a [`Sample`] — one
//! call per internal-rate tick (ICD Table 4.3: 2 kHz, 4 kHz on the K201).
//!
//! ```text
//! truth(t) ──► sensor errors + saturation ──► FIR LPF (5.6) ──► cascade (5.8) ──► variant accumulator (5.3.6)
//!   (sensor axes)        (sensor axes)     │                                         │
//!                                          └─► mounting (App. B) ──► alignment (5.7) / attitude (App. C)
//!                                                                                    ▼
//!                                            output(): mounting rotation, bias, orientation ──► Sample
//! ```
//!
//! The FIR, the cascade and the accumulator are linear and treat the three
//! axes of a triad alike, so they run in *sensor* axes and the Alignment_Angles
//! rotation is applied once per output (it commutes with them: the Δθ/Δv
//! corrections are cross products, which commute with rotations). The AHRS
//! needs carrier axes every tick and gets them from the pre-FIR data.
//!
//! # Integration contract (for [`crate::device::Device`])
//!
//! - Power-on: [`SignalChain::new`]`(product, seed)`.
//! - **Every internal tick, in every mode**: [`SignalChain::tick`]`(now)`
//!   (the sensors, the FIR history, temperature and attitude keep running while
//!   the device is idle, like a real unit).
//! - At a data command / stream start (5.3.1): [`SignalChain::configure`] with
//!   [`ChainConfig::from_block`] of the live parameters. It keeps the FIR's
//!   input history (a real FIR runs on the sensor stream continuously; only
//!   the coefficients change), starts the cascade in the steady state of its
//!   current input (no transient) and empties the variant accumulator.
//! - A format with orientation: Initial_Alignment_Time > 0 →
//!   [`SignalChain::begin_alignment`], then after that many seconds of ticks
//!   [`SignalChain::end_alignment`]; = 0 → [`SignalChain::skip_alignment`].
//!   Formats without orientation call neither (the AHRS keeps its state).
//! - At an output tick: [`SignalChain::output`] (covers the ticks since the
//!   previous output, then restarts the interval), then
//!   [`SignalChain::status`] for USW (Table 5.26), USW-extended (Table 5.27);
//!   GetBIT (Table 5.18) takes `status().bit`.
//!
//! # Decisions (README "Protocol notes")
//!
//! - FIR: Blackman-windowed sinc, −3 dB exactly at the Table 5.29 bandwidth,
//!   order 192…12 at 2 kHz (doubled on the K201 at 4 kHz), coefficients in
//!   `const`, delay exactly N/2 samples; orders 192 and 96 as a symmetric
//!   two-stage product P(z)·G(z^L) of the same order ([`crate::dsp::fir`]).
//! - Cascade: bilinear transform pre-warped at each section's ω (Filter3 at
//!   1/τ) ([`crate::dsp::cascade`]); it feeds only UDD 0x2D/0x91/0x92; the
//!   gyro bias is subtracted after it (no transient when the bias changes).
//! - Incremental output = Δθ/T and Δv/T with coning/sculling corrections,
//!   °/s and g ([`crate::dsp::variant`]); Average_Output_Data = 1 forces the
//!   average.
//! - Physics: g = 9.8106 m/s², Earth rate 15.041 °/h, default site 45° N,
//!   heading 0, level ([`crate::sensor::motion`]). The built-in motion moves
//!   the unit itself ([`TruthFrame::Sensor`]); Alignment_Angles rotate what it
//!   reports.
//! - Errors: per-model defaults in [`crate::sensor::errors::ErrorSpec`];
//!   temperature: warm-up from 25 °C by +8 °C, τ 600 s
//!   ([`crate::sensor::temperature`]).
//! - Alignment: averaging with the STD of 10 ms means vs the threshold, or a
//!   Kalman filter (ZUPT); heading relative (0 after alignment)
//!   ([`crate::ahrs::alignment`]).
//! - USW bits 10–12 report a gyro axis (sensor axes) beyond the measurement
//!   range at any tick of the interval the output covers.
//! - Float path on FPU cores; the `fixed-point` feature runs the FIR (Q15
//!   taps, `i32` samples) and the cascade (Q24, 64-bit products) in integers
//!   for cores without an FPU; everything else stays `f32`.
//!
//! # Cost
//!
//! Instructions executed per tick, measured under QEMU (`-singlestep`
//! trace, release + LTO), worst configuration: K120 (aux accelerometer, all
//! 9 channels), all three cascade filters, incremental output, non-zero
//! Alignment_Angles, coning motion, attitude running:
//!
//! | LPF | Cortex-M4F (float) | ARMv6-M (`fixed-point`, soft-float `f32`) |
//! |---|---|---|
//! | 16 Hz (192, two-stage) | 3 917 | 86 057 |
//! | 33 Hz (96, two-stage) | 3 828 | 85 927 |
//! | 66 Hz (48) | 4 001 | 85 935 |
//! | 131 Hz (24) | 3 449 | 84 280 |
//! | 262 Hz (12) | 3 173 | 83 663 |
//! | off | 2 844 | 83 150 |
//! | K110 factory (262 Hz, no cascade, instant) | 1 926 | 54 256 |
//!
//! `output()` adds 764 (M4F) / 3 035 (v6-M). On ARMv6-M ~84 % of the
//! instructions are inside the compiler's soft-float routines (≈ 780 `f32`
//! operations a tick: error model, AHRS, truth, accumulator), so the cycle
//! count on an RP2040 depends on the float library the firmware links (the
//! RP2040 boot-ROM routines are several times faster than the generic
//! ones). On the host (criterion, `benches/tick.rs`) a worst-case tick takes
//! ≈ 0.31 µs and a factory tick ≈ 0.15 µs.

use crate::ahrs::alignment::{level_from, AlignConfig, Alignment};
use crate::ahrs::attitude::Attitude;
use crate::ahrs::mounting::Mounting;
use crate::ahrs::rotation::{Quat, Vec3};
#[cfg(not(feature = "fixed-point"))]
use crate::dsp::cascade::Cascade;
use crate::dsp::cascade::{CascadeConfig, SecondOrder};
use crate::dsp::fir::{self, FirDesign, CHANNELS};
use crate::dsp::variant::{OutputVariant, VariantAccumulator};
use crate::kernel::params::{self, Block};
use crate::model::{Capability, Product};
use crate::sensor::errors::{ErrorModel, TriadEngine};
use crate::sensor::motion::{
    earth_enu, BuiltinMotion, Motion, MotionSource, Truth, TruthFrame, DEFAULT_LATITUDE_DEG,
};
use crate::sensor::rng::Rng;
use crate::sensor::temperature::{TemperatureModel, OPERATING_RANGE_C, UPDATE_TICKS};
use crate::sensor::Sample;
use crate::time::Instant;

/// Saturation of the aux (high-g) accelerometer, g (product code `A90`).
pub const AUX_RANGE_G: f32 = 90.0;
/// Supply voltage reported unless a fault overrides it, V.
pub const NOMINAL_SUPPLY_V: f32 = 12.0;

/// What the chain takes from the parameter block (Table 5.24).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainConfig {
    /// Internal rate of the model, Hz (Table 4.3).
    pub internal_rate_hz: u32,
    /// LPF_Bandwidth code (0..4, 0xFF off; 5.6).
    pub lpf_code: u8,
    /// Filter mask and Filt1/Filt2/Tau (5.8).
    pub cascade: CascadeConfig,
    /// Output_Variant, with Average_Output_Data = 1 forcing the average (5.3.6).
    pub output_variant: OutputVariant,
    /// Alignment_Angles heading, pitch, roll, degrees (Appendix B).
    pub alignment_angles_deg: [f32; 3],
    /// ZUPT, Align_Gyro_STD_Threshold and the AHRS tuning rows (5.7).
    pub align: AlignConfig,
}

impl ChainConfig {
    /// The factory configuration of `product`.
    pub fn defaults(product: &Product) -> Self {
        ChainConfig::from_block(&params::factory_block(product), product)
    }

    /// Reads the parameters the chain uses from `block` (the live RAM copy).
    pub fn from_block(block: &Block, product: &Product) -> Self {
        let f = |id: u16, default: f32| {
            params::find(id)
                .map(|p| p.read_f32(block, 0))
                .filter(|v| v.is_finite())
                .unwrap_or(default)
        };
        let so = |base: u16, omega: f32| SecondOrder {
            zeta_num: f(base, 0.1),
            zeta_den: f(base + 4, 0.7),
            omega: f(base + 8, omega),
        };
        let angle = |i: usize| {
            let v = params::ALIGNMENT_ANGLES.read_f32(block, i);
            if v.is_finite() {
                v
            } else {
                0.0
            }
        };
        ChainConfig {
            internal_rate_hz: product.model.internal_rate_hz,
            lpf_code: params::LPF_BANDWIDTH.read_int(block) as u8,
            cascade: CascadeConfig {
                mask: params::FILTER.read_int(block) as u8 & 0x07,
                filt1: so(0x0452, 314.159_27),
                filt2: so(0x045E, 628.318_5),
                tau: f(params::TAU.id, 0.01),
            },
            output_variant: OutputVariant::from_params(
                params::OUTPUT_VARIANT.read_int(block) as u8,
                params::AVERAGE_OUTPUT_DATA.read_int(block) as u8,
            ),
            alignment_angles_deg: [angle(0), angle(1), angle(2)],
            align: AlignConfig {
                zupt: params::ZUPT.read_int(block) == 1,
                std_threshold_dps: f(params::ALIGN_GYRO_STD_THRESHOLD.id, 0.05),
                gyro_noise_rms: f(0x03EE, 0.1),
                gyro_bias_rms: f(0x03FA, 0.1),
                gyro_bias_drift: f(0x03F6, 0.001),
            },
        }
    }

    /// The FIR design this configuration selects (`None` = off).
    pub fn fir_design(&self) -> Option<&'static FirDesign> {
        fir::design(self.lpf_code, self.internal_rate_hz)
    }
}

/// Injectable faults (they drive the status words and GetBIT).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Faults {
    /// Internal sensors stop answering: the data freeze at the last good
    /// values; USW bit 1 (Table 5.26).
    pub sensor_comm: bool,
    /// Internal sensor configuration failed: USW bit 2.
    pub sensor_config: bool,
    /// Gyroscope BIT fails: GetBIT gyro result 1 (Table 5.18 bits 2–4).
    pub gyro_bit: bool,
    /// Accelerometer BIT fails: GetBIT accel result 1 (bits 0–1; 0 and 2 are
    /// "okay").
    pub accel_bit: bool,
    /// Flash check fails: GetBIT bits 12–13 = 1.
    pub flash_check: bool,
    /// Forces the sensor temperature, °C; outside −40…85 °C sets USW bit 14.
    pub temperature_c: Option<f32>,
    /// Forces the reported supply voltage, V.
    pub supply_voltage: Option<f32>,
}

/// Status words of the chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Status {
    /// Unit Status Word (Table 5.26): bit 1 sensor communication failure,
    /// bit 2 sensor configuration failure, bits 10/11/12 X/Y/Z angular rate
    /// out of range, bit 14 temperature out of the operating range.
    pub usw: u16,
    /// Extended USW (Table 5.27): bit 0 initial alignment complete (clear only
    /// while aligning), bit 1 gyro bias estimation failed.
    pub usw_ext: u16,
    /// GetBIT payload (Table 5.18), 4 bytes.
    pub bit: [u8; 4],
}

/// USW bits (Table 5.26).
pub mod usw {
    /// Communication failure of internal sensors.
    pub const SENSOR_COMM: u16 = 1 << 1;
    /// Configuration failure of internal sensors.
    pub const SENSOR_CONFIG: u16 = 1 << 2;
    /// X angular rate out of range (Y is `<< 1`, Z `<< 2`).
    pub const RATE_X_RANGE: u16 = 1 << 10;
    /// Temperature out of the operating range.
    pub const TEMPERATURE: u16 = 1 << 14;
    /// Extended: initial alignment complete (Table 5.27).
    pub const EXT_ALIGNED: u16 = 1 << 0;
    /// Extended: gyro bias estimation failed.
    pub const EXT_BIAS_FAILED: u16 = 1 << 1;
}

/// Per-channel scale of the fixed-point FIR: gyro 2¹⁷ per °/s (LSB 7.6e-6 °/s,
/// finer than the 1e-5 of the HR formats), accelerometers 2²⁰ per g (9.5e-7 g).
pub const FIXED_SCALE: [f32; CHANNELS] = [
    131_072.0,
    131_072.0,
    131_072.0,
    1_048_576.0,
    1_048_576.0,
    1_048_576.0,
    1_048_576.0,
    1_048_576.0,
    1_048_576.0,
];

/// 1 / [`FIXED_SCALE`] (exact: powers of two).
pub const FIXED_UNIT: [f32; CHANNELS] = [
    1.0 / 131_072.0,
    1.0 / 131_072.0,
    1.0 / 131_072.0,
    1.0 / 1_048_576.0,
    1.0 / 1_048_576.0,
    1.0 / 1_048_576.0,
    1.0 / 1_048_576.0,
    1.0 / 1_048_576.0,
    1.0 / 1_048_576.0,
];

/// The FIR and the cascade, float (FPU cores).
#[cfg(not(feature = "fixed-point"))]
#[derive(Debug, Clone)]
struct Filters {
    fir: fir::FirBank,
    cascade: Cascade,
    last: [f32; CHANNELS],
}

#[cfg(not(feature = "fixed-point"))]
impl Filters {
    fn new(cfg: &ChainConfig, x: &[f32; CHANNELS]) -> Self {
        Filters {
            fir: fir::FirBank::new(cfg.fir_design(), x),
            cascade: Cascade::new(&cfg.cascade, cfg.internal_rate_hz, x),
            last: *x,
        }
    }
    fn configure(&mut self, cfg: &ChainConfig) {
        self.fir.set_design(cfg.fir_design());
        self.cascade
            .configure(&cfg.cascade, cfg.internal_rate_hz, &self.last);
    }
    /// (FIR output, cascade output), sensor axes.
    #[inline]
    fn push(&mut self, x: &[f32; CHANNELS]) -> ([f32; CHANNELS], [f32; CHANNELS]) {
        let y = self.fir.push(x);
        self.last = y;
        let mut z = y;
        self.cascade.process(&mut z);
        (y, z)
    }
    fn last(&self) -> [f32; CHANNELS] {
        self.last
    }
}

/// The FIR and the cascade in fixed point (`fixed-point` feature).
#[cfg(feature = "fixed-point")]
#[derive(Debug, Clone)]
struct Filters {
    fir: fir::FirBankFixed,
    cascade: crate::dsp::cascade::CascadeFixed,
    last: [i32; CHANNELS],
}

#[cfg(feature = "fixed-point")]
impl Filters {
    /// To the fixed-point scale, rounded half away from zero (sign by bit
    /// copy, no float compare), clamped to ±2²⁹.
    #[inline]
    fn to_fixed(x: &[f32; CHANNELS]) -> [i32; CHANNELS] {
        let mut o = [0i32; CHANNELS];
        for c in 0..CHANNELS {
            let v = x[c] * FIXED_SCALE[c];
            o[c] = ((v + 0.5f32.copysign(v)) as i32).clamp(-(1 << 29), 1 << 29);
        }
        o
    }
    #[inline]
    fn to_float(y: &[i32; CHANNELS]) -> [f32; CHANNELS] {
        let mut o = [0.0f32; CHANNELS];
        for c in 0..CHANNELS {
            o[c] = y[c] as f32 * FIXED_UNIT[c];
        }
        o
    }
    fn new(cfg: &ChainConfig, x: &[f32; CHANNELS]) -> Self {
        let q = Self::to_fixed(x);
        Filters {
            fir: fir::FirBankFixed::new(cfg.fir_design(), &q),
            cascade: crate::dsp::cascade::CascadeFixed::new(&cfg.cascade, cfg.internal_rate_hz, &q),
            last: q,
        }
    }
    fn configure(&mut self, cfg: &ChainConfig) {
        self.fir.set_design(cfg.fir_design());
        self.cascade
            .configure(&cfg.cascade, cfg.internal_rate_hz, &self.last);
    }
    #[inline]
    fn push(&mut self, x: &[f32; CHANNELS]) -> ([f32; CHANNELS], [f32; CHANNELS]) {
        let y = self.fir.push(&Self::to_fixed(x));
        self.last = y;
        let mut z = y;
        self.cascade.process(&mut z);
        (Self::to_float(&y), Self::to_float(&z))
    }
    fn last(&self) -> [f32; CHANNELS] {
        Self::to_float(&self.last)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Ahrs {
    Aligning(Alignment),
    Running,
}

/// The signal chain of one unit (module doc). Fixed size, no heap.
#[derive(Debug, Clone)]
pub struct SignalChain {
    product: Product,
    rate_hz: u32,
    dt: f32,
    has_aux: bool,
    rng: Rng,
    errors: ErrorModel,
    errors_dirty: bool,
    engines: [TriadEngine; 3],
    temp_model: TemperatureModel,
    temp_ticks: u32,
    temperature: f32,
    faults: Faults,
    motion: BuiltinMotion,
    truth_frame: TruthFrame,
    cfg: ChainConfig,
    mounting: Mounting,
    filters: Filters,
    variant: VariantAccumulator,
    /// Last sensor-axis measurement (gyro, acc, aux): frozen on a comm fault.
    sensor: [Vec3; 3],
    ahrs: Ahrs,
    attitude: Attitude,
    bias: Vec3,
    bias_failed: bool,
    earth_assumed: Vec3,
    sat_live: u8,
    sat_reported: u8,
    ticks: u64,
    interval: f32,
}

fn pack(s: &[Vec3; 3]) -> [f32; CHANNELS] {
    [
        s[0][0], s[0][1], s[0][2], s[1][0], s[1][1], s[1][2], s[2][0], s[2][1], s[2][2],
    ]
}

fn triad(x: &[f32; CHANNELS], i: usize) -> Vec3 {
    [x[3 * i], x[3 * i + 1], x[3 * i + 2]]
}

impl SignalChain {
    /// Power-on of `product` with every random process seeded by `seed`.
    ///
    /// The unit is static, level, z up, heading 0 at
    /// [`DEFAULT_LATITUDE_DEG`] (the gyros read the Earth rate plus their
    /// errors, AccZ +1 g); errors are one unit drawn from the model's
    /// [`crate::sensor::ErrorSpec`]; the parameters are the factory
    /// defaults until [`SignalChain::configure`]. The AHRS starts levelled,
    /// unaligned (bias 0), USW-extended bit 0 set.
    pub fn new(product: Product, seed: u64) -> Self {
        let rate_hz = product.model.internal_rate_hz;
        let dt = 1.0 / rate_hz as f32;
        let has_aux = product.model.has(Capability::AuxAccel);
        let mut rng = Rng::new(seed);
        let errors = ErrorModel::for_product(&product, &mut rng);
        let mut engines = [
            TriadEngine::new(product.gyro.full_scale() as f32),
            TriadEngine::new(product.accel.full_scale() as f32),
            TriadEngine::new(AUX_RANGE_G),
        ];
        let temp_model = TemperatureModel::default();
        let temperature = temp_model.temperature_c();
        let sensors = [&errors.gyro, &errors.acc, &errors.aux];
        for (e, s) in engines.iter_mut().zip(sensors) {
            e.randomize_gm(s, &mut rng);
        }
        let cfg = ChainConfig::defaults(&product);
        let motion = BuiltinMotion::new(Motion::default(), dt);
        let t0 = Truth::at_rest();
        let sensor = [
            t0.rate_dps,
            t0.specific_force_g,
            if has_aux {
                t0.specific_force_g
            } else {
                [0.0; 3]
            },
        ];
        let x = pack(&sensor);
        let earth_assumed = earth_enu(DEFAULT_LATITUDE_DEG);
        let mut chain = SignalChain {
            product,
            rate_hz,
            dt,
            has_aux,
            rng,
            errors,
            errors_dirty: true,
            engines,
            temp_model,
            temp_ticks: 0,
            temperature,
            faults: Faults::default(),
            motion,
            truth_frame: TruthFrame::Sensor,
            cfg,
            mounting: Mounting::from_angles_deg(cfg.alignment_angles_deg),
            filters: Filters::new(&cfg, &x),
            variant: VariantAccumulator::new(cfg.output_variant, dt),
            sensor,
            ahrs: Ahrs::Running,
            attitude: Attitude::new(level_from(&t0.specific_force_g), earth_assumed, dt),
            bias: [0.0; 3],
            bias_failed: false,
            earth_assumed,
            sat_live: 0,
            sat_reported: 0,
            ticks: 0,
            interval: dt,
        };
        chain.refresh_errors();
        chain
    }

    /// The emulated product.
    pub fn product(&self) -> &Product {
        &self.product
    }

    /// The configuration in force.
    pub fn config(&self) -> &ChainConfig {
        &self.cfg
    }

    /// Applies a configuration (5.3.1: at every data command). See the module
    /// doc: FIR history kept, cascade in steady state, accumulator emptied.
    pub fn configure(&mut self, cfg: &ChainConfig) {
        self.cfg = *cfg;
        self.mounting = Mounting::from_angles_deg(cfg.alignment_angles_deg);
        // The cascade starts in the steady state of the last FIR output
        // (exact for a steady signal).
        self.filters.configure(cfg);
        self.variant = VariantAccumulator::new(cfg.output_variant, self.dt);
    }

    /// Chooses a built-in motion, from its initial state (level at its
    /// heading, phase 0), from the next tick on.
    pub fn set_motion(&mut self, m: Motion) {
        self.motion = BuiltinMotion::new(m, self.dt);
    }

    /// Which axes the motion describes (default: the unit's own).
    pub fn set_truth_frame(&mut self, frame: TruthFrame) {
        self.truth_frame = frame;
    }

    /// The true attitude of the built-in motion at the last tick (housing or
    /// carrier per [`TruthFrame`], Appendix C convention).
    pub fn truth_attitude(&self) -> Option<Quat> {
        self.motion.attitude()
    }

    /// The error model, for reading or changing (changes apply at the next
    /// tick).
    pub fn errors_mut(&mut self) -> &mut ErrorModel {
        self.errors_dirty = true;
        &mut self.errors
    }

    /// The error model in force.
    pub fn errors(&self) -> &ErrorModel {
        &self.errors
    }

    /// The temperature model, for reading or changing.
    pub fn temperature_mut(&mut self) -> &mut TemperatureModel {
        self.errors_dirty = true;
        &mut self.temp_model
    }

    /// Injectable faults.
    pub fn faults_mut(&mut self) -> &mut Faults {
        &mut self.faults
    }

    /// The sensor temperature now, °C.
    pub fn temperature(&self) -> f32 {
        self.temperature
    }

    /// The last measurement in sensor axes, before any filter: gyro (°/s),
    /// acc (g), aux acc (g).
    pub fn last_sensor(&self) -> [Vec3; 3] {
        self.sensor
    }

    /// The estimated gyro bias, carrier axes, °/s.
    pub fn gyro_bias(&self) -> Vec3 {
        self.bias
    }

    /// Whether an initial alignment is running.
    pub fn is_aligning(&self) -> bool {
        matches!(self.ahrs, Ahrs::Aligning(_))
    }

    /// The attitude filter (tests switch its tilt correction).
    pub fn attitude_mut(&mut self) -> &mut Attitude {
        &mut self.attitude
    }

    /// Seconds the last [`SignalChain::output`] covered (its ticks × the
    /// tick period): Δθ = gyro × this in the incremental variant.
    pub fn output_interval(&self) -> f32 {
        self.interval
    }

    /// Ticks run since power-on.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    fn refresh_errors(&mut self) {
        let dt = self.dt;
        let t = self.temperature;
        self.engines[0].configure(&self.errors.gyro, t, dt);
        self.engines[1].configure(&self.errors.acc, t, dt);
        self.engines[2].configure(&self.errors.aux, t, dt);
        self.temp_model.prepare(UPDATE_TICKS as f32 * dt);
        self.errors_dirty = false;
    }

    /// One internal-rate tick with the built-in motion: truth → errors and
    /// saturation → FIR → cascade → variant accumulator, and alignment or
    /// attitude. `now` is the tick's time (handed to the motion source).
    pub fn tick(&mut self, now: Instant) {
        let truth = self.motion.next(now, self.dt);
        self.process(&truth);
    }

    /// One tick with an external motion source (a host's trajectory player)
    /// instead of the built-in motion.
    pub fn tick_with(&mut self, now: Instant, source: &mut dyn MotionSource) {
        let truth = source.next(now, self.dt);
        self.process(&truth);
    }

    fn process(&mut self, truth: &Truth) {
        self.ticks += 1;
        if self.errors_dirty {
            self.refresh_errors();
        }
        // Temperature: the model every UPDATE_TICKS, an override at once.
        self.temp_ticks += 1;
        let forced = self.faults.temperature_c.or(truth.temperature_c);
        let update = self.temp_ticks >= UPDATE_TICKS;
        if update {
            self.temp_ticks = 0;
            self.temp_model.step();
        }
        let t = forced.unwrap_or_else(|| self.temp_model.temperature_c());
        if update || t != self.temperature {
            self.temperature = t;
            self.engines[0].set_temperature(&self.errors.gyro, t);
            self.engines[1].set_temperature(&self.errors.acc, t);
            self.engines[2].set_temperature(&self.errors.aux, t);
        }

        // Sensors (sensor axes).
        if !self.faults.sensor_comm {
            let (rate, force) = match self.truth_frame {
                TruthFrame::Sensor => (truth.rate_dps, truth.specific_force_g),
                TruthFrame::Carrier => (
                    self.mounting.to_sensor(&truth.rate_dps),
                    self.mounting.to_sensor(&truth.specific_force_g),
                ),
            };
            let (g, over) = self.engines[0].measure(&rate, &mut self.rng);
            let (a, _) = self.engines[1].measure(&force, &mut self.rng);
            let aux = if self.has_aux {
                self.engines[2].measure(&force, &mut self.rng).0
            } else {
                [0.0; 3]
            };
            self.sat_live |= over;
            self.sensor = [g, a, aux];
        }

        // AHRS on carrier axes, before the FIR.
        let gc = self.mounting.to_carrier(&self.sensor[0]);
        let ac = self.mounting.to_carrier(&self.sensor[1]);
        match &mut self.ahrs {
            Ahrs::Aligning(al) => {
                al.add(&gc, &ac);
                self.attitude.note_rate(&gc);
            }
            Ahrs::Running => {
                let g = [
                    gc[0] - self.bias[0],
                    gc[1] - self.bias[1],
                    gc[2] - self.bias[2],
                ];
                self.attitude.update(&g, &ac);
            }
        }

        // Filters (sensor axes).
        let (y, z) = self.filters.push(&pack(&self.sensor));
        self.variant.add(&y, &z);
    }

    /// Enters the initial alignment (5.3.1): gyro bias and level estimation
    /// start from the next tick.
    pub fn begin_alignment(&mut self) {
        self.ahrs = Ahrs::Aligning(Alignment::new(self.cfg.align, self.rate_hz));
    }

    /// Ends the initial alignment (its time elapsed): accepts or rejects the
    /// bias (5.7), levels from the accelerometers, heading 0, and starts the
    /// attitude. Without an alignment running, the same as
    /// [`SignalChain::skip_alignment`].
    pub fn end_alignment(&mut self) {
        let result = match &self.ahrs {
            Ahrs::Aligning(al) if al.ticks() > 0 => al.finish(&self.earth_assumed),
            _ => return self.skip_alignment(),
        };
        self.bias = result.bias_dps;
        self.bias_failed = !result.accepted;
        self.attitude.set(result.attitude);
        self.ahrs = Ahrs::Running;
        self.variant.reset();
    }

    /// Initial_Alignment_Time = 0: no bias estimation (bias 0, not failed),
    /// levelled at once from the FIR-filtered accelerometers, heading 0.
    pub fn skip_alignment(&mut self) {
        let f = self.mounting.to_carrier(&triad(&self.filters.last(), 1));
        self.bias = [0.0; 3];
        self.bias_failed = false;
        self.attitude.set(level_from(&f));
        self.ahrs = Ahrs::Running;
        self.variant.reset();
    }

    /// The output of this output tick: data per the output variant over the
    /// interval since the previous output, in carrier axes; restarts the
    /// interval. See [`Sample`] for units.
    pub fn output(&mut self) -> Sample {
        let v = self.variant.take();
        self.interval = v.ticks as f32 * self.dt;
        self.sat_reported = self.sat_live;
        self.sat_live = 0;
        let m = &self.mounting;
        let gyro = m.to_carrier(&triad(&v.main, 0));
        let acc = m.to_carrier(&triad(&v.main, 1));
        let gyro_f = m.to_carrier(&triad(&v.filtered, 0));
        let acc_f = m.to_carrier(&triad(&v.filtered, 1));
        let (aux, aux_f) = if self.has_aux {
            (
                m.to_carrier(&triad(&v.main, 2)),
                m.to_carrier(&triad(&v.filtered, 2)),
            )
        } else {
            ([0.0; 3], [0.0; 3])
        };
        let b = self.bias;
        let (quat, euler) = match &self.ahrs {
            Ahrs::Aligning(al) => {
                let a = Attitude::new(al.level(), self.earth_assumed, self.dt);
                (a.quat(), a.euler_deg())
            }
            Ahrs::Running => (self.attitude.quat(), self.attitude.euler_deg()),
        };
        Sample {
            gyro,
            acc,
            aux_acc: aux,
            euler,
            quat,
            gyro_filtered: [gyro_f[0] - b[0], gyro_f[1] - b[1], gyro_f[2] - b[2]],
            gyro_bias: b,
            acc_filtered: acc_f,
            aux_acc_filtered: aux_f,
            temperature: self.temperature,
            supply_voltage: self.faults.supply_voltage.unwrap_or(NOMINAL_SUPPLY_V),
        }
    }

    /// USW, USW-extended and the GetBIT payload now. The rate-range bits
    /// cover the interval of the last [`SignalChain::output`] and the ticks
    /// since, so they read the same before or after `output()` at an output
    /// tick.
    pub fn status(&self) -> Status {
        let f = &self.faults;
        let mut usw = 0u16;
        if f.sensor_comm {
            usw |= usw::SENSOR_COMM;
        }
        if f.sensor_config {
            usw |= usw::SENSOR_CONFIG;
        }
        usw |= u16::from((self.sat_live | self.sat_reported) & 0x07) << 10;
        let (lo, hi) = OPERATING_RANGE_C;
        if !(lo..=hi).contains(&self.temperature) {
            usw |= usw::TEMPERATURE;
        }
        let mut usw_ext = 0u16;
        if !self.is_aligning() {
            usw_ext |= usw::EXT_ALIGNED;
        }
        if self.bias_failed {
            usw_ext |= usw::EXT_BIAS_FAILED;
        }
        let mut bit = [0u8; 4];
        if f.accel_bit {
            bit[0] |= 0x01;
        }
        if f.gyro_bit {
            bit[0] |= 0x04;
        }
        if f.flash_check {
            bit[1] |= 0x10;
        }
        Status { usw, usw_ext, bit }
    }
}
