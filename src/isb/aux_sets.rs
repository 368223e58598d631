//! The IMX-5's data sets beside navigation and the IMU: SYS_FAULT,
//! GPS1_VERSION, MAG_CAL, GPS1_SIG, IMU3_RAW and PORT_MONITOR, each declared once with
//! [`crate::data_set!`] (layouts: SDK 2.7.1 `data_sets.h`, protocol 2.1,
//! `docs/isb-data-sets.md` "Status, version, calibration and signal data
//! sets", which also says why that header is taken as 2.7.1's).

crate::data_set! {
    /// `system_fault_t`, 32 bytes: DID_SYS_FAULT, what the last critical
    /// fault left (all zeros on a unit that never faulted).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct SystemFault in mod sys_fault, 32 bytes {
        /// `eSysFaultStatus` bits (0: hardware reset, no fault).
        status: u32 = STATUS @ 0 => ["status"],
        /// Task running at the fault.
        g1_task: u32 = G1_TASK @ 4 => ["g1Task"],
        /// Source file number of the fault.
        g2_file_num: u32 = G2_FILE_NUM @ 8 => ["g2FileNum"],
        /// Source line number of the fault.
        g3_line_num: u32 = G3_LINE_NUM @ 12 => ["g3LineNum"],
        /// Multipurpose register.
        g4: u32 = G4 @ 16 => ["g4"],
        /// Link register at the fault.
        g5_lr: u32 = G5_LR @ 20 => ["g5Lr"],
        /// Program counter at the fault.
        pc: u32 = PC @ 24 => ["pc"],
        /// Program status register at the fault.
        psr: u32 = PSR @ 28 => ["psr"],
    }
}

/// Length of `gps_version_t.swVersion`.
pub(crate) const GPS_SW_VERSION_LEN: usize = 30;
/// Length of `gps_version_t.hwVersion`.
pub(crate) const GPS_HW_VERSION_LEN: usize = 10;
/// `GPS_VER_NUM_EXTENSIONS`: entries of `gps_version_t.extension`, each
/// a 30-byte string (`gps_extension_ver_t`).
pub(crate) const GPS_VER_NUM_EXTENSIONS: usize = 6;

crate::data_set! {
    /// `gps_version_t`, 220 bytes: DID_GPS1_VERSION, the receiver's version
    /// strings, NUL padded.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct GpsVersion in mod gps_version, 220 bytes {
        /// Receiver software version.
        sw_version: [u8; GPS_SW_VERSION_LEN] = SW_VERSION @ 0,
        /// Receiver hardware version.
        hw_version: [u8; GPS_HW_VERSION_LEN] = HW_VERSION @ 30,
        /// Extension strings (firmware, protocol, module, constellations).
        extension: [[u8; 30]; GPS_VER_NUM_EXTENSIONS] = EXTENSION @ 40,
    }
}

/// A NUL-padded fixed string field of `s` (cut to `N` bytes).
pub(crate) const fn padded<const N: usize>(s: &str) -> [u8; N] {
    let b = s.as_bytes();
    let mut out = [0u8; N];
    let mut i = 0;
    while i < b.len() && i < N {
        out[i] = b[i];
        i += 1;
    }
    out
}

/// The emulated receiver's version strings (`docs/isb-data-sets.md`
/// "GPS1_VERSION": the emulator's choice, in the form a u-blox receiver
/// reports them).
pub(crate) const RECEIVER_VERSION: GpsVersion = GpsVersion {
    sw_version: padded("EXT CORE 1.00 (emulated)"),
    hw_version: padded("00190000"),
    extension: [
        padded("ROM BASE 0x118B2060"),
        padded("FWVER=HPG 1.32"),
        padded("PROTVER=27.31"),
        padded("MOD=ZED-F9P"),
        padded("GPS;GLO;GAL;BDS"),
        padded("SBAS;QZSS"),
    ],
};

crate::data_set! {
    /// `mag_cal_t`, 12 bytes: DID_MAG_CAL, the magnetometer recalibration
    /// command and its progress.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct MagCal in mod mag_cal, 12 bytes {
        /// `eMagCalState`: commands 1 multi-axis, 2 single-axis, 101 abort;
        /// status 200 running, 201 done.
        state: u32 = STATE @ 0 => ["state"],
        /// Progress, 0..100 %.
        progress: f32 = PROGRESS @ 4 => ["progress" in "%"],
        /// Magnetic declination estimate, rad.
        declination: f32 = DECLINATION @ 8 => ["declination" in "rad"],
    }
}

