//! `--web ADDR`: a live web view of the emulated unit(s). The HTTP side
//! is [`server`] (bounded connections, sizes and times, whatever a client
//! does; synchronous, no async runtime: the page polls a JSON endpoint,
//! so no WebSocket or Server-Sent-Events stack is needed); this module is
//! the routes ([`Site`]), the JSON and the page.
//!
//! The device loop never waits for the web side:
//! - **Out of the loop**: each runner holds a [`Tap`]. It copies the bytes
//!   the unit sends (after the link faults: what a client sees) into a
//!   bounded ring, and, at most every [`PUBLISH_EVERY`], the control
//!   socket's `status` words, the device time and the truth attitude. Each
//!   of these takes its lock with `try_lock`: when the web thread holds it,
//!   the bytes are counted as lost to the view (`Slot::lost`) and the
//!   loop goes on. A closed or slow tab therefore costs the device nothing.
//! - **The web thread** drains the ring, decodes the frames (the
//!   protocol's [`live::LiveDecoder`], on the client's decoders), keeps
//!   the last [`KEEP_POINTS`] points per device with their device time
//!   (and, for ISB, their data set's name: field names repeat across sets),
//!   and answers the page's polls.
//! - **One device clock**: every point, the truth and the status are on
//!   the runner's device time (s since power-on), whatever the frame
//!   carries (`Timing`): the tap stamps each run of bytes with the
//!   device time it left the emulated line, and a frame's time is its
//!   stream's previous time plus the step of its own clock — the 2 kHz
//!   counter (a 16-bit wrap every 32.768 s resolved by the stamps), the
//!   IMU time, an ISB set's time since boot or GPS time of week — or, for
//!   a format without a time field (Orientation, Quaternion, GAA, GAm,
//!   GAAm), the whole output periods at its known rate (the status's
//!   `output-rate`) nearest the stamps: the frames' order and rate. A
//!   stream whose step disagrees with the stamps by more than
//!   [`REANCHOR_S`] (a pause, a restart, a power cycle) starts again at
//!   its stamp. For an IMX the GPS time of week of device time 0 is
//!   reported too (from the GPS-timed sets), a second label of the axis.
//! - **Commands**: `POST /api/command?dev=K` carries one control-socket
//!   line. It is parsed here with the control socket's own parser
//!   ([`control::parse`]): a malformed line gets HTTP 400 with the parser's
//!   words and never reaches the device; a line over [`MAX_BODY`] bytes
//!   gets 413. A valid command is queued for device K's runner, which
//!   carries it out between ticks with the same executor as the control
//!   socket (`Runner`'s `apply`), and its answer comes back (`ok …` 200,
//!   `error …` 422; 503 while the device is off). A request must carry the
//!   header `X-Imu-Emu: 1` (a cross-site page cannot add it) and a `Host`
//!   naming this server.

use std::collections::VecDeque;
use std::io::Read as _;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use imu_emu::model::Product;

use crate::control;
use live::{Frame, Live, LiveDecoder, Own, WEEK_S};

pub mod live;
pub mod server;

/// How often a runner publishes its status (host time): 25 Hz.
pub const PUBLISH_EVERY: Duration = Duration::from_millis(40);
/// Bytes of output kept for the web thread between two of its polls.
pub const TX_RING: usize = 512 * 1024;
/// Stamped runs of output bytes kept between two polls, at most.
const MAX_MARKS: usize = 16 * 1024;
/// Decoded points kept per device (the page asks for what is new).
pub const KEEP_POINTS: usize = 8192;
/// Most points one poll returns.
pub const MAX_POINTS_PER_POLL: usize = 2000;
/// Largest command body accepted, bytes.
pub const MAX_BODY: usize = 256;
/// Commands a runner takes from its queue per pass.
const COMMANDS_PER_PASS: usize = 8;
/// Commands waiting for a runner, at most (then 503).
const MAX_QUEUED: usize = 16;
/// How long the web thread waits for a runner's answer.
const ANSWER_WITHIN: Duration = Duration::from_secs(2);
/// A stream's own step and its line stamps may differ by this much (the
/// TX queue's and the line's delay) before it starts again at its stamp.
pub const REANCHOR_S: f64 = 0.3;

