//! `imu-emu client …`: the host side of a KERNEL line, against the
//! emulator or a real unit on a serial port (`--serial DEV --baud N`) or
//! TCP (`--tcp HOST:PORT`).
//!
//! | subcommand | what it does |
//! |---|---|
//! | `info` | GetDevInfo (5.3.3): serial number, firmware, IMU type |
//! | `bit` | GetBIT (5.3.4): the BIT bytes |
//! | `start FORMAT` | a data command (Table 5.16) by name (`GA`) or code (`0x8F`); waits for the acknowledgement |
//! | `stop` | Stop (5.3.2) |
//! | `get PARAM` / `set PARAM VALUE` | ReadRAM / SaveFlash (5.3.7, 5.3.8) by Table 5.24 name |
//! | `commit-baud` | CommitBaudRate (5.3.9) |
//! | `udd TYPE,…` | User_Def_Data_config (5.3.5) with the type codes, prints the device's check |
//! | `record` | decoded frames to CSV or JSON lines, each with its device time, for `--frames N` or `--duration S` of device time, with a progress line on a terminal |
//! | `decode FILE` | a raw capture decoded the same way (its protocol detected) |
//! | `reset`, `factory-reset` | IMX-5 only: SYS_CMD with its inverse in one packet |
//! | `plot CSV` | a recording to PNG or SVG: rates, accelerations, attitude against device time |
//!
//! Errors are one line: the port cannot be opened, no answer within
//! `--timeout`, answers that fail their checksum.

pub mod decode;
pub mod isb;
pub mod nmea;
pub mod plot;
pub mod tool_protocol;

use std::io::{IsTerminal as _, Read, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context as _};
use imu_emu::kernel::command::{self, Command};
use imu_emu::kernel::frame::{Decoder, TYPE_DATA};
use imu_emu::kernel::params::{self, Kind, ParamSpec, PARAMS};
use imu_emu::model::Product;

use crate::error::UsageError;
use crate::protocol::Protocol;

/// Options of `imu-emu client`.
#[derive(clap::Args, Debug, Clone)]
pub struct ClientArgs {
    /// The unit's TCP address (the emulator's `listening on tcp …`).
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "serial")]
    pub tcp: Option<String>,

    /// The unit's serial port (e.g. /dev/ttyUSB0, or the emulator's pty).
    #[arg(long, value_name = "DEV")]
    pub serial: Option<PathBuf>,

    /// Line rate of --serial, bit/s.
    #[arg(long, value_name = "N", default_value_t = 115_200)]
    pub baud: u32,

    /// How long to wait for an answer (or, with `record`, for a data
    /// frame), seconds: more than 0, at most 3600.
    #[arg(long, value_name = "S", default_value_t = 2.0, value_parser = parse_timeout)]
    pub timeout: f64,

    /// The unit's protocol: `kernel` (an Inertial Labs KERNEL) or `isb`
    /// (an Inertial Sense IMX-5) [default: kernel; `decode`: detected from
    /// the capture].
    #[arg(long, value_enum)]
    pub protocol: Option<Protocol>,

    /// The unit's model (scale factors of the low-resolution fields,
    /// Table 5.6; KERNEL only).
    #[arg(long, value_name = "MODEL", default_value = "K110", value_parser = parse_product)]
    pub model: Product,

    /// What to do.
    #[command(subcommand)]
    pub cmd: ClientCmd,
}

/// `--timeout`: a finite number of seconds in (0, 3600]; NaN, infinities
/// and absurd values are usage errors (they used to panic or wait for
/// ever).
fn parse_timeout(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|t| *t > 0.0 && *t <= MAX_TIMEOUT_S)
        .ok_or_else(|| format!("not a time in seconds in (0, {MAX_TIMEOUT_S}]: {s}"))
}

/// `decode --rate`: a finite rate in (0, 4000] Hz.
fn parse_rate(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|r| *r > 0.0 && *r <= 4000.0)
        .ok_or_else(|| format!("not an output rate in (0, 4000] Hz: {s}"))
}

/// The output rate that times clockless frames in `decode` without
/// `--rate`: the factory Data_Rate (ICD Table 5.24).
pub const DEFAULT_DECODE_RATE_HZ: f64 = 100.0;

/// Longest `--timeout`, seconds.
pub const MAX_TIMEOUT_S: f64 = 3600.0;

fn parse_product(s: &str) -> Result<Product, String> {
    Product::parse(s).map_err(|e| e.to_string())
}

/// Output format of `record` and `decode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OutFormat {
    /// Comma-separated values with a header row.
    Csv,
    /// One JSON object per line.
    Json,
}

