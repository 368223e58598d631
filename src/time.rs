//! Time as the core sees it: nanoseconds on the board's monotonic clock.
//!
//! The core never reads a clock; every call that needs time receives an
//! [`Instant`] from the board (sans-IO: see the crate front page). GPS
//! time, which a board may give a personality, is counted from the GPS
//! epoch ([`gps_s_of_unix`]).

/// Unix time of the GPS epoch, 1980-01-06 00:00:00 UTC.
pub const GPS_EPOCH_UNIX_S: u64 = 315_964_800;

/// GPS − UTC, s: 18 since 2017-01-01 (the IMX-5 SDK's
/// `C_GPS_LEAP_SECONDS`, docs/isb.md).
pub(crate) const LEAP_SECONDS: u8 = 18;

/// GPS seconds since the GPS epoch of a UTC Unix time, with today's
/// [`LEAP_SECONDS`] (a time before the epoch reads as the epoch).
pub const fn gps_s_of_unix(unix_s: u64) -> u64 {
    unix_s.saturating_sub(GPS_EPOCH_UNIX_S) + LEAP_SECONDS as u64
}

/// A point in time, in nanoseconds since an epoch the board chooses (usually
/// the moment it powered the device on). Monotonic: boards never go back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Instant(pub u64);

impl Instant {
    /// The board's epoch.
    pub const ZERO: Instant = Instant(0);

    /// Nanoseconds since the epoch.
    pub const fn as_nanos(self) -> u64 {
        self.0
    }

    /// Builds an instant from nanoseconds since the epoch.
    pub const fn from_nanos(ns: u64) -> Self {
        Instant(ns)
    }

    /// Builds an instant from microseconds since the epoch (saturating).
    pub const fn from_micros(us: u64) -> Self {
        Instant(us.saturating_mul(1_000))
    }

    /// Builds an instant from milliseconds since the epoch (saturating).
    pub const fn from_millis(ms: u64) -> Self {
        Instant(ms.saturating_mul(1_000_000))
    }

    /// Nanoseconds from `earlier` to `self`, zero if `earlier` is later.
    pub const fn since(self, earlier: Instant) -> u64 {
        self.0.saturating_sub(earlier.0)
    }

    /// This instant plus `ns` nanoseconds (saturating).
    pub const fn plus_nanos(self, ns: u64) -> Instant {
        Instant(self.0.saturating_add(ns))
    }
}

/// Nanoseconds per second.
const NS_PER_S: u64 = 1_000_000_000;

/// The device's time base (KERNEL 5.2.3.1): power-on, internal-rate ticks,
/// the latest time the board told, the last RX byte, and 1PPS. The shell
/// keeps it up to date at each entry point; a personality reads it (and
/// takes the second fraction and the 1PPS flag) through
/// [`crate::personality::Context::time`].
#[derive(Debug, Clone, Copy)]
pub struct TimeBase {
    powered_at: Instant,
    ticks: u64,
    /// Latest time the board told us (every entry point carries one).
    clock: Instant,
    last_rx: Instant,
    /// Start of the current second: the last 1PPS edge, or power-on,
    /// advanced by whole seconds.
    second_start: Instant,
    last_pps: Option<Instant>,
    pps_since_frame: bool,
}

impl TimeBase {
    /// The time base of a device powered on at `now`.
    pub const fn new(now: Instant) -> Self {
        TimeBase {
            powered_at: now,
            ticks: 0,
            clock: now,
            last_rx: now,
            second_start: now,
            last_pps: None,
            pps_since_frame: false,
        }
    }

    /// The board told the time `now` (never moves the clock back).
    #[inline]
    pub(crate) fn tell(&mut self, now: Instant) {
        self.clock = self.clock.max(now);
    }

    /// One more internal-rate tick.
    #[inline]
    pub(crate) fn tick(&mut self) {
        self.ticks = self.ticks.wrapping_add(1);
    }

    /// A 1PPS rising edge at `at`: the second starts there.
    pub(crate) fn pps(&mut self, at: Instant) {
        self.last_pps = Some(at);
        self.second_start = at;
        self.pps_since_frame = true;
    }

    /// When the device powered on.
    pub fn powered_at(&self) -> Instant {
        self.powered_at
    }

    /// Internal-rate ticks since power-on.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// The latest time the board told the device.
    pub fn clock(&self) -> Instant {
        self.clock
    }

    /// When the last host → device byte arrived (power-on if none).
    pub fn last_rx(&self) -> Instant {
        self.last_rx
    }

    /// Restarts the RX idle time from `now` (a byte arrived, or a
    /// personality abandoned a frame cut short).
    pub fn touch_rx(&mut self, now: Instant) {
        self.last_rx = now;
    }

    /// Nanoseconds since the current second began at `now` (KERNEL
    /// 5.2.3.1): the second starts at the last 1PPS edge, or at power-on,
    /// advanced by whole seconds (a division only when a second boundary
    /// has passed).
    pub fn second_fraction_ns(&mut self, now: Instant) -> u64 {
        let mut into_second = now.since(self.second_start);
        if into_second >= NS_PER_S {
            let whole = into_second - into_second % NS_PER_S;
            self.second_start = self.second_start.plus_nanos(whole);
            into_second -= whole;
        }
        into_second
    }

    /// Whether a 1PPS rising edge came since the last
    /// [`TimeBase::clear_pps_flag`].
    pub fn pps_since_frame(&self) -> bool {
        self.pps_since_frame
    }

    /// Clears the "1PPS since the last frame" flag (a frame carried it).
    pub fn clear_pps_flag(&mut self) {
        self.pps_since_frame = false;
    }

    /// Whether more than a second has passed at `now` without a 1PPS edge
    /// (counted from power-on when none came).
    pub fn pps_lost(&self, now: Instant) -> bool {
        now.since(self.last_pps.unwrap_or(self.powered_at)) > NS_PER_S
    }
}
