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

use core::cell::Cell;

use heapless::Vec;

use crate::chain::{ChainConfig, Health};
use crate::dsp::integrals::{self, Increment, Integrals};
use crate::io::{Level, Mode, Pin};
use crate::isb::asce;
use crate::isb::aux_sets::{self, mag_cal_state, Imu3, Imus, MagCal, SystemFault};
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
use crate::personality::{Context, Personality};
use crate::store::ImageSpec;
use crate::time::Instant;

// The NMEA streams' hooks (`$ASCE`, the sentences due at a tick).
mod nmea_hooks;
// PORT_MONITOR's byte counts.
mod port_monitor;
use port_monitor::{second_of, Counting, PortCounts};

/// How long a magnetometer recalibration takes, ms (emulator's choice:
/// the unit is not asked to rotate, `docs/isb-data-sets.md` "MAG_CAL").
pub const MAG_RECAL_MS: u64 = 10_000;

/// Persistent streams the image holds (the first ten running streams are
/// saved; the image layout is unchanged since the IMU-mode device).
pub const MAX_STREAMS: usize = 10;
/// Streams the device runs at once (one per served data set).
pub const MAX_RUNNING: usize = did::DATA_SETS.len();
/// Bytes of one persistent-stream entry in the image: `u8 did, u8 0,
/// u16 size, u16 offset, u16 period`.
const ENTRY: usize = 8;
/// Where the persistent streams start in the image (after FLASH_CONFIG):
/// Largest frame the IMX writes in one piece: the largest data set
/// (GPS1_SAT, 408 bytes) with an offset (+ 2 payload bytes + 8 of
/// framing); the `$INFO` sentence is at most 200. The shell's TX queue is
/// sized by it ([`Isb`]'s `TxBuffer`).
pub const MAX_FRAME: usize = did::MAX_SIZE + 2 + 8;

/// `u32 count`, then [`MAX_STREAMS`] entries.
const PERSIST: usize = flash::SIZE;
/// Where the persistent NMEA table starts ([`asce::Table::to_image`]).
const PERSIST_NMEA: usize = PERSIST + 4 + MAX_STREAMS * ENTRY;
/// The ISB image in flash: FLASH_CONFIG, the persistent streams, the
/// persistent NMEA table.
pub const IMAGE_LEN: usize = PERSIST_NMEA + asce::IMAGE_LEN;
/// How the ISB image is stored ([`crate::store`]): its own magic, so a
/// flash written by the KERNEL personality is not taken for it. Version 2
/// added the NMEA table (a version-1 image loads as none: factory
/// defaults).
pub const IMAGE: ImageSpec = ImageSpec {
    len: IMAGE_LEN as u16,
    magic: *b"ISB1",
    version: 2,
};
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
    /// MAG_CAL: the last command's state and the tick it came at
    /// (`docs/isb-data-sets.md` "MAG_CAL").
    mag_cal: (u32, u64),
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
                mag_cal: (mag_cal_state::DO_NOTHING, 0),
                port: PortCounts::default(),
                dropped_seen: 0,
                tx_limited: false,
                parse_errors: 0,
                gps_dt_ms: flash::DEFAULT_GPS_DT_MS,
                nav: NavState::new(0),
                start_times: StartTimes::default(),
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
        let mut image = [0u8; IMAGE_LEN];
        let loaded = matches!(cx.load_image(&mut image), Ok(true));
        let mut cfg = FlashConfig([0; flash::SIZE]);
        cfg.0.copy_from_slice(&image[..PERSIST]);
        // A FLASH_CONFIG whose `key` is not the firmware's is replaced by
        // the factory defaults (docs/isb-data-sets.md).
        if loaded && cfg.is_valid() && cfg.key() == flash::FACTORY_KEY {
            st.cfg = cfg;
            st.persist.copy_from_slice(&image[PERSIST..PERSIST_NMEA]);
            st.persist_nmea.copy_from_slice(&image[PERSIST_NMEA..]);
        } else {
            st.cfg = FlashConfig::factory();
            st.persist = [0; 4 + MAX_STREAMS * ENTRY];
            st.persist_nmea = [0; asce::IMAGE_LEN];
        }
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
        st.mag_cal = (mag_cal_state::DO_NOTHING, 0);
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
        let n = (le::u32(&st.persist, 0) as usize).min(MAX_STREAMS);
        for k in 0..n {
            let e = &st.persist[4 + k * ENTRY..4 + (k + 1) * ENTRY];
            let req = GetRequest {
                did: u16::from(e[0]),
                size: le::u16(e, 2),
                offset: le::u16(e, 4),
                period: le::u16(e, 6),
            };
            if let GetReply::Serve {
                set,
                offset,
                size,
                period,
            } = message::resolve_get(&req)
            {
                if period > 0 {
                    st.start_stream(cx, set, offset, size, period);
                }
            }
        }
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
    /// FLASH_CONFIG as the device holds it now.
    pub fn flash_config(&self) -> &FlashConfig {
        &self.st.cfg
    }

    /// The navigation state (INS phases, errors, faults).
    pub fn nav(&self) -> &NavState {
        &self.st.nav
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

    /// The `$ASCE` table in force.
    pub fn nmea_table(&self) -> &asce::Table {
        &self.st.nmea.table
    }

    /// `$ASCE` pairs dropped since power-on (unknown or out-of-range IDs,
    /// missing periods, more than 20 pairs).
    pub fn asce_rejected(&self) -> u32 {
        self.st.nmea.rejected
    }

    /// Sets the receiver's times to first fix from a cold and from a warm
    /// start (from the next power-on or reset).
    pub fn set_start_times(&mut self, t: StartTimes) {
        self.st.start_times = t;
    }

    /// DIDs streaming now, in the order they were started.
    pub fn streams(&self) -> impl Iterator<Item = u8> + '_ {
        self.st.streams.iter().map(|s| s.did)
    }
}