/// The subcommands.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum ClientCmd {
    /// GetDevInfo: serial number, firmware, IMU type.
    Info,
    /// GetBIT: the built-in-test bytes.
    Bit,
    /// Start a data stream: a format name (GA, GAm, GAA, GAAm, Orientation,
    /// Quaternion, Calibrated-HR, UDD) or code (0x8F).
    Start {
        /// The format.
        format: String,
    },
    /// Stop the stream.
    Stop,
    /// Read a parameter (ReadRAM) by its Table 5.24 name.
    Get {
        /// Name (e.g. Data_Rate) or ID (0x0012).
        param: String,
    },
    /// Save a parameter (SaveFlash); the value as printed by `get`. ISB: a
    /// field (`SET.field`) or a whole set (`SET`, every field's value in
    /// order, comma-separated, in one SET_DATA).
    Set {
        /// Name (e.g. Data_Rate) or ID (0x0012); ISB: SET.field or SET.
        param: String,
        /// The value (three comma-separated numbers for Alignment_Angles).
        value: String,
    },
    /// CommitBaudRate: the saved Baud_Rate takes effect.
    CommitBaud,
    /// IMX-5 (ISB): software reset, SYS_CMD 99 with its inverse in one
    /// SET_DATA; saved FLASH_CONFIG values (startupNavDtMs, ser0BaudRate,
    /// …) take effect.
    Reset,
    /// IMX-5 (ISB): factory reset, FLASH_CONFIG back to its defaults,
    /// saved, then a reset (SYS_CMD manufacturing unlock, then factory
    /// reset, each with its inverse in one SET_DATA).
    FactoryReset,
    /// Configure User Defined Data: type codes, comma-separated (0x21,0x23).
    Udd {
        /// The types.
        types: String,
    },
    /// Record decoded frames.
    Record {
        /// Start this format first (and stop it at the end).
        #[arg(long, value_name = "FORMAT")]
        format: Option<String>,
        /// Record this many seconds of device time, counted from the
        /// frames' own clock (counter, IMU time, ISB `time`; a format without
        /// one from the rate the device runs, Formula 5.1, and the frames'
        /// order), at whatever rate the device sends.
        #[arg(long, value_name = "S", conflicts_with = "frames")]
        duration: Option<f64>,
        /// Record this many frames.
        #[arg(long, value_name = "N")]
        frames: Option<u64>,
        /// Output file (default, or `-`: stdout).
        #[arg(long, short, value_name = "FILE")]
        out: Option<PathBuf>,
        /// csv or json (lines).
        #[arg(long, value_enum, default_value_t = OutFormat::Csv)]
        to: OutFormat,
        /// Also keep the raw bytes received in this file.
        #[arg(long, value_name = "FILE")]
        raw: Option<PathBuf>,
        /// ISB: the data sets to stream and record, comma-separated names
        /// or numbers (IMU,PIMU); default IMU.
        #[arg(long, value_name = "SETS")]
        did: Option<String>,
        /// ISB: stream every N source periods of the set (GET_DATA period).
        #[arg(long, value_name = "N", default_value_t = 1)]
        period: u16,
        /// ISB: record these NMEA sentences instead (`$ASCE` names or
        /// numbers, comma-separated: GNGGA,GNRMC,GPGSV), every --period
        /// source periods, as an NMEA log (each sentence as received).
        #[arg(long, value_name = "SENTENCES", conflicts_with_all = ["did", "to"])]
        nmea: Option<String>,
    },
    /// Decode a raw capture (the bytes of a line) to CSV or JSON lines.
    Decode {
        /// The capture.
        file: PathBuf,
        /// Output file (default, or `-`: stdout).
        #[arg(long, short, value_name = "FILE")]
        out: Option<PathBuf>,
        /// csv or json (lines).
        #[arg(long, value_enum, default_value_t = OutFormat::Csv)]
        to: OutFormat,
        /// ISB: only this data set (a CSV holds the first set seen otherwise).
        #[arg(long, value_name = "SET")]
        did: Option<String>,
        /// KERNEL: the output rate, Hz, that times the frames of a format
        /// without a clock (Orientation, Quaternion, GAA, GAm, GAAm, a UDD
        /// without IMU time) [default: 100, the factory Data_Rate].
        #[arg(long, value_name = "HZ", value_parser = parse_rate)]
        rate: Option<f64>,
    },
    /// Plot a CSV recording (rates, accelerations, attitude against device
    /// time) to PNG or SVG, by the output's extension.
    Plot {
        /// The CSV recording (from `record` or `decode`).
        file: PathBuf,
        /// The .png or .svg to write (its folder must exist).
        #[arg(long, short, value_name = "FILE")]
        out: PathBuf,
    },
}

trait Port: Read + Write + Send {}
impl<T: Read + Write + Send> Port for T {}

/// The rate of the KERNEL frame counter, whatever the model's internal
/// rate (ICD Tables 5.7, 5.10 note 3).
const COUNTER_HZ: u16 = 2000;

/// Largest frame decoded.
const CAP: usize = 4096;

/// A byte line to a unit (TCP or serial), protocol-free.
pub struct Line {
    port: Box<dyn Port>,
    /// How long to wait for an answer (`--timeout`).
    pub timeout: Duration,
    /// The line as the user named it (`--tcp 127.0.0.1:7000`), for errors.
    pub what: String,
    /// Raw bytes received go here too (`record --raw`).
    pub tee: Option<std::fs::File>,
    /// Bytes read and not yet taken by the decoder: `inbuf[inpos..]`.
    inbuf: Vec<u8>,
    inpos: usize,
}

impl Line {
    /// Opens the line `args` name.
    pub fn open(args: &ClientArgs) -> anyhow::Result<Line> {
        let timeout = Duration::from_secs_f64(args.timeout.clamp(0.01, MAX_TIMEOUT_S));
        let (port, what): (Box<dyn Port>, String) = match (&args.tcp, &args.serial) {
            (Some(addr), None) => {
                use std::net::ToSocketAddrs as _;
                let what = format!("--tcp {addr}");
                let sa = addr
                    .to_socket_addrs()
                    .map_err(|e| UsageError(format!("{what}: {e}; expected HOST:PORT")))?
                    .next()
                    .ok_or_else(|| UsageError(format!("{what}: no address")))?;
                let s = std::net::TcpStream::connect_timeout(&sa, timeout)
                    .map_err(|e| anyhow!("{what}: cannot connect: {e}"))?;
                s.set_nodelay(true)?;
                s.set_read_timeout(Some(Duration::from_millis(20)))?;
                (Box::new(s), what)
            }
            (None, Some(dev)) => {
                let what = format!("--serial {}", dev.display());
                let p = serialport::new(dev.to_string_lossy(), args.baud)
                    .timeout(Duration::from_millis(20))
                    .open()
                    .map_err(|e| anyhow!("{what}: cannot open: {e}"))?;
                (Box::new(p), what)
            }
            _ => {
                return Err(UsageError(
                    "client: say where the unit is: --tcp HOST:PORT or --serial DEV".to_owned(),
                )
                .into())
            }
        };
        Ok(Line {
            port,
            timeout,
            what,
            tee: None,
            inbuf: Vec::new(),
            inpos: 0,
        })
    }

