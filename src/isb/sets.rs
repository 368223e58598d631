//! Byte layouts of the ISB data sets the emulated IMX-5 serves, with the
//! status bits and option words that go in them.
//!
//! Every struct is packed little-endian (`docs/protocol-facts.md` "ISB")
//! and declared once with [`crate::data_set!`]: its module gives the byte
//! offset of every field, `SIZE` and the named fields (`FIELDS`); the
//! typed structs ([`DevInfo`], [`Imu`], [`Pimu`], [`Rmc`],
//! [`SystemCommand`], [`StrobeInTime`], [`SysParams`], [`NvmFlashCfg`],
//! [`Bit`]) encode to and decode from a `[u8; SIZE]`. The device keeps
//! FLASH_CONFIG as a byte image ([`FlashConfig`]) with accessors, because
//! a SET_DATA writes into it at any offset. Sources:
//! protocol-facts.md "ISB" first; fields it does not list (FLASH_CONFIG
//! past `ser2BaudRate`, `bit_t`) from the SDK's `data_sets.h` of protocol 2.1
//! (`PROTOCOL_VERSION_CHAR1 1`). `docs/isb-data-sets.md` lists every
//! layout and where the two sources differ.

/// Little-endian field access on a byte image; out-of-range accesses read
/// 0 and write nothing (never panic).
pub mod le {
    /// Reads `N` bytes at `off`, zeros when out of range.
    pub fn get<const N: usize>(b: &[u8], off: usize) -> [u8; N] {
        off.checked_add(N)
            .and_then(|end| b.get(off..end))
            .and_then(|s| s.try_into().ok())
            .unwrap_or([0; N])
    }
    /// Writes `v` at `off` if it fits.
    pub fn put(b: &mut [u8], off: usize, v: &[u8]) {
        if let Some(d) = off.checked_add(v.len()).and_then(|end| b.get_mut(off..end)) {
            d.copy_from_slice(v);
        }
    }
    /// `u16` at `off`.
    pub fn u16(b: &[u8], off: usize) -> u16 {
        u16::from_le_bytes(get(b, off))
    }
    /// `u32` at `off`.
    pub fn u32(b: &[u8], off: usize) -> u32 {
        u32::from_le_bytes(get(b, off))
    }
    /// `u64` at `off`.
    pub fn u64(b: &[u8], off: usize) -> u64 {
        u64::from_le_bytes(get(b, off))
    }
    /// `f32` at `off`.
    pub fn f32(b: &[u8], off: usize) -> f32 {
        f32::from_le_bytes(get(b, off))
    }
    /// `f64` at `off`.
    pub fn f64(b: &[u8], off: usize) -> f64 {
        f64::from_le_bytes(get(b, off))
    }
    /// Three `f32` from `off`.
    pub fn f32x3(b: &[u8], off: usize) -> [f32; 3] {
        [f32(b, off), f32(b, off + 4), f32(b, off + 8)]
    }
    /// Writes three `f32` from `off`.
    pub fn put_f32x3(b: &mut [u8], off: usize, v: [f32; 3]) {
        for (i, x) in v.iter().enumerate() {
            put(b, off + 4 * i, &x.to_le_bytes());
        }
    }
}

crate::data_set! {
    /// `dev_info_t`, 84 bytes (protocol-facts.md "ISB"; `data_sets.h` of
    /// protocol 2.1 agrees: `reserved` u16, `hardwareType`, `hdwRunState`).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct DevInfo in mod dev_info, 84 bytes {
        _: u16 = RESERVED @ 0,
        /// `hardwareType` (3 = IMX).
        hardware_type: u8 = HARDWARE_TYPE @ 2 => ["hardwareType"],
        /// `hdwRunState` (2 = application).
        hdw_run_state: u8 = HDW_RUN_STATE @ 3 => ["hdwRunState"],
        /// `serialNumber`; the vendor tool refuses 0.
        serial_number: u32 = SERIAL_NUMBER @ 4 => ["serialNumber"],
        /// `hardwareVer` (5.0.0.0 for an IMX-5).
        hardware_ver: [u8; 4] = HARDWARE_VER @ 8 => ["hardwareVer" as Version],
        /// `firmwareVer`.
        firmware_ver: [u8; 4] = FIRMWARE_VER @ 12 => ["firmwareVer" as Version],
        /// `buildNumber`.
        build_number: u32 = BUILD_NUMBER @ 16 => ["buildNumber"],
        /// `protocolVer` ([`dev_info::PROTOCOL_2_1`]).
        protocol_ver: [u8; 4] = PROTOCOL_VER @ 20 => ["protocolVer" as Version],
        /// `repoRevision`.
        repo_revision: u32 = REPO_REVISION @ 24 => ["repoRevision"],
        /// `manufacturer`, NUL padded.
        manufacturer: [u8; 24] = MANUFACTURER @ 28 => ["manufacturer"],
        /// `buildType` (`'r'` release, …).
        build_type: u8 = BUILD_TYPE @ 52 => ["buildType"],
        /// `buildYear − 2000`, `buildMonth`, `buildDay`.
        build_date: [u8; 3] = BUILD_DATE @ 53,
        /// `buildHour`, `buildMinute`, `buildSecond`, `buildMillisecond`.
        build_time: [u8; 4] = BUILD_TIME @ 56,
        /// `addInfo`, NUL padded.
        add_info: [u8; 24] = ADD_INFO @ 60 => ["addInfo"],
    }
    /// Length of the two strings.
    pub const STR_LEN: usize = 24;
    /// `eIsHardwareType` IMX.
    pub const HARDWARE_TYPE_IMX: u8 = 3;
    /// `eHdwRunStates` application.
    pub(crate) const RUN_STATE_APP: u8 = 2;
    /// Protocol version 2.1.0.0 (protocol-facts.md: the SDK 2.7.1 speaks it and
    /// accepts a device only with `protocolVer[0] == 2`).
    pub const PROTOCOL_2_1: [u8; 4] = [2, 1, 0, 0];
    /// Firmware 2.7.1.0: the IMX-5 firmware released with SDK 2.7.1 (each
    /// SDK release ships the IMX-5 firmware of its own version,
    /// `IS_IMX-5_vX.Y.Z…hex`: the SDK's release page; docs/isb.md).
    pub(crate) const FIRMWARE_2_7_1: [u8; 4] = [2, 7, 1, 0];
    /// `buildNumber` reported with it (the 2.7.1 build number is not
    /// public; the emulator's choice, docs/isb.md).
    pub(crate) const BUILD_NUMBER_2_7_1: u32 = 1;
}