/// Queues an ISB packet of `n` bytes written by `encode` (which returns
/// the length it wrote).
fn push(
    cx: &mut impl Context<Integrals>,
    n: usize,
    encode: impl FnOnce(&mut [u8]) -> Option<usize>,
) -> bool {
    cx.push_frame(n, |f| encode(f) == Some(n)).is_some()
}

fn send_ack(cx: &mut impl Context<Integrals>, info: &AckInfo, nack: bool) {
    push(cx, OVERHEAD + message::ACK_PAYLOAD_LEN, |f| {
        if nack {
            message::encode_nack(info, f)
        } else {
            message::encode_ack(info, f)
        }
    });
}

/// The chain's last measurement in the IMX body frame: rate (rad/s) and
/// specific force (m/s²).
fn last_measurement(cx: &impl Context<Integrals>) -> ([f32; 3], [f32; 3]) {
    let [g, a, _] = cx.chain().last_sensor();
    (
        frd(g.map(|x| f64::from(x).to_radians())),
        frd(a.map(|x| f64::from(x) * f64::from(crate::math::G))),
    )
}

/// `(x, y, z)` of the chain's carrier frame (the KERNEL's housing axes:
/// right, forward, up; ICD Figure 2.2) in the IMX body frame (forward,
/// right, down), the vehicle's body frame ([`crate::vehicle::housing_to_body`]),
/// so an IMX on a vehicle reads forward motion on its x axis.
fn frd(v: [f64; 3]) -> [f32; 3] {
    crate::vehicle::housing_to_body(&v).map(|x| x as f32)
}

impl State {
    /// The period grids advance; pending flash writes happen; every
    /// periodic stream due sends.
    fn tick(&mut self, cx: &mut impl Context<Integrals>, now: Instant) {
        let st = self;
        let (nav, imu) = (
            st.grid_ticks(cx, st.nav_dt_ms),
            st.grid_ticks(cx, st.imu_dt_ms),
        );
        let ticks = cx.time().ticks();
        // The receiver's models step half a navigation period after the
        // grid, on a tick of their own (the firmware's tick budget): a fix
        // enters the filter at the receiver's next epoch.
        if ticks % u64::from(st.grid_ticks(cx, ins::STEP_MS)) == u64::from(nav / 2) {
            let truth = st.truth(cx);
            st.nav.set_year(st.gps_time(cx).1.decimal_year());
            st.nav.step(ticks as f64 / f64::from(rate(cx)), &truth);
        }
        if ticks.is_multiple_of(u64::from(nav)) {
            st.nav_grid = [st.nav_grid[1], cx.chain().integrals()];
            st.navigate(cx);
        } else {
            st.nav_work(cx);
        }
        if ticks.is_multiple_of(u64::from(imu)) {
            st.imu_grid = [st.imu_grid[1], cx.chain().integrals()];
        }
        if st.save_pending {
            st.save(cx);
        }
        let mut sent = false;
        for i in 0..st.streams.len() {
            let s = &mut st.streams[i];
            if s.every == 0 {
                continue;
            }
            s.countdown = s.countdown.saturating_sub(1);
            if s.countdown == 0 {
                s.countdown = s.every;
                st.send_stream(cx, i, now);
                sent = true;
            }
        }
        if sent {
            // Saturation is reported since the previous packet.
            cx.chain_mut().restart_health_interval();
        }
        st.nmea_tick(cx, now);
    }

    /// A strobe (module doc).
    fn strobe(&mut self, cx: &mut impl Context<Integrals>, at: Instant) {
        let st = self;
        st.strobe_count = st.strobe_count.wrapping_add(1);
        if let Some(i) = st.find(did::STROBE_IN_TIME) {
            st.send_stream(cx, i, at);
        }
        let due = st.nmea.due_on_strobe();
        st.send_nmea(cx, due, at);
    }

    fn find(&self, did: u8) -> Option<usize> {
        self.streams.iter().position(|s| s.did == did)
    }

    /// Ticks per source period of `set` (at least 1).
    fn source_ticks(&self, rate_hz: u32, set: &DataSet) -> u32 {
        let ms = set
            .source
            .period_ms(self.imu_dt_ms, self.nav_dt_ms, self.gps_dt_ms);
        (ms.saturating_mul(rate_hz) / 1000).max(1)
    }

    /// Ticks in `ms` (at least 1).
    fn grid_ticks(&self, cx: &impl Context<Integrals>, ms: u32) -> u32 {
        (ms.saturating_mul(rate(cx)) / 1000).max(1)
    }

    /// The period grid a windowed data set lives on: IMU_RAW the IMU
    /// sample period's, the others the navigation period's.
    fn grid(&self, did: u8) -> [Integrals; 2] {
        if matches!(did, did::IMU_RAW | did::IMU3_RAW) {
            self.imu_grid
        } else {
            self.nav_grid
        }
    }

    /// Ticks of the period of [`Self::grid`]`(did)`.
    fn window_ticks(&self, cx: &impl Context<Integrals>, did: u8) -> u32 {
        let ms = if matches!(did, did::IMU_RAW | did::IMU3_RAW) {
            self.imu_dt_ms
        } else {
            self.nav_dt_ms
        };
        self.grid_ticks(cx, ms)
    }

