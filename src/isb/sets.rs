//! Byte layouts of the ISB data sets the emulated IMX-5 serves, with the
//! status bits and option words that go in them.
//!
//! Every struct is packed little-endian (`docs/protocol-facts.md` "ISB").
//! Each module below gives the byte offset of every field and `SIZE`; the
//! typed structs
//! ([`DevInfo`], [`Imu`], [`Pimu`], [`Rmc`], [`SystemCommand`],
//! [`StrobeInTime`], [`SysParams`], [`Bit`]) encode to and decode from a
//! `[u8; SIZE]`; FLASH_CONFIG stays a byte image ([`FlashConfig`]) with
//! accessors, because a SET_DATA writes into it at any offset. Sources:
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

/// `dev_info_t`, 84 bytes (protocol-facts.md "ISB"; `data_sets.h` of protocol 2.1
/// agrees: `reserved` u16, `hardwareType`, `hdwRunState`).
pub mod dev_info {
    /// Struct size.
    pub const SIZE: usize = 84;
    /// `u16 reserved`.
    pub const RESERVED: usize = 0;
    /// `u8 hardwareType` (3 = IMX).
    pub const HARDWARE_TYPE: usize = 2;
    /// `u8 hdwRunState` (2 = application).
    pub const HDW_RUN_STATE: usize = 3;
    /// `u32 serialNumber`.
    pub const SERIAL_NUMBER: usize = 4;
    /// `u8 hardwareVer[4]`.
    pub const HARDWARE_VER: usize = 8;
    /// `u8 firmwareVer[4]`.
    pub const FIRMWARE_VER: usize = 12;
    /// `u32 buildNumber`.
    pub const BUILD_NUMBER: usize = 16;
    /// `u8 protocolVer[4]`.
    pub const PROTOCOL_VER: usize = 20;
    /// `u32 repoRevision`.
    pub const REPO_REVISION: usize = 24;
    /// `char manufacturer[24]`.
    pub const MANUFACTURER: usize = 28;
    /// `u8 buildType` (`'r'` release, …).
    pub const BUILD_TYPE: usize = 52;
    /// `u8 buildYear` (year − 2000), then month, day.
    pub const BUILD_DATE: usize = 53;
    /// `u8 buildHour`, minute, second, millisecond.
    pub const BUILD_TIME: usize = 56;
    /// `char addInfo[24]`.
    pub const ADD_INFO: usize = 60;
    /// Length of the two strings.
    pub const STR_LEN: usize = 24;
    /// `eIsHardwareType` IMX.
    pub const HARDWARE_TYPE_IMX: u8 = 3;
    /// `eHdwRunStates` application.
    pub const RUN_STATE_APP: u8 = 2;
    /// Protocol version 2.1.0.0 (protocol-facts.md: the SDK 2.7.1 speaks it and
    /// accepts a device only with `protocolVer[0] == 2`).
    pub const PROTOCOL_2_1: [u8; 4] = [2, 1, 0, 0];
    /// Firmware 2.7.1.0: the IMX-5 firmware released with SDK 2.7.1 (each
    /// SDK release ships the IMX-5 firmware of its own version,
    /// `IS_IMX-5_vX.Y.Z…hex`: the SDK's release page; docs/isb.md).
    pub const FIRMWARE_2_7_1: [u8; 4] = [2, 7, 1, 0];
    /// `buildNumber` reported with it (the 2.7.1 build number is not
    /// public; the emulator's choice, docs/isb.md).
    pub const BUILD_NUMBER_2_7_1: u32 = 1;
}

/// `dev_info_t` ([`dev_info`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DevInfo {
    /// `hardwareType` (3 = IMX).
    pub hardware_type: u8,
    /// `hdwRunState` (2 = application).
    pub hdw_run_state: u8,
    /// `serialNumber`; the vendor tool refuses 0.
    pub serial_number: u32,
    /// `hardwareVer` (5.0.0.0 for an IMX-5).
    pub hardware_ver: [u8; 4],
    /// `firmwareVer`.
    pub firmware_ver: [u8; 4],
    /// `buildNumber`.
    pub build_number: u32,
    /// `protocolVer` ([`dev_info::PROTOCOL_2_1`]).
    pub protocol_ver: [u8; 4],
    /// `repoRevision`.
    pub repo_revision: u32,
    /// `manufacturer`, NUL padded.
    pub manufacturer: [u8; 24],
    /// `buildType`.
    pub build_type: u8,
    /// `buildYear − 2000`, `buildMonth`, `buildDay`.
    pub build_date: [u8; 3],
    /// `buildHour`, `buildMinute`, `buildSecond`, `buildMillisecond`.
    pub build_time: [u8; 4],
    /// `addInfo`, NUL padded.
    pub add_info: [u8; 24],
}