impl DevInfo {
    /// The product hardware id the SDK derives from `hardwareType` and
    /// `hardwareVer[0..2]` (6:4:6 bits, `data_sets.h`); the vendor tool
    /// refuses a device where it is 0xFFFF (protocol-facts.md).
    pub fn hardware_id(&self) -> u16 {
        let t = u16::from(self.hardware_type) << 10 & 0xFC00;
        let major = u16::from(self.hardware_ver[0]) << 6 & 0x03C0;
        let minor = u16::from(self.hardware_ver[1]) & 0x003F;
        t | major | minor
    }

    /// Whether the SDK 2.7.1 accepts this as an IMX it can talk to
    /// (protocol-facts.md: type ≠ 0, serial ≠ 0, protocol major 2, run state ≠ 0,
    /// hardware id ≠ 0xFFFF).
    pub fn accepted_by_sdk(&self) -> bool {
        self.hardware_type != 0
            && self.serial_number != 0
            && self.protocol_ver[0] == 2
            && self.hdw_run_state != 0
            && self.hardware_id() != 0xFFFF
    }
}

/// A NUL-padded 24-byte string field from `s` (truncated to 24 bytes).
pub fn str24(s: &str) -> [u8; 24] {
    let mut out = [0u8; 24];
    for (o, b) in out.iter_mut().zip(s.bytes()) {
        *o = b;
    }
    out
}

crate::data_set! {
    /// `imu_t`, 36 bytes (protocol-facts.md "ISB"): DID_IMU and DID_IMU_RAW.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Imu in mod imu, 36 bytes {
        /// Seconds since boot.
        time: f64 = TIME @ 0 => ["time" in "s"],
        /// [`imu_status`] bits.
        status: u32 = STATUS @ 8 => ["status"],
        /// Angular rate, rad/s.
        pqr: [f32; 3] = PQR @ 12 => ["pqr" in "rad/s"],
        /// Specific force, m/s².
        acc: [f32; 3] = ACC @ 24 => ["acc" in "m/s²"],
    }
}

crate::data_set! {
    /// `pimu_t`, 40 bytes (protocol-facts.md "ISB").
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Pimu in mod pimu, 40 bytes {
        /// Seconds since boot, end of the integration period.
        time: f64 = TIME @ 0 => ["time" in "s"],
        /// Integration period, s (= `startupNavDtMs`).
        dt: f32 = DT @ 8 => ["dt" in "s"],
        /// [`imu_status`] bits.
        status: u32 = STATUS @ 12 => ["status"],
        /// Δθ, rad.
        theta: [f32; 3] = THETA @ 16 => ["theta" in "rad"],
        /// Δv, m/s.
        vel: [f32; 3] = VEL @ 28 => ["vel" in "m/s"],
    }
}

/// `imu_t.status` / `pimu_t.status` bits (protocol-facts.md "ISB"; the 2.1
/// `data_sets.h` numbers these differently — per-IMU saturation in the low
/// bits, OK bits from 0x10000 — and protocol-facts.md, checked against SDK 2.7.1,
/// is followed: `docs/isb-data-sets.md`).
pub mod imu_status {
    /// Gyro X sensor OK.
    pub const GYR_X_OK: u32 = 0x01;
    /// Gyro Y sensor OK.
    pub const GYR_Y_OK: u32 = 0x02;
    /// Gyro Z sensor OK.
    pub const GYR_Z_OK: u32 = 0x04;
    /// Accelerometer X sensor OK.
    pub const ACC_X_OK: u32 = 0x08;
    /// Accelerometer Y sensor OK.
    pub const ACC_Y_OK: u32 = 0x10;
    /// Accelerometer Z sensor OK.
    pub const ACC_Z_OK: u32 = 0x20;
    /// All six sensors OK.
    pub const ALL_OK: u32 = 0x3F;
    /// Fault rejection excludes a gyro.
    pub const GYR_FAULT_REJECT: u32 = 0x0100_0000;
    /// Fault rejection excludes an accelerometer.
    pub const ACC_FAULT_REJECT: u32 = 0x0200_0000;
    /// Gyro saturation.
    pub const SATURATION_GYR: u32 = 0x4000_0000;
    /// Accelerometer saturation.
    pub(crate) const SATURATION_ACC: u32 = 0x8000_0000;
}