const INDEX_HTML: &str = include_str!("web/index.html");
const APP_JS: &str = include_str!("web/app.js");
const STYLE_CSS: &str = include_str!("web/style.css");

/// A command waiting for its runner, with where its answer goes.
#[derive(Debug)]
pub struct Pending {
    cmd: control::Command,
    answer: mpsc::SyncSender<Result<String, String>>,
}

impl Pending {
    /// Carries the command out with `apply` and sends its answer back
    /// (never blocks: the channel has room for one).
    pub fn run(self, apply: impl FnOnce(control::Command) -> Result<String, String>) {
        let r = apply(self.cmd);
        let _ = self.answer.try_send(r);
    }
}

/// What a runner published last.
#[derive(Debug, Default)]
struct Shared {
    tx: VecDeque<u8>,
    /// Runs of `tx`: (device time the bytes left the line, ns; how many).
    marks: VecDeque<(u64, usize)>,
    status: String,
    device_ns: u64,
    /// Truth at device times, ns: attitude (heading, pitch, roll, deg)
    /// and position (latitude, longitude deg, height m).
    truth: VecDeque<(u64, Truth)>,
    on: bool,
}

/// The truth the runner publishes ([`Tap::publish`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Heading, pitch, roll, deg (none for a motion without attitude).
    pub attitude: Option<[f32; 3]>,
    /// Latitude, longitude (deg), height (m).
    pub lla: [f64; 3],
}

/// One device's place in the hub.
#[derive(Debug)]
pub struct Slot {
    name: String,
    product: Product,
    place: String,
    shared: Mutex<Shared>,
    commands: Mutex<VecDeque<Pending>>,
    /// Output bytes the view missed (its lock was busy, or the ring full).
    lost: AtomicU64,
}

/// The devices the web view shows.
#[derive(Debug)]
pub struct Hub {
    live: Live,
    slots: Vec<Arc<Slot>>,
}

impl Hub {
    /// A hub for devices named `name` at `places` (`tcp 127.0.0.1:7000`),
    /// whose output `live` decodes.
    pub fn new(live: Live, product: Product, name: &str, places: &[String]) -> Arc<Hub> {
        Arc::new(Hub {
            live,
            slots: places
                .iter()
                .map(|p| {
                    Arc::new(Slot {
                        name: name.to_owned(),
                        product,
                        place: p.clone(),
                        shared: Mutex::new(Shared {
                            status: "mode=off".to_owned(),
                            ..Shared::default()
                        }),
                        commands: Mutex::new(VecDeque::new()),
                        lost: AtomicU64::new(0),
                    })
                })
                .collect(),
        })
    }

    /// Device `k`'s tap, for its runner.
    pub fn tap(&self, k: usize) -> Option<Tap> {
        Some(Tap {
            slot: Arc::clone(self.slots.get(k)?),
            published_at: None,
        })
    }
}

/// A runner's end: never blocks.
pub struct Tap {
    slot: Arc<Slot>,
    published_at: Option<Instant>,
}

impl Tap {
    /// The bytes the unit sent (as the client receives them), leaving the
    /// line at device time `device_ns`.
    pub fn tx(&self, bytes: &[u8], device_ns: u64) {
        let Ok(mut s) = self.slot.shared.try_lock() else {
            self.slot
                .lost
                .fetch_add(bytes.len() as u64, Ordering::Relaxed);
            return;
        };
        let room = TX_RING.saturating_sub(s.tx.len());
        let take = bytes.len().min(room);
        s.tx.extend(&bytes[..take]);
        let full = s.marks.len() >= MAX_MARKS;
        match s.marks.back_mut() {
            // The same time, or no room for another stamp (no page has
            // polled for long): the bytes join the last run.
            Some((ns, n)) if *ns == device_ns || full => *n += take,
            _ if take > 0 => s.marks.push_back((device_ns, take)),
            _ => {}
        }
        if take < bytes.len() {
            self.slot
                .lost
                .fetch_add((bytes.len() - take) as u64, Ordering::Relaxed);
        }
    }

