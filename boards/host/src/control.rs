//! The control socket: what a test rig does to the device's other pins.
//!
//! `--control ADDR` listens on TCP (one client at a time, a new one replaces
//! the old). The protocol is text, one command per line, each answered with
//! `ok` or `error <why>`:
//!
//! | line | effect |
//! |---|---|
//! | `pps` | a 1PPS rising edge now (ICD 5.2.3.1) |
//! | `extrig high` / `extrig low` | the EXTRIG input changes level now (4.1.3) |
//! | `power-cycle [boot=high\|boot=low]` | power cycle, BOOT at that level (or floating) |
//!
//! The device's TOV output (4.1.4) is reported to the client as lines
//! `tov high <ns>` / `tov low <ns>` (ns since the program started), in the
//! order the device produces them.

use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};

use anyhow::Context as _;
use imu_emu::device::{Level, Pin};

/// A parsed control command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// A pin edge now.
    Edge(Pin, Level),
    /// Power cycle with BOOT at a level (`None` = floating).
    PowerCycle(Option<Level>),
}

/// Parses one line of the control protocol.
pub fn parse(line: &str) -> Result<Command, String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["pps"] => Ok(Command::Edge(Pin::Pps, Level::High)),
        ["extrig", "high"] => Ok(Command::Edge(Pin::Extrig, Level::High)),
        ["extrig", "low"] => Ok(Command::Edge(Pin::Extrig, Level::Low)),
        ["power-cycle"] => Ok(Command::PowerCycle(None)),
        ["power-cycle", "boot=high"] => Ok(Command::PowerCycle(Some(Level::High))),
        ["power-cycle", "boot=low"] => Ok(Command::PowerCycle(Some(Level::Low))),
        _ => Err(format!("unknown command: {line}")),
    }
}

/// The control listener and its client.
pub struct Control {
    listener: TcpListener,
    client: Option<TcpStream>,
    line: Vec<u8>,
}

impl Control {
    /// Listens on `addr`.
    pub fn bind(addr: &str) -> anyhow::Result<Self> {
        let listener =
            TcpListener::bind(addr).with_context(|| format!("binding control {addr}"))?;
        listener.set_nonblocking(true)?;
        Ok(Control {
            listener,
            client: None,
            line: Vec::new(),
        })
    }

    /// The bound address.
    pub fn local_addr(&self) -> anyhow::Result<std::net::SocketAddr> {
        Ok(self.listener.local_addr()?)
    }

    /// Accepts a new client and reads complete command lines; each is
    /// handed to `apply`, whose answer goes back to the client. Never blocks.
    pub fn poll(
        &mut self,
        apply: &mut dyn FnMut(Command) -> Result<(), String>,
    ) -> anyhow::Result<()> {
        match self.listener.accept() {
            Ok((s, _)) => {
                s.set_nonblocking(true)?;
                s.set_nodelay(true)?;
                self.client = Some(s);
                self.line.clear();
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            Err(e) => return Err(e.into()),
        }
        let Some(client) = self.client.as_mut() else {
            return Ok(());
        };
        let mut buf = [0u8; 256];
        loop {
            match client.read(&mut buf) {
                Ok(0) => {
                    self.client = None;
                    return Ok(());
                }
                Ok(n) => self.line.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(_) => {
                    self.client = None;
                    return Ok(());
                }
            }
        }
        while let Some(end) = self.line.iter().position(|&b| b == b'\n') {
            let raw: Vec<u8> = self.line.drain(..=end).collect();
            let text = String::from_utf8_lossy(&raw);
            let text = text.trim();
            if text.is_empty() {
                continue;
            }
            let answer = match parse(text).and_then(&mut *apply) {
                Ok(()) => "ok\n".to_owned(),
                Err(e) => format!("error {e}\n"),
            };
            self.say(&answer);
        }
        Ok(())
    }

    /// Sends a line to the client, if one is connected (best effort: a
    /// client that does not read loses lines rather than stalling the device).
    pub fn say(&mut self, line: &str) {
        if let Some(c) = self.client.as_mut() {
            if c.write_all(line.as_bytes()).is_err() {
                self.client = None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_protocol() {
        assert_eq!(parse("pps"), Ok(Command::Edge(Pin::Pps, Level::High)));
        assert_eq!(
            parse(" extrig  low "),
            Ok(Command::Edge(Pin::Extrig, Level::Low))
        );
        assert_eq!(
            parse("power-cycle boot=high"),
            Ok(Command::PowerCycle(Some(Level::High)))
        );
        assert_eq!(parse("power-cycle"), Ok(Command::PowerCycle(None)));
        assert!(parse("extrig sideways").is_err());
    }
}
