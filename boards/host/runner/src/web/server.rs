//! The web view's HTTP/1.1 transport: a bounded server loop around
//! [`httparse`] (the request-head parser of hyper, small and fuzzed
//! upstream). The routes, the JSON and the page are the web view's
//! ([`super`]); this module only turns bytes on a socket into a
//! [`Request`] and a [`Response`] into bytes, within limits no client can
//! push past:
//!
//! - **Connections**: at most [`MAX_CONNECTIONS`] at once, each served by
//!   a thread of its own (one descriptor, a [`THREAD_STACK`] stack); the
//!   next is answered `503 Service Unavailable` (with `Retry-After`) and
//!   closed, never queued behind the others. A slow or silent client
//!   holds only its own connection.
//! - **Time**: a request's head and body must arrive within
//!   [`REQUEST_WITHIN`] of its first byte (else `408`, then close: a
//!   slowloris costs one slot for at most that long), a kept-alive
//!   connection may sit idle [`IDLE_WITHIN`] between requests, and each
//!   response must be taken by the client within [`WRITE_WITHIN`] (a
//!   client that pipelines requests and never reads its answers is closed
//!   when the socket's buffers are full and that time has passed).
//! - **Size**: a request head is at most [`MAX_HEAD`] bytes and
//!   [`MAX_HEADERS`] headers (`431`); a body at most the caller's
//!   `max_body` bytes (`413` from the `Content-Length` alone: an announced
//!   body beyond it, however large, even beyond `u64`, is never read,
//!   allocated or drained — the connection is closed instead); a chunked
//!   body is refused (`411`, the page never sends one). A connection's
//!   memory is its fixed head buffer, one body and one response, freed
//!   when it closes; pipelined requests wait in the head buffer, never
//!   beyond it.
//! - **Descriptors**: a failing `accept()` (EMFILE and the like) pauses
//!   the listener [`crate::transport::ACCEPT_BACKOFF`] and is reported at
//!   most once a second ([`crate::transport::AcceptGuard`], as the other
//!   sockets do); it never ends the accept loop.
//! - `HEAD` is answered as `GET` without the body.
//!
//! Why not a general server crate: tiny_http (used before) allocates a
//! body's announced length to drain it and has no connection or header
//! limits; hyper or axum would bring an async runtime for a page that
//! polls a JSON endpoint. A loop of ours around `httparse` is short and
//! every limit above is a constant here.

use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::transport::AcceptGuard;

/// Connections served at once; the next ones get `503`.
pub const MAX_CONNECTIONS: usize = 32;
/// Largest request head (request line and headers), bytes.
pub const MAX_HEAD: usize = 8 * 1024;
/// Most headers in a request.
pub const MAX_HEADERS: usize = 32;
/// A request's head and body arrive within this of its first byte.
pub const REQUEST_WITHIN: Duration = Duration::from_secs(10);
/// A kept-alive connection may wait this long for its next request.
pub const IDLE_WITHIN: Duration = Duration::from_secs(5);
/// A response is taken by the client within this.
pub const WRITE_WITHIN: Duration = Duration::from_secs(10);
/// Stack of a connection's thread (the handlers build their answers on
/// the heap).
pub const THREAD_STACK: usize = 256 * 1024;

/// A request method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// `GET` (and `HEAD`, which the server answers as `GET` without the
    /// body).
    Get,
    /// `POST`.
    Post,
    /// Any other method.
    Other,
}

/// One request, as the handler sees it.
#[derive(Debug, Clone)]
pub struct Request {
    /// Its method (`HEAD` is given as [`Method::Get`]).
    pub method: Method,
    /// Its target (`/api/state?dev=0`).
    pub target: String,
    /// Its headers, names as sent.
    pub headers: Vec<(String, String)>,
    /// Its body (at most the server's `max_body` bytes).
    pub body: Vec<u8>,
}

impl Request {
    /// The value of header `name` (case-insensitive), if present.
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// One response: status, content type, body.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Response {
    /// HTTP status code.
    pub status: u16,
    /// `Content-Type`.
    pub content_type: &'static str,
    /// The body.
    pub body: String,
}

