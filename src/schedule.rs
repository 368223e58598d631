//! The tick/pump schedule every board runs: one piece of code for the host
//! runner and the firmware shell, sans-IO like the rest of the core (the
//! board passes its time in and lends its UART and pins through a [`Port`]).
//!
//! One [`Schedule::poll`] (a *pass*), at device time `now` (ns since
//! power-on):
//!
//! 1. **Ticks** on absolute deadlines `deadline_k = k × period`
//!    ([`Device::tick_period_ns`], k = 1, 2, …), each run with its own
//!    deadline as its time, so a late pass never shifts the schedule: every
//!    tick due by `now` (plus [`Limits::early_ns`]) runs, in order, at most
//!    [`Limits::max_ticks`] per pass (the rest run in the next passes).
//!    Before each tick: [`Port::before_tick`] (pin edges, motion stamped up
//!    to the deadline), then the line is advanced to the deadline and the
//!    device's TX queue drained within the line credit ([`Pacer`]). So a
//!    catch-up runs ticks *and* the line in their real order: every tick
//!    finds the TX queue as a real UART would have left it, and no tick
//!    runs without the line time that came before it.
//! 2. **The schedule's time** is `now` once every due tick ran; while ticks
//!    are still due (the pass cap was hit) it is the deadline of the last
//!    tick run: the line does not run ahead of the ticks still waiting.
//! 3. **Input**: at most [`Limits::max_rx`] bytes from [`Port::read`] go to
//!    [`Device::on_rx`] at the schedule's time (a flood never starves the
//!    ticks), then [`Port::after_rx`].
//! 4. **Output** up to the schedule's time, then events: a line-rate switch
//!    ([`Event::LineRate`]) takes effect once the bytes queued before it
//!    were handed out and [`Port::tx_idle`] says they left the wire; the
//!    credit restarts at the new rate. TOV edges go to [`Port::tov`].
//!
//! [`Schedule::poll_at`] says when the next pass has something to do
//! (smoltcp's `poll_at`): the deadline of the next tick that produces
//! output ([`Device::ticks_to_next_output`]), or the time the line can
//! carry what is queued, whichever is first. A board may sleep until then
//! (ticks in between change nothing visible and are run late, in order).
//!
//! Loss is never silent: a frame that does not fit the device's TX queue is
//! dropped whole and counted ([`Device::tx_dropped`]); the line never
//! carries part of a frame.

use embedded_storage::nor_flash::NorFlash;

use crate::device::{Device, Event, Level};
use crate::line::Pacer;
use crate::personality::Personality;
use crate::time::Instant;

/// What the board lends the schedule: its UART and pins. Every method must
/// return at once (never block).
pub trait Port<F: NorFlash, K: Personality> {
    /// What the board's I/O can fail with (`Infallible` on an MCU).
    type Error;

    /// Bytes [`Port::write`] accepts now (UART FIFO or buffer space).
    fn tx_room(&mut self) -> usize;
    /// Hands device output to the UART; `bytes.len() <= tx_room()`.
    fn write(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
    /// Whether everything written so far has left the wire, so the line
    /// rate can change without corrupting a byte.
    fn tx_idle(&mut self) -> bool {
        true
    }
    /// Switches the UART to `bps` bit/s (only while [`Port::tx_idle`]).
    fn set_line_rate(&mut self, bps: u32) -> Result<(), Self::Error>;
    /// Moves received bytes into `buf`; how many (0: none waiting).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;
    /// The device asks for a TOV edge (ICD 4.1.4) at `at` (may be ahead).
    fn tov(&mut self, _level: Level, _at: Instant) -> Result<(), Self::Error> {
        Ok(())
    }
    /// Right before the tick at `deadline`: hand the device the pin edges
    /// stamped up to it.
    fn before_tick(
        &mut self,
        _dev: &mut Device<F, K>,
        _deadline: Instant,
    ) -> Result<(), Self::Error> {
        Ok(())
    }
    /// Runs the tick: [`Device::on_tick`] (a board may set the motion for
    /// the tick first, or time the call).
    fn tick(&mut self, dev: &mut Device<F, K>, deadline: Instant) -> Result<(), Self::Error> {
        dev.on_tick(deadline);
        Ok(())
    }
    /// After the received bytes were executed at `at`, before any reply is
    /// handed to the UART (persist the flash, serve other inputs at `at`).
    fn after_rx(&mut self, _dev: &mut Device<F, K>, _at: Instant) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// How much one [`Schedule::poll`] may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Most ticks one pass runs (catching up after a stall).
    pub max_ticks: u32,
    /// Most received bytes one pass takes from [`Port::read`].
    pub max_rx: usize,
    /// A tick whose deadline is at most this far ahead of `now` runs now
    /// (a timer interrupt derived from the same clock may fire early).
    pub early_ns: u64,
}

/// What one [`Schedule::poll`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Pass {
    /// Ticks run.
    pub ticks: u32,
    /// Bytes received and fed to the device.
    pub rx: usize,
    /// Bytes handed to the UART.
    pub tx: usize,
    /// Ticks are still due: the pass hit [`Limits::max_ticks`].
    pub behind: bool,
}

