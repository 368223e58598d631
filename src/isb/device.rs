//! The ISB personality: an emulated Inertial Sense IMX-5 in IMU mode on
//! the device shell (through its [`Context`]) — the same sensor model,
//! filters, pins, line and flash store as the KERNEL, speaking the ISB
//! protocol (`docs/isb-data-sets.md`, `docs/protocol-facts.md` "ISB").
//!
//! What it does with each input (decisions marked; `docs/isb.md`):
//!
//! - **GET_DATA** ([`message::resolve_get`]): NACK for DID ≥ 132 and 95,
//!   silence for an in-range DID it does not serve, else one DATA packet
//!   now and, with a period multiple `n > 0`, a stream every `n ×` the data
//!   set's source period ([`did::Source`], from the `startupImuDtMs` /
//!   `startupNavDtMs` latched at boot); `n = 0` stops that DID's stream.
//!   One stream per DID: a GET for a DID already streaming replaces its
//!   stream; *decision*: a GET identical to the running stream changes
//!   nothing and sends nothing (the vendor tool re-sends its GETs every
//!   second, and a second packet would split a PIMU window).
//! - **IMU, IMU_RAW, PIMU** are windows of the chain's cumulative
//!   integrals ([`crate::dsp::integrals`]): a stream's packet covers
//!   exactly the ticks since its previous packet (PIMU: coning- and
//!   sculling-corrected Δθ, Δv, with `dt` that window; IMU and IMU_RAW: the
//!   window's mean rate and specific force). The packet a GET sends at
//!   once covers the last whole source period (on the grid of periods
//!   counted from power-on), a stream starts where it ended and sends on
//!   that grid, so `time` is a multiple of the period and PIMU `dt` is
//!   always `n ×` the period. Axes: the IMX's body frame is forward,
//!   right, down; the chain's carrier frame is the KERNEL's (x, y, z up),
//!   so the IMX reports `(x, −y, −z)` — at rest `acc = (0, 0, −g)`.
//! - **SET_DATA** ([`message::apply_set`]): FLASH_CONFIG (checksum
//!   recomputed, saved to flash at the next tick: "flash write pending"
//!   until then; `startupImuDtMs`, `startupNavDtMs` and `ser0BaudRate`
//!   apply after a reset: "system reset required" while they differ from
//!   the running values), RMC (below), SYS_CMD (1 save persistent
//!   messages, 97 save flash, 99 software reset, 5 zero motion: accepted,
//!   no effect; 1122334455 then 1357924680: factory reset of FLASH_CONFIG,
//!   saved, then a reset; ignored unless `invCommand == !command`), SYS_PARAMS
//!   (`genFaultCode`), BIT (`command` ≠ 0 runs the test at once: state
//!   done, the result from the chain's BIT faults).
//! - **RMC**: its bits stand for the streams of the data sets that have an
//!   RMC bit (IMU, PIMU, STROBE_IN_TIME, IMU_RAW and the navigation sets;
//!   with `RMC_BITS_PRESET` the device picks the multiples, `docs/isb.md`); a SET starts those whose
//!   bit is set (period multiple 1) and, without `OPTIONS_PRESERVE_CTRL`,
//!   stops those whose bit is clear; `OPTIONS_PERSISTENT` then saves the
//!   streams as persistent. The port mask is ignored (one port). A GET of
//!   RMC reads the bits of the running streams.
//! - **Navigation** (INS_1..4, GPS1_POS, GPS1_VEL, GPS1_SAT, MAGNETOMETER,
//!   BAROMETER, SYS_SENSORS, IMU_MAG, PIMU_MAG): built by
//!   [`crate::isb::ins`] from [`crate::isb::nav::truth_of`], the INS and
//!   GNSS models stepped every [`ins::STEP_MS`]; GPS time from
//!   [`Isb::set_gps_time`]; faults from [`Isb::set_nav_faults`]
//!   (`docs/isb.md` "Navigation").
//! - **STROBE_IN_TIME** is sent on every rising EXTRIG edge while its
//!   stream is on (a GET with `n > 0`, or its RMC bit), counting edges
//!   since power-on, time of week = ms since power-on (no GPS).
//! - **Stops**: STOP_BROADCASTS_ALL_PORTS / CURRENT_PORT stop every stream
//!   and are ACKed; STOP_DID_BROADCAST stops one, no reply; `$STPB` and
//!   `$STPC` stop every stream, no reply.
//! - **NMEA**: `$INFO` is answered with the `$INFO` sentence, `$PERS`
//!   saves the running streams (ISB and NMEA) as persistent, `$SRST`
//!   resets (after the bytes already queued have been handed out),
//!   `$ASCE` sets or reads the NMEA streams ([`crate::isb::asce`],
//!   [`crate::isb::nmea_stream`]). Persistent streams start by themselves
//!   at every boot.
//! - **Host DATA** packets apply as SET_DATA, unanswered.
//! - **Status words** (IMU `status`, SYS_PARAMS `hdwStatus`) come from the
//!   chain's neutral health — the conditions behind the KERNEL's USW:
//!   saturation (since the previous packet), sensor faults, over-
//!   temperature — plus reset required, flash write pending, TX limited
//!   (a packet dropped because the line was too slow) and the parse-error
//!   count.
//!
//! This file is the [`Personality`] implementation and the device state;
//! its parts are in `device/`: `streams.rs` (the period grids, the
//! streams, when each is due), `requests.rs` (GET, SET, the stops, NMEA
//! commands, what a written set changes), `encode.rs` (one encoder per data
//! set, a table with one row per row of [`did::DATA_SETS`]),
//! `navigation.rs` (the INS on the navigation grid, the navigation sets),
//! `status.rs` (status words), `persist.rs` (the flash image),
//! `self_test.rs` (BIT), `identity.rs` (DEV_INFO), `nmea_hooks.rs` (the
//! NMEA streams) and `port_monitor.rs` (PORT_MONITOR's counts).

