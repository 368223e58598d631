//! A RAM NOR-flash model with real NOR semantics, for tests, the host runner
//! and the QEMU board.
//!
//! * erase sets a whole sector to `0xFF`;
//! * program only clears bits (the stored byte becomes `old & new`);
//! * power can be cut after any number of program/erase *steps* (one step is
//!   one `WRITE_SIZE` word or one sector erase); the step in progress when the
//!   power goes is left half done (half the bytes of the word programmed,
//!   half the sector erased) and every later operation fails until
//!   [`RamNor::restore_power`].
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
}

impl<const N: usize> core::fmt::Debug for RamNor<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RamNor")
            .field("capacity", &N)
            .field("steps", &self.steps)
            .field("budget", &self.budget)
            .field("dead", &self.dead)
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
    /// next one starts).
    pub fn cut_power_after(&mut self, steps: u32) {
        self.budget = Some(steps);
    }

    /// Power is back: operations work again, no cut is scheduled.
    pub fn restore_power(&mut self) {
        self.budget = None;
        self.dead = false;
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
            let stop = if full {
                end
            } else {
                sector + RAM_NOR_ERASE_SIZE / 2
            };
            self.data[sector..stop].fill(0xFF);
            if !full {
                return Err(RamNorError::PowerLost);
            }
            sector = end;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        let base = offset as usize;
        for (i, word) in bytes.chunks(RAM_NOR_WRITE_SIZE).enumerate() {
            let full = self.step()?;
            let n = if full { word.len() } else { word.len() / 2 };
            let at = base + i * RAM_NOR_WRITE_SIZE;
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
}
