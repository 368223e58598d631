//! The port adapter: what the core's schedule drives on this board
//! ([`Port`]) — the transport behind the link faults, the input paced at
//! the line rate, the `--pps` generator, the motion sources played into
//! the chain each tick, TOV edges as events, and after each input the
//! monitor, the web view's tap and the control socket (carried out by
//! `exec.rs`).

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::{Device, Level, Pin};
use imu_emu::schedule::Port;
use imu_emu::sensor::Motion;
use imu_emu::time::Instant;
use imu_emu::Pacer;

use crate::control::Control;
use crate::feed::{FeedSocket, FeedState};
use crate::link::Link;
use crate::monitor::InputMonitor as _;
use crate::protocol::HostProtocol;
use crate::trajectory::Trajectory;
use crate::transport::Transport;
use crate::vehicle::VehicleSource;

/// What the schedule drives on this board: the transport, the control
/// socket, the `--pps` generator and the trajectory.
pub(super) struct HostPort<T: Transport, P: HostProtocol> {
    pub(super) transport: T,
    /// The control socket (`--control`), if any.
    pub(super) control: Option<Control>,
    /// Next 1PPS edge of the `--pps` generator, ns since the epoch.
    pub(super) next_pps_ns: Option<u64>,
    /// Motion replayed from a file (`--trajectory`), if any.
    pub(super) trajectory: Option<Trajectory>,
    /// The vehicle source (`--motion`, `motion script|file`), if any.
    pub(super) vehicle: Option<VehicleSource>,
    /// The live motion feed's state (`--motion-feed`), if any.
    pub(super) feed: Option<FeedState>,
    /// The feed's socket, unless the feed is shared by a fleet.
    pub(super) feed_socket: Option<FeedSocket>,
    /// Faults between the device's UART and the transport (`link …`).
    pub(super) link: Link,
    /// The device's input decoded on the host side (logs, `status`).
    pub(super) monitor: P::Monitor,
    /// Input past the faults that did not fit the device's read yet.
    pub(super) rx_carry: std::collections::VecDeque<u8>,
    /// Input credit at the line rate (device time): what the device's
    /// UART could have received by now.
    pub(super) rx_pacer: Pacer,
    /// The last read was bounded by the credit (more input may wait in
    /// the transport, which is not waited on for input meanwhile).
    pub(super) rx_held: bool,
    /// Deadline of the last tick run, ns, and the tick period: input is
    /// credited up to the schedule's time, never past the next tick (the
    /// clock's `now` runs ahead while ticks are behind, and goes back when
    /// the clock is held back).
    pub(super) tick_ns: u64,
    pub(super) period_ns: u64,
    /// Device time of the current pass, ns.
    pub(super) now_ns: u64,
    /// Bytes the line carried (before link faults).
    pub(super) line_bytes: u64,
    /// Device time held back so far (copied from the clock), ns.
    pub(super) held_back_ns: u64,
    /// Reused buffer of what passes the link faults.
    pub(super) scratch: Vec<u8>,
    /// Events (TOV edges) kept for the owner of a shared control socket
    /// (the many-device mode) instead of sent to `control`.
    pub(super) events: Option<Vec<String>>,
    /// Prefix of stderr messages naming the device (`dev 3: `), or empty.
    pub(super) label: String,
    /// The device is in firmware-update mode (BOOT high at power-on): its
    /// input is firmware data, not KERNEL commands, so the monitor does
    /// not decode, log or count it.
    pub(super) fw_update: bool,
    /// The web view's tap (`--web`), if any: never blocks.
    pub(super) web: Option<crate::web::Tap>,
    /// Device time the last input byte reached the device, ns.
    pub(super) last_rx_ns: Option<u64>,
}

