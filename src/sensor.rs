//! What the device measures. Until the signal chain lands this is a device
//! sitting static and level, Z up (ICD 2.2 axes).

/// One sample of everything the output formats carry, in physical units and
/// carrier axes (ICD 5.2 notes: X lateral, Y longitudinal, Z vertical).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Angular rates, deg/s.
    pub gyro: [f32; 3],
    /// Specific force of the main accelerometer, g (9.8106 m/s², ICD 5.2.1).
    pub acc: [f32; 3],
    /// Specific force of the aux (high-g) accelerometer, g; zero without one.
    pub aux_acc: [f32; 3],
    /// Heading, pitch, roll in degrees (Appendix C conventions).
    pub euler: [f32; 3],
    /// Orientation quaternion q0..q3 (Appendix C.3).
    pub quat: [f32; 4],
    /// Bias-compensated, cascade-filtered angular rates, deg/s (UDD 0x2D).
    pub gyro_filtered: [f32; 3],
    /// Estimated gyro bias, deg/s (UDD 0x2E).
    pub gyro_bias: [f32; 3],
    /// Cascade-filtered main accelerometer, g (UDD 0x91).
    pub acc_filtered: [f32; 3],
    /// Cascade-filtered aux accelerometer, g (UDD 0x92).
    pub aux_acc_filtered: [f32; 3],
    /// Average gyro temperature, °C.
    pub temperature: f32,
    /// Supply voltage, V.
    pub supply_voltage: f32,
}

impl Sample {
    /// Static, level, Z up, heading 0, 25 °C, 12 V.
    pub const STATIC_LEVEL: Sample = Sample {
        gyro: [0.0; 3],
        acc: [0.0, 0.0, 1.0],
        aux_acc: [0.0, 0.0, 1.0],
        gyro_filtered: [0.0; 3],
        gyro_bias: [0.0; 3],
        acc_filtered: [0.0, 0.0, 1.0],
        aux_acc_filtered: [0.0, 0.0, 1.0],
        euler: [0.0; 3],
        quat: [1.0, 0.0, 0.0, 0.0],
        temperature: 25.0,
        supply_voltage: 12.0,
    };
}
