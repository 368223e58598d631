//! The runner's errors, below every other module of the runner (no module
//! imports another's error types, so `control`, `flash`, `fleet` and
//! `runner` do not import each other for them). [`UsageError`] (exit
//! status 2) is the tools crate's, the one type the program's `report`
//! looks for.

pub use imu_emu_tools::error::UsageError;

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