    /// Starts (or replaces) the stream of `set`.
    fn start_stream(
        &mut self,
        cx: &impl Context<Integrals>,
        set: &DataSet,
        offset: u16,
        size: u16,
        period: u16,
    ) {
        let every = if set.did == did::STROBE_IN_TIME {
            0
        } else {
            self.source_ticks(cx.product().model.internal_rate_hz, set)
                .saturating_mul(u32::from(period))
        };
        // The first packet falls on the source period's grid (ticks since
        // power-on a multiple of it) and a windowed one covers `period`
        // whole source periods from the last boundary (module doc).
        let src = self.source_ticks(rate(cx), set);
        let phase = (cx.time().ticks() % u64::from(src)) as u32;
        let s = Stream {
            did: set.did,
            offset,
            size,
            period,
            every,
            countdown: every.saturating_sub(phase).max(1),
            start: self.grid(set.did)[1],
        };
        match self.find(set.did) {
            Some(i) => self.streams[i] = s,
            None => {
                let _ = self.streams.push(s);
            }
        }
    }

    fn stop_stream(&mut self, did: u8) {
        if let Some(i) = self.find(did) {
            self.streams.remove(i);
        }
    }

    // ----- input -----

    fn packet(&mut self, cx: &mut impl Context<Integrals>, p: &Packet<'_>, now: Instant) {
        match Request::of(p) {
            Request::Get(g) => self.get(cx, &g, now),
            Request::BadGet { rx_flags, rx_did } => {
                send_ack(cx, &AckInfo::of(rx_flags, rx_did), true)
            }
            Request::Set(req) => self.set(cx, &req, now, true),
            Request::Data(req) => self.set(cx, &req, now, false),
            Request::StopAllPorts | Request::StopCurrentPort => {
                self.streams.clear();
                self.nmea.table.stop();
                send_ack(cx, &AckInfo::of(p.flags, p.did), false);
            }
            Request::StopDid(did) => self.stop_stream(did),
            Request::Ignored => {}
        }
    }

    fn get(&mut self, cx: &mut impl Context<Integrals>, g: &GetRequest, now: Instant) {
        match message::resolve_get(g) {
            GetReply::Nack => send_ack(cx, &AckInfo::of(PacketType::GetData as u8, 0), true),
            GetReply::Silent => {}
            GetReply::Serve {
                set,
                offset,
                size,
                period,
            } => {
                let running = self.find(set.did).map(|i| self.streams[i]);
                if period > 0
                    && running
                        .is_some_and(|s| (s.offset, s.size, s.period) == (offset, size, period))
                {
                    return;
                }
                self.send_once(cx, set, offset, size, now);
                if period == 0 {
                    self.stop_stream(set.did);
                } else {
                    self.start_stream(cx, set, offset, size, period);
                }
            }
        }
    }

    fn set(
        &mut self,
        cx: &mut impl Context<Integrals>,
        req: &message::SetRequest<'_>,
        now: Instant,
        reply: bool,
    ) {
        let mut image = [0u8; did::MAX_SIZE];
        let n = self.image_of(cx, req.did, &mut image, now);
        let outcome = message::apply_set(req, &mut image[..n]);
        // Host DATA: the same effect, no ACK or NACK.
        let send_ack = |cx: &mut _, info: &AckInfo, nack| {
            if reply {
                send_ack(cx, info, nack);
            }
        };
        match outcome {
            SetOutcome::Nack(info) | SetOutcome::Refused(info) => send_ack(cx, &info, true),
            SetOutcome::Silent => {}
            SetOutcome::AckOnly(info) => send_ack(cx, &info, false),
            SetOutcome::Written { ack, .. }
                if req.did == did::FLASH_CONFIG && !ins::flash_nav_valid(&image[..n]) =>
            {
                send_ack(cx, &ack, true)
            }
            SetOutcome::Written { ack, .. } => {
                // The ACK goes first: a software reset clears the queue
                // only after it has been handed out.
                send_ack(cx, &ack, false);
                self.written(cx, req.did, &image[..n]);
            }
        }
    }

    /// Acts on a data set written by a SET_DATA (module doc).
    fn written(&mut self, cx: &mut impl Context<Integrals>, did: u8, image: &[u8]) {
        match did {
            did::FLASH_CONFIG => {
                self.cfg.0.copy_from_slice(&image[..flash::SIZE]);
                self.cfg.update_checksum();
                self.save_pending = true;
            }
            did::RMC => {
                let mut b = [0u8; rmc::SIZE];
                b.copy_from_slice(&image[..rmc::SIZE]);
                self.rmc(cx, &Rmc::decode(&b));
            }
            did::SYS_CMD => {
                let mut b = [0u8; sys_cmd::SIZE];
                b.copy_from_slice(&image[..sys_cmd::SIZE]);
                let cmd = SystemCommand::decode(&b).valid();
                let unlocked = core::mem::replace(&mut self.unlocked, false);
                match cmd {
                    Some(sys_cmd::SAVE_PERSISTENT_MESSAGES) => self.save_persistent(cx),
                    Some(sys_cmd::SAVE_FLASH) => self.save(cx),
                    Some(sys_cmd::SOFTWARE_RESET) => self.software_reset(cx),
                    Some(sys_cmd::MANF_UNLOCK) => self.unlocked = true,
                    // FLASH_CONFIG back to the factory defaults, saved, then
                    // a reset (docs/isb.md); only right after the unlock.
                    Some(sys_cmd::MANF_FACTORY_RESET) if unlocked => {
                        self.cfg = FlashConfig::factory();
                        self.save(cx);
                        cx.request_reset();
                    }
                    _ => {}
                }
            }
            did::SYS_PARAMS => {
                self.gen_fault_code = le::u32(image, sets::sys_params::GEN_FAULT_CODE);
            }
            did::NMEA_BCAST_PERIOD => {
                let mut b = [0u8; asce::nmea_msgs::SIZE];
                b.copy_from_slice(&image[..asce::nmea_msgs::SIZE]);
                let a = self.nmea.table.apply_msgs(&b);
                self.nmea.rejected = self.nmea.rejected.wrapping_add(u32::from(a.rejected));
                self.nmea.next_in = Some(1);
                if a.persistent {
                    self.save_persistent(cx);
                }
            }
            did::MAG_CAL => {
                let state = le::u32(image, aux_sets::mag_cal::STATE);
                let tick = cx.time().ticks();
                match state {
                    mag_cal_state::MULTI_AXIS | mag_cal_state::SINGLE_AXIS => {
                        self.mag_cal = (mag_cal_state::RECAL_RUNNING, tick)
                    }
                    mag_cal_state::ABORT => self.mag_cal = (mag_cal_state::DO_NOTHING, tick),
                    _ => {}
                }
            }
            did::BIT if image[bit::COMMAND] != bit::CMD_NONE => {
                self.run_bit(cx, image[bit::COMMAND]);
            }
            _ => {}
        }
    }