impl DevInfo {
    /// The image.
    pub fn encode(&self) -> [u8; dev_info::SIZE] {
        use dev_info::*;
        let mut b = [0u8; SIZE];
        b[HARDWARE_TYPE] = self.hardware_type;
        b[HDW_RUN_STATE] = self.hdw_run_state;
        le::put(&mut b, SERIAL_NUMBER, &self.serial_number.to_le_bytes());
        le::put(&mut b, HARDWARE_VER, &self.hardware_ver);
        le::put(&mut b, FIRMWARE_VER, &self.firmware_ver);
        le::put(&mut b, BUILD_NUMBER, &self.build_number.to_le_bytes());
        le::put(&mut b, PROTOCOL_VER, &self.protocol_ver);
        le::put(&mut b, REPO_REVISION, &self.repo_revision.to_le_bytes());
        le::put(&mut b, MANUFACTURER, &self.manufacturer);
        b[BUILD_TYPE] = self.build_type;
        le::put(&mut b, BUILD_DATE, &self.build_date);
        le::put(&mut b, BUILD_TIME, &self.build_time);
        le::put(&mut b, ADD_INFO, &self.add_info);
        b
    }

    /// Decodes an image (reserved bytes ignored).
    pub fn decode(b: &[u8; dev_info::SIZE]) -> Self {
        use dev_info::*;
        DevInfo {
            hardware_type: b[HARDWARE_TYPE],
            hdw_run_state: b[HDW_RUN_STATE],
            serial_number: le::u32(b, SERIAL_NUMBER),
            hardware_ver: le::get(b, HARDWARE_VER),
            firmware_ver: le::get(b, FIRMWARE_VER),
            build_number: le::u32(b, BUILD_NUMBER),
            protocol_ver: le::get(b, PROTOCOL_VER),
            repo_revision: le::u32(b, REPO_REVISION),
            manufacturer: le::get(b, MANUFACTURER),
            build_type: b[BUILD_TYPE],
            build_date: le::get(b, BUILD_DATE),
            build_time: le::get(b, BUILD_TIME),
            add_info: le::get(b, ADD_INFO),
        }
    }

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
        time: f64 = TIME @ 0,
        /// [`imu_status`] bits.
        status: u32 = STATUS @ 8,
        /// Angular rate, rad/s.
        pqr: [f32; 3] = PQR @ 12,
        /// Specific force, m/s².
        acc: [f32; 3] = ACC @ 24,
    }
}

