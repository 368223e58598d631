//! End-to-end tests of `imu-emu client …`: each subcommand of
//! the real binary against the real emulator, checked by what it prints,
//! what it writes and what the device did.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::process::{Command, Output};
use std::time::Duration;

use support::Emu;

/// Runs `imu-emu client --tcp ADDR ARGS…` (killed after 20 s at most).
fn client(addr: &str, args: &[&str]) -> Output {
    let mut all = vec!["client", "--tcp", addr];
    all.extend_from_slice(args);
    run(&all)
}

fn run(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            panic!("client {args:?} did not finish");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Runs `imu-emu client plot CSV -o OUT`.
fn plot(csv: &std::path::Path, out: &std::path::Path) -> Output {
    run(&[
        "client",
        "plot",
        csv.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ])
}

fn stdout(o: &Output) -> String {
    assert!(
        o.status.success(),
        "{:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout.clone()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

/// `record SEL… --duration S -o CSV --raw RAW`.
fn record_args<'a>(
    sel: &[&'a str],
    duration: &'a str,
    csv: &'a std::path::Path,
    raw: &'a std::path::Path,
) -> Vec<&'a str> {
    let mut args = vec!["record"];
    args.extend_from_slice(sel);
    args.extend([
        "--duration",
        duration,
        "-o",
        csv.to_str().unwrap(),
        "--raw",
        raw.to_str().unwrap(),
    ]);
    args
}

fn emu() -> (Emu, String) {
    let e = Emu::tcp(&["--power-on", "now"]);
    let a = e.addr().to_string();
    (e, a)
}

#[test]
fn info_bit_get_set_and_their_errors() {
    let (_e, a) = emu();
    let info = stdout(&client(&a, &["info"]));
    let lines: Vec<&str> = info.lines().collect();
    assert_eq!(lines.len(), 3, "{info}");
    assert_eq!(lines[0], "serial: 10000000");
    assert!(
        lines[1].starts_with("firmware: KERNEL-110-G2000-A40 imu-emu "),
        "{info}"
    );
    // IMU_type as the README and Table 4.3 write it.
    assert_eq!(lines[2], "imu_type: 110");
    assert_eq!(
        stdout(&client(&a, &["bit"])),
        "bit: 00 00 00 00 (pass: accelerometer 0 ok, gyroscope 0 ok, flash 0 ok)\n"
    );
    assert_eq!(
        stdout(&client(&a, &["get", "Data_Rate"])),
        "Data_Rate = 100\n"
    );
    assert_eq!(
        stdout(&client(&a, &["set", "data_rate", "50"])),
        "Data_Rate saved = 50\n"
    );
    assert_eq!(stdout(&client(&a, &["get", "0x0012"])), "Data_Rate = 50\n");
    assert_eq!(
        stdout(&client(&a, &["get", "Alignment_Angles"])),
        "Alignment_Angles = 0,0,0\n"
    );
    // Refused by the device: no acknowledgement.
    let o = client(&a, &["--timeout", "0.5", "set", "Data_Rate", "33"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        format!(
            "imu-emu: --tcp {a}: SaveFlash Data_Rate 33: no acknowledgement within 500ms: the \
             unit refused the value (ICD 5.3.7) or did not hear it\n"
        )
    );
    // Refused by the client: a name not in Table 5.24.
    let o = client(&a, &["get", "Warp_Factor"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with("imu-emu: no parameter Warp_Factor; Table 5.24 names: Data_Rate")
    );
}

#[test]
fn start_stop_udd_and_commit_baud_act_on_the_device() {
    let (_e, a) = emu();
    assert_eq!(
        stdout(&client(&a, &["udd", "0x21,0x23,0x53"])),
        "udd configured: 3 types, max rate 250 Hz\n"
    );
    assert_eq!(
        stdout(&client(&a, &["start", "udd"])),
        "started UDD (0x95)\n"
    );
    // The stream runs the configured types.
    let o = client(&a, &["record", "--frames", "3", "--to", "json"]);
    let rows = stdout(&o);
    assert_eq!(rows.lines().count(), 3);
    for l in rows.lines() {
        assert!(l.starts_with("{\"frame\":"), "{l}");
        assert!(l.contains("\"format\":\"UDD\""), "{l}");
        assert!(l.contains("\"gyro_x\":") && l.contains("\"acc_z\":") && l.contains("\"usw\":0}"));
    }
    assert_eq!(stdout(&client(&a, &["stop"])), "stopped\n");
    assert_eq!(
        stdout(&client(&a, &["start", "0x8f"])),
        "started GA (0x8f)\n"
    );
    assert_eq!(stdout(&client(&a, &["stop"])), "stopped\n");
    let o = client(&a, &["start", "warp"]);
    assert_eq!(o.status.code(), Some(2));
    let o = client(&a, &["udd", "0x21,0x77"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("udd refused: error bits"),
        "{}",
        stderr(&o)
    );
    // Baud_Rate 230400 (code 8) saved, committed: the device switches; a
    // TCP client does not notice the rate, it still gets answers.
    // Typed in bit/s; the hint says the line changes on CommitBaudRate.
    assert_eq!(
        stdout(&client(&a, &["set", "Baud_Rate", "230400"])),
        "Baud_Rate saved = 230400 bit/s (code 8) (the line changes after `imu-emu client \
         commit-baud`, CommitBaudRate, ICD 5.3.9, or at the next power-on; `get` reads the \
         running rate until then)\n"
    );
    let o = client(&a, &["set", "Baud_Rate", "12345"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with("imu-emu: Baud_Rate: 12345 is not a line rate; bit/s: 115200 4800"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        stdout(&client(&a, &["commit-baud"])),
        "baud rate committed\n"
    );
    assert_eq!(
        stdout(&client(&a, &["get", "Baud_Rate"])),
        "Baud_Rate = 230400 bit/s (code 8)\n"
    );
}

/// A BIT that fails: exit status 1, the failing result named on stdout and
/// stderr (a script can test `$?`).
#[test]
fn a_failing_bit_exits_non_zero_and_names_the_bits() {
    let ctl = format!("127.0.0.1:{}", support::free_port());
    let e = Emu::tcp(&["--power-on", "now", "--control", &ctl]);
    let a = e.addr().to_string();
    let mut c = support::Control::connect(&ctl);
    assert_eq!(c.cmd("fault gyro-bit on"), "ok");
    let o = client(&a, &["bit"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        "bit: 04 00 00 00 (FAIL: accelerometer 0 ok, gyroscope 1 FAIL, flash 0 ok)\n"
    );
    assert_eq!(
        stderr(&o),
        "imu-emu: BIT failed: accelerometer 0 ok, gyroscope 1 FAIL, flash 0 ok\n"
    );
}

/// `record` of a 2 s GA stream at 100 Hz: 200 rows, the 2 kHz counter
/// stepping by 20 on every row; `decode` of its raw capture gives the same
/// rows; `plot` writes a PNG.
#[test]
fn record_decode_and_plot() {
    let (_e, a) = emu();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("ga.csv");
    let raw = dir.path().join("ga.bin");
    let o = client(&a, &record_args(&["--format", "GA"], "2", &csv, &raw));
    stdout(&o);
    assert_eq!(
        stderr(&o),
        "imu-emu: 200 frames recorded, 1.990 s of device time, 0 failed their checksum, 0 \
         counter gaps\n"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "frame,format,device_time_s,host_time_s,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,\
         counter,usw,temp_c"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 200);
    // Device time from the frames' counter: 10 ms a row from 0.
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[2], format!("{:.6}", i as f64 * 0.01), "row {i}");
    }
    let counters: Vec<u16> = rows.iter().map(|r| r[10].parse().unwrap()).collect();
    for (i, w) in counters.windows(2).enumerate() {
        assert_eq!(w[1], w[0].wrapping_add(20), "gap after row {i}");
    }
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[0], i.to_string());
        assert_eq!(r[1], "GA");
        // At rest, level: about 1 g on Z.
        let az: f64 = r[9].parse().unwrap();
        assert!((az - 1.0).abs() < 0.05, "{az}");
    }

    // The raw capture holds the acknowledgement and the GA frames;
    // decoding it gives the same GA rows (no host time), on stdout when
    // the output is named `-`.
    let o = run(&["client", "decode", raw.to_str().unwrap(), "-o", "-"]);
    let decoded = stdout(&o);
    let mut dl = decoded.lines();
    assert_eq!(
        dl.next().unwrap(),
        "frame,format,device_time_s,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,counter,usw,temp_c"
    );
    let drows: Vec<Vec<&str>> = dl.map(|l| l.split(',').collect()).collect();
    assert!(drows.len() >= 200, "{}", drows.len());
    let first = drows.iter().position(|r| r[9] == rows[0][10]).unwrap();
    for (r, d) in rows.iter().zip(&drows[first..]) {
        assert_eq!(r[4..], d[3..]);
    }

    let png = dir.path().join("ga.png");
    let o = plot(&csv, &png);
    assert_eq!(stdout(&o), format!("{}: 200 rows plotted\n", png.display()));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width and height.
    assert_eq!(&bytes[12..16], b"IHDR");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 1200);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 900);
    assert!(bytes.len() > 10_000, "{}", bytes.len());

    // SVG by extension: titled, labelled axes with units, a legend, ticks.
    let svg = dir.path().join("ga.svg");
    let o = plot(&csv, &svg);
    assert_eq!(stdout(&o), format!("{}: 200 rows plotted\n", svg.display()));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..80]);
    for label in [
        "ga.csv: GA, 200 rows",
        "Angular rate",
        "Acceleration",
        "device time (s)",
        "angular rate (deg/s)",
        "specific force (g)",
        "X",
        "Z",
        "1.0",
        "1.8",
    ] {
        // plotters writes each text on a line of its own.
        assert!(
            text.contains(&format!(">\n{label}\n<")),
            "no {label} in the SVG"
        );
    }
    // A missing folder and an unknown extension: one clear line each.
    let o = run(&[
        "client",
        "plot",
        csv.to_str().unwrap(),
        "-o",
        "/nonexistent/ga.png",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        "imu-emu: plot: /nonexistent/ga.png: the folder /nonexistent does not exist\n"
    );
    let o = plot(&csv, std::path::Path::new("ga.jpg"));
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr(&o),
        "imu-emu: plot: ga.jpg: name a .png or .svg file\n"
    );
}

