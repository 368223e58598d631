//! The KERNEL personality: commands, parameters, UDD, streams and frame
//! emission (ICD 5.1, 5.3, section 6) through the shell's
//! [`Context`], and the KERNEL's convenience constructors of
//! [`Device`].

use core::mem::MaybeUninit;

use embedded_storage::nor_flash::NorFlash;

use crate::device::{Device, PowerOn};
use crate::dsp::integrals::NoIntegrals;
use crate::io::{Event, Level, Mode, Pin};
use crate::kernel::command::{self, Command};
use crate::kernel::fields::{self, Field, OutputCtx};
use crate::kernel::formats::{self, UDD};
use crate::kernel::frame::{self, Decoder, TYPE_COMMAND, TYPE_DATA};
use crate::kernel::model::{self, Capability};
use crate::kernel::params::{self, Apply, Block, ParamSpec, BLOCK_LEN};
use crate::kernel::{config, rate, status, udd};
use crate::line::TX_CAP;
use crate::model::Product;
use crate::personality::{Context, Personality};
use crate::store::KernelImage;
use crate::time::Instant;

/// Largest device → host frame: a UDD frame of [`params::UDD_MAX_TYPES`]
/// types of the largest field, 217 bytes (Table 5.13); GetDevInfo's is 174.
/// The shell's TX queue is sized by it ([`Kernel`]'s `TxBuffer`).
pub const MAX_FRAME: usize = 217;
/// A KERNEL device ([`Device`] carrying the [`Kernel`] personality).
pub type KernelDevice<F> = Device<F, Kernel>;

/// Largest host → device frame: a UDD config message `96 N` + 255 types.
pub const RX_FRAME_CAP: usize = frame::OVERHEAD + 2 + 255;
/// An incomplete frame with no new byte for this long is abandoned and the
/// decoder resyncs on the bytes after its first byte (a frame cut short).
pub const RX_IDLE_ABANDON_NS: u64 = 100_000_000;

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

/// The KERNEL protocol personality (ICD section 5): its decoder, the live
/// and saved parameter blocks (Table 5.24), the running stream.
pub struct Kernel {
    rx: Decoder<RX_FRAME_CAP>,
    /// Live parameters (what ReadRAM answers and the device runs with).
    ram: Block,
    /// The flash copy (what SaveFlash wrote).
    saved: Block,
    stream: Option<Stream>,
    udd_pending: bool,
    /// Last accepted EXTRIG edge (hold-off reference, 4.1.3).
    last_trigger: Option<Instant>,
}

impl Personality for Kernel {
    type Integrate = NoIntegrals;
    type Image = KernelImage;
    const IMAGE: KernelImage = KernelImage;
    type TxBuffer = [u8; TX_CAP + MAX_FRAME];

    #[inline(always)]
    fn unpowered() -> Self {
        Kernel {
            rx: Decoder::new(),
            ram: [0; BLOCK_LEN],
            saved: [0; BLOCK_LEN],
            stream: None,
            udd_pending: false,
            last_trigger: None,
        }
    }

    /// Parameters load from flash (factory defaults if it holds none), the
    /// line starts at Baud_Rate, AutoStart runs (section 6) unless BOOT put
    /// the device in firmware update.
    fn boot(&mut self, cx: &mut impl Context<NoIntegrals>, _now: Instant) {
        self.rx = Decoder::new();
        self.stream = None;
        self.udd_pending = false;
        self.last_trigger = None;
        let product = cx.product();
        let mut block = [0u8; BLOCK_LEN];
        if let Ok(true) = cx.load_image(&mut block) {
            params::sanitize(&mut block, &product);
        } else {
            block = params::factory_block(&product);
        }
        self.saved = block;
        self.ram = block;
        cx.chain_mut()
            .configure(&config::chain_config(&self.ram, &product));
        cx.set_line_rate(params::baud_rate(
            params::BAUD_RATE.read_int(&self.ram) as u8
        ));
        if cx.firmware_update() {
            return;
        }
        let auto = params::AUTO_START.read_int(&self.ram) as u8;
        if auto != 0 && product.model.supports_format(auto) {
            send(cx, 0x00, &formats::AUTOSTART_PAYLOAD);
            self.start_stream(cx, auto);
        }
    }

