//! The tick/pump schedule every board runs: one piece of code for the host
//! runner and the firmware shell, sans-IO like the rest of the core (the
//! board passes its time in and lends its UART and pins through a [`Port`]).
//!
//! One [`Schedule::poll`] (a *pass*), at device time `now` (ns since
//! power-on):
//!
//! 1. **Ticks** on absolute deadlines `deadline_k = k × period`
//!    ([`Device::tick_period_ns`], k = 1, 2, …), each run with its own
//!    deadline as its time, so a late pass never shifts the schedule: every
//!    tick due by `now` (plus [`Limits::early_ns`]) runs, in order, at most
//!    [`Limits::max_ticks`] per pass (the rest run in the next passes).
//!    Before each tick: [`Port::before_tick`] (pin edges, motion stamped up
//!    to the deadline), then the line is advanced to the deadline and the
//!    device's TX queue drained within the line credit ([`Pacer`]). So a
//!    catch-up runs ticks *and* the line in their real order: every tick
//!    finds the TX queue as a real UART would have left it, and no tick
//!    runs without the line time that came before it.
//! 2. **The schedule's time** is `now` once every due tick ran; while ticks
//!    are still due (the pass cap was hit) it is the deadline of the last
//!    tick run: the line does not run ahead of the ticks still waiting.
//! 3. **Input**: at most [`Limits::max_rx`] bytes from [`Port::read`] go to
//!    [`Device::on_rx`] at the schedule's time (a flood never starves the
//!    ticks), then [`Port::after_rx`].
//! 4. **Output** up to the schedule's time, then events: a line-rate switch
//!    ([`Event::LineRate`]) takes effect once the bytes queued before it
//!    were handed out and [`Port::tx_idle`] says they left the wire; the
//!    credit restarts at the new rate. TOV edges go to [`Port::tov`].
//!
//! [`Schedule::poll_at`] says when the next pass has something to do
//! (smoltcp's `poll_at`): the deadline of the next tick that produces
//! output ([`Device::ticks_to_next_output`]), or the time the line can
//! carry what is queued, whichever is first. A board may sleep until then
//! (ticks in between change nothing visible and are run late, in order).
//!
//! Loss is never silent: a frame that does not fit the device's TX queue is
//! dropped whole and counted ([`Device::tx_dropped`]); the line never
//! carries part of a frame.

use embedded_storage::nor_flash::NorFlash;

use crate::device::{Device, Event, Level};
use crate::line::Pacer;
use crate::time::Instant;

/// What the board lends the schedule: its UART and pins. Every method must
/// return at once (never block).
pub trait Port<F: NorFlash> {
    /// What the board's I/O can fail with (`Infallible` on an MCU).
    type Error;

    /// Bytes [`Port::write`] accepts now (UART FIFO or buffer space).
    fn tx_room(&mut self) -> usize;
    /// Hands device output to the UART; `bytes.len() <= tx_room()`.
    fn write(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
    /// Whether everything written so far has left the wire, so the line
    /// rate can change without corrupting a byte.
    fn tx_idle(&mut self) -> bool {
        true
    }
    /// Switches the UART to `bps` bit/s (only while [`Port::tx_idle`]).
    fn set_line_rate(&mut self, bps: u32) -> Result<(), Self::Error>;
    /// Moves received bytes into `buf`; how many (0: none waiting).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;
    /// The device asks for a TOV edge (ICD 4.1.4) at `at` (may be ahead).
    fn tov(&mut self, _level: Level, _at: Instant) -> Result<(), Self::Error> {
        Ok(())
    }
    /// Right before the tick at `deadline`: hand the device the pin edges
    /// stamped up to it.
    fn before_tick(&mut self, _dev: &mut Device<F>, _deadline: Instant) -> Result<(), Self::Error> {
        Ok(())
    }
    /// Runs the tick: [`Device::on_tick`] (a board may set the motion for
    /// the tick first, or time the call).
    fn tick(&mut self, dev: &mut Device<F>, deadline: Instant) -> Result<(), Self::Error> {
        dev.on_tick(deadline);
        Ok(())
    }
    /// After the received bytes were executed at `at`, before any reply is
    /// handed to the UART (persist the flash, serve other inputs at `at`).
    fn after_rx(&mut self, _dev: &mut Device<F>, _at: Instant) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// How much one [`Schedule::poll`] may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Most ticks one pass runs (catching up after a stall).
    pub max_ticks: u32,
    /// Most received bytes one pass takes from [`Port::read`].
    pub max_rx: usize,
    /// A tick whose deadline is at most this far ahead of `now` runs now
    /// (a timer interrupt derived from the same clock may fire early).
    pub early_ns: u64,
}

/// What one [`Schedule::poll`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Pass {
    /// Ticks run.
    pub ticks: u32,
    /// Bytes received and fed to the device.
    pub rx: usize,
    /// Bytes handed to the UART.
    pub tx: usize,
    /// Ticks are still due: the pass hit [`Limits::max_ticks`].
    pub behind: bool,
}