use core::cell::Cell;

use heapless::Vec;

use crate::chain::{ChainConfig, Health};
use crate::dsp::integrals::{self, Increment, Integrals};
use crate::io::{Level, Mode, Pin};
use crate::isb::asce;
use crate::isb::aux_sets::{self, Imu3, Imus, MagCal, SystemFault};
use crate::isb::can::{self, CanConfig};
use crate::isb::did::{self, DataSet};
use crate::isb::ins::{self, mech, NavConfig, NavFaults, NavState, StartTimes};
use crate::isb::message::{self, AckInfo, GetReply, GetRequest, Request, SetOutcome};
use crate::isb::nav::{self, GpsTime, NavTruth};
use crate::isb::nav_sets::{rmc_nav, InsHeader, SysSensors};
use crate::isb::nmea::{self, Command as Nmea, Event as Input_, Input};
use crate::isb::nmea_stream::{Epochs, NmeaStreams, Snapshot};
use crate::isb::packet::{Packet, PacketType, MAX_PACKET, OVERHEAD};
use crate::isb::sets::{
    self, bit, dev_info, flash, hdw_status, imu_status, le, rmc, sys_cmd, Bit, DevInfo,
    FlashConfig, Imu, Pimu, Rmc, StrobeInTime, SysParams, SystemCommand,
};
use crate::isb::{magcal, rtos};
use crate::personality::{Context, Personality};
use crate::store::ImageSpec;
use crate::time::Instant;

// DEV_INFO.
mod identity;
// One encoder per data set.
mod encode;
// The navigation side.
mod navigation;
// The NMEA streams' hooks (`$ASCE`, the sentences due at a tick).
mod nmea_hooks;
// What is kept in flash.
mod persist;
// PORT_MONITOR's byte counts.
mod port_monitor;
// GET, SET, stops, NMEA commands.
mod requests;
// BIT.
mod self_test;
// Status words.
mod status;
// Streams and the output grid.
mod streams;

use identity::dev_info_of;
use persist::ENTRY;
pub use persist::{IMAGE, IMAGE_LEN};
use port_monitor::{second_of, Counting, PortCounts};
use requests::push;
use status::imu_status_of;

/// Persistent streams the image holds (the first ten running streams are
/// saved; the image layout is unchanged since the IMU-mode device).
pub const MAX_STREAMS: usize = 10;
/// Streams the device runs at once (one per served data set).
pub const MAX_RUNNING: usize = did::DATA_SETS.len();
/// Largest frame the IMX writes in one piece: the largest data set
/// (GPS1_SAT, 408 bytes) with an offset (+ 2 payload bytes + 8 of
/// framing); the `$INFO` sentence is at most 200. The shell's TX queue is
/// sized by it ([`Isb`]'s `TxBuffer`).
pub(crate) const MAX_FRAME: usize = did::MAX_SIZE + 2 + 8;

