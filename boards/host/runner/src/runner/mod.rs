//! The loop: one virtual device driven by the wall clock — in real time,
//! scaled, or as fast as possible ([`crate::clock`], `--speed`; every time
//! below is device time, ns since power-on).
//!
//! In files by purpose: this one is the loop and its clocks (the device
//! clock of `--speed`, and in lockstep the feed's samples paced by a
//! second clock) and its reports; `port.rs` is the port adapter the
//! core's schedule drives (transport, link, input pacing, pins, motion
//! sources); `exec.rs` carries out control commands and answers `status`
//! and `truth`; `build.rs` builds a runner and is its owner's handle.
//!
//! Each pass is one [`Schedule::poll`] of the core's shared tick/pump
//! schedule ([`imu_emu::schedule`], the same code the firmware shell runs):
//! ticks on absolute deadlines `k × period`, each with its own deadline as
//! `now`; before each tick the line is advanced to that deadline and the
//! device's TX queue drained at the line rate ([`imu_emu::Pacer`]);
//! input after the ticks due; a line-rate switch after the bytes queued
//! before it. This board adds:
//!
//! * **Bounded work per pass**: at most [`MAX_TICKS_PER_PASS`] ticks and
//!   [`MAX_RX_PER_PASS`] received bytes, so a flood of input never starves
//!   the ticks and SIGINT/SIGTERM stop the loop within one pass.
//! * **Bounded lag**: when the host cannot keep up (a `--speed` factor
//!   beyond what it computes, a stalled host) device time is held back so
//!   it lags the clock by at most [`MAX_LAG`] ([`Clock::hold_back`]): every
//!   tick still runs in order and no frame is lost, device time just runs
//!   slower than asked. Logged on stderr (at most once a second).
//! * **Visible loss**: a frame the device's TX queue could not take is
//!   dropped whole by the core ([`Device::tx_dropped`]); the runner logs it
//!   (at most once a second) and counts it in [`Stats::tx_dropped`].
//! * **Input at the line rate**: whatever the transport delivers at once
//!   (a 70 KB burst of commands in one TCP write, a pty or serial buffer
//!   full), the device gets its input no faster than its UART would at
//!   the line rate: a host-side [`Pacer`](imu_emu::Pacer) at the device's line rate, in
//!   device time, bounds what each pass reads; the rest waits in the
//!   transport (the kernel's buffers, then the peer: TCP flow control),
//!   whose wait does not wake for input meanwhile
//!   ([`Transport::hold_input`]) but when a burst of credit is there. So
//!   the replies to a burst of commands, each shorter than its command,
//!   always fit the line and the device's TX queue, as on a real UART.
//!   (The firmware's UART delivers at the line rate by itself: this is
//!   the host board's part, not the core schedule's.) Not in lockstep
//!   (`--lockstep`), where device time moves only with the feed's
//!   samples: there input goes in as it comes.
//! * **A status line** on stdout once a second when it is a terminal
//!   (mode, format, rates, frames sent, frames rejected).
//! * **Sleeping**: until [`Schedule::poll_at`] (the next tick that produces
//!   output, or when the line can carry what is queued — but not before the
//!   next tick or [`BUSY_WAKE`], whichever is first), the next `--pps` edge
//!   or [`IDLE_WAKE`], whichever is first; [`BUSY_WAKE`] while bytes wait
//!   for the client; not at all while ticks are due. UART input wakes it at
//!   once. The process asks for a timer slack of 1 ns (the program's
//!   `cli::run`), so a wake is not up to the kernel's default 50 µs late.
//! * **`--speed max`**: device time moves on by [`MAX_BATCH_TICKS`] ticks
//!   a pass (batches end on multiples of it), in rounds of passes that end
//!   when [`MAX_BACKLOG`] bytes wait for the client (or input came, or
//!   [`MAX_ROUND_TICKS`] ran, or the device went quiet): one read at a
//!   round's start, one send at its end; while no client is connected
//!   device time waits. The loop never sleeps then, it only polls the
//!   transport (or waits for the client to read). **Repeatable sessions**:
//!   while the device is quiet (`Runner::max_quiet`: nothing to send,
//!   no stream, no reset waiting, input neither held back nor within the
//!   RX idle time) device time waits for the client's input too, and input
//!   is read only then or while a stream runs; so a client that waits for
//!   each answer before its next command sends every command at the same
//!   device time, run after run, and one seed gives the same bytes
//!   (README "Repeatable sessions").

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::Device;
use imu_emu::schedule::{Limits, Pass, Schedule};

