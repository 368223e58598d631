//! The parameter store (ICD 5.3.7 SaveFlash persistence) survives a power
//! cut at every program/erase step of a save, never loads garbage from any
//! flash contents, and respects `WRITE_SIZE`/`READ_SIZE` alignment.

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashError, NorFlashErrorKind,
    ReadNorFlash,
};
use imu_emu::nor::RamNor;
use imu_emu::store::{
    Image, ImageSpec, KernelImage, ParamStore, StoreError, KERNEL_IMAGE, PARAM_BLOCK_LEN,
};
use proptest::prelude::*;

mod common;
use common::xorshift::XorShift;

type Block = [u8; PARAM_BLOCK_LEN];
type Nor = RamNor<8192>;

const SECTOR: usize = 4096;
/// Steps of one save on `RamNor` (WRITE_SIZE 4): 1 erase + 0x610 / 4 header
/// and block words + 1 commit word.
const SAVE_STEPS: u32 = 1 + 0x610 / 4 + 1;

/// [`XorShift`] bytes as a parameter block.
trait Blocks {
    fn block(&mut self) -> Block;
}

impl Blocks for XorShift {
    fn block(&mut self) -> Block {
        self.bytes()
    }
}

/// OLD and NEW differ in most bytes — every bit of those flips, so plenty
/// of bits go 0→1 as well as 1→0 — and agree on every 7th byte.
fn old_and_new() -> (Block, Block) {
    let old = XorShift(0x1234_5678).block();
    let mut new = old;
    for (i, b) in new.iter_mut().enumerate() {
        if !i.is_multiple_of(7) {
            *b = !*b;
        }
    }
    (old, new)
}

/// The newest image of any spec, as a `Vec`.
fn load_img<F: NorFlash, I: Image + Copy>(store: &ParamStore<I>, flash: &mut F) -> Option<Vec<u8>> {
    let mut out = vec![0; usize::from(store.spec().len)];
    store
        .load(flash, &mut out)
        .expect("load never fails on a powered flash")
        .then_some(out)
}

fn load<F: NorFlash>(store: &ParamStore, flash: &mut F) -> Option<Block> {
    let mut out = [0; PARAM_BLOCK_LEN];
    store
        .load(flash, &mut out)
        .expect("load never fails on a powered flash")
        .then_some(out)
}

/// A flash whose power can be cut after a number of steps.
trait Sim: NorFlash + Clone {
    fn cut_power_after(&mut self, steps: u32);
    fn restore_power(&mut self);
    fn steps(&self) -> u32;
    fn image(&self) -> &[u8];
}

impl<const N: usize> Sim for RamNor<N> {
    fn cut_power_after(&mut self, steps: u32) {
        RamNor::cut_power_after(self, steps)
    }
    fn restore_power(&mut self) {
        RamNor::restore_power(self)
    }
    fn steps(&self) -> u32 {
        RamNor::steps(self)
    }
    fn image(&self) -> &[u8] {
        RamNor::image(self)
    }
}

/// Test-only flash with `WRITE_SIZE` `W`, `READ_SIZE` `R` and `ERASE_SIZE`
/// `E` over a `RamNor` (whose 4-byte program steps and power cuts it
/// inherits); it rejects every access not aligned to its own sizes.
#[derive(Clone, Debug)]
struct Wide<const W: usize, const R: usize, const E: usize = 4096>(RamNor<16384>);

impl<const W: usize, const R: usize, const E: usize> Wide<W, R, E> {
    fn new() -> Self {
        Wide(RamNor::new())
    }
}

impl<const W: usize, const R: usize, const E: usize> ErrorType for Wide<W, R, E> {
    type Error = NorFlashErrorKind;
}

impl<const W: usize, const R: usize, const E: usize> ReadNorFlash for Wide<W, R, E> {
    const READ_SIZE: usize = R;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        self.0.read(offset, bytes).map_err(|e| e.kind())
    }

    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<const W: usize, const R: usize, const E: usize> NorFlash for Wide<W, R, E> {
    const WRITE_SIZE: usize = W;
    const ERASE_SIZE: usize = E;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        self.0.erase(from, to).map_err(|e| e.kind())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        self.0.write(offset, bytes).map_err(|e| e.kind())
    }
}

