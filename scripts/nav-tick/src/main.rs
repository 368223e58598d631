//! `Device::on_tick` instructions of a navigating IMX-5 (the ISB
//! personality) on the firmware targets, counted on the Cortex-M4 model of
//! `qemu-system-arm -M mps2-an386` under `-icount shift=0` (SysTick on the
//! processor clock: one count is 40 instructions, the figures are ±40).
//! Built for thumbv7em-none-eabihf (the M4F images: `f32` on the FPU) or
//! thumbv6m-none-eabi `--features fixed-point` (the RP2040 image's core:
//! soft float, run here on the M4 model). The probe streams what the
//! conformance test `tick_cost_navigating` streams (INS_2 every navigation
//! period, INL2_NED_SIGMA every 100 ms, GPS1_POS every receiver epoch),
//! with the receiver's cold start shortened to 6 s, waits for NAV (with
//! `--features nav-off`, the filter off: for the receiver's fix), and
//! prints over semihosting, for 12 s of navigation (60 receiver epochs, a declination among them):
//! `1 worst mean`, then `2 phase worst` for each tick of the 8-tick
//! navigation period, then `3 tick-in-epoch instructions` for the 8 dearest
//! ticks. Run it with `scripts/nav-tick.sh`; the figures are in
//! docs/performance.md "Navigation filter".
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use imu_emu::isb::ins::{Phase, StartTimes};
use imu_emu::isb::message::{encode_get, GetRequest};
use imu_emu::isb::{did, Isb};
use imu_emu::model::Product;
use imu_emu::{Device, Instant, PowerOn, RamNor};

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
    print(&[999]);
    exit()
}

type Dev = Device<RamNor<8192>, Isb>;

struct Run {
    dev: Dev,
    now: Instant,
    /// Ticks since the power cycle.
    n: u32,
}

impl Run {
    fn drain(&mut self) {
        let mut out = [0u8; 256];
        while self.dev.poll_tx(&mut out) > 0 {}
        while self.dev.poll_event().is_some() {}
    }
    /// One tick; its instructions.
    fn tick(&mut self) -> u32 {
        self.now = self.now.plus_nanos(self.dev.tick_period_ns());
        self.n += 1;
        let a = cvr();
        self.dev.on_tick(self.now);
        let b = cvr();
        self.drain();
        (a.wrapping_sub(b) & 0x00FF_FFFF) * 40
    }
    fn get(&mut self, d: u8, period: u16) {
        let req = GetRequest {
            did: u16::from(d),
            size: 0,
            offset: 0,
            period,
        };
        let mut out = [0u8; 32];
        let n = encode_get(&req, &mut out).unwrap_or_else(|| exit());
        self.dev.on_rx(&out[..n], self.now);
    }
}

/// Instructions of `f` (its result kept).
fn cost<T>(f: impl FnOnce() -> T) -> u32 {
    let a = cvr();
    let x = f();
    let b = cvr();
    core::hint::black_box(x);
    (a.wrapping_sub(b) & 0x00FF_FFFF) * 40
}

