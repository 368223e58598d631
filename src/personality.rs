//! The seam between the device shell and a protocol personality
//! (ARCHITECTURE.md "Shell and personalities").
//!
//! The shell ([`crate::device::Shell`]) owns what every emulated device
//! shares: power and the BOOT level, the flash and its store, the serial
//! line (TX queue and wire time), pins and events, the time base and the
//! signal chain. A personality owns its protocol: its decoder, its
//! commands, its parameter image, its output streams and encoders, its
//! status words. [`crate::device::Device`] calls the personality at each
//! entry point, after the shell has done its own part, and hands it the
//! shell.
//!
//! Static dispatch: `Device<F, P>` is generic over the personality, so a
//! firmware image links exactly one protocol (the RP2040 image has no room
//! for two) and no call goes through a vtable.

use embedded_storage::nor_flash::NorFlash;

use crate::device::{Level, Mode, Pin, Shell};
use crate::dsp::integrals::Integrate;
use crate::store::Image;
use crate::time::Instant;

/// A protocol personality: what a device speaks on its serial line.
///
/// The shell calls, in order: [`Personality::unpowered`] once (a cheap
/// placeholder that can be built in place), then at every power-on
/// [`Personality::boot`]; afterwards the entry points as the board drives
/// them. Each call gets the shell and the time the board gave.
/// In firmware-update mode (BOOT asserted at power-on) the shell calls
/// nothing but [`Personality::boot`].
pub trait Personality: Sized {
    /// Whether the chain keeps cumulative integrals for this personality
    /// ([`crate::dsp::integrals::Integrals`]) or not
    /// ([`crate::dsp::integrals::NoIntegrals`]: no storage, no code).
    type Integrate: Integrate;
    /// The image this personality persists in the shell's store.
    type Image: Image + Copy;
    /// Its value (a type like [`crate::store::KernelImage`] folds it into
    /// constants).
    const IMAGE: Self::Image;

    /// The personality before power-on: every field a placeholder that
    /// [`Personality::boot`] sets. Cheap to build (mostly zeros).
    fn unpowered() -> Self;

    /// Power-on (and power cycle): start over from the image in flash (or
    /// the factory image), configure the chain, set the line rate, and
    /// start whatever the device starts by itself. The shell has reset
    /// itself (queue empty, chain at power-on, time base at `now`) and
    /// knows whether BOOT put the device in firmware-update mode
    /// ([`Shell::firmware_update`]).
    fn boot<F: NorFlash>(&mut self, sh: &mut Shell<F, Self>, now: Instant);

    /// Host → device bytes, any chunking.
    fn on_rx<F: NorFlash>(&mut self, bytes: &[u8], sh: &mut Shell<F, Self>, now: Instant);

    /// The start of an internal-rate tick, before the chain ticks (e.g. to
    /// abandon a frame cut short).
    fn before_tick<F: NorFlash>(&mut self, _sh: &mut Shell<F, Self>, _now: Instant) {}

    /// An internal-rate tick, after the chain has ticked: produce the
    /// output due at this tick.
    fn on_tick<F: NorFlash>(&mut self, sh: &mut Shell<F, Self>, now: Instant);

    /// An input pin edge at `at`, after the shell's time base has taken it
    /// (1PPS).
    fn on_pin<F: NorFlash>(&mut self, pin: Pin, level: Level, sh: &mut Shell<F, Self>, at: Instant);

    /// The mode outside firmware update (which the shell knows itself).
    fn mode(&self) -> Mode;

    /// The running periodic output rate in Hz, if any.
    fn output_rate<F: NorFlash>(&self, sh: &Shell<F, Self>) -> Option<u32>;

    /// Ticks from now until the next tick that produces periodic output
    /// (1 = the very next tick), `None` when none is due.
    fn ticks_to_next_output(&self) -> Option<u64>;
}
