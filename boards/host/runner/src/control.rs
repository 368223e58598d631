//! The control socket: what a test rig does to the device's other pins
//! and to its line.
//!
//! `--control ADDR` listens on TCP (one client at a time, a new one replaces
//! the old). The protocol is text, one command per line, each answered by
//! exactly one line: `ok`, `ok <text>` (`help`, `status`) or
//! `error <why>` (a syntax error names the expected syntax). Lines the
//! device raises by itself start with `event ` and never answer a command.
//!
//! The grammar is one table, [`COMMANDS`]: a row per form of a command
//! (its syntax, whether `dev K` may address it, its parser). The parser,
//! the `help` answer and the syntax an error names all read it, so a new
//! command is a new row (what each command does: `docs/host-runner.md`,
//! "The control protocol"; `HostPort::apply`, `runner/exec.rs`, carries it out).
//!
//! Link faults ([`crate::link`]) draw from a generator seeded by `--seed`.
//!
//! The device's TOV output (4.1.4) is reported to the client as lines
//! `event tov high <ns>` / `event tov low <ns>` (device time, ns since
//! power-on), in the order the device produces them; in a many-device run
//! as `event dev K tov high <ns>`.
//!
//! Limits (a hostile or broken client cannot stall the device or grow its
//! memory): a line is at most [`MAX_LINE`] bytes — a longer one is answered
//! `error line longer than 256 bytes` and skipped up to its newline; each
//! runner pass executes at most [`MAX_COMMANDS_PER_POLL`] commands and reads
//! at most [`MAX_READ_PER_POLL`] bytes, the rest waiting for the next pass;
//! a client that does not read its replies gets no more commands executed
//! once [`MAX_PENDING_OUTPUT`] bytes wait for it (events that do not
//! fit are dropped; an answer never is: every line gets its whole answer,
//! however long, in order). A blank line is answered `error empty line`.
//! A device number is canonical decimal (`dev 01`, `dev +1` are refused). A client that closes its sending side still gets its
//! replies and the events.

use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};

use imu_emu::device::{Level, Pin};
use imu_emu::sensor::Motion;
use imu_emu::Faults;

use crate::link::{Dir, LinkChange, MAX_NOISE};
use crate::transport::AcceptGuard;

/// A parsed control command.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// A pin edge now.
    Edge(Pin, Level),
    /// Power cycle with BOOT at a level (`None` = floating).
    PowerCycle(Option<Level>),
    /// Change the injected faults.
    Fault(FaultChange),
    /// A navigation fault (ISB): `fault gps off|on`, `fault mag|baro on|off`.
    NavFault(NavFault),
    /// Change the motion the unit undergoes.
    Motion(Motion),
    /// Fly a manoeuvre script from now (`motion script …`).
    Script(Box<imu_emu::vehicle::Script>),
    /// A manoeuvre script or full-state CSV file from now (`motion file …`).
    MotionFile(std::path::PathBuf),
    /// Report the vehicle truth (`ok key=value …`).
    Truth,
    /// Change the link faults.
    Link(LinkChange),
    /// Report the device's and the line's state (`ok key=value …`).
    Status,
    /// List the commands (answered by the socket itself).
    Help,
    /// List the devices and where each listens (`ok count=N dev0=…`).
    Devices,
}

/// A navigation fault of the ISB personality (`docs/isb.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NavFault {
    /// GPS fix available (`fault gps on`) or lost (`fault gps off`).
    Gps(bool),
    /// Magnetic disturbance on/off.
    Mag(bool),
    /// Barometer failure on/off.
    Baro(bool),
}

/// One change to [`Faults`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultChange {
    /// Sensor communication failure on/off.
    Comm(bool),
    /// Sensor configuration failure on/off.
    Config(bool),
    /// Gyro BIT failure on/off.
    GyroBit(bool),
    /// Accelerometer BIT failure on/off.
    AccelBit(bool),
    /// Flash check failure on/off.
    Flash(bool),
    /// Forced temperature, °C, or `None` for the model's own.
    Temperature(Option<f32>),
}

impl FaultChange {
    /// Applies the change.
    pub fn apply(self, f: &mut Faults) {
        match self {
            FaultChange::Comm(on) => f.sensor_comm = on,
            FaultChange::Config(on) => f.sensor_config = on,
            FaultChange::GyroBit(on) => f.gyro_bit = on,
            FaultChange::AccelBit(on) => f.accel_bit = on,
            FaultChange::Flash(on) => f.flash_check = on,
            FaultChange::Temperature(t) => f.temperature_c = t,
        }
    }
}

fn on_off(w: &str) -> Result<bool, String> {
    match w {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected on or off, got {w}")),
    }
}

fn number(w: &str) -> Result<f32, String> {
    w.parse::<f32>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("not a number: {w}"))
}

