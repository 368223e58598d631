//! ISB packets (ISB protocol page "Packet structure";
//! `docs/protocol-facts.md` "ISB").
//!
//! `EF 49 | flags | did | size u16 LE | payload | a b`: the low nibble of
//! `flags` is the [`PacketType`]; flag [`FLAG_OFFSET`] means the payload
//! starts with a `u16` offset into the data set. The checksum is two
//! wrapping 8-bit sums over every byte from the preamble through the
//! payload: per byte `a += x; b += a`, written `a` then `b` (not the
//! textbook mod-255 Fletcher; both hex examples of the page match this).
//! A whole packet is at most [`MAX_PACKET`] bytes.

use crate::framing::{Framing, Scanner};

/// The two preamble bytes.
pub const PREAMBLE: [u8; 2] = [0xEF, 0x49];
/// Header bytes (preamble, flags, DID, payload size).
pub const HEADER_LEN: usize = 6;
/// Bytes a packet adds around its payload (header 6, checksum 2).
pub const OVERHEAD: usize = 8;
/// Largest whole packet the protocol allows, bytes.
pub const MAX_PACKET: usize = 2048;
/// `flags` bit: the payload starts with a `u16` offset into the data set.
pub const FLAG_OFFSET: u8 = 0x20;
/// `flags` bit: extended payload (not used by protocol 2.1).
pub const FLAG_EXTENDED: u8 = 0x10;

/// Packet type: the low nibble of `flags`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PacketType {
    /// Acknowledgement of a SET_DATA or a stop command.
    Ack = 1,
    /// Negative acknowledgement (e.g. GET_DATA of an unknown DID).
    Nack = 2,
    /// Request one packet or a stream of a data set.
    GetData = 3,
    /// A data set (or a part of it).
    Data = 4,
    /// Write (part of) a data set.
    SetData = 5,
    /// Stop every broadcast on every port.
    StopBroadcastsAllPorts = 6,
    /// Stop the broadcast of the DID in the header.
    StopDidBroadcast = 7,
    /// Stop every broadcast on this port.
    StopBroadcastsCurrentPort = 8,
}

impl PacketType {
    /// The type of a packet with these `flags`, if it is one of the eight.
    pub fn from_flags(flags: u8) -> Option<Self> {
        Some(match flags & 0x0F {
            1 => PacketType::Ack,
            2 => PacketType::Nack,
            3 => PacketType::GetData,
            4 => PacketType::Data,
            5 => PacketType::SetData,
            6 => PacketType::StopBroadcastsAllPorts,
            7 => PacketType::StopDidBroadcast,
            8 => PacketType::StopBroadcastsCurrentPort,
            _ => return None,
        })
    }
}

/// The checksum `[a, b]` of `bytes` (preamble through payload).
pub fn checksum(bytes: &[u8]) -> [u8; 2] {
    let (mut a, mut b) = (0u8, 0u8);
    for &x in bytes {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    [a, b]
}

/// A decoded packet borrowing the decoder's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Packet<'a> {
    /// The `flags` byte (type in the low nibble, [`FLAG_OFFSET`]).
    pub flags: u8,
    /// Data set identifier (0 in GET_DATA, ACK and NACK headers).
    pub did: u8,
    /// The payload (with the offset, if [`FLAG_OFFSET`] is set).
    pub payload: &'a [u8],
}

impl<'a> Packet<'a> {
    /// The packet type, if `flags` names one.
    pub fn kind(&self) -> Option<PacketType> {
        PacketType::from_flags(self.flags)
    }

    /// The payload split into its offset (0 without [`FLAG_OFFSET`]) and
    /// the data; `None` if the flag is set but the payload is shorter than
    /// the offset.
    pub fn offset_and_data(&self) -> Option<(u16, &'a [u8])> {
        if self.flags & FLAG_OFFSET == 0 {
            return Some((0, self.payload));
        }
        let (off, data) = self.payload.split_first_chunk::<2>()?;
        Some((u16::from_le_bytes(*off), data))
    }
}

/// Encodes a packet into `out`; returns its length, or `None` if `out` is
/// too small or the packet longer than [`MAX_PACKET`].
pub fn encode(flags: u8, did: u8, payload: &[u8], out: &mut [u8]) -> Option<usize> {
    encode_parts(flags, did, &[], payload, out)
}

