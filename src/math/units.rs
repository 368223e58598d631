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
/// Truth entering the fixed-point engine is clamped to ±2³⁰ (2048 °/s,
/// 128 g: beyond every range, so the saturation flags still see it), and
/// each entry of M − I to ±¼, so M·truth cannot overflow.
pub const TRUTH_LIMIT: i32 = 1 << 30;
