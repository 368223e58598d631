//! Byte layouts of the navigation data sets of an IMX-5 as a GNSS-INS
//! (Inertial Sense SDK 2.7.1 `data_sets.h`; `docs/isb-data-sets.md`
//! "Navigation data sets", `docs/protocol-facts.md` "ISB"), each declared
//! once with [`crate::data_set!`], and the status words and RMC bits that go
//! with them.

use super::sets::{Imu, Pimu};

crate::data_set! {
    /// The first 20 bytes of `ins_1_t` … `ins_4_t`: GPS time and the
    /// status words.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct InsHeader in mod ins_header, 20 bytes {
        /// GPS weeks since 1980-01-06 (0 before GPS time is known).
        week: u32 = WEEK @ 0 => ["week"],
        /// GPS seconds since the start of the week (time since boot before
        /// GPS time is known).
        time_of_week: f64 = TIME_OF_WEEK @ 4 => ["timeOfWeek" in "s"],
        /// [`ins_status`] bits.
        ins_status: u32 = INS_STATUS @ 12 => ["insStatus"],
        /// `hdwStatus` bits ([`super::sets::hdw_status`], [`hdw_nav`]).
        hdw_status: u32 = HDW_STATUS @ 16 => ["hdwStatus"],
    }
}

crate::data_set! {
    /// `ins_1_t`, 80 bytes: Euler attitude and NED offset from `refLla`.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Ins1 in mod ins1, 80 bytes {
        /// GPS time and status words.
        header: InsHeader = HEADER @ 0 => [..],
        /// Roll, pitch, yaw, rad, body relative to NED.
        theta: [f32; 3] = THETA @ 20 => ["theta" in "rad"],
        /// Body-frame velocity, m/s.
        uvw: [f32; 3] = UVW @ 32 => ["uvw" in "m/s"],
        /// Latitude °, longitude °, height above the WGS84 ellipsoid, m.
        lla: [f64; 3] = LLA @ 44 => ["lla" in "deg, deg, m"],
        /// North, east, down offset of `lla` from FLASH_CONFIG `refLla`, m.
        ned: [f32; 3] = NED @ 68 => ["ned" in "m"],
    }
}

crate::data_set! {
    /// `ins_2_t`, 72 bytes: quaternion attitude.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Ins2 in mod ins2, 72 bytes {
        /// GPS time and status words.
        header: InsHeader = HEADER @ 0 => [..],
        /// W, X, Y, Z: body attitude relative to NED (Hamilton).
        qn2b: [f32; 4] = QN2B @ 20 => ["qn2b"],
        /// Body-frame velocity, m/s.
        uvw: [f32; 3] = UVW @ 36 => ["uvw" in "m/s"],
        /// Latitude °, longitude °, height above the ellipsoid, m.
        lla: [f64; 3] = LLA @ 48 => ["lla" in "deg, deg, m"],
    }
}

crate::data_set! {
    /// `ins_3_t`, 76 bytes: the fields of `ins_2_t` (same offsets) plus
    /// the height above mean sea level.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Ins3 in mod ins3, 76 bytes {
        /// The `ins_2_t` part.
        ins2: Ins2 = INS2 @ 0 => [..],
        /// Height above mean sea level, m.
        msl: f32 = MSL @ 72 => ["msl" in "m"],
    }
}

crate::data_set! {
    /// `ins_4_t`, 72 bytes: ECEF attitude, velocity and position.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Ins4 in mod ins4, 72 bytes {
        /// GPS time and status words.
        header: InsHeader = HEADER @ 0 => [..],
        /// W, X, Y, Z: body attitude relative to ECEF.
        qe2b: [f32; 4] = QE2B @ 20 => ["qe2b"],
        /// ECEF velocity, m/s.
        ve: [f32; 3] = VE @ 36 => ["ve" in "m/s"],
        /// ECEF position, m.
        ecef: [f64; 3] = ECEF @ 48 => ["ecef" in "m"],
    }
}

