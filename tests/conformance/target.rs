//! The device under test, on either target, behind one interface:
//!
//! * [`Kind::Host`] — the `imu-emu` binary (`--tcp 127.0.0.1:0`, `--flash`,
//!   `--control` for the pins, `--motion-feed` for [`Dut::feed`]);
//! * [`Kind::Qemu`] — the `boards/qemu-mps2` firmware in
//!   `qemu-system-arm -machine mps2-an386`, UART0 on a TCP port, the pin
//!   bridge (UART1) on another, the flash file through semihosting.
//!
//! Both keep the flash in a file of a temporary directory, so
//! [`Dut::restart`] (stop the program, start it again) is a power cycle that
//! keeps saved parameters. Every read has a timeout; children are killed on
//! drop.
//!
//! The QEMU image is built once per test run by `cargo build --release` in
//! `boards/qemu-mps2` (target dir `$CARGO_TARGET_DIR/fw-qemu`, or
//! `target/fw-qemu`), unless `IMU_EMU_QEMU_ELF` names a prebuilt image.
//! With [`Opts::isb`] the device speaks ISB: the host runner gets
//! `--protocol isb`, QEMU runs the `isb` image (`--features isb`, target dir
//! `…/fw-qemu-isb`, or `IMU_EMU_QEMU_ISB_ELF`).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

pub use crate::support::free_port;
use crate::support::{Conn, Control as HostControl, Emu, TIMEOUT};

/// Which implementation runs the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The host runner binary.
    Host,
    /// The mps2-an386 firmware under QEMU.
    Qemu,
}

/// Whether `kind` can run here. QEMU missing: a loud skip on a developer
/// machine, a failure under CI (which installs it).
pub fn available(kind: Kind) -> bool {
    if kind == Kind::Host {
        return true;
    }
    static QEMU: OnceLock<bool> = OnceLock::new();
    let ok = *QEMU.get_or_init(|| {
        Command::new("qemu-system-arm")
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    });
    if !ok {
        assert!(
            std::env::var_os("CI").is_none(),
            "qemu-system-arm is not installed (apt-get install qemu-system-arm)"
        );
        eprintln!("SKIPPED: qemu-system-arm is not installed (apt-get install qemu-system-arm)");
    }
    ok
}

/// How to start the device.
#[derive(Debug, Clone)]
pub struct Opts {
    /// `--model` / `model=`.
    pub model: String,
    /// Seed.
    pub seed: u64,
    /// QEMU only: extra QEMU options (e.g. `-icount shift=0`).
    pub qemu_args: Vec<String>,
    /// The ISB personality (an IMX-5) instead of the KERNEL; `model` is
    /// then not passed.
    pub isb: bool,
}

impl Default for Opts {
    fn default() -> Self {
        Opts {
            model: "K110".into(),
            seed: 0,
            qemu_args: Vec::new(),
            isb: false,
        }
    }
}

impl Opts {
    /// An IMX-5 over ISB (seed 0).
    // Used by the ISB suite only.
    #[allow(dead_code)]
    pub fn isb() -> Opts {
        Opts {
            isb: true,
            ..Opts::default()
        }
    }

    /// Default options with this model.
    pub fn model(m: &str) -> Opts {
        Opts {
            model: m.into(),
            ..Opts::default()
        }
    }
}

/// A running device with a client connection on its UART.
pub struct Dut {
    /// Which target.
    pub kind: Kind,
    opts: Opts,
    _dir: tempfile::TempDir,
    flash: PathBuf,
    proc: Option<Proc>,
    /// The client on the device's KERNEL UART.
    pub c: Conn,
}

enum Proc {
    Host {
        emu: Emu,
        ctl: HostControl,
        /// `--motion-feed`'s address, and the connection once used.
        feed: (SocketAddr, Option<TcpStream>),
    },
    Qemu(Qemu),
}

impl Dut {
    /// Starts the device with a fresh (erased) flash and connects.
    pub fn start(kind: Kind, opts: Opts) -> Dut {
        let dir = tempfile::tempdir().unwrap();
        let flash = dir.path().join("flash.bin");
        let (proc, c) = launch(kind, &opts, &flash);
        Dut {
            kind,
            opts,
            _dir: dir,
            flash,
            proc: Some(proc),
            c,
        }
    }

    /// Power cycle by restarting the program (the flash file stays); the
    /// old connection is replaced.
    pub fn restart(&mut self) {
        self.stop();
        let (proc, c) = launch(self.kind, &self.opts, &self.flash);
        self.proc = Some(proc);
        self.c = c;
    }

