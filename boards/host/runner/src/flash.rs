//! The device's flash, optionally backed by a file.
//!
//! [`FileNor`] wraps [`RamNor`] (real NOR semantics: erase sets `0xFF`,
//! program only clears bits) and writes every program and erase through to
//! a file at the same offset, so stopping and restarting the runner is a
//! power cycle that keeps the saved parameters. A missing file is created
//! erased; a short file reads as erased past its end (and is padded with
//! `0xFF` on open, so later writes never leave zero-filled holes). Bytes
//! reach the operating system on every operation (`pwrite`), so they survive
//! the process being killed at any moment; they are not `fsync`ed.
//!
//! The file must be a regular file (or a path where one can be created):
//! a FIFO, a device (`/dev/null`, `/dev/full`), a directory or a socket is
//! refused with one line, without blocking (the file is opened
//! `O_NONBLOCK` and checked with `fstat` before anything is read). It is
//! locked (`flock`, exclusive, non-blocking) while the program runs, so a
//! second emulator on the same file is refused instead of silently losing
//! the first one's saves.

use std::fs::{File, OpenOptions};
use std::io::{self, Read};
use std::os::unix::fs::{FileExt, FileTypeExt as _, OpenOptionsExt as _};
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use imu_emu::nor::{RamNor, RamNorError, RAM_NOR_ERASE_SIZE, RAM_NOR_WRITE_SIZE};

/// Size of the emulated flash: 8 KiB (two 4 KiB sectors).
pub const FLASH_SIZE: usize = 8192;

/// The in-memory flash used without `--flash`.
pub type MemNor = RamNor<FLASH_SIZE>;

/// Errors of [`FileNor`].
#[derive(Debug)]
pub enum FileNorError {
    /// The NOR model refused the operation.
    Nor(RamNorError),
    /// Writing the image through to the file failed.
    Io(io::Error),
}

impl NorFlashError for FileNorError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            FileNorError::Nor(e) => e.kind(),
            FileNorError::Io(_) => NorFlashErrorKind::Other,
        }
    }
}

impl core::fmt::Display for FileNorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FileNorError::Nor(e) => write!(f, "flash: {e:?}"),
            FileNorError::Io(e) => write!(f, "flash file: {e}"),
        }
    }
}

impl std::error::Error for FileNorError {}

/// An 8 KiB NOR flash whose image lives in a file (write-through).
#[derive(Debug)]
pub struct FileNor {
    nor: MemNor,
    file: File,
    path: PathBuf,
    /// Writes to the file that failed so far, and when that was last said
    /// on stderr (at most once a second: a full disk fails every save).
    failed_writes: u64,
    reported_at: Option<std::time::Instant>,
}

impl FileNor {
    /// Opens (or creates) the flash image at `path` and locks it; refuses
    /// anything that is not a regular file ([`crate::error::UsageError`])
    /// and a file another process holds locked.
    pub fn open(path: &Path) -> anyhow::Result<Self> {
        let shown = path.display();
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            // A FIFO would block the open until a writer shows up; a
            // terminal would become the controlling one.
            .custom_flags(nix::fcntl::OFlag::O_NONBLOCK.bits() | nix::fcntl::OFlag::O_NOCTTY.bits())
            .open(path)
            .with_context(|| format!("--flash {shown}: cannot open or create it"))?;
        let kind = file
            .metadata()
            .with_context(|| format!("--flash {shown}: stat"))?
            .file_type();
        if !kind.is_file() {
            return Err(crate::error::UsageError(format!(
                "--flash {shown}: not a regular file ({}); give the path of a file to keep the \
                 flash image in",
                describe(kind)
            ))
            .into());
        }
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => anyhow::bail!(
                "--flash {shown}: in use by another process (locked; another imu-emu?); \
                 stop it or give another file"
            ),
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(anyhow::Error::new(e).context(format!("--flash {shown}: lock")))
            }
        }
        // Back to blocking I/O for the reads and writes proper.
        let fl = nix::fcntl::fcntl(&file, nix::fcntl::FcntlArg::F_GETFL)
            .with_context(|| format!("--flash {shown}: fcntl"))?;
        nix::fcntl::fcntl(
            &file,
            nix::fcntl::FcntlArg::F_SETFL(
                nix::fcntl::OFlag::from_bits_truncate(fl) & !nix::fcntl::OFlag::O_NONBLOCK,
            ),
        )
        .with_context(|| format!("--flash {shown}: fcntl"))?;
        let mut image = Vec::with_capacity(FLASH_SIZE);
        (&mut file)
            .take(FLASH_SIZE as u64)
            .read_to_end(&mut image)
            .with_context(|| format!("--flash {shown}: reading"))?;
        let nor = MemNor::from_image(&image);
        if image.len() < FLASH_SIZE {
            // A file that reads but cannot be written to (e.g. /proc/...,
            // a full or read-only file system): not a place for an image.
            file.write_all_at(&nor.image()[image.len()..], image.len() as u64)
                .map_err(|e| {
                    crate::error::UsageError(format!(
                        "--flash {shown}: cannot write the {FLASH_SIZE}-byte flash image there \
                         ({e}); give the path of an ordinary file on a writable disk"
                    ))
                })?;
        }
        Ok(FileNor {
            nor,
            file,
            path: path.to_owned(),
            failed_writes: 0,
            reported_at: None,
        })
    }

    /// The file holding the image.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The current image.
    pub fn image(&self) -> &[u8; FLASH_SIZE] {
        self.nor.image()
    }

    /// Writes `image[from..to]` through to the file.
    fn write_back(&mut self, from: usize, to: usize) -> Result<(), FileNorError> {
        let to = to.min(FLASH_SIZE);
        if from >= to {
            return Ok(());
        }
        self.file
            .write_all_at(&self.nor.image()[from..to], from as u64)
            .map_err(|e| {
                self.failed_writes += 1;
                let due = self
                    .reported_at
                    .is_none_or(|t| t.elapsed() >= std::time::Duration::from_secs(1));
                if due {
                    self.reported_at = Some(std::time::Instant::now());
                    eprintln!(
                        "imu-emu: {}: {e} ({} failed writes so far; said at most once a second)",
                        self.path.display(),
                        self.failed_writes
                    );
                }
                FileNorError::Io(e)
            })
    }

    /// Writes the touched range back, then reports the NOR result. A range
    /// refused up front (alignment, bounds) changed nothing.
    fn finish(
        &mut self,
        r: Result<(), RamNorError>,
        from: usize,
        to: usize,
    ) -> Result<(), FileNorError> {
        match r {
            Err(e @ (RamNorError::NotAligned | RamNorError::OutOfBounds)) => {
                Err(FileNorError::Nor(e))
            }
            r => {
                self.write_back(from, to)?;
                r.map_err(FileNorError::Nor)
            }
        }
    }
}

