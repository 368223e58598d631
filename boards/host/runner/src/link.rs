//! Link-level faults between the device's UART and the transport: what a
//! bad cable, a noisy RS-422 pair or a stalled USB adapter does to the
//! bytes (control socket `link …`, see [`crate::control`]).
//!
//! The host board puts a [`Link`] on both directions of the line: `tx` is
//! device → client, `rx` is client → device. Each direction can
//!
//! * **drop**, **corrupt** (XOR with a random non-zero byte) or
//!   **duplicate** each byte with a probability;
//! * take a **noise** burst of random bytes now;
//!
//! and the output (`tx`) can also be
//!
//! * **stalled** for T ms of device time: the bytes the line carries meanwhile
//!   are held (up to [`MAX_HELD`] bytes, the rest dropped and counted) and
//!   released at once when the stall ends — a stalled adapter;
//! * **cut** mid-frame: the rest of the frame being sent is lost (between
//!   frames: the next frame after its header — 6 bytes for KERNEL). Frames
//!   are followed with the core's [`Framing`] rules ([`Wire`]), so another
//!   personality's packets work the same way.
//!
//! Every random draw comes from the core's [`Rng`] seeded from `--seed`
//! (one stream per direction), so a seed and a sequence of commands replay
//! the same faults on the same bytes.

use std::collections::VecDeque;

use imu_emu::framing::Framing;
use imu_emu::sensor::Rng;

/// Most bytes a stall holds back; beyond it output is dropped (counted in
/// [`LinkStats::stall_dropped`]). 1 s of line at 921 600 bit/s.
pub const MAX_HELD: usize = 96 * 1024;

/// Longest noise burst accepted by `link noise`, bytes.
pub const MAX_NOISE: usize = 64 * 1024;

/// Which way a fault acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dir {
    /// Device → client.
    Tx,
    /// Client → device.
    Rx,
    /// Both.
    Both,
}

impl Dir {
    fn tx(self) -> bool {
        matches!(self, Dir::Tx | Dir::Both)
    }
    fn rx(self) -> bool {
        matches!(self, Dir::Rx | Dir::Both)
    }
}

/// A change to the link faults (control socket `link …`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinkChange {
    /// `link drop <rate> [tx|rx]`: each byte lost with this probability.
    Drop(f64, Dir),
    /// `link corrupt <rate> [tx|rx]`: each byte XORed with a random
    /// non-zero value with this probability.
    Corrupt(f64, Dir),
    /// `link duplicate <rate> [tx|rx]`: each byte sent twice with this
    /// probability.
    Duplicate(f64, Dir),
    /// `link noise <bytes> [tx|rx]`: a burst of random bytes now.
    Noise(usize, Dir),
    /// `link stall <ms>`: the output held for this long (device time).
    Stall(u64),
    /// `link cut`: the rest of the output frame being sent is lost.
    Cut,
    /// `link clear`: no faults (a stall ends now, its bytes go out).
    Clear,
}

/// Per-byte fault probabilities of one direction, as 32-bit thresholds
/// (`p × 2³²`: a byte is hit when a draw is below it; `p = 1` hits all).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Rates {
    drop: u64,
    corrupt: u64,
    duplicate: u64,
}

impl Rates {
    fn any(&self) -> bool {
        self.drop | self.corrupt | self.duplicate != 0
    }
}

fn threshold(p: f64) -> u64 {
    (p.clamp(0.0, 1.0) * 4_294_967_296.0).round() as u64
}

fn hit(rng: &mut Rng, t: u64) -> bool {
    t != 0 && u64::from(rng.next_u32()) < t
}

/// What the link did so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Bytes dropped (`drop`), tx + rx.
    pub dropped: u64,
    /// Bytes corrupted, tx + rx.
    pub corrupted: u64,
    /// Bytes duplicated, tx + rx.
    pub duplicated: u64,
    /// Noise bytes injected, tx + rx.
    pub noise: u64,
    /// Output bytes lost to `link cut`.
    pub cut: u64,
    /// Output bytes a stall could not hold ([`MAX_HELD`]).
    pub stall_dropped: u64,
}

