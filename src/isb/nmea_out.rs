//! The NMEA sentences an IMX-5 prints (Inertial Sense SDK 2.7.1
//! `protocol_nmea.cpp`, `docs/isb-nmea.md`): the proprietary ones (PIMU,
//! PPIMU, PRIMU, PINS1, PINS2, PGPSP, PASHR, PSTRB, INTEL, POWGPS, POWTLV),
//! the GNSS ones (GGA, GLL, GSA, GSV, RMC, VTG, ZDA), the `$ASCE` table
//! reply. Each is written from the decoded bytes of the ISB data set it
//! prints (so NMEA and ISB agree on every shared field to the bit), with
//! the release's field order, formats and talker (`GN`), `*`, the XOR
//! checksum in upper-case hex and CR LF.
//!
//! Floats go through `core::fmt` with the release's `printf` precisions
//! (`%.3f` → `{:.3}`): both print the exact decimal value of the binary
//! number rounded half to even, so the digits are the release's.

use core::fmt::Write;

use super::nav::quat_e2n;
use super::nav_sets::{GpsPos, GpsSat, GpsVel, Ins1, Ins2};
use super::nmea::checksum;
use super::sets::{Imu, Pimu, StrobeInTime};
use crate::math::double::rotate_inv;

/// `NMEA_BUFFER_SIZE` (`data_sets.h`): the longest sentence, CR LF
/// included.
pub(crate) const MAX_SENTENCE: usize = 256;

/// Talker of GGA, GLL, GSA, RMC, ZDA, VTG: several constellations (the
/// release's default `$GN`).
pub(crate) const TALKER: &str = "GN";

/// `C_RAD2DEG` as the SDK writes it (`ISConstants.h`: 57.29578).
const RAD2DEG: f64 = 57.295_78;
/// m/s → knots (`C_METERS_KNOTS`).
const KNOTS: f64 = 1.943_844;
/// m/s → km/h.
const KMH: f64 = 3.6;

/// One sentence being written: `$` first, then [`Line::finish`] appends the
/// checksum and CR LF. Writing past [`MAX_SENTENCE`] fails (never panics).
pub struct Line {
    buf: [u8; MAX_SENTENCE],
    len: usize,
}

impl Default for Line {
    fn default() -> Self {
        Self::new()
    }
}

impl Line {
    /// An empty sentence (`$` written).
    pub(crate) fn new() -> Self {
        let mut buf = [0u8; MAX_SENTENCE];
        buf[0] = b'$';
        Line { buf, len: 1 }
    }

    /// Appends `*`, the checksum of the body in upper-case hex and CR LF;
    /// the whole sentence, or `None` if it does not fit.
    pub(crate) fn finish(&mut self) -> Option<&[u8]> {
        let sum = checksum(self.buf.get(1..self.len)?);
        write!(self, "*{sum:02X}\r\n").ok()?;
        self.buf.get(..self.len)
    }
}

impl Write for Line {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        // Room for the footer stays free until `finish`.
        let end = self.len.checked_add(s.len()).ok_or(core::fmt::Error)?;
        let dst = self.buf.get_mut(self.len..end).ok_or(core::fmt::Error)?;
        dst.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// UTC of a GPS time: `(hour, minute, second, millisecond)` of the day
/// and `(year, month, day)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Utc {
    /// Hours, 0-23.
    pub hour: u32,
    /// Minutes.
    pub min: u32,
    /// Seconds.
    pub sec: u32,
    /// Milliseconds.
    pub ms: u32,
    /// Year.
    pub year: i64,
    /// Month, 1-12.
    pub month: u32,
    /// Day of the month.
    pub day: u32,
}

/// Days from 1970-01-01 to 1980-01-06 (the GPS epoch).
const GPS_EPOCH_DAYS: i64 = 3657;