/// The schedule's state: the tick count, the line credit, a line-rate
/// switch waiting for the UART, and an `N`-byte buffer that bytes cross
/// between the UART and the device in.
#[derive(Debug, Clone)]
pub struct Schedule<const N: usize> {
    period_ns: u64,
    /// Ticks run since power-on.
    ticks: u64,
    /// Deadline of the last tick run (0 before the first): `ticks × period`,
    /// kept by addition (a 64-bit multiply is a library call on a
    /// Cortex-M0+).
    last_tick_ns: u64,
    pacer: Pacer,
    /// A line-rate switch waiting for [`Port::tx_idle`].
    pending_rate: Option<u32>,
    /// Device time the schedule has reached (see the module docs).
    time: u64,
    buf: [u8; N],
}

impl<const N: usize> Schedule<N> {
    /// The schedule of a device just powered on (time 0): its tick period
    /// and line rate.
    pub fn new<F: NorFlash, K: Personality>(dev: &Device<F, K>) -> Self {
        Schedule {
            period_ns: dev.tick_period_ns().max(1),
            ticks: 0,
            last_tick_ns: 0,
            pacer: Pacer::new(dev.line_rate(), 0),
            pending_rate: None,
            time: 0,
            buf: [0; N],
        }
    }

    /// Starts again from time 0 after a power cycle of `dev` (in place:
    /// the buffer is not rebuilt on the stack). The line keeps the rate the
    /// UART runs at: the device's power-on [`Event::LineRate`] switches it
    /// if the device came up at another rate.
    pub fn restart<F: NorFlash, K: Personality>(&mut self, dev: &Device<F, K>) {
        self.period_ns = dev.tick_period_ns().max(1);
        self.ticks = 0;
        self.last_tick_ns = 0;
        self.pacer = Pacer::new(self.pacer.rate(), 0);
        self.pending_rate = None;
        self.time = 0;
    }

    /// Tick period, ns.
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// Ticks run since power-on.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// Deadline of the next tick, ns.
    pub fn next_deadline(&self) -> u64 {
        self.last_tick_ns.saturating_add(self.period_ns)
    }

    /// Device time the schedule has reached: the last pass's `now`, or the
    /// deadline of the last tick run while ticks are still due.
    pub fn time(&self) -> u64 {
        self.time
    }

    /// How far device time `now` is ahead of the last tick run while ticks
    /// are due (0 when caught up): the backlog a board may cap.
    pub fn lag(&self, now: u64) -> u64 {
        if self.next_deadline() <= now {
            now - self.last_tick_ns
        } else {
            0
        }
    }

    /// The line rate the line runs at, bit/s.
    pub fn line_rate(&self) -> u32 {
        self.pacer.rate()
    }

    /// One pass at device time `now` (see the module docs).
    pub fn poll<F: NorFlash, K: Personality, P: Port<F, K>>(
        &mut self,
        dev: &mut Device<F, K>,
        port: &mut P,
        now: u64,
        limits: &Limits,
    ) -> Result<Pass, P::Error> {
        let mut pass = Pass::default();
        let early = now.saturating_add(limits.early_ns);
        while pass.ticks < limits.max_ticks && self.next_deadline() <= early {
            let deadline = self.next_deadline();
            let at = Instant::from_nanos(deadline);
            port.before_tick(dev, at)?;
            pass.tx += self.pump(dev, port, deadline)?;
            port.tick(dev, at)?;
            self.ticks += 1;
            self.last_tick_ns = deadline;
            pass.ticks += 1;
        }
        pass.behind = self.next_deadline() <= now;
        let t = if pass.behind { self.last_tick_ns } else { now };
        self.time = self.time.max(t);
        let at = Instant::from_nanos(self.time);

        while pass.rx < limits.max_rx {
            let room = (limits.max_rx - pass.rx).min(N);
            let n = port.read(&mut self.buf[..room])?.min(room);
            if n == 0 {
                break;
            }
            dev.on_rx(&self.buf[..n], at);
            pass.rx += n;
        }
        port.after_rx(dev, at)?;
        pass.tx += self.pump(dev, port, self.time)?;
        Ok(pass)
    }

