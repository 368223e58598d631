//! Host throughput of the packet decoders, reported as bytes per second.
//!
//! `kernel_decode`: a 64 MiB KERNEL stream (every fixed format and real
//! UDD configurations, payloads written by the device's own field writer,
//! ~2 % garbage, one frame in 200 corrupted; [`kernel_stream`]) fed in
//! 64 KiB reads: `framing_64MiB` finds the frames (ICD Table 5.2),
//! `typed_64MiB` also decodes every value (`kernel::decode`).
//! `isb_decode`: ISB packets (DATA of IMU, PIMU, DEV_INFO), 1 MiB in 4 KiB
//! chunks, the packet layer only.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use imu_emu::isb::packet as isb;
use imu_emu::kernel::decode;
use imu_emu::kernel::fields::{self, Field, OutputCtx, Scales, Value};
use imu_emu::kernel::formats::{FORMATS, UDD};
use imu_emu::kernel::frame::{encode, Decoder};
use imu_emu::kernel::udd::UDD_TYPES;
use imu_emu::model::Product;
use imu_emu::sensor::Sample;
use std::hint::black_box;
use std::time::Duration;

/// Size of the KERNEL stream: far beyond the L2 (4 MiB a core here), so it
/// streams from memory as a recording would.
const STREAM: usize = 64 << 20;
/// Bytes a host read hands the decoder.
const CHUNK: usize = 64 << 10;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn f(&mut self, r: f32) -> f32 {
        ((self.next() >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * r
    }
    fn v3(&mut self, r: f32) -> [f32; 3] {
        [self.f(r), self.f(r), self.f(r)]
    }
}

/// The payload layouts of the stream: every fixed format and real UDD
/// configurations (the factory one, the K201's starred types, a navigation
/// set, the largest: 16 types).
fn layouts() -> Vec<(u8, Vec<u8>, Vec<Field>)> {
    let mut l: Vec<(u8, Vec<u8>, Vec<Field>)> = FORMATS
        .iter()
        .map(|f| (f.code, Vec::new(), f.fields.to_vec()))
        .collect();
    let largest: Vec<u8> = UDD_TYPES.iter().map(|t| t.code).take(16).collect();
    for config in [
        &[0x02, 0x21, 0x23, 0x52, 0x53][..],
        &[0x02, 0x21, 0x23, 0x52, 0x53][..4],
        &[0x02, 0x05, 0x08, 0x09, 0x2D, 0x91, 0x53, 0x5B],
        &largest,
    ] {
        let mut header = vec![config.len() as u8];
        header.extend_from_slice(config);
        let fields = config
            .iter()
            .map(|&c| decode::udd_field(c).unwrap())
            .collect();
        l.push((UDD, header, fields));
    }
    l
}

/// ≥ 64 MiB as a KERNEL sends it: frames of every layout with payloads the
/// device's writer produced from a moving sample, about 2 % of the bytes
/// garbage (runs of random bytes between frames, `AA` included), and one
/// frame in 200 corrupted (a payload byte flipped: its checksum fails).
/// Returns the stream and the number of valid frames in it.
fn kernel_stream() -> (Vec<u8>, usize) {
    let product = Product::parse("K120").unwrap();
    let layouts = layouts();
    let mut r = Rng(0x2545_F491_4F6C_DD1D);
    let mut out = Vec::with_capacity(STREAM + 4096);
    let mut buf = [0u8; 512];
    let mut payload = Vec::new();
    let (mut k, mut valid, mut garbage) = (0u64, 0usize, 0usize);
    while out.len() < STREAM {
        let (code, header, fields) = &layouts[(r.next() % layouts.len() as u64) as usize];
        let s = Sample {
            gyro: r.v3(300.0),
            acc: r.v3(4.0),
            aux_acc: r.v3(20.0),
            euler: [r.f(180.0) + 180.0, r.f(90.0), r.f(180.0)],
            quat: [r.f(1.0), r.f(1.0), r.f(1.0), r.f(1.0)],
            gyro_filtered: r.v3(300.0),
            gyro_bias: r.v3(0.1),
            acc_filtered: r.v3(4.0),
            aux_acc_filtered: r.v3(20.0),
            temperature: 25.0 + r.f(10.0),
            supply_voltage: 12.0 + r.f(1.0),
        };
        let ctx = OutputCtx {
            sample: &s,
            product: &product,
            counter: k as u16,
            usw: 0,
            usw_ext: 0,
            time_flags: 0,
            second_fraction_ns: (k * 500_000 % 1_000_000_000) as u32,
            imu_time_ns: k * 500_000,
        };
        payload.clear();
        payload.extend_from_slice(header);
        let at = payload.len();
        payload.resize(at + fields::payload_len(fields), 0);
        fields::write_all(fields, &ctx, &mut payload[at..]).unwrap();
        let n = encode(1, *code, &payload, &mut buf).unwrap();
        if k % 200 == 199 {
            buf[6 + (r.next() as usize % payload.len())] ^= 0x10;
        } else {
            valid += 1;
        }
        out.extend_from_slice(&buf[..n]);
        // Garbage: ~2 % of the bytes, in runs of 1–64 bytes.
        while garbage * 50 < out.len() {
            let run = 1 + (r.next() % 64) as usize;
            for _ in 0..run {
                let b = r.next() as u8;
                out.push(if b < 8 { 0xAA } else { b });
            }
            garbage += run;
        }
        k += 1;
    }
    (out, valid)
}

/// Framing only: every valid frame found (its id summed).
fn frame_all(bytes: &[u8]) -> (usize, u32) {
    let mut d = Decoder::<512>::new();
    let (mut frames, mut sum) = (0usize, 0u32);
    for chunk in bytes.chunks(CHUNK) {
        let mut input = chunk;
        while let Some(f) = d.next_frame(&mut input) {
            frames += 1;
            sum = sum.wrapping_add(u32::from(f.id));
        }
    }
    (frames, sum)
}

/// Framing and typed decoding: every value of every valid frame, folded
/// into a hash of their bits (one-cycle integer steps, so the consumer
/// adds no floating-point dependency chain of its own).
fn decode_all(bytes: &[u8], scales: Scales) -> (usize, u64) {
    let mut d = Decoder::<512>::new();
    let (mut frames, mut hash) = (0usize, 0u64);
    let bits = |x: f64| x.to_bits();
    for chunk in bytes.chunks(CHUNK) {
        let mut input = chunk;
        while let Some(f) = d.next_frame(&mut input) {
            let Ok(fields) = decode::frame(&f, scales) else {
                continue;
            };
            frames += 1;
            for (_, v) in fields {
                hash = hash.rotate_left(5)
                    ^ match v {
                        Value::Angles(a) | Value::Rate(a) | Value::Accel(a) => {
                            bits(a[0]) ^ bits(a[1]).rotate_left(1) ^ bits(a[2]).rotate_left(2)
                        }
                        Value::Quat(q) => {
                            bits(q[0])
                                ^ bits(q[1]).rotate_left(1)
                                ^ bits(q[2]).rotate_left(2)
                                ^ bits(q[3]).rotate_left(3)
                        }
                        Value::Celsius(x) | Value::Volts(x) => bits(x),
                        Value::Word(w) => u64::from(w),
                        Value::Nanos(n) => n,
                        Value::Reserved => 0,
                    };
            }
        }
    }
    (frames, hash)
}

fn decode(c: &mut Criterion) {
    let (bytes, valid) = kernel_stream();
    let scales = Scales::of(&Product::parse("K120").unwrap());
    assert_eq!(frame_all(&bytes).0, valid);
    assert_eq!(decode_all(&bytes, scales).0, valid);
    let mut g = c.benchmark_group("kernel_decode");
    g.sample_size(10);
    g.warm_up_time(Duration::from_secs(1));
    g.measurement_time(Duration::from_secs(4));
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("framing_64MiB", |b| b.iter(|| black_box(frame_all(&bytes))));
    g.bench_function("typed_64MiB", |b| {
        b.iter(|| black_box(decode_all(&bytes, scales)))
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
