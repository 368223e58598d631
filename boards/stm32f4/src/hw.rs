//! Register-level pieces the HAL does not offer in the shape the shell
//! needs (register map: RM0383, STM32F411 reference manual): the USART1
//! DMA streams, the TIM2 time base with input capture, the TIM3 tick, and
//! the parameter window over the HAL's flash driver.

use core::cell::Cell;
use core::ptr::{read_volatile, write_volatile};

use critical_section::Mutex;
use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use fw_shell::{Clock, TovPin, Uart};
use imu_emu::device::Level;
use imu_emu::time::Instant;
use stm32f4xx_hal::flash::{FlashExt, LockedFlash};

/// System clock (and APB2; APB1 is half of it). The F411 runs at 100 MHz;
/// the F446's APB1 may not exceed 45 MHz, so it runs at 90 MHz. Either
/// divides 2 Mbit/s exactly (BRR 50 / 45) and gives whole timer prescalers.
#[cfg(feature = "black-pill")]
pub const SYSCLK_HZ: u32 = 100_000_000;
/// System clock (and APB2; APB1 is half of it): see the Black Pill's.
#[cfg(feature = "nucleo-f446re")]
pub const SYSCLK_HZ: u32 = 90_000_000;
/// APB1 limit of the chip (datasheets: F411 50 MHz, F446 45 MHz). The HAL
/// checks it only at run time, by panicking in init.
#[cfg(feature = "black-pill")]
const APB1_MAX_HZ: u32 = 50_000_000;
/// APB1 limit of the chip: see the Black Pill's.
#[cfg(feature = "nucleo-f446re")]
const APB1_MAX_HZ: u32 = 45_000_000;
const _: () = assert!(SYSCLK_HZ / 2 <= APB1_MAX_HZ, "APB1 over its limit");

/// Timer kernel clock: APB1 timers run at twice APB1 (its prescaler is 2).
pub const TIMER_CLK_HZ: u32 = SYSCLK_HZ;
/// USART1 kernel clock (APB2).
pub const USART1_CLK_HZ: u32 = SYSCLK_HZ;
/// TIM2 counts at 10 MHz: 100 ns per count.
const TIM2_HZ: u32 = 10_000_000;
const NS_PER_COUNT: u64 = 1_000_000_000 / TIM2_HZ as u64;

fn rd(addr: usize) -> u32 {
    // SAFETY: callers pass addresses of memory-mapped registers (RM0383).
    unsafe { read_volatile(addr as *const u32) }
}
fn wr(addr: usize, v: u32) {
    // SAFETY: as for `rd`.
    unsafe { write_volatile(addr as *mut u32, v) }
}
fn modify(addr: usize, f: impl FnOnce(u32) -> u32) {
    wr(addr, f(rd(addr)));
}

const RCC: usize = 0x4002_3800;
const RCC_AHB1ENR: usize = RCC + 0x30;
const RCC_APB1ENR: usize = RCC + 0x40;
const RCC_APB2ENR: usize = RCC + 0x44;

/// Clocks DMA2, TIM2, TIM3 and USART1.
pub fn enable_clocks() {
    modify(RCC_AHB1ENR, |v| v | 1 << 22); // DMA2EN
    modify(RCC_APB1ENR, |v| v | 1 << 0 | 1 << 1); // TIM2EN, TIM3EN
    modify(RCC_APB2ENR, |v| v | 1 << 4); // USART1EN
    let _ = rd(RCC_APB2ENR); // the clock is on after one more bus cycle
}

// ----- time base and capture: TIM2 (32-bit) -----

const TIM2: usize = 0x4000_0000;
const TIM3: usize = 0x4000_0400;
const CR1: usize = 0x00;
const DIER: usize = 0x0C;
const SR: usize = 0x10;
const EGR: usize = 0x14;
const CCMR1: usize = 0x18;
const CCER: usize = 0x20;
const CNT: usize = 0x24;
const PSC: usize = 0x28;
const ARR: usize = 0x2C;
const CCR1: usize = 0x34;
const CCR2: usize = 0x38;

