//! Host throughput of the packet decoders: KERNEL frames (ICD Table 5.2;
//! GA, Calibrated HR, UDD) and ISB packets (DATA of IMU, PIMU, DEV_INFO),
//! 1 MiB streams fed in 4 KiB chunks, as a host driver would. Reported as
//! bytes per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imu_emu::isb::packet as isb;
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

/// 1 MiB of ISB DATA packets: IMU (36 B), PIMU (40 B), DEV_INFO (84 B).
fn isb_stream() -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = [0u8; 128];
    let mut k = 0u32;
    while out.len() < 1 << 20 {
        let (did, len) = match k % 3 {
            0 => (58, 36),
            1 => (3, 40),
            _ => (1, 84),
        };
        let payload: Vec<u8> = (0..len).map(|i| (i as u32 * 7 + k) as u8).collect();
        let n = isb::encode(4, did, &payload, &mut buf).unwrap();
        out.extend_from_slice(&buf[..n]);
        k += 1;
    }
    out
}

fn decode_isb(c: &mut Criterion) {
    let bytes = isb_stream();
    let mut g = c.benchmark_group("isb_decode");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("1MiB_in_4KiB_chunks", |b| {
        b.iter(|| {
            let mut d = isb::Decoder::<{ isb::MAX_PACKET }>::new();
            let mut packets = 0usize;
            let mut sum = 0u32;
            for chunk in bytes.chunks(4096) {
                let mut input = chunk;
                while let Some(p) = d.next_packet(&mut input) {
                    packets += 1;
                    sum = sum.wrapping_add(u32::from(p.did));
                }
            }
            black_box((packets, sum))
        })
    });
    g.finish();
}

criterion_group!(benches, decode, decode_isb);
criterion_main!(benches);