use crate::clock::{Clock, Speed, MAX_BACKLOG, MAX_BATCH_TICKS};
use crate::feed::FeedState;
use crate::protocol::HostProtocol;
use crate::transport::Transport;

mod build;
mod exec;
#[cfg(test)]
mod fake;
mod port;

use port::HostPort;

/// Wake interval while bytes wait for the client.
pub const BUSY_WAKE: Duration = Duration::from_millis(1);
/// Wake interval while the device is idle with nothing queued.
pub const IDLE_WAKE: Duration = Duration::from_millis(10);
/// Most ticks one pass runs (128 ms of device time at 2 kHz).
pub const MAX_TICKS_PER_PASS: u32 = 256;
/// Most received bytes one pass feeds to the device.
pub const MAX_RX_PER_PASS: usize = 4096;
/// How far device time may lag the clock before the clock is held back.
/// Below the transport's 64 KiB backlog at 2 Mbit/s (≈ 330 ms of line), so
/// the output of a whole catch-up fits it even if the client reads late.
pub const MAX_LAG: Duration = Duration::from_millis(200);
/// Bytes crossing between the transport and the device at once.
const CHUNK: usize = 4096;

const LIMITS: Limits = Limits {
    max_ticks: MAX_TICKS_PER_PASS,
    max_rx: MAX_RX_PER_PASS,
    early_ns: 0,
};
/// Most ticks a pass runs while input is held back at the line rate:
/// 2–4 ms of device time, so that input, fed after a pass's ticks, stays
/// interleaved with them even when the host is behind (a command cut
/// between two passes is not abandoned by the device's 100 ms RX idle
/// rule because the ticks of a host stall ran in between).
pub const HELD_RX_TICKS: u32 = 8;
const HELD: Limits = Limits {
    max_ticks: HELD_RX_TICKS,
    ..LIMITS
};
/// The passes of a `--speed max` round after its first: no input read.
const NO_RX: Limits = Limits {
    max_rx: 0,
    ..LIMITS
};
/// Most ticks one `--speed max` round runs before it sends and reads
/// (0.5 s of device time at 2 kHz): input is seen at least this often.
pub const MAX_ROUND_TICKS: u64 = 1024;

/// What the runner counted so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stats {
    /// Ticks run.
    pub ticks: u64,
    /// Bytes received from the client and fed to the device.
    pub rx_bytes: u64,
    /// Bytes the line carried to the transport.
    pub tx_bytes: u64,
    /// Frames the device dropped whole because its TX queue was full
    /// ([`Device::tx_dropped`]).
    pub tx_dropped: u32,
    /// Device time held back because the host could not keep up, ns.
    pub held_back_ns: u64,
}

/// The board: a device, the shared schedule, a transport and the pins.
pub struct Runner<F: NorFlash, T: Transport, P: HostProtocol> {
    dev: Device<F, P>,
    sched: Box<Schedule<CHUNK>>,
    io: HostPort<T, P>,
    clock: Clock,
    stats: Stats,
    /// Device frames dropped already reported on stderr.
    reported_drops: u32,
    /// Held-back device time already reported on stderr.
    reported_held_ns: u64,
    /// When loss or lag was last reported (host time).
    reported_at: Option<std::time::Instant>,
    /// When the terminal status line was last drawn (`None`: stdout is
    /// not a terminal, no status line).
    status_at: Option<std::time::Instant>,
    /// Lockstep at a `--speed` factor: device time does not run ahead of
    /// this clock either.
    pace: Option<Clock>,
    /// Lockstep: the time of the newest sample taken, ns (device time
    /// moves on to it).
    lockstep_target: u64,
}

impl<F: NorFlash, T: Transport, P: HostProtocol> Runner<F, T, P> {
    /// Hands the device a sample of a shared feed (or its rejection) that
    /// reached the socket `age` ago (host time; the kernel's receive
    /// timestamp, [`FeedSocket::read_stamped`]): in real time it is dated
    /// with the device time of its arrival, as a device's own feed's
    /// samples are; zero: now.
    ///
    /// [`FeedSocket::read_stamped`]: crate::feed::FeedSocket::read_stamped
    pub fn feed_offer(
        &mut self,
        r: Result<imu_emu::feed::Sample, imu_emu::feed::Reject>,
        age: Duration,
    ) {
        let at = self.clock.arrived_ns(age);
        if let Some(f) = self.io.feed.as_mut() {
            if let Some(p) = &self.pace {
                f.set_pace(p.now_ns());
            }
            f.offer(r, at);
        }
    }

