//! The KERNEL models and their product-code options — one table, one place.
//!
//! Sources: ICD section 2.1 (models), 3.2.2 (product codes), Table 4.1 notes
//! (EXTRIG, BOOT polarity), Table 4.3 (internal rate), 5.2 (K201 formats),
//! Table 5.6 (KG/KA), Table 5.15 notes (per-model UDD types), Table 5.24
//! (Sensors_Measurement_Range nibbles, LPF codes), and
//! `docs/protocol-facts.md` "KERNEL numbers that must agree".
//!
//! Each row is a unit's protocol-free sensor half ([`Model`]: internal
//! rate, aux accelerometer, pins, sensor profile) and the KERNEL's product
//! columns beside it ([`KernelModel`]). The KERNEL's conveniences on the
//! neutral types — [`Product::parse`], [`Product::code`],
//! [`Product::measurement_range`], [`Model::has`],
//! [`Model::supports_format`] — are defined here.

use crate::model::{Model, Product};

/// Gyroscope measurement range option of a product code (`G450`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GyroRange {
    /// ±450 °/s, KG = 50.
    G450,
    /// ±950 °/s, KG = 20.
    G950,
    /// ±2000 °/s, KG = 10.
    G2000,
}

/// Accelerometer measurement range option of a product code (`A8`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AccelRange {
    /// ±8 g, KA = 4000.
    A8,
    /// ±15 g, KA = 2000.
    A15,
    /// ±40 g, KA = 500.
    A40,
}

impl GyroRange {
    /// The option of a ± `dps` range (G2000 for any range no option has).
    pub const fn of_dps(dps: u32) -> Self {
        match dps {
            450 => GyroRange::G450,
            950 => GyroRange::G950,
            _ => GyroRange::G2000,
        }
    }
    /// Full scale in °/s.
    pub const fn full_scale(self) -> u32 {
        match self {
            GyroRange::G450 => 450,
            GyroRange::G950 => 950,
            GyroRange::G2000 => 2000,
        }
    }
    /// KG scale factor of Table 5.6.
    pub const fn kg(self) -> u32 {
        match self {
            GyroRange::G450 => 50,
            GyroRange::G950 => 20,
            GyroRange::G2000 => 10,
        }
    }
    /// High nibble of Sensors_Measurement_Range (Table 5.24).
    pub const fn nibble(self) -> u8 {
        match self {
            GyroRange::G450 => 6,
            GyroRange::G950 => 8,
            GyroRange::G2000 => 9,
        }
    }
    /// The product-code option (`G2000`).
    pub const fn option(self) -> &'static str {
        match self {
            GyroRange::G450 => "G450",
            GyroRange::G950 => "G950",
            GyroRange::G2000 => "G2000",
        }
    }
    fn parse(s: &str) -> Option<Self> {
        match s {
            "G450" => Some(GyroRange::G450),
            "G950" => Some(GyroRange::G950),
            "G2000" => Some(GyroRange::G2000),
            _ => None,
        }
    }
}

impl AccelRange {
    /// The option of a ± `g` range (A40 for any range no option has).
    pub const fn of_g(g: u32) -> Self {
        match g {
            8 => AccelRange::A8,
            15 => AccelRange::A15,
            _ => AccelRange::A40,
        }
    }
    /// Full scale in g.
    pub const fn full_scale(self) -> u32 {
        match self {
            AccelRange::A8 => 8,
            AccelRange::A15 => 15,
            AccelRange::A40 => 40,
        }
    }
    /// KA scale factor of Table 5.6.
    pub const fn ka(self) -> u32 {
        match self {
            AccelRange::A8 => 4000,
            AccelRange::A15 => 2000,
            AccelRange::A40 => 500,
        }
    }
    /// Low nibble of Sensors_Measurement_Range (Table 5.24).
    pub const fn nibble(self) -> u8 {
        match self {
            AccelRange::A8 => 3,
            AccelRange::A15 => 5,
            AccelRange::A40 => 6,
        }
    }
    /// The product-code option (`A40`).
    pub const fn option(self) -> &'static str {
        match self {
            AccelRange::A8 => "A8",
            AccelRange::A15 => "A15",
            AccelRange::A40 => "A40",
        }
    }
    fn parse(s: &str) -> Option<Self> {
        match s {
            "A8" => Some(AccelRange::A8),
            "A15" => Some(AccelRange::A15),
            "A40" => Some(AccelRange::A40),
            _ => None,
        }
    }
}

