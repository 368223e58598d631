//! The named fields of every data set the emulated IMX-5 serves, for
//! hosts: the field names of the SDK's `data_sets.h` (protocol 2.1), their
//! byte offsets (the layouts of [`crate::isb::sets`], listed in
//! `docs/isb-data-sets.md`), types and units, and a typed reader. The
//! device never uses this table; `imu-emu client --protocol isb` and the
//! tests read and write data sets by field name through it.

use crate::isb::asce;
use crate::isb::aux_sets as aux;
use crate::isb::did;
use crate::isb::nav_sets as nav;
use crate::isb::sets::{self, le};
use crate::isb::{can, rtos};

/// The type of a field, as packed in the struct.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `u8`.
    U8,
    /// `u16`.
    U16,
    /// `u32`.
    U32,
    /// `u64`.
    U64,
    /// `f32`.
    F32,
    /// `f64`.
    F64,
    /// `f32[3]`.
    F32x3,
    /// `f32[4]` (a quaternion).
    F32x4,
    /// `f64[3]`.
    F64x3,
    /// `u8[4]` version `a.b.c.d`.
    Version,
    /// `char[24]`, NUL padded.
    Str24,
}

impl Kind {
    /// Bytes the field takes.
    pub const fn size(self) -> usize {
        match self {
            Kind::U8 => 1,
            Kind::U16 => 2,
            Kind::U32 | Kind::F32 | Kind::Version => 4,
            Kind::U64 | Kind::F64 => 8,
            Kind::F32x3 => 12,
            Kind::F32x4 => 16,
            Kind::F64x3 => 24,
            Kind::Str24 => 24,
        }
    }
}

/// One field of a data set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldSpec {
    /// Its `data_sets.h` name (`startupNavDtMs`).
    pub name: &'static str,
    /// Byte offset in the struct.
    pub offset: usize,
    /// Type.
    pub kind: Kind,
    /// Unit of the value (`""` for none).
    pub unit: &'static str,
}

/// A field's value as read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// An unsigned integer.
    Unsigned(u64),
    /// A float.
    Float(f64),
    /// Three floats (x, y, z).
    Vec3([f64; 3]),
    /// Four floats (a quaternion w, x, y, z).
    Vec4([f64; 4]),
    /// A version `a.b.c.d`.
    Version([u8; 4]),
    /// NUL-padded text: the bytes, and the length up to the first NUL.
    Text([u8; 24], usize),
}

const fn f(name: &'static str, offset: usize, kind: Kind, unit: &'static str) -> FieldSpec {
    FieldSpec {
        name,
        offset,
        kind,
        unit,
    }
}

use Kind::*;

const DEV_INFO: &[FieldSpec] = &[
    f("hardwareType", sets::dev_info::HARDWARE_TYPE, U8, ""),
    f("hdwRunState", sets::dev_info::HDW_RUN_STATE, U8, ""),
    f("serialNumber", sets::dev_info::SERIAL_NUMBER, U32, ""),
    f("hardwareVer", sets::dev_info::HARDWARE_VER, Version, ""),
    f("firmwareVer", sets::dev_info::FIRMWARE_VER, Version, ""),
    f("buildNumber", sets::dev_info::BUILD_NUMBER, U32, ""),
    f("protocolVer", sets::dev_info::PROTOCOL_VER, Version, ""),
    f("repoRevision", sets::dev_info::REPO_REVISION, U32, ""),
    f("manufacturer", sets::dev_info::MANUFACTURER, Str24, ""),
    f("buildType", sets::dev_info::BUILD_TYPE, U8, ""),
    f("addInfo", sets::dev_info::ADD_INFO, Str24, ""),
];

const IMU: &[FieldSpec] = &[
    f("time", sets::imu::TIME, F64, "s"),
    f("status", sets::imu::STATUS, U32, ""),
    f("pqr", sets::imu::PQR, F32x3, "rad/s"),
    f("acc", sets::imu::ACC, F32x3, "m/s²"),
];

const PIMU: &[FieldSpec] = &[
    f("time", sets::pimu::TIME, F64, "s"),
    f("dt", sets::pimu::DT, F32, "s"),
    f("status", sets::pimu::STATUS, U32, ""),
    f("theta", sets::pimu::THETA, F32x3, "rad"),
    f("vel", sets::pimu::VEL, F32x3, "m/s"),
];

const RMC: &[FieldSpec] = &[
    f("bits", sets::rmc::BITS, U64, ""),
    f("options", sets::rmc::OPTIONS, U32, ""),
];

