//! Whole-process measurement client for the IMX-5's navigation outputs
//! (docs/performance.md "Navigation filter", `scripts/isb-fleet.sh`):
//! connects to one or more running `imu-emu --protocol isb` devices
//! (`--tcp`, or the ports of `--count N`), raises each line to 3 Mbaud
//! (FLASH_CONFIG `ser0BaudRate`, then `$SRST`), and streams every
//! navigation data set at its source period: INS_1..INS_4, INL2_STATES,
//! INL2_NED_SIGMA (4 ms), GPS1_POS, GPS1_VEL (200 ms), GPS1_SAT (1 s),
//! MAGNETOMETER (10 ms), BAROMETER (8 ms). One thread, one `poll` over
//! every socket, so that the client's own reading is one place to look
//! at when something is late.
//!
//! Every packet's own time field must step by exactly its data set's
//! output period from the previous packet of that data set (4 ms for the
//! navigation period's, 200 ms, 1 s, 10 ms, 8 ms for the others) — none
//! missed, none repeated. The step at the first fix, when the time fields
//! switch from time since boot to GPS time (a jump of more than 1 000 s:
//! run the emulator with a `--gps-time` whose time of week is larger), is
//! counted apart (`timebase_switches`).
//!
//! ```text
//! isb_navload ADDR[,ADDR…] SECONDS [--pid PID] [--control ADDR] [--list N] [--warmup S]
//! ```
//!
//! The measured window starts `--warmup` seconds (default 2) after the
//! streams were asked for and lasts SECONDS. Prints one line of
//! `key=value` pairs: `devices`, `packets` (in the window, every data
//! set), `checked` (those whose step was checked), `wrong_steps` (packets
//! whose step is not their period), `missing_periods` (periods absent
//! from a data set's sequence), `repeated`, `decoder_errors` (candidates the
//! packet decoder dropped: bytes lost or corrupted on the way),
//! `wall_s`, `factor` (device seconds of INS_2, by its own time field, per
//! wall second, the mean over the devices), the lateness of every INS_2
//! packet against its own time (`late_p50_us`, `late_p99_us`,
//! `late_p999_us`, `late_max_us`: its arrival − its time field, aligned on
//! that device's earliest, so ≥ 0: how far the stream ran behind real time
//! at worst; only in real time, a `factor` below 1.5), and the client's own
//! CPU (`client_cpu_pct`). With `--pid`:
//! the emulator's CPU share of one core over the window (`cpu_pct`,
//! `/proc/PID/stat` utime + stime), the device seconds it computed per
//! second of its CPU (`device_s_per_cpu_s`: about what `--speed max` reaches
//! with a core of its own and a client that keeps up) and its memory (`rss_kib`,
//! `hwm_kib`).
//! With `--control` (the emulator's control socket): the emulator's own
//! counts summed over the devices at the end — frames its TX queues
//! dropped (`emu_tx_dropped`), bytes its transports' backlogs dropped for a
//! client that did not read (`emu_backlog_dropped`), and how long it held
//! device time back because it could not keep up (`emu_held_back_ms`).
//! `--list N` lists the first N wrong steps on stderr (`dev`, data set,
//! previous and new time, step, arrival).

use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use nix::poll::{PollFd, PollFlags, PollTimeout};

use imu_emu::isb::did;
use imu_emu::isb::message::{encode_get, encode_set, GetRequest};
use imu_emu::isb::packet::Decoder;
use imu_emu::isb::sets::flash;

/// The navigation period of the default configuration, s.
const NAV_PERIOD_S: f64 = 0.004;

fn get(did: u8, period: u16) -> Vec<u8> {
    let req = GetRequest {
        did: u16::from(did),
        size: 0,
        offset: 0,
        period,
    };
    let mut out = [0u8; 64];
    let n = encode_get(&req, &mut out).unwrap();
    out[..n].to_vec()
}

/// Every data set streamed, and its output period, s: the six of the
/// navigation period, then the receiver's (`startupGPSDtMs`, 200 ms; GPS1_SAT
/// 1 s), the magnetometer's (10 ms) and the barometer's (8 ms)
/// (`src/isb/did.rs` sources).
const STREAMS: [(u8, f64); 11] = [
    (did::INS_1, NAV_PERIOD_S),
    (did::INS_2, NAV_PERIOD_S),
    (did::INS_3, NAV_PERIOD_S),
    (did::INS_4, NAV_PERIOD_S),
    (did::INL2_STATES, NAV_PERIOD_S),
    (did::INL2_NED_SIGMA, NAV_PERIOD_S),
    (did::GPS1_POS, 0.2),
    (did::GPS1_VEL, 0.2),
    (did::GPS1_SAT, 1.0),
    (did::MAGNETOMETER, 0.010),
    (did::BAROMETER, 0.008),
];

