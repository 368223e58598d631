//! Line-rate pacing of the UART transmitter.
//!
//! A byte takes 10 bit times on the wire (start, 8 data, stop). The pacer
//! keeps a byte credit that grows by `elapsed × rate / 10`, kept exactly
//! with a fractional remainder (credit is counted in bit·ns, so no rounding
//! is lost from tick to tick), and capped to a small burst so an idle or
//! blocked line does not bank transmission time.
//!
//! Why pace at all on an MCU whose UART paces itself? QEMU's UART transmits
//! instantly, and on real boards the device's own TX queue must hold what a
//! real KERNEL's would (frames dropped when the line is too slow, TOV's
//! falling edge at the frame's last bit): the bytes leave the core at the
//! line rate, the UART FIFO/DMA only smooths the edges.

/// Bit times per byte on the wire: start + 8 data + stop.
pub const BITS_PER_BYTE: u64 = 10;
/// Smallest burst cap in bytes.
pub const MIN_BURST_BYTES: u64 = 64;
/// Burst cap as line time: 2 ms.
pub const BURST_NS: u64 = 2_000_000;
const NS_PER_S: u64 = 1_000_000_000;
/// Credit units (bit·ns/s) per byte.
const UNITS_PER_BYTE: u64 = BITS_PER_BYTE * NS_PER_S;

/// Byte credit at a line rate.
#[derive(Debug, Clone)]
pub struct Pacer {
    rate: u32,
    last_ns: u64,
    /// elapsed ns × rate, minus what was spent.
    credit: u64,
    cap: u64,
}

impl Pacer {
    /// A pacer at `rate` bit/s from `now_ns`, without credit.
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

    /// Line rate, bit/s.
    pub const fn rate(&self) -> u32 {
        self.rate
    }

    /// Switches to `rate` at `now_ns`; the credit restarts from zero.
    pub fn set_rate(&mut self, rate: u32, now_ns: u64) {
        *self = Pacer::new(rate, self.last_ns.max(now_ns));
    }

    /// Accrues credit up to `now_ns` (earlier times are ignored).
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

    /// Accounts `n` bytes handed to the UART.
    pub fn consume(&mut self, n: usize) {
        self.credit = self
            .credit
            .saturating_sub((n as u64).saturating_mul(UNITS_PER_BYTE));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
