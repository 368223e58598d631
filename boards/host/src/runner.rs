//! The loop: one virtual device driven by the wall clock — in real time,
//! scaled, or as fast as possible ([`crate::clock`], `--speed`; every time
//! below is device time, ns since power-on).
//!
//! * **Ticks** run on absolute deadlines `deadline_k = epoch + k × period`
//!   (`period = dev.tick_period_ns()`, k = 1, 2, …), each called with its own
//!   deadline as `now`, so sleep error never accumulates; when the loop is
//!   late it runs every due tick (catching up).
//! * **Output** leaves the device's TX queue only as fast as the emulated
//!   line carries it ([`crate::pacer`]). Before each tick the line is
//!   advanced to that tick's deadline and drained, so a late wakeup catches
//!   up output and ticks in their real order and the device's queue holds
//!   what a real UART's would.
//! * **Input** is fed with `dev.on_rx(bytes, now)` as soon as the transport
//!   wakes the loop (`ppoll`), after the ticks due by then.
//! * **Sleeping**: while bytes are queued the loop wakes every
//!   [`BUSY_WAKE`]; otherwise it sleeps until the deadline of the next tick
//!   that produces output ([`Device::ticks_to_next_output`]), the next
//!   `--pps` edge, or [`IDLE_WAKE`], whichever is first, then runs every
//!   tick due in one batch. UART input wakes it at once.
//! * **`--speed max`**: before each pass device time moves on by
//!   [`MAX_BATCH_TICKS`] ticks unless [`MAX_BACKLOG`] bytes wait for the
//!   client or none is connected; the loop never sleeps then, it only polls the transport (or
//!   waits for the client to read).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, Event, Level, Pin};
use imu_emu::sensor::Motion;
use imu_emu::time::Instant;

use crate::clock::{Clock, Speed, MAX_BACKLOG, MAX_BATCH_TICKS};
use crate::control::{self, Control};
use crate::pacer::Pacer;
use crate::trajectory::Trajectory;
use crate::transport::Transport;

/// Wake interval while the device streams or has output queued.
pub const BUSY_WAKE: Duration = Duration::from_millis(1);
/// Wake interval while the device is idle with nothing queued.
pub const IDLE_WAKE: Duration = Duration::from_millis(10);

/// The board: a device, its line pacer and a transport.
pub struct Runner<F: NorFlash, T: Transport> {
    dev: Device<F>,
    transport: T,
    pacer: Pacer,
    clock: Clock,
    period_ns: u64,
    /// Ticks run so far; the next deadline is `(ticks + 1) × period`.
    ticks: u64,
    buf: Box<[u8; 4096]>,
    /// Device frames dropped (TX queue full) already reported on stderr.
    reported_drops: u32,
    /// When drops were last reported, ns since the epoch.
    reported_at_ns: u64,
    /// The control socket (`--control`), if any.
    control: Option<Control>,
    /// Next 1PPS edge of the `--pps` generator, ns since the epoch.
    next_pps_ns: Option<u64>,
    /// Motion replayed from a file (`--trajectory`), if any.
    trajectory: Option<Trajectory>,
}

impl<F: NorFlash, T: Transport> Runner<F, T> {
    /// Wraps a device powered on at `Instant::ZERO` = `epoch`, in real
    /// time ([`Runner::with_speed`] changes that).
    pub fn new(dev: Device<F>, transport: T, epoch: std::time::Instant) -> Self {
        let pacer = Pacer::new(dev.line_rate(), 0);
        let period_ns = dev.tick_period_ns().max(1);
        Runner {
            dev,
            transport,
            pacer,
            clock: Clock::new(epoch, Speed::default()),
            period_ns,
            ticks: 0,
            buf: Box::new([0; 4096]),
            reported_drops: 0,
            reported_at_ns: 0,
            control: None,
            next_pps_ns: None,
            trajectory: None,
        }
    }

    /// Replays `t` as the motion the device measures: before each tick the
    /// sample for that tick's time is handed to the signal chain.
    pub fn with_trajectory(mut self, t: Trajectory) -> Self {
        self.trajectory = Some(t);
        self
    }

    /// Runs device time at `speed` (`--speed`), from the same epoch.
    pub fn with_speed(mut self, speed: Speed) -> Self {
        self.clock = Clock::new(self.clock.epoch(), speed);
        self
    }

    /// Serves the control socket (pin edges, power cycle, TOV reports).
    pub fn with_control(mut self, control: Control) -> Self {
        self.control = Some(control);
        self
    }

    /// Generates a 1PPS rising edge at every whole second of device time
    /// (`--pps`; the host clock at `--speed 1`).
    pub fn with_pps(mut self) -> Self {
        self.next_pps_ns = Some(1_000_000_000);
        self
    }

