//! PORT_MONITOR's counts (`docs/isb-data-sets.md` "PORT_MONITOR"): every
//! byte the personality receives, and every frame it queues on the line,
//! through [`Counting`], a [`Context`] that counts what passes.

use super::*;
use crate::chain::SignalChain;
use crate::io::Event;
use crate::model::Product;
use crate::store::StoreError;
use crate::time::TimeBase;

/// Byte counts of the one serial port since power-on, and the bytes of
/// the current and the previous whole second of device time.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PortCounts {
    pub(super) tx_bytes: u32,
    pub(super) rx_bytes: u32,
    pub(super) tx_drops: u32,
    pub(super) tx_bytes_dropped: u32,
    /// The second (since power-on) `*_in` count.
    second: u64,
    tx_in: u32,
    rx_in: u32,
    /// The bytes of second `second − 1`.
    tx_prev: u32,
    rx_prev: u32,
}

impl PortCounts {
    fn roll(&mut self, second: u64) {
        if second != self.second {
            let (tx, rx) = self.rates_at(second);
            self.tx_prev = tx;
            self.rx_prev = rx;
            self.tx_in = 0;
            self.rx_in = 0;
            self.second = second;
        }
    }

    /// Bytes sent and received in the whole second before `second`.
    pub(super) fn rates_at(&self, second: u64) -> (u32, u32) {
        if second == self.second {
            (self.tx_prev, self.rx_prev)
        } else if second == self.second + 1 {
            (self.tx_in, self.rx_in)
        } else {
            (0, 0)
        }
    }

    pub(super) fn received(&mut self, second: u64, n: usize) {
        self.roll(second);
        let n = n as u32;
        self.rx_bytes = self.rx_bytes.wrapping_add(n);
        self.rx_in = self.rx_in.wrapping_add(n);
    }

    pub(super) fn sent(&mut self, second: u64, c: &Tally) {
        self.roll(second);
        self.tx_bytes = self.tx_bytes.wrapping_add(c.sent);
        self.tx_in = self.tx_in.wrapping_add(c.sent);
        self.tx_drops = self.tx_drops.wrapping_add(c.drops);
        self.tx_bytes_dropped = self.tx_bytes_dropped.wrapping_add(c.dropped_bytes);
    }
}

/// What one call queued.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Tally {
    sent: u32,
    drops: u32,
    dropped_bytes: u32,
}

/// A [`Context`] that counts the frames pushed through it.
pub(super) struct Counting<'a, C> {
    pub(super) cx: &'a mut C,
    pub(super) tally: Tally,
}

impl<'a, C: Context<Integrals>> Counting<'a, C> {
    pub(super) fn new(cx: &'a mut C) -> Self {
        Counting {
            cx,
            tally: Tally::default(),
        }
    }
}

impl<C: Context<Integrals>> Context<Integrals> for Counting<'_, C> {
    fn product(&self) -> Product {
        self.cx.product()
    }
    fn seed(&self) -> u64 {
        self.cx.seed()
    }
    fn firmware_update(&self) -> bool {
        self.cx.firmware_update()
    }
    fn chain(&self) -> &SignalChain<Integrals> {
        self.cx.chain()
    }
    fn chain_mut(&mut self) -> &mut SignalChain<Integrals> {
        self.cx.chain_mut()
    }
    fn push_frame(&mut self, n: usize, fill: impl FnOnce(&mut [u8]) -> bool) -> Option<Instant> {
        // `Some(false)`: the writer gave up (nothing to send, not a drop).
        let mut filled = None;
        let r = self.cx.push_frame(n, |f| {
            let ok = fill(f);
            filled = Some(ok);
            ok
        });
        if r.is_some() {
            self.tally.sent = self.tally.sent.wrapping_add(n as u32);
        } else if filled != Some(false) {
            // Not queued (the line was full): a write that could not send.
            self.tally.drops = self.tally.drops.wrapping_add(1);
            self.tally.dropped_bytes = self.tally.dropped_bytes.wrapping_add(n as u32);
        }
        r
    }
    fn line_rate(&self) -> u32 {
        self.cx.line_rate()
    }
    fn tx_dropped(&self) -> u32 {
        self.cx.tx_dropped()
    }
    fn set_line_rate(&mut self, bps: u32) {
        self.cx.set_line_rate(bps)
    }
    fn switch_line_rate(&mut self, bps: u32) {
        self.cx.switch_line_rate(bps)
    }
    fn push_event(&mut self, ev: Event) {
        self.cx.push_event(ev)
    }
    fn load_image(&mut self, image: &mut [u8]) -> Result<bool, StoreError> {
        self.cx.load_image(image)
    }
    fn save_image(&mut self, image: &[u8]) -> Result<(), StoreError> {
        self.cx.save_image(image)
    }
    fn request_reset(&mut self) {
        self.cx.request_reset()
    }
    fn time(&self) -> &TimeBase {
        self.cx.time()
    }
    fn time_mut(&mut self) -> &mut TimeBase {
        self.cx.time_mut()
    }
}

/// Whole seconds of device time since power-on at `now`.
pub(super) fn second_of(cx: &impl Context<Integrals>, now: Instant) -> u64 {
    now.since(cx.time().powered_at()) / 1_000_000_000
}

impl State {
    /// PORT_MONITOR now: port 0 is the serial line (a UART, index 0 —
    /// ser0, whose baud rate it follows); the others unused.
    pub(super) fn port_monitor(
        &self,
        cx: &impl Context<Integrals>,
        now: Instant,
    ) -> aux_sets::PortMonitor {
        let p = &self.port;
        let (tx_rate, rx_rate) = p.rates_at(second_of(cx, now));
        let mut m = aux_sets::PortMonitor::default();
        m.port[0] = aux_sets::PortMonitorSet {
            port_info: aux_sets::PORT_TYPE_UART,
            status: 0,
            tx_bytes_per_sec: tx_rate,
            rx_bytes_per_sec: rx_rate,
            tx_bytes: p.tx_bytes,
            rx_bytes: p.rx_bytes,
            tx_data_drops: p.tx_drops,
            rx_overflows: 0,
            tx_bytes_dropped: p.tx_bytes_dropped,
            rx_checksum_errors: self.parse_errors,
        };
        m.active_ports = 1;
        m
    }
}
