//! Serving: the checks of a serving command line, then one device
//! ([`with_flash`]) or a fleet ([`many`]) built from the arguments and
//! run until SIGINT/SIGTERM — the one place the protocol choice becomes
//! a type (`Kernel` or `Isb`, then generic over
//! [`HostProtocol`]).

use std::io::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, PowerOn};
use imu_emu::isb::Isb;
use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu::time::Instant;

use imu_emu_runner::flash::{FileNor, MemNor};
use imu_emu_runner::protocol::HostProtocol;
use imu_emu_runner::runner::Runner;
use imu_emu_runner::transport::{PtyTransport, TcpTransport, Transport};
use imu_emu_tools::allan::Unit;
use imu_emu_tools::error::UsageError;
use imu_emu_tools::protocol::Protocol;

use super::args::{Args, PowerOnAt, DEFAULT_TCP};
use super::as_usage;

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

/// The feed's clock and timeout from the arguments, if there is a feed.
fn feed_config(args: &Args) -> Option<imu_emu_runner::feed::FeedConfig> {
    args.motion_feed.as_ref()?;
    Some(imu_emu_runner::feed::FeedConfig {
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
pub(super) fn check_addresses(args: &Args) -> anyhow::Result<()> {
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

/// The web view of `--web`, if asked for: its hub and its running server
/// (which stops when dropped).
fn web_view<P: HostProtocol>(
    args: &Args,
    product: Product,
    name: &str,
    places: &[String],
) -> anyhow::Result<Option<(Arc<imu_emu_runner::web::Hub>, imu_emu_runner::web::Server)>> {
    let Some(addr) = &args.web else {
        return Ok(None);
    };
    let hub = imu_emu_runner::web::Hub::new(P::live(), product, name, places);
    let server = imu_emu_runner::web::Server::start(addr, Arc::clone(&hub))?;
    Ok(Some((hub, server)))
}

/// Options that parse but make no sense together: refused rather than
/// ignored.
pub(super) fn check_combinations(args: &Args) -> anyhow::Result<()> {
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

/// `--count N`: N devices in one loop ([`imu_emu_runner::fleet`]).
pub(super) fn many(args: &Args, stop: &AtomicBool) -> anyhow::Result<()> {
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
/// A run once its protocol is a type.
trait Run {
    /// What the run gives back.
    type Out;
    fn run<P: HostProtocol>(self) -> anyhow::Result<Self::Out>;
}

/// `run` for the protocol of `--protocol` (or of the unit `imu-emu allan`
/// runs): the one place the choice becomes a type.
fn with_protocol<R: Run>(protocol: Protocol, run: R) -> anyhow::Result<R::Out> {
    match protocol {
        Protocol::Kernel => run.run::<Kernel>(),
        Protocol::Isb => run.run::<Isb>(),
    }
}

/// A fleet's run.
struct Many<'a, F> {
    flashes: Vec<F>,
    args: &'a Args,
    stop: &'a AtomicBool,
    started: &'a std::cell::Cell<bool>,
}

impl<F: NorFlash> Run for Many<'_, F> {
    type Out = ();
    fn run<P: HostProtocol>(self) -> anyhow::Result<()> {
        many_transports::<F, P>(self.flashes, self.args, self.stop, self.started)
    }
}

/// One device's run.
struct One<'a, F> {
    flash: F,
    args: &'a Args,
    stop: &'a AtomicBool,
}

impl<F: NorFlash> Run for One<'_, F> {
    type Out = ();
    fn run<P: HostProtocol>(self) -> anyhow::Result<()> {
        with_transport::<F, P>(self.flash, self.args, self.stop)
    }
}

/// The unit `imu-emu allan` runs in process ([`imu_emu_tools::allan::Unit`]).
struct AllanUnit<'a> {
    unit: &'a Unit,
    sample: &'a mut dyn FnMut(&[f64]),
}

impl Run for AllanUnit<'_> {
    type Out = String;
    fn run<P: HostProtocol>(self) -> anyhow::Result<String> {
        P::run_unit(self.unit, self.sample)
    }
}

/// Runs `unit` in process, as its protocol's runner does
/// ([`HostProtocol::run_unit`]): `imu-emu allan`'s [`imu_emu_tools::allan::RunUnit`].
pub fn run_unit(unit: &Unit, sample: &mut dyn FnMut(&[f64])) -> anyhow::Result<String> {
    with_protocol(unit.protocol, AllanUnit { unit, sample })
}

fn many_with<F: NorFlash>(
    flashes: Vec<F>,
    args: &Args,
    stop: &AtomicBool,
    started: &std::cell::Cell<bool>,
) -> anyhow::Result<()> {
    let run = Many {
        flashes,
        args,
        stop,
        started,
    };
    with_protocol(args.protocol, run)
}

