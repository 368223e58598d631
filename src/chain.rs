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
//!   the personality's configuration of its live parameters (KERNEL:
//!   [`crate::kernel::config::chain_config`]). It keeps the FIR's
//!   input history (a real FIR runs on the sensor stream continuously; only
//!   the coefficients change), starts the cascade in the steady state of its
//!   current input (no transient) and empties the variant accumulator.
//! - A format with orientation: Initial_Alignment_Time > 0 →
//!   [`SignalChain::begin_alignment`], then after that many seconds of ticks
//!   [`SignalChain::end_alignment`]; = 0 → [`SignalChain::skip_alignment`].
//!   Formats without orientation call neither (the AHRS keeps its state).
//! - At an output tick: `SignalChain::output` (covers the ticks since the
//!   previous output, then restarts the interval), then
//!   [`SignalChain::health`], which the personality encodes (KERNEL: USW,
//!   USW-extended and GetBIT in [`crate::kernel::status`]).
//! - Streams that window the measurement themselves (the IMX's IMU and
//!   PIMU): a `SignalChain<`[`Integrals`]`>` ([`SignalChain::powered_on`])
//!   and [`SignalChain::integrals`] snapshots, differenced by
//!   [`crate::dsp::integrals::window`]. The default `SignalChain` (the
//!   KERNEL's) keeps none: no storage, no per-tick cost.
//!
//! The chain knows no protocol: nothing here or in `sensor`, `ahrs`, `dsp`
//! imports `kernel` or `isb`; [`ChainConfig`] and [`Health`] are neutral and
//! each personality maps its parameters and status words onto them.
//!
//! # Decisions (docs/kernel.md "Protocol notes")
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
//! - Physics: g = 9.8106 m/s², Earth rate 15.041 °/h, default site 50.1° N
//!   (Newlyn), heading 0, level ([`crate::sensor::motion`]). The built-in motion moves
//!   the unit itself ([`TruthFrame::Sensor`]); Alignment_Angles rotate what it
//!   reports.
//! - Errors and temperature model: the model's built-in sensor profile
//!   ([`crate::sensor::profiles`]) or one set with
//!   [`SignalChain::set_profile`]; default warm-up from 25 °C by +8 °C,
//!   τ 600 s ([`crate::sensor::temperature`]).
//! - Alignment: averaging with the STD of 10 ms means vs the threshold, or a
//!   Kalman filter (ZUPT); heading relative (0 after alignment)
//!   ([`crate::ahrs::alignment`]).
//! - [`Health::gyro_over_range`] reports a gyro axis (sensor axes) beyond
//!   the measurement range at any tick of the interval the output covers.
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
//! 10 184 B `fixed-point` before the flicker bias (budget then 10 KiB;
//! 18 792 B before this layout); the flicker's six states a sensor axis
//! and the profile terms' coefficients add ≈ 0.75 KiB (10 920 B float on
//! a 64-bit host), the vehicle state a board may set
//! ([`SignalChain::set_vehicle`]) 144 B (budget now 12 KiB,
//! `tests/signal_chain.rs`); `SignalChain<Integrals>` adds the 104 B of
//! [`Integrals`]. The
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
//! The arithmetic is chosen in one place: `chain/float.rs` and
//! `chain/fixed.rs` define the same numeric core (`Core`, with the same
//! methods, and the same helper functions and type names), and one
//! `cfg_attr(path)` on the module picks one; the rest of this file has no
//! `cfg`. Every per-tick stage is integer; the few `f32` operations left run once
//! per output (one division) or once per temperature change (one axis a
//! tick); trigonometry only at configuration time.
//!
//! | stage | representation |
//! |---|---|
//! | truth ([`crate::sensor::motion::BuiltinMotionFixed`]) | °/s·2¹⁹, g·2²³; attitude Q62, phasors Q30, static truth cached |
//! | error model ([`crate::sensor::errors::TriadEngineFixed`]) | same scale; M − I and noise levels as 14-bit-mantissa [`crate::math::fixed::Coef`]s, integer Irwin–Hall Gaussian and Gauss–Markov |
//! | mounting ([`crate::ahrs::mounting::MountingFixed`]) | Q30 matrix |
//! | attitude ([`crate::ahrs::attitude::AttitudeFixed`]) | rates in Q36 rad a tick, quaternion Q62, Euler angles by CORDIC |
//! | FIR ([`crate::dsp::fir::FirBankFixed`]) | °/s·2¹⁷, g·2²⁰ (the sensor scale rounded), Q15 taps |
//! | cascade ([`crate::dsp::cascade::CascadeFixed`]) | g Q26, a Q29, 32-bit products (64-bit beyond 2²⁹) |
//! | accumulator ([`crate::dsp::variant::VariantFixed`]) | exact `i64` sums, coning/sculling in block floating point |
//!
//! The attitude runs every tick at full rate (no decimation): its stated
//! bounds hold unchanged (coning 5° at 2 Hz, 10 s: 2e-4° against 1e-2°; a
//! static unit stays within 1e-3° over 120 s). Products are exact
//! 32 × 32 → 64 from four 16-bit `MULS` ([`crate::math::fixed::mul64`]),
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
//! helpers went out of line to fit the rp2040 image in 64 KiB; the chain
//! alone has not been re-measured since. The whole device tick has (below).
//!
//! The firmware images build with `opt-level = "s"`, which does not unroll
//! loops: the FIR's channel loop is written out for them (at opt-level 3
//! the compiler did it already; the M4F figures above moved by 0 to −25).
//! A whole `Device::on_tick` in the qemu-mps2 image (M4F, opt-level "s",
//! K110 factory settings, 2 Mbit/s, the `qemu::tick_cost` conformance
//! tests): 3 800 with a GA frame at 2 kHz, 5 640–5 840 with the largest UDD
//! frame. With `fixed-point` on thumbv6m (`scripts/v6m-tick.sh`, worst of
//! 40 ticks, ±40; with the flicker bias, docs/sensors.md): 11 080 a tick
//! without output, 14 760 GA at 2 kHz, 22 920 the largest UDD, 27 000 the
//! same with LPF 16 Hz. `docs/performance.md`, `docs/firmware-budget.md`.
//! On the host (criterion, `benches/tick.rs`) a worst-case tick takes
//! ≈ 0.3 µs and a factory tick ≈ 0.15 µs.

