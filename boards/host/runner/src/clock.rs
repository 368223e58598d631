//! Device time against the host clock (`--speed`).
//!
//! The runner reads the device's time from a [`Clock`]: ns since power-on,
//! which every tick deadline, 1PPS edge, received byte, trajectory sample
//! and line-rate credit is measured in. The speed decides how that time
//! follows the host's:
//!
//! * [`Speed::Factor`]`(k)` — device time runs `k` times as fast as the
//!   host's (`--speed 1`, the default, is real time; `--speed 10` shows ten
//!   seconds of data a second; `--speed 0.5` half speed). The emulated line
//!   runs `k` times faster too: a 115 200 bit/s line carries `k` times as
//!   many bytes a host second, so nothing a real line would not carry is
//!   ever dropped.
//! * [`Speed::Max`] — device time advances as fast as the host computes
//!   and the client reads: the runner moves it on by a batch of ticks
//!   ([`MAX_BATCH_TICKS`]) whenever less than [`MAX_BACKLOG`] bytes wait
//!   for the client, and otherwise waits for the client to read. Nothing
//!   is dropped for speed's sake, so a slow client slows device time down
//!   instead (with no client connected, time stops; and while the
//!   device is quiet — nothing to send, no input pending — time waits for
//!   input: `crate::runner`, "Repeatable sessions").
//!
//! Either way the device sees the same sequence of ticks and bytes at the
//! same device times as in real time: a recorded session replays
//! identically faster (the seed fixing the noise).
//!
//! A factor the host cannot compute (or a stalled host) would leave device
//! time ever further behind the clock: the runner then holds the clock back
//! ([`Clock::hold_back`]) so device time lags by at most
//! [`crate::runner::MAX_LAG`] — device time runs as fast as the host
//! computes, every tick still runs, and the backlog of ticks stays bounded.

use std::str::FromStr;
use std::time::Duration;

/// How fast device time runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Speed {
    /// This many device seconds per host second (finite, > 0).
    Factor(f64),
    /// As fast as the host computes and the client reads.
    Max,
}

impl Default for Speed {
    fn default() -> Self {
        Speed::Factor(1.0)
    }
}

impl FromStr for Speed {
    type Err = String;

    /// `max`, or a factor such as `1`, `10`, `0.25` (finite, > 0, ≤ 1e6).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.eq_ignore_ascii_case("max") {
            return Ok(Speed::Max);
        }
        match s.parse::<f64>() {
            Ok(k) if k.is_finite() && k > 0.0 && k <= 1e6 => Ok(Speed::Factor(k)),
            _ => Err(format!(
                "speed must be `max` or a factor in (0, 1e6], not {s:?}"
            )),
        }
    }
}

/// In [`Speed::Max`], how many ticks device time moves on at once.
pub const MAX_BATCH_TICKS: u64 = 64;
/// In [`Speed::Max`], device time waits while this many bytes wait for the
/// client (well below the transport's 64 KiB backlog, which drops when
/// full).
pub const MAX_BACKLOG: usize = 16 * 1024;

/// Device time: ns since power-on, per [`Speed`].
#[derive(Debug, Clone)]
pub struct Clock {
    epoch: std::time::Instant,
    speed: Speed,
    /// [`Speed::Max`]: device time now.
    virtual_ns: u64,
    /// [`Speed::Factor`]: device time held back so far ([`Clock::hold_back`]).
    held_ns: u64,
}

impl Clock {
    /// Device time 0 is `epoch` (host time).
    pub fn new(epoch: std::time::Instant, speed: Speed) -> Self {
        Clock {
            epoch,
            speed,
            virtual_ns: 0,
            held_ns: 0,
        }
    }

    /// Host time of device time 0.
    pub fn epoch(&self) -> std::time::Instant {
        self.epoch
    }

    /// The speed.
    pub fn speed(&self) -> Speed {
        self.speed
    }

    /// Device time now, ns since power-on.
    pub fn now_ns(&self) -> u64 {
        match self.speed {
            Speed::Factor(k) => {
                let host = self.epoch.elapsed().as_nanos() as f64;
                // Saturates at u64::MAX (centuries of device time).
                ((host * k) as u64).saturating_sub(self.held_ns)
            }
            Speed::Max => self.virtual_ns,
        }
    }

    /// The device time at which something that happened `age` ago (host
    /// time) happened, e.g. a feed sample's arrival at its socket: `age`
    /// scaled by the speed; at [`Speed::Max`], where host time does not
    /// drive the device, now.
    pub fn arrived_ns(&self, age: Duration) -> u64 {
        let k = match self.speed {
            Speed::Factor(k) => k,
            Speed::Max => 0.0,
        };
        self.now_ns()
            .saturating_sub((age.as_nanos() as f64 * k) as u64)
    }

