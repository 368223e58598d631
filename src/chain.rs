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
//! - Float path on FPU cores; the `fixed-point` feature (cores without an
//!   FPU: ARMv6-M, RP2040) runs every per-tick stage in integers — see
//!   "Fixed point" below. A seed gives the same bytes on every platform for
//!   a given feature set; the two builds agree to the fixed-point resolution
//!   (same random draws: gyro within ~2e-4 °/s, acc ~3e-6 g, Euler angles
//!   ~2e-4°), not bit for bit.
//! - `output()` with no tick since [`SignalChain::configure`] or
//!   [`SignalChain::new`] gives the last FIR output (the accumulator keeps
//!   it across a reconfiguration), not zeros.
//!
//! # Memory
//!
//! `size_of::<SignalChain>()` (thumbv7em / thumbv6m): 10 160 B float,
//! 10 184 B `fixed-point` (budget 10 KiB; 18 792 B before this layout). The
//! FIR history is 8 136 B of it: single rings read as up to three runs
//! ([`crate::dsp::fir`]; a doubled ring would be 16 272 B) — 49 input rows
//! and 177 pre-filter rows of 9 channels, the minimum for the order-192
//! design plus the 49 rows the order-48 designs need (both histories always
//! run, so switching designs never needs a refill). The cascade keeps its
//! input history and each section's w only (11 values a channel instead of
//! 20, [`crate::dsp::cascade`]); the motion, the alignment and the error
//! engines keep no copies of configuration the chain already holds; the
//! last measurement is the FIR's newest input row. `i16` storage was
//! rejected: the float FIR's tests pin an impulse response to 1e-7 and the
//! fixed one a ramp exactly, which 16-bit samples cannot hold at ±2000 °/s.
//!
//! # Fixed point (`fixed-point` feature)
//!
//! Every per-tick stage is integer; the few `f32` operations left run once
//! per output (one division) or once per temperature change (one axis a
//! tick); trigonometry only at configuration time.
//!
//! | stage | representation |
//! |---|---|
//! | truth ([`crate::sensor::motion::BuiltinMotionFixed`]) | °/s·2¹⁹, g·2²³; attitude Q62, phasors Q30, static truth cached |
//! | error model ([`crate::sensor::errors::TriadEngineFixed`]) | same scale; M − I and noise levels as 14-bit-mantissa [`crate::dsp::fixed::Coef`]s, integer Irwin–Hall Gaussian and Gauss–Markov |
//! | mounting ([`crate::ahrs::mounting::MountingFixed`]) | Q30 matrix |
//! | attitude ([`crate::ahrs::attitude::AttitudeFixed`]) | rates in Q36 rad a tick, quaternion Q62, Euler angles by CORDIC |
//! | FIR ([`crate::dsp::fir::FirBankFixed`]) | °/s·2¹⁷, g·2²⁰ (the sensor scale rounded), Q15 taps |
//! | cascade ([`crate::dsp::cascade::CascadeFixed`]) | g Q26, a Q29, 32-bit products (64-bit beyond 2²⁹) |
//! | accumulator ([`crate::dsp::variant::VariantFixed`]) | exact `i64` sums, coning/sculling in block floating point |
//!
//! The attitude runs every tick at full rate (no decimation): its stated
//! bounds hold unchanged (coning 5° at 2 Hz, 10 s: 2e-4° against 1e-2°; a
//! static unit stays within 1e-3° over 120 s). Products are exact
//! 32 × 32 → 64 from four 16-bit `MULS` ([`crate::dsp::fixed::mul64`]),
//! since a plain `i64` product is a library call on ARMv6-M.
//!
//! # Cost
//!
//! Instructions executed, measured under QEMU (`-singlestep` trace, release
//! build with LTO, `qemu-system-arm -M mps2-an386`; the thumbv6m image runs
//! on that Cortex-M4 model, whose instruction count for ARMv6-M code is the
//! same), over 64 consecutive ticks (one temperature update among them):
//! mean / worst tick, then one `output()` after them. Worst configuration: K120
//! (aux accelerometer, all 9 channels), all three cascade filters,
//! incremental output, non-zero Alignment_Angles, coning motion, attitude
//! running:
//!
//! | LPF | Cortex-M4F (float) | ARMv6-M (`fixed-point`)¹ |
//! |---|---|---|
//! | 16 Hz (192, two-stage) | 3 843 / 4 012 | 19 543 / 20 743 |
//! | 33 Hz (96, two-stage) | 3 687 / 3 825 | 19 551 / 20 726 |
//! | 66 Hz (48) | 3 779 / 3 925 | 20 227 / 21 420 |
//! | 131 Hz (24) | 3 194 / 3 321 | 18 351 / 19 517 |
//! | 262 Hz (12) | 2 905 / 3 045 | 17 414 / 18 593 |
//! | off | 2 495 / 2 643 | 16 145 / 17 332 |
//! | K110 factory (262 Hz, no cascade, instant) | 1 911 / 2 052 | 9 463 / 10 624 |
//! | 66 Hz, constant rotation, truth in carrier axes | 3 846 / 3 992 | 21 422 / 22 615 |
//! | 66 Hz, vibration, 1 Hz output (2000 ticks) | 3 830 / 4 040 | 21 033 / 22 772 |
//!
//! `output()`: 790 (M4F; 671 K110 factory) / 12 052–12 119 (v6-M; 8 398
//! averaged, 5 464 instant). Worst tick + output: 4 830 (M4F), 34 891
//! (v6-M). The tick that ends an alignment ([`SignalChain::end_alignment`],
//! no output in it) costs 9 045 / 29 735; an aligning tick at most 3 880 /
//! 24 670 (the 10 ms block tick). Before the chain's performance work: M4F
//! 3 924 mean / 4 183 worst, v6-M 86 234 / 92 250 a tick and 30 291 an
//! output (84 % of it in soft-float routines).
//!
//! ¹ The v6-M column was measured before the FIR's channel loop was written
//! out (`each_channel!`) and before the fixed-point multiply/convert
//! helpers went out of line to fit the rp2040 image in 64 KiB (+10–14 % on
//! the whole device tick, README "Performance"); not re-measured since.
//!
//! The firmware images build with `opt-level = "s"`, which does not unroll
//! loops: the FIR's channel loop is written out for them (at opt-level 3
//! the compiler did it already; the M4F figures above moved by 0 to −25).
//! A whole `Device::on_tick` under the same single-step trace, opt-level
//! "s", K110 factory settings, 2 Mbit/s (before this work in brackets):
//! 2 124 a tick without output (3 349), ≈ 3 260 with a GA frame (5 546),
//! 5 115–5 220 with the largest UDD frame (≈ 8 900), at most 5 480 (9 464)
//! when the temperature update falls on an output tick. With `fixed-point`
//! on thumbv6m: 8 962 (9 857), ≈ 12 520 GA, ≈ 19 700 UDD; worst
//! 13 808 GA (18 819), 21 016 UDD (24 821). README "Performance".
//! On the host (criterion, `benches/tick.rs`) a worst-case tick takes
//! ≈ 0.3 µs and a factory tick ≈ 0.15 µs.

