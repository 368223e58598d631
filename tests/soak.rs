//! Soak: the core driven directly, faster than real time, at
//! the maximum rate of the largest UDD configuration on a 2 Mbaud line
//! (and GA at 2 kHz), with commands interleaved every 100 ms — ReadRAM,
//! GetBIT, SaveFlash of a harmless parameter, Get_User_Def_Data_struct.
//! The TX queue is drained at line rate (100 bytes per 500 µs tick at
//! 2 Mbaud), as a UART would.
//!
//! Checked: zero lost or duplicated frames (IMU time advancing by exactly
//! one output period in every UDD frame, the 2 kHz counter by exactly one
//! in every GA frame, across its 16-bit wraps), every command answered once
//! with the exact bytes, the TX queue bounded (its high-water mark in the
//! last part of the run no higher than in the first) and nothing dropped,
//! and the time fields exact at the end.
//!
//! Duration in device time: `SOAK_HOURS` (a decimal number) if set, else
//! one hour in a release build (`cargo test -p imu-emu --release --test
//! soak`, as `.ci/run` runs it; ≈ 7 s here) and 40 s (the GA counter wraps
//! once) in a debug build (so the plain `cargo test` stays quick). The
//! 24 h run: `SOAK_HOURS=24 cargo test -p imu-emu --release --test soak --
//! --nocapture`.

use std::collections::VecDeque;
use std::time::Instant as WallClock;

use imu_emu::device::{Device, Mode, PowerOn};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::{encode, Decoder};
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;
use imu_emu::Kernel;

/// Tick period at 2 kHz.
const TICK_NS: u64 = 500_000;
/// Bytes a 2 Mbaud line carries per tick (10 bit times a byte).
const LINE_BYTES_PER_TICK: usize = 100;
/// A command every this many ticks (100 ms).
const COMMAND_EVERY: u64 = 200;

/// The largest UDD configuration of a K120 (Table 5.15): 16 types, every
/// one it supports but the 2-byte USW-extended — 155-byte payloads.
const LARGEST_UDD: [u8; 16] = [
    0x02, 0x05, 0x07, 0x08, 0x09, 0x20, 0x21, 0x22, 0x23, 0x2D, 0x2E, 0x2F, 0x91, 0x92, 0x52, 0x53,
];
const UDD_PAYLOAD: usize =
    1 + 16 + 8 + 4 + 6 + 12 + 8 + 6 + 12 + 6 + 12 + 12 + 12 + 12 + 12 + 12 + 2 + 2;

/// Device time to run, in ticks.
fn duration_ticks() -> u64 {
    let hours = match std::env::var("SOAK_HOURS") {
        Ok(h) => h.parse::<f64>().expect("SOAK_HOURS is a number"),
        Err(_) if cfg!(debug_assertions) => 40.0 / 3600.0,
        Err(_) => 1.0,
    };
    (hours * 3600.0 * 2000.0).round() as u64
}

fn frame(cmd: Command) -> Vec<u8> {
    let mut out = [0u8; 300];
    let n = cmd.encode(&mut out).unwrap();
    out[..n].to_vec()
}

/// The device frame (type 1) for `id` and `payload`, as bytes.
fn reply(id: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; payload.len() + 8];
    let n = encode(1, id, payload, &mut out).unwrap();
    out.truncate(n);
    out
}

struct Soak {
    dev: Device<RamNor<8192>, Kernel>,
    tick: u64,
    reader: Decoder<512>,
    /// Replies still expected, in order.
    expect: VecDeque<Vec<u8>>,
    max_tx: usize,
}

impl Soak {
    /// A K120 switched to a 2 Mbaud line (Baud_Rate 0x0B, CommitBaudRate), idle.
    fn new() -> Self {
        let product = Product::parse("K120").unwrap();
        let dev = Device::power_on_with(
            PowerOn {
                product,
                boot: None,
                seed: 24,
            },
            RamNor::new(),
            Instant::ZERO,
        );
        let mut s = Soak {
            dev,
            tick: 0,
            reader: Decoder::new(),
            expect: VecDeque::new(),
            max_tx: 0,
        };
        s.setup(&frame(Command::SaveFlash {
            id: 0x03B2,
            len: 1,
            value: &[0x0B],
        }));
        s.setup(&frame(Command::CommitBaudRate));
        assert_eq!(s.dev.line_rate(), 2_000_000);
        s
    }

    /// Sends `bytes` at tick 0 and drains everything (no checks).
    fn setup(&mut self, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        self.dev.on_rx(bytes, Instant(self.tick * TICK_NS));
        let mut out = Vec::new();
        let mut buf = [0u8; 4096];
        loop {
            let n = self.dev.poll_tx(&mut buf);
            let events = std::iter::from_fn(|| self.dev.poll_event()).count();
            if n == 0 && events == 0 {
                break;
            }
            let mut input = &buf[..n];
            while let Some(f) = self.reader.next_frame(&mut input) {
                out.push((f.id, f.payload.to_vec()));
            }
        }
        out
    }

