//! Data set identifiers (DIDs) and the table of the data sets the emulated
//! IMX-5 in IMU mode serves (`docs/protocol-facts.md` "ISB"; the SDK's
//! `data_sets.h`, protocol 2.1; `docs/isb-data-sets.md` has every layout with offsets).
//!
//! One [`DataSet`] row per supported DID says how big the set is, which
//! source period its streams count in ([`Source`]), which bytes a SET_DATA
//! may change ([`DataSet::writable`]) and its RMC bit. The rule for DIDs
//! outside the table is [`classify`]: NACK for DID ≥ [`DID_COUNT`] and for
//! DID 95, silence for any other DID the table does not hold.

use super::asce::nmea_msgs;
use super::aux_sets::{self, rmc_aux};
use super::layout::FieldSpec;
use super::nav_sets::{
    barometer, gps_pos, gps_sat, gps_vel, imu_mag, inl2_ned_sigma, inl2_states, ins1, ins2, ins3,
    ins4, magnetometer, pimu_mag, rmc_nav, sys_sensors,
};
use super::sets;

/// Count of DIDs (including the null DID 0): `DID_COUNT` in `data_sets.h`.
/// A GET or SET of a DID at or above it is NACKed (protocol-facts.md "ISB").
pub const DID_COUNT: u16 = 132;

/// Null (invalid) DID.
pub const NULL: u8 = 0;
/// `dev_info_t`: device information (protocol-facts.md "ISB").
pub const DEV_INFO: u8 = 1;
/// `system_fault_t`: system fault information.
pub const SYS_FAULT: u8 = 2;
/// `pimu_t`: preintegrated IMU (coning and sculling integrals).
pub const PIMU: u8 = 3;
/// `ins_1_t`: INS output, Euler attitude and NED offset.
pub const INS_1: u8 = 4;
/// `ins_2_t`: INS output, quaternion attitude.
pub const INS_2: u8 = 5;
/// `ins_3_t`: INS output, quaternion attitude and MSL height.
pub const INS_3: u8 = 65;
/// `ins_4_t`: INS output, ECEF.
pub const INS_4: u8 = 66;
/// `inl2_states_t`: the INS filter's states.
pub const INL2_STATES: u8 = 48;
/// `inl2_ned_sigma_t`: standard deviations of the INS filter's estimates.
pub const INL2_NED_SIGMA: u8 = 67;
/// `gps_pos_t`: GNSS position (the better of GPS1_RCVR_POS / RTK).
pub const GPS1_POS: u8 = 13;
/// `gps_sat_t`: the satellites the receiver tracks.
pub const GPS1_SAT: u8 = 15;
/// `gps_version_t`: the GNSS receiver's version strings.
pub const GPS1_VERSION: u8 = 17;
/// `mag_cal_t`: magnetometer recalibration.
pub const MAG_CAL: u8 = 19;
/// `gps_sig_t`: the signals the receiver tracks.
pub const GPS1_SIG: u8 = 45;
/// `rtos_info_t`: the firmware's task table ([`super::rtos`]).
pub const RTOS_INFO: u8 = 38;
/// `can_config_t`: CAN output settings, kept in flash ([`super::can`]).
pub const CAN_CONFIG: u8 = 90;
/// `port_monitor_t`: byte counts and rates of each port.
pub const PORT_MONITOR: u8 = 75;
/// `gps_vel_t`: GNSS velocity.
pub const GPS1_VEL: u8 = 30;
/// `imu_mag_t`: IMU and magnetometer.
pub const IMU_MAG: u8 = 85;
/// `pimu_mag_t`: PIMU and magnetometer.
pub const PIMU_MAG: u8 = 86;
/// `system_command_t`: system commands.
pub const SYS_CMD: u8 = 7;
/// `DID_NMEA_BCAST_PERIOD` (`nmea_msgs_t`: the NMEA stream table).
pub const NMEA_BCAST_PERIOD: u8 = 8;
/// `gps_pos_t` of the GNSS receiver (GPS1_POS is the better of it and the
/// RTK solution: without RTK, the same).
pub const GPS1_RCVR_POS: u8 = 6;
/// `rmc_t`: realtime message controller.
pub const RMC: u8 = 9;
/// `sys_params_t`: system parameters.
pub const SYS_PARAMS: u8 = 10;
/// `sys_sensors_t`: system sensors.
pub const SYS_SENSORS: u8 = 11;
/// `nvm_flash_cfg_t`: flash configuration.
pub const FLASH_CONFIG: u8 = 12;
/// `magnetometer_t`: magnetometer.
pub const MAGNETOMETER: u8 = 52;
/// `barometer_t`: barometer.
pub const BAROMETER: u8 = 53;
/// `imu3_t` uncalibrated triple IMU (not served).
pub const IMU3_UNCAL: u8 = 57;
/// `imu_t`: IMU data at the navigation period.
pub const IMU: u8 = 58;
/// `bit_t`: built-in self-test.
pub const BIT: u8 = 64;
/// `strobe_in_time_t`: time stamp of a strobe input (EXTRIG) edge.
pub const STROBE_IN_TIME: u8 = 68;
/// Reference IMU (manufacturing); NACKed like DIDs ≥ 132 (protocol-facts.md: the
/// IMX firmware counts DIDs only to 100 and answers 95 with a NACK).
pub const REFERENCE_IMU: u8 = 95;
/// `imu3_t`: the three IMUs at the IMU sample period.
pub const IMU3_RAW: u8 = 96;
/// `imu_t`: IMU data at the IMU sample period.
pub const IMU_RAW: u8 = 97;
/// GPX flash configuration (not served: no GPX on board; the vendor tool
/// asks for it and tolerates silence).
pub const GPX_FLASH_CFG: u8 = 121;
/// GPX status (not served, as [`GPX_FLASH_CFG`]).
pub const GPX_STATUS: u8 = 123;