/// A `--speed max` recording spans the whole device-time axis: its rows
/// are 10 ms apart in device time however fast the host received them.
#[test]
fn a_speed_max_recording_is_plotted_against_device_time() {
    let e = Emu::tcp(&["--power-on", "now", "--speed", "max"]);
    let a = e.addr().to_string();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("fast.csv");
    let o = client(
        &a,
        &[
            "record",
            "--format",
            "GA",
            "--frames",
            "500",
            "-o",
            csv.to_str().unwrap(),
        ],
    );
    stdout(&o);
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 500);
    assert_eq!(rows[499][2], "4.990000");
    let svg = dir.path().join("fast.svg");
    let o = plot(&csv, &svg);
    stdout(&o);
    let text = std::fs::read_to_string(&svg).unwrap();
    // Ticks up to the last device second.
    assert!(text.contains(">\n4.5\n<"), "no 4.5 s tick");
}

/// One clear line for each failure: a port nobody listens on, a unit that
/// does not answer, answers that fail their checksum.
#[test]
fn errors_are_one_clear_line() {
    // Nobody listens.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    let o = client(&addr, &["info"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        format!("imu-emu: --tcp {addr}: cannot connect: Connection refused (os error 111)\n")
    );
    // Something listens but never answers.
    let silent = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = silent.local_addr().unwrap().to_string();
    let o = client(&addr, &["--timeout", "0.3", "info"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        format!(
            "imu-emu: --tcp {addr}: no answer to GetDevInfo within 300ms (is the unit on, the \
             line rate right?)\n"
        )
    );
    // The emulator with every output byte corrupted: checksum errors.
    let ctl = format!(
        "127.0.0.1:{}",
        std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port()
    );
    let e = Emu::tcp(&["--power-on", "now", "--control", &ctl]);
    let mut c = support::Control::connect(&ctl);
    assert_eq!(c.cmd("link corrupt 0.05 tx"), "ok");
    let a = e.addr().to_string();
    let o = client(&a, &["--timeout", "0.5", "info"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.starts_with(&format!(
            "imu-emu: --tcp {a}: no valid answer to GetDevInfo within 500ms: "
        )) && err.ends_with(" frames failed their checksum (wrong --baud?)\n"),
        "{err}"
    );
    // Neither --tcp nor --serial.
    let o = run(&["client", "info"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr(&o),
        "imu-emu: client: say where the unit is: --tcp HOST:PORT or --serial DEV\n"
    );
}

/// `client --serial DEV`: the emulator's pty as the serial port.
#[test]
fn the_client_talks_over_a_serial_port() {
    let e = Emu::start(&["--pty"]);
    let path = e.pty_path();
    let o = run(&[
        "client",
        "--serial",
        path.to_str().unwrap(),
        "--baud",
        "115200",
        "get",
        "Data_Rate",
    ]);
    assert_eq!(stdout(&o), "Data_Rate = 100\n");
    let o = run(&["client", "--serial", "/nonexistent/tty", "info"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).starts_with("imu-emu: --serial /nonexistent/tty: cannot open: "),
        "{}",
        stderr(&o)
    );
}

/// `client record --format GA -o CSV` running in the background, once
/// rows arrive (the header and some rows are flushed by 8 KiB blocks:
/// wait for the file to grow).
fn recording(a: &str, csv: &std::path::Path) -> std::process::Child {
    let child = Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["client", "--tcp", a, "record", "--format", "GA", "-o"])
        .arg(csv)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    while std::fs::metadata(csv).map_or(0, |m| m.len()) == 0 {
        assert!(std::time::Instant::now() < deadline, "no rows");
        std::thread::sleep(Duration::from_millis(50));
    }
    child
}

/// Ctrl-C during `record`: the stream the client started is stopped, the
/// summary printed, the exit status 0; the unit then sends nothing.
#[test]
fn ctrl_c_during_record_stops_the_stream_and_prints_a_summary() {
    let (_e, a) = emu();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("ga.csv");
    let mut child = recording(&a, &csv);
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGINT,
    )
    .unwrap();
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    while child.try_wait().unwrap().is_none() {
        assert!(std::time::Instant::now() < deadline, "record did not stop");
        std::thread::sleep(Duration::from_millis(10));
    }
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.starts_with("imu-emu: ")
            && err.ends_with(
                " s of device time, 0 failed their checksum, 0 counter gaps (interrupted; \
                 stream stopped)\n"
            ),
        "{err}"
    );
    let rows: u64 = err["imu-emu: ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count() as u64, rows + 1);
    // The stream is off: a new client hears no data frame.
    let o = client(&a, &["--timeout", "0.5", "record", "--frames", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("no data frame within 500ms after 0 rows"),
        "{}",
        stderr(&o)
    );
}

/// The ISB emulator (`--protocol isb`) on TCP, and `client --protocol isb`.
fn isb_emu() -> (Emu, String) {
    let e = Emu::tcp(&["--protocol", "isb", "--power-on", "now"]);
    let a = e.addr().to_string();
    (e, a)
}

fn isb(addr: &str, args: &[&str]) -> Output {
    let mut all = vec!["--protocol", "isb"];
    all.extend_from_slice(args);
    client(addr, &all)
}

/// `--protocol isb`: info, BIT, get and set of data-set fields by name,
/// the unit's NACK of a read-only field as exit status 1, names refused.
#[test]
fn isb_client_info_bit_get_and_set() {
    let (_e, a) = isb_emu();
    let info = stdout(&isb(&a, &["info"]));
    for line in [
        "hardwareType = 3",
        "serialNumber = 10000000 (0x989680)",
        "protocolVer = 2.1.0.0",
        "manufacturer = Inertial Sense Inc",
    ] {
        assert!(info.lines().any(|l| l == line), "no {line} in\n{info}");
    }
    assert_eq!(
        stdout(&isb(&a, &["bit"])),
        "hdwBitStatus: 0x00000002 (pass: passed without GPS)\n"
    );
    assert_eq!(
        stdout(&isb(&a, &["get", "startupNavDtMs"])),
        "startupNavDtMs = 4 ms\n"
    );
    assert_eq!(
        stdout(&isb(&a, &["set", "flash_config.startupNavDtMs", "8"])),
        "FLASH_CONFIG.startupNavDtMs saved = 8\n(takes effect after a reset: `imu-emu client \
         --protocol isb reset` (SYS_CMD 99 with its inverse), or a power cycle)\n"
    );
    assert_eq!(
        stdout(&isb(&a, &["get", "startupNavDtMs"])),
        "startupNavDtMs = 8 ms\n"
    );
    let rmc = stdout(&isb(&a, &["get", "RMC"]));
    assert_eq!(rmc, "bits = 0\noptions = 0\n");
    // The unit refuses a change of a read-only byte (NACK): exit 1.
    let o = isb(&a, &["set", "SYS_PARAMS.imuTemp", "99"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        format!(
            "imu-emu: --tcp {a}: SET_DATA SYS_PARAMS.imuTemp 99: the unit refused the value \
             (NACK)\n"
        )
    );
    // Ambiguous or unknown names, KERNEL-only commands: usage errors.
    let o = isb(&a, &["get", "time"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).starts_with("imu-emu: no field time; name it SET.field"));
    let o = isb(&a, &["commit-baud"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).starts_with("imu-emu: commit-baud is a KERNEL command;"));
    // A KERNEL client against the ISB unit: no answer, exit 1.
    let o = client(&a, &["--timeout", "0.3", "info"]);
    assert_eq!(o.status.code(), Some(1));
}

/// `--protocol isb record`: IMU packets to CSV with the set's own time as
/// device time (4 ms apart), one second of device time; the raw capture
/// decodes to the same rows; the plot is in the IMU's units; two sets to
/// JSON lines.
#[test]
fn isb_client_record_decode_and_plot() {
    let (_e, a) = isb_emu();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("imu.csv");
    let raw = dir.path().join("imu.bin");
    let o = isb(&a, &record_args(&["--did", "IMU"], "1", &csv, &raw));
    stdout(&o);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "frame,did,device_time_s,host_time_s,time,status,pqr_x,pqr_y,pqr_z,acc_x,acc_y,acc_z"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let times: Vec<f64> = rows.iter().map(|r| r[4].parse().unwrap()).collect();
    // After the packet the GET answers with at once, a stream on the 4 ms
    // navigation period, up to one second after the first.
    for w in times[1..].windows(2) {
        assert!((w[1] - w[0] - 0.004).abs() < 1e-9, "{w:?}");
    }
    assert!(times[times.len() - 1] - times[0] < 1.0);
    assert!(times[times.len() - 1] + 0.004 - times[0] >= 1.0 - 1e-9);
    assert_eq!(
        stderr(&o),
        format!(
            "imu-emu: {} packets recorded (IMU {} over {:.3} s of device time), 0 failed their \
             checksum\n",
            rows.len(),
            rows.len(),
            times[times.len() - 1] - times[0]
        )
    );
    for r in &rows {
        assert_eq!(r[1], "IMU");
        // At rest, level, the IMX's z axis down: acc z about −g.
        let az: f64 = r[11].parse().unwrap();
        assert!((az + 9.81).abs() < 0.1, "{az}");
    }
    let o = run(&[
        "client",
        "--protocol",
        "isb",
        "decode",
        "--did",
        "IMU",
        raw.to_str().unwrap(),
    ]);
    let decoded = stdout(&o);
    let drows: Vec<Vec<&str>> = decoded
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    for (r, d) in rows.iter().zip(&drows) {
        assert_eq!(r[4..], d[3..]);
    }
    let svg = dir.path().join("imu.svg");
    stdout(&plot(&csv, &svg));
    let text = std::fs::read_to_string(&svg).unwrap();
    for label in [
        "angular rate (rad/s)",
        "specific force (m/s²)",
        "device time (s)",
    ] {
        assert!(text.contains(&format!(">\n{label}\n<")), "no {label}");
    }
    // Two sets: JSON lines (a CSV holds one set's columns).
    let o = isb(
        &a,
        &[
            "record", "--did", "IMU,PIMU", "--frames", "4", "--to", "json",
        ],
    );
    let rows = stdout(&o);
    assert_eq!(rows.lines().count(), 4);
    assert!(rows.contains("\"did\":\"IMU\"") && rows.contains("\"did\":\"PIMU\""));
    assert!(rows.contains("\"theta_x\":") && rows.contains("\"pqr_x\":"));
    let o = isb(&a, &["record", "--did", "IMU,PIMU", "--frames", "4"]);
    assert_eq!(o.status.code(), Some(2));
    // A navigation set: INS_2 with its GPS time of week as device time.
    let o = isb(
        &a,
        &["record", "--did", "ins_2", "--frames", "3", "--to", "json"],
    );
    let rows = stdout(&o);
    assert_eq!(rows.lines().count(), 3);
    for l in rows.lines() {
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        assert_eq!(v["did"], "INS_2");
        let tow = v["timeOfWeek"].as_f64().unwrap();
        assert!(
            (v["device_time_s"].as_f64().unwrap() - tow).abs() < 1e-6,
            "{l}"
        );
        assert!(v["qn2b_w"].is_number() && v["lla_z"].is_number(), "{l}");
    }
}

/// `set Data_Rate 1000` at 115 200 bit/s says the rate the device lowers
/// it to (Formula 5.1: GA 250 Hz), and `record --duration 2` then records
/// two seconds of device time at that rate (500 frames 8 counter ticks
/// apart), not 2 × 1000 frames.
#[test]
fn record_duration_counts_device_time_at_the_rate_the_device_runs() {
    let (_e, a) = emu();
    assert_eq!(
        stdout(&client(&a, &["set", "Data_Rate", "1000"])),
        "Data_Rate saved = 1000\nat 115200 bit/s the device lowers it (ICD 5.5, Formula 5.1): \
         it sends GA, GAm at 250 Hz; Orientation, GAA, GAAm, Quaternion at 200 Hz; Calibrated \
         HR at 125 Hz (a UDD by its length; a faster line rate keeps 1000 Hz)\n"
    );
    // A rate every format keeps: nothing more.
    assert_eq!(
        stdout(&client(&a, &["set", "Data_Rate", "50"])),
        "Data_Rate saved = 50\n"
    );
    stdout(&client(&a, &["set", "Data_Rate", "1000"]));
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("ga.csv");
    let started = std::time::Instant::now();
    let o = client(
        &a,
        &[
            "record",
            "--format",
            "GA",
            "--duration",
            "2",
            "-o",
            csv.to_str().unwrap(),
        ],
    );
    stdout(&o);
    assert_eq!(
        stderr(&o),
        "imu-emu: 500 frames recorded, 1.996 s of device time, 0 failed their checksum, 0 \
         counter gaps\n"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 500);
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[2], format!("{:.6}", i as f64 * 0.004), "row {i}");
    }
    let counters: Vec<u16> = rows.iter().map(|r| r[10].parse().unwrap()).collect();
    assert!(counters.windows(2).all(|w| w[1] == w[0].wrapping_add(8)));
    // Real time: about the two seconds asked for (it was 8 s).
    assert!(
        started.elapsed() < Duration::from_secs(6),
        "{:?}",
        started.elapsed()
    );
}

