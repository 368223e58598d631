//! Host throughput of the KERNEL frame decoder (ICD Table 5.2): a stream
//! of device frames (GA, Calibrated HR, UDD) fed in 4 KiB chunks, as a host
//! driver would. Reported as bytes per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imu_emu::kernel::frame::{encode, Decoder};
use std::hint::black_box;

fn stream() -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = [0u8; 512];
    let mut k = 0u32;
    while out.len() < 1 << 20 {
        let (id, len) = match k % 3 {
            0 => (0x8F, 32),
            1 => (0x81, 52),
            _ => (0x95, 63),
        };
        let payload: Vec<u8> = (0..len).map(|i| (i as u32 * 7 + k) as u8).collect();
        let n = encode(1, id, &payload, &mut buf).unwrap();
        out.extend_from_slice(&buf[..n]);
        k += 1;
    }
    out
}

fn decode(c: &mut Criterion) {
    let bytes = stream();
    let mut g = c.benchmark_group("kernel_decode");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("1MiB_in_4KiB_chunks", |b| {
        b.iter(|| {
            let mut d = Decoder::<512>::new();
            let mut frames = 0usize;
            let mut sum = 0u32;
            for chunk in bytes.chunks(4096) {
                let mut input = chunk;
                while let Some(f) = d.next_frame(&mut input) {
                    frames += 1;
                    sum = sum.wrapping_add(u32::from(f.id));
                }
            }
            black_box((frames, sum))
        })
    });
    g.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