    /// When the next pass has something to do, device time ns (`now` if
    /// at once), or `None` when nothing is scheduled (idle, nothing
    /// queued): the board then wakes for input, pins or its own reasons.
    pub fn poll_at<F: NorFlash, K: Personality>(
        &self,
        dev: &Device<F, K>,
        now: u64,
    ) -> Option<u64> {
        let next = self.next_deadline();
        if next <= now {
            return Some(now);
        }
        let at = dev
            .ticks_to_next_output()
            .map(|k| (self.last_tick_ns).saturating_add(k.max(1).saturating_mul(self.period_ns)));
        let line = if self.pending_rate.is_some() {
            // The line waits for the UART to go idle: look again at the
            // next tick.
            Some(next)
        } else {
            let queued = dev.tx_len();
            (queued > 0).then(|| self.pacer.ready_at(queued).max(now))
        };
        match (at, line) {
            (Some(a), Some(l)) => Some(a.min(l)),
            (a, l) => a.or(l),
        }
    }

    /// Acts on the device's pending events (after a power cycle, a pin
    /// edge, …): a line-rate switch is kept for the next pump, TOV edges go
    /// to [`Port::tov`]; whether a line-rate switch came.
    pub fn events<F: NorFlash, K: Personality, P: Port<F, K>>(
        &mut self,
        dev: &mut Device<F, K>,
        port: &mut P,
    ) -> Result<bool, P::Error> {
        let mut switched = false;
        while let Some(ev) = dev.poll_event() {
            match ev {
                Event::LineRate(bps) => {
                    if bps != self.pacer.rate() || self.pending_rate.is_some() {
                        self.pending_rate = Some(bps);
                    }
                    switched = true;
                }
                Event::Tov { level, at } => port.tov(level, at)?,
            }
        }
        Ok(switched)
    }

    /// Advances the line to `at` and moves what it can carry from the
    /// device to the UART; bytes moved.
    fn pump<F: NorFlash, K: Personality, P: Port<F, K>>(
        &mut self,
        dev: &mut Device<F, K>,
        port: &mut P,
        at: u64,
    ) -> Result<usize, P::Error> {
        self.pacer.advance(at);
        let mut sent = 0;
        loop {
            self.events(dev, port)?;
            if let Some(rate) = self.pending_rate {
                if !port.tx_idle() {
                    break;
                }
                port.set_line_rate(rate)?;
                self.pacer.set_rate(rate, at);
                self.pending_rate = None;
            }
            let room = self.pacer.available().min(port.tx_room()).min(N);
            if room == 0 {
                break;
            }
            let n = dev.poll_tx(&mut self.buf[..room]);
            if n == 0 {
                // The queue is empty or stops at a line-rate switch, which
                // the events hand out: then go on at the new rate.
                if self.events(dev, port)? {
                    continue;
                }
                break;
            }
            port.write(&self.buf[..n])?;
            self.pacer.consume(n);
            sent += n;
        }
        Ok(sent)
    }
}

#[cfg(test)]
mod tests {
    use std::vec::Vec;

    use super::*;
    // A real personality to drive: the KERNEL.
    use crate::kernel::Kernel;
    use crate::model::Product;
    use crate::nor::RamNor;

    type Dev = Device<RamNor<8192>, Kernel>;

    /// A board that records what the schedule did.
    #[derive(Default)]
    struct Fake {
        rx: Vec<u8>,
        tx: Vec<u8>,
        /// (bytes written before, new rate) of every line-rate switch.
        rates: Vec<(usize, u32)>,
        /// Deadline of every tick run.
        ticks: Vec<u64>,
        busy: bool,
    }

