//! Line-rate pacing: a byte credit at the line rate, capped to a burst.
//!
//! The credit grows by `elapsed × rate / 10` bytes (10 bit times per byte,
//! ICD Table 4.3: 1 start, 8 data, no parity, 1 stop) and is kept exactly: it is counted in
//! bit·ns/s (elapsed ns × rate), so no fraction of a byte is lost from one
//! call to the next. A board takes bytes from the device's TX queue only as
//! far as the credit allows, so the device's queue fills — and overflows,
//! dropping whole frames — exactly as a real UART's would. The credit is
//! capped to a small burst ([`MIN_BURST_BYTES`] or [`BURST_NS`] of line
//! time, whichever is larger) so an idle or blocked line does not bank
//! transmission time.
//!
//! Everything is `u64`: the largest value kept is the burst cap,
//! `2 ms × 2 Mbit/s = 4e12`, and a long gap saturates before it is capped
//! (no `u128`, which costs library calls on a Cortex-M0+).

/// Bit times per byte on the wire: start + 8 data + stop (8N1).
pub const BITS_PER_BYTE: u64 = 10;
/// Smallest burst cap, in bytes.
pub const MIN_BURST_BYTES: u64 = 64;
/// Burst cap as line time: 2 ms.
pub const BURST_NS: u64 = 2_000_000;
const NS_PER_S: u64 = 1_000_000_000;
/// Credit units (bit·ns/s) per byte.
const UNITS_PER_BYTE: u64 = BITS_PER_BYTE * NS_PER_S;

/// Time one byte takes on the wire at `rate` bit/s, in picoseconds
/// (10 bit times; a rate of 0 counts as 1 bit/s).
pub const fn byte_time_ps(rate: u32) -> u64 {
    let rate = if rate == 0 { 1 } else { rate };
    BITS_PER_BYTE * 1_000_000_000_000 / rate as u64
}

/// `n · byte_ps / 1000`: ns on the wire for `n` bytes of `byte_ps` ps each
/// ([`byte_time_ps`]), rounded down. Split at 1000 (exactly: `n·(q·1000 +
/// r)/1000 = n·q + ⌊n·r/1000⌋`) so that, for every rate above
/// 2.3 kbit/s and fewer than 65 536 bytes, only 32-bit divisions by a
/// constant remain (a 64-bit division is a library call on a Cortex-M).
pub fn wire_ns(n: usize, byte_ps: u64) -> u64 {
    match (u32::try_from(n), u32::try_from(byte_ps)) {
        (Ok(n), Ok(ps)) if n < 1 << 16 => {
            u64::from(n) * u64::from(ps / 1000) + u64::from(n * (ps % 1000) / 1000)
        }
        _ => (n as u64).saturating_mul(byte_ps) / 1000,
    }
}

/// Byte credit at a line rate (see the module docs).
#[derive(Debug, Clone)]
pub struct Pacer {
    rate: u32,
    last_ns: u64,
    /// elapsed ns × rate, minus what was spent.
    credit: u64,
    cap: u64,
}

impl Pacer {
    /// A pacer at `rate` bit/s (0 counts as 1) from `now_ns`, without credit.
    pub const fn new(rate: u32, now_ns: u64) -> Self {
        let rate = if rate == 0 { 1 } else { rate };
        Pacer {
            rate,
            last_ns: now_ns,
            credit: 0,
            cap: Self::cap_for(rate),
        }
    }

    const fn cap_for(rate: u32) -> u64 {
        let burst = BURST_NS * rate as u64;
        let min = MIN_BURST_BYTES * UNITS_PER_BYTE;
        if burst > min {
            burst
        } else {
            min
        }
    }

    /// The line rate, bit/s.
    pub const fn rate(&self) -> u32 {
        self.rate
    }

    /// The time the credit was last advanced to, ns.
    pub const fn time(&self) -> u64 {
        self.last_ns
    }

    /// The burst cap in bytes at the current rate.
    pub const fn burst_bytes(&self) -> usize {
        (self.cap / UNITS_PER_BYTE) as usize
    }

    /// Switches to `rate` bit/s at `now_ns` (never before the time already
    /// reached); the credit restarts from zero: everything handed out
    /// before went at the old rate.
    pub fn set_rate(&mut self, rate: u32, now_ns: u64) {
        *self = Pacer::new(rate, self.last_ns.max(now_ns));
    }

    /// Accrues credit for the line time up to `now_ns` (earlier times are
    /// ignored: time never goes back).
    pub fn advance(&mut self, now_ns: u64) {
        if now_ns > self.last_ns {
            let dt = now_ns - self.last_ns;
            let add = dt.saturating_mul(u64::from(self.rate));
            self.credit = self.credit.saturating_add(add).min(self.cap);
            self.last_ns = now_ns;
        }
    }

    /// Whole bytes the line can carry now.
    pub const fn available(&self) -> usize {
        (self.credit / UNITS_PER_BYTE) as usize
    }

