//! `imu-emu allan` through the binary, at a reduced duration (the full
//! 24 h figures of every built-in profile are `scripts/allan.sh`'s, in
//! docs/sensors.md): a K110 run in process with a profile whose bias
//! instability floor shows within minutes reads back its white noise and
//! bias instability; a recording's white noise reads back; the plots are
//! written (PNG, SVG with its labels).

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
        .filter(|l| l.starts_with("gyro_") || l.starts_with("acc_"))
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
    let (ok, shown, err) = imu_emu(&["sensor-profile", "show", "K110"]);
    assert!(ok, "{err}");
    // Floors that meet the white noise at τ ≈ 5 s (ARW 0.2 °/√h, 8 °/h;
    // VRW 0.03 m/s/√h, 34 µg): 600 s hold a decade of floor.
    let file = shown
        .replace(
            "bias_instability = 0.00055555557",
            "bias_instability = 0.0022222223",
        )
        .replace("bias_instability = 7e-6", "bias_instability = 3.4e-5");
    assert_ne!(file, shown);
    let path = dir.join("floor.toml");
    std::fs::write(&path, file).unwrap();
    let (png, svg) = (dir.join("a.png"), dir.join("a.svg"));
    let (ok, out, err) = imu_emu(&[
        "allan",
        "--model",
        "K110",
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
    let r = rows(&out);
    assert_eq!(r.len(), 6, "{out}");
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
