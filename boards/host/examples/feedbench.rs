//! Live motion feed benchmark for `scripts/feed-bench.sh` (docs/feed.md,
//! "Figures"): the delay from a sample's arrival to the first frame that
//! carries it, and the feed's throughput, against a running
//! `imu-emu --tcp … --control … --motion-feed …` (real time).
//!
//! ```text
//! feedbench UART CONTROL FEED [--rate HZ] [--lpf CODE] [--steps N] [--burst N]
//! ```
//!
//! **Delay.** The device is switched to 2 Mbaud, Data_Rate `HZ` (default
//! 2000) and LPF_Bandwidth `CODE` (default 255: off, so that the first
//! frame computed from a sample shows it whole — with the power-on 262 Hz
//! FIR a step shows only through the filter's taps, 2 ticks later by the
//! 2 °/s test below, 3 ms to its middle: the sensor's own group delay,
//! ICD Table 5.24) and streams GA. A thread sends binary samples at
//! 2 kHz (paced by the host clock); every 40 ms the X rate steps between
//! +100 and −100 °/s. For each step the delay is from just before the
//! write of its first sample to the arrival of the first GA frame whose X
//! left the old value by more than 2 °/s (noise is ~0.05 °/s): what the
//! issue bounds by one internal tick plus the output period. The frame's
//! line time is not taken off: the emulator's line credit lets a frame
//! leave whole when its tick makes it (docs/feed.md).
//!
//! **Decomposed.** At Data_Rate = the internal rate every tick sends one
//! frame, so frame `n` is tick `n0 + n`, due at host time `base + n·P`
//! (`P` the output period) with `base` the earliest any frame came
//! relative to that grid (an upper bound of the true one by the best
//! wake-up, a few µs to tens of µs). Each step's delay is then split
//! into *send → its tick's deadline* (the design part: the first tick at
//! or after the sample's arrival, so below one period unless the
//! emulator read it late) and *deadline → frame read* (the emulator's
//! wake-up for that tick, the send, loopback and this reader's wake-up:
//! host scheduling), and counted: steps whose tick's deadline is a period
//! or more after their send (`late_ticks`: not the first tick after it).
//!
//! **Throughput.** A burst of `N` binary samples (default 200 000), then
//! of `N` text rows, each written as fast as the socket takes them; the
//! time until `status` counts them all.
//!
//! Prints the figures, then one line of `key=value` pairs.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use imu_emu::feed::{encode, RateSample, MAX_FRAME, OWN_DEVICE};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::Decoder;
use imu_emu::kernel::params;
use imu_emu::sensor::Truth;

fn send(s: &mut TcpStream, c: Command) {
    let mut out = [0u8; 64];
    let n = c.encode(&mut out).expect("encode");
    s.write_all(&out[..n]).expect("send");
}

fn save(s: &mut TcpStream, id: u16, value: &[u8]) {
    let len = value.len() as u16;
    send(s, Command::SaveFlash { id, len, value });
}

fn sample(t_ns: u64, x: f32) -> Vec<u8> {
    let s = RateSample {
        device: OWN_DEVICE,
        time_ns: t_ns,
        truth: Truth {
            rate_dps: [x, 0.0, 0.0],
            specific_force_g: [0.0, 0.0, 1.0],
            temperature_c: None,
        },
    };
    let mut f = [0u8; MAX_FRAME];
    let n = encode(&s, &mut f);
    f[..n].to_vec()
}

/// `feed-samples` of the `status` reply.
fn samples(ctl: &mut TcpStream) -> u64 {
    ctl.write_all(b"status\n").unwrap();
    let mut line = Vec::new();
    let mut b = [0u8; 1];
    while ctl.read(&mut b).unwrap() == 1 && b[0] != b'\n' {
        line.push(b[0]);
    }
    let line = String::from_utf8_lossy(&line);
    line.split_whitespace()
        .find_map(|w| w.strip_prefix("feed-samples="))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no feed-samples in {line}"))
}

fn pct(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() as f64 - 1.0) * p).round() as usize]
}

