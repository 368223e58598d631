//! Target `device`: the whole KERNEL device for several models, driven
//! by a script decoded from the input.

use std::collections::BTreeMap;

use imu_emu::device::{Device, Level, Mode, Pin, PowerOn, TX_CAP};
use imu_emu::kernel::command::{Command, SAVE_FLASH};
use imu_emu::kernel::frame;
use imu_emu::kernel::params::{self, PARAMS};
use imu_emu::kernel::RX_FRAME_CAP;
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;
use imu_emu::Kernel;

use crate::script::{drain_tx, Cursor};

/// Models the device target runs (one per input, from its first byte).
const MODELS: [&str; 6] = ["K110", "K201", "K120", "K100", "K110M-G450-A8", "K220"];
/// Most ticks one input may run (keeps an execution in milliseconds).
pub(crate) const TICK_BUDGET: u32 = 24_000;

/// Checks the TX byte stream of one power session: whole frames of type
/// 1 with good checksums, back to back.
#[derive(Default)]
struct TxCheck {
    pending: Vec<u8>,
}

impl TxCheck {
    /// Takes `bytes`; returns the frames completed, as (id, payload).
    fn feed(&mut self, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        self.pending.extend_from_slice(bytes);
        let mut out = Vec::new();
        loop {
            let p = &self.pending;
            if p.len() < 6 {
                break;
            }
            assert_eq!(p[..2], frame::HEADER, "TX: not at a frame start: {p:02X?}");
            assert_eq!(p[2], frame::TYPE_DATA, "TX: device frames are type 1");
            let len = usize::from(u16::from_le_bytes([p[4], p[5]]));
            assert!(len >= 6, "TX: length field {len}");
            let n = len + 2;
            if p.len() < n {
                break;
            }
            let sum = u16::from_le_bytes([p[n - 2], p[n - 1]]);
            assert_eq!(frame::checksum(&p[2..n - 2]), sum, "TX: checksum");
            out.push((p[3], p[6..n - 2].to_vec()));
            self.pending.drain(..n);
        }
        out
    }

    /// At a power cycle (after the queue was drained): nothing half sent.
    fn end_session(&mut self) {
        assert!(self.pending.is_empty(), "TX: a frame cut short");
    }
}

/// Every SaveFlash frame (valid `type 0, id 0` frame whose payload parses
/// as SaveFlash) found anywhere in `rx`, as checksum → (id, value).
fn save_flash_frames(rx: &[u8]) -> Vec<(u16, u16, Vec<u8>)> {
    let mut out = Vec::new();
    for i in 0..rx.len() {
        let w = &rx[i..];
        if w.len() < 14 || w[..4] != [0xAA, 0x55, 0x00, 0x00] || w[6..8] != SAVE_FLASH.to_le_bytes()
        {
            continue;
        }
        let n = usize::from(u16::from_le_bytes([w[4], w[5]])) + 2;
        if n > w.len() || !(8..=RX_FRAME_CAP).contains(&n) {
            continue;
        }
        let sum = u16::from_le_bytes([w[n - 2], w[n - 1]]);
        if frame::checksum(&w[2..n - 2]) != sum {
            continue;
        }
        if let Ok(Command::SaveFlash { id, value, .. }) = Command::parse(&w[6..n - 2]) {
            out.push((sum, id, value.to_vec()));
        }
    }
    out
}

/// The device harness: the device, its clock, what it was sent and what
/// it must hold.
struct Harness {
    dev: Device<RamNor<8192>, Kernel>,
    product: Product,
    now: u64,
    ticks_left: u32,
    tx: TxCheck,
    /// RX bytes of this power session (to find the SaveFlash frames).
    rx: Vec<u8>,
    /// SaveFlash acknowledgements seen this session (their checksums).
    acks: Vec<u16>,
    /// Per parameter ID, the values it may hold after a power cycle.
    allowed: BTreeMap<u16, Vec<Vec<u8>>>,
    dropped_at_start: u32,
    /// The SaveFlash sent while a power cut was scheduled: the cut may
    /// come after its last flash step (a torn step can end fully done), so
    /// the new value may load although no acknowledgement left.
    cut_save: Option<(u16, Vec<u8>)>,
    /// Periodic-output tracking: (rate, tick of the last stream frame).
    last_output: Option<(u32, u64)>,
    tick_no: u64,
}

