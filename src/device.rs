//! The device: modes, power cycle, model — the one sans-IO entry point
//! (ICD 5.1, 5.3, section 6; DESIGN.md "One entry point").
//!
//! ```text
//! let mut dev = Device::power_on(product, flash, now);
//! dev.on_rx(bytes, now);          // host → device bytes, any chunking
//! dev.on_tick(now);               // every internal-rate tick (2 or 4 kHz)
//! dev.on_pin(Pin::Pps, Level::High, at);
//! let n = dev.poll_tx(&mut buf);  // device → host bytes
//! dev.poll_event();               // line-rate switches
//! dev.power_cycle(now);
//! ```

use core::mem::MaybeUninit;

use embedded_storage::nor_flash::NorFlash;
use heapless::Deque;

use crate::chain::SignalChain;
use crate::kernel::command::Command;
use crate::kernel::fields::{self, Field, OutputCtx};
use crate::kernel::formats::{self, UDD};
use crate::kernel::frame::{self, Decoder, TYPE_COMMAND, TYPE_DATA};
use crate::kernel::params::{self, Apply, Block, ParamSpec, BLOCK_LEN};
use crate::kernel::{rate, udd};
use crate::model::{Capability, Product};
use crate::store::ParamStore;
use crate::time::Instant;

/// Largest host → device frame: a UDD config message `96 N` + 255 types.
pub const RX_FRAME_CAP: usize = frame::OVERHEAD + 2 + 255;
/// Device TX queue (the UART buffer): frames that do not fit are dropped
/// whole, as a device whose line is too slow would.
pub const TX_CAP: usize = 2048;
/// An incomplete frame with no new byte for this long is abandoned and the
/// decoder resyncs on the bytes after its first byte (a frame cut short).
pub const RX_IDLE_ABANDON_NS: u64 = 100_000_000;
/// Largest payload the device sends: a UDD frame of 16 types of 12 bytes.
const MAX_PAYLOAD: usize = 1 + params::UDD_MAX_TYPES * 13;
/// Nanoseconds per second.
const NS_PER_S: u64 = 1_000_000_000;
/// Where the parameter store lives in the device's flash.
pub const STORE_BASE: u32 = 0;

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
    /// 1PPS input (pin 3); a rising edge marks the second.
    Pps,
    /// External trigger input (pin 8).
    Extrig,
}

/// Operating mode (ICD 5.1, 5.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Waiting for commands.
    Idle,
    /// Initial alignment before a format with orientation streams (5.3.1).
    Aligning,
    /// Streaming a data format.
    Continuous,
    /// Entered by BOOT at power-on; answers nothing until power cycle.
    FirmwareUpdate,
}

/// Something the board must act on, from [`Device::poll_event`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// Set the UART to this line rate (bit/s) now. Every byte queued before
    /// the switch has already been handed out by [`Device::poll_tx`]; bytes
    /// after it are held back until this event is taken. Raised at power-on
    /// and on CommitBaudRate (5.3.9).
    LineRate(u32),
    /// Drive the TOV output (ICD 4.1.4) to `level` at time `at` (which may
    /// lie in the future: the falling edge comes when the frame's last bit
    /// has left the line). Only with TOV_Control = 1.
    Tov {
        /// New pin level.
        level: Level,
        /// When.
        at: Instant,
    },
}

/// Board-side facts fixed at power-on.
#[derive(Debug, Clone, Copy)]
pub struct PowerOn {
    /// The emulated product.
    pub product: Product,
    /// Level of the BOOT input at power-on; `None` = floating (not
    /// asserted). The model decides the active level (Table 4.1 notes 4–5).
    pub boot: Option<Level>,
    /// Seed of every random process (and of the serial number).
    pub seed: u64,
}

/// Largest frame the device sends (a UDD frame; GetDevInfo is smaller).
const MAX_FRAME: usize = MAX_PAYLOAD + frame::OVERHEAD;

/// The UART transmit queue: [`TX_CAP`] bytes (what [`TxRing::free`]
/// counts) in a buffer [`MAX_FRAME`] bytes longer, so that a frame is always
/// written in place in one piece ([`TxRing::push_frame`]): one that starts
/// near the end runs on past [`TX_CAP`], that point becomes the end of the
/// ring until the reader has passed it, and the next frame starts at 0.
struct TxRing {
    buf: [u8; TX_CAP + MAX_FRAME],
    head: usize,
    len: usize,
    /// Where the bytes wrap to 0: [`TX_CAP`], or the end of a frame that ran
    /// past it (until the reader passes it).
    end: usize,
}

impl TxRing {
    const fn new() -> Self {
        TxRing {
            buf: [0; TX_CAP + MAX_FRAME],
            head: 0,
            len: 0,
            end: TX_CAP,
        }
    }

