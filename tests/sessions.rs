//! Golden sessions (nothing changes on the wire): scripted
//! sessions driven straight through the core [`Device`] with a fixed seed
//! and a fixed tick schedule (tick `k` at `k × tick_period_ns()`), recorded
//! byte for byte — every TX byte and every event, with the tick it appeared
//! at — and compared exactly with the transcripts committed under
//! `tests/data/sessions/` (`float/`, or `fixed/` with the `fixed-point`
//! feature: the two arithmetic paths give different sensor bytes).
//!
//! The transcripts were first recorded from commit 61779f3, before the
//! device was split into a shell and a KERNEL personality; any change to
//! them is a change on the wire and must be deliberate. To rewrite them
//! after such a change, run with `IMU_EMU_BLESS=1` and review the diff:
//!
//! ```text
//! IMU_EMU_BLESS=1 cargo test -p imu-emu --test sessions
//! IMU_EMU_BLESS=1 cargo test -p imu-emu --test sessions --features fixed-point
//! ```
//!
//! The scripts use only the public `Device` entry points (power-on with a
//! seed and BOOT level, `on_rx`, `on_tick`, `on_pin`, `poll_tx`,
//! `poll_event`, `tick_period_ns`, `tx_dropped`, `into_flash`) and build their command
//! frames by hand from the ICD (Table 5.2 framing), so they survive a
//! reorganisation of the crate. A power cycle is a fresh power-on with the
//! same flash, seed and time line.
//!
//! Transcript lines: `k=<tick> <what> <detail>`, where `<what>` is
//! * `on` — power-on (BOOT level, seed),
//! * `rx` — bytes handed to `on_rx` (hex) and what they are,
//! * `pin` — an `on_pin` edge and its time in ns,
//! * `tx` — bytes from `poll_tx`, hex, one line per frame (the lines
//!   concatenated are the exact stream),
//! * `ev` — an event from `poll_event`,
//! * `stall` / `resume` — the board stops / starts again reading `poll_tx`
//!   and `poll_event` (a stalled board lets the TX queue fill),
//! * `end` — the last tick run, with `tx_dropped`.

use std::fmt::Write as _;
use std::path::PathBuf;

use imu_emu::device::{Device, Event, Level, Pin, PowerOn};
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;
use imu_emu::Kernel;

type Flash = RamNor<8192>;

// ----- command frames (ICD Table 5.2, 5.3, Tables 5.23, 5.25) -----

/// A host → device frame: `AA 55 00 00 len16 payload sum16`.
fn frame(payload: &[u8]) -> Vec<u8> {
    let mut f = vec![0xAA, 0x55, 0x00, 0x00];
    f.extend_from_slice(&((payload.len() + 6) as u16).to_le_bytes());
    f.extend_from_slice(payload);
    let sum = f[2..]
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)));
    f.extend_from_slice(&sum.to_le_bytes());
    f
}

/// SaveFlash (Table 5.23): `B2 FF id16 len16 value`.
fn save(id: u16, value: &[u8]) -> Vec<u8> {
    save_len(id, value.len() as u16, value)
}

/// SaveFlash with an explicit length field.
fn save_len(id: u16, len: u16, value: &[u8]) -> Vec<u8> {
    let mut p = vec![0xB2, 0xFF];
    p.extend_from_slice(&id.to_le_bytes());
    p.extend_from_slice(&len.to_le_bytes());
    p.extend_from_slice(value);
    frame(&p)
}

/// ReadRAM (Table 5.25): `B1 FF id16 len16`.
fn read(id: u16, len: u16) -> Vec<u8> {
    let mut p = vec![0xB1, 0xFF];
    p.extend_from_slice(&id.to_le_bytes());
    p.extend_from_slice(&len.to_le_bytes());
    frame(&p)
}

/// A one-byte command (data command, Stop, GetDevInfo, …).
fn cmd(code: u8) -> Vec<u8> {
    frame(&[code])
}

// Parameter IDs of Table 5.24.
const DATA_RATE: u16 = 0x0012;
const INITIAL_ALIGNMENT_TIME: u16 = 0x0014;
const ALIGNMENT_ANGLES: u16 = 0x023A;
const SENSORS_MEASUREMENT_RANGE: u16 = 0x028F;
const AUTO_START: u16 = 0x03A9;
const BAUD_RATE: u16 = 0x03B2;
const OUTPUT_VARIANT: u16 = 0x03D0;
const LPF_BANDWIDTH: u16 = 0x03D7;
const TOV_CONTROL: u16 = 0x0499;
const TRIGGER_CONTROL: u16 = 0x05FA;
const POLARITY: u16 = 0x05FB;
const HOLD_OFF_TIME: u16 = 0x05FE;

