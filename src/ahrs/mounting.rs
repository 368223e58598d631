//! Mounting of the unit in the carrier: the Alignment_Angles of ICD
//! Appendix B (Table 5.24 ID 0x023A).
//!
//! The three angles describe the IMU's rotation relative to the carrier in
//! the order and with the signs of Appendix B — heading about Z, clockwise
//! positive; then pitch about X, counter-clockwise positive; then roll about
//! Y, counter-clockwise positive — which is exactly the Euler convention of
//! Appendix C with the IMU as the "object" and the carrier as the
//! "reference". So the sensor-to-carrier matrix is (C.1) of the angles:
//!
//! ```text
//! v_carrier = M · v_sensor,   M = Rz(−heading) · Rx(pitch) · Ry(roll)
//! ```
//!
//! The Figure B.1 examples (pinned by `tests/signal_mounting.rs`):
//!
//! | angles (h p r) | unit | sensor X → | sensor Y → | sensor Z → |
//! |---|---|---|---|---|
//! | 0 0 0 | parallel to the carrier | +X | +Y | +Z |
//! | 0 0 180 | upside down (rolled about the longitudinal axis) | −X | +Y | −Z |
//! | −90 0 0 | turned 90° counter-clockwise seen from above | +Y | −X | +Z |
//! | 0 0 90 | rolled 90° right side down | −Z | +Y | +X |

use crate::math::rotation::{dcm_from_euler, mat_t_vec, mat_vec, Mat3, Vec3, MAT3_IDENTITY};

const DEG: f32 = core::f32::consts::PI / 180.0;

/// The sensor → carrier rotation of a set of alignment angles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mounting {
    m: Mat3,
    identity: bool,
    angles_deg: Vec3,
}

impl Default for Mounting {
    fn default() -> Self {
        Mounting::from_angles_deg([0.0; 3])
    }
}

impl Mounting {
    /// From Alignment_Angles `[heading, pitch, roll]` in degrees.
    pub fn from_angles_deg(angles: Vec3) -> Self {
        let m = dcm_from_euler(angles[0] * DEG, angles[1] * DEG, angles[2] * DEG);
        // Snap to exact 0/±1: angles such as 90° or 180° give cos = −4e-8,
        // and an exact permutation keeps the axis mapping exact.
        let mut snapped = m;
        for row in snapped.iter_mut() {
            for x in row.iter_mut() {
                if x.abs() < 1e-6 {
                    *x = 0.0;
                } else if (x.abs() - 1.0).abs() < 1e-6 {
                    *x = x.signum();
                }
            }
        }
        Mounting {
            m: snapped,
            identity: snapped == MAT3_IDENTITY,
            angles_deg: angles,
        }
    }

    /// The matrix M (sensor → carrier).
    pub fn matrix(&self) -> &Mat3 {
        &self.m
    }

    /// The angles it was built from, degrees.
    pub fn angles_deg(&self) -> Vec3 {
        self.angles_deg
    }

    /// Whether M is the identity (no work per tick).
    pub fn is_identity(&self) -> bool {
        self.identity
    }

    /// Sensor axes → carrier axes.
    #[inline]
    pub fn to_carrier(&self, v: &Vec3) -> Vec3 {
        if self.identity {
            *v
        } else {
            mat_vec(&self.m, v)
        }
    }

    /// Carrier axes → sensor axes.
    #[inline]
    pub fn to_sensor(&self, v: &Vec3) -> Vec3 {
        if self.identity {
            *v
        } else {
            mat_t_vec(&self.m, v)
        }
    }
}

/// [`Mounting`] in Q30 for the `fixed-point` build (the snapped 0/±1
/// entries stay exact, so axis permutations map integers exactly).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MountingFixed {
    m: [[i32; 3]; 3],
    identity: bool,
}

impl MountingFixed {
    /// The Q30 matrix of `m`.
    pub fn new(m: &Mounting) -> Self {
        MountingFixed {
            m: m.matrix().map(|row| row.map(crate::math::rotation::q30)),
            identity: m.is_identity(),
        }
    }

    /// Sensor axes → carrier axes (any `v`: summed in `i64`, saturated).
    #[inline]
    pub fn to_carrier(&self, v: &[i32; 3]) -> [i32; 3] {
        if self.identity {
            return *v;
        }
        let m = &self.m;
        [
            dot(m[0][0], m[0][1], m[0][2], v),
            dot(m[1][0], m[1][1], m[1][2], v),
            dot(m[2][0], m[2][1], m[2][2], v),
        ]
    }

    /// Carrier axes → sensor axes (any `v`: summed in `i64`, saturated).
    #[inline]
    pub fn to_sensor(&self, v: &[i32; 3]) -> [i32; 3] {
        if self.identity {
            return *v;
        }
        let m = &self.m;
        [
            dot(m[0][0], m[1][0], m[2][0], v),
            dot(m[0][1], m[1][1], m[2][1], v),
            dot(m[0][2], m[1][2], m[2][2], v),
        ]
    }
}

/// `a·v₀ + b·v₁ + c·v₂` of Q30 entries (|·| ≤ 1), each product as
/// [`mul_q30`](crate::math::fixed::mul_q30) (exact in 32 bits for
/// |v| < 2³¹: `i32::MIN` is raised by one), the sum in `i64` and saturated
/// to the `i32`: a rotated vector's component is bounded by its norm, and
/// three axes at the IMX-5's 4000 °/s have a norm of 1.7·2³¹ at
/// `GYRO_BITS`. Identical to the 32-bit sum wherever that fits.
#[inline(always)]
fn dot(a: i32, b: i32, c: i32, v: &[i32; 3]) -> i32 {
    let p = |m: i32, x: i32| i64::from(crate::math::fixed::mul_q30(m, x.max(-i32::MAX)));
    let s = p(a, v[0]) + p(b, v[1]) + p(c, v[2]);
    s.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}
