//! The live motion feed (`--motion-feed ADDR`): samples from a simulator or
//! a HIL rig over TCP (`HOST:PORT`) or UDP (`udp:HOST:PORT`), decoded by
//! the core's [`imu_emu::feed::Decoder`] (text rows in the `--trajectory`
//! format and binary samples, mixed), applied to the device's ticks.
//!
//! Two clocks (`docs/feed.md`):
//!
//! * **Real time** (default): a sample applies from its arrival — from the
//!   first tick whose deadline is at or after the device time it reached
//!   the socket at (the kernel's receive timestamp, else the time it was
//!   read) — and holds until the next. Silence longer than `--feed-timeout`
//!   (device time) raises [`Faults::motion_feed_lost`], which the KERNEL
//!   reports as USW bit 1 and the IMX as a sensor fault; the next sample
//!   clears it.
//! * **Lockstep** (`--lockstep`): device time advances only as samples
//!   arrive, to each sample's time, with the values interpolated between
//!   the last two ([`imu_emu::feed::Track`]); nothing else moves it.
//!   The same feed and seed give the same output bytes.
//!
//! Full-state rows (after a full-state header, `docs/feed.md`) drive the
//! unit's vehicle ([`imu_emu::SignalChain::set_vehicle`]) instead of
//! its rates and forces: in real time the newest row's state holds, its
//! rates and forces the row's own or, without them, derived from the last
//! two rows at the newest ([`fullstate::between`]); in lockstep the state
//! moves between the last two rows as a `--motion` full-state CSV plays
//! ([`fullstate::sample`]). `truth` and `status` then report it.
//!
//! A TCP feed takes one client at a time (a new one replaces the old, with
//! a fresh decoder); UDP takes each datagram as a whole (a `\n` is added
//! after one that does not end a line). Every sample and rejection is
//! counted ([`FeedState::status`]); a rejection is logged at `-v`.
//!
//! [`Faults::motion_feed_lost`]: imu_emu::Faults::motion_feed_lost

use std::collections::VecDeque;
use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::os::fd::{AsFd, AsRawFd};
use std::time::{Duration, SystemTime};

use imu_emu::feed::{Counts, Decoder, Live, Reject, Sample, Track, MAX_LEAD_NS, OWN_DEVICE};
use imu_emu::sensor::Truth;
use imu_emu::vehicle::{fullstate, FullStateRow, VehicleState};
use nix::poll::{PollFd, PollFlags};

/// Default `--feed-timeout`, s.
pub const DEFAULT_TIMEOUT_S: f64 = 0.1;
/// Most samples waiting for lockstep: the socket is not read beyond
/// (its own buffer then holds the simulator back).
pub const MAX_PENDING: usize = 256;
/// Most bytes read from a feed a pass.
pub const MAX_READ: usize = 64 * 1024;

/// Where a feed listens.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FeedAddr {
    /// `HOST:PORT`.
    Tcp(String),
    /// `udp:HOST:PORT`.
    Udp(String),
}

impl FeedAddr {
    /// `udp:HOST:PORT` or `HOST:PORT` (TCP; `tcp:` may be written).
    pub fn parse(s: &str) -> Self {
        match s.strip_prefix("udp:") {
            Some(a) => FeedAddr::Udp(a.to_owned()),
            None => FeedAddr::Tcp(s.strip_prefix("tcp:").unwrap_or(s).to_owned()),
        }
    }

    /// The `HOST:PORT` part.
    pub fn host_port(&self) -> &str {
        match self {
            FeedAddr::Tcp(a) | FeedAddr::Udp(a) => a,
        }
    }

    /// The same kind of address at `addr`.
    pub fn with(&self, addr: String) -> Self {
        match self {
            FeedAddr::Tcp(_) => FeedAddr::Tcp(addr),
            FeedAddr::Udp(_) => FeedAddr::Udp(addr),
        }
    }
}

enum Socket {
    Tcp {
        listener: TcpListener,
        client: Option<(TcpStream, SocketAddr)>,
    },
    Udp(UdpSocket),
}

/// A feed's socket and its decoder.
pub struct FeedSocket {
    socket: Socket,
    local: SocketAddr,
    decoder: Decoder,
    /// The label of messages (`dev 3: ` or empty).
    label: String,
}

