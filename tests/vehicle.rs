//! Self-consistency of the vehicle truth: for each motion
//! source, a strapdown integration of the ideal sensor output — the truth
//! the chain takes, as `f32` (float build) and as the fixed-point build's
//! integers — reproduces the source's own position, velocity and attitude
//! within 1 m, 0.05 m/s and 0.01° over a 10-minute manoeuvre script with
//! turns and climbs.
//!
//! The integrator and the Earth model here are written for this test from
//! NIMA TR8350.2 and the textbook NED mechanization, independently of
//! `src/vehicle/`; they share only the `VehicleState` they compare.
//!
//! Both truths are checked in one build: the sources compute the same in
//! either (the `fixed-point` feature changes only the chain and inlining),
//! so the `fixed-point` test run skips this file rather than repeat
//! minutes of debug-build integration.
#![cfg(not(feature = "fixed-point"))]

use imu_emu::math::units::{ACC_BITS, GYRO_BITS};
use imu_emu::sensor::motion::{
    BuiltinMotion, BuiltinMotionFixed, Motion, MotionSource, Truth, TruthFixed,
};

use imu_emu::time::Instant;
use imu_emu::vehicle::{
    builtin_state, fullstate, FullStateLayout, FullStateRow, Manoeuvres, Script, Site, Strapdown,
    VehicleState,
};

const DT: f64 = 0.0005; // 2 kHz
const G_ICD: f64 = 9.8106;

// ---- an independent WGS84 / NED strapdown (TR8350.2 Tables 3.1, 3.4) ----

const A: f64 = 6_378_137.0;
const FL: f64 = 1.0 / 298.257_223_563;
const W_IE: f64 = 7.292_115e-5;
const GE: f64 = 9.780_325_335_9;
const GP: f64 = 9.832_184_937_8;
const GM: f64 = 3.986_004_418e14;

fn e2() -> f64 {
    FL * (2.0 - FL)
}

fn gravity(lat: f64, h: f64) -> f64 {
    let b = A * (1.0 - FL);
    let k = (b * GP - A * GE) / (A * GE);
    let m = W_IE * W_IE * A * A * b / GM;
    let s2 = lat.sin().powi(2);
    let g0 = GE * (1.0 + k * s2) / (1.0 - e2() * s2).sqrt();
    g0 * (1.0 - 2.0 / A * (1.0 + FL + m - 2.0 * FL * s2) * h + 3.0 * h * h / (A * A))
}

type V = [f64; 3];
type Q = [f64; 4];

