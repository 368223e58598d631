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
//! [`crate::allan_input`]).
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
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use imu_emu::device::{Device, PowerOn};
use imu_emu::kernel::Capability;
use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu::sensor::profile::{density_to_arw, density_to_vrw, SensorProfile, SensorSpec};
use imu_emu::time::Instant;
use imu_emu::OutputVariant;
use imu_emu::{ChainConfig, SignalChain};

use crate::flash::MemNor;
use crate::plot::Kind;

/// Flicker floor / B: √(2 ln 2/π) (IEEE 952).
pub const FLICKER_FLOOR: f64 = 0.664_282;
/// Phases kept per axis at most.
const KEEP: usize = 1 << 20;
/// Channels: gyro X Y Z (°/s), acc X Y Z (g), and on the K120/K220 the
/// aux accelerometer X Y Z (g): the `client record` column names.
pub const AXES: [&str; 9] = [
    "gyro_x",
    "gyro_y",
    "gyro_z",
    "acc_x",
    "acc_y",
    "acc_z",
    "aux_acc_x",
    "aux_acc_y",
    "aux_acc_z",
];

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
    #[arg(long, value_enum, default_value_t = crate::allan_input::Format::Auto)]
    pub format: crate::allan_input::Format,
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

/// Phases of the channels (the first `channels` of [`AXES`]), kept every
/// `stride` samples.
pub(crate) struct Phases {
    tau0: f64,
    stride: usize,
    /// Samples pushed.
    pub(crate) n: usize,
    acc: Vec<f64>,
    first: Option<Vec<f64>>,
    kept: Vec<Vec<f64>>,
}

impl Phases {
    pub(crate) fn new(tau0: f64, expected: usize, channels: usize) -> Self {
        let stride = expected.div_ceil(KEEP).max(1);
        let mut p = Phases {
            tau0,
            stride,
            n: 0,
            acc: vec![0.0; channels],
            first: None,
            kept: vec![Vec::new(); channels],
        };
        for k in &mut p.kept {
            k.reserve(expected / stride + 2);
            k.push(0.0);
        }
        p
    }

    /// The channels' count.
    fn channels(&self) -> usize {
        self.acc.len()
    }

    /// One sample of every channel (`y.len()` = [`Phases::channels`]).
    pub(crate) fn push(&mut self, y: &[f64]) {
        // Relative to the first sample: the phases stay small (the Allan
        // deviation ignores a constant).
        let y0 = self.first.get_or_insert_with(|| y.to_vec());
        for ((a, v), v0) in self.acc.iter_mut().zip(y).zip(y0.iter()) {
            *a += (v - v0) * self.tau0;
        }
        self.n += 1;
        if self.n.is_multiple_of(self.stride) {
            for (k, a) in self.kept.iter_mut().zip(&self.acc) {
                k.push(*a);
            }
        }
    }
}

/// One axis's Allan deviation: (τ s, σ, samples n/m) points.
#[derive(Debug, Clone)]
pub struct Curve {
    /// (τ, σ(τ), n/m).
    pub points: Vec<(f64, f64, f64)>,
}

fn curves(p: &Phases) -> Vec<Curve> {
    let kept = p.kept[0].len();
    let max_k = (kept.saturating_sub(1)) / 4;
    let mut ks: Vec<usize> = Vec::new();
    let mut e = 0.0f64;
    while 10f64.powf(e / 10.0) <= max_k as f64 {
        let k = 10f64.powf(e / 10.0).round() as usize;
        if ks.last() != Some(&k) {
            ks.push(k);
        }
        e += 1.0;
    }
    p.kept
        .iter()
        .map(|x| {
            let points = ks
                .iter()
                .map(|&k| {
                    let m = k * p.stride;
                    let tau = m as f64 * p.tau0;
                    let terms = x.len() - 2 * k;
                    let s: f64 = (0..terms)
                        .map(|i| {
                            let d = x[i + 2 * k] - 2.0 * x[i + k] + x[i];
                            d * d
                        })
                        .sum();
                    let var = s / (2.0 * tau * tau * terms as f64);
                    (tau, var.sqrt(), p.n as f64 / m as f64)
                })
                .collect();
            Curve { points }
        })
        .collect()
}

/// Fitted terms of one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// White-noise density, unit/√Hz.
    pub n: f64,
    /// Bias instability B = floor / 0.6643, unit.
    pub b: f64,
    /// Rate random walk, unit/√s.
    pub k: f64,
    /// The datasheet reading: min σ / 0.6643 over τ ≤ `tau_min_max`
    /// (where each estimate averages ≥ 100 intervals: the minimum of a
    /// noisier estimate reads low), unit.
    pub b_min: f64,
}