/// Encodes a packet whose payload is `prefix` then `data` (e.g. the `u16`
/// offset of a [`FLAG_OFFSET`] payload, then the data) into `out` without
/// assembling the payload first; returns its length, or `None` if `out` is
/// too small or the packet longer than [`MAX_PACKET`].
pub fn encode_parts(
    flags: u8,
    did: u8,
    prefix: &[u8],
    data: &[u8],
    out: &mut [u8],
) -> Option<usize> {
    let len = prefix.len().checked_add(data.len())?;
    let total = len.checked_add(OVERHEAD)?;
    if total > MAX_PACKET {
        return None;
    }
    let out = out.get_mut(..total)?;
    out[..2].copy_from_slice(&PREAMBLE);
    out[2] = flags;
    out[3] = did;
    out[4..6].copy_from_slice(&(len as u16).to_le_bytes());
    out[6..6 + prefix.len()].copy_from_slice(prefix);
    out[6 + prefix.len()..6 + len].copy_from_slice(data);
    let sum = checksum(&out[..6 + len]);
    out[6 + len..].copy_from_slice(&sum);
    Some(total)
}

/// The ISB rules for the shared [`Scanner`].
#[derive(Debug, Clone, Copy)]
pub struct Isb;

impl Framing for Isb {
    const PREAMBLE: [u8; 2] = PREAMBLE;
    const HEADER_LEN: usize = HEADER_LEN;

    #[inline]
    fn total_len(header: &[u8]) -> Option<usize> {
        let size = usize::from(u16::from_le_bytes([header[4], header[5]]));
        let total = size + OVERHEAD;
        (total <= MAX_PACKET).then_some(total)
    }

    #[inline]
    fn check(packet: &[u8]) -> bool {
        let n = packet.len();
        checksum(&packet[..n - 2]) == [packet[n - 2], packet[n - 1]]
    }
}

/// Streaming ISB decoder with a bounded buffer of `CAP` bytes (the largest
/// packet it accepts; [`MAX_PACKET`] for every legal packet). Any chunking
/// gives the same packets; a bad checksum, a bad size or a stray byte is
/// dropped one byte at a time and the scan resumes right after it
/// ([`crate::framing`]), so the next good packet is found.
pub type Decoder<const CAP: usize> = Scanner<Isb, CAP>;

impl<const CAP: usize> Scanner<Isb, CAP> {
    /// Feeds bytes from `input` (advancing it past what was taken) and
    /// returns the next complete, valid packet, if any. Call in a loop until
    /// it returns `None`; then all of `input` has been taken.
    pub fn next_packet<'r, 's: 'r, 'i: 'r>(
        &'s mut self,
        input: &mut &'i [u8],
    ) -> Option<Packet<'r>> {
        let b = self.next_raw(input)?;
        Some(Packet {
            flags: b[2],
            did: b[3],
            payload: &b[HEADER_LEN..b.len() - 2],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_wraps_in_eight_bits() {
        // Stop broadcasts, all ports (the protocol page).
        assert_eq!(checksum(&[0xEF, 0x49, 0x06, 0, 0, 0]), [0x3E, 0x1F]);
        assert_eq!(checksum(&[0xFF; 3]), [0xFD, 0xFA]);
    }

    #[test]
    fn offset_flag_splits_the_payload() {
        let p = Packet {
            flags: 0x25,
            did: 12,
            payload: &[0x0C, 0x00, 2, 0, 0, 0],
        };
        assert_eq!(p.kind(), Some(PacketType::SetData));
        assert_eq!(p.offset_and_data(), Some((12, &[2u8, 0, 0, 0][..])));
        let short = Packet { payload: &[1], ..p };
        assert_eq!(short.offset_and_data(), None);
        assert_eq!(PacketType::from_flags(0x09), None);
    }

    #[test]
    fn encode_refuses_oversized_packets() {
        let mut out = [0u8; MAX_PACKET + 8];
        assert_eq!(
            encode(4, 58, &[0; MAX_PACKET - 8], &mut out),
            Some(MAX_PACKET)
        );
        assert_eq!(encode(4, 58, &[0; MAX_PACKET - 7], &mut out), None);
        assert_eq!(encode(4, 58, &[0; 4], &mut out[..11]), None);
    }
}
