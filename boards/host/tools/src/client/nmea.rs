//! `imu-emu client --protocol isb record --nmea GNGGA,GNRMC …`: an IMX-5's
//! NMEA sentences recorded as an NMEA log (`docs/isb.md` "NMEA"). The
//! sentences are enabled with one `$ASCE` (the names or numbers given, each
//! every `--period` source periods), every whole sentence with a valid
//! checksum is written as received (`$…*CS` CR LF, whatever its ID: the
//! unit's other NMEA streams too), ISB packets and noise between them are
//! skipped, and `$STPC` stops the port's streams at the end.

use std::io::Write;
use std::time::{Duration, Instant};

use anyhow::bail;
use imu_emu::isb::nmea::checksum;

use super::isb::IsbLink;

/// Longest sentence kept (the IMX-5's receive limit is 200 bytes; its
/// output buffer 256).
const MAX_SENTENCE: usize = 256;

/// Cuts whole NMEA sentences out of a byte stream: `$`, printable bytes,
/// `*`, two hex digits matching the XOR of the body, CR LF. Anything else
/// (ISB packets, noise, a sentence with a bad checksum) is skipped.
#[derive(Debug, Default)]
pub struct SentenceReader {
    buf: Vec<u8>,
    /// Sentences dropped for a bad checksum or form.
    pub bad: u64,
}

impl SentenceReader {
    /// The next whole sentence in `input` (consumed up to it; every byte of
    /// `input` is taken when none completes, its partial sentence kept).
    pub fn next(&mut self, input: &mut &[u8]) -> Option<Vec<u8>> {
        while let Some((&b, rest)) = input.split_first() {
            *input = rest;
            if b == b'$' {
                if !self.buf.is_empty() {
                    self.bad += 1;
                }
                self.buf.clear();
                self.buf.push(b);
                continue;
            }
            if self.buf.is_empty() {
                continue;
            }
            self.buf.push(b);
            if b == b'\n' {
                let s = std::mem::take(&mut self.buf);
                if valid(&s) {
                    return Some(s);
                }
                self.bad += 1;
            } else if self.buf.len() > MAX_SENTENCE || !(b == b'\r' || (0x20..0x7F).contains(&b)) {
                self.buf.clear();
                self.bad += 1;
            }
        }
        None
    }
}

/// Whether `s` is `$body*HH\r\n` with the right checksum.
pub fn valid(s: &[u8]) -> bool {
    let n = s.len();
    n >= 6
        && s[0] == b'$'
        && s.ends_with(b"\r\n")
        && s[n - 5] == b'*'
        && std::str::from_utf8(&s[n - 4..n - 2])
            .ok()
            .and_then(|h| u8::from_str_radix(h, 16).ok())
            == Some(checksum(&s[1..n - 5]))
}

/// The `$ASCE` sentence enabling `names` (comma-separated names or
/// numbers) every `period` source periods on this port.
pub fn asce(names: &str, period: u8) -> Vec<u8> {
    let mut body = String::from("ASCE,0");
    for n in names.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        body.push_str(&format!(",{n},{period}"));
    }
    format!("${body}*{:02X}\r\n", checksum(body.as_bytes())).into_bytes()
}

/// Records the sentences `names` (every `period` source periods) to `w`
/// until `frames` sentences or `duration` seconds (of the recording),
/// or `stop`; then stops the port's streams. How many were written.
pub fn record(
    link: &mut IsbLink,
    w: &mut dyn Write,
    names: &str,
    period: u8,
    frames: Option<u64>,
    duration: Option<f64>,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<u64> {
    link.line.write(&asce(names, period))?;
    let mut rx = SentenceReader::default();
    let (t0, mut quiet) = (Instant::now(), Instant::now());
    let mut n = 0u64;
    let r = loop {
        if frames.is_some_and(|f| n >= f)
            || duration.is_some_and(|d| t0.elapsed().as_secs_f64() >= d)
            || stop()
        {
            break Ok(n);
        }
        match link
            .line
            .next_before(Instant::now() + Duration::from_millis(100), |i| rx.next(i))
        {
            Ok(Some(s)) => {
                quiet = Instant::now();
                w.write_all(&s)?;
                n += 1;
            }
            Ok(None) if quiet.elapsed() > link.line.timeout => {
                break Err(anyhow::anyhow!(
                    "{}: no NMEA sentence within {:?} after {n}",
                    link.line.what,
                    link.line.timeout
                ))
            }
            Ok(None) => {}
            Err(e) => break Err(e),
        }
    };
    link.line.write(b"$STPC*14\r\n")?;
    let n = r?;
    if n == 0 && frames != Some(0) {
        bail!("{}: no NMEA sentence", link.line.what);
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sentences_are_cut_out_of_isb_and_noise() {
        let mut r = SentenceReader::default();
        let mut stream = vec![0xEF, 0x49, b'$', 0x04];
        stream.extend(b"$GNZDA,152744.000,13,03,2026,00,00*4E\r\nxx$BAD*00\r\n");
        stream.extend(b"$ASCE,0*08\r\n");
        let mut input = &stream[..];
        assert_eq!(
            r.next(&mut input).unwrap(),
            b"$GNZDA,152744.000,13,03,2026,00,00*4E\r\n"
        );
        assert_eq!(r.next(&mut input).unwrap(), b"$ASCE,0*08\r\n");
        assert!(r.next(&mut input).is_none());
        assert_eq!(r.bad, 2);
        assert_eq!(asce("GNGGA, 10", 5), b"$ASCE,0,GNGGA,5,10,5*41\r\n");
    }
}