    /// An RMC write (module doc).
    fn rmc(&mut self, cx: &mut impl Context<Integrals>, r: &Rmc) {
        let preserve = r.options & rmc::OPTIONS_PRESERVE_CTRL != 0;
        let preset = r.bits & rmc::BITS_PRESET != 0;
        for set in did::DATA_SETS.iter().filter(|s| s.rmc_bit != 0) {
            if r.bits & set.rmc_bit != 0 {
                // A preset chooses the period multiples (docs/isb.md): in
                // a PPD preset INS_2 every 100 ms, everything else at its
                // source period.
                let ppd = preset && r.bits & rmc_nav::BITS_INTERNAL_PPD != 0;
                let n = if ppd && set.did == did::INS_2 {
                    (rmc_nav::PPD_NAV_PERIOD_MS / self.nav_dt_ms).max(1) as u16
                } else {
                    1
                };
                let same = self.find(set.did).map(|i| self.streams[i].period);
                if same.is_none() || (preset && same != Some(n)) {
                    self.start_stream(cx, set, 0, set.size, n);
                }
            } else if !preserve {
                self.stop_stream(set.did);
            }
        }
        self.rmc_options = r.options;
        if r.options & rmc::OPTIONS_PERSISTENT != 0 {
            self.save_persistent(cx);
        }
    }

    fn nmea(&mut self, cx: &mut impl Context<Integrals>, c: Nmea, _now: Instant) {
        match c {
            Nmea::Info => {
                let mut out = [0u8; INFO_MAX];
                if let Some(n) = nmea::info_sentence(&dev_info_of(cx), &mut out) {
                    cx.push_frame(n, |f| {
                        f.copy_from_slice(&out[..n]);
                        true
                    });
                }
            }
            Nmea::StopAllPorts | Nmea::StopCurrentPort => {
                self.streams.clear();
                self.nmea.table.stop();
            }
            Nmea::SavePersistent => self.save_persistent(cx),
            Nmea::SoftwareReset => self.software_reset(cx),
        }
    }

    // ----- flash -----

    /// The running streams become the persistent ones, saved at once: the
    /// first [`MAX_STREAMS`] of them (up to [`MAX_RUNNING`] run; the flash
    /// image keeps its layout).
    fn save_persistent(&mut self, cx: &mut impl Context<Integrals>) {
        self.persist = [0; 4 + MAX_STREAMS * ENTRY];
        let n = self.streams.len().min(MAX_STREAMS);
        le::put(&mut self.persist, 0, &(n as u32).to_le_bytes());
        for (k, s) in self.streams.iter().take(n).enumerate() {
            let e = &mut self.persist[4 + k * ENTRY..4 + (k + 1) * ENTRY];
            e[0] = s.did;
            le::put(e, 2, &s.size.to_le_bytes());
            le::put(e, 4, &s.offset.to_le_bytes());
            le::put(e, 6, &s.period.max(1).to_le_bytes());
        }
        self.persist_nmea = self.nmea.table.to_image();
        self.save(cx);
    }

    /// A software reset (`$SRST`, SYS_CMD): a FLASH_CONFIG write still
    /// waiting for its tick is saved first, since the reset discards the
    /// RAM copy and the write was acknowledged (a write and a reset within
    /// one tick kept the old line rate).
    fn software_reset(&mut self, cx: &mut impl Context<Integrals>) {
        if self.save_pending {
            self.save(cx);
        }
        cx.request_reset();
    }

    /// Writes FLASH_CONFIG and the persistent streams (power-fail safe); a
    /// flash failure leaves the write pending.
    fn save(&mut self, cx: &mut impl Context<Integrals>) {
        let mut image = [0u8; IMAGE_LEN];
        image[..PERSIST].copy_from_slice(&self.cfg.0);
        image[PERSIST..PERSIST_NMEA].copy_from_slice(&self.persist);
        image[PERSIST_NMEA..].copy_from_slice(&self.persist_nmea);
        self.save_pending = cx.save_image(&image).is_err();
    }

    fn run_bit(&mut self, cx: &impl Context<Integrals>, command: u8) {
        let h = cx.chain().health();
        let mut hdw = bit::HDW_PASSED_NO_GPS;
        if h.gyro_bit_failed {
            hdw = bit::HDW_FAULT_NOISE_PQR;
        }
        if h.accel_bit_failed {
            hdw = if h.gyro_bit_failed {
                bit::HDW_FAULT_NOISE_PQR | bit::HDW_FAULT_NOISE_ACC
            } else {
                bit::HDW_FAULT_NOISE_ACC
            };
        }
        self.bit = Bit {
            command: bit::CMD_NONE,
            last_command: command,
            state: bit::STATE_DONE,
            hdw_bit_status: hdw,
            cal_bit_status: bit::CAL_PASSED_ALL,
            ..Bit::default()
        };
    }

    // ----- output -----

