//! What the device received, decoded on the host side: every command
//! frame logged, every frame the device rejects or ignores counted with
//! the reason (`status` on the control socket, `-v` logs). Each protocol
//! names its monitor ([`InputMonitor`], `HostProtocol::Monitor`): the
//! KERNEL's [`Monitor`], or [`Silent`].
//!
//! The core is `no_std` and does not log; the host decodes the same bytes
//! the device's UART received (after the link faults) with the core's own
//! codec ([`imu_emu::kernel::frame::Decoder`], [`Command::parse`]) and
//! validates SaveFlash values with [`ParamSpec::validate`] against the
//! device's parameter RAM, so the reasons name the ICD rule that applies.

use imu_emu::kernel::command::{Command, ParseError};
use imu_emu::kernel::frame::{Decoder, TYPE_COMMAND};
use imu_emu::kernel::params::{self, ParamError, ParamSpec, PARAMS};
use imu_emu::model::Product;

/// Largest command frame decoded (as the device's own RX buffer).
const CAP: usize = 512;

/// Why the device rejected or ignored a frame it received.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Reject {
    /// A candidate with a bad length field or checksum (Table 5.2).
    Checksum,
    /// A frame that is not a command (`type ≠ 0` or `id ≠ 0`, Table 5.2).
    NotCommand,
    /// A payload that is not a command (5.3).
    Malformed,
    /// A one-byte code the device does not know.
    UnknownCommand,
    /// A data command for a format the model does not run (Table 5.16).
    UnsupportedFormat,
    /// SaveFlash/ReadRAM of an ID not in Table 5.24.
    UnknownParameter,
    /// SaveFlash/ReadRAM whose length is not the parameter's.
    WrongLength,
    /// SaveFlash of a value breaking the parameter's rule (5.3.7).
    BadValue,
    /// SaveFlash of a read-only or unsupported parameter.
    ReadOnly,
}

impl Reject {
    /// Every reason, in `status` order.
    pub const ALL: [Reject; 9] = [
        Reject::Checksum,
        Reject::NotCommand,
        Reject::Malformed,
        Reject::UnknownCommand,
        Reject::UnsupportedFormat,
        Reject::UnknownParameter,
        Reject::WrongLength,
        Reject::BadValue,
        Reject::ReadOnly,
    ];

    /// The word `status` uses for it.
    pub fn name(self) -> &'static str {
        match self {
            Reject::Checksum => "checksum",
            Reject::NotCommand => "not-command",
            Reject::Malformed => "malformed",
            Reject::UnknownCommand => "unknown-command",
            Reject::UnsupportedFormat => "unsupported-format",
            Reject::UnknownParameter => "unknown-parameter",
            Reject::WrongLength => "wrong-length",
            Reject::BadValue => "bad-value",
            Reject::ReadOnly => "read-only",
        }
    }
}

/// A command frame the device received, copied out of the decoder.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Received {
    msg_type: u8,
    id: u8,
    payload: Vec<u8>,
}

/// The host-side decoder of the device's input and its counters.
pub struct Monitor {
    rx: Box<Decoder<CAP>>,
    /// Frames decoded, waiting for [`Monitor::judge`].
    pending: Vec<Received>,
    /// Bad candidates already counted.
    seen_errors: u32,
    /// The next message is a UDD configuration (after 0x96).
    udd_pending: bool,
    commands: u64,
    rejected: [u64; Reject::ALL.len()],
}

impl Default for Monitor {
    fn default() -> Self {
        Self::new()
    }
}

impl Monitor {
    /// No frame seen yet.
    pub fn new() -> Self {
        Monitor {
            rx: Box::new(Decoder::new()),
            pending: Vec::new(),
            seen_errors: 0,
            udd_pending: false,
            commands: 0,
            rejected: [0; Reject::ALL.len()],
        }
    }

    /// Feeds bytes the device received.
    pub fn feed(&mut self, mut bytes: &[u8]) {
        while let Some(f) = self.rx.next_frame(&mut bytes) {
            self.pending.push(Received {
                msg_type: f.msg_type,
                id: f.id,
                payload: f.payload.to_vec(),
            });
        }
        let errors = self.rx.errors();
        for _ in self.seen_errors..errors {
            self.count(Reject::Checksum);
            tracing::info!("frame rejected: bad length or checksum (ICD Table 5.2) — dropped");
        }
        self.seen_errors = errors;
    }

    fn count(&mut self, r: Reject) {
        self.rejected[r as usize] += 1;
    }

    /// Judges the frames fed since the last call: logs each command and,
    /// for those the device rejects or ignores, why. `param` reads the
    /// device's parameter RAM (`Device::param_ram`).
    pub fn judge(&mut self, product: &Product, param: &dyn Fn(u16) -> Option<Vec<u8>>) {
        for f in core::mem::take(&mut self.pending) {
            self.judge_one(&f, product, param);
        }
    }

