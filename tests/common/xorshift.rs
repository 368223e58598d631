//! The tests' deterministic xorshift32 (Marsaglia's 13/17/5 triple), so a
//! seeded loop that fails names its round and replays. Shared by the core
//! suites (through `tests/common/mod.rs`) and the host power-kill test
//! (by path).

/// Deterministic xorshift32 (seed must be non-zero).
pub struct XorShift(pub u32);

impl XorShift {
    /// The next 32-bit value.
    pub fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    /// A value below `n` (`next() % n`).
    pub fn below(&mut self, n: u32) -> u32 {
        self.next() % n
    }

    /// Fills `bytes`, one `next()` (its low byte) a byte.
    pub fn fill(&mut self, bytes: &mut [u8]) {
        for b in bytes {
            *b = self.next() as u8;
        }
    }

    /// `N` bytes as [`fill`](Self::fill) gives them.
    pub fn bytes<const N: usize>(&mut self) -> [u8; N] {
        let mut b = [0; N];
        self.fill(&mut b);
        b
    }
}