use crate::ahrs::alignment::{level_from, AlignConfig, Alignment};
#[cfg(not(feature = "fixed-point"))]
use crate::ahrs::attitude::Attitude;
#[cfg(feature = "fixed-point")]
use crate::ahrs::attitude::AttitudeFixed;
use crate::ahrs::mounting::Mounting;
#[cfg(feature = "fixed-point")]
use crate::ahrs::mounting::MountingFixed;
#[cfg(not(feature = "fixed-point"))]
use crate::ahrs::rotation::{canonical, euler_from_quat};
#[cfg(feature = "fixed-point")]
use crate::ahrs::rotation::{euler_deg_q30, level_q30, quat_rotate_inv_q30};
use crate::ahrs::rotation::{Quat, Vec3};
#[cfg(not(feature = "fixed-point"))]
use crate::dsp::cascade::Cascade;
#[cfg(feature = "fixed-point")]
use crate::dsp::cascade::CascadeFixed;
use crate::dsp::cascade::{CascadeConfig, SecondOrder};
#[cfg(not(feature = "fixed-point"))]
use crate::dsp::fir::FirBank;
#[cfg(feature = "fixed-point")]
use crate::dsp::fir::FirBankFixed;
use crate::dsp::fir::{self, FirDesign, CHANNELS};
#[cfg(feature = "fixed-point")]
use crate::dsp::fixed::{scaled_f32, to_fixed};
use crate::dsp::variant::OutputVariant;
#[cfg(not(feature = "fixed-point"))]
use crate::dsp::variant::VariantAccumulator;
#[cfg(feature = "fixed-point")]
use crate::dsp::variant::VariantFixed;
use crate::kernel::params::{self, Block};
use crate::model::{Capability, Product};
use crate::sensor::errors::ErrorModel;
#[cfg(not(feature = "fixed-point"))]
use crate::sensor::errors::TriadEngine;
#[cfg(feature = "fixed-point")]
use crate::sensor::errors::{TriadEngineFixed, ACC_BITS, GYRO_BITS, TRUTH_LIMIT};
#[cfg(not(feature = "fixed-point"))]
use crate::sensor::motion::BuiltinMotion;
#[cfg(feature = "fixed-point")]
use crate::sensor::motion::{BuiltinMotionFixed, TruthFixed};
use crate::sensor::motion::{Motion, MotionSource, Truth, TruthFrame};
use crate::sensor::rng::Rng;
use crate::sensor::temperature::{TemperatureModel, OPERATING_RANGE_C, UPDATE_TICKS};
use crate::sensor::Sample;
use crate::time::Instant;

