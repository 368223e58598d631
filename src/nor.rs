//! A RAM NOR-flash model with real NOR semantics, for tests, the host runner
//! and the QEMU board.
//!
//! * erase sets a whole sector to `0xFF`;
//! * program only clears bits (the stored byte becomes `old & new`);
//! * power can be cut after any number of program/erase *steps* (one step is
//!   one `WRITE_SIZE` word or one sector erase); the step in progress when the
//!   power goes is left half done (half the bytes of the word programmed,
//!   half the sector erased) and every later operation fails until
//!   [`RamNor::restore_power`];
//! * or the step in progress is left *torn* ([`RamNor::cut_power_torn`]),
//!   as on real silicon: a program clears only a pseudo-random subset of the
//!   bits it was to clear, an erase sets a pseudo-random prefix of the
//!   sector to `0xFF` and a pseudo-random subset of the bits after it to 1.
//!
//! Implements [`embedded_storage::nor_flash::NorFlash`] so the parameter
//! store ([`crate::store`]) runs on it exactly as on an MCU's flash.

use embedded_storage::nor_flash::{
    check_erase, check_read, check_write, ErrorType, NorFlash, NorFlashError, NorFlashErrorKind,
    ReadNorFlash,
};

/// Errors of [`RamNor`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RamNorError {
    /// Offset or length not aligned to `READ_SIZE`/`WRITE_SIZE`/`ERASE_SIZE`.
    NotAligned,
    /// The range runs past the end of the flash.
    OutOfBounds,
    /// The simulated power was cut: nothing more is written until restored.
    PowerLost,
}

impl NorFlashError for RamNorError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            RamNorError::NotAligned => NorFlashErrorKind::NotAligned,
            RamNorError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            RamNorError::PowerLost => NorFlashErrorKind::Other,
        }
    }
}

impl From<NorFlashErrorKind> for RamNorError {
    fn from(kind: NorFlashErrorKind) -> Self {
        match kind {
            NorFlashErrorKind::NotAligned => RamNorError::NotAligned,
            _ => RamNorError::OutOfBounds,
        }
    }
}

/// Sector size of [`RamNor`]: 4 KiB, the common serial-NOR erase unit.
pub const RAM_NOR_ERASE_SIZE: usize = 4096;
/// Program unit of [`RamNor`]: one 32-bit word.
pub const RAM_NOR_WRITE_SIZE: usize = 4;

/// `N` bytes of simulated NOR flash, erased (all `0xFF`) when new.
#[derive(Clone)]
pub struct RamNor<const N: usize> {
    data: [u8; N],
    /// Steps left before the power is cut; `None` = never.
    budget: Option<u32>,
    /// Total program/erase steps performed (for counting a save's steps).
    steps: u32,
    dead: bool,
    /// xorshift32 state of a torn cut ([`RamNor::cut_power_torn`]);
    /// `None` = the cut step is left half done.
    tear: Option<u32>,
}

impl<const N: usize> core::fmt::Debug for RamNor<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RamNor")
            .field("capacity", &N)
            .field("steps", &self.steps)
            .field("budget", &self.budget)
            .field("dead", &self.dead)
            .field("torn", &self.tear.is_some())
            .finish()
    }
}

impl<const N: usize> Default for RamNor<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> RamNor<N> {
    /// A fully erased flash.
    pub const fn new() -> Self {
        RamNor {
            data: [0xFF; N],
            budget: None,
            steps: 0,
            dead: false,
            tear: None,
        }
    }

    /// A flash holding `image` (shorter images are padded with `0xFF`,
    /// longer ones truncated) — e.g. a flash file read back by a board.
    pub fn from_image(image: &[u8]) -> Self {
        let mut nor = Self::new();
        let n = image.len().min(N);
        nor.data[..n].copy_from_slice(&image[..n]);
        nor
    }

    /// The raw contents.
    pub fn image(&self) -> &[u8; N] {
        &self.data
    }

    /// Cut the power after `steps` more program/erase steps (0 = before the
    /// next one starts); the step in progress is left half done.
    pub fn cut_power_after(&mut self, steps: u32) {
        self.budget = Some(steps);
        self.tear = None;
    }

