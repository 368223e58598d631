//! Bad input never crashes, hangs or corrupts the device: random bytes,
//! random valid-looking commands with random payloads, random pin edges and
//! ticks — then the device still answers the next good frame correctly and
//! its saved parameters are intact or validly changed.

mod common;
use common::*;

use imu_emu::device::{Level, Pin};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::encode;
use imu_emu::time::Instant;
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Op {
    Garbage(Vec<u8>),
    /// A well-formed command frame with an arbitrary payload.
    Frame(Vec<u8>),
    /// A SaveFlash of an arbitrary ID/value.
    Save(u16, Vec<u8>),
    Ticks(u16),
    Edge(bool, bool),
    PowerCycle,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..80).prop_map(Op::Garbage),
        prop::collection::vec(any::<u8>(), 0..40).prop_map(Op::Frame),
        prop::collection::vec(
            prop_oneof![
                Just(0x33u8),
                Just(0x8F),
                Just(0x95),
                Just(0x96),
                Just(0x97),
                Just(0x12),
                Just(0xFE),
                Just(0xC2)
            ],
            1..2
        )
        .prop_map(Op::Frame),
        (any::<u16>(), prop::collection::vec(any::<u8>(), 0..14))
            .prop_map(|(i, v)| Op::Save(i % 0x0700, v)),
        (0u16..800).prop_map(Op::Ticks),
        (any::<bool>(), any::<bool>()).prop_map(|(a, b)| Op::Edge(a, b)),
        Just(Op::PowerCycle),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 100, ..ProptestConfig::default() })]

    #[test]
    fn no_input_breaks_the_device(model in prop_oneof![Just("K110"), Just("K201"), Just("K120"), Just("K100")],
                                   ops in prop::collection::vec(op(), 0..40)) {
        let mut b = Bench::new(model);
        for op in ops {
            match op {
                Op::Garbage(g) => b.send(&g),
                Op::Frame(p) => {
                    let mut out = [0u8; 64];
                    let n = encode(0, 0, &p, &mut out).unwrap();
                    b.send(&out[..n]);
                }
                Op::Save(id, v) => {
                    b.cmd(Command::SaveFlash { id, len: v.len() as u16, value: &v });
                }
                Op::Ticks(n) => {
                    b.run_ticks(u64::from(n));
                }
                Op::Edge(pps, high) => {
                    let pin = if pps { Pin::Pps } else { Pin::Extrig };
                    let level = if high { Level::High } else { Level::Low };
                    b.dev.on_pin(pin, level, Instant(b.now));
                }
                Op::PowerCycle => b.dev.power_cycle(Instant(b.now)),
            }
            b.drain();
        }
        // Whatever happened: stop, flush a half frame out (idle gap), and
        // the device answers GetBIT exactly once.
        b.run_secs(0.15);
        b.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0xFE, 0x05, 0x01]);
        b.run_secs(0.5);
        b.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00]);
        let f = b.drain();
        prop_assert_eq!(f.len(), 1);
        prop_assert_eq!(f[0].id, 0x1A);
        // Parameters are valid for the model after a power cycle.
        b.dev.power_cycle(Instant(b.now));
        let rate = u16::from_le_bytes(b.read_ram(0x0012, 2).unwrap().try_into().unwrap());
        prop_assert!(rate >= 1 && b.dev.product().model.internal_rate_hz.is_multiple_of(u32::from(rate)));
    }
}
