//! The maths every stage shares, at the bottom of the core: `sensor/`,
//! `ahrs/`, `dsp/` and `chain` import it, it imports none of them, and no
//! stage imports another stage's helpers.
//!
//! - [`trig`]: `f32` trigonometry in `f32` arithmetic, and the `f64`
//!   helpers of the fixed-point configuration maths (re-exported here:
//!   `math::sinf`, `math::exp2i`, …).
//! - [`rotation`]: vectors, matrices and quaternions, the orientation forms
//!   of ICD Appendix C and their conversions, in `f32` and in Q30.
//! - [`fixed`]: the Q-format integer arithmetic of the `fixed-point` build.
//! - [`units`]: g and the fixed-point scales of the sensor signals.
//! - [`decimal`]: decimal numbers in text, without `str::parse`.
//! - [`double`]: `f64` vectors, quaternions and rotation matrices of the
//!   vehicle truth and the navigation outputs.

pub mod decimal;
pub mod double;
pub mod fixed;
pub mod rotation;
pub(crate) mod trig;
pub mod units;

pub use rotation::{Mat3, Quat, Vec3};
pub use trig::{asinf, atan2f, cosf, exp2i, sincos, sincosf, sinf, tanf};
pub use units::{ACC_BITS, G, GYRO_BITS, RATE_TRUTH_LIMIT, TRUTH_LIMIT};