fn arg(args: &[String], name: &str, default: u64) -> u64 {
    args.iter()
        .position(|a| a == name)
        .map_or(default, |i| args[i + 1].parse().expect("a number"))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (uart, control, feed) = (&args[1], &args[2], &args[3]);
    let rate = arg(&args, "--rate", 2000) as u16;
    let steps = arg(&args, "--steps", 200);
    let burst = arg(&args, "--burst", 200_000);
    let lpf = arg(&args, "--lpf", 255) as u8;

    let mut u = TcpStream::connect(uart).expect("uart");
    u.set_nodelay(true).unwrap();
    save(&mut u, params::BAUD_RATE.id, &[0x0B]);
    send(&mut u, Command::CommitBaudRate);
    std::thread::sleep(Duration::from_millis(50));
    save(&mut u, params::DATA_RATE.id, &rate.to_le_bytes());
    save(&mut u, params::LPF_BANDWIDTH.id, &[lpf]);
    std::thread::sleep(Duration::from_millis(100));
    send(&mut u, Command::Data(0x8F));
    u.set_read_timeout(Some(Duration::from_millis(50))).unwrap();

    // The sender: 2 kHz samples, a step every 40 ms; each step's send time.
    let mut f = TcpStream::connect(feed).expect("feed");
    f.set_nodelay(true).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let sent: Arc<Mutex<Vec<(Instant, f32)>>> = Arc::default();
    let sender = {
        let (stop, sent) = (Arc::clone(&stop), Arc::clone(&sent));
        std::thread::spawn(move || {
            let t0 = Instant::now();
            let mut k = 0u64;
            let mut x = 100.0f32;
            while !stop.load(Ordering::Relaxed) {
                if k.is_multiple_of(80) {
                    x = -x;
                }
                // Each step moves the grid by 61 µs (mod 500): the steps
                // reach the device at every phase of its tick, not at the
                // one this run's start happened to give.
                let due = t0 + Duration::from_micros(500 * k + (k / 80) * 61 % 500);
                if let Some(d) = due.checked_duration_since(Instant::now()) {
                    std::thread::sleep(d);
                }
                let bytes = sample(k * 500_000 + 1, x);
                let at = Instant::now();
                f.write_all(&bytes).unwrap();
                if k.is_multiple_of(80) {
                    sent.lock().unwrap().push((at, x));
                }
                k += 1;
            }
            f
        })
    };

    // The reader: GA frames' X and arrival.
    let mut dec = Decoder::<64>::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut frames: Vec<(Instant, f64)> = Vec::new();
    let end = Instant::now() + Duration::from_millis(40 * (steps + 5));
    while Instant::now() < end {
        let n = match u.read(&mut buf) {
            Ok(n) => n,
            Err(_) => continue,
        };
        let at = Instant::now();
        let mut input = &buf[..n];
        while let Some(fr) = dec.next_frame(&mut input) {
            if fr.id == 0x8F && fr.payload.len() == 32 {
                let x = i32::from_le_bytes(fr.payload[..4].try_into().unwrap());
                frames.push((at, f64::from(x) * 1e-5));
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
    let mut f = sender.join().unwrap();

    // Frame n is due at base + n·P: base the earliest any frame came.
    let period = Duration::from_nanos(1_000_000_000 / u64::from(rate));
    let slot = |n: usize| period * n as u32;
    let base = frames
        .iter()
        .enumerate()
        .map(|(n, &(at, _))| at - slot(n))
        .min()
        .expect("GA frames");
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    // Every frame's lateness against the grid: the GA stream's own.
    let mut lateness: Vec<f64> = frames
        .iter()
        .enumerate()
        .map(|(n, &(at, _))| us(at - (base + slot(n))))
        .collect();
    let [f50, f99] = [0.5, 0.99].map(|p| pct(&mut lateness, p));
    let (mut delays, mut apply, mut host) = (Vec::new(), Vec::new(), Vec::new());
    let mut late_ticks = 0;
    for (i, &(t, x)) in sent.lock().unwrap().iter().enumerate().skip(2) {
        let old = -f64::from(x);
        if let Some((n, &(at, _))) = frames
            .iter()
            .enumerate()
            .find(|&(_, &(at, v))| at >= t && (v - old).abs() > 2.0)
        {
            let due = base + slot(n);
            delays.push(us(at - t));
            // Signed: a deadline before the send would be a frame
            // computed before its sample arrived (or a shifted grid).
            let a = if due >= t { us(due - t) } else { -us(t - due) };
            apply.push(a);
            host.push(us(at - due));
            // Not the first tick after the send (by more than the grid's
            // uncertainty: a deadline a whole period or more after it).
            if a >= us(period) {
                late_ticks += 1;
            }
        } else if i + 2 < steps as usize {
            panic!("step {i} never showed");
        }
    }

    // Throughput: binary, then text.
    let mut ctl = TcpStream::connect(control).expect("control");
    let mut t_ns = 1_000_000_000_000u64;
    let mut rate_of = |f: &mut TcpStream, text: bool| {
        let base = samples(&mut ctl);
        let mut bytes = Vec::with_capacity(burst as usize * 48);
        for _ in 0..burst {
            t_ns += 500_000;
            if text {
                bytes.extend(format!("{},1,0,0,0,0,1\n", t_ns as f64 * 1e-9).into_bytes());
            } else {
                bytes.extend(sample(t_ns, 1.0));
            }
        }
        let t0 = Instant::now();
        f.write_all(&bytes).unwrap();
        while samples(&mut ctl) < base + burst {
            std::thread::sleep(Duration::from_millis(1));
        }
        burst as f64 / t0.elapsed().as_secs_f64()
    };
    let binary = rate_of(&mut f, false);
    let text = rate_of(&mut f, true);

    let n = delays.len();
    let bound = 1e6 / 2000.0 + 1e6 / f64::from(rate);
    let [d50, d99, dmax] = [0.5, 0.99, 1.0].map(|p| pct(&mut delays, p));
    let [a50, a99, amax] = [0.5, 0.99, 1.0].map(|p| pct(&mut apply, p));
    let [h50, h99, hmax] = [0.5, 0.99, 1.0].map(|p| pct(&mut host, p));
    let within = delays.iter().filter(|&&d| d <= bound).count();
    println!("feed delay: {n} steps, GA at {rate} Hz, LPF_Bandwidth code {lpf}");
    println!(
        "  sample sent -> first GA frame carrying it  p50 {d50:.0} us  p99 {d99:.0} us  \
         max {dmax:.0} us  (bound {bound:.0} us: p99 {}; {within}/{n} within)",
        if d99 <= bound { "met" } else { "NOT met" }
    );
    println!(
        "  sent -> deadline of the tick that applied it  p50 {a50:.0} us  p99 {a99:.0} us  \
         max {amax:.0} us  (design: < {:.0} us; {late_ticks} steps a tick late)",
        1e6 / f64::from(rate)
    );
    println!(
        "  deadline -> frame read (host scheduling)     p50 {h50:.0} us  p99 {h99:.0} us  \
         max {hmax:.0} us"
    );
    println!(
        "  every GA frame, read after its deadline      p50 {f50:.0} us  p99 {f99:.0} us  \
         ({} frames)",
        frames.len()
    );
    if f50 > 0.5 * us(period) {
        println!(
            "  (warning: most frames a half period or more off the grid: frames lost or \
             device time held back; the decomposition is off)"
        );
    }
    println!("feed throughput: binary {binary:.0} samples/s, text {text:.0} rows/s");
    println!(
        "steps={n} rate_hz={rate} lpf={lpf} delay_p50_us={d50:.0} delay_p99_us={d99:.0} \
         delay_max_us={dmax:.0} bound_us={bound:.0} apply_p50_us={a50:.0} apply_p99_us={a99:.0} \
         apply_max_us={amax:.0} late_ticks={late_ticks} host_p50_us={h50:.0} host_p99_us={h99:.0} \
         host_max_us={hmax:.0} frame_p50_us={f50:.0} frame_p99_us={f99:.0} binary_samples_per_s={binary:.0} text_samples_per_s={text:.0}"
    );
}