/// Formats without a clock field (GAA, Orientation, Quaternion, GAm, GAAm)
/// get `device_time_s` too: the frame's place in the stream at the rate
/// the device runs (read from the unit by `record`; `decode --rate`, else
/// the factory 100 Hz), and `--duration` counts it.
#[test]
fn clockless_formats_are_timed_from_their_rate_and_order() {
    let (_e, a) = emu();
    stdout(&client(&a, &["set", "Data_Rate", "50"]));
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("gaa.csv");
    let raw = dir.path().join("gaa.bin");
    let o = client(&a, &record_args(&["--format", "GAA"], "1", &csv, &raw));
    stdout(&o);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("frame,format,device_time_s,host_time_s,gyro_x"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 50);
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[1], "GAA");
        assert_eq!(r[2], format!("{:.6}", i as f64 * 0.02), "row {i}");
    }
    // decode: --rate times them; without it the factory 100 Hz, said.
    let o = run(&["client", "decode", raw.to_str().unwrap(), "--rate", "50"]);
    let d: Vec<String> = stdout(&o).lines().skip(1).map(str::to_owned).collect();
    assert!(d.len() >= 50, "{}", d.len());
    assert_eq!(d[49].split(',').nth(2), Some("0.980000"));
    let o = run(&["client", "decode", raw.to_str().unwrap()]);
    let d: Vec<String> = stdout(&o).lines().skip(1).map(str::to_owned).collect();
    assert_eq!(d[1].split(',').nth(2), Some("0.010000"));
    assert!(
        stderr(&o).starts_with(&format!(
            "imu-emu: {}: GAA frames carry no clock: device_time_s counts them at 100 Hz, the \
             factory Data_Rate (--rate HZ for another)\n",
            raw.display()
        )),
        "{}",
        stderr(&o)
    );
}