    /// A new connection to a fleet's shared feed: a new feed timeline
    /// ([`FeedState::new_timeline`]).
    pub fn feed_new_timeline(&mut self) {
        if let Some(f) = self.io.feed.as_mut() {
            f.new_timeline();
        }
    }

    /// Whether the device's feed takes more samples now.
    pub fn feed_wants_more(&self) -> bool {
        self.io.feed.as_ref().is_some_and(FeedState::wants_more)
    }

    /// Appends the feed socket's descriptors to wait on (none while the
    /// lockstep queue is full: the socket is not read then).
    pub fn feed_interest<'a>(&'a self, fds: &mut Vec<nix::poll::PollFd<'a>>) {
        if let Some(s) = &self.io.feed_socket {
            if self.feed_wants_more() {
                s.interest(fds);
            }
        }
    }

    /// Reads the device's own feed socket (not while the lockstep queue is
    /// full). In real time each sample is stamped with the device time it
    /// reached the socket (the kernel's receive timestamp; the time of the
    /// read where there is none), in lockstep with now.
    fn read_feed(&mut self) -> anyhow::Result<()> {
        let (Some(sock), Some(state)) = (self.io.feed_socket.as_mut(), self.io.feed.as_mut())
        else {
            return Ok(());
        };
        if !state.wants_more() {
            return Ok(());
        }
        if sock.accept()? {
            state.new_timeline();
        }
        if let Some(p) = &self.pace {
            state.set_pace(p.now_ns());
        }
        let clock = &self.clock;
        let lockstep_now = state.lockstep().then(|| clock.now_ns());
        sock.read_stamped(&mut |r, age| {
            state.offer(r, lockstep_now.unwrap_or_else(|| clock.arrived_ns(age)));
        })
    }

    /// A lockstep turn: device time moves on to each queued sample's
    /// time in order (bounded work a turn), waiting for the client when
    /// [`MAX_BACKLOG`] bytes wait for it; input and control are served
    /// every turn.
    fn lockstep_turn(&mut self) -> anyhow::Result<Duration> {
        self.read_feed()?;
        let mut ticks = 0u64;
        let mut wait = IDLE_WAKE;
        loop {
            if self.io.transport.backlog_len() >= MAX_BACKLOG {
                wait = BUSY_WAKE;
                break;
            }
            if self.sched.next_deadline() > self.clock.now_ns() {
                // Device time moves on to the newest sample taken, or
                // takes the next; at a `--speed` factor no further than
                // the host clock: a sample ahead of it is reached tick by
                // tick as the host clock goes (interpolated from the one
                // before), the unit never silent, its control and UART
                // served meanwhile (the wait is at most `IDLE_WAKE`).
                let target = if self.lockstep_target > self.clock.now_ns() {
                    self.lockstep_target
                } else {
                    let Some(t) = self.io.feed.as_mut().and_then(FeedState::advance) else {
                        break;
                    };
                    self.lockstep_target = t;
                    t
                };
                let to = self
                    .pace
                    .as_ref()
                    .map_or(target, |p| target.min(p.now_ns()));
                self.clock.advance_to(to);
                let due = self.sched.next_deadline();
                if to < target && due > self.clock.now_ns() {
                    if let Some(p) = &self.pace {
                        wait = p.host_wait(due - p.now_ns().min(due)).min(IDLE_WAKE);
                    }
                    break;
                }
            }
            let pass = self.step()?;
            ticks += u64::from(pass.ticks);
            if ticks >= MAX_ROUND_TICKS {
                wait = Duration::ZERO;
                break;
            }
        }
        if ticks == 0 {
            // No sample moved time: still serve input and control.
            self.step()?;
        }
        Ok(wait)
    }

    /// Waits on the transport and the feed socket together.
    fn wait(&mut self, timeout: Duration) -> anyhow::Result<()> {
        if self.io.feed_socket.is_none() {
            return self.io.transport.wait(timeout);
        }
        self.io.transport.prepare_wait()?;
        let (revents, n) = {
            let mut fds = Vec::with_capacity(4);
            self.io.transport.interest(&mut fds);
            let n = fds.len();
            self.feed_interest(&mut fds);
            crate::transport::poll_fds(&mut fds, timeout)?;
            (crate::transport::revents(&fds), n)
        };
        self.io.transport.polled(&revents[..n]);
        Ok(())
    }

    /// Device time now, ns since power-on.
    fn now_ns(&self) -> u64 {
        self.clock.now_ns()
    }

    /// Runs until `stop` is set (by SIGINT/SIGTERM): checked before every
    /// pass, and a pass does bounded work.
    pub fn run(&mut self, stop: &AtomicBool) -> anyhow::Result<()> {
        while !stop.load(Ordering::Relaxed) {
            let timeout = self.turn()?;
            self.wait(timeout)?;
        }
        if self.status_at.is_some() {
            // End the status line before the last messages.
            println!();
        }
        Ok(())
    }

    /// One turn of the loop without its wait: a pass (or a `--speed max`
    /// round), the reports; how long the transport may then be waited on
    /// (host time) before the next turn.
    pub fn turn(&mut self) -> anyhow::Result<Duration> {
        if self.io.feed.as_ref().is_some_and(FeedState::lockstep) {
            let wait = self.lockstep_turn()?;
            self.report();
            self.status_line();
            return Ok(wait);
        }
        let max = self.clock.speed() == Speed::Max;
        // Nobody to read (output would be dropped): time waits.
        let client_keeps_up =
            self.io.transport.connected() && self.io.transport.backlog_len() < MAX_BACKLOG;
        // Quiet: time waits for input (read by the step, at this time).
        let quiet = max && self.max_quiet();
        let pass = if max && client_keeps_up && !quiet {
            self.max_round()?
        } else {
            self.step()?
        };
        let now = self.now_ns();
        self.report();
        self.status_line();
        Ok(if pass.behind || pass.rx == MAX_RX_PER_PASS {
            // More is due or waiting: go on at once.
            Duration::ZERO
        } else if max {
            // Poll only, wait for input (quiet: a wait ends at once when
            // it comes), or wait (briefly) for the client to read.
            if pass.rx == 0 && self.max_quiet() {
                IDLE_WAKE
            } else if self.io.transport.connected() && self.io.transport.backlog_len() < MAX_BACKLOG
            {
                Duration::ZERO
            } else {
                BUSY_WAKE
            }
        } else {
            self.clock
                .host_wait(self.next_wake(now).saturating_sub(now))
        })
    }

    /// When to wake next, ns since the epoch (see the module docs).
    fn next_wake(&self, now: u64) -> u64 {
        let idle_until = now.saturating_add(IDLE_WAKE.as_nanos() as u64);
        let busy_until = now.saturating_add(BUSY_WAKE.as_nanos() as u64);
        // Output the line can carry before the next tick waits for it (or
        // for BUSY_WAKE, if sooner): bytes leave in batches, as ticks run.
        let batch = busy_until.min(self.sched.next_deadline());
        let mut wake = self
            .sched
            .poll_at(&self.dev, now)
            .map_or(idle_until, |t| t.max(batch).min(idle_until));
        if self.io.transport.backlog_len() > 0 {
            wake = wake.min(busy_until);
        }
        if self.io.rx_held {
            // Input may wait in the transport: read again when a burst of
            // it can reach the device.
            wake = wake.min(self.io.rx_pacer.ready_at(usize::MAX));
        }
        if let Some(pps) = self.io.next_pps_ns {
            // Delivered before the first tick at or after it.
            wake = wake.min(pps.max(self.sched.next_deadline()));
        }
        wake.max(now)
    }

    /// Redraws a one-line status on stdout (a terminal only) once a second:
    /// mode, format, rates, frames and bytes sent, rejected frames.
    fn status_line(&mut self) {
        let Some(at) = self.status_at else { return };
        if at.elapsed() < Duration::from_secs(1) {
            return;
        }
        self.status_at = Some(std::time::Instant::now());
        let words = self.io.status(&self.dev);
        let short: Vec<&str> = words
            .split_whitespace()
            .filter(|w| {
                [
                    "mode=",
                    "format=",
                    "output-rate=",
                    "line-rate=",
                    "frames-sent=",
                    "rejected=",
                ]
                .iter()
                .any(|k| w.starts_with(k))
            })
            .collect();
        use std::io::Write as _;
        let mut out = std::io::stdout().lock();
        let _ = write!(out, "\r{}\x1b[K", short.join(" "));
        let _ = out.flush();
    }

    /// Tells stderr, at most once a second, that the device dropped frames
    /// because its TX queue overflowed (the line is too slow for the
    /// output, e.g. with EXTRIG bursts), or that device time was held back
    /// because the host could not keep up.
    fn report(&mut self) {
        let dropped = self.dev.tx_dropped();
        let held = self.clock.held_back_ns();
        if dropped == self.reported_drops && held == self.reported_held_ns {
            return;
        }
        let host_now = std::time::Instant::now();
        if self
            .reported_at
            .is_some_and(|t| host_now.duration_since(t) < Duration::from_secs(1))
        {
            return;
        }
        if dropped != self.reported_drops {
            eprintln!(
                "imu-emu: {}device TX queue overflowed: {dropped} frames dropped so far",
                self.io.label
            );
            self.reported_drops = dropped;
        }
        if held != self.reported_held_ns {
            eprintln!(
                "imu-emu: {}the host cannot keep up: device time held back by {} ms so far",
                self.io.label,
                held / 1_000_000
            );
            self.reported_held_ns = held;
        }
        self.reported_at = Some(host_now);
    }

    /// `--speed max`, while the client keeps up: device time moves on
    /// [`MAX_BATCH_TICKS`] ticks a pass, input is read in the first pass
    /// only, and passes go on until [`MAX_BACKLOG`] bytes wait for the
    /// client, input arrived or [`MAX_ROUND_TICKS`] ticks ran; then one
    /// send. Fewer, larger sends and reads: one of each per ≈ 16 KiB of
    /// output instead of per 64 ticks (the kernel's send and the reader's
    /// wake-up were half the cost of `--speed max`). The device sees the
    /// same ticks at the same device times.
    fn max_round(&mut self) -> anyhow::Result<Pass> {
        let period = self.sched.period_ns();
        let end = self.sched.ticks() + MAX_ROUND_TICKS;
        let mut total = Pass::default();
        let mut first = self.max_reads_input();
        loop {
            // Batches end on multiples of MAX_BATCH_TICKS, wherever the
            // round began (rounds end as the client reads): the device
            // goes quiet at the same device time run after run.
            let batch = self.sched.ticks() / MAX_BATCH_TICKS + 1;
            let to = (batch * MAX_BATCH_TICKS).saturating_mul(period);
            self.clock.advance_to(to);
            let now = self.now_ns();
            self.io.now_ns = now;
            let limits = if first { &LIMITS } else { &NO_RX };
            first = false;
            let pass = self.sched.poll(&mut self.dev, &mut self.io, now, limits)?;
            total.ticks += pass.ticks;
            total.rx += pass.rx;
            total.tx += pass.tx;
            total.behind |= pass.behind;
            if pass.rx > 0
                || self.io.transport.backlog_len() >= MAX_BACKLOG
                || self.sched.ticks() >= end
                || self.max_quiet()
            {
                break;
            }
        }
        self.stats.ticks += u64::from(total.ticks);
        self.stats.rx_bytes += total.rx as u64;
        self.stats.tx_bytes += total.tx as u64;
        self.io.transport.flush()?;
        Ok(total)
    }

    /// `--speed max`: whether the device has nothing to do until its
    /// next input, so device time waits for it — nothing to send or
    /// switch on the line ([`Schedule::poll_at`]: no stream, its
    /// alignment included), no software reset waiting, no input held
    /// back at the line rate or within the protocol's RX idle time
    /// ([`HostProtocol::RX_IDLE_NS`]: a frame cut short is abandoned
    /// after it) and a tick of its last byte,
    /// no link stall to end, no `--pps` generator and no live feed
    /// (their time is the host's business).
    fn max_quiet(&self) -> bool {
        let now = self.now_ns();
        self.sched.poll_at(&self.dev, now).is_none()
            && !self.dev.reset_pending()
            && !self.io.rx_held
            && self.io.rx_carry.is_empty()
            && self.io.link.stall_until().is_none()
            && self.io.next_pps_ns.is_none()
            && self.io.feed.is_none()
            && self
                .io
                .last_rx_ns
                .is_none_or(|t| now > t.saturating_add(P::RX_IDLE_NS + self.sched.period_ns()))
    }

    /// `--speed max`: whether a round reads input at its start. Not while
    /// the device only finishes an answer (or a reset, or its RX idle
    /// time): a command sent on reading an answer then arrives when the
    /// device is quiet again, however fast the client sends it
    /// (repeatable sessions). While a stream runs, input is held back at
    /// the line rate or by link faults, or time runs for the `--pps`
    /// generator, a live feed or a link stall, it is read as it comes.
    fn max_reads_input(&self) -> bool {
        self.dev.ticks_to_next_output().is_some()
            || self.io.rx_held
            || !self.io.rx_carry.is_empty()
            || self.io.next_pps_ns.is_some()
            || self.io.feed.is_some()
            || self.io.link.stall_until().is_some()
    }

    /// One pass of the shared schedule at the clock's time, then the
    /// transport flushed and the lag bounded.
    pub fn step(&mut self) -> anyhow::Result<Pass> {
        let now = self.now_ns();
        self.io.now_ns = now;
        self.io.held_back_ns = self.clock.held_back_ns();
        self.io.release()?;
        let limits = if self.io.rx_held { &HELD } else { &LIMITS };
        if !self.io.feed.as_ref().is_some_and(FeedState::lockstep) {
            // Before the ticks: a sample that reached the socket before a
            // deadline this pass runs applies from that tick, however
            // late the host woke the runner (docs/feed.md, "Figures").
            self.read_feed()?;
        }
        let pass = self.sched.poll(&mut self.dev, &mut self.io, now, limits)?;
        self.stats.ticks += u64::from(pass.ticks);
        self.stats.rx_bytes += pass.rx as u64;
        self.stats.tx_bytes += pass.tx as u64;
        self.io.transport.flush()?;
        let max_lag = MAX_LAG.as_nanos() as u64;
        let lag = self.sched.lag(now);
        if lag > max_lag {
            self.clock.hold_back(lag - max_lag);
        }
        Ok(pass)
    }
}