impl FeedSocket {
    /// Binds `addr` (port 0 picks a free port).
    pub fn bind(addr: &FeedAddr) -> anyhow::Result<Self> {
        let a = addr.host_port();
        let err = |e| crate::error::bind_error(e, "--motion-feed", a);
        let (socket, local) = match addr {
            FeedAddr::Tcp(_) => {
                let l = TcpListener::bind(a).map_err(err)?;
                l.set_nonblocking(true)?;
                let local = l.local_addr()?;
                (
                    Socket::Tcp {
                        listener: l,
                        client: None,
                    },
                    local,
                )
            }
            FeedAddr::Udp(_) => {
                let u = UdpSocket::bind(a).map_err(err)?;
                u.set_nonblocking(true)?;
                stamp_arrivals(&u);
                let local = u.local_addr()?;
                (Socket::Udp(u), local)
            }
        };
        Ok(FeedSocket {
            socket,
            local,
            decoder: Decoder::new(),
            label: String::new(),
        })
    }

    /// Names the device in messages.
    pub fn set_label(&mut self, label: &str) {
        self.label = label.to_owned();
    }

    /// `tcp 127.0.0.1:9000` / `udp 127.0.0.1:9000`.
    pub fn describe(&self) -> String {
        match self.socket {
            Socket::Tcp { .. } => format!("tcp {}", self.local),
            Socket::Udp(_) => format!("udp {}", self.local),
        }
    }

    /// The descriptors to wait on for input.
    pub fn interest<'a>(&'a self, fds: &mut Vec<PollFd<'a>>) {
        match &self.socket {
            Socket::Tcp { listener, client } => {
                fds.push(PollFd::new(listener.as_fd(), PollFlags::POLLIN));
                if let Some((s, _)) = client {
                    fds.push(PollFd::new(s.as_fd(), PollFlags::POLLIN));
                }
            }
            Socket::Udp(u) => fds.push(PollFd::new(u.as_fd(), PollFlags::POLLIN)),
        }
    }

    /// Reads what is there (at most [`MAX_READ`] bytes) and hands each
    /// decoded outcome to `each` with how long ago (host time) the bytes
    /// that ended it reached the socket: the kernel's receive timestamp
    /// (`SO_TIMESTAMPNS`; for TCP that of the newest segment a read took),
    /// zero where there is none. Never blocks. A waiting TCP client is
    /// not taken here: the caller takes it with [`FeedSocket::accept`]
    /// first, which tells it a new timeline begins (a client taken here
    /// silently would have its first samples judged on the old timeline).
    pub fn read_stamped(
        &mut self,
        each: &mut dyn FnMut(Result<Sample, Reject>, Duration),
    ) -> anyhow::Result<()> {
        let mut buf = [0u8; 4096];
        let mut got = 0;
        match &mut self.socket {
            Socket::Tcp { client, .. } => {
                while let Some((s, peer)) = client.as_mut() {
                    if got >= MAX_READ {
                        break;
                    }
                    match recv_stamped(s, &mut buf) {
                        Ok((0, _)) => {
                            eprintln!("imu-emu: {}motion feed client {peer} closed", self.label);
                            *client = None;
                        }
                        Ok((n, age)) => {
                            got += n;
                            self.decoder.decode(&buf[..n], &mut |r| each(r, age));
                        }
                        Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        Err(e) => {
                            eprintln!("imu-emu: {}motion feed client {peer}: {e}", self.label);
                            *client = None;
                        }
                    }
                }
            }
            Socket::Udp(u) => {
                let mut d = [0u8; 65536];
                while got < MAX_READ {
                    match recv_stamped(u, &mut d) {
                        Ok((n, age)) => {
                            got += n.max(1);
                            let each = &mut |r| each(r, age);
                            self.decoder.decode(&d[..n], each);
                            if n > 0 && d[n - 1] != b'\n' {
                                self.decoder.decode(b"\n", each);
                            }
                        }
                        Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        // ICMP errors of earlier sends and the like.
                        Err(_) => break,
                    }
                }
            }
        }
        Ok(())
    }
}