fn many_transports<F: NorFlash, P: HostProtocol>(
    flashes: Vec<F>,
    args: &Args,
    stop: &AtomicBool,
    started: &std::cell::Cell<bool>,
) -> anyhow::Result<()> {
    let rate = P::FACTORY_RATE;
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
fn load_vehicle(args: &Args) -> anyhow::Result<Option<imu_emu_runner::vehicle::VehicleSource>> {
    let Some(path) = &args.motion else {
        return Ok(None);
    };
    // A file that does not load is a bad argument, as a bad
    // --sensor-profile is (exit status 2).
    let v = imu_emu_runner::vehicle::VehicleSource::load(path)
        .map_err(|e| as_usage(e.context(format!("--motion {}", path.display()))))?;
    eprintln!("imu-emu: motion {}: {}", path.display(), v.describe());
    Ok(Some(v))
}

fn serve_many<F: NorFlash, T: Transport, P: HostProtocol>(
    parts: Vec<(F, T)>,
    args: &Args,
    stop: &AtomicBool,
    started: &std::cell::Cell<bool>,
) -> anyhow::Result<()> {
    let trajectory = match &args.trajectory {
        Some(path) => Some(imu_emu_runner::trajectory::Trajectory::load(
            path,
            args.trajectory_loop,
        )?),
        None => None,
    };
    let vehicle = load_vehicle(args)?;
    let control = match &args.control {
        Some(addr) => Some(imu_emu_runner::control::Control::bind(addr)?),
        None => None,
    };
    let mut feeds = Vec::new();
    if let Some(f) = &args.motion_feed {
        let addr = imu_emu_runner::feed::FeedAddr::parse(f);
        let n = if args.feed_shared { 1 } else { parts.len() };
        for k in 0..n {
            let a = addr.with(port_plus("--motion-feed", addr.host_port(), k, args.count)?);
            feeds.push(imu_emu_runner::feed::FeedSocket::bind(&a)?);
        }
    }
    let (product, name) = P::product(args.product());
    let places: Vec<String> = parts.iter().map(|(_, t)| t.describe()).collect();
    let web = web_view::<P>(args, product, &name, &places)?;
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
    let setup = imu_emu_runner::fleet::Setup {
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
    let mut fleet = imu_emu_runner::fleet::Fleet::<F, T, P>::new(parts, setup, control)
        .with_feeds(feeds, shared);
    started.set(true);
    fleet.run(stop)?;
    eprintln!("imu-emu: stopped");
    Ok(())
}

pub(super) fn with_flash<F: NorFlash>(
    flash: F,
    args: &Args,
    stop: &AtomicBool,
) -> anyhow::Result<()> {
    with_protocol(args.protocol, One { flash, args, stop })
}

fn with_transport<F: NorFlash, P: HostProtocol>(
    flash: F,
    args: &Args,
    stop: &AtomicBool,
) -> anyhow::Result<()> {
    let rate = P::FACTORY_RATE;
    if let Some(dev) = &args.serial {
        let t = imu_emu_runner::transport::SerialTransport::open(dev, rate)?;
        serve::<F, _, P>(flash, t, args, stop)
    } else if args.pty {
        let t = PtyTransport::open(rate, args.link.as_deref())?;
        serve::<F, _, P>(flash, t, args, stop)
    } else {
        let t = TcpTransport::bind(args.tcp.as_deref().unwrap_or(DEFAULT_TCP))?;
        serve::<F, _, P>(flash, t, args, stop)
    }
}

fn serve<F: NorFlash, T: Transport, P: HostProtocol>(
    flash: F,
    mut transport: T,
    args: &Args,
    stop: &AtomicBool,
) -> anyhow::Result<()> {
    let trajectory = match &args.trajectory {
        Some(path) => {
            let t = imu_emu_runner::trajectory::Trajectory::load(path, args.trajectory_loop)?;
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
        Some(addr) => Some(imu_emu_runner::control::Control::bind(addr)?),
        None => None,
    };
    let feed = match &args.motion_feed {
        Some(a) => Some(imu_emu_runner::feed::FeedSocket::bind(
            &imu_emu_runner::feed::FeedAddr::parse(a),
        )?),
        None => None,
    };
    let (product, name) = P::product(args.product());
    let web = web_view::<P>(args, product, &name, &[transport.describe()])?;
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
                    imu_emu_runner::control::Command::Status => Ok("mode=off".to_owned()),
                    imu_emu_runner::control::Command::Devices => {
                        Ok(imu_emu_runner::control::devices_reply(&[
                            transport.describe()
                        ]))
                    }
                    _ => Err(
                        "the device is off: it powers on when a client connects to the UART \
                         (or use --power-on now)"
                            .to_owned(),
                    ),
                })?;
            }
            transport.wait(imu_emu_runner::runner::IDLE_WAKE)?;
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
        .set_gps_time(imu_emu_runner::clock::gps_s_at_power_on(args.gps_time));
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
        let state = imu_emu_runner::feed::FeedState::new(cfg, 0, true, "");
        runner = runner.with_feed(state, Some(sock));
    }
    runner.run(stop)?;
    eprintln!("imu-emu: stopped");
    Ok(())
}
