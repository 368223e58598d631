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
//! argument ([`UsageError`], [`crate::error`]), 1 for a failure while running.

use std::io::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context as _;
use clap::Parser;
use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, PowerOn};
use imu_emu::isb::Isb;
use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu::time::Instant;

use crate::clock::Speed;
use crate::error::UsageError;
use crate::flash::{FileNor, MemNor};
use crate::runner::{HostPersonality, Runner};
use crate::transport::{PtyTransport, TcpTransport, Transport};

/// Default TCP address.
pub const DEFAULT_TCP: &str = "127.0.0.1:7000";

/// A virtual Inertial Labs KERNEL IMU on a TCP port or a pseudo-terminal.
#[derive(Parser, Debug, Clone)]
#[command(name = "imu-emu", version, about)]
pub struct Args {
    /// The device's protocol: `kernel` (an Inertial Labs KERNEL, the
    /// default) or `isb` (an Inertial Sense IMX-5 speaking ISB: its IMU,
    /// INS, GNSS, magnetometer and barometer data sets; `--model` does not
    /// apply, the line starts at 921 600 bit/s).
    #[arg(long, value_name = "PROTOCOL", value_enum, default_value_t = Protocol::Kernel)]
    pub protocol: Protocol,

    /// Model name or product code: K100 K102 K108 K110 K110M K120 K201 K210
    /// K220, or e.g. KERNEL-110-G2000-A8 (a bare name takes the model's
    /// first product code) [default: K110]. KERNEL only.
    #[arg(long, value_name = "MODEL", value_parser = parse_product)]
    pub model: Option<Product>,

    /// Serve the UART on this TCP address (one client at a time; port 0
    /// picks a free port; loopback only without --allow-remote)
    /// [default: 127.0.0.1:7000].
    #[arg(long, value_name = "ADDR", conflicts_with = "pty")]
    pub tcp: Option<String>,

    /// Serve the UART on a pseudo-terminal (raw mode) instead of TCP.
    #[arg(long, conflicts_with = "serial")]
    pub pty: bool,

    /// Serve the UART on a real serial port (e.g. /dev/ttyUSB0, a USB-RS-422
    /// adapter) whose rate follows the device's line rate (Baud_Rate,
    /// CommitBaudRate). The device powers on at start.
    #[arg(long, value_name = "DEV", conflicts_with = "tcp")]
    pub serial: Option<PathBuf>,

    /// With --pty: also symlink the pty's slave at PATH (an existing
    /// symlink is replaced; removed at exit).
    #[arg(long, value_name = "PATH", requires = "pty")]
    pub link: Option<PathBuf>,

    /// Keep the device's 8 KiB flash image in FILE (created erased if
    /// missing): restarting the program is a power cycle that keeps saved
    /// parameters. Without it the flash lives in memory only.
    #[arg(long, value_name = "FILE")]
    pub flash: Option<PathBuf>,

    /// Serve the control socket on this TCP address: inject 1PPS/EXTRIG
    /// edges, faults, motion and link faults, power-cycle with BOOT, read
    /// the status and TOV edges (send `help` on it for every command;
    /// docs/tools.md). Its address is the second stdout line:
    /// `control on tcp ADDR`. Loopback only without --allow-remote.
    #[arg(long, value_name = "ADDR")]
    pub control: Option<String>,

    /// Serve a live web view on this TCP address (`127.0.0.1:8080`; port 0
    /// picks a free one): identity, status, rejections, link faults, live
    /// plots of the output and the truth, buttons for the control socket's
    /// commands. Its address is a stdout line: `web on http://ADDR/`.
    /// Loopback only without --allow-remote.
    #[arg(long, value_name = "ADDR")]
    pub web: Option<String>,

    /// Generate a 1PPS rising edge every second of device time (so it
    /// follows --speed).
    #[arg(long)]
    pub pps: bool,

    /// Replay the motion from a CSV file: `time_s, wx, wy, wz, fx, fy, fz[,
    /// temp_c]` (deg/s, g, unit axes), interpolated per tick.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,

    /// With --trajectory: start the file over after its last sample.
    #[arg(long, requires = "trajectory")]
    pub trajectory_loop: bool,

    /// The vehicle the unit rides on, from a file: a manoeuvre script
    /// (first statement `start lat lon height heading speed`) or a
    /// full-state CSV (header `time,lat,lon,height,vn,ve,vd,roll,pitch,yaw`
    /// then optionally `,wx,wy,wz,fx,fy,fz` and `,temp`); docs/motion.md.
    #[arg(long, value_name = "FILE", conflicts_with = "trajectory")]
    pub motion: Option<PathBuf>,

