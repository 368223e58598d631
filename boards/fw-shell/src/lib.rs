//! # fw-shell — what every MCU board does the same way
//!
//! The emulator core ([`imu_emu::device::Device`]) is sans-IO. This crate is
//! the firmware half every board shares, generic over a few small traits the
//! board implements:
//!
//! | trait | the board provides |
//! |---|---|
//! | [`Clock`] | a free-running monotonic timestamp in ns |
//! | [`Uart`] | non-blocking RX drain, TX room/write, TX-idle query, baud set |
//! | [`TovPin`] | the TOV output pin |
//! | [`EdgeSource`] | 1PPS/EXTRIG edges timestamped in the board's ISR or capture unit |
//! | `NorFlash` | the flash the parameter store lives in (2 sectors at offset 0) |
//!
//! The board calls [`Shell::service`] from its tick interrupt (the highest
//! priority, 2 kHz; 4 kHz on the K201, [`Shell::tick_hz`]). One call is one
//! pass of the core's tick/pump schedule ([`imu_emu::schedule`], the same
//! code the host runner runs), with this crate's traits as its
//! [`imu_emu::schedule::Port`]:
//!
//! 1. runs every tick that is due on the absolute schedule
//!    `deadline_k = epoch + k × period` (a late interrupt catches up, capped
//!    at [`MAX_CATCH_UP`] per call), each with its own deadline as `now`;
//!    before each tick it delivers the pin edges stamped at or before that
//!    deadline and moves the bytes the line carried by then — while ticks
//!    are still due the line never runs ahead of them, so a catch-up after
//!    a stall loses no frame the line had time for;
//! 2. feeds at most [`MAX_RX`] bytes the UART received into `on_rx`;
//! 3. drains `poll_tx` into the UART at the line rate
//!    ([`imu_emu::Pacer`]): bytes allowed = elapsed × `line_rate()/10`
//!    with a fractional accumulator, never more than the UART's room, never
//!    blocking;
//! 4. acts on events: `LineRate` → the UART switches once everything before
//!    it has left the wire ([`Uart::tx_idle`]); `Tov` → the pin edge is
//!    applied at its time (at the first service at or after it).
//!
//! The device is owned by the tick alone: interrupts that receive bytes or
//! stamp edges only push into lock-free SPSC queues that the tick drains, so
//! nothing the tick needs is ever locked by a lower priority.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod feed;
pub mod image;
#[cfg(feature = "defmt")]
pub mod panic;

use core::mem::MaybeUninit;

use embedded_storage::nor_flash::NorFlash;
use heapless::Deque;
pub use imu_emu;
use imu_emu::device::{Device, Level, Pin, PowerOn};
use imu_emu::personality::Personality;
use imu_emu::schedule::{Limits, Port, Schedule};
use imu_emu::time::Instant;

/// Most ticks one [`Shell::service`] call runs (catching up after a stall,
/// e.g. a flash erase); the rest run on the next calls.
pub const MAX_CATCH_UP: u32 = 16;
/// A tick whose deadline is at most this fraction of a period in the future
/// is run now: interrupts derived from the same clock may fire a few ns
/// early.
pub const EARLY_SLACK_DIV: u64 = 8;
/// Most received bytes one [`Shell::service`] call feeds to the device
/// (2.5 tick periods of a 2 Mbit/s line): a flood never starves the tick.
pub const MAX_RX: usize = 256;
/// Bytes moved per UART read/write chunk.
const CHUNK: usize = 128;

/// A free-running monotonic clock.
pub trait Clock {
    /// Now, in ns since an arbitrary epoch (the shell takes its own epoch at
    /// power-on). Must never go back; called from the tick only.
    fn now(&mut self) -> Instant;
}