    /// Commands the page sent, a few at a time.
    pub fn commands(&self) -> Vec<Pending> {
        let Ok(mut q) = self.slot.commands.try_lock() else {
            return Vec::new();
        };
        let n = q.len().min(COMMANDS_PER_PASS);
        q.drain(..n).collect()
    }

    /// Whether a status is due ([`PUBLISH_EVERY`]).
    pub fn publish_due(&self) -> bool {
        self.published_at
            .is_none_or(|t| t.elapsed() >= PUBLISH_EVERY)
    }

    /// Publishes the `status` words, the device time and the truth, if
    /// the web thread is not reading right now.
    pub fn publish(&mut self, status: String, device_ns: u64, truth: Truth) {
        self.published_at = Some(Instant::now());
        let Ok(mut s) = self.slot.shared.try_lock() else {
            return;
        };
        s.status = status;
        s.device_ns = device_ns;
        s.on = true;
        if s.truth.len() >= KEEP_POINTS {
            s.truth.pop_front();
        }
        s.truth.push_back((device_ns, truth));
    }
}

/// One decoded output frame: its sequence number, device time (s), the
/// ISB data set it came from (fields of several sets share names:
/// `lla` is in INS_1..3 and GPS1_POS) and named values.
struct Point {
    seq: u64,
    t: f64,
    set: Option<&'static str>,
    values: Vec<(String, f64)>,
}

/// One stream's clock ([`Timing`]).
#[derive(Debug, Clone, Copy)]
struct Stream {
    /// Device time given to its last frame, s.
    t: f64,
    /// Its own clock then, s, if it has one.
    own: Option<f64>,
}

/// Puts every frame on the device clock (module doc, "One device clock").
#[derive(Debug, Default)]
struct Timing {
    /// Per stream: the KERNEL's frame ID, the ISB's data set ID + 256.
    streams: std::collections::HashMap<u16, Stream>,
}

impl Timing {
    /// The device time (s) of a frame of `stream` whose last byte left the
    /// line at `stamp` (s), with its own clock `own`, or, without one,
    /// sent every `1 / rate` s (`rate` Hz, if known).
    fn time(&mut self, stream: u16, stamp: f64, own: Option<Own>, rate: Option<f64>) -> f64 {
        let t = match (self.streams.get(&stream), own) {
            (Some(prev), Some(o)) if prev.own.is_some() => {
                let mut step = o.value - prev.own.unwrap_or(o.value);
                if let Some(w) = o.wrap {
                    // The wraps the stamps say passed (a pause).
                    step = step.rem_euclid(w);
                    step += w * ((stamp - prev.t - step) / w).round().max(0.0);
                }
                prev.t + step
            }
            (Some(prev), None) => match rate.filter(|r| *r > 0.0) {
                Some(r) => prev.t + ((stamp - prev.t) * r).round().max(1.0) / r,
                None => stamp,
            },
            _ => stamp,
        };
        let prev = self.streams.get(&stream).map(|p| p.t);
        let t = if (t - stamp).abs() > REANCHOR_S || prev.is_some_and(|p| t <= p) {
            stamp
        } else {
            t
        };
        self.streams.insert(
            stream,
            Stream {
                t,
                own: own.map(|o| o.value),
            },
        );
        t
    }
}

/// The web thread's view of one device.
struct View {
    slot: Arc<Slot>,
    /// The protocol's decoder of the output.
    live: Box<dyn LiveDecoder>,
    /// Reused list of the frames one chunk held.
    frames_of_chunk: Vec<Frame>,
    timing: Timing,
    /// GPS time of week at device time 0, s (an IMX's GPS-timed sets).
    gps_tow_at_zero: Option<f64>,
    points: VecDeque<Point>,
    truth: VecDeque<(u64, f64, Truth)>,
    seq: u64,
    truth_seq: u64,
    frames: u64,
}

