//! The pin bridge on UART1: a one-byte-per-event line protocol.
//!
//! Host → firmware:
//!
//! | byte | meaning |
//! |---|---|
//! | `P` / `p` | 1PPS goes high / low (stamped when the byte arrives) |
//! | `E` / `e` | EXTRIG goes high / low (stamped likewise) |
//! | `B` / `b` / `f` | BOOT is high / low / floating at the next power-on |
//! | `R` | power cycle now (RAM reloads from flash, BOOT is sampled) |
//! | `S` | report the tick's timing figures (one text line, below) |
//! | `Z` | zero the timing figures |
//!
//! Firmware → host: `T` / `t` when TOV goes high / low; `R` after a power
//! cycle; and for `S` one line
//! `S ticks=… services=… on_tick_max_ns=… tick_max_ns=… service_max_ns=…
//! service_batch_max_ns=… service_rx_max_ns=… batch_max=… tx=… rx=…
//! dropped=… stack=… stack_init=…\n` — the fields of `fw_shell::Stats`
//! (`stack` = the running firmware's stack high-water mark in bytes,
//! `stack_init` = what power-on used). Other bytes are ignored.
//!
//! The same UART carries the live motion feed's binary samples
//! (docs/feed.md): a byte `F5` (never a command) starts a sample, and the
//! sample's bytes — its length is in its fifth byte — go to the feed
//! queue instead of being read as commands ([`Split`]). The tick decodes
//! them ([`fw_shell::Shell::feed`]).

use fw_shell::Edge;
use heapless::spsc::{Consumer, Producer};
use imu_emu::device::{Level, Pin};

use crate::app::BoardShell;
use crate::board;
use crate::mps2::UART1;
use crate::semi;

/// Where a byte of the bridge UART goes: commands and edges, or a feed
/// sample (ISR side).
#[derive(Debug, Clone, Copy, Default)]
pub enum Split {
    /// Between samples: bytes are commands (or start a sample).
    #[default]
    Commands,
    /// Inside a sample's header: bytes left of sync, version, kind, length.
    Head(u8),
    /// Inside a sample's body and checksum: bytes left.
    Body(u8),
}

impl Split {
    /// Whether `b` belongs to a feed sample (then it goes to the feed
    /// queue); updates the state.
    pub fn feed_byte(&mut self, b: u8) -> bool {
        use imu_emu::feed::{CRC_LEN, HEAD, MAX_BODY, SYNC};
        *self = match *self {
            Split::Commands if b == SYNC[0] => Split::Head(HEAD as u8 - 1),
            Split::Commands => return false,
            // Not a sample after all: the decoder drops it, commands go on.
            Split::Head(4) if b != SYNC[1] => Split::Commands,
            Split::Head(1) if b > MAX_BODY => Split::Commands,
            Split::Head(1) => Split::Body(b + CRC_LEN as u8),
            Split::Head(n) => Split::Head(n - 1),
            Split::Body(1) | Split::Body(0) => Split::Commands,
            Split::Body(n) => Split::Body(n - 1),
        };
        true
    }
}

/// ISR side: stamps edges, forwards commands.
pub fn on_byte(b: u8, edges: &mut Producer<'static, Edge>, cmds: &mut Producer<'static, u8>) {
    let (pin, level) = match b {
        b'P' => (Pin::Pps, Level::High),
        b'p' => (Pin::Pps, Level::Low),
        b'E' => (Pin::Extrig, Level::High),
        b'e' => (Pin::Extrig, Level::Low),
        _ => {
            let _ = cmds.enqueue(b);
            return;
        }
    };
    let _ = edges.enqueue(Edge {
        pin,
        level,
        at: board::now(),
    });
}

/// Tick side: executes commands.
pub struct Bridge {
    cmds: Consumer<'static, u8>,
    boot: Option<Level>,
}

impl Bridge {
    /// `boot` = the BOOT level the board powered on with.
    pub fn new(cmds: Consumer<'static, u8>, boot: Option<Level>) -> Self {
        Bridge { cmds, boot }
    }

    /// Executes the commands received so far.
    pub fn serve(&mut self, shell: &mut BoardShell) {
        while let Some(c) = self.cmds.dequeue() {
            match c {
                b'B' => self.boot = Some(Level::High),
                b'b' => self.boot = Some(Level::Low),
                b'f' => self.boot = None,
                b'R' => {
                    shell.power_cycle(self.boot);
                    UART1.put_wait(b'R');
                }
                b'S' => report(shell),
                b'Z' => shell.reset_stats(),
                _ => {}
            }
        }
    }
}

fn report(shell: &mut BoardShell) {
    let s = shell.stats();
    let stack_init = INIT_STACK.load(core::sync::atomic::Ordering::Relaxed);
    let fields: [(&str, u64); 13] = [
        ("S ticks=", s.ticks),
        (" services=", s.services),
        (" on_tick_max_ns=", s.max_on_tick_ns),
        (" tick_max_ns=", s.max_tick_ns),
        (" service_max_ns=", s.max_service_ns),
        (" service_batch_max_ns=", s.max_batch_service_ns),
        (" service_rx_max_ns=", s.max_service_rx_ns),
        (" batch_max=", u64::from(s.max_batch)),
        (" tx=", s.tx_bytes),
        (" rx=", s.rx_bytes),
        (" dropped=", u64::from(shell.device().tx_dropped())),
        (" stack=", stack_used() as u64),
        (" stack_init=", stack_init as u64),
    ];
    let line = fields
        .iter()
        .fold(semi::Line::default(), |l, &(k, v)| l.str(k).dec(v))
        .str("\n");
    for &b in line.bytes() {
        UART1.put_wait(b);
    }
}

/// Stack the power-on (init) used, bytes.
static INIT_STACK: core::sync::atomic::AtomicUsize = core::sync::atomic::AtomicUsize::new(0);

/// Remembers the stack power-on used and paints the free stack again, so
/// [`stack_used`] then tells what the running firmware uses. Called once,
/// from `idle`, with the interrupts already running.
pub fn repaint_stack() {
    extern "C" {
        static __sheap: u32;
    }
    INIT_STACK.store(stack_used(), core::sync::atomic::Ordering::Relaxed);
    let sp = cortex_m::register::msp::read() as usize - 256;
    // SAFETY: paints the free RAM below this frame. Interrupt frames live
    // there only while an interrupt runs, and then this loop does not.
    unsafe {
        let mut p = core::ptr::addr_of!(__sheap) as *mut u32;
        while (p as usize) < sp {
            core::ptr::write_volatile(p, PAINT);
            p = p.add(1);
        }
    }
}

/// The stack paint.
const PAINT: u32 = 0x5A5A_A5A5;

/// Stack high-water mark in bytes: the RAM between the end of the statics
/// and the reset stack pointer was painted at reset (`__pre_init`); the
/// lowest word no longer holding the paint is as deep as the stack went.
pub fn stack_used() -> usize {
    extern "C" {
        static __sheap: u32;
        static _stack_start: u32;
    }
    // SAFETY: linker symbols; the range between them is RAM owned by the
    // stack, read word by word.
    unsafe {
        let mut p = core::ptr::addr_of!(__sheap);
        let top = core::ptr::addr_of!(_stack_start);
        while p < top && core::ptr::read_volatile(p) == PAINT {
            p = p.add(1);
        }
        top as usize - p as usize
    }
}
