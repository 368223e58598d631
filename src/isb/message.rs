//! The ISB message layer over [`packet`]s: what a received packet asks for
//! ([`Request`]), the rules that decide the answer (GET_DATA windows and
//! NACKs, SET_DATA trimming, read-only bytes), and the encoders of the
//! answers (ACK / NACK, DATA) into a caller's buffer. Pure: the device keeps
//! the data set images and the streams; these functions only read and
//! write the bytes they are handed. Facts from `docs/protocol-facts.md`
//! "ISB" and "what the vendor's command-line tool needs"; decisions are marked as such.

use super::did::{self, Class, DataSet};
use super::packet::{self, Packet, PacketType, FLAG_OFFSET};

/// GET_DATA payload length: `u16 did, u16 size, u16 offset, u16 period`.
pub(crate) const GET_PAYLOAD_LEN: usize = 8;
/// ACK / NACK payload length: `u8 rx_flags, u8 rx_did, u16 pkt_counter,
/// u8 id, u16 size, u16 offset`.
pub(crate) const ACK_PAYLOAD_LEN: usize = 9;
/// A SET_DATA leaving fewer bytes than this between its offset and the end
/// of the struct is dropped without an ACK (the SDK's rule, protocol-facts.md).
pub const MIN_SET_ROOM: u16 = 4;
/// Largest DATA payload a client accepts (protocol-facts.md: data payloads over
/// 1024 bytes are dropped).
pub const MAX_DATA_PAYLOAD: usize = 1024;

/// A GET_DATA request (header DID 0; the DID is in the payload).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GetRequest {
    /// Requested DID (a `u16`: values ≥ 132 are NACKed).
    pub did: u16,
    /// Bytes requested (0 with offset 0: the whole struct).
    pub size: u16,
    /// First byte requested.
    pub offset: u16,
    /// 0: one packet and that stream off; n > 0: one packet now and then
    /// every n source periods ([`did::Source`]).
    pub period: u16,
}

impl GetRequest {
    /// Parses a GET_DATA payload; `None` unless it is exactly
    /// [`GET_PAYLOAD_LEN`] bytes (decision: any other length is a bad GET,
    /// answered with a NACK by [`Request::Get`]'s caller).
    pub fn parse(payload: &[u8]) -> Option<Self> {
        let p: &[u8; GET_PAYLOAD_LEN] = payload.try_into().ok()?;
        let w = |i: usize| u16::from_le_bytes([p[i], p[i + 1]]);
        Some(GetRequest {
            did: w(0),
            size: w(2),
            offset: w(4),
            period: w(6),
        })
    }

    /// The payload bytes (what a host sends).
    pub fn encode(&self) -> [u8; GET_PAYLOAD_LEN] {
        let mut b = [0u8; GET_PAYLOAD_LEN];
        b[0..2].copy_from_slice(&self.did.to_le_bytes());
        b[2..4].copy_from_slice(&self.size.to_le_bytes());
        b[4..6].copy_from_slice(&self.offset.to_le_bytes());
        b[6..8].copy_from_slice(&self.period.to_le_bytes());
        b
    }
}

/// Encodes a GET_DATA packet of `req` (flags [`PacketType::GetData`],
/// header DID 0, the DID in the payload; `docs/protocol-facts.md` "ISB")
/// into `out`, what a host sends; its length, or `None` if `out` is shorter
/// than 16 bytes.
pub fn encode_get(req: &GetRequest, out: &mut [u8]) -> Option<usize> {
    packet::encode(PacketType::GetData as u8, 0, &req.encode(), out)
}

/// Encodes a SET_DATA packet writing `data` at `offset` of data set `did`
/// (flags [`PacketType::SetData`] with [`FLAG_OFFSET`], payload the `u16`
/// offset then the data; `docs/protocol-facts.md` "ISB") into `out`, what a
/// host sends; its length, or `None` if `out` is too small or the packet
/// longer than [`packet::MAX_PACKET`].
pub fn encode_set(did: u8, offset: u16, data: &[u8], out: &mut [u8]) -> Option<usize> {
    packet::encode_parts(
        PacketType::SetData as u8 | FLAG_OFFSET,
        did,
        &offset.to_le_bytes(),
        data,
        out,
    )
}

