//! The seam between the device shell and a protocol personality
//! (ARCHITECTURE.md "Shell and personalities").
//!
//! The shell ([`crate::device::Shell`]) owns what every emulated device
//! shares: power and the BOOT level, the flash and its store, the serial
//! line (TX queue and wire time), pins and events, the time base and the
//! signal chain. A personality owns its protocol: its decoder, its
//! commands, its parameter image, its output streams and encoders, its
//! status words. [`crate::device::Device`] calls the personality at each
//! entry point, after the shell has done its own part, and hands it a
//! [`Context`]: the narrow view of the shell a personality may use (the
//! shell implements it; a personality's unit tests implement it with a
//! small fake). The seam points one way: this module and [`crate::io`]
//! (pins, levels, events, mode) are below both the shell and the
//! personalities, and import neither.
//!
//! Static dispatch: `Device<F, P>` is generic over the personality, so a
//! firmware image links exactly one protocol (the RP2040 image has no room
//! for two) and no call goes through a vtable.

use crate::chain::SignalChain;
use crate::dsp::integrals::Integrate;
use crate::io::{Event, Level, Mode, Pin};
use crate::line::TxBuffer;
use crate::model::Product;
use crate::store::{Image, StoreError};
use crate::time::{Instant, TimeBase};

/// What a personality may use of the device around it (implemented by
/// [`crate::device::Shell`]): the product, the signal chain, the line (a
/// frame pushed in place, the line rate), board events, its image in the
/// store, a software reset, and the time base. `I` is the personality's
/// [`Personality::Integrate`].
pub trait Context<I: Integrate> {
    /// The emulated product.
    fn product(&self) -> Product;
    /// The seed of every random process (and of the serial number).
    fn seed(&self) -> u64;
    /// Whether BOOT put the device in firmware-update mode at power-on.
    fn firmware_update(&self) -> bool;
    /// The signal chain.
    fn chain(&self) -> &SignalChain<I>;
    /// The signal chain, mutably (configuration, output).
    fn chain_mut(&mut self) -> &mut SignalChain<I>;
    /// Queues an `n`-byte frame that `fill` writes in place in the TX queue
    /// at the device's latest time (`false` from `fill`: nothing is sent);
    /// returns when its last bit leaves the line, `None` if it was dropped
    /// ([`crate::line::Line::push_frame`]).
    fn push_frame(&mut self, n: usize, fill: impl FnOnce(&mut [u8]) -> bool) -> Option<Instant>;
    /// The line rate now, bit/s.
    fn line_rate(&self) -> u32;
    /// Frames dropped so far because the TX queue was full.
    fn tx_dropped(&self) -> u32;
    /// Sets the line rate at once and tells the board
    /// ([`Event::LineRate`]), as at power-on.
    fn set_line_rate(&mut self, bps: u32);
    /// Switches the line rate after the bytes already queued have left at
    /// the old rate (the board is told when it has taken them).
    fn switch_line_rate(&mut self, bps: u32);
    /// Queues a board event (dropped if the queue is full).
    fn push_event(&mut self, ev: Event);
    /// Loads the personality's image from flash into `image`: `Ok(true)`
    /// if a valid one was found.
    fn load_image(&mut self, image: &mut [u8]) -> Result<bool, StoreError>;
    /// Saves the personality's image, power-fail safe
    /// ([`crate::store::ParamStore::save`]).
    fn save_image(&mut self, image: &[u8]) -> Result<(), StoreError>;
    /// Asks for a software reset: the device powers on again — BOOT
    /// floating, the image reloaded — at the first tick after the bytes
    /// already queued (the command's reply) have been handed to the board.
    fn request_reset(&mut self);
    /// The time base (power-on, ticks, clock, last RX byte, 1PPS).
    fn time(&self) -> &TimeBase;
    /// The time base, mutably (second fraction, 1PPS flag, RX idle time).
    fn time_mut(&mut self) -> &mut TimeBase;
}