    /// The current bytes of data set `did` into `out`; its size.
    fn image_of(
        &self,
        cx: &mut impl Context<Integrals>,
        did: u8,
        out: &mut [u8; did::MAX_SIZE],
        now: Instant,
    ) -> usize {
        let mut put = |b: &[u8]| {
            out[..b.len()].copy_from_slice(b);
            b.len()
        };
        match did {
            did::DEV_INFO => put(&dev_info_of(cx).encode()),
            did::FLASH_CONFIG => put(&self.cfg.0),
            did::SYS_PARAMS => put(&self.sys_params(cx, now).encode()),
            did::RMC => put(&Rmc {
                bits: self.rmc_bits(),
                options: self.rmc_options,
            }
            .encode()),
            did::SYS_CMD => put(&SystemCommand::default().encode()),
            did::NMEA_BCAST_PERIOD => put(&self.nmea.table.to_msgs()),
            did::BIT => put(&self.bit.encode()),
            // A unit that never faulted: all zeros (`docs/isb-data-sets.md`).
            did::SYS_FAULT => put(&SystemFault::default().encode()),
            did::GPS1_VERSION => put(&aux_sets::RECEIVER_VERSION.encode()),
            did::MAG_CAL => put(&self.mag_cal_of(cx).encode()),
            did::PORT_MONITOR => put(&self.port_monitor(cx, now).encode()),
            did::STROBE_IN_TIME => {
                // GPS time of the edge once GPS time is known.
                let (week, time_of_week_ms) = if self.nav.gps_time_valid() {
                    let since = now.since(cx.time().powered_at());
                    let t = GpsTime::of_ns(self.gps_ns_at_zero + cx.time().powered_at().0 + since);
                    (t.week, t.tow_ms())
                } else {
                    (0, ms_since(cx, now))
                };
                put(&StrobeInTime {
                    week,
                    time_of_week_ms,
                    pin: 0,
                    count: self.strobe_count,
                }
                .encode())
            }
            did::INS_1
            | did::INS_2
            | did::INS_3
            | did::INS_4
            | did::GPS1_POS
            | did::GPS1_RCVR_POS
            | did::GPS1_VEL
            | did::GPS1_SAT
            | did::GPS1_SIG
            | did::MAGNETOMETER
            | did::BAROMETER
            | did::INL2_STATES
            | did::INL2_NED_SIGMA => {
                let hdw = self.sys_params(cx, now).hdw_status;
                self.nav_image(cx, did, hdw, out)
            }
            did::SYS_SENSORS => put(&self.sys_sensors(cx).encode()),
            d if is_windowed(d) => {
                let [a, b] = self.grid(did);
                let w = integrals::window(&a, &b, rate(cx));
                let end =
                    cx.time().ticks() - cx.time().ticks() % u64::from(self.window_ticks(cx, did));
                self.windowed(cx, did, &w, end, out)
            }
            _ => 0,
        }
    }

    /// The navigation truth at the last tick ([`nav::truth_of`], once a
    /// tick).
    fn truth(&self, cx: &impl Context<Integrals>) -> NavTruth {
        let tick = cx.time().ticks();
        match self.truth.get() {
            Some((t, truth)) if t == tick => truth,
            _ => {
                let truth = nav::truth_of(cx.chain());
                self.truth.set(Some((tick, truth)));
                truth
            }
        }
    }

    /// `(since boot, GPS time)` at the last tick (on the sample grid).
    fn gps_time(&self, cx: &impl Context<Integrals>) -> (u64, GpsTime) {
        let since_boot = cx.time().ticks() * (1_000_000_000 / u64::from(rate(cx)));
        let gps = self.gps_ns_at_zero + cx.time().powered_at().0 + since_boot;
        (since_boot, GpsTime::of_ns(gps))
    }

    /// The FLASH_CONFIG fields the navigation uses.
    fn nav_config(&self) -> NavConfig {
        let b = &self.cfg.0;
        let f64x3 = |off: usize| [0, 8, 16].map(|k| le::f64(b, off + k));
        NavConfig {
            ref_lla: f64x3(flash::REF_LLA),
            last_lla: f64x3(flash::LAST_LLA),
            ins_rotation: le::f32x3(b, flash::INS_ROTATION),
            ins_offset: le::f32x3(b, flash::INS_OFFSET),
            gps1_ant_offset: le::f32x3(b, flash::GPS1_ANT_OFFSET),
            last_lla_week: le::u32(b, flash::LAST_LLA_WEEK),
            last_lla_update_distance: le::f32(b, flash::LAST_LLA_UPDATE_DISTANCE),
            sys_cfg_bits: le::u32(b, flash::SYS_CFG_BITS),
        }
    }

    /// One navigation period of the INS (at each boundary of the
    /// navigation grid): the chain's coning- and sculling-corrected
    /// increments of the period — the Δθ, Δv a PIMU of that period reports
    /// — in body axes, the receiver's fix, the magnetometer and barometer
    /// as the unit reads them; then `lastLla` saved if the INS asks.
    fn navigate(&mut self, cx: &mut impl Context<Integrals>) {
        let w = integrals::window(&self.nav_grid[0], &self.nav_grid[1], rate(cx));
        let tick = cx.time().ticks();
        let t_s = tick as f64 / f64::from(rate(cx));
        let inc = mech::Increment {
            dtheta: crate::vehicle::housing_to_body(&w.dtheta_rad),
            dv: crate::vehicle::housing_to_body(&w.dv_mps),
            dt: w.samples as f64 / f64::from(rate(cx)),
        };
        let cfg = self.nav_config();
        let gps_dt_s = f64::from(self.gps_dt_ms) / 1000.0;
        let (_, gps) = self.gps_time(cx);
        // The aiding sensors are read at the receiver's epochs only, by the
        // INS on the ticks that follow (`nav_work`).
        let epoch = self.nav.epoch_due(t_s, gps_dt_s).then(|| {
            let year = ins::decimal_year(gps.week as f64 * nav::WEEK_S as f64 + gps.tow_s());
            (self.truth(cx), tick, year)
        });
        self.nav.navigate_truth(t_s, &inc, gps_dt_s, epoch, &cfg);
        self.save_last_lla(cx);
    }