crate::data_set! {
    /// `pimu_t`, 40 bytes (protocol-facts.md "ISB").
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Pimu in mod pimu, 40 bytes {
        /// Seconds since boot, end of the integration period.
        time: f64 = TIME @ 0,
        /// Integration period, s (= `startupNavDtMs`).
        dt: f32 = DT @ 8,
        /// [`imu_status`] bits.
        status: u32 = STATUS @ 12,
        /// Δθ, rad.
        theta: [f32; 3] = THETA @ 16,
        /// Δv, m/s.
        vel: [f32; 3] = VEL @ 28,
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
    pub const SATURATION_ACC: u32 = 0x8000_0000;
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
    pub const SATURATION_ACC: u32 = 0x0000_0200;
    /// Saturation mask (gyro, accel, mag, baro).
    pub const SATURATION_MASK: u32 = 0x0000_0F00;
    /// A system reset is required for proper function (e.g. after a
    /// FLASH_CONFIG change that applies only at reset).
    pub const SYSTEM_RESET_REQUIRED: u32 = 0x0000_1000;
    /// A flash write is staged or in progress.
    pub const FLASH_WRITE_PENDING: u32 = 0x0000_8000;
    /// Transmit buffer limited.
    pub const ERR_COM_TX_LIMITED: u32 = 0x0001_0000;
    /// Receive buffer overrun.
    pub const ERR_COM_RX_OVERRUN: u32 = 0x0002_0000;
    /// Parse error count field (4 bits).
    pub const COM_PARSE_ERR_COUNT_MASK: u32 = 0x00F0_0000;
    /// Shift of the parse error count field.
    pub const COM_PARSE_ERR_COUNT_SHIFT: u32 = 20;
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
    pub const fn with_parse_errors(status: u32, count: u32) -> u32 {
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
        bits: u64 = BITS @ 0,
        /// Port mask and options.
        options: u32 = OPTIONS @ 8,
    }
    /// DID_IMU stream.
    pub const BITS_IMU: u64 = 0x10;
    /// DID_PIMU stream.
    pub const BITS_PIMU: u64 = 0x20;
    /// DID_STROBE_IN_TIME on each strobe input event.
    pub const BITS_STROBE_IN_TIME: u64 = 0x2_0000;
    /// DID_IMU_RAW stream.
    pub const BITS_IMU_RAW: u64 = 0x200_0000_0000;
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
    pub const OPTIONS_PERSISTENT: u32 = 0x200;
}

crate::data_set! {
    /// `system_command_t`, 8 bytes, and its command codes (protocol-facts.md
    /// "ISB"; `data_sets.h` `eSystemCommand`).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct SystemCommand in mod sys_cmd, 8 bytes {
        /// Command code.
        command: u32 = COMMAND @ 0,
        /// Bitwise inverse of `command` for the command to take effect.
        inv_command: u32 = INV_COMMAND @ 4,
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
        week: u32 = WEEK @ 0,
        /// Time of week (or since boot without GPS), ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 4,
        /// The strobe input pin.
        pin: u16 = PIN @ 8,
        /// Serial number of the event.
        count: u16 = COUNT @ 10,
    }
}

crate::data_set! {
    /// `sys_params_t`, 64 bytes (protocol-facts.md "ISB").
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct SysParams in mod sys_params, 64 bytes {
        /// Time of week (since boot without GPS), ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 0,
        /// INS status (`eInsStatusFlags`).
        ins_status: u32 = INS_STATUS @ 4,
        /// [`hdw_status`] bits.
        hdw_status: u32 = HDW_STATUS @ 8,
        /// IMU temperature, °C.
        imu_temp: f32 = IMU_TEMP @ 12,
        /// Barometer temperature, °C.
        baro_temp: f32 = BARO_TEMP @ 16,
        /// MCU temperature, °C.
        mcu_temp: f32 = MCU_TEMP @ 20,
        /// System status bits.
        sys_status: u32 = SYS_STATUS @ 24,
        /// IMU sample period, ms.
        imu_sample_period_ms: u32 = IMU_SAMPLE_PERIOD_MS @ 28,
        /// PIMU integration and output period, ms.
        nav_output_period_ms: u32 = NAV_OUTPUT_PERIOD_MS @ 32,
        /// Measured sample period, s.
        sensor_true_period: f64 = SENSOR_TRUE_PERIOD @ 36,
        /// FLASH_CONFIG checksum (= FLASH_CONFIG `checksum`).
        flash_cfg_checksum: u32 = FLASH_CFG_CHECKSUM @ 44,
        /// Filter update period, ms.
        nav_update_period_ms: u32 = NAV_UPDATE_PERIOD_MS @ 48,
        /// General fault code (writable: set to 0 to reset).
        gen_fault_code: u32 = GEN_FAULT_CODE @ 52,
        /// Up time, s.
        up_time: f64 = UP_TIME @ 56,
    }
}

