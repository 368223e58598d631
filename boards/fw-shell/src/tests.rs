//! Host tests of the shell with fake peripherals.

extern crate std;
use std::cell::RefCell;
use std::rc::Rc;
use std::vec::Vec;

use imu_emu::device::{Level, Pin, PowerOn};
use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;

use super::*;

/// What the fake board saw; shared between the test and the fakes.
#[derive(Default)]
struct Board {
    now: u64,
    rx: Vec<u8>,
    /// (time, byte) of every byte written.
    tx: Vec<(u64, u8)>,
    /// UART FIFO size; the fake FIFO empties between service calls.
    room: usize,
    fifo: usize,
    idle: bool,
    bauds: Vec<(u64, u32)>,
    tov: Vec<(u64, Level)>,
    edges: Vec<Edge>,
}

type Shared = Rc<RefCell<Board>>;

struct FakeUart(Shared);
impl Uart for FakeUart {
    fn read(&mut self, buf: &mut [u8]) -> usize {
        let mut b = self.0.borrow_mut();
        let n = b.rx.len().min(buf.len());
        buf[..n].copy_from_slice(&b.rx[..n]);
        b.rx.drain(..n);
        n
    }
    fn tx_room(&mut self) -> usize {
        let b = self.0.borrow();
        b.room - b.fifo
    }
    fn write(&mut self, bytes: &[u8]) {
        let mut b = self.0.borrow_mut();
        assert!(bytes.len() <= b.room - b.fifo);
        b.fifo += bytes.len();
        let now = b.now;
        b.tx.extend(bytes.iter().map(|&x| (now, x)));
    }
    fn tx_idle(&mut self) -> bool {
        self.0.borrow().idle
    }
    fn set_baud(&mut self, bps: u32) {
        let mut b = self.0.borrow_mut();
        let now = b.now;
        b.bauds.push((now, bps));
    }
}

struct FakeClock(Shared);
impl Clock for FakeClock {
    fn now(&mut self) -> Instant {
        Instant::from_nanos(self.0.borrow().now)
    }
}

struct FakeTov(Shared);
impl TovPin for FakeTov {
    fn set(&mut self, level: Level) {
        let mut b = self.0.borrow_mut();
        let now = b.now;
        b.tov.push((now, level));
    }
}

struct FakeEdges(Shared);
impl EdgeSource for FakeEdges {
    fn pop(&mut self) -> Option<Edge> {
        let mut b = self.0.borrow_mut();
        if b.edges.is_empty() {
            None
        } else {
            Some(b.edges.remove(0))
        }
    }
}

type TestShell = Shell<'static, RamNor<8192>, FakeUart, FakeClock, FakeTov, FakeEdges, Kernel>;

/// A K110 powered on at board time 1 ms (so the epoch is not 0).
fn shell() -> (TestShell, Shared) {
    let b: Shared = Rc::new(RefCell::new(Board {
        now: 1_000_000,
        room: 64,
        idle: true,
        ..Board::default()
    }));
    let cfg = PowerOn {
        product: Product::parse("K110").unwrap(),
        boot: None,
        seed: 1,
    };
    let slot = std::boxed::Box::leak(std::boxed::Box::new(core::mem::MaybeUninit::uninit()));
    let dev = power_on(slot, cfg, RamNor::new());
    let s = Shell::new(
        dev,
        FakeUart(b.clone()),
        FakeClock(b.clone()),
        FakeTov(b.clone()),
        FakeEdges(b.clone()),
    );
    (s, b)
}

fn frame(payload: &[u8]) -> Vec<u8> {
    let len = (payload.len() + 6) as u16;
    let mut f = std::vec![0xAA, 0x55, 0, 0];
    f.extend_from_slice(&len.to_le_bytes());
    f.extend_from_slice(payload);
    let s = f[2..]
        .iter()
        .fold(0u16, |s, &x| s.wrapping_add(u16::from(x)));
    f.extend_from_slice(&s.to_le_bytes());
    f
}

