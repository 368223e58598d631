//! The fuzz targets' bodies (issue 13 "Fuzzing"): each takes the raw
//! fuzzer input and panics on a broken invariant, never merely on bad
//! input. Kept in a library so the four `fuzz_targets/*.rs` stay one line
//! and a crash input can be replayed from a unit test or a debugger.
//!
//! * [`kernel_frame`] — the KERNEL frame decoder (ICD Table 5.2).
//! * [`isb_packet`] — the ISB packet decoder.
//! * [`device`] — the whole KERNEL device for several models, driven by a
//!   script decoded from the input.
//! * [`isb_device`] — the whole ISB device (the emulated IMX-5), driven by
//!   a script decoded from the input.
//! * [`store`] — the parameter store with power cuts at arbitrary
//!   program/erase steps.

use std::collections::BTreeMap;

// The invariants lean on the core's debug assertions and overflow checks
// too: refuse a build without them (see Cargo.toml's release profile).
#[cfg(not(debug_assertions))]
compile_error!("build the fuzz targets with debug assertions (fuzz/Cargo.toml release profile)");

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, Level, Mode, Pin, PowerOn, TX_CAP};
use imu_emu::kernel::RX_FRAME_CAP;
use imu_emu::kernel::command::{Command, SAVE_FLASH};
use imu_emu::kernel::frame::{self, Decoder as KernelDecoder};
use imu_emu::kernel::params::{self, PARAMS};
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::store::{ImageSpec, ParamStore, KERNEL_IMAGE};
use imu_emu::time::Instant;
use imu_emu::{framing, isb};

/// Reads the fuzzer input as a script: bytes and little numbers, 0 when
/// the input is used up.
pub struct Cursor<'a> {
    data: &'a [u8],
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Cursor { data }
    }

    /// Whether every byte has been read.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The next byte (0 past the end).
    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    /// The next little-endian u16.
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    /// The next little-endian u32.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// Up to `n` next bytes.
    pub fn bytes(&mut self, n: usize) -> &'a [u8] {
        let (head, rest) = self.data.split_at(n.min(self.data.len()));
        self.data = rest;
        head
    }
}

/// Chunk lengths 0..=16 from a xorshift seeded by `seed`.
struct Chunks(u32);

impl Chunks {
    fn next(&mut self) -> usize {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x % 17) as usize
    }
}

/// Every packet a scanner finds in `input` fed in the chunks `chunk`
/// gives (0-length chunks included), as raw bytes.
fn scan_all<F: framing::Framing, const CAP: usize>(
    input: &[u8],
    mut chunk: impl FnMut() -> usize,
) -> Vec<Vec<u8>> {
    let mut s = framing::Scanner::<F, CAP>::new();
    let mut out = Vec::new();
    let mut rest = input;
    loop {
        let n = chunk().min(rest.len());
        let (mut piece, tail) = rest.split_at(n);
        while let Some(raw) = s.next_raw(&mut piece) {
            out.push(raw.to_vec());
        }
        assert!(piece.is_empty(), "the scanner takes every byte it is given");
        rest = tail;
        if rest.is_empty() {
            break;
        }
    }
    out
}

/// The same packets whatever the chunking: one shot, byte by byte, and
/// pseudo-random chunks (seeded by the input's first four bytes).
fn chunking_invariant<F: framing::Framing, const CAP: usize>(data: &[u8]) -> Vec<Vec<u8>> {
    let mut c = Cursor::new(data);
    let seed = c.u32() | 1;
    let input = c.bytes(data.len());
    let one = scan_all::<F, CAP>(input, || usize::MAX);
    let bytewise = scan_all::<F, CAP>(input, || 1);
    assert_eq!(one, bytewise, "byte-by-byte chunking changed the packets");
    let mut chunks = Chunks(seed);
    let random = scan_all::<F, CAP>(input, || chunks.next());
    assert_eq!(one, random, "chunking changed the packets");
    one
}

