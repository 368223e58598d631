//! The IMX-5's NMEA streams: when each sentence of the `$ASCE` table is
//! due and what it prints (`docs/isb.md` "NMEA").
//!
//! Each ID has the source period of the data set it prints (`docs/isb-nmea.md`
//! §2: SDK 2.0 mapping): PIMU, PPIMU, PINS1, PINS2 the navigation period
//! (`startupNavDtMs`), PRIMU the IMU sample period (`startupImuDtMs`),
//! INFO DEV_INFO's (1 ms, as its ISB stream), GSV GPS1_SAT's 1 s, and
//! PGPSP, GGA, GLL, GSA, RMC, ZDA, VTG, PASHR, INTEL, POWGPS, POWTLV the
//! receiver's epoch (`startupGPSDtMs`); PSTRB goes out on each strobe.
//! Period `N` sends on every source epoch whose index is a multiple of
//! `N`. The GNSS epochs and the GSV second are counted in GPS time, so at
//! period 5 of 200 ms the GNSS sentences fall on whole GPS seconds, all in
//! step (the release's 1 s alignment, SDK PR #532); the others count from
//! power-on. Period 0 sends once at the next source epoch, then the ID is
//! off. Within an epoch the sentences go out in ID order, each one whole
//! frame on the line (so NMEA and ISB interleave whole).

use super::asce::{id, Table};
use super::did::{self, MAX_SIZE};
use super::nav_sets::{GpsPos, GpsSat, GpsVel, Ins1, Ins2};
use super::nmea_out::{self as out, Line};
use super::sets::{DevInfo, Imu, Pimu, StrobeInTime};

/// Where a sentence's source epoch comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Clock {
    /// The navigation period.
    Nav,
    /// The IMU sample period.
    Imu,
    /// 1 ms.
    Millisecond,
    /// The receiver's epoch (GPS time).
    Gps,
    /// The GPS second.
    GpsSecond,
    /// Sent on a strobe.
    Strobe,
    /// Never sent (ID 0).
    Never,
}

/// The source clock of ID `i`.
pub(crate) const fn clock_of(i: u8) -> Clock {
    match i {
        id::PIMU | id::PPIMU | id::PINS1 | id::PINS2 => Clock::Nav,
        id::PRIMU => Clock::Imu,
        id::INFO => Clock::Millisecond,
        id::GSV => Clock::GpsSecond,
        id::PSTRB => Clock::Strobe,
        id::PGPSP
        | id::GGA
        | id::GLL
        | id::GSA
        | id::RMC
        | id::ZDA
        | id::VTG
        | id::PASHR
        | id::INTEL
        | id::POWGPS
        | id::POWTLV => Clock::Gps,
        _ => Clock::Never,
    }
}

/// The source epochs that begin at this tick: for each clock, `Some(index)`
/// of the epoch starting now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Epochs {
    /// Navigation period index.
    pub nav: Option<u64>,
    /// IMU sample period index.
    pub imu: Option<u64>,
    /// Millisecond index.
    pub ms: Option<u64>,
    /// Receiver epoch index (GPS time / `startupGPSDtMs`).
    pub gps: Option<u64>,
    /// GPS second.
    pub gps_second: Option<u64>,
}

impl Epochs {
    fn of(&self, c: Clock) -> Option<u64> {
        match c {
            Clock::Nav => self.nav,
            Clock::Imu => self.imu,
            Clock::Millisecond => self.ms,
            Clock::Gps => self.gps,
            Clock::GpsSecond => self.gps_second,
            Clock::Strobe | Clock::Never => None,
        }
    }
}

/// Samples the 5-sample median speed filter keeps.
const FILTER_LEN: usize = 5;

