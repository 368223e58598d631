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
    density_to_arw, density_to_vrw, Sensor, SensorProfile, SensorSpec, TemperatureSpec,
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
    aux: FileSpec,
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
    let p = SensorProfile {
        gyro: f.gyro.into(),
        acc: f.acc.into(),
        aux: f.aux.into(),
        temperature: TemperatureSpec {
            ambient_c: f.temperature.ambient_c,
            self_heating_c: f.temperature.self_heating_c,
            time_constant_s: f.temperature.time_constant_s,
        },
    };
    p.validate().map_err(|e| usage(format!("{what}: {e}")))?;
    Ok(p)
}

/// A bad profile is a bad argument (exit status 2).
fn usage(msg: String) -> anyhow::Error {
    crate::error::UsageError(msg).into()
}

/// Reads and checks the profile in `path`.
pub fn load(path: &Path) -> anyhow::Result<SensorProfile> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--sensor-profile {}", path.display()))?;
    parse(&text, &format!("--sensor-profile {}", path.display()))
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
            Sensor::Gyro => format!("{u}/√Hz (ARW {} °/√h)", density_to_arw(v)),
            _ => format!("{u}/√Hz (VRW {} m/s/√h)", density_to_vrw(v)),
        },
        "bias_instability" => match sensor {
            Sensor::Gyro => format!("{u}, Allan floor / 0.6643 ({} °/h)", v * 3600.0),
            _ => format!("{u}, Allan floor / 0.6643 ({} µg)", v * 1e6),
        },
        "rate_random_walk" => format!("{u}/√s (Allan +½ slope: K·√(τ/3))"),
        "turn_on_bias_sigma" => format!("{u}, 1σ"),
        "scale_factor_sigma" => format!("fraction, 1σ ({} ppm)", v * 1e6),
        "nonlinearity" => "fraction of full scale".to_owned(),
        "misalignment_sigma" => format!("rad, 1σ ({} °)", v.to_degrees()),
        "g_sensitivity" => format!("{per}/g"),
        "temp_bias" => format!("{u}/°C"),
        "temp_scale" => "1/°C".to_owned(),
        "resolution" => format!("{u} (0 = none)"),
        "bandwidth_hz" => "Hz, −3 dB, first order (0 = not given: no filter)".to_owned(),
        _ => String::new(),
    }
}

/// The profile as a file (every key, with its units and range in
/// comments): what `sensor-profile show` prints; [`parse`] reads it back
/// to the same values.
pub fn to_toml(p: &SensorProfile, title: &str, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# imu-emu sensor profile: {title}");
    let _ = writeln!(s, "# source: {source}");
    let _ = writeln!(
        s,
        "# Every key is required; units and allowed ranges in the comments (docs/sensors.md)."
    );
    for sensor in [Sensor::Gyro, Sensor::Acc, Sensor::Aux] {
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
            let text = to_toml(b.profile, b.name, b.source);
            let p = parse(&text, b.name).unwrap();
            assert_eq!(&p, b.profile, "{}", b.name);
        }
    }

    #[test]
    fn errors_name_the_key() {
        let text = to_toml(&profiles::IMX5_PROFILE, "x", "y");
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
