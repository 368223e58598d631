//! Whole-process measurement client for `scripts/bench.sh` (README,
//! "Performance"): connects to one or more running devices (`imu-emu
//! --tcp`, or the ports of `imu-emu --count N`), switches each to 2 Mbaud
//! (Baud_Rate 0x0B, CommitBaudRate), Data_Rate 2000, optionally LPF 16 Hz
//! and all cascade filters, starts GA and reads them all for a while, in
//! one thread (one `ppoll` over every socket).
//!
//! Every GA frame's 2 kHz counter (Table 5.7) must step by exactly one on
//! each device — device time exact, no frame lost or repeated — or the
//! client fails.
//!
//! ```text
//! loadgen ADDR[,ADDR…] SECONDS [--filters] [--pid PID] [--rate HZ] [--worst N] [--at-once]
//! ```
//!
//! `--at-once` (TCP) sends the configuration and the start without the
//! pauses between them: at `--speed max` device time runs on while the
//! client pauses (ticks without output, as many as the host computes
//! meanwhile), which `scripts/speed-instr.sh` keeps out of its count.
//!
//! `--rate HZ` streams at that Data_Rate instead of 2000 (a divisor of
//! 2000): every counter step must then be 2000 / HZ. `--worst N` (with
//! `--pid`) also lists the N latest frames on stderr (`late_us= dev=
//! frame=`): frames of every device late at the same frame index are a
//! stall of the whole emulator, client or machine, not of one device.
//!
//! An ADDR starting with `/` is a pty (`imu-emu --pty`'s slave or its
//! `--link`), opened raw; the rest are TCP addresses.
//!
//! Prints one line of `key=value` pairs: `devices`, `frames` (all
//! devices), `wall_s`, `factor` (device seconds per wall second, the mean
//! over the devices), and with `--pid` the emulator's CPU share of one
//! core over the read (`/proc/PID/stat` utime + stime, from when every
//! device streams), and the lateness of each frame against its wire time,
//! `late_p50_us`, `late_p99_us`, `late_p999_us`, `late_max_us` over the
//! frames of all devices: a frame's wire time is its device's counter ×
//! 500 µs plus its own time on a 2 Mbaud line, aligned on that device's
//! earliest frame (so lateness ≥ 0; only meaningful at `--speed 1`).

use std::fs::File;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use nix::poll::{PollFd, PollFlags, PollTimeout};

use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::Decoder;
use imu_emu::kernel::params;

/// A device's line: a TCP connection or a pty opened raw.
enum Line {
    Tcp(TcpStream),
    Pty(File),
}

impl Line {
    fn open(addr: &str) -> Line {
        if addr.starts_with('/') {
            use nix::sys::termios;
            use std::os::unix::fs::OpenOptionsExt;
            let f = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .custom_flags(nix::fcntl::OFlag::O_NOCTTY.bits())
                .open(addr)
                .expect("open the pty");
            let mut t = termios::tcgetattr(&f).expect("tcgetattr");
            termios::cfmakeraw(&mut t);
            // The device's factory rate; `follow_baud` switches later.
            termios::cfsetspeed(&mut t, termios::BaudRate::B115200).expect("cfsetspeed");
            termios::tcsetattr(&f, termios::SetArg::TCSANOW, &t).expect("tcsetattr");
            Line::Pty(f)
        } else {
            let s = TcpStream::connect(addr).expect("connect");
            s.set_nodelay(true).ok();
            Line::Tcp(s)
        }
    }

    /// After CommitBaudRate: a pty's port follows the device to 2 Mbaud
    /// (a mismatch garbles, as on a real line); TCP has no rate.
    fn follow_baud(&self) -> bool {
        let Line::Pty(f) = self else { return false };
        use nix::sys::termios;
        let mut t = termios::tcgetattr(f).expect("tcgetattr");
        termios::cfsetspeed(&mut t, termios::BaudRate::B2000000).expect("cfsetspeed");
        termios::tcsetattr(f, termios::SetArg::TCSADRAIN, &t).expect("tcsetattr");
        true
    }

