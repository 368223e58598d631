//! A minimal hand-written device module for the MPS2+ AN386 FPGA image as
//! QEMU models it (`-machine mps2-an386`): the interrupt numbers RTIC needs,
//! the vector table, and the two CMSDK peripherals the firmware uses.
//!
//! Facts (ARM AN386 / QEMU `hw/arm/mps2.c`, CMSDK TRM):
//! * system clock 25 MHz, feeds both CMSDK timers and the UARTs;
//! * UART0 0x4000_4000 (RX IRQ 0, TX IRQ 1), UART1 0x4000_5000 (2, 3),
//!   UART2 0x4000_6000 (4, 5); the UART overflow IRQs are ORed into IRQ 12;
//! * TIMER0 0x4000_0000 (IRQ 8), TIMER1 0x4000_1000 (IRQ 9), dual timer
//!   0x4000_2000 (IRQ 10);
//! * the Cortex-M4 of the real AN386 implements 3 priority bits.

use core::ptr::{read_volatile, write_volatile};

/// Priority bits of the NVIC (AN386: 3).
pub const NVIC_PRIO_BITS: u8 = 3;

/// System clock, Hz.
pub const SYSCLK_HZ: u32 = 25_000_000;

/// External interrupts of the AN386 image (the ones this firmware knows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u16)]
#[allow(
    non_camel_case_types,
    clippy::upper_case_acronyms,
    missing_docs,
    dead_code
)]
pub enum Interrupt {
    UART0RX = 0,
    UART0TX = 1,
    UART1RX = 2,
    UART1TX = 3,
    UART2RX = 4,
    UART2TX = 5,
    TIMER0 = 8,
    TIMER1 = 9,
    DUALTIMER = 10,
    UARTOVF = 12,
}

// SAFETY: the discriminants are the AN386 IRQ numbers.
unsafe impl cortex_m::interrupt::InterruptNumber for Interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

/// What RTIC looks interrupts up by (PACs re-export the enum this way).
pub use Interrupt as interrupt;

/// An entry of the vector table.
#[derive(Clone, Copy)]
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: usize,
}

extern "C" {
    fn UART0RX();
    fn UART0TX();
    fn UART1RX();
    fn UART1TX();
    fn UART2RX();
    fn UART2TX();
    fn TIMER0();
    fn TIMER1();
    fn DUALTIMER();
    fn UARTOVF();
}

/// The device part of the vector table (cortex-m-rt's `device` feature);
/// `device.x` points every handler not defined by the app at
/// `DefaultHandler`.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
pub static __INTERRUPTS: [Vector; 16] = [
    Vector { handler: UART0RX },
    Vector { handler: UART0TX },
    Vector { handler: UART1RX },
    Vector { handler: UART1TX },
    Vector { handler: UART2RX },
    Vector { handler: UART2TX },
    Vector { reserved: 0 },
    Vector { reserved: 0 },
    Vector { handler: TIMER0 },
    Vector { handler: TIMER1 },
    Vector { handler: DUALTIMER },
    Vector { reserved: 0 },
    Vector { handler: UARTOVF },
    Vector { reserved: 0 },
    Vector { reserved: 0 },
    Vector { reserved: 0 },
];

/// A CMSDK APB UART.
#[derive(Debug, Clone, Copy)]
pub struct CmsdkUart {
    base: usize,
}

/// UART0: the KERNEL protocol.
pub const UART0: CmsdkUart = CmsdkUart { base: 0x4000_4000 };
/// UART1: the pin bridge.
pub const UART1: CmsdkUart = CmsdkUart { base: 0x4000_5000 };

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const STATE_TXFULL: u32 = 1 << 0;
const STATE_RXFULL: u32 = 1 << 1;
const CTRL_TXEN: u32 = 1 << 0;
const CTRL_RXEN: u32 = 1 << 1;
const CTRL_RXINTEN: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;

