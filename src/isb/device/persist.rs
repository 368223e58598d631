//! What the ISB personality keeps in flash: FLASH_CONFIG, the persistent
//! streams, the persistent NMEA table and CAN_CONFIG, in one power-fail-safe image
//! ([`crate::store`]).

use super::*;

/// Bytes of one persistent-stream entry in the image: `u8 did, u8 0,
/// u16 size, u16 offset, u16 period`.
pub(super) const ENTRY: usize = 8;
/// Where the persistent streams start in the image (after FLASH_CONFIG):
/// `u32 count`, then [`MAX_STREAMS`] entries.
pub(super) const PERSIST: usize = flash::SIZE;
/// Where the persistent NMEA table starts ([`asce::Table::to_image`]).
pub(super) const PERSIST_NMEA: usize = PERSIST + 4 + MAX_STREAMS * ENTRY;
/// Where CAN_CONFIG starts ([`can`]).
pub(super) const PERSIST_CAN: usize = PERSIST_NMEA + asce::IMAGE_LEN;
/// The ISB image in flash: FLASH_CONFIG, the persistent streams, the
/// persistent NMEA table, CAN_CONFIG.
pub const IMAGE_LEN: usize = PERSIST_CAN + can::can_config::SIZE;
/// How the ISB image is stored ([`crate::store`]): its own magic, so a
/// flash written by the KERNEL personality is not taken for it. Version 2
/// added the NMEA table, version 3 CAN_CONFIG (an image of an older
/// version loads as none: factory defaults).
pub const IMAGE: ImageSpec = ImageSpec {
    len: IMAGE_LEN as u16,
    magic: *b"ISB1",
    version: 3,
};

impl State {
    /// FLASH_CONFIG and the persistent streams and NMEA table from flash;
    /// factory defaults and none if it holds no valid ISB image, or one
    /// whose `key` is not the factory key.
    pub(super) fn load(&mut self, cx: &mut impl Context<Integrals>) {
        let st = self;
        let mut image = [0u8; IMAGE_LEN];
        let loaded = matches!(cx.load_image(&mut image), Ok(true));
        let mut cfg = FlashConfig([0; flash::SIZE]);
        cfg.0.copy_from_slice(&image[..PERSIST]);
        // A FLASH_CONFIG whose `key` is not the firmware's is replaced by
        // the factory defaults (docs/isb-data-sets.md).
        if loaded && cfg.is_valid() && cfg.key() == flash::FACTORY_KEY {
            st.cfg = cfg;
            st.persist.copy_from_slice(&image[PERSIST..PERSIST_NMEA]);
            st.persist_nmea
                .copy_from_slice(&image[PERSIST_NMEA..PERSIST_CAN]);
            let mut c = [0u8; can::can_config::SIZE];
            c.copy_from_slice(&image[PERSIST_CAN..]);
            st.can = CanConfig::decode(&c);
        } else {
            st.cfg = FlashConfig::factory();
            st.persist = [0; 4 + MAX_STREAMS * ENTRY];
            st.persist_nmea = [0; asce::IMAGE_LEN];
            st.can = can::FACTORY;
        }
    }

    /// The persistent streams start (at boot).
    pub(super) fn start_persistent(&mut self, cx: &mut impl Context<Integrals>) {
        let st = self;
        let n = (le::u32(&st.persist, 0) as usize).min(MAX_STREAMS);
        for k in 0..n {
            let e = &st.persist[4 + k * ENTRY..4 + (k + 1) * ENTRY];
            let req = GetRequest {
                did: u16::from(e[0]),
                size: le::u16(e, 2),
                offset: le::u16(e, 4),
                period: le::u16(e, 6),
            };
            if let GetReply::Serve {
                set,
                offset,
                size,
                period,
            } = message::resolve_get(&req)
            {
                if period > 0 {
                    st.start_stream(cx, set, offset, size, period);
                }
            }
        }
    }

    /// The running streams become the persistent ones, saved at once: the
    /// first [`MAX_STREAMS`] of them (up to [`MAX_RUNNING`] run; the flash
    /// image keeps its layout).
    pub(super) fn save_persistent(&mut self, cx: &mut impl Context<Integrals>) {
        self.persist = [0; 4 + MAX_STREAMS * ENTRY];
        let n = self.streams.len().min(MAX_STREAMS);
        le::put(&mut self.persist, 0, &(n as u32).to_le_bytes());
        for (k, s) in self.streams.iter().take(n).enumerate() {
            let e = &mut self.persist[4 + k * ENTRY..4 + (k + 1) * ENTRY];
            e[0] = s.did;
            le::put(e, 2, &s.size.to_le_bytes());
            le::put(e, 4, &s.offset.to_le_bytes());
            le::put(e, 6, &s.period.max(1).to_le_bytes());
        }
        self.persist_nmea = self.nmea.table.to_image();
        self.save(cx);
    }

    /// A software reset (`$SRST`, SYS_CMD): a FLASH_CONFIG write still
    /// waiting for its tick is saved first, since the reset discards the
    /// RAM copy and the write was acknowledged (a write and a reset within
    /// one tick kept the old line rate).
    pub(super) fn software_reset(&mut self, cx: &mut impl Context<Integrals>) {
        if self.save_pending {
            self.save(cx);
        }
        cx.request_reset();
    }

    /// Writes FLASH_CONFIG and the persistent streams (power-fail safe); a
    /// flash failure leaves the write pending.
    pub(super) fn save(&mut self, cx: &mut impl Context<Integrals>) {
        let mut image = [0u8; IMAGE_LEN];
        image[..PERSIST].copy_from_slice(&self.cfg.0);
        image[PERSIST..PERSIST_NMEA].copy_from_slice(&self.persist);
        image[PERSIST_NMEA..PERSIST_CAN].copy_from_slice(&self.persist_nmea);
        image[PERSIST_CAN..].copy_from_slice(&self.can.encode());
        self.save_pending = cx.save_image(&image).is_err();
    }
}