/// `(last raw count, counts so far)`: TIM2 extended to 64 bits.
static TIME: Mutex<Cell<(u32, u64)>> = Mutex::new(Cell::new((0, 0)));

/// Starts TIM2 free-running at 10 MHz with CH1 (PA0, 1PPS) and CH2 (PA1,
/// EXTRIG) capturing both edges (input filter: 8 samples at the timer clock),
/// their interrupts on.
pub fn start_time_base() {
    wr(TIM2 + CR1, 0);
    wr(TIM2 + PSC, TIMER_CLK_HZ / TIM2_HZ - 1);
    wr(TIM2 + ARR, u32::MAX);
    // CC1S = 01 (TI1), IC1F = 0011; CC2S = 01 (TI2), IC2F = 0011.
    wr(TIM2 + CCMR1, 0b01 | 0b0011 << 4 | 0b01 << 8 | 0b0011 << 12);
    // CC1E | CC1P | CC1NP, CC2E | CC2P | CC2NP: both edges.
    wr(TIM2 + CCER, 1 | 1 << 1 | 1 << 3 | 1 << 4 | 1 << 5 | 1 << 7);
    wr(TIM2 + EGR, 1); // load the prescaler
    wr(TIM2 + SR, 0);
    wr(TIM2 + DIER, 1 << 1 | 1 << 2); // CC1IE, CC2IE
    wr(TIM2 + CR1, 1); // CEN
}

/// Extends a raw TIM2 count that lies at most 429 s before now.
fn extend(raw_then: u32) -> Instant {
    critical_section::with(|cs| {
        let cell = TIME.borrow(cs);
        let (last, total) = cell.get();
        let raw = rd(TIM2 + CNT);
        let total = total + u64::from(raw.wrapping_sub(last));
        cell.set((raw, total));
        let then = total - u64::from(raw.wrapping_sub(raw_then));
        Instant::from_nanos(then * NS_PER_COUNT)
    })
}

/// Now, in ns (any priority; read by the tick 2000 times a second, far more
/// often than TIM2's 429 s wrap).
pub fn now() -> Instant {
    extend(rd(TIM2 + CNT))
}

/// One capture event: which channel, the captured count's time.
pub fn take_capture() -> Option<(u8, Instant)> {
    let sr = rd(TIM2 + SR);
    if sr & 1 << 1 != 0 {
        let ccr = rd(TIM2 + CCR1); // reading CCR1 clears CC1IF
        return Some((1, extend(ccr)));
    }
    if sr & 1 << 2 != 0 {
        let ccr = rd(TIM2 + CCR2);
        return Some((2, extend(ccr)));
    }
    // Over-captures (an edge lost while the previous one was unread).
    wr(TIM2 + SR, !(1 << 9 | 1 << 10));
    None
}

/// The shell's clock.
pub struct Tim2Clock;
impl Clock for Tim2Clock {
    fn now(&mut self) -> Instant {
        now()
    }
}

// ----- the tick: TIM3 -----

/// TIM3 update interrupt at `hz` (1 MHz counter).
pub fn start_tick(hz: u32) {
    wr(TIM3 + CR1, 0);
    wr(TIM3 + PSC, TIMER_CLK_HZ / 1_000_000 - 1);
    wr(TIM3 + ARR, 1_000_000 / hz - 1);
    wr(TIM3 + EGR, 1);
    wr(TIM3 + SR, 0);
    wr(TIM3 + DIER, 1); // UIE
    wr(TIM3 + CR1, 1);
}

/// Acknowledges the tick interrupt.
pub fn clear_tick() {
    wr(TIM3 + SR, 0);
}

// ----- USART1 with DMA2 (RX stream 2 circular, TX stream 7), channel 4 -----

const USART1: usize = 0x4001_1000;
const USART_SR: usize = USART1;
const USART_DR: usize = USART1 + 0x04;
const USART_BRR: usize = USART1 + 0x08;
const USART_CR1: usize = USART1 + 0x0C;
const USART_CR3: usize = USART1 + 0x14;