/// The UART carrying the device's protocol. Every method is non-blocking.
pub trait Uart {
    /// Moves received bytes into `buf`; how many.
    fn read(&mut self, buf: &mut [u8]) -> usize;
    /// Bytes [`Uart::write`] accepts now (FIFO space, free DMA buffer…).
    fn tx_room(&mut self) -> usize;
    /// Queues `bytes` for transmission; `bytes.len() <= tx_room()`.
    fn write(&mut self, bytes: &[u8]);
    /// Whether everything written so far has left the wire (shift register
    /// empty), so the baud rate can change without corrupting a byte.
    fn tx_idle(&mut self) -> bool;
    /// Sets the line rate in bit/s (called only while [`Uart::tx_idle`]).
    fn set_baud(&mut self, bps: u32);
}

/// The TOV output (ICD 4.1.4).
pub trait TovPin {
    /// Drives the pin.
    fn set(&mut self, level: Level);
}

/// A board without a TOV pin.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoTov;
impl TovPin for NoTov {
    fn set(&mut self, _level: Level) {}
}

/// An input edge on 1PPS or EXTRIG, stamped by the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// Which pin.
    pub pin: Pin,
    /// The level after the edge.
    pub level: Level,
    /// When, on the [`Clock`]'s time base.
    pub at: Instant,
}

/// Where the shell takes pin edges from (in time order).
pub trait EdgeSource {
    /// The oldest edge not taken yet.
    fn pop(&mut self) -> Option<Edge>;
}

/// The consumer end of an SPSC queue filled by the board's pin ISR.
impl EdgeSource for heapless::spsc::Consumer<'_, Edge> {
    fn pop(&mut self) -> Option<Edge> {
        self.dequeue()
    }
}

/// A board without pin inputs.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoEdges;
impl EdgeSource for NoEdges {
    fn pop(&mut self) -> Option<Edge> {
        None
    }
}

/// The BOOT input sampled at reset, as [`PowerOn::boot`] wants it:
/// `None` when the board cannot tell (floating or not wired).
pub fn boot_level(high: Option<bool>) -> Option<Level> {
    high.map(|h| if h { Level::High } else { Level::Low })
}

/// Timing figures of the tick service, in ns of the board's clock.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Stats {
    /// Ticks run since the last reset.
    pub ticks: u64,
    /// [`Shell::service`] calls since the last reset.
    pub services: u64,
    /// Longest `Device::on_tick` call.
    pub max_on_tick_ns: u64,
    /// Longest tick: the edges due, the TX pump up to its deadline and
    /// `on_tick` (in a catch-up batch, each tick counts alone).
    pub max_tick_ns: u64,
    /// Longest whole [`Shell::service`] call that ran one tick (or none)
    /// and no `on_rx` with bytes: the steady-state cost of the tick
    /// interrupt (tick, RX drain, TX pump, events).
    pub max_service_ns: u64,
    /// Longest [`Shell::service`] call that caught up several ticks.
    pub max_batch_service_ns: u64,
    /// Longest [`Shell::service`] call including received commands (a
    /// SaveFlash writes flash here).
    pub max_service_rx_ns: u64,
    /// Most ticks one call had to run (1 = never late).
    pub max_batch: u32,
    /// Bytes handed to the UART.
    pub tx_bytes: u64,
    /// Bytes received.
    pub rx_bytes: u64,
}

/// The firmware shell: a device and the board's peripherals.
///
/// The device is borrowed, not owned: it is ~12 KiB, and a board builds it
/// in place in a static of its own ([`power_on`]) so power-on does not need
/// copies of it on the stack.
///
/// `P` is the device's protocol personality ([`Personality`]; ARCHITECTURE.md
/// "Shell and personalities"), e.g. [`imu_emu::kernel::Kernel`] or
/// [`imu_emu::isb::Isb`], with no default. One image carries one
/// personality ([`image::Proto`] chooses it for the MCU boards).
pub struct Shell<'d, F: NorFlash, U: Uart, C: Clock, T: TovPin, E: EdgeSource, P: Personality> {
    dev: &'d mut Device<F, P>,
    sched: Schedule<CHUNK>,
    io: Io<U, C, T, E>,
}

