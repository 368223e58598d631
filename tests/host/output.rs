//! End-to-end tests of the output engine through the real `imu-emu` binary
//! over TCP (issue "Output engine"): frames per second on the wire for every
//! format at several data rates and baud rates (ICD 5.5, Table 5.28), and
//! the pins driven through the control socket (1PPS, EXTRIG, TOV, BOOT).

// Shared with the e2e suite; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::time::{Duration, Instant};

use support::{
    assert_rate, bytes_per_device_second, command, device_times, free_port, read_ram, save, Conn,
    Control, DeviceClock, Emu, Frame,
};

const DATA_RATE: u16 = 0x0012;
const ALIGN_TIME: u16 = 0x0014;
const BAUD_RATE: u16 = 0x03B2;
const TOV_CONTROL: u16 = 0x0499;
const TRIGGER_CONTROL: u16 = 0x05FA;

/// Sets the baud rate code and commits it; waits until it took effect.
fn set_baud(c: &mut Conn, code: u8) {
    save(c, BAUD_RATE, &[code]);
    c.send(&command(0xC2));
    // ReadRAM answers the live value once the commit went through.
    c.send(&read_ram(BAUD_RATE, 1));
    assert_eq!(c.frame_with_id(0xB1).payload(), &[code]);
}

/// The device clock the frames of data command `code` carry, if any: the
/// 2 kHz counter of GA and Calibrated HR, the second fraction of GAm and
/// GAAm, the IMU time of the factory UDD (type 0x02 after the 1 + 5 bytes
/// of its type list).
fn clock_of(code: u8) -> Option<DeviceClock> {
    match code {
        0x8F => Some(DeviceClock::Counter(24)),
        0x81 => Some(DeviceClock::Counter(42)),
        0x9B => Some(DeviceClock::SecondFraction(26)),
        0xA6 => Some(DeviceClock::SecondFraction(38)),
        0x95 => Some(DeviceClock::ImuTime(6)),
        _ => None,
    }
}

/// Counts frames with `id` (checking their payload length) arriving in a
/// window of `secs` after `settle`, and the bytes received in the window:
/// for the formats that carry no device clock (Orientation, Quaternion,
/// GAA), a wall-clock measure.
fn measure(
    c: &mut Conn,
    id: u8,
    payload_len: usize,
    settle: Duration,
    secs: f64,
) -> (usize, usize) {
    let start = Instant::now() + settle;
    while Instant::now() < start {
        let _ = c.frame_before(start);
    }
    let bytes0 = c.received;
    let end = start + Duration::from_secs_f64(secs);
    let mut n = 0;
    while let Some(f) = c.frame_before(end) {
        assert_eq!(f.id(), id);
        assert_eq!(f.payload().len(), payload_len, "frame length of {id:02X}");
        n += 1;
    }
    (n, c.received - bytes0)
}

struct Case {
    model: &'static str,
    code: u8,
    payload: usize,
    baud_code: u8,
    baud: u32,
    data_rate: u16,
    /// Frames per second expected on the wire (Table 5.28 / Formula 5.1).
    expect: usize,
}

