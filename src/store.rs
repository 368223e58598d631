//! Power-fail-safe parameter persistence over `embedded-storage` NorFlash
//! (the non-volatile side of ICD 5.3.7 SaveFlash).
//!
//! # Format
//!
//! [`ParamStore`] owns two consecutive erase sectors ("A" and "B") starting
//! at its `base` offset; a sector is `F::ERASE_SIZE` bytes. Each sector holds
//! one complete copy of the store's *image*, described by an [`ImageSpec`]
//! (length `L`, magic, version): for the KERNEL ([`KERNEL_IMAGE`],
//! [`ParamStore::new`]) the [`PARAM_BLOCK_LEN`]-byte parameter block of ICD
//! Table 5.24; another personality (the ISB FLASH_CONFIG image) brings its
//! own spec ([`ParamStore::for_image`]) and gets the same guarantees. The
//! store is generic over an [`Image`]: a type that fixes the spec
//! ([`KernelImage`], the default; the compiler then folds the layout into
//! constants, as small in firmware as a hard-wired layout) or an
//! [`ImageSpec`] value carried at run time.
//!
//! | offset                              | size             | content                                   |
//! |-------------------------------------|------------------|-------------------------------------------|
//! | 0                                   | 4                | magic (KERNEL: `"KPRM"`, `0x4D52_504B` LE) |
//! | 4                                   | 4                | sequence number `seq` (u32 LE)            |
//! | 8                                   | 4                | length word: `L` in bits 0–15, the version in bits 16–31 (LE); KERNEL: `0x0000_0600` |
//! | 12                                  | 4                | CRC-32 (LE), see below                    |
//! | 16                                  | `L` (KERNEL `0x600`) | the image                             |
//! | `C` = `16 + L` rounded up to `WRITE_SIZE` | `WRITE_SIZE` rounded up from 4 | commit marker `0x5AFE_C0DE` (LE), then `0xFF` padding |
//!
//! The KERNEL's spec has version 0, so its length word is the plain length
//! `0x600` and its sectors are byte for byte those of the store before it
//! was made generic: existing flash images (`--flash` files) load unchanged.
//!
//! The CRC is CRC-32/ISO-HDLC (the zlib/Ethernet CRC) over the first 12
//! header bytes (magic, seq, length word) followed by the image, so a bit
//! error in `seq` cannot silently reorder the two images. Bytes between the
//! image and `C` (when `16 + L` is not a multiple of `WRITE_SIZE`) are
//! `0xFF`.
//!
//! A sector is **valid** iff the magic, the length word (so the length *and*
//! the version), the commit marker (the exact 32-bit value) and the CRC all
//! match: a store never loads another spec's image — a different
//! personality's, or an older layout of its own (a personality bumps its
//! version when its image layout changes; the old image then loads as
//! "none", i.e. factory defaults). [`ParamStore::load`] returns
//! the valid sector with the newest `seq`; [`ParamStore::save`] erases the
//! *other* sector (sector A if neither is valid), programs header and block,
//! and programs the commit marker **last**, then reads the sector back.
//!
//! Sequence numbers are compared as serial numbers (RFC 1982 style:
//! `b` is newer than `a` iff `b.wrapping_sub(a)`, read as `i32`, is
//! positive; ties go to sector A). A save always writes `newest + 1`
//! (wrapping) into the sector that does not hold the newest image, so two
//! valid sectors always hold `n` and `n + 1` (mod 2³²) and the comparison is
//! exact even when `seq` passes `u32::MAX` → `0`. (Reaching that takes 2³²
//! saves, far beyond any flash's endurance, so in practice this only matters
//! for a crafted flash image — which is then still handled correctly rather
//! than pinning the store to a stale block.)
//!
//! # Why a power cut at any step is safe
//!
//! A save is: one sector erase, then header+block programs, then the commit
//! program. It never touches the sector holding the newest valid image, so
//! that image survives every interruption. The target sector becomes valid
//! only once its commit marker reads back exactly `0x5AFE_C0DE`:
//!
//! * cut during the erase: the save stops; the target sector was not the
//!   newest image, so whatever it now holds (half old, half `0xFF`, or even an
//!   intact *older* image) loses to — or is no rival of — the newest image;
//! * cut while programming header/block: the commit area is still erased
//!   (`0xFFFF_FFFF`), which is not the marker;
//! * cut while programming the commit word: NOR programming only clears bits,
//!   so a half-programmed word still has a `1` where the marker has a `0` and
//!   is not the exact marker (no marker byte is `0xFF`, so this also holds
//!   for a byte-wise flash that programs a prefix of the word);
//! * the commit completed: the new image is valid with `seq = newest + 1` and
//!   wins; the save is done (the read-back only confirms it).
//!
//! So after the next power-on [`ParamStore::load`] sees either the complete
//! old block or the complete new block, never a mix. A later save recovers
//! from any interrupted one, since it again erases the non-newest sector.
//! The test `tests/store_power_cut.rs` proves this exhaustively for every
//! step of a save on [`crate::nor::RamNor`], which models NOR semantics and
//! leaves the interrupted step half done. (What it cannot model — bits left
//! in a weak, read-unstable state by an interrupted program on real silicon —
//! is also caught by the CRC and the exact-marker check with overwhelming
//! probability.)
//!
//! # Why hand-written rather than `sequential-storage`
//!
//! `sequential-storage` 8 is async-only, over `embedded-storage-async`,
//! while this core is a synchronous sans-IO state machine driven from a
//! 2 kHz interrupt context. A whole-block A/B image is the simplest layout
//! whose safety can be proven exhaustively by a test, and it needs no heap
//! and only a 256-byte stack buffer. Wear: one sector erase per save,
//! alternating between the two sectors — fine for configuration writes.
//!
//! # Several images in one flash
//!
//! Each personality's store takes its own two sectors (its own `base`, at
//! least [`ParamStore::footprint`] apart); saves of one never touch the
//! other's sectors, and the magic keeps a store pointed at the wrong sectors
//! from loading them.
//!
//! # Flash geometry
//!
//! Writes go through a 256-byte stack buffer in chunks that are multiples of
//! `F::WRITE_SIZE` (the tail padded with `0xFF`); reads go through the same
//! kind of buffer, aligned to `F::READ_SIZE`. Both sizes must divide 256
//! (every common MCU flash: 1…256); other flashes get
//! `StoreError::Flash(NotAligned)`. `base` must be a multiple of
//! `F::ERASE_SIZE`, and a sector must fit header + image + commit word
//! ([`StoreError::SectorTooSmall`] otherwise). The buffer handed to
//! [`ParamStore::load`]/[`ParamStore::save`] must be exactly the spec's
//! length ([`StoreError::ImageLength`] otherwise).