/// A streamed packet's time, s: its own time field (SDK 2.7.1 layouts,
/// docs/isb-data-sets.md).
fn time_of(d: u8, p: &[u8]) -> Option<f64> {
    let f64_at = |o: usize| f64::from_le_bytes(p.get(o..o + 8)?.try_into().ok()?).into();
    let ms_at =
        |o: usize| Some(f64::from(u32::from_le_bytes(p.get(o..o + 4)?.try_into().ok()?)) / 1e3);
    match d {
        did::INS_1 | did::INS_2 | did::INS_3 | did::INS_4 => f64_at(4),
        did::INL2_STATES | did::MAGNETOMETER | did::BAROMETER => f64_at(0),
        did::GPS1_POS => ms_at(4),
        did::INL2_NED_SIGMA | did::GPS1_VEL | did::GPS1_SAT => ms_at(0),
        _ => None,
    }
}

/// One device's connection and what was seen on it.
struct Dev {
    s: TcpStream,
    dec: Decoder<4096>,
    last: [Option<f64>; 11],
    packets: u64,
    checked: u64,
    wrong: u64,
    missing: u64,
    repeated: u64,
    switches: u64,
    /// INS_2: device seconds counted by its steps, and the correction that
    /// makes its time field continuous across the time-base switch.
    ins2_s: f64,
    ins2_corr: f64,
    /// INS_2 arrival (s since the client's start) − its (continuous) time.
    offsets: Vec<f64>,
}

/// utime + stime of `/proc/PID/stat`, clock ticks.
fn cpu_ticks(pid: &str) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc/PID/stat");
    // After the command's closing parenthesis: fields 3.. of proc(5).
    let rest = &s[s.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap()
}