    /// [`Speed::Max`]: moves device time on to `ns` (never back). No
    /// effect at a factor, where the host clock drives it.
    pub fn advance_to(&mut self, ns: u64) {
        if self.speed == Speed::Max {
            self.virtual_ns = self.virtual_ns.max(ns);
        }
    }

    /// [`Speed::Factor`]: device time from now on runs `ns` behind the
    /// factor (the host could not keep up). No effect in [`Speed::Max`],
    /// which never runs ahead of the ticks.
    pub fn hold_back(&mut self, ns: u64) {
        if let Speed::Factor(_) = self.speed {
            self.held_ns = self.held_ns.saturating_add(ns);
        }
    }

    /// Device time held back so far, ns.
    pub fn held_back_ns(&self) -> u64 {
        self.held_ns
    }

    /// How long the host waits for `device_ns` of device time to pass:
    /// scaled by the factor; nothing in [`Speed::Max`] (the runner decides
    /// there, from the backlog).
    pub fn host_wait(&self, device_ns: u64) -> Duration {
        match self.speed {
            Speed::Factor(k) => Duration::from_nanos((device_ns as f64 / k).ceil() as u64),
            Speed::Max => Duration::ZERO,
        }
    }
}

/// GPS seconds at device instant 0: `--gps-time` (Unix seconds, UTC) or the
/// host clock now, as GPS time (+18 leap seconds).
pub fn gps_s_at_power_on(gps_time: Option<u64>) -> u64 {
    let unix = gps_time.unwrap_or_else(|| {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs())
    });
    imu_emu::time::gps_s_of_unix(unix)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_max_and_factors() {
        assert_eq!("max".parse::<Speed>(), Ok(Speed::Max));
        assert_eq!("MAX".parse::<Speed>(), Ok(Speed::Max));
        assert_eq!("10".parse::<Speed>(), Ok(Speed::Factor(10.0)));
        assert_eq!("0.25".parse::<Speed>(), Ok(Speed::Factor(0.25)));
        for bad in ["0", "-1", "nan", "inf", "2e6", "fast", ""] {
            assert!(bad.parse::<Speed>().is_err(), "{bad}");
        }
    }

    #[test]
    fn factor_scales_waits_and_max_is_driven() {
        let c = Clock::new(std::time::Instant::now(), Speed::Factor(4.0));
        assert_eq!(c.host_wait(1_000_000), Duration::from_micros(250));
        let mut m = Clock::new(std::time::Instant::now(), Speed::Max);
        assert_eq!(m.now_ns(), 0);
        m.advance_to(5_000);
        m.advance_to(3_000);
        assert_eq!(m.now_ns(), 5_000);
        assert_eq!(m.host_wait(1_000_000), Duration::ZERO);
        m.hold_back(1_000);
        assert_eq!((m.now_ns(), m.held_back_ns()), (5_000, 0));
    }

    /// An arrival `age` ago is that much device time ago, scaled by the
    /// speed; at `--speed max` it is now (the shared and own feeds both).
    #[test]
    fn an_arrival_is_dated_back_by_its_scaled_age() {
        let epoch = std::time::Instant::now() - Duration::from_secs(10);
        let c = Clock::new(epoch, Speed::Factor(2.0));
        let before = c.now_ns();
        let at = c.arrived_ns(Duration::from_millis(50));
        let after = c.now_ns();
        assert!(at + 100_000_000 >= before && at + 100_000_000 <= after);
        assert_eq!(c.arrived_ns(Duration::from_secs(100)), 0);
        let mut m = Clock::new(epoch, Speed::Max);
        m.advance_to(7_000);
        assert_eq!(m.arrived_ns(Duration::from_millis(50)), 7_000);
    }

    #[test]
    fn held_back_time_stays_behind() {
        // At 1e6 device seconds a host second, a 1 s hold is 1 µs of host
        // time: the clock reads at least 1 s less than the factor gives.
        let epoch = std::time::Instant::now();
        let mut c = Clock::new(epoch, Speed::Factor(1e6));
        c.hold_back(1_000_000_000);
        std::thread::sleep(Duration::from_millis(1));
        let before = (epoch.elapsed().as_nanos() as f64 * 1e6) as u64;
        let now = c.now_ns();
        let after = (epoch.elapsed().as_nanos() as f64 * 1e6) as u64;
        assert!(now + 1_000_000_000 >= before && now + 1_000_000_000 <= after);
        assert_eq!(c.held_back_ns(), 1_000_000_000);
    }
}
