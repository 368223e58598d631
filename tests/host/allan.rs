//! `imu-emu allan` through the binary, at a reduced duration (the full
//! 100 h figures of every built-in profile are `scripts/allan.sh`'s, in
//! docs/sensors.md): a K120 run in process (its UDD frames: gyro, acc and
//! the aux accelerometer) with a profile whose bias instability floor
//! shows within minutes reads back its white noise and bias instability; a
//! recording's white noise reads back; the plots are written (PNG, SVG
//! with its labels).

use std::path::PathBuf;
use std::process::Command;

fn imu_emu(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .output()
        .expect("run imu-emu");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn temp_dir(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-emu-allan-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// (white, bias instability fit, profile white, profile B) of each axis
/// line of the report.
fn rows(report: &str) -> Vec<(String, f64, f64, f64, f64)> {
    report
        .lines()
        .filter(|l| l.starts_with("gyro_") || l.contains("acc_"))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            let num = |i: usize| {
                w[i].trim_matches(|c| c == '(' || c == ')')
                    .parse::<f64>()
                    .unwrap()
            };
            // axis white unit profile bi unit ( min ) profile rrw
            (w[0].to_owned(), num(1), num(4), num(3), num(8))
        })
        .collect()
}

#[test]
fn a_short_run_reads_back_its_white_noise_and_bias_instability() {
    let dir = temp_dir("run");
    let (ok, shown, err) = imu_emu(&["sensor-profile", "show", "K120"]);
    assert!(ok, "{err}");
    // Floors that meet the white noise at τ ≈ 5 s (ARW 0.2 °/√h, 8 °/h;
    // VRW 0.03 m/s/√h, 34 µg; the aux's 0.3 m/s/√h and 340 µg): 600 s
    // hold a decade of floor.
    let file = shown
        .replace(
            "bias_instability = 0.00055555557",
            "bias_instability = 0.0022222223",
        )
        .replace("bias_instability = 7e-6", "bias_instability = 3.4e-5")
        .replace("bias_instability = 0.0002", "bias_instability = 0.00034");
    assert_ne!(file, shown);
    let path = dir.join("floor.toml");
    std::fs::write(&path, file).unwrap();
    let (png, svg) = (dir.join("a.png"), dir.join("a.svg"));
    let (ok, out, err) = imu_emu(&[
        "allan",
        "--model",
        "K120",
        "--sensor-profile",
        path.to_str().unwrap(),
        "--seconds",
        "600",
        "--png",
        png.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    println!("{out}");
    assert!(
        out.contains("UDD (gyro, acc, aux acc) frames at 100 Hz"),
        "{out}"
    );
    let r = rows(&out);
    assert_eq!(r.len(), 9, "{out}");
    for (axis, white, bi, white_p, bi_p) in r {
        // 60 000 samples: the white noise to 5 %; the floor from ~10
        // independent intervals of its longest τ: 30 % (seen: 0.77–1.09).
        assert!(
            (white / white_p - 1.0).abs() < 0.05,
            "{axis}: white {white} vs {white_p}"
        );
        assert!((bi / bi_p - 1.0).abs() < 0.30, "{axis}: B {bi} vs {bi_p}");
    }
    let png = std::fs::read(&png).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(&svg).unwrap();
    for label in [
        "averaging time τ (s)",
        "Allan deviation σ(τ) (°/s)",
        "gyro X",
        "aux acc Z",
        "profile: white",
    ] {
        assert!(svg.contains(label), "{label}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_recording_reads_back_its_white_noise() {
    // A `client record`-style CSV: 100 Hz, white noise of density 0.01
    // (°/s/√Hz and g/√Hz) from a xorshift generator (sum of 12 uniforms).
    let dir = temp_dir("csv");
    let mut s = 0x2545_F491_4F6C_DD1Du64;
    let mut uniform = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut text =
        String::from("frame,host_time_s,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,temp_c\n");
    let sigma = 0.01 * 100f64.sqrt();
    for k in 0..60_000 {
        let mut row = format!("{k},{:.6}", k as f64 / 100.0);
        for _ in 0..6 {
            let g: f64 = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
            row.push_str(&format!(",{:.7}", g * sigma));
        }
        row.push_str(",25.0\n");
        text.push_str(&row);
    }
    let path = dir.join("rec.csv");
    std::fs::write(&path, text).unwrap();
    let (ok, out, err) = imu_emu(&["allan", "--input", path.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("(100 Hz)"), "{out}");
    let axes = out
        .lines()
        .filter(|l| l.starts_with("gyro_") || l.starts_with("acc_"));
    assert_eq!(axes.clone().count(), 6, "{out}");
    for l in axes {
        let w: Vec<&str> = l.split_whitespace().collect();
        let (axis, white): (&str, f64) = (w[0], w[1].parse().unwrap());
        let density = if axis.starts_with("gyro") {
            white / 60.0
        } else {
            white / 60.0 / 9.8106
        };
        assert!((density / 0.01 - 1.0).abs() < 0.05, "{axis}: {density}");
    }
    // A file without the columns: one line saying which.
    std::fs::write(&path, "a,b\n1,2\n").unwrap();
    let (ok, _, err) = imu_emu(&["allan", "--input", path.to_str().unwrap()]);
    assert!(!ok && err.contains("no gyro_x column"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `secs` seconds of a device's serial output, started by `commands`
/// (bytes a host sends), as a capture tool would save them.
fn capture<P: imu_emu::personality::Personality>(
    product: imu_emu::model::Product,
    commands: &[Vec<u8>],
    secs: u64,
) -> Vec<u8> {
    use imu_emu::device::{Device, PowerOn};
    use imu_emu::time::Instant;
    use imu_emu_host::flash::MemNor;
    let cfg = PowerOn {
        product,
        boot: None,
        seed: 5,
    };
    let mut dev = Device::<MemNor, P>::new(cfg, MemNor::new(), Instant::ZERO);
    let period = dev.tick_period_ns();
    let mut now = 0;
    for c in commands {
        dev.on_rx(c, Instant::from_nanos(now));
    }
    // A capture starts mid-frame: a partial frame of junk first.
    let mut out = vec![0xAA, 0x55, 0x01, 0xEF, 0x49, 0x04];
    let mut buf = [0u8; 4096];
    while now < secs * 1_000_000_000 {
        now += period;
        dev.on_tick(Instant::from_nanos(now));
        loop {
            let n = dev.poll_tx(&mut buf);
            if n == 0 {
                break;
            }
            out.extend_from_slice(&buf[..n]);
        }
    }
    out
}

/// Runs `allan --input` on `bytes` and checks each axis's white noise
/// against (ARW °/√h, VRW m/s/√h) within 5 %; the report's first line.
fn reads_white(what: &str, bytes: &[u8], extra: &[&str], arw: f64, vrw: f64) -> String {
    let dir = temp_dir(what);
    let path = dir.join("capture.bin");
    std::fs::write(&path, bytes).unwrap();
    let mut args = vec!["allan", "--input", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    let (ok, out, err) = imu_emu(&args);
    assert!(ok, "{err}");
    println!("{out}");
    let r: Vec<(&str, f64)> = out
        .lines()
        .filter(|l| l.starts_with("gyro_") || l.starts_with("acc_"))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w[0], w[1].parse().unwrap())
        })
        .collect();
    assert_eq!(r.len(), 6, "{out}");
    for (axis, white) in r {
        let want = if axis.starts_with("gyro") { arw } else { vrw };
        assert!(
            (white / want - 1.0).abs() < 0.05,
            "{axis}: {white} vs {want}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    out.lines().next().unwrap().to_owned()
}

#[test]
fn a_raw_kernel_capture_reads_back_its_white_noise_at_its_counter_rate() {
    use imu_emu::kernel::command::Command;
    let enc = |c: Command| {
        let mut b = [0u8; 64];
        let n = c.encode(&mut b).unwrap();
        b[..n].to_vec()
    };
    let product = imu_emu::model::Product::parse("K110").unwrap();
    let cmds = [
        enc(Command::SaveFlash {
            id: 0x0012,
            len: 2,
            value: &100u16.to_le_bytes(),
        }),
        enc(Command::Data(0x8F)),
    ];
    let bytes = capture::<imu_emu::kernel::Kernel>(product, &cmds, 600);
    // K110 profile: ARW 0.2 °/√h, VRW 0.03 m/s/√h; the 2 kHz counter
    // steps 20 a frame: 100 Hz.
    let head = reads_white("kernel", &bytes, &[], 0.2, 0.03);
    assert!(head.contains("KERNEL GA frames"), "{head}");
    assert!(head.contains(", 100 Hz)"), "{head}");
    assert!(head.contains("60000 samples"), "{head}");
}

#[test]
fn raw_isb_captures_of_imu_and_pimu_read_back_their_white_noise() {
    use imu_emu::isb::message::{encode_get, GetRequest};
    use imu_emu::isb::{did, Isb};
    for (set, name) in [
        (did::IMU, "ISB IMU packets"),
        (did::PIMU, "ISB PIMU (Δθ/dt"),
    ] {
        let mut b = [0u8; 64];
        let req = GetRequest {
            did: u16::from(set),
            size: 0,
            offset: 0,
            period: 1,
        };
        let n = encode_get(&req, &mut b).unwrap();
        let bytes = capture::<Isb>(imu_emu::model::Product::imx5(), &[b[..n].to_vec()], 300);
        // IMX-5 profile: ARW 0.23 °/√h, VRW 0.020 m/s/√h; the sets' time
        // steps 4 ms (startupNavDtMs): 250 Hz.
        let head = reads_white(
            &format!("isb{set}"),
            &bytes,
            &["--format", "isb"],
            0.23,
            0.02,
        );
        assert!(head.contains(name), "{head}");
        assert!(head.contains(", 250 Hz)"), "{head}");
    }
}