/// KERNEL frame decoder: chunking invariance, and every frame it emits
/// re-encodes ([`frame::encode`]) to exactly its bytes, with a valid
/// header, length field and checksum.
pub fn kernel_frame(data: &[u8]) {
    for raw in chunking_invariant::<frame::Kernel, RX_FRAME_CAP>(data) {
        let n = raw.len();
        assert!((frame::OVERHEAD..=RX_FRAME_CAP).contains(&n));
        assert_eq!(raw[..2], frame::HEADER);
        assert_eq!(usize::from(u16::from_le_bytes([raw[4], raw[5]])), n - 2);
        let mut out = vec![0u8; n];
        let m = frame::encode(raw[2], raw[3], &raw[6..n - 2], &mut out);
        assert_eq!(m, Some(n));
        assert_eq!(out, raw, "re-encode differs");
        // The typed decoder agrees with the raw one.
        let mut d = KernelDecoder::<RX_FRAME_CAP>::new();
        let mut input = &raw[..];
        let f = d.next_frame(&mut input).expect("a frame decodes again");
        assert_eq!(
            (f.msg_type, f.id, f.payload),
            (raw[2], raw[3], &raw[6..n - 2])
        );
        // A command payload parses and, when it does, re-encodes the same.
        if let Ok(cmd) = Command::parse(f.payload) {
            let mut again = [0u8; 300];
            if let Some(k) = cmd.encode(&mut again) {
                if f.msg_type == frame::TYPE_COMMAND && f.id == 0 {
                    assert_eq!(&again[..k], &raw[..], "command re-encode");
                }
            }
        }
    }
}

/// ISB packet decoder: chunking invariance, and every packet re-encodes
/// ([`isb::packet::encode`]) to exactly its bytes.
pub fn isb_packet(data: &[u8]) {
    use isb::packet::{encode, Isb, MAX_PACKET, OVERHEAD, PREAMBLE};
    for raw in chunking_invariant::<Isb, MAX_PACKET>(data) {
        let n = raw.len();
        assert!((OVERHEAD..=MAX_PACKET).contains(&n));
        assert_eq!(raw[..2], PREAMBLE);
        assert_eq!(usize::from(u16::from_le_bytes([raw[4], raw[5]])), n - 8);
        let mut out = vec![0u8; n];
        assert_eq!(encode(raw[2], raw[3], &raw[6..n - 2], &mut out), Some(n));
        assert_eq!(out, raw, "re-encode differs");
        let mut d = isb::packet::Decoder::<MAX_PACKET>::new();
        let mut input = &raw[..];
        let p = d.next_packet(&mut input).expect("a packet decodes again");
        assert_eq!(
            (p.flags, p.did, p.payload),
            (raw[2], raw[3], &raw[6..n - 2])
        );
    }
}

// ---------------------------------------------------------------- device

/// Models the device target runs (one per input, from its first byte).
const MODELS: [&str; 6] = ["K110", "K201", "K120", "K100", "K110M-G450-A8", "K220"];
/// Most ticks one input may run (keeps an execution in milliseconds).
const TICK_BUDGET: u32 = 24_000;

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
    dev: Device<RamNor<8192>>,
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
        let mut buf = [0u8; 1024];
        let mut frames = Vec::new();
        let mut left = max;
        while left > 0 {
            while self.dev.poll_event().is_some() {}
            let n = self.dev.poll_tx(&mut buf[..left.min(1024)]);
            if n == 0 {
                break;
            }
            left -= n;
            frames.extend(self.tx.feed(&buf[..n]));
        }
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

// ---------------------------------------------------------------- store

/// A 301-byte second image (the shape of the ISB FLASH_CONFIG one).
const OTHER: ImageSpec = ImageSpec {
    len: 301,
    magic: *b"ISBC",
    version: 1,
};

/// One store's expectations.
struct StoreTrack {
    store: ParamStore<ImageSpec>,
    /// What loads (the newest complete save; `None` before the first).
    current: Option<Vec<u8>>,
}

