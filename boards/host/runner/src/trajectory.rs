//! Trajectory replay (`--trajectory FILE`): the motion the device measures
//! read from a CSV file instead of a built-in motion source.
//!
//! One sample per line: `time_s, wx, wy, wz, fx, fy, fz[, temp_c]` — time in
//! seconds from the start, angular rate in °/s and specific force in g
//! (g = 9.8106 m/s², ICD 5.2.1; at rest +1 g along up), in the unit's axes,
//! optionally the sensor temperature in °C. Blank lines, lines starting with
//! `#` and a first line that is not numeric (a header) are skipped; times
//! must increase. Between samples the values are interpolated linearly;
//! before the first sample the first holds, after the last the last holds
//! (or, with `--trajectory-loop`, the file starts over).
//!
//! The vehicle state of such a file (`truth`, docs/motion.md) is the
//! strapdown integration of its values ([`Trajectory::vehicle_at`]) from
//! the built-in motions' site (Newlyn, 50.1° N, at rest, heading 0); the truth the
//! chain measures stays the file's values, byte for byte.

use std::path::Path;

use anyhow::{bail, Context as _};
use imu_emu::sensor::{Motion, Truth};
use imu_emu::vehicle::{housing_to_body, Strapdown, VehicleState, G_ICD};

/// A loaded trajectory.
#[derive(Debug, Clone)]
pub struct Trajectory {
    rows: Vec<(f64, Truth)>,
    looped: bool,
    /// Index of the row at or before the last time asked (times only grow).
    cursor: usize,
    /// The vehicle integrated from the file's values, and the time of its
    /// last step, s ([`Trajectory::vehicle_at`]).
    vehicle: Option<(Strapdown, f64)>,
}

/// A file value as `f32`, saturated at ±`f32::MAX` (3.5e38 would become
/// ∞; the sensor model then saturates it at its range like any value
/// beyond it).
fn to_f32(v: f64) -> f32 {
    v.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32
}

impl Trajectory {
    /// Reads and parses `path`.
    pub fn load(path: &Path, looped: bool) -> anyhow::Result<Self> {
        let text = crate::vehicle::read_motion_file(path, "trajectory")?;
        Self::parse(&text, looped).with_context(|| format!("in {}", path.display()))
    }