impl View {
    fn new(slot: Arc<Slot>, live: Box<dyn LiveDecoder>) -> View {
        View {
            slot,
            live,
            frames_of_chunk: Vec::new(),
            timing: Timing::default(),
            gps_tow_at_zero: None,
            points: VecDeque::new(),
            truth: VecDeque::new(),
            seq: 0,
            truth_seq: 0,
            frames: 0,
        }
    }

    /// Takes what the runner published; decodes the new bytes.
    fn refresh(&mut self) -> (String, u64, bool) {
        let (bytes, marks, status, device_ns, truth, on) = {
            let Ok(mut s) = self.slot.shared.lock() else {
                return ("mode=off".to_owned(), 0, false);
            };
            (
                std::mem::take(&mut s.tx),
                std::mem::take(&mut s.marks),
                s.status.clone(),
                s.device_ns,
                std::mem::take(&mut s.truth),
                s.on,
            )
        };
        for (ns, a) in truth {
            self.truth_seq += 1;
            self.truth.push_back((self.truth_seq, ns as f64 * 1e-9, a));
        }
        while self.truth.len() > KEEP_POINTS {
            self.truth.pop_front();
        }
        // The known output rate of a KERNEL stream (formats without a
        // time field are timed by it).
        let rate: Option<f64> = status
            .split_whitespace()
            .find_map(|w| w.strip_prefix("output-rate="))
            .and_then(|r| r.parse().ok());
        let bytes: Vec<u8> = bytes.into();
        let mut at = 0;
        for (ns, n) in marks {
            let chunk = &bytes[at.min(bytes.len())..(at + n).min(bytes.len())];
            at += n;
            self.decode(chunk, ns as f64 * 1e-9, rate);
        }
        (status, device_ns, on)
    }

    /// Decodes `chunk`, which left the line at device time `stamp` (s),
    /// the stream's known output rate `rate` (Hz) if any.
    fn decode(&mut self, chunk: &[u8], stamp: f64, rate: Option<f64>) {
        let product = self.slot.product;
        let mut frames = core::mem::take(&mut self.frames_of_chunk);
        self.live.decode(chunk, &product, &mut frames);
        for f in frames.drain(..) {
            let rate = if f.rated { rate } else { None };
            let t = self.timing.time(f.stream, stamp, f.own, rate);
            if let (true, Some(o)) = (f.gps, f.own) {
                self.gps_tow_at_zero = Some((o.value - t).rem_euclid(WEEK_S));
            }
            self.push(t, f.set, f.values);
        }
        self.frames_of_chunk = frames;
    }

    fn push(&mut self, t: f64, set: Option<&'static str>, values: Vec<(String, f64)>) {
        self.seq += 1;
        self.frames += 1;
        self.points.push_back(Point {
            seq: self.seq,
            t,
            set,
            values,
        });
        while self.points.len() > KEEP_POINTS {
            self.points.pop_front();
        }
    }
}

/// The running web view: its HTTP server ([`server`]) and what it shows.
pub struct Server {
    /// The address it listens on.
    pub addr: SocketAddr,
    _http: server::HttpServer,
}

impl Server {
    /// Binds `addr` and serves `hub` ([`server::HttpServer`]: a thread
    /// per connection, within its limits).
    pub fn start(addr: &str, hub: Arc<Hub>) -> anyhow::Result<Server> {
        let listener = std::net::TcpListener::bind(addr)
            .map_err(|e| crate::error::bind_error(e, "--web", addr))?;
        let bound = listener.local_addr()?;
        let site = Site::new(hub, bound);
        let handler: Arc<server::Handler> = Arc::new(move |r: &server::Request| site.respond(r));
        let http = server::HttpServer::start(listener, handler, MAX_BODY)?;
        Ok(Server {
            addr: bound,
            _http: http,
        })
    }
}

/// The web view's routes over a hub: what a request gets, whatever
/// carries it (the server, the fuzz target).
pub struct Site {
    hub: Arc<Hub>,
    views: Vec<Mutex<View>>,
    bound: SocketAddr,
}