/// UTC of GPS `week`, `tow_ms`, GPS − UTC `leap_s` (the SDK's
/// `time_conversion.cpp`: time of day = time of week − leap seconds,
/// wrapped within the week; the date from the whole count of days).
pub(crate) fn utc_of(week: u32, tow_ms: u32, leap_s: u8) -> Utc {
    const WEEK_MS: i64 = 604_800_000;
    const DAY_MS: i64 = 86_400_000;
    let tow = (i64::from(tow_ms) - i64::from(leap_s) * 1000).rem_euclid(WEEK_MS);
    let day_ms = tow % DAY_MS;
    let total_ms = i64::from(week) * WEEK_MS + i64::from(tow_ms) - i64::from(leap_s) * 1000;
    let days = total_ms.div_euclid(DAY_MS) + GPS_EPOCH_DAYS;
    let (year, month, day) = civil_of_days(days);
    Utc {
        hour: (day_ms / 3_600_000) as u32,
        min: (day_ms / 60_000 % 60) as u32,
        sec: (day_ms / 1000 % 60) as u32,
        ms: (day_ms % 1000) as u32,
        year,
        month,
        day,
    }
}

/// The Gregorian date of `z` days since 1970-01-01 (the "civil from
/// days" algorithm of H. Hinnant, written here).
fn civil_of_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

fn put_utc(l: &mut Line, u: &Utc, decimals: bool) -> core::fmt::Result {
    write!(l, "{:02}{:02}{:02}", u.hour, u.min, u.sec)?;
    if decimals {
        write!(l, ".{:03}", u.ms)?;
    }
    Ok(())
}

/// `ddmm.mmmmm,N` / `dddmm.mmmmm,E`: whole degrees, then minutes with 5
/// decimals zero-padded to 8 characters (`protocol_nmea.cpp:680-718`).
fn put_lat_lon(l: &mut Line, lat: f64, lon: f64) -> core::fmt::Result {
    let (alat, alon) = (lat.abs(), lon.abs());
    let (dlat, dlon) = (alat as u32, alon as u32);
    write!(
        l,
        "{:02}{:08.5},{},{:03}{:08.5},{}",
        dlat,
        (alat - f64::from(dlat)) * 60.0,
        if lat >= 0.0 { 'N' } else { 'S' },
        dlon,
        (alon - f64::from(dlon)) * 60.0,
        if lon >= 0.0 { 'E' } else { 'W' },
    )
}

/// Fix type of a `gps_pos_t.status` word (bits 8-12).
pub(crate) fn fix_type(status: u32) -> u32 {
    (status >> 8) & 0x1F
}

/// GGA quality of a fix type (`protocol_nmea.cpp:764-778`).
fn gga_quality(fix: u32) -> u32 {
    match fix {
        2 | 3 | 9 | 10 => 1,
        8 => 2,
        5 => 3,
        12 => 4,
        11 => 5,
        1 | 4 => 6,
        _ => 0,
    }
}

fn utc_of_pos(p: &GpsPos) -> Utc {
    utc_of(p.week, p.time_of_week_ms, p.leap_s)
}

/// `$PIMU` (or `$PRIMU` with `raw`) of an IMU record: time (3 dp), pqr (4
/// dp), acc (3 dp).
pub(crate) fn pimu(l: &mut Line, m: &Imu, raw: bool) -> core::fmt::Result {
    let [p, q, r] = m.pqr;
    let [x, y, z] = m.acc;
    write!(
        l,
        "{},{:.3},{p:.4},{q:.4},{r:.4},{x:.3},{y:.3},{z:.3}",
        if raw { "PRIMU" } else { "PIMU" },
        m.time
    )
}

/// `$PPIMU` of a PIMU record: time (3 dp), Δθ (4 dp), Δv (4 dp), dt (3 dp).
pub(crate) fn ppimu(l: &mut Line, m: &Pimu) -> core::fmt::Result {
    let [a, b, c] = m.theta;
    let [x, y, z] = m.vel;
    write!(
        l,
        "PPIMU,{:.3},{a:.4},{b:.4},{c:.4},{x:.4},{y:.4},{z:.4},{:.3}",
        m.time, m.dt
    )
}

