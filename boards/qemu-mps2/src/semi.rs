//! Semihosting (ARM semihosting v2 as QEMU implements it with
//! `-semihosting-config enable=on,target=native`): the command line, the
//! flash file, log lines on QEMU's stderr.

use cortex_m_semihosting::{nr, syscall};

/// The semihosting command line (`arg=` values joined by spaces; without
/// any `arg=`, the kernel file name) into `buf`; its length.
pub fn cmdline(buf: &mut [u8]) -> usize {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most block[1] bytes to block[0] and
    // the length back into block[1].
    let r = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if r != 0 {
        return 0;
    }
    block[1].min(buf.len())
}

/// An open host file.
pub struct File(usize);

/// Path bytes must be NUL-terminated for SYS_OPEN: copies into `buf`.
fn c_path<'a>(path: &[u8], buf: &'a mut [u8; 256]) -> Option<&'a [u8]> {
    if path.len() >= buf.len() {
        return None;
    }
    buf[..path.len()].copy_from_slice(path);
    buf[path.len()] = 0;
    Some(&buf[..=path.len()])
}

impl File {
    /// Opens `path` with an `fopen` mode from [`nr::open`].
    pub fn open(path: &[u8], mode: usize) -> Option<File> {
        let mut b = [0u8; 256];
        let p = c_path(path, &mut b)?;
        // SAFETY: a NUL-terminated path, its length without the NUL.
        let h = unsafe { syscall!(OPEN, p.as_ptr(), mode, p.len() - 1) };
        if h == usize::MAX {
            None
        } else {
            Some(File(h))
        }
    }

    /// Reads into `buf`; bytes read.
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        // SAFETY: the host writes at most buf.len() bytes into buf.
        let left = unsafe { syscall!(READ, self.0, buf.as_mut_ptr(), buf.len()) };
        buf.len().saturating_sub(left)
    }

    /// Writes all of `bytes`; whether it succeeded.
    pub fn write_all(&mut self, bytes: &[u8]) -> bool {
        // SAFETY: the host reads bytes.len() bytes from bytes.
        let left = unsafe { syscall!(WRITE, self.0, bytes.as_ptr(), bytes.len()) };
        left == 0
    }
}

impl Drop for File {
    fn drop(&mut self) {
        // SAFETY: closes a handle SYS_OPEN returned.
        unsafe {
            syscall!(CLOSE, self.0);
        }
    }
}

/// Renames `from` to `to` (replacing `to`); whether it succeeded.
pub fn rename(from: &[u8], to: &[u8]) -> bool {
    let (mut a, mut b) = ([0u8; 256], [0u8; 256]);
    let (Some(f), Some(t)) = (c_path(from, &mut a), c_path(to, &mut b)) else {
        return false;
    };
    // SAFETY: two NUL-terminated paths with their lengths.
    let r = unsafe { syscall!(RENAME, f.as_ptr(), f.len() - 1, t.as_ptr(), t.len() - 1) };
    r == 0
}

/// A text line built without `core::fmt` (whose formatting machinery,
/// ≈ 3 KiB, the image would otherwise carry only for these messages).
/// Text beyond the capacity is cut.
#[derive(Default)]
pub struct Line(heapless::Vec<u8, 320>);

impl Line {
    /// Appends `s`.
    pub fn str(mut self, s: &str) -> Self {
        for &b in s.as_bytes() {
            let _ = self.0.push(b);
        }
        self
    }

    /// Appends `v` in decimal.
    pub fn dec(mut self, v: u64) -> Self {
        let mut digits = [0u8; 20];
        let (mut i, mut v) = (digits.len(), v);
        loop {
            i -= 1;
            digits[i] = b'0' + (v % 10) as u8;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        let _ = self.0.extend_from_slice(&digits[i..]);
        self
    }

    /// Appends `v` as `0x` and eight hex digits.
    pub fn hex(mut self, v: u32) -> Self {
        let _ = self.0.extend_from_slice(b"0x");
        for k in (0..8).rev() {
            let _ = self
                .0
                .push(b"0123456789abcdef"[(v >> (4 * k)) as usize & 15]);
        }
        self
    }

    /// The line so far.
    pub fn bytes(&self) -> &[u8] {
        &self.0
    }

    /// Writes the line to QEMU's stderr (SYS_WRITE to handle 2 is not
    /// portable; `:tt` opened for append is the semihosting stderr).
    pub fn eprintln(self) {
        if let Some(mut f) = File::open(b":tt", nr::open::W_APPEND) {
            let _ = f.write_all(&self.0);
            let _ = f.write_all(b"\n");
        }
    }
}

/// Writes `s` as a line to QEMU's stderr.
pub fn eprintln(s: &str) {
    Line::default().str(s).eprintln();
}

/// Exits QEMU with `code` (SYS_EXIT, ADP_Stopped_ApplicationExit).
pub fn exit(code: u32) -> ! {
    let reason: usize = if code == 0 { 0x20026 } else { 0x20023 };
    loop {
        // SAFETY: SYS_EXIT with a reason code; QEMU terminates.
        unsafe {
            cortex_m_semihosting::syscall1(nr::REPORT_EXCEPTION, reason);
        }
    }
}