/// `sys_params_t.hdwStatus` bits (protocol-facts.md "ISB"; `data_sets.h`
/// `eHdwStatusFlags`).
pub mod hdw_status {
    /// Gyro motion detected.
    pub const MOTION_GYR: u32 = 0x0000_0001;
    /// Accelerometer motion detected.
    pub const MOTION_ACC: u32 = 0x0000_0002;
    /// An event occurred on a strobe input pin.
    pub const STROBE_IN_EVENT: u32 = 0x0000_0020;
    /// Gyro saturation.
    pub const SATURATION_GYR: u32 = 0x0000_0100;
    /// Accelerometer saturation.
    pub(crate) const SATURATION_ACC: u32 = 0x0000_0200;
    /// Saturation mask (gyro, accel, mag, baro).
    pub const SATURATION_MASK: u32 = 0x0000_0F00;
    /// A system reset is required for proper function (e.g. after a
    /// FLASH_CONFIG change that applies only at reset).
    pub const SYSTEM_RESET_REQUIRED: u32 = 0x0000_1000;
    /// A flash write is staged or in progress.
    pub const FLASH_WRITE_PENDING: u32 = 0x0000_8000;
    /// Transmit buffer limited.
    pub(crate) const ERR_COM_TX_LIMITED: u32 = 0x0001_0000;
    /// Receive buffer overrun.
    pub const ERR_COM_RX_OVERRUN: u32 = 0x0002_0000;
    /// Parse error count field (4 bits).
    pub(crate) const COM_PARSE_ERR_COUNT_MASK: u32 = 0x00F0_0000;
    /// Shift of the parse error count field.
    pub(crate) const COM_PARSE_ERR_COUNT_SHIFT: u32 = 20;
    /// BIT running.
    pub const BIT_RUNNING: u32 = 0x0100_0000;
    /// BIT passed.
    pub const BIT_PASSED: u32 = 0x0200_0000;
    /// BIT failed (both BIT bits).
    pub const BIT_FAILED: u32 = 0x0300_0000;
    /// BIT field mask.
    pub const BIT_MASK: u32 = 0x0300_0000;
    /// Temperature outside the specified operating range.
    pub const ERR_TEMPERATURE: u32 = 0x0400_0000;
    /// Reset cause field mask.
    pub const RESET_CAUSE_MASK: u32 = 0x7000_0000;
    /// Reset cause: software reset.
    pub const RESET_CAUSE_SOFT: u32 = 0x3000_0000;
    /// Critical system fault.
    pub const FAULT_SYS_CRITICAL: u32 = 0x8000_0000;

    /// `status` with the parse error count field set to `count`
    /// (saturating at 15).
    pub(crate) const fn with_parse_errors(status: u32, count: u32) -> u32 {
        let c = if count > 15 { 15 } else { count };
        (status & !COM_PARSE_ERR_COUNT_MASK) | (c << COM_PARSE_ERR_COUNT_SHIFT)
    }
}

crate::data_set! {
    /// `rmc_t`, 12 bytes, and its bits and options (protocol-facts.md "ISB";
    /// `data_sets.h` `RMC_BITS_*`, `RMC_OPTIONS_*`).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct Rmc in mod rmc, 12 bytes {
        /// Stream enable bits.
        bits: u64 = BITS @ 0 => ["bits"],
        /// Port mask and options.
        options: u32 = OPTIONS @ 8 => ["options"],
    }
    /// DID_IMU stream.
    pub const BITS_IMU: u64 = 0x10;
    /// DID_PIMU stream.
    pub const BITS_PIMU: u64 = 0x20;
    /// DID_STROBE_IN_TIME on each strobe input event.
    pub(crate) const BITS_STROBE_IN_TIME: u64 = 0x2_0000;
    /// DID_IMU_RAW stream.
    pub(crate) const BITS_IMU_RAW: u64 = 0x200_0000_0000;
    /// `bits` is a preset.
    pub const BITS_PRESET: u64 = 0x8000_0000_0000_0000;
    /// The PPD preset bits of SDK 2.7 (protocol-facts.md; the protocol page's
    /// example packet carries pre-2.7 bits).
    pub const PRESET_PPD_2_7: u64 = 0xC000_6090_0135_3CE2;
    /// `options`: port mask (0 = the port the request came in on).
    pub const OPTIONS_PORT_MASK: u32 = 0xFF;
    /// Port: this one.
    pub const OPTIONS_PORT_CURRENT: u32 = 0x00;
    /// Port: serial 0.
    pub const OPTIONS_PORT_SER0: u32 = 0x01;
    /// Port: serial 1 (also SPI).
    pub const OPTIONS_PORT_SER1: u32 = 0x02;
    /// Port: serial 2.
    pub const OPTIONS_PORT_SER2: u32 = 0x04;
    /// Port: USB.
    pub const OPTIONS_PORT_USB: u32 = 0x08;
    /// OR the new bits into the current ones instead of replacing them.
    pub const OPTIONS_PRESERVE_CTRL: u32 = 0x100;
    /// Save the port's streams to flash (they resume after reset).
    pub(crate) const OPTIONS_PERSISTENT: u32 = 0x200;
}