/// `$PINS1` of INS_1.
pub(crate) fn pins1(l: &mut Line, s: &Ins1) -> core::fmt::Result {
    let h = &s.header;
    let [r, p, y] = s.theta;
    let [u, v, w] = s.uvw;
    let [n, e, d] = s.ned;
    write!(
        l,
        "PINS1,{:.3},{},{},{},{r:.4},{p:.4},{y:.4},{u:.3},{v:.3},{w:.3},{:.8},{:.8},{:.3},{n:.3},{e:.3},{d:.3}",
        h.time_of_week, h.week, h.ins_status, h.hdw_status, s.lla[0], s.lla[1], s.lla[2]
    )
}

/// `$PINS2` of INS_2.
pub(crate) fn pins2(l: &mut Line, s: &Ins2) -> core::fmt::Result {
    let h = &s.header;
    let [qw, qx, qy, qz] = s.qn2b;
    let [u, v, w] = s.uvw;
    write!(
        l,
        "PINS2,{:.3},{},{},{},{qw:.4},{qx:.4},{qy:.4},{qz:.4},{u:.3},{v:.3},{w:.3},{:.8},{:.8},{:.3}",
        h.time_of_week, h.week, h.ins_status, h.hdw_status, s.lla[0], s.lla[1], s.lla[2]
    )
}

/// `$PGPSP` of GPS1_POS and GPS1_VEL.
pub(crate) fn pgpsp(l: &mut Line, p: &GpsPos, v: &GpsVel) -> core::fmt::Result {
    let [x, y, z] = v.vel;
    write!(
        l,
        "PGPSP,{},{},{},{:.8},{:.8},{:.2},{:.2},{:.2},{:.2},{:.2},{x:.2},{y:.2},{z:.2},{:.2},{:.1},{:.4},{}",
        p.time_of_week_ms,
        p.week,
        p.status,
        p.lla[0],
        p.lla[1],
        p.lla[2],
        p.h_msl,
        p.p_dop,
        p.h_acc,
        p.v_acc,
        v.s_acc,
        p.cno_mean,
        p.tow_offset,
        p.leap_s
    )
}

/// `$GNGGA` of GPS1_POS: pDop in the HDOP slot, MSL and the geoid
/// separation HAE − MSL.
pub(crate) fn gga(l: &mut Line, p: &GpsPos) -> core::fmt::Result {
    write!(l, "{TALKER}GGA,")?;
    put_utc(l, &utc_of_pos(p), true)?;
    l.write_char(',')?;
    put_lat_lon(l, p.lla[0], p.lla[1])?;
    write!(
        l,
        ",{},{:02},{:.2},{:.2},M,{:.2},M,,",
        gga_quality(fix_type(p.status)),
        p.status & 0xFF,
        p.p_dop,
        p.h_msl,
        p.lla[2] - f64::from(p.h_msl)
    )
}

/// `$GNGLL` of GPS1_POS: position (empty without a fix type), UTC, `A` if
/// the week is past 2269 (time validity, not the fix).
pub(crate) fn gll(l: &mut Line, p: &GpsPos) -> core::fmt::Result {
    write!(l, "{TALKER}GLL,")?;
    if fix_type(p.status) == 0 {
        l.write_str(",,,")?;
    } else {
        put_lat_lon(l, p.lla[0], p.lla[1])?;
    }
    l.write_char(',')?;
    put_utc(l, &utc_of_pos(p), true)?;
    write!(l, ",{}", if p.week > 2269 { 'A' } else { 'V' })
}

/// `$GNGSA` of GPS1_POS and GPS1_SAT: the first 12 listed satellites,
/// then pDop, hAcc, vAcc (the release's choice of fields, 1 dp).
pub(crate) fn gsa(l: &mut Line, p: &GpsPos, s: &GpsSat) -> core::fmt::Result {
    let fix = match fix_type(p.status) {
        2 => 2,
        3 | 8 | 9 | 10 | 11 | 12 => 3,
        _ => 0,
    };
    write!(l, "{TALKER}GSA,A,{fix:02}")?;
    for sv in &s.sat[..12] {
        if sv.sv_id == 0 {
            l.write_char(',')?;
        } else {
            write!(l, ",{:02}", sv.sv_id)?;
        }
    }
    write!(l, ",{:.1},{:.1},{:.1}", p.p_dop, p.h_acc, p.v_acc)
}