    fn set_nonblocking(&self) {
        match self {
            Line::Tcp(s) => s.set_nonblocking(true).expect("nonblocking"),
            Line::Pty(f) => {
                use nix::fcntl::{fcntl, FcntlArg, OFlag};
                let fl = OFlag::from_bits_truncate(fcntl(f, FcntlArg::F_GETFL).expect("F_GETFL"));
                fcntl(f, FcntlArg::F_SETFL(fl | OFlag::O_NONBLOCK)).expect("F_SETFL");
            }
        }
    }
}

impl Read for Line {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self {
            Line::Tcp(s) => s.read(buf),
            Line::Pty(f) => f.read(buf),
        }
    }
}

impl Write for Line {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Line::Tcp(s) => s.write(buf),
            Line::Pty(f) => f.write(buf),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl AsFd for Line {
    fn as_fd(&self) -> std::os::fd::BorrowedFd<'_> {
        match self {
            Line::Tcp(s) => s.as_fd(),
            Line::Pty(f) => f.as_fd(),
        }
    }
}

fn send(s: &mut Line, c: Command) {
    let mut out = [0u8; 64];
    let n = c.encode(&mut out).expect("encode");
    s.write_all(&out[..n]).expect("send");
}

fn save(s: &mut Line, id: u16, value: &[u8]) {
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

/// One device being read.
struct Dev {
    s: Line,
    d: Decoder<1024>,
    acked: bool,
    last: Option<u16>,
    /// Counter steps seen (device time in 500 µs).
    unwrapped: u64,
    frames: u64,
    /// Host time of the first data frame.
    t0: Option<Instant>,
    /// (arrival ns since t0) − (counter × 500 µs) − wire time, per frame.
    offsets: Vec<i64>,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let addrs: Vec<&str> = args[1].split(',').collect();
    let secs: f64 = args[2].parse().expect("SECONDS");
    let filters = args.iter().any(|a| a == "--filters");
    let at_once = args.iter().any(|a| a == "--at-once");
    let pause = |ms| {
        if !at_once {
            std::thread::sleep(Duration::from_millis(ms));
        }
    };
    let rate: u16 = args
        .iter()
        .position(|a| a == "--rate")
        .map_or(2000, |i| args[i + 1].parse().expect("HZ"));
    assert!(rate > 0 && 2000 % rate == 0, "--rate must divide 2000");
    let step = 2000 / rate;
    let worst: usize = args
        .iter()
        .position(|a| a == "--worst")
        .map_or(0, |i| args[i + 1].parse().expect("N"));
    let pid: Option<u32> = args
        .iter()
        .position(|a| a == "--pid")
        .map(|i| args[i + 1].parse().expect("PID"));

    let mut devs: Vec<Dev> = addrs
        .iter()
        .map(|addr| {
            let mut s = Line::open(addr);
            save(&mut s, params::BAUD_RATE.id, &[0x0B]);
            send(&mut s, Command::CommitBaudRate);
            pause(20);
            if s.follow_baud() {
                // The emulator reads the port's speed every 20 ms.
                std::thread::sleep(Duration::from_millis(100));
            }
            save(&mut s, params::DATA_RATE.id, &rate.to_le_bytes());
            if filters {
                save(&mut s, params::LPF_BANDWIDTH.id, &[0]);
                save(&mut s, params::FILTER.id, &[7]);
            }
            Dev {
                s,
                d: Decoder::new(),
                acked: false,
                last: None,
                unwrapped: 0,
                frames: 0,
                t0: None,
                offsets: Vec::new(),
            }
        })
        .collect();
    pause(200);
    for dev in &mut devs {
        send(&mut dev.s, Command::Data(0x8F));
        dev.s.set_nonblocking();
    }

    let mut buf = vec![0u8; 1 << 20];
    // When every device streams, and the emulator's CPU time then.
    let mut all_at: Option<Instant> = None;
    let mut cpu0 = 0;
    let mut idle_since = Instant::now();
    // GA frame on a 2 Mbaud line: 40 bytes × 10 bits.
    let wire_ns = 40 * 10 * 1_000_000_000 / 2_000_000;
    loop {
        {
            let mut fds: Vec<PollFd<'_>> = devs
                .iter()
                .map(|d| PollFd::new(d.s.as_fd(), PollFlags::POLLIN))
                .collect();
            nix::poll::poll(&mut fds, PollTimeout::from(100u16)).expect("poll");
        }
        let mut got_any = false;
        for dev in &mut devs {
            let n = match dev.s.read(&mut buf) {
                Ok(0) => panic!("emulator closed the connection"),
                Ok(n) => n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => continue,
                Err(e) => panic!("read: {e}"),
            };
            got_any = true;
            let at = Instant::now();
            let mut input = &buf[..n];
            while let Some(f) = dev.d.next_frame(&mut input) {
                if f.id != 0x8F {
                    continue;
                }
                if !dev.acked {
                    // The acknowledgement (2 bytes) comes first.
                    if f.payload.len() == 2 {
                        dev.acked = true;
                    }
                    continue;
                }
                let c = u16::from_le_bytes([f.payload[24], f.payload[25]]);
                match dev.last {
                    None => dev.t0 = Some(at),
                    Some(l) => {
                        assert_eq!(c, l.wrapping_add(step), "frame lost or repeated");
                        dev.unwrapped += u64::from(step);
                    }
                }
                dev.last = Some(c);
                dev.frames += 1;
                if pid.is_some() {
                    let t0 = dev.t0.unwrap_or(at);
                    let arrival = at.duration_since(t0).as_nanos() as i64;
                    dev.offsets
                        .push(arrival - (dev.unwrapped * 500_000) as i64 - wire_ns);
                }
            }
        }
        let now = Instant::now();
        if got_any {
            idle_since = now;
        }
        assert!(
            now.duration_since(idle_since) < Duration::from_secs(5),
            "no data for 5 s"
        );
        if all_at.is_none() && devs.iter().all(|d| d.t0.is_some()) {
            all_at = Some(now);
            cpu0 = pid.map_or(0, cpu_ticks);
        }
        if devs.iter().all(|d| {
            d.t0.is_some_and(|t| now.duration_since(t).as_secs_f64() >= secs)
        }) {
            break;
        }
    }
    let end = Instant::now();
    let frames: u64 = devs.iter().map(|d| d.frames).sum();
    let factor = devs
        .iter()
        .map(|d| d.unwrapped as f64 / 2000.0 / end.duration_since(d.t0.unwrap()).as_secs_f64())
        .sum::<f64>()
        / devs.len() as f64;
    let wall = end.duration_since(devs.iter().filter_map(|d| d.t0).min().unwrap());
    print!(
        "devices={} frames={frames} wall_s={:.3} factor={factor:.1}",
        devs.len(),
        wall.as_secs_f64()
    );
    if let Some(pid) = pid {
        let hz = 100.0; // USER_HZ on Linux
        let cpu = (cpu_ticks(pid) - cpu0) as f64 / hz;
        let window = end.duration_since(all_at.unwrap()).as_secs_f64();
        if worst > 0 {
            let mut w: Vec<(i64, usize, usize)> = Vec::new();
            for (k, d) in devs.iter().enumerate() {
                let min = *d.offsets.iter().min().unwrap();
                for (i, o) in d.offsets.iter().enumerate() {
                    w.push((o - min, k, i));
                }
            }
            w.sort_unstable();
            for (l, k, i) in w.iter().rev().take(worst) {
                eprintln!("late_us={} dev={k} frame={i}", l / 1000);
            }
        }
        let mut late: Vec<i64> = Vec::with_capacity(frames as usize);
        for d in &devs {
            let min = *d.offsets.iter().min().unwrap();
            late.extend(d.offsets.iter().map(|o| o - min));
        }
        late.sort_unstable();
        let p = |q: f64| late[((late.len() - 1) as f64 * q).round() as usize] as f64 / 1000.0;
        print!(
            " cpu_pct={:.2} late_p50_us={:.0} late_p99_us={:.0} late_p999_us={:.0} late_max_us={:.0}",
            100.0 * cpu / window,
            p(0.5),
            p(0.99),
            p(0.999),
            p(1.0)
        );
    }
    println!();
}