use crate::ahrs::alignment::{AlignConfig, Alignment};
use crate::dsp::cascade::CascadeConfig;
use crate::dsp::fir::{self, Bandwidth, FirDesign, CHANNELS};
use crate::dsp::integrals::{Integrals, Integrate, NoIntegrals};
use crate::dsp::variant::OutputVariant;
use crate::math::rotation::{Quat, Vec3};
use crate::model::Product;
use crate::sensor::errors::ErrorModel;
use crate::sensor::motion::{Motion, MotionSource, Truth, TruthFrame};
use crate::sensor::profile::SensorProfile;
use crate::sensor::rng::Rng;
use crate::sensor::temperature::{TemperatureModel, OPERATING_RANGE_C, UPDATE_TICKS};
use crate::sensor::Sample;
use crate::time::Instant;
use crate::vehicle::VehicleState;

// Float or fixed point: chosen here, once. Both files define the same items
// (`Core` with the same methods, `Fir`, `Attitude`, `Truth`, `Sensor`,
// `Triad` and the same free functions).
#[cfg_attr(not(feature = "fixed-point"), path = "chain/float.rs")]
#[cfg_attr(feature = "fixed-point", path = "chain/fixed.rs")]
mod arith;
use arith::Core;

const RAD: f32 = 180.0 / core::f32::consts::PI;

/// Saturation of the aux (high-g) accelerometer, g (product code `A90`).
pub(crate) const AUX_RANGE_G: f32 = 90.0;
/// Supply voltage reported unless a fault overrides it, V.
pub(crate) const NOMINAL_SUPPLY_V: f32 = 12.0;

