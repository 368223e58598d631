//! The fixed output formats (ICD 5.2.1–5.2.7, Tables 5.5–5.12, 5.16) — one
//! row each — and the acknowledgement/announcement messages.

use super::fields::Field::{self, *};
use super::fields::OutputCtx;

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

/// Defines [`FORMATS`] from one list and, in host builds, the fixed
/// formats' payload writers from the same list ([`write_payload`]).
macro_rules! fixed_formats {
    ($($code:literal $name:literal [$($field:expr),* $(,)?])*) => {
        /// The seven fixed formats.
        pub static FORMATS: &[FormatSpec] = &[$(FormatSpec {
            code: $code,
            name: $name,
            fields: &[$($field),*],
        }),*];

        /// The payload of fixed format `code` written into
        /// `out` as [`super::fields::write_all`] of its [`FormatSpec::fields`]
        /// writes it (the same bytes), by one writer per format with its
        /// fields in line: no dispatch per field, the scales constant.
        /// `None` if `code` is no fixed format or `out` is too short.
        pub(crate) fn write_payload(code: u8, ctx: &OutputCtx<'_>, out: &mut [u8]) -> Option<usize> {
            match code {
                $($code => {
                    let mut at = 0;
                    $(at += $field.write_inline(ctx, out.get_mut(at..)?)?;)*
                    Some(at)
                })*
                _ => None,
            }
        }
    };
}

fixed_formats! {
    // Table 5.5: heading, pitch, roll, gyro·KG, acc·KA, mag 0, reserved 4,
    // USW, reserved 2, temperature — 34 bytes.
    0x33 "Orientation" [Euler, Gyro, Acc, Zero(6), Zero(4), Usw, Zero(2), Temperature]
    // Table 5.7: gyro HR, acc HR, counter, USW, reserved, temperature — 32.
    0x8F "GA" [GyroHr, AccHr, Counter, Usw, Zero(2), Temperature]
    // Table 5.8: gyro HR, acc HR, time flag, second fraction, temperature — 32.
    0x9B "GAm" [GyroHr, AccHr, TimeFlags, SecondFraction, Temperature]
    // Table 5.11: gyro, acc1, acc2 (aux), reserved, USW, reserved, temp — 44.
    0xA5 "GAA" [GyroHr, AccHr, AuxAccHr, Zero(2), Usw, Zero(2), Temperature]
    // Table 5.12: gyro, acc1, acc2, time flag, second fraction, temp — 44.
    0xA6 "GAAm" [GyroHr, AccHr, AuxAccHr, TimeFlags, SecondFraction, Temperature]
    // Table 5.9: heading, pitch, roll, q0..q3, reserved 14, USW, reserved,
    // temperature — 34.
    0x82 "Quaternion" [Euler, Quat, Zero(14), Usw, Zero(2), Temperature]
    // Table 5.10: HR angles, gyro HR, acc HR, mag 0, counter, reserved, USW,
    // reserved, temperature — 52.
    0x81 "Calibrated HR" [
        EulerHr, GyroHr, AccHr, Zero(6), Counter, Zero(2), Usw, Zero(2), Temperature,
    ]
}

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

    /// The host's writer of each fixed format gives the bytes of the loop
    /// over its fields, for samples with every kind of value (signs,
    /// ties, saturation, NaN, ∞), and refuses a short buffer as it does.
    #[test]
    fn each_format_writer_writes_what_the_field_loop_writes() {
        use crate::kernel::fields::{write_all, OutputCtx};
        use crate::model::Product;
        use crate::sensor::Sample;
        let specials = [
            0.0,
            -0.0,
            0.5e-5,
            -0.5e-5,
            1e-6,
            359.995,
            -720.0,
            3.0e38,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut state = 0x0123_4567_89AB_CDEFu64;
        let mut next = |i: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            if i.is_multiple_of(5) {
                specials[(state >> 60) as usize % specials.len()]
            } else {
                ((state >> 32) as i32) as f32 * 1e-6
            }
        };
        for model in ["K110", "K120", "KERNEL-110-G450-A40", "K201"] {
            let product = Product::parse(model).unwrap();
            for i in 0..2000 {
                let mut s = Sample::STATIC_LEVEL;
                for v in s
                    .gyro
                    .iter_mut()
                    .chain(&mut s.acc)
                    .chain(&mut s.aux_acc)
                    .chain(&mut s.euler)
                    .chain(&mut s.quat)
                    .chain(&mut s.gyro_filtered)
                    .chain(&mut s.gyro_bias)
                    .chain(&mut s.acc_filtered)
                    .chain(&mut s.aux_acc_filtered)
                    .chain([&mut s.temperature, &mut s.supply_voltage])
                {
                    *v = next(i);
                }
                let ctx = OutputCtx {
                    sample: &s,
                    product: &product,
                    counter: i as u16,
                    usw: 0x1234 ^ i as u16,
                    usw_ext: 0x8001,
                    time_flags: 9,
                    second_fraction_ns: 999_999_999 - i as u32,
                    imu_time_ns: u64::MAX - i as u64,
                };
                for f in FORMATS {
                    let (mut a, mut b) = ([0xA5u8; 64], [0x5Au8; 64]);
                    let n = f.payload_len();
                    assert_eq!(write_payload(f.code, &ctx, &mut a), Some(n));
                    assert_eq!(write_all(f.fields, &ctx, &mut b), Some(n));
                    assert_eq!(a[..n], b[..n], "{} {i}", f.name);
                    assert_eq!(write_payload(f.code, &ctx, &mut a[..n - 1]), None);
                }
                assert_eq!(write_payload(UDD, &ctx, &mut [0; 8]), None);
            }
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
