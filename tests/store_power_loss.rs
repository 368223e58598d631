//! Power-loss campaigns on the parameter store (power loss at any instant):
//! thousands of randomized save sequences on the NOR model with the power
//! cut at a random program/erase step — half-done steps and *torn* ones
//! ([`RamNor::cut_power_torn`]: a program that clears a random subset of its
//! bits, an erase that leaves part of the sector) — and after every
//! power-on:
//!
//! * what loads is the last acknowledged image or the one being saved when
//!   the power went (so every parameter holds a value that was saved, and
//!   the last acknowledged save is never lost);
//! * a save that returned `Ok` (the device's acknowledgement) loads;
//! * the store keeps working as the flash wears: erases spread over both
//!   sectors of each store, every erase accounted for, and clean saves keep
//!   succeeding after thousands of cut ones.
//!
//! Seeded loops (xorshift), so a failure names its round and replays.

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashError, NorFlashErrorKind,
    ReadNorFlash,
};
use imu_emu::device::{Device, PowerOn};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::Decoder;
use imu_emu::kernel::params::PARAMS;
use imu_emu::model::Product;
use imu_emu::nor::RamNor;
use imu_emu::store::{ImageSpec, ParamStore, KERNEL_IMAGE};
use imu_emu::time::Instant;
use imu_emu::Kernel;

mod common;
use common::xorshift::XorShift;

const SECTOR: usize = 4096;
/// Capacity of the campaign flash: two stores of two sectors each.
const CAP: usize = 16384;

/// A `RamNor` seen through `WRITE_SIZE` `W` / `READ_SIZE` `R` (alignment
/// enforced), counting the erases of each sector: the wear.
#[derive(Clone)]
struct Worn<const W: usize, const R: usize> {
    nor: RamNor<CAP>,
    erases: [u32; CAP / SECTOR],
}

impl<const W: usize, const R: usize> Worn<W, R> {
    fn new() -> Self {
        Worn {
            nor: RamNor::new(),
            erases: [0; CAP / SECTOR],
        }
    }
}

impl<const W: usize, const R: usize> ErrorType for Worn<W, R> {
    type Error = NorFlashErrorKind;
}

impl<const W: usize, const R: usize> ReadNorFlash for Worn<W, R> {
    const READ_SIZE: usize = R;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        self.nor.read(offset, bytes).map_err(|e| e.kind())
    }

    fn capacity(&self) -> usize {
        CAP
    }
}

impl<const W: usize, const R: usize> NorFlash for Worn<W, R> {
    const WRITE_SIZE: usize = W;
    const ERASE_SIZE: usize = SECTOR;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        if !self.nor.power_lost() {
            // The erase starts (and wears the sector) even if it is cut.
            for s in from as usize / SECTOR..to as usize / SECTOR {
                self.erases[s] += 1;
            }
        }
        self.nor.erase(from, to).map_err(|e| e.kind())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        self.nor.write(offset, bytes).map_err(|e| e.kind())
    }
}

/// A 301-byte image shaped like the ISB FLASH_CONFIG one.
const OTHER: ImageSpec = ImageSpec {
    len: 301,
    magic: *b"ISBC",
    version: 1,
};

/// One store's campaign state.
struct Track {
    store: ParamStore<ImageSpec>,
    /// What loads now (the model of the flash contents).
    current: Option<Vec<u8>>,
    /// Steps of one save on this flash.
    steps: u32,
    /// Erases started on this store's sectors.
    erases_started: u32,
}

/// Outcome counts, to show the campaign exercised what it claims.
#[derive(Debug, Default)]
struct Stats {
    saves: u32,
    acked: u32,
    cuts: u32,
    torn: u32,
    old_after_cut: u32,
    new_after_cut: u32,
}

/// The next image: the current one (or zeros) with 1–3 "parameters"
/// (1, 2, 4 or 12 bytes at a random offset) changed; now and then the same
/// image again, or an entirely new one.
fn mutate(rng: &mut XorShift, current: Option<&Vec<u8>>, len: usize) -> Vec<u8> {
    let mut next = current.cloned().unwrap_or_else(|| vec![0; len]);
    match rng.below(32) {
        0 => {}
        1 => rng.fill(&mut next),
        _ => {
            for _ in 0..=rng.below(3) {
                let n = [1, 2, 4, 12][rng.below(4) as usize].min(len);
                let at = rng.below((len - n + 1) as u32) as usize;
                rng.fill(&mut next[at..at + n]);
            }
        }
    }
    next
}

fn load<F: NorFlash>(store: &ParamStore<ImageSpec>, flash: &mut F) -> Option<Vec<u8>> {
    let mut out = vec![0; usize::from(store.spec().len)];
    store
        .load(flash, &mut out)
        .expect("a powered flash always loads")
        .then_some(out)
}