    /// Runs `ticks` ticks: every [`COMMAND_EVERY`] ticks the next command
    /// of `commands` (with its expected reply, if any) is sent; the TX
    /// queue is drained at line rate; every output frame goes to `check`.
    fn run(
        &mut self,
        ticks: u64,
        commands: &[(Vec<u8>, Option<Vec<u8>>)],
        mut check: impl FnMut(u64, &[u8]),
    ) -> (u64, usize, usize) {
        let mut buf = [0u8; LINE_BYTES_PER_TICK];
        let mut next_cmd = 0;
        let mut answered = 0;
        let (mut first_max, mut last_max) = (0, 0);
        for i in 0..ticks {
            self.tick += 1;
            let now = Instant(self.tick * TICK_NS);
            self.dev.on_tick(now);
            if self.tick.is_multiple_of(COMMAND_EVERY) {
                let (bytes, want) = &commands[next_cmd % commands.len()];
                next_cmd += 1;
                self.dev.on_rx(bytes, now);
                if let Some(w) = want {
                    self.expect.push_back(w.clone());
                }
            }
            let tx = self.dev.tx_len();
            self.max_tx = self.max_tx.max(tx);
            if i < ticks / 10 {
                first_max = first_max.max(tx);
            } else if i >= ticks - ticks / 10 {
                last_max = last_max.max(tx);
            }
            let n = self.dev.poll_tx(&mut buf);
            let mut input = &buf[..n];
            while let Some(f) = self.reader.next_frame(&mut input) {
                if f.id == 0x95 || f.id == 0x8F {
                    check(self.tick, f.payload);
                } else {
                    let got = reply(f.id, f.payload);
                    let want = self.expect.pop_front();
                    assert_eq!(Some(got), want, "tick {}: reply", self.tick);
                    answered += 1;
                }
            }
            assert_eq!(self.dev.poll_event(), None);
        }
        // The line drains what is left.
        let mut tail = [0u8; 4096];
        let n = self.dev.poll_tx(&mut tail);
        let mut input = &tail[..n];
        while let Some(f) = self.reader.next_frame(&mut input) {
            if f.id == 0x95 || f.id == 0x8F {
                check(self.tick, f.payload);
            } else {
                assert_eq!(Some(reply(f.id, f.payload)), self.expect.pop_front());
                answered += 1;
            }
        }
        assert!(self.expect.is_empty(), "unanswered: {:?}", self.expect);
        assert_eq!(self.dev.tx_dropped(), 0, "nothing dropped");
        assert!(
            last_max <= first_max,
            "TX queue grew: {first_max} then {last_max}"
        );
        (next_cmd as u64, answered, self.max_tx)
    }
}

/// The interleaved commands and their exact replies (`hold_off` values
/// alternate; Hold-off_Time is harmless with Trigger_Control 0).
fn commands(data_rate: u16, udd: &[u8]) -> Vec<(Vec<u8>, Option<Vec<u8>>)> {
    let mut cmds = vec![
        (
            frame(Command::ReadRam { id: 0x0012, len: 2 }),
            Some(reply(0xB1, &data_rate.to_le_bytes())),
        ),
        (frame(Command::GetBit), Some(reply(0x1A, &[0; 4]))),
        (
            frame(Command::ReadRam { id: 0x03B2, len: 1 }),
            Some(reply(0xB1, &[0x0B])),
        ),
    ];
    for hold_off in [7u16, 0] {
        let bytes = frame(Command::SaveFlash {
            id: 0x05FE,
            len: 2,
            value: &hold_off.to_le_bytes(),
        });
        let sum = bytes[bytes.len() - 2..].to_vec();
        cmds.push((bytes, Some(reply(0xB2, &sum))));
    }
    if !udd.is_empty() {
        let mut p = vec![udd.len() as u8];
        p.extend_from_slice(udd);
        cmds.push((frame(Command::GetUddStruct), Some(reply(0x97, &p))));
    }
    // A bad frame now and then: silence.
    cmds.push((
        vec![0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x22, 0x00],
        None,
    ));
    cmds
}

fn report(what: &str, ticks: u64, frames: u64, cmds: u64, max_tx: usize, wall: WallClock) {
    let secs = wall.elapsed().as_secs_f64();
    eprintln!(
        "soak {what}: {:.3} h device time ({ticks} ticks), {frames} frames, {cmds} commands, \
         max TX queue {max_tx} B, {secs:.1} s wall ({:.0}× real time)",
        ticks as f64 / 7.2e6,
        ticks as f64 / 2000.0 / secs
    );
}

