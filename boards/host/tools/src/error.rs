//! The usage error the host crates share, in the lowest of them (the
//! runner and the program use it too, so no module imports another's
//! error types).
//!
//! An error is one line on stderr (`imu-emu: …`, the program's `report`):
//! exit status 2 for a [`UsageError`] anywhere in its chain (what the user
//! asked for is wrong, as clap's usage errors), 1 for a failure while
//! running.

/// An error in what the user asked for (exit status 2, as clap's usage
/// errors), as opposed to one met while running (exit status 1).
#[derive(Debug)]
pub struct UsageError(pub String);

impl core::fmt::Display for UsageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}
