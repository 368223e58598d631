//! The live motion feed: a sans-IO decoder of the samples a simulator or a
//! HIL rig sends (host: `--motion-feed`; firmware: a second UART), and the
//! per-device track that turns them into one truth a tick.
//!
//! Two encodings share one stream and may be mixed (`docs/feed.md` has the
//! byte-by-byte layout):
//!
//! * **Text**: one sample a line in the `--trajectory` row format,
//!   `time_s, wx, wy, wz, fx, fy, fz[, temp_c]` (s, °/s, g — at rest +1 g
//!   along up, ICD 5.2.1 — and °C), `\n` ended. Blank lines, `#` comments
//!   and a header naming the columns (`time,wx,…`) are skipped. After a
//!   full-state header, full-state rows (below).
//! * **Binary** ([`SYNC`], [`VERSION`], a kind, a body length, a device
//!   index, time in ns, six or seven `f32`, a CRC-16/CCITT-FALSE): 41 or
//!   45 bytes, for 2 kHz feeds over a UART.
//!
//! [`Decoder`] takes bytes in any chunking ([`Decoder::push`]) and yields
//! samples or counted rejections ([`Decoder::poll`]); the sequence depends
//! on the bytes only, never on how they were split. Garbage is skipped up
//! to the next line end or binary sync (one [`Reject::Malformed`] for the
//! torn line); a binary frame whose length or checksum is wrong is
//! rejected and the search for a sync goes on from its second byte, so a
//! good frame inside a bad one is still found (what follows a bad frame is
//! skipped up to the next `\n` or sync: a text row right after it is lost
//! with it).
//!
//! [`Track`] keeps the last two samples of one device: it rejects times
//! that do not increase ([`Reject::NonIncreasing`]), holds the last sample
//! and interpolates linearly between the two (what lockstep needs: device
//! time never passes the newest sample's time).
//!
//! **Full-state rows.** A text header naming the full-state columns
//! (`time,lat,lon,height,vn,ve,vd,roll,pitch,yaw[,wx,…,fz][,temp]`, the
//! header of a `--motion` full-state CSV,
//! [`FullStateLayout::from_header`]) switches the stream's text rows to
//! full-state rows ([`Sample::FullState`]), parsed by the vehicle module's
//! [`FullStateRow::parse`]; a rate header (`time,wx,…`) switches back. A
//! binary full-state kind ([`kind::FULL_STATE`]) stays reserved:
//! rejected as [`Reject::UnsupportedKind`].

use crc::{Crc, NoTable, CRC_16_IBM_3740};

use crate::math::decimal::parse as parse_number;
use crate::sensor::motion::{TRUTH_FORCE_LIMIT_G, TRUTH_RATE_LIMIT_DPS};
use crate::sensor::Truth;
use crate::vehicle::{FullStateLayout, FullStateRow, RowError, G_ICD};

/// The two bytes a binary sample starts with (never in text: not ASCII).
pub const SYNC: [u8; 2] = [0xF5, 0xED];
/// The binary layout's version (byte 2).
pub const VERSION: u8 = 1;
/// The device index meaning "the device this feed belongs to".
pub const OWN_DEVICE: u16 = 0xFFFF;
/// Longest text line, bytes (without its `\n`): room for a 17-column
/// full-state row (below the decoder's 256-byte buffer: a line is
/// decided within it).
pub const MAX_LINE: usize = 240;
/// Largest binary body (byte 4), bytes: room for a full-state kind.
pub const MAX_BODY: u8 = 128;
/// Bytes before the body: sync, version, kind, body length.
pub const HEAD: usize = 5;
/// Bytes of the checksum after the body.
pub const CRC_LEN: usize = 2;
/// Latest sample time accepted, s (about 58 years: far from `u64` ns
/// overflow).
pub const MAX_TIME_S: f64 = 1.8e9;
/// Sensor temperatures accepted, °C.
pub const TEMPERATURE_RANGE_C: (f32, f32) = (-100.0, 200.0);

/// The checksum: CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no
/// reflection, no final xor), over bytes 2 to the end of the body.
pub const CRC: Crc<u16, NoTable> = Crc::<u16, NoTable>::new(&CRC_16_IBM_3740);

/// Binary sample kinds (byte 3).
pub mod kind {
    /// Angular rate and specific force: six `f32`.
    pub const RATES: u8 = 1;
    /// Angular rate, specific force and sensor temperature: seven `f32`.
    pub const RATES_TEMP: u8 = 2;
    /// Reserved for the full vehicle state (module docs): rejected as
    /// [`super::Reject::UnsupportedKind`]; full-state samples are text rows.
    pub const FULL_STATE: u8 = 3;
}

/// Longest binary frame this build decodes (kind 2), bytes.
pub const MAX_FRAME: usize = 45;

/// The body length of a known kind: device (2) + time (8) + 4 × values.
pub const fn body_len(k: u8) -> Option<u8> {
    match k {
        kind::RATES => Some(10 + 24),
        kind::RATES_TEMP => Some(10 + 28),
        _ => None,
    }
}

const BUF: usize = 256;

/// One rate/force sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateSample {
    /// The device it is for ([`OWN_DEVICE`]: the feed's own; text rows).
    pub device: u16,
    /// Its time, ns (the simulator's clock; in lockstep, device time).
    pub time_ns: u64,
    /// Angular rate (°/s), specific force (g), temperature (°C) if given.
    pub truth: Truth,
}

/// One full-state sample: a text row after a full-state header (module
/// docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FullStateSample {
    /// The device it is for (text rows: [`OWN_DEVICE`]).
    pub device: u16,
    /// Its time, ns (`row.time_s` rounded to the ns).
    pub time_ns: u64,
    /// The row: position, velocity, attitude, and the rates, forces and
    /// temperature if its header names them.
    pub row: FullStateRow,
}

