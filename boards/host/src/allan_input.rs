//! The recordings `imu-emu allan --input FILE` reads (docs/sensors.md
//! "Recordings"): the CSV of `imu-emu client record`, or a raw capture of
//! a unit's serial byte stream, told apart by their content (or named
//! with `--format`):
//!
//! - **KERNEL**: the bytes of its ICD frames (ICD 5.1 framing; the data
//!   formats of Tables 5.5–5.12 and the UDD of Tables 5.13–5.15), decoded
//!   with the core's frame decoder and typed payload decoder
//!   ([`crate::client::decode`]). The first data format with gyro and
//!   accelerometer values sets the stream (GA, GAm, GAA, GAAm, Orientation,
//!   Calibrated HR, or a UDD with gyro and acc types); frames of other
//!   formats are skipped. The sample period comes from the frames' own
//!   clock ([`crate::client::DeviceClock`]: the UDD's IMU time, else the
//!   2 kHz counter of GA and Calibrated HR), else `--rate`.
//! - **ISB**: the bytes of its packets (ISB protocol "Packet structure"):
//!   whole DATA packets of DID_IMU, DID_IMU_RAW or DID_IMU_MAG (`imu_t`:
//!   rad/s, m/s²), or of DID_PIMU / DID_PIMU_MAG (`pimu_t`: Δθ rad and
//!   Δv m/s over `dt`, read as their means Δθ/dt, Δv/dt), the first of
//!   them seen setting the stream; the sample period from the sets' own
//!   `time`.
//!
//! Bytes that are no valid frame or packet are skipped (the decoders
//! resynchronise), and counted in the title.

use std::path::Path;

use anyhow::{bail, Context as _};
use imu_emu::isb::packet::{Decoder as IsbDecoder, PacketType, MAX_PACKET};
use imu_emu::isb::{did, sets};
use imu_emu::kernel::frame::{Decoder as KernelDecoder, TYPE_DATA};
use imu_emu::model::Product;

use crate::allan::{Phases, Source, AXES};
use crate::client::decode::decode;
use crate::client::DeviceClock;

/// What `--input` holds (`--format`).
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// Decided from the content: a CSV with a `gyro_x` column, else the
    /// protocol whose frames or packets the first 64 KiB hold more of
    /// (text with neither: CSV).
    #[default]
    Auto,
    /// `imu-emu client record` CSV.
    Csv,
    /// Raw KERNEL byte stream (ICD frames).
    Kernel,
    /// Raw ISB byte stream (IMX-5 packets).
    Isb,
}

/// The product `--model` names: a KERNEL model or product code, or the
/// IMX-5.
pub fn product(model: &str) -> anyhow::Result<Product> {
    if model.eq_ignore_ascii_case("IMX-5") || model.eq_ignore_ascii_case("IMX5") {
        return Ok(Product::imx5());
    }
    Product::parse(model).map_err(|e| {
        crate::error::UsageError(format!("allan --model {model}: {e} (or IMX-5)")).into()
    })
}

/// Samples decoded from a raw capture: per sample the channels and the
/// device time (s) when the frames carry one.
struct Samples {
    rows: Vec<(Vec<f64>, Option<f64>)>,
    what: String,
}

/// Reads `path` as `format` (module doc); `product` gives the KG/KA
/// scales of a KERNEL capture's low-resolution fields (Table 5.6), `rate`
/// the sample rate when the frames carry no clock.
pub(crate) fn read(
    path: &Path,
    format: Format,
    product: &Product,
    rate: u32,
) -> anyhow::Result<Source> {
    let bytes = std::fs::read(path).with_context(|| format!("allan {}", path.display()))?;
    let format = match format {
        Format::Auto => detect(&bytes),
        f => f,
    };
    let samples = match format {
        Format::Csv | Format::Auto => return crate::allan::read_csv(path, rate),
        Format::Kernel => kernel(&bytes, product),
        Format::Isb => isb(&bytes),
    };
    let Some(first) = samples.rows.first() else {
        bail!(
            "allan {}: no {} with gyro and accelerometer data",
            path.display(),
            if format == Format::Isb {
                "IMU or PIMU packet"
            } else {
                "KERNEL data frame"
            }
        );
    };
    let channels = first.0.len();
    let times: Vec<f64> = samples.rows.iter().filter_map(|r| r.1).collect();
    let tau0 = median_step(&times).unwrap_or(1.0 / f64::from(rate.max(1)));
    let mut phases = Phases::new(tau0, samples.rows.len(), channels);
    for (y, _) in &samples.rows {
        phases.push(y);
    }
    crate::allan::enough(path, phases.n)?;
    Ok(Source {
        title: format!(
            "{} ({}, {:.0} Hz{})",
            path.display(),
            samples.what,
            1.0 / tau0,
            if times.is_empty() { ", --rate" } else { "" }
        ),
        profile: None,
        phases,
    })
}

/// The median of the positive steps of `t`.
pub fn median_step(t: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied()
}