/// `5 item instructions`: the parts of a navigating tick, one by one.
fn parts(dev: &Dev) {
    use imu_emu::isb::ins::filter::{Interval, ProcessNoise};
    use imu_emu::isb::ins::mech::Increment;
    use imu_emu::isb::ins::{self, NavConfig};
    use imu_emu::isb::nav::{self, GpsTime};
    use imu_emu::isb::nav_sets::InsHeader;
    let nav = dev.personality().nav();
    let cfg = NavConfig::default();
    let truth = nav::truth_of(dev.chain());
    let h = InsHeader::default();
    let sol = nav.solution(&cfg);
    let t = GpsTime::of_ns(1_451_606_400_000_000_000);
    let inc = Increment {
        dtheta: [1e-5, -2e-5, 3e-5],
        dv: [0.001, 0.002, -0.0392],
        dt: 0.004,
    };
    let iv = Interval {
        dt: 0.02,
        f_n: [0.1, 0.2, -9.8],
        c_nb: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        w_in: [5e-5, 0.0, -5e-5],
        grav_grad: 3e-6,
    };
    let q = ProcessNoise {
        vel: 1e-6,
        att: 1e-9,
        bg: 1e-14,
        ba: 1e-10,
    };
    let items: [u32; 18] = [
        cost(|| nav::truth_of(dev.chain())),
        cost(|| nav.solution(&cfg)),
        cost(|| ins::ins2(&h, &sol).encode()),
        cost(|| nav.ins_status()),
        cost(|| {
            let mut n = *nav.nominal();
            n.mechanise(&inc)
        }),
        cost(|| nav.filter().clone()),
        cost(|| {
            let mut f = nav.filter().clone();
            f.propagate(&iv, &q);
            f
        }),
        cost(|| {
            let mut f = nav.filter().clone();
            f.update(&[(0, 1.0)], 0.5, 1.0, 0.0);
            f
        }),
        cost(|| nav.gnss(&truth, &cfg)),
        cost(|| ins::gps_pos(&t, nav.gps_report(&truth, &cfg).as_ref(), 0.0).encode()),
        cost(|| nav.inl2_ned_sigma(0).encode()),
        cost(|| t.decimal_year()),
        cost(|| imu_emu::earth::geoid_undulation_m(truth.lat_deg, truth.lon_deg)),
        cost(|| nav::ecef_of(&sol.lla)),
        cost(|| ins::ins1(&h, &sol, &cfg).encode()),
        cost(|| nav.inl2_states(0.0).encode()),
        cost(|| nav.clone()),
        cost(|| {
            let mut n = nav.clone();
            n.step(100.0, &truth);
            n
        }),
    ];
    for (i, c) in items.iter().enumerate() {
        print(&[5, i as u32 + 1, *c]);
    }
}

#[entry]
fn main() -> ! {
    // SAFETY: SysTick on the processor clock, no interrupt, full reload.
    unsafe {
        core::ptr::write_volatile(SYST_RVR, 0x00FF_FFFF);
        core::ptr::write_volatile(SYST_CVR, 0);
        core::ptr::write_volatile(SYST_CSR, 0b101);
    }
    let cfg = PowerOn {
        product: Product::imx5(),
        boot: None,
        seed: 0,
    };
    let mut r = Run {
        dev: Device::new(cfg, RamNor::new(), Instant::from_nanos(0)),
        now: Instant::from_nanos(0),
        n: 0,
    };
    r.dev.personality_mut().set_start_times(StartTimes {
        cold_s: 6.0,
        warm_s: 6.0,
    });
    r.dev.power_cycle(r.now);
    r.n = 0;
    let filter = !cfg!(feature = "nav-off");
    r.dev.personality_mut().set_navigation(filter);
    r.tick();
    r.get(did::INS_2, 1);
    r.get(did::INL2_NED_SIGMA, 25);
    r.get(did::GPS1_POS, 1);
    let mut n = 0u32;
    let ready = |d: &Dev| {
        let nav = d.personality().nav();
        if filter {
            nav.phase() == Phase::Nav
        } else {
            nav.has_fix()
        }
    };
    while !ready(&r.dev) {
        r.tick();
        n += 1;
        if n > 40_000 {
            print(&[998]);
            exit();
        }
    }
    for _ in 0..600 {
        r.tick();
    }
    parts(&r.dev);
    let (mut worst, mut sum) = (0u32, 0u64);
    let mut phase = [0u32; 8];
    let mut top = [(0u32, 0u32); 8];
    let mut epoch = [0u32; 400];
    let ticks = 24_000u32;
    for _ in 0..ticks {
        let c = r.tick();
        let i = r.n;
        worst = worst.max(c);
        sum += u64::from(c);
        let e = &mut epoch[(i % 400) as usize];
        *e = (*e).max(c);
        let k = (i % 8) as usize;
        phase[k] = phase[k].max(c);
        if c > top[7].1 {
            top[7] = (i, c);
            top.sort_unstable_by(|a, b| b.1.cmp(&a.1));
        }
    }
    print(&[1, worst, (sum / u64::from(ticks)) as u32]);
    for (k, w) in phase.iter().enumerate() {
        print(&[2, k as u32, *w]);
    }
    for (i, c) in top {
        print(&[3, i, c]);
    }
    for (i, c) in epoch.iter().enumerate() {
        if *c > 20_000 && (i % 8 != 0 || i % 200 == 0 || i < 20 || i > 380) {
            print(&[4, i as u32, *c]);
        }
    }
    exit()
}
