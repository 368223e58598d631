//! The device: modes, power cycle, model — the one sans-IO entry point.
//! (API contract; being implemented.)

use embedded_storage::nor_flash::NorFlash;

use crate::model::Product;
use crate::time::Instant;

/// Logic level of an input pin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// Low.
    Low,
    /// High.
    High,
}

/// Input pins of the KERNEL connector (ICD Table 4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pin {
    /// 1PPS input (pin 3).
    Pps,
    /// External trigger input (pin 8).
    Extrig,
}

/// Operating mode (ICD 5.1, 5.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Waiting for commands.
    Idle,
    /// Initial alignment before an orientation/quaternion format streams.
    Aligning,
    /// Streaming a data format.
    Continuous,
    /// Entered by BOOT at power-on; answers nothing until power cycle.
    FirmwareUpdate,
}

/// Something the board must act on, from [`Device::poll_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// Switch the UART to this line rate (bit/s) now: every byte queued before
    /// the switch has already been handed out by [`Device::poll_tx`].
    LineRate(u32),
}

/// Board-side facts fixed at power-on.
#[derive(Debug, Clone, Copy)]
pub struct PowerOn {
    /// The emulated product.
    pub product: Product,
    /// Level of the BOOT input at power-on (model decides the active level).
    pub boot: Option<Level>,
    /// Seed of every random process.
    pub seed: u64,
}

/// An emulated KERNEL IMU owning its flash.
pub struct Device<F: NorFlash> {
    flash: F,
    product: Product,
}

impl<F: NorFlash> Device<F> {
    /// Powers the device on with BOOT floating and seed 0.
    pub fn power_on(product: Product, flash: F, now: Instant) -> Self {
        Self::power_on_with(PowerOn { product, boot: None, seed: 0 }, flash, now)
    }
    /// Powers the device on.
    pub fn power_on_with(cfg: PowerOn, flash: F, _now: Instant) -> Self {
        Device { flash, product: cfg.product }
    }
    /// Host → device bytes, any chunking.
    pub fn on_rx(&mut self, _bytes: &[u8], _now: Instant) {}
    /// One internal-rate tick (every 1/internal_rate s).
    pub fn on_tick(&mut self, _now: Instant) {}
    /// An input pin edge at time `at`.
    pub fn on_pin(&mut self, _pin: Pin, _level: Level, _at: Instant) {}
    /// Device → host bytes: copies up to `buf.len()` queued bytes into `buf`.
    pub fn poll_tx(&mut self, _buf: &mut [u8]) -> usize { 0 }
    /// Bytes queued for transmission.
    pub fn tx_len(&self) -> usize { 0 }
    /// The next board action, if any.
    pub fn poll_event(&mut self) -> Option<Event> { None }
    /// Power cycle: RAM reloads from flash, output stops (AutoStart applies).
    pub fn power_cycle(&mut self, _now: Instant) {}
    /// Power cycle with a new BOOT level.
    pub fn power_cycle_with(&mut self, _boot: Option<Level>, _now: Instant) {}
    /// Current line rate in bit/s.
    pub fn line_rate(&self) -> u32 { 115_200 }
    /// Tick period in nanoseconds (1e9 / internal rate).
    pub fn tick_period_ns(&self) -> u64 { 1_000_000_000 / u64::from(self.product.model.internal_rate_hz) }
    /// The current mode.
    pub fn mode(&self) -> Mode { Mode::Idle }
    /// The emulated product.
    pub fn product(&self) -> Product { self.product }
    /// The flash (e.g. to persist its image).
    pub fn flash(&self) -> &F { &self.flash }
    /// The flash, mutably.
    pub fn flash_mut(&mut self) -> &mut F { &mut self.flash }
    /// Takes the flash back.
    pub fn into_flash(self) -> F { self.flash }
}
