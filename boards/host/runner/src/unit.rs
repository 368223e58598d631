//! Units run in process for `imu-emu allan` (its [`Unit`]): no line, no
//! transport, no clock — device time moves tick by tick as fast as the
//! host computes, and the output is read as it is produced. Which run a
//! unit gets is its protocol's ([`crate::protocol::HostProtocol::run_unit`]):
//!
//! * [`kernel_frames`] — a KERNEL `Device` streaming GA frames at the
//!   unit's rate with the average output variant (on a model with an aux
//!   accelerometer a UDD of gyro, acc and aux acc), the frames decoded with
//!   the client's typed decoder;
//! * [`chain_averaged`] — the IMX-5's signal chain averaged over each
//!   output interval (what its IMU message carries).

use anyhow::Context as _;
use imu_emu::device::{Device, PowerOn};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::formats::UDD;
use imu_emu::kernel::frame::{Decoder, TYPE_DATA};
use imu_emu::kernel::Kernel;
use imu_emu::time::Instant;
use imu_emu::{ChainConfig, OutputVariant, SignalChain};
use imu_emu_tools::allan::deviation::AXES;
use imu_emu_tools::allan::Unit;

use crate::flash::MemNor;

/// UDD types of the aux-carrying stream (ICD Table 5.14): gyro HR, acc
/// HR, aux accelerometer.
const AUX_UDD: [u8; 3] = [0x21, 0x23, 0x2F];

/// Format code of GA (ICD Table 5.8).
const GA: u8 = 0x8F;

/// A KERNEL device streaming at `unit.rate`: `unit.outputs` frames
/// decoded, each frame's channels to `sample`. GA (gyro and acc), or with
/// `unit.aux` a UDD of `AUX_UDD` (GA does not carry the aux
/// accelerometer). The flash is in memory (the runner's size) and nothing
/// is kept after the run.
pub fn kernel_frames(unit: &Unit, sample: &mut dyn FnMut(&[f64])) -> anyhow::Result<String> {
    let product = unit.product;
    let cfg = PowerOn {
        product,
        boot: None,
        seed: unit.seed,
    };
    let mut dev =
        Device::<MemNor, Kernel>::with_profile(cfg, unit.profile, MemNor::new(), Instant::ZERO);
    dev.chain_mut().faults_mut().temperature_c = unit.temperature_c;
    let period = dev.tick_period_ns();
    let mut now = 0u64;
    // Data_Rate (Table 5.24 ID 0x0012) and Output_Variant average (ID
    // 0x03D0 = 1), then the UDD list (5.3.5) and the data command: the
    // rate applies at the data command (5.3.1). In process the line is
    // not paced (that is a board's job), so any rate fits. The average,
    // as a datasheet's figures are read: the factory Instant variant
    // samples the FIR's output and aliases its band's noise into the
    // output's (its ARW reads higher: docs/sensors.md "Decimation").
    let rate = u16::try_from(unit.rate).context("allan --rate: at most 65535")?;
    let format = if unit.aux { UDD } else { GA };
    let udd = [AUX_UDD.len() as u8, AUX_UDD[0], AUX_UDD[1], AUX_UDD[2]];
    let rate = rate.to_le_bytes();
    let mut cmds = vec![
        Command::SaveFlash {
            id: 0x0012,
            len: 2,
            value: &rate,
        },
        Command::SaveFlash {
            id: 0x03D0,
            len: 1,
            value: &[1],
        },
    ];
    if unit.aux {
        cmds.extend([Command::UddConfig, Command::UddConfigMessage(&udd)]);
    }
    cmds.push(Command::Data(format));
    let mut cmd = [0u8; 64];
    for c in cmds {
        let n = c.encode(&mut cmd).context("encoding a command")?;
        dev.on_rx(&cmd[..n], Instant::from_nanos(now));
    }
    let mut buf = vec![0u8; 4096];
    let mut rx = Box::new(Decoder::<512>::new());
    let mut got = 0usize;
    let mut y = vec![0.0; unit.channels()];
    while got < unit.outputs {
        now += period;
        dev.on_tick(Instant::from_nanos(now));
        loop {
            let n = dev.poll_tx(&mut buf);
            if n == 0 {
                break;
            }
            let mut input = &buf[..n];
            while let Some(f) = rx.next_frame(&mut input) {
                if f.msg_type != TYPE_DATA || f.id != format || got == unit.outputs {
                    continue;
                }
                let Some(d) = imu_emu_tools::client::decode::decode(f.id, f.payload, &product)
                else {
                    continue;
                };
                for (v, name) in y.iter_mut().zip(AXES) {
                    *v = d.get(name).unwrap_or(0.0);
                }
                sample(&y);
                got += 1;
            }
        }
    }
    Ok(format!(
        "{}, seed {}, {} frames at {} Hz, average variant",
        product.code(),
        unit.seed,
        if unit.aux {
            "UDD (gyro, acc, aux acc)"
        } else {
            "GA"
        },
        unit.rate
    ))
}