    impl Port<RamNor<8192>, Kernel> for Fake {
        type Error = core::convert::Infallible;
        fn tx_room(&mut self) -> usize {
            usize::MAX
        }
        fn write(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
            self.tx.extend_from_slice(bytes);
            Ok(())
        }
        fn tx_idle(&mut self) -> bool {
            !self.busy
        }
        fn set_line_rate(&mut self, bps: u32) -> Result<(), Self::Error> {
            self.rates.push((self.tx.len(), bps));
            Ok(())
        }
        fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
            let n = buf.len().min(self.rx.len());
            buf[..n].copy_from_slice(&self.rx[..n]);
            self.rx.drain(..n);
            Ok(n)
        }
        fn tick(&mut self, dev: &mut Dev, deadline: Instant) -> Result<(), Self::Error> {
            self.ticks.push(deadline.as_nanos());
            dev.on_tick(deadline);
            Ok(())
        }
    }

    const ALL: Limits = Limits {
        max_ticks: u32::MAX,
        max_rx: usize::MAX,
        early_ns: 0,
    };

    fn k110() -> Dev {
        Device::power_on(
            Product::parse("K110").unwrap(),
            RamNor::new(),
            Instant::ZERO,
        )
    }

    /// A command frame (ICD Table 5.2, type 0, id 0).
    fn command(payload: &[u8]) -> Vec<u8> {
        let len = (payload.len() + 6) as u16;
        let mut f = std::vec![0xAA, 0x55, 0, 0];
        f.extend_from_slice(&len.to_le_bytes());
        f.extend_from_slice(payload);
        let s = f[2..]
            .iter()
            .fold(0u16, |s, &x| s.wrapping_add(u16::from(x)));
        f.extend_from_slice(&s.to_le_bytes());
        f
    }

    fn save_flash(id: u16, value: &[u8]) -> Vec<u8> {
        let mut p = std::vec![0xB2, 0xFF];
        p.extend_from_slice(&id.to_le_bytes());
        p.extend_from_slice(&(value.len() as u16).to_le_bytes());
        p.extend_from_slice(value);
        command(&p)
    }

    /// The 2 kHz counters (payload offset 24) of the GA frames (Table 5.6)
    /// in `tx` after `skip` bytes; panics on anything else.
    fn ga_counters(tx: &[u8], skip: usize) -> Vec<u16> {
        tx[skip..]
            .chunks(40)
            .filter(|f| f.len() == 40)
            .map(|f| {
                assert_eq!(&f[..6], &[0xAA, 0x55, 0x01, 0x8F, 0x26, 0x00]);
                u16::from_le_bytes([f[30], f[31]])
            })
            .collect()
    }

    #[test]
    fn ticks_run_on_absolute_deadlines_in_order() {
        let mut dev = k110();
        let mut s = Schedule::<64>::new(&dev);
        let mut p = Fake::default();
        let pass = s
            .poll(&mut dev, &mut p, 5 * 500_000 + 499_999, &ALL)
            .unwrap();
        assert_eq!((pass.ticks, pass.behind), (5, false));
        assert_eq!(
            p.ticks,
            [500_000, 1_000_000, 1_500_000, 2_000_000, 2_500_000]
        );
        assert_eq!(s.time(), 2_999_999);
        // A tick due a little ahead runs early only with the slack.
        let early = Limits { early_ns: 1, ..ALL };
        s.poll(&mut dev, &mut p, 2_999_998, &ALL).unwrap();
        assert_eq!(s.ticks(), 5);
        s.poll(&mut dev, &mut p, 2_999_999, &early).unwrap();
        assert_eq!(p.ticks.last(), Some(&3_000_000));
    }

    #[test]
    fn catch_up_is_capped_and_the_line_never_runs_ahead_of_the_ticks_due() {
        // GA at 250 Hz on 115 200 bit/s: 87 % of the line. A 200 ms stall
        // caught up 16 ticks a pass must lose no frame.
        let mut dev = k110();
        let mut s = Schedule::<64>::new(&dev);
        let mut rx = save_flash(0x0012, &250u16.to_le_bytes());
        rx.extend(command(&[0x8F]));
        let mut p = Fake {
            rx,
            ..Fake::default()
        };
        let mut now = 0;
        while now < 500_000_000 {
            now += 500_000;
            s.poll(&mut dev, &mut p, now, &ALL).unwrap();
        }
        now += 200_000_000;
        let cap = Limits {
            max_ticks: 16,
            ..ALL
        };
        let mut passes = 0;
        loop {
            let pass = s.poll(&mut dev, &mut p, now, &cap).unwrap();
            passes += 1;
            if !pass.behind {
                break;
            }
            assert_eq!(pass.ticks, 16);
            assert_eq!(
                s.time(),
                s.ticks() * 500_000,
                "the line waits for the ticks"
            );
            assert_eq!(s.lag(now), now - s.time());
        }
        assert_eq!(passes, 25); // 400 ticks due, 16 a pass
        assert_eq!((s.lag(now), s.time()), (0, now));
        for _ in 0..2000 {
            now += 500_000;
            s.poll(&mut dev, &mut p, now, &ALL).unwrap();
        }
        assert_eq!(dev.tx_dropped(), 0);
        let counters = ga_counters(&p.tx, 20);
        assert!(counters.len() > 420, "{}", counters.len());
        for w in counters.windows(2) {
            assert_eq!(w[1].wrapping_sub(w[0]), 8);
        }
    }

    #[test]
    fn input_per_pass_is_bounded() {
        let mut dev = k110();
        let mut s = Schedule::<64>::new(&dev);
        let mut p = Fake {
            rx: std::vec![0; 10_000],
            ..Fake::default()
        };
        let lim = Limits {
            max_rx: 4096,
            ..ALL
        };
        assert_eq!(s.poll(&mut dev, &mut p, 0, &lim).unwrap().rx, 4096);
        assert_eq!(s.poll(&mut dev, &mut p, 0, &lim).unwrap().rx, 4096);
        assert_eq!(s.poll(&mut dev, &mut p, 0, &lim).unwrap().rx, 1808);
        assert_eq!(s.poll(&mut dev, &mut p, 0, &lim).unwrap().rx, 0);
    }

    #[test]
    fn a_line_rate_switch_follows_the_bytes_queued_before_it() {
        let mut dev = k110();
        let mut s = Schedule::<64>::new(&dev);
        let mut rx = save_flash(0x03B2, &[0x0B]); // Baud_Rate 2 000 000
        rx.extend(command(&[0xC2])); // CommitBaudRate
        rx.extend(command(&[0x12])); // GetDevInfo: 174 bytes
        let mut p = Fake {
            rx,
            busy: true,
            ..Fake::default()
        };
        let mut now = 0;
        for _ in 0..20 {
            now += 500_000;
            s.poll(&mut dev, &mut p, now, &ALL).unwrap();
        }
        // The SaveFlash acknowledgement left at 115 200; the switch waits
        // for the UART to go idle.
        assert_eq!((p.tx.len(), p.rates.len(), s.line_rate()), (10, 0, 115_200));
        assert_eq!(s.poll_at(&dev, now), Some(now + 500_000));
        p.busy = false;
        now += 500_000;
        s.poll(&mut dev, &mut p, now, &ALL).unwrap();
        assert_eq!(p.rates, [(10, 2_000_000)]);
        // The credit restarted at the switch: 100 bytes a tick at 2 Mbit/s.
        assert_eq!(p.tx.len(), 10);
        now += 500_000;
        s.poll(&mut dev, &mut p, now, &ALL).unwrap();
        assert_eq!(p.tx.len(), 110);
        now += 500_000;
        s.poll(&mut dev, &mut p, now, &ALL).unwrap();
        assert_eq!(p.tx.len(), 184);
        assert_eq!(&p.tx[10..14], &[0xAA, 0x55, 0x01, 0x12]);
    }

    #[test]
    fn poll_at_is_the_next_output_tick_or_when_the_line_carries_the_queue() {
        let mut dev = k110();
        let mut s = Schedule::<64>::new(&dev);
        let mut p = Fake::default();
        // Idle, nothing queued: nothing scheduled; a due tick: now.
        assert_eq!(s.poll_at(&dev, 0), None);
        assert_eq!(s.poll_at(&dev, 500_000), Some(500_000));
        // GA at 100 Hz: after its acknowledgement, frames every 20 ticks.
        p.rx = command(&[0x8F]);
        s.poll(&mut dev, &mut p, 0, &ALL).unwrap();
        // The 10-byte acknowledgement waits for line credit: 10 bytes at
        // 115 200 bit/s = ⌈868 055.5⌉ ns.
        assert_eq!(dev.tx_len(), 10);
        assert_eq!(s.poll_at(&dev, 0), Some(868_056));
        s.poll(&mut dev, &mut p, 868_056, &ALL).unwrap();
        assert_eq!((p.tx.len(), dev.tx_len()), (10, 0));
        let k = dev.ticks_to_next_output().unwrap();
        assert_eq!(s.poll_at(&dev, 868_056), Some((s.ticks() + k) * 500_000));
    }
}