/// An incomplete packet or sentence with no new byte for this long is
/// dropped (as the KERNEL does with a frame cut short).
pub const RX_IDLE_ABANDON_NS: u64 = 100_000_000;
/// Largest `$INFO` sentence ([`nmea::info_sentence`]).
const INFO_MAX: usize = 200;

/// One running stream.
#[derive(Debug, Clone, Copy)]
struct Stream {
    did: u8,
    offset: u16,
    size: u16,
    /// Period multiple of the GET (0 never: such a GET stops the stream).
    period: u16,
    /// Ticks between packets; 0: sent on events (STROBE_IN_TIME).
    every: u32,
    /// Ticks to the next packet.
    countdown: u32,
    /// The integrals at the previous packet (IMU, IMU_RAW, PIMU windows).
    start: Integrals,
}

/// The device state the input callback works on (beside the input
/// classifier, so the two can be borrowed apart).
struct State {
    /// FLASH_CONFIG as the device holds it (RAM); saved to flash when
    /// `save_pending`.
    cfg: FlashConfig,
    /// The persistent streams as saved (`u32 count` + entries).
    persist: [u8; 4 + MAX_STREAMS * ENTRY],
    /// The persistent NMEA table as saved.
    persist_nmea: [u8; asce::IMAGE_LEN],
    /// The NMEA streams (`$ASCE`).
    nmea: NmeaStreams,
    /// `startupImuDtMs`, `startupNavDtMs`, `ser0BaudRate` at boot (what
    /// runs until the next reset).
    imu_dt_ms: u32,
    nav_dt_ms: u32,
    baud: u32,
    save_pending: bool,
    streams: Vec<Stream, MAX_RUNNING>,
    rmc_options: u32,
    /// The integrals at the last two boundaries of the navigation period
    /// and of the IMU sample period (ticks since power-on a multiple of
    /// it): a one-shot IMU/PIMU covers the last whole period, a stream
    /// starts at the last boundary (module doc).
    nav_grid: [Integrals; 2],
    imu_grid: [Integrals; 2],
    /// The manufacturing unlock (SYS_CMD 1122334455) was the last command:
    /// a factory reset may follow.
    unlocked: bool,
    strobe_count: u16,
    bit: Bit,
    gen_fault_code: u32,
    /// MAG_CAL: the magnetometer recalibration ([`magcal`]).
    mag_cal: magcal::Recal,
    /// CAN_CONFIG as saved in flash ([`can`]).
    can: CanConfig,
    /// PORT_MONITOR: the serial port's byte counts.
    port: PortCounts,
    /// `tx_dropped` of the line at the last SYS_PARAMS (TX limited since).
    dropped_seen: u32,
    tx_limited: bool,
    /// ISB candidates dropped (bad checksum, size) since power-on.
    parse_errors: u32,
    /// `startupGPSDtMs` at boot.
    gps_dt_ms: u32,
    /// The navigation side: INS, GNSS, magnetometer, barometer.
    nav: NavState,
    /// The receiver's cold and warm start times (kept across resets).
    start_times: StartTimes,
    /// Whether the navigation filter runs ([`Isb::set_navigation`]).
    navigation: bool,
    /// GPS nanoseconds since the GPS epoch at device instant 0 (set by the
    /// board: `Isb::set_gps_time`).
    gps_ns_at_zero: u64,
    /// The navigation truth of a tick (read once a tick however many
    /// navigation packets go out: deriving it is `f64` work).
    truth: Cell<Option<(u64, NavTruth)>>,
}

/// The ISB personality (module doc): an IMX-5 in IMU mode.
pub struct Isb {
    input: Input<MAX_PACKET>,
    st: State,
}

impl Personality for Isb {
    type Integrate = Integrals;
    type Image = ImageSpec;
    const IMAGE: ImageSpec = IMAGE;
    type TxBuffer = [u8; crate::line::TX_CAP + MAX_FRAME];