/// The part `(offset, size)` of a `struct_size`-byte set a GET of `size`
/// bytes at `offset` gets (protocol-facts.md "ISB"): size 0 and offset 0 → the whole
/// struct; a request running past the struct → the whole struct. Decision:
/// size 0 with an offset inside the struct → from the offset to the end;
/// with an offset at or past the end → the whole struct.
pub const fn window(struct_size: u16, size: u16, offset: u16) -> (u16, u16) {
    let whole = (0, struct_size);
    if offset >= struct_size {
        return whole;
    }
    if size == 0 {
        return (offset, struct_size - offset);
    }
    if size > struct_size - offset {
        return whole;
    }
    (offset, size)
}

/// What to do about a GET_DATA.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GetReply {
    /// NACK ([`did::is_nacked`], or a malformed GET payload).
    Nack,
    /// An in-range DID the device does not serve: no reply (protocol-facts.md).
    Silent,
    /// Send this part of the set now; then stream it if `period > 0`, stop
    /// its stream if `period == 0`.
    Serve {
        /// The data set.
        set: &'static DataSet,
        /// First byte ([`window`]).
        offset: u16,
        /// Bytes ([`window`]).
        size: u16,
        /// Period multiple (0: once, and that stream off).
        period: u16,
    },
}

/// The rule for a GET_DATA ([`GetReply`]).
pub fn resolve_get(req: &GetRequest) -> GetReply {
    match did::classify(req.did) {
        Class::Nack => GetReply::Nack,
        Class::Unsupported => GetReply::Silent,
        Class::Supported(set) => {
            let (offset, size) = window(set.size, req.size, req.offset);
            GetReply::Serve {
                set,
                offset,
                size,
                period: req.period,
            }
        }
    }
}

/// The fields of an ACK / NACK payload (protocol-facts.md "ISB"): the received
/// packet's flags and DID, then for a SET_DATA the DID, size (without the
/// two offset bytes) and offset it wrote; zeros otherwise. The packet
/// counter is always 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AckInfo {
    /// `flags` byte of the packet acknowledged (0x20 included when it had
    /// an offset).
    pub rx_flags: u8,
    /// Header DID of the packet acknowledged (0 for a GET_DATA).
    pub rx_did: u8,
    /// The DID written (SET_DATA only).
    pub id: u8,
    /// Bytes written (SET_DATA only).
    pub size: u16,
    /// Offset written at (SET_DATA only).
    pub offset: u16,
}

impl AckInfo {
    /// The ACK of a packet that wrote nothing (stop commands, a bad GET).
    pub const fn of(rx_flags: u8, rx_did: u8) -> Self {
        AckInfo {
            rx_flags,
            rx_did,
            id: 0,
            size: 0,
            offset: 0,
        }
    }

    /// The payload bytes.
    pub(crate) fn encode(&self) -> [u8; ACK_PAYLOAD_LEN] {
        let mut b = [0u8; ACK_PAYLOAD_LEN];
        b[0] = self.rx_flags;
        b[1] = self.rx_did;
        // b[2..4]: packet counter, always 0.
        b[4] = self.id;
        b[5..7].copy_from_slice(&self.size.to_le_bytes());
        b[7..9].copy_from_slice(&self.offset.to_le_bytes());
        b
    }
}

/// Encodes an ACK (header DID 0) into `out`; its length, or `None` if `out`
/// is shorter than 17 bytes.
pub fn encode_ack(info: &AckInfo, out: &mut [u8]) -> Option<usize> {
    packet::encode(PacketType::Ack as u8, 0, &info.encode(), out)
}

/// Encodes a NACK (header DID 0) into `out`; its length, or `None` if `out`
/// is shorter than 17 bytes.
pub fn encode_nack(info: &AckInfo, out: &mut [u8]) -> Option<usize> {
    packet::encode(PacketType::Nack as u8, 0, &info.encode(), out)
}