    fn judge_one(
        &mut self,
        f: &Received,
        product: &Product,
        param: &dyn Fn(u16) -> Option<Vec<u8>>,
    ) {
        if f.msg_type != TYPE_COMMAND || f.id != 0 {
            self.count(Reject::NotCommand);
            tracing::info!(
                "frame type {:#04x} id {:#04x} ignored: not a command (type 0, id 0; ICD Table 5.2)",
                f.msg_type,
                f.id
            );
            return;
        }
        self.commands += 1;
        let parsed = Command::parse(&f.payload);
        if core::mem::take(&mut self.udd_pending)
            && matches!(parsed, Ok(Command::Unknown(_)) | Err(_))
        {
            tracing::info!("command User_Def_Data_config message {:02X?}", f.payload);
            return;
        }
        let cmd = match parsed {
            Ok(c) => c,
            Err(e) => {
                self.count(Reject::Malformed);
                let why = match e {
                    ParseError::Empty => "empty payload",
                    ParseError::BadLength => "size disagrees with its length field",
                    ParseError::Unrecognised => "not a known command",
                };
                tracing::info!(
                    "command {:02X?} ignored: {why} — no reply, ICD 5.3",
                    &f.payload[..f.payload.len().min(8)]
                );
                return;
            }
        };
        match cmd {
            Command::Data(code) => {
                if product.model.supports_format(code) {
                    tracing::info!("command start format {code:#04x}");
                } else {
                    self.count(Reject::UnsupportedFormat);
                    tracing::info!(
                        "command start format {code:#04x} ignored: {} does not run it — no \
                         reply, ICD Table 5.16",
                        product.code()
                    );
                }
            }
            Command::Unknown(code) => {
                self.count(Reject::UnknownCommand);
                tracing::info!("command {code:#04x} ignored: unknown command — no reply, ICD 5.3");
            }
            Command::UddConfig => {
                self.udd_pending = true;
                tracing::info!("command User_Def_Data_config");
            }
            Command::SaveFlash { id, len, value } => {
                self.save_flash(id, len, value, product, param)
            }
            Command::ReadRam { id, len } => match params::find(id) {
                None => {
                    self.count(Reject::UnknownParameter);
                    tracing::info!(
                        "ReadRAM {id:#06x}: no such parameter — no reply, ICD Table 5.24"
                    );
                }
                Some(p) if p.byte_len() != len => {
                    self.count(Reject::WrongLength);
                    tracing::info!(
                        "ReadRAM {} length {len}: it is {} bytes — no reply, ICD 5.3.8",
                        p.name,
                        p.byte_len()
                    );
                }
                Some(p) => tracing::info!("command ReadRAM {}", p.name),
            },
            other => tracing::info!("command {other:?}"),
        }
    }

    fn save_flash(
        &mut self,
        id: u16,
        len: u16,
        value: &[u8],
        product: &Product,
        param: &dyn Fn(u16) -> Option<Vec<u8>>,
    ) {
        let Some(p) = params::find(id) else {
            self.count(Reject::UnknownParameter);
            tracing::info!("SaveFlash {id:#06x}: no such parameter — no reply, ICD 5.3.7");
            return;
        };
        if p.byte_len() != len {
            self.count(Reject::WrongLength);
            tracing::info!(
                "SaveFlash {} length {len}: it is {} bytes — no reply, ICD 5.3.7",
                p.name,
                p.byte_len()
            );
            return;
        }
        let block = block_of(product, param);
        match p.validate(value, product, &block) {
            Ok(()) => tracing::info!("parameter saved: {} = {}", p.name, show(p, value)),
            Err(e) => {
                let r = match e {
                    ParamError::ReadOnly => Reject::ReadOnly,
                    ParamError::UnknownId => Reject::UnknownParameter,
                    ParamError::WrongLength => Reject::WrongLength,
                    ParamError::BadValue => Reject::BadValue,
                };
                self.count(r);
                tracing::info!(
                    "SaveFlash {} {}: {} — no reply, ICD 5.3.7",
                    p.name,
                    show(p, value),
                    why(p, e, product)
                );
            }
        }
    }

    /// Command frames decoded so far.
    pub fn commands(&self) -> u64 {
        self.commands
    }

    /// Frames rejected or ignored so far, per reason (non-zero ones).
    pub fn rejected(&self) -> Vec<(Reject, u64)> {
        Reject::ALL
            .iter()
            .map(|&r| (r, self.rejected[r as usize]))
            .filter(|&(_, n)| n > 0)
            .collect()
    }
}

/// What the runner asks of a protocol's monitor of the device's input
/// (`crate::protocol::HostProtocol::Monitor`): fed what the device's UART
/// received, judged after the device took it, counted in `status`.
pub trait InputMonitor<P>: Default {
    /// Feeds bytes the device received.
    fn feed(&mut self, bytes: &[u8]);
    /// Judges what was fed since the last call against the device's
    /// personality `dev` of `product` (logs, counters).
    fn judge(&mut self, dev: &P, product: &Product);
    /// Commands decoded so far (`status commands=`).
    fn commands(&self) -> u64;
    /// Input rejected or ignored so far, per reason word (`status
    /// rejected-…=`, the non-zero ones, in a fixed order).
    fn rejected(&self) -> Vec<(&'static str, u64)>;
}

/// The KERNEL's: the commands and the reasons of Table 5.24's rules, read
/// against the device's parameter RAM.
impl InputMonitor<imu_emu::kernel::Kernel> for Monitor {
    fn feed(&mut self, bytes: &[u8]) {
        Monitor::feed(self, bytes);
    }

