//! `$ASCE`: the IMX-5's NMEA stream table and the sentence that sets it
//! (Inertial Sense SDK 2.7.1 `nmea_parse_asce`, `docs/isb-nmea.md`).
//!
//! `$ASCE,<options>{,<id>,<period>}*CS`: options decimal or `0x` hex (port
//! mask 0xFF, 0x200 persistent, 0xC00 speed filter); up to
//! [`MAX_PAIRS`] pairs; an ID is a number or a name (the release's 4-byte
//! windows, case-sensitive); a period is the multiple of the sentence's
//! source period, stored as a `u8` (256 → 0), 0 = once. The release does
//! not validate IDs (an unknown name or an out-of-range number writes past
//! its table); the emulator drops such a pair and counts it (decision).
//! `$ASCE` alone (`$ASCE*14`) asks for the table ([`Table::reply`]).

use core::fmt::Write as _;

use super::nmea_out::Line;

/// The NMEA message IDs of SDK 2.7.1 (`data_sets.h` `NMEA_MSG_ID_*`;
/// 1-based since SDK 2.x, 0 invalid).
pub(crate) mod id {
    /// `$PIMU` (IMU).
    pub(crate) const PIMU: u8 = 1;
    /// `$PPIMU` (PIMU).
    pub(crate) const PPIMU: u8 = 2;
    /// `$PRIMU` (IMU_RAW).
    pub(crate) const PRIMU: u8 = 3;
    /// `$PINS1` (INS_1).
    pub(crate) const PINS1: u8 = 4;
    /// `$PINS2` (INS_2).
    pub(crate) const PINS2: u8 = 5;
    /// `$PGPSP` (GPS1_POS, GPS1_VEL).
    pub(crate) const PGPSP: u8 = 6;
    /// `$GxGGA`.
    pub(crate) const GGA: u8 = 7;
    /// `$GxGLL`.
    pub(crate) const GLL: u8 = 8;
    /// `$GxGSA`.
    pub(crate) const GSA: u8 = 9;
    /// `$GxRMC`.
    pub(crate) const RMC: u8 = 10;
    /// `$GxZDA`.
    pub(crate) const ZDA: u8 = 11;
    /// `$PASHR`.
    pub(crate) const PASHR: u8 = 12;
    /// `$PSTRB` (no name: numeric only).
    pub(crate) const PSTRB: u8 = 13;
    /// `$INFO` (DEV_INFO).
    pub(crate) const INFO: u8 = 14;
    /// `$GxGSV` (GPS1_SAT).
    pub(crate) const GSV: u8 = 15;
    /// `$GxVTG`.
    pub(crate) const VTG: u8 = 16;
    /// `$INTEL`.
    pub(crate) const INTEL: u8 = 17;
    /// `$POWGPS`.
    pub(crate) const POWGPS: u8 = 18;
    /// `$POWTLV`.
    pub(crate) const POWTLV: u8 = 19;
    /// Entries of the period table.
    pub(crate) const COUNT: usize = 20;
}

/// Pairs one `$ASCE` may carry; the rest is ignored.
pub(crate) const MAX_PAIRS: usize = 20;
/// Options: the port mask.
pub(crate) const OPT_PORT_MASK: u32 = 0xFF;
/// Options: persistent (saved as by `$PERS`).
pub(crate) const OPT_PERSISTENT: u32 = 0x200;
/// Options: the speed filter field (1 on, 2 off).
pub(crate) const OPT_SPEED_FILTER_SHIFT: u32 = 10;
/// The emulated line's port bit (`ser0`: the emulator's one line).
pub(crate) const PORT_SER0: u32 = 0x01;
/// GSV band filter numbers: 3840 + constellation × 16 + band bits.
pub(crate) const GSV_FILTER_BASE: i64 = 3840;
/// GSV constellations (`GSV_GROUPS` order of [`super::nmea_out`]).
pub(crate) const GSV_CONSTELLATIONS: usize = 6;

/// What one `$ASCE` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Applied {
    /// Pairs taken.
    pub pairs: u8,
    /// Pairs dropped (unknown name, out-of-range ID, over [`MAX_PAIRS`],
    /// a missing period).
    pub rejected: u8,
    /// The options asked to save the table (`OPT_PERSISTENT`).
    pub persistent: bool,
}

