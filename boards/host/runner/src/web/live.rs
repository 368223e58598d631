//! The web view's live decoding, one decoder per protocol: what the web
//! thread makes of the bytes a unit sent — each frame's stream, its own
//! clock and its named values — before [`super`] puts it on the device
//! clock. The values come from the client's decoders
//! ([`imu_emu_tools::client::decode`], [`imu_emu_tools::client::isb`]);
//! which decoder a hub runs is the protocol's
//! (`crate::protocol::HostProtocol::live`), so the web view names no
//! protocol.

use imu_emu::kernel::frame::{Decoder as KernelDecoder, TYPE_DATA};
use imu_emu::model::Product;
use imu_emu_tools::client;
use imu_emu_tools::protocol::Protocol;

/// The KERNEL's computation counter rate (ICD Tables 5.7, 5.10 note 3).
pub const COUNTER_HZ: f64 = 2000.0;
/// A GPS week, s.
pub const WEEK_S: f64 = 604_800.0;

/// A frame's own clock: its value (s) and the period it wraps at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Own {
    /// The clock's value, s.
    pub value: f64,
    /// The period it wraps at, s (`None`: it does not wrap).
    pub wrap: Option<f64>,
}

/// One decoded output frame, before it is put on the device clock.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Its stream, timed as one: the KERNEL's frame ID, the ISB's data set
    /// ID + 256.
    pub stream: u16,
    /// Its own clock, if it carries one.
    pub own: Option<Own>,
    /// Its own clock is GPS time of week (gives the GPS time of device
    /// time 0).
    pub gps: bool,
    /// Without a clock of its own, it is timed by the stream's known
    /// output rate (the status's `output-rate`; a KERNEL stream), else
    /// placed at its stamp (an ISB set's period is its own).
    pub rated: bool,
    /// The ISB data set it came from (field names repeat across sets).
    pub set: Option<&'static str>,
    /// Named values, in physical units.
    pub values: Vec<(String, f64)>,
}

/// A protocol's decoder of a unit's output, fed the bytes as they left
/// the line.
pub trait LiveDecoder: Send {
    /// Decodes `chunk` (the next bytes of the stream) of a `product`,
    /// pushing each whole frame to `out`.
    fn decode(&mut self, chunk: &[u8], product: &Product, out: &mut Vec<Frame>);
}

/// What a hub decodes: the protocol (named in `/api/devices`) and a new
/// decoder for each device's view.
#[derive(Debug, Clone, Copy)]
pub struct Live {
    /// The protocol.
    pub protocol: Protocol,
    /// A decoder in its initial state.
    pub decoder: fn() -> Box<dyn LiveDecoder>,
}

/// The KERNEL's output frames (Tables 5.5–5.15) through the client's
/// named columns.
pub struct KernelLive(Box<KernelDecoder<4096>>);

impl Default for KernelLive {
    fn default() -> Self {
        KernelLive(Box::new(KernelDecoder::new()))
    }
}

impl LiveDecoder for KernelLive {
    fn decode(&mut self, mut input: &[u8], product: &Product, out: &mut Vec<Frame>) {
        while let Some(f) = self.0.next_frame(&mut input) {
            if f.msg_type != TYPE_DATA {
                continue;
            }
            let Some(d) = client::decode::decode(f.id, f.payload, product) else {
                continue;
            };
            let own = match (d.get("imu_time_ns"), d.get("counter")) {
                (Some(ns), _) => Some(Own {
                    value: ns * 1e-9,
                    wrap: None,
                }),
                (None, Some(c)) => Some(Own {
                    value: c / COUNTER_HZ,
                    wrap: Some(65_536.0 / COUNTER_HZ),
                }),
                _ => None,
            };
            out.push(Frame {
                stream: u16::from(f.id),
                own,
                gps: false,
                rated: true,
                set: None,
                values: d
                    .values
                    .iter()
                    .map(|(k, v)| ((*k).to_owned(), *v))
                    .collect(),
            });
        }
    }
}

/// An IMX-5's ISB data sets, by field name.
pub struct IsbLive(Box<imu_emu::isb::packet::Decoder<{ imu_emu::isb::packet::MAX_PACKET }>>);

impl Default for IsbLive {
    fn default() -> Self {
        IsbLive(Box::new(imu_emu::isb::packet::Decoder::new()))
    }
}

impl LiveDecoder for IsbLive {
    fn decode(&mut self, mut input: &[u8], _product: &Product, out: &mut Vec<Frame>) {
        while let Some(p) = self.0.next_packet(&mut input) {
            let p = client::isb::Packet {
                flags: p.flags,
                did: p.did,
                payload: p.payload.to_vec(),
            };
            let Some((did, b)) = p.whole_set() else {
                continue;
            };
            let gps = gps_timed(did);
            let own = imu_emu::isb::did::device_time(did, b).map(|value| Own {
                value,
                wrap: gps.then_some(WEEK_S),
            });
            out.push(Frame {
                stream: 256 + u16::from(did),
                own,
                gps,
                rated: false,
                set: imu_emu::isb::did::set(did).map(|(name, _)| name),
                values: client::isb::numbers(did, b),
            });
        }
    }
}

/// Whether an ISB data set's time ([`imu_emu::isb::did::device_time`])
/// is GPS time of week: the set has a `timeOfWeek` or `timeOfWeekMs`
/// field (the others count seconds since boot, `time`).
fn gps_timed(did: u8) -> bool {
    imu_emu::isb::did::set(did)
        .is_some_and(|(_, fields)| fields.iter().any(|f| f.name.starts_with("timeOfWeek")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A K110's GA stream (0x8F, Table 5.8), through the virtual device:
    /// frames of one stream, timed by their 2 kHz counter (which wraps),
    /// with the client's column names.
    #[test]
    fn kernel_ga_frames_carry_their_counter_and_columns() {
        use std::io::{Read as _, Write as _};
        let product = Product::parse("K110").unwrap();
        let mut dev = crate::virtual_device::VirtualDevice::new(product);
        let mut cmd = [0u8; 16];
        let n = imu_emu::kernel::command::Command::Data(0x8F)
            .encode(&mut cmd)
            .unwrap();
        dev.write_all(&cmd[..n]).unwrap();
        dev.advance(200_000_000);
        let mut bytes = vec![0u8; dev.pending()];
        dev.read_exact(&mut bytes).unwrap();
        let mut frames = Vec::new();
        KernelLive::default().decode(&bytes, &product, &mut frames);
        assert!(frames.len() >= 10, "{} frames", frames.len());
        for f in &frames {
            assert_eq!((f.stream, f.gps, f.rated, f.set), (0x8F, false, true, None));
            let own = f.own.expect("GA carries the counter");
            assert_eq!(own.wrap, Some(65_536.0 / COUNTER_HZ));
            assert!(
                f.values.iter().any(|(k, _)| k == "gyro_x"),
                "{:?}",
                f.values
            );
        }
    }

    #[test]
    fn the_gps_timed_sets_are_those_with_a_time_of_week() {
        use imu_emu::isb::did;
        for d in [
            did::INS_1,
            did::INS_2,
            did::GPS1_POS,
            did::GPS1_VEL,
            did::SYS_PARAMS,
        ] {
            assert!(gps_timed(d), "{d}");
        }
        for d in [did::IMU, did::PIMU, did::MAGNETOMETER, did::BAROMETER] {
            assert!(!gps_timed(d), "{d}");
        }
    }
}