    /// A share of the INS's pending work (its covariance propagation, a
    /// receiver epoch's aiding) on a tick between navigation periods:
    /// the firmware's tick budget (`docs/performance.md`).
    fn nav_work(&mut self, cx: &mut impl Context<Integrals>) {
        if self.nav.work() {
            self.save_last_lla(cx);
        }
    }

    /// `lastLla` saved if the INS asks, stamped with the GPS time of the
    /// navigation period it was found in.
    fn save_last_lla(&mut self, cx: &mut impl Context<Integrals>) {
        let Some(lla) = self.nav.take_last_lla() else {
            return;
        };
        let (_, gps) = self.gps_time(cx);
        let nav_ticks = u64::from(self.grid_ticks(cx, self.nav_dt_ms));
        let back = (cx.time().ticks() % nav_ticks) * (1_000_000_000 / u64::from(rate(cx)));
        let gps = GpsTime::of_ns(
            (u64::from(gps.week) * nav::WEEK_S * 1_000_000_000 + gps.tow_ns).saturating_sub(back),
        );
        for (k, x) in lla.iter().enumerate() {
            le::put(&mut self.cfg.0, flash::LAST_LLA + 8 * k, &x.to_le_bytes());
        }
        le::put(
            &mut self.cfg.0,
            flash::LAST_LLA_TIME_OF_WEEK_MS,
            &gps.tow_ms().to_le_bytes(),
        );
        le::put(
            &mut self.cfg.0,
            flash::LAST_LLA_WEEK,
            &gps.week.to_le_bytes(),
        );
        self.cfg.update_checksum();
        self.save_pending = true;
    }

    /// The bytes of a navigation data set now (`docs/isb.md`
    /// "Navigation").
    fn nav_image(
        &self,
        cx: &impl Context<Integrals>,
        did: u8,
        hdw: u32,
        out: &mut [u8; did::MAX_SIZE],
    ) -> usize {
        let mut put = |b: &[u8]| {
            out[..b.len()].copy_from_slice(b);
            b.len()
        };
        let truth = self.truth(cx);
        let cfg = self.nav_config();
        let (since_ns, gps) = self.gps_time(cx);
        // INS, the filter's states and sigmas, magnetometer, barometer:
        // stamped on their output grid (the last multiple of the source
        // period: the navigation step the state is from), as streams are,
        // also in a one-shot GET and a stream's first packet.
        let back = match did::lookup(u16::from(did)) {
            Some(set)
                if matches!(
                    did,
                    did::INS_1
                        | did::INS_2
                        | did::INS_3
                        | did::INS_4
                        | did::INL2_STATES
                        | did::INL2_NED_SIGMA
                        | did::MAGNETOMETER
                        | did::BAROMETER
                ) =>
            {
                let ms = set
                    .source
                    .period_ms(self.imu_dt_ms, self.nav_dt_ms, self.gps_dt_ms);
                since_ns % (u64::from(ms.max(1)) * 1_000_000)
            }
            _ => 0,
        };
        let since_ns = since_ns - back;
        let gps = GpsTime::of_ns(
            (u64::from(gps.week) * nav::WEEK_S * 1_000_000_000 + gps.tow_ns).saturating_sub(back),
        );
        let since_s = since_ns as f64 / 1e9;
        let valid = self.nav.gps_time_valid();
        let h = InsHeader {
            week: if valid { gps.week } else { 0 },
            time_of_week: if valid { gps.tow_s() } else { since_s },
            ins_status: self.nav.ins_status(),
            hdw_status: hdw,
        };
        // The receiver's last epoch (GPS time a multiple of its period).
        let gps_dt_ns = u64::from(self.gps_dt_ms) * 1_000_000;
        let epoch = if valid {
            GpsTime {
                week: gps.week,
                tow_ns: gps.tow_ns - gps.tow_ns % gps_dt_ns,
            }
        } else {
            GpsTime {
                week: 0,
                tow_ns: since_ns - since_ns % gps_dt_ns,
            }
        };
        let tow_offset = if valid { gps.tow_s() - since_s } else { 0.0 };
        // The receiver's fix only where it is reported (a conversion in
        // soft double precision on the M4F).
        let fix = || self.nav.gnss(&truth, &cfg);
        let tick = cx.time().ticks();
        match did {
            did::INS_1 => put(&ins::ins1(&h, &self.nav.solution(&truth, &cfg), &cfg).encode()),
            did::INS_2 => put(&ins::ins2(&h, &self.nav.solution(&truth, &cfg)).encode()),
            did::INS_3 => put(&ins::ins3(&h, &self.nav.solution(&truth, &cfg)).encode()),
            did::INS_4 => put(&ins::ins4(&h, &self.nav.solution(&truth, &cfg)).encode()),
            // Without RTK the receiver's solution is GPS1_POS.
            did::GPS1_POS | did::GPS1_RCVR_POS => {
                put(&ins::gps_pos(&epoch, fix(), tow_offset).encode())
            }
            did::GPS1_VEL => put(&ins::gps_vel(&epoch, fix()).encode()),
            did::GPS1_SAT => put(&self.nav.gps_sat(&epoch).encode()),
            // The signals of the satellites GPS1_SAT reports.
            did::GPS1_SIG => put(&aux_sets::gps_sig_of(&self.nav.gps_sat(&epoch)).encode()),
            did::MAGNETOMETER => {
                put(&ins::magnetometer(since_s, self.nav.magnetometer(&truth, tick)).encode())
            }
            did::BAROMETER => {
                let p = self.nav.pressure_kpa(&truth, tick);
                put(&ins::barometer(since_s, p, cx.chain().temperature()).encode())
            }
            did::INL2_STATES => put(&self.nav.inl2_states(h.time_of_week).encode()),
            did::INL2_NED_SIGMA => {
                let ms = if valid {
                    gps.tow_ms()
                } else {
                    (since_ns / 1_000_000) as u32
                };
                put(&self.nav.inl2_ned_sigma(ms).encode())
            }
            _ => 0,
        }
    }