/// The schedule's state: the tick count, the line credit, a line-rate
/// switch waiting for the UART, and an `N`-byte buffer that bytes cross
/// between the UART and the device in.
#[derive(Debug, Clone)]
pub struct Schedule<const N: usize> {
    period_ns: u64,
    /// Ticks run since power-on; the next deadline is `(ticks + 1) × period`.
    ticks: u64,
    pacer: Pacer,
    /// A line-rate switch waiting for [`Port::tx_idle`].
    pending_rate: Option<u32>,
    /// Device time the schedule has reached (see the module docs).
    time: u64,
    buf: [u8; N],
}

impl<const N: usize> Schedule<N> {
    /// The schedule of a device just powered on (time 0): its tick period
    /// and line rate.
    pub fn new<F: NorFlash>(dev: &Device<F>) -> Self {
        Schedule {
            period_ns: dev.tick_period_ns().max(1),
            ticks: 0,
            pacer: Pacer::new(dev.line_rate(), 0),
            pending_rate: None,
            time: 0,
            buf: [0; N],
        }
    }

    /// Starts again from time 0 after a power cycle of `dev` (in place:
    /// the buffer is not rebuilt on the stack). The line keeps the rate the
    /// UART runs at: the device's power-on [`Event::LineRate`] switches it
    /// if the device came up at another rate.
    pub fn restart<F: NorFlash>(&mut self, dev: &Device<F>) {
        self.period_ns = dev.tick_period_ns().max(1);
        self.ticks = 0;
        self.pacer = Pacer::new(self.pacer.rate(), 0);
        self.pending_rate = None;
        self.time = 0;
    }

    /// Tick period, ns.
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// Ticks run since power-on.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// Deadline of the next tick, ns.
    pub fn next_deadline(&self) -> u64 {
        (self.ticks + 1).saturating_mul(self.period_ns)
    }

    /// Device time the schedule has reached: the last pass's `now`, or the
    /// deadline of the last tick run while ticks are still due.
    pub fn time(&self) -> u64 {
        self.time
    }

    /// How far device time `now` is ahead of the last tick run while ticks
    /// are due (0 when caught up): the backlog a board may cap.
    pub fn lag(&self, now: u64) -> u64 {
        if self.next_deadline() <= now {
            now - self.ticks.saturating_mul(self.period_ns)
        } else {
            0
        }
    }

    /// The line rate the line runs at, bit/s.
    pub fn line_rate(&self) -> u32 {
        self.pacer.rate()
    }

