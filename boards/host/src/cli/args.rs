//! The command line: the arguments ([`Args`], clap's derive), their
//! parsers, and what the program says about itself (completions, man
//! pages) from the same definition.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Parser;
use imu_emu::model::Product;

use imu_emu_runner::clock::Speed;
use imu_emu_tools::error::UsageError;
use imu_emu_tools::protocol::Protocol;

use super::print_all;

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
    #[arg(long, value_name = "SECONDS", default_value_t = imu_emu_runner::feed::DEFAULT_TIMEOUT_S,
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
          value_parser = clap::value_parser!(u16).range(1..=imu_emu_runner::fleet::MAX_COUNT as i64))]
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
    #[arg(long = "sensor-profile", value_name = "[K=]FILE", value_parser = imu_emu_tools::profile_file::parse_arg)]
    pub sensor_profile: Vec<imu_emu_tools::profile_file::ProfileArg>,

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
    Client(Box<imu_emu_tools::client::ClientArgs>),
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
    Allan(imu_emu_tools::allan::AllanArgs),
    /// Print the layouts of the ISB data sets the emulated IMX-5 serves
    /// (DID, name, struct, size, named fields with offset, kind and unit).
    #[command(name = "isb-layouts")]
    IsbLayouts {
        /// As JSON, one data set a line (what `scripts/isb-layouts.py` reads).
        #[arg(long)]
        json: bool,
    },
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

fn parse_timeout(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 && t <= 3600.0 => Ok(t),
        _ => Err(format!("a feed timeout is seconds in (0, 3600], not {s:?}")),
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
pub(super) fn man(path: &[String], dir: Option<&std::path::Path>) -> anyhow::Result<()> {
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
    if unix < imu_emu::time::GPS_EPOCH_UNIX_S {
        return Err(format!("{s}: before the GPS epoch 1980-01-06"));
    }
    Ok(unix)
}