/// A decoded sample.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Sample {
    /// Body rates and specific forces (text rows, kinds 1 and 2).
    Rates(RateSample),
    /// The vehicle's full state (text rows after a full-state header).
    FullState(FullStateSample),
}

impl Sample {
    /// The device the sample names.
    pub fn device(&self) -> u16 {
        match self {
            Sample::Rates(s) => s.device,
            Sample::FullState(s) => s.device,
        }
    }

    /// The sample's time, ns.
    pub fn time_ns(&self) -> u64 {
        match self {
            Sample::Rates(s) => s.time_ns,
            Sample::FullState(s) => s.time_ns,
        }
    }
}

/// Why a sample was rejected (counted in [`Counts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reject {
    /// A text line that is not 7 or 8 numbers — after a full-state header,
    /// not its columns' count of numbers — or a torn line, garbage.
    Malformed = 0,
    /// A text line longer than [`MAX_LINE`].
    LineTooLong,
    /// A binary body length that is not its kind's (or beyond
    /// [`MAX_BODY`]).
    BadLength,
    /// A binary checksum mismatch.
    Checksum,
    /// A binary version other than [`VERSION`].
    UnsupportedVersion,
    /// A binary kind this build does not take (the reserved full state).
    UnsupportedKind,
    /// A value out of range: time negative or beyond [`MAX_TIME_S`], a
    /// rate beyond ±[`TRUTH_RATE_LIMIT_DPS`] (8192 °/s), a force beyond
    /// ±128 g, a temperature
    /// outside [`TEMPERATURE_RANGE_C`], or not finite; in a full-state
    /// row also the vehicle module's ranges ([`RowError::OutOfRange`]).
    OutOfRange,
    /// A time not after the device's previous sample ([`Track`]).
    NonIncreasing,
    /// A device index this feed does not serve (boards).
    WrongDevice,
    /// Lockstep: a time more than [`MAX_LEAD_NS`] ahead of the device's
    /// newest sample and of its device time (the host's clock too, at a
    /// `--speed` factor): taking it would stop the unit for the lead, or
    /// run the whole lead at once.
    TooFarAhead,
}

/// Lockstep: how far ahead of the newest sample (and of device time) a
/// sample may be, ns ([`Reject::TooFarAhead`]): 60 s of device time
/// (120 000 ticks at 2 kHz).
pub const MAX_LEAD_NS: u64 = 60_000_000_000;

/// Number of [`Reject`] reasons.
pub const REJECTS: usize = 10;

impl Reject {
    /// Every reason, in counter order.
    pub const ALL: [Reject; REJECTS] = [
        Reject::Malformed,
        Reject::LineTooLong,
        Reject::BadLength,
        Reject::Checksum,
        Reject::UnsupportedVersion,
        Reject::UnsupportedKind,
        Reject::OutOfRange,
        Reject::NonIncreasing,
        Reject::WrongDevice,
        Reject::TooFarAhead,
    ];

    /// Its name in logs and `status` (`rejected-<name>=N`).
    pub fn name(self) -> &'static str {
        match self {
            Reject::Malformed => "malformed",
            Reject::LineTooLong => "line-too-long",
            Reject::BadLength => "bad-length",
            Reject::Checksum => "checksum",
            Reject::UnsupportedVersion => "version",
            Reject::UnsupportedKind => "kind",
            Reject::OutOfRange => "out-of-range",
            Reject::NonIncreasing => "non-increasing",
            Reject::WrongDevice => "wrong-device",
            Reject::TooFarAhead => "too-far-ahead",
        }
    }
}

/// Samples taken and rejections by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counts {
    /// Samples accepted.
    pub samples: u64,
    /// Rejections, indexed by `Reject as usize`.
    pub rejected: [u64; REJECTS],
}

impl Counts {
    /// Counts one outcome.
    pub fn note(&mut self, r: Result<(), Reject>) {
        match r {
            Ok(()) => self.samples += 1,
            Err(e) => self.rejected[e as usize] += 1,
        }
    }

    /// All rejections.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.iter().sum()
    }
}