/// `nmea_msgs_t`: options, then 20 `{msgID, period}` pairs.
const NMEA_MSGS: &[FieldSpec] = &[
    f("options", asce::nmea_msgs::OPTIONS, U32, ""),
    f("nmeaBroadcastMsgs[0].msgID", asce::nmea_msgs::MSGS, U8, ""),
    f(
        "nmeaBroadcastMsgs[0].period",
        asce::nmea_msgs::MSGS + 1,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[1].msgID",
        asce::nmea_msgs::MSGS + 2,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[1].period",
        asce::nmea_msgs::MSGS + 3,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[2].msgID",
        asce::nmea_msgs::MSGS + 4,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[2].period",
        asce::nmea_msgs::MSGS + 5,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[3].msgID",
        asce::nmea_msgs::MSGS + 6,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[3].period",
        asce::nmea_msgs::MSGS + 7,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[4].msgID",
        asce::nmea_msgs::MSGS + 8,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[4].period",
        asce::nmea_msgs::MSGS + 9,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[5].msgID",
        asce::nmea_msgs::MSGS + 10,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[5].period",
        asce::nmea_msgs::MSGS + 11,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[6].msgID",
        asce::nmea_msgs::MSGS + 12,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[6].period",
        asce::nmea_msgs::MSGS + 13,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[7].msgID",
        asce::nmea_msgs::MSGS + 14,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[7].period",
        asce::nmea_msgs::MSGS + 15,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[8].msgID",
        asce::nmea_msgs::MSGS + 16,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[8].period",
        asce::nmea_msgs::MSGS + 17,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[9].msgID",
        asce::nmea_msgs::MSGS + 18,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[9].period",
        asce::nmea_msgs::MSGS + 19,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[10].msgID",
        asce::nmea_msgs::MSGS + 20,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[10].period",
        asce::nmea_msgs::MSGS + 21,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[11].msgID",
        asce::nmea_msgs::MSGS + 22,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[11].period",
        asce::nmea_msgs::MSGS + 23,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[12].msgID",
        asce::nmea_msgs::MSGS + 24,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[12].period",
        asce::nmea_msgs::MSGS + 25,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[13].msgID",
        asce::nmea_msgs::MSGS + 26,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[13].period",
        asce::nmea_msgs::MSGS + 27,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[14].msgID",
        asce::nmea_msgs::MSGS + 28,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[14].period",
        asce::nmea_msgs::MSGS + 29,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[15].msgID",
        asce::nmea_msgs::MSGS + 30,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[15].period",
        asce::nmea_msgs::MSGS + 31,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[16].msgID",
        asce::nmea_msgs::MSGS + 32,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[16].period",
        asce::nmea_msgs::MSGS + 33,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[17].msgID",
        asce::nmea_msgs::MSGS + 34,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[17].period",
        asce::nmea_msgs::MSGS + 35,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[18].msgID",
        asce::nmea_msgs::MSGS + 36,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[18].period",
        asce::nmea_msgs::MSGS + 37,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[19].msgID",
        asce::nmea_msgs::MSGS + 38,
        U8,
        "",
    ),
    f(
        "nmeaBroadcastMsgs[19].period",
        asce::nmea_msgs::MSGS + 39,
        U8,
        "",
    ),
];

const SYS_CMD: &[FieldSpec] = &[
    f("command", sets::sys_cmd::COMMAND, U32, ""),
    f("invCommand", sets::sys_cmd::INV_COMMAND, U32, ""),
];

const STROBE: &[FieldSpec] = &[
    f("week", sets::strobe::WEEK, U32, ""),
    f("timeOfWeekMs", sets::strobe::TIME_OF_WEEK_MS, U32, "ms"),
    f("pin", sets::strobe::PIN, U16, ""),
    f("count", sets::strobe::COUNT, U16, ""),
];

const SYS_PARAMS: &[FieldSpec] = &[
    f("timeOfWeekMs", sets::sys_params::TIME_OF_WEEK_MS, U32, "ms"),
    f("insStatus", sets::sys_params::INS_STATUS, U32, ""),
    f("hdwStatus", sets::sys_params::HDW_STATUS, U32, ""),
    f("imuTemp", sets::sys_params::IMU_TEMP, F32, "°C"),
    f("baroTemp", sets::sys_params::BARO_TEMP, F32, "°C"),
    f("mcuTemp", sets::sys_params::MCU_TEMP, F32, "°C"),
    f("sysStatus", sets::sys_params::SYS_STATUS, U32, ""),
    f(
        "imuSamplePeriodMs",
        sets::sys_params::IMU_SAMPLE_PERIOD_MS,
        U32,
        "ms",
    ),
    f(
        "navOutputPeriodMs",
        sets::sys_params::NAV_OUTPUT_PERIOD_MS,
        U32,
        "ms",
    ),
    f(
        "sensorTruePeriod",
        sets::sys_params::SENSOR_TRUE_PERIOD,
        F64,
        "s",
    ),
    f(
        "flashCfgChecksum",
        sets::sys_params::FLASH_CFG_CHECKSUM,
        U32,
        "",
    ),
    f(
        "navUpdatePeriodMs",
        sets::sys_params::NAV_UPDATE_PERIOD_MS,
        U32,
        "ms",
    ),
    f("genFaultCode", sets::sys_params::GEN_FAULT_CODE, U32, ""),
    f("upTime", sets::sys_params::UP_TIME, F64, "s"),
];