    fn len(&self) -> usize {
        self.len
    }

    fn free(&self) -> usize {
        TX_CAP - self.len
    }

    fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.end = TX_CAP;
    }

    /// Appends an `n`-byte frame that `fill` writes in place (the caller
    /// checked [`TxRing::free`]); nothing is queued if `fill` returns
    /// `false` or the frame is longer than [`MAX_FRAME`].
    ///
    /// The tail is always below [`TX_CAP`]; written after the reader's
    /// bytes it may run into the extra bytes, written before them (wrapped)
    /// it ends at or below `head − (end − TX_CAP)` since at most [`TX_CAP`]
    /// bytes are queued, so it never meets them.
    fn push_frame(&mut self, n: usize, fill: impl FnOnce(&mut [u8]) -> bool) -> bool {
        if n > self.free().min(MAX_FRAME) {
            return false;
        }
        let mut tail = self.head + self.len;
        if tail >= self.end {
            tail -= self.end;
        }
        let Some(f) = self.buf.get_mut(tail..tail + n) else {
            return false;
        };
        if !fill(f) {
            return false;
        }
        if tail + n >= TX_CAP {
            self.end = tail + n;
        }
        self.len += n;
        true
    }

    /// Moves up to `out.len()` bytes out.
    fn pop(&mut self, out: &mut [u8]) -> usize {
        let n = out.len().min(self.len);
        let first = n.min(self.end - self.head);
        out[..first].copy_from_slice(&self.buf[self.head..self.head + first]);
        out[first..n].copy_from_slice(&self.buf[..n - first]);
        self.head += n;
        if self.head >= self.end {
            self.head -= self.end;
            self.end = TX_CAP;
        }
        self.len -= n;
        n
    }
}

/// `n · byte_ps / 1000` (ns on the wire for `n` bytes of `byte_ps` ps):
/// split at 1000 so that, for every rate above 2.3 kbit/s, only 32-bit
/// divisions by the constant remain (a 64-bit one is a library call on a
/// Cortex-M).
fn wire_ns(n: usize, byte_ps: u64) -> u64 {
    match (u32::try_from(n), u32::try_from(byte_ps)) {
        (Ok(n), Ok(ps)) if n < 1 << 16 => {
            u64::from(n) * u64::from(ps / 1000) + u64::from(n * (ps % 1000) / 1000)
        }
        _ => n as u64 * byte_ps / 1000,
    }
}

/// What [`queue_frame`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Queued {
    /// The frame is queued.
    Yes,
    /// No room in the queue: dropped whole.
    Full,
    /// Not sent (the payload writer refused, or no valid length field).
    No,
}

/// Queues a device frame (`type 1`, Table 5.2) with a `len`-byte payload
/// that `fill` writes straight into the queue (`false`: send nothing).
fn queue_frame(
    tx: &mut TxRing,
    id: u8,
    len: usize,
    fill: impl FnOnce(&mut [u8]) -> bool,
) -> Queued {
    let Ok(len_field) = u16::try_from(len + 6) else {
        return Queued::No;
    };
    let n = len + frame::OVERHEAD;
    if tx.free() < n {
        return Queued::Full;
    }
    let len_field = len_field.to_le_bytes();
    let queued = tx.push_frame(n, |f| {
        let (body, sum) = f.split_at_mut(6 + len);
        let (head, payload) = body.split_at_mut(6);
        head.copy_from_slice(&[
            frame::HEADER[0],
            frame::HEADER[1],
            TYPE_DATA,
            id,
            len_field[0],
            len_field[1],
        ]);
        if !fill(payload) {
            return false;
        }
        sum.copy_from_slice(&frame::checksum(&body[2..]).to_le_bytes());
        true
    });
    if queued {
        Queued::Yes
    } else {
        Queued::No
    }
}

/// What an output frame carries: the UDD header (N and the type list; empty
/// for fixed formats) and the fields, resolved once per stream.
#[derive(Debug, Clone, Default)]
struct Layout {
    header: heapless::Vec<u8, { 1 + params::UDD_MAX_TYPES }>,
    fields: heapless::Vec<Field, { params::UDD_MAX_TYPES }>,
    /// Payload bytes (header and fields).
    len: usize,
    /// Whether a field carries the orientation (Euler angles, quaternion):
    /// the chain computes it only then.
    attitude: bool,
}

impl Layout {
    fn payload_len(&self) -> usize {
        self.len
    }
}

#[derive(Debug, Clone)]
struct Stream {
    /// Data command code (Table 5.16).
    code: u8,
    /// Output every `divisor` ticks.
    divisor: u32,
    /// Ticks until the next periodic output (counts down from `divisor`).
    countdown: u32,
    /// Alignment ticks still to run.
    align_left: u64,
    /// The frame layout.
    layout: Layout,
    /// Output only on EXTRIG edges (Trigger_Control, latched at start).
    triggered: bool,
    /// TOV output on (TOV_Control, latched at start).
    tov: bool,
}

