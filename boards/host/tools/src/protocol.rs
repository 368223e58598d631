//! The protocol a unit speaks (`--protocol`): the one choice the program,
//! the runner and the tools share, in the lowest module so that none of
//! them imports another for it. What differs between the protocols on the
//! runner's side is `imu_emu_runner::protocol::HostProtocol`, not matches
//! on this enum.

/// The emulated device's protocol (`--protocol`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Protocol {
    /// Inertial Labs KERNEL (ICD rev 1.42).
    Kernel,
    /// Inertial Sense IMX-5 over ISB (protocol 2.1).
    Isb,
}

impl Protocol {
    /// Its `--protocol` value (`kernel`, `isb`), as the web view's JSON
    /// names it too.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Kernel => "kernel",
            Protocol::Isb => "isb",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum as _;

    #[test]
    fn names_are_the_command_line_values() {
        for p in Protocol::value_variants() {
            let v = p.to_possible_value().unwrap();
            assert_eq!(v.get_name(), p.name());
        }
    }
}