/// The board's peripherals as the schedule's [`Port`].
struct Io<U, C, T, E> {
    uart: U,
    clock: C,
    tov: T,
    edges: E,
    /// Next edge taken from `edges`, waiting for its tick.
    lookahead: Option<Edge>,
    /// Clock reading at power-on: the device's `Instant::ZERO`.
    epoch: u64,
    /// TOV edges waiting for their time.
    tov_queue: Deque<(Level, Instant), 8>,
    stats: Stats,
    /// Device time the current service call started at.
    service_start: u64,
    /// Ticks run so far in the current service call.
    batch: u32,
    /// When the current tick started (its edges, TX pump and `on_tick`).
    tick_start: u64,
}

impl<U: Uart, C: Clock, T: TovPin, E: EdgeSource> Io<U, C, T, E> {
    /// Device time now (ns since power-on).
    fn now(&mut self) -> u64 {
        self.clock.now().as_nanos().saturating_sub(self.epoch)
    }

    /// Delivers the edges stamped at or before `until` (device time).
    fn deliver_edges<F: NorFlash, P: Personality>(&mut self, dev: &mut Device<F, P>, until: u64) {
        loop {
            let edge = match self.lookahead.take().or_else(|| self.edges.pop()) {
                Some(e) => e,
                None => return,
            };
            let at = edge.at.as_nanos().saturating_sub(self.epoch);
            if at > until {
                self.lookahead = Some(edge);
                return;
            }
            dev.on_pin(edge.pin, edge.level, Instant::from_nanos(at));
        }
    }

    /// Drives the TOV edges whose time has come.
    fn apply_tov(&mut self, now: u64) {
        while let Some(&(level, when)) = self.tov_queue.front() {
            if when.as_nanos() > now {
                break;
            }
            self.tov.set(level);
            self.tov_queue.pop_front();
        }
    }
}

impl<F: NorFlash, P: Personality, U: Uart, C: Clock, T: TovPin, E: EdgeSource> Port<F, P>
    for Io<U, C, T, E>
{
    type Error = core::convert::Infallible;

    fn tx_room(&mut self) -> usize {
        self.uart.tx_room()
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        self.uart.write(bytes);
        Ok(())
    }

    fn tx_idle(&mut self) -> bool {
        self.uart.tx_idle()
    }

    fn set_line_rate(&mut self, bps: u32) -> Result<(), Self::Error> {
        self.uart.set_baud(bps);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        Ok(self.uart.read(buf))
    }

    fn tov(&mut self, level: Level, at: Instant) -> Result<(), Self::Error> {
        if self.tov_queue.is_full() {
            // Too many frames in flight to keep every edge: drop the
            // oldest pair's edge.
            self.tov_queue.pop_front();
        }
        // Applied from the next tick on (and at the end of the service).
        let _ = self.tov_queue.push_back((level, at));
        Ok(())
    }

    fn before_tick(
        &mut self,
        dev: &mut Device<F, P>,
        deadline: Instant,
    ) -> Result<(), Self::Error> {
        self.tick_start = if self.batch == 0 {
            self.service_start
        } else {
            self.now()
        };
        self.deliver_edges(dev, deadline.as_nanos());
        self.apply_tov(deadline.as_nanos());
        Ok(())
    }

    fn tick(&mut self, dev: &mut Device<F, P>, deadline: Instant) -> Result<(), Self::Error> {
        let a = self.now();
        dev.on_tick(deadline);
        let b = self.now();
        let s = &mut self.stats;
        s.max_on_tick_ns = s.max_on_tick_ns.max(b - a);
        s.max_tick_ns = s.max_tick_ns.max(b.saturating_sub(self.tick_start));
        self.batch += 1;
        Ok(())
    }

    fn after_rx(&mut self, dev: &mut Device<F, P>, at: Instant) -> Result<(), Self::Error> {
        self.deliver_edges(dev, at.as_nanos());
        Ok(())
    }
}

/// [`Io`] with a one-shot hook run right after the received bytes.
struct Hooked<'a, IO, H> {
    io: &'a mut IO,
    after_rx: Option<H>,
}

