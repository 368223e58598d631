//! Output-rate rules (ICD 5.5): rates are divisors of the internal rate, and
//! Formula 5.1 caps them by the line rate.

/// Bits per transferred byte in Formula 5.1 (the device's budget; on the
/// wire a byte occupies 10 bit times: start, 8 data, stop).
pub const FORMULA_BITS_PER_BYTE: u32 = 11;

/// Formula 5.1: the highest output rate, a divisor of `internal_hz`, with
/// `rate × 11 × (payload_len + 8) ≤ baud`. Never below 1 Hz (the minimum
/// Data_Rate): a frame too large even for 1 Hz still goes out at 1 Hz.
pub fn max_rate(baud: u32, payload_len: usize, internal_hz: u32) -> u32 {
    let bits_per_frame = u64::from(FORMULA_BITS_PER_BYTE) * (payload_len as u64 + 8);
    let limit = u64::from(baud) / bits_per_frame.max(1);
    (1..=internal_hz)
        .filter(|k| internal_hz.is_multiple_of(*k))
        .map(|k| internal_hz / k)
        .find(|&r| u64::from(r) <= limit)
        .unwrap_or(1)
}

/// The rate a stream actually runs at: the configured Data_Rate, lowered to
/// [`max_rate`] when it does not fit the line (5.2.8, Table 5.21 bit 3).
pub fn effective_rate(data_rate: u32, baud: u32, payload_len: usize, internal_hz: u32) -> u32 {
    // max/min rather than `clamp`, whose min > max panic would bring
    // `u32`'s `Debug` formatting into the firmware (0.4 KiB); the same
    // value for every internal rate ≥ 1.
    data_rate
        .max(1)
        .min(internal_hz)
        .min(max_rate(baud, payload_len, internal_hz))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every cell of Table 5.28.
    #[test]
    fn table_5_28() {
        let bauds = [38_400, 115_200, 460_800, 2_000_000];
        let rows: [(usize, [u32; 4]); 7] = [
            (34, [80, 200, 500, 2000]),  // Orientation, package 42
            (32, [80, 250, 1000, 2000]), // GA, 40
            (32, [80, 250, 1000, 2000]), // GAm, 40
            (34, [80, 200, 500, 2000]),  // Quaternion, 42
            (52, [50, 125, 500, 2000]),  // Calibrated HR, 60
            (44, [50, 200, 500, 2000]),  // GAA, 52
            (44, [50, 200, 500, 2000]),  // GAAm, 52
        ];
        for (payload, expect) in rows {
            for (baud, want) in bauds.iter().zip(expect) {
                assert_eq!(
                    max_rate(*baud, payload, 2000),
                    want,
                    "payload {payload} @ {baud}"
                );
            }
        }
    }

    #[test]
    fn k201_uses_divisors_of_4000_and_slow_lines_floor_at_1_hz() {
        assert_eq!(max_rate(4_000_000, 32, 4000), 4000);
        assert_eq!(max_rate(2_000_000, 32, 4000), 4000);
        assert_eq!(max_rate(4_800, 32, 2000), 10);
        assert_eq!(max_rate(4_800, 1000, 2000), 1);
        assert_eq!(effective_rate(2000, 115_200, 32, 2000), 250);
        assert_eq!(effective_rate(100, 115_200, 32, 2000), 100);
    }
}