/// A probability for `link drop|corrupt|duplicate`.
fn rate(w: &str) -> Result<f64, String> {
    w.parse::<f64>()
        .ok()
        .filter(|x| (0.0..=1.0).contains(x))
        .ok_or_else(|| format!("not a probability in 0..1: {w}"))
}

fn dir(w: Option<&&str>, default: Dir) -> Result<Dir, String> {
    match w.copied() {
        None => Ok(default),
        Some("tx") => Ok(Dir::Tx),
        Some("rx") => Ok(Dir::Rx),
        Some(other) => Err(format!("expected tx or rx, got {other}")),
    }
}

/// One form of a control command: a row of [`COMMANDS`], the one table
/// that drives the parser ([`parse`], [`parse_addressed`]), the `help`
/// answer ([`help`]) and the syntax an error names ([`usage`]).
///
/// Adding a command is adding a row (and, if it needs one, a [`Command`]
/// variant and what the runner does with it, `HostPort::apply` in `runner/exec.rs`).
#[derive(Debug, Clone, Copy)]
pub struct Form {
    /// Its syntax, as `help` lists it and errors name it; the first word
    /// selects the family of forms tried for a line.
    pub syntax: &'static str,
    /// Added after the syntax in `help` only (not in error hints).
    pub note: &'static str,
    /// Whether `dev K` may address it (a device's command); the others are
    /// answered by the socket itself.
    pub device: bool,
    /// Parses the line's words after the first: `None` if they do not have
    /// this form's shape (the next form of the family is tried, and when
    /// none takes them the error names the family's syntax), `Some(Err)`
    /// for a right shape with a wrong value (that error is the answer).
    pub parse: fn(&[&str]) -> Option<Result<Command, String>>,
}

impl Form {
    /// The word that starts the command.
    pub fn word(&self) -> &'static str {
        self.syntax.split(' ').next().unwrap_or("")
    }
}

/// Shorthand for the rows of [`COMMANDS`].
const fn form(
    syntax: &'static str,
    device: bool,
    parse: fn(&[&str]) -> Option<Result<Command, String>>,
) -> Form {
    Form {
        syntax,
        note: "",
        device,
        parse,
    }
}

