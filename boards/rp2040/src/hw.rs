//! Register-level pieces (RP2040 datasheet): the 64-bit µs timer as the
//! time base and ALARM0 as the tick, UART0 (PL011) data path and baud
//! rate, and the parameter store in the last 8 KiB of the QSPI flash
//! through the boot ROM's flash functions.

use core::ptr::{read_volatile, write_volatile};

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use fw_shell::{Clock, Uart};
use heapless::spsc::Consumer;
use imu_emu::time::Instant;
use rp2040_hal::rom_data;

fn rd(addr: usize) -> u32 {
    // SAFETY: callers pass addresses of memory-mapped registers.
    unsafe { read_volatile(addr as *const u32) }
}
fn wr(addr: usize, v: u32) {
    // SAFETY: as for `rd`.
    unsafe { write_volatile(addr as *mut u32, v) }
}

// ----- TIMER: 64-bit µs counter, ALARM0 = the tick -----

const TIMER: usize = 0x4005_4000;
const ALARM0: usize = TIMER + 0x10;
const TIMERAWH: usize = TIMER + 0x24;
const TIMERAWL: usize = TIMER + 0x28;
const INTR: usize = TIMER + 0x34;
const INTE: usize = TIMER + 0x38;

/// µs since reset; lock-free and safe from any priority (high, low, high
/// again until the high word is stable).
pub fn micros() -> u64 {
    loop {
        let hi = rd(TIMERAWH);
        let lo = rd(TIMERAWL);
        if rd(TIMERAWH) == hi {
            return u64::from(hi) << 32 | u64::from(lo);
        }
    }
}

/// Now, in ns (out of line: the tick, the shell and the edge interrupt
/// read it; 0.35 KiB of flash inlined).
#[inline(never)]
pub fn now() -> Instant {
    Instant::from_micros(micros())
}

/// The shell's clock.
pub struct TimerClock;
impl Clock for TimerClock {
    fn now(&mut self) -> Instant {
        now()
    }
}

/// The tick: ALARM0 every `period_us`, on the absolute schedule.
pub struct Tick {
    next: u32,
    period_us: u32,
}

impl Tick {
    /// Arms the first alarm one period from now.
    pub fn start(hz: u32) -> Tick {
        let period_us = 1_000_000 / hz;
        let mut t = Tick {
            next: rd(TIMERAWL),
            period_us,
        };
        wr(INTE, rd(INTE) | 1);
        t.rearm();
        t
    }

    /// Acknowledges the alarm and arms the next one (skipping ahead if the
    /// schedule was missed; the shell catches the ticks up).
    pub fn rearm(&mut self) {
        wr(INTR, 1);
        self.next = self.next.wrapping_add(self.period_us);
        let now = rd(TIMERAWL);
        if (self.next.wrapping_sub(now) as i32) < 2 {
            self.next = now.wrapping_add(2);
        }
        wr(ALARM0, self.next);
    }
}

// ----- UART0 (PL011) -----

const UART0: usize = 0x4003_4000;
const DR: usize = UART0;
const FR: usize = UART0 + 0x18;
const IBRD: usize = UART0 + 0x24;
const FBRD: usize = UART0 + 0x28;
const LCR_H: usize = UART0 + 0x2C;
const IFLS: usize = UART0 + 0x34;
const IMSC: usize = UART0 + 0x38;
const ICR: usize = UART0 + 0x44;
const FR_BUSY: u32 = 1 << 3;
const FR_RXFE: u32 = 1 << 4;
const FR_TXFF: u32 = 1 << 5;
const FR_TXFE: u32 = 1 << 7;

/// UART0 (the HAL configured pins, clock and 8N1): the RX interrupt fills
/// an SPSC ring the tick drains; TX writes the 32-byte FIFO.
pub struct Uart0 {
    /// Bytes from the RX interrupt.
    pub rx: Consumer<'static, u8>,
    /// `clk_peri`, Hz.
    pub clk_hz: u32,
}