    /// Complete frames are executed at once; replies are queued.
    fn on_rx(&mut self, mut bytes: &[u8], cx: &mut impl Context<NoIntegrals>, _now: Instant) {
        while let Some(f) = self.rx.next_frame(&mut bytes) {
            if f.msg_type != TYPE_COMMAND || f.id != 0 {
                continue;
            }
            // Copy out of the decoder so it can be borrowed again.
            let mut payload = [0u8; RX_FRAME_CAP];
            let n = f.payload.len();
            payload[..n].copy_from_slice(f.payload);
            let checksum = f.checksum;
            self.execute(cx, &payload[..n], checksum);
        }
    }

    /// A frame cut short ([`RX_IDLE_ABANDON_NS`] without a byte) is
    /// abandoned.
    fn before_tick(&mut self, cx: &mut impl Context<NoIntegrals>, now: Instant) {
        if self.rx.has_partial() && now.since(cx.time().last_rx()) > RX_IDLE_ABANDON_NS {
            self.rx.abandon();
            cx.time_mut().touch_rx(now);
            self.on_rx(&[], cx, now);
        }
    }

    /// Alignment runs, output frames are produced at the data rate.
    fn on_tick(&mut self, cx: &mut impl Context<NoIntegrals>, now: Instant) {
        let Some(s) = self.stream.as_mut() else {
            return;
        };
        if s.align_left > 0 {
            s.align_left -= 1;
            if s.align_left == 0 {
                cx.chain_mut().end_alignment();
            }
            return;
        }
        s.countdown = s.countdown.saturating_sub(1);
        if s.countdown == 0 {
            s.countdown = s.divisor;
        }
        if !s.triggered && s.countdown == s.divisor {
            self.emit(cx, now);
        }
    }

    /// EXTRIG (4.1.3): with Trigger_Control = 1 on a model with EXTRIG,
    /// each edge of the Polarity parameter's sense (0 negative: falling,
    /// 1 positive: rising) sends one frame of the running format with the
    /// latest data at once; edges within Hold-off_Time ms of the last
    /// accepted one are ignored. Periodic output is off while triggering.
    fn on_pin(&mut self, pin: Pin, level: Level, cx: &mut impl Context<NoIntegrals>, at: Instant) {
        if pin != Pin::Extrig {
            return;
        }
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
        self.emit(cx, at);
    }

    fn mode(&self) -> Mode {
        match &self.stream {
            None => Mode::Idle,
            Some(s) if s.align_left > 0 => Mode::Aligning,
            Some(_) => Mode::Continuous,
        }
    }

    fn output_rate(&self, cx: &impl Context<NoIntegrals>) -> Option<u32> {
        self.stream
            .as_ref()
            .map(|s| cx.product().model.internal_rate_hz / s.divisor)
    }

    fn ticks_to_next_output(&self) -> Option<u64> {
        let s = self.stream.as_ref()?;
        if s.triggered {
            return None;
        }
        Some(s.align_left + u64::from(s.countdown))
    }
}

impl<F: NorFlash> Device<F, Kernel> {
    /// Powers a KERNEL on with BOOT floating and seed 0.
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

    /// Powers a KERNEL on: parameters load from flash (factory defaults if
    /// it holds none), BOOT is checked, AutoStart runs (section 6).
    pub fn power_on_with(cfg: PowerOn, flash: F, now: Instant) -> Self {
        Self::new(cfg, flash, now)
    }

    /// [`Device::power_on_with`] straight into `slot` ([`Device::new_into`]).
    pub fn power_on_into(
        slot: &mut MaybeUninit<Self>,
        cfg: PowerOn,
        flash: F,
        now: Instant,
    ) -> &mut Self {
        Self::new_into(slot, cfg, flash, now)
    }

