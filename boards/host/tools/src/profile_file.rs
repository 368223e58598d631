//! Sensor profile files (`--sensor-profile FILE`, `imu-emu sensor-profile
//! show NAME`): a [`SensorProfile`] as TOML, one section per sensor
//! (`[gyro]`, `[acc]`, `[aux]`) and `[temperature]`, every key required,
//! in the units of [`imu_emu::sensor::profile`] (°/s and g; the comments
//! of a shown file give the datasheet figures: ARW °/√h, VRW m/s/√h, bias
//! instability °/h and µg). docs/sensors.md describes every key.
//!
//! A file is checked whole: a TOML or unknown/missing-key error names the
//! key (the `toml` crate's message, with the line), a value outside its
//! range names the key and the range ([`imu_emu::sensor::profile::ProfileError`]).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use imu_emu::sensor::profile::{
    arw_to_density, density_to_arw, density_to_vrw, vrw_to_density, Sensor, SensorProfile,
    SensorSpec, TemperatureSpec,
};
use imu_emu::sensor::profiles::{self, Builtin};
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    range: f32,
    noise_density: f32,
    bias_instability: f32,
    rate_random_walk: f32,
    turn_on_bias_sigma: f32,
    scale_factor_sigma: f32,
    nonlinearity: f32,
    misalignment_sigma: f32,
    g_sensitivity: f32,
    temp_bias: f32,
    temp_scale: f32,
    resolution: f32,
    bandwidth_hz: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileTemperature {
    ambient_c: f32,
    self_heating_c: f32,
    time_constant_s: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileProfile {
    gyro: FileSpec,
    acc: FileSpec,
    /// Only for the models with an aux accelerometer (K120, K220); absent,
    /// the built-in aux figures ([`profiles::AUX`]) stand.
    aux: Option<FileSpec>,
    temperature: FileTemperature,
}

impl From<FileSpec> for SensorSpec {
    fn from(f: FileSpec) -> Self {
        SensorSpec {
            range: f.range,
            noise_density: f.noise_density,
            bias_instability: f.bias_instability,
            rate_random_walk: f.rate_random_walk,
            turn_on_bias_sigma: f.turn_on_bias_sigma,
            scale_factor_sigma: f.scale_factor_sigma,
            nonlinearity: f.nonlinearity,
            misalignment_sigma: f.misalignment_sigma,
            g_sensitivity: f.g_sensitivity,
            temp_bias: f.temp_bias,
            temp_scale: f.temp_scale,
            resolution: f.resolution,
            bandwidth_hz: f.bandwidth_hz,
        }
    }
}

/// Parses and checks a profile's text (`what` names it in errors).
pub fn parse(text: &str, what: &str) -> anyhow::Result<SensorProfile> {
    parse_with_aux(text, what).map(|(p, _)| p)
}

/// [`parse`], and whether the text has an `[aux]` section.
pub fn parse_with_aux(text: &str, what: &str) -> anyhow::Result<(SensorProfile, bool)> {
    let f: FileProfile = toml::from_str(text).map_err(|e| {
        // "line N (`[gyro]`): missing field `range`": the line the parser
        // points at, and its message (which names the key).
        let at = e.span().map_or_else(String::new, |sp| {
            let line = text[..sp.start.min(text.len())].matches('\n').count() + 1;
            let src = text.lines().nth(line - 1).unwrap_or("").trim();
            format!("line {line} (`{src}`): ")
        });
        usage(format!("{what}: {at}{}", e.message().trim_end()))
    })?;
    let has_aux = f.aux.is_some();
    let p = SensorProfile {
        gyro: f.gyro.into(),
        acc: f.acc.into(),
        aux: f.aux.map_or(profiles::AUX, Into::into),
        temperature: TemperatureSpec {
            ambient_c: f.temperature.ambient_c,
            self_heating_c: f.temperature.self_heating_c,
            time_constant_s: f.temperature.time_constant_s,
        },
    };
    p.validate().map_err(|e| usage(format!("{what}: {e}")))?;
    Ok((p, has_aux))
}

/// A bad profile is a bad argument (exit status 2).
fn usage(msg: String) -> anyhow::Error {
    crate::error::UsageError(msg).into()
}

/// Reads and checks the profile in `path`.
pub fn load(path: &Path) -> anyhow::Result<SensorProfile> {
    load_with_aux(path).map(|(p, _)| p)
}

/// [`load`], and whether the file has an `[aux]` section.
pub fn load_with_aux(path: &Path) -> anyhow::Result<(SensorProfile, bool)> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--sensor-profile {}", path.display()))?;
    parse_with_aux(&text, &format!("--sensor-profile {}", path.display()))
}