fn save_flash(id: u16, value: &[u8]) -> Vec<u8> {
    let mut p = std::vec![0xB2, 0xFF];
    p.extend_from_slice(&id.to_le_bytes());
    p.extend_from_slice(&(value.len() as u16).to_le_bytes());
    p.extend_from_slice(value);
    frame(&p)
}

/// Services every `step` ns until board time `until`.
fn run(s: &mut TestShell, b: &Shared, until: u64, step: u64) {
    loop {
        let now = b.borrow().now;
        if now >= until {
            break;
        }
        b.borrow_mut().now = (now + step).min(until);
        b.borrow_mut().fifo = 0;
        s.service();
    }
}

#[test]
fn power_on_sets_the_line_rate_and_tov_low() {
    let (s, b) = shell();
    assert_eq!(b.borrow().bauds, [(1_000_000, 115_200)]);
    assert_eq!(b.borrow().tov, [(1_000_000, Level::Low)]);
    assert_eq!(s.tick_hz(), 2000);
}

#[test]
fn ticks_follow_absolute_deadlines_and_catch_up_in_bounded_batches() {
    let (mut s, b) = shell();
    // Exactly on time: one tick per call.
    run(&mut s, &b, 1_000_000 + 10 * 500_000, 500_000);
    assert_eq!(s.stats().ticks, 10);
    assert_eq!(s.stats().max_batch, 1);
    // A 20 ms stall: 40 ticks due, at most MAX_CATCH_UP per call.
    b.borrow_mut().now += 20_000_000;
    s.service();
    assert_eq!(s.stats().ticks, 10 + u64::from(MAX_CATCH_UP));
    s.service();
    s.service();
    assert_eq!(s.stats().ticks, 50);
    assert_eq!(s.stats().max_batch, MAX_CATCH_UP);
    // An interrupt a few ns early still runs its tick.
    b.borrow_mut().now += 500_000 - 100;
    s.service();
    assert_eq!(s.stats().ticks, 51);
}

#[test]
fn replies_leave_at_the_line_rate() {
    let (mut s, b) = shell();
    b.borrow_mut().rx = frame(&[0x12]); // GetDevInfo: 174 bytes
    b.borrow_mut().now += 500_000;
    s.service();
    // 115200 bit/s = 11.52 bytes/ms; the request came at device time
    // 0.5 ms, the credit counts from power-on: 10.5 ms → 120 bytes.
    run(&mut s, &b, 1_500_000 + 10_000_000, 500_000);
    let sent = b.borrow().tx.len();
    assert!((118..=121).contains(&sent), "{sent}");
    run(&mut s, &b, 40_000_000, 500_000);
    let tx: Vec<u8> = b.borrow().tx.iter().map(|&(_, x)| x).collect();
    assert_eq!(tx.len(), 174);
    assert_eq!(&tx[..4], &[0xAA, 0x55, 0x01, 0x12]);
}

#[test]
fn tx_never_exceeds_the_uart_room() {
    let (mut s, b) = shell();
    b.borrow_mut().room = 3;
    b.borrow_mut().rx = frame(&[0x12]);
    run(&mut s, &b, 11_000_000, 500_000);
    // 20 calls × a 3-byte FIFO.
    assert_eq!(b.borrow().tx.len(), 60);
}

#[test]
fn a_baud_switch_waits_for_the_uart_to_be_idle() {
    let (mut s, b) = shell();
    let mut cmd = save_flash(0x03B2, &[0x0B]); // 2 000 000 bit/s
    cmd.extend(frame(&[0xC2])); // CommitBaudRate
    cmd.extend(frame(&[0x12])); // GetDevInfo, answered at the new rate
    b.borrow_mut().rx = cmd;
    b.borrow_mut().idle = false;
    run(&mut s, &b, 10_000_000, 500_000);
    // The SaveFlash ack (10 bytes) left at 115200; the switch waits.
    assert_eq!(b.borrow().tx.len(), 10);
    assert_eq!(b.borrow().bauds.len(), 1);
    b.borrow_mut().idle = true;
    let t = b.borrow().now;
    run(&mut s, &b, t + 500_000, 500_000);
    assert_eq!(b.borrow().bauds[1], (t + 500_000, 2_000_000));
    // The credit restarts at the switch: 2 Mbit/s = 100 bytes per tick,
    // the UART FIFO takes 64 per call.
    assert_eq!(b.borrow().tx.len(), 10);
    run(&mut s, &b, t + 1_000_000, 500_000);
    assert_eq!(b.borrow().tx.len(), 10 + 64);
    run(&mut s, &b, t + 2_000_000, 500_000);
    assert_eq!(b.borrow().tx.len(), 10 + 174);
}