impl Site {
    /// The routes of `hub`, served at `bound` (the `Host` a request must
    /// name).
    pub fn new(hub: Arc<Hub>, bound: SocketAddr) -> Site {
        let views = hub
            .slots
            .iter()
            .map(|s| Mutex::new(View::new(Arc::clone(s), (hub.live.decoder)())))
            .collect();
        Site { hub, views, bound }
    }

    /// The answer to `r`.
    pub fn respond(&self, r: &server::Request) -> server::Response {
        let parts = Parts {
            method: r.method,
            url: r.target.clone(),
            host: r.header("Host").map(str::to_owned),
            marked: r.header("X-Imu-Emu") == Some("1"),
            length: Some(r.body.len()),
        };
        let (status, content_type, body) = handle(
            &self.hub,
            &self.views,
            self.bound,
            parts,
            &mut r.body.as_slice(),
        );
        server::Response {
            status,
            content_type,
            body,
        }
    }
}

/// What `handle` needs of a request.
struct Parts {
    method: server::Method,
    url: String,
    host: Option<String>,
    marked: bool,
    length: Option<usize>,
}

type Reply = (u16, &'static str, String);

const TEXT: &str = "text/plain; charset=utf-8";
const JSON: &str = "application/json";

fn text(code: u16, s: impl Into<String>) -> Reply {
    (code, TEXT, s.into())
}

fn handle(
    hub: &Hub,
    views: &[Mutex<View>],
    bound: SocketAddr,
    p: Parts,
    body: &mut dyn std::io::Read,
) -> Reply {
    let host_ok = p.host.as_deref().is_some_and(|h| {
        h.eq_ignore_ascii_case(&bound.to_string())
            || h.eq_ignore_ascii_case(&format!("localhost:{}", bound.port()))
    });
    if !host_ok {
        return text(421, "this server answers to its own address only");
    }
    let (path, query) = p.url.split_once('?').unwrap_or((&p.url, ""));
    let param = |name: &str| {
        query
            .split('&')
            .find_map(|kv| kv.strip_prefix(name)?.strip_prefix('='))
    };
    let dev = || -> Result<usize, Reply> {
        let k = param("dev").unwrap_or("0");
        let k: usize = k
            .parse()
            .map_err(|_| text(400, format!("not a device number: {k}")))?;
        if k >= views.len() {
            return Err(text(
                404,
                format!("no device {k}: this run has devices 0..{}", views.len() - 1),
            ));
        }
        Ok(k)
    };
    use server::Method::{Get, Post};
    match (&p.method, path) {
        (Get, "/") => (200, "text/html; charset=utf-8", INDEX_HTML.to_owned()),
        (Get, "/app.js") => (200, "text/javascript; charset=utf-8", APP_JS.to_owned()),
        (Get, "/style.css") => (200, "text/css; charset=utf-8", STYLE_CSS.to_owned()),
        (Get, "/api/devices") => (200, JSON, devices_json(hub)),
        (Get, "/api/state") => {
            let k = match dev() {
                Ok(k) => k,
                Err(r) => return r,
            };
            let since: u64 = param("since").and_then(|s| s.parse().ok()).unwrap_or(0);
            let truth_since: u64 = param("truth_since")
                .and_then(|s| s.parse().ok())
                .unwrap_or(0);
            let Ok(mut v) = views[k].lock() else {
                return text(500, "error internal");
            };
            (200, JSON, state_json(&mut v, since, truth_since))
        }
        (Post, "/api/command") => {
            if !p.marked {
                return text(403, "commands need the header X-Imu-Emu: 1");
            }
            let k = match dev() {
                Ok(k) => k,
                Err(r) => return r,
            };
            if p.length.is_some_and(|n| n > MAX_BODY) {
                return text(413, format!("a command is at most {MAX_BODY} bytes"));
            }
            let mut raw = Vec::new();
            if body
                .take(MAX_BODY as u64 + 1)
                .read_to_end(&mut raw)
                .is_err()
            {
                return text(400, "could not read the request body");
            }
            if raw.len() > MAX_BODY {
                return text(413, format!("a command is at most {MAX_BODY} bytes"));
            }
            let Ok(line) = String::from_utf8(raw) else {
                return text(400, "error not UTF-8");
            };
            let line = line.trim();
            if line.chars().any(char::is_control) {
                return text(400, "error one line, no control characters");
            }
            command(hub, k, line)
        }
        (_, "/" | "/app.js" | "/style.css" | "/api/devices" | "/api/state" | "/api/command") => {
            text(405, "method not allowed")
        }
        _ => text(404, "not found"),
    }
}

/// One control line for device `k`: parsed here, carried out by its runner.
fn command(hub: &Hub, k: usize, line: &str) -> Reply {
    let cmd = match control::parse(line) {
        Ok(c) => c,
        Err(e) => return text(400, format!("error {e}")),
    };
    match cmd {
        control::Command::Help => return text(200, format!("ok {}", control::help())),
        control::Command::Devices => {
            let places: Vec<String> = hub.slots.iter().map(|s| s.place.clone()).collect();
            return text(200, format!("ok {}", control::devices_reply(&places)));
        }
        _ => {}
    }
    let slot = &hub.slots[k];
    let (answer, rx) = mpsc::sync_channel(1);
    {
        let Ok(mut q) = slot.commands.lock() else {
            return text(500, "error internal");
        };
        if q.len() >= MAX_QUEUED {
            return text(503, "error busy: too many commands waiting");
        }
        q.push_back(Pending { cmd, answer });
    }
    match rx.recv_timeout(ANSWER_WITHIN) {
        Ok(Ok(t)) if t.is_empty() => text(200, "ok"),
        Ok(Ok(t)) => text(200, format!("ok {t}")),
        Ok(Err(e)) => text(422, format!("error {e}")),
        Err(_) => {
            // Not taken: the device is off (or stalled); drop it so that it
            // does not run later by surprise.
            if let Ok(mut q) = slot.commands.lock() {
                q.clear();
            }
            text(
                503,
                format!(
                    "error dev {k} did not answer within {ANSWER_WITHIN:?} (off? it powers on \
                     when a client connects to its UART, or with --power-on now)"
                ),
            )
        }
    }
}

/// `"` and `\` escaped, control characters dropped.
fn json_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {}
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A finite number, or `null`.
fn json_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".to_owned()
    }
}