impl<T: Transport, P: HostProtocol> HostPort<T, P> {
    /// A port on `transport` for a device whose line starts at
    /// `line_rate` bit/s and ticks every `period_ns`: no control socket,
    /// pins, motion source or feed yet, a clean link.
    pub(super) fn new(transport: T, line_rate: u32, period_ns: u64) -> Self {
        HostPort {
            transport,
            control: None,
            next_pps_ns: None,
            trajectory: None,
            vehicle: None,
            feed: None,
            feed_socket: None,
            link: Link::with_wire(0, P::wire()),
            monitor: P::Monitor::default(),
            rx_carry: std::collections::VecDeque::new(),
            rx_pacer: Pacer::new(line_rate, 0),
            rx_held: false,
            tick_ns: 0,
            period_ns,
            now_ns: 0,
            line_bytes: 0,
            held_back_ns: 0,
            scratch: Vec::new(),
            events: None,
            label: String::new(),
            fw_update: false,
            web: None,
            last_rx_ns: None,
        }
    }

    /// Hands what the link let through to the web view's tap and the
    /// transport.
    #[inline]
    pub(super) fn deliver(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        if let Some(w) = &self.web {
            w.tx(bytes, self.rx_time());
        }
        if bytes.is_empty() {
            Ok(())
        } else {
            self.transport.send(bytes)
        }
    }

    /// Device time input is credited up to: the pass's time, but no later
    /// than the tick after the last one run.
    pub(super) fn rx_time(&self) -> u64 {
        self.now_ns.min(self.tick_ns.saturating_add(self.period_ns))
    }

    /// Hands the transport what a stall released, if it is over.
    pub(super) fn release(&mut self) -> anyhow::Result<()> {
        let mut out = Vec::new();
        self.link.release(self.now_ns, &mut out);
        if !out.is_empty() {
            self.transport.send(&out)?;
        }
        Ok(())
    }
}

impl<F: NorFlash, T: Transport, P: HostProtocol> Port<F, P> for HostPort<T, P> {
    type Error = anyhow::Error;

    fn tx_room(&mut self) -> usize {
        // The transport's backlog takes everything the line carries.
        usize::MAX
    }

