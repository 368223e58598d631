//! What the targets share: the script reader over the fuzzer input and
//! the chunking invariance of the packet scanners.

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::Device;
use imu_emu::framing;
use imu_emu::personality::Personality;

/// Reads the fuzzer input as a script: bytes and little numbers, 0 when
/// the input is used up.
pub struct Cursor<'a> {
    data: &'a [u8],
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Cursor { data }
    }

    /// Whether every byte has been read.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The next byte (0 past the end).
    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    /// The next little-endian u16.
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    /// The next little-endian u32.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// Up to `n` next bytes.
    pub fn bytes(&mut self, n: usize) -> &'a [u8] {
        let (head, rest) = self.data.split_at(n.min(self.data.len()));
        self.data = rest;
        head
    }
}

/// Chunk lengths 0..=16 from a xorshift seeded by `seed`.
pub(crate) struct Chunks(pub(crate) u32);

impl Chunks {
    pub(crate) fn next(&mut self) -> usize {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x % 17) as usize
    }
}

/// Every packet a scanner finds in `input` fed in the chunks `chunk`
/// gives (0-length chunks included), as raw bytes.
pub(crate) fn scan_all<F: framing::Framing, const CAP: usize>(
    input: &[u8],
    mut chunk: impl FnMut() -> usize,
) -> Vec<Vec<u8>> {
    let mut s = framing::Scanner::<F, CAP>::new();
    let mut out = Vec::new();
    let mut rest = input;
    loop {
        let n = chunk().min(rest.len());
        let (mut piece, tail) = rest.split_at(n);
        while let Some(raw) = s.next_raw(&mut piece) {
            out.push(raw.to_vec());
        }
        assert!(piece.is_empty(), "the scanner takes every byte it is given");
        rest = tail;
        if rest.is_empty() {
            break;
        }
    }
    out
}

/// The same packets whatever the chunking: one shot, byte by byte, and
/// pseudo-random chunks (seeded by the input's first four bytes).
pub(crate) fn chunking_invariant<F: framing::Framing, const CAP: usize>(
    data: &[u8],
) -> Vec<Vec<u8>> {
    let mut c = Cursor::new(data);
    let seed = c.u32() | 1;
    let input = c.bytes(data.len());
    let one = scan_all::<F, CAP>(input, || usize::MAX);
    let bytewise = scan_all::<F, CAP>(input, || 1);
    assert_eq!(one, bytewise, "byte-by-byte chunking changed the packets");
    let mut chunks = Chunks(seed);
    let random = scan_all::<F, CAP>(input, || chunks.next());
    assert_eq!(one, random, "chunking changed the packets");
    one
}

/// Moves up to `max` TX bytes out of `dev` (taking line-rate events as
/// they come), handing each chunk to `sink`.
pub(crate) fn drain_tx<F: NorFlash, P: Personality>(
    dev: &mut Device<F, P>,
    max: usize,
    mut sink: impl FnMut(&[u8]),
) {
    let mut buf = [0u8; 1024];
    let mut left = max;
    while left > 0 {
        while dev.poll_event().is_some() {}
        let n = dev.poll_tx(&mut buf[..left.min(1024)]);
        if n == 0 {
            break;
        }
        left -= n;
        sink(&buf[..n]);
    }
}
