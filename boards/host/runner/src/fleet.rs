//! Many devices in one process (`--count N`): N independent virtual
//! devices driven by one scheduler loop on one thread.
//!
//! Each device has its own transport (TCP port or pty), its own flash
//! (`--flash FILE` keeps device K's in `FILE.K`), its own seed (`--seed S`
//! gives device K the seed `S + K`), its own clock and its own
//! [`Runner`] (schedule, pacer, link faults, monitor). The loop gives every
//! device one [`Runner::turn`] a round and then waits once, in a single
//! `ppoll` over every transport's descriptors and the control socket, for
//! the earliest time any device asked for.
//!
//! **One wake for all.** A device powers on (when its first client
//! connects, or at start with `--power-on now`) with its device-time epoch
//! on a 1 ms grid of host time shared by the whole run ([`GRID`]): every
//! internal rate the models have (1, 2 and 4 kHz) divides it, so the
//! ticks of all devices fall due at the same host instants and the loop
//! wakes once per tick period for all of them, not once per device.
//!
//! **One control socket** (`--control ADDR`) serves every device: a
//! command addresses device K as `dev K <command>`; `devices` lists them
//! (`ok count=N dev0=tcp:ADDR …`); TOV edges come as
//! `event dev K tov high <ns>` ([`crate::control`]).
//!
//! What one device does is exactly what a single `imu-emu` does; a slow
//! or absent client of one device never holds up another (each has its
//! own bounded backlog and its own `--speed max` back-pressure).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant as HostInstant};

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, PowerOn};
use imu_emu::model::Product;
use imu_emu::time::Instant;

use crate::clock::Speed;
use crate::control::{Command, Control};
use crate::feed::{FeedConfig, FeedSocket, FeedState};
use crate::protocol::HostProtocol;
use crate::runner::{Runner, IDLE_WAKE};
use crate::trajectory::Trajectory;
use crate::transport::Transport;

/// The host-time grid device epochs are aligned on (see the module docs).
pub const GRID: Duration = Duration::from_millis(1);

/// Most devices one process runs.
pub const MAX_COUNT: usize = 1000;

/// What every device of a run shares.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The product every device is.
    pub product: Product,
    /// Its name in messages.
    pub name: String,
    /// Device seconds per host second.
    pub speed: Speed,
    /// Device K's seed is `seed + K`.
    pub seed: u64,
    /// Device K's sensor profile (`--sensor-profile`; `None` or missing:
    /// the model's built-in one).
    pub profiles: Vec<Option<&'static imu_emu::sensor::SensorProfile>>,
    /// A 1PPS edge every device second.
    pub pps: bool,
    /// The motion each device replays, if any (each from its start).
    pub trajectory: Option<Trajectory>,
    /// The vehicle each device rides on (`--motion`), if any (each from
    /// its start).
    pub vehicle: Option<crate::vehicle::VehicleSource>,
    /// Power on at start instead of at the first client.
    pub power_on_now: bool,
    /// The web view (`--web`), fed by each device's runner.
    pub web: Option<std::sync::Arc<crate::web::Hub>>,
    /// `--gps-time` (Unix seconds, UTC), else the host clock at power-on.
    pub gps_time: Option<u64>,
    /// The live motion feed's clock and timeout, if there is a feed.
    pub feed: Option<FeedConfig>,
}

/// One device: off (waiting for its first client) or running.
enum Slot<F: NorFlash, T: Transport, P: HostProtocol> {
    Off { flash: F, transport: T },
    On(Box<Runner<F, T, P>>),
}

/// N devices, one loop.
pub struct Fleet<F: NorFlash, T: Transport, P: HostProtocol> {
    slots: Vec<Option<Slot<F, T, P>>>,
    setup: Setup,
    control: Option<Control>,
    /// The start of the run: the grid's origin.
    origin: HostInstant,
    /// Where each device listens (`tcp 127.0.0.1:7000`).
    places: Vec<String>,
    /// Device K's own feed socket until it powers on ([`Fleet::with_feeds`]).
    feeds: Vec<Option<FeedSocket>>,
    /// One feed for all devices, its samples routed by their device index.
    shared_feed: Option<FeedSocket>,
    /// The shared feed's outcomes no device took: decoder rejections and
    /// samples for a device that is off or does not exist.
    shared_counts: imu_emu::feed::Counts,
}

impl<F: NorFlash, T: Transport, P: HostProtocol> Fleet<F, T, P> {
    /// Devices on `parts` (flash and transport of device K at index K),
    /// all off until [`Fleet::run`] powers them on.
    pub fn new(parts: Vec<(F, T)>, setup: Setup, control: Option<Control>) -> Self {
        let places = parts.iter().map(|(_, t)| t.describe()).collect();
        Fleet {
            slots: parts
                .into_iter()
                .map(|(flash, transport)| Some(Slot::Off { flash, transport }))
                .collect(),
            setup,
            control,
            origin: HostInstant::now(),
            places,
            feeds: Vec::new(),
            shared_feed: None,
            shared_counts: imu_emu::feed::Counts::default(),
        }
    }

