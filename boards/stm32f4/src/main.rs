//! # imu-emu on an STM32F411 "Black Pill"
//!
//! Pinout (README "Flash it to a board"):
//!
//! | pin | function |
//! |---|---|
//! | PA9 / PA10 | USART1 TX / RX (AF7): the KERNEL UART, to an RS-422 transceiver |
//! | PA0 | 1PPS input, TIM2_CH1 capture (both edges) |
//! | PA1 | EXTRIG input, TIM2_CH2 capture (both edges) |
//! | PB0 | TOV output |
//! | PB1 | BOOT input, sampled at reset (driven high / low / floating) |
//!
//! Clocks: 25 MHz crystal → 100 MHz system, USART1 and timers at 100 MHz
//! (2 Mbit/s divides exactly). TIM3 interrupts at the internal rate (2 kHz;
//! 4 kHz on the K201) and runs the shell's tick service at the top
//! priority; TIM2 is the 10 MHz time base whose input captures stamp 1PPS
//! and EXTRIG edges in hardware. USART1 RX is a circular DMA ring the tick
//! drains, TX a DMA transfer the tick starts. Parameters live in flash
//! sectors 1–2 (memory.x keeps code out of them). Model and seed are fixed
//! at build time (`IMU_EMU_MODEL`, `IMU_EMU_SEED`, default K110 and 0).
#![no_std]
#![no_main]

mod hw;

use defmt_rtt as _;
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use core::mem::MaybeUninit;

    use fw_shell::{Edge, Shell};
    use heapless::spsc::{Consumer, Producer, Queue};
    use imu_emu::device::{Device, Level, Pin, PowerOn};
    use imu_emu::model::Product;
    use stm32f4xx_hal::flash::LockedFlash;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::Config;

    use crate::hw::{self, ParamFlash, Tim2Clock, TovPb0, Usart1Dma, RX_LEN, TX_LEN};

    type BoardDevice = Device<ParamFlash>;
    type BoardShell =
        Shell<'static, ParamFlash, Usart1Dma, Tim2Clock, TovPb0, Consumer<'static, Edge>>;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        shell: BoardShell,
        edges_in: Producer<'static, Edge>,
    }

    #[init(local = [
        device: MaybeUninit<BoardDevice> = MaybeUninit::uninit(),
        rx: [u8; RX_LEN] = [0; RX_LEN],
        tx: [u8; TX_LEN] = [0; TX_LEN],
        edgeq: Queue<Edge, 32> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut rcc = dp.RCC.freeze(
            Config::hse(25.MHz())
                .sysclk(100.MHz())
                .pclk1(50.MHz())
                .pclk2(100.MHz()),
        );
        hw::enable_clocks();
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let _tx = gpioa.pa9.into_alternate::<7>();
        let _rx = gpioa.pa10.into_alternate::<7>();
        let _pps = gpioa.pa0.into_alternate::<1>();
        let _extrig = gpioa.pa1.into_alternate::<1>();
        let tov = TovPb0(gpiob.pb0.into_push_pull_output());

        // BOOT: pulled up and then down; a driven pin reads the same both
        // times, a floating one follows the pull.
        let boot_pin = gpiob.pb1.into_pull_up_input();
        cortex_m::asm::delay(1000);
        let up = boot_pin.is_high();
        let boot_pin = boot_pin.into_pull_down_input();
        cortex_m::asm::delay(1000);
        let down = boot_pin.is_high();
        let boot = if up == down {
            fw_shell::boot_level(Some(up))
        } else {
            None
        };

        let product = Product::parse(option_env!("IMU_EMU_MODEL").unwrap_or("K110"))
            .unwrap_or_else(|_| panic!("IMU_EMU_MODEL is not a KERNEL model"));
        let seed = option_env!("IMU_EMU_SEED")
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let flash = ParamFlash(LockedFlash::new(dp.FLASH));
        let dev = fw_shell::power_on(
            cx.local.device,
            PowerOn {
                product,
                boot,
                seed,
            },
            flash,
        );

        hw::start_time_base();
        let uart = Usart1Dma::new(cx.local.rx, cx.local.tx, dev.line_rate());
        let (edges_in, edges_out) = cx.local.edgeq.split();
        let shell = Shell::new(dev, uart, Tim2Clock, tov, edges_out);
        hw::start_tick(shell.tick_hz());
        defmt::info!(
            "imu-emu: {} on STM32F411, BOOT {}, tick {} Hz",
            product.code().as_str(),
            match boot {
                None => "floating",
                Some(Level::High) => "high",
                Some(Level::Low) => "low",
            },
            shell.tick_hz()
        );
        (Shared {}, Local { shell, edges_in })
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// The tick: the device's only owner.
    #[task(binds = TIM3, priority = 3, local = [shell])]
    fn tick(cx: tick::Context) {
        hw::clear_tick();
        cx.local.shell.service();
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