const DMA2: usize = 0x4002_6400;
const DMA_LIFCR: usize = DMA2 + 0x08;
const DMA_HIFCR: usize = DMA2 + 0x0C;
const fn stream(n: usize) -> usize {
    DMA2 + 0x10 + 0x18 * n
}
const S_CR: usize = 0x00;
const S_NDTR: usize = 0x04;
const S_PAR: usize = 0x08;
const S_M0AR: usize = 0x0C;
const RX_STREAM: usize = 2;
const TX_STREAM: usize = 7;
const CHSEL4: u32 = 4 << 25;
const MINC: u32 = 1 << 10;
const CIRC: u32 = 1 << 8;
const DIR_M2P: u32 = 0b01 << 6;
const EN: u32 = 1;

/// RX ring size: 2.5 ms at 2 Mbit/s; the tick drains it every 0.5 ms.
pub const RX_LEN: usize = 512;
/// TX buffer: one DMA transfer.
pub const TX_LEN: usize = 256;

/// USART1 driven by DMA: RX into a circular ring the tick drains, TX
/// from a buffer the tick fills when the previous transfer is done.
pub struct Usart1Dma {
    rx: &'static mut [u8; RX_LEN],
    tx: &'static mut [u8; TX_LEN],
    /// Next unread ring index.
    rx_pos: usize,
}

impl Usart1Dma {
    /// Sets up USART1 (8N1 at `bps`) and both streams; PA9/PA10 must be in
    /// AF7 already.
    pub fn new(rx: &'static mut [u8; RX_LEN], tx: &'static mut [u8; TX_LEN], bps: u32) -> Self {
        wr(USART_CR1, 0);
        set_brr(bps);
        wr(USART_CR3, 1 << 6 | 1 << 7); // DMAR, DMAT
        wr(USART_CR1, 1 << 13 | 1 << 3 | 1 << 2); // UE, TE, RE

        let s = stream(RX_STREAM);
        wr(s + S_CR, 0);
        wr(DMA_LIFCR, 0x3D << 16);
        wr(s + S_PAR, USART_DR as u32);
        wr(s + S_M0AR, rx.as_mut_ptr() as u32);
        wr(s + S_NDTR, RX_LEN as u32);
        wr(s + S_CR, CHSEL4 | MINC | CIRC | EN);

        let s = stream(TX_STREAM);
        wr(s + S_CR, 0);
        wr(s + S_PAR, USART_DR as u32);
        Usart1Dma { rx, tx, rx_pos: 0 }
    }

    fn tx_busy(&self) -> bool {
        rd(stream(TX_STREAM) + S_CR) & EN != 0
    }
}

fn set_brr(bps: u32) {
    // Oversampling by 16: BRR = f_ck / baud (mantissa.fraction in 1/16).
    let bps = bps.max(1);
    wr(USART_BRR, (USART1_CLK_HZ + bps / 2) / bps);
}

impl Uart for Usart1Dma {
    fn read(&mut self, buf: &mut [u8]) -> usize {
        let head = RX_LEN - rd(stream(RX_STREAM) + S_NDTR) as usize;
        let head = head % RX_LEN;
        let mut n = 0;
        while self.rx_pos != head && n < buf.len() {
            // SAFETY: a byte the DMA has written (volatile: it keeps
            // writing the ring behind our back).
            buf[n] = unsafe { read_volatile(&self.rx[self.rx_pos]) };
            self.rx_pos = (self.rx_pos + 1) % RX_LEN;
            n += 1;
        }
        n
    }

    fn tx_room(&mut self) -> usize {
        if self.tx_busy() {
            0
        } else {
            TX_LEN
        }
    }