const RAD: f32 = 180.0 / core::f32::consts::PI;

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

/// The numeric core of the chain, float (FPU cores): sensor engines, the
/// built-in motion, mounting, FIR, cascade, accumulator and attitude.
#[cfg(not(feature = "fixed-point"))]
#[derive(Debug, Clone)]
struct Core {
    engines: [TriadEngine; 3],
    motion: BuiltinMotion,
    mounting: Mounting,
    cascade: Cascade,
    variant: VariantAccumulator,
    attitude: Attitude,
}

/// The numeric core in integers (`fixed-point` feature, cores without an
/// FPU): the same stages on `i32` samples (module doc, "Fixed point").
#[cfg(feature = "fixed-point")]
#[derive(Debug, Clone)]
struct Core {
    engines: [TriadEngineFixed; 3],
    motion: BuiltinMotionFixed,
    mounting: MountingFixed,
    cascade: CascadeFixed,
    variant: VariantFixed,
    attitude: AttitudeFixed,
    /// Sensor axes whose temperature terms are still to be updated (one a
    /// tick, module doc).
    temp_pending: u8,
    /// The gyro bias in FIR units (°/s·2¹⁷), for the filtered gyro.
    bias_fir: [i32; 3],
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
    dt: f32,
    has_aux: bool,
    rng: Rng,
    errors: ErrorModel,
    errors_dirty: bool,
    temp_model: TemperatureModel,
    temperature: f32,
    faults: Faults,
    truth_frame: TruthFrame,
    cfg: ChainConfig,
    core: Core,
    /// The FIR bank (outside [`Core`]: it is most of the chain's size, and
    /// [`SignalChain::reset`] refills it in place).
    fir: ChainFir,
    ahrs: Ahrs,
    bias: Vec3,
    bias_failed: bool,
    sat_live: u8,
    sat_reported: u8,
    ticks: u64,
    interval: f32,
}

#[cfg(not(feature = "fixed-point"))]
fn pack(s: &[Vec3; 3]) -> [f32; CHANNELS] {
    [
        s[0][0], s[0][1], s[0][2], s[1][0], s[1][1], s[1][2], s[2][0], s[2][1], s[2][2],
    ]
}

fn triad<T: Copy>(x: &[T; CHANNELS], i: usize) -> [T; 3] {
    [x[3 * i], x[3 * i + 1], x[3 * i + 2]]
}

/// The Earth rate the AHRS assumes (module doc of [`crate::ahrs::alignment`]):
/// `earth_enu(DEFAULT_LATITUDE_DEG)`, as a constant (a unit test pins the
/// equality bit for bit).
pub const EARTH_ASSUMED: Vec3 = [
    0.0,
    f32::from_bits(0x3858_4525), // 5.156281e-5 rad/s
    f32::from_bits(0x3858_4525),
];

/// [`EARTH_ASSUMED`] in °/s·2^(GYRO_BITS + 8) (the fixed-point motion's unit).
#[cfg(feature = "fixed-point")]
fn earth_assumed_fixed() -> [i32; 3] {
    EARTH_ASSUMED.map(|w| to_fixed(w * RAD, GYRO_BITS + 8))
}