    /// The device.
    pub fn device(&self) -> &Device<F> {
        &self.dev
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// Gives the device back (e.g. to inspect its flash).
    pub fn into_device(self) -> Device<F> {
        self.dev
    }

    /// Device time now, ns since power-on.
    fn now_ns(&self) -> u64 {
        self.clock.now_ns()
    }

    fn next_deadline(&self) -> u64 {
        (self.ticks + 1).saturating_mul(self.period_ns)
    }

    /// Runs until `stop` is set (by SIGINT/SIGTERM).
    pub fn run(&mut self, stop: &AtomicBool) -> anyhow::Result<()> {
        while !stop.load(Ordering::Relaxed) {
            let max = self.clock.speed() == Speed::Max;
            // Nobody to read (output would be dropped): time waits.
            let client_keeps_up =
                self.transport.connected() && self.transport.backlog_len() < MAX_BACKLOG;
            if max && client_keeps_up {
                let to = (self.ticks + MAX_BATCH_TICKS).saturating_mul(self.period_ns);
                self.clock.advance_to(to);
            }
            self.step()?;
            let now = self.now_ns();
            self.report_drops(now);
            let timeout = if max {
                // Poll only, or wait (briefly) for the client to read.
                if self.transport.connected() && self.transport.backlog_len() < MAX_BACKLOG {
                    Duration::ZERO
                } else {
                    BUSY_WAKE
                }
            } else {
                self.clock
                    .host_wait(self.next_wake(now).saturating_sub(now))
            };
            self.transport.wait(timeout)?;
        }
        Ok(())
    }

    /// When to wake next, ns since the epoch: while output is queued,
    /// [`BUSY_WAKE`] from now (the pacer hands it out as the line allows);
    /// otherwise at the deadline of the next tick that produces output, the
    /// next `--pps` edge or [`IDLE_WAKE`] from now, whichever comes first —
    /// never before the next tick deadline, so ticks run in batches on the
    /// absolute schedule.
    fn next_wake(&self, now: u64) -> u64 {
        let busy_until = now.saturating_add(BUSY_WAKE.as_nanos() as u64);
        let idle_until = now.saturating_add(IDLE_WAKE.as_nanos() as u64);
        let mut wake = if self.dev.tx_len() > 0 || self.transport.backlog_len() > 0 {
            busy_until
        } else {
            match self.dev.ticks_to_next_output() {
                Some(k) => (self.ticks + k)
                    .saturating_mul(self.period_ns)
                    .min(idle_until),
                None => idle_until,
            }
        };
        if let Some(pps) = self.next_pps_ns {
            wake = wake.min(pps);
        }
        wake.max(self.next_deadline())
    }

    /// Tells stderr, at most once a second, that the device dropped frames
    /// because its TX queue overflowed (the line is too slow for the
    /// output, e.g. after a catch-up or with EXTRIG bursts).
    fn report_drops(&mut self, now_ns: u64) {
        let dropped = self.dev.tx_dropped();
        if dropped != self.reported_drops && now_ns >= self.reported_at_ns + 1_000_000_000 {
            eprintln!(
                "imu-emu: device TX queue overflowed: {} frames dropped so far",
                dropped
            );
            self.reported_drops = dropped;
            self.reported_at_ns = now_ns;
        }
    }

    /// One pass: due ticks (with output paced up to each), output up to
    /// now, input, output again.
    pub fn step(&mut self) -> anyhow::Result<()> {
        let now = self.now_ns();
        while self.next_deadline() <= now {
            let deadline = self.next_deadline();
            while let Some(pps) = self.next_pps_ns.filter(|&p| p <= deadline) {
                self.dev
                    .on_pin(Pin::Pps, Level::High, Instant::from_nanos(pps));
                self.next_pps_ns = Some(pps + 1_000_000_000);
            }
            self.pump_tx(deadline)?;
            if let Some(t) = self.trajectory.as_mut() {
                let truth = t.at(deadline as f64 * 1e-9);
                self.dev.chain_mut().set_motion(Motion::Sample(truth));
            }
            self.dev.on_tick(Instant::from_nanos(deadline));
            self.ticks += 1;
        }
        self.pump_tx(now)?;

        let t = Instant::from_nanos(now);
        let dev = &mut self.dev;
        self.transport.receive(&mut |bytes| dev.on_rx(bytes, t))?;
        if let Some(ctl) = self.control.as_mut() {
            let dev = &mut self.dev;
            ctl.poll(&mut |cmd| {
                match cmd {
                    control::Command::Edge(pin, level) => dev.on_pin(pin, level, t),
                    control::Command::PowerCycle(boot) => dev.power_cycle_with(boot, t),
                    control::Command::Fault(change) => change.apply(dev.chain_mut().faults_mut()),
                    control::Command::Motion(m) => dev.chain_mut().set_motion(m),
                }
                Ok(())
            })?;
        }
        self.pump_tx(now)?;
        self.transport.flush()
    }

    /// Moves bytes the line can carry by `at_ns` from the device to the
    /// transport, then acts on device events.
    fn pump_tx(&mut self, at_ns: u64) -> anyhow::Result<()> {
        self.pacer.advance(at_ns);
        loop {
            let room = self.pacer.available().min(self.buf.len());
            if room == 0 {
                break;
            }
            let n = self.dev.poll_tx(&mut self.buf[..room]);
            if n == 0 {
                break;
            }
            self.pacer.consume(n);
            self.transport.send(&self.buf[..n])?;
            // A line-rate switch restarts the credit: the bytes after it go
            // at the new rate.
            self.handle_events(at_ns)?;
        }
        self.handle_events(at_ns)
    }

    /// Acts on pending device events.
    fn handle_events(&mut self, at_ns: u64) -> anyhow::Result<()> {
        while let Some(ev) = self.dev.poll_event() {
            match ev {
                Event::LineRate(bps) => {
                    eprintln!("imu-emu: line rate {bps} bit/s");
                    self.pacer.set_rate(bps, at_ns);
                    self.transport.set_line_rate(bps)?;
                }
                // The host board has no TOV pin: edges go to the control
                // client, if any.
                Event::Tov { level, at } => {
                    if let Some(ctl) = self.control.as_mut() {
                        let l = if level == Level::High { "high" } else { "low" };
                        ctl.say(&format!("tov {l} {}\n", at.as_nanos()));
                    }
                }
            }
        }
        Ok(())
    }
}
