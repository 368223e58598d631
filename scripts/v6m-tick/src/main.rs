//! `Device::on_tick` instructions for thumbv6m `--features fixed-point`
//! (the RP2040 build of the core, opt-level "s", fat LTO), counted on the
//! Cortex-M4 model of `qemu-system-arm -M mps2-an386` under
//! `-icount shift=0`: SysTick runs on the 25 MHz processor clock, so one
//! count is 40 instructions (the figures are ±40). For each load the probe
//! powers a K110 on, sends the commands a host would, streams 400 ticks,
//! then times 40 ticks and prints `load worst mean` over semihosting
//! (load 0 is the empty measurement; line 9 gives
//! `size_of` the signal chain without and with integrals). Run it with `scripts/v6m-tick.sh`;
//! the figures are in docs/firmware-budget.md and docs/firmware.md.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use imu_emu::{Device, Instant, Kernel, PowerOn, Product, RamNor};

const SYST_CSR: *mut u32 = 0xE000_E010 as *mut u32;
const SYST_RVR: *mut u32 = 0xE000_E014 as *mut u32;
const SYST_CVR: *mut u32 = 0xE000_E018 as *mut u32;

/// SysTick's current value (counts down, 24 bits).
fn cvr() -> u32 {
    // SAFETY: SysTick's CVR, a core register, read-only here.
    unsafe { core::ptr::read_volatile(SYST_CVR) }
}

/// Prints `v` as one line of decimal numbers over semihosting.
fn print(v: &[u32]) {
    let mut b = [0u8; 96];
    let mut i = 0;
    for &x in v {
        let mut d = [0u8; 10];
        let mut n = 0;
        let mut y = x;
        loop {
            d[n] = b'0' + (y % 10) as u8;
            n += 1;
            y /= 10;
            if y == 0 {
                break;
            }
        }
        while n > 0 {
            n -= 1;
            b[i] = d[n];
            i += 1;
        }
        b[i] = b' ';
        i += 1;
    }
    b[i] = b'\n';
    // SAFETY: semihosting SYS_WRITE0 of `b`, NUL-terminated (zeroed).
    unsafe {
        core::arch::asm!("bkpt 0xab", inout("r0") 0x04u32 => _, in("r1") b.as_ptr());
    }
}

