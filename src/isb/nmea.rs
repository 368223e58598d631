//! NMEA on the ISB port, and the one input classifier every received byte
//! goes through ([`Input`]).
//!
//! The vendor's command-line tool sends five NMEA commands
//! (`docs/protocol-facts.md` "ISB"):
//! `$INFO*0E`, `$STPB*15`, `$STPC*14`, `$PERS*14`, `$SRST*06` ([`Command`]),
//! each ended by `\r\n`, and around them bytes that mean nothing to an IMX
//! application: a stray second footer `*56\r\n`, bootloader probes (`U`
//! bytes, newlines, the Intel-HEX line `:020000041000EA`). A sentence is
//! `$`, a body, `*`, two hex digits (either case) of the XOR of the body
//! bytes, then `\r\n` — decision: `\n` alone or `\r` alone also ends it, and
//! it is taken as soon as its first end byte arrives. [`Input`] hands out
//! ISB packets and valid command sentences and drops everything else
//! silently (never echoed), counting it.
//!
//! The `$INFO` reply ([`info_sentence`]) has the fields of the SDK's
//! `nmea_dev_info` (the field list of its protocol-2 source): serial,
//! hardware version, firmware version, build number, protocol version,
//! repository revision, manufacturer, build date `YYYY-MM-DD`, build time
//! `HH:MM:SS.ss`, additional info, hardware type, run state (decision: the
//! 2.x encoder prints a reserved byte there, its newest version the run
//! state; the run state is what a reader can use), build type character;
//! then `*` and the checksum in upper-case hex (as the SDK's footer writes
//! it) and `\r\n`.

use super::packet::{Decoder, Packet, HEADER_LEN, MAX_PACKET};
use super::sets::DevInfo;
use core::fmt::Write as _;

/// Longest sentence body kept (bytes between `$` and `*`): the release's
/// receive limit `MAX_MSG_LENGTH_NMEA` (200 bytes for the whole sentence,
/// `$`, `*`, two hex digits and CR LF included; `docs/isb-nmea.md`);
/// longer bodies are dropped as bad sentences.
pub const MAX_BODY: usize = 200 - 6;

/// XOR of `body` (the bytes between `$` and `*`).
pub fn checksum(body: &[u8]) -> u8 {
    body.iter().fold(0, |x, &b| x ^ b)
}

/// An NMEA command the device obeys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// `$INFO`: reply with the `$INFO` sentence ([`info_sentence`]).
    Info,
    /// `$STPB`: stop every stream on every port.
    StopAllPorts,
    /// `$STPC`: stop every stream on this port.
    StopCurrentPort,
    /// `$PERS`: save the running streams as persistent.
    SavePersistent,
    /// `$SRST`: software reset.
    SoftwareReset,
}

impl Command {
    /// All five.
    pub const ALL: [Command; 5] = [
        Command::Info,
        Command::StopAllPorts,
        Command::StopCurrentPort,
        Command::SavePersistent,
        Command::SoftwareReset,
    ];

    /// The sentence body (between `$` and `*`).
    pub const fn body(self) -> &'static str {
        match self {
            Command::Info => "INFO",
            Command::StopAllPorts => "STPB",
            Command::StopCurrentPort => "STPC",
            Command::SavePersistent => "PERS",
            Command::SoftwareReset => "SRST",
        }
    }

    /// The whole sentence as the vendor tool sends it, `\r\n` included.
    pub const fn sentence(self) -> &'static str {
        match self {
            Command::Info => "$INFO*0E\r\n",
            Command::StopAllPorts => "$STPB*15\r\n",
            Command::StopCurrentPort => "$STPC*14\r\n",
            Command::SavePersistent => "$PERS*14\r\n",
            Command::SoftwareReset => "$SRST*06\r\n",
        }
    }

    /// The command with this body, if any (exact match).
    pub fn from_body(body: &[u8]) -> Option<Self> {
        Command::ALL
            .into_iter()
            .find(|c| c.body().as_bytes() == body)
    }
}

/// Writes into a byte slice, failing (not panicking) when it is full.
struct Cursor<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl core::fmt::Write for Cursor<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let end = self.len.checked_add(s.len()).ok_or(core::fmt::Error)?;
        let dst = self.out.get_mut(self.len..end).ok_or(core::fmt::Error)?;
        dst.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Writes a NUL-terminated string field, each byte that would break the
/// sentence (outside `0x20..=0x7E`, or `,` `*` `$`) as `_` (decision).
fn put_str(c: &mut Cursor<'_>, field: &[u8]) -> core::fmt::Result {
    for &b in field.iter().take_while(|&&b| b != 0) {
        let b = if (0x20..=0x7E).contains(&b) && !b",*$".contains(&b) {
            b
        } else {
            b'_'
        };
        c.write_char(char::from(b))?;
    }
    Ok(())
}

