//! The ISB personality's status words from the chain's neutral health:
//! IMU `status` and SYS_PARAMS `hdwStatus` (module doc of [`super`]).

use super::*;

impl State {
    pub(super) fn sys_params(&self, cx: &mut impl Context<Integrals>, now: Instant) -> SysParams {
        let h = cx.chain().health();
        let mut hdw = 0u32;
        if h.gyro_over_range != 0 {
            hdw |= hdw_status::SATURATION_GYR;
        }
        if h.accel_over_range != 0 {
            hdw |= hdw_status::SATURATION_ACC;
        }
        if h.over_temperature {
            hdw |= hdw_status::ERR_TEMPERATURE;
        }
        if h.gyro_bit_failed || h.accel_bit_failed {
            hdw |= hdw_status::BIT_FAILED;
        } else if self.bit.state == bit::STATE_DONE {
            hdw |= hdw_status::BIT_PASSED;
        }
        if h.sensor_comm_failure || h.sensor_config_failure {
            hdw |= hdw_status::FAULT_SYS_CRITICAL;
        }
        let cfg = &self.cfg;
        if cfg.startup_imu_dt_ms() != self.imu_dt_ms
            || cfg.startup_nav_dt_ms() != self.nav_dt_ms
            || cfg.u32_at(flash::SER0_BAUD_RATE) != self.baud
        {
            hdw |= hdw_status::SYSTEM_RESET_REQUIRED;
        }
        if self.save_pending {
            hdw |= hdw_status::FLASH_WRITE_PENDING;
        }
        if self.mag_cal.complete() {
            hdw |= magcal::HDW_STATUS_MAG_RECAL_COMPLETE;
        }
        if cx.tx_dropped() != self.dropped_seen {
            hdw |= hdw_status::ERR_COM_TX_LIMITED;
        }
        hdw |= self.nav.hdw_bits();
        hdw = hdw_status::with_parse_errors(hdw, self.parse_errors);
        let t = cx.chain().temperature();
        let up = now.since(cx.time().powered_at()) as f64 / 1e9;
        let time_of_week_ms = if self.nav.gps_time_valid() {
            self.gps_time(cx).1.tow_ms()
        } else {
            ms_since(cx, now)
        };
        SysParams {
            time_of_week_ms,
            ins_status: self.nav.ins_status(),
            hdw_status: hdw,
            imu_temp: t,
            baro_temp: t,
            mcu_temp: t,
            sys_status: 0,
            imu_sample_period_ms: self.imu_dt_ms,
            nav_output_period_ms: self.nav_dt_ms,
            sensor_true_period: f64::from(self.imu_dt_ms) * 1e-3,
            flash_cfg_checksum: cfg.checksum(),
            nav_update_period_ms: self.nav_dt_ms,
            gen_fault_code: self.gen_fault_code,
            up_time: up,
        }
    }
}

/// IMU `status` from the chain's health (module doc).
pub(super) fn imu_status_of(h: &Health) -> u32 {
    let mut s = if h.sensor_comm_failure || h.sensor_config_failure {
        0
    } else {
        imu_status::ALL_OK
    };
    if h.gyro_over_range != 0 {
        s |= imu_status::SATURATION_GYR;
    }
    if h.accel_over_range != 0 {
        s |= imu_status::SATURATION_ACC;
    }
    s
}