/// The control grammar, in the order `help` lists it.
pub const COMMANDS: &[Form] = &[
    form("help", false, |w| w.is_empty().then_some(Ok(Command::Help))),
    form("status", true, |w| {
        w.is_empty().then_some(Ok(Command::Status))
    }),
    form("pps", true, |w| {
        w.is_empty()
            .then_some(Ok(Command::Edge(Pin::Pps, Level::High)))
    }),
    form("extrig high|low", true, |w| match w {
        ["high"] => Some(Ok(Command::Edge(Pin::Extrig, Level::High))),
        ["low"] => Some(Ok(Command::Edge(Pin::Extrig, Level::Low))),
        _ => None,
    }),
    // A strobe: a rising EXTRIG edge (the IMX-5 answers with
    // STROBE_IN_TIME and `$PSTRB` when they are on).
    form("strobe", true, |w| {
        w.is_empty()
            .then_some(Ok(Command::Edge(Pin::Extrig, Level::High)))
    }),
    form("power-cycle [boot=high|boot=low]", true, |w| match w {
        [] => Some(Ok(Command::PowerCycle(None))),
        ["boot=high"] => Some(Ok(Command::PowerCycle(Some(Level::High)))),
        ["boot=low"] => Some(Ok(Command::PowerCycle(Some(Level::Low)))),
        _ => None,
    }),
    // Before the sensor faults' row, whose parser takes any `fault <word>
    // <state>`.
    form("fault gps off|on", true, |w| match w {
        ["gps", s] => Some(on_off(s).map(|on| Command::NavFault(NavFault::Gps(on)))),
        _ => None,
    }),
    form("fault mag|baro on|off", true, |w| match w {
        ["mag", s] => Some(on_off(s).map(|on| Command::NavFault(NavFault::Mag(on)))),
        ["baro", s] => Some(on_off(s).map(|on| Command::NavFault(NavFault::Baro(on)))),
        _ => None,
    }),
    form(
        "fault comm|config|gyro-bit|accel-bit|flash on|off",
        true,
        |w| match w {
            [which, state] if *which != "temperature" => Some(on_off(state).and_then(|on| {
                Ok(Command::Fault(match *which {
                    "comm" => FaultChange::Comm(on),
                    "config" => FaultChange::Config(on),
                    "gyro-bit" => FaultChange::GyroBit(on),
                    "accel-bit" => FaultChange::AccelBit(on),
                    "flash" => FaultChange::Flash(on),
                    _ => return Err(format!("unknown fault: {which}")),
                }))
            })),
            _ => None,
        },
    ),
    form("fault temperature <degC>|off", true, |w| match w {
        ["temperature", "off"] => Some(Ok(Command::Fault(FaultChange::Temperature(None)))),
        ["temperature", t] => {
            Some(number(t).map(|t| Command::Fault(FaultChange::Temperature(Some(t)))))
        }
        _ => None,
    }),
    form("motion static [<lat> <heading>]", true, |w| match w {
        ["static"] => Some(Ok(Command::Motion(Motion::Static {
            lat_deg: 45.0,
            heading_deg: 0.0,
        }))),
        ["static", lat, heading] => Some((|| {
            Ok(Command::Motion(Motion::Static {
                lat_deg: number(lat)?,
                heading_deg: number(heading)?,
            }))
        })()),
        _ => None,
    }),
    form("motion rotate <x> <y> <z>", true, |w| match w {
        ["rotate", x, y, z] => Some((|| {
            Ok(Command::Motion(Motion::ConstantRotation {
                lat_deg: 45.0,
                heading_deg: 0.0,
                rate_dps: [number(x)?, number(y)?, number(z)?],
            }))
        })()),
        _ => None,
    }),
    form("motion script <statement>; …", true, |w| match w {
        ["script", rest @ ..] if !rest.is_empty() => Some(
            imu_emu::vehicle::Script::parse(&rest.join(" "))
                .map(|s| Command::Script(Box::new(s)))
                .map_err(|e| format!("manoeuvre script: {e}")),
        ),
        _ => None,
    }),
    form("motion file <path>", true, |w| match w {
        ["file", path] => Some(Ok(Command::MotionFile((*path).into()))),
        _ => None,
    }),
    form("truth", true, |w| {
        w.is_empty().then_some(Ok(Command::Truth))
    }),
    form(
        "link drop|corrupt|duplicate <rate 0..1> [tx|rx]",
        true,
        |w| match w {
            [what @ ("drop" | "corrupt" | "duplicate"), p, rest @ ..] if rest.len() <= 1 => {
                Some((|| {
                    let (p, d) = (rate(p)?, dir(rest.first(), Dir::Both)?);
                    Ok(Command::Link(match *what {
                        "drop" => LinkChange::Drop(p, d),
                        "corrupt" => LinkChange::Corrupt(p, d),
                        _ => LinkChange::Duplicate(p, d),
                    }))
                })())
            }
            _ => None,
        },
    ),
    form("link noise <bytes> [tx|rx]", true, |w| match w {
        ["noise", n, rest @ ..] if rest.len() <= 1 => Some((|| {
            let n = n
                .parse::<usize>()
                .ok()
                .filter(|&n| (1..=MAX_NOISE).contains(&n))
                .ok_or_else(|| format!("not a byte count in 1..={MAX_NOISE}: {n}"))?;
            Ok(Command::Link(LinkChange::Noise(
                n,
                dir(rest.first(), Dir::Tx)?,
            )))
        })()),
        _ => None,
    }),
    form("link stall <ms>", true, |w| match w {
        ["stall", ms] => Some(
            ms.parse::<u64>()
                .ok()
                .filter(|&ms| ms <= 3_600_000)
                .map(|ms| Command::Link(LinkChange::Stall(ms)))
                .ok_or_else(|| format!("not a time in ms (0..=3600000): {ms}")),
        ),
        _ => None,
    }),
    form("link cut", true, |w| {
        (w == ["cut"]).then_some(Ok(Command::Link(LinkChange::Cut)))
    }),
    form("link clear", true, |w| {
        (w == ["clear"]).then_some(Ok(Command::Link(LinkChange::Clear)))
    }),
    form("devices", false, |w| {
        w.is_empty().then_some(Ok(Command::Devices))
    }),
    // `dev K …` is taken apart by `parse_addressed` before the table is
    // consulted; its row gives its syntax to `help` and the errors.
    Form {
        note: " (device K of a --count run)",
        ..form("dev <K> <command>", false, |_| None)
    },
];

/// The answer to `help` (after `ok `): every form of [`COMMANDS`].
pub fn help() -> String {
    let forms: Vec<String> = COMMANDS
        .iter()
        .map(|f| format!("{}{}", f.syntax, f.note))
        .collect();
    format!("commands: {}", forms.join(" | "))
}

/// The syntax of the command family starting with `word`, for errors
/// (`a, b, or c`), from [`COMMANDS`]; `None` for a word that starts no
/// command.
pub fn usage(word: &str) -> Option<String> {
    let forms: Vec<&str> = COMMANDS
        .iter()
        .filter(|f| f.word() == word)
        .map(|f| f.syntax)
        .collect();
    match forms.as_slice() {
        [] => None,
        [one] => Some((*one).to_owned()),
        [init @ .., last] => Some(format!("{}, or {last}", init.join(", "))),
    }
}

/// Parses one line of the control protocol. An error names the expected
/// syntax (`bad syntax: …; expected extrig high|low`), says what a value
/// should be (`not a probability in 0..1: 2`), or says `try help` for a
/// word that starts no command.
pub fn parse(line: &str) -> Result<Command, String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    parse_one(line, &words).map(|(_, c)| c)
}