    fn judge(&mut self, dev: &imu_emu::kernel::Kernel, product: &Product) {
        Monitor::judge(self, product, &|id| dev.param_ram(id).map(<[u8]>::to_vec));
    }

    fn commands(&self) -> u64 {
        Monitor::commands(self)
    }

    fn rejected(&self) -> Vec<(&'static str, u64)> {
        Monitor::rejected(self)
            .into_iter()
            .map(|(r, n)| (r.name(), n))
            .collect()
    }
}

/// No host-side decoding of the input: `status` counts no commands and no
/// rejections, nothing is logged (a protocol whose device reports its own
/// input counters, as the IMX-5's PORT_MONITOR does).
#[derive(Debug, Default, Clone, Copy)]
pub struct Silent;

impl<P> InputMonitor<P> for Silent {
    fn feed(&mut self, _bytes: &[u8]) {}

    fn judge(&mut self, _dev: &P, _product: &Product) {}

    fn commands(&self) -> u64 {
        0
    }

    fn rejected(&self) -> Vec<(&'static str, u64)> {
        Vec::new()
    }
}

/// The device's parameter block as far as `param` tells it (factory values
/// elsewhere).
fn block_of(product: &Product, param: &dyn Fn(u16) -> Option<Vec<u8>>) -> params::Block {
    let mut block = params::factory_block(product);
    for p in PARAMS {
        if let Some(v) = param(p.id).filter(|v| v.len() == p.range().len()) {
            block[p.range()].copy_from_slice(&v);
        }
    }
    block
}

/// A value as a person writes it.
fn show(p: &ParamSpec, value: &[u8]) -> String {
    use params::Kind;
    match p.kind {
        Kind::U8 => value[0].to_string(),
        Kind::U16 => u16::from_le_bytes([value[0], value[1]]).to_string(),
        _ => value
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]).to_string())
            .collect::<Vec<_>>()
            .join(" "),
    }
}

/// Why `p`'s rule refused a value, in words.
fn why(p: &ParamSpec, e: ParamError, product: &Product) -> String {
    use params::Rule;
    if e != ParamError::BadValue {
        return match e {
            ParamError::ReadOnly => "read-only".to_owned(),
            ParamError::WrongLength => format!("not {} bytes", p.byte_len()),
            _ => "no such parameter".to_owned(),
        };
    }
    match p.rule {
        Rule::Range(lo, hi) => format!("outside {lo}..={hi}"),
        Rule::DivisorOfInternalRate => {
            format!("not a divisor of {}", product.model.internal_rate_hz)
        }
        Rule::AlignmentAngles => "heading/roll beyond ±180° or pitch beyond ±90°".to_owned(),
        Rule::NonNegative => "not a finite value ≥ 0".to_owned(),
        Rule::Positive => "not a finite value > 0".to_owned(),
        Rule::AutoStart => format!("not 0 or a format {} runs", product.model.short),
        Rule::Lpf => format!("not an LPF code of {}", product.model.short),
        Rule::Switch { .. } => {
            "not 0 or 1, or 1 is not possible on this model / with the other pin function on"
                .to_owned()
        }
        _ => "refused".to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn product() -> Product {
        Product::parse("K110").unwrap()
    }

    fn cmd(c: Command<'_>) -> Vec<u8> {
        let mut out = [0u8; 300];
        let n = c.encode(&mut out).unwrap();
        out[..n].to_vec()
    }

    #[test]
    fn reasons_come_from_the_decoded_frames() {
        let mut m = Monitor::new();
        let p = product();
        m.feed(&cmd(Command::GetDevInfo));
        m.feed(&cmd(Command::Unknown(0x77)));
        m.feed(&cmd(Command::SaveFlash {
            id: params::DATA_RATE.id,
            len: 2,
            value: &33u16.to_le_bytes(),
        }));
        m.feed(&cmd(Command::SaveFlash {
            id: params::DATA_RATE.id,
            len: 2,
            value: &200u16.to_le_bytes(),
        }));
        let mut bad = cmd(Command::Stop);
        *bad.last_mut().unwrap() ^= 1;
        m.feed(&bad);
        m.judge(&p, &|_| None);
        assert_eq!(m.commands(), 4);
        assert_eq!(
            m.rejected(),
            [
                (Reject::Checksum, 1),
                (Reject::UnknownCommand, 1),
                (Reject::BadValue, 1)
            ]
        );
        assert_eq!(
            why(&params::DATA_RATE, ParamError::BadValue, &p),
            "not a divisor of 2000"
        );
    }
}