/// FLASH_CONFIG: every field but `wheelConfig` (a struct of its own) and
/// the GNSS thresholds the IMU mode does not use.
const FLASH: &[FieldSpec] = &[
    f("size", sets::flash::SIZE_FIELD, U32, ""),
    f("checksum", sets::flash::CHECKSUM, U32, ""),
    f("key", sets::flash::KEY, U32, ""),
    f("startupImuDtMs", sets::flash::STARTUP_IMU_DT_MS, U32, "ms"),
    f("startupNavDtMs", sets::flash::STARTUP_NAV_DT_MS, U32, "ms"),
    f("ser0BaudRate", sets::flash::SER0_BAUD_RATE, U32, "bit/s"),
    f("ser1BaudRate", sets::flash::SER1_BAUD_RATE, U32, "bit/s"),
    f("insRotation", sets::flash::INS_ROTATION, F32x3, "rad"),
    f("insOffset", sets::flash::INS_OFFSET, F32x3, "m"),
    f("gps1AntOffset", sets::flash::GPS1_ANT_OFFSET, F32x3, "m"),
    f("dynamicModel", sets::flash::DYNAMIC_MODEL, U8, ""),
    f("debug", sets::flash::DEBUG, U8, ""),
    f("gnssSatSigConst", sets::flash::GNSS_SAT_SIG_CONST, U16, ""),
    f("sysCfgBits", sets::flash::SYS_CFG_BITS, U32, ""),
    f("refLla", sets::flash::REF_LLA, F64x3, "deg, deg, m"),
    f("lastLla", sets::flash::LAST_LLA, F64x3, "deg, deg, m"),
    f(
        "lastLlaTimeOfWeekMs",
        sets::flash::LAST_LLA_TIME_OF_WEEK_MS,
        U32,
        "ms",
    ),
    f("lastLlaWeek", sets::flash::LAST_LLA_WEEK, U32, ""),
    f(
        "lastLlaUpdateDistance",
        sets::flash::LAST_LLA_UPDATE_DISTANCE,
        F32,
        "m",
    ),
    f("ioConfig", sets::flash::IO_CONFIG, U32, ""),
    f("platformConfig", sets::flash::PLATFORM_CONFIG, U32, ""),
    f("gps2AntOffset", sets::flash::GPS2_ANT_OFFSET, F32x3, "m"),
    f(
        "zeroVelRotation",
        sets::flash::ZERO_VEL_ROTATION,
        F32x3,
        "rad",
    ),
    f("zeroVelOffset", sets::flash::ZERO_VEL_OFFSET, F32x3, "m"),
    f(
        "gpsTimeUserDelay",
        sets::flash::GPS_TIME_USER_DELAY,
        F32,
        "s",
    ),
    f("magDeclination", sets::flash::MAG_DECLINATION, F32, "rad"),
    f(
        "gpsTimeSyncPeriodMs",
        sets::flash::GPS_TIME_SYNC_PERIOD_MS,
        U32,
        "ms",
    ),
    f("startupGPSDtMs", sets::flash::STARTUP_GPS_DT_MS, U32, "ms"),
    f("RTKCfgBits", sets::flash::RTK_CFG_BITS, U32, ""),
    f("sensorConfig", sets::flash::SENSOR_CONFIG, U32, ""),
    f(
        "gpsMinimumElevation",
        sets::flash::GPS_MINIMUM_ELEVATION,
        F32,
        "rad",
    ),
    f("ser2BaudRate", sets::flash::SER2_BAUD_RATE, U32, "bit/s"),
    f(
        "magInterferenceThreshold",
        sets::flash::MAG_INTERFERENCE_THRESHOLD,
        F32,
        "",
    ),
    f(
        "magCalibrationQualityThreshold",
        sets::flash::MAG_CALIBRATION_QUALITY_THRESHOLD,
        F32,
        "",
    ),
    f(
        "imuRejectThreshGyroLow",
        sets::flash::IMU_REJECT_THRESH_GYRO_LOW,
        U8,
        "",
    ),
    f(
        "imuRejectThreshGyroHigh",
        sets::flash::IMU_REJECT_THRESH_GYRO_HIGH,
        U8,
        "",
    ),
    f(
        "imuShockDetectLatencyMs",
        sets::flash::IMU_SHOCK_DETECT_LATENCY_MS,
        U8,
        "ms",
    ),
    f(
        "imuShockRejectLatchMs",
        sets::flash::IMU_SHOCK_REJECT_LATCH_MS,
        U8,
        "ms",
    ),
    f("imuShockOptions", sets::flash::IMU_SHOCK_OPTIONS, U8, ""),
];

const BIT: &[FieldSpec] = &[
    f("command", sets::bit::COMMAND, U8, ""),
    f("lastCommand", sets::bit::LAST_COMMAND, U8, ""),
    f("state", sets::bit::STATE, U8, ""),
    f("hdwBitStatus", sets::bit::HDW_BIT_STATUS, U32, ""),
    f("calBitStatus", sets::bit::CAL_BIT_STATUS, U32, ""),
    f("pqr", sets::bit::PQR, F32, "rad/s"),
    f("acc", sets::bit::ACC, F32, "m/s²"),
    f("pqrSigma", sets::bit::PQR_SIGMA, F32, "rad/s"),
    f("accSigma", sets::bit::ACC_SIGMA, F32, "m/s²"),
    f("testMode", sets::bit::TEST_MODE, U8, ""),
    f("testVar", sets::bit::TEST_VAR, U8, ""),
    f(
        "detectedHardwareId",
        sets::bit::DETECTED_HARDWARE_ID,
        U16,
        "",
    ),
];

