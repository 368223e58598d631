//! An in-process virtual KERNEL for Rust driver tests: a byte pipe backed
//! by the core [`Device`], implementing [`std::io::Read`] + [`std::io::Write`]
//! and [`embedded_io::Read`] + [`embedded_io::Write`], with simulated time.
//!
//! No thread, no socket, no wall clock: time is device time and moves only
//! when
//!
//! * the driver **reads**: each byte handed out takes its wire time at the
//!   device's line rate (10 bit times, 8N1), and the ticks due meanwhile
//!   run (so a stream keeps coming at its real rate); a read with nothing
//!   queued first advances to the next tick that produces output, or — if
//!   none will (idle device) — by [`VirtualDevice::read_timeout`] and fails
//!   with [`std::io::ErrorKind::TimedOut`] (as a serial port's read with a
//!   timeout);
//! * the test **advances** it ([`VirtualDevice::advance`]).
//!
//! Writes reach the device at the current time, at once (the host's own
//! line time is not modelled). A line-rate switch (CommitBaudRate) is taken
//! when the bytes before it were read.

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, PowerOn};
use imu_emu::model::Product;
use imu_emu::time::Instant;
use imu_emu::Kernel;

use crate::flash::MemNor;

/// How long a read waits, in device time, when no output will come.
pub const DEFAULT_READ_TIMEOUT_NS: u64 = 100_000_000;

/// A virtual KERNEL on the other end of a byte pipe (module docs).
pub struct VirtualDevice<F: NorFlash = MemNor> {
    dev: Device<F, Kernel>,
    /// Device time now, ns since power-on.
    now: u64,
    /// Ticks run (tick `k` runs at `k × period`).
    ticks: u64,
    period: u64,
    read_timeout_ns: u64,
}

impl VirtualDevice<MemNor> {
    /// A `product` powered on at time 0 with erased in-memory flash.
    pub fn new(product: Product) -> Self {
        Self::with_flash(product, 0, MemNor::new())
    }
}

impl<F: NorFlash> VirtualDevice<F> {
    /// A `product` with sensor seed `seed` powered on at time 0 with
    /// `flash` (e.g. an image saved by an earlier run).
    pub fn with_flash(product: Product, seed: u64, flash: F) -> Self {
        let cfg = PowerOn {
            product,
            boot: None,
            seed,
        };
        let dev = Device::power_on_with(cfg, flash, Instant::ZERO);
        let period = dev.tick_period_ns();
        let mut v = VirtualDevice {
            dev,
            now: 0,
            ticks: 0,
            period,
            read_timeout_ns: DEFAULT_READ_TIMEOUT_NS,
        };
        v.take_events();
        v
    }

    /// Sets how long a read waits (device time) when no output will come.
    pub fn read_timeout(mut self, ns: u64) -> Self {
        self.read_timeout_ns = ns;
        self
    }

    /// The device (mode, output rate, parameters, flash).
    pub fn device(&self) -> &Device<F, Kernel> {
        &self.dev
    }

    /// The device, to change its motion, faults or pins.
    pub fn device_mut(&mut self) -> &mut Device<F, Kernel> {
        &mut self.dev
    }

    /// Device time now, ns since power-on.
    pub fn now_ns(&self) -> u64 {
        self.now
    }

    /// Moves device time on by `ns`, running the ticks due. Output produced
    /// meanwhile waits in the device's TX queue for the next read (a
    /// driver that reads late gets it, as from a UART FIFO, up to the
    /// queue's size).
    pub fn advance(&mut self, ns: u64) {
        self.run_to(self.now.saturating_add(ns));
    }

    /// Bytes waiting to be read.
    pub fn pending(&self) -> usize {
        self.dev.tx_len()
    }

    fn run_to(&mut self, t: u64) {
        while self.ticks.saturating_mul(self.period) <= t {
            let at = self.ticks * self.period;
            self.dev.on_tick(Instant::from_nanos(at));
            self.ticks += 1;
        }
        self.now = self.now.max(t);
        self.take_events();
    }

    fn take_events(&mut self) {
        // Line-rate switches and TOV edges: the rate is read from the
        // device when needed; TOV has no pin here.
        while self.dev.poll_event().is_some() {}
    }

    /// Wire time of `n` bytes at the current line rate, ns.
    fn wire_ns(&self, n: usize) -> u64 {
        (n as u64 * 10 * 1_000_000_000).div_ceil(u64::from(self.dev.line_rate().max(1)))
    }