impl Uart0 {
    /// RX interrupt at ¼ full plus the receive timeout.
    pub fn enable_rx_irq() {
        enable_rx_irq(UART0);
    }
}

/// UART1 (the live motion feed, docs/feed.md): its registers are UART0's
/// moved by 0x4000.
pub const UART1: usize = 0x4003_8000;

/// RX interrupt of the PL011 at `base` at ¼ full plus the receive timeout.
pub fn enable_rx_irq(base: usize) {
    wr(base + (IFLS - UART0), 0b001 << 3); // RX FIFO ≥ 1/4 (8 bytes)
    wr(base + (IMSC - UART0), 1 << 4 | 1 << 6); // RXIM, RTIM
}

/// RX interrupt side: drains UART0's FIFO into `out`.
pub fn uart0_rx(out: &mut heapless::spsc::Producer<'static, u8>) {
    uart_rx(UART0, out);
}

/// RX interrupt side: drains the FIFO of the PL011 at `base` into `out`.
pub fn uart_rx(base: usize, out: &mut heapless::spsc::Producer<'static, u8>) {
    wr(base + (ICR - UART0), 1 << 4 | 1 << 6);
    while rd(base + (FR - UART0)) & FR_RXFE == 0 {
        let b = rd(base + (DR - UART0)) as u8;
        // A full ring (the tick stalled) drops the byte, like an overrun.
        let _ = out.enqueue(b);
    }
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
        let fr = rd(FR);
        if fr & FR_TXFE != 0 {
            32
        } else if fr & FR_TXFF == 0 {
            1
        } else {
            0
        }
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while rd(FR) & FR_TXFF != 0 {}
            wr(DR, u32::from(b));
        }
    }

    fn tx_idle(&mut self) -> bool {
        rd(FR) & (FR_BUSY | FR_TXFE) == FR_TXFE
    }

    fn set_baud(&mut self, bps: u32) {
        // Divisor in 1/64: clk × 4 / baud, rounded.
        let div = (u64::from(self.clk_hz) * 8 / u64::from(bps.max(1))).div_ceil(2);
        let (ibrd, fbrd) = ((div >> 6) as u32, (div & 63) as u32);
        wr(IBRD, ibrd.clamp(1, 0xFFFF));
        wr(FBRD, fbrd);
        // The divisors latch on an LCR_H write.
        wr(LCR_H, rd(LCR_H));
    }
}

// ----- parameters: the last 8 KiB of the 2 MiB flash, via the boot ROM -----

/// Flash size of the Pico (W25Q16JV).
pub const FLASH_SIZE: u32 = 2 * 1024 * 1024;
/// The store's window: the last two 4 KiB sectors (memory.x keeps code out).
pub const PARAM_OFFSET: u32 = FLASH_SIZE - 8192;
const XIP_BASE: usize = 0x1000_0000;
const SECTOR: u32 = 4096;
const PAGE: u32 = 256;

/// Boot ROM flash functions, resolved while XIP still works.
#[derive(Clone, Copy)]
struct RomFns {
    connect: unsafe extern "C" fn(),
    exit_xip: unsafe extern "C" fn(),
    erase: unsafe extern "C" fn(u32, usize, u32, u8),
    program: unsafe extern "C" fn(u32, *const u8, usize),
    flush: unsafe extern "C" fn(),
    enter_xip: unsafe extern "C" fn(),
    /// The RAM copy of boot2 (+1: Thumb), which puts XIP back in fast
    /// QSPI mode.
    boot2: unsafe extern "C" fn(),
}

/// Erase (`data` null) or program, with XIP off: runs from RAM
/// (`.data`), calls only the ROM, touches no flash-resident data.
#[inline(never)]
#[link_section = ".data.ram_func"]
unsafe extern "C" fn flash_op_in_ram(f: &RomFns, addr: u32, data: *const u8, len: usize) {
    (f.connect)();
    (f.exit_xip)();
    if data.is_null() {
        // 4 KiB sector erase (command 0x20).
        (f.erase)(addr, len, SECTOR, 0x20);
    } else {
        (f.program)(addr, data, len);
    }
    (f.flush)();
    (f.enter_xip)();
    (f.boot2)();
}