/// Horizontal NED velocity of GPS1_VEL at the fix's position (ECEF rotated
/// to NED; as is when the NMEA-sourced flag 0x8000 is set).
pub(crate) fn vel_ne(p: &GpsPos, v: &GpsVel) -> (f64, f64) {
    if v.status & 0x8000 != 0 {
        return (f64::from(v.vel[0]), f64::from(v.vel[1]));
    }
    let e = v.vel.map(f64::from);
    let ned = rotate_inv(&quat_e2n(p.lla[0], p.lla[1]), &e);
    (ned[0], ned[1])
}

/// Course over ground, degrees (−180…180, never wrapped) and 2-D speed,
/// m/s.
pub(crate) fn course_speed(vn: f64, ve: f64) -> (f64, f64) {
    (libm::atan2(ve, vn) * RAD2DEG, libm::sqrt(vn * vn + ve * ve))
}

/// `$GNRMC`: UTC without decimals, status, position, knots, course, date
/// `ddmmyy`, |magnetic variation| with E/W (`mag_decl_rad`: FLASH_CONFIG
/// `magDeclination`); no mode field.
pub(crate) fn rmc(
    l: &mut Line,
    p: &GpsPos,
    course_deg: f64,
    speed_mps: f64,
    mag_decl_rad: f32,
) -> core::fmt::Result {
    let u = utc_of_pos(p);
    write!(l, "{TALKER}RMC,")?;
    put_utc(l, &u, false)?;
    write!(l, ",{},", if fix_type(p.status) != 0 { 'A' } else { 'V' })?;
    put_lat_lon(l, p.lla[0], p.lla[1])?;
    let decl = f64::from(mag_decl_rad) * RAD2DEG;
    write!(
        l,
        ",{:05.1},{:05.1},{:02}{:02}{:02},{:05.1},{}",
        speed_mps * KNOTS,
        course_deg,
        u.day,
        u.month,
        u.year - 2000,
        decl.abs(),
        if decl >= 0.0 { 'E' } else { 'W' }
    )
}

/// `$GNVTG`: course (true), empty magnetic course, knots, km/h, mode.
pub(crate) fn vtg(l: &mut Line, p: &GpsPos, course_deg: f64, speed_mps: f64) -> core::fmt::Result {
    let mode = match fix_type(p.status) {
        2 | 3 => 'A',
        1 | 4 => 'E',
        8 | 10 | 11 | 12 => 'D',
        _ => 'N',
    };
    write!(
        l,
        "{TALKER}VTG,{course_deg:.2},T,,M,{:.2},N,{:.2},K,{mode}",
        speed_mps * KNOTS,
        speed_mps * KMH
    )
}

/// `$GNZDA`: UTC, day, month, year, zone 00 00.
pub(crate) fn zda(l: &mut Line, p: &GpsPos) -> core::fmt::Result {
    let u = utc_of_pos(p);
    write!(l, "{TALKER}ZDA,")?;
    put_utc(l, &u, true)?;
    write!(l, ",{:02},{:02},{:04},00,00", u.day, u.month, u.year)
}

/// `$PASHR`: UTC of the fix, heading (yaw, −180…180), roll and pitch
/// (signed), heave 0, attitude σ (`sigma_rad`: roll, pitch, heading), GPS
/// quality from the INS fix field, INS 1 with a NAV/AHRS/VRS solution.
pub(crate) fn pashr(l: &mut Line, p: &GpsPos, ins: &Ins1, sigma_rad: [f32; 3]) -> core::fmt::Result {
    let d = |x: f32| f64::from(x) * RAD2DEG;
    let [r, pi, y] = ins.theta;
    let [sr, sp, sy] = sigma_rad;
    let status = ins.header.ins_status;
    let nav_fix = (status >> 24) & 0x3;
    let quality = match nav_fix {
        2 | 3 => 2,
        1 => 1,
        _ => 0,
    };
    let solution = (status >> 16) & 0xF;
    write!(l, "PASHR,")?;
    put_utc(l, &utc_of_pos(p), true)?;
    write!(
        l,
        ",{:.2},T,{:+.2},{:+.2},{:+.2},{:.3},{:.3},{:.3},{quality},{}",
        d(y),
        d(r),
        d(pi),
        0.0,
        d(sr),
        d(sp),
        d(sy),
        u8::from(solution >= 3)
    )
}