fn load_image<F: NorFlash>(s: &ParamStore<ImageSpec>, flash: &mut F) -> Option<Vec<u8>> {
    let mut out = vec![0; usize::from(s.spec().len)];
    s.load(flash, &mut out)
        .expect("a powered flash loads")
        .then_some(out)
}

/// The parameter store with power cuts at arbitrary program/erase steps
/// (half-done or torn): two stores (the KERNEL block at 0, a 301-byte image
/// at 8192) in one flash; each op saves an image derived from the input to
/// one of them, maybe cut. After every op: a completed (`Ok`) save loads;
/// a cut one loads the previous image or the new one, never anything
/// else, never older than the last completed save; the other store is
/// untouched.
pub fn store(data: &[u8]) {
    let mut c = Cursor::new(data);
    let mut flash = RamNor::<16384>::new();
    let mut tracks = [
        StoreTrack {
            store: ParamStore::for_image(0, KERNEL_IMAGE),
            current: None,
        },
        StoreTrack {
            store: ParamStore::for_image(8192, OTHER),
            current: None,
        },
    ];
    while !c.is_empty() {
        let op = c.u8();
        let which = usize::from(op & 1);
        let t = &tracks[which];
        let len = usize::from(t.store.spec().len);
        // The new image: the current one with some bytes changed.
        let mut image = t.current.clone().unwrap_or_else(|| vec![0xFF; len]);
        for _ in 0..(op >> 1) % 8 {
            let at = usize::from(c.u16()) % len;
            image[at] = c.u8();
        }
        let cut = c.u16();
        let torn = c.u32();
        match cut % 4 {
            0 => {}
            1 => flash.cut_power_after(u32::from(cut >> 2)),
            _ => flash.cut_power_torn(u32::from(cut >> 2), torn),
        }
        let r = tracks[which].store.save(&mut flash, &image);
        let was_cut = flash.power_lost();
        flash.restore_power();
        assert_eq!(r.is_ok(), !was_cut, "Ok iff the save ran to the end");
        for (i, t) in tracks.iter_mut().enumerate() {
            let got = load_image(&t.store, &mut flash);
            if i != which {
                assert_eq!(got, t.current, "the other store changed");
            } else if r.is_ok() {
                assert_eq!(got.as_ref(), Some(&image), "a completed save loads");
            } else {
                assert!(
                    got == t.current || got.as_ref() == Some(&image),
                    "a cut save loaded neither the old nor the new image"
                );
            }
            t.current = got;
        }
    }
}

// ------------------------------------------------------------ isb_device

/// Checks the TX byte stream of an ISB session: whole ISB packets with good
/// checksums or whole `$…*hh\r\n` sentences with good checksums, back to
/// back.
#[derive(Default)]
struct IsbTx {
    pending: Vec<u8>,
}

impl IsbTx {
    fn feed(&mut self, bytes: &[u8]) {
        use isb::packet::{checksum, MAX_PACKET, OVERHEAD, PREAMBLE};
        self.pending.extend_from_slice(bytes);
        loop {
            let p = &self.pending;
            let Some(&first) = p.first() else { break };
            if first == b'$' {
                let Some(end) = p.iter().position(|&b| b == b'\n') else {
                    assert!(p.len() < 256, "TX: a sentence without an end");
                    break;
                };
                let s = &p[..=end];
                assert!(
                    s.len() >= 6 && s[s.len() - 2] == b'\r',
                    "TX: sentence ending"
                );
                let star = s.len() - 5;
                assert_eq!(s[star], b'*', "TX: sentence checksum field");
                let want = s[1..star].iter().fold(0u8, |a, &c| a ^ c);
                let hex = std::str::from_utf8(&s[star + 1..star + 3]).expect("hex");
                assert_eq!(u8::from_str_radix(hex, 16).ok(), Some(want), "TX: NMEA sum");
                self.pending.drain(..=end);
                continue;
            }
            assert_eq!(first, PREAMBLE[0], "TX: not at a packet or sentence start");
            if p.len() < 6 {
                break;
            }
            assert_eq!(p[1], PREAMBLE[1], "TX: preamble");
            let n = usize::from(u16::from_le_bytes([p[4], p[5]])) + OVERHEAD;
            assert!(n <= MAX_PACKET, "TX: packet of {n} bytes");
            if p.len() < n {
                break;
            }
            assert_eq!(checksum(&p[..n - 2]), p[n - 2..n], "TX: ISB checksum");
            self.pending.drain(..n);
        }
    }