/// Optional features a UDD type (Table 5.15) or a parameter may require.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Capability {
    /// Gyro bias output, UDD 0x2E (not K100, K102, K201).
    GyroBiasOutput,
    /// Aux (high-g, ±90 g) accelerometer: K120, K220 (UDD 0x2F); the
    /// unit's [`Model::aux_accel`].
    AuxAccel,
    /// Supply-voltage measurement: K100, K102 (UDD 0x50).
    SupplyVoltage,
    /// EXTRIG input (Table 4.1 note 1); the unit's [`Model::extrig`].
    Extrig,
}

/// One row of the KERNEL model table: the unit and the KERNEL's columns.
#[derive(Debug)]
pub struct KernelModel {
    /// The unit's sensor half: short name (`K110`, as accepted by
    /// `--model`), internal update rate (Table 4.3), aux accelerometer,
    /// EXTRIG, BOOT level (Table 4.1 notes 4, 5; Table 4.4 pin 9) and
    /// sensor profile.
    pub model: Model,
    /// Number in the product code (`110` in `KERNEL-110-…`; `110M`).
    pub number: &'static str,
    /// Data command codes the model runs (Table 5.16; 5.2 for K201).
    pub formats: &'static [u8],
    /// Only the UDD types marked `*` in Table 5.15 (K201, `docs/protocol-facts.md`).
    pub udd_starred_only: bool,
    /// Optional features the model has beyond the unit's aux accelerometer
    /// and EXTRIG ([`Model::aux_accel`], [`Model::extrig`]).
    pub caps: &'static [Capability],
    /// LPF_Bandwidth codes accepted (Table 5.24; K201 lacks 16/33 Hz).
    pub lpf_codes: &'static [u8],
    /// Product-code options of ICD 3.2.2 in its order; the first is the
    /// default. Models 3.2.2 does not list default to G2000-A40 (and A90 aux
    /// where the model has one).
    pub products: &'static [(GyroRange, AccelRange)],
    /// IMU_type byte of GetDevInfo (Table 5.17). The ICD gives no values;
    /// the emulator uses the model number (100, 102, …; 111 for K110M,
    /// 201 wraps to 201) so host software can tell models apart.
    pub imu_type: u8,
}

impl KernelModel {
    /// Whether the model has `cap`.
    pub fn has(&self, cap: Capability) -> bool {
        match cap {
            AuxAccel => self.model.aux_accel,
            Extrig => self.model.extrig,
            _ => self.caps.contains(&cap),
        }
    }
    /// Whether the model runs data command `code` (Table 5.16).
    pub fn supports_format(&self, code: u8) -> bool {
        self.formats.contains(&code)
    }
}

/// The KERNEL columns of a unit that is no KERNEL model (an IMX-5 driven
/// by the KERNEL personality): no formats, no LPF codes, IMU_type 0.
static UNLISTED: KernelModel = KernelModel {
    model: Model {
        short: "",
        internal_rate_hz: 2000,
        aux_accel: false,
        extrig: false,
        boot_active_low: false,
        profile: &profiles::KERNEL_MID,
    },
    number: "",
    formats: &[],
    udd_starred_only: false,
    caps: &[],
    lpf_codes: &[],
    products: &[(GyroRange::G2000, AccelRange::A40)],
    imu_type: 0,
};

/// The KERNEL row of `model` (a row of [`MODELS`], found by address), or
/// empty KERNEL columns for a unit that is none.
pub fn row(model: &Model) -> &'static KernelModel {
    MODELS
        .iter()
        .find(|m| core::ptr::eq(&m.model, model))
        .unwrap_or(&UNLISTED)
}

/// The KERNEL's view of a unit.
impl Model {
    /// Whether the unit has `cap` (a KERNEL model's capability, ICD 2.1;
    /// the aux accelerometer and EXTRIG of any unit).
    pub fn has(&self, cap: Capability) -> bool {
        match cap {
            AuxAccel => self.aux_accel,
            Extrig => self.extrig,
            _ => row(self).caps.contains(&cap),
        }
    }
    /// Whether the unit runs KERNEL data command `code` (Table 5.16).
    pub fn supports_format(&self, code: u8) -> bool {
        row(self).supports_format(code)
    }
}

