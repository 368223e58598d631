//! Device state machine through the sans-IO entry point (ICD 5.1, 5.3, 6).

mod common;
use common::*;

use imu_emu::device::{Device, Event, Level, Mode, PowerOn};
use imu_emu::kernel::command::Command;
use imu_emu::model::Product;
use imu_emu::time::Instant;
use imu_emu::Kernel;

const GA: u8 = 0x8F;

#[test]
fn data_command_is_acknowledged_with_its_checksum_then_streams_at_data_rate() {
    let mut b = Bench::new("K110");
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x8F, 0x96, 0x00]);
    let f = b.drain();
    assert_eq!(
        b.raw,
        [0xAA, 0x55, 0x01, 0x8F, 0x08, 0x00, 0x96, 0x00, 0x2E, 0x01]
    );
    assert_eq!(f.len(), 1);
    assert_eq!(b.dev.mode(), Mode::Continuous);
    // Default Data_Rate 100 Hz: one frame every 20 ticks.
    let frames = b.run_secs(1.0);
    assert_eq!(frames.len(), 100);
    assert!(frames.iter().all(|f| f.id == GA && f.payload.len() == 32));
    let ticks: Vec<u64> = frames.iter().map(|f| f.tick).collect();
    assert!(ticks.windows(2).all(|w| w[1] - w[0] == 20));
}

#[test]
fn static_level_ga_payload_has_1g_on_z_and_a_2khz_counter() {
    let mut b = Bench::new("K110");
    b.cmd(Command::Data(GA));
    b.drain();
    let frames = b.run_ticks(40);
    let p = &frames[0].payload;
    // Default K110 errors: turn-on bias and noise of a few 0.01 deg/s and
    // a few mg around the static, level truth.
    for axis in 0..3 {
        assert!(
            i32_at(p, 4 * axis).abs() < 50_000,
            "gyro {axis} within 0.5 deg/s"
        );
    }
    assert!(i32_at(p, 12).abs() < 20_000 && i32_at(p, 16).abs() < 20_000);
    assert!((i32_at(p, 20) - 1_000_000).abs() < 20_000, "AccZ = 1 g");
    let c0 = u16_at(p, 24);
    let c1 = u16_at(&frames[1].payload, 24);
    assert_eq!(c1.wrapping_sub(c0), 20);
    assert_eq!(u16_at(p, 26), 0, "USW");
    assert_eq!(i16_at(p, 30), 250, "25.0 degC at power-on");
}

#[test]
fn with_ideal_sensors_the_gyros_read_earth_rate_at_the_built_in_site() {
    let mut b = Bench::new("K110");
    *b.dev.chain_mut().errors_mut() = imu_emu::sensor::errors::ErrorModel::IDEAL;
    b.cmd(Command::Data(GA));
    b.drain();
    let p = &b.run_ticks(20)[0].payload;
    // 15.041 deg/h = 0.0041781 deg/s at Newlyn, 50.10167 deg N; level, Y
    // north: north component on Y, 0.0041781 * cos 50.10167 = 0.0026790
    // deg/s, and up component on Z, 0.0041781 * sin 50.10167 = 0.0032056
    // (the fixed-point build's integer truth reads it one unit lower:
    // 0.0032056 is just above the half unit).
    let up = if cfg!(feature = "fixed-point") {
        320
    } else {
        321
    };
    assert_eq!((i32_at(p, 0), i32_at(p, 4), i32_at(p, 8)), (0, 268, up));
    assert_eq!(
        (i32_at(p, 12), i32_at(p, 16), i32_at(p, 20)),
        (0, 0, 1_000_000)
    );
}

#[test]
fn orientation_waits_for_initial_alignment_default_2_s() {
    let mut b = Bench::new("K110");
    b.cmd(Command::Data(0x33));
    let ack = b.drain();
    assert_eq!(ack.len(), 1);
    assert_eq!(b.dev.mode(), Mode::Aligning);
    assert!(b.run_secs(1.99).is_empty());
    let frames = b.run_secs(1.01);
    assert_eq!(b.dev.mode(), Mode::Continuous);
    assert_eq!(frames.len(), 100);
    assert!(frames.iter().all(|f| f.id == 0x33 && f.payload.len() == 34));
    // Level within the accelerometer bias, heading 0 after alignment
    // (relative heading), AccZ = 1 g * KA (500 for A40).
    let p = &frames[0].payload;
    // 0.00° or 360.00° (a hair below 0 rounds to 36000).
    let heading = u16_at(p, 0);
    assert!(heading <= 1 || heading >= 35_999, "heading {heading}");
    assert!(
        i16_at(p, 2).abs() < 50 && i16_at(p, 4).abs() < 50,
        "pitch, roll within 0.5 deg"
    );
    assert!((i16_at(p, 16) - 500).abs() < 10);
}