/// The port's NMEA state: the table, the receiver-epoch counters, the
/// speed filter, counts.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct NmeaStreams {
    /// The `$ASCE` table.
    pub table: Table,
    /// `$ASCE` pairs dropped since power-on (unknown or out-of-range IDs,
    /// missing periods, more than 20 pairs).
    pub rejected: u32,
    /// Ticks from the last tick to the next sentence due (`None`: none is
    /// periodic), for the board's wake-up ([`NmeaStreams::plan`]).
    pub next_in: Option<u64>,
    /// Speed filter: the last speeds (m/s) and the epoch they belong to.
    speeds: [f64; FILTER_LEN],
    speed_n: usize,
    speed_tow: Option<u32>,
}

/// The data sets a set of due sentences prints, decoded from the very
/// bytes the ISB packets carry.
pub(crate) struct Snapshot {
    /// GPS1_POS.
    pub pos: GpsPos,
    /// GPS1_VEL.
    pub vel: GpsVel,
    /// GPS1_SAT (only when GSV or GSA is due).
    pub sat: Option<GpsSat>,
    /// INS_1.
    pub ins1: Ins1,
    /// INS_2.
    pub ins2: Ins2,
    /// IMU, PIMU, IMU_RAW.
    pub imu: Imu,
    /// PIMU.
    pub pimu: Pimu,
    /// IMU_RAW.
    pub imu_raw: Imu,
    /// STROBE_IN_TIME.
    pub strobe: StrobeInTime,
    /// DEV_INFO.
    pub dev_info: Option<DevInfo>,
    /// FLASH_CONFIG `magDeclination`, rad (RMC).
    pub mag_decl_rad: f32,
    /// Attitude σ roll, pitch, heading, rad (PASHR).
    pub att_sigma_rad: [f32; 3],
}

fn decode<T, const N: usize>(
    fetch: &mut impl FnMut(u8, &mut [u8; MAX_SIZE]) -> usize,
    d: u8,
    f: fn(&[u8; N]) -> T,
) -> T {
    let mut buf = [0u8; MAX_SIZE];
    fetch(d, &mut buf);
    let mut b = [0u8; N];
    b.copy_from_slice(&buf[..N]);
    f(&b)
}

impl Snapshot {
    /// The data sets the IDs of `due` print, read through `fetch` (the
    /// device's data set bytes now); unread ones are zeros.
    pub(crate) fn fill(
        due: u32,
        mag_decl_rad: f32,
        att_sigma_rad: [f32; 3],
        mut fetch: impl FnMut(u8, &mut [u8; MAX_SIZE]) -> usize,
    ) -> Self {
        let has = |i: u8| due & (1 << i) != 0;
        let gps = (id::PGPSP..=id::POWTLV).any(|i| has(i) && clock_of(i) == Clock::Gps);
        let mut s = Snapshot {
            pos: GpsPos::default(),
            vel: GpsVel::default(),
            sat: None,
            ins1: Ins1::default(),
            ins2: Ins2::default(),
            imu: Imu::default(),
            pimu: Pimu::default(),
            imu_raw: Imu::default(),
            strobe: StrobeInTime::default(),
            dev_info: None,
            mag_decl_rad,
            att_sigma_rad,
        };
        let f = &mut fetch;
        if gps {
            s.pos = decode(f, did::GPS1_POS, GpsPos::decode);
            s.vel = decode(f, did::GPS1_VEL, GpsVel::decode);
        }
        if has(id::GSV) || has(id::GSA) {
            s.sat = Some(decode(f, did::GPS1_SAT, GpsSat::decode));
        }
        if has(id::PINS1) || has(id::PASHR) {
            s.ins1 = decode(f, did::INS_1, Ins1::decode);
        }
        if has(id::PINS2) {
            s.ins2 = decode(f, did::INS_2, Ins2::decode);
        }
        if has(id::PIMU) {
            s.imu = decode(f, did::IMU, Imu::decode);
        }
        if has(id::PRIMU) {
            s.imu_raw = decode(f, did::IMU_RAW, Imu::decode);
        }
        if has(id::PPIMU) {
            s.pimu = decode(f, did::PIMU, Pimu::decode);
        }
        if has(id::PSTRB) {
            s.strobe = decode(f, did::STROBE_IN_TIME, StrobeInTime::decode);
        }
        if has(id::INFO) {
            s.dev_info = Some(decode(f, did::DEV_INFO, DevInfo::decode));
        }
        s
    }
}