// Command codes (ICD 5.3, Table 5.16).
const STOP: u8 = 0xFE;
const GET_DEV_INFO: u8 = 0x12;
const GET_BIT: u8 = 0x1A;
const UDD_CONFIG: u8 = 0x96;
const GET_UDD_STRUCT: u8 = 0x97;
const COMMIT_BAUD_RATE: u8 = 0xC2;
const DEVICE_PARAMETERS: u8 = 0x41;
const ORIENTATION: u8 = 0x33;
const GA: u8 = 0x8F;
const GAM: u8 = 0x9B;
const GAA: u8 = 0xA5;
const GAAM: u8 = 0xA6;
const QUATERNION: u8 = 0x82;
const CALIBRATED_HR: u8 = 0x81;
const UDD: u8 = 0x95;

// ----- the session recorder -----

/// One device, its time line and the transcript of what it did.
struct Session {
    dev: Option<Device<Flash, Kernel>>,
    product: Product,
    seed: u64,
    period: u64,
    tick: u64,
    /// Whether the board reads what the device sends after every step
    /// (off: a board that stalls, so the TX queue fills).
    reading: bool,
    out: String,
}

fn hex(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        let _ = write!(s, "{b:02X}");
    }
    s
}

fn level(l: Level) -> &'static str {
    match l {
        Level::Low => "low",
        Level::High => "high",
    }
}

impl Session {
    fn new(name: &str, model: &str, seed: u64) -> Self {
        let product = Product::parse(model).unwrap();
        let mut s = Session {
            dev: None,
            product,
            seed,
            period: 0,
            tick: 0,
            reading: true,
            out: String::new(),
        };
        let _ = writeln!(
            s.out,
            "# golden session {name}: model {model} ({}), seed {seed}",
            product.code()
        );
        let period = Device::power_on(product, Flash::new(), Instant::ZERO).tick_period_ns();
        let _ = writeln!(
            s.out,
            "# tick k at k * {period} ns; the format is described in tests/sessions.rs"
        );
        s.power_on(None);
        s
    }

    fn dev(&mut self) -> &mut Device<Flash, Kernel> {
        self.dev.as_mut().unwrap()
    }

    fn now(&self) -> Instant {
        Instant(self.tick * self.period)
    }

    /// Writes a transcript line at the current tick.
    fn line(&mut self, what: &str, detail: &str) {
        let _ = writeln!(self.out, "k={} {what} {detail}", self.tick);
    }

    /// Power-on (or power cycle: same flash, seed and time line).
    fn power_on(&mut self, boot: Option<Level>) {
        let flash = match self.dev.take() {
            Some(d) => d.into_flash(),
            None => Flash::new(),
        };
        let cfg = PowerOn {
            product: self.product,
            boot,
            seed: self.seed,
        };
        let dev = Device::power_on_with(cfg, flash, self.now());
        self.period = dev.tick_period_ns();
        self.dev = Some(dev);
        let boot = boot.map_or("floating", level);
        self.line("on", &format!("power on, BOOT {boot}, seed {}", self.seed));
        self.drain();
    }

    /// Records everything the device has to say now: TX bytes (one line per
    /// frame) and events, in the order the board would take them.
    fn drain(&mut self) {
        if !self.reading {
            return;
        }
        let mut buf = [0u8; 8192];
        loop {
            let n = self.dev().poll_tx(&mut buf);
            if n > 0 {
                let mut rest = &buf[..n];
                while !rest.is_empty() {
                    // One line per frame where the bytes parse as one.
                    let take = match rest {
                        [0xAA, 0x55, _, _, lo, hi, ..] => {
                            (usize::from(u16::from_le_bytes([*lo, *hi])) + 2).min(rest.len())
                        }
                        _ => rest.len(),
                    };
                    let (f, r) = rest.split_at(take.max(1));
                    self.line("tx", &hex(f));
                    rest = r;
                }
            }
            let ev = self.dev().poll_event();
            if let Some(e) = ev {
                let text = match e {
                    Event::LineRate(bps) => format!("LineRate {bps}"),
                    Event::Tov { level: l, at } => {
                        format!("Tov {} at {}", level(l), at.as_nanos())
                    }
                };
                self.line("ev", &text);
            }
            if n == 0 && ev.is_none() {
                return;
            }
        }
    }

    /// The board stops reading TX bytes and events (they queue up).
    fn stall(&mut self) {
        self.line("stall", "the board stops reading");
        self.reading = false;
    }

    /// The board reads again, and takes everything queued.
    fn resume(&mut self) {
        self.line("resume", "the board reads again");
        self.reading = true;
        self.drain();
    }

    /// Bytes from the host at the current tick's time.
    fn rx(&mut self, bytes: &[u8], what: &str) {
        self.line("rx", &format!("{} {what}", hex(bytes)));
        let now = self.now();
        self.dev().on_rx(bytes, now);
        self.drain();
    }