/// The chain's configuration, protocol neutral: each personality builds it
/// from its own parameters (the KERNEL's Table 5.24 rows:
/// [`crate::kernel::config::chain_config`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainConfig {
    /// Internal rate of the model, Hz (Table 4.3).
    pub internal_rate_hz: u32,
    /// FIR low-pass bandwidth (5.6, Table 5.29).
    pub lpf: Bandwidth,
    /// Cascade filter mask and Filt1/Filt2/Tau (5.8).
    pub cascade: CascadeConfig,
    /// What an output carries over its interval (5.3.6).
    pub output_variant: OutputVariant,
    /// Mounting (alignment) angles heading, pitch, roll, degrees (Appendix B).
    pub alignment_angles_deg: [f32; 3],
    /// Alignment method, threshold and the AHRS tuning (5.7).
    pub align: AlignConfig,
}

impl ChainConfig {
    /// The power-on configuration of `product`: LPF 262 Hz, cascade off
    /// (its filters at their default tuning), instant output, no mounting
    /// rotation, averaging alignment with the default threshold and tuning.
    /// (The KERNEL's factory parameters map to exactly this; a unit test in
    /// [`crate::kernel::config`] pins it.)
    #[inline(never)]
    pub fn defaults(product: &Product) -> Self {
        ChainConfig {
            internal_rate_hz: product.model.internal_rate_hz,
            lpf: Bandwidth::Hz262,
            cascade: CascadeConfig::default(),
            output_variant: OutputVariant::Instant,
            alignment_angles_deg: [0.0; 3],
            align: AlignConfig::default(),
        }
    }

    /// The FIR design this configuration selects (`None` = off); for the
    /// crate's tests.
    #[cfg(feature = "internals")]
    pub fn fir_design(&self) -> Option<&'static FirDesign> {
        fir::design(self.lpf, self.internal_rate_hz)
    }
}

/// Injectable faults (they drive [`Health`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Faults {
    /// Internal sensors stop answering: the data freeze at the last good
    /// values; [`Health::sensor_comm_failure`].
    pub sensor_comm: bool,
    /// Internal sensor configuration failed: [`Health::sensor_config_failure`].
    pub sensor_config: bool,
    /// Gyroscope BIT fails: [`Health::gyro_bit_failed`].
    pub gyro_bit: bool,
    /// Accelerometer BIT fails: [`Health::accel_bit_failed`].
    pub accel_bit: bool,
    /// Flash check fails: [`Health::flash_check_failed`].
    pub flash_check: bool,
    /// Forces the sensor temperature, °C; outside
    /// [`OPERATING_RANGE_C`] sets [`Health::over_temperature`].
    pub temperature_c: Option<f32>,
    /// Forces the reported supply voltage, V.
    pub supply_voltage: Option<f32>,
    /// The board's live motion feed has been silent beyond its timeout
    /// (`crate::feed`): reported as [`Health::sensor_comm_failure`] (the
    /// feed is this unit's sensor), but the data do not freeze — the last
    /// sample holds, with the sensor errors on it.
    pub motion_feed_lost: bool,
}

/// The unit's health now, protocol neutral (the KERNEL encodes it as USW,
/// USW-extended and GetBIT in [`crate::kernel::status`]). Axis masks: bit 0
/// X, bit 1 Y, bit 2 Z, sensor axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Health {
    /// The internal sensors do not answer (data frozen).
    pub sensor_comm_failure: bool,
    /// The internal sensors' configuration failed.
    pub sensor_config_failure: bool,
    /// Gyro axes beyond the measurement range at any tick of the interval
    /// of the last `SignalChain::output` or since.
    pub gyro_over_range: u8,
    /// Accelerometer axes beyond the measurement range, same interval.
    pub accel_over_range: u8,
    /// The sensor temperature is outside [`OPERATING_RANGE_C`].
    pub over_temperature: bool,
    /// The gyroscope built-in test failed.
    pub gyro_bit_failed: bool,
    /// The accelerometer built-in test failed.
    pub accel_bit_failed: bool,
    /// The flash check failed.
    pub flash_check_failed: bool,
    /// An initial alignment is running (clear: complete, or skipped).
    pub aligning: bool,
    /// The last alignment rejected its gyro bias estimate (5.7).
    pub bias_estimation_failed: bool,
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

