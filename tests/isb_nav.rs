//! The navigation data sets of the emulated IMX-5 (Inertial Sense SDK 2.7.1
//! `data_sets.h`; `docs/isb-data-sets.md` "Navigation data sets").

use imu_emu::isb::nav_sets::*;
use imu_emu::isb::sets::{Imu, Pimu};

/// Every size and offset of the SDK 2.7.1 structs (`sizeof`/`offsetof`,
/// docs/isb-data-sets.md), against the declarations.
#[test]
fn layouts_are_the_sdk_structs() {
    assert_eq!(
        [ins1::SIZE, ins2::SIZE, ins3::SIZE, ins4::SIZE],
        [80, 72, 76, 72]
    );
    assert_eq!(
        [
            ins_header::SIZE,
            ins_header::WEEK,
            ins_header::TIME_OF_WEEK,
            ins_header::INS_STATUS,
            ins_header::HDW_STATUS
        ],
        [20, 0, 4, 12, 16]
    );
    assert_eq!(
        [ins1::HEADER, ins1::THETA, ins1::UVW, ins1::LLA, ins1::NED],
        [0, 20, 32, 44, 68]
    );
    assert_eq!(
        [ins2::HEADER, ins2::QN2B, ins2::UVW, ins2::LLA],
        [0, 20, 36, 48]
    );
    // ins_3_t is ins_2_t's bytes then msl.
    assert_eq!([ins3::INS2, ins3::MSL], [0, 72]);
    assert_eq!(
        [ins4::HEADER, ins4::QE2B, ins4::VE, ins4::ECEF],
        [0, 20, 36, 48]
    );
    assert_eq!(gps_pos::SIZE, 92);
    assert_eq!(
        [
            gps_pos::WEEK,
            gps_pos::TIME_OF_WEEK_MS,
            gps_pos::STATUS,
            gps_pos::ECEF,
            gps_pos::LLA,
            gps_pos::H_MSL,
            gps_pos::H_ACC,
            gps_pos::V_ACC,
            gps_pos::P_DOP,
            gps_pos::CNO_MEAN,
            gps_pos::TOW_OFFSET,
            gps_pos::LEAP_S,
            gps_pos::SATS_USED,
            gps_pos::CNO_MEAN_SIGMA,
            gps_pos::STATUS2
        ],
        [0, 4, 8, 12, 36, 60, 64, 68, 72, 76, 80, 88, 89, 90, 91]
    );
    assert_eq!(gps_vel::SIZE, 24);
    assert_eq!(
        [
            gps_vel::TIME_OF_WEEK_MS,
            gps_vel::VEL,
            gps_vel::S_ACC,
            gps_vel::STATUS
        ],
        [0, 4, 16, 20]
    );
    assert_eq!([magnetometer::SIZE, magnetometer::MAG], [20, 8]);
    assert_eq!(
        [
            barometer::SIZE,
            barometer::BAR,
            barometer::MSL_BAR,
            barometer::BAR_TEMP,
            barometer::HUMIDITY
        ],
        [24, 8, 12, 16, 20]
    );
    assert_eq!([imu_mag::SIZE, imu_mag::MAG], [56, 36]);
    assert_eq!([pimu_mag::SIZE, pimu_mag::MAG], [60, 40]);
    assert_eq!(
        [
            sys_sensors::SIZE,
            sys_sensors::TEMP,
            sys_sensors::PQR,
            sys_sensors::ACC,
            sys_sensors::MAG,
            sys_sensors::BAR,
            sys_sensors::BAR_TEMP,
            sys_sensors::MSL_BAR,
            sys_sensors::HUMIDITY,
            sys_sensors::VIN,
            sys_sensors::ANA
        ],
        [80, 8, 12, 24, 36, 48, 52, 56, 60, 64, 68]
    );
}