    /// The next item `take` decodes from the bytes received (it advances
    /// its input past what it took) before `deadline`, or `None`.
    pub fn next_before<T>(
        &mut self,
        deadline: Instant,
        mut take: impl FnMut(&mut &[u8]) -> Option<T>,
    ) -> anyhow::Result<Option<T>> {
        loop {
            let mut input: &[u8] = &self.inbuf[self.inpos..];
            let before = input.len();
            let got = take(&mut input);
            self.inpos += before - input.len();
            if got.is_some() {
                return Ok(got);
            }
            self.inbuf.clear();
            self.inpos = 0;
            if Instant::now() >= deadline {
                return Ok(None);
            }
            self.read_more()?;
        }
    }

    /// Writes `bytes`.
    pub fn write(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.port
            .write_all(bytes)
            .and_then(|()| self.port.flush())
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::BrokenPipe | std::io::ErrorKind::ConnectionReset => {
                    self.closed()
                }
                _ => anyhow!("{}: write: {e}", self.what),
            })
    }

    /// The error of a line the unit closed; over TCP it says why that
    /// happens to an emulator's client.
    fn closed(&self) -> anyhow::Error {
        if self.what.starts_with("--tcp") {
            anyhow!(
                "{}: the unit closed the connection (the emulator serves one client at a \
                 time: another client connecting took the line over, or the emulator stopped)",
                self.what
            )
        } else {
            anyhow!("{}: the unit closed the connection", self.what)
        }
    }

    /// Appends what arrives within about 20 ms to the input (also to the
    /// tee); an error when the unit closed the connection.
    fn read_more(&mut self) -> anyhow::Result<()> {
        let mut buf = [0u8; 4096];
        let n = match self.port.read(&mut buf) {
            Ok(0) => return Err(self.closed()),
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => return Err(self.closed()),
            Err(e) => bail!("{}: read: {e}", self.what),
        };
        if let Some(t) = self.tee.as_mut() {
            t.write_all(&buf[..n])?;
        }
        self.inbuf.extend_from_slice(&buf[..n]);
        Ok(())
    }
}

/// A KERNEL line: a [`Line`] with a frame decoder.
pub struct Link {
    line: Line,
    rx: Box<Decoder<CAP>>,
}

/// A frame received: identifier and payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    /// Message type.
    pub msg_type: u8,
    /// Identifier.
    pub id: u8,
    /// Payload.
    pub payload: Vec<u8>,
}

impl Link {
    /// Opens the line `args` name.
    pub fn open(args: &ClientArgs) -> anyhow::Result<Link> {
        Ok(Link {
            line: Line::open(args)?,
            rx: Box::new(Decoder::new()),
        })
    }

    /// Sends a command.
    pub fn send(&mut self, c: Command<'_>) -> anyhow::Result<()> {
        let mut buf = [0u8; 300];
        let n = c.encode(&mut buf).context("command too long")?;
        self.line.write(&buf[..n])
    }

    /// Frames that failed their length or checksum so far.
    pub fn checksum_errors(&self) -> u32 {
        self.rx.errors()
    }

    /// The next frame before `deadline`, or `None`.
    pub fn frame_before(&mut self, deadline: Instant) -> anyhow::Result<Option<Frame>> {
        let rx = &mut self.rx;
        self.line.next_before(deadline, |input| {
            rx.next_frame(input).map(|f| Frame {
                msg_type: f.msg_type,
                id: f.id,
                payload: f.payload.to_vec(),
            })
        })
    }

    /// Sends `c` and waits for a data frame with `id`; a one-line error
    /// after the timeout (saying if frames failed their checksum).
    pub fn request(&mut self, c: Command<'_>, id: u8, what: &str) -> anyhow::Result<Frame> {
        let errors = self.checksum_errors();
        self.send(c)?;
        self.answer(id, what, errors)
    }

    fn answer(&mut self, id: u8, what: &str, errors_before: u32) -> anyhow::Result<Frame> {
        let deadline = Instant::now() + self.line.timeout;
        while let Some(f) = self.frame_before(deadline)? {
            if f.msg_type == TYPE_DATA && f.id == id {
                return Ok(f);
            }
        }
        let bad = self.checksum_errors() - errors_before;
        if bad > 0 {
            bail!(
                "{}: no valid answer to {what} within {:?}: {bad} frames failed their \
                 checksum (wrong --baud?)",
                self.line.what,
                self.line.timeout
            );
        }
        bail!(
            "{}: no answer to {what} within {:?} (is the unit on, the line rate right?)",
            self.line.what,
            self.line.timeout
        )
    }

    /// Reads and discards whatever arrives during `d`.
    pub fn drain(&mut self, d: Duration) -> anyhow::Result<()> {
        let end = Instant::now() + d;
        while self.frame_before(end)?.is_some() {}
        Ok(())
    }
}

/// The row of a parameter by Table 5.24 name (any case) or ID.
pub fn find_param(s: &str) -> anyhow::Result<&'static ParamSpec> {
    let by_id = s
        .strip_prefix("0x")
        .and_then(|h| u16::from_str_radix(h, 16).ok())
        .and_then(params::find);
    by_id
        .or_else(|| PARAMS.iter().find(|p| p.name.eq_ignore_ascii_case(s)))
        .ok_or_else(|| {
            let names: Vec<&str> = PARAMS.iter().map(|p| p.name).collect();
            UsageError(format!(
                "no parameter {s}; Table 5.24 names: {}",
                names.join(" ")
            ))
            .into()
        })
}

/// A parameter value as text (`get`).
pub fn show_value(p: &ParamSpec, v: &[u8]) -> String {
    if p.id == params::BAUD_RATE.id {
        return format!("{} bit/s (code {})", params::baud_rate(v[0]), v[0]);
    }
    match p.kind {
        Kind::U8 => v[0].to_string(),
        Kind::U16 => u16::from_le_bytes([v[0], v[1]]).to_string(),
        Kind::F32 | Kind::F32x3 => v
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]).to_string())
            .collect::<Vec<_>>()
            .join(","),
    }
}

