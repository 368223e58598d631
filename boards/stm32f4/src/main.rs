//! # imu-emu on an STM32F411 "Black Pill" or a Nucleo-F446RE
//!
//! One image per board, chosen by cargo feature: `black-pill` (default) or
//! `nucleo-f446re`. Both chips have the same peripherals at the same
//! addresses for everything used here (USART1, DMA2, TIM2/3, GPIOA/B,
//! flash sectors 0–3 of 16 KiB), so only the clock source differs.
//!
//! Pinout (docs/firmware.md "Flash it to a board"):
//!
//! | pin | function |
//! |---|---|
//! | PA9 / PA10 | USART1 TX / RX (AF7): the KERNEL UART, to an RS-422 transceiver |
//! | PA3 | USART2 RX (AF7), 921 600 bit/s 8N1: the live motion feed (docs/feed.md; on the Nucleo the ST-LINK's virtual COM port) |
//! | PA0 | 1PPS input, TIM2_CH1 capture (both edges) |
//! | PA1 | EXTRIG input, TIM2_CH2 capture (both edges) |
//! | PB0 | TOV output |
//! | PB1 | BOOT input, sampled at reset (driven high / low / floating) |
//!
//! Clocks: 25 MHz crystal (Black Pill) or the ST-LINK's 8 MHz MCO (Nucleo,
//! HSE bypass) → 100 MHz system (90 MHz on the F446, whose APB1 stops at
//! 45 MHz), USART1 and timers at the system clock (2 Mbit/s divides
//! exactly). TIM3 interrupts at the internal rate (2 kHz;
//! 4 kHz on the K201) and runs the shell's tick service at the top
//! priority; TIM2 is the 10 MHz time base whose input captures stamp 1PPS
//! and EXTRIG edges in hardware. USART1 RX is a circular DMA ring the tick
//! drains, TX a DMA transfer the tick starts. Parameters live in flash
//! sectors 1–2 (memory.x keeps code out of them). Model and seed are fixed
//! at build time (`IMU_EMU_MODEL`, `IMU_EMU_SEED`, default K110 and 0).
#![no_std]
#![no_main]

#[cfg(all(feature = "black-pill", feature = "nucleo-f446re"))]
compile_error!("choose one board: --no-default-features --features nucleo-f446re");
#[cfg(not(any(feature = "black-pill", feature = "nucleo-f446re")))]
compile_error!("choose a board feature: black-pill or nucleo-f446re");

mod hw;

use defmt_rtt as _;