    fn rmc_bits(&self) -> u64 {
        self.streams
            .iter()
            .filter_map(|s| did::lookup(u16::from(s.did)))
            .fold(0, |b, set| b | set.rmc_bit)
    }

    /// IMU / IMU_RAW / PIMU (and IMU_MAG / PIMU_MAG: the same then the
    /// magnetometer at the window's end) of the window `w` into `image`
    /// (module doc); its size.
    fn windowed(
        &self,
        cx: &impl Context<Integrals>,
        did: u8,
        w: &Increment,
        end_tick: u64,
        image: &mut [u8; did::MAX_SIZE],
    ) -> usize {
        let h = cx.chain().health();
        let status = imu_status_of(&h);
        // On the sample grid: the tick that ends the window.
        let time = end_tick as f64 / f64::from(rate(cx));
        let dt = w.samples as f64 / f64::from(rate(cx));
        let mut out = [0u8; sets::pimu::SIZE];
        let base = if matches!(did, did::PIMU | did::PIMU_MAG) {
            out.copy_from_slice(
                &Pimu {
                    time,
                    dt: dt as f32,
                    status,
                    theta: frd(w.dtheta_rad),
                    vel: frd(w.dv_mps),
                }
                .encode(),
            );
            sets::pimu::SIZE
        } else {
            let (pqr, acc) = if w.samples > 0 {
                let inv = 1.0 / dt;
                let mean = |v: [f64; 3]| frd([v[0] * inv, v[1] * inv, v[2] * inv]);
                (mean(w.dtheta_raw_rad), mean(w.dv_raw_mps))
            } else {
                // No whole period measured yet (a GET right after power-on):
                // the last measurement, as SYS_SENSORS reports it, not zeros.
                last_measurement(cx)
            };
            if did == did::IMU3_RAW {
                // The chain has one sensor: IMU_RAW averages the three
                // IMUs, so each of them reads what IMU_RAW reads
                // (`docs/isb-data-sets.md` "IMU3_RAW").
                let one = Imus { pqr, acc };
                let b = Imu3 {
                    time,
                    status,
                    imu: [one; 3],
                }
                .encode();
                image[..b.len()].copy_from_slice(&b);
                return b.len();
            }
            out[..sets::imu::SIZE].copy_from_slice(
                &Imu {
                    time,
                    status,
                    pqr,
                    acc,
                }
                .encode(),
            );
            sets::imu::SIZE
        };
        image[..base].copy_from_slice(&out[..base]);
        if !matches!(did, did::IMU_MAG | did::PIMU_MAG) {
            return base;
        }
        let truth = self.truth(cx);
        let m = ins::magnetometer(time, self.nav.magnetometer(&truth, end_tick)).encode();
        image[base..base + m.len()].copy_from_slice(&m);
        base + m.len()
    }

    /// MAG_CAL now (`docs/isb-data-sets.md` "MAG_CAL"): after a
    /// recalibration command the progress runs from 0 to 100 % over
    /// [`MAG_RECAL_MS`], then the state reads done; the declination is
    /// FLASH_CONFIG's `magDeclination`.
    fn mag_cal_of(&self, cx: &impl Context<Integrals>) -> MagCal {
        let (state, at) = self.mag_cal;
        let declination = le::f32(&self.cfg.0, flash::MAG_DECLINATION);
        let (state, progress) = if state == mag_cal_state::RECAL_RUNNING {
            let ms = cx.time().ticks().saturating_sub(at) * 1000 / u64::from(rate(cx));
            if ms >= MAG_RECAL_MS {
                (mag_cal_state::RECAL_COMPLETE, 100.0)
            } else {
                (state, (ms * 100) as f32 / MAG_RECAL_MS as f32)
            }
        } else {
            (state, 0.0)
        };
        MagCal {
            state,
            progress,
            declination,
        }
    }

    /// SYS_SENSORS now: the last measurement (body axes), the magnetometer
    /// and barometer, the temperatures; supply 5 V, analog inputs 0.
    fn sys_sensors(&self, cx: &impl Context<Integrals>) -> SysSensors {
        let tick = cx.time().ticks();
        let time = tick as f64 / f64::from(rate(cx));
        let truth = self.truth(cx);
        let (g, a) = last_measurement(cx);
        let temp = cx.chain().temperature();
        let bar = self.nav.pressure_kpa(&truth, tick);
        let b = ins::barometer(time, bar, temp);
        SysSensors {
            time,
            temp,
            pqr: g,
            acc: a,
            mag: self.nav.magnetometer(&truth, tick),
            bar,
            bar_temp: temp,
            msl_bar: b.msl_bar,
            humidity: b.humidity,
            vin: 5.0,
            ana: [0.0; 3],
        }
    }

    /// One DATA packet of `set` now (the GET's reply).
    fn send_once(
        &mut self,
        cx: &mut impl Context<Integrals>,
        set: &DataSet,
        offset: u16,
        size: u16,
        now: Instant,
    ) {
        let mut image = [0u8; did::MAX_SIZE];
        let n = self.image_of(cx, set.did, &mut image, now);
        send_data(cx, set.did, &image[..n], offset, size);
    }