#[derive(Debug, Clone, PartialEq)]
enum Ahrs {
    Aligning(Alignment),
    Running,
}

/// The signal chain of one unit (module doc). Fixed size, no heap.
///
/// `I` chooses whether it keeps the cumulative integrals
/// ([`crate::dsp::integrals`]): [`NoIntegrals`] (the default, what the
/// KERNEL runs: no storage, no cost) or [`Integrals`]
/// ([`SignalChain::integrals`]; a personality whose streams window them).
#[derive(Debug, Clone)]
pub struct SignalChain<I: Integrate = NoIntegrals> {
    product: Product,
    dt: f32,
    has_aux: bool,
    rng: Rng,
    errors: ErrorModel,
    errors_dirty: bool,
    /// A profile replacing the built-in one at each power-on.
    profile: Option<&'static SensorProfile>,
    temp_model: TemperatureModel,
    temperature: f32,
    faults: Faults,
    truth_frame: TruthFrame,
    cfg: ChainConfig,
    core: Core,
    /// The FIR bank (outside [`Core`]: it is most of the chain's size, and
    /// [`SignalChain::reset`] refills it in place).
    fir: arith::Fir,
    ahrs: Ahrs,
    bias: Vec3,
    bias_failed: bool,
    sat_live: u8,
    sat_reported: u8,
    ticks: u64,
    interval: f32,
    integrals: I,
    /// The vehicle a board's source set for this tick
    /// ([`SignalChain::set_vehicle`]); `None`: the built-in motion's.
    vehicle: Option<VehicleState>,
    /// The built-in motion's site (set with the motion).
    site: crate::vehicle::Site,
}

fn triad<T: Copy>(x: &[T; CHANNELS], i: usize) -> [T; 3] {
    [x[3 * i], x[3 * i + 1], x[3 * i + 2]]
}

/// The three sensors' measurement of a tick's truth, one sequence for
/// both number paths (`chain/float.rs`, `chain/fixed.rs`): the truth
/// `(rate, force)` given in `frame` is turned into sensor axes
/// (`to_sensor`: the mounting), then the gyro, the accelerometer and — on a
/// unit with one — the aux accelerometer measure it in that order (the
/// order of their random draws; `measure(i, input, force)` is engine `i`),
/// `zero` standing for an absent aux. Returns the triads and the gyro
/// (bits 0–2) and accelerometer (bits 3–5) axes beyond their range.
#[inline(always)]
fn measure_sensors<T: Copy>(
    (rate, force): (T, T),
    frame: TruthFrame,
    to_sensor: impl Fn(&T) -> T,
    has_aux: bool,
    zero: T,
    mut measure: impl FnMut(usize, &T, &T) -> (T, u8),
) -> ([T; 3], u8) {
    let (rate, force) = match frame {
        TruthFrame::Sensor => (rate, force),
        TruthFrame::Carrier => (to_sensor(&rate), to_sensor(&force)),
    };
    let (g, over) = measure(0, &rate, &force);
    let (a, over_a) = measure(1, &force, &force);
    let aux = if has_aux {
        measure(2, &force, &force).0
    } else {
        zero
    };
    ([g, a, aux], over | over_a << 3)
}

/// The Earth rate the AHRS assumes (module doc of [`crate::ahrs::alignment`]):
/// `earth_enu(DEFAULT_LATITUDE_DEG)`, as a constant (a unit test pins the
/// equality bit for bit).
pub(crate) const EARTH_ASSUMED: Vec3 = [
    0.0,
    f32::from_bits(0x3844_2E90), // 4.6773406e-5 rad/s
    f32::from_bits(0x386A_A511), // 5.5943678e-5 rad/s
];

/// What an output interval gives, carrier axes, °/s and g (the core's
/// conversion of its accumulator).
#[derive(Debug, Clone, Copy)]
struct Outputs {
    gyro: Vec3,
    acc: Vec3,
    gyro_f: Vec3,
    acc_f: Vec3,
    aux: Vec3,
    aux_f: Vec3,
}