#[test]
fn every_format_streams_at_the_icd_rate_for_its_baud_rate() {
    // Table 5.28 cells (Data_Rate 2000 lowered to the maximum) and a
    // Data_Rate below the maximum.
    let cases = [
        Case {
            model: "K110",
            code: 0x33,
            payload: 34,
            baud_code: 0x05,
            baud: 38_400,
            data_rate: 2000,
            expect: 80,
        },
        Case {
            model: "K110",
            code: 0x8F,
            payload: 32,
            baud_code: 0x00,
            baud: 115_200,
            data_rate: 2000,
            expect: 250,
        },
        Case {
            model: "K110",
            code: 0x9B,
            payload: 32,
            baud_code: 0x09,
            baud: 460_800,
            data_rate: 2000,
            expect: 1000,
        },
        Case {
            model: "K110",
            code: 0x82,
            payload: 34,
            baud_code: 0x00,
            baud: 115_200,
            data_rate: 2000,
            expect: 200,
        },
        Case {
            model: "K110",
            code: 0x81,
            payload: 52,
            baud_code: 0x05,
            baud: 38_400,
            data_rate: 2000,
            expect: 50,
        },
        Case {
            model: "K120",
            code: 0xA5,
            payload: 44,
            baud_code: 0x09,
            baud: 460_800,
            data_rate: 2000,
            expect: 500,
        },
        Case {
            model: "K120",
            code: 0xA6,
            payload: 44,
            baud_code: 0x0B,
            baud: 2_000_000,
            data_rate: 2000,
            expect: 2000,
        },
        Case {
            model: "K120",
            code: 0x8F,
            payload: 32,
            baud_code: 0x0B,
            baud: 2_000_000,
            data_rate: 400,
            expect: 400,
        },
        // UDD, factory config: 1 + 5 + 8 + 12 + 12 + 2 + 2 = 42 bytes.
        Case {
            model: "K110",
            code: 0x95,
            payload: 42,
            baud_code: 0x00,
            baud: 115_200,
            data_rate: 100,
            expect: 100,
        },
        Case {
            model: "K201",
            code: 0x8F,
            payload: 32,
            baud_code: 0x10,
            baud: 4_000_000,
            data_rate: 4000,
            expect: 4000,
        },
    ];
    // Run in batches of a few emulators at a time (2 cores).
    for batch in cases.chunks(4) {
        let handles: Vec<_> = batch
            .iter()
            .map(|case| {
                let (model, code, payload, baud_code, baud, rate, expect) = (
                    case.model, case.code, case.payload, case.baud_code, case.baud, case.data_rate, case.expect,
                );
                std::thread::spawn(move || {
                    let emu = Emu::tcp(&["--model", model]);
                    let mut c = emu.connect();
                    save(&mut c, ALIGN_TIME, &[0, 0]);
                    save(&mut c, DATA_RATE, &rate.to_le_bytes());
                    set_baud(&mut c, baud_code);
                    c.send(&command(code));
                    let ack = c.frame_with_id(code);
                    assert_eq!(ack.payload(), &command(code)[7..9]);
                    if let Some(clock) = clock_of(code) {
                        // One second of device time: `expect` frames, each
                        // exactly one period after the last.
                        let stamps = device_times(&mut c, code, expect + 1, clock);
                        assert!(
                            stamps.iter().all(|s| s.len == payload + 8),
                            "frame length of {code:02X}"
                        );
                        let what = format!("{model} {code:02X} at {baud} bps, Data_Rate {rate}");
                        assert_rate(&what, &stamps, clock, expect as u64);
                        let bytes = bytes_per_device_second(&stamps, clock);
                        assert!(
                            bytes <= f64::from(baud / 10 + 128),
                            "{bytes} B per device second exceeds the line at {baud} bps"
                        );
                        return;
                    }
                    let (frames, bytes) = measure(&mut c, code, payload, Duration::from_millis(300), 1.0);
                    let tol = (expect / 20).max(2);
                    assert!(
                        frames.abs_diff(expect) <= tol,
                        "{model} {code:02X} at {baud} bps, Data_Rate {rate}: {frames} frames/s, expected {expect}\n{}",
                        emu.stderr()
                    );
                    assert!(bytes as u32 <= baud / 10 + 128, "{bytes} B/s exceeds the line at {baud} bps");
                })
            })
            .collect();
        for h in handles {
            h.join().expect("case passed");
        }
    }
}

#[test]
fn a_slow_baud_rate_really_limits_the_line() {
    // GA at 9600 bps: Formula 5.1 gives 9600 / (11 × 40) = 21.8 → 20 Hz;
    // 20 × 40 = 800 B/s, within the 960 B/s of the line.
    let emu = Emu::tcp(&["--model", "K110"]);
    let mut c = emu.connect();
    save(&mut c, DATA_RATE, &1000u16.to_le_bytes());
    set_baud(&mut c, 0x02);
    c.send(&command(0x8F));
    c.frame_with_id(0x8F);
    // Two seconds of device time (the 2 kHz counter): 40 frames.
    let clock = DeviceClock::Counter(24);
    let stamps = device_times(&mut c, 0x8F, 41, clock);
    assert!(stamps.iter().all(|s| s.len == 40), "GA frame length");
    assert_rate("GA at 9600 bps", &stamps, clock, 20);
    let bytes = 2.0 * bytes_per_device_second(&stamps, clock);
    assert!(bytes <= 2.0 * 960.0 + 64.0, "{bytes} bytes in 2 s");
}