impl Harness {
    fn new(product: Product, seed: u64) -> Self {
        let dev = Device::power_on_with(
            PowerOn {
                product,
                boot: None,
                seed,
            },
            RamNor::new(),
            Instant::ZERO,
        );
        let factory = params::factory_block(&product);
        let allowed = PARAMS
            .iter()
            .map(|p| (p.id, vec![factory[p.range()].to_vec()]))
            .collect();
        let h = Harness {
            dev,
            product,
            now: 0,
            ticks_left: TICK_BUDGET,
            tx: TxCheck::default(),
            rx: Vec::new(),
            acks: Vec::new(),
            allowed,
            dropped_at_start: 0,
            cut_save: None,
            last_output: None,
            tick_no: 0,
        };
        h.check_params();
        h
    }

    /// Sends a SaveFlash frame (ICD 5.3.7) of `value` for parameter `id`.
    fn save_flash(&mut self, id: u16, value: &[u8]) {
        let mut out = [0u8; 32];
        let n = Command::SaveFlash {
            id,
            len: value.len() as u16,
            value,
        }
        .encode(&mut out)
        .unwrap_or(0);
        self.rx(&out[..n]);
    }

    fn rx(&mut self, bytes: &[u8]) {
        self.rx.extend_from_slice(bytes);
        self.dev.on_rx(bytes, Instant(self.now));
        self.last_output = None;
        self.invariants();
    }

    /// Moves up to `max` TX bytes out (taking line-rate events as they
    /// come) and checks them; returns the frames completed.
    fn read_tx(&mut self, max: usize) -> Vec<(u8, Vec<u8>)> {
        let mut frames = Vec::new();
        let tx = &mut self.tx;
        drain_tx(&mut self.dev, max, |b| frames.extend(tx.feed(b)));
        for (id, payload) in &frames {
            if *id == 0xB2 && payload.len() == 2 {
                self.acks.push(u16::from_le_bytes([payload[0], payload[1]]));
            }
        }
        frames
    }

    fn drain(&mut self) -> Vec<(u8, Vec<u8>)> {
        let mut all = Vec::new();
        loop {
            let f = self.read_tx(4096);
            let empty = f.is_empty() && self.dev.tx_len() == 0;
            all.extend(f);
            if empty {
                break;
            }
        }
        all
    }

    /// Runs `n` ticks, the TX queue drained after each one (a fast line):
    /// checks that periodic output comes exactly every `internal / rate`
    /// ticks while nothing else happens.
    fn ticks(&mut self, n: u32) {
        let n = n.min(self.ticks_left);
        self.ticks_left -= n;
        let internal = self.product.model.internal_rate_hz;
        // What RX ops queued goes out first, so no output frame is dropped
        // for a full queue.
        self.drain();
        for _ in 0..n {
            let dropped = self.dev.tx_dropped();
            let rate = self.dev.output_rate();
            let mode = self.dev.mode();
            let periodic = self.dev.ticks_to_next_output().is_some();
            self.now += self.dev.tick_period_ns();
            self.tick_no += 1;
            self.dev.on_tick(Instant(self.now));
            let frames = self.drain();
            let replies = frames
                .iter()
                .filter(|(id, p)| !(imu_emu::kernel::formats::is_data_command(*id) && p.len() > 2))
                .count();
            let outputs = frames.len() - replies;
            if replies > 0
                || rate != self.dev.output_rate()
                || mode != self.dev.mode()
                || dropped != self.dev.tx_dropped()
            {
                // A command was executed inside the tick (a frame found
                // after an idle abandon): the schedule may restart.
                self.last_output = None;
                continue;
            }
            assert!(outputs <= 1, "one output frame per tick at most");
            if outputs == 1 {
                assert!(
                    periodic,
                    "output frame from a stream without periodic output"
                );
                let r = rate.expect("output while streaming");
                if let Some((r0, t0)) = self.last_output {
                    if r0 == r {
                        assert_eq!(
                            self.tick_no - t0,
                            u64::from(internal / r),
                            "output not at the rate's divisor"
                        );
                    }
                }
                self.last_output = Some((r, self.tick_no));
            }
            self.invariants();
        }
    }