fn devices_json(hub: &Hub) -> String {
    let protocol = hub.live.protocol.name();
    let devs: Vec<String> = hub
        .slots
        .iter()
        .enumerate()
        .map(|(k, s)| {
            format!(
                "{{\"dev\":{k},\"name\":{},\"place\":{}}}",
                json_str(&s.name),
                json_str(&s.place)
            )
        })
        .collect();
    format!(
        "{{\"protocol\":\"{protocol}\",\"help\":{},\"devices\":[{}]}}",
        json_str(control::help().trim_start_matches("commands: ")),
        devs.join(",")
    )
}

fn state_json(v: &mut View, since: u64, truth_since: u64) -> String {
    let (status, device_ns, on) = v.refresh();
    let words: Vec<String> = status
        .split_whitespace()
        .filter_map(|w| w.split_once('='))
        .map(|(k, val)| format!("{}:{}", json_str(k), json_str(val)))
        .collect();
    let new: Vec<&Point> = v.points.iter().filter(|p| p.seq > since).collect();
    let skip = new.len().saturating_sub(MAX_POINTS_PER_POLL);
    let points: Vec<String> = new[skip..]
        .iter()
        .map(|p| {
            // seq, t, the set (ISB), then the values: one list, so that a
            // point with no values is still well-formed JSON.
            let mut fields = vec![
                format!("\"seq\":{}", p.seq),
                format!("\"t\":{}", json_num(p.t)),
            ];
            fields.extend(p.set.map(|s| format!("\"set\":{}", json_str(s))));
            fields.extend(
                p.values
                    .iter()
                    .map(|(k, x)| format!("{}:{}", json_str(k), json_num(*x))),
            );
            format!("{{{}}}", fields.join(","))
        })
        .collect();
    let truth: Vec<String> = v
        .truth
        .iter()
        .filter(|t| t.0 > truth_since)
        .map(|(seq, t, truth)| {
            let mut fields = vec![format!("\"seq\":{seq}"), format!("\"t\":{}", json_num(*t))];
            if let Some(a) = truth.attitude {
                for (k, x) in ["heading", "pitch", "roll"].iter().zip(a) {
                    fields.push(format!("\"{k}\":{}", json_num(f64::from(x))));
                }
            }
            for (k, x) in ["lat", "lon", "height"].iter().zip(truth.lla) {
                fields.push(format!("\"{k}\":{}", json_num(x)));
            }
            format!("{{{}}}", fields.join(","))
        })
        .collect();
    format!(
        "{{\"on\":{on},\"device_time_s\":{},\"gps_tow_at_zero_s\":{},\"status\":{{{}}},\
         \"frames_decoded\":{},\"view_lost_bytes\":{},\"points\":[{}],\"truth\":[{}]}}",
        json_num(device_ns as f64 * 1e-9),
        v.gps_tow_at_zero.map_or("null".to_owned(), json_num),
        words.join(","),
        v.frames,
        v.slot.lost.load(Ordering::Relaxed),
        points.join(","),
        truth.join(",")
    )
}

