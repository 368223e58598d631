//! User Defined Data (ICD 5.2.8, Tables 5.13–5.15, 5.19–5.21): the type
//! table — one row per type — configuration checking and the config reply.

use super::block::{Block, UDD_CONFIG_OFFSET, UDD_MAX_TYPES};
use super::fields::Field;
use crate::kernel::model::Capability;
use crate::model::Product;

/// One UDD type of Table 5.15.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UddType {
    /// Type code (Table 5.14).
    pub code: u8,
    /// Description.
    pub name: &'static str,
    /// Layout (its size is the Table 5.15 size).
    pub field: Field,
    /// Marked `*` in Table 5.15: the only types a K201 takes (note 5).
    pub starred: bool,
    /// Model feature the type needs (Table 5.14/5.15 notes,
    /// `docs/protocol-facts.md` "KERNEL numbers that must agree").
    pub requires: Option<Capability>,
}

impl UddType {
    /// Whether the type carries the orientation ([`Field::is_attitude`]):
    /// a UDD stream with it waits for the initial alignment (5.3.1).
    pub fn carries_attitude(&self) -> bool {
        self.field.is_attitude()
    }
}

const fn t(
    code: u8,
    name: &'static str,
    field: Field,
    starred: bool,
    requires: Option<Capability>,
) -> UddType {
    UddType {
        code,
        name,
        field,
        starred,
        requires,
    }
}

use Capability::*;

/// Table 5.15.
pub static UDD_TYPES: &[UddType] = &[
    t(0x02, "IMU Time", Field::ImuTime, true, None),
    t(0x05, "Second Fraction", Field::SecondFraction, false, None),
    t(0x07, "Orientation Angles", Field::Euler, false, None),
    t(0x08, "Orientation Angles HR", Field::EulerHr, false, None),
    t(0x09, "Quaternion of Orientation", Field::Quat, false, None),
    t(0x20, "Gyro Data", Field::Gyro, false, None),
    t(0x21, "Gyro Data HR", Field::GyroHr, true, None),
    t(0x22, "Accelerometer Data", Field::Acc, false, None),
    t(0x23, "Accelerometer Data HR", Field::AccHr, true, None),
    t(
        0x2D,
        "Bias-compensated Gyro Data",
        Field::GyroBiasCompHr,
        false,
        None,
    ),
    t(
        0x2E,
        "Gyro Bias",
        Field::GyroBiasHr,
        false,
        Some(GyroBiasOutput),
    ),
    t(
        0x2F,
        "Aux Accelerometer",
        Field::AuxAccHr,
        false,
        Some(AuxAccel),
    ),
    t(
        0x91,
        "Filtered Low-G Accels HR",
        Field::FilteredAccHr,
        false,
        None,
    ),
    t(
        0x92,
        "Filtered High-G Accels HR",
        Field::FilteredAuxAccHr,
        false,
        None,
    ),
    t(
        0x50,
        "Supply Voltage",
        Field::SupplyVoltage,
        false,
        Some(SupplyVoltage),
    ),
    t(0x52, "Temperature", Field::Temperature, true, None),
    t(0x53, "Unit Status Word", Field::Usw, true, None),
    t(
        0x5B,
        "Unit Status Word Extended",
        Field::UswExt,
        false,
        None,
    ),
];

/// Factory UDD configuration: IMU time, gyro HR, accel HR, temperature, USW
/// — all starred, so valid on every model (emulator decision).
pub(crate) const DEFAULT_CONFIG: &[u8] = &[0x02, 0x21, 0x23, 0x52, 0x53];

/// A UDD configuration: the ordered type codes.
pub(crate) type Config = heapless::Vec<u8, UDD_MAX_TYPES>;

/// The row of a type code.
pub fn find(code: u8) -> Option<&'static UddType> {
    UDD_TYPES.iter().find(|t| t.code == code)
}

/// The row of `code` if `product` supports it.
pub fn supported(code: u8, product: &Product) -> Option<&'static UddType> {
    find(code).filter(|t| {
        (t.starred || !crate::kernel::model::row(product.model).udd_starred_only)
            && t.requires.is_none_or(|c| product.model.has(c))
    })
}

/// UDD payload length for a configuration: `1 + N + Σ sizes` (Table 5.13).
pub fn payload_len(types: &[u8]) -> usize {
    1 + types.len()
        + types
            .iter()
            .filter_map(|&c| find(c))
            .map(|t| t.field.size())
            .sum::<usize>()
}

/// Writes `types` (at most [`UDD_MAX_TYPES`]) to the block's UDD region.
pub(crate) fn write_config(block: &mut Block, types: &[u8]) {
    let n = types.len().min(UDD_MAX_TYPES);
    let region = &mut block[UDD_CONFIG_OFFSET..UDD_CONFIG_OFFSET + 1 + UDD_MAX_TYPES];
    region.fill(0);
    region[0] = n as u8;
    region[1..1 + n].copy_from_slice(&types[..n]);
}