impl FeedSocket {
    /// TCP: takes a new client if one is waiting (it replaces the old, with
    /// a fresh decoder); whether one came (a new feed timeline,
    /// [`FeedState::new_timeline`]). UDP: never.
    pub fn accept(&mut self) -> anyhow::Result<bool> {
        let Socket::Tcp { listener, client } = &mut self.socket else {
            return Ok(false);
        };
        let mut came = false;
        loop {
            match listener.accept() {
                Ok((s, peer)) => {
                    s.set_nonblocking(true)?;
                    stamp_arrivals(&s);
                    eprintln!(
                        "imu-emu: {}motion feed client {peer} connected to {}",
                        self.label, self.local
                    );
                    *client = Some((s, peer));
                    self.decoder = Decoder::new();
                    came = true;
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) if crate::transport::is_transient_accept_error(&e) => break,
                Err(e) => return Err(anyhow::Error::new(e).context("motion feed accept")),
            }
        }
        Ok(came)
    }
}

/// Asks the kernel to timestamp what `s` receives (`SO_TIMESTAMPNS`):
/// when a sample arrived, rather than when the runner got to read it. A
/// failure only costs that precision.
fn stamp_arrivals(s: &impl AsFd) {
    let _ = nix::sys::socket::setsockopt(s, nix::sys::socket::sockopt::ReceiveTimestampns, &true);
}

/// The oldest receive timestamp believed (older: unknown, zero).
const MAX_AGE: Duration = Duration::from_secs(1);

/// One non-blocking receive into `buf`: the bytes and how long ago (host
/// time) the kernel received them (zero without a timestamp: the kernel
/// stamps only once timestamping is on, a moment after the first socket
/// asks). Errors are those of `read` (`WouldBlock`, `Interrupted`, …).
fn recv_stamped(s: &impl AsRawFd, buf: &mut [u8]) -> io::Result<(usize, Duration)> {
    use nix::sys::socket::{recvmsg, ControlMessageOwned, MsgFlags};
    let mut cmsg = nix::cmsg_space!(nix::sys::time::TimeSpec);
    let mut iov = [io::IoSliceMut::new(buf)];
    let msg = recvmsg::<()>(
        s.as_raw_fd(),
        &mut iov,
        Some(&mut cmsg),
        MsgFlags::MSG_DONTWAIT,
    )
    .map_err(io::Error::from)?;
    let mut age = Duration::ZERO;
    if let Ok(cmsgs) = msg.cmsgs() {
        for c in cmsgs {
            if let ControlMessageOwned::ScmTimestampns(ts) = c {
                let at = std::time::UNIX_EPOCH + Duration::from(ts);
                age = SystemTime::now().duration_since(at).unwrap_or_default();
                if age > MAX_AGE {
                    // Not a receive time of this clock (a stepped clock,
                    // another clock's stamp): unknown.
                    age = Duration::ZERO;
                }
            }
        }
    }
    Ok((msg.bytes, age))
}

/// How the feed drives the device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeedConfig {
    /// Lockstep (`--lockstep`) instead of real time.
    pub lockstep: bool,
    /// Silence after which the fault is raised, ns of device time.
    pub timeout_ns: u64,
}

/// What a sample carries, queued or held.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Item {
    /// Body rates and specific forces.
    Rates(Truth),
    /// The vehicle's full state.
    Full(FullStateRow),
}

/// What the feed gives a tick (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FeedMotion {
    /// Rates and forces: the chain measures them
    /// ([`imu_emu::sensor::Motion::Sample`]).
    Rates(Truth),
    /// The vehicle: the chain measures its `truth()` and reports it.
    Vehicle(VehicleState),
}

impl FeedMotion {
    /// The rates and forces the chain measures.
    pub fn truth(&self) -> Truth {
        match self {
            FeedMotion::Rates(t) => *t,
            FeedMotion::Vehicle(s) => s.truth(),
        }
    }
}

/// Full-state rows as lockstep plays them: the newest two since the
/// stream switched to full states, and the time of the last tick (the
/// mean since then is measured, as for a `--motion` file).
#[derive(Debug, Clone, Default)]
struct FullTrack {
    rows: Vec<FullStateRow>,
    last_s: f64,
}

