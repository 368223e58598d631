//! End-to-end tests of the many-device mode (`imu-emu --count N`, issue
//! 12): several devices in one process over TCP, each with its own port,
//! flash, seed and parameters (surviving a restart), addressed one by one
//! on the one control socket.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use support::{command, frames_with_counter, free_port, read_ram, save, Conn, Control, Emu};

const GA: u8 = 0x8F;
const STOP: u8 = 0xFE;
const GET_BIT: u8 = 0x1A;
const DATA_RATE: u16 = 0x0012;
const BAUD_RATE: u16 = 0x03B2;
/// Table 5.7: the 2 kHz counter at payload offset 24.
const COUNTER: usize = 24;

fn temp_dir(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-emu-fleet-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A `--count n` run with a control socket: the emulator, each device's
/// address (in the order of the stdout lines) and the control address.
fn start(n: usize, flash: &Path, extra: &[&str]) -> (Emu, Vec<SocketAddr>, String) {
    let ctl = format!("127.0.0.1:{}", free_port());
    let count = n.to_string();
    let flash = flash.to_str().unwrap();
    let mut args = vec![
        "--count",
        &count,
        "--tcp",
        "127.0.0.1:0",
        "--flash",
        flash,
        "--control",
        &ctl,
    ];
    args.extend_from_slice(extra);
    let emu = Emu::start(&args);
    let addrs: Vec<SocketAddr> = emu.tcp_addrs(n);
    assert_eq!(emu.more_lines(n)[n - 1], format!("control on tcp {ctl}"));
    (emu, addrs, ctl)
}

fn data_rate(c: &mut Conn) -> u16 {
    c.send(&read_ram(DATA_RATE, 2));
    let f = c.frame_with_id(0xB1);
    u16::from_le_bytes([f.payload()[0], f.payload()[1]])
}

/// GA frames' counter steps: each device streams at its own Data_Rate,
/// by its own 2 kHz counter (exact: every step is 2000 / rate).
fn assert_streams_at(c: &mut Conn, rate: u16) {
    c.send(&command(GA));
    c.frame_with_id(GA);
    let counters = frames_with_counter(c, GA, 20, COUNTER);
    for w in counters.windows(2) {
        assert_eq!(
            w[1].wrapping_sub(w[0]),
            2000 / rate,
            "at {rate} Hz: {counters:?}"
        );
    }
    c.send(&command(STOP));
}

#[test]
fn each_device_keeps_its_own_parameters_across_a_restart() {
    let dir = temp_dir("restart");
    let flash = dir.join("imu.flash");
    let rates = [200u16, 100, 50];
    {
        let (mut emu, addrs, _) = start(3, &flash, &["--seed", "7"]);
        let mut conns: Vec<Conn> = addrs.iter().map(|&a| Conn::tcp(a)).collect();
        // Device 1 keeps the factory Data_Rate (100 Hz); 0 and 2 save theirs.
        save(&mut conns[0], DATA_RATE, &rates[0].to_le_bytes());
        save(&mut conns[2], DATA_RATE, &rates[2].to_le_bytes());
        for (c, &r) in conns.iter_mut().zip(&rates) {
            assert_eq!(data_rate(c), r);
        }
        for (c, &r) in conns.iter_mut().zip(&rates) {
            assert_streams_at(c, r);
        }
        assert!(emu.terminate().success());
        let log = emu.stderr();
        for k in 0..3 {
            assert!(
                log.contains(&format!(
                    "dev {k}: KERNEL-110-G2000-A40 powered on at 115200 bit/s, seed {}",
                    7 + k
                )),
                "{log}"
            );
        }
    }
    // One flash file per device.
    for k in 0..3 {
        let f = dir.join(format!("imu.flash.{k}"));
        assert_eq!(
            std::fs::metadata(&f).unwrap().len(),
            8192,
            "{}",
            f.display()
        );
    }
    // Restarting is a power cycle of every device: each boots with what it
    // saved, and only that.
    let (_emu, addrs, _) = start(3, &flash, &["--seed", "7"]);
    for (&a, &r) in addrs.iter().zip(&rates) {
        let mut c = Conn::tcp(a);
        assert_eq!(data_rate(&mut c), r, "{a}");
        assert_streams_at(&mut c, r);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_control_socket_addresses_each_device() {
    let dir = temp_dir("control");
    let (_emu, addrs, ctl) = start(3, &dir.join("f"), &[]);
    let mut ctl = Control::connect(&ctl);
    let listed: Vec<String> = addrs
        .iter()
        .enumerate()
        .map(|(k, a)| format!("dev{k}=tcp:{a}"))
        .collect();
    assert_eq!(
        ctl.cmd("devices"),
        format!("ok count=3 {}", listed.join(" "))
    );
    // Each device powers on at its own first client.
    assert_eq!(ctl.cmd("dev 2 status"), "ok mode=off");
    assert_eq!(
        ctl.cmd("dev 2 pps"),
        "error dev 2 is off: it powers on when a client connects to its UART (or use --power-on now)"
    );
    let mut c: Vec<Conn> = addrs.iter().map(|&a| Conn::tcp(a)).collect();
    for (k, c) in c.iter_mut().enumerate() {
        c.send(&command(STOP));
        c.drain_for(Duration::from_millis(50));
        let s = ctl.cmd(&format!("dev {k} status"));
        assert!(s.starts_with("ok mode=idle "), "{s}");
    }
    // Without an address, a device command is refused and says how.
    assert_eq!(
        ctl.cmd("status"),
        "error this run has 3 devices: address one, dev <K> <command> (K = 0..2)"
    );
    assert_eq!(
        ctl.cmd("dev 3 status"),
        "error no device 3: this run has devices 0..2"
    );
    assert_eq!(ctl.cmd("dev x status"), "error not a device number: x");
    assert_eq!(
        ctl.cmd("dev 1"),
        "error bad syntax: dev 1; expected dev <K> <command>"
    );
    assert_eq!(ctl.cmd("dev 1 fault warp on"), "error unknown fault: warp");
    // A fault injected into device 1 shows in its GetBIT only.
    assert_eq!(ctl.cmd("dev 1 fault gyro-bit on"), "ok");
    let bits: Vec<u8> = c
        .iter_mut()
        .map(|c| {
            c.send(&command(GET_BIT));
            c.frame_with_id(GET_BIT).payload()[0]
        })
        .collect();
    assert_eq!(bits[0] & 0b1_1100, 0, "{bits:?}");
    assert_ne!(bits[1] & 0b1_1100, 0, "{bits:?}");
    assert_eq!(bits[2] & 0b1_1100, 0, "{bits:?}");
    // Device 2's status counts only its own commands.
    let s = ctl.cmd("dev 2 status");
    assert!(s.contains(" commands=2 "), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// GA at 2 kHz on a 2 Mbaud line for `n` frames: each frame's gyro and
/// acc bytes (Table 5.7, the 24 bytes the sensor noise lands in) by its
/// 2 kHz counter.
fn noise_by_counter(c: &mut Conn, n: usize) -> std::collections::HashMap<u16, Vec<u8>> {
    save(c, BAUD_RATE, &[0x0B]); // 2 000 000 bit/s
    c.send(&command(0xC2)); // CommitBaudRate
    c.send(&read_ram(BAUD_RATE, 1));
    assert_eq!(c.frame_with_id(0xB1).payload(), &[0x0B]);
    save(c, DATA_RATE, &2000u16.to_le_bytes());
    c.send(&command(GA));
    c.frame_with_id(GA);
    (0..n)
        .map(|_| {
            let f = c.frame_with_id(GA);
            let counter = u16::from_le_bytes([f.payload()[COUNTER], f.payload()[COUNTER + 1]]);
            (counter, f.payload()[..24].to_vec())
        })
        .collect()
}

#[test]
fn device_k_draws_its_noise_from_seed_plus_k() {
    // The sensor noise of a device at a given tick depends only on its seed
    // (static unit, factory settings): device K of a `--count` run with
    // --seed S is, tick for tick, a single device with --seed S + K.
    let dir = temp_dir("seed");
    let (_fleet, addrs, _) = start(2, &dir.join("f"), &["--seed", "7"]);
    let single = Emu::tcp(&["--seed", "8"]);
    // All three power on together (at their first clients) and are read
    // at once, so their counters overlap.
    let mut conns = [Conn::tcp(addrs[0]), Conn::tcp(addrs[1]), single.connect()];
    let [dev0, dev1, seed8] = std::thread::scope(|s| {
        let jobs: Vec<_> = conns
            .iter_mut()
            .map(|c| s.spawn(|| noise_by_counter(c, 2000)))
            .collect();
        let mut got = jobs.into_iter().map(|j| j.join().unwrap());
        [(); 3].map(|()| got.next().unwrap())
    });
    let common: Vec<u16> = dev1
        .keys()
        .filter(|k| seed8.contains_key(k) && dev0.contains_key(k))
        .copied()
        .collect();
    assert!(common.len() > 100, "only {} common ticks", common.len());
    for k in &common {
        assert_eq!(dev1[k], seed8[k], "tick {k}");
    }
    let same = common.iter().filter(|k| dev0[*k] == seed8[*k]).count();
    assert!(
        same < common.len() / 10,
        "dev 0 (seed 7) matches seed 8 at {same} ticks"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn count_with_a_serial_port_is_a_usage_error() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["--count", "2", "--serial", "/dev/null"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim(),
        "imu-emu: --count does not go with --serial (one port, one device)"
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["--count", "0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn devices_on_ptys_each_get_their_own_link() {
    let dir = temp_dir("pty");
    let link = dir.join("imu");
    let emu = Emu::start(&["--count", "2", "--pty", "--link", link.to_str().unwrap()]);
    let mut places = vec![format!("listening on {}", emu.listening)];
    places.extend(emu.more_lines(1));
    for (k, place) in places.iter().enumerate() {
        let slave = PathBuf::from(place.strip_prefix("listening on pty ").unwrap());
        let l = dir.join(format!("imu.{k}"));
        assert_eq!(std::fs::read_link(&l).unwrap(), slave, "{}", l.display());
        // Each answers on its own line, device 1 with its own Data_Rate.
        let mut c = Conn::serial(&l);
        if k == 1 {
            save(&mut c, DATA_RATE, &50u16.to_le_bytes());
        }
        assert_eq!(data_rate(&mut c), [100, 50][k]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `Max open files` of a process: (soft, hard).
fn open_file_limits(pid: &str) -> (u64, u64) {
    let limits = std::fs::read_to_string(format!("/proc/{pid}/limits")).unwrap();
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max open files"))
        .unwrap();
    let w: Vec<&str> = line.split_whitespace().collect();
    (w[3].parse().unwrap(), w[4].parse().unwrap())
}

#[test]
fn many_devices_raise_the_soft_open_file_limit() {
    // 100 devices need about 3 × 100 + 64 descriptors: started under a
    // soft limit of 128, the program raises it (up to the hard limit) and
    // every device listens.
    let (_, hard) = open_file_limits("self");
    let mut cmd = std::process::Command::new("sh");
    cmd.args([
        "-c",
        "ulimit -Sn 128 && exec \"$0\" \"$@\"",
        env!("CARGO_BIN_EXE_imu-emu"),
        "--count",
        "100",
        "--tcp",
        "127.0.0.1:0",
        "--power-on",
        "now",
    ]);
    let emu = Emu::start_command(cmd);
    let lines = emu.more_lines(99);
    assert!(lines.iter().all(|l| l.starts_with("listening on tcp ")));
    let (soft, _) = open_file_limits(&emu.pid().to_string());
    assert_eq!(soft, 364.min(hard));
    let mut c = Conn::tcp(
        lines[98]
            .strip_prefix("listening on tcp ")
            .unwrap()
            .parse()
            .unwrap(),
    );
    assert_eq!(data_rate(&mut c), 100);
}