/// The period a stream of a data set counts in: a GET_DATA `period` is a
/// multiple of it (ISB page "Data Source Update Rates"; protocol-facts.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// `FLASH_CONFIG.startupNavDtMs` (default 4 ms): IMU and PIMU. The
    /// page's table says `startupImuDtMs`; the SDK and protocol-facts.md say
    /// `startupNavDtMs` — the SDK is followed (protocol-facts.md "ISB").
    NavDt,
    /// `FLASH_CONFIG.startupImuDtMs` (default 1 ms): IMU_RAW, which
    /// `data_sets.h` describes as the IMU data for periods faster than the
    /// navigation period.
    ImuDt,
    /// `FLASH_CONFIG.startupGPSDtMs` (default 200 ms): GPS1_POS, GPS1_VEL
    /// (SDK 2.7.1 `RMC_BITS_GPS1_*` comments).
    GpsDt,
    /// A fixed period, ms: MAGNETOMETER 10, BAROMETER 8, GPS1_SAT 1000
    /// (SDK 2.7.1 `RMC_BITS_*` comments: "~10 ms", "~8 ms", "1 s"; the
    /// ISB page puts every GPS DID at `startupGPSDtMs`, the SDK's comment
    /// is followed, `docs/isb.md`).
    Fixed(u32),
    /// 1 ms: every other DID (ISB page, "All other DIDs 1ms").
    Millisecond,
}

impl Source {
    /// The source period in ms for these FLASH_CONFIG values
    /// (`startupImuDtMs`, `startupNavDtMs`, `startupGPSDtMs`); a stream
    /// with period multiple `n` sends every `n ×` this.
    pub const fn period_ms(
        self,
        startup_imu_dt_ms: u32,
        startup_nav_dt_ms: u32,
        startup_gps_dt_ms: u32,
    ) -> u32 {
        match self {
            Source::NavDt => startup_nav_dt_ms,
            Source::ImuDt => startup_imu_dt_ms,
            Source::GpsDt => startup_gps_dt_ms,
            Source::Fixed(ms) => ms,
            Source::Millisecond => 1,
        }
    }
}

/// A half-open byte range `[start, end)` inside a data set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Range {
    /// First byte.
    pub start: u16,
    /// One past the last byte.
    pub end: u16,
}

impl Range {
    /// The range `[start, end)`.
    pub const fn new(start: u16, end: u16) -> Self {
        Range { start, end }
    }