crate::data_set! {
    /// `gps_pos_t`, 92 bytes: DID_GPS1_POS.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct GpsPos in mod gps_pos, 92 bytes {
        /// GPS week.
        week: u32 = WEEK @ 0 => ["week"],
        /// GPS time of week of the solution, ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 4 => ["timeOfWeekMs" in "ms"],
        /// [`gps_status`]: satellites used, fix type, flags.
        status: u32 = STATUS @ 8 => ["status"],
        /// ECEF position, m.
        ecef: [f64; 3] = ECEF @ 12 => ["ecef" in "m"],
        /// Latitude °, longitude °, height above the ellipsoid, m.
        lla: [f64; 3] = LLA @ 36 => ["lla" in "deg, deg, m"],
        /// Height above mean sea level, m.
        h_msl: f32 = H_MSL @ 60 => ["hMSL" in "m"],
        /// Horizontal accuracy, m.
        h_acc: f32 = H_ACC @ 64 => ["hAcc" in "m"],
        /// Vertical accuracy, m.
        v_acc: f32 = V_ACC @ 68 => ["vAcc" in "m"],
        /// Position dilution of precision.
        p_dop: f32 = P_DOP @ 72 => ["pDop"],
        /// Mean C/N0 of the satellites received, dBHz.
        cno_mean: f32 = CNO_MEAN @ 76 => ["cnoMean" in "dBHz"],
        /// GPS time of week = time since boot + this, s.
        tow_offset: f64 = TOW_OFFSET @ 80 => ["towOffset" in "s"],
        /// GPS − UTC, s.
        leap_s: u8 = LEAP_S @ 88 => ["leapS" in "s"],
        /// Satellites in the solution.
        sats_used: u8 = SATS_USED @ 89 => ["satsUsed"],
        /// Standard deviation of `cno_mean` over 5 s, 0.1 dBHz.
        cno_mean_sigma: u8 = CNO_MEAN_SIGMA @ 90 => ["cnoMeanSigma" in "0.1 dBHz"],
        /// Jamming / spoofing flags (`eGpsStatus2`).
        status2: u8 = STATUS2 @ 91 => ["status2"],
    }
}

crate::data_set! {
    /// `gps_vel_t`, 24 bytes: DID_GPS1_VEL.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct GpsVel in mod gps_vel, 24 bytes {
        /// GPS time of week of the solution, ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 0 => ["timeOfWeekMs" in "ms"],
        /// ECEF velocity, m/s.
        vel: [f32; 3] = VEL @ 4 => ["vel" in "m/s"],
        /// Speed accuracy, m/s.
        s_acc: f32 = S_ACC @ 16 => ["sAcc" in "m/s"],
        /// The [`gps_status`] word of GPS1_POS.
        status: u32 = STATUS @ 20 => ["status"],
    }
}

crate::data_set! {
    /// `gps_sat_sv_t`, 8 bytes: one satellite of DID_GPS1_SAT.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct GpsSatSv in mod gps_sat_sv, 8 bytes {
        /// Constellation (`eSatSvGnssId`: 1 GPS, 2 SBAS, 3 Galileo, 4
        /// BeiDou, 5 QZSS, 6 GLONASS, 7 NavIC, 8 IMES).
        gnss_id: u8 = GNSS_ID @ 0 => ["gnssId"],
        /// Satellite number within the constellation.
        sv_id: u8 = SV_ID @ 1 => ["svId"],
        /// Elevation, degrees (±90).
        elev: i8 = ELEV @ 2,
        /// Azimuth, degrees (±180).
        azim: i16 = AZIM @ 3,
        /// Carrier-to-noise density, dBHz.
        cno: u8 = CNO @ 5 => ["cno" in "dBHz"],
        /// [`sat_status`] bits (`eSatSvStatus`).
        status: u16 = STATUS @ 6,
    }
}

/// `MAX_NUM_SATELLITES`: entries of `gps_sat_t.sat`.
pub const MAX_NUM_SATELLITES: usize = 50;