/// A `/proc/PID/status` line's value in KiB (`VmRSS`, `VmHWM`).
fn status_kib(pid: &str, key: &str) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// The emulator's counts, summed over `n` devices, from its control socket.
fn emulator_counts(control: &str, n: usize) -> (u64, u64, u64) {
    let mut s = TcpStream::connect(control).expect("connect to the control socket");
    let mut r = BufReader::new(s.try_clone().unwrap());
    let (mut tx, mut backlog, mut held) = (0, 0, 0);
    let word = |line: &str, key: &str| -> u64 {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    };
    for k in 0..n {
        writeln!(s, "dev {k} status").unwrap();
        let mut line = String::new();
        loop {
            line.clear();
            r.read_line(&mut line).unwrap();
            if !line.starts_with("event ") {
                break;
            }
        }
        assert!(line.starts_with("ok "), "dev {k} status: {line}");
        tx += word(&line, "tx-dropped=");
        backlog += word(&line, "backlog-dropped=");
        held += word(&line, "held-back-ms=");
    }
    (tx, backlog, held)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let addrs: Vec<String> = args[1].split(',').map(str::to_owned).collect();
    let secs: f64 = args[2].parse().unwrap();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .map(|i| args[i + 1].clone())
    };
    let pid = opt("--pid");
    let control = opt("--control");
    let list: u64 = opt("--list").map_or(0, |v| v.parse().unwrap());
    let warmup: f64 = opt("--warmup").map_or(2.0, |v| v.parse().unwrap());

    let t0 = Instant::now();
    let mut devs: Vec<Dev> = addrs
        .iter()
        .map(|a| {
            let s = TcpStream::connect(a).expect("connect");
            s.set_nodelay(true).ok();
            Dev {
                s,
                dec: Decoder::new(),
                last: [None; 11],
                packets: 0,
                checked: 0,
                wrong: 0,
                missing: 0,
                repeated: 0,
                switches: 0,
                ins2_s: 0.0,
                ins2_corr: 0.0,
                offsets: Vec::new(),
            }
        })
        .collect();
    let mut out = [0u8; 64];
    let n = encode_set(
        did::FLASH_CONFIG,
        flash::SER0_BAUD_RATE as u16,
        &3_000_000u32.to_le_bytes(),
        &mut out,
    )
    .unwrap();
    for d in &mut devs {
        d.s.write_all(&out[..n]).unwrap();
    }
    std::thread::sleep(Duration::from_millis(200));
    for d in &mut devs {
        d.s.write_all(b"$SRST*06\r\n").unwrap();
    }
    std::thread::sleep(Duration::from_millis(300));
    for d in &mut devs {
        for (id, _) in STREAMS {
            d.s.write_all(&get(id, 1)).unwrap();
        }
        d.s.set_nonblocking(true).unwrap();
    }
    let start = Instant::now() + Duration::from_secs_f64(warmup);
    let end = start + Duration::from_secs_f64(secs);
    let mut cpu0 = None;
    let self_pid = std::process::id().to_string();
    let mut self0 = 0;
    let mut listed = 0;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let now = Instant::now();
        if now >= end {
            break;
        }
        if now >= start && cpu0.is_none() {
            cpu0 = Some(pid.as_deref().map_or(0, cpu_ticks));
            self0 = cpu_ticks(&self_pid);
        }
        {
            let mut fds: Vec<PollFd<'_>> = devs
                .iter()
                .map(|d| PollFd::new(d.s.as_fd(), PollFlags::POLLIN))
                .collect();
            nix::poll::poll(&mut fds, PollTimeout::from(100u16)).expect("poll");
        }
        for (k, dev) in devs.iter_mut().enumerate() {
            let n = match dev.s.read(&mut buf) {
                Ok(0) => panic!("dev {k}: the emulator closed the connection"),
                Ok(n) => n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => continue,
                Err(e) => panic!("dev {k}: read: {e}"),
            };
            let at = Instant::now();
            let in_window = at >= start;
            let arrival = at.duration_since(t0).as_secs_f64();
            let mut input = &buf[..n];
            let errors = dev.dec.errors();
            while let Some(p) = dev.dec.next_packet(&mut input) {
                if p.flags != 4 {
                    continue;
                }
                if in_window {
                    dev.packets += 1;
                }
                let Some(i) = STREAMS.iter().position(|&(d, _)| d == p.did) else {
                    continue;
                };
                let period = STREAMS[i].1;
                let Some(t) = time_of(p.did, p.payload) else {
                    continue;
                };
                let prev = dev.last[i].replace(t);
                if !in_window {
                    continue;
                }
                dev.checked += 1;
                let Some(prev) = prev else { continue };
                let step = t - prev;
                if step.abs() >= 1000.0 {
                    // The time base's switch to GPS time at the first fix.
                    dev.switches += 1;
                    if p.did == did::INS_2 {
                        dev.ins2_corr += step - NAV_PERIOD_S;
                    }
                } else if (step - period).abs() > 1e-6 {
                    dev.wrong += 1;
                    let periods = (step / period).round();
                    if step.abs() < 1e-6 {
                        dev.repeated += 1;
                    } else if periods >= 2.0 && (step - periods * period).abs() < 1e-6 {
                        dev.missing += periods as u64 - 1;
                    }
                    if listed < list {
                        listed += 1;
                        eprintln!(
                            "wrong step: dev={k} did={} prev={prev:.4} t={t:.4} step_ms={:.3} \
                             arrival_s={arrival:.4} decoder_errors_before_read={errors}",
                            p.did,
                            step * 1e3,
                        );
                    }
                }
                if p.did == did::INS_2 {
                    dev.ins2_s += NAV_PERIOD_S;
                    dev.offsets.push(arrival - (t - dev.ins2_corr));
                }
            }
        }
    }
    let cpu1 = pid.as_deref().map_or(0, cpu_ticks);
    let self1 = cpu_ticks(&self_pid);
    let hz = 100.0; // USER_HZ on Linux
    let sum = |f: fn(&Dev) -> u64| devs.iter().map(f).sum::<u64>();
    let factor = devs.iter().map(|d| d.ins2_s).sum::<f64>() / devs.len() as f64 / secs;
    let mut late: Vec<f64> = devs
        .iter()
        .flat_map(|d| {
            let min = d.offsets.iter().copied().fold(f64::INFINITY, f64::min);
            d.offsets.iter().map(move |o| (o - min) * 1e6)
        })
        .collect();
    late.sort_by(f64::total_cmp);
    let pct = |p: f64| {
        late.get(((late.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    print!(
        "devices={} packets={} checked={} wrong_steps={} missing_periods={} repeated={} \
         timebase_switches={} decoder_errors={} wall_s={secs:.1} factor={factor:.3} \
         client_cpu_pct={:.1}",
        devs.len(),
        sum(|d| d.packets),
        sum(|d| d.checked),
        sum(|d| d.wrong),
        sum(|d| d.missing),
        sum(|d| d.repeated),
        sum(|d| d.switches),
        devs.iter().map(|d| u64::from(d.dec.errors())).sum::<u64>(),
        (self1 - self0) as f64 / hz / secs * 100.0,
    );
    if factor < 1.5 {
        print!(
            " late_p50_us={:.0} late_p99_us={:.0} late_p999_us={:.0} late_max_us={:.0}",
            pct(0.5),
            pct(0.99),
            pct(0.999),
            late.last().copied().unwrap_or(0.0),
        );
    }
    if let Some(pid) = &pid {
        let cpu_s = (cpu1 - cpu0.unwrap_or(cpu1)) as f64 / hz;
        print!(
            " cpu_pct={:.1} device_s_per_cpu_s={:.0} rss_kib={} hwm_kib={}",
            cpu_s / secs * 100.0,
            factor * secs / cpu_s.max(0.01),
            status_kib(pid, "VmRSS:"),
            status_kib(pid, "VmHWM:"),
        );
    }
    if let Some(c) = &control {
        let (tx, backlog, held) = emulator_counts(c, devs.len());
        print!(" emu_tx_dropped={tx} emu_backlog_dropped={backlog} emu_held_back_ms={held}");
    }
    println!();
}
