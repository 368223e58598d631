//! The live web view (`--web`) end to end in a real headless browser:
//! Debian's `chromium`, driven over the Chrome DevTools protocol. The page
//! loads, its plot advances in device time, a fault button pressed on the
//! page shows in the unit's status word on the wire, and a malformed
//! command gets an HTTP error. `.ci/run` installs chromium when missing;
//! without it this test fails (it never skips).
//!
//! `IMU_EMU_WEB_SCREENSHOT=docs/web-view.png` also saves a screenshot.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use support::{Conn, Emu};

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
    let lines = emu.more_lines(2);
    let web = lines[1]
        .strip_prefix("web on ")
        .unwrap_or_else(|| panic!("no web line: {lines:?}"))
        .to_owned();
    // A client on the UART: GA at 100 Hz, no fault yet.
    let mut uart = Conn::tcp(emu.addr());
    uart.send(&support::command(0x8F));
    let first = uart.frame_with_id(0x8F);
    assert_eq!(first.payload().len(), 2, "the acknowledgement");
    assert_eq!(usw(&uart.frame_with_id(0x8F)), 0);

    let browser = Browser::start();
    let mut page = browser.page();
    page.call("Page.enable", json!({}));
    page.call("Page.navigate", json!({"url": web}));
    page.wait_for("typeof window.imuEmu === 'object' && window.imuEmu.lastT !== null");
    assert_eq!(
        page.eval("document.getElementById('identity').textContent"),
        Value::String(format!(
            "KERNEL-110-G2000-A40 · KERNEL · tcp {}",
            emu.addr()
        ))
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

    if let Ok(path) = std::env::var("IMU_EMU_WEB_SCREENSHOT") {
        // The fault off, some motion for the plots, then the picture.
        for cmd in ["fault comm off", "motion rotate 0 0 30"] {
            page.eval(&format!(
                "document.querySelector('button[data-cmd=\"{cmd}\"]').click()"
            ));
            page.wait_for(&format!("window.imuEmu.lastReply === '{cmd} → ok'"));
        }
        std::thread::sleep(Duration::from_secs(4));
        let shot = page.call("Page.captureScreenshot", json!({"format": "png"}));
        let png = base64(shot["data"].as_str().unwrap());
        std::fs::write(&path, png).unwrap();
    }
}