/// A free local port for `--control`.
/// Starts an emulator with a control socket; returns it, a UART client and
/// the control connection.
fn with_control(args: &[&str]) -> (Emu, Conn, Control) {
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    let mut all = vec!["--control", addr.as_str()];
    all.extend_from_slice(args);
    let emu = Emu::tcp(&all);
    let c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    (emu, c, ctl)
}

fn u16_at(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([p[i], p[i + 1]])
}
fn u32_at(p: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]])
}

#[test]
fn pps_through_the_control_socket_sets_the_gam_time_flag_and_realigns_the_second() {
    let (_emu, mut c, mut ctl) = with_control(&["--model", "K110"]);
    c.send(&command(0x9B));
    c.frame_with_id(0x9B);
    // Well over 1 s without 1PPS: flag 0x0008.
    std::thread::sleep(Duration::from_millis(1200));
    c.drain_for(Duration::from_millis(50));
    let f = c.frame_with_id(0x9B);
    assert_eq!(u16_at(f.payload(), 24) & 0x0008, 0x0008);
    assert_eq!(ctl.cmd("pps"), "ok");
    // The frame after the edge: 0x0001, second fraction since the edge
    // below one frame period plus scheduling slack.
    let mut seen = false;
    for _ in 0..20 {
        let f = c.frame_with_id(0x9B);
        let flags = u16_at(f.payload(), 24);
        if flags & 0x0001 != 0 {
            assert_eq!(flags & 0x0008, 0);
            assert!(
                u32_at(f.payload(), 26) < 30_000_000,
                "second fraction after 1PPS"
            );
            seen = true;
            break;
        }
    }
    assert!(seen, "a frame with the 1PPS flag");
}

#[test]
fn pps_generator_flags_one_frame_each_second() {
    let emu = Emu::tcp(&["--model", "K110", "--pps"]);
    let mut c = emu.connect();
    c.send(&command(0x9B));
    c.frame_with_id(0x9B);
    // 2.6 s of device time at 100 Hz, by the second fraction (the
    // generator's edges fall on whole device seconds, so it steps by
    // exactly 10 ms across them too).
    let fs = frames(&mut c, 0x9B, 261);
    let clock = DeviceClock::SecondFraction(26);
    let stamps: Vec<_> = fs
        .iter()
        .map(|f| support::Stamp {
            time: clock.read(f.payload()),
            len: f.bytes.len(),
        })
        .collect();
    assert_rate("GAm with --pps", &stamps, clock, 100);
    let flagged = fs[1..]
        .iter()
        .filter(|f| u16_at(f.payload(), 24) & 0x0001 != 0)
        .count();
    assert!(
        (2..=3).contains(&flagged),
        "{flagged} frames flagged with 1PPS in 2.6 s"
    );
}

#[test]
fn extrig_through_the_control_socket_sends_one_frame_per_edge() {
    let (_emu, mut c, mut ctl) = with_control(&["--model", "K110"]);
    save(&mut c, TRIGGER_CONTROL, &[1]);
    c.send(&command(0x8F));
    c.frame_with_id(0x8F);
    assert_eq!(
        c.drain_for(Duration::from_millis(300)),
        0,
        "no periodic output"
    );
    for _ in 0..3 {
        assert_eq!(ctl.cmd("extrig high"), "ok");
        assert_eq!(ctl.cmd("extrig low"), "ok");
    }
    for _ in 0..3 {
        assert_eq!(c.frame().id(), 0x8F);
    }
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(300))
        .is_none());
}

#[test]
fn tov_edges_are_reported_on_the_control_socket() {
    let (_emu, mut c, mut ctl) = with_control(&["--model", "K110"]);
    save(&mut c, TOV_CONTROL, &[1]);
    c.send(&command(0x8F));
    c.frame_with_id(0x8F);
    let mut edges = Vec::new();
    while edges.len() < 20 {
        let l = ctl.line();
        let mut w = l.split_whitespace();
        assert_eq!(w.next(), Some("event"));
        assert_eq!(w.next(), Some("tov"));
        let level = w.next().unwrap().to_owned();
        let at: u64 = w.next().unwrap().parse().unwrap();
        edges.push((level, at));
    }
    for pair in edges.chunks(2) {
        assert_eq!(pair[0].0, "high");
        assert_eq!(pair[1].0, "low");
        // GA frame at 115200 bps: 40 bytes × 10 bit times = 3.47 ms.
        assert_eq!(pair[1].1 - pair[0].1, 40 * 10 * 1_000_000_000 / 115_200);
    }
    // 100 Hz: rising edges 10 ms apart.
    assert_eq!(edges[2].1 - edges[0].1, 10_000_000);
}