/// The parameter store's flash: the last 8 KiB of the QSPI flash,
/// erased and programmed through the boot ROM with interrupts off (all
/// code but [`flash_op_in_ram`] lives in flash). A sector erase takes
/// ~45 ms (W25Q16JV, typ.); the tick catches up afterwards.
pub struct RomFlash {
    fns: RomFns,
}

/// Flash errors (only bounds and alignment: the ROM reports nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlashError {
    /// Outside the window or misaligned.
    Bad(NorFlashErrorKind),
}

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            FlashError::Bad(k) => *k,
        }
    }
}

impl RomFlash {
    /// Resolves the ROM functions and copies boot2 to RAM; call once at
    /// start-up, while XIP runs.
    pub fn new(boot2_ram: &'static mut [u32; 64]) -> RomFlash {
        for (i, w) in boot2_ram.iter_mut().enumerate() {
            // SAFETY: the first 256 bytes of flash are boot2.
            *w = unsafe { read_volatile((XIP_BASE as *const u32).add(i)) };
        }
        // SAFETY: boot2's entry is its first byte; a Thumb function.
        let boot2: unsafe extern "C" fn() =
            unsafe { core::mem::transmute(boot2_ram.as_ptr() as usize + 1) };
        RomFlash {
            fns: RomFns {
                connect: rom_data::connect_internal_flash::ptr(),
                exit_xip: rom_data::flash_exit_xip::ptr(),
                erase: rom_data::flash_range_erase::ptr(),
                program: rom_data::flash_range_program::ptr(),
                flush: rom_data::flash_flush_cache::ptr(),
                enter_xip: rom_data::flash_enter_cmd_xip::ptr(),
                boot2,
            },
        }
    }

    fn op(&mut self, addr: u32, data: *const u8, len: usize) {
        let fns = self.fns;
        cortex_m::interrupt::free(|_| {
            // SAFETY: interrupts are off, the other core is parked (never
            // started), the function and everything it uses are in RAM
            // or ROM.
            unsafe { flash_op_in_ram(&fns, PARAM_OFFSET + addr, data, len) }
        });
    }
}

impl ErrorType for RomFlash {
    type Error = FlashError;
}

fn check(offset: u32, len: usize, align: u32) -> Result<(), FlashError> {
    let end = offset as usize + len;
    if end > 8192 {
        return Err(FlashError::Bad(NorFlashErrorKind::OutOfBounds));
    }
    if !offset.is_multiple_of(align) || !len.is_multiple_of(align as usize) {
        return Err(FlashError::Bad(NorFlashErrorKind::NotAligned));
    }
    Ok(())
}

impl ReadNorFlash for RomFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        check(offset, bytes.len(), 1)?;
        let base = XIP_BASE + (PARAM_OFFSET + offset) as usize;
        for (i, b) in bytes.iter_mut().enumerate() {
            // SAFETY: inside the flash's XIP window.
            *b = unsafe { read_volatile((base + i) as *const u8) };
        }
        Ok(())
    }
    fn capacity(&self) -> usize {
        8192
    }
}

impl NorFlash for RomFlash {
    const WRITE_SIZE: usize = PAGE as usize;
    const ERASE_SIZE: usize = SECTOR as usize;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        check(from, (to - from) as usize, SECTOR)?;
        self.op(from, core::ptr::null(), (to - from) as usize);
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        check(offset, bytes.len(), PAGE)?;
        // The data must not come from flash (XIP is off meanwhile): a page
        // at a time through RAM.
        let mut page = [0u8; PAGE as usize];
        for (i, chunk) in bytes.chunks(PAGE as usize).enumerate() {
            page.copy_from_slice(chunk);
            self.op(offset + i as u32 * PAGE, page.as_ptr(), page.len());
        }
        Ok(())
    }
}