/// Parses one line that may address a device: `dev K <command>` gives
/// `(Some(K), command)`, any other line `(None, command)`.
pub fn parse_addressed(line: &str) -> Result<(Option<usize>, Command), String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["dev", k, rest @ ..] if !rest.is_empty() => {
            let k = device_number(k).ok_or_else(|| format!("not a device number: {k}"))?;
            let start = line.find(rest[0]).unwrap_or(0);
            match parse_one(&line[start..], rest)? {
                (form, _) if !form.device => Err(format!("not a device command: {}", rest[0])),
                (_, c) => Ok((Some(k), c)),
            }
        }
        ["dev", ..] => Err(format!("bad syntax: {line}; expected dev <K> <command>")),
        _ => Ok((None, parse_one(line, &words)?.1)),
    }
}

/// A device number in canonical decimal (`0`, `17`; not `+1`, `01`).
fn device_number(w: &str) -> Option<usize> {
    let canonical = w.bytes().all(|b| b.is_ascii_digit()) && (w == "0" || !w.starts_with('0'));
    canonical.then(|| w.parse().ok()).flatten()
}

/// [`parse_addressed`] for a line as received (trimmed): a blank line is
/// answered `error empty line` (every line gets exactly one answer).
fn parse_line(text: &str) -> Result<(Option<usize>, Command), String> {
    if text.is_empty() {
        return Err("empty line".to_owned());
    }
    parse_addressed(text)
}

/// The form of [`COMMANDS`] that takes `words` and its command.
fn parse_one(line: &str, words: &[&str]) -> Result<(&'static Form, Command), String> {
    let first = words.first().copied().unwrap_or("");
    let mut family = COMMANDS.iter().filter(|f| f.word() == first).peekable();
    if family.peek().is_none() {
        return Err(format!("unknown command: {line}; try help"));
    }
    for form in family {
        if let Some(r) = (form.parse)(&words[1..]) {
            return r.map(|c| (form, c));
        }
    }
    Err(format!(
        "bad syntax: {line}; expected {}",
        usage(first).unwrap_or_default()
    ))
}

/// Longest command line accepted, bytes (the newline excluded). A longer
/// line is answered `error line longer than 256 bytes` once and skipped up
/// to its newline.
pub const MAX_LINE: usize = 256;

/// Commands executed per [`Control::poll`] (one runner pass); the rest wait
/// for the next pass, so a burst of lines never holds up the ticks.
pub const MAX_COMMANDS_PER_POLL: usize = 256;

/// Bytes read from the client per [`Control::poll`].
pub const MAX_READ_PER_POLL: usize = 256 * 1024;

/// Replies and reports queued for a client that does not read, bytes.
/// While the queue is fuller than this less a reply, no further command is
/// executed (the client's own sending is held up by TCP instead); a TOV
/// report that does not fit is dropped.
pub const MAX_PENDING_OUTPUT: usize = 64 * 1024;

/// Room a reply needs in the output queue: the longest one echoes a
/// [`MAX_LINE`] line.
const REPLY_ROOM: usize = MAX_LINE + 64;

/// The answer to `devices`: how many devices and where each listens,
/// from their transports' [`crate::transport::Transport::describe`]
/// (`count=2 dev0=tcp:127.0.0.1:7000 dev1=tcp:127.0.0.1:7001`).
pub fn devices_reply(places: &[String]) -> String {
    let mut s = format!("count={}", places.len());
    for (k, p) in places.iter().enumerate() {
        s.push_str(&format!(" dev{k}={}", p.replacen(' ', ":", 1)));
    }
    s
}

/// The control listener and its client.
///
/// Input is scanned once as it arrives (O(n) in the bytes received) from a
/// fixed 16 KiB buffer, at most [`MAX_READ_PER_POLL`] bytes and
/// [`MAX_COMMANDS_PER_POLL`] commands a pass; memory stays bounded whatever
/// the client sends (a line without a newline is cut at [`MAX_LINE`], its
/// output queue at [`MAX_PENDING_OUTPUT`]).
pub struct Control {
    listener: TcpListener,
    accept: AcceptGuard,
    client: Option<Client>,
    /// A connection may be waiting: the last shared `ppoll` saw the
    /// listener readable, or none ran since the last poll (a single
    /// device's loop does not wait on the control socket: always true
    /// there).
    listener_ready: bool,
    /// The client may have sent something: as above, for its socket.
    client_ready: bool,
}

/// The connected control client.
struct Client {
    stream: TcpStream,
    /// Received bytes not yet parsed: `inbuf[start..end]`.
    inbuf: Box<[u8; INBUF]>,
    start: usize,
    end: usize,
    /// Skipping the rest of an over-long line, up to its newline.
    discarding: bool,
    /// Output not yet taken by the socket.
    out: VecDeque<u8>,
    /// The client closed its sending side: no more commands will come.
    read_closed: bool,
}