    /// The packet of stream `i` at `now`; its window restarts.
    fn send_stream(&mut self, cx: &mut impl Context<Integrals>, i: usize, now: Instant) {
        let s = self.streams[i];
        let mut image = [0u8; did::MAX_SIZE];
        let n = match s.did {
            d if is_windowed(d) => {
                let end = cx.chain().integrals();
                let w = integrals::window(&s.start, &end, rate(cx));
                self.streams[i].start = end;
                self.windowed(cx, s.did, &w, cx.time().ticks(), &mut image)
            }
            _ => self.image_of(cx, s.did, &mut image, now),
        };
        send_data(cx, s.did, &image[..n], s.offset, s.size);
    }

    fn sys_params(&self, cx: &mut impl Context<Integrals>, now: Instant) -> SysParams {
        let h = cx.chain().health();
        let mut hdw = 0u32;
        if h.gyro_over_range != 0 {
            hdw |= hdw_status::SATURATION_GYR;
        }
        if h.accel_over_range != 0 {
            hdw |= hdw_status::SATURATION_ACC;
        }
        if h.over_temperature {
            hdw |= hdw_status::ERR_TEMPERATURE;
        }
        if h.gyro_bit_failed || h.accel_bit_failed {
            hdw |= hdw_status::BIT_FAILED;
        } else if self.bit.state == bit::STATE_DONE {
            hdw |= hdw_status::BIT_PASSED;
        }
        if h.sensor_comm_failure || h.sensor_config_failure {
            hdw |= hdw_status::FAULT_SYS_CRITICAL;
        }
        let cfg = &self.cfg;
        if cfg.startup_imu_dt_ms() != self.imu_dt_ms
            || cfg.startup_nav_dt_ms() != self.nav_dt_ms
            || cfg.u32_at(flash::SER0_BAUD_RATE) != self.baud
        {
            hdw |= hdw_status::SYSTEM_RESET_REQUIRED;
        }
        if self.save_pending {
            hdw |= hdw_status::FLASH_WRITE_PENDING;
        }
        if cx.tx_dropped() != self.dropped_seen {
            hdw |= hdw_status::ERR_COM_TX_LIMITED;
        }
        hdw |= self.nav.hdw_bits();
        hdw = hdw_status::with_parse_errors(hdw, self.parse_errors);
        let t = cx.chain().temperature();
        let up = now.since(cx.time().powered_at()) as f64 / 1e9;
        let time_of_week_ms = if self.nav.gps_time_valid() {
            self.gps_time(cx).1.tow_ms()
        } else {
            ms_since(cx, now)
        };
        SysParams {
            time_of_week_ms,
            ins_status: self.nav.ins_status(),
            hdw_status: hdw,
            imu_temp: t,
            baro_temp: t,
            mcu_temp: t,
            sys_status: 0,
            imu_sample_period_ms: self.imu_dt_ms,
            nav_output_period_ms: self.nav_dt_ms,
            sensor_true_period: f64::from(self.imu_dt_ms) * 1e-3,
            flash_cfg_checksum: cfg.checksum(),
            nav_update_period_ms: self.nav_dt_ms,
            gen_fault_code: self.gen_fault_code,
            up_time: up,
        }
    }
}

/// A DATA packet of `image[offset..offset + size]`.
fn send_data(cx: &mut impl Context<Integrals>, did: u8, image: &[u8], offset: u16, size: u16) {
    let whole = offset == 0 && usize::from(size) == image.len();
    let n = OVERHEAD + usize::from(size) + if whole { 0 } else { 2 };
    push(cx, n, |f| message::encode_data(did, image, offset, size, f));
}

/// Whether `did` is a window of the integrals (IMU, IMU_RAW, PIMU and
/// their `_MAG` forms).
fn is_windowed(did: u8) -> bool {
    matches!(
        did,
        did::IMU | did::IMU_RAW | did::IMU3_RAW | did::PIMU | did::IMU_MAG | did::PIMU_MAG
    )
}

fn rate(cx: &impl Context<Integrals>) -> u32 {
    cx.product().model.internal_rate_hz
}

fn ms_since(cx: &impl Context<Integrals>, now: Instant) -> u32 {
    (now.since(cx.time().powered_at()) / 1_000_000) as u32
}

/// IMU `status` from the chain's health (module doc).
fn imu_status_of(h: &Health) -> u32 {
    let mut s = if h.sensor_comm_failure || h.sensor_config_failure {
        0
    } else {
        imu_status::ALL_OK
    };
    if h.gyro_over_range != 0 {
        s |= imu_status::SATURATION_GYR;
    }
    if h.accel_over_range != 0 {
        s |= imu_status::SATURATION_ACC;
    }
    s
}

/// DEV_INFO of this unit: an IMX-5 (hardware 5.0), protocol 2.1.0.0, the
/// serial number from the seed (never 0).
fn dev_info_of(cx: &impl Context<Integrals>) -> DevInfo {
    DevInfo {
        hardware_type: dev_info::HARDWARE_TYPE_IMX,
        hdw_run_state: dev_info::RUN_STATE_APP,
        serial_number: 10_000_000 + (cx.seed() % 90_000_000) as u32,
        hardware_ver: [5, 0, 0, 0],
        firmware_ver: dev_info::FIRMWARE_2_7_1,
        build_number: dev_info::BUILD_NUMBER_2_7_1,
        protocol_ver: dev_info::PROTOCOL_2_1,
        repo_revision: 0,
        manufacturer: sets::str24("Inertial Sense Inc"),
        build_type: b'r',
        build_date: [26, 12, 1],
        build_time: [0, 0, 0, 0],
        add_info: sets::str24(concat!("imu-emu ", env!("CARGO_PKG_VERSION"))),
    }
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