    fn write(&mut self, bytes: &[u8]) {
        let n = bytes.len().min(TX_LEN);
        self.tx[..n].copy_from_slice(&bytes[..n]);
        let s = stream(TX_STREAM);
        wr(DMA_HIFCR, 0x3D << 22);
        wr(USART_SR, !(1 << 6)); // clear TC
        wr(s + S_M0AR, self.tx.as_ptr() as u32);
        wr(s + S_NDTR, n as u32);
        cortex_m::asm::dmb();
        wr(s + S_CR, CHSEL4 | MINC | DIR_M2P | EN);
    }

    fn tx_idle(&mut self) -> bool {
        !self.tx_busy() && rd(USART_SR) & 1 << 6 != 0
    }

    fn set_baud(&mut self, bps: u32) {
        set_brr(bps);
    }
}

// ----- USART2: the live motion feed (RX only, interrupt per byte) -----

const USART2: usize = 0x4000_4400;
/// The feed's line rate, bit/s (docs/feed.md).
pub const FEED_BAUD: u32 = 921_600;

/// Sets up USART2 (8N1 at [`FEED_BAUD`], receiver only, RXNE interrupt);
/// PA3 must be in AF7 already. APB1 runs at half the system clock.
pub fn start_feed_uart() {
    modify(RCC_APB1ENR, |v| v | 1 << 17); // USART2EN
    let _ = rd(RCC_APB1ENR);
    wr(USART2 + 0x0C, 0);
    wr(USART2 + 0x08, (SYSCLK_HZ / 2 + FEED_BAUD / 2) / FEED_BAUD);
    wr(USART2 + 0x0C, 1 << 13 | 1 << 5 | 1 << 2); // UE, RXNEIE, RE
}

/// A byte USART2 received, if any (reading DR also clears an overrun).
pub fn feed_byte() -> Option<u8> {
    let sr = rd(USART2);
    // RXNE, or ORE (an overrun: the byte in DR is still read, the lost
    // ones make a torn sample the decoder rejects).
    (sr & (1 << 5 | 1 << 3) != 0).then(|| rd(USART2 + 0x04) as u8)
}

// ----- TOV -----

/// TOV on PB0.
pub struct TovPb0(pub stm32f4xx_hal::gpio::PB0<stm32f4xx_hal::gpio::Output>);
impl TovPin for TovPb0 {
    fn set(&mut self, level: Level) {
        match level {
            Level::High => self.0.set_high(),
            Level::Low => self.0.set_low(),
        }
    }
}

// ----- parameters: flash sectors 1 and 2 -----

/// Flash offset of the parameter window: sector 1 (0x0800_4000).
pub const PARAM_OFFSET: u32 = 0x4000;
/// Sectors 1 and 2 are 16 KiB each.
pub const PARAM_SECTOR: u32 = 16 * 1024;

/// The two 16 KiB sectors reserved for parameters (memory.x keeps code out
/// of them), as the store's `NorFlash` at offset 0, over the HAL's flash
/// driver (`LockedFlash`, unlocked per operation). Erasing one sector stalls
/// the CPU for ~250 ms (RM0383: 16 KiB, ×32 parallelism); the tick catches
/// up afterwards.
pub struct ParamFlash(pub LockedFlash);

/// Flash driver error.
pub type FlashError = stm32f4xx_hal::flash::Error;

impl ErrorType for ParamFlash {
    type Error = FlashError;
}

impl ReadNorFlash for ParamFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        ReadNorFlash::read(&mut self.0, PARAM_OFFSET + offset, bytes)
    }
    fn capacity(&self) -> usize {
        2 * PARAM_SECTOR as usize
    }
}

impl NorFlash for ParamFlash {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = PARAM_SECTOR as usize;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        let mut unlocked = self.0.unlocked();
        let mut at = from;
        while at < to {
            unlocked.erase(1 + (at / PARAM_SECTOR) as u8)?;
            at += PARAM_SECTOR;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        self.0
            .unlocked()
            .program((PARAM_OFFSET + offset) as usize, bytes.iter())
    }
}

/// The level of pin PA`n` (GPIOA IDR; it reads the pin in any mode).
pub fn pa_high(n: u32) -> bool {
    rd(0x4002_0000 + 0x10) & 1 << n != 0
}
