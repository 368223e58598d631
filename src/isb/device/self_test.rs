//! BIT: the built-in test a BIT `command` (or the start-up) runs, its
//! result from the chain's BIT faults (`docs/isb-data-sets.md` "bit_t").

use super::*;

impl State {
    pub(super) fn run_bit(&mut self, cx: &impl Context<Integrals>, command: u8) {
        let h = cx.chain().health();
        let mut hdw = bit::HDW_PASSED_NO_GPS;
        if h.gyro_bit_failed {
            hdw = bit::HDW_FAULT_NOISE_PQR;
        }
        if h.accel_bit_failed {
            hdw = if h.gyro_bit_failed {
                bit::HDW_FAULT_NOISE_PQR | bit::HDW_FAULT_NOISE_ACC
            } else {
                bit::HDW_FAULT_NOISE_ACC
            };
        }
        self.bit = Bit {
            command: bit::CMD_NONE,
            last_command: command,
            state: bit::STATE_DONE,
            hdw_bit_status: hdw,
            cal_bit_status: bit::CAL_PASSED_ALL,
            ..Bit::default()
        };
    }
}