    /// Reads up to `buf.len()` bytes (module docs: time moves with them).
    fn read_bytes(&mut self, buf: &mut [u8]) -> Result<usize, std::io::ErrorKind> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.dev.tx_len() == 0 {
            match self.dev.ticks_to_next_output() {
                Some(k) => {
                    let due = (self.ticks + k - 1).saturating_mul(self.period);
                    self.run_to(due.max(self.now));
                }
                None => {
                    self.advance(self.read_timeout_ns);
                    if self.dev.tx_len() == 0 {
                        return Err(std::io::ErrorKind::TimedOut);
                    }
                }
            }
        }
        let mut n = 0;
        // Byte by byte in wire time, so ticks interleave as on the line.
        while n < buf.len() {
            let k = self.dev.poll_tx(&mut buf[n..n + 1]);
            if k == 0 {
                self.take_events();
                if self.dev.poll_tx(&mut buf[n..n + 1]) == 0 {
                    break;
                }
            }
            n += 1;
            let t = self.now + self.wire_ns(1);
            self.run_to(t);
        }
        if n == 0 {
            return Err(std::io::ErrorKind::TimedOut);
        }
        Ok(n)
    }
}

impl<F: NorFlash> std::io::Read for VirtualDevice<F> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.read_bytes(buf).map_err(std::io::Error::from)
    }
}

impl<F: NorFlash> std::io::Write for VirtualDevice<F> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.dev.on_rx(buf, Instant::from_nanos(self.now));
        self.take_events();
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The error of the `embedded_io` impls: only a timed-out read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TimedOut;

impl core::fmt::Display for TimedOut {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("read timed out: no output from the device")
    }
}

impl std::error::Error for TimedOut {}

impl embedded_io::Error for TimedOut {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::TimedOut
    }
}

impl<F: NorFlash> embedded_io::ErrorType for VirtualDevice<F> {
    type Error = TimedOut;
}

impl<F: NorFlash> embedded_io::Read for VirtualDevice<F> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, TimedOut> {
        self.read_bytes(buf).map_err(|_| TimedOut)
    }
}

impl<F: NorFlash> embedded_io::Write for VirtualDevice<F> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, TimedOut> {
        self.dev.on_rx(buf, Instant::from_nanos(self.now));
        self.take_events();
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), TimedOut> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read as _, Write as _};

    fn frame(payload: &[u8]) -> Vec<u8> {
        let mut f = vec![0u8; payload.len() + 8];
        let n = imu_emu::kernel::frame::encode(0, 0, payload, &mut f).unwrap();
        f.truncate(n);
        f
    }

    #[test]
    fn ga_frames_come_at_the_data_rate_in_device_time() {
        let mut v = VirtualDevice::new(Product::parse("K110").unwrap());
        let mut buf = [0u8; 10];
        // Idle: a read times out after 100 ms of device time.
        assert_eq!(
            v.read(&mut buf).unwrap_err().kind(),
            std::io::ErrorKind::TimedOut
        );
        assert_eq!(v.now_ns(), 100_000_000);
        v.write_all(&frame(&[0x8F])).unwrap();
        v.read_exact(&mut buf).unwrap();
        assert_eq!(
            buf,
            [0xAA, 0x55, 0x01, 0x8F, 0x08, 0x00, 0x96, 0x00, 0x2E, 0x01]
        );
        // 100 GA frames of 40 bytes: 1 s of device time.
        let t0 = v.now_ns();
        let mut ga = vec![0u8; 40 * 100];
        v.read_exact(&mut ga).unwrap();
        let secs = (v.now_ns() - t0) as f64 * 1e-9;
        assert!((0.98..=1.01).contains(&secs), "{secs}");
        let counters: Vec<u16> = ga
            .chunks(40)
            .map(|f| {
                assert_eq!(&f[..4], &[0xAA, 0x55, 0x01, 0x8F]);
                u16::from_le_bytes([f[30], f[31]])
            })
            .collect();
        for w in counters.windows(2) {
            assert_eq!(w[1], w[0].wrapping_add(20));
        }
    }

    #[test]
    fn embedded_io_reads_the_same_bytes() {
        let p = Product::parse("K110").unwrap();
        let mut a = VirtualDevice::new(p);
        let mut b = VirtualDevice::new(p);
        let get_info = frame(&[0x12]);
        std::io::Write::write_all(&mut a, &get_info).unwrap();
        embedded_io::Write::write_all(&mut b, &get_info).unwrap();
        let mut x = [0u8; 174];
        let mut y = [0u8; 174];
        std::io::Read::read_exact(&mut a, &mut x).unwrap();
        embedded_io::Read::read_exact(&mut b, &mut y).unwrap();
        assert_eq!(x, y);
        assert_eq!(&x[..4], &[0xAA, 0x55, 0x01, 0x12]);
        assert_eq!(embedded_io::Read::read(&mut b, &mut y), Err(TimedOut));
    }
}