/// The wire protocol's packet rules the output follower needs, from the
/// core's [`Framing`] (KERNEL frames, ISB packets).
#[derive(Debug, Clone, Copy)]
pub struct Wire {
    preamble: [u8; 2],
    header_len: usize,
    total_len: fn(&[u8]) -> Option<usize>,
    /// Offset of the identifier byte shown by `status` (`format=`).
    id_at: usize,
}

impl Wire {
    /// The rules of framing `K`; `id_at` is the offset of the byte
    /// `status` reports as the format (KERNEL: 3, the frame's ID).
    pub fn of<K: Framing>(id_at: usize) -> Self {
        Wire {
            preamble: K::PREAMBLE,
            header_len: K::HEADER_LEN.min(HDR_MAX),
            total_len: K::total_len,
            id_at,
        }
    }

    /// The total length of a packet starting with `hdr` (its first
    /// `header_len` bytes), if it is one (longer than its header).
    fn total(&self, hdr: &[u8]) -> Option<usize> {
        (self.total_len)(&hdr[..self.header_len]).filter(|&t| t > self.header_len)
    }
}

/// Longest header followed.
const HDR_MAX: usize = 16;

/// Where the output stream is with respect to the device's packets (it
/// sends whole ones; this follows them byte by byte).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct FramePos {
    /// Bytes of the current packet seen (0 = between packets).
    at: usize,
    /// Its total length once its header was seen.
    total: Option<usize>,
    hdr: [u8; HDR_MAX],
}

impl FramePos {
    /// Follows one byte; whether it ended a packet.
    fn step(&mut self, b: u8, w: &Wire) -> bool {
        match self.at {
            0 => {
                if b == w.preamble[0] {
                    self.hdr[0] = b;
                    self.at = 1;
                }
                return false;
            }
            1 => {
                if b == w.preamble[1] {
                    self.hdr[1] = b;
                    self.at = 2;
                } else {
                    self.at = usize::from(b == w.preamble[0]);
                }
                return false;
            }
            at if at < w.header_len => {
                self.hdr[at] = b;
                if at + 1 == w.header_len {
                    match w.total(&self.hdr) {
                        Some(t) => self.total = Some(t),
                        None => {
                            *self = FramePos::default();
                            return false;
                        }
                    }
                }
            }
            _ => {}
        }
        self.at += 1;
        if self.total == Some(self.at) {
            *self = FramePos::default();
            return true;
        }
        false
    }

    fn in_frame(&self) -> bool {
        self.at >= 2
    }
}

/// The faults on both directions of the line, and their state.
#[derive(Debug, Clone)]
pub struct Link {
    tx_rng: Rng,
    rx_rng: Rng,
    tx: Rates,
    rx: Rates,
    /// The output's packet rules.
    wire: Wire,
    /// The output frame being sent (for `cut` and the frame counts).
    pos: FramePos,
    /// `link cut` is waiting for a frame to cut.
    cut_armed: bool,
    /// Cutting: output dropped up to the end of the current frame.
    cutting: bool,
    /// The stall ends at this device time, ns.
    stall_until: Option<u64>,
    held: VecDeque<u8>,
    /// Noise waiting to go to the device (taken by [`Link::rx_noise`]).
    rx_noise: Vec<u8>,
    stats: LinkStats,
    /// Frames the device sent (complete, before any fault).
    frames_sent: u64,
    /// ID of the last frame the device sent.
    last_id: Option<u8>,
}