    fn end_session(&mut self) {
        assert!(self.pending.is_empty(), "TX: a packet cut short");
    }
}

/// DIDs an ISB script asks for: every served one, some unserved and some
/// NACKed.
const ISB_DIDS: [u8; 16] = [
    1, 3, 7, 9, 10, 12, 58, 64, 68, 97, 2, 95, 121, 123, 132, 200,
];

struct IsbHarness {
    dev: Device<RamNor<16384>, isb::Isb>,
    now: u64,
    ticks_left: u32,
    tx: IsbTx,
}

impl IsbHarness {
    fn read_tx(&mut self, max: usize) {
        let mut buf = [0u8; 1024];
        let mut left = max;
        while left > 0 {
            while self.dev.poll_event().is_some() {}
            let n = self.dev.poll_tx(&mut buf[..left.min(1024)]);
            if n == 0 {
                break;
            }
            left -= n;
            self.tx.feed(&buf[..n]);
        }
    }

    fn drain(&mut self) {
        while self.dev.tx_len() > 0 {
            self.read_tx(4096);
        }
        self.read_tx(4096);
    }

    fn rx(&mut self, bytes: &[u8]) {
        self.dev.on_rx(bytes, Instant(self.now));
        self.invariants();
    }

    fn ticks(&mut self, n: u32) {
        let n = n.min(self.ticks_left);
        self.ticks_left -= n;
        self.drain();
        for _ in 0..n {
            self.now += self.dev.tick_period_ns();
            self.dev.on_tick(Instant(self.now));
            self.drain();
            self.invariants();
        }
    }

    fn invariants(&self) {
        assert!(self.dev.tx_len() <= TX_CAP, "TX queue bounded");
        let cfg = self.dev.personality().flash_config();
        assert!(cfg.is_valid(), "FLASH_CONFIG checksum in step");
        assert!(
            self.dev.personality().streams().count() <= isb::device::MAX_STREAMS,
            "streams bounded"
        );
    }

    fn power_cycle(&mut self, boot: Option<Level>) {
        self.drain();
        self.tx.end_session();
        self.dev.flash_mut().restore_power();
        self.now += 1_000_000;
        self.dev.power_cycle_with(boot, Instant(self.now));
        self.drain();
        self.invariants();
    }

    fn config(&self) -> Vec<u8> {
        self.dev.personality().flash_config().0.to_vec()
    }
}

/// What a boot makes of a saved FLASH_CONFIG: itself, or the factory
/// defaults when its `key` is not the factory key.
fn expected_after_boot(saved: Vec<u8>) -> Vec<u8> {
    use isb::sets::{flash, le, FlashConfig};
    if le::u32(&saved, flash::KEY) == flash::FACTORY_KEY {
        saved
    } else {
        FlashConfig::factory().0.to_vec()
    }
}

fn isb_get(did: u8, size: u16, offset: u16, period: u16) -> Vec<u8> {
    let req = isb::message::GetRequest {
        did: u16::from(did),
        size,
        offset,
        period,
    };
    let mut out = [0u8; 32];
    let n = isb::message::encode_get(&req, &mut out).unwrap_or(0);
    out[..n].to_vec()
}

fn isb_set(did: u8, offset: u16, data: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 512];
    let n = isb::message::encode_set(did, offset, data, &mut out).unwrap_or(0);
    out[..n].to_vec()
}