    /// The live value of a KERNEL parameter (what ReadRAM answers), if the
    /// ID is one of Table 5.24.
    pub fn param_ram(&self, id: u16) -> Option<&[u8]> {
        self.personality().param_ram(id)
    }
}

/// Queues a device frame (`type 1`, Table 5.2) with a `len`-byte payload
/// that `fill` writes straight into the TX queue (`false`: send nothing).
/// Returns when its last bit will have left the line.
fn queue_frame(
    cx: &mut impl Context<NoIntegrals>,
    id: u8,
    len: usize,
    fill: impl FnOnce(&mut [u8]) -> bool,
) -> Option<Instant> {
    let len_field = u16::try_from(len + 6).ok()?.to_le_bytes();
    cx.push_frame(len + frame::OVERHEAD, |f| {
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
    })
}

/// The fields of `layout` written into `out`: a fixed format by its own
/// writer ([`formats::write_payload`], the same bytes as the loop over its
/// fields); UDD by the loop.
#[inline(always)]
fn write_payload(code: u8, layout: &Layout, ctx: &OutputCtx<'_>, out: &mut [u8]) -> Option<usize> {
    if layout.header.is_empty() {
        if let Some(n) = formats::write_payload(code, ctx, out) {
            return Some(n);
        }
    }
    fields::write_all(&layout.fields, ctx, out)
}

/// Queues a device frame with `payload`; dropped whole if it does not fit.
fn send(cx: &mut impl Context<NoIntegrals>, id: u8, payload: &[u8]) -> Option<Instant> {
    queue_frame(cx, id, payload.len(), |out| {
        out.copy_from_slice(payload);
        true
    })
}

impl Kernel {
    /// The live value of a parameter (what ReadRAM answers), if the ID is
    /// one of Table 5.24.
    pub fn param_ram(&self, id: u16) -> Option<&[u8]> {
        params::find(id).map(|p| p.bytes(&self.ram))
    }

    // ----- commands -----

    fn execute(&mut self, cx: &mut impl Context<NoIntegrals>, payload: &[u8], checksum: u16) {
        let parsed = Command::parse(payload);
        if core::mem::take(&mut self.udd_pending) {
            // The message after User_Def_Data_config is the configuration,
            // unless it is itself a command (5.3.5, docs/protocol-facts.md).
            match parsed {
                Ok(Command::Unknown(_)) | Err(_) => return self.udd_config(cx, payload, checksum),
                _ => {}
            }
        }
        let Ok(cmd) = parsed else {
            return;
        };
        match cmd {
            Command::Data(code) => {
                if cx.product().model.supports_format(code) {
                    send(cx, code, &checksum.to_le_bytes());
                    self.apply_saved();
                    self.start_stream(cx, code);
                }
            }
            Command::Stop => {
                self.stream = None;
                self.apply_saved();
            }
            Command::GetDevInfo => {
                let info = dev_info(cx);
                send(cx, command::GET_DEV_INFO, &info);
            }
            Command::GetBit => {
                let bit = status::bit(&cx.chain().health());
                send(cx, command::GET_BIT, &bit);
            }
            Command::UddConfig => self.udd_pending = true,
            Command::UddConfigMessage(list) => self.udd_config(cx, list, checksum),
            Command::GetUddStruct => {
                let mut p = [0u8; 1 + params::UDD_MAX_TYPES];
                let config = self.udd_config_now(cx);
                p[0] = config.len() as u8;
                p[1..1 + config.len()].copy_from_slice(&config);
                send(cx, command::GET_UDD_STRUCT, &p[..1 + config.len()]);
            }
            Command::CommitBaudRate => self.commit_baud_rate(cx),
            Command::DeviceParameters => {
                let p = self.device_parameters();
                send(cx, command::DEVICE_PARAMETERS, &p);
            }
            Command::SaveFlash { id, len, value } => self.save_flash(cx, id, len, value, checksum),
            Command::ReadRam { id, len } => {
                if let Some(p) = params::find(id).filter(|p| p.byte_len() == len) {
                    let mut v = [0u8; 12];
                    let n = usize::from(p.byte_len());
                    v[..n].copy_from_slice(p.bytes(&self.ram));
                    send(cx, 0xB1, &v[..n]);
                }
            }
            Command::Unknown(_) => {}
        }
    }