/// Input buffer size: a whole pass of reads fits in a few refills.
const INBUF: usize = 16 * 1024;

/// What one scan of the input buffer found.
enum Line {
    /// A complete line `inbuf[from..to]` (newline excluded).
    Complete(usize, usize),
    /// A line over [`MAX_LINE`] started: reply once, then discard.
    TooLong,
    /// No complete line buffered.
    None,
}

impl Client {
    fn new(stream: TcpStream) -> Self {
        Client {
            stream,
            inbuf: Box::new([0; INBUF]),
            start: 0,
            end: 0,
            discarding: false,
            out: VecDeque::new(),
            read_closed: false,
        }
    }

    /// The next line in the buffer, if any; consumes it (or, while
    /// discarding, everything up to and including the next newline).
    fn next_line(&mut self) -> Line {
        loop {
            let pending = &self.inbuf[self.start..self.end];
            let nl = pending.iter().position(|&b| b == b'\n');
            if self.discarding {
                match nl {
                    Some(i) => {
                        self.start += i + 1;
                        self.discarding = false;
                        continue;
                    }
                    None => {
                        self.start = self.end;
                        return Line::None;
                    }
                }
            }
            return match nl {
                Some(i) if i <= MAX_LINE => {
                    let from = self.start;
                    self.start += i + 1;
                    Line::Complete(from, from + i)
                }
                Some(i) => {
                    // Over-long but complete: skip it with its newline.
                    self.start += i + 1;
                    Line::TooLong
                }
                None if pending.len() > MAX_LINE => {
                    self.start = self.end;
                    self.discarding = true;
                    Line::TooLong
                }
                None => Line::None,
            };
        }
    }