/// FIR units (°/s·2¹⁷, g·2²⁰) of a fixed-point measurement, rounded.
#[cfg(feature = "fixed-point")]
#[inline(never)]
fn fir_units(s: &[[i32; 3]; 3]) -> [i32; CHANNELS] {
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

#[cfg(not(feature = "fixed-point"))]
impl Core {
    fn new(product: &Product, cfg: &ChainConfig, t0: &[Vec3; 3], dt: f32) -> Self {
        let x = fir_row(t0);
        Core {
            engines: [
                TriadEngine::new(product.gyro.full_scale() as f32),
                TriadEngine::new(product.accel.full_scale() as f32),
                TriadEngine::new(AUX_RANGE_G),
            ],
            motion: BuiltinMotion::new(Motion::default(), dt),
            mounting: Mounting::from_angles_deg(cfg.alignment_angles_deg),
            cascade: Cascade::new(&cfg.cascade, cfg.internal_rate_hz, &x),
            variant: VariantAccumulator::new(cfg.output_variant, dt, &x),
            attitude: Attitude::new(level_from(&t0[1]), EARTH_ASSUMED, dt),
        }
    }
}

#[cfg(feature = "fixed-point")]
impl Core {
    fn new(product: &Product, cfg: &ChainConfig, t0: &[Vec3; 3], dt: f32) -> Self {
        let x = fir_row(t0);
        let mounting = Mounting::from_angles_deg(cfg.alignment_angles_deg);
        Core {
            engines: [
                TriadEngineFixed::new(product.gyro.full_scale() as f32, GYRO_BITS),
                TriadEngineFixed::new(product.accel.full_scale() as f32, ACC_BITS),
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
}

/// The FIR bank of this build: float, or integer (`fixed-point`).
#[cfg(not(feature = "fixed-point"))]
type ChainFir = FirBank;
/// The FIR bank of this build: float, or integer (`fixed-point`).
#[cfg(feature = "fixed-point")]
type ChainFir = FirBankFixed;

/// A measurement (gyro, acc, aux acc) as a FIR input row.
#[cfg(not(feature = "fixed-point"))]
fn fir_row(t: &[Vec3; 3]) -> [f32; CHANNELS] {
    pack(t)
}

/// A measurement (gyro, acc, aux acc) as a FIR input row, in FIR units.
#[cfg(feature = "fixed-point")]
fn fir_row(t: &[Vec3; 3]) -> [i32; CHANNELS] {
    fir_units(&[
        t[0].map(|v| to_fixed(v, GYRO_BITS)),
        t[1].map(|v| to_fixed(v, ACC_BITS)),
        t[2].map(|v| to_fixed(v, ACC_BITS)),
    ])
}

/// What [`SignalChain::attitude_mut`] gives: the attitude filter of this
/// build ([`crate::ahrs::attitude::Attitude`], or
/// [`crate::ahrs::attitude::AttitudeFixed`] with the `fixed-point` feature;
/// both have `set`, `set_tilt_correction`, `quat`, `euler_deg`).
#[cfg(not(feature = "fixed-point"))]
pub type ChainAttitude = Attitude;
/// What [`SignalChain::attitude_mut`] gives (see the float build's doc).
#[cfg(feature = "fixed-point")]
pub type ChainAttitude = AttitudeFixed;

impl SignalChain {
    /// Power-on of `product` with every random process seeded by `seed`.
    ///
    /// The unit is static, level, z up, heading 0 at
    /// [`crate::sensor::motion::DEFAULT_LATITUDE_DEG`] (the gyros read the Earth rate plus their
    /// errors, AccZ +1 g); errors are one unit drawn from the model's
    /// [`crate::sensor::ErrorSpec`]; the parameters are the factory
    /// defaults until [`SignalChain::configure`]. The AHRS starts levelled,
    /// unaligned (bias 0), USW-extended bit 0 set.
    pub fn new(product: Product, seed: u64) -> Self {
        let mut chain = Self::unpowered(product);
        chain.reset(product, seed);
        chain
    }

    /// A placeholder chain for `product` (zero histories, no random draws)
    /// that [`SignalChain::reset`] turns into a powered-on one: cheap to
    /// build in place (`Device::power_on_into`).
    #[inline(always)]
    pub fn unpowered(product: Product) -> Self {
        let dt = 1.0 / product.model.internal_rate_hz as f32;
        let cfg = ChainConfig::defaults(&product);
        let t0 = [[0.0; 3]; 3];
        SignalChain {
            product,
            dt,
            has_aux: false,
            rng: Rng::new(0),
            errors: ErrorModel::default(),
            errors_dirty: true,
            temp_model: TemperatureModel::default(),
            temperature: 0.0,
            faults: Faults::default(),
            truth_frame: TruthFrame::Sensor,
            cfg,
            core: Core::new(&product, &cfg, &t0, dt),
            fir: ChainFir::new(None, &fir_row(&t0)),
            ahrs: Ahrs::Running,
            bias: [0.0; 3],
            bias_failed: false,
            sat_live: 0,
            sat_reported: 0,
            ticks: 0,
            interval: dt,
        }
    }

    /// [`SignalChain::new`] in place: the same power-on state, without a
    /// second chain on the stack (the FIR history, most of the chain's
    /// size, is refilled where it is; everything else is small). What a
    /// power cycle runs on a microcontroller.
    pub fn reset(&mut self, product: Product, seed: u64) {
        let rate_hz = product.model.internal_rate_hz;
        let dt = 1.0 / rate_hz as f32;
        let has_aux = product.model.has(Capability::AuxAccel);
        let mut rng = Rng::new(seed);
        let errors = ErrorModel::for_product(&product, &mut rng);
        let temp_model = TemperatureModel::default();
        let cfg = ChainConfig::defaults(&product);
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
        let mut core = Core::new(&product, &cfg, &sensor, dt);
        let sensors = [&errors.gyro, &errors.acc, &errors.aux];
        for (e, s) in core.engines.iter_mut().zip(sensors) {
            e.randomize_gm(s, &mut rng);
        }
        // Every field, by name: a field added later cannot be forgotten.
        let SignalChain {
            product: product_,
            dt: dt_,
            has_aux: has_aux_,
            rng: rng_,
            errors: errors_,
            errors_dirty,
            temp_model: temp_model_,
            temperature,
            faults,
            truth_frame,
            cfg: cfg_,
            core: core_,
            fir,
            ahrs,
            bias,
            bias_failed,
            sat_live,
            sat_reported,
            ticks,
            interval,
        } = self;
        *product_ = product;
        *dt_ = dt;
        *has_aux_ = has_aux;
        *rng_ = rng;
        *errors_ = errors;
        *errors_dirty = true;
        *temp_model_ = temp_model;
        *temperature = temp_model.temperature_c();
        *faults = Faults::default();
        *truth_frame = TruthFrame::Sensor;
        *cfg_ = cfg;
        *core_ = core;
        fir.reset(cfg.fir_design(), &fir_row(&sensor));
        *ahrs = Ahrs::Running;
        *bias = [0.0; 3];
        *bias_failed = false;
        *sat_live = 0;
        *sat_reported = 0;
        *ticks = 0;
        *interval = dt;
        self.refresh_errors();
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
        let mounting = Mounting::from_angles_deg(cfg.alignment_angles_deg);
        let c = &mut self.core;
        self.fir.set_design(cfg.fir_design());
        // The cascade starts in the steady state of the last FIR output
        // (exact for a steady signal).
        let last = c.variant.last();
        c.cascade
            .configure(&cfg.cascade, cfg.internal_rate_hz, &last);
        #[cfg(not(feature = "fixed-point"))]
        {
            c.mounting = mounting;
            c.variant = VariantAccumulator::new(cfg.output_variant, self.dt, &last);
        }
        #[cfg(feature = "fixed-point")]
        {
            c.mounting = MountingFixed::new(&mounting);
            c.variant = VariantFixed::new(cfg.output_variant, self.dt, &last);
        }
    }

    /// Chooses a built-in motion, from its initial state (level at its
    /// heading, phase 0), from the next tick on.
    pub fn set_motion(&mut self, m: Motion) {
        #[cfg(not(feature = "fixed-point"))]
        {
            self.core.motion = BuiltinMotion::new(m, self.dt);
        }
        #[cfg(feature = "fixed-point")]
        {
            self.core.motion = BuiltinMotionFixed::new(m, self.dt);
        }
    }

    /// Which axes the motion describes (default: the unit's own).
    pub fn set_truth_frame(&mut self, frame: TruthFrame) {
        self.truth_frame = frame;
    }

    /// The true attitude of the built-in motion at the last tick (housing or
    /// carrier per [`TruthFrame`], Appendix C convention).
    pub fn truth_attitude(&self) -> Option<Quat> {
        self.core.motion.attitude()
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
        #[cfg(not(feature = "fixed-point"))]
        {
            // The FIR's newest input row is the last measurement.
            let x = self.fir.last_input();
            [triad(&x, 0), triad(&x, 1), triad(&x, 2)]
        }
        #[cfg(feature = "fixed-point")]
        {
            // The FIR's newest input row: the last measurement in FIR units.
            let x = self.fir.last_input();
            [
                triad(&x, 0).map(|v| scaled_f32(v, 17)),
                triad(&x, 1).map(|v| scaled_f32(v, 20)),
                triad(&x, 2).map(|v| scaled_f32(v, 20)),
            ]
        }
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
    pub fn attitude_mut(&mut self) -> &mut ChainAttitude {
        &mut self.core.attitude
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
        let e = &self.errors;
        let t = self.temperature;
        let c = &mut self.core.engines;
        c[0].configure(&e.gyro, t, dt);
        c[1].configure(&e.acc, t, dt);
        c[2].configure(&e.aux, t, dt);
        #[cfg(feature = "fixed-point")]
        {
            self.core.temp_pending = 0;
        }
        self.temp_model.prepare(UPDATE_TICKS as f32 * dt);
        self.errors_dirty = false;
    }

    /// The start of every tick: tick count, error-model changes, and the
    /// temperature (the model every [`UPDATE_TICKS`], an override at once).
    #[inline]
    fn begin_tick(&mut self, truth_temperature: Option<f32>) {
        self.ticks += 1;
        if self.errors_dirty {
            self.refresh_errors();
        }
        let forced = self.faults.temperature_c.or(truth_temperature);
        let update = self.ticks.is_multiple_of(u64::from(UPDATE_TICKS));
        if update {
            self.temp_model.step();
        }
        let t = forced.unwrap_or_else(|| self.temp_model.temperature_c());
        if update || t != self.temperature {
            self.temperature = t;
            #[cfg(not(feature = "fixed-point"))]
            {
                let (e, c) = (&self.errors, &mut self.core.engines);
                c[0].set_temperature(&e.gyro, t);
                c[1].set_temperature(&e.acc, t);
                c[2].set_temperature(&e.aux, t);
            }
            #[cfg(feature = "fixed-point")]
            {
                self.core.temp_pending = 9;
            }
        }
        // Fixed point: one axis a tick (two soft-float products each).
        #[cfg(feature = "fixed-point")]
        if self.core.temp_pending > 0 {
            self.core.temp_pending -= 1;
            let k = usize::from(self.core.temp_pending);
            let (e, i) = (
                [2, 2, 2, 1, 1, 1, 0, 0, 0][k],
                [2, 1, 0, 2, 1, 0, 2, 1, 0][k],
            );
            let errs = [&self.errors.gyro, &self.errors.acc, &self.errors.aux][e];
            self.core.engines[e].set_axis_temperature(errs, i, self.temperature);
        }
    }

    /// One internal-rate tick with the built-in motion: truth → errors and
    /// saturation → FIR → cascade → variant accumulator, and alignment or
    /// attitude. `now` is the tick's time (handed to the motion source).
    pub fn tick(&mut self, now: Instant) {
        #[cfg(not(feature = "fixed-point"))]
        {
            let truth = self.core.motion.next(now, self.dt);
            self.process(&truth);
        }
        #[cfg(feature = "fixed-point")]
        {
            let _ = now;
            let truth = self.core.motion.step();
            self.process(&truth);
        }
    }

    /// One tick with an external motion source (a host's trajectory player)
    /// instead of the built-in motion.
    pub fn tick_with(&mut self, now: Instant, source: &mut dyn MotionSource) {
        let truth = source.next(now, self.dt);
        #[cfg(not(feature = "fixed-point"))]
        self.process(&truth);
        #[cfg(feature = "fixed-point")]
        self.process(&TruthFixed::from_truth(&truth));
    }

    #[cfg(not(feature = "fixed-point"))]
    fn process(&mut self, truth: &Truth) {
        let truth = &truth.bounded();
        self.begin_tick(truth.temperature_c);
        let c = &mut self.core;
        // Sensors (sensor axes).
        let sensor = if !self.faults.sensor_comm {
            let (rate, force) = match self.truth_frame {
                TruthFrame::Sensor => (truth.rate_dps, truth.specific_force_g),
                TruthFrame::Carrier => (
                    c.mounting.to_sensor(&truth.rate_dps),
                    c.mounting.to_sensor(&truth.specific_force_g),
                ),
            };
            let (g, over) = c.engines[0].measure(&rate, &mut self.rng);
            let (a, _) = c.engines[1].measure(&force, &mut self.rng);
            let aux = if self.has_aux {
                c.engines[2].measure(&force, &mut self.rng).0
            } else {
                [0.0; 3]
            };
            self.sat_live |= over;
            pack(&[g, a, aux])
        } else {
            // Frozen: the FIR's newest input is the last good measurement.
            self.fir.last_input()
        };

        // AHRS on carrier axes, before the FIR.
        let gc = c.mounting.to_carrier(&triad(&sensor, 0));
        let ac = c.mounting.to_carrier(&triad(&sensor, 1));
        match &mut self.ahrs {
            Ahrs::Aligning(al) => {
                al.add(&gc, &ac, &self.cfg.align);
                c.attitude.note_rate(&gc);
            }
            Ahrs::Running => {
                let g = [
                    gc[0] - self.bias[0],
                    gc[1] - self.bias[1],
                    gc[2] - self.bias[2],
                ];
                c.attitude.update(&g, &ac);
            }
        }

        // Filters (sensor axes).
        let y = self.fir.push(&sensor);
        let mut z = y;
        c.cascade.process(&mut z);
        c.variant.add(&y, &z);
    }

    #[cfg(feature = "fixed-point")]
    fn process(&mut self, truth: &TruthFixed) {
        self.begin_tick(truth.temperature_c);
        let c = &mut self.core;
        // Sensors (sensor axes), scaled by 2^GYRO_BITS, 2^ACC_BITS.
        let sensor = if !self.faults.sensor_comm {
            let (rate, force) = match self.truth_frame {
                TruthFrame::Sensor => (truth.rate, truth.force),
                TruthFrame::Carrier => (
                    c.mounting.to_sensor(&truth.rate),
                    c.mounting.to_sensor(&truth.force),
                ),
            };
            let (g, over) = c.engines[0].measure(&rate, &mut self.rng);
            let (a, _) = c.engines[1].measure(&force, &mut self.rng);
            let aux = if self.has_aux {
                c.engines[2].measure(&force, &mut self.rng).0
            } else {
                [0; 3]
            };
            self.sat_live |= over;
            [g, a, aux]
        } else {
            // Frozen: the FIR's newest input (FIR units) is the last good
            // measurement.
            let x = self.fir.last_input();
            let (g, a) = (GYRO_BITS - 17, ACC_BITS - 20);
            [
                triad(&x, 0).map(|v| v << g),
                triad(&x, 1).map(|v| v << a),
                triad(&x, 2).map(|v| v << a),
            ]
        };

        // AHRS on carrier axes, before the FIR.
        let gc = c.mounting.to_carrier(&sensor[0]);
        let ac = c.mounting.to_carrier(&sensor[1]);
        match &mut self.ahrs {
            Ahrs::Aligning(al) => {
                al.add(
                    &gc.map(|v| scaled_f32(v, GYRO_BITS)),
                    &ac.map(|v| scaled_f32(v, ACC_BITS)),
                    &self.cfg.align,
                );
                c.attitude.note_rate(&gc);
            }
            Ahrs::Running => c.attitude.update(&gc, &ac),
        }

        // Filters (sensor axes).
        let y = self.fir.push(&fir_units(&sensor));
        let mut z = y;
        c.cascade.process(&mut z);
        c.variant.add(&y, &z);
    }

    /// Enters the initial alignment (5.3.1): gyro bias and level estimation
    /// start from the next tick.
    pub fn begin_alignment(&mut self) {
        self.ahrs = Ahrs::Aligning(Alignment::new(
            &self.cfg.align,
            self.product.model.internal_rate_hz,
        ));
    }

    /// Ends the initial alignment (its time elapsed): accepts or rejects the
    /// bias (5.7), levels from the accelerometers, heading 0, and starts the
    /// attitude. Without an alignment running, the same as
    /// [`SignalChain::skip_alignment`].
    pub fn end_alignment(&mut self) {
        let result = match &self.ahrs {
            Ahrs::Aligning(al) if al.ticks() > 0 => {
                #[cfg(not(feature = "fixed-point"))]
                {
                    al.finish(&EARTH_ASSUMED, &self.cfg.align)
                }
                #[cfg(feature = "fixed-point")]
                {
                    // Levelling and the Earth rate in integers (CORDIC): no
                    // soft-float trigonometry in this tick.
                    let f = al
                        .mean_force()
                        .map(|v| to_fixed(v, ACC_BITS).clamp(-TRUTH_LIMIT, TRUTH_LIMIT));
                    let q = level_q30(&f);
                    let w = quat_rotate_inv_q30(&q, &earth_assumed_fixed());
                    let r = al.finish_at(
                        q.map(|v| scaled_f32(v, 30)),
                        w.map(|v| scaled_f32(v, GYRO_BITS + 8)),
                        &self.cfg.align,
                    );
                    self.core.attitude.set_q30(q);
                    r
                }
            }
            _ => return self.skip_alignment(),
        };
        self.bias_failed = !result.accepted;
        #[cfg(not(feature = "fixed-point"))]
        self.core.attitude.set(result.attitude);
        self.set_bias(result.bias_dps);
        self.ahrs = Ahrs::Running;
        self.core.variant.reset();
    }

    /// Initial_Alignment_Time = 0: no bias estimation (bias 0, not failed),
    /// levelled at once from the FIR-filtered accelerometers, heading 0.
    pub fn skip_alignment(&mut self) {
        let last = self.core.variant.last();
        let f = self.core.mounting.to_carrier(&triad(&last, 1));
        #[cfg(not(feature = "fixed-point"))]
        self.core.attitude.set(level_from(&f));
        #[cfg(feature = "fixed-point")]
        self.core.attitude.set_q30(level_q30(&f));
        self.bias_failed = false;
        self.set_bias([0.0; 3]);
        self.ahrs = Ahrs::Running;
        self.core.variant.reset();
    }

    fn set_bias(&mut self, b: Vec3) {
        self.bias = b;
        #[cfg(feature = "fixed-point")]
        {
            self.core.attitude.set_bias(&b, self.dt);
            self.core.bias_fir = b.map(|v| to_fixed(v, 17));
        }
    }

    /// The orientation now: (quaternion, Euler angles in degrees).
    fn orientation(&self) -> (Quat, Vec3) {
        match &self.ahrs {
            #[cfg(not(feature = "fixed-point"))]
            Ahrs::Aligning(al) => {
                let q = al.level();
                let e = euler_from_quat(&q);
                (canonical(&q), [e[0] * RAD, e[1] * RAD, e[2] * RAD])
            }
            #[cfg(feature = "fixed-point")]
            Ahrs::Aligning(al) => {
                let f = al
                    .mean_force()
                    .map(|v| to_fixed(v, ACC_BITS).clamp(-TRUTH_LIMIT, TRUTH_LIMIT));
                let q = level_q30(&f);
                (q.map(|v| scaled_f32(v, 30)), euler_deg_q30(&q))
            }
            Ahrs::Running => (self.core.attitude.quat(), self.core.attitude.euler_deg()),
        }
    }

    /// The output of this output tick: data per the output variant over the
    /// interval since the previous output, in carrier axes; restarts the
    /// interval. See [`Sample`] for units.
    pub fn output(&mut self) -> Sample {
        self.output_with(true)
    }

    /// [`SignalChain::output`], computing the orientation only if
    /// `attitude` (the frame carries it): without, [`Sample::quat`] is the
    /// identity and [`Sample::euler`] zeros. Nothing else differs; the
    /// orientation has no state of its own to advance.
    pub fn output_with(&mut self, attitude: bool) -> Sample {
        let v = self.core.variant.take();
        self.interval = v.ticks as f32 * self.dt;
        self.sat_reported = self.sat_live;
        self.sat_live = 0;
        let m = &self.core.mounting;
        #[cfg(not(feature = "fixed-point"))]
        let (gyro, acc, gyro_f, acc_f, (aux, aux_f)) = {
            let b = self.bias;
            let gf = m.to_carrier(&triad(&v.filtered, 0));
            (
                m.to_carrier(&triad(&v.main, 0)),
                m.to_carrier(&triad(&v.main, 1)),
                [gf[0] - b[0], gf[1] - b[1], gf[2] - b[2]],
                m.to_carrier(&triad(&v.filtered, 1)),
                if self.has_aux {
                    (
                        m.to_carrier(&triad(&v.main, 2)),
                        m.to_carrier(&triad(&v.filtered, 2)),
                    )
                } else {
                    ([0.0; 3], [0.0; 3])
                },
            )
        };
        #[cfg(feature = "fixed-point")]
        let (gyro, acc, gyro_f, acc_f, (aux, aux_f)) = {
            let f = |x: &[i32; CHANNELS], i: usize, k: u32| {
                m.to_carrier(&triad(x, i)).map(|v| scaled_f32(v, k))
            };
            let b = self.core.bias_fir;
            let gf = m.to_carrier(&triad(&v.filtered, 0));
            (
                f(&v.main, 0, 17),
                f(&v.main, 1, 20),
                [
                    scaled_f32(gf[0].saturating_sub(b[0]), 17),
                    scaled_f32(gf[1].saturating_sub(b[1]), 17),
                    scaled_f32(gf[2].saturating_sub(b[2]), 17),
                ],
                f(&v.filtered, 1, 20),
                if self.has_aux {
                    (f(&v.main, 2, 20), f(&v.filtered, 2, 20))
                } else {
                    ([0.0; 3], [0.0; 3])
                },
            )
        };
        let (quat, euler) = if attitude {
            self.orientation()
        } else {
            ([1.0, 0.0, 0.0, 0.0], [0.0; 3])
        };
        Sample {
            gyro,
            acc,
            aux_acc: aux,
            euler,
            quat,
            gyro_filtered: gyro_f,
            gyro_bias: self.bias,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::motion::{earth_enu, DEFAULT_LATITUDE_DEG};

    #[test]
    fn the_assumed_earth_rate_is_the_default_site_s() {
        let e = earth_enu(DEFAULT_LATITUDE_DEG);
        assert_eq!(
            e.map(f32::to_bits),
            EARTH_ASSUMED.map(f32::to_bits),
            "{e:?}"
        );
    }
}