const ALL_FORMATS: &[u8] = &[0x33, 0x8F, 0x9B, 0xA5, 0xA6, 0x82, 0x81, 0x95];
const K201_FORMATS: &[u8] = &[0x8F, 0x9B, 0xA5, 0xA6, 0x95];
const ALL_LPF: &[u8] = &[0, 1, 2, 3, 4, 0xFF];
const K201_LPF: &[u8] = &[2, 3, 4, 0xFF];
const G2000_A40: &[(GyroRange, AccelRange)] = &[(GyroRange::G2000, AccelRange::A40)];
/// ICD 3.2.2 lists A40, A15 and A8 (G2000) for K108, K110 and K120.
const LISTED_3_2_2: &[(GyroRange, AccelRange)] = &[
    (GyroRange::G2000, AccelRange::A40),
    (GyroRange::G2000, AccelRange::A15),
    (GyroRange::G2000, AccelRange::A8),
];

use crate::sensor::profiles;
use Capability::*;

/// The model table (ICD section 2.1 models, in its order).
pub static MODELS: &[KernelModel] = &[
    KernelModel {
        model: Model {
            short: "K100",
            internal_rate_hz: 2000,
            aux_accel: false,
            extrig: true,
            boot_active_low: true,
            profile: &profiles::KERNEL_ENTRY,
        },
        number: "100",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[SupplyVoltage],
        lpf_codes: ALL_LPF,
        products: G2000_A40,
        imu_type: 100,
    },
    KernelModel {
        model: Model {
            short: "K102",
            internal_rate_hz: 2000,
            aux_accel: false,
            extrig: false,
            boot_active_low: false,
            profile: &profiles::KERNEL_ENTRY,
        },
        number: "102",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[SupplyVoltage],
        lpf_codes: ALL_LPF,
        products: G2000_A40,
        imu_type: 102,
    },
    KernelModel {
        model: Model {
            short: "K108",
            internal_rate_hz: 2000,
            aux_accel: false,
            extrig: true,
            boot_active_low: false,
            profile: &profiles::KERNEL_MID,
        },
        number: "108",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[GyroBiasOutput],
        lpf_codes: ALL_LPF,
        products: LISTED_3_2_2,
        imu_type: 108,
    },
    KernelModel {
        model: Model {
            short: "K110",
            internal_rate_hz: 2000,
            aux_accel: false,
            extrig: true,
            boot_active_low: false,
            profile: &profiles::KERNEL_MID,
        },
        number: "110",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[GyroBiasOutput],
        lpf_codes: ALL_LPF,
        products: LISTED_3_2_2,
        imu_type: 110,
    },
    KernelModel {
        model: Model {
            short: "K110M",
            internal_rate_hz: 2000,
            aux_accel: false,
            extrig: true,
            boot_active_low: true,
            profile: &profiles::KERNEL_MID,
        },
        number: "110M",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[GyroBiasOutput],
        lpf_codes: ALL_LPF,
        products: LISTED_3_2_2,
        imu_type: 111,
    },
    KernelModel {
        model: Model {
            short: "K120",
            internal_rate_hz: 2000,
            aux_accel: true,
            extrig: true,
            boot_active_low: false,
            profile: &profiles::KERNEL_MID,
        },
        number: "120",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[GyroBiasOutput],
        lpf_codes: ALL_LPF,
        products: LISTED_3_2_2,
        imu_type: 120,
    },
    KernelModel {
        model: Model {
            short: "K201",
            internal_rate_hz: 4000,
            aux_accel: false,
            extrig: false,
            boot_active_low: false,
            profile: &profiles::KERNEL_ENTRY,
        },
        number: "201",
        formats: K201_FORMATS,
        udd_starred_only: true,
        caps: &[],
        lpf_codes: K201_LPF,
        products: G2000_A40,
        imu_type: 201,
    },
    KernelModel {
        model: Model {
            short: "K210",
            internal_rate_hz: 2000,
            aux_accel: false,
            extrig: true,
            boot_active_low: false,
            profile: &profiles::KERNEL_HIGH,
        },
        number: "210",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[GyroBiasOutput],
        lpf_codes: ALL_LPF,
        products: G2000_A40,
        imu_type: 210,
    },
    KernelModel {
        model: Model {
            short: "K220",
            internal_rate_hz: 2000,
            aux_accel: true,
            extrig: true,
            boot_active_low: false,
            profile: &profiles::KERNEL_HIGH,
        },
        number: "220",
        formats: ALL_FORMATS,
        udd_starred_only: false,
        caps: &[GyroBiasOutput],
        lpf_codes: ALL_LPF,
        products: G2000_A40,
        imu_type: 220,
    },
];

