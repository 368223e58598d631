//! The live web view (`--web`) end to end in a real headless browser:
//! Debian's `chromium`, driven over the Chrome DevTools protocol. The page
//! loads, its plot advances in device time, a fault button pressed on the
//! page shows in the unit's status word on the wire, and a malformed
//! command gets an HTTP error. For the IMX (`--protocol isb`) the
//! navigation plots advance and the page's "GPS outage" shows in INS_2 and
//! GPS1_POS on the wire. Every panel is on one device clock, across a
//! pause longer than a counter wrap, every format reaches the page (those
//! without a time field timed by their rate and order), and the position
//! panel draws the truth's (and an IMX's INS and GPS) track. `.ci/run`
//! installs chromium when missing; without it these tests fail (they
//! never skip).
//!
//! `IMU_EMU_WEB_SCREENSHOT=docs/web-view.png` and
//! `IMU_EMU_WEB_SCREENSHOT_IMX=docs/web-view-imx.png` also save screenshots.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use imu_emu::isb::did;
use imu_emu::isb::nav_sets::{gps_status, ins_status, GpsPos, Ins2};
use serde_json::{json, Value};
use support::{isb_get, isb_packet, Conn, Emu};

const TIMEOUT: Duration = Duration::from_secs(20);

/// A headless chromium with a fresh profile, killed on drop.
struct Browser {
    child: Child,
    _profile: tempfile::TempDir,
    port: u16,
}