/// `$PSTRB` of STROBE_IN_TIME: week, time of week ms, pin, count.
pub(crate) fn pstrb(l: &mut Line, s: &StrobeInTime) -> core::fmt::Result {
    write!(
        l,
        "PSTRB,{},{},{},{}",
        s.week, s.time_of_week_ms, s.pin, s.count
    )
}

/// `$POWGPS`: time valid (week > 2359), week, time of week µs, leap
/// valid (10 < leapS < 30), leapS, 0.
fn powgps_fields(l: &mut Line, p: &GpsPos) -> core::fmt::Result {
    write!(
        l,
        "{},{},{},{},{},0",
        u8::from(p.week > 2359),
        p.week,
        u64::from(p.time_of_week_ms) * 1000,
        u8::from(p.leap_s > 10 && p.leap_s < 30),
        p.leap_s
    )
}

/// `$POWGPS` of GPS1_POS.
pub(crate) fn powgps(l: &mut Line, p: &GpsPos) -> core::fmt::Result {
    l.write_str("POWGPS,")?;
    powgps_fields(l, p)
}

/// `$POWTLV`: the POWGPS fields, position, HAE and MSL (3 dp), then of the
/// raw GPS1_VEL vector |(x, y)|, z and atan2(y, x) (3 dp).
pub(crate) fn powtlv(l: &mut Line, p: &GpsPos, v: &GpsVel) -> core::fmt::Result {
    l.write_str("POWTLV,")?;
    powgps_fields(l, p)?;
    let [x, y, z] = v.vel.map(f64::from);
    write!(
        l,
        ",{:.8},{:.8},{:.3},{:.3},{:.3},{z:.3},{:.3}",
        p.lla[0],
        p.lla[1],
        p.lla[2],
        p.h_msl,
        libm::sqrt(x * x + y * y),
        libm::atan2(y, x)
    )
}

/// `$INTEL`: `KIM`, firmware version, time of week s, week, leapS, 0.000,
/// 0.000, 0, the GPS1_VEL vector, the cached NED velocity (north, east,
/// down 0).
pub(crate) fn intel(
    l: &mut Line,
    fw: [u8; 4],
    p: &GpsPos,
    v: &GpsVel,
    ne: (f64, f64),
) -> core::fmt::Result {
    let [x, y, z] = v.vel;
    write!(
        l,
        "INTEL,KIM,{}.{}.{}.{},{:.3},{},{},0.000,0.000,0,{x:.3},{y:.3},{z:.3},{:.3},{:.3},{:.3}",
        fw[0],
        fw[1],
        fw[2],
        fw[3],
        f64::from(p.time_of_week_ms) / 1000.0,
        p.week,
        p.leap_s,
        ne.0,
        ne.1,
        0.0
    )
}

/// GSV constellations in the release's order, with their talker and
/// `gnssId`s (SBAS prints inside `GP`, as PRN − 87).
pub(crate) const GSV_GROUPS: [(&str, &[u8]); 6] = [
    ("GP", &[1, 2]),
    ("GA", &[3]),
    ("GB", &[4]),
    ("GQ", &[5]),
    ("GL", &[6]),
    ("GI", &[7]),
];