    /// Runs `n` ticks, draining after each.
    fn ticks(&mut self, n: u64) {
        for _ in 0..n {
            self.tick += 1;
            let now = self.now();
            self.dev().on_tick(now);
            self.drain();
        }
    }

    /// Seconds of ticks.
    fn seconds(&mut self, s: f64) {
        let n = (s * 1e9 / self.period as f64).round() as u64;
        self.ticks(n);
    }

    /// A pin edge `offset_ns` after the current tick.
    fn pin(&mut self, pin: Pin, l: Level, offset_ns: u64) {
        let at = self.now().plus_nanos(offset_ns);
        let name = match pin {
            Pin::Pps => "1PPS",
            Pin::Extrig => "EXTRIG",
        };
        self.line("pin", &format!("{name} {} at {}", level(l), at.as_nanos()));
        self.dev().on_pin(pin, l, at);
        self.drain();
    }

    /// Compares the transcript with its fixture (or rewrites it).
    fn check(mut self, name: &str) {
        let dropped = self.dev().tx_dropped();
        self.line("end", &format!("tx_dropped {dropped}"));
        let variant = if cfg!(feature = "fixed-point") {
            "fixed"
        } else {
            "float"
        };
        // The package directory cargo runs the test in (set at run time
        // too), so a binary built from another copy of the tree still
        // reads this copy's fixtures.
        let root = std::env::var_os("CARGO_MANIFEST_DIR")
            .map_or_else(|| env!("CARGO_MANIFEST_DIR").into(), PathBuf::from);
        let path = root
            .join("tests/data/sessions")
            .join(variant)
            .join(format!("{name}.txt"));
        if std::env::var_os("IMU_EMU_BLESS").is_some_and(|v| v == "1") {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &self.out).unwrap();
            return;
        }
        let want = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (IMU_EMU_BLESS=1 records it)", path.display()));
        if want == self.out {
            return;
        }
        let got: Vec<&str> = self.out.lines().collect();
        let exp: Vec<&str> = want.lines().collect();
        let i = got
            .iter()
            .zip(&exp)
            .position(|(a, b)| a != b)
            .unwrap_or(got.len().min(exp.len()));
        let from = i.saturating_sub(3);
        let show = |v: &[&str]| v[from.min(v.len())..(i + 4).min(v.len())].join("\n");
        panic!(
            "{}: session differs from line {} on (of {} recorded, {} now)\n\
             --- recorded:\n{}\n--- now:\n{}\n\
             (a deliberate change on the wire: IMU_EMU_BLESS=1 and review the diff)",
            path.display(),
            i + 1,
            exp.len(),
            got.len(),
            show(&exp),
            show(&got),
        );
    }
}

// ----- the sessions -----

/// K110: identification, BIT, ReadRAM, SaveFlash valid and invalid, a
/// frame split across reads and one abandoned, power cycle (RAM reloads
/// from flash), GA at the saved rate, Stop.
#[test]
fn k110_commands() {
    let mut s = Session::new("k110_commands", "K110", 1001);
    s.ticks(3);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo");
    s.rx(&cmd(GET_BIT), "GetBIT");
    s.rx(&cmd(DEVICE_PARAMETERS), "device parameters (0x41)");
    s.rx(&read(DATA_RATE, 2), "ReadRAM Data_Rate");
    s.rx(&read(BAUD_RATE, 1), "ReadRAM Baud_Rate");
    s.rx(&read(ALIGNMENT_ANGLES, 12), "ReadRAM Alignment_Angles");
    s.rx(&read(0x0013, 2), "ReadRAM unknown ID (no answer)");
    s.rx(&read(DATA_RATE, 4), "ReadRAM wrong length (no answer)");
    s.ticks(2);
    s.rx(
        &save(DATA_RATE, &200u16.to_le_bytes()),
        "SaveFlash Data_Rate 200",
    );
    s.rx(&read(DATA_RATE, 2), "ReadRAM Data_Rate");
    s.rx(
        &save(DATA_RATE, &3u16.to_le_bytes()),
        "SaveFlash Data_Rate 3 (not a divisor: refused)",
    );
    s.rx(&save(0x0013, &[1, 0]), "SaveFlash unknown ID (refused)");
    s.rx(
        &save_len(DATA_RATE, 4, &[100, 0, 0, 0]),
        "SaveFlash wrong length (refused)",
    );
    s.rx(
        &save(SENSORS_MEASUREMENT_RANGE, &[0]),
        "SaveFlash read-only (refused)",
    );
    s.rx(
        &save(LPF_BANDWIDTH, &[9]),
        "SaveFlash LPF_Bandwidth 9 (bad value)",
    );
    s.rx(
        &save(LPF_BANDWIDTH, &[2]),
        "SaveFlash LPF_Bandwidth 2 (66 Hz)",
    );
    s.rx(
        &save(
            ALIGNMENT_ANGLES,
            &[0, 0, 0x34, 0x42, 0, 0, 0, 0, 0, 0, 0x20, 0x41],
        ),
        "SaveFlash Alignment_Angles 45 0 10",
    );
    s.rx(&read(LPF_BANDWIDTH, 1), "ReadRAM LPF_Bandwidth");
    s.rx(&cmd(GET_UDD_STRUCT), "Get_User_Def_Data_struct (default)");
    s.rx(&cmd(0x55), "unknown command (no answer)");
    // A frame split across two reads, then one cut short and abandoned.
    let info = cmd(GET_DEV_INFO);
    s.rx(&info[..4], "GetDevInfo, first half");
    s.ticks(1);
    s.rx(&info[4..], "GetDevInfo, second half");
    s.rx(&cmd(GET_BIT)[..5], "GetBIT cut short");
    s.seconds(0.15);
    s.rx(&cmd(GET_BIT), "GetBIT after the idle abandon");
    s.ticks(1);
    s.power_on(None);
    s.rx(&read(DATA_RATE, 2), "ReadRAM Data_Rate after power cycle");
    s.rx(
        &read(LPF_BANDWIDTH, 1),
        "ReadRAM LPF_Bandwidth after power cycle",
    );
    s.rx(&cmd(GA), "GA");
    s.seconds(0.1);
    s.rx(&cmd(GET_BIT), "GetBIT while streaming");
    s.seconds(0.02);
    s.rx(&cmd(STOP), "Stop");
    s.ticks(40);
    s.rx(&cmd(DEVICE_PARAMETERS), "device parameters (0x41)");
    s.check("k110_commands");
}