crate::data_set! {
    /// `gps_sat_t`, 408 bytes: DID_GPS1_SAT, the satellites the receiver
    /// tracks (the first `num_sats` entries of `sat`; the rest zeros).
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub struct GpsSat in mod gps_sat, 408 bytes {
        /// GPS time of week of the receiver's epoch, ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 0 => ["timeOfWeekMs" in "ms"],
        /// Entries of `sat` in use.
        num_sats: u32 = NUM_SATS @ 4 => ["numSats"],
        /// The satellites.
        sat: [GpsSatSv; MAX_NUM_SATELLITES] = SAT @ 8 => [..],
    }
}

crate::data_set! {
    /// `magnetometer_t`, 20 bytes.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Magnetometer in mod magnetometer, 20 bytes {
        /// Seconds since boot.
        time: f64 = TIME @ 0 => ["time" in "s"],
        /// Field, sensor frame, normalized gauss (`docs/isb.md`).
        mag: [f32; 3] = MAG @ 8 => ["mag" in "normalized"],
    }
}

crate::data_set! {
    /// `barometer_t`, 24 bytes.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Barometer in mod barometer, 24 bytes {
        /// Seconds since boot.
        time: f64 = TIME @ 0 => ["time" in "s"],
        /// Pressure, kPa.
        bar: f32 = BAR @ 8 => ["bar" in "kPa"],
        /// Altitude above MSL from the pressure, m.
        msl_bar: f32 = MSL_BAR @ 12 => ["mslBar" in "m"],
        /// Temperature, °C.
        bar_temp: f32 = BAR_TEMP @ 16 => ["barTemp" in "°C"],
        /// Relative humidity, %.
        humidity: f32 = HUMIDITY @ 20 => ["humidity" in "%"],
    }
}

crate::data_set! {
    /// `imu_mag_t`, 56 bytes: an `imu_t` then a `magnetometer_t`.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct ImuMag in mod imu_mag, 56 bytes {
        /// The IMU part.
        imu: Imu = IMU @ 0 => [..],
        /// The magnetometer part.
        mag: Magnetometer = MAG @ 36 => [.. "time" => "magTime"],
    }
}

crate::data_set! {
    /// `pimu_mag_t`, 60 bytes: a `pimu_t` then a `magnetometer_t`.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct PimuMag in mod pimu_mag, 60 bytes {
        /// The PIMU part.
        pimu: Pimu = PIMU @ 0 => [..],
        /// The magnetometer part.
        mag: Magnetometer = MAG @ 40 => [.. "time" => "magTime"],
    }
}

crate::data_set! {
    /// `sys_sensors_t`, 80 bytes (barTemp before mslBar, the opposite order
    /// from `barometer_t`).
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct SysSensors in mod sys_sensors, 80 bytes {
        /// Seconds since boot.
        time: f64 = TIME @ 0 => ["time" in "s"],
        /// IMU temperature, °C.
        temp: f32 = TEMP @ 8 => ["temp" in "°C"],
        /// Angular rate, rad/s.
        pqr: [f32; 3] = PQR @ 12 => ["pqr" in "rad/s"],
        /// Specific force, m/s².
        acc: [f32; 3] = ACC @ 24 => ["acc" in "m/s²"],
        /// Magnetic field, normalized gauss.
        mag: [f32; 3] = MAG @ 36 => ["mag" in "normalized"],
        /// Pressure, kPa.
        bar: f32 = BAR @ 48 => ["bar" in "kPa"],
        /// Barometer temperature, °C.
        bar_temp: f32 = BAR_TEMP @ 52 => ["barTemp" in "°C"],
        /// Altitude above MSL from the pressure, m.
        msl_bar: f32 = MSL_BAR @ 56 => ["mslBar" in "m"],
        /// Relative humidity, %.
        humidity: f32 = HUMIDITY @ 60 => ["humidity" in "%"],
        /// Supply voltage, V.
        vin: f32 = VIN @ 64 => ["vin" in "V"],
        /// Analog inputs 1, 3, 4, V.
        ana: [f32; 3] = ANA @ 68 => ["ana" in "V"],
    }
}

