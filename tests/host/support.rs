//! Test support: start the real `imu-emu` binary, talk to it as a client,
//! and read KERNEL frames with timeouts (no test can hang).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// Upper bound of every wait in these tests.
pub const TIMEOUT: Duration = Duration::from_secs(5);

/// Parses `"AA 55 00 …"`.
pub fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
        .collect()
}

/// Wrapping u16 sum (ICD Table 5.2), computed independently of the core.
pub fn sum16(bytes: &[u8]) -> u16 {
    bytes
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)))
}

/// A complete frame: `AA 55 type id len payload sum`.
pub fn frame(msg_type: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let len = u16::try_from(payload.len() + 6).unwrap();
    let mut f = vec![0xAA, 0x55, msg_type, id];
    f.extend_from_slice(&len.to_le_bytes());
    f.extend_from_slice(payload);
    let s = sum16(&f[2..]);
    f.extend_from_slice(&s.to_le_bytes());
    f
}

/// A one-byte command (`type 0, id 0, payload = code`).
pub fn command(code: u8) -> Vec<u8> {
    frame(0, 0, &[code])
}

/// SaveFlash of parameter `id` (ICD 5.3.7).
pub fn save_flash(id: u16, value: &[u8]) -> Vec<u8> {
    let mut p = vec![0xB2, 0xFF];
    p.extend_from_slice(&id.to_le_bytes());
    p.extend_from_slice(&u16::try_from(value.len()).unwrap().to_le_bytes());
    p.extend_from_slice(value);
    frame(0, 0, &p)
}

/// ReadRAM of `len` bytes of parameter `id` (ICD 5.3.8).
pub fn read_ram(id: u16, len: u16) -> Vec<u8> {
    let mut p = vec![0xB1, 0xFF];
    p.extend_from_slice(&id.to_le_bytes());
    p.extend_from_slice(&len.to_le_bytes());
    frame(0, 0, &p)
}

/// The acknowledgement of `cmd` (a data command or SaveFlash): a frame with
/// `id` whose payload is the command's checksum field.
pub fn ack_of(id: u8, cmd: &[u8]) -> Vec<u8> {
    frame(1, id, &cmd[cmd.len() - 2..])
}

/// A frame read from the device.
#[derive(Debug, Clone)]
pub struct Frame {
    /// All its bytes, header to checksum.
    pub bytes: Vec<u8>,
}

impl Frame {
    /// Message type.
    pub fn msg_type(&self) -> u8 {
        self.bytes[2]
    }
    /// KERNEL data identifier.
    pub fn id(&self) -> u8 {
        self.bytes[3]
    }
    /// The payload.
    pub fn payload(&self) -> &[u8] {
        &self.bytes[6..self.bytes.len() - 2]
    }
}

/// Frames longer than this are taken as garbage (resync).
const MAX_FRAME: usize = 2048;

/// What a [`Conn`] reads and writes.
pub trait Port: Read + Write + Send {}
impl<T: Read + Write + Send> Port for T {}

/// A client connection (TCP socket or pty) with a frame reader.
pub struct Conn {
    port: Box<dyn Port>,
    buf: Vec<u8>,
    /// Candidates dropped for a bad length or checksum.
    pub bad: usize,
    /// Bytes skipped while looking for `AA 55`.
    pub skipped: usize,
    /// Bytes received in total.
    pub received: usize,
}

impl Conn {
    /// Connects to the emulator's TCP port.
    pub fn tcp(addr: SocketAddr) -> Conn {
        let s = TcpStream::connect_timeout(&addr, TIMEOUT).expect("connect");
        Conn::from_tcp(s)
    }

    /// A client over an already connected TCP stream (e.g. QEMU's serial
    /// port, tests/conformance).
    pub fn from_tcp(s: TcpStream) -> Conn {
        s.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
        s.set_write_timeout(Some(TIMEOUT)).unwrap();
        s.set_nodelay(true).unwrap();
        Conn::new(Box::new(s))
    }