/// The NMEA stream table of the port (bits and periods per ID) and the
/// global settings `$ASCE` also writes (GSV masks, speed filter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Table {
    /// Bit `id` set: the sentence is on (period 0: once).
    pub bits: u32,
    /// Period multiple per ID.
    pub periods: [u8; id::COUNT],
    /// GSV band masks per constellation (global).
    pub gsv_masks: [u8; GSV_CONSTELLATIONS],
    /// The 5-sample median filter of the printed speed is on.
    pub speed_filter: bool,
}

/// Bytes of a table in the flash image: `u32 bits`, the periods, the GSV
/// masks, a flags byte (speed filter), padding to 32.
pub const IMAGE_LEN: usize = 32;

impl Table {
    /// Whether ID `i` is on.
    pub(crate) fn on(&self, i: u8) -> bool {
        usize::from(i) < id::COUNT && self.bits & (1 << i) != 0
    }

    /// Turns every stream off (stops; the GSV masks and filter stay).
    pub(crate) fn stop(&mut self) {
        self.bits = 0;
        self.periods = [0; id::COUNT];
    }

    /// A one-shot went out: its bit clears.
    pub(crate) fn clear(&mut self, i: u8) {
        if usize::from(i) < id::COUNT {
            self.bits &= !(1 << i);
        }
    }

    /// The persistent image (one-shots are not kept).
    pub(crate) fn to_image(self) -> [u8; IMAGE_LEN] {
        let mut b = [0u8; IMAGE_LEN];
        let mut bits = self.bits;
        for (i, p) in self.periods.iter().enumerate() {
            if *p == 0 {
                bits &= !(1 << i);
            }
        }
        b[..4].copy_from_slice(&bits.to_le_bytes());
        b[4..24].copy_from_slice(&self.periods);
        b[24..30].copy_from_slice(&self.gsv_masks);
        b[30] = u8::from(self.speed_filter);
        b
    }

    /// Of a persistent image.
    pub(crate) fn from_image(b: &[u8; IMAGE_LEN]) -> Self {
        let mut t = Table {
            bits: u32::from_le_bytes([b[0], b[1], b[2], b[3]]) & ((1 << id::COUNT) - 1),
            speed_filter: b[30] & 1 != 0,
            ..Table::default()
        };
        t.periods.copy_from_slice(&b[4..24]);
        t.gsv_masks.copy_from_slice(&b[24..30]);
        t
    }

    /// The reply to `$ASCE*14`: `$ASCE,0` then `,id,period` for every ID on
    /// with a period > 0, ascending; into `out`.
    pub(crate) fn reply(&self, out: &mut Line) -> core::fmt::Result {
        out.write_str("ASCE,0")?;
        for i in 0..id::COUNT as u8 {
            let p = self.periods[usize::from(i)];
            if self.on(i) && p > 0 {
                write!(out, ",{i},{p}")?;
            }
        }
        Ok(())
    }

    /// Applies the fields after `ASCE` (`body` = the bytes between `$` and
    /// `*`, starting `ASCE,`) as the release does (module doc).
    pub(crate) fn apply(&mut self, body: &[u8]) -> Applied {
        let mut a = Applied::default();
        let mut fields = body.split(|&b| b == b',');
        let _name = fields.next();
        let options = fields.next().map_or(0, parse_options);
        a.persistent = options & OPT_PERSISTENT != 0;
        match (options >> OPT_SPEED_FILTER_SHIFT) & 3 {
            1 => self.speed_filter = true,
            2 => self.speed_filter = false,
            _ => {}
        }
        let mask = options & OPT_PORT_MASK;
        // The one line is ser0 (module doc of `docs/isb.md` "NMEA").
        let here = mask == 0 || mask == OPT_PORT_MASK || mask & PORT_SER0 != 0;
        let mut taken = 0usize;
        while let Some(idf) = fields.next() {
            let Some(pf) = fields.next() else {
                // An ID with no period drops that pair.
                a.rejected = a.rejected.saturating_add(1);
                break;
            };
            if pf.is_empty() && fields.clone().next().is_none() {
                // An empty period right before `*` drops the pair.
                a.rejected = a.rejected.saturating_add(1);
                break;
            }
            if taken == MAX_PAIRS {
                a.rejected = a.rejected.saturating_add(1);
                continue;
            }
            taken += 1;
            let period = (parse_int(pf) & 0xFF) as u8;
            let Some(target) = resolve_id(idf) else {
                a.rejected = a.rejected.saturating_add(1);
                continue;
            };
            let i = match target {
                Target::Id(i) => i,
                Target::Gsv {
                    constellations,
                    bands,
                } => {
                    if period != 0 {
                        for (g, m) in self.gsv_masks.iter_mut().enumerate() {
                            if constellations & (1 << g) != 0 {
                                *m = bands;
                            }
                        }
                    } else if mask == OPT_PORT_MASK && constellations == ALL_CONSTELLATIONS {
                        self.gsv_masks = [0; GSV_CONSTELLATIONS];
                    }
                    id::GSV
                }
            };
            if here {
                self.bits |= 1 << i;
                self.periods[usize::from(i)] = period;
            }
            a.pairs = a.pairs.saturating_add(1);
        }
        a
    }
}