crate::data_set! {
    /// `inl2_states_t`, 96 bytes: the INS filter's states (DID_INL2_STATES,
    /// 48).
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Inl2States in mod inl2_states, 96 bytes {
        /// GPS time of week, s.
        time_of_week: f64 = TIME_OF_WEEK @ 0 => ["timeOfWeek" in "s"],
        /// W, X, Y, Z: body attitude relative to ECEF.
        qe2b: [f32; 4] = QE2B @ 8 => ["qe2b"],
        /// ECEF velocity, m/s.
        ve: [f32; 3] = VE @ 24 => ["ve" in "m/s"],
        /// ECEF position, m.
        ecef: [f64; 3] = ECEF @ 36 => ["ecef" in "m"],
        /// Gyro bias, rad/s.
        bias_pqr: [f32; 3] = BIAS_PQR @ 60 => ["biasPqr" in "rad/s"],
        /// Accelerometer bias, m/s².
        bias_acc: [f32; 3] = BIAS_ACC @ 72 => ["biasAcc" in "m/s^2"],
        /// Barometer bias, m.
        bias_baro: f32 = BIAS_BARO @ 84 => ["biasBaro" in "m"],
        /// Magnetic declination, rad.
        mag_dec: f32 = MAG_DEC @ 88 => ["magDec" in "rad"],
        /// Magnetic inclination, rad.
        mag_inc: f32 = MAG_INC @ 92 => ["magInc" in "rad"],
    }
}

crate::data_set! {
    /// `inl2_ned_sigma_t`, 72 bytes: standard deviations of the INS
    /// filter's estimates, NED (DID_INL2_NED_SIGMA, 67).
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Inl2NedSigma in mod inl2_ned_sigma, 72 bytes {
        /// GPS time of week, ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 0 => ["timeOfWeekMs" in "ms"],
        /// Position, NED, m.
        std_pos_ned: [f32; 3] = STD_POS_NED @ 4 => ["StdPosNed" in "m"],
        /// Velocity, NED, m/s.
        std_vel_ned: [f32; 3] = STD_VEL_NED @ 16 => ["StdVelNed" in "m/s"],
        /// Attitude, NED, rad.
        std_att_ned: [f32; 3] = STD_ATT_NED @ 28 => ["StdAttNed" in "rad"],
        /// Accelerometer bias, m/s².
        std_acc_bias: [f32; 3] = STD_ACC_BIAS @ 40 => ["StdAccBias" in "m/s^2"],
        /// Gyro bias, rad/s.
        std_gyr_bias: [f32; 3] = STD_GYR_BIAS @ 52 => ["StdGyrBias" in "rad/s"],
        /// Barometer bias, m.
        std_bar_bias: f32 = STD_BAR_BIAS @ 64 => ["StdBarBias" in "m"],
        /// Magnetic declination, rad.
        std_mag_declination: f32 = STD_MAG_DECLINATION @ 68 => ["StdMagDeclination" in "rad"],
    }
}