    /// Reads what the socket has, at most `budget` bytes, into the free
    /// room of the buffer (moving the unparsed rest to its front first).
    /// Returns bytes read and whether the client is gone.
    fn fill(&mut self, budget: usize) -> (usize, bool) {
        if self.read_closed {
            return (0, false);
        }
        if self.start > 0 {
            self.inbuf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        let room = (INBUF - self.end).min(budget);
        if room == 0 {
            return (0, false);
        }
        match self.stream.read(&mut self.inbuf[self.end..self.end + room]) {
            Ok(0) => {
                // Half-closed or closed: no more commands; replies and TOV
                // reports still go out until a write fails.
                self.read_closed = true;
                (0, false)
            }
            Ok(n) => {
                self.end += n;
                (n, false)
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => {
                (0, false)
            }
            Err(_) => (0, true),
        }
    }

    /// Queues an event `line` if there is room (else drops it).
    fn event(&mut self, line: &[u8]) {
        if self.out.len() + line.len() <= MAX_PENDING_OUTPUT {
            self.out.extend(line);
        }
    }

    /// Queues the answer to a line, whole, however long: a command is only
    /// executed while the queue has room ([`MAX_PENDING_OUTPUT`] less
    /// [`REPLY_ROOM`]), so the queue stays below that plus one answer.
    fn answer(&mut self, line: &[u8]) {
        self.out.extend(line);
    }

    /// Writes queued output the socket takes now; `false` if the client is
    /// gone.
    fn flush(&mut self) -> bool {
        while !self.out.is_empty() {
            let (front, _) = self.out.as_slices();
            match self.stream.write(front) {
                Ok(0) => return false,
                Ok(n) => {
                    self.out.drain(..n);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return true,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return false,
            }
        }
        true
    }
}

impl Control {
    /// Listens on `addr`.
    pub fn bind(addr: &str) -> anyhow::Result<Self> {
        let listener =
            TcpListener::bind(addr).map_err(|e| crate::error::bind_error(e, "--control", addr))?;
        listener.set_nonblocking(true)?;
        Ok(Control {
            listener,
            accept: AcceptGuard::new("control"),
            client: None,
            listener_ready: true,
            client_ready: true,
        })
    }

    /// The bound address.
    pub fn local_addr(&self) -> anyhow::Result<std::net::SocketAddr> {
        Ok(self.listener.local_addr()?)
    }

    /// Failed `accept()` calls so far (EMFILE and the like: transient).
    pub fn accept_failures(&self) -> u64 {
        self.accept.failures()
    }

    fn accept_new(&mut self) -> anyhow::Result<()> {
        if !self.accept.ready() {
            return Ok(());
        }
        match self.listener.accept() {
            Ok((s, _)) => {
                s.set_nonblocking(true)?;
                s.set_nodelay(true)?;
                self.client = Some(Client::new(s));
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            Err(e) if crate::transport::is_transient_accept_error(&e) => self.accept.failed(&e),
            Err(e) => return Err(anyhow::Error::new(e).context("control socket accept")),
        }
        Ok(())
    }

    /// Accepts a new client and executes the command lines it sent; each is
    /// handed to `apply`, whose answer goes back to the client (`ok`, `ok
    /// <text>` for a non-empty text, `error <why>`); `help` is answered
    /// here. Never
    /// blocks, and does bounded work: at most [`MAX_READ_PER_POLL`] bytes
    /// read and [`MAX_COMMANDS_PER_POLL`] commands executed; what is left
    /// waits for the next call.
    pub fn poll(
        &mut self,
        apply: &mut dyn FnMut(Command) -> Result<String, String>,
    ) -> anyhow::Result<()> {
        self.poll_addressed(&mut |k, c| match k {
            None | Some(0) => apply(c),
            Some(k) => Err(format!("no device {k}: this run has one device, dev 0")),
        })
    }

    /// [`Control::poll`] for several devices: `apply` gets the device a
    /// line addresses (`dev K …`), or `None`.
    pub fn poll_addressed(
        &mut self,
        apply: &mut dyn FnMut(Option<usize>, Command) -> Result<String, String>,
    ) -> anyhow::Result<()> {
        let mut may_read = std::mem::replace(&mut self.client_ready, true);
        if std::mem::replace(&mut self.listener_ready, true) {
            let had = self.client.is_some();
            self.accept_new()?;
            // A new client may have sent its commands already.
            may_read |= !had && self.client.is_some();
        }
        let Some(c) = self.client.as_mut() else {
            return Ok(());
        };
        let mut commands = 0;
        let mut read = 0;
        let mut gone = false;
        'pass: while commands < MAX_COMMANDS_PER_POLL {
            // Backpressure: a client that does not read its replies gets no
            // more commands executed until it does.
            if MAX_PENDING_OUTPUT - c.out.len().min(MAX_PENDING_OUTPUT) < REPLY_ROOM {
                if !c.flush() {
                    gone = true;
                }
                break;
            }
            match c.next_line() {
                Line::Complete(from, to) => {
                    let text = String::from_utf8_lossy(&c.inbuf[from..to]);
                    let text = text.trim();
                    commands += 1;
                    let answer = match parse_line(text).and_then(|(k, c)| match c {
                        Command::Help => Ok(help()),
                        c => apply(k, c),
                    }) {
                        Ok(t) if t.is_empty() => "ok\n".to_owned(),
                        Ok(t) => format!("ok {t}\n"),
                        Err(e) => format!("error {e}\n"),
                    };
                    c.answer(answer.as_bytes());
                }
                Line::TooLong => {
                    commands += 1;
                    c.answer(format!("error line longer than {MAX_LINE} bytes\n").as_bytes());
                }
                Line::None => {
                    if read >= MAX_READ_PER_POLL || !may_read {
                        break;
                    }
                    let (n, closed) = c.fill(MAX_READ_PER_POLL - read);
                    read += n;
                    if closed {
                        gone = true;
                        break 'pass;
                    }
                    if n == 0 {
                        break;
                    }
                }
            }
        }
        if gone || !c.flush() {
            self.client = None;
        }
        Ok(())
    }

    /// Appends the descriptors to wait on for the control socket to have
    /// work (a connection, a command, room for replies) to a `ppoll` shared
    /// with the devices' transports ([`crate::fleet`]).
    pub fn interest<'a>(&'a self, fds: &mut Vec<nix::poll::PollFd<'a>>) {
        use nix::poll::{PollFd, PollFlags};
        use std::os::fd::AsFd as _;
        if !self.accept.paused() {
            fds.push(PollFd::new(self.listener.as_fd(), PollFlags::POLLIN));
        }
        if let Some(c) = &self.client {
            let mut ev = if c.read_closed {
                PollFlags::empty()
            } else {
                PollFlags::POLLIN
            };
            if !c.out.is_empty() {
                ev |= PollFlags::POLLOUT;
            }
            fds.push(PollFd::new(c.stream.as_fd(), ev));
        }
    }

    /// What the shared `ppoll` saw on the descriptors [`Control::interest`]
    /// appended, in order: the next [`Control::poll_addressed`] skips its
    /// `accept` and `read` calls where nothing was seen.
    pub fn polled(&mut self, revents: &[nix::poll::PollFlags]) {
        use nix::poll::PollFlags;
        let readable = PollFlags::POLLIN | PollFlags::POLLHUP | PollFlags::POLLERR;
        // The client's descriptor is last when there is one; the
        // listener's comes first unless it was backing off.
        let (listener, client) = match (revents, self.client.is_some()) {
            ([l, c], _) => (Some(l), Some(c)),
            ([c], true) => (None, Some(c)),
            ([l], false) => (Some(l), None),
            _ => (None, None),
        };
        self.listener_ready = listener.is_some_and(|r| r.intersects(readable));
        self.client_ready = client.is_some_and(|r| r.intersects(readable));
    }

    /// Sends an event line to the client, if one is connected, as
    /// `event <what>` (best effort: a
    /// client that does not read loses reports once
    /// [`MAX_PENDING_OUTPUT`] bytes wait, rather than stalling the device).
    pub fn event(&mut self, what: &str) {
        if let Some(c) = self.client.as_mut() {
            c.event(format!("event {what}\n").as_bytes());
            if !c.flush() {
                self.client = None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_protocol() {
        assert_eq!(parse("pps"), Ok(Command::Edge(Pin::Pps, Level::High)));
        assert_eq!(
            parse(" extrig  low "),
            Ok(Command::Edge(Pin::Extrig, Level::Low))
        );
        assert_eq!(
            parse("power-cycle boot=high"),
            Ok(Command::PowerCycle(Some(Level::High)))
        );
        assert_eq!(parse("power-cycle"), Ok(Command::PowerCycle(None)));
        assert!(parse("extrig sideways").is_err());
        assert_eq!(
            parse("fault comm on"),
            Ok(Command::Fault(FaultChange::Comm(true)))
        );
        assert_eq!(
            parse("fault temperature 95.5"),
            Ok(Command::Fault(FaultChange::Temperature(Some(95.5))))
        );
        assert_eq!(
            parse("fault temperature off"),
            Ok(Command::Fault(FaultChange::Temperature(None)))
        );
        assert!(parse("fault comm maybe").is_err());
        assert_eq!(
            parse("fault gps off"),
            Ok(Command::NavFault(NavFault::Gps(false)))
        );
        assert_eq!(
            parse("fault baro on"),
            Ok(Command::NavFault(NavFault::Baro(true)))
        );
        assert!(parse("fault gps maybe").is_err());
        assert!(parse("fault temperature NaN").is_err());
        assert!(matches!(
            parse("motion rotate 0 600 0"),
            Ok(Command::Motion(Motion::ConstantRotation { .. }))
        ));
        assert!(parse("motion rotate 0 x 0").is_err());
    }

    #[test]
    fn parses_the_link_faults_help_and_status() {
        assert_eq!(parse("help"), Ok(Command::Help));
        assert_eq!(parse("status"), Ok(Command::Status));
        assert_eq!(
            parse("link drop 0.25"),
            Ok(Command::Link(LinkChange::Drop(0.25, Dir::Both)))
        );
        assert_eq!(
            parse("link corrupt 1 tx"),
            Ok(Command::Link(LinkChange::Corrupt(1.0, Dir::Tx)))
        );
        assert_eq!(
            parse("link duplicate 0 rx"),
            Ok(Command::Link(LinkChange::Duplicate(0.0, Dir::Rx)))
        );
        assert_eq!(
            parse("link noise 10"),
            Ok(Command::Link(LinkChange::Noise(10, Dir::Tx)))
        );
        assert_eq!(
            parse("link noise 10 rx"),
            Ok(Command::Link(LinkChange::Noise(10, Dir::Rx)))
        );
        assert_eq!(
            parse("link stall 200"),
            Ok(Command::Link(LinkChange::Stall(200)))
        );
        assert_eq!(parse("link cut"), Ok(Command::Link(LinkChange::Cut)));
        assert_eq!(parse("link clear"), Ok(Command::Link(LinkChange::Clear)));
        assert_eq!(
            parse("link drop -0.1"),
            Err("not a probability in 0..1: -0.1".to_owned())
        );
        assert_eq!(
            parse("link stall 1 2"),
            Err(
                "bad syntax: link stall 1 2; expected link drop|corrupt|duplicate <rate 0..1> \
                 [tx|rx], link noise <bytes> [tx|rx], link stall <ms>, link cut, or link clear"
                    .to_owned()
            )
        );
        assert_eq!(
            parse("warp 9"),
            Err("unknown command: warp 9; try help".to_owned())
        );
    }

    #[test]
    fn the_table_gives_the_help_and_the_hints() {
        assert_eq!(
            help(),
            "commands: help | status | pps | extrig high|low | strobe | power-cycle [boot=high|boot=low] \
             | fault gps off|on | fault mag|baro on|off \
             | fault comm|config|gyro-bit|accel-bit|flash on|off | fault temperature <degC>|off \
             | motion static [<lat> <heading>] | motion rotate <x> <y> <z> \
             | motion script <statement>; … | motion file <path> | truth \
             | link drop|corrupt|duplicate <rate 0..1> [tx|rx] | link noise <bytes> [tx|rx] \
             | link stall <ms> | link cut | link clear \
             | devices | dev <K> <command> (device K of a --count run)"
        );
        assert_eq!(
            usage("fault").as_deref(),
            Some(
                "fault gps off|on, fault mag|baro on|off, fault comm|config|gyro-bit|accel-bit|flash \
                 on|off, or fault temperature <degC>|off"
            )
        );
        assert_eq!(
            usage("motion").as_deref(),
            Some(
                "motion static [<lat> <heading>], motion rotate <x> <y> <z>, \
                 motion script <statement>; …, or motion file <path>"
            )
        );
        assert_eq!(usage("pps").as_deref(), Some("pps"));
        assert_eq!(usage("dev").as_deref(), Some("dev <K> <command>"));
        assert_eq!(usage("warp"), None);
        assert_eq!(
            parse("fault bogus on"),
            Err("unknown fault: bogus".to_owned())
        );
        assert_eq!(
            parse("fault comm"),
            Err(
                "bad syntax: fault comm; expected fault gps off|on, fault mag|baro on|off, \
                 fault comm|config|gyro-bit|accel-bit|flash on|off, or fault temperature <degC>|off"
                    .to_owned()
            )
        );
        assert_eq!(
            parse("motion static 1"),
            Err("bad syntax: motion static 1; expected \
            motion static [<lat> <heading>], motion rotate <x> <y> <z>, \
            motion script <statement>; …, or motion file <path>"
                .to_owned())
        );
        assert_eq!(
            parse_addressed("dev 2 pps"),
            Ok((Some(2), Command::Edge(Pin::Pps, Level::High)))
        );
        assert_eq!(
            parse_addressed("dev 2 devices"),
            Err("not a device command: devices".to_owned())
        );
        assert_eq!(
            parse("dev 2 pps"),
            Err("bad syntax: dev 2 pps; expected dev <K> <command>".to_owned())
        );
    }

    /// A control socket and a connected client whose first poll accepted it.
    fn pair() -> (Control, TcpStream) {
        let mut ctl = Control::bind("127.0.0.1:0").unwrap();
        let client = TcpStream::connect(ctl.local_addr().unwrap()).unwrap();
        client
            .set_read_timeout(Some(std::time::Duration::from_secs(5)))
            .unwrap();
        for _ in 0..500 {
            ctl.poll(&mut |_| Ok(String::new())).unwrap();
            if ctl.client.is_some() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        assert!(ctl.client.is_some());
        (ctl, client)
    }

    /// Polls until `n` commands were applied (each poll applying at most
    /// the per-pass budget); returns the count applied by each poll.
    fn polls_until(ctl: &mut Control, n: usize) -> Vec<usize> {
        let mut per_poll = Vec::new();
        let mut total = 0;
        for _ in 0..10_000 {
            let mut k = 0;
            ctl.poll(&mut |_| {
                k += 1;
                Ok(String::new())
            })
            .unwrap();
            if k > 0 {
                per_poll.push(k);
            }
            total += k;
            if total >= n {
                return per_poll;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        panic!("{total} of {n} commands applied: {per_poll:?}");
    }

    #[test]
    fn work_per_poll_is_bounded_and_every_line_is_answered() {
        let (mut ctl, mut client) = pair();
        client.write_all(&b"pps\n".repeat(1000)).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(50));
        let per_poll = polls_until(&mut ctl, 1000);
        assert_eq!(per_poll.iter().sum::<usize>(), 1000);
        assert!(
            per_poll.iter().all(|&k| k <= MAX_COMMANDS_PER_POLL),
            "{per_poll:?}"
        );
        assert_eq!(per_poll[0], MAX_COMMANDS_PER_POLL);
        let mut r = std::io::BufReader::new(client);
        let mut line = String::new();
        for _ in 0..1000 {
            line.clear();
            std::io::BufRead::read_line(&mut r, &mut line).unwrap();
            assert_eq!(line, "ok\n");
        }
    }

    #[test]
    fn an_over_long_line_is_refused_once_and_the_next_line_parses() {
        let (mut ctl, mut client) = pair();
        // Split across writes and polls, the newline far beyond the limit.
        client.write_all(&[b'x'; 1000]).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        ctl.poll(&mut |_| Ok(String::new())).unwrap();
        client.write_all(&[b'y'; 70_000]).unwrap();
        client.write_all(b"\nextrig sideways\npps\n").unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        let mut applied = Vec::new();
        for _ in 0..100 {
            ctl.poll(&mut |c| {
                applied.push(c);
                Ok(String::new())
            })
            .unwrap();
        }
        assert_eq!(applied, [Command::Edge(Pin::Pps, Level::High)]);
        let mut r = std::io::BufReader::new(client);
        let mut lines = Vec::new();
        for _ in 0..3 {
            let mut l = String::new();
            std::io::BufRead::read_line(&mut r, &mut l).unwrap();
            lines.push(l);
        }
        assert_eq!(
            lines,
            [
                "error line longer than 256 bytes\n",
                "error bad syntax: extrig sideways; expected extrig high|low\n",
                "ok\n"
            ]
        );
        assert!(ctl.client.as_ref().is_some_and(|c| !c.discarding));
    }
}
