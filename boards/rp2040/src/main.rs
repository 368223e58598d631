//! # imu-emu on a Raspberry Pi Pico (RP2040)
//!
//! Pinout (docs/firmware.md "Flash it to a board"):
//!
//! | pin | function |
//! |---|---|
//! | GP0 / GP1 | UART0 TX / RX: the KERNEL UART, to an RS-422 transceiver |
//! | GP2 | 1PPS input (edge interrupt, stamped with the µs timer) |
//! | GP3 | EXTRIG input (likewise) |
//! | GP4 | TOV output |
//! | GP5 | BOOT input, sampled at reset (driven high / low / floating) |
//! | GP9 (GP8) | UART1 RX (TX unused), 921 600 bit/s 8N1: the live motion feed (docs/feed.md) |
//!
//! Clocks: 12 MHz crystal → 125 MHz system and `clk_peri`. TIMER ALARM0
//! interrupts at the internal rate (2 kHz; 4 kHz on the K201) and runs the
//! shell's tick service at the top priority; the 64-bit µs TIMER is the
//! time base. UART0 RX interrupts fill a ring the tick drains, TX writes the
//! 32-byte FIFO. Parameters live in the last 8 KiB of the flash, written
//! through the boot ROM (src/hw.rs). The core runs its fixed-point FIR
//! (`fixed-point` feature: no FPU). Model and seed are fixed at build time
//! (`IMU_EMU_MODEL`, `IMU_EMU_SEED`, default K110 and 0).
#![no_std]
#![no_main]

mod hw;

use defmt_rtt as _;

/// Logs the panic in one defmt line ([`fw_shell::panic`]: no `core::fmt`),
/// then stops at `udf` (probe-rs shows the backtrace).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    fw_shell::panic::log(info);
    cortex_m::asm::udf()
}

/// The second-stage bootloader for the Pico's W25Q16JV flash.
#[link_section = ".boot2"]
#[used]
pub static BOOT2_FIRMWARE: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

#[rtic::app(device = rp2040_hal::pac, peripherals = true)]
mod app {
    use core::mem::MaybeUninit;

    use embedded_hal::digital::{InputPin, OutputPin};
    use fw_shell::feed::FeedIn;
    use fw_shell::image::{self, Proto};
    use fw_shell::{Edge, Shell, TovPin};
    use heapless::spsc::{Consumer, Producer, Queue};
    use imu_emu::device::{Device, Level, Pin};
    use rp2040_hal::clocks::{self, Clock as _};
    use rp2040_hal::fugit::RateExtU32;
    use rp2040_hal::gpio::{
        self, FunctionSio, FunctionUart, Interrupt, Pins, PullDown, SioInput, SioOutput,
    };
    use rp2040_hal::uart::{DataBits, StopBits, UartConfig, UartPeripheral};
    use rp2040_hal::{Sio, Timer, Watchdog};

    use crate::hw::{self, RomFlash, Tick, TimerClock, Uart0};

    type TovGpio = gpio::Pin<gpio::bank0::Gpio4, FunctionSio<SioOutput>, PullDown>;
    type PpsGpio = gpio::Pin<gpio::bank0::Gpio2, FunctionSio<SioInput>, PullDown>;
    type ExtrigGpio = gpio::Pin<gpio::bank0::Gpio3, FunctionSio<SioInput>, PullDown>;

    /// TOV on GP4.
    pub struct Tov(TovGpio);
    impl TovPin for Tov {
        fn set(&mut self, level: Level) {
            let _ = match level {
                Level::High => self.0.set_high(),
                Level::Low => self.0.set_low(),
            };
        }
    }

