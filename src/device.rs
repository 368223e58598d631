//! The device: a shell that owns what every emulated IMU shares, carrying
//! one protocol personality — the one sans-IO entry point
//! (ARCHITECTURE.md "Shell and personalities").
//!
//! ```text
//! let mut dev = Device::power_on(product, flash, now);   // the KERNEL
//! dev.on_rx(bytes, now);          // host → device bytes, any chunking
//! dev.on_tick(now);               // every internal-rate tick (2 or 4 kHz)
//! dev.on_pin(Pin::Pps, Level::High, at);
//! let n = dev.poll_tx(&mut buf);  // device → host bytes
//! dev.poll_event();               // line-rate switches, TOV edges
//! dev.power_cycle(now);
//! ```
//!
//! The shell ([`Shell`]) owns power-on and power cycle with the BOOT level,
//! the flash and its store, the serial line ([`crate::line::Line`]: TX
//! queue and wire time at the current rate), the board events, the time
//! base (power-on time, tick count, 1PPS) and the signal chain, which it
//! ticks. The personality ([`crate::personality::Personality`]) owns the
//! protocol and sizes what depends on it (the TX queue's room for its
//! largest frame, its image in the store). The shell names no personality:
//! the KERNEL's conveniences (`power_on*`, `param_ram`) are an
//! `impl Device<F, Kernel>` in its own folder.

use core::mem::MaybeUninit;

use embedded_storage::nor_flash::NorFlash;
use heapless::Deque;

use crate::chain::SignalChain;
use crate::line::Line;
use crate::model::Product;
use crate::personality::{Context, Personality};
use crate::store::{ParamStore, StoreError};
use crate::time::{Instant, TimeBase};

pub use crate::io::{Event, Level, Mode, Pin};
pub use crate::line::TX_CAP;
/// Where the parameter store lives in the device's flash.
pub const STORE_BASE: u32 = 0;
/// Board events the device can hold before the board takes them.
const EVENTS: usize = 16;

/// Board-side facts fixed at power-on.
#[derive(Debug, Clone, Copy)]
pub struct PowerOn {
    /// The emulated product (its sensors and model facts).
    pub product: Product,
    /// Level of the BOOT input at power-on; `None` = floating (not
    /// asserted). The model decides the active level (Table 4.1 notes 4–5).
    pub boot: Option<Level>,
    /// Seed of every random process (and of the serial number).
    pub seed: u64,
}

/// What every personality shares: power, BOOT, flash and store, the line,
/// events, the time base, and the signal chain. A personality sees it
/// through [`Context`] at every call ([`crate::personality::Personality`]).
pub struct Shell<F: NorFlash, P: Personality> {
    flash: F,
    store: ParamStore<P::Image>,
    cfg: PowerOn,
    firmware_update: bool,
    line: Line<P::TxBuffer>,
    events: Deque<Event, EVENTS>,
    time: TimeBase,
    /// What the device measures and computes (ICD 5.3.6, 5.6–5.8, App. B/C).
    chain: SignalChain<P::Integrate>,
    /// A software reset waits for the bytes queued before it.
    reset_pending: bool,
}

impl<F: NorFlash, P: Personality> Shell<F, P> {
    /// The shell with its flash and configuration but no power yet: cheap
    /// to build in place (mostly zeros); [`Shell::cold_start`] powers it.
    #[inline(always)]
    fn unpowered(cfg: PowerOn, flash: F, now: Instant) -> Self {
        Shell {
            flash,
            store: ParamStore::for_image(STORE_BASE, P::IMAGE),
            cfg,
            firmware_update: false,
            line: Line::new(now),
            events: Deque::new(),
            time: TimeBase::new(now),
            chain: SignalChain::placeholder(cfg.product),
            reset_pending: false,
        }
    }

    /// Power-on, in place: everything but the flash, the configuration and
    /// the drop count starts over; BOOT is sampled.
    fn cold_start(&mut self, now: Instant) {
        self.line.reset(now);
        self.reset_pending = false;
        self.events.clear();
        self.time = TimeBase::new(now);
        self.chain.reset(self.cfg.product, self.cfg.seed);
        let active = if self.cfg.product.model.boot_active_low {
            Level::Low
        } else {
            Level::High
        };
        self.firmware_update = self.cfg.boot == Some(active);
    }
}

impl<F: NorFlash, P: Personality> Context<P::Integrate> for Shell<F, P> {
    fn product(&self) -> Product {
        self.cfg.product
    }

    fn seed(&self) -> u64 {
        self.cfg.seed
    }

    fn firmware_update(&self) -> bool {
        self.firmware_update
    }

    fn chain(&self) -> &SignalChain<P::Integrate> {
        &self.chain
    }

    fn chain_mut(&mut self) -> &mut SignalChain<P::Integrate> {
        &mut self.chain
    }

