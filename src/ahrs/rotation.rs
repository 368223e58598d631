//! Orientation forms of ICD Appendix C: Euler angles, the direction cosine
//! matrix (DCM) and the quaternion, and the conversions (C.1)–(C.7).
//!
//! Conventions (Appendix C, pinned by `tests/signal_attitude.rs`):
//! - The reference frame is ENU (x east, y north, z up); the object frame is
//!   x lateral (right), y longitudinal (forward), z vertical (up).
//! - `C` (the DCM) takes object-frame vectors to the reference frame:
//!   `v_enu = C · v_obj`. In Euler angles (C.1)
//!   `C = Rz(−K) · Rx(θ) · Ry(γ)`: heading K about z, *clockwise* positive,
//!   then pitch θ about the new x, then roll γ about the new y, both
//!   counter-clockwise (right-hand) positive.
//! - The quaternion `Q = (q0, q1, q2, q3)` (C.3) has the DCM (C.4), i.e.
//!   `v_enu = Q ⊗ v_obj ⊗ Q*`, and obeys `Q̇ = ½ Q ⊗ (0, ω_obj)`.
//! - Angles are in radians here; the chain converts to degrees at its edge.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use libm::{atan2f, cosf, sinf, sqrtf};

/// A 3-vector.
pub type Vec3 = [f32; 3];
/// A 3×3 matrix, row-major: `m[row][col]`, so `m[0][1]` is c₁₂.
pub type Mat3 = [[f32; 3]; 3];
/// A quaternion `[q0, q1, q2, q3]`, q0 the real part (C.3).
pub type Quat = [f32; 4];