/// Why a `--model` string was not understood.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProductError {
    /// Not `Kxxx` nor `KERNEL-xxx[-Gnnn-Ann[A90]][-…]`.
    Syntax,
    /// No such model in [`MODELS`].
    UnknownModel,
    /// Unknown gyro option (G450, G950, G2000).
    UnknownGyroRange,
    /// Unknown accel option (A8, A15, A40, with A90 appended for aux).
    UnknownAccelRange,
    /// `A90` given for a model without aux accelerometer, or missing on one
    /// with it.
    AuxMismatch,
}

impl core::fmt::Display for ProductError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ProductError::Syntax => "expected K110 or KERNEL-110-G2000-A40",
            ProductError::UnknownModel => {
                "unknown model (K100 K102 K108 K110 K110M K120 K201 K210 K220)"
            }
            ProductError::UnknownGyroRange => "gyro range must be G450, G950 or G2000",
            ProductError::UnknownAccelRange => "accel range must be A8, A15 or A40",
            ProductError::AuxMismatch => "A90 (aux accelerometer) exists exactly on K120 and K220",
        })
    }
}

/// The KERNEL's product codes (ICD 3.2.2) on the neutral product.
impl Product {
    /// Parses `K120`, `KERNEL-120`, or a product code such as
    /// `KERNEL-120-G2000-A40A90` (trailing `-TGA-C12-S-V1.2` options are
    /// accepted and ignored). A bare model takes its first product code.
    pub fn parse(s: &str) -> Result<Product, ProductError> {
        let s = s.trim();
        let mut parts = s.split('-');
        let head = parts.next().ok_or(ProductError::Syntax)?;
        let number = if head.eq_ignore_ascii_case("KERNEL") {
            parts.next().ok_or(ProductError::Syntax)?
        } else if let Some(n) = head.strip_prefix('K').or_else(|| head.strip_prefix('k')) {
            n
        } else {
            return Err(ProductError::Syntax);
        };
        let row = MODELS
            .iter()
            .find(|m| m.number.eq_ignore_ascii_case(number))
            .ok_or(ProductError::UnknownModel)?;
        let model = &row.model;
        let (dg, da) = row.products[0];
        let (gyro, accel) = match (parts.next(), parts.next()) {
            (None, _) => (dg, da),
            (Some(g), Some(a)) => {
                let gyro = GyroRange::parse(g).ok_or(ProductError::UnknownGyroRange)?;
                let (main, aux) = match a.strip_suffix("A90") {
                    Some(main) => (main, true),
                    None => (a, false),
                };
                let accel = AccelRange::parse(main).ok_or(ProductError::UnknownAccelRange)?;
                if aux != model.aux_accel {
                    return Err(ProductError::AuxMismatch);
                }
                (gyro, accel)
            }
            (Some(_), None) => return Err(ProductError::Syntax),
        };
        Ok(Product {
            model,
            gyro_range_dps: gyro.full_scale(),
            accel_range_g: accel.full_scale(),
        })
    }

    /// The product code, e.g. `KERNEL-120-G2000-A40A90`.
    pub fn code(&self) -> heapless::String<32> {
        let mut s = heapless::String::new();
        let aux = if self.model.aux_accel { "A90" } else { "" };
        // 32 bytes always fit the longest code (KERNEL-110M-G2000-A15 = 21);
        // no core::fmt, which would cost firmware flash.
        for part in [
            "KERNEL-",
            row(self.model).number,
            "-",
            self.gyro().option(),
            "-",
            self.accel().option(),
            aux,
        ] {
            let _ = s.push_str(part);
        }
        s
    }

