//! The built-in sensor profiles ([`SensorProfile`]), as data, each citing
//! its source. `imu-emu sensor-profile show NAME` prints one as a starting
//! file; docs/sensors.md has the table and the figures measured from the
//! emulator's own output.
//!
//! - **IMX-5**: the Inertial Sense IMX-5 IMU datasheet's figures, as
//!   quoted in issue 19 ("Inertial Sense IMX-5 IMU datasheet"): ±4000 °/s,
//!   ±16 g, gyro bias instability 1.5 °/h, ARW 0.16 °/√h, accelerometer
//!   bias instability 19 µg, VRW 0.02 m/s/√h, bandwidth 539 Hz gyro /
//!   416 Hz accelerometer. The revision could not be checked: the public
//!   material searched (Inertial Sense user manual, ©2022, chapter 2 "Data
//!   Sheets") lists the data sheet but not its figures. The terms the quote
//!   does not give (turn-on bias, scale factor, misalignment, temperature
//!   coefficients) are the emulator's mid-grade values below.
//! - **KERNEL models**: Inertial Labs publishes no noise figures for the
//!   KERNEL family that we could find (the ICD gives none; the search found
//!   only an Inertial Labs knowledge-base page on how they measure ARW, VRW
//!   and bias instability for another product, the IMU-P). The figures are
//!   the emulator's three grades of tactical MEMS units, unchanged from
//!   before profiles existed; misalignment 0.01° 1σ is ICD 2.2
//!   ("non-orthogonality … in the order of 0.01°"). Ranges are those of the
//!   model's first product code (ICD 3.2.2); a product code's range option
//!   replaces them (`crate::model::Product::sensor_profile`).
//!
//! | profile | gyro ARW °/√h | gyro B °/h | acc VRW m/s/√h | acc B µg |
//! |---|---|---|---|---|
//! | entry (K100, K102, K201) | 0.24 | 3 | 0.04 | 10 |
//! | mid (K108, K110, K110M, K120) | 0.2 | 2 | 0.03 | 7 |
//! | high (K210, K220) | 0.1 | 1 | 0.02 | 5 |
//! | aux (K120, K220) | — | — | 0.3 | 200 |
//! | IMX-5 | 0.16 | 1.5 | 0.02 | 19 |

use super::profile::{arw_to_density, vrw_to_density, SensorProfile, SensorSpec, TemperatureSpec};

/// ICD 2.2: "non-orthogonality between axes … in the order of 0.01°".
const MISALIGN_SIGMA: f32 = 0.01 * core::f32::consts::PI / 180.0;

/// A KERNEL-grade gyro: ARW °/√h, bias instability °/h, the emulator's
/// other terms (turn-on bias 1σ 0.05 °/s, scale factor 1σ 300 ppm,
/// 1e-4 °/s/°C, 10 ppm/°C).
const fn gyro(range: f32, arw: f32, bias_inst_deg_h: f32, bandwidth_hz: f32) -> SensorSpec {
    SensorSpec {
        range,
        noise_density: arw_to_density(arw),
        bias_instability: bias_inst_deg_h / 3600.0,
        rate_random_walk: 0.0,
        turn_on_bias_sigma: 0.05,
        scale_factor_sigma: 300e-6,
        nonlinearity: 0.0,
        misalignment_sigma: MISALIGN_SIGMA,
        g_sensitivity: 0.0,
        temp_bias: 1e-4,
        temp_scale: 10e-6,
        resolution: 0.0,
        bandwidth_hz,
    }
}

/// A KERNEL-grade accelerometer: VRW m/s/√h, bias instability µg, the
/// emulator's other terms (turn-on bias 1σ 1 mg, scale factor 1σ 300 ppm,
/// 10 µg/°C, 10 ppm/°C).
const fn acc(range: f32, vrw: f32, bias_inst_ug: f32, bandwidth_hz: f32) -> SensorSpec {
    SensorSpec {
        range,
        noise_density: vrw_to_density(vrw),
        bias_instability: bias_inst_ug * 1e-6,
        rate_random_walk: 0.0,
        turn_on_bias_sigma: 1e-3,
        scale_factor_sigma: 300e-6,
        nonlinearity: 0.0,
        misalignment_sigma: MISALIGN_SIGMA,
        g_sensitivity: 0.0,
        temp_bias: 10e-6,
        temp_scale: 10e-6,
        resolution: 0.0,
        bandwidth_hz,
    }
}