#[test]
fn alignment_time_zero_skips_alignment() {
    let mut b = Bench::new("K110");
    assert_eq!(b.save(0x0014, &[0, 0]).len(), 1);
    b.cmd(Command::Data(0x82));
    b.drain();
    assert_eq!(b.dev.mode(), Mode::Continuous);
    let f = b.run_ticks(20);
    assert_eq!(f.len(), 1);
    assert_eq!(i16_at(&f[0].payload, 6), 10_000, "q0 = 1");
}

#[test]
fn stop_returns_to_idle_from_any_mode_and_repeated_stops_are_harmless() {
    let mut b = Bench::new("K110");
    for start in [0x33u8, GA] {
        b.cmd(Command::Data(start));
        b.run_ticks(10);
        for _ in 0..5 {
            b.cmd(Command::Stop);
        }
        assert_eq!(b.dev.mode(), Mode::Idle);
        assert!(b.run_secs(0.5).is_empty());
    }
}

#[test]
fn a_new_data_command_switches_format_cleanly() {
    let mut b = Bench::new("K120");
    b.cmd(Command::Data(GA));
    b.run_ticks(100);
    b.cmd(Command::Data(0xA5));
    let f = b.drain();
    assert_eq!(f.len(), 1, "only the ack");
    assert_eq!(f[0].payload, cmd_checksum(Command::Data(0xA5)));
    let frames = b.run_secs(0.2);
    assert_eq!(frames.len(), 20);
    assert!(frames.iter().all(|f| f.id == 0xA5 && f.payload.len() == 44));
    // K120 has an aux accelerometer: Acc2Z = 1 g.
    assert!((i32_at(&frames[0].payload, 32) - 1_000_000).abs() < 50_000);
}

#[test]
fn get_dev_info_is_166_bytes_with_serial_firmware_and_imu_type() {
    let mut b = Bench::new("KERNEL-120-G2000-A8A90");
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x12, 0x19, 0x00]);
    let f = b.drain();
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].id, 0x12);
    let p = &f[0].payload;
    assert_eq!(p.len(), 166);
    assert_eq!(&p[0..8], b"10000007");
    assert!(p[8..48].starts_with(b"KERNEL-120-G2000-A8A90 imu-emu "));
    assert_eq!(p[49], 120);
    assert_eq!(&p[0..8], &p[50..58]);
    assert_eq!(&p[8..48], &p[58..98]);
    assert!(p[98..].iter().all(|&x| x == 0));
}

#[test]
fn get_bit_is_4_bytes_all_ok() {
    let mut b = Bench::new("K110");
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00]);
    assert_eq!(b.raw.len(), 0);
    let f = b.drain();
    assert_eq!(
        b.raw,
        [0xAA, 0x55, 0x01, 0x1A, 0x0A, 0x00, 0, 0, 0, 0, 0x25, 0x00]
    );
    assert_eq!(f[0].payload, [0; 4]);
}

#[test]
fn read_ram_measurement_range_matches_the_icd_example() {
    let mut b = Bench::new("KERNEL-110-G2000-A8");
    b.send(&[
        0xAA, 0x55, 0x00, 0x00, 0x0C, 0x00, 0xB1, 0xFF, 0x8F, 0x02, 0x01, 0x00, 0x4E, 0x02,
    ]);
    b.drain();
    assert_eq!(
        b.raw,
        [0xAA, 0x55, 0x01, 0xB1, 0x07, 0x00, 0x93, 0x4C, 0x01]
    );
}