/// Full-state rows in real time: the newest row, its state, the device
/// time it arrived at and the state the last tick applied.
#[derive(Debug, Clone, Default)]
struct FullLive {
    row: Option<FullStateRow>,
    newest: Option<VehicleState>,
    arrived_ns: Option<u64>,
    applied: Option<VehicleState>,
}

/// One device's feed: its samples, counters and fault (module docs).
#[derive(Debug, Clone)]
pub struct FeedState {
    cfg: FeedConfig,
    /// The device index samples must name (or [`OWN_DEVICE`]).
    device: u16,
    /// Whether samples naming no device ([`OWN_DEVICE`]) are this
    /// device's (its own feed) or rejected (a shared feed).
    own: bool,
    /// Lockstep: the newest two rate samples the device reached.
    track: Track,
    /// Lockstep: the full-state rows; `Some` while the newest sample
    /// reached is a full state.
    full: Option<FullTrack>,
    /// Real time: the full-state rows (the rest is in `live`).
    full_live: FullLive,
    /// Real time: the samples as they arrive, the fault.
    live: Live,
    /// Real time: samples read whose arrival no tick has reached yet
    /// (arrival, time, sample), oldest first: a pass reads the socket
    /// before its ticks, so that a sample dated before a deadline applies
    /// from that tick, and a newer one that came after it must wait for
    /// its own (`Live` keeps only the newest).
    arriving: VecDeque<(u64, u64, Item)>,
    counts: Counts,
    /// Samples waiting for the device to reach their time (lockstep).
    pending: VecDeque<(u64, Item)>,
    /// Host time of the newest sample (status in lockstep).
    last_host: Option<std::time::Instant>,
    /// Lockstep at a `--speed` factor: the device time the host clock
    /// allows now ([`FeedState::set_pace`]).
    pace_ns: Option<u64>,
    /// Real time: a new timeline began ([`FeedState::new_timeline`]); the
    /// next sample is taken whatever its time.
    restarted: bool,
    /// Rate limit of the `silent` / `back` messages.
    silence_log: crate::transport::LogLimit,
    label: String,
}

impl FeedState {
    /// The feed of device `device`; `own`: samples naming no device are
    /// its own.
    pub fn new(cfg: FeedConfig, device: u16, own: bool, label: &str) -> Self {
        FeedState {
            cfg,
            device,
            own,
            track: Track::new(),
            full: None,
            full_live: FullLive::default(),
            live: Live::new(cfg.timeout_ns),
            arriving: VecDeque::new(),
            counts: Counts::default(),
            pending: VecDeque::new(),
            last_host: None,
            pace_ns: None,
            restarted: false,
            silence_log: crate::transport::LogLimit::default(),
            label: label.to_owned(),
        }
    }

    /// Lockstep or real time.
    pub fn lockstep(&self) -> bool {
        self.cfg.lockstep
    }

    /// Whether another sample may be read (lockstep queue not full).
    pub fn wants_more(&self) -> bool {
        self.pending.len() < MAX_PENDING
    }

    /// Counters so far.
    pub fn counts(&self) -> &Counts {
        &self.counts
    }

    /// Lockstep at a `--speed` factor: device time may not pass `ns` now
    /// (the host clock); a sample more than [`MAX_LEAD_NS`] beyond it is
    /// [`Reject::TooFarAhead`].
    pub fn set_pace(&mut self, ns: u64) {
        self.pace_ns = Some(ns);
    }

    /// A new timeline: a new feed connection or a power cycle. In real
    /// time the next sample is taken whatever its time (what arrived
    /// before applies now; the newest holds until then), so one
    /// far-future sample cannot lock the feed. In lockstep device time
    /// cannot go back: times go on from the newest (and
    /// [`Reject::TooFarAhead`] keeps a far-future one out).
    pub fn new_timeline(&mut self) {
        if self.cfg.lockstep {
            return;
        }
        while let Some((a, t, item)) = self.arriving.pop_front() {
            let _ = self.offer_live(t, item, a);
        }
        self.live.restart();
        self.full_live.row = None;
        self.restarted = true;
    }