#[test]
fn tov_rises_at_the_output_tick_and_falls_after_the_last_bit() {
    let (mut s, b) = shell();
    let mut cmd = save_flash(0x0499, &[1]); // TOV_Control
    cmd.extend(frame(&[0x8F])); // GA
    b.borrow_mut().rx = cmd;
    b.borrow_mut().room = 1000;
    run(&mut s, &b, 60_000_000, 500_000);
    let tov = b.borrow().tov.clone();
    // Low at power-on, then pairs: 100 Hz for ~59 ms → 5 frames.
    assert!(tov.len() > 2 * 5, "{tov:?}");
    for pair in tov[1..].chunks(2) {
        assert_eq!(pair[0].1, Level::High);
        assert_eq!(pair[1].1, Level::Low);
        // A 40-byte GA frame takes 3.47 ms at 115200: falls ~7 ticks later.
        let width = pair[1].0 - pair[0].0;
        assert!((3_000_000..=4_500_000).contains(&width), "{width}");
    }
}

#[test]
fn edges_reach_the_device_before_the_tick_at_their_time() {
    let (mut s, b) = shell();
    // EXTRIG triggers GA: Trigger_Control 1, Polarity 1 (rising), GA.
    let mut cmd = save_flash(0x05FA, &[1]);
    cmd.extend(save_flash(0x05FB, &[1]));
    cmd.extend(frame(&[0x8F]));
    b.borrow_mut().rx = cmd;
    b.borrow_mut().room = 1000;
    run(&mut s, &b, 5_000_000, 500_000);
    let before = b.borrow().tx.len();
    // A rising edge stamped 2 ms from now, queued at once: delivered only
    // when its time comes, then exactly one frame.
    let at = b.borrow().now + 2_000_000;
    b.borrow_mut().edges.push(Edge {
        pin: Pin::Extrig,
        level: Level::High,
        at: Instant::from_nanos(at),
    });
    run(&mut s, &b, at - 500_000, 500_000);
    assert_eq!(b.borrow().tx.len(), before);
    run(&mut s, &b, at + 10_000_000, 500_000);
    assert_eq!(b.borrow().tx.len(), before + 40);
}

#[test]
fn power_cycle_restarts_the_schedule_and_keeps_flash() {
    let (mut s, b) = shell();
    b.borrow_mut().rx = save_flash(0x0012, &50u16.to_le_bytes());
    run(&mut s, &b, 5_000_000, 500_000);
    s.power_cycle(None);
    assert_eq!(s.device().param_ram(0x0012), Some(&50u16.to_le_bytes()[..]));
    let t = b.borrow().now;
    run(&mut s, &b, t + 1_000_000, 500_000);
    assert_eq!(s.device().mode(), imu_emu::device::Mode::Idle);
}

/// The GA frames (ICD Table 5.6) in what the UART sent: their 2 kHz
/// counters (payload offset 24); panics on any byte that is not part of a
/// GA frame (a torn frame or garbage).
fn ga_counters(tx: &[(u64, u8)], skip: usize) -> Vec<u16> {
    let bytes: Vec<u8> = tx.iter().map(|&(_, x)| x).collect();
    let mut at = skip;
    let mut out = Vec::new();
    while at + 40 <= bytes.len() {
        let f = &bytes[at..at + 40];
        assert_eq!(
            &f[..6],
            &[0xAA, 0x55, 0x01, 0x8F, 0x26, 0x00],
            "at byte {at}"
        );
        let sum = f[2..38]
            .iter()
            .fold(0u16, |s, &x| s.wrapping_add(u16::from(x)));
        assert_eq!(&f[38..], &sum.to_le_bytes(), "checksum at byte {at}");
        out.push(u16::from_le_bytes([f[6 + 24], f[6 + 25]]));
        at += 40;
    }
    out
}