#[test]
fn boot_high_at_power_on_silences_the_device_until_the_next_power_cycle() {
    let (_emu, mut c, mut ctl) = with_control(&["--model", "K110"]);
    c.send(&command(0x1A));
    assert_eq!(c.frame().id(), 0x1A);
    assert_eq!(ctl.cmd("power-cycle boot=high"), "ok");
    c.send(&command(0x1A));
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(400))
        .is_none());
    assert_eq!(ctl.cmd("power-cycle"), "ok");
    c.send(&command(0x1A));
    assert_eq!(c.frame().id(), 0x1A);
}

#[test]
fn in_firmware_update_mode_the_monitor_does_not_decode_the_input() {
    // What a loader sends in firmware-update mode is not KERNEL commands:
    // `-v` logs no commands and no rejections for it, `status` counts none.
    let (emu, mut c, mut ctl) = with_control(&["--model", "K110", "-v"]);
    c.send(&command(0x1A));
    assert_eq!(c.frame().id(), 0x1A);
    assert_eq!(ctl.cmd("power-cycle boot=high"), "ok");
    c.send(&command(0x1A));
    c.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x12, 0x00, 0x00]);
    c.send(&[0x5A; 64]);
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(300))
        .is_none());
    let st = ctl.cmd("status");
    assert!(
        st.contains(" commands=1 ") && st.contains(" rejected=0"),
        "{st}"
    );
    let log = emu.log_with("firmware-update mode (BOOT high at power-on)");
    assert!(
        log.contains("firmware-update mode (BOOT high at power-on)"),
        "{log}"
    );
    let after = &log[log.find("firmware-update mode").unwrap()..];
    assert!(!after.contains("command "), "{after}");
    assert!(!after.contains("rejected"), "{after}");
    // After a normal power cycle it decodes again.
    assert_eq!(ctl.cmd("power-cycle"), "ok");
    c.send(&command(0x1A));
    assert_eq!(c.frame().id(), 0x1A);
    let st = ctl.cmd("status");
    assert!(st.contains(" commands=2 "), "{st}");
}

#[test]
fn injected_faults_and_motion_reach_usw_and_getbit_on_the_wire() {
    let (_emu, mut c, mut ctl) = with_control(&["--model", "KERNEL-110-G450-A40"]);
    c.send(&command(0x8F));
    c.frame_with_id(0x8F);
    let usw_now = |c: &mut Conn| {
        c.drain_for(Duration::from_millis(60));
        u16_at(c.frame_with_id(0x8F).payload(), 26)
    };
    assert_eq!(usw_now(&mut c), 0);
    assert_eq!(ctl.cmd("fault comm on"), "ok");
    assert_eq!(usw_now(&mut c), 1 << 1);
    assert_eq!(ctl.cmd("fault comm off"), "ok");
    assert_eq!(ctl.cmd("fault temperature 100"), "ok");
    let f = {
        c.drain_for(Duration::from_millis(60));
        c.frame_with_id(0x8F)
    };
    assert_eq!(u16_at(f.payload(), 26), 1 << 14);
    assert_eq!(&f.payload()[30..32], &1000i16.to_le_bytes());
    assert_eq!(ctl.cmd("fault temperature off"), "ok");
    // 600 deg/s about Z on a 450 deg/s gyro: Z out of range.
    assert_eq!(ctl.cmd("motion rotate 0 0 600"), "ok");
    assert_eq!(usw_now(&mut c), 1 << 12);
    assert_eq!(ctl.cmd("motion static"), "ok");
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(usw_now(&mut c), 0);
    // GetBIT reflects a gyro BIT failure.
    c.send(&command(0xFE));
    c.drain_for(Duration::from_millis(100));
    assert_eq!(ctl.cmd("fault gyro-bit on"), "ok");
    c.send(&command(0x1A));
    let bit = c.frame_with_id(0x1A);
    assert_ne!(bit.payload()[0] & 0b1_1100, 0);
    assert_eq!(ctl.cmd("fault warp on"), "error unknown fault: warp");
}