#[test]
fn save_flash_examples_are_acknowledged_and_read_back() {
    let mut b = Bench::new("K110");
    let ex1 = [
        0xAA, 0x55, 0x00, 0x00, 0x0E, 0x00, 0xB2, 0xFF, 0x12, 0x00, 0x02, 0x00, 0xD0, 0x07, 0xAA,
        0x02,
    ];
    b.send(&ex1);
    b.drain();
    assert_eq!(
        b.raw,
        [0xAA, 0x55, 0x01, 0xB2, 0x08, 0x00, 0xAA, 0x02, 0x67, 0x01]
    );
    assert_eq!(b.read_ram(0x0012, 2).unwrap(), [0xD0, 0x07]);
    let ex4 = [
        0xAA, 0x55, 0x00, 0x00, 0x18, 0x00, 0xB2, 0xFF, 0x3A, 0x02, 0x0C, 0x00, 0x00, 0x00, 0x20,
        0x41, 0x00, 0x00, 0xA0, 0x41, 0x00, 0x00, 0xF0, 0x41, 0x84, 0x04,
    ];
    b.send(&ex4);
    let f = b.drain();
    assert_eq!(f[0].payload, [0x84, 0x04]);
    assert_eq!(b.read_ram(0x023A, 12).unwrap(), ex4[12..24]);
}

#[test]
fn bad_save_flash_changes_nothing_and_gets_no_answer() {
    let mut b = Bench::new("K201");
    let before = b.read_ram(0x0012, 2).unwrap();
    let bad: &[(u16, &[u8])] = &[
        (0x0013, &[1]),          // no such ID (inside Data_Rate)
        (0x0012, &[0xE8]),       // wrong length
        (0x0012, &[0, 0]),       // 0 Hz
        (0x0012, &[0xB0, 0x04]), // 1200 Hz: not a divisor of 4000
        (0x028F, &[0x66]),       // read-only
        (0x0496, &[1]),          // IMU-P_Interface unsupported
        (0x03D7, &[0]),          // K201 has no 16 Hz LPF
        (0x03B2, &[0x11]),       // no such baud code
        (0x0014, &[31, 0]),      // > 30 s alignment
        (0x03A9, &[0x33]),       // K201 cannot auto-start Orientation
        (0x05FA, &[1]),          // K201 has no EXTRIG
        (0x045A, &f32::NAN.to_le_bytes()),
        (0x023A, &[0, 0, 0x48, 0x43, 0, 0, 0, 0, 0, 0, 0, 0]), // heading 200
    ];
    for (id, value) in bad {
        assert!(b.save(*id, value).is_empty(), "id {id:#06x} {value:?}");
    }
    assert_eq!(b.read_ram(0x0012, 2).unwrap(), before);
    assert_eq!(b.read_ram(0x028F, 1).unwrap(), [0x96]);
    b.dev.power_cycle(Instant(b.now));
    assert_eq!(b.read_ram(0x0012, 2).unwrap(), before);
    // Malformed SaveFlash (length field disagrees with the value) and
    // ReadRAM with a wrong length or unknown ID: silence.
    b.send(&[
        0xAA, 0x55, 0x00, 0x00, 0x0D, 0x00, 0xB2, 0xFF, 0x12, 0x00, 0x02, 0x00, 0x64, 0x89, 0x01,
    ]);
    assert!(b.drain().is_empty());
    assert_eq!(b.read_ram(0x0012, 1), None);
    assert_eq!(b.read_ram(0x0001, 1), None);
}

#[test]
fn tov_and_extrig_are_exclusive() {
    let mut b = Bench::new("K110");
    assert_eq!(b.save(0x05FA, &[1]).len(), 1);
    assert!(b.save(0x0499, &[1]).is_empty());
    assert_eq!(b.save(0x05FA, &[0]).len(), 1);
    assert_eq!(b.save(0x0499, &[1]).len(), 1);
}

#[test]
fn data_rate_saved_while_idle_applies_to_the_next_stream() {
    let mut b = Bench::new("K110");
    b.save(0x0012, &200u16.to_le_bytes());
    assert_eq!(b.read_ram(0x0012, 2).unwrap(), 200u16.to_le_bytes());
    b.cmd(Command::Data(GA));
    assert_eq!(b.run_secs(1.0).len(), 1 + 200);
}

