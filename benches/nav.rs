//! The IMX-5's navigation filter, host-measured (criterion;
//! docs/performance.md "Navigation filter").
//!
//! - `nav/mechanise`: one navigation period of the strapdown
//!   mechanisation (`f64`);
//! - `nav/propagate`: one covariance propagation (15 states, `f32`; every
//!   20 ms);
//! - `nav/update`: one scalar measurement update (8 of them at a GNSS
//!   epoch: position, velocity, barometer, magnetometer);
//! - `nav/200ms`: 50 navigation periods of a navigating unit (one GNSS
//!   epoch's worth at the default 4 ms / 200 ms: 50 mechanisations, 10
//!   propagations, one epoch's updates); per period, divide by 50.

use criterion::{criterion_group, criterion_main, Criterion};
use imu_emu::isb::ins::filter::{Filter, Interval, ProcessNoise, N, POS};
use imu_emu::isb::ins::mech::{Increment, Nominal};
use imu_emu::isb::ins::{Aiding, NavConfig, NavState, StartTimes};
use imu_emu::isb::nav::NavTruth;
use imu_emu::vehicle::VehicleState;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let s = VehicleState::at_rest(0.79, 0.12, 300.0, 0.5);
    let dt = 0.004;
    let inc = Increment {
        dtheta: s.rate_ib_b.map(|x| x * dt),
        dv: s.force_b.map(|x| x * dt),
        dt,
    };
    let mut g = c.benchmark_group("nav");
    let mut n = Nominal::at(&[45.26, 6.9, 300.0]);
    g.bench_function("mechanise", |b| b.iter(|| black_box(n.mechanise(&inc))));
    let mut f = Filter::new(&[0.1; N]);
    let iv = Interval {
        dt: 0.02,
        f_n: [0.1, 0.2, -9.8],
        c_nb: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        w_in: [5e-5, 0.0, -5e-5],
        grav_grad: 3e-6,
    };
    let q = ProcessNoise {
        vel: 1e-7,
        att: 1e-11,
        bg: 1e-14,
        ba: 1e-10,
    };
    g.bench_function("propagate", |b| {
        b.iter(|| {
            f.propagate(black_box(&iv), &q);
        })
    });
    g.bench_function("update", |b| {
        b.iter(|| {
            let u = f.update(&[(POS, 1.0)], black_box(0.1), 1.0, 0.0);
            f.take_correction();
            u
        })
    });
    // A navigating unit: aligned, fixed, then 50 periods an iteration.
    let truth = NavTruth {
        lat_deg: s.lat_rad.to_degrees(),
        lon_deg: s.lon_rad.to_degrees(),
        h_m: s.height_m,
        v_ned: [0.0; 3],
        q_nb: s.q_nb,
    };
    let cfg = NavConfig {
        last_lla: [truth.lat_deg, truth.lon_deg, truth.h_m],
        ..NavConfig::default()
    };
    let mut nav = NavState::new(1);
    nav.boot(&cfg, StartTimes::default());
    let mut t = 0.0;
    let period = |nav: &mut NavState, t: &mut f64| {
        *t += dt;
        if ((*t / 0.02).round() * 0.02 - *t).abs() < 1e-9 {
            nav.step(*t, &truth);
        }
        let aiding = nav.epoch_due(*t, 0.2).then(|| {
            let tick = (*t * 2000.0) as u64;
            let aid = Aiding {
                mag: nav.magnetometer(&truth, tick),
                pressure_kpa: nav.pressure_kpa(&truth, tick),
                year: 2026.0,
            };
            (nav.gnss(&truth, &cfg), aid)
        });
        nav.navigate(*t, &inc, 0.2, aiding, &cfg);
    };
    while t < 40.0 {
        period(&mut nav, &mut t);
    }
    assert!(nav.has_fix());
    g.bench_function("200ms", |b| {
        b.iter(|| {
            for _ in 0..50 {
                period(&mut nav, &mut t);
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