/// Logs the panic in one defmt line ([`fw_shell::panic`]: no `core::fmt`),
/// then stops at `udf` (probe-rs shows the backtrace).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    fw_shell::panic::log(info);
    cortex_m::asm::udf()
}

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use core::mem::MaybeUninit;

    use fw_shell::feed::FeedIn;
    use fw_shell::image::{self, Proto};
    use fw_shell::{Edge, Shell};
    use heapless::spsc::{Consumer, Producer, Queue};
    use imu_emu::device::{Device, Level, Pin};
    use stm32f4xx_hal::flash::LockedFlash;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::Config;

    use crate::hw::{self, ParamFlash, Tim2Clock, TovPb0, Usart1Dma, RX_LEN, TX_LEN};

    /// The board this image is for (the boot log names it).
    #[cfg(feature = "black-pill")]
    const BOARD: &str = "STM32F411 Black Pill";
    /// The board this image is for (the boot log names it).
    #[cfg(feature = "nucleo-f446re")]
    const BOARD: &str = "Nucleo-F446RE";

    type BoardDevice = Device<ParamFlash, Proto>;
    type BoardShell =
        Shell<'static, ParamFlash, Usart1Dma, Tim2Clock, TovPb0, Consumer<'static, Edge>, Proto>;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        shell: BoardShell,
        edges_in: Producer<'static, Edge>,
        feed: FeedIn,
        feed_in: Producer<'static, u8>,
        feed_out: Consumer<'static, u8>,
    }

    #[init(local = [
        device: MaybeUninit<BoardDevice> = MaybeUninit::uninit(),
        rx: [u8; RX_LEN] = [0; RX_LEN],
        tx: [u8; TX_LEN] = [0; TX_LEN],
        edgeq: Queue<Edge, 32> = Queue::new(),
        feedq: Queue<u8, 256> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        // System and APB2 at hw::SYSCLK_HZ, APB1 at half of it (its
        // timers run at twice APB1: hw::TIMER_CLK_HZ = SYSCLK_HZ).
        #[cfg(feature = "black-pill")]
        let hse = Config::hse(25.MHz());
        #[cfg(feature = "nucleo-f446re")]
        let hse = Config::hse(8.MHz()).bypass_hse_oscillator();
        let mut rcc = dp.RCC.freeze(
            hse.sysclk(hw::SYSCLK_HZ.Hz())
                .pclk1((hw::SYSCLK_HZ / 2).Hz())
                .pclk2(hw::SYSCLK_HZ.Hz()),
        );
        hw::enable_clocks();
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let _tx = gpioa.pa9.into_alternate::<7>();
        let _rx = gpioa.pa10.into_alternate::<7>();
        let _pps = gpioa.pa0.into_alternate::<1>();
        let _extrig = gpioa.pa1.into_alternate::<1>();
        let _feed_rx = gpioa.pa3.into_alternate::<7>();
        let tov = TovPb0(gpiob.pb0.into_push_pull_output());

        // BOOT: read pulled up and then down (`image::boot_from_pulls`).
        let boot_pin = gpiob.pb1.into_pull_up_input();
        cortex_m::asm::delay(1000);
        let up = boot_pin.is_high();
        let boot_pin = boot_pin.into_pull_down_input();
        cortex_m::asm::delay(1000);
        let down = boot_pin.is_high();
        let boot = image::boot_from_pulls(up, down);

        // The product, seed and personality the image is built as.
        let cfg = image::power_on_config(boot);
        let flash = ParamFlash(LockedFlash::new(dp.FLASH));
        let dev = fw_shell::power_on(cx.local.device, cfg, flash);

        hw::start_time_base();
        let uart = Usart1Dma::new(cx.local.rx, cx.local.tx, dev.line_rate());
        let (edges_in, edges_out) = cx.local.edgeq.split();
        let (feed_in, feed_out) = cx.local.feedq.split();
        hw::start_feed_uart();
        let shell = Shell::new(dev, uart, Tim2Clock, tov, edges_out);
        hw::start_tick(shell.tick_hz());
        defmt::info!(
            "imu-emu: {} on {}, BOOT {}, tick {} Hz",
            cfg.product.code().as_str(),
            BOARD,
            match boot {
                None => "floating",
                Some(Level::High) => "high",
                Some(Level::Low) => "low",
            },
            shell.tick_hz()
        );
        (
            Shared {},
            Local {
                shell,
                edges_in,
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
    #[task(binds = TIM3, priority = 3, local = [shell, feed, feed_out])]
    fn tick(cx: tick::Context) {
        hw::clear_tick();
        let shell = cx.local.shell;
        shell.feed(cx.local.feed, cx.local.feed_out);
        shell.service();
    }

    /// The motion feed's bytes (USART2 RX) into the tick's queue; a full
    /// queue drops the byte, as an overrun would.
    #[task(binds = USART2, priority = 1, local = [feed_in])]
    fn feed_rx(cx: feed_rx::Context) {
        while let Some(b) = hw::feed_byte() {
            let _ = cx.local.feed_in.enqueue(b);
        }
    }

    /// 1PPS / EXTRIG edges: the time comes from the capture register; the
    /// level is read right after (edges closer than this ISR's latency
    /// report the later level).
    #[task(binds = TIM2, priority = 2, local = [edges_in])]
    fn capture(cx: capture::Context) {
        while let Some((ch, at)) = hw::take_capture() {
            let (pin, high) = match ch {
                1 => (Pin::Pps, hw::pa_high(0)),
                _ => (Pin::Extrig, hw::pa_high(1)),
            };
            let level = if high { Level::High } else { Level::Low };
            let _ = cx.local.edges_in.enqueue(Edge { pin, level, at });
        }
    }
}