/// What [`SignalChain::attitude_mut`] gives: the attitude filter of this
/// build ([`crate::ahrs::attitude::Attitude`], or
/// [`crate::ahrs::attitude::AttitudeFixed`] with the `fixed-point` feature;
/// both have `set`, `set_tilt_correction`, `quat`, `euler_deg`).
pub(crate) type ChainAttitude = arith::Attitude;

impl SignalChain {
    /// Power-on of `product` with every random process seeded by `seed`
    /// (no integrals; [`SignalChain::powered_on`] for any `I`).
    ///
    /// The unit is static, level, z up, heading 0 at
    /// [`crate::sensor::motion::DEFAULT_LATITUDE_DEG`] (the gyros read the Earth rate plus their
    /// errors, AccZ +1 g); errors are one unit drawn from the model's
    /// built-in profile ([`Product::sensor_profile`]); the configuration is
    /// [`ChainConfig::defaults`] until [`SignalChain::configure`]. The AHRS
    /// starts levelled, unaligned (bias 0), not aligning.
    pub fn new(product: Product, seed: u64) -> Self {
        Self::powered_on(product, seed)
    }

    /// A placeholder chain for `product` (zero histories, no random draws)
    /// that [`SignalChain::reset`] turns into a powered-on one: cheap to
    /// build in place (`Device::power_on_into`).
    #[inline(always)]
    pub fn unpowered(product: Product) -> Self {
        Self::placeholder(product)
    }
}

impl SignalChain<Integrals> {
    /// The cumulative integrals since power-on now (a snapshot): a stream
    /// keeps the one of its window's start and, at its end,
    /// [`crate::dsp::integrals::window`]`(&start, &chain.integrals(),
    /// internal_rate_hz)` gives the coning/sculling-corrected Δθ and Δv.
    /// Pre-FIR measurement, carrier axes, gyro bias not removed
    /// ([`crate::dsp::integrals`]).
    pub fn integrals(&self) -> Integrals {
        self.integrals
    }
}

impl<I: Integrate> SignalChain<I> {
    /// [`SignalChain::new`] for a chain of any `I`.
    pub fn powered_on(product: Product, seed: u64) -> Self {
        let mut chain = Self::placeholder(product);
        chain.reset(product, seed);
        chain
    }