/// An emulated KERNEL IMU owning its flash.
pub struct Device<F: NorFlash> {
    flash: F,
    store: ParamStore,
    cfg: PowerOn,
    rx: Decoder<RX_FRAME_CAP>,
    last_rx: Instant,
    tx: TxRing,
    tx_dropped: u32,
    /// Live parameters (what ReadRAM answers and the device runs with).
    ram: Block,
    /// The flash copy (what SaveFlash wrote).
    saved: Block,
    firmware_update: bool,
    stream: Option<Stream>,
    udd_pending: bool,
    powered_at: Instant,
    ticks: u64,
    line_rate: u32,
    /// Time one byte occupies the line at `line_rate`, ps.
    byte_time_ps: u64,
    /// Line-rate switch waiting for the bytes queued before it: (rate, bytes).
    line_switch: Option<(u32, usize)>,
    events: Deque<Event, 16>,
    /// Latest time the board told us (every entry point carries one).
    clock: Instant,
    /// When the UART will have sent everything queued so far, at the
    /// current line rate (10 bit times per byte).
    line_free_at: Instant,
    /// Start of the current second of the second fraction (5.2.3.1): the
    /// last 1PPS edge, or power-on, advanced by whole seconds.
    second_start: Instant,
    /// Last accepted EXTRIG edge (hold-off reference, 4.1.3).
    last_trigger: Option<Instant>,
    last_pps: Option<Instant>,
    pps_since_frame: bool,
    /// What the device measures and computes (ICD 5.3.6, 5.6–5.8, App. B/C).
    chain: SignalChain,
}

impl<F: NorFlash> core::fmt::Debug for Device<F> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Device")
            .field("product", &self.cfg.product.code())
            .field("mode", &self.mode())
            .field("line_rate", &self.line_rate)
            .field("tx_len", &self.tx.len())
            .finish()
    }
}

impl<F: NorFlash> Device<F> {
    /// Powers the device on with BOOT floating and seed 0.
    pub fn power_on(product: Product, flash: F, now: Instant) -> Self {
        Self::power_on_with(
            PowerOn {
                product,
                boot: None,
                seed: 0,
            },
            flash,
            now,
        )
    }

    /// Powers the device on: parameters load from flash (factory defaults
    /// if it holds none), BOOT is checked, AutoStart runs (section 6).
    pub fn power_on_with(cfg: PowerOn, flash: F, now: Instant) -> Self {
        let mut dev = Self::unpowered(cfg, flash, now);
        dev.cold_start(now);
        dev
    }

    /// [`Device::power_on_with`] straight into `slot`, for microcontrollers:
    /// the device (~12 KiB, most of it the signal chain's FIR history) is
    /// built where it will live, with a few hundred bytes of stack, instead
    /// of being assembled on the stack and moved.
    pub fn power_on_into(
        slot: &mut MaybeUninit<Self>,
        cfg: PowerOn,
        flash: F,
        now: Instant,
    ) -> &mut Self {
        let dev = slot.write(Self::unpowered(cfg, flash, now));
        dev.cold_start(now);
        dev
    }

    /// A device with its flash and configuration but no power yet: every
    /// field a placeholder that [`Device::cold_start`] sets. Cheap to build
    /// (mostly zeros), so a caller's slot can take it in place.
    #[inline(always)]
    fn unpowered(cfg: PowerOn, flash: F, now: Instant) -> Self {
        let factory = [0u8; BLOCK_LEN];
        Device {
            flash,
            store: ParamStore::new(STORE_BASE),
            cfg,
            rx: Decoder::new(),
            last_rx: now,
            tx: TxRing::new(),
            tx_dropped: 0,
            ram: factory,
            saved: factory,
            firmware_update: false,
            stream: None,
            udd_pending: false,
            powered_at: now,
            ticks: 0,
            line_rate: 115_200,
            byte_time_ps: 10_000_000_000_000 / 115_200,
            line_switch: None,
            events: Deque::new(),
            clock: now,
            line_free_at: now,
            second_start: now,
            last_trigger: None,
            last_pps: None,
            pps_since_frame: false,
            chain: SignalChain::unpowered(cfg.product),
        }
    }

    /// Power cycle with BOOT floating: RAM reloads from flash, the queues
    /// empty, output stops (and AutoStart applies again).
    pub fn power_cycle(&mut self, now: Instant) {
        self.power_cycle_with(None, now);
    }

    /// Power cycle with the BOOT input at `boot`.
    pub fn power_cycle_with(&mut self, boot: Option<Level>, now: Instant) {
        self.cfg.boot = boot;
        self.cold_start(now);
    }