/// The whole ISB device (the emulated IMX-5), driven by a script: raw RX
/// bytes, GET_DATA and SET_DATA of any DID, size, offset and period, the
/// NMEA commands, SYS_CMD, ticks, EXTRIG edges, power cycles with and
/// without BOOT, power cuts (torn) in a FLASH_CONFIG save, TX reads of any
/// size. Invariants: TX bytes are always whole ISB packets or NMEA
/// sentences with good checksums; FLASH_CONFIG's checksum is always in
/// step; a power cycle keeps the FLASH_CONFIG saved before it (or restores
/// the defaults when its `key` was changed), and a cut save leaves the old
/// or the new one; the TX queue and the streams stay
/// bounded; nothing panics.
pub fn isb_device(data: &[u8]) {
    let mut c = Cursor::new(data);
    let dev = Device::<RamNor<16384>, isb::Isb>::new(
        PowerOn {
            product: Product::imx5(),
            boot: None,
            seed: u64::from(c.u8()),
        },
        RamNor::new(),
        Instant::ZERO,
    );
    let mut h = IsbHarness {
        dev,
        now: 0,
        ticks_left: TICK_BUDGET,
        tx: IsbTx::default(),
    };
    while !c.is_empty() {
        match c.u8() % 11 {
            0 => {
                let n = usize::from(c.u8() % 64);
                let bytes = c.bytes(n).to_vec();
                h.rx(&bytes);
            }
            1 | 2 => {
                let did = ISB_DIDS[usize::from(c.u8()) % ISB_DIDS.len()];
                let (size, offset, period) = (c.u16() % 320, c.u16() % 320, c.u16() % 8);
                h.rx(&isb_get(did, size, offset, period));
            }
            3 => {
                let did = ISB_DIDS[usize::from(c.u8()) % ISB_DIDS.len()];
                let offset = c.u16() % 300;
                let n = usize::from(c.u8() % 40);
                let data = c.bytes(n).to_vec();
                h.rx(&isb_set(did, offset, &data));
            }
            4 => {
                let s = isb::nmea::Command::ALL[usize::from(c.u8()) % 5].sentence();
                h.rx(s.as_bytes());
            }
            5 => {
                let n = u32::from(c.u8()) * 8;
                h.ticks(n);
            }
            6 => {
                let t = c.u8();
                let level = if t & 1 == 0 { Level::Low } else { Level::High };
                h.dev.on_pin(Pin::Extrig, level, Instant(h.now));
                h.read_tx(4096);
                h.invariants();
            }
            7 => {
                // A clean power cycle keeps what was saved (one tick
                // flushes a pending save first).
                h.ticks_left += 1;
                h.ticks(1);
                let before = h.config();
                let boot = match c.u8() % 3 {
                    0 => None,
                    1 => Some(Level::Low),
                    _ => Some(Level::High),
                };
                h.power_cycle(boot);
                assert_eq!(
                    h.config(),
                    expected_after_boot(before),
                    "FLASH_CONFIG kept over a power cycle"
                );
            }
            8 => {
                // A FLASH_CONFIG write whose save is cut at step k (torn):
                // afterwards the old or the new image, nothing else.
                h.ticks_left += 1;
                h.ticks(1);
                let old = h.config();
                let offset = 12 + 4 * (c.u16() % 60);
                let value = c.u32().to_le_bytes();
                h.rx(&isb_set(isb::did::FLASH_CONFIG, offset, &value));
                let new = h.config();
                let k = u32::from(c.u16() % 200);
                let seed = c.u32();
                h.dev.flash_mut().cut_power_torn(k, seed);
                h.ticks_left += 1;
                h.ticks(1);
                h.power_cycle(None);
                let got = h.config();
                assert!(
                    got == expected_after_boot(old) || got == expected_after_boot(new),
                    "a cut save left a third image"
                );
            }
            9 => {
                let n = usize::from(c.u16() % 600);
                h.read_tx(n);
                h.invariants();
            }
            _ => {
                let code = [1u32, 5, 97, 99, 0][usize::from(c.u8()) % 5];
                let cmd = isb::sets::SystemCommand::new(code);
                h.rx(&isb_set(isb::did::SYS_CMD, 0, &cmd.encode()));
            }
        }
    }
    h.power_cycle(None);
}