impl Link {
    /// A clean link for output framed by `wire` (the protocol's,
    /// `HostProtocol::wire`) whose random draws derive from `seed`
    /// (`--seed`).
    pub fn with_wire(seed: u64, wire: Wire) -> Self {
        Link {
            wire,
            tx_rng: Rng::new(seed ^ 0x6C69_6E6B_2D74_7800),
            rx_rng: Rng::new(seed ^ 0x6C69_6E6B_2D72_7800),
            tx: Rates::default(),
            rx: Rates::default(),
            pos: FramePos::default(),
            cut_armed: false,
            cutting: false,
            stall_until: None,
            held: VecDeque::new(),
            rx_noise: Vec::new(),
            stats: LinkStats::default(),
            frames_sent: 0,
            last_id: None,
        }
    }

    /// Applies a change at device time `now` (ns). Noise on `tx` is
    /// written to `out` (it goes to the client at once, or into the stall's
    /// hold); noise on `rx` goes to the device with the next [`Link::rx`].
    pub fn apply(&mut self, change: LinkChange, now: u64, out: &mut Vec<u8>) {
        let set = |r: &mut Rates, dir: Dir, is_tx: bool, f: &dyn Fn(&mut Rates)| {
            if (is_tx && dir.tx()) || (!is_tx && dir.rx()) {
                f(r);
            }
        };
        match change {
            LinkChange::Drop(p, d) => {
                let t = threshold(p);
                set(&mut self.tx, d, true, &|r| r.drop = t);
                set(&mut self.rx, d, false, &|r| r.drop = t);
            }
            LinkChange::Corrupt(p, d) => {
                let t = threshold(p);
                set(&mut self.tx, d, true, &|r| r.corrupt = t);
                set(&mut self.rx, d, false, &|r| r.corrupt = t);
            }
            LinkChange::Duplicate(p, d) => {
                let t = threshold(p);
                set(&mut self.tx, d, true, &|r| r.duplicate = t);
                set(&mut self.rx, d, false, &|r| r.duplicate = t);
            }
            LinkChange::Noise(n, d) => {
                if d.tx() {
                    let noise = self.noise(n, true);
                    self.stats.noise += n as u64;
                    self.hold_or_pass(&noise, now, out);
                }
                if d.rx() {
                    let noise = self.noise(n, false);
                    self.stats.noise += n as u64;
                    self.rx_noise.extend_from_slice(&noise);
                }
            }
            LinkChange::Stall(ms) => {
                let until = now.saturating_add(ms.saturating_mul(1_000_000));
                self.stall_until = Some(self.stall_until.map_or(until, |u| u.max(until)));
            }
            LinkChange::Cut => {
                if self.pos.in_frame() {
                    self.cutting = true;
                } else {
                    self.cut_armed = true;
                }
            }
            LinkChange::Clear => {
                self.tx = Rates::default();
                self.rx = Rates::default();
                self.cut_armed = false;
                self.cutting = false;
                self.stall_until = None;
                out.extend(self.held.drain(..));
            }
        }
    }

    fn noise(&mut self, n: usize, tx: bool) -> Vec<u8> {
        let rng = if tx {
            &mut self.tx_rng
        } else {
            &mut self.rx_rng
        };
        (0..n).map(|_| rng.next_u32() as u8).collect()
    }

    /// Whether the output is stalled at device time `now`.
    pub fn stalled(&self, now: u64) -> bool {
        self.stall_until.is_some_and(|u| now < u)
    }

    /// When the current stall ends, device time ns.
    pub fn stall_until(&self) -> Option<u64> {
        self.stall_until
    }

    /// Output bytes held by a stall.
    pub fn held(&self) -> usize {
        self.held.len()
    }

    fn hold_or_pass(&mut self, bytes: &[u8], now: u64, out: &mut Vec<u8>) {
        if self.stalled(now) {
            let room = MAX_HELD - self.held.len();
            let k = bytes.len().min(room);
            self.held.extend(&bytes[..k]);
            self.stats.stall_dropped += (bytes.len() - k) as u64;
        } else {
            out.extend_from_slice(bytes);
        }
    }

    /// Releases what a stall held once it is over (device time `now`),
    /// into `out`.
    pub fn release(&mut self, now: u64, out: &mut Vec<u8>) {
        if self.stall_until.is_some() && !self.stalled(now) {
            self.stall_until = None;
            out.extend(self.held.drain(..));
        }
    }

