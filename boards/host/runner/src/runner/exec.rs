//! Control execution and status: a control command carried out on the
//! device and the port between passes (from the control socket, a
//! fleet's, or the web view), and the `status` and `truth` words it
//! answers with.

use embedded_storage::nor_flash::NorFlash;
use imu_emu::device::Device;
use imu_emu::sensor::Motion;
use imu_emu::time::Instant;

use super::port::HostPort;
use crate::control;
use crate::feed::FeedState;
use crate::monitor::InputMonitor;
use crate::protocol::HostProtocol;
use crate::transport::Transport;
use crate::vehicle::VehicleSource;

impl<T: Transport, P: HostProtocol> HostPort<T, P> {
    /// Carries out one control command at device time `at`; the answer
    /// for the control client (`Ok` text after `ok`, `Err` after `error`).
    pub(super) fn apply<F: NorFlash>(
        &mut self,
        dev: &mut Device<F, P>,
        cmd: control::Command,
        at: Instant,
    ) -> Result<String, String> {
        match cmd {
            control::Command::Edge(pin, level) => dev.on_pin(pin, level, at),
            control::Command::PowerCycle(boot) => {
                dev.power_cycle_with(boot, at);
                if let Some(f) = self.feed.as_mut() {
                    f.new_timeline();
                }
                self.fw_update = dev.mode() == imu_emu::device::Mode::FirmwareUpdate;
                if self.fw_update {
                    tracing::info!(
                        "{}firmware-update mode (BOOT high at power-on): input is not decoded \
                         until the next power cycle",
                        self.label
                    );
                }
            }
            control::Command::Fault(change) => change.apply(dev.chain_mut().faults_mut()),
            control::Command::NavFault(change) => dev.personality_mut().nav_fault(change)?,
            control::Command::Motion(m) => {
                self.trajectory = None;
                self.vehicle = None;
                dev.chain_mut().set_motion(m);
            }
            control::Command::Script(s) => {
                self.trajectory = None;
                let v = VehicleSource::script(*s).starting_at(at.as_nanos() as f64 * 1e-9);
                self.vehicle = Some(v);
            }
            control::Command::MotionFile(path) => {
                let v = VehicleSource::load(&path).map_err(|e| format!("{e:#}"))?;
                self.trajectory = None;
                self.vehicle = Some(v.starting_at(at.as_nanos() as f64 * 1e-9));
            }
            control::Command::Truth => return Ok(self.truth(dev, "")),
            control::Command::Link(change) => {
                let mut noise = Vec::new();
                self.link.apply(change, self.now_ns, &mut noise);
                if !noise.is_empty() {
                    self.transport
                        .send(&noise)
                        .map_err(|e| format!("sending the noise: {e}"))?;
                }
            }
            control::Command::Status => return Ok(self.status(dev)),
            control::Command::Devices => {
                return Ok(control::devices_reply(&[self.transport.describe()]))
            }
            control::Command::Help => {}
        }
        Ok(String::new())
    }

    /// `truth`: the vehicle truth in `key=value` words, each key after
    /// `prefix` ([`crate::vehicle::truth_words`]).
    pub(super) fn truth<F: NorFlash>(&self, dev: &Device<F, P>, prefix: &str) -> String {
        let chain = dev.chain();
        let source = if self.trajectory.is_some() {
            "trajectory"
        } else if let Some(v) = &self.vehicle {
            v.kind()
        } else if self.feed.as_ref().is_some_and(FeedState::drives_vehicle) {
            "feed"
        } else {
            match chain.core_motion() {
                Motion::Static { .. } => "static",
                Motion::ConstantRotation { .. } => "rotation",
                Motion::Vibration { .. } => "vibration",
                Motion::Coning { .. } => "coning",
                Motion::Sample(_) => "sample",
            }
        };
        crate::vehicle::truth_words(&chain.vehicle(), source, chain.temperature(), prefix)
    }

