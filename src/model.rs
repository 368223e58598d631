//! The unit a device emulates, as the shell and the chain see it: its
//! sensor half, with no protocol in it.
//!
//! A [`Model`] is what every personality's unit has: the internal update
//! rate, the aux accelerometer, the EXTRIG and BOOT pins, and its built-in
//! sensor profile ([`crate::sensor::profiles`], where each cites its
//! source). A [`Product`] is one configured unit: a model and its
//! measurement ranges. The rows themselves are each personality's, in its
//! own folder with its product tables: the KERNEL models with their
//! formats, LPF codes and product codes in `kernel/model.rs` (ICD section
//! 2.1, 3.2.2), the IMX-5 in `isb/model.rs`.

use crate::sensor::profile::SensorProfile;

/// A unit's sensor half: what the shell and the chain read of it.
#[derive(Debug)]
pub struct Model {
    /// Short name (`K110`, `IMX-5`), as the built-in profiles name it.
    pub short: &'static str,
    /// Internal update rate, Hz: the tick rate of the shell and the chain
    /// (KERNEL: ICD Table 4.3).
    pub internal_rate_hz: u32,
    /// Whether the unit has the aux (high-g, ±90 g) accelerometer the chain
    /// then measures and filters (KERNEL K120, K220: ICD 2.1).
    pub aux_accel: bool,
    /// Whether the unit has an EXTRIG (strobe) input pin (KERNEL: Table 4.1
    /// note 1; the IMX-5's strobe input).
    pub extrig: bool,
    /// BOOT input enters firmware-update mode when held low at power-on
    /// (KERNEL K100: pull-up, Table 4.1 note 4; K110M: Table 4.4 pin 9);
    /// otherwise when held high (note 5).
    pub boot_active_low: bool,
    /// The built-in sensor profile: every error term of its sensors.
    pub profile: &'static SensorProfile,
}

/// Rows are equal when they are the same unit (the short name is unique
/// among the rows; the profile holds `f32`s, which have no `Eq`).
impl PartialEq for Model {
    fn eq(&self, other: &Self) -> bool {
        self.short == other.short
    }
}

impl Eq for Model {}

/// One configured unit: a model and its measurement ranges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Product {
    /// The unit's row.
    pub model: &'static Model,
    /// Gyro measurement range, ± °/s.
    pub gyro_range_dps: u32,
    /// Main accelerometer measurement range, ± g.
    pub accel_range_g: u32,
}

impl Product {
    /// The sensor profile of this product: its model's
    /// ([`Model::profile`]) with the product's ranges as the gyro and
    /// accelerometer ranges.
    pub fn sensor_profile(&self) -> SensorProfile {
        let mut p = *self.model.profile;
        p.gyro.range = self.gyro_range_dps as f32;
        p.acc.range = self.accel_range_g as f32;
        p
    }
}