    /// Whether byte `i` lies in the range.
    pub const fn contains(&self, i: u16) -> bool {
        self.start <= i && i < self.end
    }
}

/// One data set the emulated IMX serves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DataSet {
    /// Its DID.
    pub did: u8,
    /// Its name in `data_sets.h` without `DID_` (`FLASH_CONFIG`).
    pub did_name: &'static str,
    /// The C type name in `data_sets.h`, for diagnostics.
    pub name: &'static str,
    /// Size of the packed struct, bytes.
    pub size: u16,
    /// The fields a host reads by name: the table its layout's
    /// [`crate::data_set!`] declaration makes.
    pub fields: &'static [FieldSpec],
    /// What a stream period multiplies.
    pub source: Source,
    /// The byte ranges a SET_DATA may change; every other byte is read-only
    /// (a SET may only carry its current value there, see
    /// [`crate::isb::message::apply_set`]).
    pub writable: &'static [Range],
    /// Its bit in `rmc_t.bits`, 0 when it has none.
    pub rmc_bit: u64,
}

impl DataSet {
    /// Whether byte `i` of the set may be changed by a SET_DATA.
    pub fn is_writable(&self, i: u16) -> bool {
        self.writable.iter().any(|r| r.contains(i))
    }
}

const NONE: &[Range] = &[];
const ALL_RMC: &[Range] = &[Range::new(0, sets::rmc::SIZE as u16)];
const ALL_SYS_CMD: &[Range] = &[Range::new(0, sets::sys_cmd::SIZE as u16)];
/// NMEA_BCAST_PERIOD: all (options and pairs).
const ALL_NMEA_MSGS: &[Range] = &[Range::new(0, nmea_msgs::SIZE as u16)];
/// SYS_PARAMS: only `genFaultCode` ("set to zero to reset fault code",
/// `data_sets.h`); the rest is the device's report.
const SYS_PARAMS_W: &[Range] = &[Range::new(
    sets::sys_params::GEN_FAULT_CODE as u16,
    sets::sys_params::GEN_FAULT_CODE as u16 + 4,
)];
/// FLASH_CONFIG: everything but `size`. The `checksum` word is accepted
/// (the vendor tool's `-flashCfg=` path uploads the checksum it computed
/// itself, protocol-facts.md) but the device recomputes it after every write, so
/// what stays is always the XOR of bytes 8..287.
const FLASH_W: &[Range] = &[Range::new(
    sets::flash::CHECKSUM as u16,
    sets::flash::SIZE as u16,
)];
/// BIT: the `command` byte starts a test; `lastCommand`, `state` and
/// the reserved byte beside it may be written with it (a host writes the
/// first `u32`; the test's run rewrites them); the rest is the result.
const BIT_W: &[Range] = &[Range::new(0, 4)];
/// MAG_CAL: the `state` word (a command); progress and declination are
/// the device's report.
const MAG_CAL_W: &[Range] = &[Range::new(0, 4)];
/// CAN_CONFIG: all of it.
const ALL_CAN: &[Range] = &[Range::new(0, super::can::can_config::SIZE as u16)];

/// A read-only data set (`docs/isb-data-sets.md` "Navigation data sets",
/// "Status, version, calibration and signal data sets").
const fn nav(
    did: u8,
    did_name: &'static str,
    name: &'static str,
    size: usize,
    fields: &'static [FieldSpec],
    source: Source,
    rmc_bit: u64,
) -> DataSet {
    DataSet {
        did,
        did_name,
        name,
        size: size as u16,
        fields,
        source,
        writable: NONE,
        rmc_bit,
    }
}