    /// Power-on, in place: everything but the flash and the configuration
    /// starts over, then [`Device::boot`] loads the parameters.
    fn cold_start(&mut self, now: Instant) {
        self.rx = Decoder::new();
        self.last_rx = now;
        self.tx.clear();
        self.stream = None;
        self.udd_pending = false;
        self.powered_at = now;
        self.ticks = 0;
        self.line_switch = None;
        self.events.clear();
        self.clock = now;
        self.line_free_at = now;
        self.second_start = now;
        self.last_trigger = None;
        self.last_pps = None;
        self.pps_since_frame = false;
        self.chain.reset(self.cfg.product, self.cfg.seed);
        self.boot(now);
    }

    fn boot(&mut self, _now: Instant) {
        let product = self.cfg.product;
        let mut block = [0u8; BLOCK_LEN];
        if let Ok(true) = self.store.load(&mut self.flash, &mut block) {
            params::sanitize(&mut block, &product);
        } else {
            block = params::factory_block(&product);
        }
        self.saved = block;
        self.ram = block;
        self.chain
            .configure(&crate::kernel::config::chain_config(&self.ram, &product));
        self.set_line_rate(params::baud_rate(
            params::BAUD_RATE.read_int(&self.ram) as u8
        ));
        let _ = self.events.push_back(Event::LineRate(self.line_rate));
        let active = if product.model.boot_active_low {
            Level::Low
        } else {
            Level::High
        };
        self.firmware_update = self.cfg.boot == Some(active);
        if self.firmware_update {
            return;
        }
        let auto = params::AUTO_START.read_int(&self.ram) as u8;
        if auto != 0 && product.model.supports_format(auto) {
            self.send(0x00, &formats::AUTOSTART_PAYLOAD);
            self.start_stream(auto);
        }
    }

    /// Host → device bytes, any chunking. Complete frames are executed at
    /// once; replies are queued for [`Device::poll_tx`].
    pub fn on_rx(&mut self, mut bytes: &[u8], now: Instant) {
        if self.firmware_update {
            return;
        }
        self.clock = self.clock.max(now);
        if !bytes.is_empty() {
            self.last_rx = now;
        }
        while let Some(f) = self.rx.next_frame(&mut bytes) {
            if f.msg_type != TYPE_COMMAND || f.id != 0 {
                continue;
            }
            // Copy out of the decoder so it can be borrowed again.
            let mut payload = [0u8; RX_FRAME_CAP];
            let n = f.payload.len();
            payload[..n].copy_from_slice(f.payload);
            let checksum = f.checksum;
            self.execute(&payload[..n], checksum);
        }
    }

    /// One internal-rate tick (every 1/internal rate; 2 kHz, 4 kHz on K201):
    /// alignment runs, output frames are produced at the data rate.
    pub fn on_tick(&mut self, now: Instant) {
        if self.firmware_update {
            return;
        }
        self.clock = self.clock.max(now);
        self.ticks = self.ticks.wrapping_add(1);
        if self.rx.has_partial() && now.since(self.last_rx) > RX_IDLE_ABANDON_NS {
            self.rx.abandon();
            self.last_rx = now;
            self.on_rx(&[], now);
        }
        self.chain.tick(now);
        let Some(s) = self.stream.as_mut() else {
            return;
        };
        if s.align_left > 0 {
            s.align_left -= 1;
            if s.align_left == 0 {
                self.chain.end_alignment();
            }
            return;
        }
        s.countdown = s.countdown.saturating_sub(1);
        if s.countdown == 0 {
            s.countdown = s.divisor;
        }
        if !s.triggered && s.countdown == s.divisor {
            let code = s.code;
            self.emit(code, now);
        }
    }

    /// An input pin edge at time `at` (the new level).
    ///
    /// * 1PPS: the rising edge marks the second (5.2.3.1, Table 4.1 note 6).
    /// * EXTRIG (4.1.3): with Trigger_Control = 1 on a model with EXTRIG,
    ///   each edge of the Polarity parameter's sense (0 negative: falling,
    ///   1 positive: rising) sends one frame of the running format with the
    ///   latest data at once; edges within Hold-off_Time ms of the last
    ///   accepted one are ignored. Periodic output is off while triggering.
    pub fn on_pin(&mut self, pin: Pin, level: Level, at: Instant) {
        if self.firmware_update {
            return;
        }
        self.clock = self.clock.max(at);
        match (pin, level) {
            (Pin::Pps, Level::High) => {
                self.last_pps = Some(at);
                self.second_start = at;
                self.pps_since_frame = true;
            }
            (Pin::Pps, Level::Low) => {}
            (Pin::Extrig, level) => {
                let want = match params::POLARITY.read_int(&self.ram) {
                    0 => Level::Low,
                    _ => Level::High,
                };
                let triggered = self
                    .stream
                    .as_ref()
                    .is_some_and(|s| s.triggered && s.align_left == 0);
                if !triggered || level != want {
                    return;
                }
                let hold_off_ns = u64::from(params::HOLD_OFF_TIME.read_int(&self.ram)) * 1_000_000;
                if self.last_trigger.is_some_and(|t| at.since(t) < hold_off_ns) {
                    return;
                }
                self.last_trigger = Some(at);
                if let Some(code) = self.stream.as_ref().map(|s| s.code) {
                    self.emit(code, at);
                }
            }
        }
    }

