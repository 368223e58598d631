//! The loop: one virtual device driven by the wall clock — in real time,
//! scaled, or as fast as possible ([`crate::clock`], `--speed`; every time
//! below is device time, ns since power-on).
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
//!   the line rate: a host-side [`Pacer`] at the device's line rate, in
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
//!   once. The process asks for a timer slack of 1 ns (`cli::run`), so a
//!   wake is not up to the kernel's default 50 µs late.
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
use imu_emu::device::{Device, Level, Pin};
use imu_emu::isb::Isb;
use imu_emu::kernel::Kernel;
use imu_emu::personality::Personality;
use imu_emu::schedule::{Limits, Pass, Port, Schedule};
use imu_emu::sensor::Motion;
use imu_emu::time::Instant;
use imu_emu::Pacer;

use crate::clock::{Clock, Speed, MAX_BACKLOG, MAX_BATCH_TICKS};
use crate::control::{self, Control};
use crate::feed::{FeedSocket, FeedState};
use crate::link::Link;
use crate::monitor::Monitor;
use crate::trajectory::Trajectory;
use crate::transport::Transport;
use crate::vehicle::VehicleSource;

/// What the host runner asks of a personality beyond the core's seam.
pub trait HostPersonality: Personality {
    /// The packet rules of this protocol's output, which the link follows to
    /// count packets (`status frames-sent`, `format=`) and to cut whole ones.
    fn wire() -> crate::link::Wire;

    /// The live value of a parameter (the KERNEL's Table 5.24), for the
    /// monitor's reasons (`-v`); `None` where the protocol has no such
    /// parameters.
    fn param(&self, id: u16) -> Option<&[u8]>;

    /// Sets GPS time: `gps_s` GPS seconds since 1980-01-06 at device
    /// instant 0 (`--gps-time`, or the host clock at power-on); nothing
    /// where the protocol has no GPS.
    fn set_gps_time(&mut self, _gps_s: u64) {}

    /// A navigation fault (`fault gps|mag|baro on|off`); an error where the
    /// protocol has no navigation side.
    fn nav_fault(&mut self, _change: control::NavFault) -> Result<(), String> {
        Err("no GPS, magnetometer or barometer on this protocol (--protocol isb has them)".into())
    }
}

impl HostPersonality for Kernel {
    fn wire() -> crate::link::Wire {
        crate::link::Wire::kernel()
    }

    fn param(&self, id: u16) -> Option<&[u8]> {
        self.param_ram(id)
    }
}

impl HostPersonality for imu_emu::isb::Isb {
    /// ISB packets (the data set ID at byte 3 of the header).
    fn wire() -> crate::link::Wire {
        crate::link::Wire::of::<imu_emu::isb::packet::Isb>(3)
    }

    fn param(&self, _id: u16) -> Option<&[u8]> {
        None
    }

    fn set_gps_time(&mut self, gps_s: u64) {
        Isb::set_gps_time(self, gps_s.saturating_mul(1_000_000_000));
    }

