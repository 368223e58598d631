//! The unit the ISB personality emulates: an Inertial Sense IMX-5 in IMU
//! mode. Its sensor half is all the shell and the chain read: the chain at
//! 2 kHz, EXTRIG as the strobe input, and its sensor profile
//! ([`profiles::IMX5_PROFILE`]: ±4000 °/s, ±16 g and the datasheet's noise
//! figures, `sensor/profiles.rs` citing them).

use crate::model::{Model, Product};
use crate::sensor::profiles;

/// The IMX-5's row: not a KERNEL model (`--model` never takes it).
pub static IMX5: Model = Model {
    short: "IMX-5",
    internal_rate_hz: 2000,
    aux_accel: false,
    extrig: true,
    boot_active_low: false,
    profile: &profiles::IMX5_PROFILE,
};

/// The IMX-5 on the neutral product.
impl Product {
    /// The IMX-5 of the ISB personality ([`IMX5`]): one range, its
    /// profile's (±4000 °/s, ±16 g).
    pub const fn imx5() -> Product {
        Product {
            model: &IMX5,
            gyro_range_dps: 4000,
            accel_range_g: 16,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_imx5_keeps_its_own_ranges() {
        assert!(core::ptr::eq(IMX5.profile, &profiles::IMX5_PROFILE));
        assert!(core::ptr::eq(
            profiles::builtin("imx5").unwrap().profile,
            IMX5.profile
        ));
        let p = Product::imx5().sensor_profile();
        assert_eq!((p.gyro.range, p.acc.range), (4000.0, 16.0));
        assert_eq!(p.gyro.noise_density, 0.23 / 60.0);
        assert_eq!(
            profiles::builtin("imx-5-2022")
                .unwrap()
                .profile
                .gyro
                .noise_density,
            0.16 / 60.0
        );
    }
}