    /// Whether output is EXTRIG-triggered (Trigger_Control = 1 on a model
    /// with EXTRIG), per the live parameters.
    fn trigger_enabled(&self) -> bool {
        self.cfg.product.model.has(Capability::Extrig)
            && params::TRIGGER_CONTROL.read_int(&self.ram) == 1
    }

    /// Device → host bytes: moves up to `buf.len()` queued bytes into `buf`
    /// and returns how many. Stops at a pending line-rate switch until
    /// [`Device::poll_event`] hands it out.
    pub fn poll_tx(&mut self, buf: &mut [u8]) -> usize {
        let limit = match self.line_switch {
            Some((_, before)) => before,
            None => usize::MAX,
        };
        let want = buf.len().min(limit);
        let n = self.tx.pop(&mut buf[..want]);
        if let Some((_, before)) = self.line_switch.as_mut() {
            *before -= n;
        }
        n
    }

    /// Bytes queued for transmission.
    pub fn tx_len(&self) -> usize {
        self.tx.len()
    }

    /// Frames dropped because the TX queue was full (line too slow).
    pub fn tx_dropped(&self) -> u32 {
        self.tx_dropped
    }

    /// The next board action, if any.
    pub fn poll_event(&mut self) -> Option<Event> {
        if let Some((rate, 0)) = self.line_switch {
            self.line_switch = None;
            return Some(Event::LineRate(rate));
        }
        self.events.pop_front()
    }

    /// The line rate the device runs at now, bit/s (Formula 5.1 uses it).
    pub fn line_rate(&self) -> u32 {
        self.line_rate
    }

    /// Tick period in nanoseconds (1e9 / internal rate).
    pub fn tick_period_ns(&self) -> u64 {
        1_000_000_000 / u64::from(self.cfg.product.model.internal_rate_hz)
    }

    /// The current mode.
    pub fn mode(&self) -> Mode {
        match (&self.stream, self.firmware_update) {
            (_, true) => Mode::FirmwareUpdate,
            (None, false) => Mode::Idle,
            (Some(s), false) if s.align_left > 0 => Mode::Aligning,
            (Some(_), false) => Mode::Continuous,
        }
    }

    /// The running output rate in Hz (after Formula 5.1), if streaming.
    pub fn output_rate(&self) -> Option<u32> {
        self.stream
            .as_ref()
            .map(|s| self.cfg.product.model.internal_rate_hz / s.divisor)
    }

    /// Ticks from now until the next tick that produces periodic output
    /// (1 = the very next tick), or `None` when no periodic output is due
    /// (idle, firmware update, EXTRIG-triggered). Lets a board sleep
    /// through ticks that change nothing visible (it must still call
    /// [`Device::on_tick`] for each of them, late is fine).
    pub fn ticks_to_next_output(&self) -> Option<u64> {
        let s = self.stream.as_ref()?;
        if self.firmware_update || s.triggered {
            return None;
        }
        Some(s.align_left + u64::from(s.countdown))
    }

    /// The emulated product.
    pub fn product(&self) -> Product {
        self.cfg.product
    }

    /// The live value of a parameter (what ReadRAM answers), if the ID is
    /// one of Table 5.24.
    pub fn param_ram(&self, id: u16) -> Option<&[u8]> {
        params::find(id).map(|p| p.bytes(&self.ram))
    }

    /// The flash (e.g. to persist its image).
    pub fn flash(&self) -> &F {
        &self.flash
    }

    /// The flash, mutably (e.g. a test double's power-cut switch).
    pub fn flash_mut(&mut self) -> &mut F {
        &mut self.flash
    }

    /// Takes the flash back.
    pub fn into_flash(self) -> F {
        self.flash
    }

    // ----- commands -----

