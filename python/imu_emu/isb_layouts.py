"""The layouts of the ISB data sets the emulated IMX-5 serves: generated
by ``scripts/isb-layouts.py`` from ``imu-emu isb-layouts --json`` (the
program's one declaration of each set); do not edit.
"""

from typing import Dict, Sequence, Tuple

#: A named field: (``data_sets.h`` name, byte offset, kind, unit).
Field = Tuple[str, int, str, str]

__all__ = ["DEV_INFO", "SYS_FAULT", "PIMU", "SYS_CMD", "NMEA_BCAST_PERIOD", "RMC", "SYS_PARAMS", "FLASH_CONFIG", "GPS1_VERSION", "MAG_CAL", "RTOS_INFO", "CAN_CONFIG", "IMU", "BIT", "PORT_MONITOR", "STROBE_IN_TIME", "IMU3_RAW", "IMU_RAW", "INS_1", "INS_2", "INS_3", "INS_4", "INL2_STATES", "INL2_NED_SIGMA", "GPS1_POS", "GPS1_RCVR_POS", "GPS1_VEL", "GPS1_SAT", "GPS1_SIG", "MAGNETOMETER", "BAROMETER", "SYS_SENSORS", "IMU_MAG", "PIMU_MAG", "LAYOUTS", "Field"]

DEV_INFO = 1
SYS_FAULT = 2
PIMU = 3
SYS_CMD = 7
NMEA_BCAST_PERIOD = 8
RMC = 9
SYS_PARAMS = 10
FLASH_CONFIG = 12
GPS1_VERSION = 17
MAG_CAL = 19
RTOS_INFO = 38
CAN_CONFIG = 90
IMU = 58
BIT = 64
PORT_MONITOR = 75
STROBE_IN_TIME = 68
IMU3_RAW = 96
IMU_RAW = 97
INS_1 = 4
INS_2 = 5
INS_3 = 65
INS_4 = 66
INL2_STATES = 48
INL2_NED_SIGMA = 67
GPS1_POS = 13
GPS1_RCVR_POS = 6
GPS1_VEL = 30
GPS1_SAT = 15
GPS1_SIG = 45
MAGNETOMETER = 52
BAROMETER = 53
SYS_SENSORS = 11
IMU_MAG = 85
PIMU_MAG = 86

