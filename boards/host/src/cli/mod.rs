//! Command line and program setup.
//!
//! ```text
//! imu-emu [--protocol kernel|isb] [--model K110] [--tcp 127.0.0.1:7000 | --pty [--link PATH]]
//!         [--flash FILE] [--control ADDR] [--allow-remote] [--seed N]
//!         [--sensor-profile [K=]FILE]… …
//! imu-emu client (--tcp HOST:PORT | --serial DEV [--baud N]) SUBCOMMAND …
//! imu-emu sensor-profile (show NAME | check FILE)
//! imu-emu allan [--model K110 | --input CSV] [--hours H] [--png F] [--svg F] …
//! ```
//!
//! The first stdout line tells where the device listens —
//! `listening on tcp 127.0.0.1:7000` (the bound address, so `--tcp …:0`
//! reveals the port it got) or `listening on pty /dev/pts/5` — and is
//! flushed at once. Diagnostics go to stderr. SIGINT/SIGTERM stop the
//! program cleanly (exit 0; a second signal exits at once with status 1).
//!
//! `--tcp` and `--control` must be loopback addresses unless
//! `--allow-remote` is given (then a warning says what is exposed). Errors
//! are one line (`imu-emu: …`, [`report`]): exit status 2 for a bad
//! argument ([`UsageError`], [`imu_emu_tools::error`]), 1 for a failure while running.

use std::io::Write as _;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context as _;
use imu_emu_runner::flash::{FileNor, MemNor};
use imu_emu_tools::error::UsageError;

mod args;
mod serve;

use args::man;
pub use args::{completions, Args, PowerOnAt, ProfileSub, Sub, DEFAULT_MODEL, DEFAULT_TCP};
use serve::{check_addresses, check_combinations, many, with_flash};
pub use serve::{check_local, numbered};

/// Runs `imu-emu sensor-profile …`.
fn sensor_profile(sub: &ProfileSub) -> anyhow::Result<()> {
    let text = match sub {
        ProfileSub::Show { name } => {
            let b = imu_emu_tools::profile_file::builtin(name)?;
            imu_emu_tools::profile_file::to_toml(b.profile, b.has_aux(), b.name, b.source)
        }
        ProfileSub::Check { file } => {
            let (p, aux) = imu_emu_tools::profile_file::load_with_aux(file)?;
            imu_emu_tools::profile_file::to_toml(&p, aux, &file.display().to_string(), "this file")
        }
    };
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(())
}

/// Sets up the `tracing` log on stderr at the level `-v`/`-q` ask for
/// (default: warnings). Calling it again does nothing.
pub fn init_logging(verbose: u8, quiet: bool) {
    use tracing::level_filters::LevelFilter;
    let level = match (quiet, verbose) {
        (true, _) => LevelFilter::ERROR,
        (false, 0) => LevelFilter::WARN,
        (false, 1) => LevelFilter::INFO,
        (false, 2) => LevelFilter::DEBUG,
        _ => LevelFilter::TRACE,
    };
    let _ = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_max_level(level)
        .with_target(false)
        .with_ansi(false)
        .without_time()
        .try_init();
}

/// Prints `e` as one line on stderr (`imu-emu: what: why: cause`) and
/// returns the exit status: 2 for a [`UsageError`], 1 otherwise. Never a
/// backtrace.
pub fn report(e: &anyhow::Error) -> u8 {
    let line = format!("{e:#}").replace('\n', " ");
    eprintln!("imu-emu: {line}");
    if e.chain().any(|c| c.is::<UsageError>()) {
        2
    } else {
        1
    }
}

/// Makes a panic print one line (`imu-emu: internal error: …`) instead of
/// the default message and backtrace, whatever `RUST_BACKTRACE` says.
pub fn one_line_panics() {
    std::panic::set_hook(Box::new(|info| {
        let what = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("imu-emu: internal error: {}{at}", what.replace('\n', " "));
    }));
}