#[test]
fn data_rate_saved_while_streaming_waits_for_the_next_data_command() {
    let mut b = Bench::new("K110");
    b.cmd(Command::Data(GA));
    b.drain();
    assert_eq!(b.save(0x0012, &50u16.to_le_bytes()).len(), 1);
    assert_eq!(
        b.read_ram(0x0012, 2).unwrap(),
        100u16.to_le_bytes(),
        "RAM keeps the running value"
    );
    assert_eq!(b.run_secs(1.0).len(), 100);
    b.cmd(Command::Data(GA));
    assert_eq!(b.drain().len(), 1);
    assert_eq!(b.read_ram(0x0012, 2).unwrap(), 50u16.to_le_bytes());
    assert_eq!(b.run_secs(1.0).len(), 50);
}

#[test]
fn rate_is_capped_by_formula_5_1_at_the_current_baud() {
    let mut b = Bench::new("K110");
    b.save(0x0012, &2000u16.to_le_bytes());
    b.cmd(Command::Data(0x81)); // Calibrated HR: 125 Hz max at 115200 (Table 5.28)
    b.save(0x0014, &[0, 0]);
    b.cmd(Command::Data(0x81));
    assert_eq!(b.dev.output_rate(), Some(125));
}

#[test]
fn baud_rate_waits_for_commit_and_switches_after_queued_bytes() {
    let mut b = Bench::new("K110");
    let mut buf = [0u8; 64];
    assert_eq!(b.dev.poll_event(), Some(Event::LineRate(115_200)));
    b.save(0x03B2, &[0x0B]);
    assert_eq!(b.dev.line_rate(), 115_200);
    assert_eq!(b.read_ram(0x03B2, 1).unwrap(), [0x00]);
    // Queue a reply, then commit: the reply leaves at the old rate.
    b.cmd(Command::GetBit);
    b.cmd(Command::CommitBaudRate);
    b.cmd(Command::GetBit);
    assert_eq!(b.dev.line_rate(), 2_000_000);
    assert_eq!(b.dev.poll_tx(&mut buf), 12, "first reply only");
    assert_eq!(b.dev.poll_tx(&mut buf), 0, "held until the switch is taken");
    assert_eq!(b.dev.poll_event(), Some(Event::LineRate(2_000_000)));
    assert_eq!(b.dev.poll_tx(&mut buf), 12);
    assert_eq!(b.read_ram(0x03B2, 1).unwrap(), [0x0B]);
    // A saved baud rate also applies at power-on.
    b.save(0x03B2, &[0x01]);
    b.dev.power_cycle(Instant(b.now));
    assert_eq!(b.dev.line_rate(), 4_800);
    assert_eq!(b.dev.poll_event(), Some(Event::LineRate(4_800)));
}

#[test]
fn saved_parameters_survive_a_power_cycle() {
    let mut b = Bench::new("K110");
    b.save(0x0012, &[0xC8, 0x00]);
    b.save(0x03D7, &[0x01]);
    b.dev.power_cycle(Instant(b.now));
    assert_eq!(b.read_ram(0x0012, 2).unwrap(), [0xC8, 0x00]);
    assert_eq!(b.read_ram(0x03D7, 1).unwrap(), [0x01]);
    // The flash image carries over to a new device (a board restart).
    let flash = b.dev.into_flash();
    let mut b2 = Bench::with_flash("K110", flash);
    assert_eq!(b2.read_ram(0x0012, 2).unwrap(), [0xC8, 0x00]);
}

#[test]
fn power_cut_at_every_step_of_a_save_flash_leaves_old_or_new() {
    let mut b = Bench::new("K110");
    b.save(0x0012, &[0xC8, 0x00]); // 200, flash now holds a block
    let base = b.dev.flash().clone();
    // Count the steps of one SaveFlash.
    let before = base.steps();
    b.save(0x0012, &[0x32, 0x00]);
    let steps = b.dev.flash().steps() - before;
    assert!(steps > 10);
    for k in 0..=steps {
        let mut flash = base.clone();
        flash.cut_power_after(k);
        let mut b = Bench::with_flash("K110", flash);
        let acks = b.save(0x0012, &[0x32, 0x00]);
        b.dev.flash_mut().restore_power();
        b.dev.power_cycle(Instant(b.now));
        let v = b.read_ram(0x0012, 2).unwrap();
        assert!(v == [0xC8, 0x00] || v == [0x32, 0x00], "cut at {k}: {v:?}");
        if acks.is_empty() {
            assert!(k < steps);
        } else {
            assert_eq!(v, [0x32, 0x00], "acknowledged means persisted");
        }
        assert_eq!(b.read_ram(0x0014, 2).unwrap(), [2, 0], "others intact");
        assert_eq!(b.read_ram(0x028F, 1).unwrap(), [0x96]);
    }
}

