//! The KERNEL's status words from the chain's neutral
//! [`Health`]: the Unit Status Word (ICD 5.4, Table 5.26), the extended
//! USW (Table 5.27) and the GetBIT payload (5.3.4, Table 5.18). Each of
//! these bit layouts is written down here and nowhere else.

use crate::chain::Health;

/// USW bits (Table 5.26) and USW-extended bits (Table 5.27).
pub mod usw {
    /// Communication failure of internal sensors (Table 5.26 bit 1).
    pub const SENSOR_COMM: u16 = 1 << 1;
    /// Configuration failure of internal sensors (bit 2).
    pub const SENSOR_CONFIG: u16 = 1 << 2;
    /// X angular rate out of range (bit 10; Y is `<< 1`, Z `<< 2`).
    pub const RATE_X_RANGE: u16 = 1 << 10;
    /// Temperature out of the operating range (bit 14).
    pub const TEMPERATURE: u16 = 1 << 14;
    /// Extended: initial alignment complete (Table 5.27 bit 0; clear only
    /// while aligning).
    pub(crate) const EXT_ALIGNED: u16 = 1 << 0;
    /// Extended: gyro bias estimation failed (bit 1).
    pub(crate) const EXT_BIAS_FAILED: u16 = 1 << 1;
}

/// GetBIT payload bits (Table 5.18): byte 0 bits 0–1 the accelerometer
/// result (1 = failed; 0 and 2 are "okay"), bits 2–4 the gyroscope result
/// (1 = failed); byte 1 bits 4–5 (payload bits 12–13) the flash check (1 =
/// failed).
mod bit {
    pub(crate) const ACCEL_FAILED: u8 = 0x01;
    pub(crate) const GYRO_FAILED: u8 = 0x04;
    pub(crate) const FLASH_FAILED: u8 = 0x10;
}

/// The status words of one moment, as the KERNEL reports them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Status {
    /// Unit Status Word (Table 5.26), [`usw()`].
    pub usw: u16,
    /// Extended USW (Table 5.27), [`usw_ext`].
    pub usw_ext: u16,
    /// GetBIT payload (Table 5.18), 4 bytes, [`bit()`].
    pub bit: [u8; 4],
}

impl Status {
    /// All three encodings of `health`.
    pub fn of(health: &Health) -> Self {
        Status {
            usw: usw(health),
            usw_ext: usw_ext(health),
            bit: bit(health),
        }
    }
}

/// The Unit Status Word (Table 5.26): bit 1 sensor communication failure,
/// bit 2 sensor configuration failure, bits 10/11/12 X/Y/Z angular rate out
/// of range (sensor axes, over the last output's interval and since), bit 14
/// temperature out of the operating range.
pub fn usw(h: &Health) -> u16 {
    let mut w = u16::from(h.gyro_over_range & 0x07) << 10;
    if h.sensor_comm_failure {
        w |= usw::SENSOR_COMM;
    }
    if h.sensor_config_failure {
        w |= usw::SENSOR_CONFIG;
    }
    if h.over_temperature {
        w |= usw::TEMPERATURE;
    }
    w
}

/// The extended USW (Table 5.27): bit 0 initial alignment complete (set
/// unless an alignment is running), bit 1 gyro bias estimation failed.
pub(crate) fn usw_ext(h: &Health) -> u16 {
    let mut w = 0;
    if !h.aligning {
        w |= usw::EXT_ALIGNED;
    }
    if h.bias_estimation_failed {
        w |= usw::EXT_BIAS_FAILED;
    }
    w
}

/// The GetBIT payload (Table 5.18), 4 bytes.
pub(crate) fn bit(h: &Health) -> [u8; 4] {
    let mut b = [0u8; 4];
    if h.accel_bit_failed {
        b[0] |= bit::ACCEL_FAILED;
    }
    if h.gyro_bit_failed {
        b[0] |= bit::GYRO_FAILED;
    }
    if h.flash_check_failed {
        b[1] |= bit::FLASH_FAILED;
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_flag_is_its_table_bit() {
        let none = Health::default();
        assert_eq!(
            Status::of(&none),
            Status {
                usw: 0,
                usw_ext: 1,
                bit: [0; 4]
            }
        );
        let all = Health {
            sensor_comm_failure: true,
            sensor_config_failure: true,
            gyro_over_range: 0b101,
            accel_over_range: 0b111,
            over_temperature: true,
            gyro_bit_failed: true,
            accel_bit_failed: true,
            flash_check_failed: true,
            aligning: true,
            bias_estimation_failed: true,
        };
        assert_eq!(
            Status::of(&all),
            Status {
                usw: 0x0002 | 0x0004 | 0x0400 | 0x1000 | 0x4000,
                usw_ext: 0x0002,
                bit: [0x05, 0x10, 0, 0],
            }
        );
    }
}