/// The data sets of the emulated IMX-5, by DID.
pub const DATA_SETS: [DataSet; 34] = [
    DataSet {
        did: DEV_INFO,
        did_name: "DEV_INFO",
        name: "dev_info_t",
        size: sets::dev_info::SIZE as u16,
        fields: sets::dev_info::FIELDS,
        source: Source::Millisecond,
        writable: NONE,
        rmc_bit: 0,
    },
    nav(
        SYS_FAULT,
        "SYS_FAULT",
        "system_fault_t",
        aux_sets::sys_fault::SIZE,
        aux_sets::sys_fault::FIELDS,
        Source::Millisecond,
        0,
    ),
    DataSet {
        did: PIMU,
        did_name: "PIMU",
        name: "pimu_t",
        size: sets::pimu::SIZE as u16,
        fields: sets::pimu::FIELDS,
        source: Source::NavDt,
        writable: NONE,
        rmc_bit: sets::rmc::BITS_PIMU,
    },
    DataSet {
        did: SYS_CMD,
        did_name: "SYS_CMD",
        name: "system_command_t",
        size: sets::sys_cmd::SIZE as u16,
        fields: sets::sys_cmd::FIELDS,
        source: Source::Millisecond,
        writable: ALL_SYS_CMD,
        rmc_bit: 0,
    },
    DataSet {
        did: NMEA_BCAST_PERIOD,
        did_name: "NMEA_BCAST_PERIOD",
        name: "nmea_msgs_t",
        size: nmea_msgs::SIZE as u16,
        fields: nmea_msgs::FIELDS,
        source: Source::Millisecond,
        writable: ALL_NMEA_MSGS,
        rmc_bit: 0,
    },
    DataSet {
        did: RMC,
        did_name: "RMC",
        name: "rmc_t",
        size: sets::rmc::SIZE as u16,
        fields: sets::rmc::FIELDS,
        source: Source::Millisecond,
        writable: ALL_RMC,
        rmc_bit: 0,
    },
    DataSet {
        did: SYS_PARAMS,
        did_name: "SYS_PARAMS",
        name: "sys_params_t",
        size: sets::sys_params::SIZE as u16,
        fields: sets::sys_params::FIELDS,
        source: Source::Millisecond,
        writable: SYS_PARAMS_W,
        rmc_bit: 0,
    },
    DataSet {
        did: FLASH_CONFIG,
        did_name: "FLASH_CONFIG",
        name: "nvm_flash_cfg_t",
        size: sets::flash::SIZE as u16,
        fields: sets::flash::FIELDS,
        source: Source::Millisecond,
        writable: FLASH_W,
        rmc_bit: 0,
    },
    nav(
        GPS1_VERSION,
        "GPS1_VERSION",
        "gps_version_t",
        aux_sets::gps_version::SIZE,
        aux_sets::gps_version::FIELDS,
        Source::Millisecond,
        0,
    ),
    DataSet {
        did: MAG_CAL,
        did_name: "MAG_CAL",
        name: "mag_cal_t",
        size: aux_sets::mag_cal::SIZE as u16,
        fields: aux_sets::mag_cal::FIELDS,
        source: Source::Millisecond,
        writable: MAG_CAL_W,
        rmc_bit: 0,
    },
    nav(
        RTOS_INFO,
        "RTOS_INFO",
        "rtos_info_t",
        super::rtos::rtos_info::SIZE,
        super::rtos::rtos_info::FIELDS,
        Source::Millisecond,
        0,
    ),
    DataSet {
        did: CAN_CONFIG,
        did_name: "CAN_CONFIG",
        name: "can_config_t",
        size: super::can::can_config::SIZE as u16,
        fields: super::can::can_config::FIELDS,
        source: Source::Millisecond,
        writable: ALL_CAN,
        rmc_bit: 0,
    },
    DataSet {
        did: IMU,
        did_name: "IMU",
        name: "imu_t",
        size: sets::imu::SIZE as u16,
        fields: sets::imu::FIELDS,
        source: Source::NavDt,
        writable: NONE,
        rmc_bit: sets::rmc::BITS_IMU,
    },
    DataSet {
        did: BIT,
        did_name: "BIT",
        name: "bit_t",
        size: sets::bit::SIZE as u16,
        fields: sets::bit::FIELDS,
        source: Source::Millisecond,
        writable: BIT_W,
        rmc_bit: 0,
    },
    nav(
        PORT_MONITOR,
        "PORT_MONITOR",
        "port_monitor_t",
        aux_sets::port_monitor::SIZE,
        aux_sets::port_monitor::FIELDS,
        Source::Millisecond,
        0,
    ),
    DataSet {
        did: STROBE_IN_TIME,
        did_name: "STROBE_IN_TIME",
        name: "strobe_in_time_t",
        size: sets::strobe::SIZE as u16,
        fields: sets::strobe::FIELDS,
        source: Source::Millisecond,
        writable: NONE,
        rmc_bit: sets::rmc::BITS_STROBE_IN_TIME,
    },
    nav(
        IMU3_RAW,
        "IMU3_RAW",
        "imu3_t",
        aux_sets::imu3::SIZE,
        aux_sets::imu3::FIELDS,
        Source::ImuDt,
        rmc_aux::BITS_IMU3_RAW,
    ),
    DataSet {
        did: IMU_RAW,
        did_name: "IMU_RAW",
        name: "imu_t",
        size: sets::imu::SIZE as u16,
        fields: sets::imu::FIELDS,
        source: Source::ImuDt,
        writable: NONE,
        rmc_bit: sets::rmc::BITS_IMU_RAW,
    },
    nav(
        INS_1,
        "INS_1",
        "ins_1_t",
        ins1::SIZE,
        ins1::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_INS1,
    ),
    nav(
        INS_2,
        "INS_2",
        "ins_2_t",
        ins2::SIZE,
        ins2::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_INS2,
    ),
    nav(
        INS_3,
        "INS_3",
        "ins_3_t",
        ins3::SIZE,
        ins3::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_INS3,
    ),
    nav(
        INS_4,
        "INS_4",
        "ins_4_t",
        ins4::SIZE,
        ins4::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_INS4,
    ),
    nav(
        INL2_STATES,
        "INL2_STATES",
        "inl2_states_t",
        inl2_states::SIZE,
        inl2_states::FIELDS,
        Source::NavDt,
        0,
    ),
    nav(
        INL2_NED_SIGMA,
        "INL2_NED_SIGMA",
        "inl2_ned_sigma_t",
        inl2_ned_sigma::SIZE,
        inl2_ned_sigma::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_INL2_NED_SIGMA,
    ),
    nav(
        GPS1_POS,
        "GPS1_POS",
        "gps_pos_t",
        gps_pos::SIZE,
        gps_pos::FIELDS,
        Source::GpsDt,
        rmc_nav::BITS_GPS1_POS,
    ),
    nav(
        GPS1_RCVR_POS,
        "GPS1_RCVR_POS",
        "gps_pos_t",
        gps_pos::SIZE,
        gps_pos::FIELDS,
        Source::GpsDt,
        rmc_nav::BITS_GPS1_RCVR_POS,
    ),
    nav(
        GPS1_VEL,
        "GPS1_VEL",
        "gps_vel_t",
        gps_vel::SIZE,
        gps_vel::FIELDS,
        Source::GpsDt,
        rmc_nav::BITS_GPS1_VEL,
    ),
    nav(
        GPS1_SAT,
        "GPS1_SAT",
        "gps_sat_t",
        gps_sat::SIZE,
        gps_sat::FIELDS,
        Source::Fixed(1000),
        rmc_nav::BITS_GPS1_SAT,
    ),
    nav(
        GPS1_SIG,
        "GPS1_SIG",
        "gps_sig_t",
        aux_sets::gps_sig::SIZE,
        aux_sets::gps_sig::FIELDS,
        Source::Fixed(1000),
        rmc_aux::BITS_GPS1_SIG,
    ),
    nav(
        MAGNETOMETER,
        "MAGNETOMETER",
        "magnetometer_t",
        magnetometer::SIZE,
        magnetometer::FIELDS,
        Source::Fixed(10),
        rmc_nav::BITS_MAGNETOMETER,
    ),
    nav(
        BAROMETER,
        "BAROMETER",
        "barometer_t",
        barometer::SIZE,
        barometer::FIELDS,
        Source::Fixed(8),
        rmc_nav::BITS_BAROMETER,
    ),
    nav(
        SYS_SENSORS,
        "SYS_SENSORS",
        "sys_sensors_t",
        sys_sensors::SIZE,
        sys_sensors::FIELDS,
        Source::Millisecond,
        0,
    ),
    nav(
        IMU_MAG,
        "IMU_MAG",
        "imu_mag_t",
        imu_mag::SIZE,
        imu_mag::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_IMU_MAG,
    ),
    nav(
        PIMU_MAG,
        "PIMU_MAG",
        "pimu_mag_t",
        pimu_mag::SIZE,
        pimu_mag::FIELDS,
        Source::NavDt,
        rmc_nav::BITS_PIMU_MAG,
    ),
];

