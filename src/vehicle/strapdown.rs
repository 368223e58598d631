//! The state of a vehicle known only by what its IMU measures (the
//! rate/force rows of `--trajectory`): a strapdown integration of ω_ib^b
//! and f^b from a start state (docs/motion.md, "Rate/force rows").
//!
//! One step a tick, from the previous sample to the new one: the body
//! rotation from the mean of the two rates with the coning term, the
//! specific force rotated at both ends and averaged, gravity, Coriolis and
//! the frame rates at the step's start, the position trapezoidal —
//! second order, well under a metre over minutes at the internal rates
//! (2–4 kHz), and exactly at rest for samples that measure rest.

use super::{
    add, cross, quat_from_rotvec, quat_mul, quat_normalize, rotate, scale, wgs84, wrap_pi,
    VehicleState, V3,
};
use libm::cos;

/// A strapdown integrator holding the state it has reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Strapdown {
    state: VehicleState,
}

impl Strapdown {
    /// Starts at `start` (its rates and forces are the first measurement).
    pub fn new(start: VehicleState) -> Self {
        Strapdown { state: start }
    }

    /// The state reached.
    pub fn state(&self) -> &VehicleState {
        &self.state
    }

    /// Moves on by `dt` seconds to a sample measuring `rate_ib_b` (rad/s)
    /// and `force_b` (m/s²), body axes (the state's measurement is the
    /// sample at the step's start); the state's measurement becomes them
    /// and its temperature `temperature_c`.
    pub fn step(&mut self, rate_ib_b: &V3, force_b: &V3, temperature_c: Option<f32>, dt: f64) {
        let s = &mut self.state;
        let wie = wgs84::earth_rate_ned(s.lat_rad);
        let wen = wgs84::transport_rate_ned(s.lat_rad, s.height_m, &s.vel_ned);
        let win = add(&wie, &wen);
        let (w0, f0) = (s.rate_ib_b, s.force_b);
        // Body rotation: mean rate plus the coning term (ω₀ × ω₁) dt²/12.
        let rot = add(
            &scale(&add(&w0, rate_ib_b), 0.5 * dt),
            &scale(&cross(&w0, rate_ib_b), dt * dt / 12.0),
        );
        let q0 = s.q_nb;
        let body = quat_from_rotvec(&rot);
        let nav = quat_from_rotvec(&scale(&win, -dt));
        let q1 = quat_normalize(&quat_mul(&nav, &quat_mul(&q0, &body)));
        let f_n = scale(&add(&rotate(&q0, &f0), &rotate(&q1, force_b)), 0.5);
        let cor = cross(&add(&scale(&wie, 2.0), &wen), &s.vel_ned);
        let g = wgs84::normal_gravity(s.lat_rad, s.height_m);
        let acc = [f_n[0] - cor[0], f_n[1] - cor[1], f_n[2] - cor[2] + g];
        let v0 = s.vel_ned;
        let v1 = add(&v0, &scale(&acc, dt));
        let vm = scale(&add(&v0, &v1), 0.5);
        let (m, n) = wgs84::radii(s.lat_rad);
        s.lat_rad += vm[0] / (m + s.height_m) * dt;
        s.lon_rad = wrap_pi(s.lon_rad + vm[1] / ((n + s.height_m) * cos(s.lat_rad)) * dt);
        s.height_m -= vm[2] * dt;
        s.vel_ned = v1;
        s.q_nb = q1;
        s.rate_ib_b = *rate_ib_b;
        s.force_b = *force_b;
        s.temperature_c = temperature_c;
        s.time_s += dt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a vehicle at rest measures keeps it at rest.
    #[test]
    fn rest_stays_at_rest() {
        let start = VehicleState::at_rest(0.7, 0.1, 50.0, 1.0);
        let mut sd = Strapdown::new(start);
        for _ in 0..120_000 {
            sd.step(&start.rate_ib_b, &start.force_b, None, 0.0005);
        }
        let s = sd.state();
        let (m, _) = wgs84::radii(0.7);
        assert!((s.lat_rad - 0.7).abs() * m < 0.01, "{s:?}");
        assert!((s.height_m - 50.0).abs() < 0.01, "{s:?}");
        assert!(s.vel_ned.iter().all(|v| v.abs() < 1e-3), "{s:?}");
        assert!((s.euler_rad()[2] - 1.0).abs() < 1e-7, "{s:?}");
    }
}
