//! `imu-emu client --protocol isb …`: the host side of an ISB line (an
//! Inertial Sense IMX-5, the emulator's `--protocol isb` or a real unit):
//! GET_DATA / SET_DATA of the data sets by field name
//! ([`imu_emu::isb::did`] and [`imu_emu::isb::layout`], the `data_sets.h` names of protocol 2.1,
//! `docs/isb-data-sets.md`), streams recorded to CSV / JSON lines with the
//! sets' own device time, raw captures decoded.

use std::io::Write;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _};
use imu_emu::isb::layout::{self, FieldSpec, Kind, Value};
use imu_emu::isb::message::{self, GetRequest};
use imu_emu::isb::packet::{self, Decoder, PacketType, FLAG_OFFSET, MAX_PACKET};
use imu_emu::isb::{did, sets};

use super::{Line, OutFormat};
use crate::error::UsageError;

/// A packet received.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Packet {
    /// Flags byte (type in the low nibble).
    pub flags: u8,
    /// Header DID.
    pub did: u8,
    /// Payload.
    pub payload: Vec<u8>,
}

impl Packet {
    /// A whole data set (DATA without the offset flag): its DID and bytes.
    pub fn whole_set(&self) -> Option<(u8, &[u8])> {
        (PacketType::from_flags(self.flags) == Some(PacketType::Data)
            && self.flags & FLAG_OFFSET == 0)
            .then_some((self.did, &self.payload[..]))
    }
}

/// An ISB line: a [`Line`] with a packet decoder.
pub struct IsbLink {
    /// The line.
    pub line: Line,
    rx: Box<Decoder<MAX_PACKET>>,
}

impl IsbLink {
    /// An ISB decoder on `line`.
    pub fn new(line: Line) -> Self {
        IsbLink {
            line,
            rx: Box::new(Decoder::new()),
        }
    }

    /// Packets that failed their checksum or size so far.
    pub fn checksum_errors(&self) -> u32 {
        self.rx.errors()
    }

    /// The next packet before `deadline`, or `None`.
    pub fn packet_before(&mut self, deadline: Instant) -> anyhow::Result<Option<Packet>> {
        let rx = &mut self.rx;
        self.line.next_before(deadline, |input| {
            rx.next_packet(input).map(|p| Packet {
                flags: p.flags,
                did: p.did,
                payload: p.payload.to_vec(),
            })
        })
    }

    /// Sends GET_DATA of the whole set `did`, once (`period` 0, which also
    /// stops its stream) or every `period` source periods.
    pub fn send_get(&mut self, did: u8, period: u16) -> anyhow::Result<()> {
        let req = GetRequest {
            did: u16::from(did),
            size: 0,
            offset: 0,
            period,
        };
        let mut buf = [0u8; 32];
        let n = message::encode_get(&req, &mut buf).context("GET_DATA")?;
        self.line.write(&buf[..n])
    }

    /// Sends STOP_BROADCASTS_CURRENT_PORT (every stream of this port).
    pub fn send_stop(&mut self) -> anyhow::Result<()> {
        let mut buf = [0u8; 16];
        let n = packet::encode(
            PacketType::StopBroadcastsCurrentPort as u8,
            0,
            &[],
            &mut buf,
        )
        .context("stop")?;
        self.line.write(&buf[..n])
    }

    /// GET_DATA of the whole set `did`, once: its bytes.
    pub fn get(&mut self, did: u8) -> anyhow::Result<Vec<u8>> {
        let (name, _) = set_of(did)?;
        let errors = self.checksum_errors();
        self.send_get(did, 0)?;
        let deadline = Instant::now() + self.line.timeout;
        while let Some(p) = self.packet_before(deadline)? {
            if let Some((d, b)) = p.whole_set() {
                if d == did {
                    return Ok(b.to_vec());
                }
            }
            if PacketType::from_flags(p.flags) == Some(PacketType::Nack) {
                bail!("{}: GET_DATA {name} refused (NACK)", self.line.what);
            }
        }
        self.no_answer(&format!("GET_DATA {name}"), errors)
    }