impl<const W: usize, const R: usize, const E: usize> Sim for Wide<W, R, E> {
    fn cut_power_after(&mut self, steps: u32) {
        self.0.cut_power_after(steps)
    }
    fn restore_power(&mut self) {
        self.0.restore_power()
    }
    fn steps(&self) -> u32 {
        self.0.steps()
    }
    fn image(&self) -> &[u8] {
        self.0.image()
    }
}

/// Which sector (0 = A, 1 = B) of the store at `base` holds header `seq`
/// with the "KPRM" magic, per the format documented in `imu_emu::store`.
fn sector_seq(image: &[u8], base: usize, sector: usize) -> Option<u32> {
    spec_sector_seq(&KERNEL_IMAGE, image, base, sector)
}

/// [`sector_seq`] for the image `spec`.
fn spec_sector_seq(spec: &ImageSpec, image: &[u8], base: usize, sector: usize) -> Option<u32> {
    let h = &image[base + sector * SECTOR..][..8];
    (h[..4] == spec.magic).then(|| u32::from_le_bytes(h[4..8].try_into().unwrap()))
}

// ---------------------------------------------------------------- basics

#[test]
fn fresh_flash_loads_nothing() {
    let mut f = Nor::new();
    let mut out = [0x5A; PARAM_BLOCK_LEN];
    assert_eq!(ParamStore::new(0).load(&mut f, &mut out), Ok(false));
    assert_eq!(out, [0x5A; PARAM_BLOCK_LEN], "block untouched on Ok(false)");
}

#[test]
fn save_then_load_round_trips() {
    let (old, _) = old_and_new();
    let store = ParamStore::new(0);
    let mut f = Nor::new();
    store.save(&mut f, &old).unwrap();
    assert_eq!(load(&store, &mut f), Some(old));
    // all-zero and all-0xFF blocks too
    for b in [[0u8; PARAM_BLOCK_LEN], [0xFF; PARAM_BLOCK_LEN]] {
        store.save(&mut f, &b).unwrap();
        assert_eq!(load(&store, &mut f), Some(b));
    }
}

#[test]
fn three_saves_alternate_sectors_and_load_returns_the_last() {
    let mut rng = XorShift(7);
    let store = ParamStore::new(0);
    let mut f = Nor::new();
    let blocks = [rng.block(), rng.block(), rng.block()];
    let expect = [[Some(0), None], [Some(0), Some(1)], [Some(2), Some(1)]];
    for (b, seqs) in blocks.iter().zip(expect) {
        store.save(&mut f, b).unwrap();
        assert_eq!(
            [sector_seq(f.image(), 0, 0), sector_seq(f.image(), 0, 1)],
            seqs
        );
        assert_eq!(load(&store, &mut f), Some(*b));
    }
}

#[test]
fn save_steps_are_one_erase_and_one_program_per_word() {
    let (old, new) = old_and_new();
    let store = ParamStore::new(0);
    let mut f = Nor::new();
    for b in [old, new, old] {
        let before = f.steps();
        store.save(&mut f, &b).unwrap();
        assert_eq!(f.steps() - before, SAVE_STEPS);
    }
    assert_eq!(SAVE_STEPS, 390);
}

#[test]
fn store_stays_inside_its_footprint() {
    // Store at 4096 in a 16 KiB flash: sectors 0 and 3 must keep their bytes.
    let mut img = [0u8; 16384];
    XorShift(99).fill(&mut img);
    let mut f = RamNor::<16384>::from_image(&img);
    let store = ParamStore::new(4096);
    assert_eq!(ParamStore::footprint::<RamNor<16384>>(), 8192);
    assert_eq!(load(&store, &mut f), None);
    let (old, new) = old_and_new();
    for b in [old, new, old] {
        store.save(&mut f, &b).unwrap();
        assert_eq!(load(&store, &mut f), Some(b));
    }
    assert_eq!(&f.image()[..4096], &img[..4096]);
    assert_eq!(&f.image()[12288..], &img[12288..]);
}