/// After a stall of the emulated CPU at high line use the
/// firmware dropped frames in a burst (2 kHz counter jumps) because the
/// catch-up ran ticks without the line time before them. GA at 250 Hz on
/// 115 200 bit/s is 40 B × 250 = 10 000 B/s: 86.8 % of the line's
/// 11 520 B/s, within Formula 5.1 (115200 / (11 × 40) = 261 Hz). Stalls of
/// 200 ms and 2 s (the interrupt not served at all) must not lose a frame:
/// every counter step is 8 ticks (2000 / 250).
#[test]
fn a_stall_at_87_percent_line_use_loses_no_frame() {
    let (mut s, b) = shell();
    let mut cmd = save_flash(0x0012, &250u16.to_le_bytes()); // Data_Rate
    cmd.extend(frame(&[0x8F])); // GA
    b.borrow_mut().rx = cmd;
    b.borrow_mut().room = 1000;
    let ack = 10 + 10; // SaveFlash and GA acknowledgements
    let mut t = 1_000_000 + 500_000_000;
    run(&mut s, &b, t, 500_000);
    let before = ga_counters(&b.borrow().tx, ack).len();
    assert!(before >= 120, "{before} frames in 0.5 s");
    for stall in [200_000_000u64, 2_000_000_000] {
        t += stall;
        b.borrow_mut().now = t;
        b.borrow_mut().fifo = 0;
        s.service();
        t += 1_000_000_000 + stall;
        run(&mut s, &b, t, 500_000);
    }
    assert_eq!(
        s.stats().max_batch,
        MAX_CATCH_UP,
        "the stalls were caught up"
    );
    assert_eq!(s.device().tx_dropped(), 0);
    let counters = ga_counters(&b.borrow().tx, ack);
    for w in counters.windows(2) {
        assert_eq!(w[1].wrapping_sub(w[0]), 8, "counter step in {counters:?}");
    }
    // Every tick ran: 6.9 s of device time at 250 Hz (less the frame
    // still on the line).
    let ticks = s.stats().ticks;
    assert_eq!(ticks, (t - 1_000_000) / 500_000);
    assert!(
        counters.len() as u64 >= ticks / 8 - 2,
        "{} frames",
        counters.len()
    );
}

// ----- the ISB personality on the same shell -----

type IsbShell =
    Shell<'static, RamNor<8192>, FakeUart, FakeClock, FakeTov, FakeEdges, imu_emu::isb::Isb>;

/// An IMX-5 (ISB personality) powered on at board time 1 ms.
fn isb_shell() -> (IsbShell, Shared) {
    let b: Shared = Rc::new(RefCell::new(Board {
        now: 1_000_000,
        room: 64,
        idle: true,
        ..Board::default()
    }));
    let cfg = PowerOn {
        product: Product::imx5(),
        boot: None,
        seed: 1,
    };
    let slot = std::boxed::Box::leak(std::boxed::Box::new(core::mem::MaybeUninit::uninit()));
    let dev = power_on::<_, imu_emu::isb::Isb>(slot, cfg, RamNor::new());
    let s = Shell::new(
        dev,
        FakeUart(b.clone()),
        FakeClock(b.clone()),
        FakeTov(b.clone()),
        FakeEdges(b.clone()),
    );
    (s, b)
}

/// Services the ISB shell every `step` ns until board time `until`.
fn run_isb(s: &mut IsbShell, b: &Shared, until: u64, step: u64) {
    loop {
        let now = b.borrow().now;
        if now >= until {
            break;
        }
        b.borrow_mut().now = (now + step).min(until);
        b.borrow_mut().fifo = 0;
        s.service();
    }
}

/// A GET_DATA request (ISB "GET_DATA": did, size, offset, period).
fn isb_get(did: u8, period: u16) -> Vec<u8> {
    let req = imu_emu::isb::message::GetRequest {
        did: u16::from(did),
        size: 0,
        offset: 0,
        period,
    };
    let mut out = [0u8; 32];
    let n = imu_emu::isb::message::encode_get(&req, &mut out).unwrap();
    out[..n].to_vec()
}