    /// Takes a decoded outcome at device time `now_ns`.
    pub fn offer(&mut self, r: Result<Sample, Reject>, now_ns: u64) {
        let r = r.and_then(|s| {
            let d = s.device();
            let mine = if d == OWN_DEVICE {
                self.own
            } else {
                d == self.device
            };
            if !mine {
                return Err(Reject::WrongDevice);
            }
            match s {
                Sample::Rates(s) => Ok((s.time_ns, Item::Rates(s.truth))),
                Sample::FullState(s) => Ok((s.time_ns, Item::Full(s.row))),
                _ => Err(Reject::UnsupportedKind),
            }
        });
        let r = match r {
            Ok((t, item)) if self.cfg.lockstep => {
                // Checked against the newest queued time, taken in order.
                let newest = self
                    .pending
                    .back()
                    .map(|p| p.0)
                    .or(self.track.last().map(|l| l.0))
                    .or(self.full.as_ref().and_then(|f| f.rows.last()).map(|r| {
                        // Full states reached: their time, ns.
                        (r.time_s * 1e9) as u64
                    }));
                let lead_from = newest.unwrap_or(0).max(now_ns);
                if newest.is_some_and(|n| t <= n) {
                    Err(Reject::NonIncreasing)
                } else if t.saturating_sub(lead_from) > MAX_LEAD_NS
                    || self
                        .pace_ns
                        .is_some_and(|p| t.saturating_sub(p) > MAX_LEAD_NS)
                {
                    Err(Reject::TooFarAhead)
                } else {
                    self.pending.push_back((t, item));
                    Ok(())
                }
            }
            Ok((t, item)) => {
                let newest = self.arriving.back().map(|a| a.1).or(self
                    .live
                    .track()
                    .last()
                    .map(|l| l.0));
                if !self.restarted && newest.is_some_and(|n| t <= n) {
                    Err(Reject::NonIncreasing)
                } else {
                    self.restarted = false;
                    if self.arriving.len() >= MAX_PENDING {
                        // Bounded: the oldest takes effect now.
                        if let Some((a, t, item)) = self.arriving.pop_front() {
                            let _ = self.offer_live(t, item, a);
                        }
                    }
                    self.arriving.push_back((now_ns, t, item));
                    Ok(())
                }
            }
            Err(e) => Err(e),
        };
        match r {
            Ok(()) => self.last_host = Some(std::time::Instant::now()),
            Err(e) => tracing::info!("{}motion feed sample rejected: {}", self.label, e.name()),
        }
        self.counts.note(r);
    }

    /// Real time: a sample arrived at device time `now_ns`. A full state
    /// holds with the rates and forces its row gives, else those of the
    /// way from the previous full-state row to it, at its end.
    fn offer_live(&mut self, t: u64, item: Item, now_ns: u64) -> Result<(), Reject> {
        let (truth, full) = match item {
            Item::Rates(truth) => (truth, None),
            Item::Full(row) => {
                let state = match &self.full_live.row {
                    Some(prev) if prev.time_s < row.time_s => {
                        fullstate::between(prev, &row, row.time_s)
                    }
                    _ => row.held(row.time_s),
                };
                (state.truth(), Some((row, state)))
            }
        };
        self.live.offer(t, truth, now_ns)?;
        let f = &mut self.full_live;
        f.row = full.map(|(row, _)| row);
        f.newest = full.map(|(_, state)| state);
        f.arrived_ns = Some(now_ns);
        Ok(())
    }

    /// Lockstep: the time of the next queued sample, if any.
    pub fn next_time(&self) -> Option<u64> {
        self.pending.front().map(|p| p.0)
    }

    /// Lockstep: makes the next queued sample the newest; its time.
    pub fn advance(&mut self) -> Option<u64> {
        let (t, item) = self.pending.pop_front()?;
        match item {
            Item::Rates(truth) => {
                if self.full.take().is_some() {
                    // No interpolation across the full states between.
                    self.track = Track::new();
                }
                // Queued in increasing order: accepted.
                let _ = self.track.accept(t, truth);
            }
            Item::Full(row) => {
                let full = self.full.get_or_insert_with(|| FullTrack {
                    rows: Vec::with_capacity(2),
                    last_s: row.time_s,
                });
                if full.rows.len() == 2 {
                    full.rows.remove(0);
                }
                full.rows.push(row);
            }
        }
        Some(t)
    }

