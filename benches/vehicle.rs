//! The vehicle truth's cost per tick on the host (criterion): what a board
//! runs before each tick for its source (docs/motion.md, "Cost").
//!
//! `vehicle/script`: `Manoeuvres::at` one 2 kHz tick on, in a coordinated
//! turn while climbing (every rate live). `vehicle/full-state`:
//! `fullstate::sample` over one tick between 10 Hz rows.
//! `vehicle/strapdown`: `Strapdown::step` (the state of `--trajectory`).
//! `vehicle/builtin`: `SignalChain::vehicle` of the built-in static motion
//! (what `truth` reads; never in a tick).

use criterion::{criterion_group, criterion_main, Criterion};
use imu_emu::chain::SignalChain;
use imu_emu::model::Product;
use imu_emu::vehicle::{fullstate, FullStateRow, Manoeuvres, Script, Strapdown};
use std::hint::black_box;

const DT: f64 = 0.0005;

fn bench(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("vehicle");
    let script = Script::parse("start 45 7 300 90 60; climb 3 1000; coord-turn 2 1000").unwrap();
    let mut m = Manoeuvres::new(script);
    let mut k = 0u64;
    g.bench_function("script", |b| {
        b.iter(|| {
            k += 1;
            black_box(m.at(k as f64 * DT))
        })
    });
    let mut m = Manoeuvres::new(
        Script::parse("start 45 7 300 90 60; climb 3 1000; coord-turn 2 1000").unwrap(),
    );
    let rows: Vec<FullStateRow> = (0..10_000)
        .map(|i| {
            let s = m.at(f64::from(i) * 0.1);
            let e = s.euler_rad().map(f64::to_degrees);
            FullStateRow {
                time_s: s.time_s,
                lat_deg: s.lat_rad.to_degrees(),
                lon_deg: s.lon_rad.to_degrees(),
                height_m: s.height_m,
                vel_ned: s.vel_ned,
                euler_deg: e,
                rate_dps: None,
                force_mps2: None,
                temperature_c: None,
            }
        })
        .collect();
    let mut k = 0u64;
    g.bench_function("full-state", |b| {
        b.iter(|| {
            k = (k + 1) % 1_990_000;
            let t = k as f64 * DT;
            black_box(fullstate::sample(&rows, t - DT, t))
        })
    });
    let s0 = Manoeuvres::new(Script::parse("start 45 7 300 90 60").unwrap()).state();
    let mut sd = Strapdown::new(s0);
    g.bench_function("strapdown", |b| {
        b.iter(|| sd.step(black_box(&s0.rate_ib_b), black_box(&s0.force_b), None, DT))
    });
    let chain = SignalChain::new(Product::parse("K110").unwrap(), 1);
    g.bench_function("builtin", |b| b.iter(|| black_box(chain.vehicle())));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
