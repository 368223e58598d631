//! `f64` vectors, quaternions and rotation matrices: what the vehicle
//! truth (`crate::vehicle`) and the navigation outputs (`crate::isb::nav`)
//! compute positions and attitudes with. Quaternions are scalar first,
//! Hamilton; a rotation matrix `C` of `q` maps `v' = C v = q ⊗ v ⊗ q*`.

use libm::{atan2, cos, sin, sqrt};

/// A 3-vector in `f64`.
pub type V3 = [f64; 3];
/// A unit quaternion in `f64`, scalar first.
pub type Q4 = [f64; 4];

/// `a + b`.
pub fn add(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a · k`.
pub fn scale(a: &V3, k: f64) -> V3 {
    [a[0] * k, a[1] * k, a[2] * k]
}

/// `a × b`.
pub fn cross(a: &V3, b: &V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Hamilton product `a ⊗ b`.
pub fn quat_mul(a: &Q4, b: &Q4) -> Q4 {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The conjugate (inverse of a unit quaternion).
pub fn quat_conj(q: &Q4) -> Q4 {
    [q[0], -q[1], -q[2], -q[3]]
}

/// `q` scaled to unit length, q0 ≥ 0 (the identity for a zero or
/// non-finite `q`).
pub fn quat_normalize(q: &Q4) -> Q4 {
    let n = sqrt(q.iter().map(|x| x * x).sum::<f64>());
    if !(n > 0.0 && n.is_finite()) {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let k = if q[0] < 0.0 { -1.0 / n } else { 1.0 / n };
    q.map(|x| x * k)
}

/// `v` rotated by `q` (`q ⊗ v ⊗ q*`).
pub fn rotate(q: &Q4, v: &V3) -> V3 {
    let c = dcm_from_quat(q);
    [
        c[0][0] * v[0] + c[0][1] * v[1] + c[0][2] * v[2],
        c[1][0] * v[0] + c[1][1] * v[1] + c[1][2] * v[2],
        c[2][0] * v[0] + c[2][1] * v[1] + c[2][2] * v[2],
    ]
}

/// `v` rotated by `q*` (`q* ⊗ v ⊗ q`).
pub fn rotate_inv(q: &Q4, v: &V3) -> V3 {
    rotate(&quat_conj(q), v)
}

/// The rotation of rotation vector `a` (rad) as a quaternion.
pub fn quat_from_rotvec(a: &V3) -> Q4 {
    let th = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    let half = 0.5 * th;
    // sin(θ/2)/θ, its series near 0.
    let k = if th < 1e-6 {
        0.5 - th * th / 48.0
    } else {
        sin(half) / th
    };
    [cos(half), a[0] * k, a[1] * k, a[2] * k]
}

/// The rotation vector (rad) of unit quaternion `q` (angle ≤ π).
pub fn rotvec_from_quat(q: &Q4) -> V3 {
    let q = quat_normalize(q);
    let s = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    let th = 2.0 * atan2(s, q[0]);
    let k = if s < 1e-12 { 2.0 } else { th / s };
    [q[1] * k, q[2] * k, q[3] * k]
}

/// The rotation matrix of unit quaternion `q`.
pub fn dcm_from_quat(q: &Q4) -> [V3; 3] {
    let [a, b, c, d] = *q;
    [
        [
            a * a + b * b - c * c - d * d,
            2.0 * (b * c - a * d),
            2.0 * (b * d + a * c),
        ],
        [
            2.0 * (b * c + a * d),
            a * a - b * b + c * c - d * d,
            2.0 * (c * d - a * b),
        ],
        [
            2.0 * (b * d - a * c),
            2.0 * (c * d + a * b),
            a * a - b * b - c * c + d * d,
        ],
    ]
}

/// The unit quaternion (q0 ≥ 0) of rotation matrix `m` (Shepperd's
/// method: the largest of the four candidates, so no component loses
/// precision).
pub fn quat_from_dcm(m: &[V3; 3]) -> Q4 {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let q = if tr > m[0][0] && tr > m[1][1] && tr > m[2][2] {
        let s = 2.0 * sqrt(1.0 + tr);
        [
            0.25 * s,
            (m[2][1] - m[1][2]) / s,
            (m[0][2] - m[2][0]) / s,
            (m[1][0] - m[0][1]) / s,
        ]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = 2.0 * sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]);
        [
            (m[2][1] - m[1][2]) / s,
            0.25 * s,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
        ]
    } else if m[1][1] > m[2][2] {
        let s = 2.0 * sqrt(1.0 - m[0][0] + m[1][1] - m[2][2]);
        [
            (m[0][2] - m[2][0]) / s,
            (m[0][1] + m[1][0]) / s,
            0.25 * s,
            (m[1][2] + m[2][1]) / s,
        ]
    } else {
        let s = 2.0 * sqrt(1.0 - m[0][0] - m[1][1] + m[2][2]);
        [
            (m[1][0] - m[0][1]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            0.25 * s,
        ]
    };
    quat_normalize(&q)
}

/// Roll φ, pitch θ, yaw ψ (rad) → body → NED quaternion
/// (`Rz(ψ) Ry(θ) Rx(φ)`), q0 ≥ 0.
pub fn quat_from_euler(roll: f64, pitch: f64, yaw: f64) -> Q4 {
    let qz = [cos(0.5 * yaw), 0.0, 0.0, sin(0.5 * yaw)];
    let qy = [cos(0.5 * pitch), 0.0, sin(0.5 * pitch), 0.0];
    let qx = [cos(0.5 * roll), sin(0.5 * roll), 0.0, 0.0];
    quat_normalize(&quat_mul(&quat_mul(&qz, &qy), &qx))
}

/// Body → NED quaternion → roll, pitch, yaw (rad; yaw in (−π, π]).
pub fn euler_from_quat(q: &Q4) -> V3 {
    let c = dcm_from_quat(q);
    let pitch = atan2(-c[2][0], sqrt(c[2][1] * c[2][1] + c[2][2] * c[2][2]));
    let roll = atan2(c[2][1], c[2][2]);
    let yaw = atan2(c[1][0], c[0][0]);
    [roll, pitch, yaw]
}

/// The body rate relative to NED (rad/s, body axes) of Euler angles
/// `(φ, θ, ψ)` changing at `(φ̇, θ̇, ψ̇)`.
pub fn body_rate_of_euler(e: &V3, rates: &V3) -> V3 {
    let (sf, cf) = (sin(e[0]), cos(e[0]));
    let (st, ct) = (sin(e[1]), cos(e[1]));
    [
        rates[0] - rates[2] * st,
        rates[1] * cf + rates[2] * ct * sf,
        -rates[1] * sf + rates[2] * ct * cf,
    ]
}

/// `x` wrapped into (−π, π].
pub fn wrap_pi(x: f64) -> f64 {
    // Already inside (what a navigation period's longitude nearly always
    // is): no `fmod` in soft double precision.
    if x > -core::f64::consts::PI && x <= core::f64::consts::PI {
        return x;
    }
    let tau = core::f64::consts::TAU;
    let mut y = libm::fmod(x, tau);
    if y > core::f64::consts::PI {
        y -= tau;
    } else if y <= -core::f64::consts::PI {
        y += tau;
    }
    y
}