/// The aux (±90 g) accelerometer of K120/K220 (the emulator's figures).
const AUX: SensorSpec = SensorSpec {
    range: 90.0,
    noise_density: vrw_to_density(0.3),
    bias_instability: 200e-6,
    rate_random_walk: 0.0,
    turn_on_bias_sigma: 5e-3,
    scale_factor_sigma: 1000e-6,
    nonlinearity: 0.0,
    misalignment_sigma: MISALIGN_SIGMA,
    g_sensitivity: 0.0,
    temp_bias: 100e-6,
    temp_scale: 20e-6,
    resolution: 0.0,
    bandwidth_hz: 0.0,
};

/// KERNEL entry grade (K100, K102, K201). Bandwidth 0: not published.
pub static KERNEL_ENTRY: SensorProfile = SensorProfile {
    gyro: gyro(2000.0, 0.24, 3.0, 0.0),
    acc: acc(40.0, 0.04, 10.0, 0.0),
    aux: AUX,
    temperature: TemperatureSpec::DEFAULT,
};

/// KERNEL mid grade (K108, K110, K110M, K120).
pub static KERNEL_MID: SensorProfile = SensorProfile {
    gyro: gyro(2000.0, 0.2, 2.0, 0.0),
    acc: acc(40.0, 0.03, 7.0, 0.0),
    aux: AUX,
    temperature: TemperatureSpec::DEFAULT,
};

/// KERNEL high grade (K210, K220).
pub static KERNEL_HIGH: SensorProfile = SensorProfile {
    gyro: gyro(2000.0, 0.1, 1.0, 0.0),
    acc: acc(40.0, 0.02, 5.0, 0.0),
    aux: AUX,
    temperature: TemperatureSpec::DEFAULT,
};

/// The IMX-5 (module doc): datasheet figures for range, ARW, VRW, bias
/// instability and bandwidth; mid-grade values for the rest. It has no aux
/// accelerometer (the aux spec is unused).
pub static IMX5_PROFILE: SensorProfile = SensorProfile {
    gyro: gyro(4000.0, 0.16, 1.5, 539.0),
    acc: acc(16.0, 0.02, 19.0, 416.0),
    aux: AUX,
    temperature: TemperatureSpec::DEFAULT,
};

/// One built-in profile: the name `--sensor-profile`-style tools accept,
/// its source, the data.
#[derive(Debug)]
pub struct Builtin {
    /// Model name (`K110`, `IMX-5`).
    pub name: &'static str,
    /// Where the figures come from.
    pub source: &'static str,
    /// The profile.
    pub profile: &'static SensorProfile,
}

const KERNEL_SOURCE: &str = "emulator figures (Inertial Labs publishes none found); \
misalignment ICD 2.2; ranges ICD 3.2.2";
const IMX5_SOURCE: &str = "Inertial Sense IMX-5 IMU datasheet as quoted in issue 19 \
(revision not verified); other terms emulator mid grade";

/// Every built-in profile, KERNEL models in ICD 2.1 order, then the IMX-5.
pub static BUILTIN: &[Builtin] = &[
    Builtin {
        name: "K100",
        source: KERNEL_SOURCE,
        profile: &KERNEL_ENTRY,
    },
    Builtin {
        name: "K102",
        source: KERNEL_SOURCE,
        profile: &KERNEL_ENTRY,
    },
    Builtin {
        name: "K108",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
    },
    Builtin {
        name: "K110",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
    },
    Builtin {
        name: "K110M",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
    },
    Builtin {
        name: "K120",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
    },
    Builtin {
        name: "K201",
        source: KERNEL_SOURCE,
        profile: &KERNEL_ENTRY,
    },
    Builtin {
        name: "K210",
        source: KERNEL_SOURCE,
        profile: &KERNEL_HIGH,
    },
    Builtin {
        name: "K220",
        source: KERNEL_SOURCE,
        profile: &KERNEL_HIGH,
    },
    Builtin {
        name: "IMX-5",
        source: IMX5_SOURCE,
        profile: &IMX5_PROFILE,
    },
];

/// The built-in profile named `name` (case-insensitive; `IMX5` = `IMX-5`).
pub fn builtin(name: &str) -> Option<&'static Builtin> {
    BUILTIN.iter().find(|b| {
        b.name.eq_ignore_ascii_case(name)
            || (b.name == "IMX-5" && name.eq_ignore_ascii_case("IMX5"))
    })
}