    /// Passes device output `bytes` (what the line carried at device time
    /// `now`) through the faults; appends what reaches the client to `out`.
    pub fn tx(&mut self, bytes: &[u8], now: u64, out: &mut Vec<u8>) {
        self.release(now, out);
        if self.clean() {
            self.pass(bytes);
            out.extend_from_slice(bytes);
            return;
        }
        let mut passed = Vec::with_capacity(bytes.len());
        for &b in bytes {
            let was_in_frame = self.pos.in_frame();
            if self.pos.at == self.wire.id_at {
                self.last_id = Some(b);
            }
            let ended = self.pos.step(b, &self.wire);
            if ended {
                self.frames_sent += 1;
            }
            // Cut: after the header of the next frame, or now.
            if self.cut_armed && self.pos.at == self.wire.header_len {
                self.cut_armed = false;
                self.cutting = true;
                passed.push(b);
                continue;
            }
            if self.cutting {
                if was_in_frame || self.pos.in_frame() {
                    self.stats.cut += 1;
                    if ended || !self.pos.in_frame() {
                        self.cutting = false;
                    }
                    continue;
                }
                self.cutting = false;
            }
            passed.push(b);
        }
        let faulted = if self.tx.any() {
            let rates = self.tx;
            let mut v = Vec::with_capacity(passed.len());
            Self::fault(&mut self.tx_rng, rates, &mut self.stats, &passed, &mut v);
            v
        } else {
            passed
        };
        self.hold_or_pass(&faulted, now, out);
    }

    /// Whether output passes as it is now: no fault, cut or stall, nothing
    /// held back. [`Link::tx`] then appends its bytes unchanged, and
    /// [`Link::pass`] does the rest of its work without that copy.
    pub fn clean(&self) -> bool {
        !self.tx.any() && !self.cut_armed && !self.cutting && self.stall_until.is_none()
    }

    /// [`Link::tx`] of output while the link is [`Link::clean`], but the
    /// bytes are not copied: they reach the client as they are. Follows
    /// the frame boundaries (frame count, last ID), skipping over their
    /// bodies.
    pub fn pass(&mut self, mut bytes: &[u8]) {
        while let Some((&b, rest)) = bytes.split_first() {
            // A whole header at a frame boundary: take it at once.
            let w = self.wire;
            if self.pos.at == 0 && bytes.len() >= w.header_len && bytes[..2] == w.preamble {
                if let Some(total) = w.total(bytes) {
                    if let Some(&id) = bytes.get(w.id_at) {
                        self.last_id = Some(id);
                    }
                    if let Some(after) = bytes.get(total..) {
                        // The whole frame is here: counted at once.
                        self.frames_sent += 1;
                        bytes = after;
                        continue;
                    }
                    self.pos = FramePos {
                        at: w.header_len,
                        total: Some(total),
                        hdr: [0; HDR_MAX],
                    };
                    bytes = &bytes[w.header_len..];
                    continue;
                }
            }
            // Inside a frame's body: jump to its last byte.
            if let Some(total) = self.pos.total {
                let skip = (total - 1 - self.pos.at).min(bytes.len());
                if skip > 0 {
                    self.pos.at += skip;
                    bytes = &bytes[skip..];
                    continue;
                }
            }
            if self.pos.at == self.wire.id_at {
                self.last_id = Some(b);
            }
            if self.pos.step(b, &self.wire) {
                self.frames_sent += 1;
            }
            bytes = rest;
        }
    }

    /// Passes client input `bytes` through the faults (noise queued by
    /// `link noise … rx` first); appends what reaches the device to `out`.
    pub fn rx(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        out.append(&mut self.rx_noise);
        if self.rx.any() {
            let rates = self.rx;
            Self::fault(&mut self.rx_rng, rates, &mut self.stats, bytes, out);
        } else {
            out.extend_from_slice(bytes);
        }
    }