/// Runs the program: sets up signals, the flash and the transport, powers
/// the device on and serves it until SIGINT/SIGTERM.
pub fn run(mut args: Args) -> anyhow::Result<()> {
    init_logging(args.verbose, args.quiet);
    match args.command {
        Some(Sub::Client(c)) => return imu_emu_tools::client::run(*c),
        Some(Sub::SensorProfile(s)) => return sensor_profile(&s),
        Some(Sub::Allan(a)) => return imu_emu_tools::allan::run(&a, &serve::run_unit),
        Some(Sub::IsbLayouts { json }) => return crate::isb_layouts::run(json),
        Some(Sub::Completions { shell }) => return print_all(&completions(shell)),
        Some(Sub::Man { command, dir }) => return man(&command, dir.as_deref()),
        None => {}
    }
    check_addresses(&args)?;
    check_combinations(&args)?;
    // Ticks run on absolute deadlines (ppoll timeouts): the kernel's
    // default timer slack (50 µs) would make every wake, and so every
    // frame and every feed sample's tick, up to 50 µs late. 1 ns is
    // the least (0 restores the default); the threads started below
    // inherit it. A failure (a kernel without it) only costs precision.
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1);
    // A bad profile file stops the program before anything listens.
    args.profiles =
        imu_emu_tools::profile_file::per_device(&args.sensor_profile, usize::from(args.count))
            .map_err(as_usage)?;
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // A second signal while shutting down exits at once.
        signal_hook::flag::register_conditional_shutdown(sig, 1, Arc::clone(&stop))
            .context("installing signal handlers")?;
        signal_hook::flag::register(sig, Arc::clone(&stop))
            .context("installing signal handlers")?;
    }
    if args.count > 1 {
        return many(&args, &stop);
    }
    match &args.flash {
        Some(path) => with_flash(FileNor::open(path)?, &args, &stop),
        None => with_flash(MemNor::new(), &args, &stop),
    }
}

/// Writes `text` to stdout; a reader that stops early (`| head`) is fine.
fn print_all(text: &[u8]) -> anyhow::Result<()> {
    match std::io::stdout().write_all(text) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// `e` as a usage error (exit status 2): a file named on the command line
/// that cannot be read or is not what the option takes.
fn as_usage(e: anyhow::Error) -> anyhow::Error {
    if e.chain().any(|c| c.is::<UsageError>()) {
        e
    } else {
        UsageError(format!("{e:#}")).into()
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use clap::Parser as _;
    use imu_emu_runner::clock::Speed;

    use super::*;

    #[test]
    fn defaults() {
        let a = Args::try_parse_from(["imu-emu"]).unwrap();
        assert_eq!(a.product().code(), "KERNEL-110-G2000-A40");
        assert_eq!(a.tcp, None);
        assert!(!a.pty);
        assert_eq!(a.seed, 0);
        assert_eq!(a.speed, Speed::Factor(1.0));
        assert_eq!(a.power_on, PowerOnAt::Connect);
        assert!(!a.allow_remote);
        let a = Args::try_parse_from(["imu-emu", "--power-on", "now"]).unwrap();
        assert_eq!(a.power_on, PowerOnAt::Now);
        assert!(Args::try_parse_from(["imu-emu", "--power-on", "later"]).is_err());
    }

    #[test]
    fn speed_takes_max_and_factors() {
        let a = Args::try_parse_from(["imu-emu", "--speed", "max"]).unwrap();
        assert_eq!(a.speed, Speed::Max);
        let a = Args::try_parse_from(["imu-emu", "--speed", "20"]).unwrap();
        assert_eq!(a.speed, Speed::Factor(20.0));
        assert!(Args::try_parse_from(["imu-emu", "--speed", "0"]).is_err());
    }

    #[test]
    fn model_takes_names_and_product_codes() {
        let a = Args::try_parse_from(["imu-emu", "--model", "K120"]).unwrap();
        assert_eq!(a.product().code(), "KERNEL-120-G2000-A40A90");
        let a = Args::try_parse_from(["imu-emu", "--model", "KERNEL-110-G2000-A8"]).unwrap();
        assert_eq!(a.product().measurement_range(), 0x93);
        assert!(Args::try_parse_from(["imu-emu", "--model", "K999"]).is_err());
    }

    #[test]
    fn transports_exclude_each_other() {
        assert!(Args::try_parse_from(["imu-emu", "--pty", "--tcp", "127.0.0.1:1"]).is_err());
        assert!(Args::try_parse_from(["imu-emu", "--link", "/tmp/x"]).is_err());
        let a = Args::try_parse_from(["imu-emu", "--pty", "--link", "/tmp/x"]).unwrap();
        assert!(a.pty);
    }

    #[test]
    fn count_is_one_to_max_and_numbers_the_files() {
        assert_eq!(Args::try_parse_from(["imu-emu"]).unwrap().count, 1);
        let a = Args::try_parse_from(["imu-emu", "--count", "50"]).unwrap();
        assert_eq!(a.count, 50);
        for bad in ["0", "1001", "-1", "x"] {
            assert!(
                Args::try_parse_from(["imu-emu", "--count", bad]).is_err(),
                "{bad}"
            );
        }
        assert_eq!(
            numbered(std::path::Path::new("/var/tmp/imu.flash"), 7),
            PathBuf::from("/var/tmp/imu.flash.7")
        );
    }
}