/// CSV if the first line names `gyro_x` (a KERNEL's) or `pqr_x` /
/// `theta_x` (an IMX-5's); else the protocol with more valid
/// frames/packets in the first 64 KiB ([`crate::client::protocol_of`];
/// text with neither is a CSV).
fn detect(bytes: &[u8]) -> Format {
    use crate::cli::Protocol;
    let head = &bytes[..bytes.len().min(1 << 16)];
    let first_line = head.split(|&b| b == b'\n').next().unwrap_or(&[]);
    if std::str::from_utf8(first_line).is_ok_and(|l| {
        l.split(',')
            .any(|c| matches!(c.trim(), "gyro_x" | "pqr_x" | "theta_x"))
    }) {
        return Format::Csv;
    }
    match crate::client::protocol_of(head) {
        Some(Protocol::Isb) => Format::Isb,
        Some(Protocol::Kernel) => Format::Kernel,
        // Neither: text is read as a CSV (whose error names the column
        // it lacks), anything else as KERNEL bytes.
        None if std::str::from_utf8(head).is_ok() => Format::Csv,
        None => Format::Kernel,
    }
}

/// The KERNEL frames of `bytes` (module doc).
fn kernel(bytes: &[u8], product: &Product) -> Samples {
    let mut rx = Box::new(KernelDecoder::<4096>::new());
    let mut input = bytes;
    let mut stream: Option<(u8, usize)> = None;
    let mut clock = DeviceClock::default();
    let mut rows = Vec::new();
    let mut skipped = 0usize;
    while let Some(f) = rx.next_frame(&mut input) {
        let d = (f.msg_type == TYPE_DATA)
            .then(|| decode(f.id, f.payload, product))
            .flatten();
        let Some(d) = d else {
            skipped += 1;
            continue;
        };
        // Gyro and acc, and the aux accelerometer when the format has it.
        let has = |names: &[&str]| names.iter().all(|n| d.get(n).is_some());
        if stream.is_none() && has(&AXES[..6]) {
            stream = Some((f.id, if has(&AXES) { 9 } else { 6 }));
        }
        let Some((_, channels)) = stream.filter(|s| s.0 == f.id) else {
            skipped += 1;
            continue;
        };
        if !has(&AXES[..channels]) {
            skipped += 1;
            continue;
        }
        let y = AXES[..channels]
            .iter()
            .map(|n| d.get(n).unwrap_or(0.0))
            .collect();
        rows.push((y, clock.time(&d)));
    }
    let name = stream.map_or("none".to_owned(), |(id, _)| {
        imu_emu::kernel::formats::find(id).map_or_else(|| "UDD".to_owned(), |f| f.name.to_owned())
    });
    Samples {
        rows,
        what: format!("KERNEL {name} frames, {skipped} other frames skipped"),
    }
}

/// The ISB packets of `bytes` (module doc).
fn isb(bytes: &[u8]) -> Samples {
    let mut rx = Box::new(IsbDecoder::<MAX_PACKET>::new());
    let mut input = bytes;
    let mut stream: Option<u8> = None;
    let mut rows = Vec::new();
    let mut skipped = 0usize;
    let deg = 180.0 / std::f64::consts::PI;
    let g = f64::from(imu_emu::G);
    while let Some(p) = rx.next_packet(&mut input) {
        // A data set from its start (with or without the offset flag).
        let data = (p.kind() == Some(PacketType::Data))
            .then(|| p.offset_and_data())
            .flatten()
            .filter(|d| d.0 == 0)
            .map_or(&[][..], |d| d.1);
        let row = match p.did {
            did::IMU | did::IMU_RAW | did::IMU_MAG => data
                .get(..sets::imu::SIZE)
                .and_then(|b| b.try_into().ok())
                .map(|b| {
                    let s = sets::Imu::decode(b);
                    let y = [s.pqr, s.acc];
                    (y, 1.0, s.time)
                }),
            did::PIMU | did::PIMU_MAG => data
                .get(..sets::pimu::SIZE)
                .and_then(|b| b.try_into().ok())
                .map(|b| {
                    let s = sets::Pimu::decode(b);
                    ([s.theta, s.vel], 1.0 / f64::from(s.dt), s.time)
                })
                .filter(|r| r.1.is_finite() && r.1 > 0.0),
            _ => None,
        };
        let Some(([w, a], per_s, time)) = row else {
            skipped += 1;
            continue;
        };
        if *stream.get_or_insert(p.did) != p.did {
            skipped += 1;
            continue;
        }
        let y = w
            .iter()
            .map(|v| f64::from(*v) * per_s * deg)
            .chain(a.iter().map(|v| f64::from(*v) * per_s / g))
            .collect();
        rows.push((y, Some(time)));
    }
    let name = match stream {
        Some(did::PIMU | did::PIMU_MAG) => "PIMU (Δθ/dt, Δv/dt)",
        Some(_) => "IMU",
        None => "no IMU",
    };
    Samples {
        rows,
        what: format!("ISB {name} packets, {skipped} other packets skipped"),
    }
}