/// The unit's signal chain, averaged over each output interval
/// (`OutputVariant::Average`): `unit.outputs` samples of gyro and acc to
/// `sample`, with no personality (what an IMX-5's IMU message carries).
pub fn chain_averaged(unit: &Unit, sample: &mut dyn FnMut(&[f64])) -> anyhow::Result<String> {
    let product = unit.product;
    let mut chain = SignalChain::new(product, unit.seed);
    chain.set_profile(unit.profile);
    chain.reset(product, unit.seed);
    chain.faults_mut().temperature_c = unit.temperature_c;
    let mut cfg = ChainConfig::defaults(&product);
    cfg.output_variant = OutputVariant::Average;
    chain.configure(&cfg);
    let internal = product.model.internal_rate_hz;
    let every = internal / unit.rate;
    let dt_ns = 1_000_000_000 / u64::from(internal);
    let mut t = 0u64;
    for _ in 0..unit.outputs {
        for _ in 0..every {
            t += dt_ns;
            chain.tick(Instant::from_nanos(t));
        }
        let s = chain.output_with(false);
        let g = s.gyro.map(f64::from);
        let f = s.acc.map(f64::from);
        sample(&[g[0], g[1], g[2], f[0], f[1], f[2]]);
    }
    Ok(format!(
        "IMX-5, seed {}, chain averaged at {} Hz",
        unit.seed, unit.rate
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_emu::model::Product;
    use imu_emu_tools::protocol::Protocol;

    fn unit(protocol: Protocol, product: Product, aux: bool) -> Unit {
        Unit {
            protocol,
            product,
            seed: 3,
            profile: None,
            temperature_c: Some(25.0),
            rate: 100,
            outputs: 50,
            aux,
        }
    }

    /// Every output asked for, each of the unit's channels, at rest: the
    /// gyro near 0 °/s and the acc near 1 g on one axis.
    fn at_rest(u: &Unit, run: imu_emu_tools::allan::RunUnit<'_>) {
        let mut rows = Vec::new();
        run(u, &mut |y| rows.push(y.to_vec())).unwrap();
        assert_eq!(rows.len(), u.outputs);
        for y in &rows {
            assert_eq!(y.len(), u.channels());
            assert!(y[..3].iter().all(|w| w.abs() < 1.0), "{y:?}");
            let g: f64 = y[3..6].iter().map(|a| a * a).sum::<f64>().sqrt();
            assert!((g - 1.0).abs() < 0.05, "{y:?}");
        }
    }

    #[test]
    fn a_kernel_with_an_aux_accelerometer_streams_nine_channels() {
        let u = unit(Protocol::Kernel, Product::parse("K120").unwrap(), true);
        at_rest(&u, &kernel_frames);
        let title = kernel_frames(&u, &mut |_| {}).unwrap();
        assert!(
            title.contains("UDD (gyro, acc, aux acc) frames at 100 Hz"),
            "{title}"
        );
        let u = unit(Protocol::Kernel, Product::parse("K110").unwrap(), false);
        at_rest(&u, &kernel_frames);
    }

    #[test]
    fn an_imx_chain_averaged_gives_six_channels() {
        let u = unit(Protocol::Isb, Product::imx5(), false);
        at_rest(&u, &chain_averaged);
        assert_eq!(
            chain_averaged(&u, &mut |_| {}).unwrap(),
            "IMX-5, seed 3, chain averaged at 100 Hz"
        );
    }
}