    /// `status`: the device, the line and the link in `key=value` words.
    pub(super) fn status<F: NorFlash>(&self, dev: &Device<F, P>) -> String {
        use imu_emu::device::Mode;
        let mode = match dev.mode() {
            Mode::Idle => "idle",
            Mode::Aligning => "aligning",
            Mode::Continuous => "continuous",
            Mode::FirmwareUpdate => "firmware-update",
        };
        let format = match (dev.mode(), self.link.last_id()) {
            (Mode::Continuous, Some(id)) => format!("{id:#04x}"),
            _ => "none".to_owned(),
        };
        let rate = dev
            .output_rate()
            .map_or("none".to_owned(), |r| r.to_string());
        let rejected = self.monitor.rejected();
        let total: u64 = rejected.iter().map(|r| r.1).sum();
        let mut s = format!(
            "mode={mode} format={format} output-rate={rate} line-rate={} frames-sent={} \
             bytes-sent={} tx-dropped={} backlog-dropped={} held-back-ms={} commands={} \
             rejected={total}",
            dev.line_rate(),
            self.link.frames_sent(),
            self.line_bytes,
            dev.tx_dropped(),
            self.transport.backlog_dropped(),
            self.held_back_ns / 1_000_000,
            self.monitor.commands(),
        );
        for (r, n) in rejected {
            s.push_str(&format!(" rejected-{r}={n}"));
        }
        s.push(' ');
        s.push_str(&self.truth(dev, "truth-"));
        let l = self.link.stats();
        s.push_str(&format!(
            " link={} link-dropped={} link-corrupted={} link-duplicated={} link-noise={} \
             link-cut={} link-stall-dropped={}",
            self.link.describe(self.now_ns),
            l.dropped,
            l.corrupted,
            l.duplicated,
            l.noise,
            l.cut,
            l.stall_dropped
        ));
        if let Some(f) = &self.feed {
            s.push_str(&f.status(self.now_ns));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::super::fake::Mem;
    use super::*;
    use crate::flash::MemNor;
    use imu_emu::device::{Level, PowerOn};
    use imu_emu::isb::Isb;
    use imu_emu::kernel::command::Command;
    use imu_emu::kernel::Kernel;
    use imu_emu::model::Product;

    fn device<P: HostProtocol>(product: Product) -> Device<MemNor, P> {
        let cfg = PowerOn {
            product,
            boot: None,
            seed: 1,
        };
        Device::new(cfg, MemNor::new(), Instant::ZERO)
    }

    fn port<P: HostProtocol>() -> HostPort<Mem, P> {
        HostPort::new(Mem::default(), P::FACTORY_RATE, 500_000)
    }

    /// `status` after the device's monitor saw a KERNEL Stop command and
    /// then `more`.
    fn status_after<P: HostProtocol>(
        p: &mut HostPort<Mem, P>,
        dev: &mut Device<MemNor, P>,
        more: &[u8],
    ) -> String {
        let mut buf = [0u8; 16];
        let n = Command::Stop.encode(&mut buf).unwrap();
        p.monitor.feed(&buf[..n]);
        p.monitor.feed(more);
        p.monitor.judge(dev.personality(), &dev.product());
        p.apply(dev, control::Command::Status, Instant::ZERO)
            .unwrap()
    }

    fn word<'a>(status: &'a str, key: &str) -> &'a str {
        status
            .split(' ')
            .find_map(|w| w.strip_prefix(key)?.strip_prefix('='))
            .unwrap_or_else(|| panic!("no {key} in {status}"))
    }

    /// A KERNEL's input is judged by its monitor: a Stop command counts,
    /// a frame that is not a command is rejected with its reason.
    #[test]
    fn status_counts_the_kernel_commands_and_rejections() {
        let mut dev = device::<Kernel>(Product::parse("K110").unwrap());
        let mut p = port::<Kernel>();
        let mut buf = [0u8; 64];
        let n = imu_emu::kernel::frame::encode(1, 0, &[0xFE], &mut buf).unwrap();
        let s = status_after(&mut p, &mut dev, &buf[..n]);
        assert_eq!(word(&s, "commands"), "1");
        assert_eq!(word(&s, "rejected"), "1");
        assert_eq!(word(&s, "rejected-not-command"), "1");
        assert_eq!(word(&s, "frames-sent"), "0");
        assert_eq!(word(&s, "link"), "clean");
    }

    /// The IMX's input is not decoded as KERNEL frames.
    #[test]
    fn an_imx_status_counts_no_kernel_commands() {
        let mut dev = device::<Isb>(Product::imx5());
        let mut p = port::<Isb>();
        let s = status_after(&mut p, &mut dev, &[]);
        assert_eq!(word(&s, "commands"), "0");
        assert_eq!(word(&s, "rejected"), "0");
    }

    /// A power cycle with BOOT high enters firmware-update mode, where the
    /// input is not decoded; navigation faults are the IMX's only.
    #[test]
    fn power_cycle_and_faults_are_carried_out() {
        let mut dev = device::<Kernel>(Product::parse("K110").unwrap());
        let mut p = port::<Kernel>();
        let at = Instant::from_nanos(1_000_000);
        p.apply(
            &mut dev,
            control::Command::PowerCycle(Some(Level::High)),
            at,
        )
        .unwrap();
        assert!(p.fw_update);
        let s = p.apply(&mut dev, control::Command::Status, at).unwrap();
        assert_eq!(word(&s, "mode"), "firmware-update");
        let nav = control::Command::NavFault(control::NavFault::Gps(false));
        assert!(p.apply(&mut dev, nav, at).is_err());
        let mut imx = device::<Isb>(Product::imx5());
        let mut p = port::<Isb>();
        let nav = control::Command::NavFault(control::NavFault::Gps(false));
        assert_eq!(p.apply(&mut imx, nav, at), Ok(String::new()));
        assert!(imx.personality().nav_faults().gps_off);
    }

    /// `motion …` replaces a script; `truth` names the source playing.
    #[test]
    fn truth_names_the_motion_source() {
        let mut dev = device::<Kernel>(Product::parse("K110").unwrap());
        let mut p = port::<Kernel>();
        let s = p
            .apply(&mut dev, control::Command::Truth, Instant::ZERO)
            .unwrap();
        assert!(s.contains("source=static"), "{s}");
        let m = Motion::ConstantRotation {
            lat_deg: 45.0,
            heading_deg: 0.0,
            rate_dps: [0.0, 0.0, 10.0],
        };
        p.apply(&mut dev, control::Command::Motion(m), Instant::ZERO)
            .unwrap();
        let s = p
            .apply(&mut dev, control::Command::Truth, Instant::ZERO)
            .unwrap();
        assert!(s.contains("source=rotation"), "{s}");
    }
}