#[test]
fn bad_geometry_is_an_error_not_a_panic() {
    let mut out = [0; PARAM_BLOCK_LEN];
    let b = [0; PARAM_BLOCK_LEN];
    let mut f = Nor::new();
    // second sector past the end
    assert_eq!(
        ParamStore::new(4096).load(&mut f, &mut out),
        Err(StoreError::OutOfBounds)
    );
    assert_eq!(
        ParamStore::new(4096).save(&mut f, &b),
        Err(StoreError::OutOfBounds)
    );
    // offset arithmetic overflowing u32
    assert_eq!(
        ParamStore::new(0xFFFF_F000).load(&mut f, &mut out),
        Err(StoreError::OutOfBounds)
    );
    // base not on a sector boundary
    assert_eq!(
        ParamStore::new(100).save(&mut f, &b),
        Err(StoreError::Flash(NorFlashErrorKind::NotAligned))
    );
    // a 1 KiB sector cannot hold header + 0x600 bytes + commit
    let mut small = Wide::<4, 1, 1024>::new();
    assert_eq!(
        ParamStore::new(0).load(&mut small, &mut out),
        Err(StoreError::SectorTooSmall)
    );
    assert_eq!(
        ParamStore::new(0).save(&mut small, &b),
        Err(StoreError::SectorTooSmall)
    );
    // a program unit that does not divide the 256-byte buffer
    let mut odd = Wide::<12, 1>::new();
    assert_eq!(
        ParamStore::new(0).save(&mut odd, &b),
        Err(StoreError::Flash(NorFlashErrorKind::NotAligned))
    );
    assert_eq!(f.image(), Nor::new().image(), "nothing was written");
}

// ---------------------------------------------------------------- power cuts

/// Saves `new` over a flash holding `old` (or nothing) with the power cut
/// after every k in 0..=S+1 steps; after power-on the store must hold
/// exactly `old` or exactly `new`, the sector holding `old` must be
/// byte-for-byte untouched, and a later save must work. Returns S.
fn exhaustive_power_cut<F: Sim>(
    flash: &F,
    base: usize,
    old: Option<Block>,
    new: Block,
    next: Block,
) -> u32 {
    spec_power_cut(
        KERNEL_IMAGE,
        flash,
        base,
        old.as_ref().map(|b| &b[..]),
        &new,
        &next,
    )
}

/// [`exhaustive_power_cut`] for the image `image` (blocks of its length).
fn spec_power_cut<F: Sim, I: Image + Copy>(
    image: I,
    flash: &F,
    base: usize,
    old: Option<&[u8]>,
    new: &[u8],
    next: &[u8],
) -> u32 {
    let store = ParamStore::for_image(base as u32, image);
    let spec = store.spec();
    let mut probe = flash.clone();
    assert_eq!(load_img(&store, &mut probe).as_deref(), old, "precondition");
    let old_sector = match (
        spec_sector_seq(&spec, flash.image(), base, 0),
        spec_sector_seq(&spec, flash.image(), base, 1),
    ) {
        (Some(a), Some(b)) => Some(if b > a { 1 } else { 0 }),
        (Some(_), None) => Some(0),
        (None, Some(_)) => Some(1),
        (None, None) => None,
    };
    assert_eq!(old_sector.is_some(), old.is_some());

    let before = probe.steps();
    store.save(&mut probe, new).unwrap();
    let s = probe.steps() - before;

    // Number of steps after which NEW must be loaded: the commit word's
    // program steps are the last ones; once the 4-byte marker itself is
    // fully programmed (maybe before its WRITE_SIZE padding) NEW is valid.
    let mut first_new = None;
    for k in 0..=s + 1 {
        let mut f = flash.clone();
        f.cut_power_after(k);
        let r = store.save(&mut f, new);
        if k < s {
            assert!(
                matches!(r, Err(StoreError::Flash(_))),
                "k={k}: a cut save must fail, got {r:?}"
            );
        } else {
            assert_eq!(r, Ok(()), "k={k}");
        }
        f.restore_power();
        let got = load_img(&store, &mut f);
        if got.as_deref() == Some(new) {
            first_new.get_or_insert(k);
        } else {
            assert_eq!(got.as_deref(), old, "k={k}: neither OLD nor NEW");
            assert!(first_new.is_none(), "k={k}: NEW appeared, then went away");
        }
        if let Some(i) = old_sector {
            let range = base + i * SECTOR..base + (i + 1) * SECTOR;
            assert_eq!(
                &f.image()[range.clone()],
                &flash.image()[range],
                "k={k}: the sector holding OLD was touched"
            );
        }
        // a later save still works
        store.save(&mut f, next).unwrap();
        assert_eq!(
            load_img(&store, &mut f).as_deref(),
            Some(next),
            "k={k}: save after cut"
        );
    }
    let first_new = first_new.expect("NEW after a complete save");
    assert!(first_new <= s, "NEW once k == S");
    // Only the commit word's steps can make NEW visible early (at most
    // WRITE_SIZE / 4 - 1 of them, for the marker's padding).
    assert!(
        s - first_new < (F::WRITE_SIZE as u32 / 4).max(1),
        "NEW visible before the commit: first at {first_new} of {s}"
    );
    s
}

