//! `imu-emu allan`: the overlapping Allan deviation of each axis of a
//! unit's output, the noise terms fitted to it beside its profile's, and a
//! log-log plot (docs/sensors.md).
//!
//! The data come either from a unit run **in process** as fast as the host
//! computes (no TCP): a KERNEL `Device` streaming GA frames at `--rate`
//! with the average output variant (on the K120/K220 a UDD with the aux
//! accelerometer; the frames decoded with the core's typed decoder,
//! `client::decode`), or, for `--model
//! IMX-5`, its signal chain averaged over each output interval (what its
//! IMU message carries); or from a recording (`--input FILE`: the CSV of
//! `imu-emu client record` or a raw KERNEL/ISB capture,
//! [`input`]).
//!
//! **Allan deviation.** The phase `x_k = Σ y_i·τ₀` of each axis is kept
//! every `S`-th sample (S chosen so that at most 2²⁰ values are kept:
//! 24 h at 100 Hz keeps every 9th); σ²(τ = m·τ₀) = Σ (x_{i+2m} − 2x_{i+m} +
//! x_i)² / (2τ²(n − 2m)) over the kept phases with m a multiple of S, ten
//! τ a decade from S·τ₀ to a quarter of the run: the overlapping estimator
//! (IEEE 952 / IEEE 1554) with overlap steps of S samples.
//!
//! **Fit.** Weighted least squares of σ²(τ) = N²/τ + F² + K²·τ/3 over τ up
//! to a tenth of the run (weights: the estimate's degrees of freedom,
//! ≈ n/m, over σ⁴), a negative term dropped and the rest refitted: N is the
//! white noise (ARW °/√h = 60·N, VRW m/s/√h = 60·g·N), F the flicker floor
//! (bias instability B = F / 0.6643), K the rate random walk. The
//! datasheet reading (the curve's minimum / 0.6643, over τ up to a
//! hundredth of the run, where each estimate averages ≥ 100 intervals;
//! docs/sensors.md "The datasheet reading" on the run length it needs) is
//! printed beside it.
//!
//! The unit is held at its warmed-up temperature unless `--warming`
//! (datasheet figures are taken at a steady temperature; the warm-up
//! drift through the temperature coefficients would otherwise dominate
//! the long τ).

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use imu_emu::device::{Device, PowerOn};
use imu_emu::kernel::Capability;
use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu::sensor::profile::{density_to_arw, density_to_vrw, SensorProfile, SensorSpec};
use imu_emu::time::Instant;
use imu_emu::OutputVariant;
use imu_emu::{ChainConfig, SignalChain};

use crate::plot::Kind;

pub mod deviation;
pub mod input;
pub mod plot;

use deviation::{curves, fit, too_short, Fit, Phases, Source, AXES};

/// The flash of the unit run in process: the runner's size (two 4 KiB
/// sectors, what the parameter store needs); nothing is kept after the run.
type UnitFlash = imu_emu::nor::RamNor<8192>;

/// `imu-emu allan …`.
#[derive(clap::Args, Debug, Clone)]
pub struct AllanArgs {
    /// The unit to run: K100 … K220 (a KERNEL streaming GA frames) or
    /// IMX-5.
    #[arg(long, default_value = "K110")]
    pub model: String,
    /// Seed of the unit's random processes.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Run this profile (TOML, `imu-emu sensor-profile show`) instead of
    /// the model's built-in one.
    #[arg(long = "sensor-profile", value_name = "FILE")]
    pub sensor_profile: Option<PathBuf>,
    /// Device time to run, hours.
    #[arg(long, default_value_t = 24.0, conflicts_with = "seconds")]
    pub hours: f64,
    /// Device time to run, seconds (instead of --hours).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Let the sensor temperature follow the profile's warm-up model (its
    /// bias drifts with it: the temperature coefficients). By default the
    /// unit is held at its warmed-up temperature (ambient + self-heating),
    /// as a datasheet's Allan figures are taken at a steady temperature.
    #[arg(long)]
    pub warming: bool,
    /// Output rate, Hz (a divisor of the internal rate; KERNEL Data_Rate).
    #[arg(long, default_value_t = 100)]
    pub rate: u32,
    /// Analyse this recording instead of running a unit: an `imu-emu
    /// client record` CSV (gyro_* and acc_* columns), or a raw capture of a
    /// KERNEL's frames or an IMX-5's ISB packets (docs/sensors.md
    /// "Recordings"). Its rate comes from its own clock (`imu_time_ns`,
    /// the 2 kHz counter, ISB `time`; a CSV's `device_time_s`, else its
    /// `host_time_s` with a warning), else --rate.
    #[arg(long, value_name = "FILE")]
    pub input: Option<PathBuf>,
    /// What --input holds: auto (from its content), csv, kernel or isb.
    #[arg(long, value_enum, default_value_t = input::Format::Auto)]
    pub format: input::Format,
    /// Plot to this PNG file.
    #[arg(long, value_name = "FILE")]
    pub png: Option<PathBuf>,
    /// Plot to this SVG file.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Write the Allan deviations (τ and σ of each axis) to this CSV.
    #[arg(long, value_name = "FILE")]
    pub table: Option<PathBuf>,
}