/// The largest data set served, bytes (GPS1_SIG's 708): what an image
/// buffer of the device and the TX queue's largest frame must hold.
pub const MAX_SIZE: usize = {
    let mut max = 0;
    let mut i = 0;
    while i < DATA_SETS.len() {
        if DATA_SETS[i].size as usize > max {
            max = DATA_SETS[i].size as usize;
        }
        i += 1;
    }
    max
};

/// The table row of `did`, if the emulated IMX serves it.
pub fn lookup(did: u16) -> Option<&'static DataSet> {
    DATA_SETS.iter().find(|s| u16::from(s.did) == did)
}

/// Whether a GET_DATA or SET_DATA of `did` is answered with a NACK: DID ≥
/// [`DID_COUNT`] (protocol-facts.md "ISB") and DID 95 (protocol-facts.md "what the vendor's
/// command-line tool needs").
pub const fn is_nacked(did: u16) -> bool {
    did >= DID_COUNT || did == REFERENCE_IMU as u16
}

/// How the device treats a request for a DID.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// Answer with a NACK ([`is_nacked`]).
    Nack,
    /// In range but not served: no reply at all (protocol-facts.md "ISB").
    Unsupported,
    /// Served: its table row.
    Supported(&'static DataSet),
}

/// Classifies a DID ([`Class`]).
pub fn classify(did: u16) -> Class {
    if is_nacked(did) {
        return Class::Nack;
    }
    match lookup(did) {
        Some(s) => Class::Supported(s),
        None => Class::Unsupported,
    }
}