    fn execute(&mut self, payload: &[u8], checksum: u16) {
        let parsed = Command::parse(payload);
        if core::mem::take(&mut self.udd_pending) {
            // The message after User_Def_Data_config is the configuration,
            // unless it is itself a command (5.3.5, NOTES.md).
            match parsed {
                Ok(Command::Unknown(_)) | Err(_) => return self.udd_config(payload, checksum),
                _ => {}
            }
        }
        let Ok(cmd) = parsed else {
            return;
        };
        match cmd {
            Command::Data(code) => {
                if self.cfg.product.model.supports_format(code) {
                    self.send(code, &checksum.to_le_bytes());
                    self.apply_saved();
                    self.start_stream(code);
                }
            }
            Command::Stop => {
                self.stream = None;
                self.apply_saved();
            }
            Command::GetDevInfo => {
                let info = self.dev_info();
                self.send(crate::kernel::command::GET_DEV_INFO, &info);
            }
            Command::GetBit => {
                let bit = crate::kernel::status::bit(&self.chain.health());
                self.send(crate::kernel::command::GET_BIT, &bit);
            }
            Command::UddConfig => self.udd_pending = true,
            Command::UddConfigMessage(list) => self.udd_config(list, checksum),
            Command::GetUddStruct => {
                let mut p = [0u8; 1 + params::UDD_MAX_TYPES];
                let config = self.udd_config_now();
                p[0] = config.len() as u8;
                p[1..1 + config.len()].copy_from_slice(&config);
                self.send(
                    crate::kernel::command::GET_UDD_STRUCT,
                    &p[..1 + config.len()],
                );
            }
            Command::CommitBaudRate => self.commit_baud_rate(),
            Command::DeviceParameters => {
                let p = self.device_parameters();
                self.send(crate::kernel::command::DEVICE_PARAMETERS, &p);
            }
            Command::SaveFlash { id, len, value } => self.save_flash(id, len, value, checksum),
            Command::ReadRam { id, len } => {
                if let Some(p) = params::find(id).filter(|p| p.byte_len() == len) {
                    let mut v = [0u8; 12];
                    let n = usize::from(p.byte_len());
                    v[..n].copy_from_slice(p.bytes(&self.ram));
                    self.send(0xB1, &v[..n]);
                }
            }
            Command::Unknown(_) => {}
        }
    }

    /// SaveFlash (5.3.7): a wrong ID, wrong length, read-only parameter or
    /// bad value changes nothing and gets no answer; a valid one is written
    /// to flash (power-fail safe), acknowledged, and reaches RAM per
    /// [`Apply`].
    fn save_flash(&mut self, id: u16, len: u16, value: &[u8], checksum: u16) {
        let product = self.cfg.product;
        let Some(p) = params::find(id) else {
            return;
        };
        if p.byte_len() != len || p.validate(value, &product, &self.saved).is_err() {
            return;
        }
        let mut next = self.saved;
        next[p.range()].copy_from_slice(value);
        if self.store.save(&mut self.flash, &next).is_err() {
            return;
        }
        self.saved = next;
        self.send(0xB2, &checksum.to_le_bytes());
        if p.apply == Apply::NextStream && self.stream.is_none() {
            self.ram[p.range()].copy_from_slice(value);
        }
    }

    /// Copies every saved [`Apply::NextStream`] parameter into RAM.
    fn apply_saved(&mut self) {
        for p in params::PARAMS
            .iter()
            .filter(|p| p.apply == Apply::NextStream)
        {
            let r = p.range();
            self.ram[r.clone()].copy_from_slice(&self.saved[r]);
        }
    }

    /// CommitBaudRate (5.3.9): the saved Baud_Rate takes effect after the
    /// bytes already queued have left at the old rate. No reply (the ICD
    /// documents none).
    fn commit_baud_rate(&mut self) {
        let p: &ParamSpec = &params::BAUD_RATE;
        let r = p.range();
        self.ram[r.clone()].copy_from_slice(&self.saved[r]);
        let rate = params::baud_rate(p.read_int(&self.ram) as u8);
        self.set_line_rate(rate);
        self.line_switch = Some((rate, self.tx.len()));
        self.refresh_stream();
    }

    /// Recomputes the running stream's layout and rate (after a baud-rate
    /// or UDD configuration change).
    fn refresh_stream(&mut self) {
        if let Some(code) = self.stream.as_ref().map(|s| s.code) {
            let layout = self.layout(code);
            let divisor = self.divisor_for(&layout);
            if let Some(s) = self.stream.as_mut() {
                s.divisor = divisor;
                s.countdown = s.countdown.min(divisor);
                s.layout = layout;
            }
        }
    }

    fn udd_config_now(&self) -> udd::Config {
        udd::read_config(&self.ram, &self.cfg.product)
            .unwrap_or_else(|| udd::Config::from_slice(udd::DEFAULT_CONFIG).unwrap_or_default())
    }