/// The `$GxGSV` sentences of GPS1_SAT (NMEA 2.3 form: one group per
/// constellation whose mask (`masks[group]`, band bit 0x1 = first band)
/// is set; only satellites with C/N0 ≠ 0; up to four per sentence; elev,
/// azim, C/N0 empty when 0), each handed to `out`.
pub(crate) fn gsv(s: &GpsSat, masks: &[u8; 6], mut out: impl FnMut(&[u8])) {
    let n = (s.num_sats as usize).min(s.sat.len());
    let sats = &s.sat[..n];
    for (g, (talker, ids)) in GSV_GROUPS.iter().enumerate() {
        if masks[g] & 1 == 0 {
            continue;
        }
        let mine = || {
            sats.iter()
                .filter(move |sv| sv.cno != 0 && ids.contains(&sv.gnss_id))
        };
        let count = mine().count();
        if count == 0 {
            continue;
        }
        let msgs = count.div_ceil(4);
        let mut it = mine();
        for k in 1..=msgs {
            let mut l = Line::new();
            let ok = (|| {
                write!(l, "{talker}GSV,{msgs},{k},{count:02}")?;
                for sv in it.by_ref().take(4) {
                    let id = if sv.gnss_id == 2 {
                        u16::from(sv.sv_id).wrapping_sub(87)
                    } else {
                        u16::from(sv.sv_id)
                    };
                    write!(l, ",{id:02},")?;
                    if sv.elev != 0 {
                        write!(l, "{:02}", sv.elev)?;
                    }
                    l.write_char(',')?;
                    if sv.azim != 0 {
                        write!(l, "{:03}", sv.azim)?;
                    }
                    l.write_char(',')?;
                    write!(l, "{:02}", sv.cno)?;
                }
                Ok::<(), core::fmt::Error>(())
            })();
            if ok.is_ok() {
                if let Some(b) = l.finish() {
                    out(b);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn done(l: &mut Line) -> std::string::String {
        std::string::String::from_utf8(l.finish().unwrap().to_vec()).unwrap()
    }

    /// The release's worked example (`docs/isb-nmea.md`): week 2409, tow
    /// 487682.000 s, leapS 18 is 2026-03-13 15:27:44 UTC.
    #[test]
    fn utc_of_the_worked_example() {
        let u = utc_of(2409, 487_682_000, 18);
        assert_eq!(
            (u.year, u.month, u.day, u.hour, u.min, u.sec, u.ms),
            (2026, 3, 13, 15, 27, 44, 0)
        );
    }

    fn example_pos() -> GpsPos {
        GpsPos {
            week: 2409,
            time_of_week_ms: 487_682_000,
            status: 14 | 3 << 8 | 0x1_0000,
            lla: [40.330578, -111.725816, 1406.39],
            h_msl: 1425.18,
            h_acc: 0.37,
            v_acc: 0.55,
            p_dop: 0.95,
            leap_s: 18,
            ..GpsPos::default()
        }
    }

    /// GGA, GLL, ZDA of the release's worked example, byte for byte.
    #[test]
    fn the_worked_examples() {
        let p = example_pos();
        let mut l = Line::new();
        gga(&mut l, &p).unwrap();
        assert_eq!(
            done(&mut l),
            "$GNGGA,152744.000,4019.83468,N,11143.54896,W,1,14,0.95,1425.18,M,-18.79,M,,*74\r\n"
        );
        let mut l = Line::new();
        gll(&mut l, &p).unwrap();
        assert_eq!(
            done(&mut l),
            "$GNGLL,4019.83468,N,11143.54896,W,152744.000,A*34\r\n"
        );
        let mut l = Line::new();
        zda(&mut l, &p).unwrap();
        assert_eq!(done(&mut l), "$GNZDA,152744.000,13,03,2026,00,00*4E\r\n");
        let (c, s) = course_speed(3.0, 4.0);
        let mut l = Line::new();
        rmc(&mut l, &p, c, s, 0.2059).unwrap();
        assert_eq!(
            done(&mut l),
            "$GNRMC,152744,A,4019.83468,N,11143.54896,W,009.7,053.1,130326,011.8,E*72\r\n"
        );
        let mut l = Line::new();
        vtg(&mut l, &p, c, 5.0).unwrap();
        assert_eq!(done(&mut l), "$GNVTG,53.13,T,,M,9.72,N,18.00,K,A*22\r\n");
    }

    #[test]
    fn no_fix_gga_is_the_releases() {
        let mut l = Line::new();
        gga(&mut l, &GpsPos::default()).unwrap();
        // Week 0, tow 0, leapS 0: the zeroed record.
        assert_eq!(
            done(&mut l),
            "$GNGGA,000000.000,0000.00000,N,00000.00000,E,0,00,0.00,0.00,M,0.00,M,,*43\r\n"
        );
    }
}