/// The identity quaternion.
pub const QUAT_IDENTITY: Quat = [1.0, 0.0, 0.0, 0.0];
/// The identity matrix.
pub const MAT3_IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// `m · v`.
#[inline]
pub fn mat_vec(m: &Mat3, v: &Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// `mᵀ · v`.
#[inline]
pub fn mat_t_vec(m: &Mat3, v: &Vec3) -> Vec3 {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// `a · b` (matrix product).
pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    m
}

/// `mᵀ`.
pub fn transpose(m: &Mat3) -> Mat3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

/// `a × b`.
#[inline]
pub fn cross(a: &Vec3, b: &Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a · b`.
#[inline]
pub fn dot(a: &Vec3, b: &Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Hamilton product `a ⊗ b`.
#[inline]
pub fn quat_mul(a: &Quat, b: &Quat) -> Quat {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The conjugate `q*` (the inverse rotation of a unit quaternion).
#[inline]
pub fn quat_conj(q: &Quat) -> Quat {
    [q[0], -q[1], -q[2], -q[3]]
}

/// Rotates `v` by `q`: `q ⊗ (0, v) ⊗ q*` (object → reference for an
/// attitude quaternion).
#[inline]
pub fn quat_rotate(q: &Quat, v: &Vec3) -> Vec3 {
    // v + 2 q0 (u × v) + 2 u × (u × v), u = vector part.
    let u = [q[1], q[2], q[3]];
    let t = cross(&u, v);
    let t = [2.0 * t[0], 2.0 * t[1], 2.0 * t[2]];
    let c = cross(&u, &t);
    [
        v[0] + q[0] * t[0] + c[0],
        v[1] + q[0] * t[1] + c[1],
        v[2] + q[0] * t[2] + c[2],
    ]
}

/// Rotates `v` by `q*` (reference → object).
#[inline]
pub fn quat_rotate_inv(q: &Quat, v: &Vec3) -> Vec3 {
    quat_rotate(&quat_conj(q), v)
}

/// Normalises `q` to unit length (exact, with a square root).
pub fn quat_normalize(q: &Quat) -> Quat {
    let n = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if n > 0.0 {
        [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
    } else {
        QUAT_IDENTITY
    }
}

/// The quaternion of a rotation by `angle` about a unit `axis`.
pub fn quat_axis_angle(axis: &Vec3, angle: f32) -> Quat {
    let (s, c) = (sinf(0.5 * angle), cosf(0.5 * angle));
    [c, s * axis[0], s * axis[1], s * axis[2]]
}

/// The quaternion of the small rotation vector `a` (radians), accurate to
/// the 4th order in |a| — without trigonometry. At the largest step the
/// chain takes (2000 °/s for 0.5 ms, |a| = 0.0175 rad) the truncation is
/// below 1e-12.
#[inline]
pub fn quat_from_rotvec_small(a: &Vec3) -> Quat {
    let n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    // cos(|a|/2) ≈ 1 − n²/8 + n⁴/384; sin(|a|/2)/|a| ≈ ½ − n²/48.
    let c = 1.0 - n2 * (1.0 / 8.0) + n2 * n2 * (1.0 / 384.0);
    let s = 0.5 - n2 * (1.0 / 48.0);
    [c, s * a[0], s * a[1], s * a[2]]
}

/// A unit quaternion integrated by many small body-frame rotations with
/// compensated (Kahan) summation.
///
/// Adding a 1e-4 increment to a component of size ~1 in f32 keeps only about
/// 11 of the increment's bits, and because successive increments are nearly
/// equal the rounding does not average out: a plain f32 integration at
/// 2 kHz drifts by ~2e-4 of the angle turned (0.015° after 90° at 30 °/s).
/// Carrying each component's rounding error in a second f32 brings that
/// below 1e-6 for 16 more floating-point operations per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuatIntegrator {
    hi: Quat,
    lo: Quat,
    steps: u32,
}

impl QuatIntegrator {
    /// Starts at `q` (normalised by the caller).
    pub const fn new(q: Quat) -> Self {
        QuatIntegrator {
            hi: q,
            lo: [0.0; 4],
            steps: 0,
        }
    }

    /// The current attitude.
    #[inline]
    pub fn get(&self) -> Quat {
        self.hi
    }

    /// Replaces the attitude.
    pub fn set(&mut self, q: Quat) {
        *self = QuatIntegrator::new(q);
    }

    /// `q ← q ⊗ exp(a/2)` for a small body-frame rotation vector `a` (rad).
    #[inline]
    pub fn rotate(&mut self, a: &Vec3) {
        let n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        // exp(a/2) − 1, without the cancellation of cos − 1.
        let d = [
            -n2 * (1.0 / 8.0) + n2 * n2 * (1.0 / 384.0),
            (0.5 - n2 * (1.0 / 48.0)) * a[0],
            (0.5 - n2 * (1.0 / 48.0)) * a[1],
            (0.5 - n2 * (1.0 / 48.0)) * a[2],
        ];
        let delta = quat_mul(&self.hi, &d);
        for i in 0..4 {
            let y = delta[i] - self.lo[i];
            let t = self.hi[i] + y;
            self.lo[i] = (t - self.hi[i]) - y;
            self.hi[i] = t;
        }
        self.steps += 1;
        if self.steps >= 64 {
            self.steps = 0;
            let h = &self.hi;
            let k = 1.5 - 0.5 * (h[0] * h[0] + h[1] * h[1] + h[2] * h[2] + h[3] * h[3]);
            for i in 0..4 {
                self.hi[i] *= k;
                self.lo[i] *= k;
            }
        }
    }
}

/// Euler angles (heading K, pitch θ, roll γ; radians) → DCM, formula (C.1).
pub fn dcm_from_euler(heading: f32, pitch: f32, roll: f32) -> Mat3 {
    let (sk, ck) = (sinf(heading), cosf(heading));
    let (st, ct) = (sinf(pitch), cosf(pitch));
    let (sg, cg) = (sinf(roll), cosf(roll));
    [
        [ck * cg + sk * sg * st, sk * ct, ck * sg - sk * cg * st],
        [-sk * cg + ck * sg * st, ck * ct, -sk * sg - ck * cg * st],
        [-ct * sg, st, ct * cg],
    ]
}

/// DCM → Euler angles (K, θ, γ; radians), formula (C.2) with four-quadrant
/// arctangents; K in [0, 2π).
///
/// θ is taken as `atan2(c₃₂, √(c₁₂² + c₂₂²))`, which equals (C.2)'s
/// `asin c₃₂` but keeps full precision near ±90° (where asin of a rounded
/// c₃₂ loses half the digits). At θ = ±90° (c₁₂ = c₂₂ = 0) only K ∓ γ is
/// defined; the emulator then reports γ = 0 and takes K from the first row
/// (`K = atan2(∓c₁₃, c₁₁)`), so that (C.1) of the result gives back the same
/// matrix.
pub fn euler_from_dcm(c: &Mat3) -> Vec3 {
    let horiz = c[0][1] * c[0][1] + c[1][1] * c[1][1];
    let pitch = atan2f(c[2][1], sqrtf(horiz));
    let (heading, roll) = if horiz < 1e-10 {
        let sign = if c[2][1] > 0.0 { 1.0 } else { -1.0 };
        (atan2f(-sign * c[0][2], c[0][0]), 0.0)
    } else {
        (atan2f(c[0][1], c[1][1]), -atan2f(c[2][0], c[2][2]))
    };
    [wrap_2pi(heading), pitch, roll]
}

/// Quaternion → DCM, formula (C.4).
pub fn dcm_from_quat(q: &Quat) -> Mat3 {
    let [q0, q1, q2, q3] = *q;
    [
        [
            q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3,
            2.0 * (q1 * q2 - q0 * q3),
            2.0 * (q1 * q3 + q0 * q2),
        ],
        [
            2.0 * (q1 * q2 + q0 * q3),
            q0 * q0 + q2 * q2 - q1 * q1 - q3 * q3,
            2.0 * (q2 * q3 - q0 * q1),
        ],
        [
            2.0 * (q1 * q3 - q0 * q2),
            2.0 * (q2 * q3 + q0 * q1),
            q0 * q0 + q3 * q3 - q1 * q1 - q2 * q2,
        ],
    ]
}

/// DCM → quaternion, literally (C.6): every magnitude from the diagonal,
/// q0 ≥ 0, the signs of q1..q3 from `c₃₂ − c₂₃`, `c₁₃ − c₃₁`, `c₂₁ − c₁₂`
/// (sign(0) = +).
///
/// Two limits of the formula as printed: a component near zero comes from
/// the square root of a small difference, so in f32 it carries an error up to
/// √ε ≈ 3e-4; and at q0 = 0 (half turns) the signs are undetermined. The
/// emulator therefore uses [`quat_from_dcm`]; this function is kept to pin
/// that both agree.
pub fn quat_from_dcm_c6(c: &Mat3) -> Quat {
    let half_sqrt = |x: f32| 0.5 * sqrtf(x.max(0.0));
    let sign = |d: f32, m: f32| if d >= 0.0 { m } else { -m };
    [
        half_sqrt(1.0 + c[0][0] + c[1][1] + c[2][2]),
        sign(
            c[2][1] - c[1][2],
            half_sqrt(1.0 + c[0][0] - c[1][1] - c[2][2]),
        ),
        sign(
            c[0][2] - c[2][0],
            half_sqrt(1.0 - c[0][0] + c[1][1] - c[2][2]),
        ),
        sign(
            c[1][0] - c[0][1],
            half_sqrt(1.0 - c[0][0] - c[1][1] + c[2][2]),
        ),
    ]
}

/// DCM → quaternion in the form (C.6) defines — q0 ≥ 0, the same quaternion
/// (C.6) gives wherever it is determined — computed without its precision
/// loss (Shepperd's method): the largest component from the diagonal, the
/// others from the off-diagonal sums and differences. At q0 = 0 (half turns,
/// where (C.6) leaves the signs open) the largest vector component is made
/// positive.
pub fn quat_from_dcm(c: &Mat3) -> Quat {
    let tr = c[0][0] + c[1][1] + c[2][2];
    let d = [tr, c[0][0], c[1][1], c[2][2]];
    let mut k = 0;
    for i in 1..4 {
        if d[i] > d[k] {
            k = i;
        }
    }
    let q = if k == 0 {
        let q0 = 0.5 * sqrtf((1.0 + tr).max(0.0));
        let f = 0.25 / q0;
        [
            q0,
            (c[2][1] - c[1][2]) * f,
            (c[0][2] - c[2][0]) * f,
            (c[1][0] - c[0][1]) * f,
        ]
    } else if k == 1 {
        let q1 = 0.5 * sqrtf((1.0 + c[0][0] - c[1][1] - c[2][2]).max(0.0));
        let f = 0.25 / q1;
        [
            (c[2][1] - c[1][2]) * f,
            q1,
            (c[0][1] + c[1][0]) * f,
            (c[0][2] + c[2][0]) * f,
        ]
    } else if k == 2 {
        let q2 = 0.5 * sqrtf((1.0 - c[0][0] + c[1][1] - c[2][2]).max(0.0));
        let f = 0.25 / q2;
        [
            (c[0][2] - c[2][0]) * f,
            (c[0][1] + c[1][0]) * f,
            q2,
            (c[1][2] + c[2][1]) * f,
        ]
    } else {
        let q3 = 0.5 * sqrtf((1.0 - c[0][0] - c[1][1] + c[2][2]).max(0.0));
        let f = 0.25 / q3;
        [
            (c[1][0] - c[0][1]) * f,
            (c[0][2] + c[2][0]) * f,
            (c[1][2] + c[2][1]) * f,
            q3,
        ]
    };
    canonical(&q)
}

/// Quaternion → Euler angles (K, θ, γ; radians), formula (C.7) with the same
/// θ = ±90° rule as [`euler_from_dcm`]; K in [0, 2π).
pub fn euler_from_quat(q: &Quat) -> Vec3 {
    euler_from_dcm(&dcm_from_quat(q))
}

/// Euler angles (radians) → quaternion: `Qz(−K) ⊗ Qx(θ) ⊗ Qy(γ)`, the
/// quaternion of (C.1), returned with q0 ≥ 0.
pub fn quat_from_euler(heading: f32, pitch: f32, roll: f32) -> Quat {
    let qz = [cosf(-0.5 * heading), 0.0, 0.0, sinf(-0.5 * heading)];
    let qx = [cosf(0.5 * pitch), sinf(0.5 * pitch), 0.0, 0.0];
    let qy = [cosf(0.5 * roll), 0.0, sinf(0.5 * roll), 0.0];
    canonical(&quat_mul(&quat_mul(&qz, &qx), &qy))
}

/// `q` or `−q`, whichever has q0 ≥ 0 — the same rotation in the form (C.6)
/// produces.
#[inline]
pub fn canonical(q: &Quat) -> Quat {
    if q[0] < 0.0 {
        [-q[0], -q[1], -q[2], -q[3]]
    } else {
        *q
    }
}

/// `a` wrapped into [0, 2π).
pub fn wrap_2pi(a: f32) -> f32 {
    const TAU: f32 = core::f32::consts::TAU;
    let mut a = a % TAU;
    if a < 0.0 {
        a += TAU;
    }
    if a >= TAU {
        a -= TAU;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Mat3, b: &Mat3, tol: f32) -> bool {
        (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() <= tol))
    }

    #[test]
    fn c1_is_rz_minus_k_rx_theta_ry_gamma() {
        let (k, t, g) = (0.3f32, -0.4f32, 1.1f32);
        let rz = [
            [cosf(k), sinf(k), 0.0],
            [-sinf(k), cosf(k), 0.0],
            [0.0, 0.0, 1.0],
        ];
        let rx = [
            [1.0, 0.0, 0.0],
            [0.0, cosf(t), -sinf(t)],
            [0.0, sinf(t), cosf(t)],
        ];
        let ry = [
            [cosf(g), 0.0, sinf(g)],
            [0.0, 1.0, 0.0],
            [-sinf(g), 0.0, cosf(g)],
        ];
        let c = mat_mul(&mat_mul(&rz, &rx), &ry);
        assert!(close(&c, &dcm_from_euler(k, t, g), 1e-6));
        assert!(close(&c, &dcm_from_quat(&quat_from_euler(k, t, g)), 1e-6));
    }
}