#[test]
fn a_trajectory_file_drives_what_the_device_measures() {
    // 100 deg/s about Z for the first 2 s, then 0; 0.5 g along X; 50 degC.
    let dir = std::env::temp_dir().join(format!("imu-emu-traj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("spin.csv");
    std::fs::write(
        &path,
        "time_s,wx,wy,wz,fx,fy,fz,temp_c\n0,0,0,100,0.5,0,1,50\n2,0,0,100,0.5,0,1,50\n2.001,0,0,0,0.5,0,1,50\n",
    )
    .unwrap();
    let emu = Emu::tcp(&["--model", "K110", "--trajectory", path.to_str().unwrap()]);
    let mut c = emu.connect();
    c.send(&command(0x8F));
    c.frame_with_id(0x8F);
    c.drain_for(Duration::from_millis(200));
    let p = c.frame_with_id(0x8F).payload().to_vec();
    let i32_at = |i: usize| i32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
    // Default K110 errors (bias, scale factor, noise) are far below 1 deg/s
    // and 0.02 g.
    assert!(
        (i32_at(8) - 10_000_000).abs() < 100_000,
        "gyro Z {}",
        i32_at(8)
    );
    assert!(
        (i32_at(12) - 500_000).abs() < 20_000,
        "acc X {}",
        i32_at(12)
    );
    assert_eq!(
        &p[30..32],
        &500i16.to_le_bytes(),
        "temperature from the file"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Reads `n` frames with `id` (60 s at most: a guard, not a measure).
fn frames(c: &mut Conn, id: u8, n: usize) -> Vec<Frame> {
    let end = Instant::now() + Duration::from_secs(60);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let f = c.frame_before(end).expect("frames under --speed");
        assert_eq!(f.id(), id);
        out.push(f);
    }
    out
}

/// `--speed max`: device time runs as fast as the client reads, and
/// nothing is lost for it: 30 000 GA frames (5 minutes of device time at
/// 100 Hz) in a row, the 2 kHz counter (Table 5.7) stepping by exactly 20
/// from each frame to the next.
#[test]
fn speed_max_streams_losslessly_faster_than_real_time() {
    let emu = Emu::tcp(&["--model", "K110", "--speed", "max"]);
    let mut c = emu.connect();
    c.send(&command(0x8F));
    c.frame_with_id(0x8F); // the acknowledgement
    let first = c.frame_with_id(0x8F);
    let mut last = u16_at(first.payload(), 24);
    let t0 = Instant::now();
    for f in frames(&mut c, 0x8F, 30_000) {
        let counter = u16_at(f.payload(), 24);
        assert_eq!(counter, last.wrapping_add(20), "frame lost or repeated");
        last = counter;
    }
    // Reported, not asserted (docs/performance.md).
    let wall = t0.elapsed().as_secs_f64();
    eprintln!("--speed max: 300 s of GA at 100 Hz in {wall:.3} s");
}

/// Under `--speed max` and `--speed 20` the 1PPS generator follows device
/// time: exactly one GAm frame in every 100 (1 s at 100 Hz) carries the
/// 1PPS flag, with the second fraction restarting.
#[test]
fn speed_keeps_pps_on_device_time() {
    for speed in ["max", "20"] {
        let emu = Emu::tcp(&["--model", "K110", "--pps", "--speed", speed]);
        let mut c = emu.connect();
        c.send(&command(0x9B));
        c.frame_with_id(0x9B);
        let fs = frames(&mut c, 0x9B, 800);
        let flagged: Vec<usize> = fs
            .iter()
            .enumerate()
            .filter(|(_, f)| u16_at(f.payload(), 24) & 0x0001 != 0)
            .map(|(i, _)| i)
            .collect();
        assert!(flagged.len() >= 7, "--speed {speed}: {flagged:?}");
        for w in flagged.windows(2) {
            assert_eq!(w[1] - w[0], 100, "--speed {speed}: {flagged:?}");
        }
    }
}

/// A bad `--speed` is refused before anything listens: exit status 2 (the
/// usage error) and a message naming the option, on the real binary.
#[test]
fn bad_speed_values_are_refused_at_start() {
    for bad in ["0", "-3", "fast", "inf", "2e6"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
            .args(["--tcp", "127.0.0.1:0", &format!("--speed={bad}")])
            .output()
            .expect("run imu-emu");
        assert_eq!(out.status.code(), Some(2), "--speed {bad}");
        assert!(out.stdout.is_empty(), "--speed {bad}: listened anyway");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--speed"), "--speed {bad}: {err}");
    }
}

/// One scripted client session over TCP with `args`, the client pausing
/// `pause` (host time) before each command and waiting for each answer
/// before the next: every byte it received.
fn kernel_session(args: &[&str], pause: Duration) -> Vec<u8> {
    let emu = Emu::tcp(args);
    let mut c = emu.connect();
    let mut got = Vec::new();
    std::thread::sleep(pause);
    c.send(&support::save_flash(DATA_RATE, &200u16.to_le_bytes()));
    got.extend(c.frame_with_id(0xB2).bytes);
    std::thread::sleep(pause);
    c.send(&read_ram(DATA_RATE, 2));
    got.extend(c.frame_with_id(0xB1).bytes);
    std::thread::sleep(pause);
    c.send(&command(0x8F));
    let fs = frames(&mut c, 0x8F, 601);
    // After the acknowledgement, the first GA frame's 2 kHz counter: the
    // device time the stream started (Table 5.7), however long the client
    // paused before its commands.
    let counter = u16_at(fs[1].payload(), 24);
    assert!(counter < 4000, "the stream started at counter {counter}");
    for f in fs {
        got.extend(f.bytes);
    }
    assert_eq!((c.bad, c.skipped), (0, 0), "every byte in a frame");
    got
}

/// Repeatable sessions: at `--speed max` device time waits while the
/// device has nothing to send and no input is pending, so one seed and
/// one command sequence give the same bytes over TCP run after run,
/// however long the client takes between its commands (README
/// "Repeatable sessions"). Before, device time raced while the client had
/// not yet sent its command (the first GA counter 45 140 in one run, 84
/// in the other). Also for an IMX-5 with a fixed `--gps-time`.
#[test]
fn a_seeded_speed_max_session_repeats_byte_for_byte() {
    let args = ["--model", "K110", "--speed", "max", "--seed", "7"];
    let a = kernel_session(&args, Duration::from_millis(10));
    let b = kernel_session(&args, Duration::from_millis(300));
    assert_eq!(a.len(), b.len());
    assert!(a == b, "the two sessions differ");

    let isb = |pause: Duration| {
        let emu = Emu::tcp(&[
            "--protocol",
            "isb",
            "--speed",
            "max",
            "--seed",
            "7",
            "--gps-time",
            "2026-03-01T12:00:00Z",
        ]);
        let mut c = emu.connect();
        let mut got = Vec::new();
        std::thread::sleep(pause);
        c.send(&support::isb_get(imu_emu::isb::did::DEV_INFO, 0));
        got.extend(support::isb_packet(&mut c).raw);
        std::thread::sleep(pause);
        c.send(&support::isb_get(imu_emu::isb::did::IMU, 1));
        for _ in 0..500 {
            got.extend(support::isb_packet(&mut c).raw);
        }
        got
    };
    let a = isb(Duration::from_millis(10));
    let b = isb(Duration::from_millis(300));
    assert!(a == b, "the two IMX-5 sessions differ");
}

/// The project's own client, twice against `--speed max --seed 7`: `set
/// Data_Rate 200`, then `record --format GA --frames 400` after a pause
/// of its own length each run; the CSVs are the same but for the host's
/// reception times (README "Repeatable sessions").
#[test]
fn the_projects_client_records_the_same_rows_run_after_run() {
    let dir = tempfile::tempdir().unwrap();
    let run = |pause: Duration, name: &str| {
        let emu = Emu::tcp(&["--model", "K110", "--speed", "max", "--seed", "7"]);
        let addr = emu.addr().to_string();
        let client = |args: &[&str]| {
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
                .args(["client", "--tcp", &addr])
                .args(args)
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        };
        std::thread::sleep(pause);
        client(&["set", "Data_Rate", "200"]);
        std::thread::sleep(pause);
        let csv = dir.path().join(name);
        let path = csv.to_str().unwrap();
        client(&["record", "--format", "GA", "--frames", "400", "-o", path]);
        // The columns but the host's time.
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let host = header.iter().position(|&h| h == "host_time_s");
        let rows: Vec<String> = lines
            .map(|l| {
                l.split(',')
                    .enumerate()
                    .filter(|&(i, _)| Some(i) != host)
                    .map(|(_, v)| v)
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect();
        assert_eq!(rows.len(), 400);
        rows
    };
    let a = run(Duration::from_millis(10), "a.csv");
    let b = run(Duration::from_millis(300), "b.csv");
    assert!(a == b, "the recordings differ:\n{}\n{}", a[0], b[0]);
}