    /// Cut the power after `steps` more steps, leaving the step in progress
    /// torn in a way `seed` decides (the same seed, the same bits): a word
    /// program clears a random subset of the bits it was to clear; a sector
    /// erase sets a random prefix of the sector to `0xFF` and about a quarter
    /// of the bits after it to 1. Either may happen to leave the step fully
    /// done or not started at all, as a real cut can.
    pub fn cut_power_torn(&mut self, steps: u32, seed: u32) {
        self.budget = Some(steps);
        // xorshift32 needs a non-zero state.
        self.tear = Some(if seed == 0 { 0x9E37_79B9 } else { seed });
    }

    /// Power is back: operations work again, no cut is scheduled.
    pub fn restore_power(&mut self) {
        self.budget = None;
        self.dead = false;
        self.tear = None;
    }

    /// The next pseudo-random word of a torn cut (`None` for a half cut).
    fn tear_word(&mut self) -> Option<u32> {
        let x = self.tear.as_mut()?;
        *x ^= *x << 13;
        *x ^= *x >> 17;
        *x ^= *x << 5;
        Some(*x)
    }

    /// Whether a scheduled cut has happened.
    pub fn power_lost(&self) -> bool {
        self.dead
    }

    /// Program/erase steps performed since creation.
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// Accounts one step; `Ok(true)` = do it fully, `Ok(false)` = the power
    /// goes during this step (do half of it, then fail).
    fn step(&mut self) -> Result<bool, RamNorError> {
        if self.dead {
            return Err(RamNorError::PowerLost);
        }
        self.steps = self.steps.wrapping_add(1);
        match &mut self.budget {
            Some(0) => {
                self.dead = true;
                Ok(false)
            }
            Some(b) => {
                *b -= 1;
                Ok(true)
            }
            None => Ok(true),
        }
    }
}

impl<const N: usize> ErrorType for RamNor<N> {
    type Error = RamNorError;
}

impl<const N: usize> ReadNorFlash for RamNor<N> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        let start = offset as usize;
        bytes.copy_from_slice(&self.data[start..start + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        N
    }
}

