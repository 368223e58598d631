//! What the tools ask of a protocol: one trait, [`ToolProtocol`],
//! implemented for the KERNEL ([`KernelTools`]) and the IMX-5's ISB
//! ([`IsbTools`]), so that the client and `imu-emu allan` name no protocol
//! and match on none. The choice itself ([`Protocol`], `--protocol`, or a
//! capture's [`Protocol::detect`]) is the lowest module's; [`of`] turns it
//! into the protocol's tools, the one place it is matched in this crate.
//!
//! This is the line side of a protocol (a host reading a unit). Its
//! device side — what the runner needs to serve a unit (packet rules,
//! input monitor, live decoder, factory rate, the unit `allan` runs) — is
//! the runner's `HostProtocol`, implemented on the personality types;
//! both are keyed by the same [`Protocol`] value. A third protocol is one
//! more impl here and one there.

use std::io::Write;
use std::path::{Path, PathBuf};

use imu_emu::model::Product;

use super::{ClientArgs, OutFormat};
use crate::protocol::Protocol;

/// A raw capture `client decode` reads, with what was asked of it.
pub struct Capture<'a> {
    /// Its path (for messages).
    pub file: &'a Path,
    /// Its bytes, from the start.
    pub src: &'a mut dyn std::io::Read,
    /// Whether it held no byte at all.
    pub empty: bool,
    /// Whether its protocol was detected from its bytes rather than
    /// given (`--protocol`).
    pub detected: bool,
    /// `--out` (default or `-`: stdout).
    pub out: Option<&'a PathBuf>,
    /// `--to`.
    pub to: OutFormat,
    /// `--did` (ISB only).
    pub did: Option<&'a str>,
    /// `--rate` (KERNEL only: frames without a clock).
    pub rate: Option<f64>,
}

/// The IMU samples of a raw capture (`imu-emu allan --input`): per sample
/// gyro X Y Z (°/s), acc X Y Z (g) and, when the stream carries it, the
/// aux accelerometer X Y Z (g) — the first 6 or 9 of
/// [`super::decode::AXES`] — with the device time (s) its frame carries.
pub struct ImuSamples {
    /// The samples and their device times.
    pub rows: Vec<(Vec<f64>, Option<f64>)>,
    /// What was read: the stream and what was skipped.
    pub what: String,
}

/// What the tools need of a protocol (module doc).
pub trait ToolProtocol: Sync {
    /// Its `--protocol` value.
    fn protocol(&self) -> Protocol;

    /// Whether `product` is a unit of this protocol.
    fn speaks(&self, product: &Product) -> bool;

    /// `imu-emu client CMD` over a live line: every command but `decode`
    /// and `plot` (which read files); a command of the other protocol is a
    /// usage error before the line is opened.
    fn client(
        &self,
        args: &ClientArgs,
        out: &mut dyn Write,
        stop: &dyn Fn() -> bool,
    ) -> anyhow::Result<()>;

    /// `imu-emu client decode`: a raw capture's data frames as rows.
    fn decode(&self, args: &ClientArgs, capture: Capture<'_>) -> anyhow::Result<()>;

    /// The IMU samples of a raw capture; `product` gives the scales of
    /// fields that depend on the unit's ranges.
    fn imu_samples(&self, bytes: &[u8], product: &Product) -> ImuSamples;

    /// The frames [`ToolProtocol::imu_samples`] reads, for the error when
    /// a capture has none.
    fn imu_frames(&self) -> &'static str;
}

/// The tools of the Inertial Labs KERNEL (ICD rev 1.42).
pub struct KernelTools;

/// The tools of the Inertial Sense IMX-5 over ISB (protocol 2.1).
pub struct IsbTools;

/// The tools of protocol `p`.
pub fn of(p: Protocol) -> &'static dyn ToolProtocol {
    match p {
        Protocol::Kernel => &KernelTools,
        Protocol::Isb => &IsbTools,
    }
}

/// The tools of the protocol `product` speaks (a KERNEL model, or the
/// IMX-5).
pub fn of_product(product: &Product) -> &'static dyn ToolProtocol {
    if IsbTools.speaks(product) {
        &IsbTools
    } else {
        &KernelTools
    }
}

impl ToolProtocol for KernelTools {
    fn protocol(&self) -> Protocol {
        Protocol::Kernel
    }

    /// A row of the KERNEL's model table.
    fn speaks(&self, product: &Product) -> bool {
        imu_emu::kernel::MODELS
            .iter()
            .any(|m| core::ptr::eq(&m.model, product.model))
    }

    fn client(
        &self,
        args: &ClientArgs,
        out: &mut dyn Write,
        stop: &dyn Fn() -> bool,
    ) -> anyhow::Result<()> {
        super::run_kernel(args, out, stop)
    }

    fn decode(&self, args: &ClientArgs, capture: Capture<'_>) -> anyhow::Result<()> {
        super::decode_kernel(args, capture)
    }

    fn imu_samples(&self, bytes: &[u8], product: &Product) -> ImuSamples {
        super::decode::imu_samples(bytes, product)
    }

    fn imu_frames(&self) -> &'static str {
        "KERNEL data frame"
    }
}

impl ToolProtocol for IsbTools {
    fn protocol(&self) -> Protocol {
        Protocol::Isb
    }

    /// The IMX-5.
    fn speaks(&self, product: &Product) -> bool {
        core::ptr::eq(product.model, &imu_emu::isb::IMX5)
    }

    fn client(
        &self,
        args: &ClientArgs,
        out: &mut dyn Write,
        stop: &dyn Fn() -> bool,
    ) -> anyhow::Result<()> {
        super::isb::run(args, out, stop)
    }

    fn decode(&self, _args: &ClientArgs, capture: Capture<'_>) -> anyhow::Result<()> {
        super::isb::decode_capture(capture)
    }

    /// An IMX-5's sets carry SI units whatever its ranges.
    fn imu_samples(&self, bytes: &[u8], _product: &Product) -> ImuSamples {
        super::isb::imu_samples(bytes)
    }

    fn imu_frames(&self) -> &'static str {
        "IMU or PIMU packet"
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum as _;

    #[test]
    fn each_protocol_has_its_tools() {
        for &p in Protocol::value_variants() {
            assert_eq!(of(p).protocol(), p);
        }
    }

    #[test]
    fn a_product_speaks_one_protocol() {
        let imx = Product::imx5();
        assert_eq!(of_product(&imx).protocol(), Protocol::Isb);
        assert!(!KernelTools.speaks(&imx));
        for m in imu_emu::kernel::MODELS {
            let k = Product::parse(m.model.short).unwrap();
            assert_eq!(
                of_product(&k).protocol(),
                Protocol::Kernel,
                "{}",
                m.model.short
            );
            assert!(!IsbTools.speaks(&k));
        }
    }
}
