//! Whole-process measurement client for `scripts/bench.sh` (README,
//! "Performance"): connects to a running `imu-emu --tcp`, switches it to
//! 2 Mbaud (Baud_Rate 0x0B, CommitBaudRate), Data_Rate 2000, optionally
//! LPF 16 Hz and all cascade filters, starts GA and reads for a while.
//!
//! Every GA frame's 2 kHz counter (Table 5.7) must step by exactly one —
//! device time exact, no frame lost or repeated — or the client fails.
//!
//! ```text
//! loadgen ADDR SECONDS [--filters] [--pid PID]
//! ```
//!
//! Prints one line of `key=value` pairs: `frames`, `wall_s`, `factor`
//! (device seconds per wall second), and with `--pid` the emulator's CPU
//! share of one core over the read (`/proc/PID/stat` utime + stime), and
//! the lateness of each frame against its wire time, `late_p50_us`,
//! `late_p99_us`, `late_p999_us`, `late_max_us`: a frame's wire time is
//! the device's counter × 500 µs plus its own time on a 2 Mbaud line,
//! aligned on the earliest frame (so lateness ≥ 0; only meaningful at
//! `--speed 1`).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::Decoder;
use imu_emu::kernel::params;

fn send(s: &mut TcpStream, c: Command) {
    let mut out = [0u8; 64];
    let n = c.encode(&mut out).expect("encode");
    s.write_all(&out[..n]).expect("send");
}

fn save(s: &mut TcpStream, id: u16, value: &[u8]) {
    send(
        s,
        Command::SaveFlash {
            id,
            len: value.len() as u16,
            value,
        },
    );
}

/// utime + stime of `pid`, in clock ticks.
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("stat");
    // Fields after the command name (which is in parentheses).
    let rest = &stat[stat.rfind(')').expect("stat") + 2..];
    let f: Vec<&str> = rest.split(' ').collect();
    f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let addr = &args[1];
    let secs: f64 = args[2].parse().expect("SECONDS");
    let filters = args.iter().any(|a| a == "--filters");
    let pid: Option<u32> = args
        .iter()
        .position(|a| a == "--pid")
        .map(|i| args[i + 1].parse().expect("PID"));

    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_nodelay(true).ok();
    save(&mut s, params::BAUD_RATE.id, &[0x0B]);
    send(&mut s, Command::CommitBaudRate);
    save(&mut s, params::DATA_RATE.id, &2000u16.to_le_bytes());
    if filters {
        save(&mut s, params::LPF_BANDWIDTH.id, &[0]);
        save(&mut s, params::FILTER.id, &[7]);
    }
    std::thread::sleep(Duration::from_millis(200));
    send(&mut s, Command::Data(0x8F));
    s.set_read_timeout(Some(Duration::from_secs(5))).ok();

    let mut d = Decoder::<1024>::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut last: Option<u16> = None;
    let mut acked = false;
    let mut frames = 0u64;
    let mut unwrapped = 0u64;
    // (arrival ns since t0) − (counter × 500 µs), per frame.
    let mut offsets: Vec<i64> = Vec::new();
    let mut t0 = Instant::now();
    let mut cpu0 = 0;
    // GA frame on a 2 Mbaud line: 40 bytes × 10 bits.
    let wire_ns = 40 * 10 * 1_000_000_000 / 2_000_000;
    loop {
        let n = s.read(&mut buf).expect("read");
        assert!(n > 0, "emulator closed the connection");
        let at = Instant::now();
        let mut input = &buf[..n];
        while let Some(f) = d.next_frame(&mut input) {
            if f.id != 0x8F {
                continue;
            }
            if !acked {
                // The acknowledgement (2 bytes) comes first.
                if f.payload.len() == 2 {
                    acked = true;
                }
                continue;
            }
            let c = u16::from_le_bytes([f.payload[24], f.payload[25]]);
            match last {
                None => {
                    t0 = at;
                    cpu0 = pid.map_or(0, cpu_ticks);
                }
                Some(l) => {
                    assert_eq!(c, l.wrapping_add(1), "frame lost or repeated");
                    unwrapped += 1;
                }
            }
            last = Some(c);
            frames += 1;
            if pid.is_some() {
                let arrival = at.duration_since(t0).as_nanos() as i64;
                offsets.push(arrival - (unwrapped * 500_000) as i64 - wire_ns);
            }
        }
        if last.is_some() && at.duration_since(t0).as_secs_f64() >= secs {
            break;
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    let device_s = unwrapped as f64 / 2000.0;
    print!(
        "frames={frames} wall_s={wall:.3} factor={:.1}",
        device_s / wall
    );
    if let Some(pid) = pid {
        let hz = 100.0; // USER_HZ on Linux
        let cpu = (cpu_ticks(pid) - cpu0) as f64 / hz;
        let min = *offsets.iter().min().unwrap();
        let mut late: Vec<i64> = offsets.iter().map(|o| o - min).collect();
        late.sort_unstable();
        let p = |q: f64| late[((late.len() - 1) as f64 * q).round() as usize] as f64 / 1000.0;
        print!(
            " cpu_pct={:.2} late_p50_us={:.0} late_p99_us={:.0} late_p999_us={:.0} late_max_us={:.0}",
            100.0 * cpu / wall,
            p(0.5),
            p(0.99),
            p(0.999),
            p(1.0)
        );
    }
    println!();
}