#[test]
fn auto_start_announces_and_streams_at_power_on() {
    let mut b = Bench::new("K110");
    b.save(0x03A9, &[GA]);
    b.dev.power_cycle(Instant(b.now));
    b.raw.clear();
    let frames = b.run_secs(0.1);
    assert_eq!(
        &b.raw[..10],
        &[0xAA, 0x55, 0x01, 0x00, 0x08, 0x00, 0x00, 0x00, 0x09, 0x00]
    );
    assert_eq!(frames.len(), 1 + 10);
    b.cmd(Command::Stop);
    assert!(b.run_secs(0.1).is_empty());
}

#[test]
fn boot_input_at_power_on_enters_firmware_update_mode_until_power_cycle() {
    let product = Product::parse("K110").unwrap();
    let mut dev = Device::power_on_with(
        PowerOn {
            product,
            boot: Some(Level::High),
            seed: 0,
        },
        Flash::new(),
        Instant::ZERO,
    );
    assert_eq!(dev.mode(), Mode::FirmwareUpdate);
    dev.on_rx(
        &[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x12, 0x19, 0x00],
        Instant::ZERO,
    );
    for i in 1..100 {
        dev.on_tick(Instant(i * 500_000));
    }
    assert_eq!(dev.tx_len(), 0);
    dev.power_cycle(Instant(50_000_000));
    assert_eq!(dev.mode(), Mode::Idle);
    // K100's BOOT is active low (Table 4.1 note 4): high is harmless there.
    let k100 = Product::parse("K100").unwrap();
    let dev = Device::power_on_with(
        PowerOn {
            product: k100,
            boot: Some(Level::High),
            seed: 0,
        },
        Flash::new(),
        Instant::ZERO,
    );
    assert_eq!(dev.mode(), Mode::Idle);
}

#[test]
fn k201_ignores_formats_it_does_not_have_and_runs_at_4khz() {
    let mut b = Bench::new("K201");
    for code in [0x33, 0x82, 0x81] {
        b.cmd(Command::Data(code));
        assert!(b.run_ticks(100).is_empty(), "{code:#x}");
        assert_eq!(b.dev.mode(), Mode::Idle);
    }
    b.save(0x0012, &4000u16.to_le_bytes());
    b.save(0x03B2, &[0x10]);
    b.cmd(Command::CommitBaudRate);
    b.cmd(Command::Data(0xA5));
    let f = b.run_ticks(4000);
    assert_eq!(f.len(), 1 + 4000);
    assert_eq!(i32_at(&f[1].payload, 32), 0, "K201 aux accel is zero");
}

#[test]
fn udd_config_get_struct_and_stream() {
    let mut b = Bench::new("K110");
    // Default configuration.
    b.cmd(Command::GetUddStruct);
    assert_eq!(b.drain()[0].payload, [5, 0x02, 0x21, 0x23, 0x52, 0x53]);
    // 0x96 command, then the Table 5.19 message.
    b.cmd(Command::UddConfig);
    assert!(b.drain().is_empty());
    let msg = [
        0xAA, 0x55, 0x00, 0x00, 0x09, 0x00, 0x02, 0x07, 0x2E, 0x40, 0x00,
    ];
    b.send(&msg);
    let r = b.drain();
    assert_eq!(r[0].id, 0x96);
    // Checksum of the message, no errors, no wrong types, max rate for a
    // 21-byte payload at 115200 bps (Formula 5.1: 350 Hz -> 250), reserved.
    assert_eq!(max_udd(115_200, 1 + 2 + 6 + 12), 250);
    assert_eq!(r[0].payload, [0x40, 0x00, 0, 0, 0, 250, 0, 0]);
    b.cmd(Command::GetUddStruct);
    assert_eq!(b.drain()[0].payload, [2, 0x07, 0x2E]);
    b.save(0x0014, &[0, 0]);
    b.cmd(Command::Data(0x95));
    let f = b.run_ticks(20);
    assert_eq!(f.len(), 2);
    assert_eq!(f[1].payload.len(), 1 + 2 + 6 + 12);
    assert_eq!(&f[1].payload[..3], &[2, 0x07, 0x2E]);
    // Persisted.
    b.dev.power_cycle(Instant(b.now));
    b.cmd(Command::GetUddStruct);
    assert_eq!(b.drain()[0].payload, [2, 0x07, 0x2E]);
}

