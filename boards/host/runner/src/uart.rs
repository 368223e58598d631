//! What a UART receiving at the wrong rate reads: bytes sent back to back
//! at one rate, sampled by a receiver at another (8N1: a start bit, eight
//! data bits LSB first, a stop bit; the line idles high).
//!
//! The receiver waits for a falling edge, checks the start bit half a bit
//! time later, samples the eight data bits and the stop bit at the centres
//! of its own bit times and, when the stop bit reads low (a framing error),
//! delivers `0x00` — what a Linux tty in raw mode hands the reader for a
//! framing error (no `IGNPAR`, no `PARMRK`). At equal rates every sample
//! falls in the middle of the bit sent, so the bytes pass unchanged.
//!
//! Used by the pty transport when the client's termios speed differs from
//! the device's line rate ([`crate::transport::PtyTransport`]).

/// The bytes a receiver at `read_bps` reads from `bytes` sent back to back
/// at `sent_bps` (idle line before and after).
pub fn resample(bytes: &[u8], sent_bps: u32, read_bps: u32) -> Vec<u8> {
    if sent_bps == read_bps || sent_bps == 0 || read_bps == 0 {
        return bytes.to_vec();
    }
    let nbits = bytes.len() * 10;
    // Level of sent bit `i` (idle high outside the burst).
    let bit = |i: usize| -> bool {
        if i >= nbits {
            return true;
        }
        match i % 10 {
            0 => false,
            9 => true,
            k => bytes[i / 10] >> (k - 1) & 1 == 1,
        }
    };
    let (s, r) = (f64::from(sent_bps), f64::from(read_bps));
    // Level at time `t` (seconds from the first start bit).
    let level = |t: f64| -> bool {
        if t < 0.0 {
            return true;
        }
        bit((t * s) as usize)
    };
    let mut out = Vec::new();
    let mut i = 0usize; // first sent bit index to look for an edge from
    while i < nbits {
        // Next high → low transition at or after bit i.
        let Some(edge) = (i..nbits).find(|&j| !bit(j) && (j == 0 || bit(j - 1))) else {
            break;
        };
        let t0 = edge as f64 / s;
        let at = |k: f64| t0 + (k + 0.5) / r;
        if level(at(0.0)) {
            // A glitch, not a start bit.
            i = edge + 1;
            continue;
        }
        let mut b = 0u8;
        for k in 0..8 {
            if level(at(f64::from(k) + 1.0)) {
                b |= 1 << k;
            }
        }
        let stop = level(at(9.0));
        out.push(if stop { b } else { 0 });
        // Look for the next edge after the stop bit's sample.
        i = ((at(9.0) * s) as usize + 1).max(edge + 1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_rates_pass_everything() {
        let b: Vec<u8> = (0..=255).collect();
        assert_eq!(resample(&b, 115_200, 115_200), b);
    }

    #[test]
    fn a_slightly_different_rate_still_reads() {
        // 2 % off: within what a UART tolerates for one byte at a time.
        let b = [0x55u8, 0xAA, 0x12];
        let mut spaced = Vec::new();
        for &x in &b {
            spaced.extend(resample(&[x], 115_200, 117_500));
        }
        assert_eq!(spaced, b);
    }

    #[test]
    fn the_wrong_rate_garbles_with_framing_errors() {
        // Device at 115200, reader at 9600: a reader bit spans 12 sent
        // bits: a frame's worth of bytes comes out as a few wrong ones.
        let frame = [0xAA, 0x55, 0x01, 0x8F, 0x26, 0x00, 0x10, 0x20];
        let slow = resample(&frame, 115_200, 9600);
        assert!(slow.len() < frame.len(), "{slow:02X?}");
        assert_ne!(slow, frame[..slow.len()]);
        // The other way: a reader 12× faster sees every sent bit as 12 of
        // its own: a start bit then zeros and ones in long runs.
        let fast = resample(&frame[..2], 9600, 115_200);
        assert_ne!(fast, frame[..2]);
        assert!(fast.contains(&0x00), "{fast:02X?}");
        // Deterministic.
        assert_eq!(resample(&frame, 115_200, 9600), slow);
    }
}