    /// The read-only Sensors_Measurement_Range byte (ID 0x028F, Table 5.24).
    pub const fn measurement_range(&self) -> u8 {
        (self.gyro().nibble() << 4) | self.accel().nibble()
    }

    /// The gyro range as a product-code option (KG, Table 5.6).
    pub const fn gyro(&self) -> GyroRange {
        GyroRange::of_dps(self.gyro_range_dps)
    }

    /// The main accelerometer range as a product-code option (KA, Table 5.6).
    pub const fn accel(&self) -> AccelRange {
        AccelRange::of_g(self.accel_range_g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_model_row_carries_its_sensor_profile() {
        use profiles::{KERNEL_ENTRY as E, KERNEL_HIGH as H, KERNEL_MID as M};
        let expect = [
            ("K100", &E),
            ("K102", &E),
            ("K108", &M),
            ("K110", &M),
            ("K110M", &M),
            ("K120", &M),
            ("K201", &E),
            ("K210", &H),
            ("K220", &H),
        ];
        assert_eq!(MODELS.len(), expect.len());
        for (m, (short, p)) in MODELS.iter().zip(expect) {
            assert_eq!(m.model.short, short);
            assert!(core::ptr::eq(m.model.profile, p), "{short}");
        }
    }

    #[test]
    fn every_model_has_the_builtin_profile_of_its_name() {
        use profiles::{builtin, BUILTIN};
        for m in MODELS.iter().map(|m| &m.model) {
            let b = builtin(m.short).unwrap();
            assert!(core::ptr::eq(b.profile, m.profile), "{}", m.short);
        }
        assert_eq!(BUILTIN.len(), MODELS.len() + 2);
        for b in BUILTIN {
            assert_eq!(b.has_aux(), matches!(b.name, "K120" | "K220"), "{}", b.name);
        }
        for m in MODELS.iter().map(|m| &m.model) {
            let b = builtin(m.short).unwrap();
            assert_eq!(b.has_aux(), m.has(Capability::AuxAccel), "{}", m.short);
        }
    }

    #[test]
    fn a_product_code_chooses_the_kernel_ranges() {
        let p = Product::parse("KERNEL-110-G2000-A8")
            .unwrap()
            .sensor_profile();
        assert_eq!((p.gyro.range, p.acc.range), (2000.0, 8.0));
    }

    #[test]
    fn bare_names_take_the_first_product_code_of_3_2_2() {
        assert_eq!(
            Product::parse("K120").unwrap().code(),
            "KERNEL-120-G2000-A40A90"
        );
        assert_eq!(
            Product::parse("K110").unwrap().code(),
            "KERNEL-110-G2000-A40"
        );
        assert_eq!(
            Product::parse("K201").unwrap().code(),
            "KERNEL-201-G2000-A40"
        );
        assert_eq!(
            Product::parse("K220").unwrap().code(),
            "KERNEL-220-G2000-A40A90"
        );
        assert_eq!(
            Product::parse("KERNEL-110M").unwrap().code(),
            "KERNEL-110M-G2000-A40"
        );
    }

    #[test]
    fn product_codes_parse_with_and_without_suffix() {
        let p = Product::parse("KERNEL-120-G2000-A8A90-TGA-C12-S-V1.2").unwrap();
        assert_eq!((p.gyro(), p.accel()), (GyroRange::G2000, AccelRange::A8));
        assert_eq!(p.measurement_range(), 0x93); // the 5.3.8.1 example
        let p = Product::parse("KERNEL-100-G450-A15").unwrap();
        assert_eq!(p.measurement_range(), 0x65);
        assert_eq!(
            Product::parse("KERNEL-110-G2000-A40A90"),
            Err(ProductError::AuxMismatch)
        );
        assert_eq!(
            Product::parse("KERNEL-120-G2000-A40"),
            Err(ProductError::AuxMismatch)
        );
        assert_eq!(Product::parse("K999"), Err(ProductError::UnknownModel));
        assert_eq!(
            Product::parse("KERNEL-110-G300-A40"),
            Err(ProductError::UnknownGyroRange)
        );
        assert_eq!(Product::parse("x"), Err(ProductError::Syntax));
    }
}