    fn nav_fault(&mut self, change: control::NavFault) -> Result<(), String> {
        let mut f = self.nav().faults();
        match change {
            control::NavFault::Gps(on) => f.gps_off = !on,
            control::NavFault::Mag(on) => f.mag_disturbed = on,
            control::NavFault::Baro(on) => f.baro_failed = on,
        }
        self.set_nav_faults(f);
        Ok(())
    }
}

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
/// `--speed max`: how long after its last input byte the device is not
/// quiet ([`Runner::max_quiet`]): the personalities' RX idle time, after
/// which a frame cut short is abandoned (both 100 ms), and a tick.
const RX_SETTLE_NS: u64 = {
    let k = imu_emu::kernel::RX_IDLE_ABANDON_NS;
    let i = imu_emu::isb::RX_IDLE_ABANDON_NS;
    if k > i {
        k
    } else {
        i
    }
};

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
pub struct Runner<F: NorFlash, T: Transport, P: HostPersonality = Kernel> {
    dev: Device<F, P>,
    sched: Box<Schedule<CHUNK>>,
    io: HostPort<T>,
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

/// What the schedule drives on this board: the transport, the control
/// socket, the `--pps` generator and the trajectory.
struct HostPort<T: Transport> {
    transport: T,
    /// The control socket (`--control`), if any.
    control: Option<Control>,
    /// Next 1PPS edge of the `--pps` generator, ns since the epoch.
    next_pps_ns: Option<u64>,
    /// Motion replayed from a file (`--trajectory`), if any.
    trajectory: Option<Trajectory>,
    /// The vehicle source (`--motion`, `motion script|file`), if any.
    vehicle: Option<VehicleSource>,
    /// The live motion feed's state (`--motion-feed`), if any.
    feed: Option<FeedState>,
    /// The feed's socket, unless the feed is shared by a fleet.
    feed_socket: Option<FeedSocket>,
    /// Faults between the device's UART and the transport (`link …`).
    link: Link,
    /// The device's input decoded on the host side (logs, `status`).
    monitor: Monitor,
    /// Input past the faults that did not fit the device's read yet.
    rx_carry: std::collections::VecDeque<u8>,
    /// Input credit at the line rate (device time): what the device's
    /// UART could have received by now.
    rx_pacer: Pacer,
    /// The last read was bounded by the credit (more input may wait in
    /// the transport, which is not waited on for input meanwhile).
    rx_held: bool,
    /// Deadline of the last tick run, ns, and the tick period: input is
    /// credited up to the schedule's time, never past the next tick (the
    /// clock's `now` runs ahead while ticks are behind, and goes back when
    /// the clock is held back).
    tick_ns: u64,
    period_ns: u64,
    /// Device time of the current pass, ns.
    now_ns: u64,
    /// Bytes the line carried (before link faults).
    line_bytes: u64,
    /// Device time held back so far (copied from the clock), ns.
    held_back_ns: u64,
    /// Reused buffer of what passes the link faults.
    scratch: Vec<u8>,
    /// Events (TOV edges) kept for the owner of a shared control socket
    /// (the many-device mode) instead of sent to `control`.
    events: Option<Vec<String>>,
    /// Prefix of stderr messages naming the device (`dev 3: `), or empty.
    label: String,
    /// The device is in firmware-update mode (BOOT high at power-on): its
    /// input is firmware data, not KERNEL commands, so the monitor does
    /// not decode, log or count it.
    fw_update: bool,
    /// The web view's tap (`--web`), if any: never blocks.
    web: Option<crate::web::Tap>,
    /// Device time the last input byte reached the device, ns.
    last_rx_ns: Option<u64>,
}

impl<T: Transport> HostPort<T> {
    /// Hands what the link let through to the web view's tap and the
    /// transport.
    #[inline]
    fn deliver(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        if let Some(w) = &self.web {
            w.tx(bytes, self.rx_time());
        }
        if bytes.is_empty() {
            Ok(())
        } else {
            self.transport.send(bytes)
        }
    }

    /// Device time input is credited up to: the pass's time, but no later
    /// than the tick after the last one run.
    fn rx_time(&self) -> u64 {
        self.now_ns.min(self.tick_ns.saturating_add(self.period_ns))
    }

    /// Hands the transport what a stall released, if it is over.
    fn release(&mut self) -> anyhow::Result<()> {
        let mut out = Vec::new();
        self.link.release(self.now_ns, &mut out);
        if !out.is_empty() {
            self.transport.send(&out)?;
        }
        Ok(())
    }

    /// `truth`: the vehicle truth in `key=value` words, each key after
    /// `prefix` ([`crate::vehicle::truth_words`]).
    fn truth<F: NorFlash, P: Personality>(&self, dev: &Device<F, P>, prefix: &str) -> String {
        let chain = dev.chain();
        let source = if self.trajectory.is_some() {
            "trajectory"
        } else if let Some(v) = &self.vehicle {
            v.kind()
        } else if self.feed.as_ref().is_some_and(FeedState::drives_vehicle) {
            "feed"
        } else {
            match chain.core_motion() {
                Motion::Static { .. } => "static",
                Motion::ConstantRotation { .. } => "rotation",
                Motion::Vibration { .. } => "vibration",
                Motion::Coning { .. } => "coning",
                Motion::Sample(_) => "sample",
            }
        };
        crate::vehicle::truth_words(&chain.vehicle(), source, chain.temperature(), prefix)
    }

