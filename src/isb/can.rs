//! DID_CAN_CONFIG (90): the unit's CAN output settings, `can_config_t`
//! (SDK 2.7.1 `data_sets.h`, `docs/isb-data-sets.md` "CAN_CONFIG"). The
//! release keeps them in flash: a SET_DATA (or a host DATA packet) writes
//! them, they are saved and read back after a power cycle. The emulated
//! IMX-5 has no CAN transceiver, so nothing is sent on a bus; the settings
//! are kept, persisted and served as the release does.

/// `NUM_CIDS`: CAN message IDs of the release (INS time … roll rate).
pub(crate) const NUM_CIDS: usize = 27;

crate::data_set! {
    /// `can_config_t`, 168 bytes (`PACKED`): DID_CAN_CONFIG.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub struct CanConfig in mod can_config, 168 bytes {
        /// Broadcast period multiple of each CAN message (0 disables it).
        can_period_mult: [u16; NUM_CIDS] = CAN_PERIOD_MULT @ 0,
        /// Transmit address of each CAN message.
        can_transmit_address: [u32; NUM_CIDS] = CAN_TRANSMIT_ADDRESS @ 54,
        /// Bus rate, kbit/s (20, 33, 50, 83, 100, 125, 200, 250, 500, 1000).
        can_baudrate_kbps: u16 = CAN_BAUDRATE_KBPS @ 162 => ["can_baudrate_kbps" in "kbit/s"],
        /// Receive address.
        can_receive_address: u32 = CAN_RECEIVE_ADDRESS @ 164 => ["can_receive_address"],
    }
}

/// Factory bus rate, kbit/s (the emulator's choice: the SDK gives no
/// default; 500 kbit/s is the common automotive rate and in the header's
/// list).
pub(crate) const FACTORY_BAUDRATE_KBPS: u16 = 500;

/// The factory settings (`docs/isb-data-sets.md` "CAN_CONFIG": the SDK
/// gives none): every message off, addresses 0, [`FACTORY_BAUDRATE_KBPS`].
pub(crate) const FACTORY: CanConfig = CanConfig {
    can_period_mult: [0; NUM_CIDS],
    can_transmit_address: [0; NUM_CIDS],
    can_baudrate_kbps: FACTORY_BAUDRATE_KBPS,
    can_receive_address: 0,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_the_headers() {
        assert_eq!(can_config::SIZE, 168);
        assert_eq!(can_config::CAN_TRANSMIT_ADDRESS, 54);
        let b = FACTORY.encode();
        assert_eq!(&b[162..164], &500u16.to_le_bytes());
        assert_eq!(CanConfig::decode(&b), FACTORY);
    }
}