/// `rounds` randomized saves alternating at random between the stores of
/// `specs` (each at its own base in one flash), each cut with probability
/// 3/4 at a random step (torn with probability 1/2).
fn campaign<const W: usize, const R: usize>(
    specs: &[(u32, ImageSpec)],
    rounds: u32,
    seed: u32,
) -> Stats {
    let mut rng = XorShift(seed);
    let mut flash = Worn::<W, R>::new();
    let mut tracks: Vec<Track> = specs
        .iter()
        .map(|&(base, spec)| {
            let store = ParamStore::for_image(base, spec);
            // Steps of one save: measured on a scratch flash.
            let mut scratch = Worn::<W, R>::new();
            store
                .save(&mut scratch, &vec![0; usize::from(spec.len)])
                .unwrap();
            Track {
                store,
                current: None,
                steps: scratch.nor.steps(),
                erases_started: 0,
            }
        })
        .collect();
    let mut stats = Stats::default();
    for round in 0..rounds {
        let which = rng.below(tracks.len() as u32) as usize;
        let t = &mut tracks[which];
        let len = usize::from(t.store.spec().len);
        let attempt = mutate(&mut rng, t.current.as_ref(), len);
        let cut = match rng.below(4) {
            0 => None,
            1 => Some((rng.below(t.steps), false)),
            _ => Some((rng.below(t.steps + 2), true)),
        };
        match cut {
            Some((k, false)) => flash.nor.cut_power_after(k),
            Some((k, true)) => flash.nor.cut_power_torn(k, rng.next()),
            None => {}
        }
        let erases_before: u32 = flash.erases.iter().sum();
        let r = t.store.save(&mut flash, &attempt);
        let erases_after: u32 = flash.erases.iter().sum();
        t.erases_started += erases_after - erases_before;
        let was_cut = flash.nor.power_lost();
        flash.nor.restore_power();
        stats.saves += 1;
        match cut {
            Some((k, _)) if k < t.steps => {
                assert!(was_cut, "round {round}: cut at {k} of {}", t.steps);
                assert!(r.is_err(), "round {round}: a cut save is not acknowledged");
            }
            _ => {
                assert!(!was_cut);
                assert_eq!(r, Ok(()), "round {round}");
            }
        }
        if was_cut {
            stats.cuts += 1;
            stats.torn += u32::from(matches!(cut, Some((_, true))));
        } else {
            stats.acked += 1;
        }
        // Power-on: every store loads what it had or, for the one being
        // saved, the attempt — never anything else, never nothing once an
        // image was acknowledged.
        for (i, t) in tracks.iter_mut().enumerate() {
            let got = load(&t.store, &mut flash);
            if i != which {
                assert_eq!(got, t.current, "round {round}: store {i} changed");
                continue;
            }
            if !was_cut {
                assert_eq!(got.as_ref(), Some(&attempt), "round {round}: acked");
            } else if got.as_ref() == Some(&attempt) && t.current.as_ref() != Some(&attempt) {
                stats.new_after_cut += 1;
            } else {
                assert_eq!(got, t.current, "round {round}: neither old nor new");
                stats.old_after_cut += 1;
            }
            t.current = got;
        }
    }
    // Wear: every erase is one the store started, both sectors of each
    // store took their share, and clean saves keep working.
    for t in &tracks {
        let first = t.store.base() as usize / SECTOR;
        let (a, b) = (flash.erases[first], flash.erases[first + 1]);
        assert_eq!(a + b, t.erases_started, "erases accounted for");
        assert!(
            a.min(b) * 3 > a.max(b),
            "wear spread over both sectors: {a} / {b}"
        );
    }
    for round in 0..50 {
        for t in tracks.iter_mut() {
            let len = usize::from(t.store.spec().len);
            let next = mutate(&mut rng, t.current.as_ref(), len);
            t.store.save(&mut flash, &next).unwrap();
            assert_eq!(load(&t.store, &mut flash), Some(next.clone()), "{round}");
            t.current = Some(next);
        }
    }
    stats
}

fn check(stats: &Stats, rounds: u32) {
    eprintln!("{stats:?}");
    assert_eq!(stats.saves, rounds);
    assert!(stats.cuts > rounds / 2, "{stats:?}");
    assert!(stats.torn > rounds / 3, "{stats:?}");
    assert!(stats.acked > rounds / 5, "{stats:?}");
    assert!(stats.old_after_cut > rounds / 3, "{stats:?}");
}

#[test]
fn kernel_image_on_ram_nor_geometry() {
    let rounds = 3000;
    let s = campaign::<4, 1>(&[(0, KERNEL_IMAGE)], rounds, 0x5EED_0001);
    check(&s, rounds);
    // With a one-word commit, a cut save never shows the new image.
    assert_eq!(s.new_after_cut, 0, "{s:?}");
}

#[test]
fn two_images_sharing_one_flash() {
    let rounds = 3000;
    let s = campaign::<4, 1>(&[(0, KERNEL_IMAGE), (8192, OTHER)], rounds, 0x5EED_0002);
    check(&s, rounds);
}