    type BoardDevice = Device<RomFlash, Proto>;
    type BoardShell =
        Shell<'static, RomFlash, Uart0, TimerClock, Tov, Consumer<'static, Edge>, Proto>;
    /// The RX ring between the UART interrupt and the tick: ≈ 5 ms of the
    /// fastest line a stalled tick must survive (KERNEL: 2 Mbit/s, 1024 B;
    /// ISB: 921 600 bit/s, 512 B — which keeps the ISB image's static RAM
    /// under the 20 KiB budget of the time: its device is 17 040 B, 688 B more than
    /// the KERNEL's, with its 2 KiB packet buffer and the chain's
    /// cumulative integrals).
    #[cfg(not(feature = "isb"))]
    const RXQ: usize = 1024;
    /// The RX ring (see the KERNEL image's).
    #[cfg(feature = "isb")]
    const RXQ: usize = 512;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        shell: BoardShell,
        tick: Tick,
        rx_in: Producer<'static, u8>,
        edges_in: Producer<'static, Edge>,
        pps: PpsGpio,
        extrig: ExtrigGpio,
        feed: FeedIn,
        feed_in: Producer<'static, u8>,
        feed_out: Consumer<'static, u8>,
    }

    #[init(local = [
        device: MaybeUninit<BoardDevice> = MaybeUninit::uninit(),
        boot2: [u32; 64] = [0; 64],
        rxq: Queue<u8, RXQ> = Queue::new(),
        edgeq: Queue<Edge, 32> = Queue::new(),
        feedq: Queue<u8, 256> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut pac = cx.device;
        let mut watchdog = Watchdog::new(pac.WATCHDOG);
        let clocks = clocks::init_clocks_and_plls(
            12_000_000,
            pac.XOSC,
            pac.CLOCKS,
            pac.PLL_SYS,
            pac.PLL_USB,
            &mut pac.RESETS,
            &mut watchdog,
        )
        .unwrap_or_else(|_| panic!("clock setup"));
        let sio = Sio::new(pac.SIO);
        let pins = Pins::new(
            pac.IO_BANK0,
            pac.PADS_BANK0,
            sio.gpio_bank0,
            &mut pac.RESETS,
        );
        // Out of reset; the shell reads the counter directly.
        let _timer = Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);

        // BOOT: read pulled up and then down (`image::boot_from_pulls`).
        let mut boot_pin = pins.gpio5.into_pull_up_input();
        cortex_m::asm::delay(2000);
        let up = boot_pin.is_high().unwrap_or(false);
        let mut boot_pin = boot_pin.into_pull_down_input();
        cortex_m::asm::delay(2000);
        let down = boot_pin.is_high().unwrap_or(false);
        let boot = image::boot_from_pulls(up, down);

        let clk_hz = clocks.peripheral_clock.freq().to_Hz();
        let uart_pins = (
            pins.gpio0.into_function::<FunctionUart>(),
            pins.gpio1.into_function::<FunctionUart>(),
        );
        let _uart = UartPeripheral::new(pac.UART0, uart_pins, &mut pac.RESETS)
            .enable(
                UartConfig::new(115_200.Hz(), DataBits::Eight, None, StopBits::One),
                clocks.peripheral_clock.freq(),
            )
            .unwrap_or_else(|_| panic!("uart setup"));
        Uart0::enable_rx_irq();
        let feed_pins = (
            pins.gpio8.into_function::<FunctionUart>(),
            pins.gpio9.into_function::<FunctionUart>(),
        );
        let _feed_uart = UartPeripheral::new(pac.UART1, feed_pins, &mut pac.RESETS)
            .enable(
                UartConfig::new(921_600.Hz(), DataBits::Eight, None, StopBits::One),
                clocks.peripheral_clock.freq(),
            )
            .unwrap_or_else(|_| panic!("feed uart setup"));
        hw::enable_rx_irq(hw::UART1);
        let (feed_in, feed_out) = cx.local.feedq.split();

        let pps = pins.gpio2.into_pull_down_input();
        let extrig = pins.gpio3.into_pull_down_input();
        for i in [Interrupt::EdgeHigh, Interrupt::EdgeLow] {
            pps.set_interrupt_enabled(i, true);
            extrig.set_interrupt_enabled(i, true);
        }
        let tov = Tov(pins.gpio4.into_push_pull_output());

        // The product, seed and personality the image is built as.
        let cfg = image::power_on_config(boot);
        let flash = RomFlash::new(cx.local.boot2);
        let dev = fw_shell::power_on(cx.local.device, cfg, flash);
        // No FPU: the IMX-5's navigation filter (soft double and single
        // precision) does not fit a 62 500-cycle tick, so this image serves
        // the IMX-5 without it (docs/navigation.md "Firmware cost").
        #[cfg(feature = "isb")]
        dev.personality_mut().set_navigation(false);
        let (rx_in, rx_out) = cx.local.rxq.split();
        let (edges_in, edges_out) = cx.local.edgeq.split();
        let uart = Uart0 { rx: rx_out, clk_hz };
        let shell = Shell::new(dev, uart, TimerClock, tov, edges_out);
        let tick = Tick::start(shell.tick_hz());
        defmt::info!(
            "imu-emu: {} on RP2040, tick {} Hz",
            cfg.product.code().as_str(),
            shell.tick_hz()
        );
        (
            Shared {},
            Local {
                shell,
                tick,
                rx_in,
                edges_in,
                pps,
                extrig,
                feed: FeedIn::default(),
                feed_in,
                feed_out,
            },
        )
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// The tick: the device's only owner.
    #[task(binds = TIMER_IRQ_0, priority = 3, local = [shell, tick, feed, feed_out])]
    fn tick(cx: tick::Context) {
        cx.local.tick.rearm();
        let shell = cx.local.shell;
        shell.feed(cx.local.feed, cx.local.feed_out);
        shell.service();
    }

    /// Motion feed RX (UART1): the FIFO into the tick's feed queue.
    #[task(binds = UART1_IRQ, priority = 1, local = [feed_in])]
    fn feed_rx(cx: feed_rx::Context) {
        hw::uart_rx(hw::UART1, cx.local.feed_in);
    }

    /// KERNEL UART RX: the FIFO into the tick's ring.
    #[task(binds = UART0_IRQ, priority = 2, local = [rx_in])]
    fn uart_rx(cx: uart_rx::Context) {
        hw::uart0_rx(cx.local.rx_in);
    }

    /// 1PPS / EXTRIG edges, stamped here with the µs timer.
    #[task(binds = IO_IRQ_BANK0, priority = 2, local = [edges_in, pps, extrig])]
    fn pins(cx: pins::Context) {
        let at = hw::now();
        let l = cx.local;
        for (i, level) in [
            (Interrupt::EdgeHigh, Level::High),
            (Interrupt::EdgeLow, Level::Low),
        ] {
            if l.pps.interrupt_status(i) {
                l.pps.clear_interrupt(i);
                let _ = l.edges_in.enqueue(Edge {
                    pin: Pin::Pps,
                    level,
                    at,
                });
            }
            if l.extrig.interrupt_status(i) {
                l.extrig.clear_interrupt(i);
                let _ = l.edges_in.enqueue(Edge {
                    pin: Pin::Extrig,
                    level,
                    at,
                });
            }
        }
    }
}