    /// Opens a serial port (the pty slave or its link) in raw mode with
    /// reads timing out after 0.1 s.
    pub fn serial(path: &Path) -> Conn {
        use nix::sys::termios::{self, SetArg, SpecialCharacterIndices as Cc};
        use std::os::unix::fs::OpenOptionsExt;
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::fcntl::OFlag::O_NOCTTY.bits())
            .open(path)
            .unwrap_or_else(|e| panic!("open {}: {e}", path.display()));
        let mut t = termios::tcgetattr(&f).unwrap();
        termios::cfmakeraw(&mut t);
        t.control_chars[Cc::VMIN as usize] = 0;
        t.control_chars[Cc::VTIME as usize] = 1;
        termios::tcsetattr(&f, SetArg::TCSANOW, &t).unwrap();
        Conn::new(Box::new(f))
    }

    /// A client over any byte pipe (reads should time out, as a socket's
    /// or a raw tty's with VTIME do).
    pub fn new(port: Box<dyn Port>) -> Conn {
        Conn {
            port,
            buf: Vec::new(),
            bad: 0,
            skipped: 0,
            received: 0,
        }
    }

    /// Sends bytes.
    pub fn send(&mut self, bytes: &[u8]) {
        self.port.write_all(bytes).expect("send");
        self.port.flush().unwrap();
    }

    /// Reads once (up to a short read timeout); whether bytes came.
    fn fill(&mut self) -> bool {
        let mut b = [0u8; 4096];
        match self.port.read(&mut b) {
            Ok(0) => {
                // pty: VTIME expired; tcp: peer closed. Either way, wait.
                std::thread::sleep(Duration::from_millis(5));
                false
            }
            Ok(n) => {
                self.buf.extend_from_slice(&b[..n]);
                self.received += n;
                true
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                false
            }
            Err(e) => panic!("read: {e}"),
        }
    }

    /// Exactly `n` raw bytes (what is buffered first), or panics after
    /// [`TIMEOUT`].
    pub fn read_bytes(&mut self, n: usize) -> Vec<u8> {
        let deadline = Instant::now() + TIMEOUT;
        while self.buf.len() < n {
            assert!(
                Instant::now() < deadline,
                "timeout: wanted {n} bytes, got {:02X?}",
                self.buf
            );
            self.fill();
        }
        self.buf.drain(..n).collect()
    }

    /// Takes the next complete valid frame from the buffer, if any.
    fn parse(&mut self) -> Option<Frame> {
        loop {
            let start = self.buf.windows(2).position(|w| w == [0xAA, 0x55]);
            let skip = match start {
                Some(i) => i,
                // Keep a trailing AA: it may be a header's first byte.
                None => self.buf.len() - usize::from(self.buf.last() == Some(&0xAA)),
            };
            self.skipped += skip;
            self.buf.drain(..skip);
            if self.buf.len() < 6 {
                return None;
            }
            let len = usize::from(u16::from_le_bytes([self.buf[4], self.buf[5]]));
            let total = len + 2;
            if len < 6 || total > MAX_FRAME {
                self.bad += 1;
                self.buf.remove(0);
                continue;
            }
            if self.buf.len() < total {
                return None;
            }
            let sum = sum16(&self.buf[2..total - 2]);
            if sum.to_le_bytes() != self.buf[total - 2..total] {
                self.bad += 1;
                self.buf.remove(0);
                continue;
            }
            return Some(Frame {
                bytes: self.buf.drain(..total).collect(),
            });
        }
    }

    /// The next valid frame arriving before `deadline`.
    pub fn frame_before(&mut self, deadline: Instant) -> Option<Frame> {
        loop {
            if let Some(f) = self.parse() {
                return Some(f);
            }
            if Instant::now() >= deadline {
                return None;
            }
            self.fill();
        }
    }

    /// The next valid frame, or panics after [`TIMEOUT`].
    pub fn frame(&mut self) -> Frame {
        self.frame_before(Instant::now() + TIMEOUT)
            .expect("timeout waiting for a frame")
    }

    /// The next frame with `id`, skipping others, or panics after
    /// [`TIMEOUT`].
    pub fn frame_with_id(&mut self, id: u8) -> Frame {
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let f = self
                .frame_before(deadline)
                .unwrap_or_else(|| panic!("timeout waiting for a frame with id {id:02X}"));
            if f.id() == id {
                return f;
            }
        }
    }

    /// Reads and discards whatever arrives during `d`; bytes read.
    pub fn drain_for(&mut self, d: Duration) -> usize {
        let end = Instant::now() + d;
        let mut n = std::mem::take(&mut self.buf).len();
        while Instant::now() < end {
            self.fill();
            n += self.buf.len();
            self.buf.clear();
        }
        n
    }
}