    /// Live motion feeds ([`Setup::feed`]): one socket per device (device
    /// K's at index K), or with `shared` one socket whose samples name
    /// their device.
    pub fn with_feeds(mut self, mut sockets: Vec<FeedSocket>, shared: bool) -> Self {
        if shared {
            self.shared_feed = sockets.pop();
        } else {
            for (k, s) in sockets.iter_mut().enumerate() {
                s.set_label(&format!("dev {k}: "));
            }
            self.feeds = sockets.into_iter().map(Some).collect();
        }
        self
    }

    /// Whether a running device's lockstep queue is full.
    fn shared_feed_full(&self) -> bool {
        self.slots.iter().flatten().any(|s| match s {
            Slot::On(r) => !r.feed_wants_more(),
            Slot::Off { .. } => false,
        })
    }

    /// Reads the shared feed, handing each sample to the device it names;
    /// not while a device's lockstep queue is full (the socket's buffer
    /// then holds the simulator back).
    fn read_shared_feed(&mut self) -> anyhow::Result<()> {
        if self.shared_feed_full() {
            return Ok(());
        }
        let Some(mut sock) = self.shared_feed.take() else {
            return Ok(());
        };
        // A new client: a new feed timeline for every device.
        match sock.accept() {
            Ok(true) => {
                for slot in self.slots.iter_mut().flatten() {
                    if let Slot::On(runner) = slot {
                        runner.feed_new_timeline();
                    }
                }
            }
            Ok(false) => {}
            Err(e) => {
                self.shared_feed = Some(sock);
                return Err(e);
            }
        }
        let slots = &mut self.slots;
        let counts = &mut self.shared_counts;
        // Each sample dated by its arrival at the socket, as a device's own
        // feed's are (the runner's `feed_offer`).
        let r = sock.read_stamped(&mut |r, age| {
            let k = r.as_ref().map(|s| usize::from(s.device()));
            match (k, r) {
                (Ok(k), r) => match slots.get_mut(k) {
                    Some(Some(Slot::On(runner))) => runner.feed_offer(r, age),
                    _ => {
                        tracing::info!("motion feed: sample for dev {k}, which is off or absent");
                        counts.note(Err(imu_emu::feed::Reject::WrongDevice));
                    }
                },
                (Err(_), Err(e)) => {
                    tracing::info!("motion feed sample rejected: {}", e.name());
                    counts.note(Err(e));
                }
                (Err(_), Ok(_)) => {}
            }
        });
        self.shared_feed = Some(sock);
        r
    }

    /// How many devices.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Device K's runner, once it is on.
    pub fn runner(&self, k: usize) -> Option<&Runner<F, T, P>> {
        match self.slots.get(k)? {
            Some(Slot::On(r)) => Some(r),
            _ => None,
        }
    }

    /// Powers device `k` on now, its epoch on the grid.
    fn power_on(&mut self, k: usize) -> anyhow::Result<()> {
        // Only an Off slot is taken (a running one stays where it is).
        let Some(Slot::Off {
            flash,
            mut transport,
        }) = self
            .slots
            .get_mut(k)
            .and_then(|s| s.take_if(|s| matches!(s, Slot::Off { .. })))
        else {
            return Ok(());
        };
        let grid = GRID.as_nanos();
        let since = self.origin.elapsed().as_nanos();
        let epoch = self.origin + Duration::from_nanos(((since / grid) * grid) as u64);
        let cfg = PowerOn {
            product: self.setup.product,
            boot: None,
            seed: self.setup.seed.wrapping_add(k as u64),
        };
        let profile = self.setup.profiles.get(k).copied().flatten();
        let mut dev = Device::<F, P>::with_profile(cfg, profile, flash, Instant::ZERO);
        dev.personality_mut()
            .set_gps_time(crate::clock::gps_s_at_power_on(self.setup.gps_time));
        transport.set_line_rate(dev.line_rate())?;
        eprintln!(
            "imu-emu: dev {k}: {} powered on at {} bit/s, seed {}",
            self.setup.name,
            dev.line_rate(),
            cfg.seed
        );
        let mut runner = Runner::new(dev, transport, epoch)
            .with_speed(self.setup.speed)
            .with_seed(cfg.seed)
            .with_label(format!("dev {k}: "))
            .shared();
        if self.setup.pps {
            runner = runner.with_pps();
        }
        if let Some(tap) = self.setup.web.as_ref().and_then(|h| h.tap(k)) {
            runner = runner.with_web(tap);
        }
        if let Some(t) = &self.setup.trajectory {
            runner = runner.with_trajectory(t.clone());
        }
        if let Some(v) = &self.setup.vehicle {
            runner = runner.with_vehicle(v.clone());
        }
        if let Some(cfg) = self.setup.feed {
            let own = self.feeds.get_mut(k).and_then(Option::take);
            let state = FeedState::new(cfg, k as u16, own.is_some(), &format!("dev {k}: "));
            runner = runner.with_feed(state, own);
        }
        self.slots[k] = Some(Slot::On(Box::new(runner)));
        Ok(())
    }

