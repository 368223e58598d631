//! Sensor profiles: every error term of a unit's sensors as data, in the
//! terms a datasheet gives them (docs/sensors.md).
//!
//! A [`SensorProfile`] holds, per sensor (gyro, accelerometer, aux
//! accelerometer), a [`SensorSpec`]: range, white-noise density (ARW /
//! VRW), bias instability, rate random walk, turn-on bias, scale factor and
//! its non-linearity, misalignment, the gyro's g-sensitivity, temperature
//! coefficients, resolution and bandwidth; and the warm-up
//! [`TemperatureSpec`]. The built-in profiles, each citing its source, are
//! in [`super::profiles`]; a host may read one from a file
//! (`--sensor-profile`). [`crate::sensor::ErrorModel::from_profile`] draws
//! one unit from a profile (turn-on bias, scale factor, misalignment and the
//! signs of the temperature coefficients are the unit's own, from its seed).
//!
//! Units: gyro figures in °/s (ARW in °/√h on the datasheet: see
//! [`arw_to_density`]), accelerometer figures in g (VRW in m/s/√h:
//! [`vrw_to_density`]), fractions as fractions (1e-4 = 100 ppm), angles in
//! radians, temperatures in °C.

use crate::math::G;

/// The error terms of one sensor triad, in its output unit (°/s for a
/// gyro, g for an accelerometer). Every axis of the triad has the same
/// figures; the realised values of the random terms differ per axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSpec {
    /// Measurement range ±, unit (the output saturates there).
    pub range: f32,
    /// White-noise density, unit/√Hz (ARW °/√h = 60 × this; VRW m/s/√h =
    /// 60 × g × this).
    pub noise_density: f32,
    /// Bias instability B, unit: the Allan floor / 0.6643 (IEEE 952),
    /// realised as flicker noise over 3 s … 3·10⁴ s
    /// ([`crate::sensor::errors`] "Flicker").
    pub bias_instability: f32,
    /// Rate random walk K, unit/√s (the Allan +½ slope: σ(τ) = K·√(τ/3)).
    pub rate_random_walk: f32,
    /// 1σ of the turn-on bias (one value per power-on), unit.
    pub turn_on_bias_sigma: f32,
    /// 1σ of the scale-factor error, fraction.
    pub scale_factor_sigma: f32,
    /// Scale-factor non-linearity, fraction of full scale: the error at
    /// full scale of a term quadratic in the input (x·|x|/range); signs
    /// drawn per axis.
    pub nonlinearity: f32,
    /// 1σ of each misalignment (cross-axis) angle, rad.
    pub misalignment_sigma: f32,
    /// Sensitivity to specific force along the same axis, unit/g (the
    /// gyro's g-sensitivity, °/s/g; zero for an accelerometer); signs drawn
    /// per axis.
    pub g_sensitivity: f32,
    /// Bias temperature coefficient, unit/°C about 25 °C (signs per axis).
    pub temp_bias: f32,
    /// Scale-factor temperature coefficient, 1/°C about 25 °C (signs per
    /// axis).
    pub temp_scale: f32,
    /// Resolution (quantisation step of the sensor's output), unit; 0 =
    /// none beyond the chain's own.
    pub resolution: f32,
    /// −3 dB bandwidth of the sensor, Hz: a first-order low-pass per axis
    /// at the chain's internal rate, before its FIR (ICD 5.6)
    /// ([`crate::sensor::bandwidth`]); 0 = not given, no filter, and none
    /// at or above the internal rate's Nyquist frequency either.
    pub bandwidth_hz: f32,
}

/// The sensor temperature model of a profile
/// ([`crate::sensor::temperature::TemperatureModel`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemperatureSpec {
    /// Ambient (power-on) temperature, °C.
    pub ambient_c: f32,
    /// Steady-state rise from self-heating, °C.
    pub self_heating_c: f32,
    /// Warm-up time constant, s.
    pub time_constant_s: f32,
}

/// Every error term of one unit's sensors (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorProfile {
    /// Gyroscopes, °/s.
    pub gyro: SensorSpec,
    /// Main accelerometers, g.
    pub acc: SensorSpec,
    /// Aux (high-g) accelerometers, g (used by models that have one).
    pub aux: SensorSpec,
    /// Temperature model.
    pub temperature: TemperatureSpec,
}

