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

use super::trig::{atan2f, cosf, sinf};
use libm::sqrtf;

/// A 3-vector.
pub type Vec3 = [f32; 3];
/// A 3×3 matrix, row-major: `m[row][col]`, so `m[0][1]` is c₁₂.
pub type Mat3 = [[f32; 3]; 3];
/// A quaternion `[q0, q1, q2, q3]`, q0 the real part (C.3).
pub type Quat = [f32; 4];

/// The identity quaternion.
pub(crate) const QUAT_IDENTITY: Quat = [1.0, 0.0, 0.0, 0.0];
/// The identity matrix.
pub(crate) const MAT3_IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

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
pub(crate) fn mat_t_vec(m: &Mat3, v: &Vec3) -> Vec3 {
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
pub(crate) fn quat_rotate(q: &Quat, v: &Vec3) -> Vec3 {
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
pub(crate) fn quat_rotate_inv(q: &Quat, v: &Vec3) -> Vec3 {
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

    /// `q ← q ⊗ exp(a/2)` for a body-frame rotation vector `a` (rad): the
    /// series for a small one, [`QuatIntegrator::rotate_large`] beyond
    /// [`SERIES_MAX_N2`] (where the series would diverge).
    #[inline]
    pub fn rotate(&mut self, a: &Vec3) {
        let n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        // NaN (a non-finite step) also takes the guarded path.
        if n2 > SERIES_MAX_N2 || n2.is_nan() {
            self.rotate_large(a);
            return;
        }
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

/// Largest |a|² (|a| = 0.1 rad) [`QuatIntegrator::rotate`] turns by the
/// series (truncation below 1e-11); beyond, e.g. an absurd rate such as
/// 1e6 °/s at 2 kHz (8.7 rad a tick), the series diverges, the attitude
/// would grow to ∞ and NaN, and every measured axis with it.
pub(crate) const SERIES_MAX_N2: f32 = 0.01;

impl QuatIntegrator {
    /// `q ← q ⊗ exp(a/2)` for any rotation vector, with trigonometry, in
    /// `f32` only (no soft `f64` on the Cortex-M4F, whose FPU is single
    /// precision: the `f64` form of this function cost the firmware images
    /// 5.7 KiB). The vector is scaled by its largest component before its
    /// length is taken, so no square overflows, and the half angle is
    /// reduced modulo 2π exactly (`fmodf`), so even a step of 3e38 rad keeps
    /// a unit attitude. A non-finite step leaves the attitude unchanged (no
    /// turn is defined). Restarts the compensation.
    #[cold]
    pub(crate) fn rotate_large(&mut self, a: &Vec3) {
        if !(a[0].is_finite() && a[1].is_finite() && a[2].is_finite()) {
            return;
        }
        let m = a[0].abs().max(a[1].abs()).max(a[2].abs());
        if m == 0.0 {
            return;
        }
        let u = [a[0] / m, a[1] / m, a[2] / m];
        // 1 ≤ r ≤ √3, so (m/2)·r ≤ 3e38 stays finite.
        let r = sqrtf(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        let half = libm::fmodf(0.5 * m * r, core::f32::consts::TAU);
        let (s, c) = crate::math::sincosf(half);
        let k = s / r;
        let step = [c, k * u[0], k * u[1], k * u[2]];
        *self = QuatIntegrator::new(quat_normalize(&quat_mul(&self.hi, &step)));
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
pub(crate) fn canonical(q: &Quat) -> Quat {
    if q[0] < 0.0 {
        [-q[0], -q[1], -q[2], -q[3]]
    } else {
        *q
    }
}

/// `a` wrapped into [0, 2π).
pub(crate) fn wrap_2pi(a: f32) -> f32 {
    const TAU: f32 = core::f32::consts::TAU;
    let mut a = small_rem(a, TAU);
    if a < 0.0 {
        a += TAU;
    }
    if a >= TAU {
        a -= TAU;
    }
    a
}

/// `a % m` (`m > 0`) with the usual case, `|a| < m` where the remainder
/// is `a` itself, taken without the library call.
pub(crate) fn small_rem(a: f32, m: f32) -> f32 {
    if -m < a && a < m {
        a
    } else {
        rem(a, m)
    }
}

/// `a % m` out of line: written inline, the compiler evaluates the
/// library call on both sides of [`small_rem`]'s test.
#[cold]
#[inline(never)]
fn rem(a: f32, m: f32) -> f32 {
    a % m
}

// ----- fixed point (the `fixed-point` build) -----

use super::fixed::{atan2_q29, mul64, mul_q30, mul_shr, to_fixed};

/// A quaternion in Q30 (1.0 = 2³⁰).
pub type QuatQ30 = [i32; 4];

/// Q30 of an `f32` quaternion component.
pub fn q30(x: f32) -> i32 {
    to_fixed(x, 30)
}

/// Hamilton product `a ⊗ b` in Q30 (unit quaternions).
#[inline]
pub fn quat_mul_q30(a: &QuatQ30, b: &QuatQ30) -> QuatQ30 {
    let m = mul_q30;
    [
        m(a[0], b[0]) - m(a[1], b[1]) - m(a[2], b[2]) - m(a[3], b[3]),
        m(a[0], b[1]) + m(a[1], b[0]) + m(a[2], b[3]) - m(a[3], b[2]),
        m(a[0], b[2]) - m(a[1], b[3]) + m(a[2], b[0]) + m(a[3], b[1]),
        m(a[0], b[3]) + m(a[1], b[2]) - m(a[2], b[1]) + m(a[3], b[0]),
    ]
}

/// `v` rotated by `q*` (reference → object) for a Q30 unit `q` and
/// |v| ≤ 2²⁹ in any unit: [`quat_rotate_inv`] in integers. Out of line in
/// the `fixed-point` build (small flash: the attitude and the alignment's
/// end share one copy).
#[cfg_attr(feature = "fixed-point", inline(never))]
#[cfg_attr(not(feature = "fixed-point"), inline)]
pub fn quat_rotate_inv_q30(q: &QuatQ30, v: &[i32; 3]) -> [i32; 3] {
    // v + 2 q0 (u × v) + 2 u × (u × v) with u = −(q1, q2, q3).
    let u = [-q[1], -q[2], -q[3]];
    let m = mul_q30;
    let t = [
        2 * (m(u[1], v[2]) - m(u[2], v[1])),
        2 * (m(u[2], v[0]) - m(u[0], v[2])),
        2 * (m(u[0], v[1]) - m(u[1], v[0])),
    ];
    [
        v[0] + m(q[0], t[0]) + m(u[1], t[2]) - m(u[2], t[1]),
        v[1] + m(q[0], t[1]) + m(u[2], t[0]) - m(u[0], t[2]),
        v[2] + m(q[0], t[2]) + m(u[0], t[1]) - m(u[1], t[0]),
    ]
}

/// The reference frame's up axis in object axes (row 3 of (C.4)) for a Q30
/// unit `q`, Q30: also gravity's specific force, in g, at attitude `q`
/// (out of line: two callers, RP2040 flash).
#[inline(never)]
pub fn up_in_body_q30(q: &QuatQ30) -> [i32; 3] {
    let m = mul_q30;
    [
        2 * (m(q[1], q[3]) - m(q[0], q[2])),
        2 * (m(q[2], q[3]) + m(q[0], q[1])),
        (m(q[0], q[0]) + m(q[3], q[3])) - (m(q[1], q[1]) + m(q[2], q[2])),
    ]
}

/// Heading (0..360), pitch, roll in degrees of a Q30 unit quaternion:
/// [`euler_from_quat`] (the same θ = ±90° rule) in integers, the
/// arctangents by CORDIC ([`atan2_q29`], ~1e-8 rad).
pub fn euler_deg_q30(q: &QuatQ30) -> Vec3 {
    let m = mul_q30;
    let [q0, q1, q2, q3] = *q;
    // The (C.4) entries (C.2) needs, Q30, |·| ≤ 1.
    let c01 = 2 * (m(q1, q2) - m(q0, q3));
    let c11 = (m(q0, q0) + m(q2, q2)) - (m(q1, q1) + m(q3, q3));
    let c21 = 2 * (m(q2, q3) + m(q0, q1));
    let horiz = mul64(c01, c01) + mul64(c11, c11);
    const RAD_Q29: f32 = 180.0 / core::f32::consts::PI / 536_870_912.0;
    let (heading, pitch, roll);
    // 1e-10 in Q60, as (C.2)'s float rule.
    if horiz < 115_292_150 {
        let c00 = (m(q0, q0) + m(q1, q1)) - (m(q2, q2) + m(q3, q3));
        let c02 = 2 * (m(q1, q3) + m(q0, q2));
        let sign = if c21 > 0 { -1 } else { 1 };
        heading = atan2_q29(sign * (c02 >> 2), c00 >> 2).0;
        pitch = if c21 > 0 { 843_314_857 } else { -843_314_857 };
        roll = 0;
    } else {
        let c20 = 2 * (m(q1, q3) - m(q0, q2));
        let c22 = (m(q0, q0) + m(q3, q3)) - (m(q1, q1) + m(q2, q2));
        // atan2(c21, √horiz): the first CORDIC gives K·√horiz, so feed the
        // second K·c21 (K the CORDIC gain).
        let (h, k_horiz) = atan2_q29(c01 >> 2, c11 >> 2);
        heading = h;
        let k_c21 = mul_shr(c21 >> 2, crate::math::fixed::CORDIC_GAIN_Q30, 30);
        pitch = atan2_q29(k_c21, k_horiz).0;
        roll = -atan2_q29(c20 >> 2, c22 >> 2).0;
    }
    let mut h = heading as f32 * RAD_Q29;
    if h < 0.0 {
        h += 360.0;
    }
    if h >= 360.0 {
        h -= 360.0;
    }
    [h, pitch as f32 * RAD_Q29, roll as f32 * RAD_Q29]
}

/// [`crate::ahrs::alignment::level_from`] in integers: the heading-0 attitude
/// whose up axis is along the specific force `f` (any scale, |f| < 2³⁰),
/// Q30. Pitch and roll by CORDIC arctangents, the half-angle quaternion by
/// CORDIC rotations (~1e-9 rad); identity for f ≈ 0.
pub fn level_q30(f: &[i32; 3]) -> QuatQ30 {
    use super::fixed::{sin_cos_q30, CORDIC_GAIN_Q30};
    // Normalise to ≤ 2²⁸ (CORDIC input range), keeping the most bits.
    let m = f[0].unsigned_abs() | f[1].unsigned_abs() | f[2].unsigned_abs();
    if m < 16 {
        return [1 << 30, 0, 0, 0];
    }
    let up = m.leading_zeros().saturating_sub(4);
    let down = (32 - m.leading_zeros()).saturating_sub(28);
    let n = |v: i32| (v << up) >> down;
    let (fx, fy, fz) = (n(f[0]), n(f[1]), n(f[2]));
    // roll γ = atan2(−f_x, f_z); the CORDIC's K·√(f_x² + f_z²) …
    let (roll, k_h) = atan2_q29(-fx, fz);
    // … gives pitch θ = atan2(f_y, √(f_x² + f_z²)) against K·f_y.
    let pitch = atan2_q29(mul_shr(fy, CORDIC_GAIN_Q30, 30), k_h).0;
    // Qx(θ) ⊗ Qy(γ) = (cθ cγ, sθ cγ, cθ sγ, sθ sγ) with half angles.
    let (sx, cx) = sin_cos_q30(pitch / 2);
    let (sy, cy) = sin_cos_q30(roll / 2);
    [
        mul_q30(cx, cy),
        mul_q30(sx, cy),
        mul_q30(cx, sy),
        mul_q30(sx, sy),
    ]
}

/// [`QuatIntegrator`] in integers: a unit quaternion in Q62 (`i64`), turned
/// by small body-frame rotations given in Q36 radians.
///
/// The increments are computed from the Q30-rounded attitude (16 exact
/// 32 × 32 → 64 products) and added to the Q62 state, so rates far below
/// the Q30 step (a few °/h at 2 kHz) still integrate — the role Kahan
/// summation plays in the float integrator; the norm is restored every
/// step from the Q62 value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QuatFixed {
    q: [i64; 4],
}

impl QuatFixed {
    /// Starts at Q30 `q`.
    pub const fn from_q30(q: QuatQ30) -> Self {
        QuatFixed {
            q: [
                (q[0] as i64) << 32,
                (q[1] as i64) << 32,
                (q[2] as i64) << 32,
                (q[3] as i64) << 32,
            ],
        }
    }

    /// Starts at `q` (`f32`), normalised (in `f64`, at set-up time).
    pub fn from_f32(q: &Quat) -> Self {
        let v = q.map(f64::from);
        let n = libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        if n.is_nan() || n <= 0.0 || !n.is_finite() {
            return QuatFixed::from_q30([1 << 30, 0, 0, 0]);
        }
        let k = 4_611_686_018_427_387_904.0 / n; // 2⁶²
        QuatFixed {
            q: v.map(|x| libm::round(x * k) as i64),
        }
    }

    /// The attitude, Q30 (rounded; out of line: several callers, flash).
    #[inline(never)]
    pub fn get(&self) -> QuatQ30 {
        let r = |x: i64| ((x + (1 << 31)) >> 32) as i32;
        [r(self.q[0]), r(self.q[1]), r(self.q[2]), r(self.q[3])]
    }

    /// The attitude as `f32` (from the Q30 value: 30 bits, more than the
    /// 24 an `f32` holds).
    pub fn to_f32(&self) -> Quat {
        self.get().map(|x| crate::math::fixed::scaled_f32(x, 30))
    }

    /// `q ← q ⊗ exp(a/2)` for a body-frame rotation vector `a` in Q36
    /// radians (2048 °/s for 0.5 ms is 0.018 rad), with the same
    /// 4th-order series as [`QuatIntegrator::rotate`]. Any `a`: one whose
    /// |a|² does not fit an `i64` (|a| ≥ 0.044 rad; an axis holds at most
    /// 0.031) turns in two halves about the same axis (the same rotation).
    #[inline]
    pub fn rotate(&mut self, a: &[i32; 3]) {
        // Each square < 2⁶², so their sum fits a u64.
        let sq = |x: i32| mul64(x, x) as u64;
        let s = sq(a[0]) + sq(a[1]) + sq(a[2]);
        if s >= 1 << 63 {
            self.rotate_halves(a);
            return;
        }
        self.rotate_by(a, s);
    }

    /// [`QuatFixed::rotate`] of a large `a` as two halves (each |·|² <
    /// 3·2⁶⁰). Cold and out of line: three axes beyond 2924 °/s at 2 kHz.
    #[cold]
    #[inline(never)]
    fn rotate_halves(&mut self, a: &[i32; 3]) {
        let h = a.map(|x| x >> 1);
        let r = [a[0] - h[0], a[1] - h[1], a[2] - h[2]];
        for v in [h, r] {
            let sq = |x: i32| mul64(x, x) as u64;
            self.rotate_by(&v, sq(v[0]) + sq(v[1]) + sq(v[2]));
        }
    }

    /// The series step of [`QuatFixed::rotate`] for `a` with |a|² = `s`
    /// (Q72) < 2⁶³.
    #[inline(always)]
    fn rotate_by(&mut self, a: &[i32; 3], s: u64) {
        // |a|² in Q40 (< 2⁻⁹ rad²).
        let n2 = (s >> 32) as i32;
        // exp(a/2) − 1 = (−n²/8 + n⁴/384, (½ − n²/48)·a): the scalar in
        // Q40; the vector as d2 = (1 − n²/24)·a = 2·(½ − n²/48)·a in Q36,
        // which keeps a exactly (a rate of a few °/h is a few hundred Q36
        // LSB per tick: halving it would round it).
        let n4 = mul_shr(n2, n2, 40);
        let d0 = -(n2 >> 3) + mul_shr(n4, 11_184_811, 32); // 2³²/384
        let n2_24 = mul_shr(n2, 178_956_971, 32); // n²/24, Q40 (2³²/24)
        let d = [
            a[0] - mul_shr(a[0], n2_24, 40),
            a[1] - mul_shr(a[1], n2_24, 40),
            a[2] - mul_shr(a[2], n2_24, 40),
        ];
        let q = self.get();
        // 2·(q ⊗ (d0, d2/2)) in Q66: vector terms Q30·Q36, scalar terms
        // 2·Q30·Q40 = Q70 >> 3.
        let p = mul64;
        let s0 = |x: i32| p(x, d0) >> 3;
        let delta = [
            s0(q[0]) - p(q[1], d[0]) - p(q[2], d[1]) - p(q[3], d[2]),
            p(q[0], d[0]) + s0(q[1]) + p(q[2], d[2]) - p(q[3], d[1]),
            p(q[0], d[1]) - p(q[1], d[2]) + s0(q[2]) + p(q[3], d[0]),
            p(q[0], d[2]) + p(q[1], d[1]) - p(q[2], d[0]) + s0(q[3]),
        ];
        for i in 0..4 {
            self.q[i] += (delta[i] + 16) >> 5;
        }
        self.normalize();
    }

    /// Restores |q| = 1 to first order: q ← q·(1 − (|q|² − 1)/2), |q|²
    /// from the Q62 value (the Q30 part squared plus the cross term).
    #[inline]
    fn normalize(&mut self) {
        let mut n2 = -(1i64 << 60);
        let mut h = [0i32; 4];
        for i in 0..4 {
            h[i] = (self.q[i] >> 32) as i32;
            let l = ((self.q[i] as u64 & 0xFFFF_FFFF) >> 1) as i32;
            n2 += mul64(h[i], h[i]) + (mul64(h[i], l) >> 30);
        }
        // |q|² − 1 in Q60: tiny after every step.
        let e = n2.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
        if e != 0 {
            for i in 0..4 {
                self.q[i] -= mul64(e, h[i]) >> 29;
            }
        }
    }
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

    fn grid() -> impl Iterator<Item = (f32, f32, f32)> {
        [0.0f32, 30.0, 90.0, 179.0, 181.0, 270.0, 359.5]
            .into_iter()
            .flat_map(|h| {
                [-90.0f32, -89.9, -45.0, 0.0, 10.0, 60.0, 89.9, 90.0]
                    .into_iter()
                    .flat_map(move |p| {
                        [-179.0f32, -90.0, -20.0, 0.0, 45.0, 90.0, 135.0, 180.0]
                            .into_iter()
                            .map(move |r| (h, p, r))
                    })
            })
    }

    fn to_q30(q: &Quat) -> QuatQ30 {
        q.map(q30)
    }

    /// Euler angles in integers (CORDIC) agree with (C.7) in float.
    #[test]
    fn fixed_point_euler_angles_match_c7() {
        const D: f32 = core::f32::consts::PI / 180.0;
        for (h, p, r) in grid() {
            let q = quat_from_euler(h * D, p * D, r * D);
            let e = euler_deg_q30(&to_q30(&q));
            let f = euler_from_quat(&q).map(|x| x / D);
            // At θ = ±90° only the matrix is unique: compare matrices.
            let c = dcm_from_euler(e[0] * D, e[1] * D, e[2] * D);
            assert!(
                close(&c, &dcm_from_quat(&q), 2e-5),
                "{h} {p} {r}: {e:?} vs {f:?}"
            );
            if p.abs() < 89.0 {
                let dh = ((e[0] - f[0] + 540.0) % 360.0) - 180.0;
                let dr = ((e[2] - f[2] + 540.0) % 360.0) - 180.0;
                assert!(
                    dh.abs() < 2e-4 && (e[1] - f[1]).abs() < 2e-4 && dr.abs() < 2e-4,
                    "{h} {p} {r}: {e:?} vs {f:?}"
                );
            }
            assert!(e[0] >= 0.0 && e[0] < 360.0);
        }
        assert_eq!(euler_deg_q30(&[1 << 30, 0, 0, 0]), [0.0, 0.0, 0.0]);
    }

    /// Rotations and the up axis in integers agree with the float ones.
    #[test]
    fn fixed_point_rotations_match_float() {
        const D: f32 = core::f32::consts::PI / 180.0;
        for (h, p, r) in grid().step_by(7) {
            let q = quat_from_euler(h * D, p * D, r * D);
            let v = [0.3f32, -0.7, 0.5];
            let k = (1u32 << 28) as f32;
            let vf = quat_rotate_inv(&q, &v);
            let vq = quat_rotate_inv_q30(&to_q30(&q), &v.map(|x| (x * k) as i32));
            for i in 0..3 {
                assert!((vq[i] as f32 / k - vf[i]).abs() < 2e-7, "{h} {p} {r}");
            }
            let u = up_in_body_q30(&to_q30(&q));
            let uf = quat_rotate_inv(&q, &[0.0, 0.0, 1.0]);
            for i in 0..3 {
                assert!((u[i] as f32 / (1u32 << 30) as f32 - uf[i]).abs() < 1e-6);
            }
            let b = quat_from_euler(0.4, -0.2, 0.1);
            let m = quat_mul_q30(&to_q30(&q), &to_q30(&b));
            let mf = quat_mul(&q, &b);
            for i in 0..4 {
                assert!((m[i] as f32 / (1u32 << 30) as f32 - mf[i]).abs() < 1e-6);
            }
        }
    }

    /// The Q62 integrator follows an f64 integration of the same rotation
    /// vectors, also for rates far below the Q30 step.
    #[test]
    fn fixed_point_integrator_tracks_f64() {
        for (rate, ticks) in [
            ([40.0f64, -25.0, 60.0], 20_000),
            ([0.002, 0.0, -0.001], 200_000),
        ] {
            let a = rate.map(|w| w.to_radians() * 0.0005);
            let mut qi = QuatFixed::from_f32(&[1.0, 0.0, 0.0, 0.0]);
            let aq = a.map(|x| libm::round(x * 68_719_476_736.0) as i32);
            let aq64 = aq.map(|x| f64::from(x) / 68_719_476_736.0);
            let mut q = [1.0f64, 0.0, 0.0, 0.0];
            let n = libm::sqrt(aq64[0] * aq64[0] + aq64[1] * aq64[1] + aq64[2] * aq64[2]);
            let (s, c) = (libm::sin(0.5 * n) / n, libm::cos(0.5 * n));
            let d = [c, s * aq64[0], s * aq64[1], s * aq64[2]];
            for _ in 0..ticks {
                qi.rotate(&aq);
                q = [
                    q[0] * d[0] - q[1] * d[1] - q[2] * d[2] - q[3] * d[3],
                    q[0] * d[1] + q[1] * d[0] + q[2] * d[3] - q[3] * d[2],
                    q[0] * d[2] - q[1] * d[3] + q[2] * d[0] + q[3] * d[1],
                    q[0] * d[3] + q[1] * d[2] - q[2] * d[1] + q[3] * d[0],
                ];
            }
            let g = qi.to_f32().map(f64::from);
            let e = [
                q[0] * g[1] - q[1] * g[0] - q[2] * g[3] + q[3] * g[2],
                q[0] * g[2] + q[1] * g[3] - q[2] * g[0] - q[3] * g[1],
                q[0] * g[3] - q[1] * g[2] + q[2] * g[1] - q[3] * g[0],
            ];
            let err = 2.0 * libm::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
            // 10 s at 75 °/s, 100 s at 0.002 °/s: within 3e-7 rad (the
            // f32 read-out alone is ~1e-7).
            assert!(err < 3e-7, "{rate:?}: {err} rad");
        }
    }
}