/// The DID name and named fields of data set `did`, if served (for
/// hosts: `imu-emu client --protocol isb` reads and writes data sets by
/// field name through these; the device never does).
pub fn set(did: u8) -> Option<(&'static str, &'static [FieldSpec])> {
    lookup(u16::from(did)).map(|s| (s.did_name, s.fields))
}

/// A data set by DID name (any case, `DID_` prefix optional) or number.
pub fn set_by_name(name: &str) -> Option<u8> {
    let bare = name
        .get(..4)
        .filter(|p| p.eq_ignore_ascii_case("did_"))
        .map_or(name, |_| &name[4..]);
    DATA_SETS
        .iter()
        .find(|s| s.did_name.eq_ignore_ascii_case(bare))
        .map(|s| s.did)
        .or_else(|| {
            let n: u8 = name.parse().ok()?;
            set(n).map(|_| n)
        })
}

/// A field named `SET.field` or, when only one data set has it, `field`
/// (any case): its DID and row.
pub fn find(name: &str) -> Option<(u8, &'static FieldSpec)> {
    let in_set = |did: u8, field: &str| {
        let (_, fs) = set(did)?;
        fs.iter()
            .find(|f| f.name.eq_ignore_ascii_case(field))
            .map(|f| (did, f))
    };
    if let Some((s, field)) = name.split_once('.') {
        return in_set(set_by_name(s)?, field);
    }
    let mut hits = DATA_SETS
        .iter()
        .filter(|s| s.did != IMU_RAW)
        .filter_map(|s| in_set(s.did, name));
    let first = hits.next()?;
    hits.next().is_none().then_some(first)
}

/// Names of the field that carries a data set's device time: `time` (s
/// since boot: IMU, IMU_RAW, IMU3_RAW, PIMU, IMU_MAG, PIMU_MAG,
/// MAGNETOMETER, BAROMETER, SYS_SENSORS), `timeOfWeek` (GPS s of the week:
/// INS_1..4, INL2_STATES) or `timeOfWeekMs` (ms: GPS1_POS, GPS1_RCVR_POS,
/// GPS1_VEL, GPS1_SAT, GPS1_SIG, INL2_NED_SIGMA, STROBE_IN_TIME,
/// SYS_PARAMS).
pub const TIME_FIELDS: [&str; 3] = ["time", "timeOfWeek", "timeOfWeekMs"];

