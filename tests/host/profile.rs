//! Sensor profiles through the binary: `imu-emu sensor-profile
//! show NAME` prints a file that `check` (and `--sensor-profile`) reads
//! back to the same profile; a bad file is one line naming the key and
//! its allowed range (exit status 2, nothing listens); `--sensor-profile
//! K=FILE` in a `--count` run changes device K only, seen in its frames.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use support::{command, Conn, Emu};

const GA: u8 = 0x8F;
/// GA (Table 5.7): acc Z (g × 10⁶) at payload offset 20.
const ACC_Z: usize = 20;

fn imu_emu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .output()
        .expect("run imu-emu")
}

fn temp_dir(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-emu-profile-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The file without its two comment lines naming it (title, source).
fn body(s: &str) -> String {
    s.lines().skip(2).collect::<Vec<_>>().join("\n")
}

fn show(name: &str, dir: &Path) -> PathBuf {
    let out = imu_emu(&["sensor-profile", "show", name]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, &out.stdout).unwrap();
    path
}

#[test]
fn every_builtin_profile_prints_as_a_file_that_reads_back_the_same() {
    let dir = temp_dir("show");
    for name in [
        "K100",
        "K102",
        "K108",
        "K110",
        "K110M",
        "K120",
        "K201",
        "K210",
        "K220",
        "IMX-5",
        "IMX-5-2022",
    ] {
        let path = show(name, &dir);
        let shown = std::fs::read_to_string(&path).unwrap();
        assert!(shown.contains("[gyro]") && shown.contains("[temperature]"));
        let out = imu_emu(&["sensor-profile", "check", path.to_str().unwrap()]);
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
        assert_eq!(body(&text(&out.stdout)), body(&shown), "{name}");
    }
    let imx = std::fs::read_to_string(dir.join("IMX-5.toml")).unwrap();
    assert!(
        imx.contains("range = 4000.0") && imx.contains("ARW 0.23 °/√h"),
        "{imx}"
    );
    let old = std::fs::read_to_string(dir.join("IMX-5-2022.toml")).unwrap();
    assert!(
        old.contains("ARW 0.16 °/√h") && old.contains("(19 µg)"),
        "{old}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The comments give the figures as a datasheet writes them (the shortest
/// decimal that gives the stored `f32` back: `0.02`, not `0.019999998`;
/// `1000 ppm`, not `1000.00006`), and only the models with an aux
/// accelerometer (K120, K220) have an `[aux]` section.
#[test]
fn comments_are_datasheet_figures_and_only_aux_models_have_aux() {
    let dir = temp_dir("figures");
    for (name, aux) in [
        ("K110", false),
        ("IMX-5", false),
        ("K120", true),
        ("K220", true),
    ] {
        let shown = std::fs::read_to_string(show(name, &dir)).unwrap();
        assert_eq!(shown.contains("\n[aux]\n"), aux, "{name}: {shown}");
        assert!(shown.contains("(VRW 0.0"), "{name}: {shown}");
        for wrong in ["0.0199999", "1000.00006", "0.99999", "00001 "] {
            assert!(!shown.contains(wrong), "{name}: {wrong} in {shown}");
        }
    }
    let imx = std::fs::read_to_string(dir.join("IMX-5.toml")).unwrap();
    for want in [
        "(ARW 0.23 °/√h)",
        "(VRW 0.02 m/s/√h)",
        "(2 °/h)",
        "(27 µg)",
        "(300 ppm)",
        "(0.01 °)",
    ] {
        assert!(imx.contains(want), "{want} in {imx}");
    }
    let k120 = std::fs::read_to_string(dir.join("K120.toml")).unwrap();
    assert!(
        k120.contains("(1000 ppm)") && k120.contains("(200 µg)"),
        "{k120}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_file_is_one_line_naming_the_key_and_its_range() {
    let dir = temp_dir("bad");
    let good = std::fs::read_to_string(show("K110", &dir)).unwrap();
    let cases = [
        (
            good.replace("range = 40.0", "range = 1000.0"),
            "acc.range = 1000 is outside the allowed range 0.5 ..= 128",
        ),
        (
            good.replace("time_constant_s = 600.0", "time_constant_s = -1.0"),
            "temperature.time_constant_s = -1 is outside the allowed range 0 ..= 1000000",
        ),
        (
            good.replacen("nonlinearity = 0.0", "nonlinearity = \"x\"", 1),
            "invalid type: string \"x\", expected f32",
        ),
        (
            good.replacen("resolution", "resolutoin", 1),
            "unknown field `resolutoin`",
        ),
    ];
    for (i, (file, want)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad{i}.toml"));
        std::fs::write(&path, file).unwrap();
        let p = path.to_str().unwrap();
        for args in [
            vec!["sensor-profile", "check", p],
            vec!["--sensor-profile", p, "--tcp", "127.0.0.1:0"],
        ] {
            let out = imu_emu(&args);
            let err = text(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{err}");
            assert!(err.contains(want), "{args:?}: {err}");
            assert!(
                out.stdout.is_empty(),
                "nothing listens: {}",
                text(&out.stdout)
            );
        }
    }
    let out = imu_emu(&["sensor-profile", "show", "K999"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("one of K100"),
        "{}",
        text(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Acc Z (g) of the fifth GA data frame of the device at `addr` (the
/// first ones average the FIR's start from the power-on history).
fn acc_z(addr: std::net::SocketAddr) -> f64 {
    let mut c = Conn::tcp(addr);
    c.send(&command(GA));
    // The acknowledgement first (a 2-byte payload), then data (32 bytes).
    let f = (0..20)
        .map(|_| c.frame_with_id(GA))
        .filter(|f| f.payload().len() == 32)
        .nth(4)
        .expect("five GA data frames");
    let p = f.payload();
    f64::from(i32::from_le_bytes(p[ACC_Z..ACC_Z + 4].try_into().unwrap())) / 1e6
}

#[test]
fn a_profile_for_one_device_of_a_fleet_changes_that_device_only() {
    let dir = temp_dir("fleet");
    let good = std::fs::read_to_string(show("K110", &dir)).unwrap();
    // The accelerometer's range at 0.5 g: a level unit's AccZ (1 g) reads
    // 0.5 g, saturated.
    let path = dir.join("half-g.toml");
    std::fs::write(&path, good.replace("range = 40.0", "range = 0.5")).unwrap();
    let arg = format!("1={}", path.display());
    let emu = Emu::start(&[
        "--count",
        "2",
        "--tcp",
        "127.0.0.1:0",
        "--sensor-profile",
        &arg,
    ]);
    let addrs = emu.tcp_addrs(2);
    let (a0, a1) = (acc_z(addrs[0]), acc_z(addrs[1]));
    assert!((a0 - 1.0).abs() < 0.01, "dev 0: {a0} g");
    assert_eq!(a1, 0.5, "dev 1 saturates at its profile's range");
    let _ = std::fs::remove_dir_all(&dir);
}
