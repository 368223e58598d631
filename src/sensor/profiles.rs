//! The built-in sensor profiles ([`SensorProfile`]), as data, each citing
//! its source. `imu-emu sensor-profile show NAME` prints one as a starting
//! file; docs/sensors.md has the table and the figures measured from the
//! emulator's own output.
//!
//! - **IMX-5** (built in): the current figures of Inertial Sense's
//!   documentation, release 3.1.1 (1 October 2026: the
//!   `docs.inertialsense.com` repository, `docs/index.md`, "Performance
//!   Specifications", IMX-5 column, "per IEEE-STD-952-1997"): gyro bias
//!   instability 2.0 °/h, ARW 0.23 °/√h, accelerometer bias instability
//!   27 µg, VRW 0.020 m/s/√h. Range ±4000 °/s, ±16 g and bandwidth 539 Hz
//!   gyro / 416 Hz accelerometer, which that table does not give, are the
//!   IMX-5 datasheet's as the emulator has carried them since.
//! - **IMX-5-2022**: the earlier figures, those of the IMX-5 hardware
//!   repository's product page (`IS-hdw`, `Products/IMX-5-0/README.md`,
//!   © 2014–2022, "Tactical Grade IMU"): 1.5 °/h, 0.16 °/√h, 19 µg,
//!   0.02 m/s/√h — the ones the emulator used until
//!   now (the user manual of release 1.9.0, September 2022, read 2.0 °/h,
//!   0.2 °/√h, 20 µg, 0.04 m/s/√h in between). Same ranges and bandwidths.
//!
//!   For both, the terms the vendor does not give (turn-on bias, scale
//!   factor, misalignment, temperature coefficients) are the emulator's
//!   mid-grade values below.
//! - **KERNEL models**: Inertial Labs publishes no noise figures for the
//!   KERNEL family that we could find (the ICD gives none; the search found
//!   only an Inertial Labs knowledge-base page on how they measure ARW, VRW
//!   and bias instability for another product, the IMU-P). The figures are
//!   the emulator's three grades of tactical MEMS units, unchanged from
//!   before profiles existed; misalignment 0.01° 1σ is ICD 2.2
//!   ("non-orthogonality … in the order of 0.01°"). Ranges are those of the
//!   model's first product code (ICD 3.2.2); a product code's range option
//!   replaces them (`crate::model::Product::sensor_profile`, the ranges
//!   of `kernel/model.rs`).
//!
//! | profile | gyro ARW °/√h | gyro B °/h | acc VRW m/s/√h | acc B µg |
//! |---|---|---|---|---|
//! | entry (K100, K102, K201) | 0.24 | 3 | 0.04 | 10 |
//! | mid (K108, K110, K110M, K120) | 0.2 | 2 | 0.03 | 7 |
//! | high (K210, K220) | 0.1 | 1 | 0.02 | 5 |
//! | aux (K120, K220) | — | — | 0.3 | 200 |
//! | IMX-5 | 0.23 | 2.0 | 0.02 | 27 |
//! | IMX-5-2022 | 0.16 | 1.5 | 0.02 | 19 |

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

/// The aux (±90 g) accelerometer of K120/K220 (the emulator's figures);
/// the unused aux part of every other profile.
pub const AUX: SensorSpec = SensorSpec {
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

/// The IMX-5 (module doc): the vendor's current figures (release 3.1.1)
/// for ARW, VRW and bias instability, the datasheet quote's range and
/// bandwidth; mid-grade values for the rest. It has no aux accelerometer
/// (the aux spec is unused).
pub static IMX5_PROFILE: SensorProfile = SensorProfile {
    gyro: gyro(4000.0, 0.23, 2.0, 539.0),
    acc: acc(16.0, 0.02, 27.0, 416.0),
    aux: AUX,
    temperature: TemperatureSpec::DEFAULT,
};

/// The IMX-5 with the earlier figures (module doc: `IS-hdw`'s product
/// page, © 2014–2022): ARW 0.16 °/√h, 1.5 °/h, VRW 0.02 m/s/√h, 19 µg.
pub static IMX5_2022_PROFILE: SensorProfile = SensorProfile {
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
    /// Whether the unit has an aux accelerometer (K120, K220: ICD 2.1; the
    /// other profiles carry an unused one). `model.rs` checks it against
    /// the model table's capability.
    pub aux: bool,
}

const KERNEL_SOURCE: &str = "emulator figures (Inertial Labs publishes none found); \
misalignment ICD 2.2; ranges ICD 3.2.2";
const IMX5_SOURCE: &str = "Inertial Sense documentation release 3.1.1 (2026-10-01), \
docs/index.md Performance Specifications (ARW, VRW, bias instability); range and \
bandwidth the IMX-5 datasheet's figures; other terms emulator mid grade";
const IMX5_2022_SOURCE: &str = "Inertial Sense IS-hdw Products/IMX-5-0/README.md \
(c 2014-2022; the figures the emulator used before release 3.1.1's); range and \
bandwidth the IMX-5 datasheet's figures; other terms emulator mid grade";

/// Every built-in profile, KERNEL models in ICD 2.1 order, then the IMX-5
/// and its earlier figures.
pub static BUILTIN: &[Builtin] = &[
    Builtin {
        name: "K100",
        source: KERNEL_SOURCE,
        profile: &KERNEL_ENTRY,
        aux: false,
    },
    Builtin {
        name: "K102",
        source: KERNEL_SOURCE,
        profile: &KERNEL_ENTRY,
        aux: false,
    },
    Builtin {
        name: "K108",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
        aux: false,
    },
    Builtin {
        name: "K110",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
        aux: false,
    },
    Builtin {
        name: "K110M",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
        aux: false,
    },
    Builtin {
        name: "K120",
        source: KERNEL_SOURCE,
        profile: &KERNEL_MID,
        aux: true,
    },
    Builtin {
        name: "K201",
        source: KERNEL_SOURCE,
        profile: &KERNEL_ENTRY,
        aux: false,
    },
    Builtin {
        name: "K210",
        source: KERNEL_SOURCE,
        profile: &KERNEL_HIGH,
        aux: false,
    },
    Builtin {
        name: "K220",
        source: KERNEL_SOURCE,
        profile: &KERNEL_HIGH,
        aux: true,
    },
    Builtin {
        name: "IMX-5",
        source: IMX5_SOURCE,
        profile: &IMX5_PROFILE,
        aux: false,
    },
    Builtin {
        name: "IMX-5-2022",
        source: IMX5_2022_SOURCE,
        profile: &IMX5_2022_PROFILE,
        aux: false,
    },
];

impl Builtin {
    /// Whether the model of this name has an aux accelerometer (K120,
    /// K220: ICD 2.1); the others' profiles carry an unused one.
    pub fn has_aux(&self) -> bool {
        self.aux
    }
}

/// The built-in profile named `name` (case-insensitive; `IMX5` = `IMX-5`).
pub fn builtin(name: &str) -> Option<&'static Builtin> {
    BUILTIN.iter().find(|b| {
        b.name.eq_ignore_ascii_case(name)
            || (b.name == "IMX-5" && name.eq_ignore_ascii_case("IMX5"))
    })
}