    /// Stops the program: the host runner cleanly (SIGTERM, exit status 0
    /// asserted), QEMU by SIGKILL (its flash file is written before every
    /// acknowledgement leaves).
    pub fn stop(&mut self) {
        match self.proc.take() {
            Some(Proc::Host { mut emu, ctl, .. }) => {
                drop(ctl);
                let status = emu.terminate();
                assert!(status.success(), "exit status {status}");
            }
            Some(Proc::Qemu(q)) => drop(q),
            None => {}
        }
    }

    /// The pins: 1PPS, EXTRIG, BOOT + power cycle, TOV.
    pub fn pins(&mut self) -> &mut dyn Pins {
        match self.proc.as_mut().expect("running") {
            Proc::Host { ctl, .. } => ctl,
            Proc::Qemu(q) => &mut q.bridge,
        }
    }

    /// Sends live motion feed bytes (docs/feed.md): the host runner's
    /// `--motion-feed` socket, the firmware's bridge UART.
    pub fn feed(&mut self, bytes: &[u8]) {
        match self.proc.as_mut().expect("running") {
            Proc::Host { feed, .. } => feed
                .1
                .get_or_insert_with(|| TcpStream::connect(feed.0).expect("feed connect"))
                .write_all(bytes)
                .expect("feed send"),
            Proc::Qemu(q) => q.bridge.send(bytes),
        }
    }

    /// QEMU only: the tick's timing figures (`S` on the pin bridge).
    pub fn qemu_stats(&mut self) -> Option<Vec<(String, u64)>> {
        match self.proc.as_mut()? {
            Proc::Qemu(q) => Some(q.bridge.stats()),
            Proc::Host { .. } => None,
        }
    }

    /// QEMU only: zero the timing figures.
    pub fn qemu_reset_stats(&mut self) {
        if let Some(Proc::Qemu(q)) = self.proc.as_mut() {
            q.bridge.send(b"Z");
        }
    }
}

impl Drop for Dut {
    fn drop(&mut self) {
        if let Some(Proc::Qemu(q)) = self.proc.as_ref() {
            if std::thread::panicking() {
                eprintln!("--- qemu stderr ---\n{}", q.stderr.lock().unwrap());
            }
        }
    }
}

fn launch(kind: Kind, opts: &Opts, flash: &Path) -> (Proc, Conn) {
    match kind {
        Kind::Host => {
            let ctl_addr = format!("127.0.0.1:{}", free_port());
            let seed = opts.seed.to_string();
            let personality: [&str; 2] = if opts.isb {
                ["--protocol", "isb"]
            } else {
                ["--model", &opts.model]
            };
            let emu = Emu::tcp(&[
                personality[0],
                personality[1],
                "--seed",
                &seed,
                "--flash",
                flash.to_str().unwrap(),
                "--control",
                &ctl_addr,
                "--motion-feed",
                "127.0.0.1:0",
            ]);
            let feed = emu.more_lines(2)[1]
                .strip_prefix("feed on tcp ")
                .expect("the feed's line")
                .parse()
                .unwrap();
            let c = emu.connect();
            let ctl = HostControl::connect(&ctl_addr);
            (
                Proc::Host {
                    emu,
                    ctl,
                    feed: (feed, None),
                },
                c,
            )
        }
        Kind::Qemu => {
            let (q, c) = Qemu::start(opts, flash);
            (Proc::Qemu(q), c)
        }
    }
}

/// A free TCP port on the loopback (bound, then released for the child).
/// The device's other pins, as a test rig drives them.
pub trait Pins {
    /// A 1PPS pulse (rising edge now).
    fn pps(&mut self);
    /// EXTRIG goes to `high`.
    fn extrig(&mut self, high: bool);
    /// Power cycle in place with BOOT at `boot` (`None` = floating).
    fn power_cycle(&mut self, boot: Option<bool>);
    /// The next `n` TOV edges (true = rising), each within [`TIMEOUT`].
    fn tov_edges(&mut self, n: usize) -> Vec<bool>;
}

// ----- host: the control socket -----

impl HostControl {
    fn ok(&mut self, c: &str) {
        assert_eq!(self.cmd(c), "ok", "control {c:?}");
    }
}

impl Pins for HostControl {
    fn pps(&mut self) {
        self.ok("pps");
    }
    fn extrig(&mut self, high: bool) {
        self.ok(if high { "extrig high" } else { "extrig low" });
    }
    fn power_cycle(&mut self, boot: Option<bool>) {
        self.ok(match boot {
            None => "power-cycle",
            Some(true) => "power-cycle boot=high",
            Some(false) => "power-cycle boot=low",
        });
    }
    fn tov_edges(&mut self, n: usize) -> Vec<bool> {
        (0..n)
            .map(|_| {
                let l = self.line();
                match l.split_whitespace().take(3).collect::<Vec<_>>()[..] {
                    ["event", "tov", "high"] => true,
                    ["event", "tov", "low"] => false,
                    _ => panic!("unexpected control line {l:?}"),
                }
            })
            .collect()
    }
}

