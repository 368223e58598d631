//! What the runner asks of a protocol beyond the core's seam
//! ([`imu_emu::personality::Personality`]): one trait, implemented for the
//! KERNEL and the IMX-5 (ISB), so that the port, the web view, the fleet
//! and the program name no protocol and match on none. The choice itself
//! ([`Protocol`], `--protocol`) is the tools crate's; the program turns it
//! into a type once, where it picks `Kernel` or `Isb`.
//!
//! A third protocol is one more impl here: its packet rules, its monitor,
//! its live decoder, its factory rate, its RX idle time, its product and
//! the unit `imu-emu allan` runs in process.

use imu_emu::isb::Isb;
use imu_emu::kernel::Kernel;
use imu_emu::model::Product;
use imu_emu::personality::Personality;
use imu_emu_tools::allan::Unit;
use imu_emu_tools::protocol::Protocol;

use crate::control::NavFault;
use crate::link::Wire;
use crate::monitor::{InputMonitor, Monitor, Silent};
use crate::web::live::{IsbLive, KernelLive, Live, LiveDecoder};

/// The host side of a protocol.
pub trait HostProtocol: Personality + Sized + 'static {
    /// Its `--protocol` value.
    const PROTOCOL: Protocol;

    /// The rate a port starts at: the factory line rate, so a client that
    /// opens it before the device powers on sees the rate a factory unit
    /// starts at.
    const FACTORY_RATE: u32;

    /// How long after its last input byte the device abandons a frame cut
    /// short, ns: at `--speed max` the device is not quiet before then.
    const RX_IDLE_NS: u64;

    /// The host-side decoder of what the device receives (logs, `status`).
    type Monitor: InputMonitor<Self>;

    /// The packet rules of this protocol's output, which the link follows
    /// to count packets (`status frames-sent`, `format=`) and to cut whole
    /// ones.
    fn wire() -> Wire;

    /// The web view's decoder of this protocol's output.
    fn live() -> Live;

    /// The product a run emulates and its name in messages, given the
    /// KERNEL model `--model` names (a protocol of one product ignores
    /// it).
    fn product(kernel_model: Product) -> (Product, String);

    /// Runs `unit` in process for `imu-emu allan` ([`crate::unit`]): its
    /// samples to `sample`, and the run's title.
    fn run_unit(unit: &Unit, sample: &mut dyn FnMut(&[f64])) -> anyhow::Result<String>;

    /// Sets GPS time: `gps_s` GPS seconds since 1980-01-06 at device
    /// instant 0 (`--gps-time`, or the host clock at power-on); nothing
    /// where the protocol has no GPS.
    fn set_gps_time(&mut self, _gps_s: u64) {}

    /// A navigation fault (`fault gps|mag|baro on|off`); an error where the
    /// protocol has no navigation side.
    fn nav_fault(&mut self, _change: NavFault) -> Result<(), String> {
        Err("no GPS, magnetometer or barometer on this protocol (--protocol isb has them)".into())
    }
}

/// A new decoder of type `D`, as [`Live::decoder`] holds it.
fn new_live<D: LiveDecoder + Default + 'static>() -> Box<dyn LiveDecoder> {
    Box::new(D::default())
}

/// The Inertial Labs KERNEL (ICD rev 1.42).
impl HostProtocol for Kernel {
    const PROTOCOL: Protocol = Protocol::Kernel;
    /// Baud_Rate's factory value (Table 5.24).
    const FACTORY_RATE: u32 = 115_200;
    const RX_IDLE_NS: u64 = imu_emu::kernel::RX_IDLE_ABANDON_NS;
    type Monitor = Monitor;

    /// KERNEL frames (ICD Table 5.2; the frame ID at byte 3).
    fn wire() -> Wire {
        Wire::of::<imu_emu::kernel::frame::Kernel>(3)
    }

    fn live() -> Live {
        Live {
            protocol: Protocol::Kernel,
            decoder: new_live::<KernelLive>,
        }
    }

    fn product(kernel_model: Product) -> (Product, String) {
        (kernel_model, kernel_model.code().to_string())
    }

    /// Its data frames, as a host reads them.
    fn run_unit(unit: &Unit, sample: &mut dyn FnMut(&[f64])) -> anyhow::Result<String> {
        crate::unit::kernel_frames(unit, sample)
    }
}