    /// Accounts `n` bytes handed to the line (at most [`Self::available`]).
    pub fn consume(&mut self, n: usize) {
        self.credit = self
            .credit
            .saturating_sub((n as u64).saturating_mul(UNITS_PER_BYTE));
    }

    /// The earliest time at which `n` bytes (at most one burst) will be
    /// [`available`](Self::available): [`Self::time`] if they are already.
    pub fn ready_at(&self, n: usize) -> u64 {
        let want = (n.min(self.burst_bytes()) as u64).saturating_mul(UNITS_PER_BYTE);
        let missing = want.saturating_sub(self.credit);
        let rate = u64::from(self.rate);
        self.last_ns.saturating_add(missing.div_ceil(rate))
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
    fn credit_grows_at_a_tenth_of_the_bit_rate_with_a_fractional_remainder() {
        let mut p = Pacer::new(115_200, 0);
        p.advance(500_000); // one 2 kHz tick: 5.76 bytes
        assert_eq!(p.available(), 5);
        p.consume(5);
        p.advance(1_000_000); // 0.76 + 5.76
        assert_eq!(p.available(), 6);
    }

    #[test]
    fn credit_is_capped_to_a_small_burst() {
        let mut p = Pacer::new(115_200, 0);
        p.advance(10_000_000_000);
        assert_eq!(p.available(), 64);
        assert_eq!(p.burst_bytes(), 64);
        let mut p = Pacer::new(2_000_000, 0);
        p.advance(10_000_000_000);
        assert_eq!(p.available(), 400); // 2 ms at 200 kB/s
        assert_eq!(p.burst_bytes(), 400);
        // Hours of idle line saturate before the cap: still one burst.
        p.advance(u64::MAX);
        assert_eq!(p.available(), 400);
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
    fn two_megabaud_is_100_bytes_per_2khz_tick() {
        let mut p = Pacer::new(2_000_000, 0);
        let mut sent = 0;
        for k in 1..=2000u64 {
            p.advance(k * 500_000);
            assert_eq!(p.available(), 100);
            sent += p.available();
            p.consume(p.available());
        }
        assert_eq!(sent, 200_000);
    }

    #[test]
    fn long_run_throughput_matches_odd_rates() {
        // 4 kHz ticks (K201) at 460800: 46080 bytes/s exactly.
        let mut p = Pacer::new(460_800, 0);
        let mut sent = 0;
        for k in 1..=4000u64 {
            p.advance(k * 250_000);
            let n = p.available();
            p.consume(n);
            sent += n;
        }
        assert_eq!(sent, 46_080);
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

    #[test]
    fn credit_is_capped_and_restarts_on_a_rate_switch() {
        let mut p = Pacer::new(115_200, 0);
        p.advance(10_000_000_000);
        assert_eq!(p.available(), 64);
        p.set_rate(4800, 10_000_000_000);
        assert_eq!(p.available(), 0);
        p.advance(10_100_000_000); // 100 ms at 480 B/s
        assert_eq!(p.available(), 48);
        let mut p = Pacer::new(2_000_000, 0);
        p.advance(1_000_000_000);
        assert_eq!(p.available(), 400);
    }

    #[test]
    fn a_rate_switch_never_moves_time_back() {
        let mut p = Pacer::new(115_200, 5_000);
        p.set_rate(9600, 1_000);
        assert_eq!(p.time(), 5_000);
        assert_eq!(p.rate(), 9600);
        assert_eq!(Pacer::new(0, 0).rate(), 1);
    }

    #[test]
    fn ready_at_is_the_first_time_the_bytes_fit() {
        // 115200 bit/s: 86 805.5… ns a byte.
        let mut p = Pacer::new(115_200, 1_000);
        assert_eq!(p.ready_at(0), 1_000);
        let t = p.ready_at(40);
        assert_eq!(t, 1_000 + 3_472_223); // ⌈40 × 1e10 / 115200⌉
        let mut q = p.clone();
        q.advance(t - 1);
        assert_eq!(q.available(), 39);
        p.advance(t);
        assert_eq!(p.available(), 40);
        assert_eq!(p.ready_at(40), t);
        // More than a burst: the burst (the rest needs another wake).
        assert_eq!(Pacer::new(115_200, 0).ready_at(1000), 5_555_556);
    }

    #[test]
    fn wire_time_is_exact_for_every_split() {
        for rate in [4800u32, 9600, 115_200, 460_800, 921_600, 2_000_000] {
            let ps = byte_time_ps(rate);
            assert_eq!(ps, 10_000_000_000_000 / u64::from(rate));
            for n in [0usize, 1, 40, 174, 65_535, 65_536, 1 << 20] {
                // n·(q·1000 + r)/1000 = n·q + ⌊n·r/1000⌋: the split is exact.
                let exact = (n as u128 * u128::from(ps) / 1000) as u64;
                assert_eq!(wire_ns(n, ps), exact, "{rate} bit/s, {n} bytes");
            }
        }
        // 40 bytes at 115200: 3.472 ms.
        assert_eq!(wire_ns(40, byte_time_ps(115_200)), 3_472_222);
        assert_eq!(byte_time_ps(0), 10_000_000_000_000);
    }
}