fn qmul(a: &Q, b: &Q) -> Q {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn qrot(q: &Q, v: &V) -> V {
    let p = qmul(
        &qmul(q, &[0.0, v[0], v[1], v[2]]),
        &[q[0], -q[1], -q[2], -q[3]],
    );
    [p[1], p[2], p[3]]
}

fn qexp(a: &V) -> Q {
    let th = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if th < 1e-12 {
        return [1.0, 0.5 * a[0], 0.5 * a[1], 0.5 * a[2]];
    }
    let k = (0.5 * th).sin() / th;
    [(0.5 * th).cos(), a[0] * k, a[1] * k, a[2] * k]
}

fn cross(a: &V, b: &V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The NED mechanization, second order: state at sample k, advanced with
/// samples k and k+1.
struct Nav {
    lat: f64,
    lon: f64,
    h: f64,
    v: V,
    q: Q,
    w: V,
    f: V,
}

impl Nav {
    fn from(s: &VehicleState, w: V, f: V) -> Self {
        Nav {
            lat: s.lat_rad,
            lon: s.lon_rad,
            h: s.height_m,
            v: s.vel_ned,
            q: s.q_nb,
            w,
            f,
        }
    }

    /// One step with samples that are means over the step (`Samples::Mean`:
    /// the rotation from the step's mean rate with the coning term of the
    /// previous and this step, the mean force at mid-step attitude) or
    /// instantaneous values at its ends (`Samples::Point`: trapezoid).
    fn step(&mut self, w1: V, f1: V, dt: f64, kind: Samples) {
        let e2 = e2();
        let sl = self.lat.sin();
        let rn = A / (1.0 - e2 * sl * sl).sqrt();
        let rm = A * (1.0 - e2) / (1.0 - e2 * sl * sl).powf(1.5);
        let (vn, ve, vd) = (self.v[0], self.v[1], self.v[2]);
        let wie = [W_IE * self.lat.cos(), 0.0, -W_IE * sl];
        let wen = [
            ve / (rn + self.h),
            -vn / (rm + self.h),
            -ve * self.lat.tan() / (rn + self.h),
        ];
        let w0 = self.w;
        let mut rot = [0.0; 3];
        let c = cross(&w0, &w1);
        for i in 0..3 {
            rot[i] = match kind {
                Samples::Point => 0.5 * (w0[i] + w1[i]) * dt + c[i] * dt * dt / 12.0,
                Samples::Mean => w1[i] * dt + c[i] * dt * dt / 12.0,
            };
        }
        let win = [
            -(wie[0] + wen[0]) * dt,
            -(wie[1] + wen[1]) * dt,
            -(wie[2] + wen[2]) * dt,
        ];
        let q1 = qmul(&qexp(&win), &qmul(&self.q, &qexp(&rot)));
        let n = q1.iter().map(|x| x * x).sum::<f64>().sqrt();
        let q1 = q1.map(|x| x / n);
        let (fa, fb) = match kind {
            Samples::Point => (qrot(&self.q, &self.f), qrot(&q1, &f1)),
            Samples::Mean => {
                let half = qmul(&self.q, &qexp(&rot.map(|x| 0.5 * x)));
                let f = qrot(&half, &f1);
                (f, f)
            }
        };
        let two_wie_wen = [
            2.0 * wie[0] + wen[0],
            2.0 * wie[1] + wen[1],
            2.0 * wie[2] + wen[2],
        ];
        let cor = cross(&two_wie_wen, &self.v);
        let g = gravity(self.lat, self.h);
        let mut v1 = [0.0; 3];
        for i in 0..3 {
            let grav = if i == 2 { g } else { 0.0 };
            v1[i] = self.v[i] + (0.5 * (fa[i] + fb[i]) - cor[i] + grav) * dt;
        }
        self.lat += 0.5 * (vn + v1[0]) / (rm + self.h) * dt;
        self.lon += 0.5 * (ve + v1[1]) / ((rn + self.h) * self.lat.cos()) * dt;
        self.h -= 0.5 * (vd + v1[2]) * dt;
        self.v = v1;
        self.q = q1;
        self.w = w1;
        self.f = f1;
    }

    /// (position m, velocity m/s, attitude °) from `s`.
    fn error(&self, s: &VehicleState) -> (f64, f64, f64) {
        let sl = s.lat_rad.sin();
        let rn = A / (1.0 - e2() * sl * sl).sqrt();
        let mut dlon = self.lon - s.lon_rad;
        dlon -= (dlon / std::f64::consts::TAU).round() * std::f64::consts::TAU;
        let dn = (self.lat - s.lat_rad) * rn;
        let de = dlon * rn * s.lat_rad.cos();
        let dh = self.h - s.height_m;
        let dv = (0..3)
            .map(|i| (self.v[i] - s.vel_ned[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let d = qmul(&[s.q_nb[0], -s.q_nb[1], -s.q_nb[2], -s.q_nb[3]], &self.q);
        let ang = 2.0
            * (d[1] * d[1] + d[2] * d[2] + d[3] * d[3])
                .sqrt()
                .atan2(d[0].abs());
        ((dn * dn + de * de + dh * dh).sqrt(), dv, ang.to_degrees())
    }
}

/// What a source's samples are.
#[derive(Clone, Copy, Debug)]
enum Samples {
    /// The value at the tick (built-in motions, rate/force rows).
    Point,
    /// The mean over the tick since the previous (manoeuvres, full state).
    Mean,
}

// ---- the ideal sensor output, as each build's chain takes it ----

#[derive(Clone, Copy, Debug)]
enum Build {
    Float,
    Fixed,
}

/// The truth as the chain of `build` takes it, back in body axes, rad/s
/// and m/s² (housing X right, Y forward, Z up → body FRD).
fn ideal(t: &Truth, build: Build) -> (V, V) {
    let (w, f) = match build {
        Build::Float => (t.rate_dps.map(f64::from), t.specific_force_g.map(f64::from)),
        Build::Fixed => {
            let x = TruthFixed::from_truth(t);
            (
                x.rate.map(|v| f64::from(v) / f64::from(1u32 << GYRO_BITS)),
                x.force.map(|v| f64::from(v) / f64::from(1u32 << ACC_BITS)),
            )
        }
    };
    let body = |v: V| [v[1], v[0], -v[2]];
    (body(w.map(f64::to_radians)), body(f.map(|x| x * G_ICD)))
}

/// Integrates a source's ideal output in each of `builds` for `ticks`
/// of `dt` seconds (one pass of the source) and asserts the worst
/// (position, velocity, attitude) error against the source's own state.
fn check(
    name: &str,
    kind: Samples,
    builds: &[Build],
    (ticks, dt): (u64, f64),
    metres: f64,
    mut source: impl FnMut(u64) -> (VehicleState, Truth),
) {
    let (s0, t0) = source(0);
    let mut navs: Vec<Nav> = builds
        .iter()
        .map(|&b| {
            let (w, f) = ideal(&t0, b);
            Nav::from(&s0, w, f)
        })
        .collect();
    let mut worst = vec![(0.0f64, 0.0f64, 0.0f64); builds.len()];
    for k in 1..=ticks {
        let (s, t) = source(k);
        for ((nav, &b), worst) in navs.iter_mut().zip(builds).zip(&mut worst) {
            let (w, f) = ideal(&t, b);
            nav.step(w, f, dt, kind);
            if k % 200 == 0 || k == ticks {
                let e = nav.error(&s);
                *worst = (worst.0.max(e.0), worst.1.max(e.1), worst.2.max(e.2));
            }
        }
    }
    for (b, w) in builds.iter().zip(worst) {
        eprintln!(
            "{name} {b:?}: worst {:.3} m, {:.4} m/s, {:.5}°",
            w.0, w.1, w.2
        );
        assert!(w.0 <= metres, "{name} {b:?}: position {} m", w.0);
        assert!(w.1 <= 0.05, "{name} {b:?}: velocity {} m/s", w.1);
        assert!(w.2 <= 0.01, "{name} {b:?}: attitude {}°", w.2);
    }
}

const BOTH: &[Build] = &[Build::Float, Build::Fixed];

/// Ten minutes of turns (flat and coordinated), climbs, descents,
/// accelerations and holds.
const TEN_MINUTES: &str = "\
start 45.5 7.25 300 30 60
hold 20
accel 1.5 20            # to 90 m/s
coord-turn 3 60
hold 20
climb 6 40
coord-turn -2.5 50
climb 0 20
turn 1 30               # a flat turn
descend 4 45
hold 30
coord-turn 5 40
climb 0 25
accel -2 20             # to 50 m/s
coord-turn -4 70
climb 3 40
hold 40
descend 2 30
";

fn script() -> Script {
    let s = Script::parse(TEN_MINUTES).unwrap();
    assert_eq!(s.duration_s(), 600.0);
    s
}

/// Ten minutes at 2 kHz.
const TEN_MIN: (u64, f64) = (1_200_000, DT);

#[test]
fn manoeuvre_script_integrates_back_to_its_state() {
    let mut m = Manoeuvres::new(script());
    check("script", Samples::Mean, BOTH, TEN_MIN, 1.0, |k| {
        let s = m.at(k as f64 * DT);
        (s, s.truth())
    });
}

/// The script written as full-state rows at 10 Hz (text, through the row
/// parser) and played back between rows: the derived rates and forces
/// integrate back to the played state.
#[test]
fn full_state_rows_integrate_back_to_their_state() {
    let mut m = Manoeuvres::new(script());
    let layout =
        FullStateLayout::from_header("time,lat,lon,height,vn,ve,vd,roll,pitch,yaw").unwrap();
    let rows: Vec<FullStateRow> = (0..=6000)
        .map(|i| {
            let s = m.at(f64::from(i) * 0.1);
            let e = s.euler_rad().map(f64::to_degrees);
            let line = format!(
                "{:.3}, {:.12}, {:.12}, {:.6}, {:.9}, {:.9}, {:.9}, {:.12}, {:.12}, {:.12}",
                s.time_s,
                s.lat_rad.to_degrees(),
                s.lon_rad.to_degrees(),
                s.height_m,
                s.vel_ned[0],
                s.vel_ned[1],
                s.vel_ned[2],
                e[0],
                e[1],
                e[2]
            );
            FullStateRow::parse(&line, &layout).unwrap()
        })
        .collect();
    check("full-state", Samples::Mean, BOTH, TEN_MIN, 1.0, |k| {
        let t = k as f64 * DT;
        let s = fullstate::sample(&rows, t - DT, t).unwrap();
        (s, s.truth())
    });
}

/// Rate/force rows (`--trajectory`): the state is the core's strapdown
/// of the rows' values at each tick (linear between rows, as the host
/// plays them). Rows: the script's measurement at 100 Hz, written as the
/// file would hold them (housing axes, °/s and g, six decimals more than
/// a file needs); the independent integration follows the core's.
#[test]
fn rate_rows_integrate_back_to_their_state() {
    let mut m = Manoeuvres::new(script());
    let rows: Vec<Truth> = (0..=60_000)
        .map(|i| {
            m.at(f64::from(i) * 0.01);
            m.state().truth()
        })
        .collect();
    let at = |t: f64| -> Truth {
        let i = ((t / 0.01) as usize).min(rows.len() - 2);
        let w = (t / 0.01 - i as f64) as f32;
        let (a, b) = (rows[i], rows[i + 1]);
        let mix = |x: [f32; 3], y: [f32; 3]| core::array::from_fn(|k| x[k] + (y[k] - x[k]) * w);
        Truth {
            rate_dps: mix(a.rate_dps, b.rate_dps),
            specific_force_g: mix(a.specific_force_g, b.specific_force_g),
            temperature_c: None,
        }
    };
    for build in [Build::Float, Build::Fixed] {
        let s0 = Manoeuvres::new(script()).state();
        let (w, f) = ideal(&at(0.0), build);
        let mut start = s0;
        start.rate_ib_b = w;
        start.force_b = f;
        let mut sd = Strapdown::new(start);
        check("rate rows", Samples::Point, &[build], TEN_MIN, 1.0, |k| {
            let t = at(k as f64 * DT);
            if k > 0 {
                let (w, f) = ideal(&t, build);
                sd.step(&w, &f, None, DT);
            }
            (*sd.state(), t)
        });
    }
}

/// The built-in motions rotate (and cone) in place at their site: their
/// truth integrates back to a vehicle at rest there with their attitude,
/// within the 1 m, 0.05 m/s and 0.01° of the issue, in ten minutes: at the
/// internal 2 kHz for the rotation (whose tick angle's rounding weighs per
/// tick) and coning (whose integration needs the rate), at 400 Hz for the
/// static truth (constant: 2 kHz would only make the test five times
/// longer).
fn built_in_integrates_back_to_its_state(m: Motion) {
    let run = match m {
        Motion::Coning { .. } | Motion::ConstantRotation { .. } => TEN_MIN,
        _ => (240_000, 0.0025),
    };
    let dt = run.1;
    let ns = (dt * 1e9) as u64;
    let name = format!("{m:?}");
    let site = Site::of(&m);
    let mut float = BuiltinMotion::new(m, dt as f32);
    check(&name, Samples::Point, &[Build::Float], run, 1.0, |k| {
        let t = float.next(Instant::from_nanos(k * ns), dt as f32);
        (builtin_state(&site, float.attitude(), &t, k as f64 * dt), t)
    });
    let mut fixed = BuiltinMotionFixed::new(m, dt as f32);
    check(&name, Samples::Point, &[Build::Fixed], run, 1.0, |k| {
        fixed.step();
        let t = fixed.truth_now();
        (builtin_state(&site, fixed.attitude(), &t, k as f64 * dt), t)
    });
}

/// A constant rotation at rates that are not whole numbers (neither `f32`
/// nor the fixed-point scale holds them exactly): before its tick angle's
/// rounding was carried (docs/motion.md, "Precision") it ended 1.1 m off
/// (float, at 400 Hz and 3, −2, 10 °/s) and 1.4 m (fixed point, here).
#[test]
fn constant_rotation_integrates_back_to_its_state() {
    built_in_integrates_back_to_its_state(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [3.3, -2.1, 10.7],
    });
}

#[test]
fn coning_integrates_back_to_its_state() {
    built_in_integrates_back_to_its_state(Motion::Coning {
        lat_deg: 45.0,
        heading_deg: 10.0,
        half_angle_deg: 5.0,
        freq_hz: 1.0,
    });
}

/// At rest at the default site and in the south, heading 250°.
#[test]
fn static_motions_integrate_back_to_their_state() {
    built_in_integrates_back_to_its_state(Motion::default());
    built_in_integrates_back_to_its_state(Motion::Static {
        lat_deg: -33.0,
        heading_deg: 250.0,
    });
}
