//! Decimal numbers in text (the live feed's rows, the full-state rows of
//! the vehicle module) without `str::parse::<f64>`, whose tables cost a
//! firmware image 15 KiB of flash.

/// Exact powers of ten in `f64` (10²² is the last one).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// A decimal number (`-12.5`, `3e-4`, `.5`, `+7`): at most 19 significant
/// digits are kept (the rest only scale), then `digits × 10^exp` —
/// correctly rounded while both fit the exact `f64` range (≤ 2⁵³,
/// |exp| ≤ 22), within a few ulps beyond (module docs: why not
/// `str::parse::<f64>`). `None` for anything else (`inf`, `NaN`, a header
/// word).
pub(crate) fn parse(s: &str) -> Option<f64> {
    let b = s.as_bytes();
    let (neg, mut i) = match b.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let (mut m, mut exp, mut digits, mut kept) = (0u64, 0i32, 0u32, 0u32);
    let mut dot = false;
    while let Some(&c) = b.get(i) {
        match c {
            b'0'..=b'9' => {
                digits += 1;
                if kept < 19 {
                    if m > 0 || c != b'0' {
                        kept += 1;
                    }
                    m = m * 10 + u64::from(c - b'0');
                    exp -= i32::from(dot);
                } else {
                    exp += i32::from(!dot);
                }
            }
            b'.' if !dot => dot = true,
            _ => break,
        }
        i += 1;
    }
    if digits == 0 {
        return None;
    }
    if let Some(b'e' | b'E') = b.get(i) {
        i += 1;
        let (eneg, start) = match b.get(i) {
            Some(b'-') => (true, i + 1),
            Some(b'+') => (false, i + 1),
            _ => (false, i),
        };
        i = start;
        let mut e = 0i32;
        while let Some(&c @ b'0'..=b'9') = b.get(i) {
            e = (e * 10 + i32::from(c - b'0')).min(10_000);
            i += 1;
        }
        if i == start {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if i != b.len() {
        return None;
    }
    let mut v = m as f64;
    let mut e = exp;
    while e > 0 && v != 0.0 && v.is_finite() {
        let k = e.min(22);
        v *= POW10[k as usize];
        e -= k;
    }
    while e < 0 && v != 0.0 {
        let k = (-e).min(22);
        v /= POW10[k as usize];
        e += k;
    }
    Some(if neg { -v } else { v })
}