/// The ISB packets in `tx`: (board time of the first byte, flags, DID,
/// payload), each checksum checked; the stream must hold nothing else.
fn isb_packets(tx: &[(u64, u8)]) -> Vec<(u64, u8, u8, Vec<u8>)> {
    let bytes: Vec<u8> = tx.iter().map(|&(_, x)| x).collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        assert_eq!(bytes[i..i + 2], [0xEF, 0x49], "packet start at {i}");
        let size = usize::from(u16::from_le_bytes([bytes[i + 4], bytes[i + 5]]));
        let end = i + 6 + size;
        assert_eq!(
            imu_emu::isb::packet::checksum(&bytes[i..end]),
            bytes[end..end + 2],
            "checksum at {i}"
        );
        out.push((
            tx[i].0,
            bytes[i + 2],
            bytes[i + 3],
            bytes[i + 6..end].to_vec(),
        ));
        i = end + 2;
    }
    out
}

#[test]
fn isb_power_on_sets_921600_and_answers_get_dev_info() {
    let (mut s, b) = isb_shell();
    // FLASH_CONFIG's factory ser0BaudRate, set before anything is sent.
    assert_eq!(b.borrow().bauds, [(1_000_000, 921_600)]);
    assert_eq!(s.device().line_rate(), 921_600);
    b.borrow_mut().rx = isb_get(imu_emu::isb::did::DEV_INFO, 0);
    // 92 bytes at 92 160 byte/s: 1 ms of line time, 3 ms to be sure.
    run_isb(&mut s, &b, 4_000_000, 500_000);
    let p = isb_packets(&b.borrow().tx);
    assert_eq!(p.len(), 1);
    let (_, flags, did, payload) = &p[0];
    assert_eq!((*flags, *did, payload.len()), (4, 1, 84));
    let info = imu_emu::isb::sets::DevInfo::decode(payload.as_slice().try_into().unwrap());
    assert!(info.accepted_by_sdk());
}

#[test]
fn isb_imu_streams_every_4_ms_on_the_fake_clock() {
    let (mut s, b) = isb_shell();
    b.borrow_mut().rx = isb_get(imu_emu::isb::did::IMU, 1);
    // Serviced every tick (500 µs) for 101 ms.
    run_isb(&mut s, &b, 102_000_000, 500_000);
    let p = isb_packets(&b.borrow().tx);
    assert!(p.iter().all(|(_, f, d, l)| (*f, *d, l.len())
        == (4, imu_emu::isb::did::IMU, imu_emu::isb::sets::imu::SIZE)));
    // The GET's own packet at once (the service that received it, 1.5 ms),
    // then one every 8 ticks: 25 in 100 ms.
    assert_eq!(
        p.len(),
        26,
        "{:?}",
        p.iter().map(|x| x.0).collect::<Vec<_>>()
    );
    assert_eq!(p[0].0, 1_500_000);
    let times: Vec<f64> = p
        .iter()
        .map(|(_, _, _, l)| imu_emu::isb::sets::Imu::decode(l.as_slice().try_into().unwrap()).time)
        .collect();
    for (w, t) in p[1..].windows(2).zip(times[1..].windows(2)) {
        // On the board's clock and in the packets' own time field.
        assert_eq!(w[1].0 - w[0].0, 4_000_000);
        assert!((t[1] - t[0] - 0.004).abs() < 1e-9, "{t:?}");
    }
    assert_eq!(s.device().mode(), imu_emu::device::Mode::Continuous);
    assert_eq!(s.device().output_rate(), Some(250));
}

/// GA frames (Table 5.7) in `tx` from byte `skip`: gyro X in 1e-5 °/s and
/// the USW of each.
fn ga_x_and_usw(tx: &[(u64, u8)], skip: usize) -> Vec<(f64, u16)> {
    let bytes: Vec<u8> = tx.iter().map(|&(_, x)| x).collect();
    bytes[skip..]
        .chunks_exact(40)
        .map(|f| {
            let p = &f[6..38];
            let x = i32::from_le_bytes([p[0], p[1], p[2], p[3]]);
            (f64::from(x) * 1e-5, u16::from_le_bytes([p[26], p[27]]))
        })
        .collect()
}