/// The shortest decimal (at most 9 significant digits) of the figure `x`
/// derived from the stored `v` that gives `v` back through `back` (the
/// way a profile writes the figure: `arw_to_density(0.16)`, `300e-6`), so
/// a comment reads `0.02`, not `0.019999998`; else `x` in full.
fn figure(v: f32, x: f64, back: impl Fn(f64) -> f32) -> String {
    (1..=9)
        .filter_map(|digits| format!("{:.*e}", digits - 1, x).parse::<f64>().ok())
        .find(|&d| back(d).to_bits() == v.to_bits())
        .map_or_else(|| format!("{x}"), |d| format!("{d}"))
}

/// Units of each key of `sensor`, and the datasheet figure of a value in
/// a comment.
fn comment(sensor: Sensor, key: &str, v: f32) -> String {
    let (u, per) = match sensor {
        Sensor::Gyro => ("°/s", "°/s"),
        _ => ("g", "g"),
    };
    match key {
        "range" => format!("± {u}"),
        "noise_density" => match sensor {
            Sensor::Gyro => {
                let x = f64::from(density_to_arw(v));
                let arw = figure(v, x, |d| arw_to_density(d as f32));
                format!("{u}/√Hz (ARW {arw} °/√h)")
            }
            _ => {
                let x = f64::from(density_to_vrw(v));
                let vrw = figure(v, x, |d| vrw_to_density(d as f32));
                format!("{u}/√Hz (VRW {vrw} m/s/√h)")
            }
        },
        "bias_instability" => match sensor {
            Sensor::Gyro => {
                let b = figure(v, f64::from(v) * 3600.0, |d| d as f32 / 3600.0);
                format!("{u}, Allan floor / 0.6643 ({b} °/h)")
            }
            _ => {
                let b = figure(v, f64::from(v) * 1e6, |d| d as f32 * 1e-6);
                format!("{u}, Allan floor / 0.6643 ({b} µg)")
            }
        },
        "rate_random_walk" => format!("{u}/√s (Allan +½ slope: K·√(τ/3))"),
        "turn_on_bias_sigma" => format!("{u}, 1σ"),
        "scale_factor_sigma" => {
            let ppm = figure(v, f64::from(v) * 1e6, |d| (d * 1e-6) as f32);
            format!("fraction, 1σ ({ppm} ppm)")
        }
        "nonlinearity" => "fraction of full scale".to_owned(),
        "misalignment_sigma" => {
            let deg = figure(v, f64::from(v).to_degrees(), |d| {
                d as f32 * core::f32::consts::PI / 180.0
            });
            format!("rad, 1σ ({deg} °)")
        }
        "g_sensitivity" => format!("{per}/g"),
        "temp_bias" => format!("{u}/°C"),
        "temp_scale" => "1/°C".to_owned(),
        "resolution" => format!("{u} (0 = none)"),
        "bandwidth_hz" => "Hz, −3 dB, first order (0 = not given: no filter)".to_owned(),
        _ => String::new(),
    }
}

/// The profile as a file (every key, with its units and range in
/// comments; `[aux]` only if `aux`: a model without an aux accelerometer
/// has no use for one): what `sensor-profile show` prints; [`parse`]
/// reads it back to the same values.
pub fn to_toml(p: &SensorProfile, aux: bool, title: &str, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# imu-emu sensor profile: {title}");
    let _ = writeln!(s, "# source: {source}");
    let _ = writeln!(
        s,
        "# Every key is required (the aux section only on a model with an aux accelerometer); units and allowed ranges in the comments (docs/sensors.md)."
    );
    let sensors: &[Sensor] = if aux {
        &[Sensor::Gyro, Sensor::Acc, Sensor::Aux]
    } else {
        &[Sensor::Gyro, Sensor::Acc]
    };
    for &sensor in sensors {
        let spec = p.sensor(sensor);
        let _ = writeln!(s, "\n[{}]", sensor.key());
        for (key, v) in SensorSpec::keys().iter().zip(spec.values()) {
            let (lo, hi) = SensorSpec::limits(sensor, key).unwrap_or((0.0, 0.0));
            let _ = writeln!(
                s,
                "{key} = {v:?}  # {}; {lo:?} ..= {hi:?}",
                comment(sensor, key, v)
            );
        }
    }
    let _ = writeln!(s, "\n[temperature]");
    for (key, v) in p.temperature.fields() {
        let (lo, hi) = TemperatureSpec::limits(key).unwrap_or((0.0, 0.0));
        let unit = if key == "time_constant_s" { "s" } else { "°C" };
        let _ = writeln!(s, "{key} = {v:?}  # {unit}; {lo:?} ..= {hi:?}");
    }
    s
}

