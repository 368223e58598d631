//! Target `isb_device`: the whole ISB device (the emulated IMX-5),
//! driven by a script decoded from the input.

use imu_emu::device::{Device, Level, Pin, PowerOn, TX_CAP};
use imu_emu::isb;
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::time::Instant;

use crate::device::TICK_BUDGET;
use crate::script::{drain_tx, Cursor};

/// Checks the TX byte stream of an ISB session: whole ISB packets with good
/// checksums or whole `$…*hh\r\n` sentences with good checksums, back to
/// back.
#[derive(Default)]
struct IsbTx {
    pending: Vec<u8>,
}

impl IsbTx {
    fn feed(&mut self, bytes: &[u8]) {
        use isb::packet::{checksum, MAX_PACKET, OVERHEAD, PREAMBLE};
        self.pending.extend_from_slice(bytes);
        loop {
            let p = &self.pending;
            let Some(&first) = p.first() else { break };
            if first == b'$' {
                let Some(end) = p.iter().position(|&b| b == b'\n') else {
                    assert!(p.len() < 256, "TX: a sentence without an end");
                    break;
                };
                let s = &p[..=end];
                assert!(
                    s.len() >= 6 && s[s.len() - 2] == b'\r',
                    "TX: sentence ending"
                );
                let star = s.len() - 5;
                assert_eq!(s[star], b'*', "TX: sentence checksum field");
                let want = s[1..star].iter().fold(0u8, |a, &c| a ^ c);
                let hex = std::str::from_utf8(&s[star + 1..star + 3]).expect("hex");
                assert_eq!(u8::from_str_radix(hex, 16).ok(), Some(want), "TX: NMEA sum");
                self.pending.drain(..=end);
                continue;
            }
            assert_eq!(first, PREAMBLE[0], "TX: not at a packet or sentence start");
            if p.len() < 6 {
                break;
            }
            assert_eq!(p[1], PREAMBLE[1], "TX: preamble");
            let n = usize::from(u16::from_le_bytes([p[4], p[5]])) + OVERHEAD;
            assert!(n <= MAX_PACKET, "TX: packet of {n} bytes");
            if p.len() < n {
                break;
            }
            assert_eq!(checksum(&p[..n - 2]), p[n - 2..n], "TX: ISB checksum");
            self.pending.drain(..n);
        }
    }

    fn end_session(&mut self) {
        assert!(self.pending.is_empty(), "TX: a packet cut short");
    }
}

/// DIDs an ISB script asks for: every served one, some unserved and some
/// NACKed.
const ISB_DIDS: [u8; 16] = [
    1, 3, 7, 9, 10, 12, 58, 64, 68, 97, 2, 95, 121, 123, 132, 200,
];

struct IsbHarness {
    dev: Device<RamNor<16384>, isb::Isb>,
    now: u64,
    ticks_left: u32,
    tx: IsbTx,
}

impl IsbHarness {
    fn read_tx(&mut self, max: usize) {
        let tx = &mut self.tx;
        drain_tx(&mut self.dev, max, |b| tx.feed(b));
    }

    fn drain(&mut self) {
        while self.dev.tx_len() > 0 {
            self.read_tx(4096);
        }
        self.read_tx(4096);
    }

    fn rx(&mut self, bytes: &[u8]) {
        self.dev.on_rx(bytes, Instant(self.now));
        self.invariants();
    }

    fn ticks(&mut self, n: u32) {
        let n = n.min(self.ticks_left);
        self.ticks_left -= n;
        self.drain();
        for _ in 0..n {
            self.now += self.dev.tick_period_ns();
            self.dev.on_tick(Instant(self.now));
            self.drain();
            self.invariants();
        }
    }

    fn invariants(&self) {
        assert!(self.dev.tx_len() <= TX_CAP, "TX queue bounded");
        let cfg = self.dev.personality().flash_config();
        assert!(cfg.is_valid(), "FLASH_CONFIG checksum in step");
        assert!(
            self.dev.personality().streams().count() <= isb::device::MAX_RUNNING,
            "streams bounded"
        );
    }

    fn power_cycle(&mut self, boot: Option<Level>) {
        self.drain();
        self.tx.end_session();
        self.dev.flash_mut().restore_power();
        self.now += 1_000_000;
        self.dev.power_cycle_with(boot, Instant(self.now));
        self.drain();
        self.invariants();
    }

    fn config(&self) -> Vec<u8> {
        self.dev.personality().flash_config().0.to_vec()
    }
}

/// What a boot makes of a saved FLASH_CONFIG: itself, or the factory
/// defaults when its `key` is not the factory key.
fn expected_after_boot(saved: Vec<u8>) -> Vec<u8> {
    use isb::sets::{flash, le, FlashConfig};
    if le::u32(&saved, flash::KEY) == flash::FACTORY_KEY {
        saved
    } else {
        FlashConfig::factory().0.to_vec()
    }
}

