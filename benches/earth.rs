//! The Earth models' cost on the host (criterion; docs/performance.md,
//! docs/earth.md): `earth/wmm_field`, one WMM2025 synthesis
//! ([`imu_emu::earth::magnetic_field_ned_nt`], degree 12, `f64`) at a
//! place that moves each call; `earth/wmm_memo_hit`, the IMX's magnetometer
//! path at rest (the memo's grid point unchanged: no synthesis);
//! `earth/geoid`, one EGM96 undulation ([`imu_emu::earth::geoid_undulation_m`],
//! bilinear in the 2° grid).

use criterion::{criterion_group, criterion_main, Criterion};
use imu_emu::earth::{geoid_undulation_m, magnetic_field_ned_nt, FieldMemo};
use std::hint::black_box;

fn bench(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("earth");
    let mut k = 0u32;
    g.bench_function("wmm_field", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let x = f64::from(k % 1000) * 0.01;
            black_box(magnetic_field_ned_nt(
                black_box(50.1 + x),
                black_box(-5.5 + x),
                black_box(62.5),
                black_box(2026.3),
            ))
        })
    });
    let memo = FieldMemo::new();
    g.bench_function("wmm_memo_hit", |b| {
        b.iter(|| {
            black_box(memo.field_ned_nt(
                black_box(50.1),
                black_box(-5.5),
                black_box(62.5),
                black_box(2026.3),
            ))
        })
    });
    g.bench_function("geoid", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let x = f64::from(k % 1000) * 0.1;
            black_box(geoid_undulation_m(
                black_box(-50.0 + x),
                black_box(-5.5 + x),
            ))
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