    /// `status`: the device, the line and the link in `key=value` words.
    fn status<F: NorFlash, P: Personality>(&self, dev: &Device<F, P>) -> String {
        use imu_emu::device::Mode;
        let mode = match dev.mode() {
            Mode::Idle => "idle",
            Mode::Aligning => "aligning",
            Mode::Continuous => "continuous",
            Mode::FirmwareUpdate => "firmware-update",
        };
        let format = match (dev.mode(), self.link.last_id()) {
            (Mode::Continuous, Some(id)) => format!("{id:#04x}"),
            _ => "none".to_owned(),
        };
        let rate = dev
            .output_rate()
            .map_or("none".to_owned(), |r| r.to_string());
        let rejected = self.monitor.rejected();
        let total: u64 = rejected.iter().map(|r| r.1).sum();
        let mut s = format!(
            "mode={mode} format={format} output-rate={rate} line-rate={} frames-sent={} \
             bytes-sent={} tx-dropped={} held-back-ms={} commands={} rejected={total}",
            dev.line_rate(),
            self.link.frames_sent(),
            self.line_bytes,
            dev.tx_dropped(),
            self.held_back_ns / 1_000_000,
            self.monitor.commands(),
        );
        for (r, n) in rejected {
            s.push_str(&format!(" rejected-{}={n}", r.name()));
        }
        s.push(' ');
        s.push_str(&self.truth(dev, "truth-"));
        let l = self.link.stats();
        s.push_str(&format!(
            " link={} link-dropped={} link-corrupted={} link-duplicated={} link-noise={} \
             link-cut={} link-stall-dropped={}",
            self.link.describe(self.now_ns),
            l.dropped,
            l.corrupted,
            l.duplicated,
            l.noise,
            l.cut,
            l.stall_dropped
        ));
        if let Some(f) = &self.feed {
            s.push_str(&f.status(self.now_ns));
        }
        s
    }
}

impl<F: NorFlash, T: Transport, P: HostPersonality> Port<F, P> for HostPort<T> {
    type Error = anyhow::Error;

    fn tx_room(&mut self) -> usize {
        // The transport's backlog takes everything the line carries.
        usize::MAX
    }

    fn write(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.line_bytes += bytes.len() as u64;
        if self.link.clean() {
            // No link fault: the bytes go as they are, without a copy.
            self.link.pass(bytes);
            return self.deliver(bytes);
        }
        let mut out = core::mem::take(&mut self.scratch);
        out.clear();
        self.link.tx(bytes, self.now_ns, &mut out);
        let r = self.deliver(&out);
        self.scratch = out;
        r
    }

    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        eprintln!("imu-emu: {}line rate {bps} bit/s", self.label);
        self.rx_pacer.set_rate(bps, self.rx_time());
        self.transport.set_line_rate(bps)
    }

    fn read(&mut self, buf: &mut [u8]) -> anyhow::Result<usize> {
        // No more than the line could have carried by now; in lockstep
        // the simulator owns device time (it stands still between samples,
        // so a command sent before the first one would never arrive): the
        // input goes in as it comes, at the device time of the next pass.
        self.rx_pacer.advance(self.rx_time());
        let limit = if self.feed.as_ref().is_some_and(FeedState::lockstep) {
            buf.len()
        } else {
            buf.len().min(self.rx_pacer.available())
        };
        let buf = &mut buf[..limit];
        // Input the faults made longer than the last read could take first.
        let mut n = self.rx_carry.len().min(buf.len());
        for (b, c) in buf.iter_mut().zip(self.rx_carry.drain(..n)) {
            *b = c;
        }
        // Called even for 0 bytes: the transport also accepts and notices
        // hang-ups there.
        let mut raw = Vec::new();
        self.transport
            .receive(buf.len() - n, &mut |bytes| raw.extend_from_slice(bytes))?;
        if !raw.is_empty() || self.link.rx_noise_pending() {
            let mut got = Vec::with_capacity(raw.len());
            self.link.rx(&raw, &mut got);
            let k = got.len().min(buf.len() - n);
            buf[n..n + k].copy_from_slice(&got[..k]);
            self.rx_carry.extend(&got[k..]);
            n += k;
        }
        self.rx_pacer.consume(n);
        if n > 0 {
            self.last_rx_ns = Some(self.rx_time());
        }
        self.rx_held = n == limit;
        self.transport.hold_input(self.rx_held);
        if !self.fw_update {
            self.monitor.feed(&buf[..n]);
        }
        Ok(n)
    }