/// A GET_DATA packet for the whole data set `did`, every `period` source
/// periods (0: once), with the core's `imu_emu::isb::message::encode_get`.
pub fn isb_get(did: u8, period: u16) -> Vec<u8> {
    let req = imu_emu::isb::message::GetRequest {
        did: u16::from(did),
        size: 0,
        offset: 0,
        period,
    };
    let mut out = [0u8; 32];
    let n = imu_emu::isb::message::encode_get(&req, &mut out).unwrap();
    out[..n].to_vec()
}

/// A SET_DATA packet of `data` at `offset` of data set `did`, with the
/// core's `imu_emu::isb::message::encode_set`.
pub fn isb_set(did: u8, offset: u16, data: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 512];
    let n = imu_emu::isb::message::encode_set(did, offset, data, &mut out).unwrap();
    out[..n].to_vec()
}

/// An ISB packet as received (`docs/protocol-facts.md` "ISB").
#[derive(Debug)]
pub struct IsbPacket {
    /// The header's `flags`.
    pub flags: u8,
    /// The header's DID.
    pub did: u8,
    /// The payload.
    pub payload: Vec<u8>,
    /// The whole packet, preamble to checksum.
    pub raw: Vec<u8>,
}

/// Reads the next ISB packet, skipping NMEA replies (a `$…\r\n` line);
/// panics on anything else or a bad checksum (checked with the core's
/// `imu_emu::isb::packet::checksum`).
pub fn isb_packet(c: &mut Conn) -> IsbPacket {
    loop {
        let b = c.read_bytes(1)[0];
        if b == b'$' {
            while c.read_bytes(1)[0] != b'\n' {}
            continue;
        }
        assert_eq!(b, 0xEF, "not a packet start");
        let head = [&[b][..], &c.read_bytes(5)].concat();
        assert_eq!(head[1], 0x49, "preamble");
        let size = usize::from(u16::from_le_bytes([head[4], head[5]]));
        let rest = c.read_bytes(size + 2);
        let raw = [&head[..], &rest[..]].concat();
        assert_eq!(
            imu_emu::isb::packet::checksum(&raw[..6 + size]),
            rest[size..],
            "checksum"
        );
        return IsbPacket {
            flags: head[2],
            did: head[3],
            payload: rest[..size].to_vec(),
            raw,
        };
    }
}

/// The next ISB packet with this DID in the header (others are skipped).
pub fn isb_packet_of(c: &mut Conn, did: u8) -> IsbPacket {
    loop {
        let p = isb_packet(c);
        if p.did == did {
            return p;
        }
    }
}

/// A running emulator; killed on drop (its stderr is printed if the test
/// is failing).
pub struct Emu {
    child: Child,
    /// What follows `listening on ` on the first stdout line.
    pub listening: String,
    stderr: Arc<Mutex<String>>,
    /// Set when the stderr pipe reached its end (the process exited).
    stderr_closed: Arc<std::sync::atomic::AtomicBool>,
    /// The stdout lines after the first.
    stdout: Arc<Mutex<Vec<String>>>,
}