fn write_info(c: &mut Cursor<'_>, d: &DevInfo) -> core::fmt::Result {
    let v = |x: [u8; 4]| (x[0], x[1], x[2], x[3]);
    let (h0, h1, h2, h3) = v(d.hardware_ver);
    let (f0, f1, f2, f3) = v(d.firmware_ver);
    let (p0, p1, p2, p3) = v(d.protocol_ver);
    // The SDK prints the u32 fields through `%d` of an `int`.
    write!(
        c,
        "$INFO,{},{h0}.{h1}.{h2}.{h3},{f0}.{f1}.{f2}.{f3},{},{p0}.{p1}.{p2}.{p3},{},",
        d.serial_number as i32, d.build_number as i32, d.repo_revision as i32,
    )?;
    put_str(c, &d.manufacturer)?;
    let [y, mo, day] = d.build_date;
    let [hh, mm, ss, ms] = d.build_time;
    write!(
        c,
        ",{:04}-{mo:02}-{day:02},{hh:02}:{mm:02}:{ss:02}.{ms:02},",
        u16::from(y) + 2000
    )?;
    put_str(c, &d.add_info)?;
    let build_type = if (0x21..=0x7E).contains(&d.build_type) && !b",*$".contains(&d.build_type) {
        char::from(d.build_type)
    } else {
        ' '
    };
    write!(c, ",{},{},{build_type}", d.hardware_type, d.hdw_run_state)
}

/// Writes the `$INFO` reply for `d` into `out` (module doc for the fields);
/// its length, or `None` if `out` is too small (200 bytes always suffice).
pub fn info_sentence(d: &DevInfo, out: &mut [u8]) -> Option<usize> {
    let mut c = Cursor { out, len: 0 };
    write_info(&mut c, d).ok()?;
    let sum = checksum(c.out.get(1..c.len)?);
    write!(c, "*{sum:02X}\r\n").ok()?;
    Some(c.len)
}

/// What [`Input`] hands out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event<'a> {
    /// A valid ISB packet (checksum right), borrowing the input buffer.
    Packet(Packet<'a>),
    /// A valid command sentence.
    Nmea(Command),
    /// A valid `$ASCE` sentence: its body (between `$` and `*`, starting
    /// `ASCE`), borrowing the classifier ([`super::asce`]).
    Asce(&'a [u8]),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Between messages.
    Idle,
    /// The ISB decoder holds a candidate packet.
    Isb,
    /// In a sentence body.
    Body,
    /// After `*`, this many hex digits seen.
    Hex(u8),
    /// After the two hex digits, waiting for the end byte.
    End,
}

/// Counts of what [`Input`] dropped (diagnostics and tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Dropped {
    /// Bytes between messages that start none (probes, newlines, stray
    /// footers, Intel-HEX lines, line noise).
    pub junk_bytes: u32,
    /// Sentences cut short, too long, or with a wrong checksum.
    pub bad_sentences: u32,
    /// Valid sentences that are not one of the five commands nor `$ASCE`.
    pub unknown_sentences: u32,
}

/// The input classifier: feed it every received byte, in any chunking; it
/// calls back with each ISB packet ([`Decoder`], resync after garbage and
/// bad checksums) and each valid command sentence, in arrival order, and
/// drops everything else. A `$` or `0xEF` always starts a new message (a
/// sentence in progress is dropped for it); while the decoder holds an ISB
/// candidate every byte goes to it, so a sentence arriving inside a
/// candidate that later fails its checksum is lost with it. A candidate
/// refused within its header (a stray `0xEF` not followed by `0x49`, an
/// impossible size) gives its bytes after the first back to the sentence
/// side, so a stray `0xEF` right before `$STPB` does not swallow the `$`.
/// `CAP` is the largest packet accepted ([`MAX_PACKET`] for every legal
/// packet).
#[derive(Debug, Clone)]
pub struct Input<const CAP: usize = MAX_PACKET> {
    isb: Decoder<CAP>,
    mode: Mode,
    /// The first bytes of the ISB candidate held, and how many it has
    /// taken (saturating).
    head: [u8; HEADER_LEN],
    taken: usize,
    body: [u8; MAX_BODY],
    body_len: usize,
    sum: u8,
    dropped: Dropped,
}

impl<const CAP: usize> Default for Input<CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize> Input<CAP> {
    /// An idle classifier.
    pub const fn new() -> Self {
        Input {
            isb: Decoder::new(),
            mode: Mode::Idle,
            head: [0; HEADER_LEN],
            taken: 0,
            body: [0; MAX_BODY],
            body_len: 0,
            sum: 0,
            dropped: Dropped {
                junk_bytes: 0,
                bad_sentences: 0,
                unknown_sentences: 0,
            },
        }
    }

    /// What was dropped so far.
    pub fn dropped(&self) -> Dropped {
        self.dropped
    }

    /// ISB candidates the decoder dropped (bad checksum or size).
    pub(crate) fn isb_errors(&self) -> u32 {
        self.isb.errors()
    }