    /// Take the motion live from a simulator or HIL rig: TCP `HOST:PORT`
    /// or UDP `udp:HOST:PORT` (port 0 picks a free port; loopback only
    /// without --allow-remote). Text rows in the --trajectory format or
    /// binary samples (docs/feed.md). The address is a stdout line `feed
    /// on tcp ADDR`; with --count, device K's feed is on port + K.
    #[arg(long, value_name = "ADDR", conflicts_with_all = ["trajectory", "motion"])]
    pub motion_feed: Option<String>,

    /// With --motion-feed: device time advances only as samples arrive,
    /// to each sample's time (interpolated between samples); with
    /// `--speed max` as fast as the feed, otherwise no faster than
    /// --speed either.
    #[arg(long, requires = "motion_feed")]
    pub lockstep: bool,

    /// With --motion-feed (real time): after this many seconds without a
    /// sample the unit reports a sensor fault (KERNEL USW bit 1, IMX IMU
    /// status), the last sample holding; cleared by the next sample.
    #[arg(long, value_name = "SECONDS", default_value_t = crate::feed::DEFAULT_TIMEOUT_S,
          requires = "motion_feed", value_parser = parse_timeout)]
    pub feed_timeout: f64,

    /// With --count and --motion-feed: one feed for every device (at ADDR
    /// itself), each binary sample naming its device (text rows, which
    /// name none, are rejected).
    #[arg(long, requires = "motion_feed")]
    pub feed_shared: bool,

    /// Allow --tcp / --control on a non-loopback address (`0.0.0.0`, `[::]`, a
    /// LAN address). Whoever reaches the port can then save parameters,
    /// power-cycle the device and inject faults: the program says so on
    /// stderr at start.
    #[arg(long)]
    pub allow_remote: bool,

    /// When the device powers on: `connect` (default) when the first
    /// client connects (TCP) or first opens the pty, so it sees the
    /// AutoStart announcement; `now` at start (what it sends before a
    /// client connects is lost, as on a real line).
    #[arg(long, value_name = "WHEN", value_enum, default_value_t = PowerOnAt::Connect)]
    pub power_on: PowerOnAt,

    /// GPS time at power-on (ISB): an RFC 3339 date and time
    /// (`2026-03-01T12:00:00Z`) or a date (`2026-03-01`, midnight UTC),
    /// truncated to the second so that 1PPS edges (`--pps`) fall on GPS
    /// seconds; default: the host clock at power-on. It then advances with
    /// device time (`--speed`).
    #[arg(long, value_name = "DATE", value_parser = parse_gps_time)]
    pub gps_time: Option<u64>,

    /// Seed of the device's random processes (sensor noise, …); with
    /// --count, device K's seed is N + K.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,

    /// Run N independent devices in this one process, driven by one loop:
    /// device K listens on the --tcp port + K (a
    /// free port each with port 0) or on a pty of its own (--link PATH:
    /// PATH.K), keeps its flash in FILE.K (--flash FILE), has the seed
    /// --seed + K and powers on at its own first client. One stdout line
    /// `listening on …` per device, in order; one control socket for all
    /// (`dev K <command>`, `devices`). Not with --serial.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u16).range(1..=crate::fleet::MAX_COUNT as i64))]
    pub count: u16,

    /// Device seconds per host second: a factor (`1` real time, `10`,
    /// `0.5`) or `max` (as fast as the host computes and the client reads;
    /// nothing is dropped, a slow client slows device time down; time
    /// waits while the device has nothing to send and no input is pending,
    /// so with --seed a session repeats byte for byte). The line
    /// rate, `--pps`, the trajectory and the control socket all follow
    /// device time.
    #[arg(long, value_name = "SPEED", default_value = "1")]
    pub speed: Speed,

    /// More log lines on stderr: `-v` every command the device received,
    /// every frame it rejected or ignored and why, parameters saved; `-vv`
    /// also control commands and transport events.
    #[arg(short, long, action = clap::ArgAction::Count, conflicts_with = "quiet")]
    pub verbose: u8,

    /// Only errors on stderr (no warnings).
    #[arg(short, long)]
    pub quiet: bool,

    /// Use the sensor profile in FILE (TOML; `imu-emu sensor-profile show
    /// K110` prints a built-in one to start from) instead of the model's
    /// built-in one. With --count, `K=FILE` is for device K only (and wins
    /// over a plain FILE, which is for every device); repeatable.
    #[arg(long = "sensor-profile", value_name = "[K=]FILE", value_parser = crate::profile_file::parse_arg)]
    pub sensor_profile: Vec<crate::profile_file::ProfileArg>,

    /// The profiles of `--sensor-profile`, loaded at start (one a device).
    #[arg(skip)]
    pub profiles: Vec<Option<&'static imu_emu::sensor::SensorProfile>>,

    /// A subcommand instead of the emulator (`imu-emu client --help`).
    #[command(subcommand)]
    pub command: Option<Sub>,
}