    fn unpowered() -> Self {
        Isb {
            input: Input::new(),
            st: State {
                cfg: FlashConfig([0; flash::SIZE]),
                persist: [0; 4 + MAX_STREAMS * ENTRY],
                persist_nmea: [0; asce::IMAGE_LEN],
                nmea: NmeaStreams::default(),
                imu_dt_ms: flash::DEFAULT_IMU_DT_MS,
                nav_dt_ms: flash::DEFAULT_NAV_DT_MS,
                baud: flash::DEFAULT_BAUD_RATE,
                save_pending: false,
                streams: Vec::new(),
                rmc_options: 0,
                nav_grid: [Integrals::default(); 2],
                imu_grid: [Integrals::default(); 2],
                unlocked: false,
                strobe_count: 0,
                bit: Bit::default(),
                gen_fault_code: 0,
                mag_cal: magcal::Recal::default(),
                can: can::FACTORY,
                port: PortCounts::default(),
                dropped_seen: 0,
                tx_limited: false,
                parse_errors: 0,
                gps_dt_ms: flash::DEFAULT_GPS_DT_MS,
                nav: NavState::new(0),
                start_times: StartTimes::default(),
                navigation: true,
                gps_ns_at_zero: nav::DEFAULT_GPS_S_AT_ZERO * 1_000_000_000,
                truth: Cell::new(None),
            },
        }
    }

    /// FLASH_CONFIG and the persistent streams load from flash (factory
    /// defaults and none if it holds no valid ISB image, or one whose
    /// `key` is not the factory key); the startup
    /// periods and `ser0BaudRate` are latched; persistent streams start.
    fn boot(&mut self, cx: &mut impl Context<Integrals>, _now: Instant) {
        self.input = Input::new();
        let st = &mut self.st;
        st.load(cx);
        st.nmea = NmeaStreams::default();
        st.imu_dt_ms = st.cfg.startup_imu_dt_ms().clamp(1, 1000);
        st.nav_dt_ms = st.cfg.startup_nav_dt_ms().clamp(st.imu_dt_ms, 1000);
        st.baud = st.cfg.u32_at(flash::SER0_BAUD_RATE).clamp(300, 10_000_000);
        st.save_pending = false;
        st.streams.clear();
        st.rmc_options = 0;
        let at_boot = cx.chain().integrals();
        st.nav_grid = [at_boot; 2];
        st.imu_grid = [at_boot; 2];
        st.unlocked = false;
        st.strobe_count = 0;
        st.bit = Bit::default();
        st.gen_fault_code = 0;
        st.mag_cal = magcal::Recal::default();
        st.port = PortCounts::default();
        st.dropped_seen = cx.tx_dropped();
        st.tx_limited = false;
        st.parse_errors = 0;
        st.gps_dt_ms = st.cfg.u32_at(flash::STARTUP_GPS_DT_MS).clamp(200, 60_000);
        // Injected faults outlast a reset (the antenna is still cut).
        let faults = st.nav.faults();
        st.nav = NavState::new(cx.seed());
        st.nav.set_faults(faults);
        st.truth.set(None);
        let product = cx.product();
        cx.chain_mut().configure(&ChainConfig::defaults(&product));
        // The filter is tuned for the unit's own sensors, and starts warm
        // from a `lastLla` an earlier NAV saved.
        match cx.chain().profile() {
            Some(p) => st.nav.set_profile(p),
            None => st.nav.set_profile(&product.sensor_profile()),
        }
        st.nav.boot(&st.nav_config(), st.start_times);
        st.nav.set_enabled(st.navigation);
        cx.set_line_rate(st.baud);
        if cx.firmware_update() {
            return;
        }
        st.nmea.table = asce::Table::from_image(&st.persist_nmea);
        // The release's BIT at start-up (a moving-unit BIT: the unit may
        // not be at rest), unless sysCfgBits disables it.
        if st.cfg.u32_at(flash::SYS_CFG_BITS) & flash::SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP == 0
        {
            st.run_bit(cx, bit::CMD_BASIC_MOVING);
        }
        st.start_persistent(cx);
    }

    fn on_rx(&mut self, bytes: &[u8], cx: &mut impl Context<Integrals>, now: Instant) {
        let second = second_of(cx, now);
        let st = &mut self.st;
        st.port.received(second, bytes.len());
        let mut cc = Counting::new(cx);
        self.input.feed(bytes, |ev| match ev {
            Input_::Packet(p) => st.packet(&mut cc, &p, now),
            Input_::Nmea(c) => st.nmea(&mut cc, c, now),
            Input_::Asce(body) => st.asce(&mut cc, body),
        });
        st.port.sent(second, &cc.tally);
        st.parse_errors = self.input.isb_errors();
    }

    /// A packet or sentence cut short ([`RX_IDLE_ABANDON_NS`] without a
    /// byte) is dropped.
    fn before_tick(&mut self, cx: &mut impl Context<Integrals>, now: Instant) {
        if self.input.has_partial() && now.since(cx.time().last_rx()) > RX_IDLE_ABANDON_NS {
            self.input.abandon();
            cx.time_mut().touch_rx(now);
            self.st.parse_errors = self.input.isb_errors();
        }
    }

