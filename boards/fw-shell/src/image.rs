//! What a firmware image is built as, the same on every MCU board: its
//! protocol personality (the board's feature `isb`, forwarded to this
//! crate's), its product and seed (fixed at build time), and the BOOT level
//! sampled at reset. One image carries one personality (the RP2040 has no
//! room for two), so the choice is a type, made here once for the boards.

use imu_emu::device::{Level, PowerOn};
use imu_emu::model::Product;

/// The image's protocol personality: the KERNEL.
#[cfg(not(feature = "isb"))]
pub type Proto = imu_emu::kernel::Kernel;
/// The image's protocol personality (feature `isb`): the IMX-5 over ISB.
#[cfg(feature = "isb")]
pub type Proto = imu_emu::isb::Isb;

/// The emulated product: a KERNEL image's is `IMU_EMU_MODEL` at build time
/// (a model or product code, default K110; one that does not parse stops
/// the image at reset). An ISB image is always an IMX-5; its line starts at
/// FLASH_CONFIG's ser0BaudRate (921 600 bit/s), set by
/// [`crate::Shell::new`].
pub fn product() -> Product {
    #[cfg(not(feature = "isb"))]
    let product = Product::parse(option_env!("IMU_EMU_MODEL").unwrap_or("K110"))
        .unwrap_or_else(|_| panic!("IMU_EMU_MODEL is not a KERNEL model"));
    #[cfg(feature = "isb")]
    let product = Product::imx5();
    product
}

/// The seed of every random process: `IMU_EMU_SEED` at build time, 0 if
/// unset or not a number.
pub fn seed() -> u64 {
    option_env!("IMU_EMU_SEED")
        .and_then(|s| s.parse().ok())
        .unwrap_or(0)
}

/// What the image powers on with: [`product`], [`seed`] and `boot`.
pub fn power_on_config(boot: Option<Level>) -> PowerOn {
    PowerOn {
        product: product(),
        boot,
        seed: seed(),
    }
}

/// The BOOT input read with its pull-up (`up`) and then its pull-down
/// (`down`) on: a driven pin reads the same both times (its level), a
/// floating one follows the pull (`None`, not asserted).
pub fn boot_from_pulls(up: bool, down: bool) -> Option<Level> {
    if up == down {
        crate::boot_level(Some(up))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_driven_boot_pin_reads_its_level_and_a_floating_one_none() {
        assert_eq!(boot_from_pulls(true, true), Some(Level::High));
        assert_eq!(boot_from_pulls(false, false), Some(Level::Low));
        assert_eq!(boot_from_pulls(true, false), None);
    }

    #[test]
    fn the_image_powers_on_with_its_product_seed_and_boot() {
        let cfg = power_on_config(Some(Level::Low));
        assert_eq!(cfg.boot, Some(Level::Low));
        assert_eq!(cfg.seed, seed());
        assert_eq!(cfg.product, product());
        #[cfg(not(feature = "isb"))]
        assert!(cfg.product.model.short.starts_with('K'));
    }
}