impl<F, P, U, C, T, E, H> Port<F, P> for Hooked<'_, Io<U, C, T, E>, H>
where
    F: NorFlash,
    P: Personality,
    U: Uart,
    C: Clock,
    T: TovPin,
    E: EdgeSource,
    H: FnOnce(&mut Device<F, P>),
{
    type Error = core::convert::Infallible;

    fn tx_room(&mut self) -> usize {
        Port::<F, P>::tx_room(self.io)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        Port::<F, P>::write(self.io, bytes)
    }
    fn tx_idle(&mut self) -> bool {
        Port::<F, P>::tx_idle(self.io)
    }
    fn set_line_rate(&mut self, bps: u32) -> Result<(), Self::Error> {
        Port::<F, P>::set_line_rate(self.io, bps)
    }
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        Port::<F, P>::read(self.io, buf)
    }
    fn tov(&mut self, level: Level, at: Instant) -> Result<(), Self::Error> {
        Port::<F, P>::tov(self.io, level, at)
    }
    fn before_tick(
        &mut self,
        dev: &mut Device<F, P>,
        deadline: Instant,
    ) -> Result<(), Self::Error> {
        self.io.before_tick(dev, deadline)
    }
    fn tick(&mut self, dev: &mut Device<F, P>, deadline: Instant) -> Result<(), Self::Error> {
        self.io.tick(dev, deadline)
    }
    fn after_rx(&mut self, dev: &mut Device<F, P>, at: Instant) -> Result<(), Self::Error> {
        if let Some(hook) = self.after_rx.take() {
            hook(dev);
        }
        self.io.after_rx(dev, at)
    }
}

/// Powers a device on at `Instant::ZERO` (parameters from `flash`, BOOT
/// from `cfg`) straight into `slot` (the board's static), right before
/// [`Shell::new`]. The device is built in place
/// ([`Device::power_on_into`]): power-on needs a few hundred bytes of
/// stack, not copies of the ~12 KiB device. Never inlined, so its frame is
/// gone when the board's init goes on.
///
/// Generic over the personality: `fw_shell::power_on::<_, Isb>(…)` (or a
/// slot typed `MaybeUninit<Device<F, Isb>>`) powers an ISB device on.
#[inline(never)]
pub fn power_on<F: NorFlash, P: Personality>(
    slot: &mut MaybeUninit<Device<F, P>>,
    cfg: PowerOn,
    flash: F,
) -> &mut Device<F, P> {
    Device::new_into(slot, cfg, flash, Instant::ZERO)
}