    /// SET_DATA of `data` at `offset` of set `did`; an error unless ACKed.
    pub fn set(&mut self, did: u8, offset: u16, data: &[u8], what: &str) -> anyhow::Result<()> {
        let mut buf = vec![0u8; MAX_PACKET];
        let n = message::encode_set(did, offset, data, &mut buf).context("SET_DATA")?;
        let errors = self.checksum_errors();
        self.line.write(&buf[..n])?;
        let deadline = Instant::now() + self.line.timeout;
        while let Some(p) = self.packet_before(deadline)? {
            let answers_us = p.payload.first().map(|f| f & 0x0F) == Some(PacketType::SetData as u8)
                && p.payload.get(1) == Some(&did);
            match PacketType::from_flags(p.flags) {
                Some(PacketType::Ack) if answers_us => return Ok(()),
                Some(PacketType::Nack) if answers_us => {
                    bail!(
                        "{}: SET_DATA {what}: the unit refused the value (NACK)",
                        self.line.what
                    )
                }
                _ => {}
            }
        }
        self.no_answer(&format!("SET_DATA {what}"), errors)
    }

    fn no_answer<T>(&self, what: &str, errors_before: u32) -> anyhow::Result<T> {
        let bad = self.checksum_errors() - errors_before;
        if bad > 0 {
            bail!(
                "{}: no valid answer to {what} within {:?}: {bad} packets failed their \
                 checksum (wrong --baud?)",
                self.line.what,
                self.line.timeout
            );
        }
        bail!(
            "{}: no answer to {what} within {:?} (is the unit on, speaking ISB, the line rate \
             right? an IMX-5 starts at 921600 bit/s)",
            self.line.what,
            self.line.timeout
        )
    }
}

/// The name and fields of served set `did`, or an error naming them all.
pub fn set_of(did: u8) -> anyhow::Result<(&'static str, &'static [FieldSpec])> {
    did::set(did)
        .ok_or_else(|| UsageError(format!("no data set {did}; served: {}", set_names())).into())
}

fn set_names() -> String {
    did::DATA_SETS
        .iter()
        .map(|s| s.did_name)
        .collect::<Vec<_>>()
        .join(" ")
}

/// A data set by name or number, or a usage error listing them.
pub fn parse_set(s: &str) -> anyhow::Result<u8> {
    did::set_by_name(s)
        .ok_or_else(|| UsageError(format!("no data set {s}; served: {}", set_names())).into())
}

/// The data sets of a comma-separated list.
pub fn parse_sets(s: &str) -> anyhow::Result<Vec<u8>> {
    s.split(',').map(|x| parse_set(x.trim())).collect()
}

/// One cell of a row: a number, or text (quoted in JSON).
enum Cell {
    Num(String),
    Text(String),
}

/// The column names of `spec` (three for a vector).
fn columns(spec: &FieldSpec) -> Vec<String> {
    match spec.kind {
        Kind::F32x3 | Kind::F64x3 => ["x", "y", "z"]
            .iter()
            .map(|a| format!("{}_{a}", spec.name))
            .collect(),
        Kind::F32x4 => ["w", "x", "y", "z"]
            .iter()
            .map(|a| format!("{}_{a}", spec.name))
            .collect(),
        _ => vec![spec.name.to_owned()],
    }
}

/// A float as sent: `f32` fields printed at `f32` precision.
fn float(kind: Kind, x: f64) -> String {
    match kind {
        Kind::F32 | Kind::F32x3 | Kind::F32x4 => (x as f32).to_string(),
        _ => x.to_string(),
    }
}

/// The cells of `spec` read from `b`.
fn cells(spec: &FieldSpec, b: &[u8]) -> Vec<Cell> {
    match layout::read(spec, b) {
        Value::Unsigned(u) => vec![Cell::Num(u.to_string())],
        Value::Float(x) => vec![Cell::Num(float(spec.kind, x))],
        Value::Vec3(v) => v.iter().map(|&x| Cell::Num(float(spec.kind, x))).collect(),
        Value::Vec4(v) => v.iter().map(|&x| Cell::Num(float(spec.kind, x))).collect(),
        Value::Version(v) => vec![Cell::Text(format!("{}.{}.{}.{}", v[0], v[1], v[2], v[3]))],
        Value::Text(t, n) => vec![Cell::Text(
            t[..n]
                .iter()
                .map(|&c| {
                    if c.is_ascii_graphic() || c == b' ' {
                        c as char
                    } else {
                        '?'
                    }
                })
                .collect(),
        )],
    }
}

/// The numeric columns of set `did` read from `b` (vectors as
/// `name_x`…; versions and text left out): what the web view plots.
pub fn numbers(did: u8, b: &[u8]) -> Vec<(String, f64)> {
    let Some((_, fs)) = did::set(did) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for f in fs {
        match layout::read(f, b) {
            Value::Unsigned(u) => out.push((f.name.to_owned(), u as f64)),
            Value::Float(x) => out.push((f.name.to_owned(), x)),
            Value::Vec3(v) => out.extend(columns(f).into_iter().zip(v)),
            Value::Vec4(v) => out.extend(columns(f).into_iter().zip(v)),
            Value::Version(_) | Value::Text(..) => {}
        }
    }
    out
}