#[cfg(test)]
mod tests {
    use super::live::COUNTER_HZ;
    use super::*;

    fn hub() -> Arc<Hub> {
        Hub::new(
            <imu_emu::kernel::Kernel as crate::protocol::HostProtocol>::live(),
            Product::parse("K110").unwrap(),
            "K110",
            &["tcp 127.0.0.1:1".to_owned()],
        )
    }

    fn call(hub: &Hub, method: server::Method, url: &str, marked: bool, body: &str) -> Reply {
        let views: Vec<Mutex<View>> = hub
            .slots
            .iter()
            .map(|s| Mutex::new(View::new(Arc::clone(s), (hub.live.decoder)())))
            .collect();
        let bound: SocketAddr = "127.0.0.1:8080".parse().unwrap();
        let p = Parts {
            method,
            url: url.to_owned(),
            host: Some("127.0.0.1:8080".to_owned()),
            marked,
            length: Some(body.len()),
        };
        handle(hub, &views, bound, p, &mut body.as_bytes())
    }

    #[test]
    fn bad_requests_never_reach_the_device() {
        use server::Method::{Get, Post};
        let h = hub();
        assert_eq!(call(&h, Post, "/api/command", false, "pps").0, 403);
        assert_eq!(call(&h, Post, "/api/command", true, "warp 9").0, 400);
        assert_eq!(
            call(&h, Post, "/api/command", true, &"p".repeat(300)).0,
            413
        );
        assert_eq!(call(&h, Post, "/api/command", true, "pps\nstatus").0, 400);
        assert_eq!(call(&h, Post, "/api/command?dev=3", true, "pps").0, 404);
        assert_eq!(call(&h, Get, "/api/command", true, "").0, 405);
        assert_eq!(call(&h, Get, "/nope", true, "").0, 404);
        assert!(h.slots[0].commands.lock().unwrap().is_empty());
        let r = call(&h, Post, "/api/command", true, "help");
        assert_eq!((r.0, r.2.starts_with("ok commands: help")), (200, true));
    }

    #[test]
    fn isb_points_name_their_set_and_stay_json_without_values() {
        let h = hub();
        let mut v = View::new(Arc::clone(&h.slots[0]), Box::new(live::IsbLive::default()));
        v.push(1.5, Some("INS_2"), vec![("lla_x".to_owned(), 45.0)]);
        v.push(2.0, None, Vec::new());
        let s: serde_json::Value = serde_json::from_str(&state_json(&mut v, 0, 0)).unwrap();
        assert_eq!(
            s["points"],
            serde_json::json!([
                {"seq": 1, "t": 1.5, "set": "INS_2", "lla_x": 45},
                {"seq": 2, "t": 2}
            ])
        );
    }