    fn invariants(&mut self) {
        assert!(self.dev.tx_len() <= TX_CAP, "TX queue bounded");
        if let Some(rate) = self.dev.output_rate() {
            let internal = self.product.model.internal_rate_hz;
            assert!(
                rate >= 1 && internal.is_multiple_of(rate),
                "rate {rate} divides {internal}"
            );
        }
        if self.dev.mode() == Mode::FirmwareUpdate {
            assert_eq!(self.dev.tx_len(), 0, "firmware-update mode sends nothing");
        }
    }

    /// Power cycle: what was queued goes out first (the acknowledgements
    /// are seen), then every parameter must hold an allowed value.
    fn power_cycle(&mut self, boot: Option<Level>) {
        self.drain();
        self.tx.end_session();
        self.settle_acks();
        let cut = self.cut_save.take();
        if let Some((id, value)) = &cut {
            // Old or new, never anything else (ICD 5.3.7 and power loss).
            let v = self.allowed.entry(*id).or_default();
            v.push(value.clone());
            v.sort();
            v.dedup();
        }
        self.dev.flash_mut().restore_power();
        self.now += 1_000_000;
        self.dev.power_cycle_with(boot, Instant(self.now));
        self.last_output = None;
        self.check_params();
        if let Some((id, _)) = cut {
            // Whichever it was, it is what the flash holds from now on.
            let got = self.dev.param_ram(id).expect("a Table 5.24 ID").to_vec();
            self.allowed.insert(id, vec![got]);
        }
        self.drain();
        self.invariants();
    }

    /// Folds this session's acknowledgements, in order, into `allowed`: an
    /// ack whose checksum matches exactly one SaveFlash frame sent fixes that
    /// value; several (a checksum collision) add each of them to what was
    /// allowed. If any frame was dropped (TX queue full), an ack may be
    /// missing: every SaveFlash sent becomes allowed.
    fn settle_acks(&mut self) {
        let frames = save_flash_frames(&self.rx);
        for &sum in &self.acks {
            let matching: Vec<_> = frames.iter().filter(|f| f.0 == sum).collect();
            assert!(
                !matching.is_empty(),
                "an ack {sum:#06x} for no SaveFlash sent"
            );
            if let [(_, id, v)] = matching[..] {
                self.allowed.insert(*id, vec![v.clone()]);
            } else {
                for (_, id, v) in matching {
                    self.allowed.entry(*id).or_default().push(v.clone());
                }
            }
        }
        if self.dev.tx_dropped() != self.dropped_at_start {
            for (_, id, v) in frames {
                self.allowed.entry(id).or_default().push(v);
            }
        }
        for v in self.allowed.values_mut() {
            v.sort();
            v.dedup();
        }
        self.rx.clear();
        self.acks.clear();
        self.dropped_at_start = self.dev.tx_dropped();
    }

    /// Every parameter holds the factory default, the value of a save a
    /// power cut interrupted (see `cut_save`) or a value acknowledged
    /// by SaveFlash (ICD 5.3.7).
    fn check_params(&self) {
        for p in PARAMS {
            let got = self.dev.param_ram(p.id).expect("a Table 5.24 ID");
            let ok = self
                .allowed
                .get(&p.id)
                .is_some_and(|v| v.iter().any(|x| x == got));
            assert!(
                ok,
                "{} holds {got:02X?}, allowed {:02X?}",
                p.name,
                self.allowed.get(&p.id)
            );
        }
    }
}

/// A few valid SaveFlash values, so scripts reach deep states quickly.
const SAVES: &[(u16, &[u8])] = &[
    (0x0012, &[0xC8, 0x00]),
    (0x0012, &[0xD0, 0x07]),
    (0x0012, &[0x01, 0x00]),
    (0x0014, &[0x00, 0x00]),
    (0x03B2, &[0x0B]),
    (0x03B2, &[0x01]),
    (0x03A9, &[0x8F]),
    (0x03A9, &[0x95]),
    (0x03D0, &[0x02]),
    (0x03D7, &[0xFF]),
    (0x0499, &[0x01]),
    (0x05FA, &[0x01]),
    (0x05FB, &[0x01]),
    (0x05FE, &[0x0A, 0x00]),
    (0x0413, &[0x01]),
];

