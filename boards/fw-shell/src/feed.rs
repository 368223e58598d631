//! The live motion feed on a board's second UART (docs/feed.md): the
//! binary samples a HIL rig sends (text rows are decoded too), fed to the
//! core's [`Decoder`] and applied in real time by the core's [`Live`] —
//! the same code the host runner's `--motion-feed` runs.
//!
//! The board's feed RX interrupt pushes bytes into an SPSC queue
//! ([`ByteSource`]); its tick calls [`crate::Shell::feed`] before
//! [`crate::Shell::service`]: the samples that arrived apply from that
//! service's ticks and hold; after [`FEED_TIMEOUT_NS`] of silence the
//! device reports a sensor fault (KERNEL USW bit 1, IMX IMU status),
//! cleared by the next sample. A firmware image is one device: samples
//! naming device 0 or [`OWN_DEVICE`] are its own, others are rejected.

use imu_emu::feed::{Counts, Decoder, Live, Reject, Sample, OWN_DEVICE};

/// Silence after which the feed is lost, ns (100 ms).
pub const FEED_TIMEOUT_NS: u64 = 100_000_000;
/// Most feed bytes one service takes (2.5 binary samples; at 2 kHz,
/// 256 kB/s, beyond any UART's rate).
pub const MAX_FEED_BYTES: usize = 128;

/// Where the feed's received bytes come from.
pub trait ByteSource {
    /// The oldest byte not taken yet.
    fn pop(&mut self) -> Option<u8>;
}

/// The consumer end of an SPSC queue filled by the feed UART's ISR.
impl ByteSource for heapless::spsc::Consumer<'_, u8> {
    fn pop(&mut self) -> Option<u8> {
        self.dequeue()
    }
}

/// The feed's state: decoder, samples, counters.
#[derive(Debug, Clone)]
pub struct FeedIn {
    decoder: Decoder,
    live: Live,
    counts: Counts,
}

impl Default for FeedIn {
    fn default() -> Self {
        Self::new(FEED_TIMEOUT_NS)
    }
}

impl FeedIn {
    /// No sample yet; the fault after `timeout_ns` of silence.
    pub const fn new(timeout_ns: u64) -> Self {
        FeedIn {
            decoder: Decoder::new(),
            live: Live::new(timeout_ns),
            counts: Counts {
                samples: 0,
                rejected: [0; imu_emu::feed::REJECTS],
            },
        }
    }

    /// Samples taken and rejections by reason.
    pub fn counts(&self) -> &Counts {
        &self.counts
    }

    /// Whether the feed is lost (silent beyond its timeout).
    pub fn lost(&self) -> bool {
        self.live.lost()
    }

    /// Takes received bytes at device time `now_ns`.
    pub fn on_bytes(&mut self, bytes: &[u8], now_ns: u64) {
        let live = &mut self.live;
        let counts = &mut self.counts;
        self.decoder.decode(bytes, &mut |r| {
            let r = r.and_then(|s| match s {
                Sample::Rates(s) if s.device == OWN_DEVICE || s.device == 0 => {
                    live.offer(s.time_ns, s.truth, now_ns)
                }
                // Full-state rows are a host feed's (docs/feed.md).
                Sample::FullState(_) => Err(Reject::UnsupportedKind),
                _ => Err(Reject::WrongDevice),
            });
            counts.note(r);
        });
    }

    /// The truth and the fault for the ticks at and after `now_ns`.
    pub fn at(&mut self, now_ns: u64) -> (Option<imu_emu::sensor::Truth>, bool) {
        self.live.at(now_ns)
    }
}