    /// [`SignalChain::unpowered`] for a chain of any `I`.
    #[inline(always)]
    pub fn placeholder(product: Product) -> Self {
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
            profile: None,
            temp_model: TemperatureModel::default(),
            temperature: 0.0,
            faults: Faults::default(),
            truth_frame: TruthFrame::Sensor,
            cfg,
            core: Core::new(&product, &cfg, &t0, dt),
            fir: arith::Fir::new(None, &arith::fir_row(&t0)),
            ahrs: Ahrs::Running,
            bias: [0.0; 3],
            bias_failed: false,
            sat_live: 0,
            sat_reported: 0,
            ticks: 0,
            interval: dt,
            integrals: I::default(),
            vehicle: None,
            site: crate::vehicle::Site::placeholder(),
        }
    }

    /// [`SignalChain::new`] in place: the same power-on state, without a
    /// second chain on the stack (the FIR history, most of the chain's
    /// size, is refilled where it is; everything else is small). What a
    /// power cycle runs on a microcontroller.
    pub fn reset(&mut self, product: Product, seed: u64) {
        let rate_hz = product.model.internal_rate_hz;
        let dt = 1.0 / rate_hz as f32;
        let has_aux = product.model.aux_accel;
        let mut rng = Rng::new(seed);
        let profile = match self.profile {
            Some(p) => *p,
            None => product.sensor_profile(),
        };
        let errors = ErrorModel::from_profile(&profile, &mut rng);
        let temp_model = TemperatureModel::from_spec(&profile.temperature);
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
            e.randomize_slow(s, &mut rng);
        }
        // Every field, by name: a field added later cannot be forgotten.
        let SignalChain {
            product: product_,
            dt: dt_,
            has_aux: has_aux_,
            rng: rng_,
            errors: errors_,
            errors_dirty,
            profile: _,
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
            integrals,
            vehicle,
            site,
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
        fir.reset(fir::design(cfg.lpf, cfg.internal_rate_hz), &arith::fir_row(&sensor));
        // A unit without the aux accelerometer does not filter its (zero)
        // channels; no output reads them (`Core::take`).
        fir.set_aux_live(has_aux);
        *ahrs = Ahrs::Running;
        *bias = [0.0; 3];
        *bias_failed = false;
        *sat_live = 0;
        *sat_reported = 0;
        *ticks = 0;
        *interval = dt;
        *integrals = I::default();
        *vehicle = None;
        *site = crate::vehicle::Site::of(&Motion::default());
        self.refresh_errors();
    }

    /// The emulated product.
    pub fn product(&self) -> &Product {
        &self.product
    }

    /// The configuration in force.
    #[cfg(feature = "internals")]
    pub fn config(&self) -> &ChainConfig {
        &self.cfg
    }

    /// Applies a configuration (5.3.1: at every data command). See the module
    /// doc: FIR history kept, cascade in steady state, accumulator emptied.
    #[inline(never)]
    pub fn configure(&mut self, cfg: &ChainConfig) {
        self.cfg = *cfg;
        self.fir.set_design(fir::design(cfg.lpf, cfg.internal_rate_hz));
        // The cascade starts in the steady state of the last FIR output
        // (exact for a steady signal).
        self.core.reconfigure(cfg, self.dt);
    }

    /// Chooses a built-in motion, from its initial state (level at its
    /// heading, phase 0), from the next tick on.
    pub fn set_motion(&mut self, m: Motion) {
        self.vehicle = None;
        self.play(m);
    }

    /// A board's vehicle source ([`crate::vehicle`]) for the next tick:
    /// the chain measures `truth` (for the script and full-state sources
    /// `state.truth()`; for rate/force rows the row's own values, so their
    /// bytes stay as they were) and reports `state` as the unit's vehicle
    /// ([`SignalChain::vehicle`]) until the next call or
    /// [`SignalChain::set_motion`].
    pub fn set_vehicle(&mut self, state: VehicleState, truth: Truth) {
        self.play(Motion::Sample(truth));
        self.vehicle = Some(state);
    }

    /// `m` into the core, the site kept with it (a live feed or a vehicle
    /// source sets a sample every tick, always at the same site: not
    /// computed again then).
    fn play(&mut self, m: Motion) {
        if crate::sensor::motion::site(&m) != crate::sensor::motion::site(self.core_motion()) {
            self.site = crate::vehicle::Site::of(&m);
        }
        self.core.set_motion(m, self.dt);
    }

    /// The unit's vehicle now: the state a board's source set
    /// ([`SignalChain::set_vehicle`]), or the built-in motion's
    /// ([`crate::vehicle::builtin_state`]: its site, at rest, its attitude
    /// and its last truth; time = ticks × tick period). Derived when read:
    /// the tick does no `f64` work for it.
    pub fn vehicle(&self) -> VehicleState {
        match &self.vehicle {
            Some(v) => *v,
            None => crate::vehicle::builtin_state(
                &self.site,
                self.core.motion.attitude(),
                &self.core.motion.truth_now(),
                self.ticks as f64 * f64::from(self.dt),
            ),
        }
    }

    /// The state a board's vehicle source set ([`SignalChain::set_vehicle`]),
    /// `None` while a built-in motion plays.
    pub fn vehicle_source(&self) -> Option<&VehicleState> {
        self.vehicle.as_ref()
    }

    /// Which axes the motion describes (default: the unit's own).
    #[cfg(feature = "internals")]
    pub fn set_truth_frame(&mut self, frame: TruthFrame) {
        self.truth_frame = frame;
    }

    /// The built-in motion in force (a board's vehicle source plays as a
    /// [`Motion::Sample`]).
    pub fn core_motion(&self) -> &Motion {
        self.core.motion.motion()
    }

    /// The true attitude of the built-in motion at the last tick (housing or
    /// carrier per [`TruthFrame`], Appendix C convention).
    pub fn truth_attitude(&self) -> Option<Quat> {
        self.core.motion.attitude()
    }

    /// Uses `profile` instead of the built-in one from the next power-on
    /// ([`SignalChain::reset`]) on: the errors are drawn from it with the
    /// seed and its temperature model runs (`None`: the built-in profile).
    /// A host holds its profiles for the process's life (`&'static`), so
    /// the chain keeps a reference, not a copy.
    pub fn set_profile(&mut self, profile: Option<&'static SensorProfile>) {
        self.profile = profile;
    }

    /// The profile set with [`SignalChain::set_profile`], if any.
    pub fn profile(&self) -> Option<&'static SensorProfile> {
        self.profile
    }

    /// The error model, for reading or changing (changes apply at the next
    /// tick).
    #[cfg(feature = "internals")]
    pub fn errors_mut(&mut self) -> &mut ErrorModel {
        self.errors_dirty = true;
        &mut self.errors
    }

    /// The error model in force.
    #[cfg(feature = "internals")]
    pub fn errors(&self) -> &ErrorModel {
        &self.errors
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
        // The FIR's newest input row is the last measurement.
        arith::sensor_of(&self.fir.last_input())
    }

    /// The estimated gyro bias, carrier axes, °/s.
    #[cfg(feature = "internals")]
    pub fn gyro_bias(&self) -> Vec3 {
        self.bias
    }

    /// Whether an initial alignment is running.
    pub(crate) fn is_aligning(&self) -> bool {
        matches!(self.ahrs, Ahrs::Aligning(_))
    }

    /// The attitude filter (tests switch its tilt correction).
    #[cfg(feature = "internals")]
    pub fn attitude_mut(&mut self) -> &mut ChainAttitude {
        &mut self.core.attitude
    }

    /// Seconds the last `SignalChain::output` covered (its ticks × the
    /// tick period): Δθ = gyro × this in the incremental variant.
    #[cfg(feature = "internals")]
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
        self.core.errors_configured();
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
            self.core.temperature_changed(&self.errors, t);
        }
        // Fixed point: one axis a tick (two soft-float products each).
        self.core.temperature_step(&self.errors, self.temperature);
    }

    /// One internal-rate tick with the built-in motion: truth → errors and
    /// saturation → FIR → cascade → variant accumulator, and alignment or
    /// attitude. `now` is the tick's time (handed to the motion source).
    pub fn tick(&mut self, now: Instant) {
        let truth = self.core.builtin_truth(now, self.dt);
        // A truth already within the bounds skips the bounding.
        if self.core.builtin_truth_bounded() {
            return self.process_bounded(&truth);
        }
        self.process(&truth);
    }

    /// One tick with an external motion source (a host's trajectory player)
    /// instead of the built-in motion.
    #[cfg(feature = "internals")]
    pub fn tick_with(&mut self, now: Instant, source: &mut dyn MotionSource) {
        let truth = source.next(now, self.dt);
        self.process(&arith::truth_of(&truth));
    }

    fn process(&mut self, truth: &arith::Truth) {
        self.process_bounded(&arith::bounded(truth));
    }

    /// [`Self::process`] of a truth within the bounds.
    #[inline(always)]
    fn process_bounded(&mut self, truth: &arith::Truth) {
        self.begin_tick(truth.temperature_c);
        let c = &mut self.core;
        // Sensors (sensor axes).
        let sensor = if !self.faults.sensor_comm {
            let (s, over) = c.measure(truth, self.truth_frame, self.has_aux, &mut self.rng);
            self.sat_live |= over;
            s
        } else {
            // Frozen: the FIR's newest input is the last good measurement.
            arith::frozen(&self.fir.last_input())
        };

        // The filters first (they do not depend on the AHRS, nor it
        // on them), so that the AHRS's long chain of dependent products
        // overlaps the encoder's work after the tick instead of the
        // filters' independent ones.
        self.filters(&sensor);
        let c = &mut self.core;

        // AHRS and the integrals on carrier axes, before the FIR.
        let (gc, ac) = c.carrier(&sensor);
        if I::ON {
            let (w, f) = arith::integral_units(&gc, &ac);
            self.integrals.add(&w, &f);
        }
        match &mut self.ahrs {
            Ahrs::Aligning(al) => {
                al.add(&arith::gyro_dps(&gc), &arith::acc_g(&ac), &self.cfg.align);
                c.attitude.note_rate(&gc);
            }
            Ahrs::Running => c.run_attitude(&gc, &ac, &self.bias),
        }
    }

    /// The filters of a tick (sensor axes): FIR → cascade → accumulator.
    #[inline(always)]
    fn filters(&mut self, sensor: &arith::Sensor) {
        let y = self.fir.push(&arith::fir_input(sensor));
        let mut z = y;
        let c = &mut self.core;
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
            Ahrs::Aligning(al) if al.ticks() > 0 => self.core.finish_alignment(al, &self.cfg.align),
            _ => return self.skip_alignment(),
        };
        self.bias_failed = !result.accepted;
        self.set_bias(result.bias_dps);
        self.ahrs = Ahrs::Running;
        self.core.variant.reset();
    }

    /// Initial_Alignment_Time = 0: no bias estimation (bias 0, not failed),
    /// levelled at once from the FIR-filtered accelerometers, heading 0.
    #[cold]
    pub fn skip_alignment(&mut self) {
        self.core.level_now();
        self.bias_failed = false;
        self.set_bias([0.0; 3]);
        self.ahrs = Ahrs::Running;
        self.core.variant.reset();
    }

    #[inline(never)]
    fn set_bias(&mut self, b: Vec3) {
        self.bias = b;
        self.core.set_bias(&b, self.dt);
    }

    /// The orientation now: (quaternion, Euler angles in degrees).
    fn orientation(&self) -> (Quat, Vec3) {
        match &self.ahrs {
            Ahrs::Aligning(al) => arith::aligning_orientation(al),
            Ahrs::Running => (self.core.attitude.quat(), self.core.attitude.euler_deg()),
        }
    }

    /// The output of this output tick: data per the output variant over the
    /// interval since the previous output, in carrier axes; restarts the
    /// interval. See [`Sample`] for units.
    #[cfg(feature = "internals")]
    pub fn output(&mut self) -> Sample {
        self.output_with(true)
    }

    /// Starts a new interval for the per-axis over-range flags of
    /// [`SignalChain::health`] (they cover the last interval and the ticks
    /// since), without taking an output: what a stream that reads no
    /// [`Sample`] (the ISB's integral windows) does at each packet.
    /// [`SignalChain::output_with`] does it too.
    pub fn restart_health_interval(&mut self) {
        self.sat_reported = self.sat_live;
        self.sat_live = 0;
    }

    /// `SignalChain::output`, computing the orientation only if
    /// `attitude` (the frame carries it): without, [`Sample::quat`] is the
    /// identity and [`Sample::euler`] zeros. Nothing else differs; the
    /// orientation has no state of its own to advance.
    pub fn output_with(&mut self, attitude: bool) -> Sample {
        let (o, ticks) = self.core.take(&self.bias, self.has_aux);
        self.interval = ticks as f32 * self.dt;
        self.restart_health_interval();
        let Outputs {
            gyro,
            acc,
            gyro_f,
            acc_f,
            aux,
            aux_f,
        } = o;
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

    /// The health now. The over-range masks cover the interval of the
    /// last `SignalChain::output` and the ticks since, so they read the
    /// same before or after `output()` at an output tick.
    pub fn health(&self) -> Health {
        let f = &self.faults;
        let sat = self.sat_live | self.sat_reported;
        let (lo, hi) = OPERATING_RANGE_C;
        Health {
            sensor_comm_failure: f.sensor_comm || f.motion_feed_lost,
            sensor_config_failure: f.sensor_config,
            gyro_over_range: sat & 0x07,
            accel_over_range: sat >> 3,
            over_temperature: !(lo..=hi).contains(&self.temperature),
            gyro_bit_failed: f.gyro_bit,
            accel_bit_failed: f.accel_bit,
            flash_check_failed: f.flash_check,
            aligning: self.is_aligning(),
            bias_estimation_failed: self.bias_failed,
        }
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