crate::data_set! {
    /// `system_command_t`, 8 bytes, and its command codes (protocol-facts.md
    /// "ISB"; `data_sets.h` `eSystemCommand`).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct SystemCommand in mod sys_cmd, 8 bytes {
        /// Command code.
        command: u32 = COMMAND @ 0 => ["command"],
        /// Bitwise inverse of `command` for the command to take effect.
        inv_command: u32 = INV_COMMAND @ 4 => ["invCommand"],
    }
    /// Save the running streams as persistent.
    pub const SAVE_PERSISTENT_MESSAGES: u32 = 1;
    /// Zero-motion command.
    pub const ZERO_MOTION: u32 = 5;
    /// Save FLASH_CONFIG to flash.
    pub const SAVE_FLASH: u32 = 97;
    /// Software reset.
    pub const SOFTWARE_RESET: u32 = 99;
    /// Manufacturing unlock (`SYS_CMD_MANF_UNLOCK`): must come right before
    /// a manufacturing command.
    pub const MANF_UNLOCK: u32 = 1_122_334_455;
    /// Factory reset (`SYS_CMD_MANF_FACTORY_RESET`), after the unlock.
    pub const MANF_FACTORY_RESET: u32 = 1_357_924_680;
}

impl SystemCommand {
    /// A valid command `code` (with its inverse).
    pub const fn new(code: u32) -> Self {
        SystemCommand {
            command: code,
            inv_command: !code,
        }
    }
    /// The command code if `inv_command == !command`, else `None` (the
    /// command is ignored, `data_sets.h` DID_SYS_CMD).
    pub const fn valid(&self) -> Option<u32> {
        if self.inv_command == !self.command {
            Some(self.command)
        } else {
            None
        }
    }
}

crate::data_set! {
    /// `strobe_in_time_t`, 12 bytes (protocol-facts.md "ISB").
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct StrobeInTime in mod strobe, 12 bytes {
        /// GPS week (0 without GPS time).
        week: u32 = WEEK @ 0 => ["week"],
        /// Time of week (or since boot without GPS), ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 4 => ["timeOfWeekMs" in "ms"],
        /// The strobe input pin.
        pin: u16 = PIN @ 8 => ["pin"],
        /// Serial number of the event.
        count: u16 = COUNT @ 10 => ["count"],
    }
}

crate::data_set! {
    /// `sys_params_t`, 64 bytes (protocol-facts.md "ISB").
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct SysParams in mod sys_params, 64 bytes {
        /// Time of week (since boot without GPS), ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 0 => ["timeOfWeekMs" in "ms"],
        /// INS status (`eInsStatusFlags`).
        ins_status: u32 = INS_STATUS @ 4 => ["insStatus"],
        /// [`hdw_status`] bits.
        hdw_status: u32 = HDW_STATUS @ 8 => ["hdwStatus"],
        /// IMU temperature, °C.
        imu_temp: f32 = IMU_TEMP @ 12 => ["imuTemp" in "°C"],
        /// Barometer temperature, °C.
        baro_temp: f32 = BARO_TEMP @ 16 => ["baroTemp" in "°C"],
        /// MCU temperature, °C.
        mcu_temp: f32 = MCU_TEMP @ 20 => ["mcuTemp" in "°C"],
        /// System status bits.
        sys_status: u32 = SYS_STATUS @ 24 => ["sysStatus"],
        /// IMU sample period, ms.
        imu_sample_period_ms: u32 = IMU_SAMPLE_PERIOD_MS @ 28 => ["imuSamplePeriodMs" in "ms"],
        /// PIMU integration and output period, ms.
        nav_output_period_ms: u32 = NAV_OUTPUT_PERIOD_MS @ 32 => ["navOutputPeriodMs" in "ms"],
        /// Measured sample period, s.
        sensor_true_period: f64 = SENSOR_TRUE_PERIOD @ 36 => ["sensorTruePeriod" in "s"],
        /// FLASH_CONFIG checksum (= FLASH_CONFIG `checksum`).
        flash_cfg_checksum: u32 = FLASH_CFG_CHECKSUM @ 44 => ["flashCfgChecksum"],
        /// Filter update period, ms.
        nav_update_period_ms: u32 = NAV_UPDATE_PERIOD_MS @ 48 => ["navUpdatePeriodMs" in "ms"],
        /// General fault code (writable: set to 0 to reset).
        gen_fault_code: u32 = GEN_FAULT_CODE @ 52 => ["genFaultCode"],
        /// Up time, s.
        up_time: f64 = UP_TIME @ 56 => ["upTime" in "s"],
    }
}

