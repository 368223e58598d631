//! Line-rate pacing of the emulated UART.
//!
//! One byte occupies 10 bit times on the wire (start, 8 data bits, stop).
//! The pacer keeps a byte credit that grows with elapsed time × rate / 10;
//! the runner takes bytes from the device's TX queue only as far as the
//! credit allows, so the device's own queue fills (and overflows, dropping
//! frames) exactly as on a real UART. The credit is capped to a small burst
//! (64 bytes or 2 ms of line time, whichever is larger) so an idle line does
//! not bank transmission time.

/// Bit times per byte on the wire: start + 8 data + stop.
pub const BITS_PER_BYTE: u64 = 10;
/// Smallest burst cap, in bytes.
pub const MIN_BURST_BYTES: u64 = 64;
/// Burst cap as line time, in nanoseconds (2 ms).
pub const BURST_NS: u64 = 2_000_000;

const NS_PER_S: u128 = 1_000_000_000;
/// Credit units per byte: credit is kept in bit·ns/s (elapsed ns × rate).
const UNITS_PER_BYTE: u128 = BITS_PER_BYTE as u128 * NS_PER_S;

/// Byte-credit accumulator at a line rate.
#[derive(Debug, Clone)]
pub struct Pacer {
    rate: u32,
    last_ns: u64,
    /// Credit in units of bit·(1e-9 s)·(bit/s) = elapsed_ns × rate.
    credit: u128,
    cap: u128,
}

impl Pacer {
    /// A pacer at `rate` bit/s starting at `now_ns` with no credit.
    pub fn new(rate: u32, now_ns: u64) -> Self {
        let mut p = Pacer {
            rate: 1,
            last_ns: now_ns,
            credit: 0,
            cap: 0,
        };
        p.set_rate(rate, now_ns);
        p
    }

    /// The current line rate in bit/s.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// The burst cap in bytes at the current rate.
    pub fn burst_bytes(&self) -> usize {
        (self.cap / UNITS_PER_BYTE) as usize
    }

    /// Switches to `rate` bit/s at `now_ns`; the credit restarts from zero
    /// (everything handed out before was sent at the old rate).
    pub fn set_rate(&mut self, rate: u32, now_ns: u64) {
        self.rate = rate.max(1);
        self.last_ns = self.last_ns.max(now_ns);
        self.credit = 0;
        let burst_time = u128::from(BURST_NS) * u128::from(self.rate);
        let burst_min = u128::from(MIN_BURST_BYTES) * UNITS_PER_BYTE;
        self.cap = burst_time.max(burst_min);
    }

    /// Accrues credit for the line time up to `now_ns` (earlier times are
    /// ignored: time never goes back).
    pub fn advance(&mut self, now_ns: u64) {
        if now_ns > self.last_ns {
            let dt = u128::from(now_ns - self.last_ns);
            self.credit = (self.credit + dt * u128::from(self.rate)).min(self.cap);
            self.last_ns = now_ns;
        }
    }

    /// Whole bytes the line can carry now.
    pub fn available(&self) -> usize {
        (self.credit / UNITS_PER_BYTE) as usize
    }

    /// Accounts `n` bytes handed to the line (at most [`Self::available`]).
    pub fn consume(&mut self, n: usize) {
        self.credit = self.credit.saturating_sub(n as u128 * UNITS_PER_BYTE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn credit_grows_at_a_tenth_of_the_bit_rate() {
        let mut p = Pacer::new(115_200, 0);
        assert_eq!(p.available(), 0);
        p.advance(1_000_000); // 1 ms → 11.52 bytes
        assert_eq!(p.available(), 11);
        p.consume(11);
        p.advance(2_000_000); // remainder carries: 0.52 + 11.52
        assert_eq!(p.available(), 12);
    }

    #[test]
    fn credit_is_capped_to_a_small_burst() {
        let mut p = Pacer::new(115_200, 0);
        p.advance(10_000_000_000);
        assert_eq!(p.available(), 64);
        let mut p = Pacer::new(2_000_000, 0);
        p.advance(10_000_000_000);
        assert_eq!(p.available(), 400); // 2 ms at 200 kB/s
    }

    #[test]
    fn long_run_throughput_matches_the_line_rate() {
        // Drain every 0.5 ms for 10 s at 4800 bit/s: 480 bytes/s.
        let mut p = Pacer::new(4800, 0);
        let mut sent = 0;
        for k in 1..=20_000u64 {
            p.advance(k * 500_000);
            let n = p.available();
            p.consume(n);
            sent += n;
        }
        assert!((4799..=4800).contains(&sent), "{sent}");
    }

    #[test]
    fn a_rate_switch_restarts_the_credit() {
        let mut p = Pacer::new(115_200, 0);
        p.advance(1_000_000);
        p.set_rate(4800, 1_000_000);
        assert_eq!(p.available(), 0);
        p.advance(1_000_000 + 100_000_000); // 100 ms at 480 B/s → 48 bytes
        assert_eq!(p.available(), 48);
    }
}