impl NmeaStreams {
    /// Whether any periodic sentence is on (the device is streaming).
    pub(crate) fn streaming(&self) -> bool {
        (1..id::COUNT as u8)
            .any(|i| self.table.on(i) && !matches!(clock_of(i), Clock::Strobe | Clock::Never))
    }

    /// The IDs (bit `id`) due at the epochs `e`.
    pub(crate) fn due(&self, e: &Epochs) -> u32 {
        let mut due = 0;
        for i in 1..id::COUNT as u8 {
            if !self.table.on(i) {
                continue;
            }
            let Some(k) = e.of(clock_of(i)) else {
                continue;
            };
            let p = self.table.periods[usize::from(i)];
            if p == 0 || k % u64::from(p) == 0 {
                due |= 1 << i;
            }
        }
        due
    }

    /// Plans the next wake-up after tick `ticks` (at `ns` on the epochs'
    /// clock, ticks `tick_ns` apart; `grids` = ticks per navigation period,
    /// IMU period and ms; `gps_ns` the receiver epoch): the ticks until the
    /// first sentence due, into [`NmeaStreams::next_in`].
    pub(crate) fn plan(&mut self, ticks: u64, ns: u64, tick_ns: u64, grids: [u64; 3], gps_ns: u64) {
        let mut next: Option<u64> = None;
        for i in 1..id::COUNT as u8 {
            if !self.table.on(i) {
                continue;
            }
            let p = u64::from(self.table.periods[usize::from(i)].max(1));
            let on_ticks = |g: u64| {
                let step = g.max(1).saturating_mul(p);
                step - ticks % step
            };
            let on_ns = |len: u64| {
                let step = len.max(1).saturating_mul(p);
                (step - ns % step).div_ceil(tick_ns.max(1)).max(1)
            };
            let k = match clock_of(i) {
                Clock::Nav => on_ticks(grids[0]),
                Clock::Imu => on_ticks(grids[1]),
                Clock::Millisecond => on_ticks(grids[2]),
                Clock::Gps => on_ns(gps_ns),
                Clock::GpsSecond => on_ns(1_000_000_000),
                Clock::Strobe | Clock::Never => continue,
            };
            next = Some(next.map_or(k, |n| n.min(k)));
        }
        self.next_in = next;
    }

    /// The IDs due on a strobe (PSTRB when on).
    pub(crate) fn due_on_strobe(&self) -> u32 {
        if self.table.on(id::PSTRB) {
            1 << id::PSTRB
        } else {
            0
        }
    }

    /// The 2-D speed the sentences print for the epoch of `s`: as measured,
    /// or the median of the last five epochs with the speed filter on.
    fn speed(&mut self, s: &Snapshot, raw: f64) -> f64 {
        if self.speed_tow != Some(s.pos.time_of_week_ms) {
            self.speed_tow = Some(s.pos.time_of_week_ms);
            self.speeds.copy_within(1.., 0);
            self.speeds[FILTER_LEN - 1] = raw;
            self.speed_n = (self.speed_n + 1).min(FILTER_LEN);
        }
        if !self.table.speed_filter {
            return raw;
        }
        let mut v = [0.0f64; FILTER_LEN];
        let n = self.speed_n.max(1);
        v[..n].copy_from_slice(&self.speeds[FILTER_LEN - n..]);
        v[..n].sort_unstable_by(f64::total_cmp);
        v[n / 2]
    }

