//! The temperature the device reports ("average temperature of the three
//! gyros", Table 5.5 note 5) and the error model's temperature input.
//!
//! A unit powers on at the ambient temperature and warms up by its own
//! dissipation, first order:
//! `T(t) = ambient + self_heating · (1 − e^(−t/τ))`, defaults 25 °C, +8 °C,
//! τ = 600 s. It is advanced every [`UPDATE_TICKS`] ticks by the exact
//! discrete step, so it costs nothing on the other ticks. A temperature from
//! the truth (a trajectory file) or from a fault override replaces it. (The
//! `fixed-point` chain then updates the error model's temperature terms one
//! sensor axis a tick, over the next nine ticks.)

use super::profile::TemperatureSpec;
use libm::expf;

/// The model is advanced once every this many ticks.
pub(crate) const UPDATE_TICKS: u32 = 64;

/// Operating temperature range of the KERNEL family, °C: outside it the chain
/// reports over-temperature (`Health::over_temperature`; KERNEL USW bit 14). (−40…+85 °C, the industrial range the
/// KERNEL datasheets give.)
pub(crate) const OPERATING_RANGE_C: (f32, f32) = (-40.0, 85.0);

/// Warm-up model of the sensor temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TemperatureModel {
    /// Ambient temperature, °C (the temperature at power-on).
    pub ambient_c: f32,
    /// Steady-state rise above ambient from self-heating, °C.
    pub self_heating_c: f32,
    /// Warm-up time constant, s.
    pub time_constant_s: f32,
    rise: f32,
    k: f32,
}

impl Default for TemperatureModel {
    fn default() -> Self {
        TemperatureModel {
            ambient_c: 25.0,
            self_heating_c: 8.0,
            time_constant_s: 600.0,
            rise: 0.0,
            k: 0.0,
        }
    }
}

impl TemperatureModel {
    /// The model of a profile's [`TemperatureSpec`] (cold: at ambient).
    pub(crate) fn from_spec(spec: &TemperatureSpec) -> Self {
        TemperatureModel {
            ambient_c: spec.ambient_c,
            self_heating_c: spec.self_heating_c,
            time_constant_s: spec.time_constant_s,
            ..TemperatureModel::default()
        }
    }

    /// The modelled temperature now, °C.
    pub(crate) fn temperature_c(&self) -> f32 {
        self.ambient_c + self.rise
    }

    /// Sets the step [`TemperatureModel::step`] takes to `seconds` (after
    /// any change of the parameters).
    pub(crate) fn prepare(&mut self, seconds: f32) {
        self.k = if self.time_constant_s > 0.0 {
            1.0 - expf(-seconds / self.time_constant_s)
        } else {
            1.0
        };
    }

    /// Advances the model by the prepared step (exact for a first-order lag).
    #[inline]
    pub(crate) fn step(&mut self) {
        self.rise += (self.self_heating_c - self.rise) * self.k;
    }
}