    /// GA frames at 100 Hz, stamped 3 ms after their counter's time, with
    /// a 45 s pause (a 16-bit counter wrap) in the middle: on the device
    /// clock, 10 ms apart, and after the pause 45 s later, not 45 − 32.768.
    #[test]
    fn the_counter_is_unwrapped_across_a_pause_by_the_stamps() {
        let mut tm = Timing::default();
        let own = |k: u64| {
            Some(Own {
                value: (k * 20 % 65_536) as f64 / COUNTER_HZ,
                wrap: Some(65_536.0 / COUNTER_HZ),
            })
        };
        let mut ts = Vec::new();
        for k in 0..500u64 {
            ts.push(tm.time(0x8F, 1.003 + k as f64 * 0.01, own(k), Some(100.0)));
        }
        // The pause: the next frame is 4500 periods (45 s) later.
        let k = 499 + 4500;
        let t = tm.time(0x8F, 1.003 + k as f64 * 0.01, own(k), Some(100.0));
        for w in ts.windows(2) {
            assert!((w[1] - w[0] - 0.01).abs() < 1e-9, "{w:?}");
        }
        assert!((t - ts[499] - 45.0).abs() < 1e-9, "{}", t - ts[499]);
        // Orientation (no time field) at 200 Hz, stamps jittering by a
        // tick: whole periods in the frames' order.
        let mut last: Option<f64> = None;
        for k in 0..400u64 {
            let jitter = if k % 3 == 0 { 0.0005 } else { 0.0 };
            let t = tm.time(0x33, 2.0 + k as f64 * 0.005 + jitter, None, Some(200.0));
            if let Some(l) = last {
                assert!((t - l - 0.005f64).abs() < 1e-9, "{k}: {t} after {l}");
            }
            last = Some(t);
        }
        // A restart (the counter from 0, 2 s later): back at the stamp.
        let t = tm.time(0x8F, 60.0, own(0), Some(100.0));
        assert_eq!(t, 60.0);
    }

    /// An IMX's INS_2 (GPS time of week) and IMU (time since boot) land on
    /// one clock; the GPS time of week of device time 0 is reported.
    #[test]
    fn isb_sets_on_two_clocks_share_the_device_clock() {
        let h = hub();
        let mut v = View::new(Arc::clone(&h.slots[0]), Box::new(live::IsbLive::default()));
        let mut ins = [0u8; 128];
        let mut imu = [0u8; 64];
        for k in 0..20u32 {
            let t = 5.0 + f64::from(k) * 0.1;
            ins[4..12].copy_from_slice(&(403_168.0 + t).to_le_bytes());
            imu[0..8].copy_from_slice(&t.to_le_bytes());
            let mut bytes = Vec::new();
            for (did, body) in [
                (imu_emu::isb::did::INS_2, &ins[..]),
                (imu_emu::isb::did::IMU, &imu[..]),
            ] {
                let size = usize::from(imu_emu::isb::did::lookup(u16::from(did)).unwrap().size);
                let mut pkt = [0u8; 512];
                let n = imu_emu::isb::message::encode_data(
                    did,
                    &body[..size],
                    0,
                    size as u16,
                    &mut pkt,
                )
                .unwrap();
                bytes.extend_from_slice(&pkt[..n]);
            }
            v.decode(&bytes, t + 0.002, None);
        }
        let last = |set: &str| {
            v.points
                .iter()
                .rev()
                .find(|p| p.set == Some(set))
                .unwrap()
                .t
        };
        assert!((last("INS_2") - last("IMU")).abs() < 1e-9);
        assert!((v.gps_tow_at_zero.unwrap() - 403_168.0).abs() < 0.01);
    }

    #[test]
    fn a_busy_lock_costs_the_tap_nothing() {
        let h = hub();
        let tap = h.tap(0).unwrap();
        let guard = h.slots[0].shared.lock().unwrap();
        tap.tx(&[1, 2, 3], 0);
        drop(guard);
        assert_eq!(h.slots[0].lost.load(Ordering::Relaxed), 3);
        tap.tx(&[4], 0);
        assert_eq!(h.slots[0].shared.lock().unwrap().tx.len(), 1);
    }
}