// ----- QEMU -----

/// The QEMU image, built once per test run (with `isb`: the ISB image,
/// `--features isb`, in a target dir of its own).
pub fn qemu_elf(isb: bool) -> PathBuf {
    static ELF: OnceLock<PathBuf> = OnceLock::new();
    static ISB_ELF: OnceLock<PathBuf> = OnceLock::new();
    let (cell, var, dir, features): (_, _, _, &[&str]) = if isb {
        (
            &ISB_ELF,
            "IMU_EMU_QEMU_ISB_ELF",
            "fw-qemu-isb",
            &["--features", "isb"],
        )
    } else {
        (&ELF, "IMU_EMU_QEMU_ELF", "fw-qemu", &[])
    };
    cell.get_or_init(|| {
        if let Some(p) = std::env::var_os(var) {
            return PathBuf::from(p);
        }
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let board = root.join("boards/qemu-mps2");
        let target_dir = std::env::var_os("CARGO_TARGET_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join("target"))
            .join(dir);
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        // The board's own .cargo/config.toml (target, link script) applies
        // because cargo runs in its directory; flags meant for the host
        // build must not leak into it.
        let out = Command::new(cargo)
            .args(["build", "--release", "--quiet"])
            .args(features)
            .current_dir(&board)
            .env("CARGO_TARGET_DIR", &target_dir)
            .env_remove("RUSTFLAGS")
            .env_remove("CARGO_ENCODED_RUSTFLAGS")
            .env_remove("CARGO_BUILD_TARGET")
            .output()
            .expect("run cargo to build the QEMU firmware");
        assert!(
            out.status.success(),
            "building boards/qemu-mps2 failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        target_dir.join("thumbv7em-none-eabihf/release/imu-emu-qemu-mps2")
    })
    .clone()
}

struct Qemu {
    child: Child,
    stderr: Arc<Mutex<String>>,
    bridge: Bridge,
}

impl Qemu {
    /// Starts QEMU on two free ports. A port picked free can be taken by
    /// another test's listener before QEMU binds it (the UART client then
    /// reaches the wrong process and QEMU never opens its second port): a
    /// start that does not get both connections is retried on new ports.
    fn start(opts: &Opts, flash: &Path) -> (Qemu, Conn) {
        let mut why = String::new();
        for _ in 0..3 {
            match Qemu::try_start(opts, flash) {
                Ok(started) => return started,
                Err(e) => why = e,
            }
        }
        panic!("{why}");
    }

    fn try_start(opts: &Opts, flash: &Path) -> Result<(Qemu, Conn), String> {
        let elf = qemu_elf(opts.isb);
        let (uart, pins) = (free_port(), free_port());
        let mut semi = String::from("enable=on,target=native");
        let model = (!opts.isb).then(|| format!("model={}", opts.model));
        for a in model.into_iter().chain([
            format!("seed={}", opts.seed),
            format!("flash={}", flash.display()),
        ]) {
            semi.push_str(",arg=");
            semi.push_str(&a.replace(',', ",,"));
        }
        let mut cmd = Command::new("qemu-system-arm");
        cmd.args(["-machine", "mps2-an386", "-cpu", "cortex-m4"])
            .args(["-nographic", "-monitor", "none"])
            .arg("-serial")
            // nodelay=on: replies leave when the firmware writes them
            // (Nagle would hold small writes back ~40 ms).
            .arg(format!("tcp:127.0.0.1:{uart},server=on,wait=on,nodelay=on"))
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{pins},server=on,wait=on,nodelay=on"))
            .arg("-semihosting-config")
            .arg(&semi)
            .args(&opts.qemu_args)
            .arg("-kernel")
            .arg(&elf)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().unwrap_or_else(|e| {
            panic!("spawn qemu-system-arm ({e}): install it, e.g. apt-get install qemu-system-arm")
        });
        let stderr = Arc::new(Mutex::new(String::new()));
        let pipe = child.stderr.take().unwrap();
        let sink = Arc::clone(&stderr);
        std::thread::spawn(move || {
            for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                let mut s = sink.lock().unwrap();
                s.push_str(&line);
                s.push('\n');
            }
        });
        // QEMU waits for both clients (UART0 first) before the firmware
        // runs, so nothing it sends is lost.
        let mut q = Qemu {
            child,
            stderr,
            bridge: Bridge::dummy(),
        };
        let uart = q.connect(uart)?;
        let pins = q.connect(pins)?;
        q.bridge = Bridge::new(pins);
        Ok((q, Conn::from_tcp(uart)))
    }

    /// Connects to one of QEMU's serial ports, retrying while it starts.
    fn connect(&mut self, port: u16) -> Result<TcpStream, String> {
        let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if let Ok(s) = TcpStream::connect_timeout(&addr, Duration::from_millis(200)) {
                return Ok(s);
            }
            if let Some(st) = self.child.try_wait().unwrap() {
                panic!(
                    "qemu exited ({st}) before listening on {port}:\n{}",
                    self.stderr.lock().unwrap()
                );
            }
            if Instant::now() >= deadline {
                return Err(format!(
                    "qemu does not listen on {port}:\n{}",
                    self.stderr.lock().unwrap()
                ));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The firmware's pin bridge (UART1; protocol in boards/qemu-mps2/src/bridge.rs).
struct Bridge {
    s: Option<TcpStream>,
    /// TOV edges and power-cycle marks read so far, in order.
    events: Vec<u8>,
    /// Text of `S` report lines read so far.
    lines: Vec<String>,
    partial: Option<String>,
}

impl Bridge {
    fn dummy() -> Bridge {
        Bridge {
            s: None,
            events: Vec::new(),
            lines: Vec::new(),
            partial: None,
        }
    }

    fn new(s: TcpStream) -> Bridge {
        s.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
        s.set_nodelay(true).unwrap();
        Bridge {
            s: Some(s),
            ..Bridge::dummy()
        }
    }

    fn send(&mut self, bytes: &[u8]) {
        let s = self.s.as_mut().expect("bridge");
        s.write_all(bytes).expect("bridge send");
    }

    /// Reads what arrived (up to a short timeout) and sorts it.
    fn fill(&mut self) {
        let mut b = [0u8; 1024];
        let n = match self.s.as_mut().expect("bridge").read(&mut b) {
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                0
            }
            Err(e) => panic!("bridge read: {e}"),
        };
        for &x in &b[..n] {
            match (&mut self.partial, x) {
                (Some(line), b'\n') => {
                    self.lines.push(std::mem::take(line));
                    self.partial = None;
                }
                (Some(line), _) => line.push(char::from(x)),
                (None, b'S') => self.partial = Some(String::from("S")),
                (None, b'T' | b't' | b'R') => self.events.push(x),
                (None, _) => {}
            }
        }
    }

    /// Waits for `pred` over the events, up to [`TIMEOUT`].
    fn wait_event(&mut self, what: &str, mut pred: impl FnMut(&mut Vec<u8>) -> bool) {
        let deadline = Instant::now() + TIMEOUT;
        while !pred(&mut self.events) {
            assert!(Instant::now() < deadline, "timeout waiting for {what}");
            self.fill();
        }
    }

    /// `S` → the report line as (key, value) pairs.
    fn stats(&mut self) -> Vec<(String, u64)> {
        self.lines.clear();
        self.send(b"S");
        let deadline = Instant::now() + TIMEOUT;
        while self.lines.is_empty() {
            assert!(Instant::now() < deadline, "timeout waiting for stats");
            self.fill();
        }
        self.lines[0]
            .split_whitespace()
            .skip(1)
            .filter_map(|kv| {
                let (k, v) = kv.split_once('=')?;
                Some((k.to_owned(), v.parse().ok()?))
            })
            .collect()
    }
}

impl Pins for Bridge {
    fn pps(&mut self) {
        self.send(b"Pp");
    }
    fn extrig(&mut self, high: bool) {
        self.send(if high { b"E" } else { b"e" });
    }
    fn power_cycle(&mut self, boot: Option<bool>) {
        self.events.retain(|&e| e != b'R');
        let b = match boot {
            None => b'f',
            Some(true) => b'B',
            Some(false) => b'b',
        };
        self.send(&[b, b'R']);
        self.wait_event("the power-cycle mark", |ev| {
            match ev.iter().position(|&e| e == b'R') {
                Some(i) => {
                    // TOV edges from before the power cycle are stale.
                    ev.drain(..=i);
                    true
                }
                None => false,
            }
        });
    }
    fn tov_edges(&mut self, n: usize) -> Vec<bool> {
        self.wait_event("TOV edges", |ev| {
            ev.retain(|&e| e != b'R');
            ev.len() >= n
        });
        self.events.drain(..n).map(|e| e == b'T').collect()
    }
}
