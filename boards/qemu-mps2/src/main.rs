//! # imu-emu on QEMU's mps2-an386 (Cortex-M4F) — the CI board
//!
//! * UART0 carries the KERNEL protocol (with the `isb` feature: the ISB
//!   protocol of an emulated IMX-5, [`imu_emu::isb::Isb`], from 921 600
//!   bit/s);
//! * UART1 is the pin bridge (see [`bridge`] and this board's README): the host
//!   injects 1PPS/EXTRIG edges, BOOT level and power cycles, reads TOV edges
//!   and the tick's timing figures, and sends live motion samples
//!   (docs/feed.md, [`fw_shell::feed`]);
//! * TIMER0 interrupts at the internal rate (2 kHz; 4 kHz on the K201) and
//!   runs [`fw_shell::Shell::service`]; TIMER1 free-runs at 25 MHz as the
//!   time base;
//! * the flash is a [`imu_emu::nor::RamNor`] persisted to a host file over
//!   semihosting, so restarting QEMU is a power cycle;
//! * model, seed, flash file and BOOT come from the semihosting command line
//!   ([`config`]).
//!
//! RTIC 2 runs it: the tick at the top priority owns the device; the UART
//! RX interrupts only push into lock-free SPSC queues the tick drains.
#![no_std]
#![no_main]

mod board;
mod bridge;
mod config;
mod mps2;
mod semi;

use core::panic::PanicInfo;

// Paints the free RAM (end of statics up to just below the reset stack
// pointer) before RAM is initialised, so the stack high-water mark can be
// measured later ([`bridge::stack_used`]).
core::arch::global_asm!(
    ".section .text.__pre_init,\"ax\"",
    ".global __pre_init",
    ".type __pre_init,%function",
    ".thumb_func",
    "__pre_init:",
    "    ldr r0, =__sheap",
    "    mov r1, sp",
    "    subs r1, r1, #64",
    "    ldr r2, =0x5A5AA5A5",
    "1:  cmp r0, r1",
    "    bhs 2f",
    "    str r2, [r0]",
    "    adds r0, r0, #4",
    "    b 1b",
    "2:  bx lr",
);

#[rtic::app(device = crate::mps2, peripherals = false)]
mod app {
    use core::mem::MaybeUninit;

    use fw_shell::feed::FeedIn;
    use fw_shell::{Edge, Shell};
    use heapless::spsc::{Consumer, Producer, Queue};
    use imu_emu::device::{Device, PowerOn};

    use crate::board::{self, BridgeTov, Flash, Mps2Clock, Persist, Uart0};
    use crate::bridge::{self, Bridge};
    use crate::config::Config;
    use crate::mps2::{SYSCLK_HZ, TIMER0_REGS, UART0, UART1};
    use crate::semi;