crate::data_set! {
    /// `{u8 msgID, u8 period}`: one entry of `nmea_msgs_t`.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct NmeaMsg in mod nmea_msg, 2 bytes {
        /// Sentence ID (0 ends the list).
        msg_id: u8 = MSG_ID @ 0 => ["msgID"],
        /// Period, in the sentence's source periods.
        period: u8 = PERIOD @ 1 => ["period"],
    }
}

crate::data_set! {
    /// `nmea_msgs_t` (DID 8, `NMEA_BCAST_PERIOD`; SDK 2.7.1 `data_sets.h`):
    /// `u32 options`, then [`MAX_PAIRS`] × `{u8 msgID, u8 period}`; an ID 0
    /// ends the list.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct NmeaMsgs in mod nmea_msgs, 44 bytes {
        /// `$ASCE` options.
        options: u32 = OPTIONS @ 0 => ["options"],
        /// The pairs.
        msgs: [NmeaMsg; MAX_PAIRS] = MSGS @ 4 => [each "nmeaBroadcastMsgs"
            [0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19] ["msgID", "period"]],
    }
}

impl Table {
    /// The table as `nmea_msgs_t` (decision: options 0, then the IDs on
    /// with a period > 0, ascending, as the `$ASCE*14` reply lists them).
    pub(crate) fn to_msgs(self) -> [u8; nmea_msgs::SIZE] {
        let mut b = [0u8; nmea_msgs::SIZE];
        let mut at = nmea_msgs::MSGS;
        for i in 1..id::COUNT as u8 {
            let p = self.periods[usize::from(i)];
            if self.on(i) && p > 0 && at + 2 <= nmea_msgs::SIZE {
                b[at] = i;
                b[at + 1] = p;
                at += 2;
            }
        }
        b
    }

    /// A write of `nmea_msgs_t`: the options and pairs applied as an
    /// `$ASCE` with them would be (decision), up to the first ID 0.
    pub(crate) fn apply_msgs(&mut self, b: &[u8; nmea_msgs::SIZE]) -> Applied {
        let options = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        let mut body: heapless::String<160> = heapless::String::new();
        let _ = write!(body, "ASCE,{options}");
        for pair in b[nmea_msgs::MSGS..].chunks_exact(2) {
            if pair[0] == 0 {
                break;
            }
            let _ = write!(body, ",{},{}", pair[0], pair[1]);
        }
        self.apply(body.as_bytes())
    }
}

/// Every constellation GSV can show but NavIC (the release's `GN`/15).
const ALL_CONSTELLATIONS: u8 = 0b01_1111;

/// What an `$ASCE` ID field names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Id(u8),
    /// GSV with its constellation set (bits of [`GSV_CONSTELLATIONS`]) and
    /// band mask.
    Gsv {
        constellations: u8,
        bands: u8,
    },
}

/// The release's options field: decimal, or hex after `0x`/`0X`; what does
/// not parse counts as 0 (`strtol`).
fn parse_options(f: &[u8]) -> u32 {
    match f {
        [b'0', b'x' | b'X', hex @ ..] => hex
            .iter()
            .map_while(|&c| (c as char).to_digit(16))
            .fold(0u32, |v, d| v.wrapping_mul(16).wrapping_add(d)),
        _ => parse_int(f) as u32,
    }
}