    /// One control command for device `k` (or for the run).
    fn command(&mut self, k: Option<usize>, cmd: Command) -> Result<String, String> {
        if cmd == Command::Devices {
            let mut s = crate::control::devices_reply(&self.places);
            if let Some(f) = &self.shared_feed {
                let c = &self.shared_counts;
                s.push_str(&format!(
                    " feed={} feed-unrouted={}",
                    f.describe().replacen(' ', ":", 1),
                    c.rejected_total()
                ));
            }
            return Ok(s);
        }
        let n = self.slots.len();
        let Some(k) = k else {
            return Err(format!(
                "this run has {n} devices: address one, dev <K> <command> (K = 0..{})",
                n - 1
            ));
        };
        match self.slots.get_mut(k) {
            Some(Some(Slot::On(r))) => r.control(cmd),
            Some(Some(Slot::Off { .. })) if cmd == Command::Status => Ok("mode=off".to_owned()),
            Some(_) => Err(format!(
                "dev {k} is off: it powers on when a client connects to its UART \
                 (or use --power-on now)"
            )),
            None => Err(format!("no device {k}: this run has devices 0..{}", n - 1)),
        }
    }

    /// Serves every device until `stop` is set (SIGINT/SIGTERM).
    pub fn run(&mut self, stop: &AtomicBool) -> anyhow::Result<()> {
        if self.setup.power_on_now {
            for k in 0..self.slots.len() {
                self.power_on(k)?;
            }
        }
        while !stop.load(Ordering::Relaxed) {
            let timeout = self.round()?;
            self.wait(timeout)?;
        }
        Ok(())
    }

    /// One turn of every device, its events to the control client, the
    /// control commands; how long the loop may then wait.
    pub fn round(&mut self) -> anyhow::Result<Duration> {
        let mut timeout = IDLE_WAKE;
        self.read_shared_feed()?;
        for k in 0..self.slots.len() {
            let off = match &mut self.slots[k] {
                Some(Slot::Off { transport, .. }) => transport.poll_client()?,
                _ => false,
            };
            if off {
                self.power_on(k)?;
            }
            if let Some(Slot::On(r)) = &mut self.slots[k] {
                timeout = timeout.min(r.turn()?);
                let events = r.take_events();
                if let Some(ctl) = self.control.as_mut() {
                    for e in events {
                        ctl.event(&format!("dev {k} {e}"));
                    }
                }
            }
        }
        if let Some(mut ctl) = self.control.take() {
            let r = ctl.poll_addressed(&mut |k, cmd| {
                tracing::debug!("control: dev {k:?} {cmd:?}");
                self.command(k, cmd)
            });
            self.control = Some(ctl);
            r?;
        }
        Ok(timeout)
    }

    /// One `ppoll` over every device's transport and the control socket.
    fn wait(&mut self, timeout: Duration) -> anyhow::Result<()> {
        for slot in self.slots.iter_mut().flatten() {
            match slot {
                Slot::Off { transport, .. } => transport.prepare_wait()?,
                Slot::On(r) => r.transport_mut().prepare_wait()?,
            }
        }
        let (revents, mut counts) = {
            let mut fds = Vec::with_capacity(2 * self.slots.len() + 2);
            let mut counts = Vec::with_capacity(self.slots.len());
            for slot in self.slots.iter().flatten() {
                let before = fds.len();
                match slot {
                    Slot::Off { transport, .. } => transport.interest(&mut fds),
                    Slot::On(r) => r.transport().interest(&mut fds),
                }
                counts.push(fds.len() - before);
            }
            let mine: usize = counts.iter().sum();
            if let Some(ctl) = &self.control {
                ctl.interest(&mut fds);
            }
            let ctl_n = fds.len() - mine;
            // Feeds last: they are read every round, only their wake-up
            // matters.
            for slot in self.slots.iter().flatten() {
                if let Slot::On(r) = slot {
                    r.feed_interest(&mut fds);
                }
            }
            if let Some(f) = self
                .shared_feed
                .as_ref()
                .filter(|_| !self.shared_feed_full())
            {
                f.interest(&mut fds);
            }
            counts.push(ctl_n);
            crate::transport::poll_fds(&mut fds, timeout)?;
            (crate::transport::revents(&fds), counts)
        };
        let ctl_n = counts.pop().unwrap_or(0);
        let mine: usize = counts.iter().sum();
        if let Some(ctl) = self.control.as_mut() {
            ctl.polled(&revents[mine..mine + ctl_n]);
        }
        let mut at = 0;
        for (slot, n) in self.slots.iter_mut().flatten().zip(counts) {
            let seen = &revents[at..at + n];
            match slot {
                Slot::Off { transport, .. } => transport.polled(seen),
                Slot::On(r) => r.transport_mut().polled(seen),
            }
            at += n;
        }
        Ok(())
    }
}