/// `nvm_flash_cfg_t`, 288 bytes. Offsets up to `ser2BaudRate` from
/// protocol-facts.md "ISB"; the others from `data_sets.h` of protocol 2.1 (its
/// `ser2BaudRate` lands at 204 and its size at 288, as protocol-facts.md says).
pub mod flash {
    /// Struct size.
    pub const SIZE: usize = 288;
    /// `u32 size` (= 288, read-only).
    pub const SIZE_FIELD: usize = 0;
    /// `u32 checksum`: XOR of the `u32` words of bytes 8..287.
    pub const CHECKSUM: usize = 4;
    /// First byte the checksum covers.
    pub const CHECKSUM_START: usize = 8;
    /// `u32 key`: factory-defaults key.
    pub const KEY: usize = 8;
    /// `u32 startupImuDtMs` (applies after reset).
    pub const STARTUP_IMU_DT_MS: usize = 12;
    /// `u32 startupNavDtMs` (applies after reset).
    pub const STARTUP_NAV_DT_MS: usize = 16;
    /// `u32 ser0BaudRate`.
    pub const SER0_BAUD_RATE: usize = 20;
    /// `u32 ser1BaudRate`.
    pub const SER1_BAUD_RATE: usize = 24;
    /// `f32 insRotation[3]`, rad.
    pub const INS_ROTATION: usize = 28;
    /// `f32 insOffset[3]`, m.
    pub const INS_OFFSET: usize = 40;
    /// `f32 gps1AntOffset[3]`, m.
    pub const GPS1_ANT_OFFSET: usize = 52;
    /// `u8 dynamicModel`.
    pub const DYNAMIC_MODEL: usize = 64;
    /// `u8 debug`.
    pub const DEBUG: usize = 65;
    /// `u16 gnssSatSigConst`.
    pub const GNSS_SAT_SIG_CONST: usize = 66;
    /// `u32 sysCfgBits`.
    pub const SYS_CFG_BITS: usize = 68;
    /// `sysCfgBits`: no BIT at start-up
    /// (`SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP`, SDK 2.7.1).
    pub const SYS_CFG_BITS_DISABLE_AUTO_BIT_ON_STARTUP: u32 = 0x0008_0000;
    /// `f64 refLla[3]`.
    pub const REF_LLA: usize = 72;
    /// `f64 lastLla[3]`.
    pub const LAST_LLA: usize = 96;
    /// `u32 lastLlaTimeOfWeekMs`.
    pub const LAST_LLA_TIME_OF_WEEK_MS: usize = 120;
    /// `u32 lastLlaWeek`.
    pub const LAST_LLA_WEEK: usize = 124;
    /// `f32 lastLlaUpdateDistance`, m.
    pub const LAST_LLA_UPDATE_DISTANCE: usize = 128;
    /// `u32 ioConfig`.
    pub const IO_CONFIG: usize = 132;
    /// `u32 platformConfig`.
    pub const PLATFORM_CONFIG: usize = 136;
    /// `f32 gps2AntOffset[3]`.
    pub const GPS2_ANT_OFFSET: usize = 140;
    /// `f32 zeroVelRotation[3]`.
    pub const ZERO_VEL_ROTATION: usize = 152;
    /// `f32 zeroVelOffset[3]`.
    pub const ZERO_VEL_OFFSET: usize = 164;
    /// `f32 gpsTimeUserDelay`, s.
    pub const GPS_TIME_USER_DELAY: usize = 176;
    /// `f32 magDeclination`, rad.
    pub const MAG_DECLINATION: usize = 180;
    /// `u32 gpsTimeSyncPeriodMs`.
    pub const GPS_TIME_SYNC_PERIOD_MS: usize = 184;
    /// `u32 startupGPSDtMs`.
    pub const STARTUP_GPS_DT_MS: usize = 188;
    /// `u32 RTKCfgBits`.
    pub const RTK_CFG_BITS: usize = 192;
    /// `u32 sensorConfig`.
    pub const SENSOR_CONFIG: usize = 196;
    /// `f32 gpsMinimumElevation`, rad.
    pub const GPS_MINIMUM_ELEVATION: usize = 200;
    /// `u32 ser2BaudRate`.
    pub const SER2_BAUD_RATE: usize = 204;
    /// `wheel_config_t wheelConfig` (60 bytes: u32 bits, 12 × f32
    /// transform, f32 track width, f32 radius).
    pub const WHEEL_CONFIG: usize = 208;
    /// `f32 magInterferenceThreshold`.
    pub const MAG_INTERFERENCE_THRESHOLD: usize = 268;
    /// `f32 magCalibrationQualityThreshold`.
    pub const MAG_CALIBRATION_QUALITY_THRESHOLD: usize = 272;
    /// `u8 gnssCn0Minimum`, dBHz.
    pub const GNSS_CN0_MINIMUM: usize = 276;
    /// `u8 gnssCn0DynMinOffset`, dBHz.
    pub const GNSS_CN0_DYN_MIN_OFFSET: usize = 277;
    /// `u8 imuRejectThreshGyroLow`.
    pub const IMU_REJECT_THRESH_GYRO_LOW: usize = 278;
    /// `u8 imuRejectThreshGyroHigh`.
    pub const IMU_REJECT_THRESH_GYRO_HIGH: usize = 279;
    /// `u8 imuShockDetectLatencyMs`.
    pub const IMU_SHOCK_DETECT_LATENCY_MS: usize = 280;
    /// `u8 imuShockRejectLatchMs`.
    pub const IMU_SHOCK_REJECT_LATCH_MS: usize = 281;
    /// `u8 imuShockOptions`.
    pub const IMU_SHOCK_OPTIONS: usize = 282;
    /// `u8 imuShockDeltaAccHighThreshold`.
    pub const IMU_SHOCK_DELTA_ACC_HIGH: usize = 283;
    /// `u8 imuShockDeltaAccLowThreshold`.
    pub const IMU_SHOCK_DELTA_ACC_LOW: usize = 284;
    /// `u8 imuShockDeltaGyroHighThreshold`.
    pub const IMU_SHOCK_DELTA_GYRO_HIGH: usize = 285;
    /// `u8 imuShockDeltaGyroLowThreshold`.
    pub const IMU_SHOCK_DELTA_GYRO_LOW: usize = 286;
    /// `u8 ioConfig2`.
    pub const IO_CONFIG2: usize = 287;

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
        let mut b = [0u8; SIZE];
        le::put(&mut b, SIZE_FIELD, &(SIZE as u32).to_le_bytes());
        le::put(&mut b, KEY, &FACTORY_KEY.to_le_bytes());
        le::put(&mut b, STARTUP_IMU_DT_MS, &DEFAULT_IMU_DT_MS.to_le_bytes());
        le::put(&mut b, STARTUP_NAV_DT_MS, &DEFAULT_NAV_DT_MS.to_le_bytes());
        for off in [SER0_BAUD_RATE, SER1_BAUD_RATE, SER2_BAUD_RATE] {
            le::put(&mut b, off, &DEFAULT_BAUD_RATE.to_le_bytes());
        }
        b[DYNAMIC_MODEL] = DEFAULT_DYNAMIC_MODEL;
        le::put(&mut b, IO_CONFIG, &DEFAULT_IO_CONFIG.to_le_bytes());
        le::put(
            &mut b,
            GPS_TIME_SYNC_PERIOD_MS,
            &DEFAULT_GPS_TIME_SYNC_PERIOD_MS.to_le_bytes(),
        );
        le::put(&mut b, STARTUP_GPS_DT_MS, &DEFAULT_GPS_DT_MS.to_le_bytes());
        le::put(&mut b, SENSOR_CONFIG, &DEFAULT_SENSOR_CONFIG.to_le_bytes());
        le::put(
            &mut b,
            GPS_MINIMUM_ELEVATION,
            &DEFAULT_GPS_MIN_ELEVATION.to_le_bytes(),
        );
        le::put(
            &mut b,
            MAG_INTERFERENCE_THRESHOLD,
            &DEFAULT_MAG_INTERFERENCE_THRESHOLD.to_le_bytes(),
        );
        le::put(
            &mut b,
            MAG_CALIBRATION_QUALITY_THRESHOLD,
            &DEFAULT_MAG_CAL_QUALITY_THRESHOLD.to_le_bytes(),
        );
        b[GNSS_CN0_MINIMUM] = DEFAULT_GNSS_CN0_MINIMUM;
        b[GNSS_CN0_DYN_MIN_OFFSET] = DEFAULT_GNSS_CN0_DYN_MIN_OFFSET;
        let mut c = FlashConfig(b);
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
    pub fn u32_at(&self, off: usize) -> u32 {
        le::u32(&self.0, off)
    }