impl Emu {
    /// Starts `imu-emu` with `args` and waits for its first stdout line.
    pub fn start(args: &[&str]) -> Emu {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_imu-emu"));
        cmd.args(args);
        Emu::start_command(cmd)
    }

    /// Runs `cmd` (an `imu-emu` command line) and waits for its first
    /// stdout line.
    pub fn start_command(mut cmd: Command) -> Emu {
        let mut child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn imu-emu");
        let stdout = child.stdout.take().unwrap();
        let stderr_pipe = child.stderr.take().unwrap();
        let stderr = Arc::new(Mutex::new(String::new()));
        let sink = Arc::clone(&stderr);
        let stderr_closed = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let closed = Arc::clone(&stderr_closed);
        std::thread::spawn(move || {
            for line in BufReader::new(stderr_pipe).lines().map_while(Result::ok) {
                let mut s = sink.lock().unwrap();
                s.push_str(&line);
                s.push('\n');
            }
            closed.store(true, std::sync::atomic::Ordering::Release);
        });
        let (tx, rx) = mpsc::channel();
        let rest = Arc::new(Mutex::new(Vec::new()));
        let keep = Arc::clone(&rest);
        std::thread::spawn(move || {
            // Keep draining stdout so the emulator never writes to a
            // closed pipe.
            let mut lines = BufReader::new(stdout).lines();
            if let Some(Ok(first)) = lines.next() {
                let _ = tx.send(first);
            }
            for line in lines.map_while(Result::ok) {
                keep.lock().unwrap().push(line);
            }
        });
        let mut emu = Emu {
            child,
            listening: String::new(),
            stderr,
            stderr_closed,
            stdout: rest,
        };
        let line = rx
            .recv_timeout(TIMEOUT)
            .unwrap_or_else(|_| panic!("no `listening on` line; stderr:\n{}", emu.stderr()));
        emu.listening = line
            .strip_prefix("listening on ")
            .unwrap_or_else(|| panic!("unexpected first line {line:?}"))
            .to_owned();
        emu
    }

    /// Starts on a free TCP port with extra `args`.
    pub fn tcp(args: &[&str]) -> Emu {
        let mut all = vec!["--tcp", "127.0.0.1:0"];
        all.extend_from_slice(args);
        Emu::start(&all)
    }

    /// The TCP addresses of the first `n` devices (`listening on tcp …`
    /// lines: the first and `n − 1` more), in order.
    pub fn tcp_addrs(&self, n: usize) -> Vec<SocketAddr> {
        let mut places = vec![format!("listening on {}", self.listening)];
        places.extend(self.more_lines(n - 1));
        places
            .iter()
            .map(|l| {
                l.strip_prefix("listening on tcp ")
                    .unwrap_or_else(|| panic!("{l:?}"))
                    .parse()
                    .unwrap()
            })
            .collect()
    }