fn max_udd(baud: u32, payload: usize) -> u16 {
    imu_emu::kernel::rate::max_rate(baud, payload, 2000) as u16
}

#[test]
fn udd_config_errors_keep_the_previous_config() {
    let mut b = Bench::new("K100");
    // Wrong types: 0x2E on K100 (2nd), 0x77 unknown (3rd).
    b.cmd(Command::UddConfigMessage(&[3, 0x21, 0x2E, 0x77]));
    let r = &b.drain()[0].payload;
    assert_eq!(&r[..5], &[0, 0, 0x04, 0b110, 0]);
    // Structure: N says 3, two types follow.
    b.cmd(Command::UddConfigMessage(&[3, 0x21, 0x23]));
    assert_eq!(b.drain()[0].payload[2], 0x01);
    // Data: N = 0.
    b.cmd(Command::UddConfigMessage(&[0]));
    assert_eq!(b.drain()[0].payload[2] & 0x02, 0x02);
    b.cmd(Command::GetUddStruct);
    assert_eq!(b.drain()[0].payload, [5, 0x02, 0x21, 0x23, 0x52, 0x53]);
}

#[test]
fn udd_config_too_large_for_the_rate_sets_bit_3_and_lowers_the_rate() {
    let mut b = Bench::new("K110");
    b.save(0x0012, &1000u16.to_le_bytes());
    let list = [0x02, 0x21, 0x23, 0x2D, 0x2E, 0x91, 0x52, 0x53];
    let mut msg = vec![list.len() as u8];
    msg.extend_from_slice(&list);
    b.cmd(Command::UddConfigMessage(&msg));
    let r = b.drain()[0].payload.clone();
    let payload_len = 1 + 8 + 8 + 12 * 5 + 2 + 2;
    let max = max_udd(115_200, payload_len);
    assert_eq!(r[2], 0x08);
    assert_eq!(u16_at(&r, 5), max);
    assert_eq!(max, 100);
    b.cmd(Command::Data(0x95));
    assert_eq!(b.dev.output_rate(), Some(100));
}

#[test]
fn gam_second_fraction_follows_power_on_then_pps() {
    let mut b = Bench::new("K110");
    b.cmd(Command::Data(0x9B));
    let f = b.run_ticks(20);
    let p = &f[1].payload;
    assert_eq!(
        u32::from_le_bytes(p[26..30].try_into().unwrap()),
        10_000_000
    );
    assert_eq!(u16_at(p, 24), 0);
    let f = b.run_secs(1.0);
    assert_eq!(
        u16_at(&f.last().unwrap().payload, 24),
        0x0008,
        "no 1PPS for > 1 s"
    );
    let at = b.now;
    b.dev.on_pin(
        imu_emu::device::Pin::Pps,
        Level::High,
        Instant(at - 1_000_000),
    );
    let f = b.run_ticks(20);
    let p = &f[0].payload;
    assert_eq!(u16_at(p, 24), 0x0001);
    assert_eq!(
        u32::from_le_bytes(p[26..30].try_into().unwrap()),
        11_000_000
    );
    let f = b.run_ticks(20);
    assert_eq!(u16_at(&f[0].payload, 24), 0);
}

#[test]
fn garbage_and_a_frame_cut_short_are_skipped() {
    let mut b = Bench::new("K110");
    let get_bit = [0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00];
    let mut junk = vec![0x00, 0xAA, 0xAA, 0x55, 0x00, 0x00, 0x02, 0x00]; // len < 6
    junk.extend_from_slice(&[0xAA, 0x55, 0x00, 0x00, 0xFF, 0xFF]); // too long
    junk.extend_from_slice(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x22, 0x00]); // bad sum
    junk.extend_from_slice(&get_bit);
    b.send(&junk);
    assert_eq!(b.drain().len(), 1);
    // A frame cut short, then silence, then a good frame.
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x0E, 0x00, 0xB2]);
    b.run_secs(0.2);
    b.send(&get_bit);
    assert_eq!(b.drain().len(), 1);
    // A frame cut short directly followed by a good one.
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x0E, 0x00, 0xB2, 0xFF]);
    b.send(&get_bit);
    b.send(&get_bit);
    assert_eq!(b.drain().len(), 2);
    b.send(&get_bit);
    assert_eq!(b.drain().len(), 1);
}