/// `field = value unit` lines of set `did` (`info`, `get SET`).
pub fn show_set(did: u8, b: &[u8]) -> anyhow::Result<String> {
    let (_, fs) = set_of(did)?;
    let mut out = String::new();
    for f in fs {
        out.push_str(&show_field(f, b));
        out.push('\n');
    }
    Ok(out)
}

/// `field = value unit` of one field.
pub fn show_field(f: &FieldSpec, b: &[u8]) -> String {
    let vals: Vec<String> = cells(f, b)
        .into_iter()
        .map(|c| match c {
            Cell::Num(s) | Cell::Text(s) => s,
        })
        .collect();
    let hex = match (f.kind, layout::read(f, b)) {
        (Kind::U32 | Kind::U64, Value::Unsigned(u)) if f.unit.is_empty() && u > 9 => {
            format!(" ({u:#x})")
        }
        _ => String::new(),
    };
    let unit = if f.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", f.unit)
    };
    format!("{} = {}{unit}{hex}", f.name, vals.join(","))
}

/// Parses `text` as a value of `f` (integers decimal or 0x hex; vectors
/// as three comma-separated numbers); its bytes.
pub fn parse_field(f: &FieldSpec, text: &str) -> anyhow::Result<Vec<u8>> {
    let bad = || UsageError(format!("{}: {text} is not a {:?} value", f.name, f.kind));
    let uint = |max: u64| -> anyhow::Result<u64> {
        let t = text.trim();
        let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
            Some(h) => u64::from_str_radix(h, 16).ok(),
            None => t.parse().ok(),
        };
        Ok(v.filter(|&v| v <= max).ok_or_else(bad)?)
    };
    let floats = |n: usize| -> anyhow::Result<Vec<f64>> {
        let xs: Vec<f64> = text
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        if xs.len() != n {
            return Err(bad().into());
        }
        Ok(xs)
    };
    Ok(match f.kind {
        Kind::U8 => vec![uint(u64::from(u8::MAX))? as u8],
        Kind::U16 => (uint(u64::from(u16::MAX))? as u16).to_le_bytes().to_vec(),
        Kind::U32 => (uint(u64::from(u32::MAX))? as u32).to_le_bytes().to_vec(),
        Kind::U64 => uint(u64::MAX)?.to_le_bytes().to_vec(),
        Kind::F32 => (floats(1)?[0] as f32).to_le_bytes().to_vec(),
        Kind::F64 => floats(1)?[0].to_le_bytes().to_vec(),
        Kind::F32x3 | Kind::F32x4 => floats(if f.kind == Kind::F32x3 { 3 } else { 4 })?
            .iter()
            .flat_map(|&x| (x as f32).to_le_bytes())
            .collect(),
        Kind::F64x3 => floats(3)?.iter().flat_map(|x| x.to_le_bytes()).collect(),
        Kind::Version | Kind::Str24 => {
            return Err(UsageError(format!("{}: not writable by the client", f.name)).into())
        }
    })
}

/// A field by `SET.field` or unique `field` name, or a usage error.
pub fn find_field(name: &str) -> anyhow::Result<(u8, &'static FieldSpec)> {
    did::find(name).ok_or_else(|| {
        UsageError(format!(
            "no field {name}; name it SET.field (e.g. FLASH_CONFIG.startupNavDtMs; a field in \
             several sets needs its set); sets: {}",
            set_names()
        ))
        .into()
    })
}

/// Writes data-set packets as rows (CSV with the first set's columns, or
/// JSON lines of any set) and counts them.
pub struct Recorder {
    to: OutFormat,
    /// The set whose columns the CSV has.
    csv_did: Option<u8>,
    /// Rows written.
    pub rows: u64,
    /// Packets of another set (CSV) or not whole sets, skipped.
    pub skipped: u64,
    /// Rows and device time span of each set, in the order first seen:
    /// each set has its own clock (IMU sets time since boot, INS and GPS
    /// sets GPS time of week), so spans are per set.
    pub per_set: Vec<SetRows>,
}

/// The rows of one data set in a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct SetRows {
    /// The set.
    pub did: u8,
    /// Rows written.
    pub rows: u64,
    /// Device time of its first and last row, s, if the set carries one.
    pub span: Option<(f64, f64)>,
}

impl Recorder {
    /// The rows of set `did` so far.
    pub fn of(&self, did: u8) -> Option<&SetRows> {
        self.per_set.iter().find(|s| s.did == did)
    }

