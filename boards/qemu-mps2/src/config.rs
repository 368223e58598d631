//! The board's configuration from the semihosting command line:
//!
//! ```text
//! -semihosting-config enable=on,target=native,arg=model=K110,arg=seed=7,arg=flash=/tmp/k.flash,arg=boot=float
//! ```
//!
//! Words without `=` (QEMU puts the kernel path first when no `arg=` is
//! given) are ignored. Keys: `model` (a model or product code, default
//! K110; not in the `isb` image, whose product is always the IMX-5), `seed` (u64, default 0), `flash` (host file of the 8 KiB flash
//! image; none = RAM only, lost at exit), `boot` (`high`, `low` or `float`:
//! the BOOT input at power-on, default `float`).

use imu_emu::device::Level;
use imu_emu::model::Product;

/// Longest flash path.
pub const PATH_MAX: usize = 200;

/// What the command line said.
pub struct Config {
    /// Emulated product.
    pub product: Product,
    /// Seed.
    pub seed: u64,
    /// Flash image file.
    pub flash: Option<heapless::Vec<u8, PATH_MAX>>,
    /// BOOT level at power-on.
    pub boot: Option<Level>,
}

/// A word the board did not understand.
#[derive(Debug)]
pub struct BadArg<'a>(pub &'a str);

impl Config {
    /// Parses the command line.
    pub fn parse(cmdline: &str) -> Result<Config, BadArg<'_>> {
        let mut c = Config {
            #[cfg(not(feature = "isb"))]
            product: Product::parse("K110").map_err(|_| BadArg("K110"))?,
            #[cfg(feature = "isb")]
            product: Product::imx5(),
            seed: 0,
            flash: None,
            boot: None,
        };
        for word in cmdline.split_ascii_whitespace() {
            let Some((k, v)) = word.split_once('=') else {
                continue;
            };
            match k {
                #[cfg(not(feature = "isb"))]
                "model" => c.product = Product::parse(v).map_err(|_| BadArg(word))?,
                "seed" => c.seed = v.parse().map_err(|_| BadArg(word))?,
                "flash" => {
                    c.flash =
                        Some(heapless::Vec::from_slice(v.as_bytes()).map_err(|_| BadArg(word))?)
                }
                "boot" => {
                    c.boot = match v {
                        "high" | "1" => Some(Level::High),
                        "low" | "0" => Some(Level::Low),
                        "float" | "" => None,
                        _ => return Err(BadArg(word)),
                    }
                }
                _ => return Err(BadArg(word)),
            }
        }
        Ok(c)
    }
}