impl<const N: usize> NorFlash for RamNor<N> {
    const WRITE_SIZE: usize = RAM_NOR_WRITE_SIZE;
    const ERASE_SIZE: usize = RAM_NOR_ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        let mut sector = from as usize;
        while sector < to as usize {
            let full = self.step()?;
            let end = sector + RAM_NOR_ERASE_SIZE;
            if full {
                self.data[sector..end].fill(0xFF);
                sector = end;
                continue;
            }
            match self.tear_word() {
                None => self.data[sector..sector + RAM_NOR_ERASE_SIZE / 2].fill(0xFF),
                Some(r) => {
                    let stop = sector + r as usize % (RAM_NOR_ERASE_SIZE + 1);
                    self.data[sector..stop].fill(0xFF);
                    for i in stop..end {
                        let (a, b) = (self.tear_word(), self.tear_word());
                        let mask = (a.unwrap_or(0) & b.unwrap_or(0)) as u8;
                        self.data[i] |= mask;
                    }
                }
            }
            return Err(RamNorError::PowerLost);
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        let base = offset as usize;
        for (i, word) in bytes.chunks(RAM_NOR_WRITE_SIZE).enumerate() {
            let full = self.step()?;
            let at = base + i * RAM_NOR_WRITE_SIZE;
            if !full {
                if let Some(r) = self.tear_word() {
                    // Bits where `r` is 1 keep their old value.
                    let keep = r.to_le_bytes();
                    for ((cell, new), k) in self.data[at..].iter_mut().zip(word).zip(keep) {
                        *cell &= *new | k;
                    }
                    return Err(RamNorError::PowerLost);
                }
            }
            let n = if full { word.len() } else { word.len() / 2 };
            for (cell, new) in self.data[at..at + n].iter_mut().zip(word) {
                *cell &= *new;
            }
            if !full {
                return Err(RamNorError::PowerLost);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn program_only_clears_bits_and_erase_sets_ff() {
        let mut f = RamNor::<8192>::new();
        f.write(0, &[0xF0, 0x0F, 0xAA, 0x55]).unwrap();
        f.write(0, &[0x3C, 0xFF, 0xFF, 0x00]).unwrap();
        let mut b = [0u8; 4];
        f.read(0, &mut b).unwrap();
        assert_eq!(b, [0x30, 0x0F, 0xAA, 0x00]);
        f.erase(0, 4096).unwrap();
        f.read(0, &mut b).unwrap();
        assert_eq!(b, [0xFF; 4]);
    }

    #[test]
    fn misaligned_and_out_of_bounds_are_rejected() {
        let mut f = RamNor::<8192>::new();
        assert_eq!(f.write(1, &[0; 4]), Err(RamNorError::NotAligned));
        assert_eq!(f.write(0, &[0; 3]), Err(RamNorError::NotAligned));
        assert_eq!(f.erase(0, 100), Err(RamNorError::NotAligned));
        assert_eq!(f.write(8192, &[0; 4]), Err(RamNorError::OutOfBounds));
    }

    #[test]
    fn a_cut_leaves_the_step_half_done_and_blocks_later_steps() {
        let mut f = RamNor::<8192>::new();
        f.cut_power_after(1);
        assert_eq!(
            f.write(0, &[0, 0, 0, 0, 0, 0, 0, 0]),
            Err(RamNorError::PowerLost)
        );
        assert_eq!(&f.image()[..8], &[0, 0, 0, 0, 0, 0, 0xFF, 0xFF]);
        assert!(f.power_lost());
        assert_eq!(f.write(8, &[0; 4]), Err(RamNorError::PowerLost));
        f.restore_power();
        f.write(8, &[0; 4]).unwrap();
    }

    #[test]
    fn a_torn_program_clears_a_subset_of_the_bits_and_only_those() {
        let mut f = RamNor::<8192>::new();
        f.write(0, &[0xF0, 0xFF, 0xFF, 0xFF]).unwrap();
        let mut seen = std::collections::BTreeSet::new();
        for seed in 0..64 {
            let mut g = f.clone();
            g.cut_power_torn(0, seed);
            assert_eq!(
                g.write(0, &[0x0F, 0x00, 0xAA, 0xFF]),
                Err(RamNorError::PowerLost)
            );
            let got = &g.image()[..4];
            // Every bit is old or old & new: never set, never cleared
            // where the program keeps a 1.
            for (i, (&g, (&old, &new))) in got
                .iter()
                .zip(
                    [0xF0u8, 0xFF, 0xFF, 0xFF]
                        .iter()
                        .zip(&[0x0Fu8, 0x00, 0xAA, 0xFF]),
                )
                .enumerate()
            {
                assert_eq!(g & !old, 0, "byte {i}: a bit was set");
                assert_eq!(!g & old & new, 0, "byte {i}: a kept bit was cleared");
            }
            seen.insert(got[1]);
            assert!(g.power_lost());
            assert_eq!(g.write(8, &[0; 4]), Err(RamNorError::PowerLost));
        }
        assert!(seen.len() > 32, "random subsets: {} distinct", seen.len());
    }

    #[test]
    fn a_torn_erase_leaves_part_of_the_sector() {
        let mut f = RamNor::<8192>::new();
        f.write(0, &[0; 4096]).unwrap();
        let mut partial = 0;
        for seed in 0..32 {
            let mut g = f.clone();
            g.cut_power_torn(0, seed);
            assert_eq!(g.erase(0, 4096), Err(RamNorError::PowerLost));
            let img = &g.image()[..4096];
            let erased = img.iter().take_while(|&&x| x == 0xFF).count();
            if erased < 4096 {
                partial += 1;
                // After the prefix, about a quarter of the bits are set.
                let ones: u32 = img[erased..].iter().map(|x| x.count_ones()).sum();
                let bits = 8 * (4096 - erased) as u32;
                assert!(ones < bits / 2, "seed {seed}: {ones} of {bits}");
            }
            assert!(g.image()[4096..].iter().all(|&x| x == 0xFF));
            g.restore_power();
            g.erase(0, 4096).unwrap();
            assert!(g.image()[..4096].iter().all(|&x| x == 0xFF));
        }
        assert!(partial > 16);
    }
}