    fn tov(&mut self, level: Level, at: Instant) -> anyhow::Result<()> {
        // The host board has no TOV pin: edges go to the control client.
        let l = if level == Level::High { "high" } else { "low" };
        if let Some(events) = self.events.as_mut() {
            events.push(format!("tov {l} {}", at.as_nanos()));
        } else if let Some(ctl) = self.control.as_mut() {
            ctl.event(&format!("tov {l} {}", at.as_nanos()));
        }
        Ok(())
    }

    fn before_tick(&mut self, dev: &mut Device<F, P>, deadline: Instant) -> anyhow::Result<()> {
        let deadline = deadline.as_nanos();
        while let Some(pps) = self.next_pps_ns.filter(|&p| p <= deadline) {
            dev.on_pin(Pin::Pps, Level::High, Instant::from_nanos(pps));
            self.next_pps_ns = Some(pps + 1_000_000_000);
        }
        Ok(())
    }

    #[inline]
    fn tick(&mut self, dev: &mut Device<F, P>, deadline: Instant) -> anyhow::Result<()> {
        let secs = || deadline.as_nanos() as f64 * 1e-9;
        if let Some(t) = self.trajectory.as_mut() {
            let (state, truth) = t.vehicle_at(secs());
            dev.chain_mut().set_vehicle(state, truth);
        } else if let Some(v) = self.vehicle.as_mut() {
            let state = v.at(secs());
            dev.chain_mut().set_vehicle(state, state.truth());
        }
        if let Some(f) = self.feed.as_mut() {
            let (motion, lost) = f.at(deadline.as_nanos());
            match motion {
                Some(crate::feed::FeedMotion::Rates(truth)) => {
                    dev.chain_mut().set_motion(Motion::Sample(truth))
                }
                Some(crate::feed::FeedMotion::Vehicle(state)) => {
                    dev.chain_mut().set_vehicle(state, state.truth())
                }
                None => {}
            }
            dev.chain_mut().faults_mut().motion_feed_lost = lost;
        }
        dev.on_tick(deadline);
        self.tick_ns = deadline.as_nanos();
        self.fw_update = dev.mode() == imu_emu::device::Mode::FirmwareUpdate;
        Ok(())
    }

    fn after_rx(&mut self, dev: &mut Device<F, P>, at: Instant) -> anyhow::Result<()> {
        let product = dev.product();
        self.monitor.judge(&product, &|id| {
            P::param(dev.personality(), id).map(<[u8]>::to_vec)
        });
        if let Some(mut w) = self.web.take() {
            // The page's commands, through the control socket's executor.
            for p in w.commands() {
                p.run(|cmd| self.apply(dev, cmd, at));
            }
            if w.publish_due() {
                // Heading, pitch, roll (deg): the vehicle's when a script,
                // file, trajectory or feed plays (heading in [0, 360) like
                // the built-in motion's), else the built-in motion's.
                let attitude = match dev.chain().vehicle_source() {
                    Some(v) => {
                        let [roll, pitch, yaw] = v.euler_rad().map(f64::to_degrees);
                        Some([yaw.rem_euclid(360.0), pitch, roll].map(|x| x as f32))
                    }
                    None => dev
                        .chain()
                        .truth_attitude()
                        .map(|q| imu_emu::euler_from_quat(&q).map(f32::to_degrees)),
                };
                // Where the unit is (the vehicle's, or the built-in
                // motion's fixed place): the page's position track.
                let v = dev.chain().vehicle();
                let lla = [v.lat_rad.to_degrees(), v.lon_rad.to_degrees(), v.height_m];
                let truth = crate::web::Truth { attitude, lla };
                w.publish(self.status(dev), at.as_nanos(), truth);
            }
            self.web = Some(w);
        }
        let Some(mut ctl) = self.control.take() else {
            return Ok(());
        };
        let r = ctl.poll(&mut |cmd| {
            tracing::debug!("control: {cmd:?}");
            self.apply(dev, cmd, at)
        });
        self.control = Some(ctl);
        r
    }
}