fn exit() -> ! {
    // SAFETY: semihosting SYS_EXIT, ADP_Stopped_ApplicationExit.
    unsafe {
        core::arch::asm!("bkpt 0xab", in("r0") 0x18u32, in("r1") 0x20026u32);
    }
    loop {
        // SAFETY: waits for an interrupt; nothing else runs.
        unsafe { core::arch::asm!("wfi") };
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    exit()
}

struct Buf {
    b: [u8; 64],
    n: usize,
}
impl Buf {
    fn frame(payload: &[u8]) -> Buf {
        let mut b = [0u8; 64];
        b[0] = 0xAA;
        b[1] = 0x55;
        let len = (payload.len() + 6) as u16;
        b[4..6].copy_from_slice(&len.to_le_bytes());
        b[6..6 + payload.len()].copy_from_slice(payload);
        let n = 6 + payload.len();
        let s = b[2..n]
            .iter()
            .fold(0u16, |s, &x| s.wrapping_add(u16::from(x)));
        b[n..n + 2].copy_from_slice(&s.to_le_bytes());
        Buf { b, n: n + 2 }
    }
    fn save(id: u16, v: &[u8]) -> Buf {
        let mut p = [0u8; 48];
        p[0] = 0xB2;
        p[1] = 0xFF;
        p[2..4].copy_from_slice(&id.to_le_bytes());
        p[4..6].copy_from_slice(&(v.len() as u16).to_le_bytes());
        p[6..6 + v.len()].copy_from_slice(v);
        Buf::frame(&p[..6 + v.len()])
    }
}

type Dev = Device<RamNor<8192>, Kernel>;

struct Run {
    dev: Dev,
    now: Instant,
}

impl Run {
    fn drain(&mut self) {
        let mut out = [0u8; 256];
        while self.dev.poll_tx(&mut out) > 0 {}
        while self.dev.poll_event().is_some() {}
    }
    fn tick(&mut self) {
        self.now = self.now.plus_nanos(self.dev.tick_period_ns());
        self.dev.on_tick(self.now);
        self.drain();
    }
    fn ticks(&mut self, n: u32) {
        for _ in 0..n {
            self.tick();
        }
    }
    fn send(&mut self, f: Buf) {
        self.dev.on_rx(&f.b[..f.n], self.now);
        self.ticks(40);
    }
    fn measure(&mut self, tag: u32, n: u32) {
        let (mut worst, mut sum) = (0u32, 0u32);
        for _ in 0..n {
            self.now = self.now.plus_nanos(self.dev.tick_period_ns());
            let a = cvr();
            self.dev.on_tick(self.now);
            let b = cvr();
            self.drain();
            let d = a.wrapping_sub(b) & 0x00FF_FFFF;
            worst = worst.max(d);
            sum += d;
        }
        print(&[tag, worst * 40, sum * 40 / n]);
    }
}

fn run(model: &str, setup: &[Buf], tag: u32) {
    let product = Product::parse(model).unwrap_or_else(|_| exit());
    let mut r = Run {
        dev: Device::power_on_with(
            PowerOn {
                product,
                boot: None,
                seed: 0,
            },
            RamNor::new(),
            Instant::from_nanos(0),
        ),
        now: Instant::from_nanos(0),
    };
    r.ticks(100);
    for f in setup {
        r.send(Buf { b: f.b, n: f.n });
    }
    r.ticks(400);
    r.measure(tag, 40);
}

const GA: u8 = 0x8F;
const UDD: u8 = 0x95;
const UDD_CONFIG: u8 = 0x96;
const DATA_RATE: u16 = 0x0012;
const ALIGN_TIME: u16 = 0x0014;
const LPF_BANDWIDTH: u16 = 0x03D7;
const BAUD_RATE: u16 = 0x03B2;

const COMMIT_BAUD_RATE: u8 = 0xC2;

#[entry]
fn main() -> ! {
    // SAFETY: SysTick on the processor clock, no interrupt, full reload.
    unsafe {
        core::ptr::write_volatile(SYST_RVR, 0x00FF_FFFF);
        core::ptr::write_volatile(SYST_CVR, 0);
        core::ptr::write_volatile(SYST_CSR, 0b101);
    }
    let (mut worst, mut sum) = (0u32, 0u32);
    for _ in 0..40 {
        let a = cvr();
        let b = cvr();
        let d = a.wrapping_sub(b) & 0x00FF_FFFF;
        worst = worst.max(d);
        sum += d;
    }
    print(&[0, worst * 40, sum]);
    // The chain's size (src/chain.rs "Memory"): 9, without and with integrals.
    print(&[
        9,
        core::mem::size_of::<imu_emu::SignalChain>() as u32,
        core::mem::size_of::<imu_emu::SignalChain<imu_emu::dsp::integrals::Integrals>>() as u32,
    ]);
    let types: [u8; 16] = [
        0x02, 0x05, 0x07, 0x08, 0x09, 0x20, 0x21, 0x22, 0x23, 0x2D, 0x2E, 0x91, 0x92, 0x52, 0x53,
        0x5B,
    ];
    let mut list = [0u8; 17];
    list[0] = 16;
    list[1..].copy_from_slice(&types);
    let setup = |lpf: u8, start: &[Buf]| {
        let mut v: [Buf; 8] = core::array::from_fn(|_| Buf::frame(&[0xFE]));
        v[0] = Buf::save(BAUD_RATE, &[0x0B]);
        v[1] = Buf::frame(&[COMMIT_BAUD_RATE]);
        v[2] = Buf::save(ALIGN_TIME, &0u16.to_le_bytes());
        v[3] = Buf::save(DATA_RATE, &2000u16.to_le_bytes());
        v[4] = Buf::save(LPF_BANDWIDTH, &[lpf]);
        let mut i = 5;
        for b in start {
            v[i] = Buf { b: b.b, n: b.n };
            i += 1;
        }
        (v, i)
    };
    // 1: K110 factory settings, no output
    run("K110", &[], 1);
    // 2: GA at 2000 Hz, 2 Mbit/s (LPF factory 0x04? kept as read below)
    let (v, n) = setup(0x04, &[Buf::frame(&[GA])]);
    run("K110", &v[..n], 2);
    // 3: largest K110 UDD (145 B) at 1000 Hz; 4: the same with LPF 16 Hz
    let udd = [
        Buf::frame(&[UDD_CONFIG]),
        Buf::frame(&list),
        Buf::frame(&[UDD]),
    ];
    let (v, n) = setup(0x04, &udd);
    run("K110", &v[..n], 3);
    let (v, n) = setup(0x00, &udd);
    run("K110", &v[..n], 4);
    exit()
}