/// A SET_DATA request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SetRequest<'a> {
    /// The received `flags` (echoed in the ACK).
    pub flags: u8,
    /// Header DID.
    pub did: u8,
    /// Offset into the set (0 without [`FLAG_OFFSET`]).
    pub offset: u16,
    /// The bytes to write.
    pub data: &'a [u8],
}

impl<'a> SetRequest<'a> {
    /// The SET_DATA (or host DATA, which the release applies alike:
    /// `docs/isb-nmea.md` §7) in `p`; `None` if `p` is neither or its
    /// offset flag is set on a payload shorter than the offset (decision:
    /// dropped without a reply, as the SDK drops a malformed packet).
    pub(crate) fn parse(p: &Packet<'a>) -> Option<Self> {
        if !matches!(p.kind(), Some(PacketType::SetData | PacketType::Data)) {
            return None;
        }
        let (offset, data) = p.offset_and_data()?;
        Some(SetRequest {
            flags: p.flags,
            did: p.did,
            offset,
            data,
        })
    }
}

/// What became of a SET_DATA ([`apply_set`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SetOutcome {
    /// DID ≥ 132 or 95: answer with a NACK of this payload.
    Nack(AckInfo),
    /// No reply: empty data, or under [`MIN_SET_ROOM`] bytes of room.
    Silent,
    /// An in-range DID the device does not serve: ACKed as the SDK does
    /// (protocol-facts.md: ACK when DID < 132 and the payload is non-empty), nothing
    /// written.
    AckOnly(AckInfo),
    /// Written: `image[offset..offset + len]` changed (possibly to the same
    /// values); answer with an ACK of this payload.
    Written {
        /// The ACK payload.
        ack: AckInfo,
        /// First byte written.
        offset: u16,
        /// Bytes written (the data trimmed to the struct).
        len: u16,
    },
    /// Refused, nothing written: it would change a read-only byte
    /// (decision: answered with a NACK of this payload, so a host waiting
    /// for the ACK learns at once).
    Refused(AckInfo),
}

/// Applies a SET_DATA to `image`, the current bytes of its data set (the
/// [`DataSet::size`] bytes of the set; ignored for DIDs not served).
///
/// Rules (protocol-facts.md "ISB" and "what the vendor's command-line tool needs"):
/// DID ≥ 132 or 95 → NACK; empty data → no reply; an offset leaving under
/// [`MIN_SET_ROOM`] bytes before the end → no reply (the SDK drops it); the
/// data is trimmed to the struct. Decision: a read-only byte
/// ([`DataSet::is_writable`]) may be carried only with its current value —
/// so a host writing back a whole struct it read is accepted — and a write
/// that would change one is refused as a whole. An `image` shorter than
/// the set counts as that short.
pub fn apply_set(req: &SetRequest<'_>, image: &mut [u8]) -> SetOutcome {
    let did = u16::from(req.did);
    let base = AckInfo::of(req.flags, req.did);
    let set = match did::classify(did) {
        Class::Nack => return SetOutcome::Nack(base),
        _ if req.data.is_empty() => return SetOutcome::Silent,
        Class::Unsupported => {
            return SetOutcome::AckOnly(AckInfo {
                id: req.did,
                size: req.data.len().min(usize::from(u16::MAX)) as u16,
                offset: req.offset,
                ..base
            })
        }
        Class::Supported(set) => set,
    };
    let size = set.size.min(image.len().min(usize::from(u16::MAX)) as u16);
    let room = size.saturating_sub(req.offset);
    if room < MIN_SET_ROOM {
        return SetOutcome::Silent;
    }
    let len = room.min(req.data.len().min(usize::from(u16::MAX)) as u16);
    let ack = AckInfo {
        id: req.did,
        size: len,
        offset: req.offset,
        ..base
    };
    let start = usize::from(req.offset);
    let end = start + usize::from(len);
    let (Some(dst), Some(src)) = (image.get_mut(start..end), req.data.get(..usize::from(len)))
    else {
        return SetOutcome::Silent;
    };
    let changes_read_only = dst
        .iter()
        .zip(src)
        .zip(req.offset..)
        .any(|((d, s), i)| d != s && !set.is_writable(i));
    if changes_read_only {
        return SetOutcome::Refused(ack);
    }
    dst.copy_from_slice(src);
    SetOutcome::Written {
        ack,
        offset: req.offset,
        len,
    }
}