/// What answers requests (the web view's routes).
pub type Handler = dyn Fn(&Request) -> Response + Send + Sync;

/// A connection the server reads and writes: a socket, or bytes in memory
/// (the fuzz target).
pub trait Conn: Read + Write {
    /// Reads from now on give up after `d` (`None`: wait without limit).
    fn set_read_limit(&mut self, d: Option<Duration>) -> std::io::Result<()>;
}

impl Conn for TcpStream {
    fn set_read_limit(&mut self, d: Option<Duration>) -> std::io::Result<()> {
        self.set_read_timeout(d)
    }
}

/// The reason phrase of the codes the web view answers with.
fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        411 => "Length Required",
        413 => "Content Too Large",
        421 => "Misdirected Request",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        500 => "Internal Server Error",
        501 => "Not Implemented",
        503 => "Service Unavailable",
        505 => "HTTP Version Not Supported",
        _ => "Status",
    }
}

/// Writes `r` (without its body for `HEAD`), closing if `close`.
fn write_response(
    c: &mut impl Conn,
    r: &Response,
    head_only: bool,
    close: bool,
) -> std::io::Result<()> {
    let mut out = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nCache-Control: no-store\r\n\
         X-Content-Type-Options: nosniff\r\n",
        r.status,
        reason(r.status),
        r.content_type,
        r.body.len()
    );
    if r.status == 503 {
        out.push_str("Retry-After: 1\r\n");
    }
    out.push_str(if close {
        "Connection: close\r\n\r\n"
    } else {
        "Connection: keep-alive\r\n\r\n"
    });
    let mut bytes = out.into_bytes();
    if !head_only {
        bytes.extend_from_slice(r.body.as_bytes());
    }
    c.write_all(&bytes)?;
    c.flush()
}

fn plain(status: u16, body: &str) -> Response {
    Response {
        status,
        content_type: "text/plain; charset=utf-8",
        body: body.to_owned(),
    }
}

/// What reading a request found.
enum Read1 {
    /// A request, and whether the connection stays open after it.
    Request(Request, bool, bool),
    /// An error answer, then close.
    Refuse(Response),
    /// The client left or idled out between requests: close silently.
    Done,
}

/// The head buffer of one connection: pipelined bytes wait here.
struct Buf {
    data: Box<[u8; MAX_HEAD]>,
    len: usize,
}

impl Buf {
    /// Reads more into the buffer before `deadline`; `Ok(0)` at its end.
    fn fill(&mut self, c: &mut impl Conn, deadline: Option<Instant>) -> std::io::Result<usize> {
        if let Some(d) = deadline {
            let left = d.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(ErrorKind::TimedOut.into());
            }
            c.set_read_limit(Some(left))?;
        }
        loop {
            match c.read(&mut self.data[self.len..]) {
                Ok(n) => {
                    self.len += n;
                    return Ok(n);
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    return Err(ErrorKind::TimedOut.into())
                }
                Err(e) => return Err(e),
            }
        }
    }

    fn consume(&mut self, n: usize) {
        self.data.copy_within(n..self.len, 0);
        self.len -= n;
    }
}