    /// The first `n` stdout lines after the first, waiting (bounded) for
    /// them.
    pub fn more_lines(&self, n: usize) -> Vec<String> {
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let lines = self.stdout.lock().unwrap().clone();
            if lines.len() >= n {
                return lines[..n].to_vec();
            }
            assert!(
                Instant::now() < deadline,
                "only {} more stdout lines: {lines:?}",
                lines.len()
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// The TCP address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.listening
            .strip_prefix("tcp ")
            .expect("a tcp emulator")
            .parse()
            .expect("socket address")
    }

    /// The pty slave path it listens on.
    pub fn pty_path(&self) -> PathBuf {
        PathBuf::from(self.listening.strip_prefix("pty ").expect("a pty emulator"))
    }

    /// A new TCP client connection.
    pub fn connect(&self) -> Conn {
        Conn::tcp(self.addr())
    }

    /// The emulator's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Whether the emulator is still running.
    pub fn running(&mut self) -> bool {
        self.child.try_wait().unwrap().is_none()
    }

    /// What the emulator wrote to stderr so far. A line the emulator
    /// has just written may not be here yet (a thread reads the pipe):
    /// to check for one, use [`Emu::log_with`].
    pub fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// The stderr log once it holds `what`, waiting (bounded by
    /// `TIMEOUT`, or until the pipe closes) for the reader thread to
    /// catch up; the caller asserts on what it returns.
    pub fn log_with(&self, what: &str) -> String {
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let closed = self
                .stderr_closed
                .load(std::sync::atomic::Ordering::Acquire);
            let log = self.stderr();
            if log.contains(what) || closed || Instant::now() > deadline {
                return log;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Sends SIGTERM and waits (bounded) for the exit status.
    pub fn terminate(&mut self) -> ExitStatus {
        use nix::sys::signal::{kill, Signal};
        use nix::unistd::Pid;
        let pid = Pid::from_raw(i32::try_from(self.child.id()).unwrap());
        kill(pid, Signal::SIGTERM).expect("kill -TERM");
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if let Some(st) = self.child.try_wait().unwrap() {
                // Let the reader thread take the last lines, so that
                // `stderr()` after `terminate()` holds all of them.
                while !self
                    .stderr_closed
                    .load(std::sync::atomic::Ordering::Acquire)
                    && Instant::now() < deadline
                {
                    std::thread::sleep(Duration::from_millis(5));
                }
                return st;
            }
            assert!(Instant::now() < deadline, "no exit after SIGTERM");
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

impl Drop for Emu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        if std::thread::panicking() {
            eprintln!("--- imu-emu stderr ---\n{}", self.stderr());
        }
    }
}

/// A TCP port free now on the loopback address (for `--control`).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Saves a parameter and waits for its acknowledgement (ICD 5.3.7).
pub fn save(c: &mut Conn, id: u16, value: &[u8]) {
    let cmd = save_flash(id, value);
    c.send(&cmd);
    let ack = c.frame_with_id(0xB2);
    assert_eq!(ack.bytes, ack_of(0xB2, &cmd));
}

/// Frames with `id` and their bytes completed within `d` of now; any other
/// frame fails.
pub fn count_for(c: &mut Conn, id: u8, d: Duration) -> (usize, usize) {
    let end = Instant::now() + d;
    let (mut frames, mut bytes) = (0, 0);
    while let Some(f) = c.frame_before(end) {
        assert_eq!(f.id(), id, "{:02X?}", f.bytes);
        frames += 1;
        bytes += f.bytes.len();
    }
    (frames, bytes)
}

/// A client of the host runner's control socket (`--control`).
pub struct Control {
    w: std::net::TcpStream,
    r: BufReader<std::net::TcpStream>,
}

impl Control {
    /// Connects to the control socket at `addr`.
    pub fn connect(addr: &str) -> Control {
        let s = std::net::TcpStream::connect(addr).expect("control socket");
        s.set_read_timeout(Some(TIMEOUT)).unwrap();
        // One segment per command, sent at once (no Nagle wait for the
        // newline: tests time what a command does).
        s.set_nodelay(true).unwrap();
        Control {
            w: s.try_clone().unwrap(),
            r: BufReader::new(s),
        }
    }

    /// The next line the runner sent (an answer, or an event: `event …`).
    pub fn line(&mut self) -> String {
        let mut l = String::new();
        self.r.read_line(&mut l).expect("control line");
        l.trim().to_owned()
    }

    /// Waits (bounded) until the device is on: a client's connection
    /// powers it on when the runner's next pass sees it, which on a loaded
    /// host may come after a control command sent right behind it.
    pub fn wait_powered(&mut self) {
        let deadline = Instant::now() + TIMEOUT;
        while self.cmd("status").starts_with("ok mode=off") {
            assert!(Instant::now() < deadline, "the device never powered on");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Sends a command and returns its answer, skipping events.
    pub fn cmd(&mut self, c: &str) -> String {
        use std::io::Write as _;
        self.w.write_all(format!("{c}\n").as_bytes()).unwrap();
        loop {
            let l = self.line();
            if !l.starts_with("event ") {
                return l;
            }
        }
    }
}

/// A device clock carried in a frame's payload, at a byte offset: what the
/// rate and timing tests measure with instead of a wall-clock window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceClock {
    /// The 2 kHz counter, u16 (Tables 5.7 and 5.10; wraps at 2^16).
    Counter(usize),
    /// The second fraction, u32 ns within the second (5.2.3.1, Tables
    /// 5.8 and 5.12, UDD 0x05; wraps at 10^9).
    SecondFraction(usize),
    /// IMU time, u64 ns since power-on (UDD 0x02, Table 5.17).
    ImuTime(usize),
}

impl DeviceClock {
    /// Its reading in `payload`.
    pub fn read(self, payload: &[u8]) -> u64 {
        let at = |i: usize, n: usize| {
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(&payload[i..i + n]);
            u64::from_le_bytes(b)
        };
        match self {
            DeviceClock::Counter(i) => at(i, 2),
            DeviceClock::SecondFraction(i) => at(i, 4),
            DeviceClock::ImuTime(i) => at(i, 8),
        }
    }

    /// Counts per device second.
    pub fn per_second(self) -> u64 {
        match self {
            DeviceClock::Counter(_) => 2000,
            DeviceClock::SecondFraction(_) | DeviceClock::ImuTime(_) => 1_000_000_000,
        }
    }

    /// Where it wraps.
    fn modulus(self) -> u128 {
        match self {
            DeviceClock::Counter(_) => 1 << 16,
            DeviceClock::SecondFraction(_) => 1_000_000_000,
            DeviceClock::ImuTime(_) => 1 << 64,
        }
    }

    /// `later − earlier` in counts, across a wrap.
    pub fn step(self, earlier: u64, later: u64) -> u64 {
        let m = self.modulus();
        ((u128::from(later) + m - u128::from(earlier)) % m) as u64
    }
}

/// One frame's device time and its length on the wire.
#[derive(Debug, Clone, Copy)]
pub struct Stamp {
    /// The frame's [`DeviceClock`] reading.
    pub time: u64,
    /// The whole frame's bytes.
    pub len: usize,
}

/// The next `n` frames, which must all have `id` (any other frame fails,
/// as in [`count_for`]), stamped with `clock`.
pub fn device_times(c: &mut Conn, id: u8, n: usize, clock: DeviceClock) -> Vec<Stamp> {
    (0..n)
        .map(|_| {
            let f = c.frame();
            assert_eq!(f.id(), id, "{:02X?}", f.bytes);
            Stamp {
                time: clock.read(f.payload()),
                len: f.bytes.len(),
            }
        })
        .collect()
}

/// The 2 kHz counter of the next `n` frames with `id`, a u16 at payload
/// offset `counter_offset` ([`device_times`] with [`DeviceClock::Counter`]).
pub fn frames_with_counter(c: &mut Conn, id: u8, n: usize, counter_offset: usize) -> Vec<u16> {
    device_times(c, id, n, DeviceClock::Counter(counter_offset))
        .iter()
        .map(|s| s.time as u16)
        .collect()
}

/// Asserts that `stamps` (consecutive frames) came at exactly `rate` Hz of
/// device time: every step between neighbours is `per_second / rate`
/// counts, no gap, no repeat. Where that is not whole (the 2 kHz counter
/// under a 4 kHz K201 stream) every run of `rate / gcd` frames spans exactly
/// `per_second / gcd` counts and no single step exceeds its share rounded
/// up. So the frames per device second equal `rate` exactly.
pub fn assert_rate(what: &str, stamps: &[Stamp], clock: DeviceClock, rate: u64) {
    assert!(stamps.len() >= 2, "{what}: {} frames", stamps.len());
    let per_s = clock.per_second();
    let g = gcd(per_s, rate);
    let (frames, counts) = (rate / g, per_s / g);
    let most = per_s.div_ceil(rate);
    let steps: Vec<u64> = stamps
        .windows(2)
        .map(|w| clock.step(w[0].time, w[1].time))
        .collect();
    for (i, s) in steps.iter().enumerate() {
        assert!(
            *s <= most && (frames > 1 || *s == counts),
            "{what}: step {s} at frame {i} ({rate} Hz is {counts}/{frames} counts of \
             {per_s}/s): {:?}",
            &steps[i.saturating_sub(3)..(i + 4).min(steps.len())]
        );
    }
    for (i, w) in steps.windows(frames as usize).enumerate() {
        let span: u64 = w.iter().sum();
        assert_eq!(span, counts, "{what}: {frames} steps from frame {i}");
    }
}

/// Device time from the first to the last of `stamps` in counts of
/// `clock` (each step across its wrap).
pub fn device_span(stamps: &[Stamp], clock: DeviceClock) -> u64 {
    stamps
        .windows(2)
        .map(|w| clock.step(w[0].time, w[1].time))
        .sum()
}

/// Bytes the frames after the first carried per second of device time
/// (the line's throughput measured on the device's clock).
pub fn bytes_per_device_second(stamps: &[Stamp], clock: DeviceClock) -> f64 {
    let bytes: usize = stamps.iter().skip(1).map(|s| s.len).sum();
    bytes as f64 * clock.per_second() as f64 / device_span(stamps, clock) as f64
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// A live motion feed sample in the binary form (docs/feed.md, kind 1):
/// rates in °/s for `device`, specific force +1 g up.
pub fn feed_sample(device: u16, time_s: f64, rate_dps: [f32; 3]) -> Vec<u8> {
    let s = imu_emu::feed::RateSample {
        device,
        time_ns: (time_s * 1e9) as u64,
        truth: imu_emu::sensor::Truth {
            rate_dps,
            specific_force_g: [0.0, 0.0, 1.0],
            temperature_c: None,
        },
    };
    let mut f = [0u8; imu_emu::feed::MAX_FRAME];
    let n = imu_emu::feed::encode(&s, &mut f);
    f[..n].to_vec()
}

/// The master of a pty pair as the far end of a serial line (the test's
/// side of the cable): reads time out after 20 ms.
pub struct Master(pub std::fs::File);

impl Read for Master {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use nix::poll::{PollFd, PollFlags, PollTimeout};
        use std::os::fd::AsFd as _;
        let mut fds = [PollFd::new(self.0.as_fd(), PollFlags::POLLIN)];
        nix::poll::poll(&mut fds, PollTimeout::from(20u8)).map_err(std::io::Error::from)?;
        if fds[0]
            .revents()
            .is_some_and(|r| r.intersects(PollFlags::POLLIN))
        {
            self.0.read(buf)
        } else {
            Err(std::io::ErrorKind::WouldBlock.into())
        }
    }
}

impl Write for Master {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// A pty pair for `--serial`: master, slave and the slave's path. Neither
/// descriptor is inherited by the emulator (or its port would never hang
/// up when the test closes the master).
pub fn pty_pair() -> (std::os::fd::OwnedFd, std::os::fd::OwnedFd, String) {
    use nix::fcntl::{fcntl, FcntlArg, FdFlag};
    let pty = nix::pty::openpty(None, None).unwrap();
    for fd in [&pty.master, &pty.slave] {
        fcntl(fd, FcntlArg::F_SETFD(FdFlag::FD_CLOEXEC)).unwrap();
    }
    let path = nix::unistd::ttyname(&pty.slave).unwrap();
    (pty.master, pty.slave, path.to_str().unwrap().to_owned())
}

/// The lowest descriptor number process `pid` has free (a soft
/// `RLIMIT_NOFILE` of it leaves the process none to open).
pub fn lowest_free_fd(pid: u32) -> u32 {
    let open: Vec<u32> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_str().unwrap().parse().unwrap())
        .collect();
    (0..).find(|n| !open.contains(n)).unwrap()
}