const INS_1: &[FieldSpec] = &[
    f("week", nav::ins_header::WEEK, U32, ""),
    f("timeOfWeek", nav::ins_header::TIME_OF_WEEK, F64, "s"),
    f("insStatus", nav::ins_header::INS_STATUS, U32, ""),
    f("hdwStatus", nav::ins_header::HDW_STATUS, U32, ""),
    f("theta", nav::ins1::THETA, F32x3, "rad"),
    f("uvw", nav::ins1::UVW, F32x3, "m/s"),
    f("lla", nav::ins1::LLA, F64x3, "deg, deg, m"),
    f("ned", nav::ins1::NED, F32x3, "m"),
];

const INS_2: &[FieldSpec] = &[
    f("week", nav::ins_header::WEEK, U32, ""),
    f("timeOfWeek", nav::ins_header::TIME_OF_WEEK, F64, "s"),
    f("insStatus", nav::ins_header::INS_STATUS, U32, ""),
    f("hdwStatus", nav::ins_header::HDW_STATUS, U32, ""),
    f("qn2b", nav::ins2::QN2B, F32x4, ""),
    f("uvw", nav::ins2::UVW, F32x3, "m/s"),
    f("lla", nav::ins2::LLA, F64x3, "deg, deg, m"),
];

const INS_3: &[FieldSpec] = &[
    f("week", nav::ins_header::WEEK, U32, ""),
    f("timeOfWeek", nav::ins_header::TIME_OF_WEEK, F64, "s"),
    f("insStatus", nav::ins_header::INS_STATUS, U32, ""),
    f("hdwStatus", nav::ins_header::HDW_STATUS, U32, ""),
    f("qn2b", nav::ins2::QN2B, F32x4, ""),
    f("uvw", nav::ins2::UVW, F32x3, "m/s"),
    f("lla", nav::ins2::LLA, F64x3, "deg, deg, m"),
    f("msl", nav::ins3::MSL, F32, "m"),
];

const INS_4: &[FieldSpec] = &[
    f("week", nav::ins_header::WEEK, U32, ""),
    f("timeOfWeek", nav::ins_header::TIME_OF_WEEK, F64, "s"),
    f("insStatus", nav::ins_header::INS_STATUS, U32, ""),
    f("hdwStatus", nav::ins_header::HDW_STATUS, U32, ""),
    f("qe2b", nav::ins4::QE2B, F32x4, ""),
    f("ve", nav::ins4::VE, F32x3, "m/s"),
    f("ecef", nav::ins4::ECEF, F64x3, "m"),
];

const INL2_STATES: &[FieldSpec] = &[
    f("timeOfWeek", nav::inl2_states::TIME_OF_WEEK, F64, "s"),
    f("qe2b", nav::inl2_states::QE2B, F32x4, ""),
    f("ve", nav::inl2_states::VE, F32x3, "m/s"),
    f("ecef", nav::inl2_states::ECEF, F64x3, "m"),
    f("biasPqr", nav::inl2_states::BIAS_PQR, F32x3, "rad/s"),
    f("biasAcc", nav::inl2_states::BIAS_ACC, F32x3, "m/s^2"),
    f("biasBaro", nav::inl2_states::BIAS_BARO, F32, "m"),
    f("magDec", nav::inl2_states::MAG_DEC, F32, "rad"),
    f("magInc", nav::inl2_states::MAG_INC, F32, "rad"),
];

const INL2_NED_SIGMA: &[FieldSpec] = &[
    f(
        "timeOfWeekMs",
        nav::inl2_ned_sigma::TIME_OF_WEEK_MS,
        U32,
        "ms",
    ),
    f("StdPosNed", nav::inl2_ned_sigma::STD_POS_NED, F32x3, "m"),
    f("StdVelNed", nav::inl2_ned_sigma::STD_VEL_NED, F32x3, "m/s"),
    f("StdAttNed", nav::inl2_ned_sigma::STD_ATT_NED, F32x3, "rad"),
    f(
        "StdAccBias",
        nav::inl2_ned_sigma::STD_ACC_BIAS,
        F32x3,
        "m/s^2",
    ),
    f(
        "StdGyrBias",
        nav::inl2_ned_sigma::STD_GYR_BIAS,
        F32x3,
        "rad/s",
    ),
    f("StdBarBias", nav::inl2_ned_sigma::STD_BAR_BIAS, F32, "m"),
    f(
        "StdMagDeclination",
        nav::inl2_ned_sigma::STD_MAG_DECLINATION,
        F32,
        "rad",
    ),
];