impl<T: Transport> HostPort<T> {
    /// Carries out one control command at device time `at`; the answer
    /// for the control client (`Ok` text after `ok`, `Err` after `error`).
    fn apply<F: NorFlash, P: HostPersonality>(
        &mut self,
        dev: &mut Device<F, P>,
        cmd: control::Command,
        at: Instant,
    ) -> Result<String, String> {
        match cmd {
            control::Command::Edge(pin, level) => dev.on_pin(pin, level, at),
            control::Command::PowerCycle(boot) => {
                dev.power_cycle_with(boot, at);
                if let Some(f) = self.feed.as_mut() {
                    f.new_timeline();
                }
                self.fw_update = dev.mode() == imu_emu::device::Mode::FirmwareUpdate;
                if self.fw_update {
                    tracing::info!(
                        "{}firmware-update mode (BOOT high at power-on): input is not decoded \
                         until the next power cycle",
                        self.label
                    );
                }
            }
            control::Command::Fault(change) => change.apply(dev.chain_mut().faults_mut()),
            control::Command::NavFault(change) => dev.personality_mut().nav_fault(change)?,
            control::Command::Motion(m) => {
                self.trajectory = None;
                self.vehicle = None;
                dev.chain_mut().set_motion(m);
            }
            control::Command::Script(s) => {
                self.trajectory = None;
                let v = VehicleSource::script(*s).starting_at(at.as_nanos() as f64 * 1e-9);
                self.vehicle = Some(v);
            }
            control::Command::MotionFile(path) => {
                let v = VehicleSource::load(&path).map_err(|e| format!("{e:#}"))?;
                self.trajectory = None;
                self.vehicle = Some(v.starting_at(at.as_nanos() as f64 * 1e-9));
            }
            control::Command::Truth => return Ok(self.truth(dev, "")),
            control::Command::Link(change) => {
                let mut noise = Vec::new();
                self.link.apply(change, self.now_ns, &mut noise);
                if !noise.is_empty() {
                    self.transport
                        .send(&noise)
                        .map_err(|e| format!("sending the noise: {e}"))?;
                }
            }
            control::Command::Status => return Ok(self.status(dev)),
            control::Command::Devices => {
                return Ok(control::devices_reply(&[self.transport.describe()]))
            }
            control::Command::Help => {}
        }
        Ok(String::new())
    }
}

impl<F: NorFlash, T: Transport, P: HostPersonality> Runner<F, T, P> {
    /// Wraps a device powered on at `Instant::ZERO` = `epoch`, in real
    /// time ([`Runner::with_speed`] changes that).
    pub fn new(dev: Device<F, P>, transport: T, epoch: std::time::Instant) -> Self {
        let sched = Box::new(Schedule::new(&dev));
        let rx_pacer = Pacer::new(dev.line_rate(), 0);
        let period_ns = sched.period_ns();
        Runner {
            dev,
            sched,
            io: HostPort {
                transport,
                control: None,
                next_pps_ns: None,
                trajectory: None,
                vehicle: None,
                feed: None,
                feed_socket: None,
                link: Link::with_wire(0, P::wire()),
                monitor: Monitor::new(),
                rx_carry: std::collections::VecDeque::new(),
                rx_pacer,
                rx_held: false,
                tick_ns: 0,
                period_ns,
                now_ns: 0,
                line_bytes: 0,
                held_back_ns: 0,
                scratch: Vec::new(),
                events: None,
                label: String::new(),
                fw_update: false,
                web: None,
                last_rx_ns: None,
            },
            clock: Clock::new(epoch, Speed::default()),
            stats: Stats::default(),
            reported_drops: 0,
            reported_held_ns: 0,
            reported_at: None,
            status_at: std::io::IsTerminal::is_terminal(&std::io::stdout())
                .then(std::time::Instant::now),
            pace: None,
            lockstep_target: 0,
        }
    }