/// What a non-regular file is, for the refusal message.
pub fn describe(kind: std::fs::FileType) -> &'static str {
    if kind.is_dir() {
        "a directory"
    } else if kind.is_fifo() {
        "a FIFO"
    } else if kind.is_char_device() {
        "a character device"
    } else if kind.is_block_device() {
        "a block device"
    } else if kind.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

impl ErrorType for FileNor {
    type Error = FileNorError;
}

impl ReadNorFlash for FileNor {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.nor.read(offset, bytes).map_err(FileNorError::Nor)
    }

    fn capacity(&self) -> usize {
        FLASH_SIZE
    }
}

impl NorFlash for FileNor {
    const WRITE_SIZE: usize = RAM_NOR_WRITE_SIZE;
    const ERASE_SIZE: usize = RAM_NOR_ERASE_SIZE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let r = self.nor.erase(from, to);
        self.finish(r, from as usize, to as usize)
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let r = self.nor.write(offset, bytes);
        let from = offset as usize;
        self.finish(r, from, from.saturating_add(bytes.len()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_file_is_created_erased() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flash.bin");
        let f = FileNor::open(&path).unwrap();
        assert!(f.image().iter().all(|&b| b == 0xFF));
        assert_eq!(std::fs::read(&path).unwrap(), vec![0xFF; FLASH_SIZE]);
    }

    #[test]
    fn programs_and_erases_write_through_and_survive_reopen() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flash.bin");
        let mut f = FileNor::open(&path).unwrap();
        f.write(4096 + 8, &[1, 2, 3, 4]).unwrap();
        f.write(0, &[0xF0, 0xF0, 0xF0, 0xF0]).unwrap();
        f.write(0, &[0x3C, 0xFF, 0xFF, 0xFF]).unwrap(); // NOR: AND
        drop(f);
        let disk = std::fs::read(&path).unwrap();
        assert_eq!(&disk[4104..4108], &[1, 2, 3, 4]);
        assert_eq!(&disk[..4], &[0x30, 0xF0, 0xF0, 0xF0]);

        let mut f = FileNor::open(&path).unwrap();
        let mut b = [0; 4];
        f.read(4104, &mut b).unwrap();
        assert_eq!(b, [1, 2, 3, 4]);
        f.erase(4096, 8192).unwrap();
        drop(f);
        let disk = std::fs::read(&path).unwrap();
        assert!(disk[4096..].iter().all(|&b| b == 0xFF));
        assert_eq!(&disk[..4], &[0x30, 0xF0, 0xF0, 0xF0]);
    }

    #[test]
    fn a_short_file_reads_as_erased_and_is_padded() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flash.bin");
        std::fs::write(&path, [0u8; 10]).unwrap();
        let mut f = FileNor::open(&path).unwrap();
        let mut b = [0; 12];
        f.read(0, &mut b).unwrap();
        assert_eq!(b, [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF]);
        f.write(8188, &[0; 4]).unwrap();
        drop(f);
        let disk = std::fs::read(&path).unwrap();
        assert_eq!(disk.len(), FLASH_SIZE);
        assert!(disk[10..8188].iter().all(|&b| b == 0xFF));
    }

    #[test]
    fn refused_operations_touch_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flash.bin");
        let mut f = FileNor::open(&path).unwrap();
        assert!(matches!(
            f.write(1, &[0; 4]),
            Err(FileNorError::Nor(RamNorError::NotAligned))
        ));
        assert!(matches!(
            f.erase(0, 8192 + 4096),
            Err(FileNorError::Nor(RamNorError::OutOfBounds))
        ));
        assert_eq!(std::fs::read(&path).unwrap(), vec![0xFF; FLASH_SIZE]);
    }
}