    /// Parses CSV text (see the module docs).
    pub fn parse(text: &str, looped: bool) -> anyhow::Result<Self> {
        let mut rows: Vec<(f64, Truth)> = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let numbers: Result<Vec<f64>, _> = cells.iter().map(|c| c.parse::<f64>()).collect();
            let Ok(v) = numbers else {
                if rows.is_empty() && i == 0 {
                    continue; // a header
                }
                bail!("line {}: not a number in {line:?}", i + 1);
            };
            if !(v.len() == 7 || v.len() == 8) || v.iter().any(|x| !x.is_finite()) {
                bail!(
                    "line {}: expected 7 or 8 finite numbers, got {line:?}",
                    i + 1
                );
            }
            if let Some((t, _)) = rows.last() {
                if v[0] <= *t {
                    bail!("line {}: time {} does not increase", i + 1, v[0]);
                }
            }
            let truth = Truth {
                rate_dps: [to_f32(v[1]), to_f32(v[2]), to_f32(v[3])],
                specific_force_g: [to_f32(v[4]), to_f32(v[5]), to_f32(v[6])],
                temperature_c: v.get(7).map(|&t| to_f32(t)),
            };
            rows.push((v[0], truth));
        }
        if rows.is_empty() {
            bail!("no samples");
        }
        Ok(Trajectory {
            rows,
            looped,
            cursor: 0,
            vehicle: None,
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there are no samples (never, once parsed).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The truth at `t` seconds (as [`Trajectory::at`]) and the vehicle
    /// state it integrates to: a strapdown of the file's rates and forces
    /// (housing axes → body axes, °/s → rad/s, g → m/s²) from the built-in
    /// motions' default site at rest, one step per call.
    pub fn vehicle_at(&mut self, t: f64) -> (VehicleState, Truth) {
        let truth = self.at(t);
        let w = housing_to_body(&truth.rate_dps.map(|x| f64::from(x).to_radians()));
        let f = housing_to_body(&truth.specific_force_g.map(|x| f64::from(x) * G_ICD));
        let (sd, last) = self.vehicle.get_or_insert_with(|| {
            let site = Motion::default();
            let at_rest = imu_emu::sensor::BuiltinMotion::new(site, 1.0).truth_now();
            let site = imu_emu::vehicle::Site::of(&site);
            let mut start = imu_emu::vehicle::builtin_state(&site, None, &at_rest, t);
            start.rate_ib_b = w;
            start.force_b = f;
            (Strapdown::new(start), t)
        });
        if t > *last {
            sd.step(&w, &f, truth.temperature_c, t - *last);
            *last = t;
        }
        let mut s = *sd.state();
        s.time_s = t;
        (s, truth)
    }

    /// The truth at `t` seconds since the start; `t` never decreases between
    /// calls (the cursor only moves forward).
    pub fn at(&mut self, t: f64) -> Truth {
        let first = self.rows[0].0;
        let last = self.rows[self.rows.len() - 1].0;
        let mut t = t;
        if self.looped && t > last && last > first {
            t = first + (t - first) % (last - first);
            if t < self.rows[self.cursor].0 {
                self.cursor = 0;
            }
        }
        if t <= first {
            return self.rows[0].1;
        }
        if t >= last {
            return self.rows[self.rows.len() - 1].1;
        }
        while self.rows[self.cursor + 1].0 < t {
            self.cursor += 1;
        }
        let (t0, a) = self.rows[self.cursor];
        let (t1, b) = self.rows[self.cursor + 1];
        imu_emu::feed::lerp_truth(&a, &b, ((t - t0) / (t1 - t0)) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CSV: &str = "time,wx,wy,wz,fx,fy,fz,temp\n\
                       # a comment\n\
                       0.0, 0, 0, 0, 0, 0, 1, 20\n\
                       1.0, 10, 0, 0, 0, 0, 1, 30\n\
                       2.0, 10, 0, 0, 0.5, 0, 1\n";

    #[test]
    fn parses_interpolates_and_holds() {
        let mut t = Trajectory::parse(CSV, false).unwrap();
        assert_eq!(t.len(), 3);
        assert_eq!(t.at(0.0).rate_dps, [0.0, 0.0, 0.0]);
        let mid = t.at(0.5);
        assert_eq!(mid.rate_dps, [5.0, 0.0, 0.0]);
        assert_eq!(mid.temperature_c, Some(25.0));
        assert_eq!(t.at(1.5).specific_force_g, [0.25, 0.0, 1.0]);
        assert_eq!(t.at(1.5).temperature_c, Some(30.0));
        assert_eq!(t.at(9.0).specific_force_g, [0.5, 0.0, 1.0]);
    }

    /// A file that measures rest at the default site keeps the vehicle
    /// there; the truth handed on is the file's.
    #[test]
    fn the_vehicle_of_a_file_at_rest_stays() {
        let rest = imu_emu::sensor::Truth::at_rest();
        let w = rest.rate_dps;
        let line = |t: f64| format!("{t},{},{},{},0,0,1\n", w[0], w[1], w[2]);
        let mut t = Trajectory::parse(&(line(0.0) + &line(600.0)), false).unwrap();
        let (s0, _) = t.vehicle_at(0.0);
        let mut last = s0;
        for k in 1..=120_000 {
            let (s, truth) = t.vehicle_at(f64::from(k) * 0.005);
            assert_eq!(truth.specific_force_g, [0.0, 0.0, 1.0]);
            last = s;
        }
        let north = (last.lat_rad - s0.lat_rad) * 6.37e6;
        assert!(
            north.abs() < 1.0 && (last.height_m - s0.height_m).abs() < 1.0,
            "{last:?}"
        );
        assert!(last.vel_ned.iter().all(|v| v.abs() < 0.05), "{last:?}");
    }

    #[test]
    fn loops_when_asked() {
        let mut t = Trajectory::parse(CSV, true).unwrap();
        assert_eq!(t.at(2.5).rate_dps, [5.0, 0.0, 0.0]);
        assert_eq!(t.at(3.5).rate_dps, [10.0, 0.0, 0.0]);
    }

    #[test]
    fn rejects_bad_files() {
        assert!(Trajectory::parse("", false).is_err());
        assert!(Trajectory::parse("0,1,2,3\n", false).is_err());
        assert!(Trajectory::parse("0,0,0,0,0,0,1\n0,0,0,0,0,0,1\n", false).is_err());
        assert!(Trajectory::parse("0,0,0,0,0,0,1\nx,0,0,0,0,0,1\n", false).is_err());
        assert!(Trajectory::parse("0,0,0,0,0,0,NaN\n", false).is_err());
    }

    #[test]
    fn values_beyond_f32_saturate_and_interpolate_finitely() {
        let mut t =
            Trajectory::parse("0,3.5e38,-1e300,0,0,0,1\n1,3.5e38,1e300,0,0,0,1\n", false).unwrap();
        let m = f32::MAX;
        assert_eq!(t.at(0.0).rate_dps, [m, -m, 0.0]);
        let mid = t.at(0.5).rate_dps;
        assert_eq!(mid[0], m);
        assert!(mid[1].is_finite() && mid[1].abs() < 1e30, "{mid:?}");
        assert_eq!(t.at(0.75).rate_dps[1], m / 2.0);
    }
}