/// K120 (aux accelerometer): every fixed format at its rate for a few
/// frames, Stop between; the first orientation format waits out the 2 s
/// initial alignment, the others run with it set to 0; output variants.
#[test]
fn k120_formats() {
    let mut s = Session::new("k120_formats", "K120", 1202);
    s.rx(&cmd(ORIENTATION), "Orientation (2 s alignment first)");
    s.seconds(2.05);
    s.rx(&cmd(STOP), "Stop");
    s.ticks(5);
    s.rx(
        &save(INITIAL_ALIGNMENT_TIME, &[0, 0]),
        "SaveFlash Initial_Alignment_Time 0",
    );
    for (code, name) in [
        (GA, "GA"),
        (GAM, "GAm"),
        (GAA, "GAA"),
        (GAAM, "GAAm"),
        (QUATERNION, "Quaternion"),
        (CALIBRATED_HR, "Calibrated HR"),
        (ORIENTATION, "Orientation"),
    ] {
        s.rx(&cmd(code), name);
        s.seconds(0.05);
        s.rx(&cmd(STOP), "Stop");
        s.ticks(3);
    }
    s.rx(
        &save(DATA_RATE, &50u16.to_le_bytes()),
        "SaveFlash Data_Rate 50",
    );
    for variant in [1u8, 2] {
        s.rx(
            &save(OUTPUT_VARIANT, &[variant]),
            &format!("SaveFlash Output_Variant {variant}"),
        );
        s.rx(&cmd(GA), "GA");
        s.seconds(0.1);
        s.rx(&cmd(STOP), "Stop");
    }
    s.rx(
        &save(DATA_RATE, &400u16.to_le_bytes()),
        "SaveFlash Data_Rate 400 (above the line's limit)",
    );
    s.rx(
        &cmd(CALIBRATED_HR),
        "Calibrated HR (rate lowered by Formula 5.1)",
    );
    s.seconds(0.03);
    s.rx(&cmd(GAA), "GAA while streaming (switch)");
    s.seconds(0.03);
    s.rx(&cmd(STOP), "Stop");
    s.check("k120_formats");
}