/// `client decode` of an IMX-5's capture without `--protocol isb` decodes
/// it as ISB (and says so); bytes that are neither fail with one line and
/// exit 1; `decode … | head` ends quietly with status 0.
#[test]
fn decode_detects_the_protocol_and_ends_quietly_on_a_closed_pipe() {
    let (_e, a) = isb_emu();
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("imu.bin");
    stdout(&isb(
        &a,
        &[
            "record",
            "--did",
            "IMU",
            "--frames",
            "300",
            "-o",
            "/dev/null",
            "--raw",
            raw.to_str().unwrap(),
        ],
    ));
    let o = run(&["client", "decode", raw.to_str().unwrap()]);
    let text = stdout(&o);
    assert!(
        text.starts_with("frame,did,device_time_s,time,status,pqr_x"),
        "{text}"
    );
    assert!(text.lines().count() >= 301);
    assert!(stderr(&o).starts_with(&format!(
        "imu-emu: {}: ISB packets (an IMX-5's capture): decoded as --protocol isb\n",
        raw.display()
    )));
    // Forced to KERNEL: nothing decodes, an error.
    let o = run(&[
        "client",
        "--protocol",
        "kernel",
        "decode",
        raw.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.starts_with(&format!(
            "imu-emu: decode {}: no KERNEL data frame in ",
            raw.display()
        )) && err.ends_with("not a KERNEL capture? (--protocol isb for an IMX-5's)\n"),
        "{err}"
    );
    // From a pipe (read once: the protocol from its head, then the rest).
    let piped = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "cat '{}' | '{}' client decode /dev/stdin",
            raw.display(),
            env!("CARGO_BIN_EXE_imu-emu")
        ))
        .output()
        .unwrap();
    assert_eq!(stdout(&piped), text);
    let junk = dir.path().join("junk.bin");
    std::fs::write(&junk, b"hello, this is not a capture\n").unwrap();
    let o = run(&["client", "decode", junk.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(err.lines().count(), 1);
    // | head: the reader goes away after two lines.
    let mut child = Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(["client", "decode", raw.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::BufRead as _;
        let mut r = std::io::BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        r.read_line(&mut line).unwrap();
        r.read_line(&mut line).unwrap();
    }
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("Broken pipe"), "{}", stderr(&o));
}

/// A recording whose line a second client takes over (the emulator serves
/// one client at a time) ends saying so, not `write: Broken pipe`.
#[test]
fn a_recording_taken_over_by_another_client_says_so() {
    let (_e, a) = emu();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("ga.csv");
    let mut child = recording(&a, &csv);
    stdout(&client(&a, &["info"]));
    let deadline = std::time::Instant::now() + Duration::from_secs(10);
    while child.try_wait().unwrap().is_none() {
        assert!(std::time::Instant::now() < deadline, "record did not end");
        std::thread::sleep(Duration::from_millis(10));
    }
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        format!(
            "imu-emu: --tcp {a}: the unit closed the connection (the emulator serves one client \
             at a time: another client connecting took the line over, or the emulator stopped)\n"
        )
    );
}