    /// Whether part of a message is held (a packet or a sentence).
    pub fn has_partial(&self) -> bool {
        self.mode != Mode::Idle
    }

    /// Drops whatever part of a message is held (e.g. after an idle gap);
    /// the bytes of an ISB candidate are dropped one by one, each counted in
    /// [`Input::isb_errors`], so none of them is rescanned later.
    pub fn abandon(&mut self) {
        match self.mode {
            Mode::Isb => {
                while self.isb.has_partial() {
                    self.isb.abandon();
                }
            }
            Mode::Idle => {}
            _ => self.dropped.bad_sentences = self.dropped.bad_sentences.wrapping_add(1),
        }
        self.mode = Mode::Idle;
    }

    /// Feeds `bytes`, calling `on` for every packet and command completed.
    pub fn feed(&mut self, bytes: &[u8], mut on: impl FnMut(Event<'_>)) {
        for &b in bytes {
            self.byte(b, &mut on);
        }
    }

    fn byte(&mut self, b: u8, on: &mut impl FnMut(Event<'_>)) {
        match self.mode {
            Mode::Idle => self.idle(b, on),
            Mode::Isb => self.isb_byte(b, on),
            Mode::Body => match b {
                b'*' => self.mode = Mode::Hex(0),
                0x20..=0x7E if b != b'$' && self.body_len < MAX_BODY => {
                    self.body[self.body_len] = b;
                    self.body_len += 1;
                }
                _ => self.bad_then_idle(b, on),
            },
            Mode::Hex(n) => match (b as char).to_digit(16) {
                Some(d) => {
                    self.sum = self.sum << 4 | d as u8;
                    self.mode = if n == 0 { Mode::Hex(1) } else { Mode::End };
                }
                None => self.bad_then_idle(b, on),
            },
            Mode::End => match b {
                b'\r' | b'\n' => {
                    self.mode = Mode::Idle;
                    let body = &self.body[..self.body_len];
                    if checksum(body) != self.sum {
                        self.dropped.bad_sentences = self.dropped.bad_sentences.wrapping_add(1);
                    } else if let Some(c) = Command::from_body(body) {
                        on(Event::Nmea(c));
                    } else if body.starts_with(b"ASCE") {
                        on(Event::Asce(body));
                    } else {
                        self.dropped.unknown_sentences =
                            self.dropped.unknown_sentences.wrapping_add(1);
                    }
                }
                _ => self.bad_then_idle(b, on),
            },
        }
    }

    fn bad_then_idle(&mut self, b: u8, on: &mut impl FnMut(Event<'_>)) {
        self.dropped.bad_sentences = self.dropped.bad_sentences.wrapping_add(1);
        self.mode = Mode::Idle;
        self.idle(b, on);
    }

    fn idle(&mut self, b: u8, on: &mut impl FnMut(Event<'_>)) {
        match b {
            b'$' => {
                self.mode = Mode::Body;
                self.body_len = 0;
                self.sum = 0;
            }
            b if b == super::packet::PREAMBLE[0] => {
                self.mode = Mode::Isb;
                self.taken = 0;
                self.isb_byte(b, on);
            }
            _ => self.dropped.junk_bytes = self.dropped.junk_bytes.wrapping_add(1),
        }
    }

    fn isb_byte(&mut self, b: u8, on: &mut impl FnMut(Event<'_>)) {
        if let Some(h) = self.head.get_mut(self.taken) {
            *h = b;
        }
        self.taken = self.taken.saturating_add(1);
        let mut one: &[u8] = core::slice::from_ref(&b);
        let mut found = false;
        while let Some(p) = self.isb.next_packet(&mut one) {
            found = true;
            on(Event::Packet(p));
        }
        if self.isb.has_partial() {
            return;
        }
        self.mode = Mode::Idle;
        if !found && self.taken <= HEADER_LEN {
            // Refused within its header: its bytes after the first go back
            // to the sentence side (the decoder has dropped them).
            let (head, n) = (self.head, self.taken);
            for &x in &head[1..n] {
                self.rescanned(x, on);
            }
        }
    }

    /// A byte the ISB decoder refused, classified again for sentences
    /// only (an `0xEF` among them was the decoder's to take: junk here).
    fn rescanned(&mut self, b: u8, on: &mut impl FnMut(Event<'_>)) {
        if b != super::packet::PREAMBLE[0] {
            self.byte(b, on);
        } else if self.mode == Mode::Idle {
            self.dropped.junk_bytes = self.dropped.junk_bytes.wrapping_add(1);
        } else {
            self.dropped.bad_sentences = self.dropped.bad_sentences.wrapping_add(1);
            self.mode = Mode::Idle;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_five_sentences_carry_their_checksums() {
        for c in Command::ALL {
            let s = c.sentence().as_bytes();
            let sum = checksum(c.body().as_bytes());
            let hex = core::str::from_utf8(&s[6..8]).unwrap();
            assert_eq!(u8::from_str_radix(hex, 16).unwrap(), sum, "{}", c.body());
        }
    }
}