    fn push_frame(&mut self, n: usize, fill: impl FnOnce(&mut [u8]) -> bool) -> Option<Instant> {
        self.line.push_frame(n, self.time.clock(), fill).end()
    }

    fn line_rate(&self) -> u32 {
        self.line.rate()
    }

    fn tx_dropped(&self) -> u32 {
        self.line.dropped()
    }

    fn set_line_rate(&mut self, bps: u32) {
        self.line.set_rate(bps);
        self.push_event(Event::LineRate(self.line.rate()));
    }

    fn switch_line_rate(&mut self, bps: u32) {
        self.line.switch_rate_after_queued(bps);
    }

    fn push_event(&mut self, ev: Event) {
        let _ = self.events.push_back(ev);
    }

    fn load_image(&mut self, image: &mut [u8]) -> Result<bool, StoreError> {
        self.store.load(&mut self.flash, image)
    }

    fn save_image(&mut self, image: &[u8]) -> Result<(), StoreError> {
        self.store.save(&mut self.flash, image)
    }

    fn request_reset(&mut self) {
        self.reset_pending = true;
    }

    fn time(&self) -> &TimeBase {
        &self.time
    }

    fn time_mut(&mut self) -> &mut TimeBase {
        &mut self.time
    }
}

/// An emulated IMU owning its flash: the [`Shell`] and one personality
/// `P` (e.g. `Device<F, Kernel>`, `Device<F, Isb>`).
pub struct Device<F: NorFlash, P: Personality> {
    shell: Shell<F, P>,
    personality: P,
}

impl<F: NorFlash, P: Personality> core::fmt::Debug for Device<F, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Device")
            .field("product", &self.shell.cfg.product.code())
            .field("mode", &self.mode())
            .field("line_rate", &self.shell.line.rate())
            .field("tx_len", &self.shell.line.len())
            .finish()
    }
}

impl<F: NorFlash, P: Personality> Device<F, P> {
    /// Powers the device on with personality `P`: the shell starts, then
    /// the personality boots ([`Personality::boot`]).
    pub fn new(cfg: PowerOn, flash: F, now: Instant) -> Self {
        let mut dev = Self::unpowered(cfg, flash, now);
        dev.cold_start(now);
        dev
    }

    /// [`Device::new`] with the sensor profile `profile` instead of the
    /// model's built-in one (`None`: the built-in one); it stays across
    /// power cycles ([`SignalChain::set_profile`]). A host's
    /// `--sensor-profile` file.
    pub fn with_profile(
        cfg: PowerOn,
        profile: Option<&'static crate::sensor::profile::SensorProfile>,
        flash: F,
        now: Instant,
    ) -> Self {
        let mut dev = Self::unpowered(cfg, flash, now);
        dev.shell.chain.set_profile(profile);
        dev.cold_start(now);
        dev
    }

    /// [`Device::new`] straight into `slot`, for microcontrollers: the
    /// device (~12 KiB, most of it the signal chain's FIR history) is built
    /// where it will live, with a few hundred bytes of stack, instead of
    /// being assembled on the stack and moved.
    pub fn new_into(
        slot: &mut MaybeUninit<Self>,
        cfg: PowerOn,
        flash: F,
        now: Instant,
    ) -> &mut Self {
        let dev = slot.write(Self::unpowered(cfg, flash, now));
        dev.cold_start(now);
        dev
    }

    #[inline(always)]
    fn unpowered(cfg: PowerOn, flash: F, now: Instant) -> Self {
        Device {
            shell: Shell::unpowered(cfg, flash, now),
            personality: P::unpowered(),
        }
    }

    /// Power cycle with BOOT floating: the image reloads from flash, the
    /// queues empty, output stops (and what starts by itself starts again).
    pub fn power_cycle(&mut self, now: Instant) {
        self.power_cycle_with(None, now);
    }

    /// Power cycle with the BOOT input at `boot`.
    pub fn power_cycle_with(&mut self, boot: Option<Level>, now: Instant) {
        self.shell.cfg.boot = boot;
        self.cold_start(now);
    }

    fn cold_start(&mut self, now: Instant) {
        self.shell.cold_start(now);
        self.personality.boot(&mut self.shell, now);
    }

    /// Host → device bytes, any chunking. Complete frames are executed at
    /// once; replies are queued for [`Device::poll_tx`].
    pub fn on_rx(&mut self, bytes: &[u8], now: Instant) {
        if self.shell.firmware_update {
            return;
        }
        let t = &mut self.shell.time;
        t.tell(now);
        if !bytes.is_empty() {
            t.touch_rx(now);
        }
        self.personality.on_rx(bytes, &mut self.shell, now);
    }