/// Parses a value for `p` (`set`).
pub fn parse_value(p: &ParamSpec, s: &str) -> anyhow::Result<Vec<u8>> {
    let bad = || UsageError(format!("{}: {s} is not a {:?} value", p.name, p.kind));
    if p.id == params::BAUD_RATE.id {
        return baud_code(s).map(|c| vec![c]);
    }
    Ok(match p.kind {
        Kind::U8 => vec![s.parse::<u8>().map_err(|_| bad())?],
        Kind::U16 => s.parse::<u16>().map_err(|_| bad())?.to_le_bytes().to_vec(),
        Kind::F32 | Kind::F32x3 => {
            let want = usize::from(p.kind.byte_len() / 4);
            let xs: Vec<f32> = s
                .split(',')
                .map(|x| x.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            if xs.len() != want {
                return Err(bad().into());
            }
            xs.iter().flat_map(|x| x.to_le_bytes()).collect()
        }
    })
}

/// The Baud_Rate code of a line rate in bit/s (`921600`), or a code
/// itself (0..=16, Table 5.24).
fn baud_code(s: &str) -> anyhow::Result<u8> {
    let n: u32 = s.trim().parse().unwrap_or(u32::MAX);
    if let Some(c) = params::BAUD_RATES.iter().position(|&r| r == n) {
        return Ok(c as u8);
    }
    if n < params::BAUD_RATES.len() as u32 {
        return Ok(n as u8);
    }
    let rates: Vec<String> = params::BAUD_RATES.iter().map(u32::to_string).collect();
    Err(UsageError(format!(
        "Baud_Rate: {s} is not a line rate; bit/s: {}",
        rates.join(" ")
    ))
    .into())
}

/// The GetBIT payload (Table 5.18) in words, and whether it passes:
/// accelerometer result (bits 0–1: 0 or 2 okay), gyroscope result (bits
/// 2–4: 0 okay), flash check (bits 12–13: 0 okay); the rest reserved.
pub fn bit_words(p: &[u8]) -> (String, bool) {
    let w = u32::from_le_bytes([
        p.first().copied().unwrap_or(0),
        p.get(1).copied().unwrap_or(0),
        p.get(2).copied().unwrap_or(0),
        p.get(3).copied().unwrap_or(0),
    ]);
    let accel = w & 0x3;
    let gyro = (w >> 2) & 0x7;
    let flash = (w >> 12) & 0x3;
    let ok = |good: bool| if good { "ok" } else { "FAIL" };
    let parts = [
        format!("accelerometer {accel} {}", ok(accel == 0 || accel == 2)),
        format!("gyroscope {gyro} {}", ok(gyro == 0)),
        format!("flash {flash} {}", ok(flash == 0)),
    ];
    let pass = (accel == 0 || accel == 2) && gyro == 0 && flash == 0;
    (parts.join(", "), pass)
}

fn ascii(b: &[u8]) -> String {
    b.iter()
        .take_while(|&&c| c != 0)
        .map(|&c| {
            if c.is_ascii_graphic() || c == b' ' {
                c as char
            } else {
                '?'
            }
        })
        .collect::<String>()
        .trim()
        .to_owned()
}

/// Runs `imu-emu client …`.
pub fn run(args: ClientArgs) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match &args.cmd {
        ClientCmd::Decode {
            file,
            out: o,
            to,
            did,
            rate,
        } => {
            let r = decode_file(&args, file, o.as_ref(), *to, did.as_deref(), *rate);
            return quiet_on_closed_output(r);
        }
        ClientCmd::Plot { file, out: png } => {
            let n = plot::plot(file, png)?;
            writeln!(out, "{}: {n} rows plotted", png.display())?;
            return Ok(());
        }
        _ => {}
    }
    let interrupted = interrupt_flag();
    let stop = || interrupted.load(std::sync::atomic::Ordering::Relaxed);
    tool_protocol::of(args.protocol.unwrap_or_default()).client(&args, &mut out, &stop)
}