#[test]
fn largest_udd_config_at_its_maximum_rate_on_2_mbaud() {
    let wall = WallClock::now();
    let ticks = duration_ticks();
    let mut s = Soak::new();
    assert_eq!(UDD_PAYLOAD, 155);
    // Data_Rate 2000; the 16-type configuration lowers it to Formula 5.1's
    // maximum at 2 Mbaud: 2e6 / (11 · 163) = 1115 → 1000 Hz (bit 3 set).
    s.setup(&frame(Command::SaveFlash {
        id: 0x0012,
        len: 2,
        value: &2000u16.to_le_bytes(),
    }));
    let mut msg = vec![16u8];
    msg.extend_from_slice(&LARGEST_UDD);
    let r = s.setup(&frame(Command::UddConfigMessage(&msg)));
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].1[2], 0x08, "too large for 2000 Hz: rate lowered");
    assert_eq!(u16::from_le_bytes([r[0].1[5], r[0].1[6]]), 1000);
    let r = s.setup(&frame(Command::Data(0x95)));
    assert_eq!(r.len(), 1, "acknowledged");
    assert_eq!(s.dev.output_rate(), Some(1000));
    assert_eq!(s.dev.mode(), Mode::Aligning);

    // Alignment (2 s = 4000 ticks), then a frame every 2 ticks: the first
    // at tick 4002.
    let first_tick = 4002;
    let mut frames = 0u64;
    let mut last_imu = None;
    let cmds = commands(2000, &LARGEST_UDD);
    let (sent, answered, max_tx) = s.run(ticks, &cmds, |_, p| {
        assert_eq!(p.len(), UDD_PAYLOAD);
        assert_eq!(p[0], 16);
        assert_eq!(&p[1..17], &LARGEST_UDD);
        let imu = u64::from_le_bytes(p[17..25].try_into().unwrap());
        let fraction = u32::from_le_bytes(p[25..29].try_into().unwrap());
        let want = first_tick * TICK_NS + frames * 1_000_000;
        assert_eq!(
            imu, want,
            "frame {frames}: IMU time (lost or duplicated frame)"
        );
        assert_eq!(u64::from(fraction), imu % 1_000_000_000, "second fraction");
        last_imu = Some(imu);
        frames += 1;
    });
    assert_eq!(s.dev.mode(), Mode::Continuous);
    // Exact at the end: one frame per 2 ticks from tick 4002 to the last.
    let last_tick = first_tick + (ticks - first_tick) / 2 * 2;
    assert_eq!(frames, (ticks - first_tick) / 2 + 1);
    assert_eq!(last_imu, Some(last_tick * TICK_NS));
    let cmds_per_cycle = cmds.len() as u64;
    let replying = cmds.iter().filter(|c| c.1.is_some()).count() as u64;
    assert_eq!(sent, ticks / COMMAND_EVERY);
    assert_eq!(
        answered as u64,
        sent / cmds_per_cycle * replying
            + cmds[..(sent % cmds_per_cycle) as usize]
                .iter()
                .filter(|c| c.1.is_some())
                .count() as u64
    );
    // A frame (163 B) and what is left of the one before, plus a reply.
    assert!(max_tx <= 200, "max TX queue {max_tx}");
    report("UDD 16 types @ 1000 Hz", ticks, frames, sent, max_tx, wall);
}

#[test]
fn ga_at_2_khz_keeps_its_counter_continuous_across_wraps() {
    let wall = WallClock::now();
    let ticks = duration_ticks();
    let mut s = Soak::new();
    s.setup(&frame(Command::SaveFlash {
        id: 0x0012,
        len: 2,
        value: &2000u16.to_le_bytes(),
    }));
    let r = s.setup(&frame(Command::Data(0x8F)));
    assert_eq!(r.len(), 1);
    assert_eq!(s.dev.output_rate(), Some(2000));
    let mut frames = 0u64;
    let mut last = None;
    let (sent, _, max_tx) = s.run(ticks, &commands(2000, &[]), |tick, p| {
        assert_eq!(p.len(), 32);
        let counter = u16::from_le_bytes([p[24], p[25]]);
        // One frame per tick from tick 1; the counter is the tick count
        // mod 2^16 (Table 5.7), drained in the tick it was made or the next.
        let expect = (frames + 1) as u16;
        assert_eq!(counter, expect, "frame {frames} at tick {tick}");
        last = Some(counter);
        frames += 1;
    });
    assert_eq!(frames, ticks, "one frame per tick, none lost or doubled");
    assert_eq!(last, Some(ticks as u16));
    // GA (40 B) each tick on a 100 B/tick line, plus replies.
    assert!(max_tx <= 64, "max TX queue {max_tx}");
    report("GA @ 2000 Hz", ticks, frames, sent, max_tx, wall);
}