const GPS_POS: &[FieldSpec] = &[
    f("week", nav::gps_pos::WEEK, U32, ""),
    f("timeOfWeekMs", nav::gps_pos::TIME_OF_WEEK_MS, U32, "ms"),
    f("status", nav::gps_pos::STATUS, U32, ""),
    f("ecef", nav::gps_pos::ECEF, F64x3, "m"),
    f("lla", nav::gps_pos::LLA, F64x3, "deg, deg, m"),
    f("hMSL", nav::gps_pos::H_MSL, F32, "m"),
    f("hAcc", nav::gps_pos::H_ACC, F32, "m"),
    f("vAcc", nav::gps_pos::V_ACC, F32, "m"),
    f("pDop", nav::gps_pos::P_DOP, F32, ""),
    f("cnoMean", nav::gps_pos::CNO_MEAN, F32, "dBHz"),
    f("towOffset", nav::gps_pos::TOW_OFFSET, F64, "s"),
    f("leapS", nav::gps_pos::LEAP_S, U8, "s"),
    f("satsUsed", nav::gps_pos::SATS_USED, U8, ""),
    f("cnoMeanSigma", nav::gps_pos::CNO_MEAN_SIGMA, U8, "dBHz"),
    f("status2", nav::gps_pos::STATUS2, U8, ""),
];

const GPS_VEL: &[FieldSpec] = &[
    f("timeOfWeekMs", nav::gps_vel::TIME_OF_WEEK_MS, U32, "ms"),
    f("vel", nav::gps_vel::VEL, F32x3, "m/s"),
    f("sAcc", nav::gps_vel::S_ACC, F32, "m/s"),
    f("status", nav::gps_vel::STATUS, U32, ""),
];

/// `gps_sat_t`: the header; the `sat` records (8 bytes each from
/// [`nav::gps_sat::SAT`], [`nav::gps_sat_sv`]) are an array the table has
/// no kind for, so only the first satellite's fields are named.
const GPS_SAT: &[FieldSpec] = &[
    f("timeOfWeekMs", nav::gps_sat::TIME_OF_WEEK_MS, U32, "ms"),
    f("numSats", nav::gps_sat::NUM_SATS, U32, ""),
    f(
        "gnssId",
        nav::gps_sat::SAT + nav::gps_sat_sv::GNSS_ID,
        U8,
        "",
    ),
    f("svId", nav::gps_sat::SAT + nav::gps_sat_sv::SV_ID, U8, ""),
    f("cno", nav::gps_sat::SAT + nav::gps_sat_sv::CNO, U8, "dBHz"),
];

const MAGNETOMETER: &[FieldSpec] = &[
    f("time", nav::magnetometer::TIME, F64, "s"),
    f("mag", nav::magnetometer::MAG, F32x3, "normalized"),
];

const BAROMETER: &[FieldSpec] = &[
    f("time", nav::barometer::TIME, F64, "s"),
    f("bar", nav::barometer::BAR, F32, "kPa"),
    f("mslBar", nav::barometer::MSL_BAR, F32, "m"),
    f("barTemp", nav::barometer::BAR_TEMP, F32, "°C"),
    f("humidity", nav::barometer::HUMIDITY, F32, "%"),
];

/// `imu_mag_t`: an `imu_t`, then a `magnetometer_t`.
const IMU_MAG: &[FieldSpec] = &[
    f("time", nav::imu_mag::IMU + sets::imu::TIME, F64, "s"),
    f("status", nav::imu_mag::IMU + sets::imu::STATUS, U32, ""),
    f("pqr", nav::imu_mag::IMU + sets::imu::PQR, F32x3, "rad/s"),
    f("acc", nav::imu_mag::IMU + sets::imu::ACC, F32x3, "m/s²"),
    f(
        "magTime",
        nav::imu_mag::MAG + nav::magnetometer::TIME,
        F64,
        "s",
    ),
    f(
        "mag",
        nav::imu_mag::MAG + nav::magnetometer::MAG,
        F32x3,
        "normalized",
    ),
];

/// `pimu_mag_t`: a `pimu_t`, then a `magnetometer_t`.
const PIMU_MAG: &[FieldSpec] = &[
    f("time", nav::pimu_mag::PIMU + sets::pimu::TIME, F64, "s"),
    f("dt", nav::pimu_mag::PIMU + sets::pimu::DT, F32, "s"),
    f("status", nav::pimu_mag::PIMU + sets::pimu::STATUS, U32, ""),
    f(
        "theta",
        nav::pimu_mag::PIMU + sets::pimu::THETA,
        F32x3,
        "rad",
    ),
    f("vel", nav::pimu_mag::PIMU + sets::pimu::VEL, F32x3, "m/s"),
    f(
        "magTime",
        nav::pimu_mag::MAG + nav::magnetometer::TIME,
        F64,
        "s",
    ),
    f(
        "mag",
        nav::pimu_mag::MAG + nav::magnetometer::MAG,
        F32x3,
        "normalized",
    ),
];

const SYS_FAULT: &[FieldSpec] = &[
    f("status", aux::sys_fault::STATUS, U32, ""),
    f("g1Task", aux::sys_fault::G1_TASK, U32, ""),
    f("g2FileNum", aux::sys_fault::G2_FILE_NUM, U32, ""),
    f("g3LineNum", aux::sys_fault::G3_LINE_NUM, U32, ""),
    f("g4", aux::sys_fault::G4, U32, ""),
    f("g5Lr", aux::sys_fault::G5_LR, U32, ""),
    f("pc", aux::sys_fault::PC, U32, ""),
    f("psr", aux::sys_fault::PSR, U32, ""),
];