/// `imu-emu client CMD` on a KERNEL line (all but `decode` and `plot`).
pub(crate) fn run_kernel(
    args: &ClientArgs,
    out: &mut dyn Write,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<()> {
    if matches!(args.cmd, ClientCmd::Reset | ClientCmd::FactoryReset) {
        return Err(UsageError(
            "reset and factory-reset are IMX-5 (--protocol isb) commands; a KERNEL resets by a \
             power cycle"
                .into(),
        )
        .into());
    }
    let mut link = Link::open(args)?;
    match &args.cmd {
        ClientCmd::Info => {
            let f = link.request(Command::GetDevInfo, command::GET_DEV_INFO, "GetDevInfo")?;
            let p = &f.payload;
            if p.len() < 50 {
                bail!("GetDevInfo answer of {} bytes, expected 166", p.len());
            }
            writeln!(out, "serial: {}", ascii(&p[0..8]))?;
            writeln!(out, "firmware: {}", ascii(&p[8..48]))?;
            writeln!(out, "imu_type: {}", p[49])?;
        }
        ClientCmd::Bit => {
            let f = link.request(Command::GetBit, command::GET_BIT, "GetBIT")?;
            let hex: Vec<String> = f.payload.iter().map(|b| format!("{b:02X}")).collect();
            let (words, pass) = bit_words(&f.payload);
            let verdict = if pass { "pass" } else { "FAIL" };
            let line = format!("bit: {} ({verdict}: {words})", hex.join(" "));
            writeln!(out, "{line}")?;
            if !pass {
                out.flush()?;
                bail!("BIT failed: {words}");
            }
        }
        ClientCmd::Start { format } => {
            let code = start(&mut link, format)?;
            writeln!(out, "started {} ({code:#04x})", decode::format_name(code))?;
        }
        ClientCmd::Stop => {
            link.send(Command::Stop)?;
            writeln!(out, "stopped")?;
        }
        ClientCmd::Get { param } => {
            let p = find_param(param)?;
            let v = get(&mut link, p)?;
            writeln!(out, "{} = {}", p.name, show_value(p, &v))?;
        }
        ClientCmd::Set { param, value } => {
            let p = find_param(param)?;
            let v = parse_value(p, value)?;
            let c = Command::SaveFlash {
                id: p.id,
                len: p.kind.byte_len(),
                value: &v,
            };
            match link.request(c, 0xB2, "SaveFlash") {
                Ok(_) if p.id == params::BAUD_RATE.id => writeln!(
                    out,
                    "{} saved = {} (the line changes after `imu-emu client commit-baud`, \
                     CommitBaudRate, ICD 5.3.9, or at the next power-on; `get` reads the running \
                     rate until then)",
                    p.name,
                    show_value(p, &v)
                )?,
                Ok(_) if p.id == params::DATA_RATE.id => {
                    writeln!(out, "{} saved = {value}", p.name)?;
                    let requested = u32::from(u16::from_le_bytes([v[0], v[1]]));
                    let baud = params::baud_rate(get(&mut link, &params::BAUD_RATE)?[0]);
                    if let Some(note) = lowered_rates(requested, baud, &args.model) {
                        writeln!(out, "{note}")?;
                    }
                }
                Ok(_) => writeln!(out, "{} saved = {value}", p.name)?,
                Err(_) => bail!(
                    "{}: SaveFlash {} {value}: no acknowledgement within {:?}: the unit refused \
                     the value (ICD 5.3.7) or did not hear it",
                    link.line.what,
                    p.name,
                    link.line.timeout
                ),
            }
        }
        ClientCmd::CommitBaud => {
            link.send(Command::CommitBaudRate)?;
            writeln!(out, "baud rate committed")?;
        }
        ClientCmd::Reset | ClientCmd::FactoryReset => unreachable!("refused before"),
        ClientCmd::Udd { types } => {
            let list = parse_types(types)?;
            link.send(Command::UddConfig)?;
            let mut msg = vec![u8::try_from(list.len()).unwrap_or(u8::MAX)];
            msg.extend_from_slice(&list);
            let f = link.request(
                Command::UddConfigMessage(&msg),
                command::UDD_CONFIG,
                "User_Def_Data_config",
            )?;
            let p = &f.payload;
            if p.len() < 8 {
                bail!("UDD configuration answer of {} bytes, expected 8", p.len());
            }
            let errors = p[2];
            if errors == 0 {
                writeln!(
                    out,
                    "udd configured: {} types, max rate {} Hz",
                    list.len(),
                    u16::from_le_bytes([p[5], p[6]])
                )?;
            } else {
                bail!(
                    "udd refused: error bits {errors:#04x}, wrong types mask {:#06x}, max rate {} Hz \
                     (ICD Table 5.21)",
                    u16::from_le_bytes([p[3], p[4]]),
                    u16::from_le_bytes([p[5], p[6]])
                );
            }
        }
        ClientCmd::Record {
            format,
            duration,
            frames,
            out: o,
            to,
            raw,
            did,
            period: _,
            nmea,
        } => {
            if did.is_some() || nmea.is_some() {
                return Err(
                    UsageError("record --did and --nmea go with --protocol isb".into()).into(),
                );
            }
            let rate = stream_rate(&mut link, &args.model);
            if let Some(r) = raw {
                link.line.tee = Some(
                    std::fs::File::create(r).with_context(|| format!("--raw {}", r.display()))?,
                );
            }
            let started = match format {
                Some(f) => Some(start(&mut link, f)?),
                None => None,
            };
            let mut w = writer(o.as_ref())?;
            let mut rec = Recorder::new(*to, args.model);
            if let Some(r) = rate {
                rec = rec.with_rate(r);
            }
            rec.end_s = *duration;
            let r = record(&mut link, &mut w, &mut rec, *frames, stop);
            // The stream is stopped even when recording failed; that
            // failure (a closed line) is the one reported.
            let stopped = match started {
                Some(_) => link.send(Command::Stop),
                None => Ok(()),
            };
            let flushed = w.flush();
            let closed_output = r.as_ref().err().is_some_and(is_broken_pipe)
                || flushed
                    .as_ref()
                    .err()
                    .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe);
            if !closed_output {
                r?;
                stopped?;
                flushed?;
            }
            let span = match (rec.first_time, rec.last_time) {
                (Some(a), Some(b)) => format!(", {:.3} s of device time", b - a),
                _ => String::new(),
            };
            eprintln!(
                "imu-emu: {} frames recorded{span}, {} failed their checksum, {} counter gaps{}",
                rec.rows,
                link.checksum_errors(),
                rec.gaps,
                if closed_output {
                    " (the output was closed)"
                } else if stop() {
                    if started.is_some() {
                        " (interrupted; stream stopped)"
                    } else {
                        " (interrupted)"
                    }
                } else {
                    ""
                }
            );
        }
        ClientCmd::Decode { .. } | ClientCmd::Plot { .. } => unreachable!(),
    }
    Ok(())
}

