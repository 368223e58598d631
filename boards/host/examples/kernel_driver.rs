//! A tiny KERNEL driver, generic over `embedded_io::{Read, Write}` as a
//! firmware driver would be, tested against the in-process virtual device
//! (`imu_emu_runner::virtual_device::VirtualDevice`): no thread, no socket,
//! device time moving with the bytes read.
//!
//! `cargo run -p imu-emu-host --example kernel_driver` prints a few GA
//! samples; `cargo test -p imu-emu-host --example kernel_driver` runs its
//! tests (also part of `cargo test --workspace`).

use embedded_io::{Read, Write};

/// GA (ICD Table 5.7) sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ga {
    /// Angular rate, deg/s.
    pub gyro: [f64; 3],
    /// Acceleration, g.
    pub acc: [f64; 3],
    /// 2 kHz counter.
    pub counter: u16,
}

/// The driver: frames out, checked frames in.
pub struct Driver<P> {
    port: P,
    buf: Vec<u8>,
}

/// What can go wrong.
#[derive(Debug)]
pub enum Error<E> {
    /// The port failed (e.g. timed out).
    Port(E),
    /// A frame failed its checksum.
    Checksum,
}

fn sum(b: &[u8]) -> u16 {
    b.iter().fold(0u16, |s, &x| s.wrapping_add(u16::from(x)))
}

impl<P: Read + Write> Driver<P> {
    /// Wraps a port.
    pub fn new(port: P) -> Self {
        Driver {
            port,
            buf: Vec::new(),
        }
    }

    /// Sends a one-byte command (type 0, id 0).
    pub fn command(&mut self, code: u8) -> Result<(), Error<P::Error>> {
        let mut f = vec![0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, code];
        let s = sum(&f[2..]);
        f.extend_from_slice(&s.to_le_bytes());
        self.port.write_all(&f).map_err(Error::Port)
    }

    /// The next frame: `(id, payload)`.
    pub fn frame(&mut self) -> Result<(u8, Vec<u8>), Error<P::Error>> {
        loop {
            while self.buf.len() >= 2 && self.buf[..2] != [0xAA, 0x55] {
                self.buf.remove(0);
            }
            if self.buf.len() >= 6 {
                let total = usize::from(u16::from_le_bytes([self.buf[4], self.buf[5]])) + 2;
                if self.buf.len() >= total {
                    let f: Vec<u8> = self.buf.drain(..total).collect();
                    if sum(&f[2..total - 2]).to_le_bytes() != f[total - 2..] {
                        return Err(Error::Checksum);
                    }
                    return Ok((f[3], f[6..total - 2].to_vec()));
                }
            }
            let mut chunk = [0u8; 64];
            let n = self.port.read(&mut chunk).map_err(Error::Port)?;
            self.buf.extend_from_slice(&chunk[..n]);
        }
    }

    /// The firmware string of GetDevInfo (5.3.3).
    pub fn firmware(&mut self) -> Result<String, Error<P::Error>> {
        self.command(0x12)?;
        loop {
            let (id, p) = self.frame()?;
            if id == 0x12 {
                let fw = &p[8..48];
                let end = fw.iter().position(|&b| b == 0).unwrap_or(fw.len());
                return Ok(String::from_utf8_lossy(&fw[..end]).into_owned());
            }
        }
    }

    /// Starts GA and waits for its acknowledgement.
    pub fn start_ga(&mut self) -> Result<(), Error<P::Error>> {
        self.command(0x8F)?;
        while self.frame()?.0 != 0x8F {}
        Ok(())
    }

    /// The next GA sample.
    pub fn ga(&mut self) -> Result<Ga, Error<P::Error>> {
        loop {
            let (id, p) = self.frame()?;
            if id != 0x8F || p.len() != 32 {
                continue;
            }
            let i =
                |k: usize| f64::from(i32::from_le_bytes(p[4 * k..4 * k + 4].try_into().unwrap()));
            return Ok(Ga {
                gyro: [i(0) / 1e5, i(1) / 1e5, i(2) / 1e5],
                acc: [i(3) / 1e6, i(4) / 1e6, i(5) / 1e6],
                counter: u16::from_le_bytes([p[24], p[25]]),
            });
        }
    }
}

fn main() {
    use imu_emu::model::Product;
    use imu_emu_runner::virtual_device::VirtualDevice;
    let mut d = Driver::new(VirtualDevice::new(Product::parse("K110").unwrap()));
    println!("firmware: {}", d.firmware().unwrap());
    d.start_ga().unwrap();
    for _ in 0..3 {
        println!("{:?}", d.ga().unwrap());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_emu::model::Product;
    use imu_emu_runner::virtual_device::VirtualDevice;

    #[test]
    fn the_driver_reads_info_and_a_gap_free_ga_stream() {
        let mut d = Driver::new(VirtualDevice::new(Product::parse("K110").unwrap()));
        assert!(d
            .firmware()
            .unwrap()
            .starts_with("KERNEL-110-G2000-A40 imu-emu "));
        d.start_ga().unwrap();
        let first = d.ga().unwrap();
        let mut last = first.counter;
        for _ in 0..199 {
            let s = d.ga().unwrap();
            assert_eq!(s.counter, last.wrapping_add(20));
            assert!((s.acc[2] - 1.0).abs() < 0.05, "{:?}", s.acc);
            last = s.counter;
        }
        // 200 frames at 100 Hz: 2 s of device time (after ~the start).
        let t = d.port.now_ns();
        assert!((2_000_000_000..2_100_000_000).contains(&t), "{t}");
    }

    #[test]
    fn an_idle_device_times_out() {
        let mut d = Driver::new(VirtualDevice::new(Product::parse("K110").unwrap()));
        assert!(matches!(d.ga(), Err(Error::Port(_))));
    }
}
