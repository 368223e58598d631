//! The units and fixed-point scales of the sensor signals, shared by the
//! motion sources ([`crate::sensor::motion`], which produce truth in them),
//! the error model ([`crate::sensor::errors`], which measures it), the AHRS
//! and the integrals: none of them needs another for them.

/// g in m/s², as the ICD defines it (Table 5.5 note 1).
pub const G: f32 = 9.8106;

/// Fraction bits of the fixed-point gyro measurement: 2¹⁹ per °/s (LSB
/// 1.9e-6 °/s; ±4096 °/s fit an `i32`).
pub const GYRO_BITS: u32 = 19;
/// Fraction bits of the fixed-point accelerometer measurements: 2²³ per g
/// (LSB 1.2e-7 g; ±256 g fit an `i32`).
pub const ACC_BITS: u32 = 23;
/// Specific force entering the fixed-point engine is clamped to ±2³⁰
/// (128 g: beyond every accelerometer range, so the saturation flags still
/// see it).
pub const TRUTH_LIMIT: i32 = 1 << 30;
/// The rate truth entering the fixed-point engine is clamped to
/// ±4095 °/s (the `i32` at [`GYRO_BITS`] holds ±4096 °/s): beyond every
/// gyro range (the IMX-5's ±4000 °/s), so the over-range flag still sees
/// it. The steps on the rate path compute in `i64` where a result can
/// exceed an `i32` and saturate (docs/sensors.md "Fixed point").
pub const RATE_TRUTH_LIMIT: i32 = 4095 << GYRO_BITS;