    /// The configuration message after User_Def_Data_config (5.3.5):
    /// checked, answered with Table 5.20, persisted when accepted.
    fn udd_config(&mut self, payload: &[u8], checksum: u16) {
        let product = self.cfg.product;
        let internal = product.model.internal_rate_hz;
        match udd::check(payload, &product) {
            udd::Checked::Ok(config) => {
                let max = rate::max_rate(self.line_rate, udd::payload_len(&config), internal);
                let requested = params::DATA_RATE.read_int(&self.ram);
                let errors = if requested > max { udd::ERR_RATE } else { 0 };
                udd::write_config(&mut self.ram, &config);
                udd::write_config(&mut self.saved, &config);
                // Persist; a flash failure leaves the new config in RAM only.
                let _ = self.store.save(&mut self.flash, &self.saved);
                if self.stream.as_ref().is_some_and(|s| s.code == UDD) {
                    self.refresh_stream();
                }
                let reply = udd::config_reply(checksum, errors, 0, max as u16);
                self.send(crate::kernel::command::UDD_CONFIG, &reply);
            }
            udd::Checked::Refused {
                errors,
                wrong_types,
            } => {
                let current = self.udd_config_now();
                let max = rate::max_rate(self.line_rate, udd::payload_len(&current), internal);
                let reply = udd::config_reply(0, errors, wrong_types, max as u16);
                self.send(crate::kernel::command::UDD_CONFIG, &reply);
            }
        }
    }

    // ----- output -----

    /// The frame layout of data command `code`: a fixed format's fields, or
    /// the UDD header and the configured types' fields (Table 5.13).
    fn layout(&self, code: u8) -> Layout {
        let mut l = Layout::default();
        match formats::find(code) {
            Some(f) => {
                for &field in f.fields {
                    let _ = l.fields.push(field);
                }
            }
            None => {
                let config = self.udd_config_now();
                let _ = l.header.push(config.len() as u8);
                for &c in &config {
                    let _ = l.header.push(c);
                    if let Some(t) = udd::find(c) {
                        let _ = l.fields.push(t.field);
                    }
                }
            }
        }
        l.len = l.header.len() + fields::payload_len(&l.fields);
        l.attitude = l.fields.iter().any(|f| f.is_attitude());
        l
    }

    /// Output every this many ticks: Data_Rate lowered by Formula 5.1.
    fn divisor_for(&self, layout: &Layout) -> u32 {
        let internal = self.cfg.product.model.internal_rate_hz;
        let requested = params::DATA_RATE.read_int(&self.ram);
        let eff = rate::effective_rate(requested, self.line_rate, layout.payload_len(), internal);
        internal / eff.max(1)
    }

    fn start_stream(&mut self, code: u8) {
        let orientation = match formats::find(code) {
            Some(f) => f.orientation,
            None => self
                .udd_config_now()
                .iter()
                .any(|&c| udd::find(c).is_some_and(|t| t.orientation)),
        };
        let align_s = u64::from(params::INITIAL_ALIGNMENT_TIME.read_int(&self.ram));
        let internal = u64::from(self.cfg.product.model.internal_rate_hz);
        let product = self.cfg.product;
        self.chain
            .configure(&crate::kernel::config::chain_config(&self.ram, &product));
        let align_left = if orientation { align_s * internal } else { 0 };
        if orientation {
            if align_left > 0 {
                self.chain.begin_alignment();
            } else {
                self.chain.skip_alignment();
            }
        }
        let layout = self.layout(code);
        let divisor = self.divisor_for(&layout);
        self.stream = Some(Stream {
            code,
            divisor,
            countdown: divisor,
            align_left,
            layout,
            triggered: self.trigger_enabled(),
            tov: params::TOV_CONTROL.read_int(&self.ram) == 1,
        });
    }

    /// The signal chain: motion source, error model and fault injection
    /// for boards, tests and scripted runs.
    pub fn chain_mut(&mut self) -> &mut SignalChain {
        &mut self.chain
    }

    /// The signal chain (read-only).
    pub fn chain(&self) -> &SignalChain {
        &self.chain
    }