/// `atoi`: optional sign, leading decimal digits, wrapping.
fn parse_int(f: &[u8]) -> i64 {
    let (neg, digits) = match f {
        [b'-', r @ ..] => (true, r),
        [b'+', r @ ..] => (false, r),
        _ => (false, f),
    };
    let v = digits
        .iter()
        .take_while(|c| c.is_ascii_digit())
        .fold(0i64, |v, &c| {
            v.wrapping_mul(10).wrapping_add(i64::from(c - b'0'))
        });
    if neg {
        v.wrapping_neg()
    } else {
        v
    }
}

/// GSV band bits of a `_…` suffix: digits 1, 2, 3, 5 → 0x1, 0x2, 0x4,
/// 0x8; none = every band.
fn gsv_bands(suffix: &[u8]) -> u8 {
    let b = suffix.iter().fold(0u8, |m, c| {
        m | match c {
            b'1' => 1,
            b'2' => 2,
            b'3' => 4,
            b'5' => 8,
            _ => 0,
        }
    });
    if b == 0 {
        0xF
    } else {
        b
    }
}

/// The ID an `$ASCE` field names (module doc): numbers as is (0…19, and
/// 3840…3951 as GSV filters), names by the release's rules.
fn resolve_id(f: &[u8]) -> Option<Target> {
    if f.first().is_some_and(u8::is_ascii_digit) {
        let n = parse_int(f);
        return match n {
            0..=19 if n as u8 == id::GSV => Some(Target::Gsv {
                constellations: ALL_CONSTELLATIONS,
                bands: 0xF,
            }),
            0..=19 => Some(Target::Id(n as u8)),
            GSV_FILTER_BASE..=3951 => {
                let c = ((n - GSV_FILTER_BASE) / 16) as u8;
                let bands = ((n - GSV_FILTER_BASE) % 16) as u8;
                gsv_constellation_bits(c).map(|constellations| Target::Gsv {
                    constellations,
                    bands,
                })
            }
            _ => None,
        };
    }
    let w = |s: &[u8]| f.starts_with(s);
    let t = if w(b"PIMU") {
        id::PIMU
    } else if w(b"PPIM") {
        id::PPIMU
    } else if w(b"PRIM") {
        id::PRIMU
    } else if w(b"PINS") {
        if f.get(4) == Some(&b'1') {
            id::PINS1
        } else {
            id::PINS2
        }
    } else if w(b"PGPS") {
        id::PGPSP
    } else if w(b"PASH") {
        id::PASHR
    } else if w(b"INFO") {
        id::INFO
    } else if w(b"INTE") {
        id::INTEL
    } else if w(b"POWG") {
        id::POWGPS
    } else if w(b"POWT") {
        id::POWTLV
    } else if f.len() >= 5 && f[0] == b'G' && &f[2..5] == b"GSV" {
        let constellations = match f[1] {
            b'N' | b'x' | b'X' => ALL_CONSTELLATIONS,
            b'P' => 1,
            b'A' => 1 << 1,
            b'B' => 1 << 2,
            b'Q' => 1 << 3,
            b'L' => 1 << 4,
            _ => return None,
        };
        let bands = match f.get(5) {
            Some(b'_') => gsv_bands(&f[6..]),
            None => 0xF,
            Some(_) => return None,
        };
        return Some(Target::Gsv {
            constellations,
            bands,
        });
    } else if f.len() == 5 && f[0] == b'G' {
        match &f[2..5] {
            b"GGA" => id::GGA,
            b"GLL" => id::GLL,
            b"GSA" => id::GSA,
            b"RMC" => id::RMC,
            b"ZDA" => id::ZDA,
            b"VTG" => id::VTG,
            _ => return None,
        }
    } else {
        return None;
    };
    Some(Target::Id(t))
}