#[test]
fn vendor_sdk_device_parameters_request_gets_60_bytes() {
    let mut b = Bench::new("K110");
    b.cmd(Command::DeviceParameters);
    let f = b.drain();
    assert_eq!(f[0].id, 0x41);
    assert_eq!(f[0].payload.len(), 60);
    assert_eq!(u16_at(&f[0].payload, 0), 100);
    // B1 6C (2-byte payload) is ignored.
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x08, 0x00, 0xB1, 0x6C, 0x25, 0x01]);
    assert!(b.drain().is_empty());
}

/// The same command script, from power-on at `t0` ns: every byte sent.
fn script(dev: &mut Device<Flash, Kernel>, t0: u64) -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = [0u8; 512];
    let period = dev.tick_period_ns();
    let n = Command::Data(0x95).encode(&mut buf).unwrap();
    dev.on_rx(&buf[..n], Instant(t0));
    for i in 1..=3000 {
        dev.on_tick(Instant(t0 + i * period));
        loop {
            let n = dev.poll_tx(&mut buf);
            if n == 0 {
                break;
            }
            out.extend_from_slice(&buf[..n]);
        }
    }
    out
}

/// A device built in place (`power_on_into`, what the firmware does), one
/// built by value and one power-cycled after a history all send the same
/// bytes: the same parameters from flash, the same seed, the same chain.
#[test]
fn power_on_in_place_by_value_and_power_cycle_agree() {
    let product = Product::parse("K120").unwrap();
    let cfg = PowerOn {
        product,
        boot: None,
        seed: 7,
    };
    let mut b = Bench::new("K120");
    b.save(0x0012, &[0xC8, 0x00]);
    let flash = b.dev.flash().clone();

    let mut slot = Box::new(core::mem::MaybeUninit::uninit());
    let a = Device::power_on_into(&mut slot, cfg, flash.clone(), Instant::ZERO);
    let expect = script(a, 0);
    assert!(expect.len() > 10_000, "{} bytes", expect.len());

    let mut v = Device::power_on_with(cfg, flash, Instant::ZERO);
    assert_eq!(script(&mut v, 0), expect);

    b.cmd(Command::Data(GA));
    b.run_ticks(5000);
    b.dev.power_cycle(Instant(b.now));
    let t0 = b.now;
    assert_eq!(script(&mut b.dev, t0), expect);
}

/// Time flag 0x0001 ("1PPS received between the last and current frame",
/// Table 5.8 note 2) of a stream's first frame covers the time since the
/// data command: an edge while idle, or during an earlier stream after its
/// last frame, is not reported (docs/kernel.md "Protocol notes").
#[test]
fn a_pps_edge_before_the_data_command_is_not_flagged_in_the_first_frame() {
    let mut b = Bench::new("K110");
    b.run_ticks(100);
    b.dev
        .on_pin(imu_emu::device::Pin::Pps, Level::High, Instant(b.now));
    b.run_ticks(100);
    b.cmd(Command::Data(0x9B));
    let f = b.run_ticks(20);
    assert_eq!(f[0].id, 0x9B);
    assert_eq!(f[1].payload.len(), 32, "{f:?}");
    assert_eq!(u16_at(&f[1].payload, 24) & 0x0001, 0);
    // An edge after the command is flagged in the next frame, once.
    b.dev
        .on_pin(imu_emu::device::Pin::Pps, Level::High, Instant(b.now));
    let f = b.run_ticks(40);
    assert_eq!(u16_at(&f[0].payload, 24) & 0x0001, 0x0001);
    assert_eq!(u16_at(&f[1].payload, 24) & 0x0001, 0);
    // Stop, an edge while idle, a new stream: not flagged.
    b.cmd(Command::Stop);
    b.dev
        .on_pin(imu_emu::device::Pin::Pps, Level::High, Instant(b.now));
    b.run_ticks(10);
    b.cmd(Command::Data(0x9B));
    let f = b.run_ticks(20);
    assert_eq!(u16_at(&f[1].payload, 24) & 0x0001, 0, "{f:?}");
}
