//! What the ISB personality does with a request: GET_DATA, SET_DATA (and
//! host DATA), the stops, the NMEA commands, and what a written data set
//! changes (module doc of [`super`]).

use super::*;

impl State {
    pub(super) fn packet(
        &mut self,
        cx: &mut impl Context<Integrals>,
        p: &Packet<'_>,
        now: Instant,
    ) {
        match Request::of(p) {
            Request::Get(g) => self.get(cx, &g, now),
            Request::BadGet { rx_flags, rx_did } => {
                send_ack(cx, &AckInfo::of(rx_flags, rx_did), true)
            }
            Request::Set(req) => self.set(cx, &req, now, true),
            Request::Data(req) => self.set(cx, &req, now, false),
            Request::StopAllPorts | Request::StopCurrentPort => {
                self.streams.clear();
                self.nmea.table.stop();
                send_ack(cx, &AckInfo::of(p.flags, p.did), false);
            }
            Request::StopDid(did) => self.stop_stream(did),
            Request::Ignored => {}
        }
    }

    pub(super) fn get(&mut self, cx: &mut impl Context<Integrals>, g: &GetRequest, now: Instant) {
        match message::resolve_get(g) {
            GetReply::Nack => send_ack(cx, &AckInfo::of(PacketType::GetData as u8, 0), true),
            GetReply::Silent => {}
            GetReply::Serve {
                set,
                offset,
                size,
                period,
            } => {
                let running = self.find(set.did).map(|i| self.streams[i]);
                if period > 0
                    && running
                        .is_some_and(|s| (s.offset, s.size, s.period) == (offset, size, period))
                {
                    return;
                }
                self.send_once(cx, set, offset, size, now);
                if period == 0 {
                    self.stop_stream(set.did);
                } else {
                    self.start_stream(cx, set, offset, size, period);
                }
            }
        }
    }

    pub(super) fn set(
        &mut self,
        cx: &mut impl Context<Integrals>,
        req: &message::SetRequest<'_>,
        now: Instant,
        reply: bool,
    ) {
        let mut image = [0u8; did::MAX_SIZE];
        let n = self.image_of(cx, req.did, &mut image, now);
        let outcome = message::apply_set(req, &mut image[..n]);
        // Host DATA: the same effect, no ACK or NACK.
        let send_ack = |cx: &mut _, info: &AckInfo, nack| {
            if reply {
                send_ack(cx, info, nack);
            }
        };
        match outcome {
            SetOutcome::Nack(info) | SetOutcome::Refused(info) => send_ack(cx, &info, true),
            SetOutcome::Silent => {}
            SetOutcome::AckOnly(info) => send_ack(cx, &info, false),
            SetOutcome::Written { ack, .. }
                if req.did == did::FLASH_CONFIG && !ins::flash_nav_valid(&image[..n]) =>
            {
                send_ack(cx, &ack, true)
            }
            SetOutcome::Written { ack, .. } => {
                // The ACK goes first: a software reset clears the queue
                // only after it has been handed out.
                send_ack(cx, &ack, false);
                self.written(cx, req.did, &image[..n]);
            }
        }
    }

    /// Acts on a data set written by a SET_DATA (module doc).
    pub(super) fn written(&mut self, cx: &mut impl Context<Integrals>, did: u8, image: &[u8]) {
        match did {
            did::FLASH_CONFIG => {
                self.cfg.0.copy_from_slice(&image[..flash::SIZE]);
                self.cfg.update_checksum();
                self.save_pending = true;
            }
            did::RMC => {
                let mut b = [0u8; rmc::SIZE];
                b.copy_from_slice(&image[..rmc::SIZE]);
                self.rmc(cx, &Rmc::decode(&b));
            }
            did::SYS_CMD => {
                let mut b = [0u8; sys_cmd::SIZE];
                b.copy_from_slice(&image[..sys_cmd::SIZE]);
                let cmd = SystemCommand::decode(&b).valid();
                let unlocked = core::mem::replace(&mut self.unlocked, false);
                match cmd {
                    Some(sys_cmd::SAVE_PERSISTENT_MESSAGES) => self.save_persistent(cx),
                    Some(sys_cmd::SAVE_FLASH) => self.save(cx),
                    Some(sys_cmd::SOFTWARE_RESET) => self.software_reset(cx),
                    Some(sys_cmd::MANF_UNLOCK) => self.unlocked = true,
                    // FLASH_CONFIG back to the factory defaults, saved, then
                    // a reset (docs/isb.md); only right after the unlock.
                    Some(sys_cmd::MANF_FACTORY_RESET) if unlocked => {
                        self.cfg = FlashConfig::factory();
                        self.save(cx);
                        cx.request_reset();
                    }
                    _ => {}
                }
            }
            did::SYS_PARAMS => {
                self.gen_fault_code = le::u32(image, sets::sys_params::GEN_FAULT_CODE);
            }
            did::NMEA_BCAST_PERIOD => {
                let mut b = [0u8; asce::nmea_msgs::SIZE];
                b.copy_from_slice(&image[..asce::nmea_msgs::SIZE]);
                let a = self.nmea.table.apply_msgs(&b);
                self.nmea.rejected = self.nmea.rejected.wrapping_add(u32::from(a.rejected));
                self.nmea.next_in = Some(1);
                if a.persistent {
                    self.save_persistent(cx);
                }
            }
            did::MAG_CAL => {
                self.mag_cal
                    .command(le::u32(image, aux_sets::mag_cal::STATE));
                self.nav.set_mag_recalibrating(self.mag_cal.running());
            }
            did::CAN_CONFIG => {
                let mut b = [0u8; can::can_config::SIZE];
                b.copy_from_slice(&image[..can::can_config::SIZE]);
                self.can = CanConfig::decode(&b);
                self.save_pending = true;
            }
            did::BIT if image[bit::COMMAND] != bit::CMD_NONE => {
                self.run_bit(cx, image[bit::COMMAND]);
            }
            _ => {}
        }
    }

    pub(super) fn nmea(&mut self, cx: &mut impl Context<Integrals>, c: Nmea, _now: Instant) {
        match c {
            Nmea::Info => {
                let mut out = [0u8; INFO_MAX];
                if let Some(n) = nmea::info_sentence(&dev_info_of(cx), &mut out) {
                    cx.push_frame(n, |f| {
                        f.copy_from_slice(&out[..n]);
                        true
                    });
                }
            }
            Nmea::StopAllPorts | Nmea::StopCurrentPort => {
                self.streams.clear();
                self.nmea.table.stop();
            }
            Nmea::SavePersistent => self.save_persistent(cx),
            Nmea::SoftwareReset => self.software_reset(cx),
        }
    }
}

/// Queues an ISB packet of `n` bytes written by `encode` (which returns
/// the length it wrote).
pub(super) fn push(
    cx: &mut impl Context<Integrals>,
    n: usize,
    encode: impl FnOnce(&mut [u8]) -> Option<usize>,
) -> bool {
    cx.push_frame(n, |f| encode(f) == Some(n)).is_some()
}

fn send_ack(cx: &mut impl Context<Integrals>, info: &AckInfo, nack: bool) {
    push(cx, OVERHEAD + message::ACK_PAYLOAD_LEN, |f| {
        if nack {
            message::encode_nack(info, f)
        } else {
            message::encode_ack(info, f)
        }
    });
}