/// `insStatus` bits (`eInsStatusFlags`, `data_sets.h`).
pub mod ins_status {
    /// Heading usable, outside spec.
    pub(crate) const HDG_ALIGN_COARSE: u32 = 0x0000_0001;
    /// Velocity usable, outside spec.
    pub(crate) const VEL_ALIGN_COARSE: u32 = 0x0000_0002;
    /// Position usable, outside spec.
    pub(crate) const POS_ALIGN_COARSE: u32 = 0x0000_0004;
    /// Heading within spec.
    pub(crate) const HDG_ALIGN_FINE: u32 = 0x0000_0010;
    /// Velocity within spec.
    pub(crate) const VEL_ALIGN_FINE: u32 = 0x0000_0020;
    /// Position within spec.
    pub(crate) const POS_ALIGN_FINE: u32 = 0x0000_0040;
    /// Heading from GPS (motion or dual antenna).
    pub(crate) const GPS_AIDING_HEADING: u32 = 0x0000_0080;
    /// Position aided by GPS.
    pub const GPS_AIDING_POS: u32 = 0x0000_0100;
    /// A GPS update just entered the solution (the position may step).
    pub const GPS_UPDATE_IN_SOLUTION: u32 = 0x0000_0200;
    /// Heading aided by the magnetometer.
    pub const MAG_AIDING_HEADING: u32 = 0x0000_0800;
    /// Position and velocity estimated (NAV); clear: AHRS.
    pub const NAV_MODE: u32 = 0x0000_1000;
    /// Velocity aided by GPS.
    pub const GPS_AIDING_VEL: u32 = 0x0000_4000;
    /// Shift of the solution field (`value << 16`).
    pub const SOLUTION_SHIFT: u32 = 16;
    /// Solution field mask.
    pub const SOLUTION_MASK: u32 = 0x000F_0000;
    /// Solution: off.
    pub const SOLUTION_OFF: u32 = 0;
    /// Solution: aligning.
    pub(crate) const SOLUTION_ALIGNING: u32 = 1;
    /// Solution: NAV, good.
    pub(crate) const SOLUTION_NAV: u32 = 3;
    /// Solution: NAV, high variance.
    pub(crate) const SOLUTION_NAV_HIGH_VARIANCE: u32 = 4;
    /// Solution: AHRS, good.
    pub const SOLUTION_AHRS: u32 = 5;
    /// Solution: AHRS, high variance.
    pub(crate) const SOLUTION_AHRS_HIGH_VARIANCE: u32 = 6;
    /// Magnetic interference, or bad or no calibration.
    pub const MAG_INTERFERENCE_OR_BAD_CAL: u32 = 0x0080_0000;
    /// Shift of the GPS fix field (`eGpsNavFixStatus << 24`).
    pub const GPS_NAV_FIX_SHIFT: u32 = 24;
    /// GPS fix field mask.
    pub const GPS_NAV_FIX_MASK: u32 = 0x0300_0000;
    /// GPS fix: 3D.
    pub const GPS_NAV_FIX_3D: u32 = 1;
    /// General fault (see SYS_PARAMS `genFaultCode`).
    pub const GENERAL_FAULT: u32 = 0x8000_0000;
    /// `INS_STATUS_ERROR_MASK`.
    pub const ERROR_MASK: u32 = 0xF8B0_0000;

    /// The solution value of `status`.
    pub const fn solution(status: u32) -> u32 {
        (status & SOLUTION_MASK) >> SOLUTION_SHIFT
    }
    /// The SDK's dead reckoning: position aligned but not GPS-aided.
    pub const fn dead_reckoning(status: u32) -> bool {
        status & (POS_ALIGN_COARSE | POS_ALIGN_FINE) != 0 && status & GPS_AIDING_POS == 0
    }
}

/// `hdwStatus` bits of the navigation side (`eHdwStatusFlags`; the others
/// are in [`super::sets::hdw_status`]).
pub mod hdw_nav {
    /// Satellites are being received.
    pub const GPS_SATELLITE_RX_VALID: u32 = 0x0000_0010;
    /// GPS time known (else timeOfWeek fields hold local time).
    pub const GPS_TIME_OF_WEEK_VALID: u32 = 0x0000_0040;
    /// Magnetometer saturation.
    pub const SATURATION_MAG: u32 = 0x0000_0400;
    /// Barometer saturation.
    pub const SATURATION_BARO: u32 = 0x0000_0800;
    /// No PPS or PPS error.
    pub const ERR_NO_GPS_PPS: u32 = 0x0004_0000;
    /// Time synchronised to the PPS.
    pub const GPS_PPS_TIMESYNC: u32 = 0x0008_0000;
}

/// `gps_pos_t.status` / `gps_vel_t.status` (`eGpsStatus`).
pub mod gps_status {
    /// Satellites used (bits 0-7).
    pub const NUM_SATS_MASK: u32 = 0x0000_00FF;
    /// Fix type field (`value << 8`).
    pub const FIX_MASK: u32 = 0x0000_1F00;
    /// Shift of the fix type.
    pub const FIX_SHIFT: u32 = 8;
    /// Fix type: none.
    pub const FIX_NONE: u32 = 0;
    /// Fix type: 3D.
    pub(crate) const FIX_3D: u32 = 3;
    /// Within the DOP and accuracy limits.
    pub const FIX_OK: u32 = 0x0001_0000;
    /// Time synchronised by PPS.
    pub const TIME_PPS_SYNC: u32 = 0x1000_0000;
}