/// A flash that has seen `prior` saves of other blocks and then a save of
/// `old` (so OLD sits in sector `prior % 2`).
fn holding<F: Sim>(flash: F, base: usize, prior: usize, old: &Block) -> F {
    spec_holding(KernelImage, flash, base, prior, old)
}

/// [`holding`] for the image `spec`.
fn spec_holding<F: Sim, I: Image + Copy>(
    image: I,
    mut flash: F,
    base: usize,
    prior: usize,
    old: &[u8],
) -> F {
    let store = ParamStore::for_image(base as u32, image);
    let spec = store.spec();
    let mut rng = XorShift(0xC0FF_EE00 + prior as u32);
    for _ in 0..prior {
        let mut b = vec![0; old.len()];
        rng.fill(&mut b);
        store.save(&mut flash, &b).unwrap();
    }
    store.save(&mut flash, old).unwrap();
    assert_eq!(
        spec_sector_seq(&spec, flash.image(), base, prior % 2),
        Some(prior as u32)
    );
    flash
}

#[test]
fn power_cut_at_every_step_leaves_old_or_new() {
    let (old, new) = old_and_new();
    let next = XorShift(42).block();
    // fresh flash: nothing or NEW
    let s = exhaustive_power_cut(&Nor::new(), 0, None, new, next);
    assert_eq!(s, SAVE_STEPS);
    // OLD in sector A (0, 2 prior saves) and in sector B (1, 3 prior saves)
    for prior in 0..4 {
        let flash = holding(Nor::new(), 0, prior, &old);
        let s = exhaustive_power_cut(&flash, 0, Some(old), new, next);
        assert_eq!(s, SAVE_STEPS, "prior={prior}");
    }
}

#[test]
fn power_cut_at_every_step_with_the_store_at_an_offset() {
    let (old, new) = old_and_new();
    let next = XorShift(43).block();
    for prior in 0..2 {
        let flash = holding(RamNor::<16384>::new(), 8192, prior, &old);
        exhaustive_power_cut(&flash, 8192, Some(old), new, next);
    }
}

#[test]
fn with_write_size_4_a_cut_save_never_shows_new() {
    // On RamNor the commit is a single word, so every k < S loads OLD.
    let (old, new) = old_and_new();
    let store = ParamStore::new(0);
    let flash = holding(Nor::new(), 0, 1, &old);
    for k in 0..SAVE_STEPS {
        let mut f = flash.clone();
        f.cut_power_after(k);
        assert!(store.save(&mut f, &new).is_err());
        f.restore_power();
        assert_eq!(load(&store, &mut f), Some(old), "k={k}");
    }
}

#[test]
fn repeated_cuts_never_lose_the_last_loaded_block() {
    // A long run of saves, each cut at a pseudo-random step (some complete):
    // what loads is always the last block that loaded, or the one attempted.
    let store = ParamStore::new(0);
    let mut rng = XorShift(2024);
    let mut f = Nor::new();
    let mut current: Option<Block> = None;
    for round in 0..300 {
        let attempt = rng.block();
        let k = rng.next() % (SAVE_STEPS + 40);
        f.cut_power_after(k);
        let r = store.save(&mut f, &attempt);
        assert_eq!(r.is_ok(), k >= SAVE_STEPS, "round {round}");
        f.restore_power();
        let got = load(&store, &mut f);
        assert!(
            got == current || got == Some(attempt),
            "round {round}, k={k}: lost the block"
        );
        current = got;
    }
    assert!(current.is_some());
}

// ---------------------------------------------------------------- other images

/// A second, differently sized image, shaped like the ISB FLASH_CONFIG
/// image (288 bytes and a few more): 301 bytes, so `16 + 301` needs
/// `WRITE_SIZE` padding; version 1, so its length word is not plain.
const OTHER: ImageSpec = ImageSpec {
    len: 301,
    magic: *b"ISBC",
    version: 1,
};
/// Steps of one OTHER save on `RamNor`: 1 erase + (16 + 301 → 320) / 4
/// words + 1 commit word.
const OTHER_STEPS: u32 = 1 + 320 / 4 + 1;

