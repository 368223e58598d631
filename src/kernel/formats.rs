//! The fixed output formats (ICD 5.2.1–5.2.7, Tables 5.5–5.12, 5.16) — one
//! row each — and the acknowledgement/announcement messages.

use super::fields::Field::{self, *};

/// Data command code of User Defined Data (Table 5.16).
pub const UDD: u8 = 0x95;

/// One fixed output format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FormatSpec {
    /// Data command code = message identifier of its frames (Table 5.16).
    pub code: u8,
    /// Name in Table 5.4.
    pub name: &'static str,
    /// Payload layout, in order.
    pub fields: &'static [Field],
}

/// The seven fixed formats.
pub static FORMATS: &[FormatSpec] = &[
    // Table 5.5: heading, pitch, roll, gyro·KG, acc·KA, mag 0, reserved 4,
    // USW, reserved 2, temperature — 34 bytes.
    FormatSpec {
        code: 0x33,
        name: "Orientation",
        fields: &[
            Euler,
            Gyro,
            Acc,
            Zero(6),
            Zero(4),
            Usw,
            Zero(2),
            Temperature,
        ],
    },
    // Table 5.7: gyro HR, acc HR, counter, USW, reserved, temperature — 32.
    FormatSpec {
        code: 0x8F,
        name: "GA",
        fields: &[GyroHr, AccHr, Counter, Usw, Zero(2), Temperature],
    },
    // Table 5.8: gyro HR, acc HR, time flag, second fraction, temperature — 32.
    FormatSpec {
        code: 0x9B,
        name: "GAm",
        fields: &[GyroHr, AccHr, TimeFlags, SecondFraction, Temperature],
    },
    // Table 5.11: gyro, acc1, acc2 (aux), reserved, USW, reserved, temp — 44.
    FormatSpec {
        code: 0xA5,
        name: "GAA",
        fields: &[GyroHr, AccHr, AuxAccHr, Zero(2), Usw, Zero(2), Temperature],
    },
    // Table 5.12: gyro, acc1, acc2, time flag, second fraction, temp — 44.
    FormatSpec {
        code: 0xA6,
        name: "GAAm",
        fields: &[
            GyroHr,
            AccHr,
            AuxAccHr,
            TimeFlags,
            SecondFraction,
            Temperature,
        ],
    },
    // Table 5.9: heading, pitch, roll, q0..q3, reserved 14, USW, reserved,
    // temperature — 34.
    FormatSpec {
        code: 0x82,
        name: "Quaternion",
        fields: &[Euler, Quat, Zero(14), Usw, Zero(2), Temperature],
    },
    // Table 5.10: HR angles, gyro HR, acc HR, mag 0, counter, reserved, USW,
    // reserved, temperature — 52.
    FormatSpec {
        code: 0x81,
        name: "Calibrated HR",
        fields: &[
            EulerHr,
            GyroHr,
            AccHr,
            Zero(6),
            Counter,
            Zero(2),
            Usw,
            Zero(2),
            Temperature,
        ],
    },
];

/// The fixed format with data command `code`.
pub fn find(code: u8) -> Option<&'static FormatSpec> {
    FORMATS.iter().find(|f| f.code == code)
}

/// Whether `code` is a data command (Table 5.16), UDD included.
pub fn is_data_command(code: u8) -> bool {
    code == UDD || find(code).is_some()
}

impl FormatSpec {
    /// Payload length in bytes.
    pub fn payload_len(&self) -> usize {
        super::fields::payload_len(self.fields)
    }

    /// Whether the format carries the orientation (a field with Euler
    /// angles or the quaternion, [`Field::is_attitude`]): such a stream
    /// starts after the initial alignment (5.3.1).
    pub fn carries_attitude(&self) -> bool {
        self.fields.iter().any(|f| f.is_attitude())
    }
}

/// Payload of the AutoStart announcement (section 6): the message
/// `AA 55 01 00 08 00 00 00 09 00` is type 1, id 0, payload `00 00`.
pub const AUTOSTART_PAYLOAD: [u8; 2] = [0x00, 0x00];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payload_sizes_are_those_of_tables_5_5_to_5_12() {
        let expect = [
            (0x33, 34),
            (0x8F, 32),
            (0x9B, 32),
            (0xA5, 44),
            (0xA6, 44),
            (0x82, 34),
            (0x81, 52),
        ];
        for (code, len) in expect {
            assert_eq!(find(code).unwrap().payload_len(), len, "{code:#x}");
        }
    }

    #[test]
    fn orientation_quaternion_and_calibrated_hr_carry_the_attitude() {
        // 5.3.1: these three wait for the initial alignment.
        let with: std::vec::Vec<u8> = FORMATS
            .iter()
            .filter(|f| f.carries_attitude())
            .map(|f| f.code)
            .collect();
        assert_eq!(with, [0x33, 0x82, 0x81]);
    }
}