/// `gps_sat_sv_t.status` (`eSatSvStatus`).
pub mod sat_status {
    /// Signal quality field (`eSatSigQuality`: 4 code locked, 5-7 code
    /// and carrier locked).
    pub const QUALITY_MASK: u16 = 0x0007;
    /// Quality 7: code and carrier locked (the highest of 5-7).
    pub(crate) const QUALITY_CARRIER_LOCKED: u16 = 7;
    /// Used in the solution.
    pub const USED_IN_SOLUTION: u16 = 0x0008;
    /// Health field mask.
    pub const HEALTH_MASK: u16 = 0x0030;
    /// Health: good.
    pub const HEALTH_GOOD: u16 = 0x0010;
    /// Health: bad.
    pub const HEALTH_BAD: u16 = 0x0020;
}

/// RMC bits and presets of the navigation data sets (`data_sets.h`
/// `RMC_BITS_*`, `RMC_PRESET_*`).
pub mod rmc_nav {
    /// DID_INS_1.
    pub(crate) const BITS_INS1: u64 = 0x1;
    /// DID_INS_2.
    pub const BITS_INS2: u64 = 0x2;
    /// DID_INS_3.
    pub(crate) const BITS_INS3: u64 = 0x4;
    /// DID_INS_4.
    pub(crate) const BITS_INS4: u64 = 0x8;
    /// DID_BAROMETER.
    pub const BITS_BAROMETER: u64 = 0x40;
    /// DID_MAGNETOMETER.
    pub const BITS_MAGNETOMETER: u64 = 0x80;
    /// DID_GPS1_POS.
    pub const BITS_GPS1_POS: u64 = 0x400;
    /// DID_GPS1_SAT.
    pub const BITS_GPS1_SAT: u64 = 0x4000;
    /// DID_GPS1_RCVR_POS.
    pub(crate) const BITS_GPS1_RCVR_POS: u64 = 0x40_0000;
    /// DID_GPS1_VEL.
    pub const BITS_GPS1_VEL: u64 = 0x10_0000;
    /// DID_INL2_NED_SIGMA (DID_INL2_STATES has no RMC bit).
    pub(crate) const BITS_INL2_NED_SIGMA: u64 = 0x800_0000;
    /// DID_IMU_MAG.
    pub const BITS_IMU_MAG: u64 = 0x4_0000_0000;
    /// DID_PIMU_MAG.
    pub(crate) const BITS_PIMU_MAG: u64 = 0x8_0000_0000;
    /// `RMC_BITS_INTERNAL_PPD`, set in every PPD preset.
    pub const BITS_INTERNAL_PPD: u64 = 0x4000_0000_0000_0000;
    /// `RMC_PRESET_IMX_PPD_NO_IMU`.
    pub const PRESET_PPD_NO_IMU: u64 = 0xC000_6010_0135_3CC2;
    /// `RMC_PRESET_IMX_PPD`.
    pub const PRESET_PPD: u64 = 0xC000_6090_0135_3CE2;
    /// `RMC_PRESET_IMX_PPD_GROUND_VEHICLE` (what the tool's `-presetPPD`
    /// sends).
    pub const PRESET_PPD_GROUND_VEHICLE: u64 = 0xC000_6091_8135_3CE2;
    /// `RMC_PRESET_INS`.
    pub const PRESET_INS: u64 = 0x8000_0000_0000_0402;
    /// `RMC_PRESET_PPD_NAV_PERIOD_MULT_MS`: INS_2 every 100 ms in a PPD
    /// preset (the older SDKs' multiple 25 × 4 ms; `docs/isb.md`).
    pub(crate) const PPD_NAV_PERIOD_MS: u32 = 100;
}