fn isb_get(did: u8, size: u16, offset: u16, period: u16) -> Vec<u8> {
    let req = isb::message::GetRequest {
        did: u16::from(did),
        size,
        offset,
        period,
    };
    let mut out = [0u8; 32];
    let n = isb::message::encode_get(&req, &mut out).unwrap_or(0);
    out[..n].to_vec()
}

fn isb_set(did: u8, offset: u16, data: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 512];
    let n = isb::message::encode_set(did, offset, data, &mut out).unwrap_or(0);
    out[..n].to_vec()
}

/// The whole ISB device (the emulated IMX-5), driven by a script: raw RX
/// bytes, GET_DATA and SET_DATA of any DID, size, offset and period, the
/// NMEA commands, SYS_CMD, ticks, EXTRIG edges, power cycles with and
/// without BOOT, power cuts (torn) in a FLASH_CONFIG save, TX reads of any
/// size. Invariants: TX bytes are always whole ISB packets or NMEA
/// sentences with good checksums; FLASH_CONFIG's checksum is always in
/// step; a power cycle keeps the FLASH_CONFIG saved before it (or restores
/// the defaults when its `key` was changed), and a cut save leaves the old
/// or the new one; the TX queue and the streams stay
/// bounded; nothing panics.
pub fn isb_device(data: &[u8]) {
    let mut c = Cursor::new(data);
    let dev = Device::<RamNor<16384>, isb::Isb>::new(
        PowerOn {
            product: Product::imx5(),
            boot: None,
            seed: u64::from(c.u8()),
        },
        RamNor::new(),
        Instant::ZERO,
    );
    let mut h = IsbHarness {
        dev,
        now: 0,
        ticks_left: TICK_BUDGET,
        tx: IsbTx::default(),
    };
    while !c.is_empty() {
        match c.u8() % 11 {
            0 => {
                let n = usize::from(c.u8() % 64);
                let bytes = c.bytes(n).to_vec();
                h.rx(&bytes);
            }
            1 | 2 => {
                let did = ISB_DIDS[usize::from(c.u8()) % ISB_DIDS.len()];
                let (size, offset, period) = (c.u16() % 320, c.u16() % 320, c.u16() % 8);
                h.rx(&isb_get(did, size, offset, period));
            }
            3 => {
                let did = ISB_DIDS[usize::from(c.u8()) % ISB_DIDS.len()];
                let offset = c.u16() % 300;
                let n = usize::from(c.u8() % 40);
                let data = c.bytes(n).to_vec();
                h.rx(&isb_set(did, offset, &data));
            }
            4 => {
                let s = isb::nmea::Command::ALL[usize::from(c.u8()) % 5].sentence();
                h.rx(s.as_bytes());
            }
            5 => {
                let n = u32::from(c.u8()) * 8;
                h.ticks(n);
            }
            6 => {
                let t = c.u8();
                let level = if t & 1 == 0 { Level::Low } else { Level::High };
                h.dev.on_pin(Pin::Extrig, level, Instant(h.now));
                h.read_tx(4096);
                h.invariants();
            }
            7 => {
                // A clean power cycle keeps what was saved (one tick
                // flushes a pending save first).
                h.ticks_left += 1;
                h.ticks(1);
                let before = h.config();
                let boot = match c.u8() % 3 {
                    0 => None,
                    1 => Some(Level::Low),
                    _ => Some(Level::High),
                };
                h.power_cycle(boot);
                assert_eq!(
                    h.config(),
                    expected_after_boot(before),
                    "FLASH_CONFIG kept over a power cycle"
                );
            }
            8 => {
                // A FLASH_CONFIG write whose save is cut at step k (torn):
                // afterwards the old or the new image, nothing else.
                h.ticks_left += 1;
                h.ticks(1);
                let old = h.config();
                let offset = 12 + 4 * (c.u16() % 60);
                let value = c.u32().to_le_bytes();
                h.rx(&isb_set(isb::did::FLASH_CONFIG, offset, &value));
                let new = h.config();
                let k = u32::from(c.u16() % 200);
                let seed = c.u32();
                h.dev.flash_mut().cut_power_torn(k, seed);
                h.ticks_left += 1;
                h.ticks(1);
                h.power_cycle(None);
                let got = h.config();
                assert!(
                    got == expected_after_boot(old) || got == expected_after_boot(new),
                    "a cut save left a third image"
                );
            }
            9 => {
                let n = usize::from(c.u16() % 600);
                h.read_tx(n);
                h.invariants();
            }
            _ => {
                let code = [1u32, 5, 97, 99, 0][usize::from(c.u8()) % 5];
                let cmd = isb::sets::SystemCommand::new(code);
                h.rx(&isb_set(isb::did::SYS_CMD, 0, &cmd.encode()));
            }
        }
    }
    h.power_cycle(None);
}