impl<'d, F: NorFlash, U: Uart, C: Clock, T: TovPin, E: EdgeSource, P: Personality>
    Shell<'d, F, U, C, T, E, P>
{
    /// Takes a device just powered on ([`power_on`]; its `Instant::ZERO` is
    /// now) and the board's peripherals. The UART is set to the device's
    /// line rate at once.
    pub fn new(dev: &'d mut Device<F, P>, uart: U, mut clock: C, tov: T, edges: E) -> Self {
        let epoch = clock.now().as_nanos();
        let rate = dev.line_rate();
        let sched = Schedule::new(dev);
        let mut shell = Shell {
            dev,
            sched,
            io: Io {
                uart,
                clock,
                tov,
                edges,
                lookahead: None,
                epoch,
                tov_queue: Deque::new(),
                stats: Stats::default(),
                service_start: 0,
                batch: 0,
                tick_start: 0,
            },
        };
        shell.io.tov.set(Level::Low);
        shell.io.uart.set_baud(rate);
        let _ = shell.sched.events(shell.dev, &mut shell.io);
        shell
    }

    /// Power cycle (e.g. a board reset request): RAM reloads from flash,
    /// queues empty, the schedule restarts. Never inlined: rebuilding the
    /// device's state takes a deep stack frame the tick interrupt must not
    /// reserve on every tick.
    #[inline(never)]
    #[cold]
    pub fn power_cycle(&mut self, boot: Option<Level>) {
        self.io.epoch = self.io.clock.now().as_nanos();
        self.dev.power_cycle_with(boot, Instant::ZERO);
        self.sched.restart(self.dev);
        self.io.lookahead = None;
        while self.io.edges.pop().is_some() {}
        self.io.tov_queue.clear();
        self.io.tov.set(Level::Low);
        let _ = self.sched.events(self.dev, &mut self.io);
    }

    /// Rate at which [`Shell::service`] should be called, Hz (the internal
    /// rate: 2000, 4000 on the K201). Calling it faster is harmless.
    pub fn tick_hz(&self) -> u32 {
        (1_000_000_000 / self.sched.period_ns()) as u32
    }

    /// Tick period, ns.
    pub fn tick_period_ns(&self) -> u64 {
        self.sched.period_ns()
    }

    /// The device.
    pub fn device(&self) -> &Device<F, P> {
        self.dev
    }

    /// The device, mutably.
    pub fn device_mut(&mut self) -> &mut Device<F, P> {
        self.dev
    }

    /// The UART.
    pub fn uart_mut(&mut self) -> &mut U {
        &mut self.io.uart
    }

    /// The clock.
    pub fn clock_mut(&mut self) -> &mut C {
        &mut self.io.clock
    }

    /// Timing figures so far.
    pub fn stats(&self) -> Stats {
        self.io.stats
    }

    /// Forgets the timing figures.
    pub fn reset_stats(&mut self) {
        self.io.stats = Stats::default();
    }

    /// Device time now (ns since power-on).
    pub fn now(&mut self) -> u64 {
        self.io.now()
    }

    /// Takes what the feed UART received ([`feed`]; at most
    /// [`feed::MAX_FEED_BYTES`]) and applies the newest sample and the
    /// feed's fault to the device: call right before [`Shell::service`].
    pub fn feed(&mut self, feed: &mut feed::FeedIn, rx: &mut impl feed::ByteSource) {
        let now = self.io.now();
        let mut buf = [0u8; feed::MAX_FEED_BYTES];
        let mut n = 0;
        while n < buf.len() {
            let Some(b) = rx.pop() else { break };
            buf[n] = b;
            n += 1;
        }
        if n > 0 {
            feed.on_bytes(&buf[..n], now);
        }
        let (truth, lost) = feed.at(now);
        let chain = self.dev.chain_mut();
        if let Some(t) = truth {
            chain.set_motion(imu_emu::sensor::Motion::Sample(t));
        }
        chain.faults_mut().motion_feed_lost = lost;
    }

    /// The tick service: call from the tick interrupt (see the crate docs).
    /// Never blocks.
    pub fn service(&mut self) {
        self.service_with(|_| {});
    }

    /// [`Shell::service`] with a hook run right after the received bytes
    /// were executed and before any reply is handed to the UART (e.g. to
    /// persist the flash image, so a client that saw a SaveFlash
    /// acknowledgement can cut the power at once).
    pub fn service_with(&mut self, after_rx: impl FnOnce(&mut Device<F, P>)) {
        let t0 = self.io.now();
        self.io.service_start = t0;
        self.io.batch = 0;
        let limits = Limits {
            max_ticks: MAX_CATCH_UP,
            max_rx: MAX_RX,
            early_ns: self.sched.period_ns() / EARLY_SLACK_DIV,
        };
        let mut port = Hooked {
            io: &mut self.io,
            after_rx: Some(after_rx),
        };
        let Ok(pass) = self.sched.poll(self.dev, &mut port, t0, &limits);
        let now = self.io.now();
        self.io.apply_tov(now);

        let s = &mut self.io.stats;
        s.ticks += u64::from(pass.ticks);
        s.max_batch = s.max_batch.max(pass.ticks);
        s.rx_bytes += pass.rx as u64;
        s.tx_bytes += pass.tx as u64;
        s.services += 1;
        let took = now.saturating_sub(t0);
        let slot = if pass.rx > 0 {
            &mut s.max_service_rx_ns
        } else if pass.ticks > 1 {
            &mut s.max_batch_service_ns
        } else {
            &mut s.max_service_ns
        };
        *slot = (*slot).max(took);
    }
}

#[cfg(test)]
mod tests;