use crc::{Crc, NoTable, CRC_32_ISO_HDLC};
use embedded_storage::nor_flash::{NorFlash, NorFlashError, NorFlashErrorKind};

/// Length of the KERNEL parameter block (ICD Table 5.24: IDs are byte
/// offsets; the highest, Hold-off_Time 0x05FE, ends at 0x0600).
pub const PARAM_BLOCK_LEN: usize = 0x600;

/// What a store persists: its image's length, magic and version (see the
/// module docs for the sector format they go into).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageSpec {
    /// Image length in bytes (at most `0xFFFF`: it shares the header's
    /// length word with the version).
    pub len: u16,
    /// Four bytes that mark a sector as this image's (header bytes 0–3).
    pub magic: [u8; 4],
    /// Layout version, in the length word's upper half; 0 keeps the length
    /// word the plain length (the KERNEL's original format).
    pub version: u16,
}

impl ImageSpec {
    /// The header's length word: `len | version << 16`.
    const fn len_word(&self) -> u32 {
        self.len as u32 | (self.version as u32) << 16
    }

    /// The magic read as a little-endian u32.
    const fn magic_word(&self) -> u32 {
        u32::from_le_bytes(self.magic)
    }
}

/// The KERNEL parameter block (ICD 5.3.7 SaveFlash, Table 5.24): 0x600
/// bytes, magic `"KPRM"`, version 0 — the format the store has always
/// written.
pub const KERNEL_IMAGE: ImageSpec = ImageSpec {
    len: PARAM_BLOCK_LEN as u16,
    magic: *b"KPRM",
    version: 0,
};
/// The commit marker, programmed last. Neither `0xFFFF_FFFF` (erased) nor
/// `0` (fully programmed), and no byte is `0xFF`.
const COMMIT: u32 = 0x5AFE_C0DE;
/// magic, seq, len, crc.
const HEADER_LEN: usize = 16;
/// The header bytes covered by the CRC (all but the CRC itself).
const HEADER_CRC_LEN: usize = 12;
/// The commit marker's size before `WRITE_SIZE` padding.
const COMMIT_LEN: usize = 4;
/// Stack buffer for reads and writes.
const CHUNK: usize = 256;