/// `client decode FILE`: the capture's protocol is `--protocol`, else
/// detected from its first 64 KiB ([`Protocol::detect`]); bytes in which no
/// data frame (no data-set packet) decodes are an error, not an empty
/// output with status 0.
fn decode_file(
    args: &ClientArgs,
    file: &std::path::Path,
    o: Option<&PathBuf>,
    to: OutFormat,
    did: Option<&str>,
    rate: Option<f64>,
) -> anyhow::Result<()> {
    let what = || format!("decode {}", file.display());
    let mut file_src = std::fs::File::open(file).with_context(what)?;
    // The first 64 KiB tell the protocol; they are read once and decoded
    // ahead of the rest (a pipe or a FIFO cannot be read twice).
    let mut head = Vec::new();
    (&mut file_src)
        .take(1 << 16)
        .read_to_end(&mut head)
        .with_context(what)?;
    let empty = head.is_empty();
    let (protocol, detected) = match args.protocol {
        Some(p) => (p, false),
        None => (Protocol::detect(&head).unwrap_or_default(), true),
    };
    let mut src = std::io::Cursor::new(head).chain(file_src);
    tool_protocol::of(protocol).decode(
        args,
        tool_protocol::Capture {
            file,
            src: &mut src,
            empty,
            detected,
            out: o,
            to,
            did,
            rate,
        },
    )
}

/// `client decode` of a KERNEL capture.
pub(crate) fn decode_kernel(
    args: &ClientArgs,
    c: tool_protocol::Capture<'_>,
) -> anyhow::Result<()> {
    let tool_protocol::Capture {
        file,
        src,
        out: o,
        to,
        did,
        rate,
        ..
    } = c;
    let what = || format!("decode {}", file.display());
    let mut w = writer(o)?;
    if did.is_some() {
        return Err(UsageError("decode --did goes with --protocol isb".into()).into());
    }
    let mut rec =
        Recorder::new(to, args.model).with_rate(RateOf::Hz(rate.unwrap_or(DEFAULT_DECODE_RATE_HZ)));
    let mut d = Box::new(Decoder::<CAP>::new());
    let mut bytes = 0u64;
    read_chunks(src, &what, &mut |chunk| {
        bytes += chunk.len() as u64;
        let mut input: &[u8] = chunk;
        while let Some(f) = d.next_frame(&mut input) {
            if f.msg_type == TYPE_DATA {
                rec.row(&mut w, f.id, f.payload, None)?;
            }
        }
        Ok(())
    })?;
    w.flush()?;
    if rec.rows == 0 && bytes > 0 {
        bail!(
            "{}: no KERNEL data frame in {bytes} bytes ({} frames failed their checksum): not a \
             KERNEL capture? (--protocol isb for an IMX-5's)",
            what(),
            d.errors()
        );
    }
    if rec.timed_by_rate && rate.is_none() {
        eprintln!(
            "imu-emu: {}: {} frames carry no clock: device_time_s counts them at \
             {DEFAULT_DECODE_RATE_HZ} Hz, the factory Data_Rate (--rate HZ for another)",
            file.display(),
            rec.format_name()
        );
    }
    eprintln!(
        "imu-emu: {} frames decoded, {} failed their checksum, {} counter gaps, {} skipped",
        rec.rows,
        d.errors(),
        rec.gaps,
        rec.skipped
    );
    Ok(())
}

/// Whether `e` is a write to a reader that went away (`… | head`).
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// `r`, but a reader of the output that went away (`decode … | head`) is
/// the end of the output, as for any filter, not an error.
fn quiet_on_closed_output(r: anyhow::Result<()>) -> anyhow::Result<()> {
    match r {
        Err(e) if is_broken_pipe(&e) => Ok(()),
        r => r,
    }
}

/// What `set Data_Rate` adds when the device will send slower than
/// `requested` Hz at `baud` bit/s (Formula 5.1, ICD 5.5): the formats it
/// lowers and their rates, or `None` when every format runs at it.
pub fn lowered_rates(requested: u32, baud: u32, product: &Product) -> Option<String> {
    use imu_emu::kernel::{formats, rate};
    let internal = product.model.internal_rate_hz;
    let mut groups: Vec<(u32, Vec<&str>)> = Vec::new();
    for f in formats::FORMATS {
        let eff = rate::effective_rate(requested, baud, f.payload_len(), internal);
        if eff == requested {
            continue;
        }
        match groups.iter_mut().find(|g| g.0 == eff) {
            Some(g) => g.1.push(f.name),
            None => groups.push((eff, vec![f.name])),
        }
    }
    if groups.is_empty() {
        return None;
    }
    groups.sort_by_key(|g| std::cmp::Reverse(g.0));
    let list: Vec<String> = groups
        .iter()
        .map(|(r, names)| format!("{} at {r} Hz", names.join(", ")))
        .collect();
    Some(format!(
        "at {baud} bit/s the device lowers it (ICD 5.5, Formula 5.1): it sends {} \
         (a UDD by its length; a faster line rate keeps {requested} Hz)",
        list.join("; ")
    ))
}

/// The rate the device sends at, read from the unit (Data_Rate lowered by
/// Formula 5.1 for a frame's length at the running line rate): it times
/// the frames of a format without a clock. `None` when the unit does not
/// answer ReadRAM (such frames then get no `device_time_s`).
fn stream_rate(link: &mut Link, product: &Product) -> Option<RateOf> {
    let data_rate = get(link, &params::DATA_RATE).ok()?;
    let baud = get(link, &params::BAUD_RATE).ok()?;
    Some(RateOf::Line {
        data_rate: u32::from(u16::from_le_bytes([data_rate[0], data_rate[1]])),
        baud: params::baud_rate(baud[0]),
        internal_hz: product.model.internal_rate_hz,
    })
}

fn parse_types(s: &str) -> anyhow::Result<Vec<u8>> {
    s.split(',')
        .map(|t| {
            let t = t.trim();
            let h = t.strip_prefix("0x").unwrap_or(t);
            u8::from_str_radix(h, 16).map_err(|_| {
                UsageError(format!("udd: {t} is not a type code (hex, e.g. 0x21)")).into()
            })
        })
        .collect()
}

fn start(link: &mut Link, format: &str) -> anyhow::Result<u8> {
    let code = decode::format_code(format).ok_or_else(|| {
        UsageError(format!(
            "start: unknown format {format}; expected GA, GAm, GAA, GAAm, Orientation, \
             Quaternion, Calibrated-HR, UDD or a code (0x8F)"
        ))
    })?;
    link.request(Command::Data(code), code, &format!("start {format}"))?;
    Ok(code)
}