/// Encodes a DATA packet of `image[offset..offset + size]` for `did` into
/// `out`. The whole set (offset 0, all of `image`) goes without the offset
/// flag — the vendor tool takes DEV_INFO only that way (protocol-facts.md) — a part
/// with [`FLAG_OFFSET`] and the `u16` offset first. `None` if the window is
/// not inside `image`, the payload is over [`MAX_DATA_PAYLOAD`], or `out`
/// is too small.
pub fn encode_data(did: u8, image: &[u8], offset: u16, size: u16, out: &mut [u8]) -> Option<usize> {
    let start = usize::from(offset);
    let end = start + usize::from(size);
    let part = image.get(start..end)?;
    let kind = PacketType::Data as u8;
    if start == 0 && end == image.len() {
        if part.len() > MAX_DATA_PAYLOAD {
            return None;
        }
        packet::encode(kind, did, part, out)
    } else {
        if part.len() + 2 > MAX_DATA_PAYLOAD {
            return None;
        }
        packet::encode_parts(kind | FLAG_OFFSET, did, &offset.to_le_bytes(), part, out)
    }
}

/// What a received packet asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request<'a> {
    /// GET_DATA with a well-formed payload ([`resolve_get`]).
    Get(GetRequest),
    /// GET_DATA whose payload is not 8 bytes: answer with a NACK of
    /// [`AckInfo::of`] its flags and DID (decision).
    BadGet {
        /// Its `flags`.
        rx_flags: u8,
        /// Its header DID.
        rx_did: u8,
    },
    /// SET_DATA ([`apply_set`]).
    Set(SetRequest<'a>),
    /// DATA from the host: applied as SET_DATA, neither ACKed nor NACKed
    /// (the release's `com_manager.cpp` ACKs only SET_DATA).
    Data(SetRequest<'a>),
    /// STOP_BROADCASTS_ALL_PORTS: stop every stream, ACK
    /// ([`AckInfo::of`] with flags 6).
    StopAllPorts,
    /// STOP_BROADCASTS_CURRENT_PORT: stop this port's streams, ACK (flags
    /// 8).
    StopCurrentPort,
    /// STOP_DID_BROADCAST of the header DID: stop that stream, no ACK.
    StopDid(u8),
    /// Anything else (ACK, NACK, unknown type, a SET or DATA with a
    /// truncated offset): ignored.
    Ignored,
}

impl<'a> Request<'a> {
    /// Classifies a decoded packet.
    pub fn of(p: &Packet<'a>) -> Self {
        match p.kind() {
            Some(PacketType::GetData) => match GetRequest::parse(p.payload) {
                Some(g) => Request::Get(g),
                None => Request::BadGet {
                    rx_flags: p.flags,
                    rx_did: p.did,
                },
            },
            Some(PacketType::SetData) => match SetRequest::parse(p) {
                Some(s) => Request::Set(s),
                None => Request::Ignored,
            },
            Some(PacketType::Data) => match SetRequest::parse(p) {
                Some(s) => Request::Data(s),
                None => Request::Ignored,
            },
            Some(PacketType::StopBroadcastsAllPorts) => Request::StopAllPorts,
            Some(PacketType::StopBroadcastsCurrentPort) => Request::StopCurrentPort,
            Some(PacketType::StopDidBroadcast) => Request::StopDid(p.did),
            _ => Request::Ignored,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The golden vector named `meaning` in `tests/data/vectors.txt`, into
    /// `buf`; its length.
    fn vector(meaning: &str, buf: &mut [u8]) -> usize {
        let text = include_str!("../../tests/data/vectors.txt");
        let line = text
            .lines()
            .find(|l| l.split('|').next().map(str::trim) == Some(meaning))
            .expect("vector in tests/data/vectors.txt");
        let hex = line.rsplit('|').next().unwrap_or("");
        let mut n = 0;
        for h in hex.split_whitespace() {
            buf[n] = u8::from_str_radix(h, 16).expect("hex byte");
            n += 1;
        }
        n
    }

    #[test]
    fn get_and_set_encode_to_the_sdk_bytes() {
        let mut want = [0u8; 64];
        let mut out = [0u8; 64];
        for (meaning, req) in [
            (
                "SDK: GET DEV_INFO once",
                GetRequest {
                    did: u16::from(did::DEV_INFO),
                    size: 0,
                    offset: 0,
                    period: 0,
                },
            ),
            (
                "SDK: GET IMU period 1",
                GetRequest {
                    did: u16::from(did::IMU),
                    size: 0,
                    offset: 0,
                    period: 1,
                },
            ),
        ] {
            let w = vector(meaning, &mut want);
            assert_eq!(encode_get(&req, &mut out), Some(w), "{meaning}");
            assert_eq!(out[..w], want[..w], "{meaning}");
        }
        let w = vector(
            "SDK: SET FLASH_CONFIG startupImuDtMs=2 (offset 12)",
            &mut want,
        );
        assert_eq!(
            encode_set(did::FLASH_CONFIG, 12, &[2, 0, 0, 0], &mut out),
            Some(w)
        );
        assert_eq!(out[..w], want[..w]);
        // Too small a buffer: no packet, no panic.
        assert_eq!(
            encode_get(
                &GetRequest {
                    did: 1,
                    size: 0,
                    offset: 0,
                    period: 0
                },
                &mut out[..15]
            ),
            None
        );
        assert_eq!(
            encode_set(did::FLASH_CONFIG, 12, &[2, 0, 0, 0], &mut out[..13]),
            None
        );
    }

    #[test]
    fn windows() {
        assert_eq!(window(84, 0, 0), (0, 84));
        assert_eq!(window(84, 4, 4), (4, 4));
        assert_eq!(window(84, 4, 80), (80, 4));
        assert_eq!(window(84, 5, 80), (0, 84));
        assert_eq!(window(84, 0, 80), (80, 4));
        assert_eq!(window(84, 0, 84), (0, 84));
        assert_eq!(window(84, 0xFFFF, 0xFFFF), (0, 84));
    }

    #[test]
    fn set_trims_and_drops() {
        let set = did::lookup(u16::from(did::FLASH_CONFIG)).unwrap();
        let mut img = [0u8; 288];
        img[0] = 0x20;
        img[1] = 0x01;
        let w = |offset, data| SetRequest {
            flags: 0x25,
            did: set.did,
            offset,
            data,
        };
        // Runs past the end: trimmed to 4 bytes.
        let out = apply_set(&w(284, &[1, 2, 3, 4, 5, 6]), &mut img);
        assert!(matches!(
            out,
            SetOutcome::Written {
                offset: 284,
                len: 4,
                ..
            }
        ));
        assert_eq!(&img[284..], &[1, 2, 3, 4]);
        // Three bytes of room: dropped.
        assert_eq!(apply_set(&w(285, &[9]), &mut img), SetOutcome::Silent);
        assert_eq!(apply_set(&w(4000, &[9; 8]), &mut img), SetOutcome::Silent);
        // `size` is read-only: same value accepted, a change refused.
        assert!(matches!(
            apply_set(&w(0, &[0x20, 0x01, 0, 0, 7]), &mut img),
            SetOutcome::Written { len: 5, .. }
        ));
        assert_eq!(img[4], 7);
        assert!(matches!(
            apply_set(&w(0, &[0x21]), &mut img),
            SetOutcome::Refused(_)
        ));
        assert_eq!(img[0], 0x20);
    }
}
