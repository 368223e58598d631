//! EXTRIG (ICD 4.1.3) and TOV (4.1.4) through the sans-IO device.

mod common;
use common::*;

use imu_emu::device::{Event, Level, Pin};
use imu_emu::kernel::command::Command;
use imu_emu::time::Instant;

const MS: u64 = 1_000_000;

fn triggered_bench(model: &str, polarity: u8, hold_off_ms: u16) -> Bench {
    let mut b = Bench::new(model);
    assert_eq!(b.save(0x05FA, &[1]).len(), 1);
    b.save(0x05FB, &[polarity]);
    b.save(0x05FE, &hold_off_ms.to_le_bytes());
    b.cmd(Command::Data(0x8F));
    assert_eq!(b.drain().len(), 1);
    b
}

#[test]
fn extrig_sends_one_frame_per_edge_of_the_configured_polarity() {
    let mut b = triggered_bench("K110", 0, 0);
    assert!(
        b.run_secs(0.5).is_empty(),
        "no periodic output while triggering"
    );
    let t = b.now;
    b.dev.on_pin(Pin::Extrig, Level::High, Instant(t));
    assert!(
        b.drain().is_empty(),
        "rising edge ignored with negative polarity"
    );
    b.dev.on_pin(Pin::Extrig, Level::Low, Instant(t + 1000));
    let f = b.drain();
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].id, 0x8F);
    assert_eq!(f[0].payload.len(), 32);
}

#[test]
fn extrig_positive_polarity_and_hold_off() {
    let mut b = triggered_bench("K120", 1, 10);
    b.run_secs(0.1);
    let t = b.now;
    let mut frames = 0;
    // Rising edges every 4 ms for 40 ms: hold-off 10 ms accepts t, t+12, t+24, t+36.
    for k in 0..10 {
        b.dev
            .on_pin(Pin::Extrig, Level::High, Instant(t + k * 4 * MS));
        b.dev
            .on_pin(Pin::Extrig, Level::Low, Instant(t + k * 4 * MS + MS));
        frames += b.drain().len();
    }
    assert_eq!(frames, 4);
}

#[test]
fn extrig_is_ignored_on_models_without_it_and_when_off() {
    // K102 has no EXTRIG: Trigger_Control cannot be turned on.
    let mut b = Bench::new("K102");
    assert!(b.save(0x05FA, &[1]).is_empty());
    b.cmd(Command::Data(0x8F));
    b.drain();
    b.dev.on_pin(Pin::Extrig, Level::Low, Instant(b.now));
    assert!(b.drain().is_empty());
    assert_eq!(b.run_secs(0.1).len(), 10, "periodic output as usual");
}

#[test]
fn tov_rises_at_sampling_and_falls_when_the_last_bit_left() {
    let mut b = Bench::new("K110");
    assert_eq!(b.save(0x0499, &[1]).len(), 1);
    b.cmd(Command::Data(0x8F));
    b.drain();
    let period = b.dev.tick_period_ns();
    let mut buf = [0u8; 4096];
    let mut edges = Vec::new();
    for _ in 0..40 {
        b.now += period;
        b.dev.on_tick(Instant(b.now));
        b.dev.poll_tx(&mut buf);
        while let Some(e) = b.dev.poll_event() {
            if let Event::Tov { level, at } = e {
                edges.push((level, at.as_nanos()));
            }
        }
    }
    assert_eq!(edges.len(), 4);
    let sample_at = 20 * period;
    assert_eq!(edges[0], (Level::High, sample_at));
    // 40-byte GA frame at 115200 bps, 10 bit times per byte: 3472.2 us.
    assert_eq!(
        edges[1],
        (Level::Low, sample_at + 40 * 10 * 1_000_000_000 / 115_200)
    );
    assert_eq!(edges[2], (Level::High, 2 * sample_at));
}

#[test]
fn no_tov_events_when_tov_control_is_off() {
    let mut b = Bench::new("K110");
    b.cmd(Command::Data(0x8F));
    b.drain();
    let period = b.dev.tick_period_ns();
    for _ in 0..100 {
        b.now += period;
        b.dev.on_tick(Instant(b.now));
        while let Some(e) = b.dev.poll_event() {
            assert!(!matches!(e, Event::Tov { .. }));
        }
    }
}