crate::data_set! {
    /// `wheel_config_t`, 60 bytes: FLASH_CONFIG `wheelConfig` (`data_sets.h`
    /// of protocol 2.1; the IMU mode does not use it).
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct WheelConfig in mod wheel_config, 60 bytes {
        /// Config bits.
        bits: u32 = BITS @ 0 => ["bits"],
        /// `transform_t`: Euler angles and offset from IMU to wheel frame,
        /// with their sigmas (12 × f32).
        transform: [f32; 12] = TRANSFORM @ 4,
        /// Track width, m.
        track_width: f32 = TRACK_WIDTH @ 52 => ["track_width" in "m"],
        /// Wheel radius, m.
        radius: f32 = RADIUS @ 56 => ["radius" in "m"],
    }
}

crate::data_set! {
    /// `nvm_flash_cfg_t`, 288 bytes: FLASH_CONFIG as a typed struct (the
    /// device keeps it as the byte image [`FlashConfig`], which a SET_DATA
    /// writes at any offset). Offsets up to `ser2BaudRate` from
    /// protocol-facts.md "ISB"; the others from `data_sets.h` of protocol
    /// 2.1 (its `ser2BaudRate` lands at 204 and its size at 288, as
    /// protocol-facts.md says).
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct NvmFlashCfg in mod flash, 288 bytes {
        /// Struct size (= 288, read-only).
        size: u32 = SIZE_FIELD @ 0 => ["size"],
        /// XOR of the `u32` words of bytes 8..287.
        checksum: u32 = CHECKSUM @ 4 => ["checksum"],
        /// Factory-defaults key.
        key: u32 = KEY @ 8 => ["key"],
        /// IMU sample period, ms (applies after reset).
        startup_imu_dt_ms: u32 = STARTUP_IMU_DT_MS @ 12 => ["startupImuDtMs" in "ms"],
        /// Navigation period, ms (applies after reset).
        startup_nav_dt_ms: u32 = STARTUP_NAV_DT_MS @ 16 => ["startupNavDtMs" in "ms"],
        /// Serial port 0 rate.
        ser0_baud_rate: u32 = SER0_BAUD_RATE @ 20 => ["ser0BaudRate" in "bit/s"],
        /// Serial port 1 rate.
        ser1_baud_rate: u32 = SER1_BAUD_RATE @ 24 => ["ser1BaudRate" in "bit/s"],
        /// INS frame rotation from the IMU, rad.
        ins_rotation: [f32; 3] = INS_ROTATION @ 28 => ["insRotation" in "rad"],
        /// INS frame offset, m.
        ins_offset: [f32; 3] = INS_OFFSET @ 40 => ["insOffset" in "m"],
        /// GPS 1 antenna offset, m.
        gps1_ant_offset: [f32; 3] = GPS1_ANT_OFFSET @ 52 => ["gps1AntOffset" in "m"],
        /// Dynamic model.
        dynamic_model: u8 = DYNAMIC_MODEL @ 64 => ["dynamicModel"],
        /// Debug.
        debug: u8 = DEBUG @ 65 => ["debug"],
        /// GNSS satellite signals and constellations.
        gnss_sat_sig_const: u16 = GNSS_SAT_SIG_CONST @ 66 => ["gnssSatSigConst"],
        /// System configuration bits.
        sys_cfg_bits: u32 = SYS_CFG_BITS @ 68 => ["sysCfgBits"],
        /// Reference latitude, longitude, height.
        ref_lla: [f64; 3] = REF_LLA @ 72 => ["refLla" in "deg, deg, m"],
        /// Last latitude, longitude, height.
        last_lla: [f64; 3] = LAST_LLA @ 96 => ["lastLla" in "deg, deg, m"],
        /// Time of week of `lastLla`, ms.
        last_lla_time_of_week_ms: u32 = LAST_LLA_TIME_OF_WEEK_MS @ 120 => ["lastLlaTimeOfWeekMs" in "ms"],
        /// GPS week of `lastLla`.
        last_lla_week: u32 = LAST_LLA_WEEK @ 124 => ["lastLlaWeek"],
        /// Distance that updates `lastLla`, m.
        last_lla_update_distance: f32 = LAST_LLA_UPDATE_DISTANCE @ 128 => ["lastLlaUpdateDistance" in "m"],
        /// Hardware interface configuration bits.
        io_config: u32 = IO_CONFIG @ 132 => ["ioConfig"],
        /// Platform configuration.
        platform_config: u32 = PLATFORM_CONFIG @ 136 => ["platformConfig"],
        /// GPS 2 antenna offset, m.
        gps2_ant_offset: [f32; 3] = GPS2_ANT_OFFSET @ 140 => ["gps2AntOffset" in "m"],
        /// Zero-velocity frame rotation, rad.
        zero_vel_rotation: [f32; 3] = ZERO_VEL_ROTATION @ 152 => ["zeroVelRotation" in "rad"],
        /// Zero-velocity frame offset, m.
        zero_vel_offset: [f32; 3] = ZERO_VEL_OFFSET @ 164 => ["zeroVelOffset" in "m"],
        /// GPS time user delay, s.
        gps_time_user_delay: f32 = GPS_TIME_USER_DELAY @ 176 => ["gpsTimeUserDelay" in "s"],
        /// Magnetic declination, rad.
        mag_declination: f32 = MAG_DECLINATION @ 180 => ["magDeclination" in "rad"],
        /// GPS time synchronisation pulse period, ms.
        gps_time_sync_period_ms: u32 = GPS_TIME_SYNC_PERIOD_MS @ 184 => ["gpsTimeSyncPeriodMs" in "ms"],
        /// GPS measurement period, ms.
        startup_gps_dt_ms: u32 = STARTUP_GPS_DT_MS @ 188 => ["startupGPSDtMs" in "ms"],
        /// RTK configuration bits.
        rtk_cfg_bits: u32 = RTK_CFG_BITS @ 192 => ["RTKCfgBits"],
        /// Sensor ranges.
        sensor_config: u32 = SENSOR_CONFIG @ 196 => ["sensorConfig"],
        /// Minimum satellite elevation, rad.
        gps_minimum_elevation: f32 = GPS_MINIMUM_ELEVATION @ 200 => ["gpsMinimumElevation" in "rad"],
        /// Serial port 2 rate.
        ser2_baud_rate: u32 = SER2_BAUD_RATE @ 204 => ["ser2BaudRate" in "bit/s"],
        /// Wheel encoder configuration.
        wheel_config: WheelConfig = WHEEL_CONFIG @ 208 => [.. "bits" => "wheelConfig.bits", "track_width" => "wheelConfig.track_width", "radius" => "wheelConfig.radius"],
        /// Magnetometer interference threshold.
        mag_interference_threshold: f32 = MAG_INTERFERENCE_THRESHOLD @ 268 => ["magInterferenceThreshold"],
        /// Magnetometer calibration quality threshold.
        mag_calibration_quality_threshold: f32 = MAG_CALIBRATION_QUALITY_THRESHOLD @ 272 => ["magCalibrationQualityThreshold"],
        /// Minimum GNSS C/N0, dBHz.
        gnss_cn0_minimum: u8 = GNSS_CN0_MINIMUM @ 276 => ["gnssCn0Minimum" in "dBHz"],
        /// Dynamic C/N0 minimum offset, dBHz.
        gnss_cn0_dyn_min_offset: u8 = GNSS_CN0_DYN_MIN_OFFSET @ 277 => ["gnssCn0DynMinOffset" in "dBHz"],
        /// IMU gyro fault rejection threshold, low.
        imu_reject_thresh_gyro_low: u8 = IMU_REJECT_THRESH_GYRO_LOW @ 278 => ["imuRejectThreshGyroLow"],
        /// IMU gyro fault rejection threshold, high.
        imu_reject_thresh_gyro_high: u8 = IMU_REJECT_THRESH_GYRO_HIGH @ 279 => ["imuRejectThreshGyroHigh"],
        /// IMU shock detection latency, ms.
        imu_shock_detect_latency_ms: u8 = IMU_SHOCK_DETECT_LATENCY_MS @ 280 => ["imuShockDetectLatencyMs" in "ms"],
        /// IMU shock rejection latch time, ms.
        imu_shock_reject_latch_ms: u8 = IMU_SHOCK_REJECT_LATCH_MS @ 281 => ["imuShockRejectLatchMs" in "ms"],
        /// IMU shock rejection options.
        imu_shock_options: u8 = IMU_SHOCK_OPTIONS @ 282 => ["imuShockOptions"],
        /// `imuShockDeltaAccHighThreshold`.
        imu_shock_delta_acc_high: u8 = IMU_SHOCK_DELTA_ACC_HIGH @ 283 => ["imuShockDeltaAccHighThreshold"],
        /// `imuShockDeltaAccLowThreshold`.
        imu_shock_delta_acc_low: u8 = IMU_SHOCK_DELTA_ACC_LOW @ 284 => ["imuShockDeltaAccLowThreshold"],
        /// `imuShockDeltaGyroHighThreshold`.
        imu_shock_delta_gyro_high: u8 = IMU_SHOCK_DELTA_GYRO_HIGH @ 285 => ["imuShockDeltaGyroHighThreshold"],
        /// `imuShockDeltaGyroLowThreshold`.
        imu_shock_delta_gyro_low: u8 = IMU_SHOCK_DELTA_GYRO_LOW @ 286 => ["imuShockDeltaGyroLowThreshold"],
        /// Hardware interface configuration bits, second word.
        io_config2: u8 = IO_CONFIG2 @ 287 => ["ioConfig2"],
    }
    /// First byte the checksum covers.
    pub const CHECKSUM_START: usize = 8;
    /// `sysCfgBits`: no BIT at start-up
    /// (`SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP`, SDK 2.7.1).
    pub const SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP: u32 = 0x0008_0000;

    /// Factory `key` of the emulator's defaults. The IMX firmware's own key
    /// value is not in the SDK; the emulator's is its own choice
    /// (`docs/isb-data-sets.md`): a change of it restores the defaults.
    pub const FACTORY_KEY: u32 = 1;
    /// Default `startupImuDtMs`, ms (protocol-facts.md).
    pub const DEFAULT_IMU_DT_MS: u32 = 1;
    /// Default `startupNavDtMs`, ms (protocol-facts.md).
    pub const DEFAULT_NAV_DT_MS: u32 = 4;
    /// Default serial rate of every port, bit/s (protocol-facts.md: `ser0BaudRate`
    /// 921600).
    pub const DEFAULT_BAUD_RATE: u32 = 921_600;
    /// Default `dynamicModel`: airborne 4 g (`DEFAULT_DYNAMIC_MODEL`).
    pub const DEFAULT_DYNAMIC_MODEL: u8 = 8;
    /// Default `ioConfig`: G1/G2 serial 2, G6/G7 serial 1
    /// (`IO_CONFIG_DEFAULT` = 0x06 | 0x40).
    pub const DEFAULT_IO_CONFIG: u32 = 0x46;
    /// Default `startupGPSDtMs`, ms (ISB page: 200 ms default).
    pub const DEFAULT_GPS_DT_MS: u32 = 200;
    /// Default `gpsTimeSyncPeriodMs`, ms.
    pub const DEFAULT_GPS_TIME_SYNC_PERIOD_MS: u32 = 1000;
    /// Default `sensorConfig`: gyro ±2000 °/s (3), accel ±16 g (3 << 4);
    /// the emulator's choice, matching the widest ranges.
    pub const DEFAULT_SENSOR_CONFIG: u32 = 0x33;
    /// Default `gpsMinimumElevation`: 10° in rad
    /// (`DEFAULT_GNSS_MIN_ELEVATION_ANGLE`).
    pub const DEFAULT_GPS_MIN_ELEVATION: f32 = 0.174_532_92;
    /// Default `magInterferenceThreshold` (`data_sets.h`: 3 default).
    pub const DEFAULT_MAG_INTERFERENCE_THRESHOLD: f32 = 3.0;
    /// Default `magCalibrationQualityThreshold` (`data_sets.h`: 10).
    pub const DEFAULT_MAG_CAL_QUALITY_THRESHOLD: f32 = 10.0;
    /// Default `gnssCn0Minimum`, dBHz (`DEFAULT_GNSS_RTK_CN0_MINIMUM`).
    pub const DEFAULT_GNSS_CN0_MINIMUM: u8 = 30;
    /// Default `gnssCn0DynMinOffset`, dBHz
    /// (`DEFAULT_GNSS_RTK_CN0_DYN_MIN_OFFSET`).
    pub const DEFAULT_GNSS_CN0_DYN_MIN_OFFSET: u8 = 20;

    /// The checksum of an image: XOR of the little-endian `u32` words of
    /// bytes 8..287 (protocol-facts.md "ISB"); bytes past the end of a short image
    /// count as 0.
    pub fn checksum(image: &[u8]) -> u32 {
        let mut x = 0u32;
        let mut off = CHECKSUM_START;
        while off < SIZE {
            x ^= super::le::u32(image, off);
            off += 4;
        }
        x
    }
}