/// The built-in profile `name`, or an error listing the names.
pub fn builtin(name: &str) -> anyhow::Result<&'static Builtin> {
    profiles::builtin(name).ok_or_else(|| {
        let names: Vec<&str> = profiles::BUILTIN.iter().map(|b| b.name).collect();
        usage(format!(
            "sensor-profile: no built-in profile {name:?} (one of {})",
            names.join(" ")
        ))
    })
}

/// One `--sensor-profile [K=]FILE`: the device it is for (`None`: all)
/// and the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProfileArg {
    /// Device index in a `--count` run; `None` = every device.
    pub device: Option<usize>,
    /// The file.
    pub path: std::path::PathBuf,
}

/// Parses `[K=]FILE`.
pub fn parse_arg(s: &str) -> Result<ProfileArg, String> {
    if let Some((k, path)) = s.split_once('=') {
        if let Ok(k) = k.parse::<usize>() {
            return Ok(ProfileArg {
                device: Some(k),
                path: path.into(),
            });
        }
    }
    Ok(ProfileArg {
        device: None,
        path: s.into(),
    })
}

/// The profile of each of `n` devices from the `--sensor-profile`
/// arguments (a `K=FILE` wins over a plain FILE; the last of each kind
/// wins), loaded and leaked for the process's life (the chain holds a
/// `&'static`): `None` = the built-in one.
pub fn per_device(
    args: &[ProfileArg],
    n: usize,
) -> anyhow::Result<Vec<Option<&'static SensorProfile>>> {
    let mut loaded = std::collections::HashMap::new();
    let mut out = vec![None; n];
    for a in args {
        if let Some(k) = a.device {
            if k >= n {
                return Err(usage(format!(
                    "--sensor-profile {k}={}: no device {k} (--count {n}: 0..={})",
                    a.path.display(),
                    n - 1
                )));
            }
        }
    }
    for specific in [false, true] {
        for a in args.iter().filter(|a| a.device.is_some() == specific) {
            let p: &'static SensorProfile = match loaded.get(&a.path) {
                Some(&p) => p,
                None => {
                    let p: &'static SensorProfile = Box::leak(Box::new(load(&a.path)?));
                    loaded.insert(a.path.clone(), p);
                    p
                }
            };
            match a.device {
                Some(k) => out[k] = Some(p),
                None => out.iter_mut().for_each(|o| *o = Some(p)),
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_round_trips_through_its_file() {
        for b in profiles::BUILTIN {
            let text = to_toml(b.profile, b.has_aux(), b.name, b.source);
            let (p, aux) = parse_with_aux(&text, b.name).unwrap();
            assert_eq!(&p, b.profile, "{}", b.name);
            assert_eq!(aux, b.has_aux(), "{}", b.name);
        }
    }

    #[test]
    fn errors_name_the_key() {
        let text = to_toml(&profiles::IMX5_PROFILE, false, "x", "y");
        let bad = text.replace("range = 16.0", "range = 500.0");
        let e = parse(&bad, "f").unwrap_err().to_string();
        assert!(
            e.contains("acc.range = 500") && e.contains("0.5 ..= 128"),
            "{e}"
        );
        let bad = text.replace("[temperature]\nambient_c", "[temperature]\nambient");
        let e = parse(&bad, "f").unwrap_err().to_string();
        assert!(e.contains("ambient"), "{e}");
    }

    /// The comments' figures are the short decimals a datasheet writes.
    #[test]
    fn figures_print_as_written() {
        let text = to_toml(&profiles::KERNEL_HIGH, true, "x", "y");
        for want in [
            "(VRW 0.02 m/s/√h)",
            "(ARW 0.1 °/√h)",
            "(1000 ppm)",
            "(300 ppm)",
            "(0.01 °)",
            "(5 µg)",
            "(1 °/h)",
        ] {
            assert!(text.contains(want), "{want} in {text}");
        }
        assert!(!text.contains("0.0199999") && !text.contains("1000.00006"));
    }

    #[test]
    fn device_arguments() {
        assert_eq!(
            parse_arg("2=a.toml").unwrap(),
            ProfileArg {
                device: Some(2),
                path: "a.toml".into()
            }
        );
        assert_eq!(parse_arg("a=b.toml").unwrap().device, None);
    }
}