    /// Drives the motion from a live feed ([`crate::feed`]): `socket` is
    /// its own (`None`: samples come through [`Runner::feed_offer`], a
    /// fleet's shared feed). In lockstep, device time then moves only
    /// with the samples (at a `--speed` factor, no faster than that
    /// either): call after [`Runner::with_speed`].
    pub fn with_feed(mut self, state: FeedState, socket: Option<FeedSocket>) -> Self {
        if state.lockstep() {
            let epoch = self.clock.epoch();
            self.pace = match self.clock.speed() {
                Speed::Factor(_) => Some(self.clock.clone()),
                Speed::Max => None,
            };
            self.clock = Clock::new(epoch, Speed::Max);
        }
        self.io.feed = Some(state);
        self.io.feed_socket = socket;
        self
    }

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

    /// Replays `t` as the motion the device measures: before each tick the
    /// sample for that tick's time is handed to the signal chain.
    pub fn with_trajectory(mut self, t: Trajectory) -> Self {
        self.io.trajectory = Some(t);
        self
    }

    /// Flies or plays `v` as the unit's vehicle (`--motion`): before each
    /// tick its state at that tick's time is handed to the signal chain.
    pub fn with_vehicle(mut self, v: VehicleSource) -> Self {
        self.io.vehicle = Some(v);
        self
    }

    /// Runs device time at `speed` (`--speed`), from the same epoch.
    pub fn with_speed(mut self, speed: Speed) -> Self {
        self.clock = Clock::new(self.clock.epoch(), speed);
        self
    }

    /// Serves the control socket (pin edges, power cycle, TOV reports).
    pub fn with_control(mut self, control: Control) -> Self {
        self.io.control = Some(control);
        self
    }

    /// Feeds the web view (`--web`): the output, the status and the truth
    /// go to `tap`, and its commands are carried out between passes.
    pub fn with_web(mut self, tap: crate::web::Tap) -> Self {
        self.io.web = Some(tap);
        self
    }

    /// Seeds the link faults' random draws (`--seed`).
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.io.link = Link::with_wire(seed, P::wire());
        self
    }

    /// Generates a 1PPS rising edge at every whole second of device time
    /// (`--pps`; the host clock at `--speed 1`).
    pub fn with_pps(mut self) -> Self {
        self.io.next_pps_ns = Some(1_000_000_000);
        self
    }

    /// Keeps the device's events (TOV edges, as the control socket words
    /// them) for [`Runner::take_events`] instead of sending them to a
    /// control socket of its own, and draws no terminal status line: the
    /// many-device mode ([`crate::fleet`]), whose one control socket
    /// serves every device.
    pub fn shared(mut self) -> Self {
        self.io.events = Some(Vec::new());
        self.status_at = None;
        self
    }

    /// Names the device in the runner's stderr messages (`dev 3: …`).
    pub fn with_label(mut self, label: String) -> Self {
        self.io.label = label;
        self
    }

    /// Carries out a control command now (device time of the last pass):
    /// what the control socket does for a single device, for the owner of
    /// a shared one. The answer is the reply's text (`ok …` / `error …`).
    pub fn control(&mut self, cmd: control::Command) -> Result<String, String> {
        let at = Instant::from_nanos(self.io.now_ns);
        // Bytes a command queued (noise, a power cycle's announcement)
        // leave with the next pass's flush.
        self.io.apply(&mut self.dev, cmd, at)
    }

    /// The events the device raised since the last call ([`Runner::shared`]).
    pub fn take_events(&mut self) -> Vec<String> {
        self.io
            .events
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// The device.
    pub fn device(&self) -> &Device<F, P> {
        &self.dev
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.io.transport
    }

    /// The transport, to wait on it together with others ([`crate::fleet`]).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.io.transport
    }

    /// What the runner counted so far (loss, lag, traffic).
    pub fn stats(&self) -> Stats {
        Stats {
            tx_dropped: self.dev.tx_dropped(),
            held_back_ns: self.clock.held_back_ns(),
            ..self.stats
        }
    }

    /// Gives the device back (e.g. to inspect its flash).
    pub fn into_device(self) -> Device<F, P> {
        self.dev
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
    /// back at the line rate or within [`RX_SETTLE_NS`] of its last byte,
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
                .is_none_or(|t| now > t.saturating_add(RX_SETTLE_NS + self.sched.period_ns()))
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