/// Runs a unit in process (module doc).
fn run_unit(a: &AllanArgs) -> anyhow::Result<Source> {
    let seconds = a.seconds.unwrap_or(a.hours * 3600.0);
    if seconds.is_nan() || seconds <= 0.0 {
        return Err(
            crate::error::UsageError("allan: the run must last more than 0 s".into()).into(),
        );
    }
    let profile: Option<&'static SensorProfile> = match &a.sensor_profile {
        Some(path) => Some(Box::leak(Box::new(crate::profile_file::load(path)?))),
        None => None,
    };
    let product = input::product(&a.model)?;
    let imx = core::ptr::eq(product.model, &imu_emu::isb::IMX5);
    let internal = product.model.internal_rate_hz;
    if a.rate == 0 || !internal.is_multiple_of(a.rate) {
        return Err(crate::error::UsageError(format!(
            "allan --rate {}: must divide the internal rate {internal} Hz",
            a.rate
        ))
        .into());
    }
    let outputs = (seconds * f64::from(a.rate)).round() as usize;
    let aux = !imx && product.model.has(Capability::AuxAccel);
    let mut phases = Phases::new(1.0 / f64::from(a.rate), outputs, if aux { 9 } else { 6 });
    let used = profile.copied().unwrap_or_else(|| product.sensor_profile());
    let title;
    if imx {
        title = format!("IMX-5, seed {}, chain averaged at {} Hz", a.seed, a.rate);
        let mut chain = SignalChain::new(product, a.seed);
        chain.set_profile(profile);
        chain.reset(product, a.seed);
        chain.faults_mut().temperature_c = steady(&used, a.warming);
        let mut cfg = ChainConfig::defaults(&product);
        cfg.output_variant = OutputVariant::Average;
        chain.configure(&cfg);
        let every = internal / a.rate;
        let dt_ns = 1_000_000_000 / u64::from(internal);
        let mut t = 0u64;
        for _ in 0..outputs {
            for _ in 0..every {
                t += dt_ns;
                chain.tick(Instant::from_nanos(t));
            }
            let s = chain.output_with(false);
            let g = s.gyro.map(f64::from);
            let f = s.acc.map(f64::from);
            phases.push(&[g[0], g[1], g[2], f[0], f[1], f[2]]);
        }
    } else {
        title = format!(
            "{}, seed {}, {} frames at {} Hz, average variant",
            product.code(),
            a.seed,
            if aux {
                "UDD (gyro, acc, aux acc)"
            } else {
                "GA"
            },
            a.rate
        );
        run_kernel(
            product,
            a,
            profile,
            steady(&used, a.warming),
            outputs,
            &mut phases,
        )?;
    }
    Ok(Source {
        title,
        profile: Some(used),
        phases,
    })
}

/// The temperature the unit is held at: its warmed-up one, unless
/// `--warming`.
fn steady(p: &SensorProfile, warming: bool) -> Option<f32> {
    (!warming).then_some(p.temperature.ambient_c + p.temperature.self_heating_c)
}

/// UDD types of the aux-carrying stream (ICD Table 5.14): gyro HR, acc
/// HR, aux accelerometer.
const AUX_UDD: [u8; 3] = [0x21, 0x23, 0x2F];

