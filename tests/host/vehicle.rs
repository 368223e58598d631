//! The vehicle truth through the real binary: `--motion` with a
//! manoeuvre script or a full-state CSV, the control socket's `truth`,
//! `motion script|file` and `status`, and the motion seen in the GA
//! frames' rates and accelerations (ICD Table 5.7: gyro HR ·1e5 °/s, acc
//! HR ·1e6 g, housing axes X right, Y forward, Z up).

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::path::PathBuf;

use support::{command, free_port, Conn, Control, Emu, Frame};

const GA: u8 = 0x8F;
/// GA frames a second on a K110 at its factory rate.
const GA_HZ: f64 = 100.0;

/// A file in a directory of this test process, removed with it.
struct TempFile {
    dir: PathBuf,
    path: PathBuf,
}

impl TempFile {
    fn new(name: &str, text: &str) -> TempFile {
        let dir =
            std::env::temp_dir().join(format!("imu-emu-vehicle-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        TempFile { dir, path }
    }

    fn path(&self) -> &str {
        self.path.to_str().unwrap()
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

fn start(args: &[&str]) -> (Emu, Conn, Control) {
    let addr = format!("127.0.0.1:{}", free_port());
    let mut all = vec!["--model", "K110", "--control", addr.as_str()];
    all.extend_from_slice(args);
    let emu = Emu::tcp(&all);
    let c = emu.connect();
    let mut ctl = Control::connect(&addr);
    ctl.wait_powered();
    (emu, c, ctl)
}

/// The number after `key=` in a `key=value` reply.
fn num(reply: &str, key: &str) -> f64 {
    reply
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {reply:?}"))
        .parse()
        .unwrap_or_else(|_| panic!("{key} not a number in {reply:?}"))
}

/// GA gyro (°/s) and acc (g), housing axes.
fn ga(f: &Frame) -> ([f64; 3], [f64; 3]) {
    let p = f.payload();
    let at = |i: usize| f64::from(i32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]));
    (
        [at(0) / 1e5, at(4) / 1e5, at(8) / 1e5],
        [at(12) / 1e6, at(16) / 1e6, at(20) / 1e6],
    )
}

/// The GA frame's device time, s: its 2 kHz counter (Table 5.7, payload
/// offset 24; ticks since power-on, so valid for the first 32.7 s).
fn ga_time(f: &Frame) -> f64 {
    f64::from(u16::from_le_bytes([f.payload()[24], f.payload()[25]])) / 2000.0
}

/// Starts GA and returns the data frames up to device time `secs` (by
/// their counters).
fn ga_until(c: &mut Conn, secs: f64) -> Vec<Frame> {
    c.send(&command(GA));
    let ack = c.frame_with_id(GA);
    assert_eq!(ack.msg_type(), 1);
    let mut v = Vec::new();
    loop {
        let f = c.frame_with_id(GA);
        let t = ga_time(&f);
        v.push(f);
        if t >= secs || v.len() as f64 > secs * GA_HZ {
            return v;
        }
    }
}

/// Full-state rows of a unit at rest at `position` (`lat,lon,height`)
/// turning at 10 °/s in yaw for `secs`, a row a second (the attitude may
/// turn less than half a turn between two rows), `extra` after each.
fn spin_rows(position: &str, extra: &str, secs: u32) -> String {
    let temp = if extra.is_empty() { "" } else { ",temp" };
    let mut s = format!("time,lat,lon,height,vn,ve,vd,roll,pitch,yaw{temp}\n");
    for t in 0..=secs {
        let yaw = (10 * t + 180) % 360;
        s.push_str(&format!(
            "{t},{position},0,0,0,0,0,{}{extra}\n",
            f64::from(yaw) - 180.0
        ));
    }
    s
}

/// A coordinated turn at 6 °/s and 50 m/s banks atan(50·6°/s / g₀) =
/// 28.1°: the housing measures ψ̇ sin φ = 2.83 °/s about X (right),
/// −ψ̇ cos φ = −5.29 °/s about Z (up), and γ/cos φ = 1.134 g along Z —
/// and `truth` reports the bank, the speed and the script as the source.
#[test]
fn a_manoeuvre_script_moves_the_unit() {
    let script = TempFile::new(
        "turn.txt",
        "# level, then a coordinated turn\nstart 45 7 300 90 50\nhold 3\ncoord-turn 6 60\n",
    );
    let (emu, mut c, mut ctl) = start(&["--speed", "4", "--motion", script.path()]);
    let frames = ga_until(&mut c, 10.0);
    let log = emu.log_with("manoeuvre script (2 segments, 63 s)");
    assert!(log.contains("manoeuvre script (2 segments, 63 s)"), "{log}");
    let at = |secs: f64| {
        frames
            .iter()
            .filter(move |f| (secs..secs + 2.0).contains(&ga_time(f)))
    };
    // Means over two seconds of frames (the K110's noise is ≈ 0.1 °/s a
    // frame at LPF 262 Hz, and which internal samples the frames carry
    // follows the phase at which the client's start command arrived: a
    // difference of two means varies by ≈ 0.01 °/s from run to run, so
    // the bounds below are 0.05 °/s).
    let mean = |secs: f64| {
        let (mut w, mut a, mut n) = ([0.0; 3], [0.0; 3], 0.0);
        for f in at(secs) {
            let (fw, fa) = ga(f);
            for i in 0..3 {
                w[i] += fw[i];
                a[i] += fa[i];
            }
            n += 1.0;
        }
        assert_eq!(n, 2.0 * GA_HZ, "frames at {secs} s");
        (w.map(|x| x / n), a.map(|x| x / n))
    };
    // Level flight before the turn: gravity only (γ at 45°, 300 m is
    // 0.99946 of the ICD's g) and the Earth's rate; the unit's own biases
    // (a few 0.01 °/s, mg) show here and cancel in the differences below.
    let (w0, a0) = mean(1.0);
    assert!(w0.iter().all(|x| x.abs() < 0.3), "{w0:?}");
    assert!(
        (a0[2] - 0.99946).abs() < 0.01 && a0[0].abs() < 0.01,
        "{a0:?}"
    );
    // Banked and turning (the roll-in ends at 3 + 2.81 s).
    let bank = (50.0 * 6f64.to_radians() / 9.80665).atan();
    let (w, a) = mean(7.0);
    let dw = [w[0] - w0[0], w[1] - w0[1], w[2] - w0[2]];
    let da = [a[0] - a0[0], a[1] - a0[1], a[2] - a0[2]];
    assert!((dw[0] - 6.0 * bank.sin()).abs() < 0.05, "{dw:?}");
    assert!(dw[1].abs() < 0.05, "{dw:?}");
    assert!((dw[2] + 6.0 * bank.cos()).abs() < 0.05, "{dw:?}");
    assert!(
        (da[2] - 0.99946 * (1.0 / bank.cos() - 1.0)).abs() < 0.002,
        "{da:?}"
    );
    assert!(da[0].abs() < 0.002 && da[1].abs() < 0.002, "{da:?}");
    let t = ctl.cmd("truth");
    assert!(t.starts_with("ok source=script time="), "{t}");
    assert!(num(&t, "time") >= 10.0, "{t}");
    assert!((num(&t, "roll") - bank.to_degrees()).abs() < 1e-3, "{t}");
    let speed = num(&t, "vn").hypot(num(&t, "ve"));
    assert!((speed - 50.0).abs() < 1e-4, "{t}");
    assert!((num(&t, "lat") - 45.0).abs() < 0.01, "{t}");
    assert!((num(&t, "height") - 300.0).abs() < 1e-6, "{t}");
    let status = ctl.cmd("status");
    assert!(
        status.contains(" truth-source=script truth-time="),
        "{status}"
    );
}

/// The built-in static motion reports its site (Newlyn, 50° 06.1′ N
/// 5° 32.5′ W, 62.5 m above the ellipsoid, where normal gravity is the
/// ICD's g) and what it
/// measures; `motion script …` flies from the command's time, `motion
/// file …` loads a full-state CSV, and bad ones are refused with the
/// reason.
#[test]
fn truth_and_motion_over_the_control_socket() {
    let (_emu, _c, mut ctl) = start(&[]);
    let t = ctl.cmd("truth");
    assert!(t.starts_with("ok source=static "), "{t}");
    assert!((num(&t, "lat") - 50.10167).abs() < 1e-5, "{t}");
    assert!((num(&t, "lon") + 5.541667).abs() < 1e-6, "{t}");
    assert!((num(&t, "height") - 62.49).abs() < 0.01, "{t}");
    assert!((num(&t, "fz") + 9.8106).abs() < 1e-5, "{t}");
    // The Earth's rate Ω (cos φ, 0, −sin φ) at heading 0, °/s.
    assert!((num(&t, "wx") - 0.0026799).abs() < 1e-7, "{t}");
    assert!((num(&t, "wz") + 0.0032053).abs() < 1e-7, "{t}");

    assert_eq!(
        ctl.cmd("motion script start 10 20 1000 180 30; turn 5 100"),
        "ok"
    );
    std::thread::sleep(std::time::Duration::from_millis(300));
    let t = ctl.cmd("truth");
    assert!(t.starts_with("ok source=script "), "{t}");
    assert!((num(&t, "lat") - 10.0).abs() < 0.001, "{t}");
    assert!((num(&t, "wz") - 5.0).abs() < 0.01, "{t}");
    let yaw = num(&t, "yaw");
    assert!(!(-170.0..=175.0).contains(&yaw), "{t}");

    let csv = TempFile::new("spin.csv", &spin_rows("-20,30,50", ",40", 100));
    assert_eq!(ctl.cmd(&format!("motion file {}", csv.path())), "ok");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let t = ctl.cmd("truth");
    assert!(t.starts_with("ok source=full-state "), "{t}");
    assert!((num(&t, "lat") + 20.0).abs() < 1e-9, "{t}");
    assert!((num(&t, "wz") - 10.0).abs() < 0.01, "{t}");
    assert_eq!(num(&t, "temp"), 40.0);

    assert_eq!(
        ctl.cmd("motion script start 95 0 0 0 0"),
        "error manoeuvre script: line 1 statement 1: value out of range"
    );
    assert_eq!(
        ctl.cmd("motion script hold 3"),
        "error manoeuvre script: line 1 statement 1: exactly one start, before the segments"
    );
    let e = ctl.cmd("motion file /nonexistent/motion.txt");
    assert!(
        e.starts_with("error reading motion /nonexistent/motion.txt"),
        "{e}"
    );
    // Still the full-state file after the refusals; a built-in motion
    // replaces it.
    assert!(ctl.cmd("truth").starts_with("ok source=full-state "));
    assert_eq!(ctl.cmd("motion static"), "ok");
    assert!(ctl.cmd("truth").starts_with("ok source=static "));
}

/// A full-state CSV turning at 10 °/s (yaw) shows as −10 °/s about the
/// housing's Z (up) in the GA frames (within the unit's bias).
#[test]
fn a_full_state_csv_moves_the_unit() {
    let csv = TempFile::new("yaw.csv", &spin_rows("45,7,300", "", 60));
    let (emu, mut c, mut ctl) = start(&["--speed", "4", "--motion", csv.path()]);
    let frames = ga_until(&mut c, 3.0);
    let late: Vec<f64> = frames
        .iter()
        .filter(|f| ga_time(f) > 1.0)
        .map(|f| ga(f).0[2])
        .collect();
    assert!(late.len() >= 150, "{}", late.len());
    let mean = late.iter().sum::<f64>() / late.len() as f64;
    assert!((mean + 10.0).abs() < 0.1, "{mean}");
    let t = ctl.cmd("truth");
    assert!(t.starts_with("ok source=full-state "), "{t}");
    drop(emu);
}

/// Runs `imu-emu` with `args` to its exit (it refuses them at once).
fn refused(args: &[&str]) -> (Option<i32>, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A `--motion` file that is neither kind, or a bad row, stops the program
/// before it listens, naming the file, the line and the reason;
/// `--motion` with `--trajectory` is a usage error.
#[test]
fn bad_motion_files_are_refused_at_start() {
    let rate = TempFile::new("rate.csv", "time_s,wx,wy,wz,fx,fy,fz\n0,0,0,0,0,0,1\n");
    let (code, out, err) = refused(&["--tcp", "127.0.0.1:0", "--motion", rate.path()]);
    assert_ne!(code, Some(0), "{err}");
    assert!(out.is_empty(), "listened anyway: {out}");
    assert!(
        err.contains(rate.path()) && err.contains("neither a manoeuvre script"),
        "{err}"
    );
    let row = TempFile::new(
        "row.csv",
        "time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n0,45,7,300,0,0,0,0,0,0\n1,45,7,x,0,0,0,0,0,0\n",
    );
    let (code, out, err) = refused(&["--tcp", "127.0.0.1:0", "--motion", row.path()]);
    assert!(out.is_empty(), "listened anyway: {out}");
    // The column named; a usage error (2), as a bad --sensor-profile is.
    assert!(
        err.contains("line 3, column height (value 4): not a finite number"),
        "{err}"
    );
    assert_eq!(code, Some(2), "{err}");
    let (code, _, err) = refused(&[
        "--tcp",
        "127.0.0.1:0",
        "--motion",
        row.path(),
        "--trajectory",
        rate.path(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--trajectory"), "{err}");
}