    /// The period grids advance; pending flash writes happen; every
    /// periodic stream due sends.
    fn on_tick(&mut self, cx: &mut impl Context<Integrals>, now: Instant) {
        let second = second_of(cx, now);
        let mut cc = Counting::new(cx);
        self.st.tick(&mut cc, now);
        self.st.port.sent(second, &cc.tally);
    }

    /// A rising EXTRIG edge is a strobe: counted, and sent as
    /// STROBE_IN_TIME while that stream is on.
    fn on_pin(&mut self, pin: Pin, level: Level, cx: &mut impl Context<Integrals>, at: Instant) {
        if (pin, level) != (Pin::Extrig, Level::High) {
            return;
        }
        let second = second_of(cx, at);
        let mut cc = Counting::new(cx);
        self.st.strobe(&mut cc, at);
        self.st.port.sent(second, &cc.tally);
    }

    fn mode(&self) -> Mode {
        if self.st.streams.iter().any(|s| s.every > 0) || self.st.nmea.streaming() {
            Mode::Continuous
        } else {
            Mode::Idle
        }
    }

    /// The rate of the fastest periodic stream.
    fn output_rate(&self, cx: &impl Context<Integrals>) -> Option<u32> {
        let every = self
            .st
            .streams
            .iter()
            .filter(|s| s.every > 0)
            .map(|s| s.every)
            .min()?;
        Some(cx.product().model.internal_rate_hz / every)
    }

    fn ticks_to_next_output(&self) -> Option<u64> {
        let isb = self
            .st
            .streams
            .iter()
            .filter(|s| s.every > 0)
            .map(|s| u64::from(s.countdown))
            .min();
        let nmea = self
            .st
            .nmea
            .streaming()
            .then_some(self.st.nmea.next_in.unwrap_or(1));
        match (isb, nmea) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

impl Isb {
    /// FLASH_CONFIG as the device holds it now (for the crate's tests).
    #[cfg(feature = "internals")]
    pub fn flash_config(&self) -> &FlashConfig {
        &self.st.cfg
    }

    /// The navigation state (INS phases, errors, faults), for the crate's
    /// tests and probes.
    #[cfg(feature = "internals")]
    pub fn nav(&self) -> &NavState {
        &self.st.nav
    }

    /// The navigation faults in force ([`Isb::set_nav_faults`]).
    pub fn nav_faults(&self) -> NavFaults {
        self.st.nav.faults()
    }

    /// Injects or clears navigation faults (GPS outage, magnetic
    /// disturbance, barometer failure); they outlast resets.
    pub fn set_nav_faults(&mut self, f: NavFaults) {
        self.st.nav.set_faults(f);
    }

    /// Sets the GPS time: `gps_ns_at_zero` GPS nanoseconds since
    /// 1980-01-06 at device instant 0 (a host passes its clock or
    /// `--gps-time`; firmware keeps [`nav::DEFAULT_GPS_S_AT_ZERO`]).
    pub fn set_gps_time(&mut self, gps_ns_at_zero: u64) {
        self.st.gps_ns_at_zero = gps_ns_at_zero;
    }

    /// `$ASCE` pairs dropped since power-on (unknown or out-of-range IDs,
    /// missing periods, more than 20 pairs); for the crate's tests.
    #[cfg(feature = "internals")]
    pub fn asce_rejected(&self) -> u32 {
        self.st.nmea.rejected
    }

    /// Sets the receiver's times to first fix from a cold and from a warm
    /// start (from the next power-on or reset); for the crate's tests.
    #[cfg(feature = "internals")]
    pub fn set_start_times(&mut self, t: StartTimes) {
        self.st.start_times = t;
    }

    /// Whether the navigation filter runs, now and at every power-on (on
    /// by default; [`NavState::set_enabled`]): a board whose processor
    /// cannot afford it turns it off.
    pub fn set_navigation(&mut self, on: bool) {
        self.st.navigation = on;
        self.st.nav.set_enabled(on);
    }

    /// DIDs streaming now, in the order they were started (for the
    /// crate's tests).
    #[cfg(feature = "internals")]
    pub fn streams(&self) -> impl Iterator<Item = u8> + '_ {
        self.st.streams.iter().map(|s| s.did)
    }
}

fn rate(cx: &impl Context<Integrals>) -> u32 {
    cx.product().model.internal_rate_hz
}

fn ms_since(cx: &impl Context<Integrals>, now: Instant) -> u32 {
    (now.since(cx.time().powered_at()) / 1_000_000) as u32
}

#[cfg(test)]
mod tests {
    use std::vec::Vec;