/// Constellation bits of a GSV filter number's constellation (`eSatSvGnssId`:
/// 0 all, 1 GPS, 2 SBAS — shown in the GPS group —, 3 Galileo, 4 BeiDou,
/// 5 QZSS, 6 GLONASS; 3857 = GPS L1).
fn gsv_constellation_bits(c: u8) -> Option<u8> {
    match c {
        0 => Some(ALL_CONSTELLATIONS),
        1 | 2 => Some(1),
        3 => Some(1 << 1),
        4 => Some(1 << 2),
        5 => Some(1 << 3),
        6 => Some(1 << 4),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn applied(s: &str) -> (Table, Applied) {
        let mut t = Table::default();
        let a = t.apply(s.as_bytes());
        (t, a)
    }

    #[test]
    fn names_numbers_and_periods_as_the_release_parses_them() {
        let (t, a) = applied("ASCE,0,PINS1,2,PPIMU,1,GNGGA,1");
        assert_eq!(a.pairs, 3);
        assert!(t.on(id::PINS1) && t.on(id::PPIMU) && t.on(id::GGA));
        assert_eq!(t.periods[4], 2);
        // 1-based IDs: "3" is PRIMU; 300 is stored as 44; GPGGA and GxGGA
        // both name GGA; PINS2 and "PINS," name PINS2.
        let (t, _) = applied("ASCE,0,3,300,GxRMC,1,PINS2,5");
        assert_eq!((t.periods[3], t.periods[10], t.periods[5]), (44, 1, 5));
        // PSTRB has no name; an unknown name is dropped and counted.
        let (t, a) = applied("ASCE,0,PSTRB,1,13,1");
        assert_eq!((a.pairs, a.rejected), (1, 1));
        assert!(t.on(id::PSTRB));
        // An ID with no period, or an empty period before `*`, drops it.
        let (t, a) = applied("ASCE,0,7");
        assert_eq!((t.bits, a.rejected), (0, 1));
        let (t, _) = applied("ASCE,0,7,");
        assert_eq!(t.bits, 0);
        // An empty period between commas is 0 (once).
        let (t, _) = applied("ASCE,0,7,,8,1");
        assert!(t.on(7) && t.periods[7] == 0 && t.periods[8] == 1);
    }

    #[test]
    fn options_ports_persistence_and_the_reply() {
        let (t, a) = applied("ASCE,512,GNGGA,1,GNRMC,1");
        assert!(a.persistent && t.on(id::GGA));
        // USB only: not this line.
        let (t, a) = applied("ASCE,8,PINS2,2");
        assert_eq!((t.bits, a.pairs), (0, 1));
        let (t, _) = applied("ASCE,0x400,GNVTG,1");
        assert!(t.speed_filter);
        let (t, _) = applied("ASCE,0,PINS1,2,GNGGA,1,GNZDA,0");
        let mut l = Line::new();
        t.reply(&mut l).unwrap();
        assert_eq!(l.finish().unwrap(), b"$ASCE,0,4,2,7,1*08\r\n");
        let mut l = Line::new();
        Table::default().reply(&mut l).unwrap();
        assert_eq!(l.finish().unwrap(), b"$ASCE,0*08\r\n");
    }

    #[test]
    fn gsv_filters_and_too_many_pairs() {
        let (t, _) = applied("ASCE,0,GPGSV_1,2");
        assert_eq!(t.gsv_masks, [1, 0, 0, 0, 0, 0]);
        let (t, _) = applied("ASCE,0,3857,1");
        assert_eq!(t.gsv_masks[0], 1);
        assert!(t.on(id::GSV));
        let (t, _) = applied("ASCE,0,15,1");
        assert_eq!(t.gsv_masks, [0xF, 0xF, 0xF, 0xF, 0xF, 0]);
        let mut s = std::string::String::from("ASCE,0");
        for _ in 0..22 {
            s.push_str(",7,1");
        }
        let (_, a) = applied(&s);
        assert_eq!((a.pairs, a.rejected), (20, 2));
        // Out-of-range numbers are dropped, never index past the table.
        let (t, a) = applied("ASCE,0,20,1,4000,1,99999999999999999999,1");
        assert_eq!((t.bits, a.rejected), (0, 3));
    }

    #[test]
    fn the_image_round_trips_without_one_shots() {
        let (t, _) = applied("ASCE,0,PINS1,2,GNGGA,0,GPGSV,1");
        let back = Table::from_image(&t.to_image());
        assert!(back.on(id::PINS1) && !back.on(id::GGA) && back.on(id::GSV));
        assert_eq!(back.gsv_masks, t.gsv_masks);
    }
}
