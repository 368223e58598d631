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
//! | `fault comm\|config\|gyro-bit\|accel-bit\|flash on\|off` | inject a sensor fault (USW bits 1–2, GetBIT) |
//! | `fault temperature <°C>\|off` | force the sensor temperature (USW bit 14 outside −40…85 °C) |
//! | `motion static [lat heading]` | the unit at rest (default 45° N, heading 0) |
//! | `motion rotate <x> <y> <z>` | constant body rate, deg/s (USW bits 10–12 beyond the range) |
//!
//! The device's TOV output (4.1.4) is reported to the client as lines
//! `tov high <ns>` / `tov low <ns>` (ns since the program started), in the
//! order the device produces them.

use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};

use anyhow::Context as _;
use imu_emu::chain::Faults;
use imu_emu::device::{Level, Pin};
use imu_emu::sensor::Motion;

/// A parsed control command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// A pin edge now.
    Edge(Pin, Level),
    /// Power cycle with BOOT at a level (`None` = floating).
    PowerCycle(Option<Level>),
    /// Change the injected faults.
    Fault(FaultChange),
    /// Change the motion the unit undergoes.
    Motion(Motion),
}

/// One change to [`Faults`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultChange {
    /// Sensor communication failure on/off.
    Comm(bool),
    /// Sensor configuration failure on/off.
    Config(bool),
    /// Gyro BIT failure on/off.
    GyroBit(bool),
    /// Accelerometer BIT failure on/off.
    AccelBit(bool),
    /// Flash check failure on/off.
    Flash(bool),
    /// Forced temperature, °C, or `None` for the model's own.
    Temperature(Option<f32>),
}

impl FaultChange {
    /// Applies the change.
    pub fn apply(self, f: &mut Faults) {
        match self {
            FaultChange::Comm(on) => f.sensor_comm = on,
            FaultChange::Config(on) => f.sensor_config = on,
            FaultChange::GyroBit(on) => f.gyro_bit = on,
            FaultChange::AccelBit(on) => f.accel_bit = on,
            FaultChange::Flash(on) => f.flash_check = on,
            FaultChange::Temperature(t) => f.temperature_c = t,
        }
    }
}

fn on_off(w: &str) -> Result<bool, String> {
    match w {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected on or off, got {w}")),
    }
}

fn number(w: &str) -> Result<f32, String> {
    w.parse::<f32>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("not a number: {w}"))
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
        ["fault", "temperature", "off"] => Ok(Command::Fault(FaultChange::Temperature(None))),
        ["fault", "temperature", t] => {
            Ok(Command::Fault(FaultChange::Temperature(Some(number(t)?))))
        }
        ["fault", which, state] => {
            let on = on_off(state)?;
            Ok(Command::Fault(match *which {
                "comm" => FaultChange::Comm(on),
                "config" => FaultChange::Config(on),
                "gyro-bit" => FaultChange::GyroBit(on),
                "accel-bit" => FaultChange::AccelBit(on),
                "flash" => FaultChange::Flash(on),
                _ => return Err(format!("unknown fault: {which}")),
            }))
        }
        ["motion", "static"] => Ok(Command::Motion(Motion::Static {
            lat_deg: 45.0,
            heading_deg: 0.0,
        })),
        ["motion", "static", lat, heading] => Ok(Command::Motion(Motion::Static {
            lat_deg: number(lat)?,
            heading_deg: number(heading)?,
        })),
        ["motion", "rotate", x, y, z] => Ok(Command::Motion(Motion::ConstantRotation {
            lat_deg: 45.0,
            heading_deg: 0.0,
            rate_dps: [number(x)?, number(y)?, number(z)?],
        })),
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
        assert_eq!(
            parse("fault comm on"),
            Ok(Command::Fault(FaultChange::Comm(true)))
        );
        assert_eq!(
            parse("fault temperature 95.5"),
            Ok(Command::Fault(FaultChange::Temperature(Some(95.5))))
        );
        assert_eq!(
            parse("fault temperature off"),
            Ok(Command::Fault(FaultChange::Temperature(None)))
        );
        assert!(parse("fault comm maybe").is_err());
        assert!(parse("fault temperature NaN").is_err());
        assert!(matches!(
            parse("motion rotate 0 600 0"),
            Ok(Command::Motion(Motion::ConstantRotation { .. }))
        ));
        assert!(parse("motion rotate 0 x 0").is_err());
    }
}