/// ARW in °/√h → noise density in °/s/√Hz.
pub const fn arw_to_density(arw_deg_per_rt_h: f32) -> f32 {
    arw_deg_per_rt_h / 60.0
}

/// VRW in m/s/√h → noise density in g/√Hz.
pub const fn vrw_to_density(vrw_m_s_per_rt_h: f32) -> f32 {
    vrw_m_s_per_rt_h / 60.0 / G
}

/// Noise density in °/s/√Hz → ARW in °/√h.
pub const fn density_to_arw(density: f32) -> f32 {
    density * 60.0
}

/// Noise density in g/√Hz → VRW in m/s/√h.
pub const fn density_to_vrw(density: f32) -> f32 {
    density * 60.0 * G
}

/// Which sensor of a profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensor {
    /// `gyro`.
    Gyro,
    /// `acc`.
    Acc,
    /// `aux`.
    Aux,
}

impl Sensor {
    /// The section name in a profile file.
    pub const fn key(self) -> &'static str {
        match self {
            Sensor::Gyro => "gyro",
            Sensor::Acc => "acc",
            Sensor::Aux => "aux",
        }
    }
}

/// A profile value outside its allowed range: the key and the range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileError {
    /// Section (`gyro`, `acc`, `aux`, `temperature`).
    pub section: &'static str,
    /// Field name, as in a profile file.
    pub key: &'static str,
    /// The value given.
    pub value: f32,
    /// Smallest allowed value.
    pub min: f32,
    /// Largest allowed value.
    pub max: f32,
}

impl core::fmt::Display for ProfileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{}.{} = {} is outside the allowed range {} ..= {}",
            self.section, self.key, self.value, self.min, self.max
        )
    }
}

/// Allowed ranges of a [`SensorSpec`]'s fields: (key, min, max) for a gyro
/// (°/s) and an accelerometer (g). The ranges bound what the engines can
/// represent (fixed point: ±4095 °/s, ±128 g of truth; M − I within ±¼)
/// and what is physical; they are wide on purpose.
const GYRO_LIMITS: [(&str, f32, f32); 13] = [
    ("range", 1.0, 4096.0),
    ("noise_density", 0.0, 1.0),
    ("bias_instability", 0.0, 1.0),
    ("rate_random_walk", 0.0, 0.1),
    ("turn_on_bias_sigma", 0.0, 10.0),
    ("scale_factor_sigma", 0.0, 0.05),
    ("nonlinearity", 0.0, 0.05),
    ("misalignment_sigma", 0.0, 0.05),
    ("g_sensitivity", 0.0, 1.0),
    ("temp_bias", 0.0, 0.1),
    ("temp_scale", 0.0, 1e-3),
    ("resolution", 0.0, 1.0),
    ("bandwidth_hz", 0.0, 2000.0),
];
const ACC_LIMITS: [(&str, f32, f32); 13] = [
    ("range", 0.5, 128.0),
    ("noise_density", 0.0, 0.1),
    ("bias_instability", 0.0, 0.1),
    ("rate_random_walk", 0.0, 0.01),
    ("turn_on_bias_sigma", 0.0, 1.0),
    ("scale_factor_sigma", 0.0, 0.05),
    ("nonlinearity", 0.0, 0.05),
    ("misalignment_sigma", 0.0, 0.05),
    ("g_sensitivity", 0.0, 0.0),
    ("temp_bias", 0.0, 0.01),
    ("temp_scale", 0.0, 1e-3),
    ("resolution", 0.0, 0.1),
    ("bandwidth_hz", 0.0, 2000.0),
];
/// Allowed ranges of a [`TemperatureSpec`].
const TEMPERATURE_LIMITS: [(&str, f32, f32); 3] = [
    ("ambient_c", -60.0, 120.0),
    ("self_heating_c", -20.0, 60.0),
    ("time_constant_s", 0.0, 1e6),
];

impl SensorSpec {
    /// The fields in the order of the limits tables.
    pub fn values(&self) -> [f32; 13] {
        [
            self.range,
            self.noise_density,
            self.bias_instability,
            self.rate_random_walk,
            self.turn_on_bias_sigma,
            self.scale_factor_sigma,
            self.nonlinearity,
            self.misalignment_sigma,
            self.g_sensitivity,
            self.temp_bias,
            self.temp_scale,
            self.resolution,
            self.bandwidth_hz,
        ]
    }