/// A protocol personality: what a device speaks on its serial line.
///
/// The shell calls, in order: [`Personality::unpowered`] once (a cheap
/// placeholder that can be built in place), then at every power-on
/// [`Personality::boot`]; afterwards the entry points as the board drives
/// them. Each call gets the [`Context`] and the time the board gave.
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
    /// The storage of the shell's TX queue: `[u8; TX_CAP + N]`, `N` the
    /// largest frame this personality writes in one piece
    /// ([`crate::line::TX_CAP`], [`TxBuffer::MAX_FRAME`]).
    type TxBuffer: TxBuffer;

    /// The personality before power-on: every field a placeholder that
    /// [`Personality::boot`] sets. Cheap to build (mostly zeros).
    fn unpowered() -> Self;

    /// Power-on (and power cycle): start over from the image in flash (or
    /// the factory image), configure the chain, set the line rate, and
    /// start whatever the device starts by itself. The shell has reset
    /// itself (queue empty, chain at power-on, time base at `now`) and
    /// knows whether BOOT put the device in firmware-update mode
    /// ([`Context::firmware_update`]).
    fn boot(&mut self, cx: &mut impl Context<Self::Integrate>, now: Instant);

    /// Host → device bytes, any chunking.
    fn on_rx(&mut self, bytes: &[u8], cx: &mut impl Context<Self::Integrate>, now: Instant);

    /// The start of an internal-rate tick, before the chain ticks (e.g. to
    /// abandon a frame cut short).
    fn before_tick(&mut self, _cx: &mut impl Context<Self::Integrate>, _now: Instant) {}

    /// An internal-rate tick, after the chain has ticked: produce the
    /// output due at this tick.
    fn on_tick(&mut self, cx: &mut impl Context<Self::Integrate>, now: Instant);

    /// An input pin edge at `at`, after the shell's time base has taken it
    /// (1PPS).
    fn on_pin(
        &mut self,
        pin: Pin,
        level: Level,
        cx: &mut impl Context<Self::Integrate>,
        at: Instant,
    );

    /// The mode outside firmware update (which the shell knows itself).
    fn mode(&self) -> Mode;

    /// The running periodic output rate in Hz, if any.
    fn output_rate(&self, cx: &impl Context<Self::Integrate>) -> Option<u32>;

    /// Ticks from now until the next tick that produces periodic output
    /// (1 = the very next tick), `None` when none is due.
    fn ticks_to_next_output(&self) -> Option<u64>;
}

/// A small fake [`Context`] for the personalities' unit tests: a chain, an
/// in-memory image, the frames and events pushed, and a time base the test
/// moves by hand.
#[cfg(test)]
pub(crate) mod fake {
    use std::vec::Vec;

    use super::*;

    /// Records what a personality asks of its context.
    pub(crate) struct FakeContext<I: Integrate> {
        pub product: Product,
        pub seed: u64,
        pub firmware_update: bool,
        pub chain: SignalChain<I>,
        /// Every frame pushed, whole.
        pub frames: Vec<Vec<u8>>,
        pub line_rate: u32,
        /// The rate of the last switch after the queued bytes.
        pub switched_to: Option<u32>,
        pub events: Vec<Event>,
        /// The saved image, if any (`load_image` finds it).
        pub image: Option<Vec<u8>>,
        pub resets: u32,
        pub time: TimeBase,
    }

    impl<I: Integrate> FakeContext<I> {
        /// A context for `product` powered on at 0, its flash empty.
        pub fn new(product: Product) -> Self {
            FakeContext {
                product,
                seed: 7,
                firmware_update: false,
                chain: SignalChain::powered_on(product, 7),
                frames: Vec::new(),
                line_rate: 0,
                switched_to: None,
                events: Vec::new(),
                image: None,
                resets: 0,
                time: TimeBase::new(Instant::ZERO),
            }
        }

        /// What the shell does before a tick at `now`.
        pub fn tick(&mut self, now: Instant) {
            self.time.tell(now);
            self.time.tick();
            self.chain.tick(now);
        }
    }

    impl<I: Integrate> Context<I> for FakeContext<I> {
        fn product(&self) -> Product {
            self.product
        }
        fn seed(&self) -> u64 {
            self.seed
        }
        fn firmware_update(&self) -> bool {
            self.firmware_update
        }
        fn chain(&self) -> &SignalChain<I> {
            &self.chain
        }
        fn chain_mut(&mut self) -> &mut SignalChain<I> {
            &mut self.chain
        }
        fn push_frame(
            &mut self,
            n: usize,
            fill: impl FnOnce(&mut [u8]) -> bool,
        ) -> Option<Instant> {
            let mut f = std::vec![0u8; n];
            if !fill(&mut f) {
                return None;
            }
            self.frames.push(f);
            // 10 bit times a byte from now.
            let ns = n as u64 * 10 * 1_000_000_000 / u64::from(self.line_rate.max(1));
            Some(self.time.clock().plus_nanos(ns))
        }
        fn line_rate(&self) -> u32 {
            self.line_rate
        }
        fn tx_dropped(&self) -> u32 {
            0
        }
        fn set_line_rate(&mut self, bps: u32) {
            self.line_rate = bps;
            self.events.push(Event::LineRate(bps));
        }
        fn switch_line_rate(&mut self, bps: u32) {
            self.switched_to = Some(bps);
        }
        fn push_event(&mut self, ev: Event) {
            self.events.push(ev);
        }
        fn load_image(&mut self, image: &mut [u8]) -> Result<bool, StoreError> {
            match &self.image {
                Some(i) if i.len() == image.len() => {
                    image.copy_from_slice(i);
                    Ok(true)
                }
                _ => Ok(false),
            }
        }
        fn save_image(&mut self, image: &[u8]) -> Result<(), StoreError> {
            self.image = Some(image.to_vec());
            Ok(())
        }
        fn request_reset(&mut self) {
            self.resets += 1;
        }
        fn time(&self) -> &TimeBase {
            &self.time
        }
        fn time_mut(&mut self) -> &mut TimeBase {
            &mut self.time
        }
    }
}