/// `gps_version_t`: 30- and 10-byte strings the table has no kind for
/// (read them from the image, [`aux::gps_version`]).
const GPS_VERSION: &[FieldSpec] = &[];

const MAG_CAL: &[FieldSpec] = &[
    f("state", aux::mag_cal::STATE, U32, ""),
    f("progress", aux::mag_cal::PROGRESS, F32, "%"),
    f("declination", aux::mag_cal::DECLINATION, F32, "rad"),
];

/// `rtos_info_t`: the heap words and the first task's figures (the
/// others follow every 60 bytes, [`crate::isb::rtos`]).
const RTOS_INFO: &[FieldSpec] = &[
    f("freeHeapSize", rtos::rtos_info::FREE_HEAP_SIZE, U32, "B"),
    f("mallocSize", rtos::rtos_info::MALLOC_SIZE, U32, "B"),
    f("freeSize", rtos::rtos_info::FREE_SIZE, U32, "B"),
    f(
        "T0_periodMs",
        rtos::rtos_info::TASK + rtos::rtos_task::PERIOD_MS,
        U32,
        "ms",
    ),
    f(
        "T0_startTimeUs",
        rtos::rtos_info::TASK + rtos::rtos_task::START_TIME_US,
        U32,
        "us",
    ),
    f(
        "T1_periodMs",
        rtos::rtos_info::TASK + 60 + rtos::rtos_task::PERIOD_MS,
        U32,
        "ms",
    ),
    f(
        "T1_startTimeUs",
        rtos::rtos_info::TASK + 60 + rtos::rtos_task::START_TIME_US,
        U32,
        "us",
    ),
];

/// `can_config_t`: the first message's period and address, the bus rate
/// and the receive address ([`crate::isb::can`]).
const CAN_CONFIG: &[FieldSpec] = &[
    f(
        "can_period_mult_0",
        can::can_config::CAN_PERIOD_MULT,
        U16,
        "",
    ),
    f(
        "can_transmit_address_0",
        can::can_config::CAN_TRANSMIT_ADDRESS,
        U32,
        "",
    ),
    f(
        "can_baudrate_kbps",
        can::can_config::CAN_BAUDRATE_KBPS,
        U16,
        "kbit/s",
    ),
    f(
        "can_receive_address",
        can::can_config::CAN_RECEIVE_ADDRESS,
        U32,
        "",
    ),
];

/// `gps_sig_t`: the header and the first signal's fields (as GPS_SAT).
const GPS_SIG: &[FieldSpec] = &[
    f("timeOfWeekMs", aux::gps_sig::TIME_OF_WEEK_MS, U32, "ms"),
    f("numSigs", aux::gps_sig::NUM_SIGS, U32, ""),
    f(
        "gnssId",
        aux::gps_sig::SIG + aux::gps_sig_sv::GNSS_ID,
        U8,
        "",
    ),
    f("svId", aux::gps_sig::SIG + aux::gps_sig_sv::SV_ID, U8, ""),
    f("sigId", aux::gps_sig::SIG + aux::gps_sig_sv::SIG_ID, U8, ""),
    f("cno", aux::gps_sig::SIG + aux::gps_sig_sv::CNO, U8, "dBHz"),
    f(
        "quality",
        aux::gps_sig::SIG + aux::gps_sig_sv::QUALITY,
        U8,
        "",
    ),
];

/// `imu3_t`: time, status, then IMU 1 (the three read alike).
const IMU3: &[FieldSpec] = &[
    f("time", aux::imu3::TIME, F64, "s"),
    f("status", aux::imu3::STATUS, U32, ""),
    f("pqr", aux::imu3::I + aux::imus::PQR, F32x3, "rad/s"),
    f("acc", aux::imu3::I + aux::imus::ACC, F32x3, "m/s²"),
];

/// `port_monitor_t`: port 0 (the serial line) and `activePorts`.
const PORT_MONITOR: &[FieldSpec] = &[
    f("portInfo", aux::port_monitor_set::PORT_INFO, U8, ""),
    f("status", aux::port_monitor_set::STATUS, U32, ""),
    f(
        "txBytesPerSec",
        aux::port_monitor_set::TX_BYTES_PER_SEC,
        U32,
        "B/s",
    ),
    f(
        "rxBytesPerSec",
        aux::port_monitor_set::RX_BYTES_PER_SEC,
        U32,
        "B/s",
    ),
    f("txBytes", aux::port_monitor_set::TX_BYTES, U32, "B"),
    f("rxBytes", aux::port_monitor_set::RX_BYTES, U32, "B"),
    f("txDataDrops", aux::port_monitor_set::TX_DATA_DROPS, U32, ""),
    f("rxOverflows", aux::port_monitor_set::RX_OVERFLOWS, U32, ""),
    f(
        "txBytesDropped",
        aux::port_monitor_set::TX_BYTES_DROPPED,
        U32,
        "B",
    ),
    f(
        "rxChecksumErrors",
        aux::port_monitor_set::RX_CHECKSUM_ERRORS,
        U32,
        "",
    ),
    f("activePorts", aux::port_monitor::ACTIVE_PORTS, U8, ""),
];