fn other_block(seed: u32) -> Vec<u8> {
    let mut b = vec![0; usize::from(OTHER.len)];
    XorShift(seed).fill(&mut b);
    b
}

/// CRC-32/ISO-HDLC, as the format documents it.
fn crc32(parts: &[&[u8]]) -> u32 {
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
    let mut d = crc.digest();
    for p in parts {
        d.update(p);
    }
    d.finalize()
}

#[test]
fn a_kernel_sector_in_the_documented_format_loads() {
    // Built by hand from the format (the layout before the store was made
    // generic): an existing `--flash` file keeps loading.
    let (old, _) = old_and_new();
    let mut img = [0xFFu8; 8192];
    img[0..4].copy_from_slice(b"KPRM");
    img[4..8].copy_from_slice(&7u32.to_le_bytes());
    img[8..12].copy_from_slice(&0x600u32.to_le_bytes());
    let crc = crc32(&[&img[0..12], &old]);
    img[12..16].copy_from_slice(&crc.to_le_bytes());
    img[16..0x610].copy_from_slice(&old);
    img[0x610..0x614].copy_from_slice(&0x5AFE_C0DEu32.to_le_bytes());
    let mut f = Nor::from_image(&img);
    let store = ParamStore::new(0);
    assert_eq!(load(&store, &mut f), Some(old));
    // And what the store writes over it is that format, seq + 1, in B.
    store.save(&mut f, &old).unwrap();
    assert_eq!(
        &f.image()[SECTOR..SECTOR + 0x614],
        {
            let mut b = img[..0x614].to_vec();
            b[4..8].copy_from_slice(&8u32.to_le_bytes());
            let crc = crc32(&[&b[0..12], &old]);
            b[12..16].copy_from_slice(&crc.to_le_bytes());
            b
        }
        .as_slice()
    );
}

#[test]
fn another_image_writes_its_own_header_and_round_trips() {
    let store = ParamStore::for_image(0, OTHER);
    let mut f = Nor::new();
    assert_eq!(load_img(&store, &mut f), None);
    let b = other_block(3);
    let before = f.steps();
    store.save(&mut f, &b).unwrap();
    assert_eq!(f.steps() - before, OTHER_STEPS);
    assert_eq!(OTHER_STEPS, 82);
    let img = f.image();
    assert_eq!(&img[0..4], b"ISBC");
    assert_eq!(&img[4..8], &0u32.to_le_bytes());
    assert_eq!(&img[8..12], &0x0001_012Du32.to_le_bytes(), "301 | 1 << 16");
    assert_eq!(&img[12..16], &crc32(&[&img[0..12], &b]).to_le_bytes());
    assert_eq!(&img[16..317], &b[..]);
    assert_eq!(&img[317..320], &[0xFF; 3], "padding to WRITE_SIZE");
    assert_eq!(&img[320..324], &0x5AFE_C0DEu32.to_le_bytes());
    assert!(img[324..].iter().all(|&x| x == 0xFF));
    assert_eq!(load_img(&store, &mut f), Some(b.clone()));
    // The wrong buffer length is refused, not truncated.
    assert_eq!(
        store.save(&mut f, &[0u8; PARAM_BLOCK_LEN]),
        Err(StoreError::ImageLength)
    );
    assert_eq!(
        store.load(&mut f, &mut [0u8; 300]),
        Err(StoreError::ImageLength)
    );
    // Another version or magic of the same length loads nothing.
    for spec in [
        ImageSpec {
            version: 2,
            ..OTHER
        },
        ImageSpec {
            version: 0,
            ..OTHER
        },
        ImageSpec {
            magic: *b"ISBD",
            ..OTHER
        },
    ] {
        let other = ParamStore::for_image(0, spec);
        assert_eq!(load_img(&other, &mut f), None, "{spec:?}");
    }
    // The KERNEL store over these sectors sees nothing either, and vice versa.
    assert_eq!(load(&ParamStore::new(0), &mut f), None);
    let mut k = Nor::new();
    ParamStore::new(0).save(&mut k, &old_and_new().0).unwrap();
    assert_eq!(load_img(&store, &mut k), None);
}