/// K110 UDD: config accepted (two-message and one-message forms), refused
/// (zero types, structure, unknown, model-forbidden, too many), the stream,
/// a config change while streaming, a type with orientation.
#[test]
fn k110_udd() {
    let mut s = Session::new("k110_udd", "K110", 1103);
    s.rx(&cmd(UDD), "UDD with the factory configuration");
    s.seconds(0.05);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&cmd(UDD_CONFIG), "User_Def_Data_config");
    s.rx(
        &frame(&[3, 0x02, 0x20, 0x22]),
        "config: IMU time, gyro, acc (accepted)",
    );
    s.rx(&cmd(GET_UDD_STRUCT), "Get_User_Def_Data_struct");
    s.rx(
        &frame(&[UDD_CONFIG, 2, 0x2E, 0x5B]),
        "config in one message: gyro bias, USW ext (accepted)",
    );
    s.rx(&cmd(UDD_CONFIG), "User_Def_Data_config");
    s.rx(&frame(&[0]), "config: 0 types (refused)");
    s.rx(
        &frame(&[UDD_CONFIG, 3, 0x02, 0x21]),
        "config: N=3, 2 types (refused)",
    );
    s.rx(
        &frame(&[UDD_CONFIG, 2, 0x02, 0x01]),
        "config: unknown type 0x01 (refused)",
    );
    s.rx(
        &frame(&[UDD_CONFIG, 2, 0x2F, 0x50]),
        "config: aux accel, supply voltage on K110 (refused)",
    );
    let mut many = vec![UDD_CONFIG, 17];
    many.extend_from_slice(&[0x52; 17]);
    s.rx(&frame(&many), "config: 17 types (refused)");
    s.rx(&cmd(GET_UDD_STRUCT), "Get_User_Def_Data_struct (unchanged)");
    s.rx(&cmd(UDD), "UDD");
    s.seconds(0.05);
    s.rx(
        &frame(&[UDD_CONFIG, 6, 0x02, 0x05, 0x21, 0x23, 0x2D, 0x91]),
        "config while streaming (accepted, layout changes)",
    );
    s.seconds(0.05);
    s.rx(
        &frame(&[UDD_CONFIG, 4, 0x02, 0x08, 0x09, 0x53]),
        "config with orientation while streaming",
    );
    s.seconds(0.03);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&cmd(UDD), "UDD with orientation (2 s alignment first)");
    s.seconds(2.03);
    s.rx(&cmd(STOP), "Stop");
    // A 16-type configuration: too big for 100 Hz at 115200 bps.
    let mut big = vec![UDD_CONFIG, 16];
    big.extend_from_slice(&[
        0x02, 0x05, 0x07, 0x08, 0x09, 0x20, 0x21, 0x22, 0x23, 0x2D, 0x2E, 0x91, 0x92, 0x52, 0x53,
        0x5B,
    ]);
    s.rx(&frame(&big), "config: 16 types (accepted, rate error bit)");
    s.rx(
        &save(INITIAL_ALIGNMENT_TIME, &[0, 0]),
        "SaveFlash Initial_Alignment_Time 0",
    );
    s.rx(&cmd(UDD), "UDD (rate lowered)");
    s.seconds(0.1);
    s.rx(&cmd(STOP), "Stop");
    s.power_on(None);
    s.rx(
        &cmd(GET_UDD_STRUCT),
        "Get_User_Def_Data_struct after power cycle",
    );
    s.check("k110_udd");
}

/// K110 line rates: SaveFlash Baud_Rate then CommitBaudRate while
/// streaming (the switch waits for the queued bytes), the rate rule at the
/// new line rate, a slow line, power cycle at the saved rate.
#[test]
fn k110_baud() {
    let mut s = Session::new("k110_baud", "K110", 1104);
    s.rx(
        &save(DATA_RATE, &1000u16.to_le_bytes()),
        "SaveFlash Data_Rate 1000",
    );
    s.rx(&cmd(GA), "GA (lowered to the 115200 bps limit)");
    s.seconds(0.02);
    s.rx(
        &save(BAUD_RATE, &[0x0A]),
        "SaveFlash Baud_Rate 0x0A (921600)",
    );
    s.seconds(0.01);
    s.rx(&cmd(COMMIT_BAUD_RATE), "CommitBaudRate while streaming");
    s.seconds(0.02);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&save(BAUD_RATE, &[0x01]), "SaveFlash Baud_Rate 0x01 (4800)");
    s.rx(&cmd(COMMIT_BAUD_RATE), "CommitBaudRate idle");
    s.rx(&cmd(GA), "GA at 4800 bps");
    s.seconds(0.3);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo at 4800 bps");
    s.seconds(0.1);
    s.rx(&cmd(STOP), "Stop");
    s.rx(
        &save(BAUD_RATE, &[0x0B]),
        "SaveFlash Baud_Rate 0x0B (2 Mbaud), not committed",
    );
    s.rx(
        &save(BAUD_RATE, &[0x11]),
        "SaveFlash Baud_Rate 0x11 (refused)",
    );
    s.ticks(2);
    s.power_on(None);
    s.rx(&read(BAUD_RATE, 1), "ReadRAM Baud_Rate after power cycle");
    s.rx(&cmd(GA), "GA at 2 Mbaud");
    s.seconds(0.01);
    s.rx(&cmd(STOP), "Stop");
    s.check("k110_baud");
}

