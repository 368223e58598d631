//! The web view's HTTP request path: raw bytes on one connection, in
//! pseudo-random read sizes, through the server loop
//! (`imu_emu_runner::web::server::serve_connection`: head limits, body
//! limits, pipelining, `HEAD`) to the routes (`imu_emu_runner::web::Site`:
//! the `Host` and `X-Imu-Emu` checks, the query parameters, the control
//! parser of `POST /api/command`, the JSON endpoints) of a one-device hub
//! whose runner answers every command `ok`.

use std::io::{Read, Write};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu_runner::protocol::HostProtocol;
use imu_emu_runner::web::server::{self, Conn, MAX_HEAD};
use imu_emu_runner::web::{Hub, Site, MAX_BODY};

/// The input as a socket: reads of `chunk` bytes at most, each write one
/// answer.
struct Mem<'a> {
    input: &'a [u8],
    chunk: usize,
    writes: Vec<Vec<u8>>,
    read: usize,
}

impl Read for Mem<'_> {
    fn read(&mut self, b: &mut [u8]) -> std::io::Result<usize> {
        let n = b.len().min(self.input.len()).min(self.chunk);
        b[..n].copy_from_slice(&self.input[..n]);
        self.input = &self.input[n..];
        self.read += n;
        // Vary the next read's size.
        self.chunk = self.chunk * 7 % 61 + 1;
        Ok(n)
    }
}

impl Write for Mem<'_> {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.writes.push(b.to_vec());
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Conn for Mem<'_> {
    fn set_read_limit(&mut self, _: Option<Duration>) -> std::io::Result<()> {
        Ok(())
    }
}

/// One hub and its routes for every run, its runner a thread that answers
/// each command `ok`.
fn site() -> &'static Site {
    static SITE: OnceLock<Site> = OnceLock::new();
    SITE.get_or_init(|| {
        let product = Product::parse("K110").expect("K110");
        let hub = Hub::new(
            Kernel::live(),
            product,
            "K110",
            &["tcp 127.0.0.1:1".to_owned()],
        );
        let tap = hub.tap(0).expect("device 0");
        std::thread::spawn(move || loop {
            for p in tap.commands() {
                p.run(|_| Ok(String::new()));
            }
            std::thread::sleep(Duration::from_micros(20));
        });
        Site::new(Arc::clone(&hub), "127.0.0.1:8080".parse().expect("address"))
    })
}

/// Drives one connection with `data` (its first byte: the first read's
/// size). Invariants: every write is one whole answer whose head parses,
/// with a known status, a `Content-Length` equal to its body (or no body:
/// `HEAD`); nothing follows an answer that says `Connection: close`; the
/// server never reads more than the input.
pub fn web_request(data: &[u8]) {
    let Some((&first, input)) = data.split_first() else {
        return;
    };
    let site = site();
    let handler = |r: &server::Request| site.respond(r);
    let mut m = Mem {
        input,
        chunk: usize::from(first % 64) + 1,
        writes: Vec::new(),
        read: 0,
    };
    server::serve_connection(&mut m, &handler, MAX_BODY);
    assert!(m.read <= input.len());
    let n = m.writes.len();
    for (k, w) in m.writes.iter().enumerate() {
        let mut headers = [httparse::EMPTY_HEADER; 16];
        let mut r = httparse::Response::new(&mut headers);
        let head = match r.parse(w) {
            Ok(httparse::Status::Complete(h)) => h,
            other => panic!("answer {k} does not parse: {other:?} {w:?}"),
        };
        let code = r.code.expect("a status");
        assert!(
            [200, 400, 403, 404, 405, 408, 411, 413, 421, 422, 431, 500, 503, 505].contains(&code),
            "status {code}"
        );
        assert!(head <= MAX_HEAD);
        let value = |name: &str| {
            r.headers
                .iter()
                .find(|h| h.name.eq_ignore_ascii_case(name))
                .map(|h| String::from_utf8_lossy(h.value).into_owned())
        };
        let len: usize = value("Content-Length")
            .and_then(|v| v.parse().ok())
            .expect("Content-Length");
        let body = w.len() - head;
        assert!(body == len || body == 0, "body {body} of {len}");
        if value("Connection").as_deref() == Some("close") {
            assert_eq!(k + 1, n, "an answer after Connection: close");
        }
    }
}