/// The Inertial Sense IMX-5 over ISB (protocol 2.1).
impl HostProtocol for Isb {
    const PROTOCOL: Protocol = Protocol::Isb;
    /// ser0BaudRate's factory value (FLASH_CONFIG).
    const FACTORY_RATE: u32 = imu_emu::isb::sets::flash::DEFAULT_BAUD_RATE;
    const RX_IDLE_NS: u64 = imu_emu::isb::RX_IDLE_ABANDON_NS;
    /// The IMX reports its own port counters (PORT_MONITOR).
    type Monitor = Silent;

    /// ISB packets (the data set ID at byte 3 of the header).
    fn wire() -> Wire {
        Wire::of::<imu_emu::isb::packet::Isb>(3)
    }

    fn live() -> Live {
        Live {
            protocol: Protocol::Isb,
            decoder: new_live::<IsbLive>,
        }
    }

    fn product(_kernel_model: Product) -> (Product, String) {
        (Product::imx5(), "IMX-5 (ISB)".to_owned())
    }

    /// Its chain averaged over each output interval, what its IMU message
    /// carries.
    fn run_unit(unit: &Unit, sample: &mut dyn FnMut(&[f64])) -> anyhow::Result<String> {
        crate::unit::chain_averaged(unit, sample)
    }

    fn set_gps_time(&mut self, gps_s: u64) {
        Isb::set_gps_time(self, gps_s.saturating_mul(1_000_000_000));
    }

    fn nav_fault(&mut self, change: NavFault) -> Result<(), String> {
        let mut f = self.nav_faults();
        match change {
            NavFault::Gps(on) => f.gps_off = !on,
            NavFault::Mag(on) => f.mag_disturbed = on,
            NavFault::Baro(on) => f.baro_failed = on,
        }
        self.set_nav_faults(f);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factory_rates_are_the_units_defaults() {
        assert_eq!(Kernel::FACTORY_RATE, 115_200);
        assert_eq!(Isb::FACTORY_RATE, 921_600);
    }

    #[test]
    fn the_live_decoders_name_their_protocol() {
        assert_eq!(Kernel::live().protocol, Kernel::PROTOCOL);
        assert_eq!(Isb::live().protocol, Isb::PROTOCOL);
        assert_eq!(Isb::PROTOCOL.name(), "isb");
    }

    #[test]
    fn products_and_their_names() {
        let k = Product::parse("K110").unwrap();
        let (p, name) = Kernel::product(k);
        assert_eq!(p.code().to_string(), "KERNEL-110-G2000-A40");
        assert_eq!(name, "KERNEL-110-G2000-A40");
        let (p, name) = Isb::product(k);
        assert_eq!(p.code().to_string(), Product::imx5().code().to_string());
        assert_eq!(name, "IMX-5 (ISB)");
    }

    /// The tools' side of each protocol (`ToolProtocol`, keyed by the same
    /// `Protocol`) reads the unit this side serves.
    #[test]
    fn the_tools_of_a_protocol_speak_its_product() {
        use imu_emu_tools::client::tool_protocol;
        let k = Product::parse("K120").unwrap();
        fn check<P: HostProtocol>(k: Product) {
            let tools = tool_protocol::of(P::PROTOCOL);
            assert_eq!(tools.protocol(), P::PROTOCOL);
            let (product, name) = P::product(k);
            assert!(tools.speaks(&product), "{name}");
            assert_eq!(tool_protocol::of_product(&product).protocol(), P::PROTOCOL);
        }
        check::<Kernel>(k);
        check::<Isb>(k);
    }

    #[test]
    fn only_the_imx_has_navigation_faults() {
        use imu_emu::device::{Device, PowerOn};
        use imu_emu::time::Instant;
        let cfg = |product| PowerOn {
            product,
            boot: None,
            seed: 1,
        };
        let flash = crate::flash::MemNor::new;
        let mut k =
            Device::<_, Kernel>::new(cfg(Product::parse("K110").unwrap()), flash(), Instant::ZERO);
        let e = k
            .personality_mut()
            .nav_fault(NavFault::Gps(false))
            .unwrap_err();
        assert!(e.contains("--protocol isb"), "{e}");
        let mut i = Device::<_, Isb>::new(cfg(Product::imx5()), flash(), Instant::ZERO);
        i.personality_mut().nav_fault(NavFault::Gps(false)).unwrap();
        assert!(i.personality().nav_faults().gps_off);
    }
}