/// Reads the next request of a connection (head, then body).
fn read_request(c: &mut impl Conn, buf: &mut Buf, max_body: usize) -> Read1 {
    // Idle between requests, then the whole request within its time.
    let mut deadline = Instant::now() + IDLE_WITHIN;
    let mut started = buf.len > 0;
    if started {
        deadline = Instant::now() + REQUEST_WITHIN;
    }
    let (head_len, method, head_only, target, headers, minor) = loop {
        if buf.len > 0 {
            let mut slots = [httparse::EMPTY_HEADER; MAX_HEADERS];
            let mut req = httparse::Request::new(&mut slots);
            match req.parse(&buf.data[..buf.len]) {
                Ok(httparse::Status::Complete(n)) => {
                    let (method, head_only) = match req.method.unwrap_or("") {
                        "GET" => (Method::Get, false),
                        "HEAD" => (Method::Get, true),
                        "POST" => (Method::Post, false),
                        _ => (Method::Other, false),
                    };
                    let headers: Vec<(String, String)> = req
                        .headers
                        .iter()
                        .map(|h| {
                            (
                                h.name.to_owned(),
                                String::from_utf8_lossy(h.value).into_owned(),
                            )
                        })
                        .collect();
                    break (
                        n,
                        method,
                        head_only,
                        req.path.unwrap_or("").to_owned(),
                        headers,
                        req.version.unwrap_or(1),
                    );
                }
                Ok(httparse::Status::Partial) => {}
                Err(httparse::Error::TooManyHeaders) => {
                    return Read1::Refuse(plain(431, &format!("at most {MAX_HEADERS} headers")))
                }
                Err(httparse::Error::Version) => return Read1::Refuse(plain(505, "HTTP/1.x only")),
                Err(_) => return Read1::Refuse(plain(400, "malformed request")),
            }
        }
        if buf.len == MAX_HEAD {
            return Read1::Refuse(plain(
                431,
                &format!("a request head is at most {MAX_HEAD} bytes"),
            ));
        }
        match buf.fill(c, Some(deadline)) {
            Ok(0) | Err(_) if !started => return Read1::Done,
            Ok(0) => return Read1::Done,
            Err(e) if e.kind() == ErrorKind::TimedOut => {
                return Read1::Refuse(plain(408, "the request took too long"))
            }
            Err(_) => return Read1::Done,
            Ok(_) => {
                if !started {
                    started = true;
                    deadline = Instant::now() + REQUEST_WITHIN;
                }
            }
        }
    };
    let req = Request {
        method,
        target,
        headers,
        body: Vec::new(),
    };
    if req.header("Transfer-Encoding").is_some() {
        return Read1::Refuse(plain(411, "a body needs a Content-Length (no chunks)"));
    }
    let lengths: Vec<&str> = req
        .headers
        .iter()
        .filter(|(k, _)| k.eq_ignore_ascii_case("Content-Length"))
        .map(|(_, v)| v.trim())
        .collect();
    let length = match lengths.as_slice() {
        [] => 0,
        [one] if !one.is_empty() && one.bytes().all(|b| b.is_ascii_digit()) => {
            // Digits only; beyond usize it is beyond any limit.
            one.parse::<usize>().unwrap_or(usize::MAX)
        }
        _ => return Read1::Refuse(plain(400, "one decimal Content-Length, at most")),
    };
    if length > max_body {
        return Read1::Refuse(plain(
            413,
            &format!("a request body is at most {max_body} bytes"),
        ));
    }
    buf.consume(head_len);
    while buf.len < length {
        match buf.fill(c, Some(deadline)) {
            Ok(0) => return Read1::Done,
            Ok(_) => {}
            Err(e) if e.kind() == ErrorKind::TimedOut => {
                return Read1::Refuse(plain(408, "the request body took too long"))
            }
            Err(_) => return Read1::Done,
        }
    }
    let body = buf.data[..length].to_vec();
    buf.consume(length);
    let connection = req.header("Connection").unwrap_or("").to_ascii_lowercase();
    let keep = if minor == 0 {
        connection.contains("keep-alive")
    } else {
        !connection.contains("close")
    };
    Read1::Request(Request { body, ..req }, keep, head_only)
}

/// Serves one connection until it closes, errs or times out: each request
/// is read within the limits (module docs) and answered by `handler`.
/// `max_body`: the largest body read.
pub fn serve_connection(c: &mut impl Conn, handler: &Handler, max_body: usize) {
    let mut buf = Buf {
        data: Box::new([0; MAX_HEAD]),
        len: 0,
    };
    loop {
        match read_request(c, &mut buf, max_body) {
            Read1::Request(req, keep, head_only) => {
                let r = if req.method == Method::Other {
                    plain(405, "method not allowed")
                } else {
                    handler(&req)
                };
                if write_response(c, &r, head_only, !keep).is_err() || !keep {
                    return;
                }
            }
            Read1::Refuse(r) => {
                let _ = write_response(c, &r, false, true);
                return;
            }
            Read1::Done => return,
        }
    }
}