/// The feed decoder (module docs). Fixed size, no heap.
#[derive(Debug, Clone)]
pub struct Decoder {
    buf: [u8; BUF],
    len: usize,
    /// Discarding the rest of a rejected line or frame (no second
    /// rejection) up to a `\n` or a sync.
    skipping: bool,
    /// The layout of text rows: `Some` after a full-state header.
    layout: Option<FullStateLayout>,
    counts: Counts,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

/// What the front of the buffer holds.
enum Front {
    /// More bytes are needed to decide.
    Wait,
    /// `n` bytes consumed, nothing to report.
    Skip(usize),
    /// `n` bytes consumed, an outcome to report; then skip the rest of a
    /// bad line or frame.
    Done(usize, Result<Sample, Reject>, bool),
}

impl Decoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; BUF],
            len: 0,
            skipping: false,
            layout: None,
            counts: Counts {
                samples: 0,
                rejected: [0; REJECTS],
            },
        }
    }

    /// The layout text rows are read in: `Some` after a full-state header
    /// (module docs), `None` for rate rows.
    pub fn layout(&self) -> Option<FullStateLayout> {
        self.layout
    }

    /// Decoded samples and the decoder's rejections so far.
    pub fn counts(&self) -> &Counts {
        &self.counts
    }

    /// Takes as many of `bytes` as fit; how many. Call [`Decoder::poll`]
    /// until `None` before pushing the rest.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        let n = bytes.len().min(BUF - self.len);
        self.buf[self.len..self.len + n].copy_from_slice(&bytes[..n]);
        self.len += n;
        n
    }

    /// Feeds `bytes` and hands every outcome to `each`, in order.
    pub fn decode(&mut self, mut bytes: &[u8], each: &mut dyn FnMut(Result<Sample, Reject>)) {
        loop {
            let n = self.push(bytes);
            bytes = &bytes[n..];
            while let Some(r) = self.poll() {
                each(r);
            }
            if bytes.is_empty() {
                return;
            }
        }
    }

    /// The next sample or rejection the buffered bytes make, if any.
    pub fn poll(&mut self) -> Option<Result<Sample, Reject>> {
        loop {
            if self.len == 0 {
                return None;
            }
            let front = if self.skipping {
                self.skip_rest()
            } else if self.buf[..self.len.min(2)] == SYNC[..self.len.min(2)] {
                self.binary()
            } else {
                self.text()
            };
            match front {
                Front::Wait => {
                    if self.len == BUF {
                        // Never: every decision needs fewer bytes than BUF.
                        self.consume(1);
                        continue;
                    }
                    return None;
                }
                Front::Skip(n) => self.consume(n),
                Front::Done(n, r, skip) => {
                    self.consume(n);
                    self.skipping = skip;
                    self.counts.note(r.map(|_| ()));
                    return Some(r);
                }
            }
        }
    }

    fn consume(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    /// Where the text from the front ends: `(i, true)` a `\n` at `i`,
    /// `(i, false)` a sync at `i >= from`; `None` if undecided within
    /// `limit` bytes (more are needed) — `Some((limit, false))` past it.
    fn line_end(&self, from: usize, limit: usize) -> Option<(usize, bool)> {
        let b = &self.buf[..self.len];
        for i in 0..limit {
            let c = *b.get(i)?;
            if c == b'\n' {
                return Some((i, true));
            }
            if c == SYNC[0] && i >= from && *b.get(i + 1)? == SYNC[1] {
                return Some((i, false));
            }
        }
        Some((limit, false))
    }

    fn skip_rest(&mut self) -> Front {
        match self.line_end(0, self.len) {
            Some((i, true)) => {
                self.skipping = false;
                Front::Skip(i + 1)
            }
            Some((i, false)) if i < self.len => {
                self.skipping = false;
                Front::Skip(i)
            }
            // All of it (the scan reached the buffer's end).
            Some((i, _)) => Front::Skip(i),
            // All but a last byte that may start a sync.
            None if self.len > 1 => Front::Skip(self.len - 1),
            None => Front::Wait,
        }
    }

    fn text(&mut self) -> Front {
        match self.line_end(1, MAX_LINE + 1) {
            None => Front::Wait,
            Some((i, true)) => match parse_line(&self.buf[..i], &mut self.layout) {
                None => Front::Skip(i + 1),
                Some(r) => Front::Done(i + 1, r, false),
            },
            Some((i, false)) if i <= MAX_LINE => {
                // A line torn by a binary sample: garbage, unless blank.
                if self.buf[..i].iter().all(u8::is_ascii_whitespace) {
                    Front::Skip(i)
                } else {
                    Front::Done(i, Err(Reject::Malformed), false)
                }
            }
            Some((i, false)) => Front::Done(i, Err(Reject::LineTooLong), true),
        }
    }

    fn binary(&mut self) -> Front {
        if self.len < HEAD {
            return Front::Wait;
        }
        let body = usize::from(self.buf[4]);
        if body > usize::from(MAX_BODY) || body < 10 {
            return Front::Done(1, Err(Reject::BadLength), true);
        }
        let total = HEAD + body + CRC_LEN;
        if self.len < total {
            return Front::Wait;
        }
        let f = &self.buf[..total];
        let sum = u16::from_le_bytes([f[total - 2], f[total - 1]]);
        if CRC.checksum(&f[2..total - 2]) != sum {
            return Front::Done(1, Err(Reject::Checksum), true);
        }
        Front::Done(total, decode_binary(f), false)
    }
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    let mut w = [0u8; 4];
    w.copy_from_slice(&b[at..at + 4]);
    f32::from_le_bytes(w)
}

/// A whole binary frame whose checksum is right.
fn decode_binary(f: &[u8]) -> Result<Sample, Reject> {
    if f[2] != VERSION {
        return Err(Reject::UnsupportedVersion);
    }
    let k = f[3];
    let Some(len) = body_len(k) else {
        return Err(Reject::UnsupportedKind);
    };
    if f[4] != len {
        return Err(Reject::BadLength);
    }
    let device = u16::from_le_bytes([f[5], f[6]]);
    let mut t = [0u8; 8];
    t.copy_from_slice(&f[7..15]);
    let time_ns = u64::from_le_bytes(t);
    let v = |i: usize| f32_at(f, 15 + 4 * i);
    let temp = (k == kind::RATES_TEMP).then(|| v(6));
    let truth = Truth {
        rate_dps: [v(0), v(1), v(2)],
        specific_force_g: [v(3), v(4), v(5)],
        temperature_c: temp,
    };
    if time_ns > (MAX_TIME_S * 1e9) as u64 {
        return Err(Reject::OutOfRange);
    }
    checked(device, time_ns, truth)
}

/// The sample if its values are in range.
fn checked(device: u16, time_ns: u64, truth: Truth) -> Result<Sample, Reject> {
    let within = |v: f32, lim: f32| v.is_finite() && v.abs() <= lim;
    let (lo, hi) = TEMPERATURE_RANGE_C;
    let ok = truth
        .rate_dps
        .iter()
        .all(|&w| within(w, TRUTH_RATE_LIMIT_DPS))
        && truth
            .specific_force_g
            .iter()
            .all(|&f| within(f, TRUTH_FORCE_LIMIT_G))
        && truth
            .temperature_c
            .is_none_or(|t| t.is_finite() && (lo..=hi).contains(&t));
    if !ok {
        return Err(Reject::OutOfRange);
    }
    Ok(Sample::Rates(RateSample {
        device,
        time_ns,
        truth,
    }))
}