    fn write(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.line_bytes += bytes.len() as u64;
        if self.link.clean() {
            // No link fault: the bytes go as they are, without a copy.
            self.link.pass(bytes);
            return self.deliver(bytes);
        }
        let mut out = core::mem::take(&mut self.scratch);
        out.clear();
        self.link.tx(bytes, self.now_ns, &mut out);
        let r = self.deliver(&out);
        self.scratch = out;
        r
    }

    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        eprintln!("imu-emu: {}line rate {bps} bit/s", self.label);
        self.rx_pacer.set_rate(bps, self.rx_time());
        self.transport.set_line_rate(bps)
    }

    fn read(&mut self, buf: &mut [u8]) -> anyhow::Result<usize> {
        // No more than the line could have carried by now; in lockstep
        // the simulator owns device time (it stands still between samples,
        // so a command sent before the first one would never arrive): the
        // input goes in as it comes, at the device time of the next pass.
        self.rx_pacer.advance(self.rx_time());
        let limit = if self.feed.as_ref().is_some_and(FeedState::lockstep) {
            buf.len()
        } else {
            buf.len().min(self.rx_pacer.available())
        };
        let buf = &mut buf[..limit];
        // Input the faults made longer than the last read could take first.
        let mut n = self.rx_carry.len().min(buf.len());
        for (b, c) in buf.iter_mut().zip(self.rx_carry.drain(..n)) {
            *b = c;
        }
        // Called even for 0 bytes: the transport also accepts and notices
        // hang-ups there.
        let mut raw = Vec::new();
        self.transport
            .receive(buf.len() - n, &mut |bytes| raw.extend_from_slice(bytes))?;
        if !raw.is_empty() || self.link.rx_noise_pending() {
            let mut got = Vec::with_capacity(raw.len());
            self.link.rx(&raw, &mut got);
            let k = got.len().min(buf.len() - n);
            buf[n..n + k].copy_from_slice(&got[..k]);
            self.rx_carry.extend(&got[k..]);
            n += k;
        }
        self.rx_pacer.consume(n);
        if n > 0 {
            self.last_rx_ns = Some(self.rx_time());
        }
        self.rx_held = n == limit;
        self.transport.hold_input(self.rx_held);
        if !self.fw_update {
            self.monitor.feed(&buf[..n]);
        }
        Ok(n)
    }

    fn tov(&mut self, level: Level, at: Instant) -> anyhow::Result<()> {
        // The host board has no TOV pin: edges go to the control client.
        let l = if level == Level::High { "high" } else { "low" };
        if let Some(events) = self.events.as_mut() {
            events.push(format!("tov {l} {}", at.as_nanos()));
        } else if let Some(ctl) = self.control.as_mut() {
            ctl.event(&format!("tov {l} {}", at.as_nanos()));
        }
        Ok(())
    }

    fn before_tick(&mut self, dev: &mut Device<F, P>, deadline: Instant) -> anyhow::Result<()> {
        let deadline = deadline.as_nanos();
        while let Some(pps) = self.next_pps_ns.filter(|&p| p <= deadline) {
            dev.on_pin(Pin::Pps, Level::High, Instant::from_nanos(pps));
            self.next_pps_ns = Some(pps + 1_000_000_000);
        }
        Ok(())
    }

    #[inline]
    fn tick(&mut self, dev: &mut Device<F, P>, deadline: Instant) -> anyhow::Result<()> {
        let secs = || deadline.as_nanos() as f64 * 1e-9;
        if let Some(t) = self.trajectory.as_mut() {
            let (state, truth) = t.vehicle_at(secs());
            dev.chain_mut().set_vehicle(state, truth);
        } else if let Some(v) = self.vehicle.as_mut() {
            let state = v.at(secs());
            dev.chain_mut().set_vehicle(state, state.truth());
        }
        if let Some(f) = self.feed.as_mut() {
            let (motion, lost) = f.at(deadline.as_nanos());
            match motion {
                Some(crate::feed::FeedMotion::Rates(truth)) => {
                    dev.chain_mut().set_motion(Motion::Sample(truth))
                }
                Some(crate::feed::FeedMotion::Vehicle(state)) => {
                    dev.chain_mut().set_vehicle(state, state.truth())
                }
                None => {}
            }
            dev.chain_mut().faults_mut().motion_feed_lost = lost;
        }
        dev.on_tick(deadline);
        self.tick_ns = deadline.as_nanos();
        self.fw_update = dev.mode() == imu_emu::device::Mode::FirmwareUpdate;
        Ok(())
    }

    fn after_rx(&mut self, dev: &mut Device<F, P>, at: Instant) -> anyhow::Result<()> {
        let product = dev.product();
        self.monitor.judge(dev.personality(), &product);
        if let Some(mut w) = self.web.take() {
            // The page's commands, through the control socket's executor.
            for p in w.commands() {
                p.run(|cmd| self.apply(dev, cmd, at));
            }
            if w.publish_due() {
                // Heading, pitch, roll (deg): the vehicle's when a script,
                // file, trajectory or feed plays (heading in [0, 360) like
                // the built-in motion's), else the built-in motion's.
                let attitude = match dev.chain().vehicle_source() {
                    Some(v) => {
                        let [roll, pitch, yaw] = v.euler_rad().map(f64::to_degrees);
                        Some([yaw.rem_euclid(360.0), pitch, roll].map(|x| x as f32))
                    }
                    None => dev
                        .chain()
                        .truth_attitude()
                        .map(|q| imu_emu::euler_from_quat(&q).map(f32::to_degrees)),
                };
                // Where the unit is (the vehicle's, or the built-in
                // motion's fixed place): the page's position track.
                let v = dev.chain().vehicle();
                let lla = [v.lat_rad.to_degrees(), v.lon_rad.to_degrees(), v.height_m];
                let truth = crate::web::Truth { attitude, lla };
                w.publish(self.status(dev), at.as_nanos(), truth);
            }
            self.web = Some(w);
        }
        let Some(mut ctl) = self.control.take() else {
            return Ok(());
        };
        let r = ctl.poll(&mut |cmd| {
            tracing::debug!("control: {cmd:?}");
            self.apply(dev, cmd, at)
        });
        self.control = Some(ctl);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::super::fake::Mem;
    use super::*;
    use crate::flash::MemNor;
    use imu_emu::isb::Isb;
    use imu_emu::kernel::Kernel;

    /// 2 kHz ticks.
    const PERIOD_NS: u64 = 500_000;

    fn read(p: &mut HostPort<Mem, Kernel>, now_ns: u64) -> usize {
        p.now_ns = now_ns;
        p.tick_ns = now_ns;
        let mut buf = [0u8; 4096];
        <HostPort<Mem, Kernel> as Port<MemNor, Kernel>>::read(p, &mut buf).unwrap()
    }

    /// However much the client sent at once, the device gets it no faster
    /// than its UART would: 11 bytes in the first ms at 115 200 bit/s
    /// (10 bits a byte), the rest held in the transport.
    #[test]
    fn input_is_paced_at_the_line_rate() {
        let mut p = HostPort::<Mem, Kernel>::new(Mem::with_input(&[0; 10_000]), 115_200, PERIOD_NS);
        assert_eq!(read(&mut p, 1_000_000), 11);
        assert!(p.rx_held && p.transport.held);
        assert_eq!(p.transport.input.len(), 10_000 - 11);
        // 0.52 byte left over + 0.5 ms = 6.28 bytes.
        assert_eq!(read(&mut p, 1_500_000), 6);
        // A long pause earns one burst (64 bytes), not the whole pause.
        assert_eq!(read(&mut p, 1_000_000_000), 64);
        assert_eq!(p.transport.input.len(), 10_000 - 11 - 6 - 64);
    }

    /// Input is credited up to the tick after the last one run, never to a
    /// pass time the ticks have not reached.
    #[test]
    fn input_credit_stops_at_the_next_tick() {
        let mut p = HostPort::<Mem, Kernel>::new(Mem::with_input(&[0; 100]), 115_200, PERIOD_NS);
        p.tick_ns = 0;
        p.now_ns = 1_000_000_000;
        assert_eq!(p.rx_time(), PERIOD_NS);
        let mut buf = [0u8; 64];
        let n = <HostPort<Mem, Kernel> as Port<MemNor, Kernel>>::read(&mut p, &mut buf).unwrap();
        assert_eq!(n, 5); // 0.5 ms at 115 200 bit/s: 5.76 bytes
    }

    /// What the line carries reaches the transport as it is (a clean
    /// link) and is counted; a line-rate switch reaches the transport and
    /// the input pacer.
    #[test]
    fn output_reaches_the_transport_and_is_counted() {
        let mut p = HostPort::<Mem, Isb>::new(Mem::default(), 921_600, PERIOD_NS);
        <HostPort<Mem, Isb> as Port<MemNor, Isb>>::write(&mut p, b"\xef\xbe abc").unwrap();
        assert_eq!(p.transport.sent, b"\xef\xbe abc");
        assert_eq!(p.line_bytes, 6);
        <HostPort<Mem, Isb> as Port<MemNor, Isb>>::set_line_rate(&mut p, 115_200).unwrap();
        assert_eq!(p.transport.rate, Some(115_200));
        assert_eq!(p.rx_pacer.rate(), 115_200);
    }

    /// The host board has no TOV pin: an edge is an event for whoever
    /// owns the control socket (here a fleet's, which collects them).
    #[test]
    fn tov_edges_become_events() {
        let mut p = HostPort::<Mem, Kernel>::new(Mem::default(), 115_200, PERIOD_NS);
        p.events = Some(Vec::new());
        let port = &mut p as &mut dyn Port<MemNor, Kernel, Error = anyhow::Error>;
        port.tov(Level::High, Instant::from_nanos(1_500)).unwrap();
        port.tov(Level::Low, Instant::from_nanos(2_500)).unwrap();
        assert_eq!(
            p.events.as_deref(),
            Some(&["tov high 1500".to_owned(), "tov low 2500".to_owned()][..])
        );
    }
}
