//! A test harness around the sans-IO device: a virtual clock, ticks, and a
//! frame reader for what the device sends.
#![allow(dead_code)]

use imu_emu::device::{Device, PowerOn};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::Decoder;
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;
use imu_emu::Kernel;

pub mod isb;
pub mod xorshift;

pub type Flash = RamNor<8192>;

/// A device frame as received by the host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rx {
    pub id: u8,
    pub payload: Vec<u8>,
    /// Device tick count when the frame was drained.
    pub tick: u64,
}

pub struct Bench {
    pub dev: Device<Flash, Kernel>,
    pub now: u64,
    pub ticks: u64,
    reader: Decoder<1024>,
    pub raw: Vec<u8>,
}

impl Bench {
    pub fn new(model: &str) -> Self {
        Self::with_flash(model, Flash::new())
    }

    pub fn with_flash(model: &str, flash: Flash) -> Self {
        let product = Product::parse(model).unwrap();
        let dev = Device::power_on_with(
            PowerOn {
                product,
                boot: None,
                seed: 7,
            },
            flash,
            Instant::ZERO,
        );
        Bench {
            dev,
            now: 0,
            ticks: 0,
            reader: Decoder::new(),
            raw: Vec::new(),
        }
    }

    pub fn send(&mut self, bytes: &[u8]) {
        self.dev.on_rx(bytes, Instant(self.now));
    }

    pub fn cmd(&mut self, cmd: Command) {
        let mut out = [0u8; 300];
        let n = cmd.encode(&mut out).unwrap();
        self.send(&out[..n]);
    }

    /// Drains everything queued and decodes it into frames.
    pub fn drain(&mut self) -> Vec<Rx> {
        let mut buf = [0u8; 4096];
        let mut frames = Vec::new();
        loop {
            let n = self.dev.poll_tx(&mut buf);
            while self.dev.poll_event().is_some() {}
            if n == 0 {
                break;
            }
            self.raw.extend_from_slice(&buf[..n]);
            let mut input = &buf[..n];
            while let Some(f) = self.reader.next_frame(&mut input) {
                assert_eq!(f.msg_type, 1, "device frames are type 1");
                frames.push(Rx {
                    id: f.id,
                    payload: f.payload.to_vec(),
                    tick: self.ticks,
                });
            }
        }
        frames
    }

    /// Runs `n` ticks, draining after each; returns the frames.
    pub fn run_ticks(&mut self, n: u64) -> Vec<Rx> {
        let period = self.dev.tick_period_ns();
        let mut frames = self.drain();
        for _ in 0..n {
            self.now += period;
            self.ticks += 1;
            self.dev.on_tick(Instant(self.now));
            frames.extend(self.drain());
        }
        frames
    }

    pub fn run_secs(&mut self, s: f64) -> Vec<Rx> {
        let rate = 1_000_000_000 / self.dev.tick_period_ns();
        self.run_ticks((s * rate as f64).round() as u64)
    }

    pub fn save(&mut self, id: u16, value: &[u8]) -> Vec<Rx> {
        self.cmd(Command::SaveFlash {
            id,
            len: value.len() as u16,
            value,
        });
        self.drain()
    }

    pub fn read_ram(&mut self, id: u16, len: u16) -> Option<Vec<u8>> {
        self.cmd(Command::ReadRam { id, len });
        let f = self.drain();
        assert!(f.len() <= 1);
        f.into_iter().next().map(|f| {
            assert_eq!(f.id, 0xB1);
            f.payload
        })
    }
}

/// The checksum field of an encoded command (what the device acknowledges).
pub fn cmd_checksum(cmd: Command) -> [u8; 2] {
    let mut out = [0u8; 300];
    let n = cmd.encode(&mut out).unwrap();
    [out[n - 2], out[n - 1]]
}

pub fn i32_at(p: &[u8], i: usize) -> i32 {
    i32::from_le_bytes(p[i..i + 4].try_into().unwrap())
}
pub fn i16_at(p: &[u8], i: usize) -> i16 {
    i16::from_le_bytes(p[i..i + 2].try_into().unwrap())
}
pub fn u16_at(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes(p[i..i + 2].try_into().unwrap())
}