    /// The motion of the tick at `deadline_ns` (`None`: no sample yet, the
    /// device's own motion goes on), and whether the feed is lost then.
    pub fn at(&mut self, deadline_ns: u64) -> (Option<FeedMotion>, bool) {
        let now_s = deadline_ns as f64 * 1e-9;
        if self.cfg.lockstep {
            if let Some(full) = self.full.as_mut() {
                let state = fullstate::sample(&full.rows, full.last_s, now_s);
                full.last_s = full.last_s.max(now_s);
                return (
                    state.map(|mut s| {
                        s.time_s = now_s;
                        FeedMotion::Vehicle(s)
                    }),
                    false,
                );
            }
            return (self.track.at(deadline_ns).map(FeedMotion::Rates), false);
        }
        while let Some(&(a, t, item)) = self.arriving.front().filter(|f| f.0 <= deadline_ns) {
            self.arriving.pop_front();
            // Checked in order when offered: accepted.
            let _ = self.offer_live(t, item, a);
        }
        let was = self.live.lost();
        let (truth, lost) = self.live.at(deadline_ns);
        // The same rule as `Live::at`: the newest applies from its arrival.
        let f = &mut self.full_live;
        if f.arrived_ns.is_some_and(|a| deadline_ns >= a) {
            f.applied = f.newest;
        }
        let motion = match f.applied {
            Some(mut s) => {
                s.time_s = now_s;
                Some(FeedMotion::Vehicle(s))
            }
            None => truth.map(FeedMotion::Rates),
        };
        let held = if lost != was {
            self.silence_log.allow()
        } else {
            None
        };
        if let Some(held) = held {
            let held = if held > 0 {
                format!(" ({held} earlier changes not logged)")
            } else {
                String::new()
            };
            if lost {
                eprintln!(
                    "imu-emu: {}motion feed silent for more than {} ms: sensor fault reported, \
                     the last sample holds{held}",
                    self.label,
                    self.cfg.timeout_ns / 1_000_000
                );
            } else {
                eprintln!(
                    "imu-emu: {}motion feed back: sensor fault cleared{held}",
                    self.label
                );
            }
        }
        (motion, lost)
    }

    /// Whether the feed's newest applied sample is a full state (the
    /// `truth` source is then `feed`).
    pub fn drives_vehicle(&self) -> bool {
        if self.cfg.lockstep {
            self.full.is_some()
        } else {
            self.full_live.applied.is_some()
        }
    }