    /// One internal-rate tick (every 1/internal rate; 2 kHz, 4 kHz on the
    /// K201): the chain ticks, the personality produces what is due.
    pub fn on_tick(&mut self, now: Instant) {
        if self.shell.firmware_update {
            return;
        }
        if self.shell.reset_pending && self.shell.line.is_empty() {
            self.shell.cfg.boot = None;
            self.cold_start(now);
        }
        let t = &mut self.shell.time;
        t.tell(now);
        t.tick();
        self.personality.before_tick(&mut self.shell, now);
        self.shell.chain.tick(now);
        self.personality.on_tick(&mut self.shell, now);
    }

    /// An input pin edge at time `at` (the new level). A 1PPS rising edge
    /// marks the second (KERNEL 5.2.3.1, Table 4.1 note 6); then the
    /// personality acts on the edge.
    pub fn on_pin(&mut self, pin: Pin, level: Level, at: Instant) {
        if self.shell.firmware_update {
            return;
        }
        let t = &mut self.shell.time;
        t.tell(at);
        if (pin, level) == (Pin::Pps, Level::High) {
            t.pps(at);
        }
        self.personality.on_pin(pin, level, &mut self.shell, at);
    }

    /// Device → host bytes: moves up to `buf.len()` queued bytes into `buf`
    /// and returns how many. Stops at a pending line-rate switch until
    /// [`Device::poll_event`] hands it out.
    pub fn poll_tx(&mut self, buf: &mut [u8]) -> usize {
        self.shell.line.pop(buf)
    }

    /// Bytes queued for transmission.
    pub fn tx_len(&self) -> usize {
        self.shell.line.len()
    }

    /// Frames dropped because the TX queue was full (line too slow).
    pub fn tx_dropped(&self) -> u32 {
        self.shell.line.dropped()
    }

    /// The next board action, if any.
    pub fn poll_event(&mut self) -> Option<Event> {
        if let Some(rate) = self.shell.line.take_due_switch() {
            return Some(Event::LineRate(rate));
        }
        self.shell.events.pop_front()
    }

    /// The line rate the device runs at now, bit/s.
    pub fn line_rate(&self) -> u32 {
        self.shell.line.rate()
    }

    /// Tick period in nanoseconds (1e9 / internal rate).
    pub fn tick_period_ns(&self) -> u64 {
        1_000_000_000 / u64::from(self.shell.cfg.product.model.internal_rate_hz)
    }

    /// The current mode.
    pub fn mode(&self) -> Mode {
        if self.shell.firmware_update {
            return Mode::FirmwareUpdate;
        }
        self.personality.mode()
    }

    /// The running output rate in Hz, if streaming.
    pub fn output_rate(&self) -> Option<u32> {
        if self.shell.firmware_update {
            return None;
        }
        self.personality.output_rate(&self.shell)
    }

    /// Ticks from now until the next tick that produces periodic output
    /// (1 = the very next tick), or `None` when no periodic output is due
    /// (idle, firmware update, EXTRIG-triggered). Lets a board sleep
    /// through ticks that change nothing visible (it must still call
    /// [`Device::on_tick`] for each of them, late is fine).
    pub fn ticks_to_next_output(&self) -> Option<u64> {
        if self.shell.firmware_update {
            return None;
        }
        self.personality.ticks_to_next_output()
    }

    /// Whether a software reset waits for the bytes queued before it (it
    /// runs at the first tick once the line is empty): the device's own
    /// work that [`Device::ticks_to_next_output`] does not show, for a
    /// board that stops its clock while the device is idle (the host's
    /// `--speed max`).
    pub fn reset_pending(&self) -> bool {
        self.shell.reset_pending
    }

    /// The emulated product.
    pub fn product(&self) -> Product {
        self.shell.cfg.product
    }

    /// The personality (its protocol state).
    pub fn personality(&self) -> &P {
        &self.personality
    }

    /// The personality, mutably: a board's settings of it (the ISB's GPS
    /// time, its navigation faults).
    pub fn personality_mut(&mut self) -> &mut P {
        &mut self.personality
    }

    /// The flash (e.g. to persist its image).
    pub fn flash(&self) -> &F {
        &self.shell.flash
    }

    /// The flash, mutably (e.g. a test double's power-cut switch).
    pub fn flash_mut(&mut self) -> &mut F {
        &mut self.shell.flash
    }

    /// Takes the flash back.
    pub fn into_flash(self) -> F {
        self.shell.flash
    }

    /// The signal chain: motion source, error model and fault injection
    /// for boards, tests and scripted runs.
    pub fn chain_mut(&mut self) -> &mut SignalChain<P::Integrate> {
        &mut self.shell.chain
    }

    /// The signal chain (read-only).
    pub fn chain(&self) -> &SignalChain<P::Integrate> {
        &self.shell.chain
    }
}