    /// The shell as this board instantiates it.
    pub type BoardShell = Shell<
        'static,
        &'static mut Flash,
        Uart0,
        Mps2Clock,
        BridgeTov,
        Consumer<'static, Edge>,
        Proto,
    >;
    /// The device as this board instantiates it.
    pub type BoardDevice = Device<&'static mut Flash, Proto>;
    /// The image's protocol personality: the KERNEL.
    #[cfg(not(feature = "isb"))]
    pub type Proto = imu_emu::kernel::Kernel;
    /// The image's protocol personality: the IMX-5 over ISB.
    #[cfg(feature = "isb")]
    pub type Proto = imu_emu::isb::Isb;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        shell: BoardShell,
        persist: Persist,
        bridge: Bridge,
        rx_in: Producer<'static, u8>,
        edges_in: Producer<'static, Edge>,
        cmds_in: Producer<'static, u8>,
        feed: FeedIn,
        feed_in: Producer<'static, u8>,
        feed_out: Consumer<'static, u8>,
        split: bridge::Split,
    }

    #[init(local = [
        flash: MaybeUninit<Flash> = MaybeUninit::uninit(),
        device: MaybeUninit<BoardDevice> = MaybeUninit::uninit(),
        rxq: Queue<u8, 1024> = Queue::new(),
        edgeq: Queue<Edge, 64> = Queue::new(),
        cmdq: Queue<u8, 32> = Queue::new(),
        feedq: Queue<u8, 512> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut line = [0u8; 512];
        let n = semi::cmdline(&mut line);
        let text = core::str::from_utf8(&line[..n]).unwrap_or("");
        let cfg = match Config::parse(text) {
            Ok(c) => c,
            Err(e) => {
                semi::Line::default()
                    .str("imu-emu: bad argument \"")
                    .str(e.0)
                    .str("\"")
                    .eprintln();
                semi::exit(2);
            }
        };

        let flash = erased_flash(cx.local.flash);
        if let Some(path) = cfg.flash.as_ref() {
            Persist::load(path, flash);
        }
        let persist = Persist::new(cfg.flash.clone(), flash);

        let (rx_in, rx_out) = cx.local.rxq.split();
        let (edges_in, edges_out) = cx.local.edgeq.split();
        let (cmds_in, cmds_out) = cx.local.cmdq.split();
        let (feed_in, feed_out) = cx.local.feedq.split();

        board::start_clock();
        UART0.init(115_200);
        UART1.init(115_200);
        let dev = fw_shell::power_on(
            cx.local.device,
            PowerOn {
                product: cfg.product,
                boot: cfg.boot,
                seed: cfg.seed,
            },
            flash,
        );
        let uart = Uart0 {
            rx: rx_out,
            tx_lost: 0,
        };
        let shell = Shell::new(dev, uart, Mps2Clock, BridgeTov, edges_out);
        let period = SYSCLK_HZ / shell.tick_hz();
        TIMER0_REGS.start(period - 1, true);
        #[cfg(not(feature = "isb"))]
        let code = cfg.product.code();
        #[cfg(not(feature = "isb"))]
        let name = code.as_str();
        #[cfg(feature = "isb")]
        let name = "IMX-5 (ISB)";
        semi::Line::default()
            .str("imu-emu: ")
            .str(name)
            .str(" on mps2-an386, tick ")
            .dec(u64::from(shell.tick_hz()))
            .str(" Hz, ")
            .dec(u64::from(shell.device().line_rate()))
            .str(" bit/s")
            .eprintln();
        (
            Shared {},
            Local {
                shell,
                persist,
                bridge: Bridge::new(cmds_out, cfg.boot),
                rx_in,
                edges_in,
                cmds_in,
                feed: FeedIn::default(),
                feed_in,
                feed_out,
                split: bridge::Split::default(),
            },
        )
    }

    // Power-on is where the stack peaks: the big objects are built in
    // functions of their own (their frames are gone when init goes on)
    // straight into their statics, not moved through init's return value.

    #[inline(never)]
    fn erased_flash(slot: &'static mut MaybeUninit<Flash>) -> &'static mut Flash {
        slot.write(Flash::new())
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        // What power-on (init) used; then measure the running firmware
        // (interrupts nest on this same stack) from a fresh paint.
        bridge::repaint_stack();
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// The tick: the device's only owner.
    #[task(binds = TIMER0, priority = 3, local = [shell, persist, bridge, feed, feed_out])]
    fn tick(cx: tick::Context) {
        TIMER0_REGS.clear_irq();
        let shell = cx.local.shell;
        shell.feed(cx.local.feed, cx.local.feed_out);
        let persist = cx.local.persist;
        shell.service_with(|dev| persist.check(dev.flash()));
        cx.local.bridge.serve(shell);
    }

    /// Pin bridge RX: edges are stamped here, commands go to the tick,
    /// feed samples to the tick's feed queue.
    #[task(binds = UART1RX, priority = 2, local = [edges_in, cmds_in, feed_in, split])]
    fn bridge_rx(cx: bridge_rx::Context) {
        UART1.clear_rx_irq();
        while let Some(b) = UART1.get() {
            if cx.local.split.feed_byte(b) {
                // A full queue drops the byte (an overrun): the decoder
                // rejects the torn sample and resyncs.
                let _ = cx.local.feed_in.enqueue(b);
            } else {
                bridge::on_byte(b, cx.local.edges_in, cx.local.cmds_in);
            }
        }
    }

    /// KERNEL UART RX: bytes into the tick's queue.
    #[task(binds = UART0RX, priority = 1, local = [rx_in])]
    fn kernel_rx(cx: kernel_rx::Context) {
        UART0.clear_rx_irq();
        while let Some(b) = UART0.get() {
            // A full queue (the tick stalled for 1024 byte times) drops the
            // byte, as a UART overrun would.
            let _ = cx.local.rx_in.enqueue(b);
        }
    }
}

#[cortex_m_rt::exception]
unsafe fn HardFault(ef: &cortex_m_rt::ExceptionFrame) -> ! {
    semi::Line::default()
        .str("imu-emu: hard fault at pc ")
        .hex(ef.pc())
        .eprintln();
    semi::exit(3)
}

/// Reports where the panic happened and its message when that is a plain
/// string; a formatted message is not rendered, so the image carries no
/// `core::fmt` machinery (none of the firmware's own code panics).
#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    let mut line = semi::Line::default().str("imu-emu: panicked");
    if let Some(l) = info.location() {
        line = line
            .str(" at ")
            .str(l.file())
            .str(":")
            .dec(u64::from(l.line()));
    }
    if let Some(m) = info.message().as_str() {
        line = line.str(": ").str(m);
    }
    line.eprintln();
    semi::exit(1)
}