/// CRC-32/ISO-HDLC, bit by bit (`NoTable`): the 1 KiB lookup table cost
/// more flash than the firmware budget allows for a CRC that runs only at
/// load and SaveFlash over 1.5 KiB (≈ 12 000 shift/xor steps, well under a
/// millisecond on the MCUs, small beside a sector erase).
static CRC32: Crc<u32, NoTable> = Crc::<u32, NoTable>::new(&CRC_32_ISO_HDLC);

/// What a [`ParamStore`] persists: an [`ImageSpec`], either fixed by the
/// type ([`KernelImage`]: the compiler folds it into constants, which keeps
/// the firmware images as small as with a hard-wired layout) or carried at
/// run time (an [`ImageSpec`] value).
pub trait Image {
    /// The image's length, magic and version.
    fn spec(&self) -> ImageSpec;
}

impl Image for ImageSpec {
    fn spec(&self) -> ImageSpec {
        *self
    }
}

/// The KERNEL parameter block, [`KERNEL_IMAGE`], as a type.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct KernelImage;

impl Image for KernelImage {
    #[inline(always)]
    fn spec(&self) -> ImageSpec {
        KERNEL_IMAGE
    }
}

/// Two-sector A/B store at a flash offset: the non-volatile home of one
/// image — for the KERNEL the parameter block written by ICD 5.3.7
/// SaveFlash ([`ParamStore::new`]), for another personality its own
/// ([`ParamStore::for_image`]).
#[derive(Debug, Clone, Copy)]
pub struct ParamStore<I: Image = KernelImage> {
    base: u32,
    image: I,
}

/// Why a [`ParamStore`] operation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StoreError {
    /// The flash reported an error (for a save interrupted by a power cut,
    /// whatever the flash says then). Also `Flash(NotAligned)` when `base` is
    /// not a multiple of `F::ERASE_SIZE` or `F::WRITE_SIZE`/`F::READ_SIZE`
    /// do not divide 256, and `Flash(Other)` when a just-saved or just-loaded
    /// sector does not read back as written/validated.
    Flash(NorFlashErrorKind),
    /// `F::ERASE_SIZE` cannot hold header + block + commit word.
    SectorTooSmall,
    /// The two sectors do not fit in the flash (or in the `u32` offset space).
    OutOfBounds,
    /// The buffer passed to load or save is not the image's length.
    ImageLength,
}

