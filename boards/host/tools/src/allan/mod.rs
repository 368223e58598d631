//! `imu-emu allan`: the overlapping Allan deviation of each axis of a
//! unit's output, the noise terms fitted to it beside its profile's, and a
//! log-log plot (docs/sensors.md).
//!
//! The data come either from a unit run **in process** as fast as the host
//! computes (no TCP; a [`Unit`], which the side that owns devices runs —
//! the program hands [`run`] the runner's): a KERNEL `Device` streaming GA
//! frames at `--rate` with the average output variant (on the K120/K220 a
//! UDD with the aux accelerometer; the frames decoded with the core's
//! typed decoder, `client::decode`), or, for `--model IMX-5`, its signal
//! chain averaged over each output interval (what its IMU message
//! carries); or from a recording (`--input FILE`: the CSV of `imu-emu
//! client record` or a raw KERNEL/ISB capture, [`input`]). This crate
//! only analyses the samples it is given.
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
use imu_emu::kernel::Capability;
use imu_emu::model::Product;
use imu_emu::sensor::profile::{density_to_arw, density_to_vrw, SensorProfile, SensorSpec};

use crate::plot::Kind;
use crate::protocol::Protocol;

pub mod deviation;
pub mod input;
pub mod plot;

use deviation::{curves, fit, too_short, Fit, Phases, Source, AXES};

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

/// A unit run in process, as `imu-emu allan` asks the side that owns
/// devices for it (the program hands [`run`] a [`RunUnit`]): a KERNEL
/// `Device` streaming at `rate` with the average output variant (GA, or
/// with `aux` a UDD of gyro, acc and the aux accelerometer), or an IMX-5's
/// signal chain averaged over each output interval.
#[derive(Debug, Clone, Copy)]
pub struct Unit {
    /// The protocol of the unit (`--model IMX-5` is ISB).
    pub protocol: Protocol,
    /// The unit (`--model`).
    pub product: Product,
    /// Seed of its random processes (`--seed`).
    pub seed: u64,
    /// The profile it runs instead of its built-in one (`--sensor-profile`).
    pub profile: Option<&'static SensorProfile>,
    /// The sensor temperature it is held at, °C (`None`: `--warming`, the
    /// profile's warm-up model).
    pub temperature_c: Option<f32>,
    /// Output rate, Hz (a divisor of the internal rate).
    pub rate: u32,
    /// Outputs to deliver.
    pub outputs: usize,
    /// Whether each output carries the aux accelerometer too (9 channels,
    /// else 6).
    pub aux: bool,
}

impl Unit {
    /// The channels of each sample: the first this many of [`AXES`].
    pub fn channels(&self) -> usize {
        if self.aux {
            AXES.len()
        } else {
            6
        }
    }
}

/// Runs a [`Unit`] in process: hands each output's channels (°/s, g;
/// [`Unit::channels`] of [`AXES`]), `outputs` of them, to `sample`, and
/// returns the run's title (what ran, and how it was read).
pub type RunUnit<'a> = &'a dyn Fn(&Unit, &mut dyn FnMut(&[f64])) -> anyhow::Result<String>;

/// The unit `a` asks for, run by `run_unit` (module doc).
fn run_unit(a: &AllanArgs, run_unit: RunUnit<'_>) -> anyhow::Result<Source> {
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
    let protocol = crate::client::tool_protocol::of_product(&product).protocol();
    let internal = product.model.internal_rate_hz;
    if a.rate == 0 || !internal.is_multiple_of(a.rate) {
        return Err(crate::error::UsageError(format!(
            "allan --rate {}: must divide the internal rate {internal} Hz",
            a.rate
        ))
        .into());
    }
    let used = profile.copied().unwrap_or_else(|| product.sensor_profile());
    let unit = Unit {
        protocol,
        product,
        seed: a.seed,
        profile,
        temperature_c: steady(&used, a.warming),
        rate: a.rate,
        outputs: (seconds * f64::from(a.rate)).round() as usize,
        // The IMX-5 has none (its chain gives gyro and acc).
        aux: product.model.has(Capability::AuxAccel),
    };
    let mut phases = Phases::new(1.0 / f64::from(a.rate), unit.outputs, unit.channels());
    let title = run_unit(&unit, &mut |y| phases.push(y))?;
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

/// Runs `imu-emu allan`: a unit run in process by `unit` (which the
/// program wires to the runner, the side that owns devices), or the
/// recording `--input` names.
pub fn run(a: &AllanArgs, unit: RunUnit<'_>) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    let src = match &a.input {
        Some(path) => {
            let product = input::product(&a.model)?;
            input::read(path, a.format, &product, a.rate)?
        }
        None => run_unit(a, unit)?,
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