/// K110 AutoStart: SaveFlash Auto_Start, power cycle (announcement and
/// stream), BOOT held high (firmware update: silent), AutoStart with UDD
/// and with an orientation format.
#[test]
fn k110_autostart() {
    let mut s = Session::new("k110_autostart", "K110", 1105);
    s.rx(&save(AUTO_START, &[GA]), "SaveFlash Auto_Start GA");
    s.rx(
        &save(AUTO_START, &[0x44]),
        "SaveFlash Auto_Start 0x44 (refused)",
    );
    s.ticks(2);
    s.power_on(None);
    s.seconds(0.05);
    s.rx(&cmd(STOP), "Stop");
    s.power_on(Some(Level::High));
    s.rx(
        &cmd(GET_DEV_INFO),
        "GetDevInfo in firmware update (no answer)",
    );
    s.seconds(0.02);
    s.power_on(Some(Level::Low));
    s.seconds(0.02);
    s.rx(&cmd(STOP), "Stop");
    s.rx(
        &frame(&[UDD_CONFIG, 2, 0x02, 0x53]),
        "UDD config IMU time, USW",
    );
    s.rx(&save(AUTO_START, &[UDD]), "SaveFlash Auto_Start UDD");
    s.power_on(None);
    s.seconds(0.03);
    s.rx(
        &save(AUTO_START, &[ORIENTATION]),
        "SaveFlash Auto_Start Orientation while streaming",
    );
    s.rx(
        &save(INITIAL_ALIGNMENT_TIME, &[1, 0]),
        "SaveFlash Initial_Alignment_Time 1",
    );
    s.power_on(None);
    s.seconds(1.03);
    s.rx(&save(AUTO_START, &[0]), "SaveFlash Auto_Start 0");
    s.power_on(None);
    s.seconds(0.02);
    s.check("k110_autostart");
}

/// K110 pins: 1PPS edges into GAm (time flags, second fraction), EXTRIG
/// triggering with Polarity and Hold-off, TOV output.
#[test]
fn k110_pins() {
    let mut s = Session::new("k110_pins", "K110", 1106);
    s.rx(&cmd(GAM), "GAm");
    s.seconds(0.03);
    s.pin(Pin::Pps, Level::High, 123_000);
    s.seconds(0.03);
    s.pin(Pin::Pps, Level::Low, 0);
    s.seconds(1.0);
    s.pin(Pin::Pps, Level::High, 7_000);
    s.seconds(0.02);
    s.rx(&cmd(STOP), "Stop");
    s.pin(Pin::Extrig, Level::High, 0);
    s.rx(&save(TRIGGER_CONTROL, &[1]), "SaveFlash Trigger_Control 1");
    s.rx(
        &save(TOV_CONTROL, &[1]),
        "SaveFlash TOV_Control 1 (refused: EXTRIG on)",
    );
    s.rx(
        &save(HOLD_OFF_TIME, &10u16.to_le_bytes()),
        "SaveFlash Hold-off_Time 10 ms",
    );
    s.rx(&cmd(GA), "GA, triggered");
    s.seconds(0.02);
    s.pin(Pin::Extrig, Level::High, 0);
    s.pin(Pin::Extrig, Level::Low, 100_000);
    s.ticks(4);
    s.pin(Pin::Extrig, Level::High, 0);
    s.pin(Pin::Extrig, Level::Low, 50_000);
    s.seconds(0.01);
    s.pin(Pin::Extrig, Level::High, 0);
    s.pin(Pin::Extrig, Level::Low, 1_000);
    s.ticks(3);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&save(POLARITY, &[1]), "SaveFlash Polarity 1 (rising)");
    s.rx(&cmd(GAM), "GAm, triggered");
    s.pin(Pin::Extrig, Level::High, 0);
    s.pin(Pin::Extrig, Level::Low, 300_000);
    s.seconds(0.02);
    s.pin(Pin::Pps, Level::High, 0);
    s.pin(Pin::Extrig, Level::High, 10);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&save(TRIGGER_CONTROL, &[0]), "SaveFlash Trigger_Control 0");
    s.rx(&save(TOV_CONTROL, &[1]), "SaveFlash TOV_Control 1");
    s.rx(&cmd(GA), "GA with TOV");
    s.seconds(0.03);
    s.pin(Pin::Extrig, Level::Low, 0);
    s.rx(&cmd(STOP), "Stop");
    s.check("k110_pins");
}