    /// SaveFlash (5.3.7): a wrong ID, wrong length, read-only parameter or
    /// bad value changes nothing and gets no answer; a valid one is written
    /// to flash (power-fail safe), acknowledged, and reaches RAM per
    /// [`Apply`].
    fn save_flash(
        &mut self,
        cx: &mut impl Context<NoIntegrals>,
        id: u16,
        len: u16,
        value: &[u8],
        checksum: u16,
    ) {
        let product = cx.product();
        let Some(p) = params::find(id) else {
            return;
        };
        if p.byte_len() != len || p.validate(value, &product, &self.saved).is_err() {
            return;
        }
        let mut next = self.saved;
        next[p.range()].copy_from_slice(value);
        if cx.save_image(&next).is_err() {
            return;
        }
        self.saved = next;
        send(cx, 0xB2, &checksum.to_le_bytes());
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
    fn commit_baud_rate(&mut self, cx: &mut impl Context<NoIntegrals>) {
        let p: &ParamSpec = &params::BAUD_RATE;
        let r = p.range();
        self.ram[r.clone()].copy_from_slice(&self.saved[r]);
        let rate = params::baud_rate(p.read_int(&self.ram) as u8);
        cx.switch_line_rate(rate);
        self.refresh_stream(cx);
    }

    /// Recomputes the running stream's layout and rate (after a baud-rate
    /// or UDD configuration change).
    fn refresh_stream(&mut self, cx: &impl Context<NoIntegrals>) {
        if let Some(code) = self.stream.as_ref().map(|s| s.code) {
            let layout = self.layout(cx, code);
            let divisor = self.divisor_for(cx, &layout);
            if let Some(s) = self.stream.as_mut() {
                s.divisor = divisor;
                s.countdown = s.countdown.min(divisor);
                s.layout = layout;
            }
        }
    }

    fn udd_config_now(&self, cx: &impl Context<NoIntegrals>) -> udd::Config {
        udd::read_config(&self.ram, &cx.product())
            .unwrap_or_else(|| udd::Config::from_slice(udd::DEFAULT_CONFIG).unwrap_or_default())
    }

    /// The configuration message after User_Def_Data_config (5.3.5):
    /// checked, answered with Table 5.20, persisted when accepted.
    fn udd_config(&mut self, cx: &mut impl Context<NoIntegrals>, payload: &[u8], checksum: u16) {
        let product = cx.product();
        let internal = product.model.internal_rate_hz;
        let line_rate = cx.line_rate();
        match udd::check(payload, &product) {
            udd::Checked::Ok(config) => {
                let max = rate::max_rate(line_rate, udd::payload_len(&config), internal);
                let requested = params::DATA_RATE.read_int(&self.ram);
                let errors = if requested > max { udd::ERR_RATE } else { 0 };
                udd::write_config(&mut self.ram, &config);
                udd::write_config(&mut self.saved, &config);
                // Persist; a flash failure leaves the new config in RAM only.
                let _ = cx.save_image(&self.saved);
                if self.stream.as_ref().is_some_and(|s| s.code == UDD) {
                    self.refresh_stream(cx);
                }
                let reply = udd::config_reply(checksum, errors, 0, max as u16);
                send(cx, command::UDD_CONFIG, &reply);
            }
            udd::Checked::Refused {
                errors,
                wrong_types,
            } => {
                let current = self.udd_config_now(cx);
                let max = rate::max_rate(line_rate, udd::payload_len(&current), internal);
                let reply = udd::config_reply(0, errors, wrong_types, max as u16);
                send(cx, command::UDD_CONFIG, &reply);
            }
        }
    }

    // ----- output -----

    /// The frame layout of data command `code`: a fixed format's fields, or
    /// the UDD header and the configured types' fields (Table 5.13).
    fn layout(&self, cx: &impl Context<NoIntegrals>, code: u8) -> Layout {
        let mut l = Layout::default();
        match formats::find(code) {
            Some(f) => {
                for &field in f.fields {
                    let _ = l.fields.push(field);
                }
            }
            None => {
                let config = self.udd_config_now(cx);
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
    fn divisor_for(&self, cx: &impl Context<NoIntegrals>, layout: &Layout) -> u32 {
        let internal = cx.product().model.internal_rate_hz;
        let requested = params::DATA_RATE.read_int(&self.ram);
        let eff = rate::effective_rate(requested, cx.line_rate(), layout.len, internal);
        internal / eff.max(1)
    }

    fn start_stream(&mut self, cx: &mut impl Context<NoIntegrals>, code: u8) {
        let layout = self.layout(cx, code);
        let divisor = self.divisor_for(cx, &layout);
        // A stream with orientation starts after the initial alignment
        // (5.3.1).
        let orientation = layout.attitude;
        let align_s = u64::from(params::INITIAL_ALIGNMENT_TIME.read_int(&self.ram));
        let product = cx.product();
        let internal = u64::from(product.model.internal_rate_hz);
        let chain = cx.chain_mut();
        chain.configure(&config::chain_config(&self.ram, &product));
        let align_left = if orientation { align_s * internal } else { 0 };
        if orientation {
            if align_left > 0 {
                chain.begin_alignment();
            } else {
                chain.skip_alignment();
            }
        }
        // The first frame's "1PPS received between the last and current
        // frame" (Table 5.8 time flags) covers the time since this data
        // command: a 1PPS edge while idle is not reported
        // (docs/kernel.md "Protocol notes").
        cx.time_mut().clear_pps_flag();
        self.stream = Some(Stream {
            code,
            divisor,
            countdown: divisor,
            align_left,
            layout,
            triggered: product.model.has(Capability::Extrig)
                && params::TRIGGER_CONTROL.read_int(&self.ram) == 1,
            tov: params::TOV_CONTROL.read_int(&self.ram) == 1,
        });
    }

    /// Produces one output frame of the running stream at `now`.
    fn emit(&mut self, cx: &mut impl Context<NoIntegrals>, now: Instant) {
        let Some(stream) = self.stream.as_ref() else {
            return;
        };
        let sample = cx.chain_mut().output_with(stream.layout.attitude);
        let status = status::Status::of(&cx.chain().health());
        let product = cx.product();
        // Second fraction (5.2.3.1).
        let into_second = cx.time_mut().second_fraction_ns(now);
        let mut time_flags = 0;
        if cx.time().pps_since_frame() {
            time_flags |= 0x0001;
        }
        if cx.time().pps_lost(now) {
            time_flags |= 0x0008;
        }
        // The counter advances at 2 kHz (Tables 5.7, 5.10 note 3).
        let counter = if product.model.internal_rate_hz == 4000 {
            cx.time().ticks() >> 1
        } else {
            cx.time().ticks()
        };
        let ctx = OutputCtx {
            sample: &sample,
            product: &product,
            counter: counter as u16,
            usw: status.usw,
            usw_ext: status.usw_ext,
            time_flags,
            second_fraction_ns: into_second as u32,
            imu_time_ns: now.since(cx.time().powered_at()),
        };
        let layout = &stream.layout;
        let tov = stream.tov;
        let code = stream.code;
        let end = queue_frame(cx, code, layout.len, |out| {
            let (head, body) = out.split_at_mut(layout.header.len());
            head.copy_from_slice(&layout.header);
            write_payload(code, layout, &ctx, body) == Some(body.len())
        });
        if let Some(end) = end {
            cx.time_mut().clear_pps_flag();
            if tov {
                cx.push_event(Event::Tov {
                    level: Level::High,
                    at: now,
                });
                cx.push_event(Event::Tov {
                    level: Level::Low,
                    at: end,
                });
            }
        }
    }

    /// Reply to the vendor INS SDK's 0x41 request (docs/protocol-facts.md): 60 bytes.
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

/// GetDevInfo payload (Table 5.17): serial, firmware string, IMU_type,
/// both duplicated; 166 bytes.
fn dev_info(cx: &impl Context<NoIntegrals>) -> [u8; 166] {
    let mut p = [0u8; 166];
    // Serial: 8 ASCII digits (no core::fmt, which costs firmware flash).
    let mut sn = [b'0'; 8];
    let mut n = 10_000_000 + cx.seed() % 90_000_000;
    for d in sn.iter_mut().rev() {
        *d = b'0' + (n % 10) as u8;
        n /= 10;
    }
    let product = cx.product();
    let mut fw: heapless::String<64> = heapless::String::new();
    for part in [
        product.code().as_str(),
        " imu-emu ",
        env!("CARGO_PKG_VERSION"),
    ] {
        let _ = fw.push_str(part);
    }
    let fw = fw.as_bytes();
    let fw = &fw[..fw.len().min(40)];
    p[0..8].copy_from_slice(&sn);
    p[8..8 + fw.len()].copy_from_slice(fw);
    p[49] = model::row(product.model).imu_type;
    p[50..58].copy_from_slice(&sn);
    p[58..58 + fw.len()].copy_from_slice(fw);
    p
}

/// The KERNEL against a fake context: what it asks of the shell, with no
/// shell (ARCHITECTURE.md "Shell and personalities").
#[cfg(test)]
mod tests {
    use std::vec::Vec;

    use super::*;
    use crate::personality::fake::FakeContext;

    type Cx = FakeContext<NoIntegrals>;

    fn booted() -> (Kernel, Cx) {
        let mut cx = Cx::new(Product::parse("KERNEL-110-G2000-A8").unwrap());
        let mut k = Kernel::unpowered();
        k.boot(&mut cx, Instant::ZERO);
        (k, cx)
    }

    #[test]
    fn the_tx_queue_takes_the_largest_udd_frame_and_dev_info() {
        let largest = udd::UDD_TYPES.iter().map(|t| t.field.size()).max().unwrap();
        let n = params::UDD_MAX_TYPES;
        assert_eq!(frame::OVERHEAD + 1 + n + n * largest, MAX_FRAME);
        let (_, cx) = booted();
        assert!(frame::OVERHEAD + dev_info(&cx).len() <= MAX_FRAME);
        assert_eq!(
            <<Kernel as Personality>::TxBuffer as crate::line::TxBuffer>::MAX_FRAME,
            MAX_FRAME
        );
    }

    fn command(c: Command<'_>) -> Vec<u8> {
        let mut out = [0u8; 300];
        let n = c.encode(&mut out).unwrap();
        out[..n].to_vec()
    }

    /// (id, payload) of a frame the personality pushed, its checksum checked.
    fn parsed(f: &[u8]) -> (u8, &[u8]) {
        let mut d = Decoder::<RX_FRAME_CAP>::new();
        let mut input = f;
        let fr = d.next_frame(&mut input).expect("a whole frame");
        assert_eq!(fr.msg_type, TYPE_DATA);
        let id = fr.id;
        (id, &f[6..f.len() - 2])
    }

    #[test]
    fn boot_from_an_empty_flash_sets_the_factory_line_rate_and_stays_idle() {
        let (k, cx) = booted();
        let factory = params::factory_block(&cx.product);
        let bps = params::baud_rate(params::BAUD_RATE.read_int(&factory) as u8);
        assert_eq!(cx.events, [Event::LineRate(bps)]);
        assert!(cx.frames.is_empty());
        assert_eq!(k.mode(), Mode::Idle);
        assert_eq!(k.output_rate(&cx), None);
    }

    #[test]
    fn get_dev_info_answers_with_the_serial_from_the_seed() {
        let (mut k, mut cx) = booted();
        k.on_rx(&command(Command::GetDevInfo), &mut cx, Instant::ZERO);
        assert_eq!(cx.frames.len(), 1);
        let (id, payload) = parsed(&cx.frames[0]);
        assert_eq!(id, command::GET_DEV_INFO);
        assert_eq!(payload.len(), 166);
        // Seed 7: 10 000 000 + 7.
        assert_eq!(&payload[0..8], b"10000007");
    }

    #[test]
    fn save_flash_writes_the_image_acknowledges_and_survives_a_boot() {
        let (mut k, mut cx) = booted();
        let p = &params::DATA_RATE;
        let value = 200u16.to_le_bytes();
        let frame = command(Command::SaveFlash {
            id: p.id,
            len: 2,
            value: &value,
        });
        k.on_rx(&frame, &mut cx, Instant::ZERO);
        let (id, _) = parsed(&cx.frames[0]);
        assert_eq!(id, 0xB2);
        assert!(cx.image.is_some());
        let mut again = Kernel::unpowered();
        again.boot(&mut cx, Instant::ZERO);
        assert_eq!(again.param_ram(p.id), Some(&value[..]));
    }

    #[test]
    fn a_data_command_streams_every_divisor_ticks_with_a_tov_pulse_per_frame() {
        let (mut k, mut cx) = booted();
        let tov_on = command(Command::SaveFlash {
            id: params::TOV_CONTROL.id,
            len: 1,
            value: &[1],
        });
        k.on_rx(&tov_on, &mut cx, Instant::ZERO);
        cx.frames.clear();
        k.on_rx(&command(Command::Data(0x8F)), &mut cx, Instant::ZERO);
        assert_eq!(parsed(&cx.frames[0]).0, 0x8F, "the acknowledgement");
        assert_eq!(k.mode(), Mode::Continuous);
        let rate = k.output_rate(&cx).unwrap();
        let internal = cx.product.model.internal_rate_hz;
        cx.frames.clear();
        cx.events.clear();
        for t in 1..=u64::from(internal) {
            let now = Instant(t * 1_000_000_000 / u64::from(internal));
            cx.tick(now);
            k.on_tick(&mut cx, now);
        }
        assert_eq!(cx.frames.len() as u32, rate);
        assert!(cx.frames.iter().all(|f| parsed(f).0 == 0x8F));
        // TOV high at the tick, low when the frame's last bit has left.
        assert_eq!(cx.events.len(), 2 * cx.frames.len());
        for pair in cx.events.chunks(2) {
            let [Event::Tov {
                level: Level::High,
                at: up,
            }, Event::Tov {
                level: Level::Low,
                at: down,
            }] = pair
            else {
                panic!("{pair:?}");
            };
            assert!(down > up);
        }
    }

    #[test]
    fn a_frame_cut_short_is_abandoned_after_the_idle_time() {
        let (mut k, mut cx) = booted();
        let f = command(Command::GetDevInfo);
        k.on_rx(&f[..3], &mut cx, Instant::ZERO);
        let quiet = Instant(RX_IDLE_ABANDON_NS / 2);
        k.before_tick(&mut cx, quiet);
        assert_eq!(cx.time.last_rx(), Instant::ZERO, "still waiting");
        let late = Instant(RX_IDLE_ABANDON_NS + 1);
        k.before_tick(&mut cx, late);
        assert_eq!(cx.time.last_rx(), late, "abandoned: the idle time restarts");
        // The rest of the frame alone is no frame.
        k.on_rx(&f[3..], &mut cx, late);
        assert!(cx.frames.is_empty());
    }
}