fn get(link: &mut Link, p: &ParamSpec) -> anyhow::Result<Vec<u8>> {
    let f = link.request(
        Command::ReadRam {
            id: p.id,
            len: p.kind.byte_len(),
        },
        0xB1,
        &format!("ReadRAM {}", p.name),
    )?;
    if f.payload.len() != usize::from(p.kind.byte_len()) {
        bail!(
            "ReadRAM {}: answer of {} bytes, expected {}",
            p.name,
            f.payload.len(),
            p.kind.byte_len()
        );
    }
    Ok(f.payload)
}

/// Feeds `src` to `f` in 64 KiB chunks (a frame cut between two is
/// completed by the decoder): any size of capture in bounded memory.
fn read_chunks(
    src: &mut dyn Read,
    what: &dyn Fn() -> String,
    f: &mut dyn FnMut(&[u8]) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut chunk = vec![0u8; 64 * 1024];
    loop {
        let n = match src.read(&mut chunk) {
            Ok(0) => return Ok(()),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(anyhow::Error::new(e).context(what())),
        };
        f(&chunk[..n])?;
    }
}

/// A flag raised by Ctrl-C (SIGINT) or SIGTERM, so that `record` stops the
/// stream it started and prints its summary instead of dying mid-stream.
fn interrupt_flag() -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Without the handler the signal keeps its default action.
        let _ = signal_hook::flag::register(sig, flag.clone());
    }
    flag
}

