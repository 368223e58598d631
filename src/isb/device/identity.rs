//! DEV_INFO: what the emulated unit says it is (`docs/isb-data-sets.md`
//! "dev_info_t").

use super::*;

/// DEV_INFO of this unit: an IMX-5 (hardware 5.0), protocol 2.1.0.0, the
/// serial number from the seed (never 0).
pub(super) fn dev_info_of(cx: &impl Context<Integrals>) -> DevInfo {
    DevInfo {
        hardware_type: dev_info::HARDWARE_TYPE_IMX,
        hdw_run_state: dev_info::RUN_STATE_APP,
        serial_number: 10_000_000 + (cx.seed() % 90_000_000) as u32,
        hardware_ver: [5, 0, 0, 0],
        firmware_ver: dev_info::FIRMWARE_2_7_1,
        build_number: dev_info::BUILD_NUMBER_2_7_1,
        protocol_ver: dev_info::PROTOCOL_2_1,
        repo_revision: 0,
        manufacturer: sets::str24("Inertial Sense Inc"),
        build_type: b'r',
        build_date: [26, 12, 1],
        build_time: [0, 0, 0, 0],
        add_info: sets::str24(concat!("imu-emu ", env!("CARGO_PKG_VERSION"))),
    }
}