    /// Writes the sentences of `due` (ID order) from `s`, each handed to
    /// `send`; one-shots (period 0) go off.
    pub(crate) fn render(&mut self, due: u32, s: &Snapshot, mut send: impl FnMut(&[u8])) {
        let (vn, ve) = out::vel_ne(&s.pos, &s.vel);
        let (course, raw_speed) = out::course_speed(vn, ve);
        let needs_speed = due & (1 << id::RMC | 1 << id::VTG) != 0;
        let speed = if needs_speed {
            self.speed(s, raw_speed)
        } else {
            raw_speed
        };
        for i in 1..id::COUNT as u8 {
            if due & (1 << i) == 0 {
                continue;
            }
            if self.table.periods[usize::from(i)] == 0 {
                self.table.clear(i);
            }
            if i == id::GSV {
                if let Some(sat) = &s.sat {
                    out::gsv(sat, &self.table.gsv_masks, &mut send);
                }
                continue;
            }
            if i == id::INFO {
                if let Some(d) = &s.dev_info {
                    let mut b = [0u8; 200];
                    if let Some(n) = super::nmea::info_sentence(d, &mut b) {
                        send(&b[..n]);
                    }
                }
                continue;
            }
            let mut l = Line::new();
            let ok = match i {
                id::PIMU => out::pimu(&mut l, &s.imu, false),
                id::PRIMU => out::pimu(&mut l, &s.imu_raw, true),
                id::PPIMU => out::ppimu(&mut l, &s.pimu),
                id::PINS1 => out::pins1(&mut l, &s.ins1),
                id::PINS2 => out::pins2(&mut l, &s.ins2),
                id::PGPSP => out::pgpsp(&mut l, &s.pos, &s.vel),
                id::GGA => out::gga(&mut l, &s.pos),
                id::GLL => out::gll(&mut l, &s.pos),
                id::GSA => match &s.sat {
                    Some(sat) => out::gsa(&mut l, &s.pos, sat),
                    None => continue,
                },
                id::RMC => out::rmc(&mut l, &s.pos, course, speed, s.mag_decl_rad),
                id::ZDA => out::zda(&mut l, &s.pos),
                id::VTG => out::vtg(&mut l, &s.pos, course, speed),
                id::PASHR => out::pashr(&mut l, &s.pos, &s.ins1, s.att_sigma_rad),
                id::PSTRB => out::pstrb(&mut l, &s.strobe),
                id::INTEL => {
                    let fw = s
                        .dev_info
                        .map_or(super::sets::dev_info::FIRMWARE_2_7_1, |d| d.firmware_ver);
                    out::intel(&mut l, fw, &s.pos, &s.vel, (vn, ve))
                }
                id::POWGPS => out::powgps(&mut l, &s.pos),
                id::POWTLV => out::powtlv(&mut l, &s.pos, &s.vel),
                _ => continue,
            };
            if ok.is_ok() {
                if let Some(b) = l.finish() {
                    send(b);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With the speed filter on (`$ASCE` options 0x400) RMC and VTG print
    /// the median of the last five epochs' speeds; off, the epoch's own.
    #[test]
    fn the_speed_filter_is_a_five_epoch_median() {
        let mut n = NmeaStreams::default();
        let mut s = Snapshot::fill(0, 0.0, [0.0; 3], |_, _| 0);
        let mut last = 0.0;
        for (k, v) in [1.0, 100.0, 2.0, 3.0, 4.0].into_iter().enumerate() {
            s.pos.time_of_week_ms = 200 * k as u32;
            last = n.speed(&s, v);
        }
        assert_eq!(last, 4.0, "off: as measured");
        n.table.speed_filter = true;
        assert_eq!(n.speed(&s, 4.0), 3.0, "the same epoch: not pushed again");
        s.pos.time_of_week_ms = 1000;
        assert_eq!(n.speed(&s, 0.5), 3.0, "100, 2, 3, 4, 0.5");
        s.pos.time_of_week_ms = 1200;
        assert_eq!(n.speed(&s, 0.2), 2.0, "2, 3, 4, 0.5, 0.2");
    }
}