    /// Produces one output frame of the running stream at `now`.
    fn emit(&mut self, code: u8, now: Instant) {
        let Some(stream) = self.stream.as_ref() else {
            return;
        };
        let sample = self.chain.output_with(stream.layout.attitude);
        let status = crate::kernel::status::Status::of(&self.chain.health());
        let product = self.cfg.product;
        // Second fraction (5.2.3.1): ns since the current second began,
        // which is the last 1PPS edge or power-on advanced by whole seconds
        // (a division only when a second boundary has passed).
        let mut into_second = now.since(self.second_start);
        if into_second >= NS_PER_S {
            let whole = into_second - into_second % NS_PER_S;
            self.second_start = self.second_start.plus_nanos(whole);
            into_second -= whole;
        }
        let mut time_flags = 0;
        if self.pps_since_frame {
            time_flags |= 0x0001;
        }
        if now.since(self.last_pps.unwrap_or(self.powered_at)) > NS_PER_S {
            time_flags |= 0x0008;
        }
        // The counter advances at 2 kHz (Tables 5.7, 5.10 note 3).
        let counter = if product.model.internal_rate_hz == 4000 {
            self.ticks >> 1
        } else {
            self.ticks
        };
        let ctx = OutputCtx {
            sample: &sample,
            product: &product,
            counter: counter as u16,
            usw: status.usw,
            usw_ext: status.usw_ext,
            time_flags,
            second_fraction_ns: into_second as u32,
            imu_time_ns: now.since(self.powered_at),
        };
        let layout = &stream.layout;
        let tov = stream.tov;
        let len = layout.payload_len();
        let queued = queue_frame(&mut self.tx, code, len, |out| {
            let (head, body) = out.split_at_mut(layout.header.len());
            head.copy_from_slice(&layout.header);
            fields::write_all(&layout.fields, &ctx, body) == Some(body.len())
        });
        if let Some(end) = self.sent(queued, len) {
            self.pps_since_frame = false;
            if tov {
                let _ = self.events.push_back(Event::Tov {
                    level: Level::High,
                    at: now,
                });
                let _ = self.events.push_back(Event::Tov {
                    level: Level::Low,
                    at: end,
                });
            }
        }
    }

    /// Queues a device frame (`type 1`); drops it whole if it does not fit.
    /// Returns when its last bit will have left the line, assuming the UART
    /// sends the queue back to back at the current line rate.
    fn send(&mut self, id: u8, payload: &[u8]) -> Option<Instant> {
        let queued = queue_frame(&mut self.tx, id, payload.len(), |out| {
            out.copy_from_slice(payload);
            true
        });
        self.sent(queued, payload.len())
    }

    /// Accounts for a [`queue_frame`] of a `len`-byte payload: counts a
    /// dropped frame; when queued, when its last bit will have left the line.
    fn sent(&mut self, queued: Queued, len: usize) -> Option<Instant> {
        match queued {
            Queued::Yes => {}
            Queued::Full => {
                self.tx_dropped = self.tx_dropped.wrapping_add(1);
                return None;
            }
            Queued::No => return None,
        }
        let n = len + frame::OVERHEAD;
        let start = self.line_free_at.max(self.clock);
        let wire_ns = wire_ns(n, self.byte_time_ps);
        self.line_free_at = start.plus_nanos(wire_ns);
        Some(self.line_free_at)
    }

    /// Sets the line rate the device models (Formula 5.1, TOV timing).
    fn set_line_rate(&mut self, bps: u32) {
        self.line_rate = bps.max(1);
        // 10 bit times per byte on the wire, in picoseconds.
        self.byte_time_ps = 10_000_000_000_000 / u64::from(self.line_rate);
    }

    // ----- identification -----

    /// GetDevInfo payload (Table 5.17): serial, firmware string, IMU_type,
    /// both duplicated; 166 bytes.
    fn dev_info(&self) -> [u8; 166] {
        let mut p = [0u8; 166];
        // Serial: 8 ASCII digits (no core::fmt, which costs firmware flash).
        let mut sn = [b'0'; 8];
        let mut n = 10_000_000 + self.cfg.seed % 90_000_000;
        for d in sn.iter_mut().rev() {
            *d = b'0' + (n % 10) as u8;
            n /= 10;
        }
        let mut fw: heapless::String<64> = heapless::String::new();
        for part in [
            self.cfg.product.code().as_str(),
            " imu-emu ",
            env!("CARGO_PKG_VERSION"),
        ] {
            let _ = fw.push_str(part);
        }
        let fw = fw.as_bytes();
        let fw = &fw[..fw.len().min(40)];
        p[0..8].copy_from_slice(&sn);
        p[8..8 + fw.len()].copy_from_slice(fw);
        p[49] = self.cfg.product.model.imu_type;
        p[50..58].copy_from_slice(&sn);
        p[58..58 + fw.len()].copy_from_slice(fw);
        p
    }

    /// Reply to the vendor INS SDK's 0x41 request (NOTES.md): 60 bytes.
    fn device_parameters(&self) -> [u8; 60] {
        let mut p = [0u8; 60];
        let rate = params::DATA_RATE.read_int(&self.ram) as u16;
        let iat = params::INITIAL_ALIGNMENT_TIME.read_int(&self.ram) as u16;
        p[0..2].copy_from_slice(&rate.to_le_bytes());
        p[2..4].copy_from_slice(&iat.to_le_bytes());
        for i in 0..3 {
            let a = params::ALIGNMENT_ANGLES.read_f32(&self.ram, i);
            let v = fields::sat_i16(a, 100);
            p[23 + 2 * i..25 + 2 * i].copy_from_slice(&v.to_le_bytes());
        }
        p[50..56].copy_from_slice(b"KERNEL");
        p
    }
}