    /// Noise queued for the device (`link noise N rx`) not yet delivered.
    pub fn rx_noise_pending(&self) -> bool {
        !self.rx_noise.is_empty()
    }

    fn fault(rng: &mut Rng, r: Rates, s: &mut LinkStats, bytes: &[u8], out: &mut Vec<u8>) {
        for &b in bytes {
            if hit(rng, r.drop) {
                s.dropped += 1;
                continue;
            }
            let mut b = b;
            if hit(rng, r.corrupt) {
                b ^= (rng.next_u32() % 255 + 1) as u8;
                s.corrupted += 1;
            }
            out.push(b);
            if hit(rng, r.duplicate) {
                out.push(b);
                s.duplicated += 1;
            }
        }
    }

    /// What the link did so far.
    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Complete frames the device sent (before any fault).
    pub fn frames_sent(&self) -> u64 {
        self.frames_sent
    }

    /// ID (format code) of the last frame the device sent.
    pub fn last_id(&self) -> Option<u8> {
        self.last_id
    }

    /// The faults in force, as `link …` words (`clean` when none).
    pub fn describe(&self, now: u64) -> String {
        let mut parts = Vec::new();
        for (name, r) in [("tx", self.tx), ("rx", self.rx)] {
            for (what, t) in [
                ("drop", r.drop),
                ("corrupt", r.corrupt),
                ("duplicate", r.duplicate),
            ] {
                if t != 0 {
                    parts.push(format!("{what}-{name}={}", t as f64 / 4_294_967_296.0));
                }
            }
        }
        if let Some(u) = self.stall_until.filter(|_| self.stalled(now)) {
            parts.push(format!("stall={}ms", (u - now).div_ceil(1_000_000)));
        }
        if self.cut_armed || self.cutting {
            parts.push("cut".to_owned());
        }
        if parts.is_empty() {
            "clean".to_owned()
        } else {
            parts.join(",")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    impl Link {
        /// A clean link for KERNEL output.
        fn new(seed: u64) -> Self {
            Self::with_wire(seed, Wire::of::<imu_emu::kernel::frame::Kernel>(3))
        }
    }

    fn frame(id: u8, payload: &[u8]) -> Vec<u8> {
        let mut f = vec![0u8; payload.len() + 8];
        let n = imu_emu::kernel::frame::encode(1, id, payload, &mut f).unwrap();
        f.truncate(n);
        f
    }

    #[test]
    fn a_clean_link_passes_everything_and_counts_frames() {
        let mut l = Link::new(1);
        let mut out = Vec::new();
        let mut stream = frame(0x33, &[1, 2, 3]);
        stream.extend(frame(0x52, &[0xAA, 0x55, 0xAA]));
        // Any chunking.
        for chunk in stream.chunks(3) {
            l.tx(chunk, 0, &mut out);
        }
        assert_eq!(out, stream);
        assert_eq!(l.frames_sent(), 2);
        assert_eq!(l.last_id(), Some(0x52));
        let mut rx = Vec::new();
        l.rx(b"abc", &mut rx);
        assert_eq!(rx, b"abc");
    }

    #[test]
    fn rate_one_hits_every_byte_and_clear_undoes_it() {
        let mut l = Link::new(7);
        let f = frame(0x33, &[9; 10]);
        let mut out = Vec::new();
        l.apply(LinkChange::Corrupt(1.0, Dir::Tx), 0, &mut out);
        l.tx(&f, 0, &mut out);
        assert_eq!(out.len(), f.len());
        assert!(out.iter().zip(&f).all(|(a, b)| a != b));
        assert_eq!(l.stats().corrupted, f.len() as u64);
        // rx untouched.
        let mut rx = Vec::new();
        l.rx(&f, &mut rx);
        assert_eq!(rx, f);
        l.apply(LinkChange::Clear, 0, &mut out);
        out.clear();
        l.tx(&f, 0, &mut out);
        assert_eq!(out, f);

        l.apply(LinkChange::Drop(1.0, Dir::Both), 0, &mut out);
        out.clear();
        l.tx(&f, 0, &mut out);
        l.rx(&f, &mut out);
        assert!(out.is_empty());
        l.apply(LinkChange::Clear, 0, &mut out);
        l.apply(LinkChange::Duplicate(1.0, Dir::Rx), 0, &mut out);
        l.rx(b"ab", &mut out);
        assert_eq!(out, b"aabb");
    }

    #[test]
    fn the_same_seed_replays_the_same_faults() {
        let f: Vec<u8> = (0..=255).collect();
        let run = |seed| {
            let mut l = Link::new(seed);
            let mut out = Vec::new();
            l.apply(LinkChange::Corrupt(0.1, Dir::Tx), 0, &mut out);
            l.apply(LinkChange::Drop(0.1, Dir::Tx), 0, &mut out);
            l.apply(LinkChange::Noise(5, Dir::Tx), 0, &mut out);
            l.tx(&f, 0, &mut out);
            out
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3), run(4));
        // About 10 % each of 256 bytes.
        let out = run(3);
        assert!((200..=250).contains(&out.len()), "{}", out.len());
    }

    #[test]
    fn a_stall_holds_the_output_and_releases_it_in_order() {
        let mut l = Link::new(0);
        let mut out = Vec::new();
        l.apply(LinkChange::Stall(200), 1_000, &mut out);
        l.tx(b"abc", 100_000_000, &mut out);
        assert!(out.is_empty());
        assert_eq!(l.held(), 3);
        l.tx(b"de", 200_000_999, &mut out);
        assert!(out.is_empty());
        l.tx(b"f", 200_001_000, &mut out);
        assert_eq!(out, b"abcdef");
        assert!(!l.stalled(200_001_000));
    }

    #[test]
    fn a_cut_loses_the_rest_of_the_frame_being_sent() {
        let a = frame(0x33, &[1; 20]);
        let b = frame(0x33, &[2; 20]);
        let mut l = Link::new(0);
        let mut out = Vec::new();
        // Mid-frame: the rest of `a` is lost, `b` passes.
        l.tx(&a[..10], 0, &mut out);
        l.apply(LinkChange::Cut, 0, &mut out);
        l.tx(&a[10..], 0, &mut out);
        l.tx(&b, 0, &mut out);
        let mut want = a[..10].to_vec();
        want.extend(&b);
        assert_eq!(out, want);
        assert_eq!(l.stats().cut, (a.len() - 10) as u64);
        // Between frames: the next frame keeps its 6 header bytes only.
        out.clear();
        l.apply(LinkChange::Cut, 0, &mut out);
        l.tx(&a, 0, &mut out);
        l.tx(&b, 0, &mut out);
        let mut want = a[..6].to_vec();
        want.extend(&b);
        assert_eq!(out, want);
        assert_eq!(l.frames_sent(), 4);
    }

    #[test]
    fn another_protocols_packets_are_followed_and_cut_the_same_way() {
        use imu_emu::isb::packet;
        let isb = |did: u8, p: &[u8]| {
            let mut f = vec![0u8; p.len() + packet::OVERHEAD];
            let n = packet::encode(0, did, p, &mut f).unwrap();
            f.truncate(n);
            f
        };
        let (a, b) = (isb(3, &[1; 24]), isb(3, &[2; 24]));
        let mut l = Link::with_wire(0, Wire::of::<packet::Isb>(3));
        let mut out = Vec::new();
        l.tx(&a, 0, &mut out);
        l.apply(LinkChange::Cut, 0, &mut out);
        l.tx(&a[..10], 0, &mut out);
        l.tx(&a[10..], 0, &mut out);
        l.tx(&b, 0, &mut out);
        let mut want = a.clone();
        want.extend(&a[..packet::HEADER_LEN]);
        want.extend(&b);
        assert_eq!(out, want);
        assert_eq!(l.frames_sent(), 3);
    }
}