/// A FLASH_CONFIG image ([`flash`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FlashConfig(pub [u8; flash::SIZE]);

impl FlashConfig {
    /// The factory defaults ([`flash`] `DEFAULT_*`), checksum set.
    pub fn factory() -> Self {
        use flash::*;
        let mut c = FlashConfig(
            NvmFlashCfg {
                size: SIZE as u32,
                key: FACTORY_KEY,
                startup_imu_dt_ms: DEFAULT_IMU_DT_MS,
                startup_nav_dt_ms: DEFAULT_NAV_DT_MS,
                ser0_baud_rate: DEFAULT_BAUD_RATE,
                ser1_baud_rate: DEFAULT_BAUD_RATE,
                ser2_baud_rate: DEFAULT_BAUD_RATE,
                dynamic_model: DEFAULT_DYNAMIC_MODEL,
                io_config: DEFAULT_IO_CONFIG,
                gps_time_sync_period_ms: DEFAULT_GPS_TIME_SYNC_PERIOD_MS,
                startup_gps_dt_ms: DEFAULT_GPS_DT_MS,
                sensor_config: DEFAULT_SENSOR_CONFIG,
                gps_minimum_elevation: DEFAULT_GPS_MIN_ELEVATION,
                mag_interference_threshold: DEFAULT_MAG_INTERFERENCE_THRESHOLD,
                mag_calibration_quality_threshold: DEFAULT_MAG_CAL_QUALITY_THRESHOLD,
                gnss_cn0_minimum: DEFAULT_GNSS_CN0_MINIMUM,
                gnss_cn0_dyn_min_offset: DEFAULT_GNSS_CN0_DYN_MIN_OFFSET,
                ..NvmFlashCfg::default()
            }
            .encode(),
        );
        c.update_checksum();
        c
    }