    /// `IMU 250 over 0.996 s of device time, INS_1 …`: the summary of
    /// each set recorded.
    pub fn summary(&self) -> String {
        self.per_set
            .iter()
            .map(|s| {
                let name = did::set(s.did).map_or("?", |x| x.0);
                match s.span {
                    Some((a, b)) => format!("{name} {} over {:.3} s of device time", s.rows, b - a),
                    None => format!("{name} {}", s.rows),
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl Recorder {
    /// No row yet.
    pub fn new(to: OutFormat) -> Self {
        Recorder {
            to,
            csv_did: None,
            rows: 0,
            skipped: 0,
            per_set: Vec::new(),
        }
    }

    /// Writes `p` as a row if it is a whole served set (with the host time
    /// `t`, seconds since the start, if given); whether it was written.
    pub fn row(&mut self, w: &mut dyn Write, p: &Packet, t: Option<f64>) -> anyhow::Result<bool> {
        let Some((d, b)) = p.whole_set() else {
            self.skipped += 1;
            return Ok(false);
        };
        let Some((name, fs)) = did::set(d) else {
            self.skipped += 1;
            return Ok(false);
        };
        let dt = did::device_time(d, b);
        if self.to == OutFormat::Csv {
            match self.csv_did {
                None => {
                    let mut h = vec!["frame".to_owned(), "did".to_owned()];
                    if dt.is_some() {
                        h.push("device_time_s".to_owned());
                    }
                    if t.is_some() {
                        h.push("host_time_s".to_owned());
                    }
                    h.extend(fs.iter().flat_map(columns));
                    writeln!(w, "{}", h.join(","))?;
                    self.csv_did = Some(d);
                }
                Some(c) if c != d => {
                    self.skipped += 1;
                    return Ok(false);
                }
                Some(_) => {}
            }
        }
        let k = match self.per_set.iter().position(|s| s.did == d) {
            Some(k) => k,
            None => {
                self.per_set.push(SetRows {
                    did: d,
                    rows: 0,
                    span: None,
                });
                self.per_set.len() - 1
            }
        };
        let set = &mut self.per_set[k];
        set.rows += 1;
        if let Some(x) = dt {
            set.span = Some((set.span.map_or(x, |s| s.0), x));
        }
        let mut line = String::new();
        match self.to {
            OutFormat::Csv => {
                line.push_str(&format!("{},{name}", self.rows));
                for x in dt.iter().chain(t.iter()) {
                    line.push_str(&format!(",{x:.6}"));
                }
                for c in fs.iter().flat_map(|f| cells(f, b)) {
                    match c {
                        Cell::Num(s) | Cell::Text(s) => line.push_str(&format!(",{s}")),
                    }
                }
            }
            OutFormat::Json => {
                line.push_str(&format!("{{\"frame\":{},\"did\":\"{name}\"", self.rows));
                if let Some(x) = dt {
                    line.push_str(&format!(",\"device_time_s\":{x:.6}"));
                }
                if let Some(x) = t {
                    line.push_str(&format!(",\"host_time_s\":{x:.6}"));
                }
                for f in fs {
                    for (col, c) in columns(f).iter().zip(cells(f, b)) {
                        match c {
                            Cell::Num(s) => line.push_str(&format!(",\"{col}\":{s}")),
                            Cell::Text(s) => line.push_str(&format!(
                                ",\"{col}\":\"{}\"",
                                s.replace(['"', '\\'], "?")
                            )),
                        }
                    }
                }
                line.push('}');
            }
        }
        writeln!(w, "{line}")?;
        self.rows += 1;
        Ok(true)
    }
}

/// Decodes a raw ISB capture read from `src` (in chunks: bounded memory)
/// to `w`; the recorder and the checksum errors.
pub fn decode(
    src: &mut dyn std::io::Read,
    what: &dyn Fn() -> String,
    w: &mut dyn Write,
    to: OutFormat,
    only: Option<u8>,
) -> anyhow::Result<(Recorder, u32)> {
    let mut rec = Recorder::new(to);
    let mut d = Box::new(Decoder::<MAX_PACKET>::new());
    super::read_chunks(src, what, &mut |chunk| {
        let mut input: &[u8] = chunk;
        while let Some(p) = d.next_packet(&mut input) {
            let p = Packet {
                flags: p.flags,
                did: p.did,
                payload: p.payload.to_vec(),
            };
            if p.whole_set()
                .is_some_and(|(x, _)| only.is_none_or(|o| o == x))
            {
                rec.row(w, &p, None)?;
            }
        }
        Ok(())
    })?;
    Ok((rec, d.errors()))
}

/// `client decode` of an ISB capture: its data-set packets as rows; said
/// on stderr when the protocol was detected rather than given.
pub(crate) fn decode_capture(c: super::tool_protocol::Capture<'_>) -> anyhow::Result<()> {
    let what = || format!("decode {}", c.file.display());
    if c.detected {
        eprintln!(
            "imu-emu: {}: ISB packets (an IMX-5's capture): decoded as --protocol isb",
            c.file.display()
        );
    }
    let mut w = super::writer(c.out)?;
    if c.rate.is_some() {
        return Err(UsageError(
            "decode --rate is for KERNEL frames: ISB sets carry their own time".into(),
        )
        .into());
    }
    let only = c.did.map(parse_set).transpose()?;
    let (rec, errors) = decode(c.src, &what, &mut w, c.to, only)?;
    w.flush()?;
    if rec.rows == 0 && !c.empty {
        bail!(
            "{}: no ISB data set packet{} ({errors} packets failed their checksum): not an \
             IMX-5's capture? (--protocol kernel for a KERNEL's)",
            what(),
            only.map_or(String::new(), |d| format!(" of set {d}"))
        );
    }
    eprintln!(
        "imu-emu: {} packets decoded, {errors} failed their checksum, {} skipped",
        rec.rows, rec.skipped
    );
    Ok(())
}

/// The IMU samples of a raw ISB capture (`imu-emu allan --input`): whole
/// DATA packets of DID_IMU, DID_IMU_RAW or DID_IMU_MAG (`imu_t`: rad/s,
/// m/s²), or of DID_PIMU / DID_PIMU_MAG (`pimu_t`: Δθ rad and Δv m/s over
/// `dt`, read as their means Δθ/dt, Δv/dt), the first of them seen
/// setting the stream, in the KERNEL's units (°/s, g); each timed by its
/// set's own `time`.
pub fn imu_samples(bytes: &[u8]) -> super::tool_protocol::ImuSamples {
    let mut rx = Box::new(Decoder::<MAX_PACKET>::new());
    let mut input = bytes;
    let mut stream: Option<u8> = None;
    let mut rows = Vec::new();
    let mut skipped = 0usize;
    let deg = 180.0 / std::f64::consts::PI;
    let g = f64::from(imu_emu::G);
    while let Some(p) = rx.next_packet(&mut input) {
        // A data set from its start (with or without the offset flag).
        let data = (p.kind() == Some(PacketType::Data))
            .then(|| p.offset_and_data())
            .flatten()
            .filter(|d| d.0 == 0)
            .map_or(&[][..], |d| d.1);
        let row = match p.did {
            did::IMU | did::IMU_RAW | did::IMU_MAG => data
                .get(..sets::imu::SIZE)
                .and_then(|b| b.try_into().ok())
                .map(|b| {
                    let s = sets::Imu::decode(b);
                    let y = [s.pqr, s.acc];
                    (y, 1.0, s.time)
                }),
            did::PIMU | did::PIMU_MAG => data
                .get(..sets::pimu::SIZE)
                .and_then(|b| b.try_into().ok())
                .map(|b| {
                    let s = sets::Pimu::decode(b);
                    ([s.theta, s.vel], 1.0 / f64::from(s.dt), s.time)
                })
                .filter(|r| r.1.is_finite() && r.1 > 0.0),
            _ => None,
        };
        let Some(([w, a], per_s, time)) = row else {
            skipped += 1;
            continue;
        };
        if *stream.get_or_insert(p.did) != p.did {
            skipped += 1;
            continue;
        }
        let y = w
            .iter()
            .map(|v| f64::from(*v) * per_s * deg)
            .chain(a.iter().map(|v| f64::from(*v) * per_s / g))
            .collect();
        rows.push((y, Some(time)));
    }
    let name = match stream {
        Some(did::PIMU | did::PIMU_MAG) => "PIMU (Δθ/dt, Δv/dt)",
        Some(_) => "IMU",
        None => "no IMU",
    };
    super::tool_protocol::ImuSamples {
        rows,
        what: format!("ISB {name} packets, {skipped} other packets skipped"),
    }
}

/// What `record` stops on.
#[derive(Debug, Clone, Copy)]
pub struct Until {
    /// This many rows.
    pub frames: Option<u64>,
    /// This much device time since the first row, s.
    pub duration: Option<f64>,
}

/// Starts the streams of `dids` (every `period` source periods), records
/// them until `until` (or `stop` is raised), and stops them again.
pub fn record(
    link: &mut IsbLink,
    w: &mut dyn Write,
    to: OutFormat,
    dids: &[u8],
    period: u16,
    until: Until,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<Recorder> {
    if to == OutFormat::Csv && dids.len() > 1 {
        return Err(UsageError(
            "record: one CSV holds one data set's columns; record several with --to json".into(),
        )
        .into());
    }
    for &d in dids {
        set_of(d)?;
        link.send_get(d, period.max(1))?;
    }
    let r = record_rows(link, w, to, dids, until, stop);
    // The streams are stopped even when recording failed; that failure
    // (a closed line) is the one reported.
    let stopped: anyhow::Result<()> = dids.iter().try_for_each(|&d| link.send_get(d, 0));
    // The single packets those GETs answer with are not recorded.
    link.line.tee = None;
    let rec = r?;
    stopped?;
    Ok(rec)
}

fn record_rows(
    link: &mut IsbLink,
    w: &mut dyn Write,
    to: OutFormat,
    dids: &[u8],
    until: Until,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<Recorder> {
    let mut rec = Recorder::new(to);
    let t0 = Instant::now();
    let mut quiet_since = Instant::now();
    // With --duration: the sets (each on its own clock) that reached it; a
    // set without a clock follows host time.
    let mut done: Vec<u8> = Vec::new();
    let mut sets = dids.to_vec();
    sets.sort_unstable();
    sets.dedup();
    while until.frames.is_none_or(|n| rec.rows < n) && done.len() < sets.len() && !stop() {
        match link.packet_before(Instant::now() + Duration::from_millis(100))? {
            Some(p) if p.whole_set().is_some_and(|(d, _)| dids.contains(&d)) => {
                quiet_since = Instant::now();
                if let (Some(dur), Some((d, b))) = (until.duration, p.whole_set()) {
                    if done.contains(&d) {
                        continue;
                    }
                    let elapsed = match (rec.of(d).and_then(|s| s.span), did::device_time(d, b)) {
                        (Some((first, _)), Some(t)) => t - first,
                        (None, Some(_)) => 0.0,
                        (_, None) => t0.elapsed().as_secs_f64(),
                    };
                    if elapsed >= dur - 1e-9 {
                        done.push(d);
                        continue;
                    }
                }
                rec.row(w, &p, Some(t0.elapsed().as_secs_f64()))?;
            }
            Some(_) => {}
            None if quiet_since.elapsed() > link.line.timeout => bail!(
                "{}: no data set packet within {:?} after {} rows",
                link.line.what,
                link.line.timeout,
                rec.rows
            ),
            None => {}
        }
    }
    Ok(rec)
}

/// What `set` prints after a FLASH_CONFIG value that applies at the next
/// start: a command that does it as printed.
pub const RESET_HINT: &str = "(takes effect after a reset: `imu-emu client --protocol isb reset` \
     (SYS_CMD 99 with its inverse), or a power cycle)";

/// Sends system command `code` with its inverse in one SET_DATA
/// (`DID_SYS_CMD`, docs/isb.md) and waits for the ACK.
pub fn system_command(link: &mut IsbLink, code: u32, what: &str) -> anyhow::Result<()> {
    let bytes = sets::SystemCommand::new(code).encode();
    link.set(did::SYS_CMD, 0, &bytes, &format!("SYS_CMD {code} ({what})"))
}

/// The bytes of a whole set from `text`: every field's value in order,
/// comma-separated (a vector takes 3 or 4); bytes no field names keep the
/// unit's values (read first with GET_DATA). A text or version field
/// cannot be written: such a set is refused.
pub fn parse_set_value(
    did: u8,
    fs: &'static [FieldSpec],
    text: &str,
    link: &mut IsbLink,
) -> anyhow::Result<Vec<u8>> {
    let (name, _) = set_of(did)?;
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let width = |f: &FieldSpec| match f.kind {
        Kind::F32x3 | Kind::F64x3 => 3,
        Kind::F32x4 => 4,
        _ => 1,
    };
    let want: usize = fs.iter().map(width).sum();
    let names: Vec<String> = fs.iter().map(|f| f.name.to_owned()).collect();
    if fs
        .iter()
        .any(|f| matches!(f.kind, Kind::Version | Kind::Str24))
    {
        return Err(UsageError(format!(
            "set {name}: the set has text or version fields, not writable by the client; set \
             its fields one by one ({name}.field)"
        ))
        .into());
    }
    if parts.len() != want {
        return Err(UsageError(format!(
            "set {name}: {} values given, the set takes {want} ({}, in order, comma-separated)",
            parts.len(),
            names.join(", ")
        ))
        .into());
    }
    let end = fs
        .iter()
        .map(|f| f.offset + f.kind.size())
        .max()
        .unwrap_or(0);
    // Bytes between fields (reserved, padding) keep the unit's values.
    let mut bytes = if fs.iter().map(|f| f.kind.size()).sum::<usize>() == end {
        vec![0u8; end]
    } else {
        let mut b = link.get(did)?;
        b.resize(end.max(b.len()), 0);
        b.truncate(end);
        b
    };
    let mut k = 0;
    for f in fs {
        let n = width(f);
        let v = parse_field(f, &parts[k..k + n].join(","))?;
        bytes[f.offset..f.offset + v.len()].copy_from_slice(&v);
        k += n;
    }
    Ok(bytes)
}

/// The hdwBitStatus bits (`bit_t`, `data_sets.h`; `docs/isb-data-sets.md`).
pub const HDW_BIT_NAMES: &[(u32, &str)] = &[
    (sets::bit::HDW_PASSED_ALL, "passed all"),
    (sets::bit::HDW_PASSED_NO_GPS, "passed without GPS"),
    (sets::bit::HDW_FAULT_NOISE_PQR, "gyro noise"),
    (sets::bit::HDW_FAULT_NOISE_ACC, "accelerometer noise"),
];

/// Runs the built-in test (BIT `command` 2, full stationary) and reads its
/// result: the `hdwBitStatus` line and whether it passed.
pub fn bit(link: &mut IsbLink) -> anyhow::Result<(String, bool)> {
    link.set(
        did::BIT,
        sets::bit::COMMAND as u16,
        &[sets::bit::CMD_FULL_STATIONARY, 0, 0, 0],
        "BIT.command 2",
    )?;
    let b = link.get(did::BIT)?;
    let status = sets::le::u32(&b, sets::bit::HDW_BIT_STATUS);
    let names: Vec<&str> = HDW_BIT_NAMES
        .iter()
        .filter(|(m, _)| status & m != 0)
        .map(|(_, n)| *n)
        .collect();
    let passed = status & (sets::bit::HDW_PASSED_ALL | sets::bit::HDW_PASSED_NO_GPS) != 0
        && status & (sets::bit::HDW_FAULT_NOISE_PQR | sets::bit::HDW_FAULT_NOISE_ACC) == 0;
    let verdict = if passed { "pass" } else { "FAIL" };
    Ok((
        format!(
            "hdwBitStatus: {status:#010x} ({verdict}: {})",
            names.join(", ")
        ),
        passed,
    ))
}

/// Runs `imu-emu client --protocol isb …` (all but `decode` and `plot`).
pub fn run(
    args: &super::ClientArgs,
    out: &mut dyn Write,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<()> {
    use super::ClientCmd as C;
    let kernel_only = |what: &str| -> anyhow::Result<()> {
        Err(UsageError(format!(
            "{what} is a KERNEL command; an IMX-5 takes its line rate from \
             FLASH_CONFIG.ser0BaudRate after a reset (set it, then `imu-emu client --protocol \
             isb reset`)"
        ))
        .into())
    };
    // Refuse before opening the line.
    match &args.cmd {
        C::CommitBaud => return kernel_only("commit-baud"),
        C::Udd { .. } => return kernel_only("udd"),
        _ => {}
    }
    let mut link = IsbLink::new(Line::open(args)?);
    match &args.cmd {
        C::Info => {
            let b = link.get(did::DEV_INFO)?;
            write!(out, "{}", show_set(did::DEV_INFO, &b)?)?;
        }
        C::Bit => {
            let (line, passed) = bit(&mut link)?;
            writeln!(out, "{line}")?;
            if !passed {
                out.flush()?;
                bail!("BIT failed: {line}");
            }
        }
        C::Start { format } => {
            let d = parse_set(format)?;
            let (name, _) = set_of(d)?;
            link.send_get(d, 1)?;
            let deadline = Instant::now() + link.line.timeout;
            loop {
                match link.packet_before(deadline)? {
                    Some(p) if p.whole_set().is_some_and(|(x, _)| x == d) => break,
                    Some(_) => {}
                    None => bail!(
                        "{}: no {name} packet within {:?} after GET_DATA",
                        link.line.what,
                        link.line.timeout
                    ),
                }
            }
            writeln!(out, "started {name} ({d})")?;
        }
        C::Stop => {
            link.send_stop()?;
            writeln!(out, "stopped")?;
        }
        C::Get { param } => match did::set_by_name(param) {
            Some(d) => {
                let b = link.get(d)?;
                write!(out, "{}", show_set(d, &b)?)?;
            }
            None => {
                let (d, f) = find_field(param)?;
                let b = link.get(d)?;
                writeln!(out, "{}", show_field(f, &b))?;
            }
        },
        C::Set { param, value } => match did::set_by_name(param) {
            Some(d) => {
                let (set_name, fs) = set_of(d)?;
                let bytes = parse_set_value(d, fs, value, &mut link)?;
                link.set(d, 0, &bytes, &format!("{set_name} {value}"))?;
                writeln!(out, "{set_name} saved = {value}")?;
                if d == did::FLASH_CONFIG {
                    writeln!(out, "{RESET_HINT}")?;
                }
            }
            None => {
                let (d, f) = find_field(param)?;
                let mut bytes = parse_field(f, value)?;
                let (set_name, _) = set_of(d)?;
                let what = format!("{set_name}.{} {value}", f.name);
                // A system command runs only with its inverse written in
                // the same SET_DATA (docs/isb.md): the client sends both.
                let pair = d == did::SYS_CMD && f.offset == sets::sys_cmd::COMMAND;
                if pair {
                    let code = sets::le::u32(&bytes, 0);
                    bytes = sets::SystemCommand::new(code).encode().to_vec();
                }
                link.set(d, f.offset as u16, &bytes, &what)?;
                writeln!(out, "{set_name}.{} saved = {value}", f.name)?;
                if pair {
                    writeln!(
                        out,
                        "(sent with SYS_CMD.invCommand = {:#010x} in the same SET_DATA: a \
                         command runs only with its inverse)",
                        !sets::le::u32(&bytes, 0)
                    )?;
                }
                if d == did::FLASH_CONFIG
                    && matches!(
                        f.offset,
                        sets::flash::STARTUP_IMU_DT_MS
                            | sets::flash::STARTUP_NAV_DT_MS
                            | sets::flash::SER0_BAUD_RATE
                    )
                {
                    writeln!(out, "{RESET_HINT}")?;
                }
            }
        },
        C::Reset => {
            system_command(&mut link, sets::sys_cmd::SOFTWARE_RESET, "software reset")?;
            writeln!(
                out,
                "reset (SYS_CMD 99): the unit restarts with its saved FLASH_CONFIG"
            )?;
        }
        C::FactoryReset => {
            system_command(
                &mut link,
                sets::sys_cmd::MANF_UNLOCK,
                "manufacturing unlock",
            )?;
            system_command(
                &mut link,
                sets::sys_cmd::MANF_FACTORY_RESET,
                "factory reset",
            )?;
            writeln!(
                out,
                "factory reset (SYS_CMD 1357924680 after the unlock): FLASH_CONFIG back to its \
                 defaults, saved; the unit restarts"
            )?;
        }
        C::Record {
            duration,
            frames,
            out: o,
            to,
            raw,
            did: dids,
            period,
            format,
            nmea,
        } => {
            if format.is_some() {
                return Err(UsageError(
                    "record --format is a KERNEL option; with --protocol isb name the data sets: \
                     --did IMU,PIMU"
                        .into(),
                )
                .into());
            }
            if let Some(names) = nmea {
                let mut w = super::writer(o.as_ref())?;
                let period = u8::try_from(*period)
                    .map_err(|_| UsageError("record --nmea: --period is 0…255".into()))?;
                let r =
                    super::nmea::record(&mut link, &mut w, names, period, *frames, *duration, stop);
                w.flush()?;
                eprintln!("imu-emu: {} NMEA sentences recorded", r?);
                return Ok(());
            }
            let dids = parse_sets(dids.as_deref().unwrap_or("IMU"))?;
            if let Some(r) = raw {
                link.line.tee = Some(
                    std::fs::File::create(r).with_context(|| format!("--raw {}", r.display()))?,
                );
            }
            let mut w = super::writer(o.as_ref())?;
            let until = Until {
                frames: *frames,
                duration: *duration,
            };
            let r = record(&mut link, &mut w, *to, &dids, *period, until, stop);
            w.flush()?;
            let rec = r?;
            eprintln!(
                "imu-emu: {} packets recorded ({}), {} failed their checksum{}",
                rec.rows,
                rec.summary(),
                link.checksum_errors(),
                if stop() {
                    " (interrupted; streams stopped)"
                } else {
                    ""
                }
            );
        }
        C::CommitBaud | C::Udd { .. } | C::Decode { .. } | C::Plot { .. } => {
            unreachable!("handled before")
        }
    }
    Ok(())
}
