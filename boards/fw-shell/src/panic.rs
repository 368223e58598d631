//! Panic report for the defmt boards (feature `defmt`): where the panic
//! happened and its message when that is a plain string (as every panic of
//! the firmware's own code is), in one defmt line.
//!
//! The boards' panic handlers call [`log`] instead of using panic-probe's
//! `print-defmt`, which renders the `PanicInfo` through `core::fmt` (≈ 2 KiB
//! of formatting code for messages the image never produces).

/// Logs `info`'s location and plain-string message at error level.
pub fn log(info: &core::panic::PanicInfo) {
    let (file, line) = info.location().map_or(("?", 0), |l| (l.file(), l.line()));
    let msg = info.message().as_str().unwrap_or("(formatted message)");
    defmt::error!("panicked at {=str}:{=u32}: {=str}", file, line, msg);
}
