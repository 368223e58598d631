//! One internal-rate tick of the signal chain, host-measured (criterion).
//!
//! `tick/worst`: K120 (aux accelerometer: all 9 channels live), LPF 16 Hz
//! (order 192), all three cascade filters, incremental output, non-zero
//! Alignment_Angles, default errors, coning motion, attitude running.
//! `tick/factory`: K110 at factory settings (LPF 262 Hz, cascade off),
//! static. `tick/worst+integrals`: `tick/worst` on a chain that keeps the
//! cumulative integrals (`SignalChain<Integrals>`, what a personality
//! windowing them runs; the KERNEL's chain has none). `output`: one output() at 100 Hz in the worst configuration.
//! Run with `--features fixed-point` for the fixed-point chain (integer
//! truth, error model, attitude, FIR, cascade and accumulator).

use criterion::{criterion_group, criterion_main, Criterion};
use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::dsp::integrals::{Integrals, Integrate};
use imu_emu::dsp::OutputVariant;
use imu_emu::model::Product;
use imu_emu::sensor::Motion;
use imu_emu::time::Instant;
use std::hint::black_box;

fn worst() -> SignalChain {
    worst_of()
}

fn worst_of<I: Integrate>() -> SignalChain<I> {
    let p = Product::parse("K120").unwrap();
    let mut c = SignalChain::<I>::powered_on(p, 1);
    let mut cfg = ChainConfig::defaults(&p);
    cfg.lpf = Bandwidth::Hz16;
    cfg.cascade.mask = 0x07;
    cfg.output_variant = OutputVariant::Incremental;
    cfg.alignment_angles_deg = [10.0, -20.0, 30.0];
    c.configure(&cfg);
    c.set_motion(Motion::Coning {
        lat_deg: 45.0,
        heading_deg: 0.0,
        half_angle_deg: 3.0,
        freq_hz: 4.0,
    });
    c.skip_alignment();
    c
}

fn bench(cr: &mut Criterion) {
    let mut c = worst();
    let mut t = 0u64;
    cr.bench_function("tick/worst", |b| {
        b.iter(|| {
            t += 500_000;
            c.tick(black_box(Instant::from_nanos(t)));
        })
    });
    let mut ci = worst_of::<Integrals>();
    cr.bench_function("tick/worst+integrals", |b| {
        b.iter(|| {
            t += 500_000;
            ci.tick(black_box(Instant::from_nanos(t)));
        })
    });
    let p = Product::parse("K110").unwrap();
    let mut f = SignalChain::new(p, 1);
    f.configure(&ChainConfig::defaults(&p));
    cr.bench_function("tick/factory", |b| {
        b.iter(|| {
            t += 500_000;
            f.tick(black_box(Instant::from_nanos(t)));
        })
    });
    let mut c = worst();
    cr.bench_function("output/worst", |b| {
        b.iter(|| {
            for _ in 0..20 {
                t += 500_000;
                c.tick(Instant::from_nanos(t));
            }
            black_box(c.output())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