impl Browser {
    fn start() -> Browser {
        let profile = tempfile::tempdir().unwrap();
        let mut child = Command::new("chromium")
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--window-size=1500,1150",
                "--remote-debugging-address=127.0.0.1",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| {
                panic!(
                    "cannot start chromium ({e}): the web view test needs Debian's chromium \
                     (apt-get install -y chromium; .ci/run installs it)"
                )
            });
        // "DevTools listening on ws://127.0.0.1:PORT/devtools/browser/…"
        let err = child.stderr.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                if let Some(rest) = line.split("ws://127.0.0.1:").nth(1) {
                    let _ = tx.send(rest.split('/').next().unwrap_or("").to_owned());
                }
            }
        });
        let port: u16 = rx
            .recv_timeout(TIMEOUT)
            .expect("chromium did not announce its DevTools port")
            .parse()
            .unwrap();
        Browser {
            child,
            _profile: profile,
            port,
        }
    }

    /// The DevTools socket of the page chromium opened.
    fn page(&self) -> Page {
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let list = http_get(self.port, "/json/list");
            if let Some(ws) = list
                .as_array()
                .into_iter()
                .flatten()
                .find(|t| t["type"] == "page")
                .and_then(|t| t["webSocketDebuggerUrl"].as_str())
            {
                let (sock, _) = tungstenite::connect(ws).expect("DevTools websocket");
                if let tungstenite::stream::MaybeTlsStream::Plain(s) = sock.get_ref() {
                    s.set_read_timeout(Some(Duration::from_millis(200)))
                        .unwrap();
                }
                return Page { sock, id: 0 };
            }
            assert!(Instant::now() < deadline, "no page target: {list}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// GET `path` of the DevTools HTTP endpoint, as JSON.
fn http_get(port: u16, path: &str) -> Value {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    // The DevTools server may keep the connection open: read until the
    // body parses (bounded).
    s.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let deadline = Instant::now() + TIMEOUT;
    let mut raw = Vec::new();
    loop {
        let mut buf = [0u8; 8192];
        match s.read(&mut buf) {
            Ok(0) => {}
            Ok(n) => raw.extend_from_slice(&buf[..n]),
            Err(_) => {}
        }
        let text = String::from_utf8_lossy(&raw);
        if let Some(body) = text.split("\r\n\r\n").nth(1) {
            if let Ok(v) = serde_json::from_str::<Value>(body) {
                return v;
            }
        }
        if Instant::now() > deadline {
            return Value::Null;
        }
    }
}

type Socket = tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>;

/// One page over the DevTools protocol.
struct Page {
    sock: Socket,
    id: u64,
}

impl Page {
    /// Sends `method` and returns its result (events in between skipped).
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.id += 1;
        let id = self.id;
        let msg = json!({"id": id, "method": method, "params": params}).to_string();
        self.sock.send(tungstenite::Message::text(msg)).unwrap();
        let deadline = Instant::now() + TIMEOUT;
        loop {
            assert!(Instant::now() < deadline, "no answer to {method}");
            let m = match self.sock.read() {
                Ok(m) => m,
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    continue
                }
                Err(e) => panic!("DevTools: {e}"),
            };
            let Ok(text) = m.to_text() else { continue };
            let v: Value = serde_json::from_str(text).unwrap_or(Value::Null);
            if v["id"] == id {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    /// Evaluates `expr` in the page; its value.
    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
        );
        r["result"]["value"].clone()
    }

    /// Waits (bounded) until `expr` is true in the page.
    fn wait_for(&mut self, expr: &str) {
        let deadline = Instant::now() + TIMEOUT;
        while self.eval(expr) != Value::Bool(true) {
            assert!(Instant::now() < deadline, "never true in the page: {expr}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// Base64 (RFC 4648) to bytes, for the screenshot.
fn base64(s: &str) -> Vec<u8> {
    let val = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            _ => 63,
        }
    };
    let clean: Vec<u8> = s.bytes().filter(|&c| c != b'=' && c != b'\n').collect();
    let mut out = Vec::with_capacity(clean.len() * 3 / 4);
    for chunk in clean.chunks(4) {
        let mut n = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            n |= val(c) << (18 - 6 * i);
        }
        let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&bytes[..chunk.len() - 1]);
    }
    out
}

/// The `web on URL` line among the emulator's first stdout lines.
fn web_url(emu: &Emu, lines: usize) -> String {
    let lines = emu.more_lines(lines);
    lines
        .iter()
        .find_map(|l| l.strip_prefix("web on "))
        .unwrap_or_else(|| panic!("no web line: {lines:?}"))
        .to_owned()
}

/// A headless chromium showing `url`, once the page has decoded output.
fn open(url: &str) -> (Browser, Page) {
    let browser = Browser::start();
    let mut page = browser.page();
    page.call("Page.enable", json!({}));
    page.call("Page.navigate", json!({"url": url}));
    page.wait_for("typeof window.imuEmu === 'object' && window.imuEmu.lastT !== null");
    (browser, page)
}

impl Page {
    /// Clicks the button sending `cmd`; waits for the device's `ok`.
    fn press(&mut self, cmd: &str) {
        self.eval(&format!(
            "document.querySelector('button[data-cmd=\"{cmd}\"]').click()"
        ));
        self.wait_for(&format!("window.imuEmu.lastReply === '{cmd} → ok'"));
    }

    /// Saves a PNG of the page to the path in `var`, if it is set.
    fn screenshot_to(&mut self, var: &str) {
        if let Ok(path) = std::env::var(var) {
            let shot = self.call("Page.captureScreenshot", json!({"format": "png"}));
            std::fs::write(&path, base64(shot["data"].as_str().unwrap())).unwrap();
        }
    }
}

/// The USW of a GA frame (ICD Table 5.7: payload bytes 26..28).
fn usw(f: &support::Frame) -> u16 {
    u16::from_le_bytes([f.payload()[26], f.payload()[27]])
}

#[test]
fn the_page_plots_the_output_and_its_fault_button_reaches_the_wire() {
    let emu = Emu::tcp(&[
        "--power-on",
        "now",
        "--web",
        "127.0.0.1:0",
        "--seed",
        "1",
        "--control",
        "127.0.0.1:0",
    ]);
    let web = web_url(&emu, 2);
    // A client on the UART: GA at 100 Hz, no fault yet.
    let mut uart = Conn::tcp(emu.addr());
    uart.send(&support::command(0x8F));
    let first = uart.frame_with_id(0x8F);
    assert_eq!(first.payload().len(), 2, "the acknowledgement");
    assert_eq!(usw(&uart.frame_with_id(0x8F)), 0);

    let (_browser, mut page) = open(&web);
    assert_eq!(
        page.eval("document.getElementById('identity').textContent"),
        Value::String(format!(
            "KERNEL-110-G2000-A40 · KERNEL · tcp {}",
            emu.addr()
        ))
    );
    // No IMX panels for a KERNEL unit.
    assert_eq!(
        page.eval("document.getElementById('nav').hidden"),
        Value::Bool(true)
    );
    // The plot advances in device time.
    let t0 = page.eval("window.imuEmu.lastT").as_f64().unwrap();
    let drawn0 = page.eval("window.imuEmu.drawn").as_u64().unwrap();
    page.wait_for(&format!("window.imuEmu.lastT > {t0} + 0.5"));
    assert!(page.eval("window.imuEmu.drawn").as_u64().unwrap() > drawn0);
    assert_eq!(
        page.eval("window.imuEmu.status['format']"),
        Value::String("0x8f".into())
    );
    // Press "comm on": the answer comes back, and the unit's USW on the
    // wire gets bit 1 (sensor communication, Table 5.26).
    page.eval("document.querySelector('button[data-cmd=\"fault comm on\"]').click()");
    page.wait_for("window.imuEmu.lastReply === 'fault comm on → ok'");
    let deadline = Instant::now() + TIMEOUT;
    loop {
        let f = uart.frame_with_id(0x8F);
        if usw(&f) & 0x0002 != 0 {
            break;
        }
        assert!(Instant::now() < deadline, "USW bit 1 never set on the wire");
    }
    // A malformed command typed into the page: an HTTP error, the parser's
    // words, nothing sent to the device.
    page.eval(
        "document.getElementById('cmd').value = 'fault comm maybe'; \
         document.querySelector('#cmd-form button').click()",
    );
    page.wait_for("window.imuEmu.lastReply.startsWith('fault comm maybe → error ')");
    assert_eq!(
        page.eval("document.getElementById('reply').className"),
        Value::String("bad".into())
    );

    if std::env::var("IMU_EMU_WEB_SCREENSHOT").is_ok() {
        // The fault off, Calibrated HR (attitude on the wire too), a
        // turning flight for the plots and the track, then the picture.
        page.press("fault comm off");
        uart.send(&support::command(0xFE));
        uart.drain_for(Duration::from_millis(50));
        uart.send(&support::command(0x81));
        let turn = "motion script start 45 0 300 350 40; coord-turn 20 60";
        page.eval(&format!(
            "document.getElementById('cmd').value = {}; \
             document.querySelector('#cmd-form button').click()",
            json!(turn)
        ));
        page.wait_for(&format!(
            "window.imuEmu.lastReply === {}",
            json!(format!("{turn} → ok"))
        ));
        // Read the stream meanwhile (a client that stops reading would
        // fill the transport's backlog).
        let until = Instant::now() + Duration::from_secs(9);
        while Instant::now() < until {
            uart.drain_for(Duration::from_millis(100));
        }
        // Tall enough for the position panel below the time plots.
        page.call(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": 1500, "height": 1500, "deviceScaleFactor": 1, "mobile": false}),
        );
        page.screenshot_to("IMU_EMU_WEB_SCREENSHOT");
    }
}

/// One device clock on every panel, across a pause longer than a 16-bit
/// counter wrap, and every output format shown: a K120 at `--speed 20`
/// streams GA, stops for 50 s of device time and streams GA again — the
/// sent points are at the device time of the truth and the status, not
/// 32.768 s behind; then Orientation, Quaternion and GAA (no time field:
/// timed by their rate and order, 10 ms apart at 100 Hz) each reach the
/// page; the position panel draws the truth's track.
#[test]
fn the_page_keeps_one_clock_across_a_pause_and_shows_every_format() {
    let emu = Emu::tcp(&[
        "--model",
        "K120",
        "--power-on",
        "now",
        "--web",
        "127.0.0.1:0",
        "--seed",
        "1",
        "--speed",
        "20",
    ]);
    let web = web_url(&emu, 1);
    let mut uart = Conn::tcp(emu.addr());
    uart.send(&support::command(0x8F));
    uart.frame_with_id(0x8F);
    let (_browser, mut page) = open(&web);
    // Newest point with `key` (and none of `not`), its device time, and
    // the device time now: within 2 s (publishing every 40 ms of host
    // time is 0.8 s of device time at --speed 20).
    let on_clock = |key: &str, not: &str| {
        format!(
            "(s => {{ const p = s.points.filter(p => '{key}' in p && !('{not}' in p));              const l = p[p.length - 1]; const tr = s.truth[s.truth.length - 1];              return !!l && !!tr && Math.abs(l.t - s.deviceTime) < 2 &&              Math.abs(tr.t - s.deviceTime) < 2; }})(window.imuEmu)"
        )
    };
    page.wait_for(&on_clock("counter", "none"));
    let before = page.eval("window.imuEmu.lastT").as_f64().unwrap();
    uart.send(&support::command(0xFE));
    uart.drain_for(Duration::from_millis(100));
    // 2.5 s at --speed 20: 50 s of device time, more than 32.768 s.
    std::thread::sleep(Duration::from_millis(2500));
    uart.send(&support::command(0x8F));
    uart.frame_with_id(0x8F);
    page.wait_for(&format!("window.imuEmu.lastT > {before} + 45"));
    page.wait_for(&on_clock("counter", "none"));
    // Every format: each reaches the page on the same clock.
    for (code, key, not) in [
        (0x33u8, "heading", "q0"),
        (0x82, "q0", "none"),
        (0xA5, "aux_acc_x", "counter"),
    ] {
        uart.send(&support::command(0xFE));
        uart.drain_for(Duration::from_millis(50));
        uart.send(&support::command(code));
        uart.frame_with_id(code);
        let n = page
            .eval(&format!(
                "window.imuEmu.points.filter(p => '{key}' in p && !('{not}' in p)).length"
            ))
            .as_u64()
            .unwrap();
        page.wait_for(&format!(
            "window.imuEmu.points.filter(p => '{key}' in p && !('{not}' in p)).length > {n} + 50"
        ));
        page.wait_for(&on_clock(key, not));
    }
    // GAA (no time field) at its known 100 Hz: whole periods in order.
    let steps = page.eval(
        "(p => p.slice(-40).map((x, i, a) => i ? x.t - a[i - 1].t : 0.01))         (window.imuEmu.points.filter(p => 'aux_acc_x' in p))",
    );
    for d in steps.as_array().unwrap() {
        assert!((d.as_f64().unwrap() - 0.01).abs() < 1e-6, "{steps}");
    }
    // The position panel: the truth's track.
    page.wait_for("!!window.imuEmu.track && window.imuEmu.track.counts[0] > 10");
}

/// The INS_2 insStatus has a GPS fix in it (NAV mode, `docs/isb.md`).
fn ins_has_fix(status: u32) -> bool {
    status & ins_status::GPS_NAV_FIX_MASK != 0 && !ins_status::dead_reckoning(status)
}

/// The IMX at `--speed 20` with a client streaming INS_2, GPS1_POS, the
/// magnetometer and the barometer: the page shows the navigation panels
/// (and hides them for KERNEL), each plot gets points and the INS plot
/// advances in device time; the manoeuvre buttons and the `motion file`
/// form are answered `ok` and the truth plot climbs with the file; "GPS outage" pressed on the page turns INS_2
/// to dead reckoning at its next output (100 ms of device time after the
/// last with a fix) and GPS1_POS to no fix on the wire (then the page's
/// own GPS panel says so), and "GPS back" restores the fix.
#[test]
fn the_imx_page_plots_navigation_and_its_gps_outage_reaches_the_wire() {
    let emu = Emu::tcp(&[
        "--protocol",
        "isb",
        "--web",
        "127.0.0.1:0",
        "--seed",
        "1",
        "--speed",
        "20",
    ]);
    let web = web_url(&emu, 1);
    let mut uart = Conn::tcp(emu.addr());
    // INS_2 every 100 ms, GPS1_POS every 200 ms, MAGNETOMETER and
    // BAROMETER at 25 of their periods (docs/isb.md).
    for (d, period) in [
        (did::INS_2, 25),
        (did::GPS1_POS, 1),
        (did::MAGNETOMETER, 25),
        (did::BAROMETER, 25),
    ] {
        uart.send(&isb_get(d, period));
    }
    // Past the 30 s cold start (device time): INS_2 navigates on a fix.
    let mut navigating = false;
    for _ in 0..5000 {
        let p = isb_packet(&mut uart);
        if p.did == did::INS_2 && ins_has_fix(ins2(&p).header.ins_status) {
            navigating = true;
            break;
        }
    }
    assert!(navigating, "no INS_2 with a GPS fix");

    let (_browser, mut page) = open(&web);
    assert_eq!(
        page.eval("document.getElementById('nav').hidden"),
        Value::Bool(false)
    );
    assert_eq!(
        page.eval("document.getElementById('identity').textContent.includes(' · ISB · tcp ')"),
        Value::Bool(true)
    );
    page.wait_for(
        "(n => n && n.ins > 0 && n.gps > 0 && n.mag > 0 && n.baro > 0 && n.gpsFix === 3)\
         (window.imuEmu.nav)",
    );
    // The INS plot advances in device time, the same clock as the
    // status's (its GPS time of week is the axis's second label).
    let t0 = page.eval("window.imuEmu.nav.insT").as_f64().unwrap();
    page.wait_for(&format!("window.imuEmu.nav.insT > {t0} + 1"));
    page.wait_for(
        "(s => Math.abs(s.nav.insT - s.deviceTime) < 2 && s.towAtZero !== null)(window.imuEmu)",
    );
    // The position panel: truth, INS and GPS1 tracks.
    page.wait_for(
        "(t => !!t && t.counts.length === 3 && t.counts.every(n => n > 3))(window.imuEmu.track)",
    );

    // Manoeuvres through the page: a preset script and a script file.
    page.press("motion script start 45 0 300 0 60; hold 5; coord-turn 3 60; hold 30");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("climb.txt");
    std::fs::write(&file, "start 45 0 300 0 60\nhold 5\nclimb 6 30\n").unwrap();
    page.eval(&format!(
        "document.getElementById('motion-file').value = {}; \
         document.querySelector('#file-form button').click()",
        json!(file.to_str().unwrap())
    ));
    page.wait_for(&format!(
        "window.imuEmu.lastReply === {}",
        json!(format!("motion file {} → ok", file.display()))
    ));
    // The truth plot follows the file's climb: 6° of pitch 5 s + 2 s of
    // device time after it started.
    page.wait_for(
        "(t => t.length > 0 && Math.abs(t[t.length - 1].pitch - 6) < 0.01)(window.imuEmu.truth)",
    );

    // "GPS outage" on the page: on the wire INS_2 falls back to dead
    // reckoning and GPS1_POS reports no fix.
    // Where that happens is fixed by device time: the first INS_2 in dead
    // reckoning directly follows (one 100 ms output period later, by its
    // own time fields) the last one with a fix: no stale fix is sent after
    // the outage began.
    page.press("fault gps off");
    let (mut dr, mut lost) = (None, false);
    let mut last_fix: Option<f64> = None;
    let deadline = Instant::now() + TIMEOUT;
    while dr.is_none() || !lost {
        assert!(
            Instant::now() < deadline,
            "the outage never reached the wire"
        );
        let p = isb_packet(&mut uart);
        match p.did {
            did::INS_2 if dr.is_none() => {
                let h = ins2(&p).header;
                if ins_has_fix(h.ins_status) {
                    last_fix = Some(h.time_of_week);
                } else {
                    assert!(
                        ins_status::dead_reckoning(h.ins_status),
                        "{:#x}",
                        h.ins_status
                    );
                    assert_eq!(h.ins_status & ins_status::GPS_NAV_FIX_MASK, 0);
                    dr = Some(h.time_of_week);
                }
            }
            did::GPS1_POS => {
                let g = GpsPos::decode(&p.payload.try_into().unwrap());
                lost |= (g.status & gps_status::FIX_MASK) >> gps_status::FIX_SHIFT
                    == gps_status::FIX_NONE;
            }
            _ => {}
        }
    }
    let (dr, last_fix) = (dr.unwrap(), last_fix.expect("an INS_2 with a fix first"));
    assert!((dr - last_fix - 0.1).abs() < 1e-6, "{last_fix} then {dr}");
    page.wait_for("window.imuEmu.nav.gpsFix === 0");
    page.press("fault gps on");
    let deadline = Instant::now() + TIMEOUT;
    loop {
        assert!(Instant::now() < deadline, "the fix never came back");
        let p = isb_packet(&mut uart);
        if p.did == did::INS_2 && ins_has_fix(ins2(&p).header.ins_status) {
            break;
        }
    }
    page.wait_for("window.imuEmu.nav.gpsFix === 3");

    if std::env::var("IMU_EMU_WEB_SCREENSHOT_IMX").is_ok() {
        page.press("motion script start 45 0 300 0 60; hold 5; coord-turn 3 60; hold 30");
        // The IMU too, for the rate and acceleration panels; the stream
        // read meanwhile.
        uart.send(&isb_get(did::IMU, 10));
        let until = Instant::now() + Duration::from_secs(4);
        while Instant::now() < until {
            uart.drain_for(Duration::from_millis(100));
        }
        // Tall enough for the navigation panels below the IMU plots.
        page.call(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": 1500, "height": 2150, "deviceScaleFactor": 1, "mobile": false}),
        );
        page.screenshot_to("IMU_EMU_WEB_SCREENSHOT_IMX");
    }
}

fn ins2(p: &support::IsbPacket) -> Ins2 {
    Ins2::decode(&p.payload.clone().try_into().unwrap())
}

/// The page's strobe button is a rising EXTRIG edge: the IMX answers on
/// its line with STROBE_IN_TIME (count 1; the GET's own reply is count 0).
#[test]
fn the_imx_pages_strobe_button_reaches_the_wire() {
    use imu_emu::isb::sets::StrobeInTime;
    let emu = Emu::tcp(&["--protocol", "isb", "--web", "127.0.0.1:0", "--seed", "1"]);
    let web = web_url(&emu, 1);
    let mut uart = Conn::tcp(emu.addr());
    uart.send(&isb_get(did::INS_2, 25));
    uart.send(&isb_get(did::STROBE_IN_TIME, 1));
    let (_browser, mut page) = open(&web);
    page.press("strobe");
    let deadline = Instant::now() + TIMEOUT;
    loop {
        assert!(Instant::now() < deadline, "no strobe on the wire");
        let p = isb_packet(&mut uart);
        if p.did == did::STROBE_IN_TIME {
            let s = StrobeInTime::decode(&p.payload.try_into().unwrap());
            if s.count == 1 {
                break;
            }
        }
    }
}
