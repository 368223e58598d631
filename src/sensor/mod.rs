//! What the device measures: truth (motion sources), the sensor error model,
//! temperature, the random source — and [`Sample`], the one record the output
//! formats consume.
//!
//! The signal chain that turns truth into samples lives in
//! [`crate::chain`]; the filters in [`crate::dsp`], alignment and attitude in
//! [`crate::ahrs`].

pub mod profile;
pub mod profiles;

internal! {
    mod bandwidth;
    mod errors;
    mod motion;
    mod rng;
    mod temperature;
}

pub use motion::{BuiltinMotion, Motion, Truth};
// The error engines and the chain's motion seam: the crate's, and its
// tests' with `internals`.
#[cfg(feature = "internals")]
pub use errors::{AxisErrors, ErrorModel, SensorErrors};
#[cfg(not(feature = "internals"))]
pub(crate) use errors::{AxisErrors, ErrorModel, SensorErrors};
#[cfg(feature = "internals")]
pub use motion::{MotionSource, TruthFrame, DEFAULT_LATITUDE_DEG};
#[cfg(not(feature = "internals"))]
pub(crate) use motion::{MotionSource, TruthFrame, DEFAULT_LATITUDE_DEG};
pub use profile::{SensorProfile, SensorSpec, TemperatureSpec};
pub use rng::Rng;

/// One sample of everything the output formats carry, in physical units and
/// carrier axes (ICD 5.2 notes: X lateral, Y longitudinal, Z vertical), after
/// the Alignment_Angles rotation (Appendix B).
///
/// `gyro`, `acc` and `aux_acc` follow the output variant (ICD 5.3.6, see
/// [`crate::dsp::variant`]): instant, the average over the output interval,
/// or — incremental — the angle / velocity increment over the interval
/// *divided by the interval* (5.3.6: "divided by the time step of data
/// output"), so the units stay °/s and g in every variant and the encoders
/// need not know the variant. `gyro · T` is Δθ in degrees and `acc · T` is
/// Δv in g·s (T = `SignalChain::output_interval`) for a
/// host that wants Table 5.15's "deg·KG" / "g·s·KA" literally.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Angular rates, deg/s.
    pub gyro: [f32; 3],
    /// Specific force of the main accelerometer, g (9.8106 m/s², ICD 5.2.1).
    pub acc: [f32; 3],
    /// Specific force of the aux (high-g) accelerometer, g; zero without one.
    pub aux_acc: [f32; 3],
    /// Heading (0..360, clockwise), pitch, roll in degrees (Appendix C
    /// conventions). Heading is relative: 0 at the end of the initial
    /// alignment (the KERNEL has no magnetometer).
    pub euler: [f32; 3],
    /// Orientation quaternion q0..q3 (Appendix C.3) in the (C.6) form: q0 ≥ 0.
    pub quat: [f32; 4],
    /// Bias-compensated, cascade-filtered angular rates, deg/s (UDD 0x2D).
    pub gyro_filtered: [f32; 3],
    /// Estimated gyro bias, deg/s (UDD 0x2E).
    pub gyro_bias: [f32; 3],
    /// Cascade-filtered main accelerometer, g (UDD 0x91).
    pub acc_filtered: [f32; 3],
    /// Cascade-filtered aux accelerometer, g (UDD 0x92).
    pub aux_acc_filtered: [f32; 3],
    /// Average gyro temperature, °C.
    pub temperature: f32,
    /// Supply voltage, V.
    pub supply_voltage: f32,
}

impl Sample {
    /// Static, level, Z up, heading 0, 25 °C, 12 V.
    pub const STATIC_LEVEL: Sample = Sample {
        gyro: [0.0; 3],
        acc: [0.0, 0.0, 1.0],
        aux_acc: [0.0, 0.0, 1.0],
        gyro_filtered: [0.0; 3],
        gyro_bias: [0.0; 3],
        acc_filtered: [0.0, 0.0, 1.0],
        aux_acc_filtered: [0.0, 0.0, 1.0],
        euler: [0.0; 3],
        quat: [1.0, 0.0, 0.0, 0.0],
        temperature: 25.0,
        supply_voltage: 12.0,
    };
}
