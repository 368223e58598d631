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
//! resynchronise), and counted in the title. Each protocol's samples come
//! from its tools ([`tool_protocol::ToolProtocol::imu_samples`]).

use std::path::Path;

use anyhow::{bail, Context as _};
use clap::ValueEnum as _;
use imu_emu::model::Product;

use super::deviation::{enough, Phases, Source, AXES};
use crate::client::tool_protocol;
use crate::protocol::Protocol;

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

impl Format {
    /// The protocol of a raw capture of this format: `kernel` and `isb`
    /// are the `--protocol` values ([`Protocol`]); `None` for a CSV (and
    /// for `auto`, decided from the content).
    fn capture(self) -> Option<Protocol> {
        let name = self.to_possible_value()?;
        Protocol::from_str(name.get_name(), false).ok()
    }
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
    let capture = match format {
        Format::Auto => detect(&bytes),
        f => f.capture(),
    };
    let Some(protocol) = capture else {
        return read_csv(path, rate);
    };
    let tools = tool_protocol::of(protocol);
    let samples = tools.imu_samples(&bytes, product);
    let Some(first) = samples.rows.first() else {
        bail!(
            "allan {}: no {} with gyro and accelerometer data",
            path.display(),
            tools.imu_frames()
        );
    };
    let channels = first.0.len();
    let times: Vec<f64> = samples.rows.iter().filter_map(|r| r.1).collect();
    let tau0 = median_step(&times).unwrap_or(1.0 / f64::from(rate.max(1)));
    let mut phases = Phases::new(tau0, samples.rows.len(), channels);
    for (y, _) in &samples.rows {
        phases.push(y);
    }
    enough(path, phases.n)?;
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

/// CSV (`None`) if the first line names `gyro_x` (a KERNEL's) or
/// `pqr_x` / `theta_x` (an IMX-5's); else the protocol with more valid
/// frames/packets in the first 64 KiB ([`Protocol::detect`]; text with
/// neither is a CSV, whose error names the column it lacks, anything else
/// the default protocol's bytes).
fn detect(bytes: &[u8]) -> Option<Protocol> {
    let head = &bytes[..bytes.len().min(1 << 16)];
    let first_line = head.split(|&b| b == b'\n').next().unwrap_or(&[]);
    if std::str::from_utf8(first_line).is_ok_and(|l| {
        l.split(',')
            .any(|c| matches!(c.trim(), "gyro_x" | "pqr_x" | "theta_x"))
    }) {
        return None;
    }
    match Protocol::detect(head) {
        Some(p) => Some(p),
        None if std::str::from_utf8(head).is_ok() => None,
        None => Some(Protocol::default()),
    }
}

/// Reads a CSV of `imu-emu client record` or `client decode`
/// (docs/sensors.md "Recordings"): a KERNEL's (`gyro_*` °/s, `acc_*` g,
/// `aux_acc_*` when all three are there) or an IMX-5's (a `did` column:
/// IMU, IMU_RAW, IMU_MAG `pqr_*` rad/s and `acc_*` m/s²; PIMU, PIMU_MAG
/// `theta_*` rad and `vel_*` m/s over `dt`, read as their means), in the
/// KERNEL's units. The sample period comes from device time
/// (`device_time_s`, else `imu_time_ns`), else host time
/// (`host_time_s`, with a warning: it carries the host's scheduling),
/// else `rate`.
pub(crate) fn read_csv(path: &Path, rate: u32) -> anyhow::Result<Source> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("allan {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .with_context(|| format!("allan {}: empty file", path.display()))?
        .split(',')
        .collect();
    let col = |name: &str| header.iter().position(|h| h.trim() == name);
    let need = |names: &[&str], what: &str| -> anyhow::Result<Vec<usize>> {
        names
            .iter()
            .map(|a| {
                col(a).with_context(|| format!("allan {}: no {a} column ({what})", path.display()))
            })
            .collect()
    };
    const RAD_S: [&str; 6] = ["pqr_x", "pqr_y", "pqr_z", "acc_x", "acc_y", "acc_z"];
    const DELTAS: [&str; 6] = ["theta_x", "theta_y", "theta_z", "vel_x", "vel_y", "vel_z"];
    let deg = 180.0 / std::f64::consts::PI;
    let g = f64::from(imu_emu::G);
    // Per column: its index and the factor to °/s or g; a PIMU's `dt`.
    let (cols, scale, dt, what): (Vec<usize>, Vec<f64>, Option<usize>, &str) =
        if col("did").is_some() {
            let isb = "an IMX-5 `client record --protocol isb` CSV of IMU or PIMU?";
            if col("pqr_x").is_some() {
                let c = need(&RAD_S, isb)?;
                (
                    c,
                    vec![deg, deg, deg, 1.0 / g, 1.0 / g, 1.0 / g],
                    None,
                    "ISB IMU",
                )
            } else {
                let c = need(&DELTAS, isb)?;
                let dt = need(&["dt"], isb)?[0];
                let s = vec![deg, deg, deg, 1.0 / g, 1.0 / g, 1.0 / g];
                (c, s, Some(dt), "ISB PIMU (Δθ/dt, Δv/dt)")
            }
        } else {
            let mut c = need(
                &AXES[..6],
                "a `client record` CSV of GA, GAm or UDD with gyro and acc, or an IMX-5's with pqr",
            )?;
            // The aux accelerometer too, when the recording has all three.
            let aux: Option<Vec<usize>> = AXES[6..].iter().map(|a| col(a)).collect();
            c.extend(aux.into_iter().flatten());
            let n = c.len();
            (c, vec![1.0; n], None, "KERNEL")
        };
    let rows: Vec<Vec<f64>> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let median_step = |c: usize, scale: f64| -> Option<f64> {
        let t: Vec<f64> = rows
            .iter()
            .filter_map(|r| Some(r.get(c)? * scale))
            .collect();
        median_step(&t)
    };
    let (tau0, clock) = if let Some(t) = col("device_time_s").and_then(|c| median_step(c, 1.0)) {
        (t, "device time")
    } else if let Some(t) = col("imu_time_ns").and_then(|c| median_step(c, 1e-9)) {
        (t, "device time")
    } else if let Some(t) = col("host_time_s").and_then(|c| median_step(c, 1.0)) {
        eprintln!(
            "imu-emu allan: warning: {}: no device time (device_time_s, imu_time_ns): the rate \
             comes from host_time_s, the host's arrival times",
            path.display()
        );
        (t, "host time")
    } else {
        (1.0 / f64::from(rate.max(1)), "--rate")
    };
    let mut phases = Phases::new(tau0, rows.len(), cols.len());
    let mut y = vec![0.0; cols.len()];
    for r in &rows {
        let per_s = dt.map_or(1.0, |c| 1.0 / r.get(c).copied().unwrap_or(f64::NAN));
        for ((v, &i), k) in y.iter_mut().zip(&cols).zip(&scale) {
            *v = r.get(i).copied().unwrap_or(f64::NAN) * k * per_s;
        }
        if y.iter().all(|v| v.is_finite()) {
            phases.push(&y);
        }
    }
    enough(path, phases.n)?;
    Ok(Source {
        title: format!(
            "{} ({what} CSV, {:.0} Hz from {clock})",
            path.display(),
            1.0 / tau0
        ),
        profile: None,
        phases,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_formats_are_the_protocols_they_name() {
        assert_eq!(Format::Kernel.capture(), Some(Protocol::Kernel));
        assert_eq!(Format::Isb.capture(), Some(Protocol::Isb));
        assert_eq!(Format::Csv.capture(), None);
        assert_eq!(Format::Auto.capture(), None);
    }

    #[test]
    fn content_tells_a_csv_from_a_capture() {
        assert_eq!(detect(b"frame,gyro_x,gyro_y\n1,2,3\n"), None);
        assert_eq!(detect(b"did,theta_x\n"), None);
        assert_eq!(detect(b"no columns here\n"), None);
        assert_eq!(detect(&[0xFF, 0x00, 0x13]), Some(Protocol::Kernel));
        let mut frame = [0u8; 64];
        let n = imu_emu::kernel::frame::encode(1, 0x8F, &[0; 10], &mut frame).unwrap();
        assert_eq!(detect(&frame[..n]), Some(Protocol::Kernel));
    }
}