/// Full-state rows are a host feed's (docs/feed.md): the firmware counts
/// them as `kind` and takes nothing.
#[test]
fn full_state_rows_are_rejected_as_kind() {
    use imu_emu::feed::Reject;
    let mut feed = feed::FeedIn::default();
    feed.on_bytes(
        b"time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n0,45,7,300,0,0,0,0,0,0\n",
        0,
    );
    let c = feed.counts();
    assert_eq!(c.rejected[Reject::UnsupportedKind as usize], 1);
    assert_eq!((c.samples, c.rejected_total()), (0, 1));
    assert_eq!(feed.at(1).0, None);
}

/// The feed UART: binary samples (split anywhere) move the gyros from the
/// next service; silence beyond the timeout sets USW bit 1 (sensor
/// communication failure), the last sample holding; a sample clears it.
#[test]
fn feed_samples_move_the_gyros_and_silence_is_a_sensor_fault() {
    use imu_emu::feed::{encode, RateSample, MAX_FRAME, OWN_DEVICE};
    use imu_emu::sensor::Truth;
    let (mut s, b) = shell();
    b.borrow_mut().rx = frame(&[0x8F]);
    b.borrow_mut().room = 1000;
    let mut feed = feed::FeedIn::default();
    let mut q: heapless::spsc::Queue<u8, 256> = heapless::spsc::Queue::new();
    let (mut tx, mut rx) = q.split();
    let sample = |t: u64, x: f32| {
        let mut f = [0u8; MAX_FRAME];
        let n = encode(
            &RateSample {
                device: OWN_DEVICE,
                time_ns: t,
                truth: Truth {
                    rate_dps: [x, 0.0, 0.0],
                    specific_force_g: [0.0, 0.0, 1.0],
                    temperature_c: None,
                },
            },
            &mut f,
        );
        f[..n].to_vec()
    };
    let mut step = |s: &mut TestShell, rx: &mut heapless::spsc::Consumer<'_, u8>, until: u64| loop {
        let now = b.borrow().now;
        if now >= until {
            break;
        }
        b.borrow_mut().now = now + 500_000;
        b.borrow_mut().fifo = 0;
        s.feed(&mut feed, rx);
        s.service();
    };
    let t0 = 1_000_000;
    step(&mut s, &mut rx, t0 + 50_000_000);
    for &byte in &sample(0, 100.0)[..20] {
        tx.enqueue(byte).unwrap();
    }
    step(&mut s, &mut rx, t0 + 51_000_000);
    for &byte in &sample(0, 100.0)[20..] {
        tx.enqueue(byte).unwrap();
    }
    step(&mut s, &mut rx, t0 + 150_000_000);
    let ack = 10;
    let before = ga_x_and_usw(&b.borrow().tx, ack);
    let n = before.len();
    assert!(before[..4].iter().all(|&(x, u)| x.abs() < 1.0 && u == 0));
    assert!((before[n - 1].0 - 100.0).abs() < 1.0, "{before:?}");
    assert_eq!(before[n - 1].1 & 2, 0);
    // Silent for more than 100 ms: the fault, the rate held.
    step(&mut s, &mut rx, t0 + 300_000_000);
    let silent = ga_x_and_usw(&b.borrow().tx, ack);
    let &(x, usw) = silent.last().unwrap();
    assert!((x - 100.0).abs() < 1.0 && usw & 2 == 2, "{silent:?}");
    for byte in sample(1, -20.0) {
        tx.enqueue(byte).unwrap();
    }
    step(&mut s, &mut rx, t0 + 350_000_000);
    let back = ga_x_and_usw(&b.borrow().tx, ack);
    let &(x, usw) = back.last().unwrap();
    assert!((x + 20.0).abs() < 1.0 && usw & 2 == 0, "{back:?}");
    assert_eq!(feed.counts().samples, 2);
}