/// One text line (without `\n`) in `layout` (a header changes it):
/// `None` for a line that is skipped (blank, comment, a header).
fn parse_line(line: &[u8], layout: &mut Option<FullStateLayout>) -> Option<Result<Sample, Reject>> {
    let Ok(line) = core::str::from_utf8(line) else {
        return Some(Err(Reject::Malformed));
    };
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return None;
    }
    if let Some(l) = *layout {
        // A header's first cell is a word: not a number.
        return match full_state(line, &l) {
            Err(None) => header(line, layout),
            r => Some(r.map_err(|e| e.unwrap_or(Reject::Malformed))),
        };
    }
    let mut v = [0f64; 8];
    let mut n = 0;
    for cell in line.split(',').map(str::trim) {
        let Some(x) = parse_number(cell) else {
            return header(line, layout);
        };
        if n == v.len() {
            return Some(Err(Reject::Malformed));
        }
        v[n] = x;
        n += 1;
    }
    if n != 7 && n != 8 {
        return Some(Err(Reject::Malformed));
    }
    if !(0.0..=MAX_TIME_S).contains(&v[0]) {
        return Some(Err(Reject::OutOfRange));
    }
    // f64 beyond f32 saturates to ±∞ and is then out of range.
    let truth = Truth {
        rate_dps: [v[1] as f32, v[2] as f32, v[3] as f32],
        specific_force_g: [v[4] as f32, v[5] as f32, v[6] as f32],
        temperature_c: (n == 8).then_some(v[7] as f32),
    };
    let time_ns = libm::round(v[0] * 1e9) as u64;
    Some(checked(OWN_DEVICE, time_ns, truth))
}

/// A full-state row in `layout`, by the vehicle module's parser; given
/// rates and forces must also be within the feed's limits. `Err(None)`: a
/// cell is not a number (maybe a header).
fn full_state(line: &str, layout: &FullStateLayout) -> Result<Sample, Option<Reject>> {
    let row = FullStateRow::parse(line, layout).map_err(|e| match e {
        RowError::OutOfRange => Some(Reject::OutOfRange),
        RowError::WrongCount => Some(Reject::Malformed),
        RowError::NotANumber => None,
    })?;
    let within =
        |v: &Option<[f64; 3]>, lim: f64| v.is_none_or(|v| v.iter().all(|x| x.abs() <= lim));
    if row.time_s > MAX_TIME_S
        || !within(&row.rate_dps, f64::from(TRUTH_RATE_LIMIT_DPS))
        || !within(&row.force_mps2, f64::from(TRUTH_FORCE_LIMIT_G) * G_ICD)
        || row.temperature_c.is_some_and(|t| {
            let (lo, hi) = TEMPERATURE_RANGE_C;
            !(lo..=hi).contains(&t)
        })
    {
        return Err(Some(Reject::OutOfRange));
    }
    Ok(Sample::FullState(FullStateSample {
        device: OWN_DEVICE,
        time_ns: libm::round(row.time_s * 1e9) as u64,
        row,
    }))
}

/// A line that is not all numbers: a full-state header (text rows become
/// full-state rows), the rate header (rate rows again; both skipped), or
/// malformed.
fn header(line: &str, layout: &mut Option<FullStateLayout>) -> Option<Result<Sample, Reject>> {
    if let Some(l) = FullStateLayout::from_header(line) {
        *layout = Some(l);
        return None;
    }
    let mut cells = line.split(',').map(str::trim);
    if !cells
        .next()
        .is_some_and(|c| c.eq_ignore_ascii_case("time") || c.eq_ignore_ascii_case("time_s"))
    {
        return Some(Err(Reject::Malformed));
    }
    let mut n = 1;
    for c in cells {
        if c.is_empty() || !c.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') {
            return Some(Err(Reject::Malformed));
        }
        n += 1;
    }
    if n == 7 || n == 8 {
        *layout = None;
        None
    } else {
        Some(Err(Reject::Malformed))
    }
}