/// `eMagCalState` values.
pub mod mag_cal_state {
    /// No command, nothing running.
    pub const DO_NOTHING: u32 = 0;
    /// Command: recalibrate using several axes.
    pub const MULTI_AXIS: u32 = 1;
    /// Command: recalibrate using one axis.
    pub const SINGLE_AXIS: u32 = 2;
    /// Command: stop and keep the old calibration.
    pub const ABORT: u32 = 101;
    /// Status: recalibration running.
    pub const RECAL_RUNNING: u32 = 200;
    /// Status: recalibration done.
    pub const RECAL_COMPLETE: u32 = 201;
}

crate::data_set! {
    /// `gps_sig_sv_t`, 7 bytes: one signal of DID_GPS1_SIG.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct GpsSigSv in mod gps_sig_sv, 7 bytes {
        /// Constellation (`eSatSvGnssId`, as `gps_sat_sv_t.gnssId`).
        gnss_id: u8 = GNSS_ID @ 0 => ["gnssId"],
        /// Satellite number within the constellation.
        sv_id: u8 = SV_ID @ 1 => ["svId"],
        /// Signal (`eSatSvSigId`: GPS L1 C/A 0).
        sig_id: u8 = SIG_ID @ 2 => ["sigId"],
        /// Carrier-to-noise density, dBHz.
        cno: u8 = CNO @ 3 => ["cno" in "dBHz"],
        /// `eSatSigQuality` (5..7: code and carrier locked).
        quality: u8 = QUALITY @ 4 => ["quality"],
        /// [`sig_status`] bits (`eSatSigStatus`).
        status: u16 = STATUS @ 5,
    }
}

/// `MAX_NUM_SAT_SIGNALS`: entries of `gps_sig_t.sig`.
pub(crate) const MAX_NUM_SAT_SIGNALS: usize = 100;

crate::data_set! {
    /// `gps_sig_t`, 708 bytes: DID_GPS1_SIG, the signals the receiver
    /// tracks (the first `num_sigs` entries of `sig`; the rest zeros).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct GpsSig in mod gps_sig, 708 bytes {
        /// GPS time of week of the receiver's epoch, ms.
        time_of_week_ms: u32 = TIME_OF_WEEK_MS @ 0 => ["timeOfWeekMs" in "ms"],
        /// Entries of `sig` in use.
        num_sigs: u32 = NUM_SIGS @ 4 => ["numSigs"],
        /// The signals.
        sig: [GpsSigSv; MAX_NUM_SAT_SIGNALS] = SIG @ 8 => [..],
    }
}

/// `gps_sig_sv_t.status` (`eSatSigStatus`).
pub(crate) mod sig_status {
    /// Health good.
    pub(crate) const HEALTH_GOOD: u16 = 0x0001;
    /// Signal used in the solution.
    pub(crate) const USED_IN_SOLUTION: u16 = 0x0004;
}

/// GPS1_SIG of the satellites of a GPS1_SAT (`docs/isb-data-sets.md`
/// "GPS1_SIG"): one L1 C/A signal (sigId 0) per satellite, with its
/// constellation, number and C/N0; quality the satellite's signal quality;
/// healthy and used when the satellite is.
pub(crate) fn gps_sig_of(sat: &super::nav_sets::GpsSat) -> GpsSig {
    let mut sig = [GpsSigSv::default(); MAX_NUM_SAT_SIGNALS];
    let n = (sat.num_sats as usize).min(sat.sat.len());
    for (s, sv) in sig.iter_mut().zip(sat.sat.iter().take(n)) {
        let mut status = 0;
        if sv.status & super::nav_sets::sat_status::HEALTH_GOOD != 0 {
            status |= sig_status::HEALTH_GOOD;
        }
        if sv.status & super::nav_sets::sat_status::USED_IN_SOLUTION != 0 {
            status |= sig_status::USED_IN_SOLUTION;
        }
        *s = GpsSigSv {
            gnss_id: sv.gnss_id,
            sv_id: sv.sv_id,
            sig_id: 0,
            cno: sv.cno,
            quality: (sv.status & 0x7) as u8,
            status,
        };
    }
    GpsSig {
        time_of_week_ms: sat.time_of_week_ms,
        num_sigs: n as u32,
        sig,
    }
}

crate::data_set! {
    /// `imus_t`, 24 bytes: one IMU's measurement.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Imus in mod imus, 24 bytes {
        /// Angular rate, rad/s.
        pqr: [f32; 3] = PQR @ 0 => ["pqr" in "rad/s"],
        /// Specific force, m/s².
        acc: [f32; 3] = ACC @ 12 => ["acc" in "m/s²"],
    }
}