impl Args {
    /// The KERNEL product emulated: `--model`, else K110's first product
    /// code.
    pub fn product(&self) -> Product {
        self.model
            .or_else(|| Product::parse(DEFAULT_MODEL).ok())
            .unwrap_or_else(Product::imx5)
    }
}

/// The model emulated without `--model`.
pub const DEFAULT_MODEL: &str = "K110";

/// Subcommands of `imu-emu`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Sub {
    /// Talk to a unit (the emulator or a real one; a KERNEL, or an IMX-5
    /// with --protocol isb) over TCP or a serial port: info, bit, start,
    /// stop, get, set, commit-baud, udd, record, decode, plot.
    Client(Box<crate::client::ClientArgs>),
    /// Print a shell completion script (from this command-line
    /// definition): `imu-emu completions bash > ~/.local/share/bash-completion/completions/imu-emu`.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print a man page (roff, from this command-line definition):
    /// `imu-emu man > imu-emu.1; man ./imu-emu.1`; a subcommand's with its
    /// path (`imu-emu man client record` is imu-emu-client-record(1)), or
    /// every page into a folder (`--dir`).
    Man {
        /// The subcommand whose page to print (`client`, `client
        /// record`, `sensor-profile show`); none: imu-emu(1).
        command: Vec<String>,
        /// Write every page (imu-emu.1, imu-emu-client.1, …) into DIR (it
        /// must exist) instead, one file a page.
        #[arg(long, value_name = "DIR", conflicts_with = "command")]
        dir: Option<PathBuf>,
    },
    /// Sensor profiles: `show NAME` prints a built-in one (K100 … K220,
    /// IMX-5, IMX-5-2022) as a file to start from; `check FILE` reads one.
    #[command(name = "sensor-profile", subcommand)]
    SensorProfile(ProfileSub),
    /// The Allan deviation of a unit run in process (or of a `client
    /// record` CSV): the fitted ARW/VRW, bias instability and rate random
    /// walk beside the profile's, and a log-log plot (PNG, SVG).
    Allan(crate::allan::AllanArgs),
}

/// `imu-emu sensor-profile …`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum ProfileSub {
    /// Print the built-in profile NAME (K100 K102 K108 K110 K110M K120
    /// K201 K210 K220 IMX-5 IMX-5-2022) as a TOML file.
    Show {
        /// Model name.
        #[arg(value_parser = ProfileName)]
        name: String,
    },
    /// Read FILE and print it back as the emulator understood it (or the
    /// error, naming the key and its allowed range).
    Check {
        /// The profile file.
        file: PathBuf,
    },
}

/// `sensor-profile show NAME`: any text (the lookup, any case, says
/// what it has), with the built-in profiles' names as its possible values
/// so that the completions offer them.
#[derive(Debug, Clone, Copy)]
struct ProfileName;

impl clap::builder::TypedValueParser for ProfileName {
    type Value = String;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        _arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<String, clap::Error> {
        Ok(value.to_string_lossy().into_owned())
    }

    fn possible_values(
        &self,
    ) -> Option<Box<dyn Iterator<Item = clap::builder::PossibleValue> + '_>> {
        Some(Box::new(
            imu_emu::sensor::profiles::BUILTIN
                .iter()
                .map(|b| clap::builder::PossibleValue::new(b.name)),
        ))
    }
}

