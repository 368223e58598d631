//! One internal-rate tick, host-measured (criterion).
//!
//! `device_tick/<format>`: `Device::on_tick` of a whole KERNEL device —
//! the signal chain and the frame encoded into the TX queue — streaming
//! each fixed format at 2 kHz (K120, factory settings otherwise, 2 Mbaud),
//! and `device_tick/worst`: K120, LPF 16 Hz, all three cascade filters,
//! incremental output, non-zero Alignment_Angles (mounting), the largest
//! UDD configuration at its largest rate at 2 Mbaud (1 kHz). Every
//! iteration also takes the queued bytes out (`poll_tx`), as a board does;
//! the benches check that a frame left at every output tick and none was
//! dropped. `device_tick/GA K110` and `device_tick/GA K110 filters`: what
//! `imu-emu --speed max` runs in `scripts/bench.sh` (a K110, GA at 2 kHz,
//! 2 Mbaud; factory settings, then LPF 16 Hz and all cascade filters).
//!
//! The chain alone:
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
use imu_emu::device::{Device, PowerOn};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::dsp::integrals::{Integrals, Integrate};
use imu_emu::dsp::OutputVariant;
use imu_emu::kernel::command::Command;
use imu_emu::kernel::formats::{FORMATS, UDD};
use imu_emu::kernel::frame::Decoder;
use imu_emu::kernel::{params, udd};
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::sensor::Motion;
use imu_emu::time::Instant;
use imu_emu::Kernel;
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

type Dev = Device<RamNor<8192>, Kernel>;

/// A powered-on device with a clock and a frame counter.
struct Rig {
    dev: Dev,
    now: u64,
    /// `tick_period_ns`, read once (a division; the schedule holds it too).
    period: u64,
    buf: Vec<u8>,
    frames: u64,
    reader: Decoder<1024>,
}

impl Rig {
    fn new(model: &str) -> Rig {
        let product = Product::parse(model).unwrap();
        let cfg = PowerOn {
            product,
            boot: None,
            seed: 7,
        };
        let dev = Device::power_on_with(cfg, RamNor::new(), Instant::ZERO);
        Rig {
            period: dev.tick_period_ns(),
            dev,
            now: 0,
            buf: vec![0; 1 << 16],
            frames: 0,
            reader: Decoder::new(),
        }
    }

    fn cmd(&mut self, c: Command) {
        let mut out = [0u8; 300];
        let n = c.encode(&mut out).unwrap();
        self.dev.on_rx(&out[..n], Instant::from_nanos(self.now));
        self.drain(true);
    }

    fn save(&mut self, id: u16, value: &[u8]) {
        self.cmd(Command::SaveFlash {
            id,
            len: value.len() as u16,
            value,
        });
    }

    /// Takes the queued bytes (and events) out; counts the frames if asked.
    fn drain(&mut self, count: bool) {
        loop {
            let n = self.dev.poll_tx(&mut self.buf);
            while self.dev.poll_event().is_some() {}
            if n == 0 {
                break;
            }
            if count {
                let mut input = &self.buf[..n];
                while self.reader.next_frame(&mut input).is_some() {
                    self.frames += 1;
                }
            }
        }
    }

    /// One tick, as a board runs it: `on_tick`, then the bytes out.
    #[inline]
    fn tick(&mut self) {
        self.now += self.period;
        self.dev.on_tick(Instant::from_nanos(self.now));
        self.drain(false);
    }

    /// 2 Mbaud (Baud_Rate 0x0B, CommitBaudRate), Data_Rate 2000, then the
    /// data command `code`; the stream is left running for 3 s (past the
    /// initial alignment) and checked: a frame at every `every` ticks.
    fn start(&mut self, code: u8, every: u64) {
        self.save(params::BAUD_RATE.id, &[0x0B]);
        self.cmd(Command::CommitBaudRate);
        assert_eq!(self.dev.line_rate(), 2_000_000);
        self.save(params::DATA_RATE.id, &2000u16.to_le_bytes());
        self.cmd(Command::Data(code));
        for _ in 0..6000 {
            self.tick();
        }
        self.frames = 0;
        for _ in 0..1000 {
            self.now += self.period;
            self.dev.on_tick(Instant::from_nanos(self.now));
            self.drain(true);
        }
        assert_eq!(self.frames, 1000 / every, "{code:#x}");
        assert_eq!(self.dev.tx_dropped(), 0);
    }
}

fn device(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("device_tick");
    for f in FORMATS {
        let mut r = Rig::new("K120");
        r.start(f.code, 1);
        g.bench_function(f.name, |b| b.iter(|| r.tick()));
        assert_eq!(r.dev.tx_dropped(), 0);
    }
    // What `imu-emu --speed max` runs in `scripts/bench.sh`: a K110 at
    // factory settings streaming GA at 2 kHz, and the same with LPF 16 Hz
    // and all cascade filters (`loadgen --filters`).
    let ga = 0x8F; // GA (Table 5.7)
    let mut r = Rig::new("K110");
    r.start(ga, 1);
    g.bench_function("GA K110", |b| b.iter(|| r.tick()));
    assert_eq!(r.dev.tx_dropped(), 0);
    let mut r = Rig::new("K110");
    r.save(params::LPF_BANDWIDTH.id, &[0]);
    r.save(params::FILTER.id, &[7]);
    r.start(ga, 1);
    g.bench_function("GA K110 filters", |b| b.iter(|| r.tick()));
    assert_eq!(r.dev.tx_dropped(), 0);
    // The worst case: K120, LPF 16 Hz, all cascade filters, incremental,
    // mounting, the largest UDD (the 16 largest types a K120 takes).
    let mut r = Rig::new("K120");
    let product = Product::parse("K120").unwrap();
    let mut types: Vec<_> = udd::UDD_TYPES
        .iter()
        .filter(|t| udd::supported(t.code, &product).is_some())
        .collect();
    types.sort_by_key(|t| std::cmp::Reverse(t.field.size()));
    types.truncate(16);
    let mut config = vec![types.len() as u8];
    config.extend(types.iter().map(|t| t.code));
    r.save(params::LPF_BANDWIDTH.id, &[0]);
    r.save(params::FILTER.id, &[7]);
    r.save(params::OUTPUT_VARIANT.id, &[2]);
    let angles: Vec<u8> = [10.0f32, -20.0, 30.0]
        .iter()
        .flat_map(|a| a.to_le_bytes())
        .collect();
    r.save(params::ALIGNMENT_ANGLES.id, &angles);
    r.cmd(Command::UddConfig);
    r.cmd(Command::UddConfigMessage(&config));
    // 177-byte payload: 1 kHz is the largest rate at 2 Mbaud (Formula 5.1).
    r.start(UDD, 2);
    g.bench_function("worst", |b| b.iter(|| r.tick()));
    assert_eq!(r.dev.tx_dropped(), 0);
    g.finish();
}

criterion_group!(benches, bench, device);
criterion_main!(benches);
