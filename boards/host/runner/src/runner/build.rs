//! Building a runner and handing it to its owner (the program, a fleet):
//! the device, transport and epoch it starts with, what it is given
//! before it runs (speed, control socket, motion sources, feed, web tap,
//! seed, `--pps`, a fleet's shared control), and what the owner reads or
//! asks of it afterwards.

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::Device;
use imu_emu::schedule::Schedule;
use imu_emu::time::Instant;

use super::port::HostPort;
use super::{Runner, Stats};
use crate::clock::{Clock, Speed};
use crate::control::{self, Control};
use crate::feed::{FeedSocket, FeedState};
use crate::link::Link;
use crate::protocol::HostProtocol;
use crate::trajectory::Trajectory;
use crate::transport::Transport;
use crate::vehicle::VehicleSource;

impl<F: NorFlash, T: Transport, P: HostProtocol> Runner<F, T, P> {
    /// Wraps a device powered on at `Instant::ZERO` = `epoch`, in real
    /// time ([`Runner::with_speed`] changes that).
    pub fn new(dev: Device<F, P>, transport: T, epoch: std::time::Instant) -> Self {
        let sched = Box::new(Schedule::new(&dev));
        let period_ns = sched.period_ns();
        let io = HostPort::new(transport, dev.line_rate(), period_ns);
        Runner {
            dev,
            sched,
            io,
            clock: Clock::new(epoch, Speed::default()),
            stats: Stats::default(),
            reported_drops: 0,
            reported_held_ns: 0,
            reported_at: None,
            status_at: std::io::IsTerminal::is_terminal(&std::io::stdout())
                .then(std::time::Instant::now),
            pace: None,
            lockstep_target: 0,
        }
    }

    /// Drives the motion from a live feed ([`crate::feed`]): `socket` is
    /// its own (`None`: samples come through [`Runner::feed_offer`], a
    /// fleet's shared feed). In lockstep, device time then moves only
    /// with the samples (at a `--speed` factor, no faster than that
    /// either): call after [`Runner::with_speed`].
    pub fn with_feed(mut self, state: FeedState, socket: Option<FeedSocket>) -> Self {
        if state.lockstep() {
            let epoch = self.clock.epoch();
            self.pace = match self.clock.speed() {
                Speed::Factor(_) => Some(self.clock.clone()),
                Speed::Max => None,
            };
            self.clock = Clock::new(epoch, Speed::Max);
        }
        self.io.feed = Some(state);
        self.io.feed_socket = socket;
        self
    }

    /// Replays `t` as the motion the device measures: before each tick the
    /// sample for that tick's time is handed to the signal chain.
    pub fn with_trajectory(mut self, t: Trajectory) -> Self {
        self.io.trajectory = Some(t);
        self
    }

    /// Flies or plays `v` as the unit's vehicle (`--motion`): before each
    /// tick its state at that tick's time is handed to the signal chain.
    pub fn with_vehicle(mut self, v: VehicleSource) -> Self {
        self.io.vehicle = Some(v);
        self
    }

    /// Runs device time at `speed` (`--speed`), from the same epoch.
    pub fn with_speed(mut self, speed: Speed) -> Self {
        self.clock = Clock::new(self.clock.epoch(), speed);
        self
    }

    /// Serves the control socket (pin edges, power cycle, TOV reports).
    pub fn with_control(mut self, control: Control) -> Self {
        self.io.control = Some(control);
        self
    }

    /// Feeds the web view (`--web`): the output, the status and the truth
    /// go to `tap`, and its commands are carried out between passes.
    pub fn with_web(mut self, tap: crate::web::Tap) -> Self {
        self.io.web = Some(tap);
        self
    }

    /// Seeds the link faults' random draws (`--seed`).
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.io.link = Link::with_wire(seed, P::wire());
        self
    }

    /// Generates a 1PPS rising edge at every whole second of device time
    /// (`--pps`; the host clock at `--speed 1`).
    pub fn with_pps(mut self) -> Self {
        self.io.next_pps_ns = Some(1_000_000_000);
        self
    }

    /// Keeps the device's events (TOV edges, as the control socket words
    /// them) for [`Runner::take_events`] instead of sending them to a
    /// control socket of its own, and draws no terminal status line: the
    /// many-device mode ([`crate::fleet`]), whose one control socket
    /// serves every device.
    pub fn shared(mut self) -> Self {
        self.io.events = Some(Vec::new());
        self.status_at = None;
        self
    }

    /// Names the device in the runner's stderr messages (`dev 3: …`).
    pub fn with_label(mut self, label: String) -> Self {
        self.io.label = label;
        self
    }

    /// Carries out a control command now (device time of the last pass):
    /// what the control socket does for a single device, for the owner of
    /// a shared one. The answer is the reply's text (`ok …` / `error …`).
    pub fn control(&mut self, cmd: control::Command) -> Result<String, String> {
        let at = Instant::from_nanos(self.io.now_ns);
        // Bytes a command queued (noise, a power cycle's announcement)
        // leave with the next pass's flush.
        self.io.apply(&mut self.dev, cmd, at)
    }

    /// The events the device raised since the last call ([`Runner::shared`]).
    pub fn take_events(&mut self) -> Vec<String> {
        self.io
            .events
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// The device.
    pub fn device(&self) -> &Device<F, P> {
        &self.dev
    }

    /// The transport.
    pub fn transport(&self) -> &T {
        &self.io.transport
    }

    /// The transport, to wait on it together with others ([`crate::fleet`]).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.io.transport
    }

    /// What the runner counted so far (loss, lag, traffic).
    pub fn stats(&self) -> Stats {
        Stats {
            tx_dropped: self.dev.tx_dropped(),
            held_back_ns: self.clock.held_back_ns(),
            ..self.stats
        }
    }

    /// Gives the device back (e.g. to inspect its flash).
    pub fn into_device(self) -> Device<F, P> {
        self.dev
    }
}