/// The whole KERNEL device, driven by a script: RX bytes (raw, as a
/// well-formed command frame, as a SaveFlash), ticks, pin edges, power
/// cycles with and without BOOT, power cuts at any step of a flash save,
/// TX reads of any size. Invariants: TX bytes always parse as whole frames
/// with good checksums; after every power cycle each parameter holds the
/// factory default, a value SaveFlash acknowledged or the value whose save
/// a power cut interrupted (old or new, nothing else); periodic output only
/// at divisors of the internal rate, exactly every `internal / rate`
/// ticks; the TX queue stays within [`TX_CAP`]; nothing panics.
pub fn device(data: &[u8]) {
    let mut c = Cursor::new(data);
    let product = Product::parse(MODELS[usize::from(c.u8()) % MODELS.len()]).expect("model");
    let mut h = Harness::new(product, u64::from(c.u8()));
    while !c.is_empty() {
        match c.u8() % 12 {
            0 => {
                let n = usize::from(c.u8() % 64);
                let bytes = c.bytes(n).to_vec();
                h.rx(&bytes);
            }
            1 | 2 => {
                // A well-formed command frame with a payload from the input.
                let n = usize::from(c.u8() % 24);
                let payload = c.bytes(n).to_vec();
                let mut out = [0u8; 64];
                if let Some(k) = frame::encode(0, 0, &payload, &mut out) {
                    h.rx(&out[..k]);
                }
            }
            3 => {
                // A one-byte command (data commands, Stop, GetBIT, UDD…).
                let codes = [
                    0x33, 0x8F, 0x9B, 0xA5, 0xA6, 0x82, 0x81, 0x95, 0xFE, 0x12, 0x1A, 0x96, 0x97,
                    0xC2, 0x41,
                ];
                let code = codes[usize::from(c.u8()) % codes.len()];
                let mut out = [0u8; 16];
                let k = Command::Data(code).encode(&mut out).unwrap_or(0);
                h.rx(&out[..k]);
            }
            4 => {
                let (id, value) = SAVES[usize::from(c.u8()) % SAVES.len()];
                h.save_flash(id, value);
            }
            5 => {
                let n = u32::from(c.u8()) * 8;
                h.ticks(n);
            }
            6 => {
                let t = c.u8();
                let pin = if t & 1 == 0 { Pin::Pps } else { Pin::Extrig };
                let level = if t & 2 == 0 { Level::Low } else { Level::High };
                let at = h.now + u64::from(t >> 2) * 1000;
                h.dev.on_pin(pin, level, Instant(at));
                h.last_output = None;
                h.read_tx(4096);
                h.invariants();
            }
            7 => {
                let b = c.u8();
                let boot = match b % 3 {
                    0 => None,
                    1 => Some(Level::Low),
                    _ => Some(Level::High),
                };
                h.power_cycle(boot);
            }
            8 => {
                // Power cut at step k (torn) of the next flash save, then
                // a SaveFlash, then the power is gone: a power cycle.
                let k = u32::from(c.u16() % 420);
                let seed = c.u32();
                h.dev.flash_mut().cut_power_torn(k, seed);
                let (id, value) = SAVES[usize::from(c.u8()) % SAVES.len()];
                h.save_flash(id, value);
                h.cut_save = Some((id, value.to_vec()));
                h.power_cycle(None);
            }
            9 => {
                let n = usize::from(c.u16() % 600);
                h.read_tx(n);
                h.invariants();
            }
            10 => {
                // A UDD configuration message with types from the input.
                let n = c.u8() % 20;
                let mut p = vec![0x96, n];
                p.extend_from_slice(c.bytes(usize::from(n)));
                let mut out = [0u8; 64];
                if let Some(k) = frame::encode(0, 0, &p, &mut out) {
                    h.rx(&out[..k]);
                }
            }
            _ => {
                // Idle time long enough to abandon a partial frame.
                h.ticks(250);
            }
        }
    }
    h.power_cycle(None);
}