/// The device time a data set carries, in seconds: its first field named
/// in [`TIME_FIELDS`] (in ms when its unit says so); `None` for a set
/// with none.
pub fn device_time(did: u8, b: &[u8]) -> Option<f64> {
    let (_, fields) = set(did)?;
    let f = fields.iter().find(|f| TIME_FIELDS.contains(&f.name))?;
    let scale = if f.unit == "ms" { 1e3 } else { 1.0 };
    match super::layout::read(f, b) {
        super::layout::Value::Float(s) => Some(s / scale),
        super::layout::Value::Unsigned(n) => Some(n as f64 / scale),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nack_rule() {
        assert!(is_nacked(132));
        assert!(is_nacked(255));
        assert!(is_nacked(0xFFFF));
        assert!(is_nacked(95));
        assert!(!is_nacked(131));
        assert!(!is_nacked(94));
        assert!(!is_nacked(0));
        assert_eq!(classify(0), Class::Unsupported);
        assert_eq!(classify(121), Class::Unsupported);
        assert_eq!(classify(95), Class::Nack);
        assert!(matches!(classify(58), Class::Supported(s) if s.size == 36));
    }

    #[test]
    fn every_row_is_consistent() {
        for s in &DATA_SETS {
            assert!(u16::from(s.did) < DID_COUNT && !is_nacked(u16::from(s.did)));
            assert_eq!(lookup(u16::from(s.did)), Some(s));
            for r in s.writable {
                assert!(r.start < r.end && r.end <= s.size, "{}", s.name);
            }
        }
    }

    #[test]
    fn every_named_field_lies_inside_its_set() {
        for s in &DATA_SETS {
            for f in s.fields {
                assert!(
                    f.offset + f.kind.size() <= usize::from(s.size),
                    "{} {}",
                    s.did,
                    f.name
                );
            }
        }
    }

    #[test]
    fn names_resolve() {
        assert_eq!(find("startupNavDtMs").unwrap().0, FLASH_CONFIG);
        assert_eq!(find("flash_config.SER0BAUDRATE").unwrap().1.offset, 20);
        // In several sets: ambiguous without the set.
        assert!(find("time").is_none());
        assert_eq!(find("imu.time").unwrap().0, IMU);
        assert_eq!(find("IMU_RAW.acc").unwrap().0, IMU_RAW);
        assert_eq!(set_by_name("did_pimu"), Some(PIMU));
        assert_eq!(set_by_name("58"), Some(IMU));
        assert_eq!(set_by_name("59"), None);
    }

    #[test]
    fn reads_typed_values() {
        let mut b = [0u8; 36];
        b[0..8].copy_from_slice(&1.5f64.to_le_bytes());
        b[24..28].copy_from_slice(&(-9.5f32).to_le_bytes());
        let (_, fs) = set(IMU).unwrap();
        assert_eq!(
            crate::isb::layout::read(&fs[0], &b),
            crate::isb::layout::Value::Float(1.5)
        );
        assert_eq!(
            crate::isb::layout::read(&fs[3], &b),
            crate::isb::layout::Value::Vec3([-9.5, 0.0, 0.0])
        );
        assert_eq!(device_time(IMU, &b), Some(1.5));
        assert_eq!(device_time(RMC, &b), None);
        let timed: heapless::Vec<u8, 64> = DATA_SETS
            .iter()
            .filter(|s| device_time(s.did, &[0; MAX_SIZE]).is_some())
            .map(|s| s.did)
            .collect();
        assert_eq!(
            timed,
            [
                PIMU,
                SYS_PARAMS,
                IMU,
                STROBE_IN_TIME,
                IMU3_RAW,
                IMU_RAW,
                INS_1,
                INS_2,
                INS_3,
                INS_4,
                INL2_STATES,
                INL2_NED_SIGMA,
                GPS1_POS,
                GPS1_RCVR_POS,
                GPS1_VEL,
                GPS1_SAT,
                GPS1_SIG,
                MAGNETOMETER,
                BAROMETER,
                SYS_SENSORS,
                IMU_MAG,
                PIMU_MAG
            ]
        );
        let mut g = [0u8; 92];
        g[4..8].copy_from_slice(&1234u32.to_le_bytes());
        assert_eq!(device_time(GPS1_POS, &g), Some(1.234));
    }
}