const SYS_SENSORS: &[FieldSpec] = &[
    f("time", nav::sys_sensors::TIME, F64, "s"),
    f("temp", nav::sys_sensors::TEMP, F32, "°C"),
    f("pqr", nav::sys_sensors::PQR, F32x3, "rad/s"),
    f("acc", nav::sys_sensors::ACC, F32x3, "m/s²"),
    f("mag", nav::sys_sensors::MAG, F32x3, "normalized"),
    f("bar", nav::sys_sensors::BAR, F32, "kPa"),
    f("barTemp", nav::sys_sensors::BAR_TEMP, F32, "°C"),
    f("mslBar", nav::sys_sensors::MSL_BAR, F32, "m"),
    f("humidity", nav::sys_sensors::HUMIDITY, F32, "%"),
    f("vin", nav::sys_sensors::VIN, F32, "V"),
    f("ana", nav::sys_sensors::ANA, F32x3, "V"),
];

/// The data sets served, by DID: the SDK's DID name and its fields.
pub const SETS: [(u8, &str, &[FieldSpec]); 34] = [
    (did::DEV_INFO, "DEV_INFO", DEV_INFO),
    (did::SYS_FAULT, "SYS_FAULT", SYS_FAULT),
    (did::PIMU, "PIMU", PIMU),
    (did::SYS_CMD, "SYS_CMD", SYS_CMD),
    (did::NMEA_BCAST_PERIOD, "NMEA_BCAST_PERIOD", NMEA_MSGS),
    (did::RMC, "RMC", RMC),
    (did::SYS_PARAMS, "SYS_PARAMS", SYS_PARAMS),
    (did::FLASH_CONFIG, "FLASH_CONFIG", FLASH),
    (did::GPS1_VERSION, "GPS1_VERSION", GPS_VERSION),
    (did::MAG_CAL, "MAG_CAL", MAG_CAL),
    (did::RTOS_INFO, "RTOS_INFO", RTOS_INFO),
    (did::CAN_CONFIG, "CAN_CONFIG", CAN_CONFIG),
    (did::IMU, "IMU", IMU),
    (did::BIT, "BIT", BIT),
    (did::PORT_MONITOR, "PORT_MONITOR", PORT_MONITOR),
    (did::STROBE_IN_TIME, "STROBE_IN_TIME", STROBE),
    (did::IMU3_RAW, "IMU3_RAW", IMU3),
    (did::IMU_RAW, "IMU_RAW", IMU),
    (did::INS_1, "INS_1", INS_1),
    (did::INS_2, "INS_2", INS_2),
    (did::INS_3, "INS_3", INS_3),
    (did::INS_4, "INS_4", INS_4),
    (did::INL2_STATES, "INL2_STATES", INL2_STATES),
    (did::INL2_NED_SIGMA, "INL2_NED_SIGMA", INL2_NED_SIGMA),
    (did::GPS1_POS, "GPS1_POS", GPS_POS),
    (did::GPS1_RCVR_POS, "GPS1_RCVR_POS", GPS_POS),
    (did::GPS1_VEL, "GPS1_VEL", GPS_VEL),
    (did::GPS1_SAT, "GPS1_SAT", GPS_SAT),
    (did::GPS1_SIG, "GPS1_SIG", GPS_SIG),
    (did::MAGNETOMETER, "MAGNETOMETER", MAGNETOMETER),
    (did::BAROMETER, "BAROMETER", BAROMETER),
    (did::IMU_MAG, "IMU_MAG", IMU_MAG),
    (did::PIMU_MAG, "PIMU_MAG", PIMU_MAG),
    (did::SYS_SENSORS, "SYS_SENSORS", SYS_SENSORS),
];

/// The DID name and fields of data set `did`, if served.
pub fn set(did: u8) -> Option<(&'static str, &'static [FieldSpec])> {
    SETS.iter().find(|s| s.0 == did).map(|s| (s.1, s.2))
}

/// A data set by DID name (any case, `DID_` prefix optional) or number.
pub fn set_by_name(name: &str) -> Option<u8> {
    let bare = name
        .get(..4)
        .filter(|p| p.eq_ignore_ascii_case("did_"))
        .map_or(name, |_| &name[4..]);
    SETS.iter()
        .find(|s| s.1.eq_ignore_ascii_case(bare))
        .map(|s| s.0)
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
    let mut hits = SETS
        .iter()
        .filter(|s| s.0 != did::IMU_RAW)
        .filter_map(|s| in_set(s.0, name));
    let first = hits.next()?;
    hits.next().is_none().then_some(first)
}