/// The running server: its accept thread.
pub struct HttpServer {
    /// The address it listens on.
    pub addr: SocketAddr,
    thread: Option<std::thread::JoinHandle<()>>,
    stop: Arc<AtomicBool>,
}

impl HttpServer {
    /// Serves `handler` on `listener` (bound by the caller) from a thread
    /// of its own; request bodies of at most `max_body` bytes.
    pub fn start(
        listener: TcpListener,
        handler: Arc<Handler>,
        max_body: usize,
    ) -> anyhow::Result<HttpServer> {
        let addr = listener.local_addr()?;
        listener.set_nonblocking(true)?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("imu-emu-web".into())
            .spawn(move || accept_loop(&listener, &handler, max_body, &flag))?;
        Ok(HttpServer {
            addr,
            thread: Some(thread),
            stop,
        })
    }
}

impl Drop for HttpServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One connection's place among [`MAX_CONNECTIONS`]: given back when its
/// thread ends.
struct Slot(Arc<AtomicUsize>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

fn accept_loop(listener: &TcpListener, handler: &Arc<Handler>, max_body: usize, stop: &AtomicBool) {
    use std::os::fd::AsFd;
    let active = Arc::new(AtomicUsize::new(0));
    let mut guard = AcceptGuard::new("web");
    let mut lingering: VecDeque<(TcpStream, Instant)> = VecDeque::new();
    while !stop.load(Ordering::Relaxed) {
        linger(&mut lingering);
        if !guard.ready() {
            std::thread::sleep(crate::transport::ACCEPT_BACKOFF / 4);
            continue;
        }
        let mut fds = [nix::poll::PollFd::new(
            listener.as_fd(),
            nix::poll::PollFlags::POLLIN,
        )];
        // Shorter while refused connections linger.
        let ms: u16 = if lingering.is_empty() { 100 } else { 10 };
        if nix::poll::poll(&mut fds, nix::poll::PollTimeout::from(ms)).unwrap_or(0) == 0 {
            continue;
        }
        let stream = match listener.accept() {
            Ok((s, _)) => s,
            Err(e) if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::Interrupted => {
                continue
            }
            Err(e) => {
                // EMFILE and the like (and anything else): pause, report
                // rate-limited, go on serving the connections there are.
                guard.failed(&e);
                continue;
            }
        };
        if active.fetch_add(1, Ordering::AcqRel) >= MAX_CONNECTIONS {
            active.fetch_sub(1, Ordering::AcqRel);
            if let Some(s) = refuse(stream) {
                if lingering.len() == MAX_LINGERING {
                    lingering.pop_front();
                }
                lingering.push_back((s, Instant::now() + LINGER));
            }
            continue;
        }
        let slot = Slot(Arc::clone(&active));
        let handler = Arc::clone(handler);
        let spawned = std::thread::Builder::new()
            .name("imu-emu-web-conn".into())
            .stack_size(THREAD_STACK)
            .spawn(move || {
                let _slot = slot;
                let mut s = stream;
                if s.set_nonblocking(false).is_err()
                    || s.set_write_timeout(Some(WRITE_WITHIN)).is_err()
                {
                    return;
                }
                let _ = s.set_nodelay(true);
                serve_connection(&mut s, handler.as_ref(), max_body);
            });
        if let Err(e) = spawned {
            // No thread to be had: the connection was moved into the
            // closure and dropped with it (closed), the slot given back.
            guard.failed(&e);
        }
    }
}

/// Refused connections kept (their input read and dropped) until the
/// client has read the `503` and closed, at most [`LINGER`]: closing one
/// with unread input would reset it, and the client could lose the answer.
const MAX_LINGERING: usize = 64;
/// How long a refused connection lingers.
const LINGER: Duration = Duration::from_secs(1);

/// Answers a connection beyond [`MAX_CONNECTIONS`] with `503` without
/// waiting on it (non-blocking: the answer is written if the socket takes
/// it now), its sending side shut; the connection, to linger.
fn refuse(mut s: TcpStream) -> Option<TcpStream> {
    s.set_nonblocking(true).ok()?;
    let r = plain(
        503,
        &format!("busy: at most {MAX_CONNECTIONS} connections at once; retry"),
    );
    let _ = write_response(&mut s, &r, false, true);
    let _ = s.shutdown(std::net::Shutdown::Write);
    Some(s)
}

/// Reads and drops what the lingering connections sent; closes those the
/// client closed and those past their time.
fn linger(lingering: &mut VecDeque<(TcpStream, Instant)>) {
    let now = Instant::now();
    let mut sink = [0u8; 4096];
    lingering.retain_mut(|(s, until)| {
        if now >= *until {
            return false;
        }
        for _ in 0..16 {
            match s.read(&mut sink) {
                Ok(0) => return false,
                Ok(_) => {}
                Err(e) => return e.kind() == ErrorKind::WouldBlock,
            }
        }
        true
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bytes in, bytes out; reads end at the input's end.
    struct Mem {
        input: Vec<u8>,
        at: usize,
        output: Vec<u8>,
    }

    impl Read for Mem {
        fn read(&mut self, b: &mut [u8]) -> std::io::Result<usize> {
            let n = b.len().min(self.input.len() - self.at).min(7);
            b[..n].copy_from_slice(&self.input[self.at..self.at + n]);
            self.at += n;
            Ok(n)
        }
    }
    impl Write for Mem {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.output.extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    impl Conn for Mem {
        fn set_read_limit(&mut self, _: Option<Duration>) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn serve(input: &[u8]) -> String {
        let mut m = Mem {
            input: input.to_vec(),
            at: 0,
            output: Vec::new(),
        };
        let h = |r: &Request| Response {
            status: 200,
            content_type: "text/plain",
            body: format!("{} {}", r.target, r.body.len()),
        };
        serve_connection(&mut m, &h, 256);
        String::from_utf8(m.output).unwrap()
    }

    #[test]
    fn pipelined_requests_are_answered_in_order_and_head_has_no_body() {
        let out = serve(
            b"GET /a HTTP/1.1\r\nHost: x\r\n\r\nHEAD /b HTTP/1.1\r\n\r\nPOST /c HTTP/1.1\r\n\
              Content-Length: 3\r\nConnection: close\r\n\r\nabc",
        );
        let answers: Vec<&str> = out.split("HTTP/1.1 ").skip(1).collect();
        assert_eq!(answers.len(), 3, "{out}");
        assert!(answers[0].ends_with("\r\n\r\n/a 0"), "{out}");
        assert!(answers[1].contains("Content-Length: 4\r\n") && answers[1].ends_with("\r\n\r\n"));
        assert!(answers[2].contains("Connection: close") && answers[2].ends_with("/c 3"));
    }

    #[test]
    fn huge_and_overflowing_lengths_are_refused_unread() {
        for len in [
            "1000000000000",
            "18446744073709551615",
            "99999999999999999999999",
        ] {
            let out = serve(format!("POST / HTTP/1.1\r\nContent-Length: {len}\r\n\r\n").as_bytes());
            assert!(out.starts_with("HTTP/1.1 413 "), "{out}");
        }
        let out = serve(b"POST / HTTP/1.1\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n");
        assert!(out.starts_with("HTTP/1.1 400 "), "{out}");
        let out = serve(b"POST / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n");
        assert!(out.starts_with("HTTP/1.1 411 "), "{out}");
    }

    #[test]
    fn heads_beyond_the_limits_are_refused() {
        let many: String = (0..40).map(|i| format!("X-{i}: y\r\n")).collect();
        let out = serve(format!("GET / HTTP/1.1\r\n{many}\r\n").as_bytes());
        assert!(out.starts_with("HTTP/1.1 431 "), "{out}");
        let long = "a".repeat(MAX_HEAD);
        let out = serve(format!("GET / HTTP/1.1\r\nX: {long}\r\n\r\n").as_bytes());
        assert!(out.starts_with("HTTP/1.1 431 "), "{out}");
        assert!(serve(b"BREW / HTTP/1.1\r\n\r\n").starts_with("HTTP/1.1 405 "));
        assert!(serve(b"\x00\x01 nonsense\r\n\r\n").starts_with("HTTP/1.1 400 "));
    }
}
