//! Target `feed`: the live motion feed decoder (text rows and binary
//! samples) and the per-device track.

use crate::script::{Chunks, Cursor};

/// The live motion feed's outcomes for `input` fed in the chunks `chunk`
/// gives, and the decoder's counts.
fn feed_all(
    input: &[u8],
    mut chunk: impl FnMut() -> usize,
) -> (
    Vec<Result<imu_emu::feed::Sample, imu_emu::feed::Reject>>,
    imu_emu::feed::Counts,
) {
    let mut d = imu_emu::feed::Decoder::new();
    let mut out = Vec::new();
    let mut rest = input;
    while !rest.is_empty() {
        let n = chunk().min(rest.len());
        d.decode(&rest[..n], &mut |r| out.push(r));
        rest = &rest[n..];
    }
    (out, *d.counts())
}

/// Live motion feed decoder (`imu_emu::feed`, docs/feed.md): the same
/// samples and rejections one shot, byte by byte and in pseudo-random
/// chunks; the counts match them; every sample is in range (full-state
/// rows too) and a rate sample's binary
/// encoding decodes to itself; a [`imu_emu::feed::Track`] and a
/// [`imu_emu::feed::Live`] take them, in and out of order, without panic,
/// and interpolate within the two samples' values.
pub fn feed(data: &[u8]) {
    use imu_emu::feed::{encode, Live, Sample, Track, MAX_FRAME};
    let mut c = Cursor::new(data);
    let seed = c.u32() | 1;
    let input = c.bytes(data.len());
    let (one, counts) = feed_all(input, || usize::MAX);
    assert_eq!(feed_all(input, || 1).0, one, "byte-by-byte chunking");
    let mut chunks = Chunks(seed);
    assert_eq!(feed_all(input, || chunks.next().max(1)).0, one, "chunking");
    assert_eq!(
        counts.samples as usize,
        one.iter().filter(|r| r.is_ok()).count()
    );
    assert_eq!(
        counts.rejected_total() as usize,
        one.iter().filter(|r| r.is_err()).count()
    );
    let mut track = Track::new();
    let mut live = Live::new(1_000_000);
    for (k, s) in one.iter().flatten().enumerate() {
        if let Sample::FullState(f) = s {
            // The vehicle module's ranges and the feed's time limit.
            let r = &f.row;
            assert!(r.lat_deg.abs() <= 89.9 && r.time_s <= 1.8e9, "{r:?}");
            assert_eq!(f.time_ns, (r.time_s * 1e9).round() as u64);
        }
        let Sample::Rates(r) = s else { continue };
        let t = &r.truth;
        assert!(t.rate_dps.iter().all(|v| v.abs() <= 8192.0));
        assert!(t.specific_force_g.iter().all(|v| v.abs() <= 128.0));
        let mut f = [0u8; MAX_FRAME];
        let n = encode(r, &mut f);
        let (again, _) = feed_all(&f[..n], || usize::MAX);
        assert_eq!(again, [Ok(*s)], "re-encode");
        let before = track.last();
        if track.accept(r.time_ns, r.truth).is_ok() {
            if let Some((t0, a)) = before {
                let mid = t0 + (r.time_ns - t0) / 2;
                let m = track.at(mid).expect("a sample");
                for i in 0..3 {
                    let (lo, hi) = (
                        a.rate_dps[i].min(t.rate_dps[i]),
                        a.rate_dps[i].max(t.rate_dps[i]),
                    );
                    assert!((lo..=hi).contains(&m.rate_dps[i]), "interpolation");
                }
            }
        }
        let _ = live.offer(r.time_ns, r.truth, k as u64 * 500_000);
        let _ = live.at(k as u64 * 500_000);
    }
}