#[test]
fn wide_program_units_where_a_cut_commit_can_complete() {
    // WRITE_SIZE 16 and 256: the commit word's padding takes several steps
    // after the marker itself, so a cut there already shows the new image.
    let rounds = 1500;
    let s = campaign::<16, 16>(&[(0, KERNEL_IMAGE), (8192, OTHER)], rounds, 0x5EED_0003);
    check(&s, rounds);
    let s = campaign::<256, 8>(&[(8192, KERNEL_IMAGE), (0, OTHER)], rounds, 0x5EED_0004);
    check(&s, rounds);
    assert!(s.new_after_cut > 0, "{s:?}");
}

// ---------------------------------------------------------------- device

/// Valid SaveFlash values on a K110 for a few parameters (id, candidates).
fn candidates() -> Vec<(u16, Vec<Vec<u8>>)> {
    let u16s = |v: &[u16]| v.iter().map(|x| x.to_le_bytes().to_vec()).collect();
    let u8s = |v: &[u8]| v.iter().map(|x| vec![*x]).collect();
    let f32s = |v: &[f32]| v.iter().map(|x| x.to_le_bytes().to_vec()).collect();
    vec![
        (0x0012, u16s(&[1, 50, 100, 200, 400, 1000, 2000])),
        (0x0014, u16s(&[0, 1, 2, 10, 30])),
        (0x03D7, u8s(&[0, 1, 2, 3, 4, 0xFF])),
        (0x03D0, u8s(&[0, 1, 2])),
        (0x03E1, u8s(&[0, 1])),
        (0x03DA, u16s(&[0, 400, 0xFFFF])),
        (0x05FE, u16s(&[0, 5, 1000])),
        (0x05FB, u8s(&[0, 1])),
        (0x03EE, f32s(&[0.0, 0.1, 3.5])),
        (
            0x023A,
            [[0.0f32, 0.0, 0.0], [10.0, -5.0, 2.5], [-180.0, 90.0, 180.0]]
                .iter()
                .map(|a| a.iter().flat_map(|v| v.to_le_bytes()).collect())
                .collect(),
        ),
    ]
}

/// Every Table 5.24 parameter's RAM value.
fn params(dev: &Device<RamNor<8192>, Kernel>) -> Vec<Vec<u8>> {
    PARAMS
        .iter()
        .map(|p| dev.param_ram(p.id).unwrap().to_vec())
        .collect()
}

#[test]
fn device_save_flash_with_power_cuts_keeps_every_acknowledged_value() {
    // SaveFlash (ICD 5.3.7) through the device, the power cut (torn) at a
    // random step of the flash save, then a power cycle: every parameter
    // holds its last acknowledged value, except that the one being saved
    // may hold the new value; an acknowledgement means the value is there.
    let product = Product::parse("K110").unwrap();
    let mut dev = Device::power_on_with(
        PowerOn {
            product,
            boot: None,
            seed: 3,
        },
        RamNor::<8192>::new(),
        Instant::ZERO,
    );
    let cands = candidates();
    let mut rng = XorShift(0xD0_0D1E);
    let mut acked = params(&dev);
    let mut reader = Decoder::<512>::new();
    let mut buf = [0u8; 512];
    let (mut cuts, mut acks) = (0, 0);
    for round in 0..400u64 {
        let (id, values) = &cands[rng.below(cands.len() as u32) as usize];
        let value = &values[rng.below(values.len() as u32) as usize];
        let k = rng.below(400 + 40);
        dev.flash_mut().cut_power_torn(k, rng.next());
        let mut frame = [0u8; 64];
        let n = Command::SaveFlash {
            id: *id,
            len: value.len() as u16,
            value,
        }
        .encode(&mut frame)
        .unwrap();
        let now = Instant(round * 1_000_000);
        dev.on_rx(&frame[..n], now);
        let mut acknowledged = false;
        loop {
            let got = dev.poll_tx(&mut buf);
            if got == 0 {
                break;
            }
            let mut input = &buf[..got];
            while let Some(f) = reader.next_frame(&mut input) {
                assert_eq!(f.id, 0xB2, "round {round}: only the SaveFlash ack");
                assert_eq!(f.payload, &frame[n - 2..n]);
                acknowledged = true;
            }
        }
        let cut = dev.flash().power_lost();
        assert_eq!(
            acknowledged, !cut,
            "round {round}: ack iff the save completed"
        );
        dev.flash_mut().restore_power();
        dev.power_cycle(Instant(round * 1_000_000 + 500_000));
        while dev.poll_event().is_some() {}
        let now_params = params(&dev);
        let idx = PARAMS.iter().position(|p| p.id == *id).unwrap();
        for (i, (got, want)) in now_params.iter().zip(&acked).enumerate() {
            if i == idx {
                assert!(
                    got == want || got == value,
                    "round {round}: {} holds a value never saved",
                    PARAMS[i].name
                );
            } else {
                assert_eq!(got, want, "round {round}: {} changed", PARAMS[i].name);
            }
        }
        if acknowledged {
            assert_eq!(&now_params[idx], value, "round {round}: acked value lost");
            acks += 1;
        } else {
            cuts += 1;
        }
        acked = now_params;
    }
    assert!(cuts > 300 && acks > 10, "cuts {cuts}, acks {acks}");
}