/// Reads `spec` from a data set image `b` (zeros past its end).
pub fn read(spec: &FieldSpec, b: &[u8]) -> Value {
    let o = spec.offset;
    match spec.kind {
        U8 => Value::Unsigned(u64::from(le::get::<1>(b, o)[0])),
        U16 => Value::Unsigned(u64::from(le::u16(b, o))),
        U32 => Value::Unsigned(u64::from(le::u32(b, o))),
        U64 => Value::Unsigned(le::u64(b, o)),
        F32 => Value::Float(f64::from(le::f32(b, o))),
        F64 => Value::Float(le::f64(b, o)),
        F32x3 => Value::Vec3(le::f32x3(b, o).map(f64::from)),
        F32x4 => Value::Vec4([0, 4, 8, 12].map(|i| f64::from(le::f32(b, o + i)))),
        F64x3 => Value::Vec3([le::f64(b, o), le::f64(b, o + 8), le::f64(b, o + 16)]),
        Version => Value::Version(le::get::<4>(b, o)),
        Str24 => {
            let s = le::get::<24>(b, o);
            let n = s.iter().position(|&c| c == 0).unwrap_or(24);
            Value::Text(s, n)
        }
    }
}

/// The device time a data set carries, in seconds: `time` (s since boot)
/// of IMU, IMU_RAW, IMU3_RAW, PIMU, IMU_MAG, PIMU_MAG, MAGNETOMETER, BAROMETER and
/// SYS_SENSORS; the GPS time of week of INS_1..4 (`timeOfWeek`), GPS1_POS,
/// GPS1_VEL, GPS1_SAT and GPS1_SIG (`timeOfWeekMs`); `timeOfWeekMs` of STROBE_IN_TIME and
/// SYS_PARAMS. `None` for the others.
pub fn device_time(did: u8, b: &[u8]) -> Option<f64> {
    match did {
        did::IMU
        | did::IMU_RAW
        | did::IMU3_RAW
        | did::PIMU
        | did::IMU_MAG
        | did::PIMU_MAG
        | did::MAGNETOMETER
        | did::BAROMETER
        | did::SYS_SENSORS => Some(le::f64(b, 0)),
        // GPS seconds of the week.
        did::INS_1 | did::INS_2 | did::INS_3 | did::INS_4 => Some(le::f64(b, 4)),
        did::INL2_STATES => Some(le::f64(b, nav::inl2_states::TIME_OF_WEEK)),
        did::INL2_NED_SIGMA => {
            Some(f64::from(le::u32(b, nav::inl2_ned_sigma::TIME_OF_WEEK_MS)) / 1e3)
        }
        did::GPS1_POS | did::GPS1_RCVR_POS => {
            Some(f64::from(le::u32(b, nav::gps_pos::TIME_OF_WEEK_MS)) / 1e3)
        }
        did::GPS1_VEL => Some(f64::from(le::u32(b, nav::gps_vel::TIME_OF_WEEK_MS)) / 1e3),
        did::GPS1_SAT => Some(f64::from(le::u32(b, nav::gps_sat::TIME_OF_WEEK_MS)) / 1e3),
        did::GPS1_SIG => Some(f64::from(le::u32(b, aux::gps_sig::TIME_OF_WEEK_MS)) / 1e3),
        did::STROBE_IN_TIME => Some(f64::from(le::u32(b, sets::strobe::TIME_OF_WEEK_MS)) / 1e3),
        did::SYS_PARAMS => Some(f64::from(le::u32(b, sets::sys_params::TIME_OF_WEEK_MS)) / 1e3),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_field_lies_inside_its_set_and_every_served_set_is_named() {
        assert_eq!(SETS.len(), did::DATA_SETS.len());
        for s in did::DATA_SETS {
            assert!(set(s.did).is_some(), "{} has no field table", s.did);
        }
        for (d, _, fs) in SETS {
            let size = usize::from(did::lookup(u16::from(d)).unwrap().size);
            for f in fs {
                assert!(f.offset + f.kind.size() <= size, "{d} {}", f.name);
            }
        }
    }

    #[test]
    fn names_resolve() {
        assert_eq!(find("startupNavDtMs").unwrap().0, did::FLASH_CONFIG);
        assert_eq!(find("flash_config.SER0BAUDRATE").unwrap().1.offset, 20);
        // In several sets: ambiguous without the set.
        assert!(find("time").is_none());
        assert_eq!(find("imu.time").unwrap().0, did::IMU);
        assert_eq!(find("IMU_RAW.acc").unwrap().0, did::IMU_RAW);
        assert_eq!(set_by_name("did_pimu"), Some(did::PIMU));
        assert_eq!(set_by_name("58"), Some(did::IMU));
        assert_eq!(set_by_name("59"), None);
    }

    #[test]
    fn reads_typed_values() {
        let mut b = [0u8; 36];
        b[0..8].copy_from_slice(&1.5f64.to_le_bytes());
        b[24..28].copy_from_slice(&(-9.5f32).to_le_bytes());
        let (_, fs) = set(did::IMU).unwrap();
        assert_eq!(read(&fs[0], &b), Value::Float(1.5));
        assert_eq!(read(&fs[3], &b), Value::Vec3([-9.5, 0.0, 0.0]));
        assert_eq!(device_time(did::IMU, &b), Some(1.5));
        assert_eq!(device_time(did::RMC, &b), None);
    }
}