    /// The field names, in the order of [`SensorSpec::values`].
    pub fn keys() -> [&'static str; 13] {
        GYRO_LIMITS.map(|(k, _, _)| k)
    }

    /// The allowed range (min, max) of field `key` for `sensor`.
    pub fn limits(sensor: Sensor, key: &str) -> Option<(f32, f32)> {
        let t = match sensor {
            Sensor::Gyro => &GYRO_LIMITS,
            _ => &ACC_LIMITS,
        };
        t.iter()
            .find(|(k, _, _)| *k == key)
            .map(|&(_, a, b)| (a, b))
    }

    fn check(&self, sensor: Sensor) -> Result<(), ProfileError> {
        let t = match sensor {
            Sensor::Gyro => &GYRO_LIMITS,
            _ => &ACC_LIMITS,
        };
        for (&(key, min, max), value) in t.iter().zip(self.values()) {
            // NaN fails both comparisons: refused too.
            if !(value >= min && value <= max) {
                return Err(ProfileError {
                    section: sensor.key(),
                    key,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }
}

impl TemperatureSpec {
    /// The power-on default: 25 °C, +8 °C, τ 600 s.
    pub const DEFAULT: TemperatureSpec = TemperatureSpec {
        ambient_c: 25.0,
        self_heating_c: 8.0,
        time_constant_s: 600.0,
    };

    /// The field names and values, in file order.
    pub fn fields(&self) -> [(&'static str, f32); 3] {
        [
            (TEMPERATURE_LIMITS[0].0, self.ambient_c),
            (TEMPERATURE_LIMITS[1].0, self.self_heating_c),
            (TEMPERATURE_LIMITS[2].0, self.time_constant_s),
        ]
    }

    /// The allowed range (min, max) of field `key`.
    pub fn limits(key: &str) -> Option<(f32, f32)> {
        TEMPERATURE_LIMITS
            .iter()
            .find(|(k, _, _)| *k == key)
            .map(|&(_, a, b)| (a, b))
    }
}

impl SensorProfile {
    /// Checks every value against its allowed range: the first one outside
    /// it, with its key and range.
    pub fn validate(&self) -> Result<(), ProfileError> {
        self.gyro.check(Sensor::Gyro)?;
        self.acc.check(Sensor::Acc)?;
        self.aux.check(Sensor::Aux)?;
        for (&(key, min, max), (_, value)) in
            TEMPERATURE_LIMITS.iter().zip(self.temperature.fields())
        {
            if !(value >= min && value <= max) {
                return Err(ProfileError {
                    section: "temperature",
                    key,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }

    /// The spec of `sensor`.
    pub fn sensor(&self, sensor: Sensor) -> &SensorSpec {
        match sensor {
            Sensor::Gyro => &self.gyro,
            Sensor::Acc => &self.acc,
            Sensor::Aux => &self.aux,
        }
    }

    /// The spec of `sensor`, to change.
    pub fn sensor_mut(&mut self, sensor: Sensor) -> &mut SensorSpec {
        match sensor {
            Sensor::Gyro => &mut self.gyro,
            Sensor::Acc => &mut self.acc,
            Sensor::Aux => &mut self.aux,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::profiles::BUILTIN;

    #[test]
    fn every_builtin_profile_is_within_its_limits() {
        for b in BUILTIN {
            assert_eq!(b.profile.validate(), Ok(()), "{}", b.name);
        }
    }

    #[test]
    fn a_value_outside_its_range_names_the_key_and_the_range() {
        let mut p = *BUILTIN[0].profile;
        p.acc.range = 500.0;
        let e = p.validate().unwrap_err();
        assert_eq!(
            (e.section, e.key, e.min, e.max),
            ("acc", "range", 0.5, 128.0)
        );
        p.acc.range = 16.0;
        p.gyro.noise_density = f32::NAN;
        assert_eq!(p.validate().unwrap_err().key, "noise_density");
    }

    #[test]
    fn unit_conversions_round_trip() {
        assert!((density_to_arw(arw_to_density(0.16)) - 0.16).abs() < 1e-7);
        assert!((density_to_vrw(vrw_to_density(0.02)) - 0.02).abs() < 1e-7);
    }
}