crate::data_set! {
    /// `imu3_t`, 84 bytes: DID_IMU3_RAW, the three IMUs' calibrated
    /// measurements.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct Imu3 in mod imu3, 84 bytes {
        /// Seconds since boot.
        time: f64 = TIME @ 0 => ["time" in "s"],
        /// IMU status word (as `imu_t.status`).
        status: u32 = STATUS @ 8 => ["status"],
        /// IMU 1, 2, 3.
        imu: [Imus; 3] = I @ 12 => [..],
    }
}

crate::data_set! {
    /// `port_monitor_set_t`, 37 bytes (packed by the header's
    /// `PUSH_PACK_1`): one port of DID_PORT_MONITOR.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct PortMonitorSet in mod port_monitor_set, 37 bytes {
        /// High nibble the port type (`ePortMonPortType`: 1 UART, 2 USB,
        /// 3 SPI, 4 I2C, 5 CAN), low nibble its index.
        port_info: u8 = PORT_INFO @ 0 => ["portInfo"],
        /// Status.
        status: u32 = STATUS @ 1 => ["status"],
        /// Bytes sent in the last whole second.
        tx_bytes_per_sec: u32 = TX_BYTES_PER_SEC @ 5 => ["txBytesPerSec" in "B/s"],
        /// Bytes received in the last whole second.
        rx_bytes_per_sec: u32 = RX_BYTES_PER_SEC @ 9 => ["rxBytesPerSec" in "B/s"],
        /// Bytes sent since power-on.
        tx_bytes: u32 = TX_BYTES @ 13 => ["txBytes" in "B"],
        /// Bytes received since power-on.
        rx_bytes: u32 = RX_BYTES @ 17 => ["rxBytes" in "B"],
        /// Writes that could not send all their data.
        tx_data_drops: u32 = TX_DATA_DROPS @ 21 => ["txDataDrops"],
        /// Receive buffer overflows.
        rx_overflows: u32 = RX_OVERFLOWS @ 25 => ["rxOverflows"],
        /// Bytes not sent.
        tx_bytes_dropped: u32 = TX_BYTES_DROPPED @ 29 => ["txBytesDropped" in "B"],
        /// Checksum failures received.
        rx_checksum_errors: u32 = RX_CHECKSUM_ERRORS @ 33 => ["rxChecksumErrors"],
    }
}

/// `NUM_SERIAL_PORTS`: entries of `port_monitor_t.port`.
pub(crate) const NUM_SERIAL_PORTS: usize = 6;

/// `ePortMonPortType` of a UART, in `portInfo`'s high nibble.
pub(crate) const PORT_TYPE_UART: u8 = 1 << 4;

crate::data_set! {
    /// `port_monitor_t`, 223 bytes: DID_PORT_MONITOR, byte counts and
    /// rates of each port.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct PortMonitor in mod port_monitor, 223 bytes {
        /// The ports (the first `active_ports` in use).
        port: [PortMonitorSet; NUM_SERIAL_PORTS] = PORT @ 0 => [..],
        /// Ports in use.
        active_ports: u8 = ACTIVE_PORTS @ 222 => ["activePorts"],
    }
}

/// RMC bits of these sets (`RMC_BITS_*`, `data_sets.h`).
pub(crate) mod rmc_aux {
    /// DID_IMU3_RAW.
    pub(crate) const BITS_IMU3_RAW: u64 = 0x0000_0100_0000_0000;
    /// DID_GPS1_SIG ("1s").
    pub(crate) const BITS_GPS1_SIG: u64 = 0x0000_0400_0000_0000;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_the_headers() {
        assert_eq!(sys_fault::SIZE, 32);
        assert_eq!(gps_version::SIZE, 220);
        assert_eq!(mag_cal::SIZE, 12);
        assert_eq!(gps_sig_sv::SIZE, 7);
        assert_eq!(gps_sig::SIZE, 708);
        assert_eq!(imu3::SIZE, 84);
        assert_eq!(port_monitor_set::SIZE, 37);
        assert_eq!(port_monitor::SIZE, 223);
        assert_eq!(port_monitor_set::RX_CHECKSUM_ERRORS, 33);
        assert_eq!(gps_version::EXTENSION, 40);
        assert_eq!(gps_sig_sv::STATUS, 5);
    }

    #[test]
    fn version_strings_are_nul_padded() {
        let b = RECEIVER_VERSION.encode();
        assert!(b[..30].starts_with(b"EXT CORE"));
        assert_eq!(b[29], 0);
        assert_eq!(&b[30..38], b"00190000");
        assert_eq!(&b[70..81], b"FWVER=HPG 1");
    }
}
