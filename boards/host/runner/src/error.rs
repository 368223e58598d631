//! The host crate's errors, below every other module (no module imports
//! another's error types, so `cli`, `client`, `control`, `flash`, `fleet`
//! and `runner` do not import each other for them).
//!
//! An error is one line on stderr (`imu-emu: …`, [`crate::cli::report`]):
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

/// The error of binding `addr` for `option` (`--tcp`, `--control`), with a
/// hint where one helps: a port in use suggests port 0, an address that
/// does not parse says `HOST:PORT` is expected.
pub fn bind_error(e: std::io::Error, option: &str, addr: &str) -> anyhow::Error {
    use std::io::ErrorKind;
    match e.kind() {
        ErrorKind::AddrInUse => anyhow::anyhow!(
            "{option} {addr}: address already in use (another imu-emu?); \
             hint: {option} 127.0.0.1:0 picks a free port"
        ),
        ErrorKind::InvalidInput => anyhow::Error::new(UsageError(format!(
            "{option} {addr}: {e}; expected HOST:PORT, e.g. {option} 127.0.0.1:7000"
        ))),
        _ => anyhow::anyhow!("{option} {addr}: {e}"),
    }
}