/// Weighted least squares of the curve (module doc) over τ ≤ `tau_max`;
/// the datasheet reading over τ ≤ `tau_min_max`.
pub fn fit(c: &Curve, tau_max: f64, tau_min_max: f64) -> Fit {
    let pts: Vec<&(f64, f64, f64)> = c
        .points
        .iter()
        .filter(|p| p.0 <= tau_max && p.1 > 0.0)
        .collect();
    let mut on = [true; 3];
    let mut x = [0.0f64; 3];
    for _ in 0..3 {
        let idx: Vec<usize> = (0..3).filter(|&i| on[i]).collect();
        let n = idx.len();
        let mut a = vec![vec![0.0f64; n]; n];
        let mut b = vec![0.0f64; n];
        for &&(tau, sigma, dof) in &pts {
            let v = sigma * sigma;
            let f = [1.0 / tau, 1.0, tau / 3.0];
            let w = dof / (v * v);
            for (r, &i) in idx.iter().enumerate() {
                b[r] += w * f[i] * v;
                for (s, &j) in idx.iter().enumerate() {
                    a[r][s] += w * f[i] * f[j];
                }
            }
        }
        let sol = solve(a, b);
        x = [0.0; 3];
        for (r, &i) in idx.iter().enumerate() {
            x[i] = sol[r];
        }
        match (0..3).find(|&i| on[i] && x[i] < 0.0) {
            Some(i) => on[i] = false,
            None => break,
        }
    }
    let x = x.map(|v| v.max(0.0));
    let b_min = pts
        .iter()
        .filter(|p| p.0 <= tau_min_max)
        .map(|p| p.1)
        .fold(f64::INFINITY, f64::min)
        / FLICKER_FLOOR;
    Fit {
        n: x[0].sqrt(),
        b: x[1].sqrt() / FLICKER_FLOOR,
        k: x[2].sqrt(),
        b_min,
    }
}

/// Gaussian elimination with partial pivoting (n ≤ 3).
#[allow(clippy::needless_range_loop)] // rows and columns by index
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, p);
        b.swap(c, p);
        if a[c][c] == 0.0 {
            continue;
        }
        for r in c + 1..n {
            let k = a[r][c] / a[c][c];
            for j in c..n {
                a[r][j] -= k * a[c][j];
            }
            b[r] -= k * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|j| a[c][j] * x[j]).sum();
        x[c] = if a[c][c] == 0.0 {
            0.0
        } else {
            (b[c] - s) / a[c][c]
        };
    }
    x
}

/// What was analysed, for the report.
pub(crate) struct Source {
    /// Plot and report title.
    pub(crate) title: String,
    /// The profile to compare with, if known.
    pub(crate) profile: Option<SensorProfile>,
    /// The channels' phases.
    pub(crate) phases: Phases,
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
    let product = crate::allan_input::product(&a.model)?;
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
        Device::<MemNor, Kernel>::with_profile(cfg, profile, MemNor::new(), Instant::ZERO);
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
        crate::allan_input::median_step(&t)
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

/// The warning for a run too short for the figures past the white noise:
/// on some axis the Allan deviation still falls at its longest τ (a
/// quarter of the run), so the floor (bias instability) and a rise (rate
/// random walk) lie beyond the data and those columns are upper bounds of
/// noise, not readings (docs/sensors.md "The datasheet reading": a floor
/// shows from about 100 times the τ where the white noise meets it, hours
/// for the built-in profiles). `None` when every curve turns.
pub fn too_short(cs: &[Curve], seconds: f64) -> Option<String> {
    let falling: Vec<&str> = cs
        .iter()
        .zip(AXES)
        .filter(|(c, _)| {
            let lowest = c
                .points
                .iter()
                .enumerate()
                .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
                .map(|(i, _)| i);
            c.points.len() < 2 || lowest == Some(c.points.len() - 1)
        })
        .map(|(_, ax)| ax)
        .collect();
    if falling.is_empty() {
        return None;
    }
    let longest = cs
        .first()
        .and_then(|c| c.points.last())
        .map_or(0.0, |p| p.0);
    Some(format!(
        "the record ({seconds:.1} s) is too short for bias instability and rate random walk: \
         the Allan deviation of {} still falls at its longest τ ({longest:.3} s), so their \
         figures below are upper bounds, not readings; only the white noise (ARW/VRW) is read",
        falling.join(" ")
    ))
}

/// A recording needs 100 samples or more.
pub(crate) fn enough(path: &Path, n: usize) -> anyhow::Result<()> {
    if n < 100 {
        bail!(
            "allan {}: {n} usable samples (need 100 or more)",
            path.display()
        );
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
            let product = crate::allan_input::product(&a.model)?;
            crate::allan_input::read(path, a.format, &product, a.rate)?
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
    let fig = crate::allan_plot::figure(&src.title, &cs, src.profile.as_ref());
    for (path, kind) in [(&a.png, Kind::Png), (&a.svg, Kind::Svg)] {
        if let Some(p) = path {
            crate::plot::render_as(&fig, p, kind)
                .with_context(|| format!("allan: plotting to {}", p.display()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// White noise of known density: the fit reads it (and no floor).
    #[test]
    fn the_fit_reads_white_noise() {
        let mut rng = imu_emu::sensor::Rng::new(3);
        let n = 0.01;
        let rate = 100.0;
        let mut p = Phases::new(1.0 / rate, 200_000, 6);
        for _ in 0..200_000 {
            let w = f64::from(rng.gaussian()) * n * rate.sqrt();
            p.push(&[w, w, w, w, w, w]);
        }
        let c = curves(&p);
        let f = fit(&c[0], 200.0, 20.0);
        assert!((f.n / n - 1.0).abs() < 0.03, "{f:?}");
        assert!(f.b < 0.1 * n, "{f:?}");
    }
}