/// The output of `record` and `decode`: the file named, or stdout when none
/// is named or the name is `-` (the usual convention; it had written a file
/// called `-`).
fn writer(path: Option<&PathBuf>) -> anyhow::Result<Box<dyn Write>> {
    Ok(match path.filter(|p| p.as_os_str() != "-") {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("{}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout())),
    })
}

/// Writes decoded frames as rows and counts them.
pub struct Recorder {
    to: OutFormat,
    product: Product,
    /// The columns of the first data frame (CSV header).
    columns: Option<(u8, Vec<&'static str>)>,
    /// Rows written.
    pub rows: u64,
    /// Frames of another format, or that did not decode, skipped.
    pub skipped: u64,
    /// Counter steps that differ from the first one.
    pub gaps: u64,
    last_counter: Option<u16>,
    step: Option<u16>,
    /// Whether rows carry `device_time_s` (the first frame had a clock,
    /// or the rate is known).
    timed: bool,
    clock: DeviceClock,
    /// The output rate that times frames without a clock.
    rate: Option<RateOf>,
    /// Whether the rows are timed by that rate (the format has no clock).
    pub timed_by_rate: bool,
    /// Stop before a row this much device time after the first, s.
    pub end_s: Option<f64>,
    /// A row reached `end_s`.
    pub done: bool,
    /// Device time of the first and the last row written, s.
    pub first_time: Option<f64>,
    /// Device time of the last row written, s.
    pub last_time: Option<f64>,
}

/// The output rate of a stream, for frames without a clock.
#[derive(Debug, Clone, Copy)]
pub enum RateOf {
    /// This rate, Hz (`decode --rate`).
    Hz(f64),
    /// The device's: Data_Rate lowered by Formula 5.1 for the frame's
    /// length at the line rate (what `record` reads from the unit).
    Line {
        /// Data_Rate, Hz.
        data_rate: u32,
        /// Running line rate, bit/s.
        baud: u32,
        /// The model's internal rate, Hz.
        internal_hz: u32,
    },
}

impl RateOf {
    /// The rate of frames with `payload_len` bytes, Hz.
    pub fn hz(self, payload_len: usize) -> f64 {
        match self {
            RateOf::Hz(h) => h,
            RateOf::Line {
                data_rate,
                baud,
                internal_hz,
            } => f64::from(imu_emu::kernel::rate::effective_rate(
                data_rate,
                baud,
                payload_len,
                internal_hz,
            )),
        }
    }
}

/// Device time from the frames themselves: seconds since the first frame,
/// from `imu_time_ns` (ns since power-on) when a frame has it, else from
/// the counter (2 kHz ticks, ICD Tables 5.7, 5.10 note 3) unwrapped, which
/// holds while frames are less than 32.768 s apart; a frame with neither
/// (Orientation, Quaternion, GAA, GAm, GAAm, a UDD without IMU time) is
/// timed by its place in the stream at the known output rate
/// ([`DeviceClock::with_rate`]), which cannot see frames lost on the line.
#[derive(Debug, Clone, Default)]
pub struct DeviceClock {
    t0_ns: Option<f64>,
    last_counter: Option<u16>,
    ticks: u64,
    rate_hz: Option<f64>,
    untimed: u64,
}

impl DeviceClock {
    /// A clock that times frames without a clock field at `hz`.
    pub fn with_rate(hz: f64) -> Self {
        DeviceClock {
            rate_hz: Some(hz),
            ..Self::default()
        }
    }

    /// The device time of frame `d`, s, or `None` if it carries no clock
    /// and no rate was given.
    pub fn time(&mut self, d: &decode::Decoded) -> Option<f64> {
        if let Some(ns) = d.get("imu_time_ns") {
            let t0 = *self.t0_ns.get_or_insert(ns);
            return Some((ns - t0) / 1e9);
        }
        let Some(c) = d.get("counter") else {
            let t = self.untimed as f64 / self.rate_hz?;
            self.untimed += 1;
            return Some(t);
        };
        let c = c as u16;
        if let Some(last) = self.last_counter {
            self.ticks += u64::from(c.wrapping_sub(last));
        }
        self.last_counter = Some(c);
        Some(self.ticks as f64 / f64::from(COUNTER_HZ))
    }
}

impl Recorder {
    /// No row yet.
    pub fn new(to: OutFormat, product: Product) -> Self {
        Recorder {
            to,
            product,
            columns: None,
            rows: 0,
            skipped: 0,
            gaps: 0,
            last_counter: None,
            step: None,
            timed: false,
            clock: DeviceClock::default(),
            rate: None,
            timed_by_rate: false,
            end_s: None,
            done: false,
            first_time: None,
            last_time: None,
        }
    }

    /// Frames without a clock are timed at `rate`.
    pub fn with_rate(mut self, rate: RateOf) -> Self {
        self.rate = Some(rate);
        self
    }

    /// The name of the format recorded (`GA`), or `none`.
    pub fn format_name(&self) -> String {
        self.columns
            .as_ref()
            .map_or_else(|| "none".to_owned(), |c| decode::format_name(c.0))
    }

    /// Writes the frame as a row (with the host time `t`, seconds since
    /// the start, if given); whether it was written.
    pub fn row(
        &mut self,
        w: &mut dyn Write,
        id: u8,
        payload: &[u8],
        t: Option<f64>,
    ) -> anyhow::Result<bool> {
        let Some(d) = decode::decode(id, payload, &self.product) else {
            self.skipped += 1;
            return Ok(false);
        };
        let cols: Vec<&'static str> = d.values.iter().map(|v| v.0).collect();
        match &self.columns {
            None => {
                let clocked = d.get("imu_time_ns").is_some() || d.get("counter").is_some();
                if let (false, Some(r)) = (clocked, self.rate) {
                    self.clock = DeviceClock::with_rate(r.hz(payload.len()));
                    self.timed_by_rate = true;
                }
                self.timed = clocked || self.timed_by_rate;
                if !self.timed && self.end_s.is_some() {
                    bail!(
                        "record --duration: {} frames carry no clock and the unit did not say its \
                         rate (ReadRAM Data_Rate): record --frames N instead",
                        decode::format_name(id)
                    );
                }
                if self.to == OutFormat::Csv {
                    let mut h = vec!["frame", "format"];
                    if self.timed {
                        h.push("device_time_s");
                    }
                    if t.is_some() {
                        h.push("host_time_s");
                    }
                    h.extend(&cols);
                    writeln!(w, "{}", h.join(","))?;
                }
                self.columns = Some((id, cols));
            }
            Some((cid, c)) if *cid != id || *c != cols => {
                self.skipped += 1;
                return Ok(false);
            }
            Some(_) => {}
        }
        let device_t = if self.timed {
            self.clock.time(&d)
        } else {
            None
        };
        if let (Some(t), Some(end)) = (device_t, self.end_s) {
            if t >= end - 1e-9 {
                self.done = true;
                return Ok(false);
            }
        }
        if let Some(t) = device_t {
            self.first_time.get_or_insert(t);
            self.last_time = Some(t);
        }
        if let Some(c) = d.get("counter") {
            let c = c as u16;
            if let Some(last) = self.last_counter {
                let step = c.wrapping_sub(last);
                match self.step {
                    None => self.step = Some(step),
                    Some(s) if s != step => self.gaps += 1,
                    Some(_) => {}
                }
            }
            self.last_counter = Some(c);
        }
        let fmt = decode::format_name(id);
        match self.to {
            OutFormat::Csv => {
                let mut line = format!("{},{fmt}", self.rows);
                if let Some(t) = device_t {
                    line.push_str(&format!(",{t:.6}"));
                }
                if let Some(t) = t {
                    line.push_str(&format!(",{t:.6}"));
                }
                for (_, v) in &d.values {
                    line.push_str(&format!(",{v}"));
                }
                writeln!(w, "{line}")?;
            }
            OutFormat::Json => {
                let mut line = format!("{{\"frame\":{},\"format\":\"{fmt}\"", self.rows);
                if let Some(t) = device_t {
                    line.push_str(&format!(",\"device_time_s\":{t:.6}"));
                }
                if let Some(t) = t {
                    line.push_str(&format!(",\"host_time_s\":{t:.6}"));
                }
                for (k, v) in &d.values {
                    line.push_str(&format!(",\"{k}\":{v}"));
                }
                line.push('}');
                writeln!(w, "{line}")?;
            }
        }
        self.rows += 1;
        Ok(true)
    }
}

/// Records data frames with `rec` until `want` rows were written or a
/// frame reaches its `end_s` of device time (or forever); a progress line
/// on stderr when it is a terminal.
fn record(
    link: &mut Link,
    w: &mut dyn Write,
    rec: &mut Recorder,
    want: Option<u64>,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let tty = std::io::stderr().is_terminal();
    let mut shown = t0;
    let mut quiet_since = Instant::now();
    while want.is_none_or(|n| rec.rows < n) && !rec.done && !stop() {
        let row = match link.frame_before(Instant::now() + Duration::from_millis(100))? {
            Some(f) if f.msg_type == TYPE_DATA => {
                rec.row(w, f.id, &f.payload, Some(t0.elapsed().as_secs_f64()))?
            }
            _ => false,
        };
        // Only a row is data: a peer sending only other frames
        // (acknowledgements, answers) times out too.
        if row {
            quiet_since = Instant::now();
        } else if quiet_since.elapsed() > link.line.timeout {
            bail!(
                "{}: no data frame within {:?} after {} rows (is a stream running? --format GA \
                 starts one)",
                link.line.what,
                link.line.timeout,
                rec.rows
            )
        }
        if tty && shown.elapsed() > Duration::from_millis(250) {
            shown = Instant::now();
            let secs = t0.elapsed().as_secs_f64();
            eprint!(
                "\r{} frames  {:.1} Hz  {} checksum errors  {} counter gaps ",
                rec.rows,
                rec.rows as f64 / secs.max(1e-9),
                link.checksum_errors(),
                rec.gaps
            );
        }
    }
    if tty {
        eprintln!();
    }
    Ok(())
}