    /// `status` words: `feed-clock`, `feed-samples`, `feed-age-ms`
    /// (device time since the newest sample arrived; in lockstep host
    /// time), `feed-lost`, `feed-rejected` and one `feed-rejected-<why>`
    /// per reason seen.
    pub fn status(&self, now_ns: u64) -> String {
        let age = if self.cfg.lockstep {
            self.last_host
                .map(|h| (h.elapsed().as_millis() as u64).to_string())
        } else {
            self.live
                .age_ns(now_ns)
                .map(|a| (a / 1_000_000).to_string())
        };
        let mut s = format!(
            " feed-clock={} feed-samples={} feed-age-ms={} feed-lost={} feed-rejected={}",
            if self.cfg.lockstep {
                "lockstep"
            } else {
                "realtime"
            },
            self.counts.samples,
            age.as_deref().unwrap_or("never"),
            u8::from(self.live.lost()),
            self.counts.rejected_total(),
        );
        for r in Reject::ALL {
            let n = self.counts.rejected[r as usize];
            if n > 0 {
                s.push_str(&format!(" feed-rejected-{}={n}", r.name()));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_emu::feed::RateSample;

    /// A sample's age is from when the socket received it, not from the
    /// read: one that waited 50 ms is read as 50 ms old (TCP and UDP). The
    /// kernel stamps only once its timestamping is on (a work item a
    /// moment after the first socket asks; what came before is stamped
    /// when read): rows are sent until one comes stamped with its
    /// arrival, at most 20.
    #[test]
    fn samples_are_dated_from_their_arrival_at_the_socket() {
        let row = b"0.0005, 10, 0, 0, 0, 0, 1\n";
        let wait = Duration::from_millis(50);
        for addr in [
            FeedAddr::parse("127.0.0.1:0"),
            FeedAddr::parse("udp:127.0.0.1:0"),
        ] {
            let mut sock = FeedSocket::bind(&addr).unwrap();
            let local = sock.local;
            type Sender = Box<dyn FnMut(&[u8])>;
            let mut send: Sender = if let FeedAddr::Tcp(_) = addr {
                let mut c = std::net::TcpStream::connect(local).unwrap();
                std::thread::sleep(Duration::from_millis(20));
                assert!(sock.accept().unwrap());
                Box::new(move |b| std::io::Write::write_all(&mut c, b).unwrap())
            } else {
                let c = UdpSocket::bind("127.0.0.1:0").unwrap();
                Box::new(move |b| {
                    c.send_to(b, local).unwrap();
                })
            };
            let mut got = Vec::new();
            for _ in 0..20 {
                got.clear();
                send(row);
                std::thread::sleep(wait);
                sock.read_stamped(&mut |r, age| got.push((r.is_ok(), age)))
                    .unwrap();
                // A datagram that came before the kernel's timestamping was
                // on is stamped when it is read (an age of µs): not yet.
                if got.iter().any(|g| g.1 >= wait) {
                    break;
                }
            }
            assert_eq!(got.len(), 1, "{addr:?}");
            let (ok, age) = got[0];
            assert!(ok, "{addr:?}");
            assert!(age >= wait && age < MAX_AGE, "{addr:?}: {age:?}");
        }
    }

    fn sample(device: u16, t: u64, w: f32) -> Result<Sample, Reject> {
        Ok(Sample::Rates(RateSample {
            device,
            time_ns: t,
            truth: Truth {
                rate_dps: [w, 0.0, 0.0],
                specific_force_g: [0.0, 0.0, 1.0],
                temperature_c: None,
            },
        }))
    }

    /// A device's own real-time feed, silent after 1 ms.
    fn real_time_1ms() -> FeedState {
        let cfg = FeedConfig {
            lockstep: false,
            timeout_ns: 1_000_000,
        };
        FeedState::new(cfg, 0, true, "")
    }

    #[test]
    fn real_time_applies_from_arrival_holds_and_times_out() {
        let mut f = real_time_1ms();
        assert_eq!(f.at(0), (None, false));
        f.offer(sample(OWN_DEVICE, 5, 1.0), 1_000);
        assert_eq!(f.at(500).0, None);
        assert_eq!(f.at(1_000).0.unwrap().truth().rate_dps[0], 1.0);
        f.offer(sample(0, 6, 2.0), 1_500);
        assert_eq!(f.at(1_400).0.unwrap().truth().rate_dps[0], 1.0);
        assert_eq!(f.at(2_000), (f.at(2_000).0, false));
        assert!(f.at(2_600_000).1);
        assert_eq!(f.at(2_600_000).0.unwrap().truth().rate_dps[0], 2.0);
        f.offer(sample(0, 6, 3.0), 2_600_000);
        f.offer(sample(1, 7, 3.0), 2_600_000);
        assert_eq!(f.counts().rejected[Reject::NonIncreasing as usize], 1);
        assert_eq!(f.counts().rejected[Reject::WrongDevice as usize], 1);
        f.offer(sample(0, 8, 3.0), 2_700_000);
        assert!(!f.at(2_700_000).1);
        assert!(f
            .status(3_000_000)
            .contains("feed-samples=3 feed-age-ms=0 feed-lost=0"));
    }

    /// Samples read together (a runner that woke late reads the socket
    /// before the ticks it owes): each tick takes the newest that had
    /// arrived by its deadline, not the newest read.
    #[test]
    fn real_time_ticks_take_the_newest_sample_arrived_by_their_deadline() {
        let mut f = real_time_1ms();
        f.offer(sample(OWN_DEVICE, 1, 1.0), 100);
        f.offer(sample(OWN_DEVICE, 2, 2.0), 450);
        f.offer(sample(OWN_DEVICE, 3, 3.0), 600);
        f.offer(sample(OWN_DEVICE, 3, 4.0), 650);
        assert_eq!(f.counts().rejected[Reject::NonIncreasing as usize], 1);
        let x = |f: &mut FeedState, d| f.at(d).0.map(|m| m.truth().rate_dps[0]);
        assert_eq!(x(&mut f, 0), None);
        assert_eq!(x(&mut f, 500), Some(2.0));
        assert_eq!(x(&mut f, 1_000), Some(3.0));
        assert!(f.status(1_000).contains("feed-samples=3 "));
    }

    fn full(t_s: f64, lat: f64, vn: f64) -> Result<Sample, Reject> {
        let layout = imu_emu::vehicle::FullStateLayout::default();
        let row = FullStateRow::parse(&format!("{t_s},{lat},7,300,{vn},0,0,0,0,0"), &layout);
        Ok(Sample::FullState(imu_emu::feed::FullStateSample {
            device: OWN_DEVICE,
            time_ns: (t_s * 1e9).round() as u64,
            row: row.unwrap(),
        }))
    }

    fn vehicle(m: Option<FeedMotion>) -> VehicleState {
        match m {
            Some(FeedMotion::Vehicle(s)) => s,
            m => panic!("{m:?}"),
        }
    }

    #[test]
    fn real_time_full_states_hold_with_rates_derived_from_the_last_two() {
        let cfg = FeedConfig {
            lockstep: false,
            timeout_ns: 1_000_000_000,
        };
        let mut f = FeedState::new(cfg, 0, true, "");
        f.offer(full(1.0, 45.0, 0.0), 1_000);
        let a = vehicle(f.at(2_000).0);
        assert!((a.time_s - 2e-6).abs() < 1e-15);
        assert_eq!(a.vel_ned, [0.0; 3]);
        assert!(f.drives_vehicle());
        // From rest to 10 m/s north in 1 s: ~1 m/s² forward, held.
        f.offer(full(2.0, 45.00005, 10.0), 3_000);
        assert_eq!(vehicle(f.at(2_500).0).vel_ned, a.vel_ned);
        let b = vehicle(f.at(5_000).0);
        assert_eq!(b.vel_ned, [10.0, 0.0, 0.0]);
        assert!((b.lat_rad.to_degrees() - 45.00005).abs() < 1e-12);
        assert!(b.force_b[0] > 1.0, "{:?}", b.force_b);
        assert_eq!(vehicle(f.at(9_000).0).force_b, b.force_b);
        // A rate sample takes over again.
        f.offer(sample(OWN_DEVICE, 3_000_000_000, 4.0), 10_000);
        assert_eq!(f.at(10_000).0.unwrap().truth().rate_dps[0], 4.0);
        assert!(!f.drives_vehicle());
    }

    #[test]
    fn lockstep_full_states_move_between_the_last_two() {
        let cfg = FeedConfig {
            lockstep: true,
            timeout_ns: 1,
        };
        let mut f = FeedState::new(cfg, 0, true, "");
        // 10 m/s north: 1 s is about 1.11e-4 ° of latitude at 45°.
        let dlat = 10.0 / 111_132.0;
        f.offer(full(1.0, 45.0, 10.0), 0);
        f.offer(full(2.0, 45.0 + dlat, 10.0), 0);
        assert_eq!(f.advance(), Some(1_000_000_000));
        assert_eq!(f.advance(), Some(2_000_000_000));
        let mid = vehicle(f.at(1_500_000_000).0);
        assert_eq!(mid.time_s, 1.5);
        assert!((mid.lat_rad.to_degrees() - (45.0 + dlat / 2.0)).abs() < 1e-7);
        assert!((mid.vel_ned[0] - 10.0).abs() < 0.05, "{:?}", mid.vel_ned);
    }

    #[test]
    fn lockstep_queues_and_interpolates() {
        let cfg = FeedConfig {
            lockstep: true,
            timeout_ns: 1,
        };
        let mut f = FeedState::new(cfg, 2, false, "");
        f.offer(sample(OWN_DEVICE, 0, 0.0), 0);
        f.offer(sample(2, 1_000, 0.0), 0);
        f.offer(sample(2, 2_000, 10.0), 0);
        f.offer(sample(2, 2_000, 10.0), 0);
        assert_eq!(f.counts().samples, 2);
        assert_eq!(f.advance(), Some(1_000));
        assert_eq!(f.next_time(), Some(2_000));
        assert_eq!(f.advance(), Some(2_000));
        assert_eq!(f.at(1_500).0.unwrap().truth().rate_dps[0], 5.0);
        assert!(!f.at(1_500).1);
        assert_eq!(f.advance(), None);
    }
}