/// Encodes a rate sample in the binary layout (kind 1, or 2 with a
/// temperature) into `out`; the frame's length (41 or 45 bytes).
pub fn encode(s: &RateSample, out: &mut [u8; MAX_FRAME]) -> usize {
    let k = if s.truth.temperature_c.is_some() {
        kind::RATES_TEMP
    } else {
        kind::RATES
    };
    let body = body_len(k).unwrap_or(0);
    out[..2].copy_from_slice(&SYNC);
    out[2] = VERSION;
    out[3] = k;
    out[4] = body;
    out[5..7].copy_from_slice(&s.device.to_le_bytes());
    out[7..15].copy_from_slice(&s.time_ns.to_le_bytes());
    let t = &s.truth;
    let vals = [
        t.rate_dps[0],
        t.rate_dps[1],
        t.rate_dps[2],
        t.specific_force_g[0],
        t.specific_force_g[1],
        t.specific_force_g[2],
        t.temperature_c.unwrap_or(0.0),
    ];
    let n = if k == kind::RATES_TEMP { 7 } else { 6 };
    for (i, v) in vals[..n].iter().enumerate() {
        out[15 + 4 * i..19 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    let end = HEAD + usize::from(body);
    let sum = CRC.checksum(&out[2..end]);
    out[end..end + 2].copy_from_slice(&sum.to_le_bytes());
    end + 2
}

/// `a + (b − a)·w` in `f64`: between two finite `f32`s it never
/// overflows.
pub fn lerp(a: f32, b: f32, w: f32) -> f32 {
    let (a, b) = (f64::from(a), f64::from(b));
    (a + (b - a) * f64::from(w)) as f32
}

/// The truth `w` of the way from `a` to `b` (0 ≤ w ≤ 1); a temperature
/// only one side knows holds.
pub fn lerp_truth(a: &Truth, b: &Truth, w: f32) -> Truth {
    let mix = |x: [f32; 3], y: [f32; 3]| {
        [
            lerp(x[0], y[0], w),
            lerp(x[1], y[1], w),
            lerp(x[2], y[2], w),
        ]
    };
    Truth {
        rate_dps: mix(a.rate_dps, b.rate_dps),
        specific_force_g: mix(a.specific_force_g, b.specific_force_g),
        temperature_c: match (a.temperature_c, b.temperature_c) {
            (Some(x), Some(y)) => Some(lerp(x, y, w)),
            (x, y) => x.or(y),
        },
    }
}

/// One device's samples: the newest two (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Track {
    prev: Option<(u64, Truth)>,
    last: Option<(u64, Truth)>,
    /// A new timeline began ([`Track::restart`]): the next sample is
    /// taken whatever its time.
    restarted: bool,
}

impl Track {
    /// No sample yet.
    pub const fn new() -> Self {
        Track {
            prev: None,
            last: None,
            restarted: false,
        }
    }

    /// Takes a sample whose time is after the previous one's (or any
    /// time, the first after [`Track::restart`]).
    pub fn accept(&mut self, time_ns: u64, truth: Truth) -> Result<(), Reject> {
        if !self.restarted && self.last.is_some_and(|(t, _)| time_ns <= t) {
            return Err(Reject::NonIncreasing);
        }
        self.prev = if self.restarted { None } else { self.last };
        self.restarted = false;
        self.last = Some((time_ns, truth));
        Ok(())
    }

    /// A new timeline (a new feed connection, a power cycle): the newest
    /// sample holds until the next, which is taken whatever its time and
    /// not interpolated with the ones before.
    pub fn restart(&mut self) {
        self.restarted = true;
    }

    /// The newest sample's time and truth.
    pub fn last(&self) -> Option<(u64, Truth)> {
        self.last
    }

    /// The truth at `t_ns`: interpolated between the newest two samples,
    /// the newest held after it, the older held before it; `None` before
    /// the first sample.
    pub fn at(&self, t_ns: u64) -> Option<Truth> {
        let (t1, b) = self.last?;
        let Some((t0, a)) = self.prev else {
            return Some(b);
        };
        Some(if t_ns >= t1 {
            b
        } else if t_ns <= t0 {
            a
        } else {
            lerp_truth(&a, &b, ((t_ns - t0) as f64 / (t1 - t0) as f64) as f32)
        })
    }
}

/// A device's feed in real time (host and firmware boards alike): a sample
/// applies from the first tick at or after the device time it arrived at
/// and holds until the next; silence beyond the timeout is the fault
/// ([`crate::chain::Faults::motion_feed_lost`]) until a sample returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Live {
    track: Track,
    /// Device time the newest sample arrived at, ns.
    arrived_ns: Option<u64>,
    /// The truth the last tick used.
    applied: Option<Truth>,
    lost: bool,
    timeout_ns: u64,
}

impl Live {
    /// No sample yet; the fault after `timeout_ns` of silence.
    pub const fn new(timeout_ns: u64) -> Self {
        Live {
            track: Track::new(),
            arrived_ns: None,
            applied: None,
            lost: false,
            timeout_ns,
        }
    }

    /// Takes a sample arrived at device time `now_ns` (its own time must
    /// increase: [`Reject::NonIncreasing`]).
    pub fn offer(&mut self, time_ns: u64, truth: Truth, now_ns: u64) -> Result<(), Reject> {
        self.track.accept(time_ns, truth)?;
        self.arrived_ns = Some(now_ns);
        Ok(())
    }

    /// The truth of the tick at `deadline_ns` (`None` before the first
    /// sample: the device's own motion goes on) and whether the feed is
    /// lost then.
    pub fn at(&mut self, deadline_ns: u64) -> (Option<Truth>, bool) {
        if let (Some(a), Some((_, newest))) = (self.arrived_ns, self.track.last()) {
            if deadline_ns >= a {
                self.applied = Some(newest);
            }
        }
        self.lost = self
            .arrived_ns
            .is_some_and(|a| deadline_ns.saturating_sub(a) > self.timeout_ns);
        (self.applied, self.lost)
    }

    /// Whether the last [`Live::at`] found the feed lost.
    pub fn lost(&self) -> bool {
        self.lost
    }

    /// Device time since the newest sample arrived, ns (`None`: never).
    pub fn age_ns(&self, now_ns: u64) -> Option<u64> {
        self.arrived_ns.map(|a| now_ns.saturating_sub(a))
    }

    /// The newest sample.
    pub fn track(&self) -> &Track {
        &self.track
    }

    /// A new timeline ([`Track::restart`]).
    pub fn restart(&mut self) {
        self.track.restart();
    }