    /// `key`.
    pub fn key(&self) -> u32 {
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

/// `bit_t`, 56 bytes, not in protocol-facts.md: from `data_sets.h` of protocol 2.1.
pub mod bit {
    /// Struct size.
    pub const SIZE: usize = 56;
    /// `u8 command` (`eBitCommand`; ignored when 0).
    pub const COMMAND: usize = 0;
    /// `u8 lastCommand`.
    pub const LAST_COMMAND: usize = 1;
    /// `u8 state` (`eBitState`).
    pub const STATE: usize = 2;
    /// `u8 reserved`.
    pub const RESERVED: usize = 3;
    /// `u32 hdwBitStatus` (`eHdwBitStatusFlags`).
    pub const HDW_BIT_STATUS: usize = 4;
    /// `u32 calBitStatus` (`eCalBitStatusFlags`).
    pub const CAL_BIT_STATUS: usize = 8;
    /// `f32 tcPqrBias`, then tcAccBias, tcPqrSlope, tcAccSlope,
    /// tcPqrLinearity, tcAccLinearity (6 × f32).
    pub const TC_PQR_BIAS: usize = 12;
    /// `f32 pqr`: gyro error, rad/s.
    pub const PQR: usize = 36;
    /// `f32 acc`: accelerometer error, m/s².
    pub const ACC: usize = 40;
    /// `f32 pqrSigma`.
    pub const PQR_SIGMA: usize = 44;
    /// `f32 accSigma`.
    pub const ACC_SIGMA: usize = 48;
    /// `u8 testMode`.
    pub const TEST_MODE: usize = 52;
    /// `u8 testVar`.
    pub const TEST_VAR: usize = 53;
    /// `u16 detectedHardwareId`.
    pub const DETECTED_HARDWARE_ID: usize = 54;

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

/// `bit_t` ([`bit`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bit {
    /// Input command.
    pub command: u8,
    /// Last command.
    pub last_command: u8,
    /// State.
    pub state: u8,
    /// Hardware BIT status.
    pub hdw_bit_status: u32,
    /// Calibration BIT status.
    pub cal_bit_status: u32,
    /// tcPqrBias, tcAccBias, tcPqrSlope, tcAccSlope, tcPqrLinearity,
    /// tcAccLinearity.
    pub tc: [f32; 6],
    /// Gyro error, rad/s.
    pub pqr: f32,
    /// Accelerometer error, m/s².
    pub acc: f32,
    /// Angular rate standard deviation.
    pub pqr_sigma: f32,
    /// Acceleration standard deviation.
    pub acc_sigma: f32,
    /// Test mode.
    pub test_mode: u8,
    /// Test variable.
    pub test_var: u8,
    /// Detected hardware id.
    pub detected_hardware_id: u16,
}

impl Bit {
    /// The image.
    pub fn encode(&self) -> [u8; bit::SIZE] {
        use bit::*;
        let mut b = [0u8; SIZE];
        b[COMMAND] = self.command;
        b[LAST_COMMAND] = self.last_command;
        b[STATE] = self.state;
        le::put(&mut b, HDW_BIT_STATUS, &self.hdw_bit_status.to_le_bytes());
        le::put(&mut b, CAL_BIT_STATUS, &self.cal_bit_status.to_le_bytes());
        for (i, v) in self.tc.iter().enumerate() {
            le::put(&mut b, TC_PQR_BIAS + 4 * i, &v.to_le_bytes());
        }
        le::put(&mut b, PQR, &self.pqr.to_le_bytes());
        le::put(&mut b, ACC, &self.acc.to_le_bytes());
        le::put(&mut b, PQR_SIGMA, &self.pqr_sigma.to_le_bytes());
        le::put(&mut b, ACC_SIGMA, &self.acc_sigma.to_le_bytes());
        b[TEST_MODE] = self.test_mode;
        b[TEST_VAR] = self.test_var;
        le::put(
            &mut b,
            DETECTED_HARDWARE_ID,
            &self.detected_hardware_id.to_le_bytes(),
        );
        b
    }
    /// Decodes an image.
    pub fn decode(b: &[u8; bit::SIZE]) -> Self {
        use bit::*;
        let mut tc = [0f32; 6];
        for (i, v) in tc.iter_mut().enumerate() {
            *v = le::f32(b, TC_PQR_BIAS + 4 * i);
        }
        Bit {
            command: b[COMMAND],
            last_command: b[LAST_COMMAND],
            state: b[STATE],
            hdw_bit_status: le::u32(b, HDW_BIT_STATUS),
            cal_bit_status: le::u32(b, CAL_BIT_STATUS),
            tc,
            pqr: le::f32(b, PQR),
            acc: le::f32(b, ACC),
            pqr_sigma: le::f32(b, PQR_SIGMA),
            acc_sigma: le::f32(b, ACC_SIGMA),
            test_mode: b[TEST_MODE],
            test_var: b[TEST_VAR],
            detected_hardware_id: le::u16(b, DETECTED_HARDWARE_ID),
        }
    }
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