    /// One pass at device time `now` (see the module docs).
    pub fn poll<F: NorFlash, P: Port<F>>(
        &mut self,
        dev: &mut Device<F>,
        port: &mut P,
        now: u64,
        limits: &Limits,
    ) -> Result<Pass, P::Error> {
        let mut pass = Pass::default();
        let early = now.saturating_add(limits.early_ns);
        while pass.ticks < limits.max_ticks && self.next_deadline() <= early {
            let deadline = self.next_deadline();
            let at = Instant::from_nanos(deadline);
            port.before_tick(dev, at)?;
            pass.tx += self.pump(dev, port, deadline)?;
            port.tick(dev, at)?;
            self.ticks += 1;
            pass.ticks += 1;
        }
        pass.behind = self.next_deadline() <= now;
        let t = if pass.behind {
            self.ticks.saturating_mul(self.period_ns)
        } else {
            now
        };
        self.time = self.time.max(t);
        let at = Instant::from_nanos(self.time);

        while pass.rx < limits.max_rx {
            let room = (limits.max_rx - pass.rx).min(N);
            let n = port.read(&mut self.buf[..room])?.min(room);
            if n == 0 {
                break;
            }
            dev.on_rx(&self.buf[..n], at);
            pass.rx += n;
        }
        port.after_rx(dev, at)?;
        pass.tx += self.pump(dev, port, self.time)?;
        Ok(pass)
    }

    /// When the next pass has something to do, device time ns (`now` if
    /// at once), or `None` when nothing is scheduled (idle, nothing
    /// queued): the board then wakes for input, pins or its own reasons.
    pub fn poll_at<F: NorFlash>(&self, dev: &Device<F>, now: u64) -> Option<u64> {
        let next = self.next_deadline();
        if next <= now {
            return Some(now);
        }
        let mut at = dev
            .ticks_to_next_output()
            .map(|k| (self.ticks + k.max(1)).saturating_mul(self.period_ns));
        let queued = dev.tx_len();
        if queued > 0 {
            let line = self.pacer.ready_at(queued).max(now);
            at = Some(at.map_or(line, |a| a.min(line)));
        }
        if self.pending_rate.is_some() {
            at = Some(at.map_or(next, |a| a.min(next)));
        }
        at
    }

    /// Acts on the device's pending events (after a power cycle, a pin
    /// edge, …): a line-rate switch is kept for the next pump, TOV edges go
    /// to [`Port::tov`]; whether a line-rate switch came.
    pub fn events<F: NorFlash, P: Port<F>>(
        &mut self,
        dev: &mut Device<F>,
        port: &mut P,
    ) -> Result<bool, P::Error> {
        let mut switched = false;
        while let Some(ev) = dev.poll_event() {
            match ev {
                Event::LineRate(bps) => {
                    if bps != self.pacer.rate() || self.pending_rate.is_some() {
                        self.pending_rate = Some(bps);
                    }
                    switched = true;
                }
                Event::Tov { level, at } => port.tov(level, at)?,
            }
        }
        Ok(switched)
    }

    /// Advances the line to `at` and moves what it can carry from the
    /// device to the UART; bytes moved.
    fn pump<F: NorFlash, P: Port<F>>(
        &mut self,
        dev: &mut Device<F>,
        port: &mut P,
        at: u64,
    ) -> Result<usize, P::Error> {
        self.pacer.advance(at);
        let mut sent = 0;
        loop {
            self.events(dev, port)?;
            if let Some(rate) = self.pending_rate {
                if !port.tx_idle() {
                    break;
                }
                port.set_line_rate(rate)?;
                self.pacer.set_rate(rate, at);
                self.pending_rate = None;
            }
            let room = self.pacer.available().min(port.tx_room()).min(N);
            if room == 0 {
                break;
            }
            let n = dev.poll_tx(&mut self.buf[..room]);
            if n == 0 {
                // The queue is empty or stops at a line-rate switch, which
                // the events hand out: then go on at the new rate.
                if self.events(dev, port)? {
                    continue;
                }
                break;
            }
            port.write(&self.buf[..n])?;
            self.pacer.consume(n);
            sent += n;
        }
        Ok(sent)
    }
}