    /// Recomputes and stores `checksum`; returns it.
    pub fn update_checksum(&mut self) -> u32 {
        let x = flash::checksum(&self.0);
        le::put(&mut self.0, flash::CHECKSUM, &x.to_le_bytes());
        x
    }

    /// The stored `checksum`.
    pub fn checksum(&self) -> u32 {
        le::u32(&self.0, flash::CHECKSUM)
    }

    /// Whether the stored checksum is the XOR of the image and `size` is
    /// 288 (an image loaded from flash is used only then).
    pub fn is_valid(&self) -> bool {
        le::u32(&self.0, flash::SIZE_FIELD) == flash::SIZE as u32
            && self.checksum() == flash::checksum(&self.0)
    }

    /// `u32` field at `off` (a [`flash`] offset).
    pub(crate) fn u32_at(&self, off: usize) -> u32 {
        le::u32(&self.0, off)
    }

    /// `key`.
    pub(crate) fn key(&self) -> u32 {
        self.u32_at(flash::KEY)
    }
    /// `startupImuDtMs`.
    pub fn startup_imu_dt_ms(&self) -> u32 {
        self.u32_at(flash::STARTUP_IMU_DT_MS)
    }
    /// `startupNavDtMs`.
    pub fn startup_nav_dt_ms(&self) -> u32 {
        self.u32_at(flash::STARTUP_NAV_DT_MS)
    }
    /// `ser0BaudRate`.
    pub fn ser0_baud_rate(&self) -> u32 {
        self.u32_at(flash::SER0_BAUD_RATE)
    }
    /// `insRotation`, rad.
    pub fn ins_rotation(&self) -> [f32; 3] {
        le::f32x3(&self.0, flash::INS_ROTATION)
    }
}