#[test]
fn another_image_survives_a_power_cut_at_every_step() {
    let (old, new, next) = (other_block(10), other_block(11), other_block(12));
    let s = spec_power_cut(OTHER, &Nor::new(), 0, None, &new, &next);
    assert_eq!(s, OTHER_STEPS);
    for prior in 0..4 {
        let flash = spec_holding(OTHER, Nor::new(), 0, prior, &old);
        let s = spec_power_cut(OTHER, &flash, 0, Some(&old), &new, &next);
        assert_eq!(s, OTHER_STEPS, "prior={prior}");
    }
    // At an offset, and on wider program units (padding of 317 bytes).
    for prior in 0..2 {
        let flash = spec_holding(OTHER, RamNor::<16384>::new(), 8192, prior, &old);
        spec_power_cut(OTHER, &flash, 8192, Some(&old), &new, &next);
    }
    for prior in 0..2 {
        let flash = spec_holding(OTHER, Wide::<8, 1>::new(), 0, prior, &old);
        assert_eq!(
            spec_power_cut(OTHER, &flash, 0, Some(&old), &new, &next),
            1 + 320 / 4 + 2
        );
        let flash = spec_holding(OTHER, Wide::<32, 8>::new(), 0, prior, &old);
        assert_eq!(
            spec_power_cut(OTHER, &flash, 0, Some(&old), &new, &next),
            1 + 320 / 4 + 8
        );
        let flash = spec_holding(OTHER, Wide::<256, 256>::new(), 0, prior, &old);
        assert_eq!(
            spec_power_cut(OTHER, &flash, 0, Some(&old), &new, &next),
            1 + 512 / 4 + 64
        );
    }
}

#[test]
fn two_images_share_one_flash_and_a_cut_of_one_never_touches_the_other() {
    // KERNEL at 0 (sectors 0–1), OTHER at 8192 (sectors 2–3) of 16 KiB.
    let kernel = ParamStore::new(0);
    let other = ParamStore::for_image(8192, OTHER);
    let (k_old, k_new) = old_and_new();
    let k_next = XorShift(77).block();
    let (o_old, o_new, o_next) = (other_block(20), other_block(21), other_block(22));
    for prior in 0..2 {
        // Both hold an image (OLD in sector `prior % 2` of each).
        let flash = holding(RamNor::<16384>::new(), 0, prior, &k_old);
        let flash = spec_holding(OTHER, flash, 8192, prior, &o_old);
        // Cut a KERNEL save at every step: OTHER's sectors stay byte for
        // byte and keep loading OLD.
        spec_power_cut(KERNEL_IMAGE, &flash, 0, Some(&k_old), &k_new, &k_next);
        spec_power_cut(OTHER, &flash, 8192, Some(&o_old), &o_new, &o_next);
        let s = {
            let mut f = flash.clone();
            let before = f.steps();
            kernel.save(&mut f, &k_new).unwrap();
            f.steps() - before
        };
        for k in 0..=s {
            let mut f = flash.clone();
            f.cut_power_after(k);
            let _ = kernel.save(&mut f, &k_new);
            f.restore_power();
            assert_eq!(&f.image()[8192..], &flash.image()[8192..], "k={k}");
            assert_eq!(load_img(&other, &mut f), Some(o_old.clone()), "k={k}");
            // …and a cut OTHER save leaves the KERNEL's sectors alone.
            let g = f.clone();
            let got_k = load(&kernel, &mut f);
            f.cut_power_after(k % (OTHER_STEPS + 1));
            let _ = other.save(&mut f, &o_new);
            f.restore_power();
            assert_eq!(&f.image()[..8192], &g.image()[..8192], "k={k}");
            assert_eq!(load(&kernel, &mut f), got_k, "k={k}");
            let o = load_img(&other, &mut f);
            assert!(
                o == Some(o_old.clone()) || o == Some(o_new.clone()),
                "k={k}"
            );
        }
    }
    // Each store pointed at the other's sectors loads nothing.
    let mut f = holding(RamNor::<16384>::new(), 0, 0, &k_old);
    let mut f2 = spec_holding(OTHER, f.clone(), 8192, 0, &o_old);
    assert_eq!(load_img(&ParamStore::for_image(0, OTHER), &mut f2), None);
    assert_eq!(load(&ParamStore::new(8192), &mut f2), None);
    assert_eq!(load(&kernel, &mut f), Some(k_old));
}

// ---------------------------------------------------------------- garbage