/// K201 at 4 kHz: its formats (no orientation), starred-only UDD, the
/// 2 kHz counter, rates above 2 kHz at 2 Mbaud.
#[test]
fn k201_4khz() {
    let mut s = Session::new("k201_4khz", "K201", 2011);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo");
    s.rx(&cmd(ORIENTATION), "Orientation (not on K201: ignored)");
    s.rx(
        &save(LPF_BANDWIDTH, &[0]),
        "SaveFlash LPF_Bandwidth 0 (not on K201)",
    );
    for (code, name) in [(GA, "GA"), (GAM, "GAm"), (GAA, "GAA"), (GAAM, "GAAm")] {
        s.rx(&cmd(code), name);
        s.seconds(0.03);
        s.rx(&cmd(STOP), "Stop");
    }
    s.rx(
        &frame(&[UDD_CONFIG, 2, 0x02, 0x20]),
        "UDD config with gyro 0x20 (not starred: refused)",
    );
    s.rx(
        &frame(&[UDD_CONFIG, 4, 0x02, 0x21, 0x23, 0x52]),
        "UDD config, starred types",
    );
    s.rx(&cmd(UDD), "UDD");
    s.seconds(0.03);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&save(BAUD_RATE, &[0x0B]), "SaveFlash Baud_Rate 2 Mbaud");
    s.rx(&cmd(COMMIT_BAUD_RATE), "CommitBaudRate");
    s.rx(
        &save(DATA_RATE, &4000u16.to_le_bytes()),
        "SaveFlash Data_Rate 4000",
    );
    s.rx(&cmd(GA), "GA at 4 kHz");
    s.ticks(24);
    s.rx(&cmd(STOP), "Stop");
    s.rx(
        &save(DATA_RATE, &2000u16.to_le_bytes()),
        "SaveFlash Data_Rate 2000",
    );
    s.rx(&cmd(UDD), "UDD at 2 kHz");
    s.ticks(24);
    s.rx(&cmd(STOP), "Stop");
    s.check("k201_4khz");
}

/// K100: supply-voltage UDD type, BOOT active low, EXTRIG with the default
/// (falling) polarity.
#[test]
fn k100_misc() {
    let mut s = Session::new("k100_misc", "K100", 1000);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo");
    s.rx(
        &frame(&[UDD_CONFIG, 2, 0x2E, 0x50]),
        "UDD config gyro bias + supply (bias not on K100: refused)",
    );
    s.rx(
        &frame(&[UDD_CONFIG, 3, 0x02, 0x50, 0x53]),
        "UDD config IMU time, supply voltage, USW",
    );
    s.rx(&cmd(UDD), "UDD");
    s.seconds(0.03);
    s.rx(&cmd(STOP), "Stop");
    s.rx(&save(TRIGGER_CONTROL, &[1]), "SaveFlash Trigger_Control 1");
    s.rx(&cmd(GA), "GA, triggered");
    s.ticks(2);
    s.pin(Pin::Extrig, Level::High, 0);
    s.pin(Pin::Extrig, Level::Low, 10_000);
    s.ticks(2);
    s.pin(Pin::Extrig, Level::High, 0);
    s.pin(Pin::Extrig, Level::Low, 10_000);
    s.ticks(1);
    s.rx(&cmd(STOP), "Stop");
    s.power_on(Some(Level::Low));
    s.rx(
        &cmd(GET_DEV_INFO),
        "GetDevInfo in firmware update (no answer)",
    );
    s.ticks(3);
    s.power_on(Some(Level::High));
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo");
    s.check("k100_misc");
}

/// K110 with a board that stalls: the TX queue fills and whole frames are
/// dropped (counted), a reply to a command is dropped too; CommitBaudRate
/// with bytes queued: the line-rate switch comes after them.
#[test]
fn k110_backpressure() {
    let mut s = Session::new("k110_backpressure", "K110", 1107);
    s.rx(&cmd(GA), "GA");
    s.seconds(0.05);
    s.stall();
    s.seconds(0.6);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo with the queue full");
    s.ticks(3);
    s.resume();
    s.seconds(0.05);
    s.stall();
    s.rx(
        &save(BAUD_RATE, &[0x0A]),
        "SaveFlash Baud_Rate 0x0A (921600)",
    );
    s.seconds(0.05);
    s.rx(&cmd(COMMIT_BAUD_RATE), "CommitBaudRate with frames queued");
    s.seconds(0.02);
    s.resume();
    s.seconds(0.02);
    s.stall();
    s.rx(&cmd(STOP), "Stop");
    s.rx(
        &save(BAUD_RATE, &[0x00]),
        "SaveFlash Baud_Rate 0x00 (115200)",
    );
    s.rx(&cmd(COMMIT_BAUD_RATE), "CommitBaudRate");
    s.rx(&cmd(GET_BIT), "GetBIT after the switch");
    s.resume();
    s.check("k110_backpressure");
}