/// Runs `imu-emu sensor-profile …`.
fn sensor_profile(sub: &ProfileSub) -> anyhow::Result<()> {
    let text = match sub {
        ProfileSub::Show { name } => {
            let b = crate::profile_file::builtin(name)?;
            crate::profile_file::to_toml(b.profile, b.has_aux(), b.name, b.source)
        }
        ProfileSub::Check { file } => {
            let (p, aux) = crate::profile_file::load_with_aux(file)?;
            crate::profile_file::to_toml(&p, aux, &file.display().to_string(), "this file")
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

/// The emulated device's protocol (`--protocol`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Protocol {
    /// Inertial Labs KERNEL (ICD rev 1.42).
    Kernel,
    /// Inertial Sense IMX-5 over ISB (protocol 2.1).
    Isb,
}

/// When the device powers on (`--power-on`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PowerOnAt {
    /// When the first client connects (TCP) or first opens the pty.
    Connect,
    /// At program start.
    Now,
}

fn parse_product(s: &str) -> Result<Product, String> {
    Product::parse(s).map_err(|e| e.to_string())
}

/// Checks that `addr` (`HOST:PORT`) given to `option` is a loopback
/// address, or that `--allow-remote` allows any; a name is resolved and
/// every address it resolves to must be loopback. Returns whether the
/// address is remote (to warn about).
pub fn check_local(option: &str, addr: &str, allow_remote: bool) -> anyhow::Result<bool> {
    use std::net::ToSocketAddrs as _;
    let addrs: Vec<std::net::SocketAddr> = addr
        .to_socket_addrs()
        .map_err(|e| {
            UsageError(format!(
                "{option} {addr}: {e}; expected HOST:PORT, e.g. {option} 127.0.0.1:7000"
            ))
        })?
        .collect();
    let remote = addrs.is_empty() || addrs.iter().any(|a| !a.ip().is_loopback());
    if remote && !allow_remote {
        return Err(UsageError(format!(
            "{option} {addr}: not a loopback address: it would expose SaveFlash, power \
             cycle and fault injection to the network; add --allow-remote to allow it"
        ))
        .into());
    }
    Ok(remote)
}

fn parse_timeout(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 && t <= 3600.0 => Ok(t),
        _ => Err(format!("a feed timeout is seconds in (0, 3600], not {s:?}")),
    }
}

/// The feed's clock and timeout from the arguments, if there is a feed.
fn feed_config(args: &Args) -> Option<crate::feed::FeedConfig> {
    args.motion_feed.as_ref()?;
    Some(crate::feed::FeedConfig {
        lockstep: args.lockstep,
        timeout_ns: (args.feed_timeout * 1e9) as u64,
    })
}

/// `addr` with its port moved on by `k` (port 0 stays 0: a free port
/// each), for device K of a `--count` run.
fn port_plus(option: &str, addr: &str, k: usize, count: u16) -> anyhow::Result<String> {
    let sock: std::net::SocketAddr = addr
        .parse()
        .map_err(|_| UsageError(format!("{option} {addr}: expected IP:PORT with --count")))?;
    let port = match sock.port() {
        0 => 0,
        p => u16::try_from(usize::from(p) + k).map_err(|_| {
            UsageError(format!(
                "{option} {addr} --count {count}: ports beyond 65535"
            ))
        })?,
    };
    Ok(std::net::SocketAddr::new(sock.ip(), port).to_string())
}