    use super::*;
    use crate::io::Event;
    use crate::isb::packet::Decoder;
    use crate::model::Product;
    use crate::personality::fake::FakeContext;

    type Cx = FakeContext<Integrals>;

    fn booted() -> (Isb, Cx) {
        let mut cx = Cx::new(Product::imx5());
        let mut d = Isb::unpowered();
        d.boot(&mut cx, Instant::ZERO);
        (d, cx)
    }

    fn get(did: u8, period: u16) -> Vec<u8> {
        let req = GetRequest {
            did: u16::from(did),
            size: 0,
            offset: 0,
            period,
        };
        let mut out = [0u8; 64];
        let n = message::encode_get(&req, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// The DIDs of the packets pushed, each checked whole.
    fn dids(cx: &Cx) -> Vec<u8> {
        let mut d = Decoder::<MAX_PACKET>::new();
        cx.frames
            .iter()
            .map(|f| {
                let mut input = &f[..];
                let did = d.next_packet(&mut input).expect("a whole packet").did;
                assert!(input.is_empty());
                did
            })
            .collect()
    }

    /// Ticks the context and the personality for `n` ticks from `*t`.
    fn run(d: &mut Isb, cx: &mut Cx, t: &mut u64, n: u64) {
        let period = 1_000_000_000 / u64::from(cx.product.model.internal_rate_hz);
        for _ in 0..n {
            *t += 1;
            let now = Instant(*t * period);
            d.before_tick(cx, now);
            cx.tick(now);
            d.on_tick(cx, now);
        }
    }

    #[test]
    fn boot_from_an_empty_flash_sets_the_factory_rate_and_stays_idle() {
        let (d, cx) = booted();
        let bps = FlashConfig::factory().u32_at(flash::SER0_BAUD_RATE);
        assert_eq!(cx.events, [Event::LineRate(bps)]);
        assert!(cx.frames.is_empty());
        assert_eq!(d.mode(), Mode::Idle);
        assert_eq!(d.output_rate(&cx), None);
    }

    #[test]
    fn a_get_with_period_zero_sends_one_packet_and_starts_nothing() {
        let (mut d, mut cx) = booted();
        d.on_rx(&get(did::DEV_INFO, 0), &mut cx, Instant::ZERO);
        assert_eq!(dids(&cx), [did::DEV_INFO]);
        assert_eq!(d.mode(), Mode::Idle);
    }

    #[test]
    fn an_imu_stream_sends_at_its_rate_and_stops_on_period_zero() {
        let (mut d, mut cx) = booted();
        let mut t = 0;
        d.on_rx(&get(did::IMU, 1), &mut cx, Instant::ZERO);
        assert_eq!(d.mode(), Mode::Continuous);
        let rate = d.output_rate(&cx).unwrap();
        let second = u64::from(cx.product.model.internal_rate_hz);
        cx.frames.clear();
        run(&mut d, &mut cx, &mut t, second);
        assert_eq!(cx.frames.len() as u32, rate);
        assert!(dids(&cx).iter().all(|&x| x == did::IMU));
        d.on_rx(&get(did::IMU, 0), &mut cx, Instant(t));
        assert_eq!(d.mode(), Mode::Idle);
        cx.frames.clear();
        run(&mut d, &mut cx, &mut t, 100);
        assert!(cx.frames.is_empty());
    }

    #[test]
    fn a_rising_extrig_edge_sends_strobe_in_time_while_its_stream_is_on() {
        let (mut d, mut cx) = booted();
        d.on_pin(Pin::Extrig, Level::High, &mut cx, Instant::ZERO);
        assert!(cx.frames.is_empty(), "no stream: counted only");
        d.on_rx(&get(did::STROBE_IN_TIME, 1), &mut cx, Instant::ZERO);
        cx.frames.clear();
        d.on_pin(Pin::Extrig, Level::Low, &mut cx, Instant(1_000));
        assert!(cx.frames.is_empty(), "falling edges are not strobes");
        d.on_pin(Pin::Extrig, Level::High, &mut cx, Instant(2_000));
        assert_eq!(dids(&cx), [did::STROBE_IN_TIME]);
    }
}
