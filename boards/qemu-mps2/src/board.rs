//! The board's implementations of the fw-shell traits, and the flash file.

use core::cell::Cell;

use critical_section::Mutex;
use fw_shell::{Clock, TovPin, Uart};
use heapless::spsc::Consumer;
use imu_emu::device::Level;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;

use crate::mps2::{SYSCLK_HZ, TIMER1_REGS, UART0, UART1};
use crate::semi;

/// Flash size: the store's two 4 KiB sectors.
pub const FLASH_LEN: usize = 8192;
/// The board's flash.
pub type Flash = RamNor<FLASH_LEN>;

/// ns per TIMER1 count (25 MHz).
const NS_PER_COUNT: u64 = 1_000_000_000 / SYSCLK_HZ as u64;

/// TIMER1 free-running from 0xFFFF_FFFF, extended to 64 bits.
/// `(last raw value, counts so far)`.
static TIME: Mutex<Cell<(u32, u64)>> = Mutex::new(Cell::new((u32::MAX, 0)));

/// Starts the time base.
pub fn start_clock() {
    TIMER1_REGS.start(u32::MAX, false);
}

/// Now in ns: safe from any priority (a short critical section). The
/// extension needs a read at least every 171 s; the tick reads it 2000
/// times a second.
pub fn now() -> Instant {
    critical_section::with(|cs| {
        let cell = TIME.borrow(cs);
        let (last, total) = cell.get();
        let raw = TIMER1_REGS.value();
        let total = total + u64::from(last.wrapping_sub(raw));
        cell.set((raw, total));
        Instant::from_nanos(total * NS_PER_COUNT)
    })
}

/// The shell's clock.
pub struct Mps2Clock;
impl Clock for Mps2Clock {
    fn now(&mut self) -> Instant {
        now()
    }
}

/// UART0: RX bytes come from the RX interrupt's SPSC queue; TX writes the
/// data register (QEMU sends each byte at once; `TXFULL` stays set only
/// while the host side does not take bytes).
pub struct Uart0 {
    /// Bytes the RX interrupt received.
    pub rx: Consumer<'static, u8>,
    /// Bytes dropped because the host side did not take them.
    pub tx_lost: u32,
}

impl Uart for Uart0 {
    fn read(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        while n < buf.len() {
            match self.rx.dequeue() {
                Some(b) => {
                    buf[n] = b;
                    n += 1;
                }
                None => break,
            }
        }
        n
    }

    fn tx_room(&mut self) -> usize {
        if UART0.tx_ready() {
            usize::MAX
        } else {
            0
        }
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if !UART0.put_wait(b) {
                self.tx_lost = self.tx_lost.wrapping_add(1);
            }
        }
    }

    fn tx_idle(&mut self) -> bool {
        UART0.tx_ready()
    }

    fn set_baud(&mut self, bps: u32) {
        UART0.set_baud(bps);
    }
}

/// TOV edges reported on the pin bridge: `T` rising, `t` falling.
pub struct BridgeTov;
impl TovPin for BridgeTov {
    fn set(&mut self, level: Level) {
        UART1.put_wait(match level {
            Level::High => b'T',
            Level::Low => b't',
        });
    }
}

/// Writes the flash image back to its host file whenever the flash's
/// program/erase step counter moved (after a SaveFlash or an accepted UDD
/// configuration), via a temporary file and a rename, so a QEMU killed at
/// any time leaves the old or the new image.
pub struct Persist {
    path: Option<heapless::Vec<u8, { crate::config::PATH_MAX }>>,
    steps: u32,
}

impl Persist {
    /// Persists to `path` (none: RAM only); `flash` as loaded.
    pub fn new(
        path: Option<heapless::Vec<u8, { crate::config::PATH_MAX }>>,
        flash: &Flash,
    ) -> Self {
        Persist {
            path,
            steps: flash.steps(),
        }
    }

    /// Loads the image from the file into the erased `flash`, if the file
    /// exists; whether it did.
    pub fn load(path: &[u8], flash: &mut Flash) -> bool {
        use embedded_storage::nor_flash::NorFlash as _;
        let Some(mut f) = semi::File::open(path, cortex_m_semihosting::nr::open::R_BINARY) else {
            return false;
        };
        let mut chunk = [0u8; 256];
        let mut at = 0;
        while at < FLASH_LEN {
            let n = f.read(&mut chunk);
            let n = n - n % 4;
            if n == 0 {
                break;
            }
            // Programming an erased flash with the image reproduces it.
            if flash.write(at as u32, &chunk[..n]).is_err() {
                break;
            }
            at += n;
        }
        true
    }

    /// Call after every service: writes the image if the flash changed.
    pub fn check(&mut self, flash: &Flash) {
        let steps = flash.steps();
        if steps == self.steps {
            return;
        }
        self.steps = steps;
        let Some(path) = self.path.as_ref() else {
            return;
        };
        let mut tmp: heapless::Vec<u8, { crate::config::PATH_MAX + 4 }> = heapless::Vec::new();
        let _ = tmp.extend_from_slice(path);
        let _ = tmp.extend_from_slice(b".tmp");
        let ok = match semi::File::open(&tmp, cortex_m_semihosting::nr::open::W_TRUNC_BINARY) {
            Some(mut f) => f.write_all(flash.image()),
            None => false,
        };
        if !ok || !semi::rename(&tmp, path) {
            semi::eprintln("imu-emu: could not write the flash file");
        }
    }
}