/// K110 and a sloppy host: garbage before a frame (its false header holds
/// the scan until its checksum fails, then the frames inside are found), a
/// bad checksum, a frame of the device's own type, several frames in one read, Stop five times,
/// commands mid-stream at 2 Mbaud and 2 kHz, a format switch mid-stream.
#[test]
fn k110_robust() {
    let mut s = Session::new("k110_robust", "K110", 1108);
    let mut garbage = vec![0x00, 0xFF, 0xAA, 0xAA, 0x55, 0x55, 0xAA, 0x55, 0x00];
    garbage.extend_from_slice(&cmd(GET_DEV_INFO));
    s.rx(
        &garbage,
        "garbage ending in a false header (its length field holds the scan), then GetDevInfo",
    );
    let mut bad = cmd(GET_BIT);
    bad[8] ^= 0x01;
    s.rx(&bad, "GetBIT with a bad checksum (dropped)");
    s.rx(
        &[0xAA, 0x55, 0x01, 0x00, 0x07, 0x00, 0x12, 0x1A, 0x00],
        "a type-1 frame (ignored)",
    );
    let mut two = cmd(GET_BIT);
    two.extend_from_slice(&read(DATA_RATE, 2));
    s.rx(&two, "GetBIT and ReadRAM in one read");
    let stops: Vec<u8> = (0..5).flat_map(|_| cmd(STOP)).collect();
    s.rx(&stops, "Stop five times");
    s.rx(
        &save(BAUD_RATE, &[0x0B]),
        "SaveFlash Baud_Rate 0x0B (2 Mbaud)",
    );
    s.rx(&cmd(COMMIT_BAUD_RATE), "CommitBaudRate");
    s.rx(
        &save(DATA_RATE, &2000u16.to_le_bytes()),
        "SaveFlash Data_Rate 2000",
    );
    s.rx(&cmd(GA), "GA at 2 kHz");
    s.ticks(10);
    s.rx(&cmd(GET_BIT), "GetBIT mid-stream");
    s.ticks(3);
    s.rx(&read(DATA_RATE, 2), "ReadRAM Data_Rate mid-stream");
    s.rx(
        &save(DATA_RATE, &500u16.to_le_bytes()),
        "SaveFlash Data_Rate 500 mid-stream",
    );
    s.rx(
        &read(DATA_RATE, 2),
        "ReadRAM Data_Rate (RAM unchanged while streaming)",
    );
    s.ticks(4);
    let info = cmd(GET_DEV_INFO);
    s.rx(&info[..3], "GetDevInfo, 3 bytes");
    s.ticks(1);
    s.rx(&info[3..], "GetDevInfo, the rest");
    s.ticks(2);
    s.rx(&cmd(GAM), "GAm mid-stream (switch, new Data_Rate)");
    s.ticks(12);
    s.rx(&cmd(GAM), "GAm again (restart)");
    s.ticks(6);
    s.rx(&stops, "Stop five times");
    s.ticks(20);
    s.check("k110_robust");
}

/// K220 (high grade, aux accelerometer): GAA and a UDD configuration with
/// the aux and filtered high-g types.
#[test]
fn k220_aux() {
    let mut s = Session::new("k220_aux", "K220", 2202);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo");
    s.rx(&cmd(GAA), "GAA");
    s.seconds(0.1);
    s.rx(&cmd(STOP), "Stop");
    s.rx(
        &frame(&[UDD_CONFIG, 4, 0x02, 0x2F, 0x92, 0x2E]),
        "UDD config aux, filtered high-g, gyro bias",
    );
    s.rx(&cmd(UDD), "UDD");
    s.seconds(0.1);
    s.rx(&cmd(STOP), "Stop");
    s.check("k220_aux");
}

/// K210 (high grade, no aux accelerometer): GAAm (aux fields zero), GA at
/// 200 Hz.
#[test]
fn k210_ga() {
    let mut s = Session::new("k210_ga", "K210", 2101);
    s.rx(&cmd(GAAM), "GAAm (no aux accelerometer: zero)");
    s.seconds(0.05);
    s.rx(
        &save(DATA_RATE, &200u16.to_le_bytes()),
        "SaveFlash Data_Rate 200",
    );
    s.rx(&cmd(GA), "GA (switch, 200 Hz)");
    s.seconds(0.1);
    s.rx(&cmd(STOP), "Stop");
    s.check("k210_ga");
}

/// K110M: BOOT is active low (Table 4.4 pin 9), so high is a normal start.
#[test]
fn k110m_boot() {
    let mut s = Session::new("k110m_boot", "K110M", 1110);
    s.rx(&save(AUTO_START, &[GAM]), "SaveFlash Auto_Start GAm");
    s.power_on(Some(Level::Low));
    s.rx(
        &cmd(GET_DEV_INFO),
        "GetDevInfo in firmware update (no answer)",
    );
    s.seconds(0.03);
    s.power_on(Some(Level::High));
    s.seconds(0.05);
    s.rx(&cmd(GET_DEV_INFO), "GetDevInfo mid-stream");
    s.rx(&cmd(STOP), "Stop");
    s.check("k110m_boot");
}