#[test]
fn xorshift_garbage_loads_nothing_and_can_be_saved_over() {
    let store = ParamStore::new(0);
    for seed in 1..=64u32 {
        let mut img = [0u8; 8192];
        XorShift(seed.wrapping_mul(0x9E37_79B9) | 1).fill(&mut img);
        let mut f = Nor::from_image(&img);
        assert_eq!(load(&store, &mut f), None, "seed {seed}");
        let b = XorShift(seed).block();
        store.save(&mut f, &b).unwrap();
        assert_eq!(load(&store, &mut f), Some(b), "seed {seed}");
    }
}

#[test]
fn garbage_next_to_a_valid_sector_is_ignored_then_replaced() {
    let (old, new) = old_and_new();
    let store = ParamStore::new(0);
    let mut f = Nor::new();
    store.save(&mut f, &old).unwrap(); // sector A
    let mut img = *f.image();
    XorShift(5).fill(&mut img[SECTOR..]);
    img[SECTOR..SECTOR + 4].copy_from_slice(b"KPRM"); // even with the magic
    img[SECTOR + 0x610..SECTOR + 0x614].copy_from_slice(&0x5AFE_C0DEu32.to_le_bytes());
    let mut f = Nor::from_image(&img);
    assert_eq!(load(&store, &mut f), Some(old));
    store.save(&mut f, &new).unwrap();
    assert_eq!(sector_seq(f.image(), 0, 1), Some(1), "went to sector B");
    assert_eq!(load(&store, &mut f), Some(new));
}

proptest! {
    #[test]
    fn arbitrary_flash_contents_load_nothing(img in proptest::collection::vec(any::<u8>(), 8192)) {
        let store = ParamStore::new(0);
        let mut f = Nor::from_image(&img);
        let mut out = [0; PARAM_BLOCK_LEN];
        prop_assert_eq!(store.load(&mut f, &mut out), Ok(false));
        // and a save over it works
        let b = XorShift(img[0] as u32 + 1).block();
        store.save(&mut f, &b).unwrap();
        prop_assert_eq!(load(&store, &mut f), Some(b));
    }

    #[test]
    fn corrupted_images_load_a_real_block_or_nothing(
        flips in proptest::collection::vec((0usize..8192, 1u8..=255), 1..8),
        prior in 0usize..2,
    ) {
        let (old, new) = old_and_new();
        let store = ParamStore::new(0);
        let mut f = holding(Nor::new(), 0, prior, &old);
        store.save(&mut f, &new).unwrap();
        let mut img = *f.image();
        for (at, mask) in &flips {
            img[*at] ^= mask;
        }
        let mut f = Nor::from_image(&img);
        let got = load(&store, &mut f);
        prop_assert!(got.is_none() || got == Some(old) || got == Some(new));
        let next = XorShift(flips.len() as u32).block();
        store.save(&mut f, &next).unwrap();
        prop_assert_eq!(load(&store, &mut f), Some(next));
    }
}

// ---------------------------------------------------------------- alignment

fn wide_round_trip_and_cuts<const W: usize, const R: usize>() -> u32 {
    let (old, new) = old_and_new();
    let next = XorShift(44).block();
    let store = ParamStore::new(0);
    let mut f = Wide::<W, R>::new();
    assert_eq!(load(&store, &mut f), None);
    for b in [new, old, next] {
        store.save(&mut f, &b).unwrap();
        assert_eq!(load(&store, &mut f), Some(b));
    }
    let mut s = 0;
    for prior in 0..2 {
        let flash = holding(Wide::<W, R>::new(), 0, prior, &old);
        s = exhaustive_power_cut(&flash, 0, Some(old), new, next);
    }
    s
}

#[test]
fn write_size_8_read_size_1() {
    // 0x610 bytes = 194 units of 8, commit 8 bytes: 1 + 388 + 2 steps
    assert_eq!(wide_round_trip_and_cuts::<8, 1>(), 391);
}

#[test]
fn write_size_16_read_size_16() {
    assert_eq!(wide_round_trip_and_cuts::<16, 16>(), 1 + 388 + 4);
}

#[test]
fn write_size_32_read_size_8() {
    // 0x610 -> 0x620 with 0xFF padding, commit 32 bytes
    assert_eq!(wide_round_trip_and_cuts::<32, 8>(), 1 + 0x620 / 4 + 8);
}

#[test]
fn write_size_256_read_size_256() {
    // 0x610 -> 0x700, commit 256 bytes
    assert_eq!(wide_round_trip_and_cuts::<256, 256>(), 1 + 0x700 / 4 + 64);
}