/// ISB `reset` and `factory-reset` send the SYS_CMD command with its
/// inverse in one packet: a saved startupNavDtMs 8 takes effect at the
/// reset (IMU packets 8 ms apart), the factory reset restores 4 ms; the
/// hint printed by `set` is that command. `set SYS_CMD.command 99` sends
/// the pair too; `set SET v,v,…` writes a whole set.
#[test]
fn isb_reset_factory_reset_and_whole_sets() {
    let (_e, a) = isb_emu();
    let imu_period = |a: &str| -> f64 {
        let o = isb(
            a,
            &["record", "--did", "IMU", "--frames", "5", "--to", "csv"],
        );
        let text = stdout(&o);
        let t: Vec<f64> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(4).unwrap().parse().unwrap())
            .collect();
        ((t[4] - t[1]) / 3.0 * 1e4).round() / 1e4
    };
    assert_eq!(imu_period(&a), 0.004);
    let set = stdout(&isb(&a, &["set", "FLASH_CONFIG.startupNavDtMs", "8"]));
    assert!(
        set.contains("`imu-emu client --protocol isb reset`"),
        "{set}"
    );
    assert_eq!(imu_period(&a), 0.004, "not before the reset");
    assert_eq!(
        stdout(&isb(&a, &["reset"])),
        "reset (SYS_CMD 99): the unit restarts with its saved FLASH_CONFIG\n"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(imu_period(&a), 0.008);
    assert_eq!(
        stdout(&isb(&a, &["factory-reset"])),
        "factory reset (SYS_CMD 1357924680 after the unlock): FLASH_CONFIG back to its \
         defaults, saved; the unit restarts\n"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        stdout(&isb(&a, &["get", "startupNavDtMs"])),
        "startupNavDtMs = 4 ms\n"
    );
    assert_eq!(imu_period(&a), 0.004);
    // One field of SYS_CMD: the client adds the inverse.
    stdout(&isb(&a, &["set", "FLASH_CONFIG.startupNavDtMs", "8"]));
    assert_eq!(
        stdout(&isb(&a, &["set", "SYS_CMD.command", "99"])),
        "SYS_CMD.command saved = 99\n(sent with SYS_CMD.invCommand = 0xffffff9c in the same \
         SET_DATA: a command runs only with its inverse)\n"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(imu_period(&a), 0.008);
    // A whole set: every field in order.
    stdout(&isb(&a, &["set", "FLASH_CONFIG.startupNavDtMs", "4"]));
    assert_eq!(
        stdout(&isb(&a, &["set", "SYS_CMD", "99,4294967196"])),
        "SYS_CMD saved = 99,4294967196\n"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(imu_period(&a), 0.004);
    let o = isb(&a, &["set", "SYS_CMD", "99"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr(&o),
        "imu-emu: set SYS_CMD: 1 values given, the set takes 2 (command, invCommand, in order, \
         comma-separated)\n"
    );
    // A KERNEL has none of it.
    let o = run(&["client", "--tcp", &a, "reset"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("reset and factory-reset are IMX-5 (--protocol isb) commands"));
}

/// A record of IMU (time since boot) and INS_1 (GPS time of week) sums
/// up each set on its own clock: no span across the two.
#[test]
fn a_mixed_isb_record_is_summed_up_per_set() {
    let (_e, a) = isb_emu();
    let o = isb(
        &a,
        &[
            "record",
            "--did",
            "IMU,INS_1",
            "--duration",
            "1",
            "--to",
            "json",
            "-o",
            "/dev/null",
        ],
    );
    stdout(&o);
    let err = stderr(&o);
    // `imu-emu: N packets recorded (IMU n over 0.99x s of device time,
    // INS_1 m over 0.99x s of device time), 0 failed their checksum`.
    let words: Vec<&str> = err
        .split([' ', '(', ','])
        .filter(|w| !w.is_empty())
        .collect();
    assert_eq!(
        words,
        [
            "imu-emu:",
            words[1],
            "packets",
            "recorded",
            "IMU",
            words[5],
            "over",
            words[7],
            "s",
            "of",
            "device",
            "time",
            "INS_1",
            words[13],
            "over",
            words[15],
            "s",
            "of",
            "device",
            "time)",
            "0",
            "failed",
            "their",
            "checksum\n"
        ],
        "{err}"
    );
    let n = |i: usize| words[i].parse::<u64>().unwrap();
    assert_eq!(n(1), n(5) + n(13));
    assert!(n(5) >= 249 && n(13) >= 249, "{err}");
    for span in [words[7], words[15]] {
        let s: f64 = span.parse().unwrap();
        // Printed to the ms: up to 1.000 for a span just under 1 s.
        assert!((0.99..=1.0).contains(&s), "{err}");
    }
    assert!(!err.contains("over -"), "{err}");
}

/// The points of each `<polyline>` of an SVG with these attributes.
fn polylines(svg: &str, attrs: &str) -> Vec<Vec<(i32, i32)>> {
    svg.lines()
        .filter(|l| l.starts_with("<polyline") && l.contains(attrs))
        .map(|l| {
            let p = &l[l.find("points=\"").unwrap() + 8..];
            p[..p.find('"').unwrap()]
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

/// A PIMU plot: the Δθ axis spans its data (10⁻⁵ rad, labelled as such,
/// not ±0.001), every data line stays inside its panel's frame, and the
/// legend stands beside the frame (it covered the last data).
#[test]
fn plots_fit_their_data_inside_the_frame_with_the_legend_beside() {
    let (_e, a) = isb_emu();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("pimu.csv");
    stdout(&isb(
        &a,
        &[
            "record",
            "--did",
            "PIMU",
            "--duration",
            "1",
            "-o",
            csv.to_str().unwrap(),
        ],
    ));
    let svg = dir.path().join("pimu.svg");
    stdout(&plot(&csv, &svg));
    let text = std::fs::read_to_string(&svg).unwrap();
    // Frames: the axis lines (1 px, black) that are whole sides: a y axis
    // (x fixed, its panel's height) and an x axis (y fixed).
    let axes = polylines(&text, "stroke=\"#000000\" stroke-width=\"1\"");
    let sides: Vec<&Vec<(i32, i32)>> = axes.iter().filter(|p| p.len() == 2).collect();
    let frames: Vec<((i32, i32), (i32, i32))> = sides
        .iter()
        .filter(|p| p[0].0 == p[1].0 && p[1].1 - p[0].1 > 200)
        .map(|y_axis| {
            let x_axis = sides
                .iter()
                .find(|q| {
                    q[0].1 == q[1].1 && (q[0].0 - y_axis[0].0).abs() <= 1 && q[1].0 - q[0].0 > 500
                })
                .expect("an x axis beside the y axis");
            (
                (y_axis[0].0, x_axis[1].0),
                (y_axis[0].1, y_axis[1].1.max(x_axis[0].1)),
            )
        })
        .collect();
    assert_eq!(frames.len(), 2, "{frames:?}");
    let lines = polylines(&text, "stroke-width=\"2\"");
    let (data, legend): (Vec<_>, Vec<_>) = lines.iter().partition(|p| p.len() > 2);
    assert_eq!(data.len(), 6);
    for (k, line) in data.iter().enumerate() {
        let ((x0, x1), (y0, y1)) = frames[k / 3];
        for &(x, y) in line.iter() {
            assert!(
                (x0..=x1).contains(&x) && (y0..=y1).contains(&y),
                "line {k}: ({x}, {y}) outside {frames:?}"
            );
        }
    }
    assert_eq!(legend.len(), 6);
    for l in &legend {
        assert!(
            l[0].0 > frames[0].0 .1,
            "legend sample at {l:?} inside the frame"
        );
    }
    // The Δθ axis is labelled in 10⁻⁶ rad (the data are ≈ 10⁻⁵ rad).
    assert!(text.contains("e-6\n<"), "no tick in 10⁻⁶");
    assert!(!text.contains(">\n0.0010\n<") && !text.contains(">\n0.001\n<"));
    assert!(!text.contains(">\n-0.0\n<"));
}