#[cfg(test)]
mod tests {
    use super::fake::Mem;
    use super::*;
    use crate::control;
    use crate::flash::MemNor;
    use imu_emu::device::PowerOn;
    use imu_emu::kernel::Kernel;
    use imu_emu::model::Product;
    use imu_emu::time::Instant;

    fn k110() -> Device<MemNor, Kernel> {
        let cfg = PowerOn {
            product: Product::parse("K110").unwrap(),
            boot: None,
            seed: 1,
        };
        Device::new(cfg, MemNor::new(), Instant::ZERO)
    }

    /// `--speed max`: device time moves in whole batches of ticks, and
    /// every byte the line carried reached the client (a clean link).
    #[test]
    fn speed_max_runs_whole_batches_and_the_client_gets_every_byte() {
        let mut r = Runner::new(k110(), Mem::default(), std::time::Instant::now())
            .with_speed(Speed::Max)
            .with_pps();
        for _ in 0..4 {
            r.turn().unwrap();
        }
        let s = r.stats();
        assert!(s.ticks >= MAX_BATCH_TICKS, "{s:?}");
        assert_eq!(s.ticks % MAX_BATCH_TICKS, 0, "{s:?}");
        assert!(s.ticks <= 4 * MAX_ROUND_TICKS, "{s:?}");
        assert_eq!(r.transport().sent.len() as u64, s.tx_bytes);
        assert_eq!(s.held_back_ns, 0);
    }