/// Golden bytes: each field lands at its offset, little-endian, and the
/// decoder reads back what the encoder wrote.
#[test]
fn golden_bytes_and_round_trips() {
    let i1 = Ins1 {
        header: InsHeader {
            week: 2400,
            time_of_week: 345_600.25,
            ins_status: 0x0103_5970,
            hdw_status: 0x0208_0050,
        },
        theta: [0.1, -0.2, 3.0],
        uvw: [1.0, 2.0, 3.0],
        lla: [45.0, 7.5, 250.0],
        ned: [-1.0, 2.0, -3.0],
    };
    let b = i1.encode();
    assert_eq!(&b[0..4], &2400u32.to_le_bytes());
    assert_eq!(&b[4..12], &345_600.25f64.to_le_bytes());
    assert_eq!(&b[12..16], &[0x70, 0x59, 0x03, 0x01]);
    assert_eq!(&b[28..32], &3.0f32.to_le_bytes());
    assert_eq!(&b[60..68], &250.0f64.to_le_bytes());
    assert_eq!(&b[76..80], &(-3.0f32).to_le_bytes());
    assert_eq!(Ins1::decode(&b), i1);

    let p = GpsPos {
        week: 2400,
        time_of_week_ms: 345_600_200,
        status: 0x0001_030C,
        ecef: [4.0e6, 5.0e5, 4.5e6],
        lla: [45.0, 7.5, 250.0],
        h_msl: 202.0,
        h_acc: 1.5,
        v_acc: 2.5,
        p_dop: 1.2,
        cno_mean: 42.0,
        tow_offset: 345_000.0,
        leap_s: 18,
        sats_used: 12,
        cno_mean_sigma: 15,
        status2: 0,
    };
    let b = p.encode();
    assert_eq!(&b[8..12], &[0x0C, 0x03, 0x01, 0x00]);
    assert_eq!(&b[80..88], &345_000.0f64.to_le_bytes());
    assert_eq!(&b[88..92], &[18, 12, 15, 0]);
    assert_eq!(GpsPos::decode(&b), p);

    let m = ImuMag {
        imu: Imu {
            time: 1.0,
            status: 0x3F,
            pqr: [0.0; 3],
            acc: [0.0, 0.0, -9.8],
        },
        mag: Magnetometer {
            time: 1.0,
            mag: [0.3, 0.0, 0.9],
        },
    };
    let b = m.encode();
    assert_eq!(&b[..36], &m.imu.encode());
    assert_eq!(&b[36..], &m.mag.encode());
    assert_eq!(ImuMag::decode(&b), m);
    let pm = PimuMag {
        pimu: Pimu {
            time: 2.0,
            dt: 0.004,
            ..Pimu::default()
        },
        mag: m.mag,
    };
    assert_eq!(&pm.encode()[40..], &m.mag.encode());
    let s = SysSensors {
        bar_temp: 25.0,
        msl_bar: 100.0,
        ..SysSensors::default()
    };
    let b = s.encode();
    assert_eq!(&b[52..56], &25.0f32.to_le_bytes());
    assert_eq!(&b[56..60], &100.0f32.to_le_bytes());
}

/// RMC bits and presets of SDK 2.7.1 (`g_didToRmcBit`, `RMC_PRESET_*`).
#[test]
fn rmc_bits_and_presets() {
    use rmc_nav::*;
    assert_eq!(
        PRESET_INS,
        0x8000_0000_0000_0000 | BITS_INS2 | BITS_GPS1_POS
    );
    assert_eq!(PRESET_PPD & !PRESET_PPD_NO_IMU, 0x20 | (1 << 39));
    for bit in [
        BITS_INS2,
        BITS_BAROMETER,
        BITS_MAGNETOMETER,
        BITS_GPS1_POS,
        BITS_GPS1_VEL,
    ] {
        assert_ne!(PRESET_PPD_NO_IMU & bit, 0);
    }
    assert!(ins_status::dead_reckoning(0x40));
    assert!(!ins_status::dead_reckoning(0x140));
}

/// `gps_sat_t` (408 bytes: time of week, numSats, 50 × `gps_sat_sv_t` of 8
/// bytes) and its RMC bit (SDK 2.7.1 `data_sets.h`): offsets, golden bytes
/// of one record at its place in the array, round trip.
#[test]
fn gps_sat_layout_and_golden_bytes() {
    use imu_emu::isb::did;
    assert_eq!(
        [
            gps_sat::SIZE,
            gps_sat::TIME_OF_WEEK_MS,
            gps_sat::NUM_SATS,
            gps_sat::SAT
        ],
        [408, 0, 4, 8]
    );
    assert_eq!(MAX_NUM_SATELLITES, 50);
    assert_eq!(
        [
            gps_sat_sv::SIZE,
            gps_sat_sv::GNSS_ID,
            gps_sat_sv::SV_ID,
            gps_sat_sv::ELEV,
            gps_sat_sv::AZIM,
            gps_sat_sv::CNO,
            gps_sat_sv::STATUS
        ],
        [8, 0, 1, 2, 3, 5, 6]
    );
    let set = did::lookup(15).unwrap();
    assert_eq!(
        (set.did, set.size, set.rmc_bit),
        (did::GPS1_SAT, 408, 0x4000)
    );
    assert_eq!(set.source, did::Source::Fixed(1000));
    assert_eq!(rmc_nav::BITS_GPS1_SAT, 0x4000);

    let mut sat = [GpsSatSv::default(); MAX_NUM_SATELLITES];
    sat[1] = GpsSatSv {
        gnss_id: 1,
        sv_id: 27,
        elev: -5,
        azim: -170,
        cno: 44,
        status: 0x001F,
    };
    let s = GpsSat {
        time_of_week_ms: 345_601_000,
        num_sats: 2,
        sat,
    };
    let b = s.encode();
    assert_eq!(&b[0..4], &345_601_000u32.to_le_bytes());
    assert_eq!(&b[4..8], &[2, 0, 0, 0]);
    // Record 1 at 8 + 8: gnssId, svId, elev, azim (i16, unaligned), cno, status.
    assert_eq!(&b[16..24], &[1, 27, 0xFB, 0x56, 0xFF, 44, 0x1F, 0x00]);
    assert!(b[8..16].iter().chain(&b[24..]).all(|&x| x == 0));
    assert_eq!(GpsSat::decode(&b), s);
}