impl From<NorFlashErrorKind> for StoreError {
    fn from(kind: NorFlashErrorKind) -> Self {
        StoreError::Flash(kind)
    }
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StoreError::Flash(kind) => write!(f, "parameter flash error: {kind:?}"),
            StoreError::SectorTooSmall => {
                f.write_str("flash erase sector too small for the parameter block")
            }
            StoreError::OutOfBounds => f.write_str("parameter store does not fit in the flash"),
            StoreError::ImageLength => {
                f.write_str("buffer length is not the stored image's length")
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for StoreError {}

/// Maps a flash driver error.
fn flash_err<E: NorFlashError>(e: E) -> StoreError {
    StoreError::Flash(e.kind())
}

/// `n` rounded up to a multiple of `a` (`None` for `a == 0` or overflow).
fn align_up(n: usize, a: usize) -> Option<usize> {
    n.checked_next_multiple_of(a)
}

/// Where things are, for one flash type, base and image.
#[derive(Debug, Clone, Copy)]
struct Layout<I: Image> {
    /// What is stored (a zero-sized constant for [`KernelImage`]).
    image: I,
    /// Flash offset of sector A; sector B follows at `base + sector`.
    base: u32,
    /// Sector size (`F::ERASE_SIZE`).
    sector: u32,
    /// Header + image, padded to `WRITE_SIZE`; also the commit word's offset.
    body_len: usize,
    /// The commit word padded to `WRITE_SIZE`.
    commit_len: usize,
    /// Bytes read to validate a sector: up to the end of the marker,
    /// padded to `READ_SIZE`.
    read_len: usize,
}

impl<I: Image + Copy> Layout<I> {
    /// Checks the geometry of `F` at `base` in a flash of `capacity` bytes.
    fn new<F: NorFlash>(image: I, base: u32, capacity: usize) -> Result<Self, StoreError> {
        let (w, r) = (F::WRITE_SIZE, F::READ_SIZE);
        if w == 0 || r == 0 || !CHUNK.is_multiple_of(w) || !CHUNK.is_multiple_of(r) {
            return Err(StoreError::Flash(NorFlashErrorKind::NotAligned));
        }
        let image_end = HEADER_LEN + usize::from(image.spec().len);
        let body_len = align_up(image_end, w).ok_or(StoreError::SectorTooSmall)?;
        let commit_len = align_up(COMMIT_LEN, w).ok_or(StoreError::SectorTooSmall)?;
        let write_end = body_len
            .checked_add(commit_len)
            .ok_or(StoreError::SectorTooSmall)?;
        let read_len = body_len
            .checked_add(COMMIT_LEN)
            .and_then(|n| align_up(n, r))
            .ok_or(StoreError::SectorTooSmall)?;
        if write_end.max(read_len) > F::ERASE_SIZE {
            return Err(StoreError::SectorTooSmall);
        }
        // ERASE_SIZE >= write_end > 0 from here on.
        let sector = u32::try_from(F::ERASE_SIZE).map_err(|_| StoreError::OutOfBounds)?;
        if !base.is_multiple_of(sector) {
            return Err(StoreError::Flash(NorFlashErrorKind::NotAligned));
        }
        let end = sector
            .checked_mul(2)
            .and_then(|span| base.checked_add(span))
            .ok_or(StoreError::OutOfBounds)?;
        if usize::try_from(end).map_or(true, |end| end > capacity) {
            return Err(StoreError::OutOfBounds);
        }
        Ok(Layout {
            image,
            base,
            sector,
            body_len,
            commit_len,
            read_len,
        })
    }

    /// The image's spec.
    #[inline(always)]
    fn spec(&self) -> ImageSpec {
        self.image.spec()
    }

    /// Header + image, before `WRITE_SIZE` padding.
    #[inline(always)]
    fn image_end(&self) -> usize {
        HEADER_LEN + usize::from(self.spec().len)
    }

    /// Flash offset of sector `idx` (0 = A, 1 = B); in range by construction.
    fn start(&self, idx: usize) -> u32 {
        if idx == 0 {
            self.base
        } else {
            self.base + self.sector
        }
    }

    /// `start + pos` for a `pos` inside the sector (so it cannot overflow:
    /// `base + 2 * sector` fits in `u32`).
    fn at(&self, idx: usize, pos: usize) -> u32 {
        // pos < sector <= u32::MAX, so the conversion cannot fail.
        self.start(idx) + u32::try_from(pos).unwrap_or(0)
    }
}

/// Reads sector `idx` and validates it; returns its `seq` if valid. With
/// `copy` (the image's length), also copies the sector's image bytes there
/// (whether valid or not).
fn scan<F: NorFlash, I: Image + Copy>(
    flash: &mut F,
    layout: &Layout<I>,
    idx: usize,
    mut copy: Option<&mut [u8]>,
) -> Result<Option<u32>, StoreError> {
    let mut buf = [0u8; CHUNK];
    let mut header = [0u8; HEADER_LEN];
    let mut marker = [0u8; COMMIT_LEN];
    let marker_at = layout.body_len;
    let mut digest = CRC32.digest();
    let mut header_hashed = false;
    let mut pos = 0;
    while pos < layout.read_len {
        // A multiple of READ_SIZE: CHUNK and read_len both are.
        let n = (layout.read_len - pos).min(CHUNK);
        let chunk = &mut buf[..n];
        flash.read(layout.at(idx, pos), chunk).map_err(flash_err)?;
        let end = pos + n;
        // Header: positions [0, 16).
        for (p, byte) in (pos..end.min(HEADER_LEN)).zip(chunk.iter()) {
            if let Some(slot) = header.get_mut(p) {
                *slot = *byte;
            }
        }
        if end >= HEADER_LEN && !header_hashed {
            if field(&header, 0) != layout.spec().magic_word()
                || field(&header, 8) != layout.spec().len_word()
            {
                // Not ours (erased, garbage, half erased): skip the rest.
                return Ok(None);
            }
            digest.update(&header[..HEADER_CRC_LEN]);
            header_hashed = true;
        }
        // Image: positions [16, 16 + len).
        let (lo, hi) = (pos.max(HEADER_LEN), end.min(layout.image_end()));
        if lo < hi {
            if let Some(data) = chunk.get(lo - pos..hi - pos) {
                digest.update(data);
                if let Some(dst) = copy
                    .as_deref_mut()
                    .and_then(|b| b.get_mut(lo - HEADER_LEN..hi - HEADER_LEN))
                {
                    dst.copy_from_slice(data);
                }
            }
        }
        // Commit marker: positions [body_len, body_len + 4).
        let (lo, hi) = (pos.max(marker_at), end.min(marker_at + COMMIT_LEN));
        if lo < hi {
            if let (Some(dst), Some(src)) = (
                marker.get_mut(lo - marker_at..hi - marker_at),
                chunk.get(lo - pos..hi - pos),
            ) {
                dst.copy_from_slice(src);
            }
        }
        pos = end;
    }
    let valid = header_hashed
        && u32::from_le_bytes(marker) == COMMIT
        && field(&header, 12) == digest.finalize();
    Ok(valid.then(|| field(&header, 4)))
}

/// The little-endian u32 at `at` in the header.
fn field(header: &[u8; HEADER_LEN], at: usize) -> u32 {
    let mut word = [0u8; 4];
    if let Some(src) = header.get(at..at + 4) {
        word.copy_from_slice(src);
    }
    u32::from_le_bytes(word)
}

/// Whether sequence number `b` is newer than `a` (serial-number order).
fn is_newer(b: u32, a: u32) -> bool {
    (b.wrapping_sub(a) as i32) > 0
}

/// The newest of the two sectors' scan results: `(sector, seq)`.
fn newest(a: Option<u32>, b: Option<u32>) -> Option<(usize, u32)> {
    match (a, b) {
        (Some(a), Some(b)) if is_newer(b, a) => Some((1, b)),
        (Some(a), _) => Some((0, a)),
        (None, Some(b)) => Some((1, b)),
        (None, None) => None,
    }
}

/// Erases sector `idx` and writes a complete copy of `block` (the image's
/// length, checked by the caller) with `seq` there, commit marker last.
fn write_sector<F: NorFlash, I: Image + Copy>(
    flash: &mut F,
    layout: &Layout<I>,
    idx: usize,
    seq: u32,
    block: &[u8],
) -> Result<(), StoreError> {
    let mut header = [0u8; HEADER_LEN];
    header[0..4].copy_from_slice(&layout.spec().magic);
    header[4..8].copy_from_slice(&seq.to_le_bytes());
    header[8..12].copy_from_slice(&layout.spec().len_word().to_le_bytes());
    let mut digest = CRC32.digest();
    digest.update(&header[..HEADER_CRC_LEN]);
    digest.update(block);
    header[12..16].copy_from_slice(&digest.finalize().to_le_bytes());

    let start = layout.start(idx);
    flash
        .erase(start, start + layout.sector)
        .map_err(flash_err)?;

    let mut buf = [0xFFu8; CHUNK];
    let mut pos = 0;
    while pos < layout.body_len {
        // A multiple of WRITE_SIZE: CHUNK and body_len both are.
        let n = (layout.body_len - pos).min(CHUNK);
        let chunk = &mut buf[..n];
        for (p, slot) in (pos..).zip(chunk.iter_mut()) {
            *slot = if p < HEADER_LEN {
                header.get(p)
            } else {
                block.get(p - HEADER_LEN)
            }
            .copied()
            .unwrap_or(0xFF);
        }
        flash.write(layout.at(idx, pos), chunk).map_err(flash_err)?;
        pos += n;
    }

    buf.fill(0xFF);
    buf[..COMMIT_LEN].copy_from_slice(&COMMIT.to_le_bytes());
    let commit = buf.get(..layout.commit_len).unwrap_or(&[]);
    flash
        .write(layout.at(idx, layout.body_len), commit)
        .map_err(flash_err)
}

impl ParamStore<KernelImage> {
    /// The KERNEL parameter store ([`KERNEL_IMAGE`]) whose two sectors start
    /// at flash offset `base` (a multiple of the flash's `ERASE_SIZE`;
    /// checked by [`load`](Self::load) and [`save`](Self::save)).
    pub const fn new(base: u32) -> Self {
        Self::for_image(base, KernelImage)
    }

    /// Flash bytes a store occupies for flash type `F`, whatever its image:
    /// two erase sectors (saturating at `u32::MAX` for absurd sector sizes).
    pub fn footprint<F: NorFlash>() -> u32 {
        u32::try_from(F::ERASE_SIZE)
            .ok()
            .and_then(|sector| sector.checked_mul(2))
            .unwrap_or(u32::MAX)
    }
}

impl<I: Image + Copy> ParamStore<I> {
    /// A store of `image` (e.g. an [`ImageSpec`] value) whose two sectors
    /// start at `base` (as for [`new`](ParamStore::new)).
    pub const fn for_image(base: u32, image: I) -> Self {
        ParamStore { base, image }
    }

    /// The image this store persists.
    pub fn spec(&self) -> ImageSpec {
        self.image.spec()
    }

    /// Flash offset of the store's first sector.
    pub const fn base(&self) -> u32 {
        self.base
    }

    /// Reads the newest valid image into `block` (exactly the spec's length,
    /// else [`StoreError::ImageLength`]); `Ok(true)` if one was found,
    /// `Ok(false)` if the flash holds none (fresh, garbage, another spec's
    /// image) — the power-on counterpart of ICD 5.3.7 SaveFlash.
    ///
    /// On `Ok(false)` `block` is untouched; on `Err` its contents are
    /// unspecified. Never panics, whatever the flash holds.
    pub fn load<F: NorFlash>(&self, flash: &mut F, block: &mut [u8]) -> Result<bool, StoreError> {
        let spec = self.spec();
        if block.len() != usize::from(spec.len) {
            return Err(StoreError::ImageLength);
        }
        let layout = Layout::new::<F>(self.image, self.base, flash.capacity())?;
        let a = scan(flash, &layout, 0, None)?;
        let b = scan(flash, &layout, 1, None)?;
        let Some((idx, seq)) = newest(a, b) else {
            return Ok(false);
        };
        // Copy pass; re-validated so `block` is exactly what the CRC covered.
        if scan(flash, &layout, idx, Some(block))? == Some(seq) {
            Ok(true)
        } else {
            Err(StoreError::Flash(NorFlashErrorKind::Other))
        }
    }

    /// Persists `block` (ICD 5.3.7 SaveFlash; exactly the spec's length,
    /// else [`StoreError::ImageLength`] and nothing is written), power-fail
    /// safe: erases the sector not holding the newest valid image (sector A
    /// if none), writes header and image, then the commit marker, then reads
    /// it back. If the power is cut at any step, the next
    /// [`load`](Self::load) returns either the previous image or `block`,
    /// complete.
    ///
    /// Costs one sector erase plus the programs of `16 + len` bytes (rounded
    /// up to `WRITE_SIZE`) and of the padded commit word — for the KERNEL
    /// block 1 + 388 + 1 = 390 steps on [`crate::nor::RamNor`]. `Ok` means
    /// the new image read back valid.
    pub fn save<F: NorFlash>(&self, flash: &mut F, block: &[u8]) -> Result<(), StoreError> {
        let spec = self.spec();
        if block.len() != usize::from(spec.len) {
            return Err(StoreError::ImageLength);
        }
        let layout = Layout::new::<F>(self.image, self.base, flash.capacity())?;
        let a = scan(flash, &layout, 0, None)?;
        let b = scan(flash, &layout, 1, None)?;
        let (idx, seq) = match newest(a, b) {
            Some((current, seq)) => (1 - current, seq.wrapping_add(1)),
            None => (0, 0),
        };
        write_sector(flash, &layout, idx, seq, block)?;
        if scan(flash, &layout, idx, None)? == Some(seq) {
            Ok(())
        } else {
            Err(StoreError::Flash(NorFlashErrorKind::Other))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nor::RamNor;

    type Nor = RamNor<8192>;

    fn block(fill: u8) -> [u8; PARAM_BLOCK_LEN] {
        let mut b = [fill; PARAM_BLOCK_LEN];
        for (i, x) in b.iter_mut().enumerate() {
            *x ^= i as u8;
        }
        b
    }

    fn layout() -> Layout<KernelImage> {
        Layout::new::<Nor>(KernelImage, 0, 8192).unwrap()
    }

    /// The table-less CRC is CRC-32/ISO-HDLC: the catalogue's check value.
    #[test]
    fn crc_is_iso_hdlc() {
        assert_eq!(CRC32.checksum(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn layout_on_ram_nor() {
        let l = layout();
        assert_eq!(
            (l.sector, l.body_len, l.commit_len, l.read_len),
            (4096, 0x610, 4, 0x614)
        );
        assert_eq!(ParamStore::footprint::<Nor>(), 8192);
    }

    #[test]
    fn save_writes_the_documented_format() {
        let mut f = Nor::new();
        let b = block(0x3C);
        ParamStore::new(0).save(&mut f, &b).unwrap();
        let img = f.image();
        assert_eq!(&img[0..4], b"KPRM");
        assert_eq!(&img[4..8], &0u32.to_le_bytes());
        assert_eq!(&img[8..12], &0x600u32.to_le_bytes());
        let mut d = CRC32.digest();
        d.update(&img[0..12]);
        d.update(&b);
        assert_eq!(&img[12..16], &d.finalize().to_le_bytes());
        assert_eq!(&img[16..0x610], &b[..]);
        assert_eq!(&img[0x610..0x614], &[0xDE, 0xC0, 0xFE, 0x5A]);
        assert!(img[0x614..].iter().all(|&x| x == 0xFF));
    }

    #[test]
    fn seq_passes_u32_max_without_losing_the_newest() {
        let mut f = Nor::new();
        let l = layout();
        write_sector(&mut f, &l, 0, u32::MAX - 1, &block(1)).unwrap();
        write_sector(&mut f, &l, 1, u32::MAX, &block(2)).unwrap();
        let store = ParamStore::new(0);
        let mut out = [0; PARAM_BLOCK_LEN];
        assert!(store.load(&mut f, &mut out).unwrap());
        assert_eq!(out, block(2));
        for (i, fill) in [3u8, 4, 5].into_iter().enumerate() {
            store.save(&mut f, &block(fill)).unwrap();
            assert!(store.load(&mut f, &mut out).unwrap());
            assert_eq!(out, block(fill));
            let seq = u32::from_le_bytes(f.image()[(i % 2) * 4096 + 4..][..4].try_into().unwrap());
            assert_eq!(seq, i as u32, "seq wrapped to 0, 1, 2");
        }
    }

    #[test]
    fn a_flipped_seq_bit_invalidates_the_sector() {
        let mut f = Nor::new();
        let store = ParamStore::new(0);
        store.save(&mut f, &block(1)).unwrap(); // A, seq 0
        store.save(&mut f, &block(2)).unwrap(); // B, seq 1
        let mut img = *f.image();
        img[4] ^= 0x10; // A's seq 0 -> 16 would outrank B if not CRC-covered
        let mut f = Nor::from_image(&img);
        let mut out = [0; PARAM_BLOCK_LEN];
        assert!(store.load(&mut f, &mut out).unwrap());
        assert_eq!(out, block(2));
    }

    #[test]
    fn the_exact_commit_marker_is_required() {
        let mut f = Nor::new();
        let store = ParamStore::new(0);
        store.save(&mut f, &block(7)).unwrap();
        let mut out = [0; PARAM_BLOCK_LEN];
        for bit in 0..32 {
            let mut img = *f.image();
            img[0x610 + bit / 8] ^= 1 << (bit % 8);
            let mut g = Nor::from_image(&img);
            assert!(!store.load(&mut g, &mut out).unwrap(), "bit {bit}");
        }
        assert_eq!(out, [0; PARAM_BLOCK_LEN], "untouched on Ok(false)");
    }

    #[test]
    fn the_kernel_spec_keeps_the_original_length_word() {
        assert_eq!(KERNEL_IMAGE.len_word(), 0x600);
        assert_eq!(KERNEL_IMAGE.magic_word(), 0x4D52_504B);
        let v = ImageSpec {
            len: 301,
            magic: *b"ISBC",
            version: 3,
        };
        assert_eq!(v.len_word(), 0x0003_012D);
    }

    #[test]
    fn a_buffer_of_the_wrong_length_is_refused_before_any_flash_access() {
        let mut f = Nor::new();
        f.cut_power_after(0); // any program/erase would fail differently
        let store = ParamStore::new(0);
        assert_eq!(store.save(&mut f, &[0; 16]), Err(StoreError::ImageLength));
        assert_eq!(
            store.load(&mut f, &mut [0; 0x601]),
            Err(StoreError::ImageLength)
        );
        assert!(!f.power_lost());
        assert_eq!(f.image(), Nor::new().image());
    }

    #[test]
    fn serial_order() {
        assert!(is_newer(1, 0));
        assert!(is_newer(0, u32::MAX));
        assert!(!is_newer(0, 0));
        assert!(!is_newer(u32::MAX, 0));
        assert_eq!(newest(Some(5), Some(5)), Some((0, 5)));
        assert_eq!(newest(Some(0), Some(u32::MAX)), Some((0, 0)));
        assert_eq!(newest(None, Some(3)), Some((1, 3)));
        assert_eq!(newest(None, None), None);
    }
}