    /// The control executor through the runner: `status` counts the
    /// frames the line sent, `devices` names the transport.
    #[test]
    fn control_answers_status_and_devices() {
        let mut r = Runner::new(k110(), Mem::default(), std::time::Instant::now())
            .with_speed(Speed::Max)
            .with_pps();
        r.turn().unwrap();
        let status = r.control(control::Command::Status).unwrap();
        assert!(status.starts_with("mode="), "{status}");
        let sent = format!("bytes-sent={}", r.stats().tx_bytes);
        assert!(status.split(' ').any(|w| w == sent), "{status}");
        assert_eq!(
            r.control(control::Command::Devices).unwrap(),
            control::devices_reply(&["mem test".to_owned()])
        );
    }

    /// `--speed max`: a quiet device (nothing to send, no stream, no
    /// input) stops device time until its next input (repeatable
    /// sessions).
    #[test]
    fn speed_max_stops_device_time_while_the_device_is_quiet() {
        let mut r =
            Runner::new(k110(), Mem::default(), std::time::Instant::now()).with_speed(Speed::Max);
        for _ in 0..8 {
            r.turn().unwrap();
        }
        assert_eq!(r.device().output_rate(), None);
        let ticks = r.stats().ticks;
        for _ in 0..8 {
            r.turn().unwrap();
        }
        assert_eq!(r.stats().ticks, ticks);
        // Input wakes it: device time moves on while the command goes in.
        let mut buf = [0u8; 16];
        let n = imu_emu::kernel::command::Command::Stop
            .encode(&mut buf)
            .unwrap();
        r.transport_mut().input.extend(&buf[..n]);
        for _ in 0..8 {
            r.turn().unwrap();
        }
        assert_eq!(r.stats().rx_bytes, n as u64);
        assert!(r.stats().ticks > ticks, "{:?}", r.stats());
    }
}