#: DID -> (DID name, C struct, size in bytes, named fields).
LAYOUTS: Dict[int, Tuple[str, str, int, Sequence[Field]]] = {
    DEV_INFO: ('DEV_INFO', 'dev_info_t', 84, (
        ("hardwareType", 2, 'u8', ""),
        ("hdwRunState", 3, 'u8', ""),
        ("serialNumber", 4, 'u32', ""),
        ("hardwareVer", 8, 'ver', ""),
        ("firmwareVer", 12, 'ver', ""),
        ("buildNumber", 16, 'u32', ""),
        ("protocolVer", 20, 'ver', ""),
        ("repoRevision", 24, 'u32', ""),
        ("manufacturer", 28, 'str24', ""),
        ("buildType", 52, 'u8', ""),
        ("addInfo", 60, 'str24', ""),
    )),
    SYS_FAULT: ('SYS_FAULT', 'system_fault_t', 32, (
        ("status", 0, 'u32', ""),
        ("g1Task", 4, 'u32', ""),
        ("g2FileNum", 8, 'u32', ""),
        ("g3LineNum", 12, 'u32', ""),
        ("g4", 16, 'u32', ""),
        ("g5Lr", 20, 'u32', ""),
        ("pc", 24, 'u32', ""),
        ("psr", 28, 'u32', ""),
    )),
    PIMU: ('PIMU', 'pimu_t', 40, (
        ("time", 0, 'f64', "s"),
        ("dt", 8, 'f32', "s"),
        ("status", 12, 'u32', ""),
        ("theta", 16, 'f32x3', "rad"),
        ("vel", 28, 'f32x3', "m/s"),
    )),
    SYS_CMD: ('SYS_CMD', 'system_command_t', 8, (
        ("command", 0, 'u32', ""),
        ("invCommand", 4, 'u32', ""),
    )),
    NMEA_BCAST_PERIOD: ('NMEA_BCAST_PERIOD', 'nmea_msgs_t', 44, (
        ("options", 0, 'u32', ""),
        ("nmeaBroadcastMsgs[0].msgID", 4, 'u8', ""),
        ("nmeaBroadcastMsgs[0].period", 5, 'u8', ""),
        ("nmeaBroadcastMsgs[1].msgID", 6, 'u8', ""),
        ("nmeaBroadcastMsgs[1].period", 7, 'u8', ""),
        ("nmeaBroadcastMsgs[2].msgID", 8, 'u8', ""),
        ("nmeaBroadcastMsgs[2].period", 9, 'u8', ""),
        ("nmeaBroadcastMsgs[3].msgID", 10, 'u8', ""),
        ("nmeaBroadcastMsgs[3].period", 11, 'u8', ""),
        ("nmeaBroadcastMsgs[4].msgID", 12, 'u8', ""),
        ("nmeaBroadcastMsgs[4].period", 13, 'u8', ""),
        ("nmeaBroadcastMsgs[5].msgID", 14, 'u8', ""),
        ("nmeaBroadcastMsgs[5].period", 15, 'u8', ""),
        ("nmeaBroadcastMsgs[6].msgID", 16, 'u8', ""),
        ("nmeaBroadcastMsgs[6].period", 17, 'u8', ""),
        ("nmeaBroadcastMsgs[7].msgID", 18, 'u8', ""),
        ("nmeaBroadcastMsgs[7].period", 19, 'u8', ""),
        ("nmeaBroadcastMsgs[8].msgID", 20, 'u8', ""),
        ("nmeaBroadcastMsgs[8].period", 21, 'u8', ""),
        ("nmeaBroadcastMsgs[9].msgID", 22, 'u8', ""),
        ("nmeaBroadcastMsgs[9].period", 23, 'u8', ""),
        ("nmeaBroadcastMsgs[10].msgID", 24, 'u8', ""),
        ("nmeaBroadcastMsgs[10].period", 25, 'u8', ""),
        ("nmeaBroadcastMsgs[11].msgID", 26, 'u8', ""),
        ("nmeaBroadcastMsgs[11].period", 27, 'u8', ""),
        ("nmeaBroadcastMsgs[12].msgID", 28, 'u8', ""),
        ("nmeaBroadcastMsgs[12].period", 29, 'u8', ""),
        ("nmeaBroadcastMsgs[13].msgID", 30, 'u8', ""),
        ("nmeaBroadcastMsgs[13].period", 31, 'u8', ""),
        ("nmeaBroadcastMsgs[14].msgID", 32, 'u8', ""),
        ("nmeaBroadcastMsgs[14].period", 33, 'u8', ""),
        ("nmeaBroadcastMsgs[15].msgID", 34, 'u8', ""),
        ("nmeaBroadcastMsgs[15].period", 35, 'u8', ""),
        ("nmeaBroadcastMsgs[16].msgID", 36, 'u8', ""),
        ("nmeaBroadcastMsgs[16].period", 37, 'u8', ""),
        ("nmeaBroadcastMsgs[17].msgID", 38, 'u8', ""),
        ("nmeaBroadcastMsgs[17].period", 39, 'u8', ""),
        ("nmeaBroadcastMsgs[18].msgID", 40, 'u8', ""),
        ("nmeaBroadcastMsgs[18].period", 41, 'u8', ""),
        ("nmeaBroadcastMsgs[19].msgID", 42, 'u8', ""),
        ("nmeaBroadcastMsgs[19].period", 43, 'u8', ""),
    )),
    RMC: ('RMC', 'rmc_t', 12, (
        ("bits", 0, 'u64', ""),
        ("options", 8, 'u32', ""),
    )),
    SYS_PARAMS: ('SYS_PARAMS', 'sys_params_t', 64, (
        ("timeOfWeekMs", 0, 'u32', "ms"),
        ("insStatus", 4, 'u32', ""),
        ("hdwStatus", 8, 'u32', ""),
        ("imuTemp", 12, 'f32', "°C"),
        ("baroTemp", 16, 'f32', "°C"),
        ("mcuTemp", 20, 'f32', "°C"),
        ("sysStatus", 24, 'u32', ""),
        ("imuSamplePeriodMs", 28, 'u32', "ms"),
        ("navOutputPeriodMs", 32, 'u32', "ms"),
        ("sensorTruePeriod", 36, 'f64', "s"),
        ("flashCfgChecksum", 44, 'u32', ""),
        ("navUpdatePeriodMs", 48, 'u32', "ms"),
        ("genFaultCode", 52, 'u32', ""),
        ("upTime", 56, 'f64', "s"),
    )),
    FLASH_CONFIG: ('FLASH_CONFIG', 'nvm_flash_cfg_t', 288, (
        ("size", 0, 'u32', ""),
        ("checksum", 4, 'u32', ""),
        ("key", 8, 'u32', ""),
        ("startupImuDtMs", 12, 'u32', "ms"),
        ("startupNavDtMs", 16, 'u32', "ms"),
        ("ser0BaudRate", 20, 'u32', "bit/s"),
        ("ser1BaudRate", 24, 'u32', "bit/s"),
        ("insRotation", 28, 'f32x3', "rad"),
        ("insOffset", 40, 'f32x3', "m"),
        ("gps1AntOffset", 52, 'f32x3', "m"),
        ("dynamicModel", 64, 'u8', ""),
        ("debug", 65, 'u8', ""),
        ("gnssSatSigConst", 66, 'u16', ""),
        ("sysCfgBits", 68, 'u32', ""),
        ("refLla", 72, 'f64x3', "deg, deg, m"),
        ("lastLla", 96, 'f64x3', "deg, deg, m"),
        ("lastLlaTimeOfWeekMs", 120, 'u32', "ms"),
        ("lastLlaWeek", 124, 'u32', ""),
        ("lastLlaUpdateDistance", 128, 'f32', "m"),
        ("ioConfig", 132, 'u32', ""),
        ("platformConfig", 136, 'u32', ""),
        ("gps2AntOffset", 140, 'f32x3', "m"),
        ("zeroVelRotation", 152, 'f32x3', "rad"),
        ("zeroVelOffset", 164, 'f32x3', "m"),
        ("gpsTimeUserDelay", 176, 'f32', "s"),
        ("magDeclination", 180, 'f32', "rad"),
        ("gpsTimeSyncPeriodMs", 184, 'u32', "ms"),
        ("startupGPSDtMs", 188, 'u32', "ms"),
        ("RTKCfgBits", 192, 'u32', ""),
        ("sensorConfig", 196, 'u32', ""),
        ("gpsMinimumElevation", 200, 'f32', "rad"),
        ("ser2BaudRate", 204, 'u32', "bit/s"),
        ("magInterferenceThreshold", 268, 'f32', ""),
        ("magCalibrationQualityThreshold", 272, 'f32', ""),
        ("imuRejectThreshGyroLow", 278, 'u8', ""),
        ("imuRejectThreshGyroHigh", 279, 'u8', ""),
        ("imuShockDetectLatencyMs", 280, 'u8', "ms"),
        ("imuShockRejectLatchMs", 281, 'u8', "ms"),
        ("imuShockOptions", 282, 'u8', ""),
    )),
    GPS1_VERSION: ('GPS1_VERSION', 'gps_version_t', 220, (
    )),
    MAG_CAL: ('MAG_CAL', 'mag_cal_t', 12, (
        ("state", 0, 'u32', ""),
        ("progress", 4, 'f32', "%"),
        ("declination", 8, 'f32', "rad"),
    )),
    RTOS_INFO: ('RTOS_INFO', 'rtos_info_t', 372, (
        ("freeHeapSize", 0, 'u32', "B"),
        ("mallocSize", 4, 'u32', "B"),
        ("freeSize", 8, 'u32', "B"),
        ("task[0].periodMs", 32, 'u32', "ms"),
        ("task[0].startTimeUs", 56, 'u32', "us"),
        ("task[1].periodMs", 92, 'u32', "ms"),
        ("task[1].startTimeUs", 116, 'u32', "us"),
        ("task[2].periodMs", 152, 'u32', "ms"),
        ("task[2].startTimeUs", 176, 'u32', "us"),
        ("task[3].periodMs", 212, 'u32', "ms"),
        ("task[3].startTimeUs", 236, 'u32', "us"),
        ("task[4].periodMs", 272, 'u32', "ms"),
        ("task[4].startTimeUs", 296, 'u32', "us"),
        ("task[5].periodMs", 332, 'u32', "ms"),
        ("task[5].startTimeUs", 356, 'u32', "us"),
    )),
    CAN_CONFIG: ('CAN_CONFIG', 'can_config_t', 168, (
        ("can_baudrate_kbps", 162, 'u16', "kbit/s"),
        ("can_receive_address", 164, 'u32', ""),
    )),
    IMU: ('IMU', 'imu_t', 36, (
        ("time", 0, 'f64', "s"),
        ("status", 8, 'u32', ""),
        ("pqr", 12, 'f32x3', "rad/s"),
        ("acc", 24, 'f32x3', "m/s²"),
    )),
    BIT: ('BIT', 'bit_t', 56, (
        ("command", 0, 'u8', ""),
        ("lastCommand", 1, 'u8', ""),
        ("state", 2, 'u8', ""),
        ("hdwBitStatus", 4, 'u32', ""),
        ("calBitStatus", 8, 'u32', ""),
        ("pqr", 36, 'f32', "rad/s"),
        ("acc", 40, 'f32', "m/s²"),
        ("pqrSigma", 44, 'f32', "rad/s"),
        ("accSigma", 48, 'f32', "m/s²"),
        ("testMode", 52, 'u8', ""),
        ("testVar", 53, 'u8', ""),
        ("detectedHardwareId", 54, 'u16', ""),
    )),
    PORT_MONITOR: ('PORT_MONITOR', 'port_monitor_t', 223, (
        ("portInfo", 0, 'u8', ""),
        ("status", 1, 'u32', ""),
        ("txBytesPerSec", 5, 'u32', "B/s"),
        ("rxBytesPerSec", 9, 'u32', "B/s"),
        ("txBytes", 13, 'u32', "B"),
        ("rxBytes", 17, 'u32', "B"),
        ("txDataDrops", 21, 'u32', ""),
        ("rxOverflows", 25, 'u32', ""),
        ("txBytesDropped", 29, 'u32', "B"),
        ("rxChecksumErrors", 33, 'u32', ""),
        ("activePorts", 222, 'u8', ""),
    )),
    STROBE_IN_TIME: ('STROBE_IN_TIME', 'strobe_in_time_t', 12, (
        ("week", 0, 'u32', ""),
        ("timeOfWeekMs", 4, 'u32', "ms"),
        ("pin", 8, 'u16', ""),
        ("count", 10, 'u16', ""),
    )),
    IMU3_RAW: ('IMU3_RAW', 'imu3_t', 84, (
        ("time", 0, 'f64', "s"),
        ("status", 8, 'u32', ""),
        ("pqr", 12, 'f32x3', "rad/s"),
        ("acc", 24, 'f32x3', "m/s²"),
    )),
    IMU_RAW: ('IMU_RAW', 'imu_t', 36, (
        ("time", 0, 'f64', "s"),
        ("status", 8, 'u32', ""),
        ("pqr", 12, 'f32x3', "rad/s"),
        ("acc", 24, 'f32x3', "m/s²"),
    )),
    INS_1: ('INS_1', 'ins_1_t', 80, (
        ("week", 0, 'u32', ""),
        ("timeOfWeek", 4, 'f64', "s"),
        ("insStatus", 12, 'u32', ""),
        ("hdwStatus", 16, 'u32', ""),
        ("theta", 20, 'f32x3', "rad"),
        ("uvw", 32, 'f32x3', "m/s"),
        ("lla", 44, 'f64x3', "deg, deg, m"),
        ("ned", 68, 'f32x3', "m"),
    )),
    INS_2: ('INS_2', 'ins_2_t', 72, (
        ("week", 0, 'u32', ""),
        ("timeOfWeek", 4, 'f64', "s"),
        ("insStatus", 12, 'u32', ""),
        ("hdwStatus", 16, 'u32', ""),
        ("qn2b", 20, 'f32x4', ""),
        ("uvw", 36, 'f32x3', "m/s"),
        ("lla", 48, 'f64x3', "deg, deg, m"),
    )),
    INS_3: ('INS_3', 'ins_3_t', 76, (
        ("week", 0, 'u32', ""),
        ("timeOfWeek", 4, 'f64', "s"),
        ("insStatus", 12, 'u32', ""),
        ("hdwStatus", 16, 'u32', ""),
        ("qn2b", 20, 'f32x4', ""),
        ("uvw", 36, 'f32x3', "m/s"),
        ("lla", 48, 'f64x3', "deg, deg, m"),
        ("msl", 72, 'f32', "m"),
    )),
    INS_4: ('INS_4', 'ins_4_t', 72, (
        ("week", 0, 'u32', ""),
        ("timeOfWeek", 4, 'f64', "s"),
        ("insStatus", 12, 'u32', ""),
        ("hdwStatus", 16, 'u32', ""),
        ("qe2b", 20, 'f32x4', ""),
        ("ve", 36, 'f32x3', "m/s"),
        ("ecef", 48, 'f64x3', "m"),
    )),
    INL2_STATES: ('INL2_STATES', 'inl2_states_t', 96, (
        ("timeOfWeek", 0, 'f64', "s"),
        ("qe2b", 8, 'f32x4', ""),
        ("ve", 24, 'f32x3', "m/s"),
        ("ecef", 36, 'f64x3', "m"),
        ("biasPqr", 60, 'f32x3', "rad/s"),
        ("biasAcc", 72, 'f32x3', "m/s^2"),
        ("biasBaro", 84, 'f32', "m"),
        ("magDec", 88, 'f32', "rad"),
        ("magInc", 92, 'f32', "rad"),
    )),
    INL2_NED_SIGMA: ('INL2_NED_SIGMA', 'inl2_ned_sigma_t', 72, (
        ("timeOfWeekMs", 0, 'u32', "ms"),
        ("StdPosNed", 4, 'f32x3', "m"),
        ("StdVelNed", 16, 'f32x3', "m/s"),
        ("StdAttNed", 28, 'f32x3', "rad"),
        ("StdAccBias", 40, 'f32x3', "m/s^2"),
        ("StdGyrBias", 52, 'f32x3', "rad/s"),
        ("StdBarBias", 64, 'f32', "m"),
        ("StdMagDeclination", 68, 'f32', "rad"),
    )),
    GPS1_POS: ('GPS1_POS', 'gps_pos_t', 92, (
        ("week", 0, 'u32', ""),
        ("timeOfWeekMs", 4, 'u32', "ms"),
        ("status", 8, 'u32', ""),
        ("ecef", 12, 'f64x3', "m"),
        ("lla", 36, 'f64x3', "deg, deg, m"),
        ("hMSL", 60, 'f32', "m"),
        ("hAcc", 64, 'f32', "m"),
        ("vAcc", 68, 'f32', "m"),
        ("pDop", 72, 'f32', ""),
        ("cnoMean", 76, 'f32', "dBHz"),
        ("towOffset", 80, 'f64', "s"),
        ("leapS", 88, 'u8', "s"),
        ("satsUsed", 89, 'u8', ""),
        ("cnoMeanSigma", 90, 'u8', "dBHz"),
        ("status2", 91, 'u8', ""),
    )),
    GPS1_RCVR_POS: ('GPS1_RCVR_POS', 'gps_pos_t', 92, (
        ("week", 0, 'u32', ""),
        ("timeOfWeekMs", 4, 'u32', "ms"),
        ("status", 8, 'u32', ""),
        ("ecef", 12, 'f64x3', "m"),
        ("lla", 36, 'f64x3', "deg, deg, m"),
        ("hMSL", 60, 'f32', "m"),
        ("hAcc", 64, 'f32', "m"),
        ("vAcc", 68, 'f32', "m"),
        ("pDop", 72, 'f32', ""),
        ("cnoMean", 76, 'f32', "dBHz"),
        ("towOffset", 80, 'f64', "s"),
        ("leapS", 88, 'u8', "s"),
        ("satsUsed", 89, 'u8', ""),
        ("cnoMeanSigma", 90, 'u8', "dBHz"),
        ("status2", 91, 'u8', ""),
    )),
    GPS1_VEL: ('GPS1_VEL', 'gps_vel_t', 24, (
        ("timeOfWeekMs", 0, 'u32', "ms"),
        ("vel", 4, 'f32x3', "m/s"),
        ("sAcc", 16, 'f32', "m/s"),
        ("status", 20, 'u32', ""),
    )),
    GPS1_SAT: ('GPS1_SAT', 'gps_sat_t', 408, (
        ("timeOfWeekMs", 0, 'u32', "ms"),
        ("numSats", 4, 'u32', ""),
        ("gnssId", 8, 'u8', ""),
        ("svId", 9, 'u8', ""),
        ("cno", 13, 'u8', "dBHz"),
    )),
    GPS1_SIG: ('GPS1_SIG', 'gps_sig_t', 708, (
        ("timeOfWeekMs", 0, 'u32', "ms"),
        ("numSigs", 4, 'u32', ""),
        ("gnssId", 8, 'u8', ""),
        ("svId", 9, 'u8', ""),
        ("sigId", 10, 'u8', ""),
        ("cno", 11, 'u8', "dBHz"),
        ("quality", 12, 'u8', ""),
    )),
    MAGNETOMETER: ('MAGNETOMETER', 'magnetometer_t', 20, (
        ("time", 0, 'f64', "s"),
        ("mag", 8, 'f32x3', "normalized"),
    )),
    BAROMETER: ('BAROMETER', 'barometer_t', 24, (
        ("time", 0, 'f64', "s"),
        ("bar", 8, 'f32', "kPa"),
        ("mslBar", 12, 'f32', "m"),
        ("barTemp", 16, 'f32', "°C"),
        ("humidity", 20, 'f32', "%"),
    )),
    SYS_SENSORS: ('SYS_SENSORS', 'sys_sensors_t', 80, (
        ("time", 0, 'f64', "s"),
        ("temp", 8, 'f32', "°C"),
        ("pqr", 12, 'f32x3', "rad/s"),
        ("acc", 24, 'f32x3', "m/s²"),
        ("mag", 36, 'f32x3', "normalized"),
        ("bar", 48, 'f32', "kPa"),
        ("barTemp", 52, 'f32', "°C"),
        ("mslBar", 56, 'f32', "m"),
        ("humidity", 60, 'f32', "%"),
        ("vin", 64, 'f32', "V"),
        ("ana", 68, 'f32x3', "V"),
    )),
    IMU_MAG: ('IMU_MAG', 'imu_mag_t', 56, (
        ("time", 0, 'f64', "s"),
        ("status", 8, 'u32', ""),
        ("pqr", 12, 'f32x3', "rad/s"),
        ("acc", 24, 'f32x3', "m/s²"),
        ("magTime", 36, 'f64', "s"),
        ("mag", 44, 'f32x3', "normalized"),
    )),
    PIMU_MAG: ('PIMU_MAG', 'pimu_mag_t', 60, (
        ("time", 0, 'f64', "s"),
        ("dt", 8, 'f32', "s"),
        ("status", 12, 'u32', ""),
        ("theta", 16, 'f32x3', "rad"),
        ("vel", 28, 'f32x3', "m/s"),
        ("magTime", 40, 'f64', "s"),
        ("mag", 48, 'f32x3', "normalized"),
    )),
}