/// Checks the listening addresses before anything is opened; warns loudly
/// on stderr about each remote one `--allow-remote` lets through.
fn check_addresses(args: &Args) -> anyhow::Result<()> {
    let mut wanted = Vec::new();
    if !args.pty && args.serial.is_none() {
        wanted.push(("--tcp", args.tcp.as_deref().unwrap_or(DEFAULT_TCP)));
    }
    if let Some(c) = &args.control {
        wanted.push(("--control", c.as_str()));
    }
    if let Some(f) = &args.motion_feed {
        wanted.push((
            "--motion-feed",
            f.strip_prefix("udp:")
                .or(f.strip_prefix("tcp:"))
                .unwrap_or(f),
        ));
    }
    if args.feed_shared && args.count < 2 {
        return Err(UsageError("--feed-shared goes with --count N (N > 1)".into()).into());
    }
    if let Some(w) = &args.web {
        wanted.push(("--web", w.as_str()));
    }
    for (option, addr) in wanted {
        if check_local(option, addr, args.allow_remote)? {
            eprintln!(
                "imu-emu: WARNING: {option} {addr} is reachable from the network \
                 (--allow-remote): anyone who connects can save parameters, \
                 power-cycle the device and inject faults"
            );
        }
    }
    Ok(())
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
        Some(Sub::Client(c)) => return crate::client::run(*c),
        Some(Sub::SensorProfile(s)) => return sensor_profile(&s),
        Some(Sub::Allan(a)) => return crate::allan::run(&a),
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
    args.profiles = crate::profile_file::per_device(&args.sensor_profile, usize::from(args.count))
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

/// The completion script for `shell`, from the command-line definition.
///
/// clap_complete's bash script (4.6.12) spells the states of a
/// hyphenated program's subcommands two ways: the loop that walks the
/// words sets `imu__emu__subcmd__client`, the case labels read
/// `imu__subcmd__emu__subcmd__client`, so nothing past the first word
/// completed. The labels are respelled the loop's way (zsh and fish keep
/// the name verbatim; fish gets the positional values it lacks,
/// `fish_positionals`).
pub fn completions(shell: clap_complete::Shell) -> Vec<u8> {
    let mut cmd = <Args as clap::CommandFactory>::command();
    let mut text = Vec::new();
    clap_complete::generate(shell, &mut cmd, "imu-emu", &mut text);
    match shell {
        clap_complete::Shell::Bash => String::from_utf8_lossy(&text)
            .replace("imu__subcmd__emu", "imu__emu")
            .into_bytes(),
        clap_complete::Shell::Fish => {
            text.extend_from_slice(fish_positionals().as_bytes());
            text
        }
        _ => text,
    }
}

/// clap_complete's fish script (4.6.12) completes options and
/// subcommands but no positional argument's values (`completions
/// <SHELL>`, `sensor-profile show <NAME>`): one line each, in the script's
/// own conditions.
fn fish_positionals() -> String {
    let mut cmd = <Args as clap::CommandFactory>::command();
    cmd.build();
    let mut out = String::new();
    let mut line = |cond: String, c: &clap::Command| {
        for a in c.get_positionals() {
            let vals: Vec<String> = a
                .get_possible_values()
                .iter()
                .filter(|v| !v.is_hide_set())
                .map(|v| v.get_name().to_owned())
                .collect();
            if !vals.is_empty() {
                out.push_str(&format!(
                    "complete -c imu-emu -n \"{cond}\" -f -a \"{}\"\n",
                    vals.join(" ")
                ));
            }
        }
    };
    for sub in cmd.get_subcommands() {
        let name = sub.get_name();
        line(format!("__fish_imu_emu_using_subcommand {name}"), sub);
        for sub2 in sub.get_subcommands() {
            line(
                format!(
                    "__fish_imu_emu_using_subcommand {name}; and __fish_seen_subcommand_from {}",
                    sub2.get_name()
                ),
                sub2,
            );
        }
    }
    out
}

/// `imu-emu man [COMMAND…] [--dir DIR]`: the page of the command at that
/// path, or every page into DIR. The `help` subcommands have no page (the
/// pages list none).
fn man(path: &[String], dir: Option<&std::path::Path>) -> anyhow::Result<()> {
    let mut cmd = <Args as clap::CommandFactory>::command().disable_help_subcommand(true);
    cmd.build();
    if let Some(d) = dir {
        clap_mangen::generate_to(cmd, d).with_context(|| format!("man --dir {}", d.display()))?;
        return Ok(());
    }
    let mut page = &cmd;
    for (i, w) in path.iter().enumerate() {
        page = page.find_subcommand(w).ok_or_else(|| {
            let names: Vec<&str> = page.get_subcommands().map(|c| c.get_name()).collect();
            UsageError(format!(
                "man: `{}` has no subcommand {w}; it has: {}",
                std::iter::once("imu-emu")
                    .chain(path[..i].iter().map(String::as_str))
                    .collect::<Vec<_>>()
                    .join(" "),
                names.join(" ")
            ))
        })?;
    }
    let mut text = Vec::new();
    clap_mangen::Man::new(page.clone()).render(&mut text)?;
    print_all(&text)
}

/// The web view of `--web`, if asked for: its hub and its running server
/// (which stops when dropped).
fn web_view(
    args: &Args,
    product: Product,
    name: &str,
    places: &[String],
) -> anyhow::Result<Option<(Arc<crate::web::Hub>, crate::web::Server)>> {
    let Some(addr) = &args.web else {
        return Ok(None);
    };
    let hub = crate::web::Hub::new(args.protocol, product, name, places);
    let server = crate::web::Server::start(addr, Arc::clone(&hub))?;
    Ok(Some((hub, server)))
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

/// Options that parse but make no sense together: refused rather than
/// ignored.
fn check_combinations(args: &Args) -> anyhow::Result<()> {
    if args.protocol == Protocol::Kernel && args.gps_time.is_some() {
        return Err(UsageError(
            "--gps-time sets an IMX-5's GPS time (--protocol isb); a KERNEL keeps no GPS time"
                .into(),
        )
        .into());
    }
    if args.protocol == Protocol::Isb {
        if let Some(m) = &args.model {
            return Err(UsageError(format!(
                "--model {} is a KERNEL model; --protocol isb emulates an IMX-5 (drop --model)",
                m.model.short
            ))
            .into());
        }
    }
    if args.link.is_some() && !args.pty {
        return Err(UsageError(
            "--link names the pty's slave: it goes with --pty, not with --tcp or --serial".into(),
        )
        .into());
    }
    Ok(())
}

/// Device K's file for a --flash or --link PATH of a many-device run.
pub fn numbered(path: &std::path::Path, k: usize) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(format!(".{k}"));
    PathBuf::from(p)
}

/// `--count N`: N devices in one loop ([`crate::fleet`]).
fn many(args: &Args, stop: &AtomicBool) -> anyhow::Result<()> {
    if args.serial.is_some() {
        return Err(
            UsageError("--count does not go with --serial (one port, one device)".into()).into(),
        );
    }
    let n = usize::from(args.count);
    open_files_for(n);
    let started = std::cell::Cell::new(false);
    match &args.flash {
        Some(path) => {
            let files: Vec<PathBuf> = (0..n).map(|k| numbered(path, k)).collect();
            let new: Vec<&PathBuf> = files
                .iter()
                .filter(|p| std::fs::symlink_metadata(p).is_err())
                .collect();
            let r = files
                .iter()
                .map(|p| FileNor::open(p))
                .collect::<anyhow::Result<Vec<_>>>()
                .and_then(|flashes| many_with(flashes, args, stop, &started));
            if r.is_err() && !started.get() {
                // A start that failed leaves no FILE.K it created.
                for p in new {
                    let _ = std::fs::remove_file(p);
                }
            }
            r
        }
        None => many_with(
            (0..n).map(|_| MemNor::new()).collect(),
            args,
            stop,
            &started,
        ),
    }
}

/// Raises the soft limit of open descriptors towards the hard one when N
/// devices need more than it allows (a listener, a client and a flash
/// file each, the control socket and a margin); says so when even the
/// hard limit is too low (binding then fails with a clear error).
fn open_files_for(n: usize) {
    use nix::sys::resource::{getrlimit, setrlimit, Resource};
    let need = (3 * n + 64) as u64;
    let Ok((soft, hard)) = getrlimit(Resource::RLIMIT_NOFILE) else {
        return;
    };
    if soft >= need {
        return;
    }
    let want = need.min(hard);
    if want > soft && setrlimit(Resource::RLIMIT_NOFILE, want, hard).is_ok() {
        tracing::info!("open-file limit raised from {soft} to {want} for {n} devices");
    }
    if want < need {
        eprintln!(
            "imu-emu: warning: {n} devices need about {need} open files, the limit is {hard} \
             (ulimit -n)"
        );
    }
}

/// `started` is set once every device is set up and the fleet runs.
fn many_with<F: NorFlash>(
    flashes: Vec<F>,
    args: &Args,
    stop: &AtomicBool,
    started: &std::cell::Cell<bool>,
) -> anyhow::Result<()> {
    match args.protocol {
        Protocol::Kernel => many_transports::<F, Kernel>(flashes, args, stop, started),
        Protocol::Isb => many_transports::<F, Isb>(flashes, args, stop, started),
    }
}

fn many_transports<F: NorFlash, P: HostPersonality>(
    flashes: Vec<F>,
    args: &Args,
    stop: &AtomicBool,
    started: &std::cell::Cell<bool>,
) -> anyhow::Result<()> {
    let rate = factory_rate(args.protocol);
    if args.pty {
        let mut parts = Vec::with_capacity(flashes.len());
        for (k, f) in flashes.into_iter().enumerate() {
            let link = args.link.as_deref().map(|p| numbered(p, k));
            parts.push((f, PtyTransport::open(rate, link.as_deref())?));
        }
        serve_many::<F, _, P>(parts, args, stop, started)
    } else {
        let addr = args.tcp.as_deref().unwrap_or(DEFAULT_TCP);
        let mut parts = Vec::with_capacity(flashes.len());
        for (k, f) in flashes.into_iter().enumerate() {
            let a = port_plus("--tcp", addr, k, args.count)?;
            parts.push((f, TcpTransport::bind(&a)?));
        }
        serve_many::<F, _, P>(parts, args, stop, started)
    }
}

/// `--motion FILE`, loaded (and said on stderr), if given.
fn load_vehicle(args: &Args) -> anyhow::Result<Option<crate::vehicle::VehicleSource>> {
    let Some(path) = &args.motion else {
        return Ok(None);
    };
    // A file that does not load is a bad argument, as a bad
    // --sensor-profile is (exit status 2).
    let v = crate::vehicle::VehicleSource::load(path)
        .map_err(|e| as_usage(e.context(format!("--motion {}", path.display()))))?;
    eprintln!("imu-emu: motion {}: {}", path.display(), v.describe());
    Ok(Some(v))
}

fn serve_many<F: NorFlash, T: Transport, P: HostPersonality>(
    parts: Vec<(F, T)>,
    args: &Args,
    stop: &AtomicBool,
    started: &std::cell::Cell<bool>,
) -> anyhow::Result<()> {
    let trajectory = match &args.trajectory {
        Some(path) => Some(crate::trajectory::Trajectory::load(
            path,
            args.trajectory_loop,
        )?),
        None => None,
    };
    let vehicle = load_vehicle(args)?;
    let control = match &args.control {
        Some(addr) => Some(crate::control::Control::bind(addr)?),
        None => None,
    };
    let mut feeds = Vec::new();
    if let Some(f) = &args.motion_feed {
        let addr = crate::feed::FeedAddr::parse(f);
        let n = if args.feed_shared { 1 } else { parts.len() };
        for k in 0..n {
            let a = addr.with(port_plus("--motion-feed", addr.host_port(), k, args.count)?);
            feeds.push(crate::feed::FeedSocket::bind(&a)?);
        }
    }
    let (product, name) = product_of(args);
    let places: Vec<String> = parts.iter().map(|(_, t)| t.describe()).collect();
    let web = web_view(args, product, &name, &places)?;
    let mut out = std::io::stdout().lock();
    for p in &places {
        writeln!(out, "listening on {p}")?;
    }
    if let Some(c) = &control {
        writeln!(out, "control on tcp {}", c.local_addr()?)?;
    }
    for f in &feeds {
        writeln!(out, "feed on {}", f.describe())?;
    }
    if let Some((_, server)) = &web {
        writeln!(out, "web on http://{}/", server.addr)?;
    }
    out.flush()?;
    drop(out);
    let setup = crate::fleet::Setup {
        product,
        name,
        speed: args.speed,
        seed: args.seed,
        profiles: args.profiles.clone(),
        pps: args.pps,
        trajectory,
        vehicle,
        power_on_now: args.power_on == PowerOnAt::Now,
        web: web.as_ref().map(|(hub, _)| Arc::clone(hub)),
        gps_time: args.gps_time,
        feed: feed_config(args),
    };
    eprintln!(
        "imu-emu: {} devices ({}), flash {}; each powers on {}",
        parts.len(),
        setup.name,
        args.flash.as_ref().map_or_else(
            || "in memory".to_owned(),
            |p| format!("{}", numbered(p, 0).with_extension("K").display())
        ),
        if setup.power_on_now {
            "now"
        } else {
            "when its first client connects"
        }
    );
    let shared = args.feed_shared;
    let mut fleet =
        crate::fleet::Fleet::<F, T, P>::new(parts, setup, control).with_feeds(feeds, shared);
    started.set(true);
    fleet.run(stop)?;
    eprintln!("imu-emu: stopped");
    Ok(())
}

/// The rate a port starts at: the protocol's factory rate (KERNEL
/// Baud_Rate 115 200, IMX ser0BaudRate 921 600), so a client that opens it
/// before the device powers on sees the rate a factory unit starts at.
fn factory_rate(protocol: Protocol) -> u32 {
    match protocol {
        Protocol::Kernel => 115_200,
        Protocol::Isb => imu_emu::isb::sets::flash::DEFAULT_BAUD_RATE,
    }
}

/// The product a run emulates and its name in messages.
fn product_of(args: &Args) -> (Product, String) {
    match args.protocol {
        Protocol::Kernel => {
            let m = args.product();
            (m, m.code().to_string())
        }
        Protocol::Isb => (Product::imx5(), "IMX-5 (ISB)".to_owned()),
    }
}

fn with_flash<F: NorFlash>(flash: F, args: &Args, stop: &AtomicBool) -> anyhow::Result<()> {
    match args.protocol {
        Protocol::Kernel => with_transport::<F, Kernel>(flash, args, stop),
        Protocol::Isb => with_transport::<F, Isb>(flash, args, stop),
    }
}

fn with_transport<F: NorFlash, P: HostPersonality>(
    flash: F,
    args: &Args,
    stop: &AtomicBool,
) -> anyhow::Result<()> {
    let rate = factory_rate(args.protocol);
    if let Some(dev) = &args.serial {
        let t = crate::transport::SerialTransport::open(dev, rate)?;
        serve::<F, _, P>(flash, t, args, stop)
    } else if args.pty {
        let t = PtyTransport::open(rate, args.link.as_deref())?;
        serve::<F, _, P>(flash, t, args, stop)
    } else {
        let t = TcpTransport::bind(args.tcp.as_deref().unwrap_or(DEFAULT_TCP))?;
        serve::<F, _, P>(flash, t, args, stop)
    }
}

fn serve<F: NorFlash, T: Transport, P: HostPersonality>(
    flash: F,
    mut transport: T,
    args: &Args,
    stop: &AtomicBool,
) -> anyhow::Result<()> {
    let trajectory = match &args.trajectory {
        Some(path) => {
            let t = crate::trajectory::Trajectory::load(path, args.trajectory_loop)?;
            eprintln!(
                "imu-emu: trajectory {} ({} samples)",
                path.display(),
                t.len()
            );
            Some(t)
        }
        None => None,
    };
    let vehicle = load_vehicle(args)?;
    let mut control = match &args.control {
        Some(addr) => Some(crate::control::Control::bind(addr)?),
        None => None,
    };
    let feed = match &args.motion_feed {
        Some(a) => Some(crate::feed::FeedSocket::bind(
            &crate::feed::FeedAddr::parse(a),
        )?),
        None => None,
    };
    let (product, name) = product_of(args);
    let web = web_view(args, product, &name, &[transport.describe()])?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "listening on {}", transport.describe())?;
    if let Some(c) = &control {
        writeln!(out, "control on tcp {}", c.local_addr()?)?;
    }
    if let Some(f) = &feed {
        writeln!(out, "feed on {}", f.describe())?;
    }
    if let Some((_, server)) = &web {
        writeln!(out, "web on http://{}/", server.addr)?;
    }
    out.flush()?;
    drop(out);

    // A serial port counts as connected at once: no message then.
    if args.power_on == PowerOnAt::Connect && !transport.poll_client()? {
        eprintln!("imu-emu: the device powers on when a client connects (--power-on now: at once)");
        loop {
            if stop.load(std::sync::atomic::Ordering::Relaxed) {
                eprintln!("imu-emu: stopped");
                return Ok(());
            }
            if let Some(c) = control.as_mut() {
                c.poll(&mut |cmd| match cmd {
                    crate::control::Command::Status => Ok("mode=off".to_owned()),
                    crate::control::Command::Devices => {
                        Ok(crate::control::devices_reply(&[transport.describe()]))
                    }
                    _ => Err(
                        "the device is off: it powers on when a client connects to the UART \
                         (or use --power-on now)"
                            .to_owned(),
                    ),
                })?;
            }
            transport.wait(crate::runner::IDLE_WAKE)?;
            if transport.poll_client()? {
                break;
            }
        }
    }
    let epoch = std::time::Instant::now();
    let cfg = PowerOn {
        product,
        boot: None,
        seed: args.seed,
    };
    let profile = args.profiles.first().copied().flatten();
    let mut dev = Device::<F, P>::with_profile(cfg, profile, flash, Instant::ZERO);
    dev.personality_mut()
        .set_gps_time(crate::clock::gps_s_at_power_on(args.gps_time));
    transport.set_line_rate(dev.line_rate())?;
    eprintln!(
        "imu-emu: {} powered on at {} bit/s, internal rate {} Hz, flash {}",
        name,
        dev.line_rate(),
        product.model.internal_rate_hz,
        args.flash
            .as_ref()
            .map_or_else(|| "in memory".to_owned(), |p| p.display().to_string()),
    );

    let mut runner = Runner::new(dev, transport, epoch)
        .with_speed(args.speed)
        .with_seed(args.seed);
    if let Some(c) = control {
        runner = runner.with_control(c);
    }
    if let Some(tap) = web.as_ref().and_then(|(hub, _)| hub.tap(0)) {
        runner = runner.with_web(tap);
    }
    if args.pps {
        runner = runner.with_pps();
    }
    if let Some(t) = trajectory {
        runner = runner.with_trajectory(t);
    }
    if let Some(v) = vehicle {
        runner = runner.with_vehicle(v);
    }
    if let (Some(cfg), Some(sock)) = (feed_config(args), feed) {
        let state = crate::feed::FeedState::new(cfg, 0, true, "");
        runner = runner.with_feed(state, Some(sock));
    }
    runner.run(stop)?;
    eprintln!("imu-emu: stopped");
    Ok(())
}

/// `--gps-time`: Unix seconds (UTC) of an RFC 3339 date and time or a
/// date (midnight UTC), truncated to the second.
fn parse_gps_time(s: &str) -> Result<u64, String> {
    let full = if s.len() == 10 {
        format!("{s}T00:00:00Z")
    } else {
        s.to_owned()
    };
    let t = humantime::parse_rfc3339_weak(&full).map_err(|e| format!("{s}: {e}"))?;
    let unix = t
        .duration_since(std::time::UNIX_EPOCH)
        .map_err(|_| format!("{s}: before 1970"))?
        .as_secs();
    if unix < imu_emu::isb::GPS_EPOCH_UNIX_S {
        return Err(format!("{s}: before the GPS epoch 1980-01-06"));
    }
    Ok(unix)
}

#[cfg(test)]
mod tests {
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