/// Reads the block's UDD configuration; `None` if it is not a valid one for
/// `product`.
pub(crate) fn read_config(block: &Block, product: &Product) -> Option<Config> {
    let n = usize::from(block[UDD_CONFIG_OFFSET]);
    if n == 0 || n > UDD_MAX_TYPES {
        return None;
    }
    let list = &block[UDD_CONFIG_OFFSET + 1..UDD_CONFIG_OFFSET + 1 + n];
    if list.iter().any(|&c| supported(c, product).is_none()) {
        return None;
    }
    Config::from_slice(list).ok()
}

/// Table 5.21 bit 0: the message's structure is wrong (length ≠ 1 + N).
pub(crate) const ERR_STRUCTURE: u8 = 0x01;
/// Table 5.21 bit 1: the data is wrong (N = 0 or N > 16).
pub(crate) const ERR_DATA: u8 = 0x02;
/// Table 5.21 bit 2: wrong types ordered (see the bitmap).
pub(crate) const ERR_TYPES: u8 = 0x04;
/// Table 5.21 bit 3: too large for the data rate at this baud rate; the rate
/// was lowered.
pub(crate) const ERR_RATE: u8 = 0x08;

/// The outcome of checking a config message (Table 5.19 payload).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Checked {
    /// Accepted: the new configuration.
    Ok(Config),
    /// Refused: Table 5.21 bits 0–2 and the wrong-type bitmap.
    Refused {
        /// Error bits.
        errors: u8,
        /// Bit i set = i-th ordered type wrong (Table 5.20 bytes 3–4).
        wrong_types: u16,
    },
}

/// Checks a Table 5.19 payload `N, list…` for `product`.
pub(crate) fn check(payload: &[u8], product: &Product) -> Checked {
    let Some((&n, list)) = payload.split_first() else {
        return Checked::Refused {
            errors: ERR_STRUCTURE,
            wrong_types: 0,
        };
    };
    let mut errors = 0;
    if list.len() != usize::from(n) {
        errors |= ERR_STRUCTURE;
    }
    if n == 0 || usize::from(n) > UDD_MAX_TYPES {
        errors |= ERR_DATA;
    }
    let mut wrong_types = 0u16;
    for (i, &c) in list.iter().enumerate().take(16) {
        if supported(c, product).is_none() {
            wrong_types |= 1 << i;
        }
    }
    if wrong_types != 0 {
        errors |= ERR_TYPES;
    }
    if errors != 0 {
        return Checked::Refused {
            errors,
            wrong_types,
        };
    }
    match Config::from_slice(list) {
        Ok(c) => Checked::Ok(c),
        Err(_) => Checked::Refused {
            errors: ERR_DATA,
            wrong_types,
        },
    }
}

/// The 8-byte reply to a config message (Table 5.20 as corrected in
/// `docs/protocol-facts.md`): checksum of the received message (0 if refused), error bits,
/// wrong-type bitmap, maximum data rate (u16), reserved.
pub(crate) fn config_reply(checksum: u16, errors: u8, wrong_types: u16, max_rate: u16) -> [u8; 8] {
    let c = checksum.to_le_bytes();
    let w = wrong_types.to_le_bytes();
    let r = max_rate.to_le_bytes();
    [c[0], c[1], errors, w[0], w[1], r[0], r[1], 0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_those_of_table_5_15() {
        let expect = [
            (0x02, 8),
            (0x05, 4),
            (0x07, 6),
            (0x08, 12),
            (0x09, 8),
            (0x20, 6),
            (0x21, 12),
            (0x22, 6),
            (0x23, 12),
            (0x2D, 12),
            (0x2E, 12),
            (0x2F, 12),
            (0x91, 12),
            (0x92, 12),
            (0x50, 2),
            (0x52, 2),
            (0x53, 2),
            (0x5B, 2),
        ];
        assert_eq!(expect.len(), UDD_TYPES.len());
        for (code, size) in expect {
            assert_eq!(find(code).unwrap().field.size(), size, "{code:#x}");
        }
    }

    #[test]
    fn orientation_types_carry_the_attitude() {
        let with: std::vec::Vec<u8> = UDD_TYPES
            .iter()
            .filter(|t| t.carries_attitude())
            .map(|t| t.code)
            .collect();
        assert_eq!(with, [0x07, 0x08, 0x09]);
    }

    #[test]
    fn per_model_support_follows_the_notes() {
        let p = |s| Product::parse(s).unwrap();
        for c in [0x02, 0x21, 0x23, 0x52, 0x53] {
            assert!(supported(c, &p("K201")).is_some());
        }
        assert!(supported(0x20, &p("K201")).is_none());
        assert!(supported(0x2E, &p("K100")).is_none());
        assert!(supported(0x2E, &p("K102")).is_none());
        assert!(supported(0x2E, &p("K110")).is_some());
        assert!(supported(0x2F, &p("K110")).is_none());
        assert!(supported(0x2F, &p("K120")).is_some());
        assert!(supported(0x2F, &p("K220")).is_some());
        assert!(supported(0x50, &p("K100")).is_some());
        assert!(supported(0x50, &p("K110")).is_none());
    }
}