    /// The silence after which the feed is lost, ns.
    pub fn timeout_ns(&self) -> u64 {
        self.timeout_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::format;
    use std::vec;
    use std::vec::Vec;

    fn all(bytes: &[u8]) -> Vec<Result<Sample, Reject>> {
        let mut d = Decoder::new();
        let mut v = Vec::new();
        d.decode(bytes, &mut |r| v.push(r));
        v
    }

    fn rs(device: u16, time_ns: u64, w: f32, temp: Option<f32>) -> RateSample {
        RateSample {
            device,
            time_ns,
            truth: Truth {
                rate_dps: [w, -w, 0.5],
                specific_force_g: [0.0, 0.25, 1.0],
                temperature_c: temp,
            },
        }
    }

    fn bin(s: &RateSample) -> Vec<u8> {
        let mut f = [0u8; 45];
        let n = encode(s, &mut f);
        f[..n].to_vec()
    }

    #[test]
    fn text_rows_decode_and_skip_comments_and_the_header() {
        let v = all(
            b"time,wx,wy,wz,fx,fy,fz,temp\r\n# c\n\n0.5, 10, 0, 0, 0, 0, 1\n1,1,2,3,4,5,6,25\n",
        );
        assert_eq!(v.len(), 2);
        let Ok(Sample::Rates(a)) = v[0] else {
            panic!("{v:?}")
        };
        assert_eq!((a.device, a.time_ns), (OWN_DEVICE, 500_000_000));
        assert_eq!(a.truth.rate_dps, [10.0, 0.0, 0.0]);
        assert_eq!(a.truth.temperature_c, None);
        let Ok(Sample::Rates(b)) = v[1] else { panic!() };
        assert_eq!(b.truth.specific_force_g, [4.0, 5.0, 6.0]);
        assert_eq!(b.truth.temperature_c, Some(25.0));
    }

    #[test]
    fn numbers_parse_as_the_standard_parser_does() {
        for s in [
            "0",
            "-0",
            "1",
            "+7",
            "12.5",
            "-12.5",
            ".5",
            "5.",
            "0.001",
            "1e-3",
            "3E4",
            "2.5e+2",
            "123456789.123456789",
            "1e300",
            "1e-300",
            "0.000000000000000000000000123",
            "98.10600000000000000000001",
            "-1e40",
            "9.8106",
        ] {
            let want: f64 = s.parse().unwrap();
            let got = parse_number(s).unwrap_or_else(|| panic!("{s}"));
            assert!(
                (got - want).abs() <= want.abs() * 4e-16,
                "{s}: {got} vs {want}"
            );
        }
        for s in [
            "", "-", ".", "e5", "1e", "1.2.3", "1x", "inf", "NaN", "time", "1 2",
        ] {
            assert_eq!(parse_number(s), None, "{s}");
        }
    }

    #[test]
    fn binary_round_trips_with_and_without_temperature() {
        for temp in [None, Some(31.5)] {
            let s = rs(3, 123_456_789, 12.5, temp);
            let f = bin(&s);
            assert_eq!(f.len(), if temp.is_some() { 45 } else { 41 });
            assert_eq!(all(&f), [Ok(Sample::Rates(s))]);
        }
    }

    #[test]
    fn the_documented_frame_bytes() {
        // docs/feed.md's example: kind 1, device 0, t = 1 ms, ω = (10,0,0),
        // f = (0,0,1).
        let s = RateSample {
            device: 0,
            time_ns: 1_000_000,
            truth: Truth {
                rate_dps: [10.0, 0.0, 0.0],
                specific_force_g: [0.0, 0.0, 1.0],
                temperature_c: None,
            },
        };
        let f = bin(&s);
        assert_eq!(
            f[..15],
            [0xF5, 0xED, 1, 1, 34, 0, 0, 0x40, 0x42, 0x0F, 0, 0, 0, 0, 0]
        );
        assert_eq!(f[15..19], 10f32.to_le_bytes());
        assert_eq!(f[35..39], 1f32.to_le_bytes());
        assert_eq!(CRC.checksum(b"123456789"), 0x29B1);
        assert_eq!(u16::from_le_bytes([f[39], f[40]]), CRC.checksum(&f[2..39]));
        assert_eq!(f[39..], [0x0C, 0x3E]);
    }

    #[test]
    fn bad_samples_are_rejected_with_their_reason() {
        use Reject::*;
        let mut long = [b'1'; MAX_LINE + 10].to_vec();
        long.extend_from_slice(b"\n0,0,0,0,0,0,1\n");
        let v = all(&long);
        assert_eq!(v[0], Err(LineTooLong));
        assert!(v[1].is_ok(), "{v:?}");
        assert_eq!(v.len(), 2);
        for (line, why) in [
            (&b"0,1,2\n"[..], Malformed),
            (b"0,1,2,3,4,5,6,7,8\n", Malformed),
            (b"x,1,2,3,4,5,6\n", Malformed),
            (b"-1,0,0,0,0,0,1\n", OutOfRange),
            (b"0,9000,0,0,0,0,1\n", OutOfRange),
            (b"0,0,0,0,0,0,200\n", OutOfRange),
            (b"0,0,0,0,0,0,1,NaN\n", Malformed),
            (b"0,0,0,0,0,0,1,1e40\n", OutOfRange),
            (b"1e300,0,0,0,0,0,1\n", OutOfRange),
            (b"time,lat,lon,h,vn,ve,vd,roll,pitch,yaw\n", Malformed),
            (b"\xff\xfe,1\n", Malformed),
        ] {
            assert_eq!(all(line), [Err(why)], "{:?}", core::str::from_utf8(line));
        }
        let good = bin(&rs(0, 5, 1.0, None));
        let mut f = good.clone();
        f[2] = 2;
        let n = f.len();
        let sum = CRC.checksum(&f[2..n - 2]).to_le_bytes();
        f[n - 2..].copy_from_slice(&sum);
        assert_eq!(all(&f), [Err(UnsupportedVersion)]);
        let mut f = good.clone();
        f[20] ^= 1;
        assert_eq!(all(&f), [Err(Checksum)]);
        let mut f = good.clone();
        f[4] = 200;
        assert_eq!(all(&f)[0], Err(BadLength));
        let mut f = good.clone();
        f[3] = kind::FULL_STATE;
        let sum = CRC.checksum(&f[2..n - 2]).to_le_bytes();
        f[n - 2..].copy_from_slice(&sum);
        assert_eq!(all(&f), [Err(UnsupportedKind)]);
        let mut f = bin(&rs(0, 5, 9999.0, None));
        assert_eq!(all(&f), [Err(OutOfRange)]);
        f.clear();
    }

    const FULL_HEADER: &str = "time,lat,lon,height,vn,ve,vd,roll,pitch,yaw";

    #[test]
    fn a_full_state_header_switches_the_rows_and_a_rate_header_back() {
        use Reject::*;
        let mut d = Decoder::new();
        let mut v = Vec::new();
        let text = format!(
            "0.5,0,0,0,0,0,1\n{FULL_HEADER}\n\
             1.25, 45.5, 7, 300, 10, 0, -1, 0, 5, 90\n\
             2,0,0,0,0,0,1\n\
             3,95,7,300,10,0,-1,0,5,90\n\
             4,45,7,300,10,0,-1,0,5,inf\n\
             time_s,wx,wy,wz,fx,fy,fz\n\
             5,0,0,0,0,0,1\n\
             {FULL_HEADER},wx,wy,wz,fx,fy,fz,temp\n\
             6,45,7,300,0,0,0,0,0,0,1,2,3,0,0,-9.8,25\n\
             7,45,7,300,0,0,0,0,0,0,9000,2,3,0,0,-9.8,25\n\
             8,45,7,300,0,0,0,0,0,0,1,2,3,0,0,-1300,25\n"
        );
        d.decode(text.as_bytes(), &mut |r| v.push(r));
        assert_eq!(v.len(), 9, "{v:?}");
        assert!(matches!(v[0], Ok(Sample::Rates(_))));
        let Ok(Sample::FullState(f)) = v[1] else {
            panic!("{:?}", v[1])
        };
        assert_eq!(f.device, OWN_DEVICE);
        assert_eq!(f.time_ns, 1_250_000_000);
        assert_eq!(
            (f.row.lat_deg, f.row.lon_deg, f.row.height_m),
            (45.5, 7.0, 300.0)
        );
        assert_eq!(f.row.vel_ned, [10.0, 0.0, -1.0]);
        assert_eq!(f.row.euler_deg, [0.0, 5.0, 90.0]);
        assert_eq!((f.row.rate_dps, f.row.temperature_c), (None, None));
        // A rate row is no full-state row: only a header switches back.
        assert_eq!(v[2], Err(Malformed));
        assert_eq!(v[3], Err(OutOfRange));
        assert_eq!(v[4], Err(Malformed));
        assert_eq!(v[5].map(|s| s.time_ns()), Ok(5_000_000_000));
        assert!(matches!(v[5], Ok(Sample::Rates(_))));
        let Ok(Sample::FullState(f)) = v[6] else {
            panic!("{:?}", v[6])
        };
        assert_eq!(f.row.rate_dps, Some([1.0, 2.0, 3.0]));
        assert_eq!(f.row.force_mps2, Some([0.0, 0.0, -9.8]));
        assert_eq!(f.row.temperature_c, Some(25.0));
        // Beyond the feed's limits (8192 °/s, 128 g) though within the
        // vehicle module's.
        assert_eq!(&v[7..], [Err(OutOfRange), Err(OutOfRange)]);
        assert!(d.layout().is_some_and(|l| l.rates_forces && l.temperature));
        // A long row of that layout still fits a line.
        let long = "9.123456789,-45.123456789012,-170.123456789012,1234.5678901,\
                    -10.1234567,20.1234567,-1.12345678,-1.12345678,2.12345678,\
                    -179.123456,-12.3456789,23.4567891,-34.5678912,1.23456789,\
                    -2.34567891,-9.80665432,25.125";
        assert!(long.len() > 200 && long.len() <= MAX_LINE, "{}", long.len());
        let mut w = Vec::new();
        d.decode(format!("{long}\n").as_bytes(), &mut |r| w.push(r));
        assert!(matches!(w[..], [Ok(Sample::FullState(_))]), "{w:?}");
        let c = d.counts();
        assert_eq!((c.samples, c.rejected_total()), (5, 5));
        assert_eq!(c.rejected[Malformed as usize], 2);
    }

    #[test]
    fn full_state_rows_decode_alike_in_any_chunking() {
        let mut b = format!("{FULL_HEADER}\n0,45,7,300,10,0,0,0,0,0\n").into_bytes();
        b.extend(bin(&rs(2, 500_000_000, 3.0, None)));
        b.extend_from_slice(b"1,45.0001,7,300,10,0,0,0,0,0\n1.5,45,7\n");
        let whole = all(&b);
        assert_eq!(whole.len(), 4, "{whole:?}");
        assert!(matches!(whole[0], Ok(Sample::FullState(_))));
        assert!(matches!(whole[1], Ok(Sample::Rates(_))));
        assert!(matches!(whole[2], Ok(Sample::FullState(_))));
        assert_eq!(whole[3], Err(Reject::Malformed));
        for cut in 1..b.len() {
            let mut d = Decoder::new();
            let mut v = Vec::new();
            d.decode(&b[..cut], &mut |r| v.push(r));
            d.decode(&b[cut..], &mut |r| v.push(r));
            assert_eq!(v, whole, "cut at {cut}");
        }
        let mut d = Decoder::new();
        let mut v = Vec::new();
        for byte in &b {
            d.decode(core::slice::from_ref(byte), &mut |r| v.push(r));
        }
        assert_eq!(v, whole);
    }

    #[test]
    fn text_and_binary_mix_and_a_torn_line_is_one_rejection() {
        let s = rs(1, 2_000_000, 3.0, None);
        let mut b = b"0.001,0,0,0,0,0,1\n0.0015,1,2".to_vec();
        b.extend(bin(&s));
        b.extend_from_slice(b"0.003,0,0,0,0,0,1\n");
        let v = all(&b);
        assert_eq!(v.len(), 4, "{v:?}");
        assert!(v[0].is_ok());
        assert_eq!(v[1], Err(Reject::Malformed));
        assert_eq!(v[2], Ok(Sample::Rates(s)));
        assert_eq!(v[3].map(|s| s.time_ns()), Ok(3_000_000));
    }

    #[test]
    fn a_frame_inside_a_bad_frame_is_found() {
        let good = bin(&rs(0, 7, 1.0, None));
        // A sync and a header claiming a long body, then a good frame.
        let mut b = vec![0xF5, 0xED, 1, 1, 34, 0, 0];
        b.extend(&good);
        let v = all(&b);
        assert_eq!(v.last(), Some(&Ok(Sample::Rates(rs(0, 7, 1.0, None)))));
        assert_eq!(v.iter().filter(|r| r.is_err()).count(), 1, "{v:?}");
    }

    #[test]
    fn the_track_rejects_going_back_holds_and_interpolates() {
        let mut t = Track::new();
        assert_eq!(t.at(0), None);
        let a = rs(0, 0, 0.0, Some(20.0)).truth;
        let b = rs(0, 0, 10.0, None).truth;
        t.accept(1_000, a).unwrap();
        assert_eq!(t.at(0), Some(a));
        assert_eq!(t.at(5_000), Some(a));
        assert_eq!(t.accept(1_000, b), Err(Reject::NonIncreasing));
        t.accept(2_000, b).unwrap();
        let mid = t.at(1_500).unwrap();
        assert_eq!(mid.rate_dps, [5.0, -5.0, 0.5]);
        assert_eq!(mid.temperature_c, Some(20.0));
        assert_eq!(t.at(9_000), Some(b));
        assert_eq!(t.at(500), Some(a));
    }

    #[test]
    fn live_applies_from_arrival_holds_and_times_out() {
        let mut l = Live::new(1_000_000);
        assert_eq!(l.at(0), (None, false));
        let a = rs(0, 0, 1.0, None).truth;
        let b = rs(0, 0, 2.0, None).truth;
        l.offer(5, a, 1_000).unwrap();
        assert_eq!(l.at(500), (None, false));
        assert_eq!(l.at(1_000), (Some(a), false));
        l.offer(6, b, 1_500).unwrap();
        assert_eq!(l.at(1_400).0, Some(a));
        assert_eq!(l.offer(6, b, 1_600), Err(Reject::NonIncreasing));
        assert_eq!(l.at(2_600_000), (Some(b), true));
        assert!(l.lost());
        assert_eq!(l.age_ns(2_600_000), Some(2_598_500));
        l.offer(7, a, 2_700_000).unwrap();
        assert_eq!(l.at(2_700_000), (Some(a), false));
    }

    fn stream() -> impl Strategy<Value = Vec<u8>> {
        let item = prop_oneof![
            (0u64..1_000_000, -100f32..100.0, any::<bool>()).prop_map(|(t, w, temp)| bin(&rs(
                (t % 4) as u16,
                t,
                w,
                temp.then_some(25.0)
            ))),
            (0u32..100_000, -100i32..100).prop_map(|(t, w)| format!(
                "{}.{:03},{w},0,0,0,0,1\n",
                t / 1000,
                t % 1000
            )
            .into_bytes()),
            proptest::collection::vec(any::<u8>(), 0..80),
            Just(format!("{FULL_HEADER}\n").into_bytes()),
            Just(b"time,wx,wy,wz,fx,fy,fz\n".to_vec()),
            (0u32..100_000, -80i32..80).prop_map(|(t, lat)| format!(
                "{}.{:03},{lat},7,300,10,0,0,0,0,90\n",
                t / 1000,
                t % 1000
            )
            .into_bytes()),
            Just(vec![0xF5, 0xED]),
            Just(b"\n".to_vec()),
        ];
        proptest::collection::vec(item, 0..30).prop_map(|v| v.concat())
    }

    proptest! {
        #[test]
        fn any_chunking_gives_the_same_outcomes(b in stream(), cuts in proptest::collection::vec(0usize..400, 0..20)) {
            let whole = all(&b);
            let mut d = Decoder::new();
            let mut v = Vec::new();
            let mut rest = &b[..];
            for c in cuts {
                let c = c.min(rest.len());
                d.decode(&rest[..c], &mut |r| v.push(r));
                rest = &rest[c..];
            }
            d.decode(rest, &mut |r| v.push(r));
            prop_assert_eq!(&v, &whole);
            let c = d.counts();
            prop_assert_eq!(c.samples as usize, whole.iter().filter(|r| r.is_ok()).count());
            prop_assert_eq!(c.rejected_total() as usize, whole.iter().filter(|r| r.is_err()).count());
        }

        #[test]
        fn after_garbage_and_a_line_end_every_sample_is_found(
            garbage in proptest::collection::vec(any::<u8>(), 0..300),
            n in 1usize..10,
        ) {
            let samples: Vec<RateSample> = (0..n).map(|i| rs(0, i as u64 + 1, i as f32, None)).collect();
            let mut b = garbage;
            // A line end and a byte that cannot start a frame end any
            // frame the garbage opened (its body is at most 128 bytes).
            b.extend_from_slice(&[b'\n'; 1]);
            b.extend_from_slice(&[b' '; 140]);
            b.push(b'\n');
            for s in &samples {
                b.extend(bin(s));
            }
            let got: Vec<Sample> = all(&b).into_iter().filter_map(Result::ok).collect();
            let want: Vec<Sample> = samples.iter().map(|s| Sample::Rates(*s)).collect();
            prop_assert!(got.ends_with(&want), "{:?}", got);
        }
    }
}