crate::data_set! {
    /// `bit_t`, 56 bytes, not in protocol-facts.md: from `data_sets.h` of
    /// protocol 2.1.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Bit in mod bit, 56 bytes {
        /// Input command (`eBitCommand`; ignored when 0).
        command: u8 = COMMAND @ 0 => ["command"],
        /// Last command.
        last_command: u8 = LAST_COMMAND @ 1 => ["lastCommand"],
        /// State (`eBitState`).
        state: u8 = STATE @ 2 => ["state"],
        _: u8 = RESERVED @ 3,
        /// Hardware BIT status (`eHdwBitStatusFlags`).
        hdw_bit_status: u32 = HDW_BIT_STATUS @ 4 => ["hdwBitStatus"],
        /// Calibration BIT status (`eCalBitStatusFlags`).
        cal_bit_status: u32 = CAL_BIT_STATUS @ 8 => ["calBitStatus"],
        /// tcPqrBias, tcAccBias, tcPqrSlope, tcAccSlope, tcPqrLinearity,
        /// tcAccLinearity.
        tc: [f32; 6] = TC_PQR_BIAS @ 12,
        /// Gyro error, rad/s.
        pqr: f32 = PQR @ 36 => ["pqr" in "rad/s"],
        /// Accelerometer error, m/s².
        acc: f32 = ACC @ 40 => ["acc" in "m/s²"],
        /// Angular rate standard deviation.
        pqr_sigma: f32 = PQR_SIGMA @ 44 => ["pqrSigma" in "rad/s"],
        /// Acceleration standard deviation.
        acc_sigma: f32 = ACC_SIGMA @ 48 => ["accSigma" in "m/s²"],
        /// Test mode.
        test_mode: u8 = TEST_MODE @ 52 => ["testMode"],
        /// Test variable.
        test_var: u8 = TEST_VAR @ 53 => ["testVar"],
        /// Detected hardware id.
        detected_hardware_id: u16 = DETECTED_HARDWARE_ID @ 54 => ["detectedHardwareId"],
    }
    /// Command: none.
    pub const CMD_NONE: u8 = 0;
    /// Command: stop.
    pub const CMD_OFF: u8 = 1;
    /// Command: full test, stationary.
    pub const CMD_FULL_STATIONARY: u8 = 2;
    /// Command: basic test, may move (run after boot).
    pub const CMD_BASIC_MOVING: u8 = 3;
    /// State: off.
    pub const STATE_OFF: u8 = 0;
    /// State: done.
    pub const STATE_DONE: u8 = 1;
    /// State: running.
    pub const STATE_RUNNING: u8 = 6;
    /// `hdwBitStatus`: passed all.
    pub const HDW_PASSED_ALL: u32 = 0x01;
    /// `hdwBitStatus`: passed without GPS.
    pub const HDW_PASSED_NO_GPS: u32 = 0x02;
    /// `hdwBitStatus`: gyro noise fault.
    pub const HDW_FAULT_NOISE_PQR: u32 = 0x100;
    /// `hdwBitStatus`: accelerometer noise fault.
    pub const HDW_FAULT_NOISE_ACC: u32 = 0x200;
    /// `calBitStatus`: passed all.
    pub const CAL_PASSED_ALL: u32 = 0x01;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factory_flash_config_is_valid_and_has_the_notes_defaults() {
        let c = FlashConfig::factory();
        assert!(c.is_valid());
        assert_eq!(c.u32_at(flash::SIZE_FIELD), 288);
        assert_eq!(c.startup_imu_dt_ms(), 1);
        assert_eq!(c.startup_nav_dt_ms(), 4);
        assert_eq!(c.ser0_baud_rate(), 921_600);
        assert_ne!(c.checksum(), 0xFFFF_FFFF);
    }

    #[test]
    fn round_trips() {
        let i = Imu {
            time: 1.5,
            status: imu_status::ALL_OK,
            pqr: [0.1, -0.2, 0.3],
            acc: [0.0, 0.0, -9.81],
        };
        assert_eq!(Imu::decode(&i.encode()), i);
        let s = SystemCommand::new(sys_cmd::SAVE_FLASH);
        assert_eq!(SystemCommand::decode(&s.encode()).valid(), Some(97));
        assert_eq!(
            SystemCommand {
                command: 97,
                inv_command: 0
            }
            .valid(),
            None
        );
        assert_eq!(hdw_status::with_parse_errors(0x1000, 99), 0x00F0_1000);
    }
}