impl CmsdkUart {
    fn read(self, off: usize) -> u32 {
        // SAFETY: an MMIO register of this UART.
        unsafe { read_volatile((self.base + off) as *const u32) }
    }
    fn write(self, off: usize, v: u32) {
        // SAFETY: an MMIO register of this UART.
        unsafe { write_volatile((self.base + off) as *mut u32, v) }
    }

    /// Enables TX and RX with the RX interrupt at `bps`.
    pub fn init(self, bps: u32) {
        self.set_baud(bps);
        self.write(CTRL, CTRL_TXEN | CTRL_RXEN | CTRL_RXINTEN);
    }

    /// Sets the divider (the CMSDK minimum is 16: at 25 MHz the fastest
    /// real rate is 1.5625 Mbit/s; QEMU's UART carries any rate instantly,
    /// so faster rates are clamped, and the line rate is kept by pacing).
    pub fn set_baud(self, bps: u32) {
        let div = (SYSCLK_HZ / bps.max(1)).max(16);
        self.write(BAUDDIV, div);
    }

    /// Whether a byte can be written now.
    pub fn tx_ready(self) -> bool {
        self.read(STATE) & STATE_TXFULL == 0
    }

    /// Writes a byte (the caller checked [`CmsdkUart::tx_ready`]).
    pub fn put(self, b: u8) {
        self.write(DATA, u32::from(b));
    }

    /// Writes a byte, waiting a bounded while for room; whether it went.
    pub fn put_wait(self, b: u8) -> bool {
        for _ in 0..10_000 {
            if self.tx_ready() {
                self.put(b);
                return true;
            }
        }
        false
    }

    /// A received byte, if any.
    pub fn get(self) -> Option<u8> {
        if self.read(STATE) & STATE_RXFULL != 0 {
            Some(self.read(DATA) as u8)
        } else {
            None
        }
    }

    /// Acknowledges the RX interrupt.
    pub fn clear_rx_irq(self) {
        self.write(INTCLEAR, INT_RX);
    }
}

/// A CMSDK APB timer (32-bit down-counter at the system clock).
#[derive(Debug, Clone, Copy)]
pub struct CmsdkTimer {
    base: usize,
}

/// TIMER0: the tick.
pub const TIMER0_REGS: CmsdkTimer = CmsdkTimer { base: 0x4000_0000 };
/// TIMER1: the free-running time base.
pub const TIMER1_REGS: CmsdkTimer = CmsdkTimer { base: 0x4000_1000 };

const T_CTRL: usize = 0x00;
const T_VALUE: usize = 0x04;
const T_RELOAD: usize = 0x08;
const T_INTCLEAR: usize = 0x0C;
const T_CTRL_EN: u32 = 1 << 0;
const T_CTRL_IRQEN: u32 = 1 << 3;

impl CmsdkTimer {
    fn read(self, off: usize) -> u32 {
        // SAFETY: an MMIO register of this timer.
        unsafe { read_volatile((self.base + off) as *const u32) }
    }
    fn write(self, off: usize, v: u32) {
        // SAFETY: an MMIO register of this timer.
        unsafe { write_volatile((self.base + off) as *mut u32, v) }
    }

    /// Starts counting down from `reload`, reloading at zero; `irq`
    /// raises the timer's interrupt at every reload.
    pub fn start(self, reload: u32, irq: bool) {
        self.write(T_CTRL, 0);
        self.write(T_RELOAD, reload);
        self.write(T_VALUE, reload);
        self.write(T_INTCLEAR, 1);
        self.write(T_CTRL, T_CTRL_EN | if irq { T_CTRL_IRQEN } else { 0 });
    }

    /// The counter.
    pub fn value(self) -> u32 {
        self.read(T_VALUE)
    }

    /// Acknowledges the interrupt.
    pub fn clear_irq(self) {
        self.write(T_INTCLEAR, 1);
    }
}