/// A KERNEL device streaming at `a.rate`: `outputs` frames decoded. GA
/// (gyro and acc), or on a model with an aux accelerometer a UDD of
/// [`AUX_UDD`] (GA does not carry it).
fn run_kernel(
    product: Product,
    a: &AllanArgs,
    profile: Option<&'static SensorProfile>,
    temperature: Option<f32>,
    outputs: usize,
    phases: &mut Phases,
) -> anyhow::Result<()> {
    use imu_emu::kernel::command::Command;
    use imu_emu::kernel::formats::UDD;
    use imu_emu::kernel::frame::{Decoder, TYPE_DATA};
    let cfg = PowerOn {
        product,
        boot: None,
        seed: a.seed,
    };
    let mut dev =
        Device::<UnitFlash, Kernel>::with_profile(cfg, profile, UnitFlash::new(), Instant::ZERO);
    dev.chain_mut().faults_mut().temperature_c = temperature;
    let period = dev.tick_period_ns();
    let mut now = 0u64;
    // Data_Rate (Table 5.24 ID 0x0012) and Output_Variant average (ID
    // 0x03D0 = 1), then the UDD list (5.3.5) and the data command: the
    // rate applies at the data command (5.3.1). In process the line is
    // not paced (that is a board's job), so any rate fits. The average,
    // as a datasheet's figures are read: the factory Instant variant
    // samples the FIR's output and aliases its band's noise into the
    // output's (its ARW reads higher: docs/sensors.md "Decimation").
    let rate = u16::try_from(a.rate).context("allan --rate: at most 65535")?;
    let aux = phases.channels() == AXES.len();
    let format = if aux { UDD } else { 0x8F };
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
    if aux {
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
    let mut y = vec![0.0; phases.channels()];
    while got < outputs {
        now += period;
        dev.on_tick(Instant::from_nanos(now));
        loop {
            let n = dev.poll_tx(&mut buf);
            if n == 0 {
                break;
            }
            let mut input = &buf[..n];
            while let Some(f) = rx.next_frame(&mut input) {
                if f.msg_type != TYPE_DATA || f.id != format || got == outputs {
                    continue;
                }
                let Some(d) = crate::client::decode::decode(f.id, f.payload, &product) else {
                    continue;
                };
                for (v, name) in y.iter_mut().zip(AXES) {
                    *v = d.get(name).unwrap_or(0.0);
                }
                phases.push(&y);
                got += 1;
            }
        }
    }
    Ok(())
}

/// The profile's sensor of channel `c` (gyro, acc, aux).
fn spec_of(p: &SensorProfile, c: usize) -> &SensorSpec {
    match c / 3 {
        0 => &p.gyro,
        1 => &p.acc,
        _ => &p.aux,
    }
}

/// The report: per axis the fitted terms beside the profile's.
fn report(src: &Source, fits: &[Fit], seconds: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "imu-emu allan: {}: {:.2} h, {} samples",
        src.title,
        seconds / 3600.0,
        src.phases.n
    );
    let _ = writeln!(
        s,
        "axis       white (fit)     profile   bias instability (fit, min/0.664)  profile   RRW (fit)"
    );
    for (c, f) in fits.iter().enumerate() {
        let gyro = c < 3;
        let spec = src.profile.as_ref().map(|p| spec_of(p, c));
        let (white, white_p, unit_w) = if gyro {
            (
                density_to_arw(f.n as f32),
                spec.map(|s| density_to_arw(s.noise_density)),
                "°/√h",
            )
        } else {
            (
                density_to_vrw(f.n as f32),
                spec.map(|s| density_to_vrw(s.noise_density)),
                "m/s/√h",
            )
        };
        let (k, unit_b) = if gyro { (3600.0, "°/h") } else { (1e6, "µg") };
        let bi = f.b * k;
        let bi_min = f.b_min * k;
        let bi_p = spec.map(|s| f64::from(s.bias_instability) * k);
        let opt = |v: Option<f64>| v.map_or("—".to_owned(), |v| format!("{v:.4}"));
        let _ = writeln!(
            s,
            "{:<10} {:>8.4} {:<7} {:>8}   {:>9.4} {:<4} ({:>9.4})          {:>8}   {:.3e}",
            AXES[c],
            white,
            unit_w,
            opt(white_p.map(f64::from)),
            bi,
            unit_b,
            bi_min,
            opt(bi_p),
            f.k,
        );
    }
    s
}

/// Runs `imu-emu allan`.
pub fn run(a: &AllanArgs) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    let src = match &a.input {
        Some(path) => {
            let product = input::product(&a.model)?;
            input::read(path, a.format, &product, a.rate)?
        }
        None => run_unit(a)?,
    };
    let seconds = src.phases.n as f64 * src.phases.tau0;
    let cs = curves(&src.phases);
    let fits: Vec<Fit> = cs
        .iter()
        .map(|c| fit(c, seconds / 10.0, seconds / 100.0))
        .collect();
    if let Some(w) = too_short(&cs, seconds) {
        eprintln!("imu-emu allan: warning: {w}");
    }
    let mut out = report(&src, &fits, seconds);
    let _ = writeln!(
        out,
        "(white: ARW °/√h, VRW m/s/√h; bias instability °/h, µg; RRW unit/√s; \
         {:.1} s of host time)",
        started.elapsed().as_secs_f64()
    );
    print!("{out}");
    if let Some(path) = &a.table {
        let mut t = String::from("tau_s");
        for ax in &AXES[..cs.len()] {
            let _ = write!(t, ",{ax}");
        }
        t.push('\n');
        for (i, p) in cs[0].points.iter().enumerate() {
            let _ = write!(t, "{}", p.0);
            for c in &cs {
                let _ = write!(t, ",{}", c.points[i].1);
            }
            t.push('\n');
        }
        std::fs::write(path, t).with_context(|| format!("allan --table {}", path.display()))?;
    }
    let fig = plot::figure(&src.title, &cs, src.profile.as_ref());
    for (path, kind) in [(&a.png, Kind::Png), (&a.svg, Kind::Svg)] {
        if let Some(p) = path {
            crate::plot::render_as(&fig, p, kind)
                .with_context(|| format!("allan: plotting to {}", p.display()))?;
        }
    }
    Ok(())
}
