//! The cases: each takes the target kind and drives the device only through
//! its UART ([`Dut::c`]), its pins ([`Dut::pins`]) and power cycles
//! ([`Dut::restart`]).

use std::thread::sleep;
use std::time::{Duration, Instant};

use crate::support::{
    ack_of, assert_rate, bytes_per_device_second, command, count_for, device_span, device_times,
    frame, frames_with_counter, hex, read_ram, save, save_flash, sum16, Conn, DeviceClock, Frame,
};
use crate::target::{Dut, Kind, Opts};

const GET_DEV_INFO: u8 = 0x12;
const GET_BIT: u8 = 0x1A;
const GA: u8 = 0x8F;
const GAM: u8 = 0x9B;
const UDD: u8 = 0x95;
const UDD_CONFIG: u8 = 0x96;
const GET_UDD_STRUCT: u8 = 0x97;
const STOP: u8 = 0xFE;
const COMMIT_BAUD_RATE: u8 = 0xC2;
const DEVICE_PARAMETERS: u8 = 0x41;

const DATA_RATE: u16 = 0x0012;
const ALIGN_TIME: u16 = 0x0014;
const ALIGNMENT_ANGLES: u16 = 0x023A;
const OUTPUT_VARIANT: u16 = 0x03D0;
const LPF_BANDWIDTH: u16 = 0x03D7;
const FILTER: u16 = 0x0451;
const SENSORS_RANGE: u16 = 0x028F;
const AUTO_START: u16 = 0x03A9;
const BAUD_RATE: u16 = 0x03B2;
const TOV_CONTROL: u16 = 0x0499;
const TRIGGER_CONTROL: u16 = 0x05FA;

const GA_FRAME_LEN: usize = 40;
const INTERNAL_RATE: u32 = 2000;

// ----- helpers -----

/// Sends GetDevInfo and checks the 174-byte reply; returns its payload.
fn get_dev_info_round_trip(c: &mut Conn) -> Vec<u8> {
    c.send(&command(GET_DEV_INFO));
    let f = c.frame();
    assert_eq!(f.bytes.len(), 174, "{:02X?}", f.bytes);
    assert_eq!(&f.bytes[..6], &[0xAA, 0x55, 0x01, 0x12, 0xAC, 0x00]);
    let sum = sum16(&f.bytes[2..172]);
    assert_eq!(&f.bytes[172..], &sum.to_le_bytes());
    assert_eq!(f.payload().len(), 166);
    assert_ne!(f.payload()[49], 0, "IMU_type");
    assert_eq!(c.bad, 0);
    f.payload().to_vec()
}

/// Starts GA streaming; returns after the acknowledgement.
fn start_ga(c: &mut Conn) {
    let cmd = command(GA);
    c.send(&cmd);
    let ack = c.frame();
    assert_eq!(ack.bytes, ack_of(GA, &cmd));
    assert_eq!(
        ack.bytes,
        [0xAA, 0x55, 0x01, 0x8F, 0x08, 0x00, 0x96, 0x00, 0x2E, 0x01]
    );
}

/// The next frame, which must be a GA frame.
fn ga_frame(c: &mut Conn) -> Frame {
    let f = c.frame();
    assert_eq!(f.id(), GA, "{:02X?}", f.bytes);
    assert_eq!(f.msg_type(), 1);
    assert_eq!(f.bytes.len(), GA_FRAME_LEN);
    assert_eq!(&f.bytes[4..6], &[0x26, 0x00]);
    f
}

/// Saves Baud_Rate `code` and commits it; returns once the line is quiet.
fn switch_baud(c: &mut Conn, code: u8) {
    save(c, BAUD_RATE, &[code]);
    c.send(&command(COMMIT_BAUD_RATE));
    sleep(Duration::from_millis(200));
    c.drain_for(Duration::from_millis(100));
}

/// Asserts that nothing arrives for `d`.
fn silent_for(c: &mut Conn, d: Duration, what: &str) {
    if let Some(f) = c.frame_before(Instant::now() + d) {
        panic!("{what}: unexpected frame {:02X?}", f.bytes);
    }
}

fn u16_at(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([p[i], p[i + 1]])
}

fn u32_at(p: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]])
}

/// Formula 5.1: the output rate of a `payload`-byte frame at `baud` when
/// `requested` Hz is asked for, rounded down to a divisor of 2000 Hz.
fn formula_5_1(requested: u32, baud: u32, payload: u32) -> u32 {
    let max = baud / (11 * (payload + 8));
    (1..=INTERNAL_RATE)
        .rev()
        .find(|r| INTERNAL_RATE.is_multiple_of(*r) && *r <= requested.min(max))
        .unwrap_or(1)
}

// ----- commands -----

pub fn get_dev_info_answers_166_bytes_with_the_seeded_serial(kind: Kind) {
    let mut d = Dut::start(
        kind,
        Opts {
            seed: 7,
            ..Opts::default()
        },
    );
    let p = get_dev_info_round_trip(&mut d.c);
    assert_eq!(&p[0..8], b"10000007", "ID_sn");
    assert_eq!(&p[50..58], b"10000007", "ID_sn copy");
    assert!(
        p[8..48].starts_with(b"KERNEL-110-G2000-A40 imu-emu "),
        "{:?}",
        &p[8..48]
    );
    assert_eq!(p[8..48], p[58..98]);
    assert_eq!(p[49], 110, "IMU_type");
}

pub fn get_bit_answers_four_zero_bytes(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    d.c.send(&command(GET_BIT));
    assert_eq!(d.c.frame().bytes, frame(1, GET_BIT, &[0, 0, 0, 0]));
}

pub fn read_ram_sensors_measurement_range(kind: Kind) {
    let mut d = Dut::start(kind, Opts::model("KERNEL-110-G2000-A8"));
    assert_eq!(
        read_ram(SENSORS_RANGE, 1),
        hex("AA 55 00 00 0C 00 B1 FF 8F 02 01 00 4E 02")
    );
    d.c.send(&hex("AA 55 00 00 0C 00 B1 FF 8F 02 01 00 4E 02"));
    assert_eq!(d.c.frame().bytes, hex("AA 55 01 B1 07 00 93 4C 01"));
}

pub fn device_parameters_request_answers_60_bytes(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    d.c.send(&command(DEVICE_PARAMETERS));
    let f = d.c.frame();
    assert_eq!(f.id(), DEVICE_PARAMETERS);
    let p = f.payload();
    assert_eq!(p.len(), 60);
    assert_eq!(u16_at(p, 0), 100, "data rate");
    assert_eq!(u16_at(p, 2), 2, "alignment time");
    assert_eq!(&p[50..56], b"KERNEL");
}

// ----- output -----

pub fn every_fixed_format_streams_its_frame_at_the_data_rate(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    save(c, ALIGN_TIME, &0u16.to_le_bytes());
    save(c, DATA_RATE, &200u16.to_le_bytes());
    // (code, payload, the device clock it carries) of Tables 5.5–5.12.
    for (code, len, clock) in [
        (0x33u8, 34usize, None),
        (0x8F, 32, Some(DeviceClock::Counter(24))),
        (0x9B, 32, Some(DeviceClock::SecondFraction(26))),
        (0xA5, 44, None),
        (0xA6, 44, Some(DeviceClock::SecondFraction(38))),
        (0x82, 34, None),
        (0x81, 52, Some(DeviceClock::Counter(42))),
    ] {
        let cmd = command(code);
        c.send(&cmd);
        assert_eq!(c.frame().bytes, ack_of(code, &cmd), "ack of {code:#04x}");
        let f = c.frame();
        assert_eq!((f.id(), f.payload().len()), (code, len), "{:02X?}", f.bytes);
        let window = Duration::from_millis(500);
        let rate = formula_5_1(200, 115_200, len as u32);
        if let Some(clock) = clock {
            // Half a second of device time: every step exactly one period.
            let n = rate as usize / 2 + 1;
            let stamps = device_times(c, code, n, clock);
            assert_rate(&format!("{code:#04x}"), &stamps, clock, rate.into());
        } else {
            // Orientation, GAA and Quaternion carry no counter or time:
            // frames counted in a wall-clock window.
            let (frames, _) = count_for(c, code, window);
            let want = f64::from(rate) * window.as_secs_f64();
            eprintln!("{code:#04x}: {frames} frames in {window:?} (expect {want})");
            assert!(
                (frames as f64) >= want * 0.8 && (frames as f64) <= want * 1.2 + 1.0,
                "{code:#04x}: {frames} frames in {window:?}, expected about {want}"
            );
        }
        c.send(&command(STOP));
        c.drain_for(Duration::from_millis(150));
    }
}

pub fn ga_streams_at_the_default_100_hz_and_stop_stops_it(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    start_ga(c);
    ga_frame(c);
    // One second of device time at 100 Hz: 2 kHz counter steps of 20.
    let clock = DeviceClock::Counter(24);
    assert_rate("GA", &device_times(c, GA, 101, clock), clock, 100);
    assert_eq!(c.bad, 0);

    c.send(&command(STOP));
    let stopped_at = Instant::now();
    let mut last = stopped_at;
    let mut late = 0;
    loop {
        assert!(
            last.duration_since(stopped_at) < Duration::from_secs(2),
            "output did not stop within 2 s of Stop"
        );
        match c.frame_before(last + Duration::from_millis(300)) {
            Some(f) => {
                late += usize::from(f.id() == GA);
                last = Instant::now();
            }
            None => break,
        }
    }
    assert!(late <= 10, "{late} GA frames after Stop");
}

pub fn k201_ticks_at_4_khz(kind: Kind) {
    // The K201's internal rate is 4 kHz: 100 Hz output is every 40th
    // tick, and the "2 kHz" counter still advances 20 per frame.
    let mut d = Dut::start(kind, Opts::model("K201"));
    let c = &mut d.c;
    start_ga(c);
    let first = ga_frame(c);
    // One second of device time at 100 Hz.
    let counters = frames_with_counter(c, GA, 101, 24);
    assert!(
        counters.windows(2).all(|w| w[1].wrapping_sub(w[0]) == 20),
        "counters at 100 Hz: {counters:?}"
    );
    let next = ga_frame(c);
    let mut prev = ga_frame(c);
    for _ in 0..5 {
        let f = ga_frame(c);
        let step = u16_at(f.payload(), 24).wrapping_sub(u16_at(prev.payload(), 24));
        assert_eq!(step, 20, "counter step between 100 Hz frames");
        prev = f;
    }
    assert_ne!(first.payload()[24..26], next.payload()[24..26]);
}

pub fn stop_is_idempotent_and_unknown_commands_are_ignored(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    for _ in 0..5 {
        c.send(&command(STOP));
    }
    c.send(&command(0x55)); // no such command
    c.send(&frame(1, 0x12, &[0x12])); // a device message: not a command
    c.send(&frame(0, 7, &[0x12])); // id ≠ 0
    silent_for(c, Duration::from_millis(300), "after Stop ×5 and unknowns");
    get_dev_info_round_trip(c);
}

pub fn udd_config_is_answered_read_back_streamed_and_persisted(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let types = [0x02u8, 0x21, 0x23, 0x52]; // IMU time 8, gyro HR 12, acc HR 12, temperature 2
    let payload_len = 1 + types.len() + 8 + 12 + 12 + 2;
    let mut list = vec![types.len() as u8];
    list.extend_from_slice(&types);

    let c = &mut d.c;
    c.send(&command(UDD_CONFIG));
    let msg = frame(0, 0, &list);
    c.send(&msg);
    let r = c.frame();
    assert_eq!(r.id(), UDD_CONFIG, "{:02X?}", r.bytes);
    let p = r.payload().to_vec();
    assert_eq!(p.len(), 8, "Table 5.20 reply");
    assert_eq!(&p[0..2], &msg[msg.len() - 2..], "checksum of the message");
    assert_eq!(p[2], 0, "error bits");
    assert_eq!(u16_at(&p, 3), 0, "wrong types");
    assert_eq!(
        u32::from(u16_at(&p, 5)),
        formula_5_1(2000, 115_200, payload_len as u32)
    );

    // A refused configuration (an unknown type) leaves this one in force.
    c.send(&command(UDD_CONFIG));
    c.send(&frame(0, 0, &[1, 0xEE]));
    let r = c.frame();
    assert_eq!(r.id(), UDD_CONFIG);
    assert_eq!(&r.payload()[0..2], &[0, 0], "refused: checksum 0");
    assert_ne!(r.payload()[2] & 0x04, 0, "unknown type bit");
    assert_eq!(u16_at(r.payload(), 3), 1, "first type wrong");

    c.send(&command(GET_UDD_STRUCT));
    assert_eq!(c.frame().bytes, frame(1, GET_UDD_STRUCT, &list));

    let cmd = command(UDD);
    c.send(&cmd);
    assert_eq!(c.frame().bytes, ack_of(UDD, &cmd));
    let f = c.frame();
    assert_eq!(f.id(), UDD);
    assert_eq!(f.payload().len(), payload_len);
    assert_eq!(&f.payload()[..list.len()], &list[..]);
    // Half a second of device time at the default 100 Hz, by the IMU time
    // (type 0x02, right after the type list): steps of exactly 10 ms.
    let clock = DeviceClock::ImuTime(list.len());
    assert_rate("UDD", &device_times(c, UDD, 51, clock), clock, 100);
    c.send(&command(STOP));

    // Accepted configurations are persisted.
    d.restart();
    d.c.send(&command(GET_UDD_STRUCT));
    assert_eq!(d.c.frame().bytes, frame(1, GET_UDD_STRUCT, &list));
}

// ----- parameters and power cycles -----

pub fn saved_parameters_survive_a_power_cycle(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let cmd = save_flash(DATA_RATE, &50u16.to_le_bytes());
    assert_eq!(
        &cmd[..14],
        &hex("AA 55 00 00 0E 00 B2 FF 12 00 02 00 32 00")[..]
    );
    save(&mut d.c, DATA_RATE, &50u16.to_le_bytes());
    d.restart();
    d.c.send(&read_ram(DATA_RATE, 2));
    let f = d.c.frame();
    assert_eq!(f.bytes, frame(1, 0xB1, &[0x32, 0x00]));
    assert_eq!(&f.bytes[..8], &hex("AA 55 01 B1 08 00 32 00")[..]);

    // An in-place power cycle (the pins' power switch) loads it too.
    d.pins().power_cycle(None);
    d.c.send(&read_ram(DATA_RATE, 2));
    assert_eq!(d.c.frame().bytes, frame(1, 0xB1, &[0x32, 0x00]));
}

pub fn auto_start_announces_and_streams_after_a_power_cycle(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    save(&mut d.c, AUTO_START, &[GA]);
    d.restart();
    let c = &mut d.c;
    assert_eq!(c.read_bytes(10), hex("AA 55 01 00 08 00 00 00 09 00"));
    for _ in 0..10 {
        ga_frame(c);
    }
    assert_eq!((c.bad, c.skipped), (0, 0));
}

pub fn invalid_save_flash_gets_no_answer_and_changes_nothing(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    c.send(&save_flash(DATA_RATE, &3u16.to_le_bytes())); // not a divisor of 2000
    c.send(&save_flash(DATA_RATE, &[50])); // wrong length
    c.send(&save_flash(SENSORS_RANGE, &[0x93])); // read-only
    c.send(&save_flash(0x0001, &[0])); // no such parameter
    silent_for(c, Duration::from_millis(400), "invalid SaveFlash");
    c.send(&read_ram(DATA_RATE, 2));
    assert_eq!(c.frame().bytes, frame(1, 0xB1, &100u16.to_le_bytes()));
}

pub fn bad_input_is_skipped_and_the_decoder_resyncs(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    let bit = command(GET_BIT);
    let mut bad_sum = bit.clone();
    *bad_sum.last_mut().unwrap() ^= 0x40;
    let mut input = vec![0x00, 0xFF, 0x55, 0xAA, 0x12, 0xAA, 0x55, 0x00];
    input.extend_from_slice(&bad_sum); // bad checksum: dropped
    input.extend_from_slice(&[0xAA, 0x55, 0x00, 0x00, 0x03, 0x00]); // length < 6
    input.push(0xAA); // a lone header byte right before a good frame
    input.extend_from_slice(&bit);
    input.extend_from_slice(&bit[..4]); // a good frame inside a bad one
    input.extend_from_slice(&bit);
    c.send(&input);
    for _ in 0..2 {
        assert_eq!(c.frame().bytes, frame(1, GET_BIT, &[0; 4]));
    }
    silent_for(c, Duration::from_millis(300), "after the garbage");

    // A frame cut short is abandoned after 100 ms without a byte.
    c.send(&bit[..5]);
    sleep(Duration::from_millis(300));
    c.send(&bit);
    assert_eq!(c.frame().bytes, frame(1, GET_BIT, &[0; 4]));
    silent_for(c, Duration::from_millis(200), "after the cut frame");
    assert_eq!(c.bad, 0);
}

// ----- baud rates -----

pub fn commit_baud_rate_4800_caps_the_rate_and_the_throughput(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    save(c, BAUD_RATE, &[0x01]); // 4800 bit/s
    c.send(&command(COMMIT_BAUD_RATE));
    sleep(Duration::from_millis(300));
    c.drain_for(Duration::from_millis(200));

    // The line is paced at 4800 bit/s: the 174-byte GetDevInfo reply takes
    // 362 ms on the wire (less a burst of at most 64 bytes: ≥ 229 ms). A
    // reply carries no device time: measured on the wall clock.
    let t0 = Instant::now();
    get_dev_info_round_trip(c);
    let took = t0.elapsed();
    eprintln!("GetDevInfo at 4800 bit/s took {took:?}");
    assert!(took >= Duration::from_millis(220), "{took:?}");
    assert!(took <= Duration::from_millis(1000), "{took:?}");

    start_ga(c);
    ga_frame(c);
    // Formula 5.1: 4800 / (11 × 40) = 10.9 → 10 Hz; the line carries at
    // most 480 bytes/s. Over 1.5 s of device time (the 2 kHz counter).
    let clock = DeviceClock::Counter(24);
    let stamps = device_times(c, GA, 16, clock);
    assert_rate("GA at 4800 bit/s", &stamps, clock, 10);
    let per_s = bytes_per_device_second(&stamps, clock);
    eprintln!("4800 bit/s: GA at 10 Hz, {per_s:.0} B per device second");
    assert!(per_s <= 500.0, "{per_s:.0} B per device second");
}

pub fn two_megabaud_carries_ga_at_2000_hz(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    switch_baud(c, 0x0B); // 2 000 000 bit/s
    save(c, DATA_RATE, &2000u16.to_le_bytes());
    start_ga(c);
    ga_frame(c);
    // One second of device time (the 2 kHz counter): a step of 1 each.
    let clock = DeviceClock::Counter(24);
    let stamps = device_times(c, GA, 2001, clock);
    assert_eq!(device_span(&stamps, clock), 2000);
    assert_rate("GA at 2 Mbit/s", &stamps, clock, 2000);
    let bytes: usize = stamps[1..].iter().map(|s| s.len).sum();
    eprintln!("2 Mbit/s: 2000 GA frames, {bytes} bytes in 1 s of device time");
    assert!(bytes <= 210_000, "{bytes} bytes in 1 s at 2 Mbit/s");
    assert_eq!(c.bad, 0);
}

// ----- pins -----

pub fn pps_sets_the_gam_time_flag_and_restarts_the_second(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    d.c.send(&command(GAM));
    d.c.frame_with_id(GAM);
    // Well over 1 s without 1PPS: flag 0x0008.
    sleep(Duration::from_millis(1200));
    d.c.drain_for(Duration::from_millis(50));
    let f = d.c.frame_with_id(GAM);
    assert_eq!(u16_at(f.payload(), 24) & 0x0008, 0x0008);
    d.pins().pps();
    // The frame after the edge: 0x0001, second fraction since the edge
    // below one frame period plus scheduling slack.
    let mut seen = false;
    for _ in 0..20 {
        let f = d.c.frame_with_id(GAM);
        let flags = u16_at(f.payload(), 24);
        if flags & 0x0001 != 0 {
            assert_eq!(flags & 0x0008, 0);
            let frac = u32_at(f.payload(), 26);
            assert!(frac < 30_000_000, "second fraction {frac} ns after 1PPS");
            seen = true;
            break;
        }
    }
    assert!(seen, "a frame with the 1PPS flag");
}

pub fn extrig_sends_one_frame_per_edge(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    save(&mut d.c, TRIGGER_CONTROL, &[1]); // Polarity 0: falling edges
    d.c.send(&command(GA));
    d.c.frame_with_id(GA);
    assert_eq!(
        d.c.drain_for(Duration::from_millis(300)),
        0,
        "no periodic output"
    );
    for _ in 0..3 {
        d.pins().extrig(true);
        d.pins().extrig(false);
        sleep(Duration::from_millis(20));
    }
    for _ in 0..3 {
        ga_frame(&mut d.c);
    }
    silent_for(
        &mut d.c,
        Duration::from_millis(300),
        "after 3 EXTRIG pulses",
    );
}

pub fn tov_pulses_high_then_low_for_every_frame(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    save(&mut d.c, TOV_CONTROL, &[1]);
    d.c.send(&command(GA));
    d.c.frame_with_id(GA);
    // (A board may report its power-on level first.)
    let mut edges = d.pins().tov_edges(21);
    let first = edges.iter().position(|&e| e).expect("a rising edge");
    edges.drain(..first);
    edges.truncate(20);
    assert_eq!(edges.len(), 20, "{edges:?}");
    for pair in edges.chunks(2) {
        assert_eq!(pair, [true, false], "{edges:?}");
    }
}

pub fn boot_asserted_at_power_on_silences_the_device(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    d.c.send(&command(GET_BIT));
    assert_eq!(d.c.frame().id(), GET_BIT);
    // K110: BOOT is asserted high (ICD Table 4.1 note 5).
    d.pins().power_cycle(Some(true));
    d.c.send(&command(GET_BIT));
    silent_for(
        &mut d.c,
        Duration::from_millis(400),
        "in firmware-update mode",
    );
    d.pins().power_cycle(None);
    d.c.send(&command(GET_BIT));
    assert_eq!(d.c.frame().id(), GET_BIT);
}

// ----- latency -----

/// A reply leaves when the device writes it, as on a wire (QEMU's
/// UART socket without `nodelay=on` held small writes back ~40 ms, so a rig
/// measured latencies no real KERNEL has, and the last frame came 40–50 ms
/// after Stop).
///
/// * Idle: a ReadRAM answer (10 bytes, 0.9 ms at 115 200 bit/s; the request
///   1.2 ms) comes back within a few ms.
/// * Streaming GA at 100 Hz, from the device's own clock: each frame's 2 kHz
///   counter says at which tick the device sent it; its arrival time less
///   that tick's time is the frame's latency up to a constant (the earliest
///   frame's). Frames held back in bursts show up as a latency spread of up
///   to the hold time; prompt frames all arrive within about a ms of it.
///
/// Medians over many samples, so one late wakeup of a loaded host does not
/// decide.
pub fn replies_and_frames_leave_without_delay(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    let c = &mut d.c;
    let ask = read_ram(DATA_RATE, 2);
    let answer = frame(1, 0xB1, &100u16.to_le_bytes());
    let mut rtt = Vec::new();
    for _ in 0..21 {
        let t0 = Instant::now();
        c.send(&ask);
        assert_eq!(c.frame().bytes, answer);
        rtt.push(t0.elapsed());
        sleep(Duration::from_millis(5));
    }
    rtt.sort();
    let reply = rtt[rtt.len() / 2];
    eprintln!(
        "ReadRAM round trip: median {reply:?}, max {:?}",
        rtt[rtt.len() - 1]
    );
    assert!(
        reply < Duration::from_millis(15),
        "median round trip {reply:?}"
    );

    start_ga(c);
    let first = ga_frame(c);
    let t0 = Instant::now();
    let c0 = u16_at(first.payload(), 24);
    // (arrival − device send time) per frame, µs, up to a constant.
    let mut lat: Vec<i64> = Vec::new();
    let mut ticks: u64 = 0;
    let mut prev = c0;
    while lat.len() < 200 {
        let f = ga_frame(c);
        let arrived = t0.elapsed().as_micros() as i64;
        let k = u16_at(f.payload(), 24);
        ticks += u64::from(k.wrapping_sub(prev));
        prev = k;
        lat.push(arrived - (ticks * 500) as i64);
    }
    c.send(&command(STOP));
    let best = *lat.iter().min().unwrap();
    let mut above: Vec<i64> = lat.iter().map(|l| l - best).collect();
    above.sort();
    let spread = above[above.len() / 2];
    eprintln!(
        "GA frame latency above the earliest: median {spread} µs, 90 % {} µs, max {} µs",
        above[above.len() * 9 / 10],
        above[above.len() - 1]
    );
    assert!(spread < 5_000, "median frame latency spread {spread} µs");
}

// ----- QEMU only: the firmware's tick cost -----

/// Starts the firmware with `-icount shift=0` (one instruction = 1 ns of
/// the virtual clock the CMSDK timers count), so the shell's timing
/// figures read as instruction counts (±40: one 25 MHz timer count).
fn icount_dut(model: &str) -> Dut {
    Dut::start(
        Kind::Qemu,
        Opts {
            model: model.into(),
            qemu_args: vec!["-icount".into(), "shift=0".into()],
            ..Opts::default()
        },
    )
}

/// Streams for a second after zeroing the figures, then reports them.
fn measure(d: &mut Dut, id: u8, what: &str) -> Vec<(String, u64)> {
    sleep(Duration::from_millis(300));
    d.qemu_reset_stats();
    let (frames, bytes) = count_for(&mut d.c, id, Duration::from_secs(1));
    let stats = d.qemu_stats().expect("qemu");
    let get = |k: &str| stats.iter().find(|(n, _)| n == k).map(|(_, v)| *v).unwrap();
    eprintln!(
        "tick cost, {what}: {frames} frames ({bytes} B) in 1 s wall; instructions: \
         tick interrupt max {} (one tick {}, on_tick {}; catch-up batch {}, \
         with received bytes {}), {} ticks, batch max {}, stack {} B (power-on {} B)",
        get("service_max_ns"),
        get("tick_max_ns"),
        get("on_tick_max_ns"),
        get("service_batch_max_ns"),
        get("service_rx_max_ns"),
        get("ticks"),
        get("batch_max"),
        get("stack"),
        get("stack_init"),
    );
    assert!(frames > 0);
    assert!(get("ticks") > 0);
    // Stack budgets a board's RAM relies on (the STM32F411 has 128 KiB, of
    // which ~19 KiB are statics): power-on builds the device in place
    // (`fw_shell::power_on`), and the running firmware's interrupts nest
    // on one stack.
    assert!(get("stack_init") <= 20 * 1024, "power-on stack");
    assert!(get("stack") <= 8 * 1024, "running stack");
    stats
}

/// The tick's cost bounds, in instructions: the whole tick interrupt
/// (`service_max_ns`: one tick with its TX pump, RX drain and events) and
/// `Device::on_tick` alone. Each is ≈ 20 % above the figure measured when
/// it was set (the worst over 1 s, five runs; figures in docs/firmware.md), so a
/// change that makes the tick markedly dearer fails here and has to say so.
fn assert_cost(stats: &[(String, u64)], interrupt: u64, on_tick: u64) {
    let get = |k: &str| stats.iter().find(|(n, _)| n == k).map(|(_, v)| *v).unwrap();
    let (s, t) = (get("service_max_ns"), get("on_tick_max_ns"));
    assert!(
        s < interrupt,
        "{s} instructions per tick interrupt (bound {interrupt})"
    );
    assert!(
        t < on_tick,
        "{t} instructions per on_tick (bound {on_tick})"
    );
}

pub fn tick_cost_ga_2khz_at_2_mbaud(kind: Kind) {
    assert_eq!(kind, Kind::Qemu);
    let mut d = icount_dut("K110");
    switch_baud(&mut d.c, 0x0B);
    save(&mut d.c, DATA_RATE, &2000u16.to_le_bytes());
    start_ga(&mut d.c);
    let stats = measure(&mut d, GA, "GA at 2000 Hz, 2 Mbit/s");
    // Measured 5 640–5 680 (on_tick 3 680–3 720), five runs; after the
    // shell/personality merge 5 760 (on_tick 3 800), three runs.
    assert_cost(&stats, 6_800, 4_500);
}

pub fn tick_cost_largest_udd(kind: Kind) {
    assert_eq!(kind, Kind::Qemu);
    let mut d = icount_dut("K110");
    // The 16 largest types a K110 has (payload 1 + 16 + 128 = 145 bytes):
    // Formula 5.1 at 2 Mbit/s → 1000 Hz.
    let types = [
        0x02u8, 0x05, 0x07, 0x08, 0x09, 0x20, 0x21, 0x22, 0x23, 0x2D, 0x2E, 0x91, 0x92, 0x52, 0x53,
        0x5B,
    ];
    stream_udd_at_2_mbaud(&mut d, &types, 145);
    let stats = measure(&mut d, UDD, "largest UDD (145 B) at 1000 Hz, 2 Mbit/s");
    // Measured 9 680–9 800 (on_tick 5 560–5 760), five runs; after the
    // shell/personality merge 9 760–10 040 (on_tick 5 640–5 840), three runs.
    assert_cost(&stats, 11_800, 6_900);
}

/// The worst case of the tick budget: every filter on (LPF 16 Hz = the order-192 FIR,
/// all three cascade filters), the aux accelerometer (K120), incremental
/// output, non-zero mounting angles, and the largest UDD a K120 has.
pub fn tick_cost_worst_case(kind: Kind) {
    assert_eq!(kind, Kind::Qemu);
    let mut d = icount_dut("K120");
    save(&mut d.c, LPF_BANDWIDTH, &[0x00]);
    save(&mut d.c, FILTER, &[0x07]);
    save(&mut d.c, OUTPUT_VARIANT, &[0x02]);
    let mut angles = Vec::new();
    for a in [10.0f32, 5.0, -3.0] {
        angles.extend_from_slice(&a.to_le_bytes());
    }
    save(&mut d.c, ALIGNMENT_ANGLES, &angles);
    // The K110 set with the aux accelerometer (0x2F, 12 B) for USW-ext
    // (2 B): payload 155 B, still 1000 Hz by Formula 5.1 at 2 Mbit/s.
    let types = [
        0x02u8, 0x05, 0x07, 0x08, 0x09, 0x20, 0x21, 0x22, 0x23, 0x2D, 0x2E, 0x2F, 0x91, 0x92, 0x52,
        0x53,
    ];
    stream_udd_at_2_mbaud(&mut d, &types, 155);
    let stats = measure(
        &mut d,
        UDD,
        "worst case (K120, LPF 16 Hz, all cascade filters, incremental, mounting, UDD 155 B at 1000 Hz)",
    );
    // Measured 12 520–12 720 (on_tick 8 280–8 520), five runs; after the
    // shell/personality merge 12 440–12 720 (on_tick 8 200–8 440), three runs.
    assert_cost(&stats, 15_300, 10_200);
}

/// 2 Mbit/s, no alignment, 2000 Hz asked; UDD `types` configured and
/// streaming with a `payload`-byte frame.
fn stream_udd_at_2_mbaud(d: &mut Dut, types: &[u8], payload: usize) {
    switch_baud(&mut d.c, 0x0B);
    save(&mut d.c, ALIGN_TIME, &0u16.to_le_bytes());
    save(&mut d.c, DATA_RATE, &2000u16.to_le_bytes());
    let mut list = vec![types.len() as u8];
    list.extend_from_slice(types);
    d.c.send(&command(UDD_CONFIG));
    d.c.send(&frame(0, 0, &list));
    let r = d.c.frame_with_id(UDD_CONFIG);
    assert_eq!(r.payload()[2] & !0x08, 0, "accepted: {:02X?}", r.payload());
    let cmd = command(UDD);
    d.c.send(&cmd);
    assert_eq!(d.c.frame().bytes, ack_of(UDD, &cmd));
    let f = d.c.frame_with_id(UDD);
    assert_eq!(f.payload().len(), payload);
}

/// The live motion feed (docs/feed.md; host: `--motion-feed`, firmware:
/// the bridge UART): binary samples of a rotation about Z show in the GA
/// frames; 100 ms of silence sets USW bit 1 (sensor communication
/// failure, ICD Table 5.26) with the rotation held; a sample clears it.
pub fn a_fed_rotation_shows_in_the_ga_frames_and_silence_is_a_fault(kind: Kind) {
    let mut d = Dut::start(kind, Opts::default());
    start_ga(&mut d.c);
    for k in 0..5 {
        d.feed(&crate::support::feed_sample(
            0xFFFF,
            f64::from(k) * 0.01,
            [0.0, 0.0, 90.0],
        ));
    }
    let z = |p: &[u8]| f64::from(u32_at(p, 8) as i32) * 1e-5;
    let usw = |p: &[u8]| u16_at(p, 26);
    let end = Instant::now() + crate::support::TIMEOUT;
    let wait = |d: &mut Dut, what: &str, ok: &dyn Fn(&[u8]) -> bool| loop {
        assert!(Instant::now() < end, "no GA frame with {what}");
        let f = ga_frame(&mut d.c);
        if ok(f.payload()) {
            return f;
        }
    };
    wait(&mut d, "Z = 90 °/s", &|p| (z(p) - 90.0).abs() < 0.5);
    let f = wait(&mut d, "USW bit 1", &|p| usw(p) & 2 != 0);
    assert!((z(f.payload()) - 90.0).abs() < 0.5, "the rotation holds");
    d.feed(&crate::support::feed_sample(0xFFFF, 1.0, [0.0, 0.0, 0.0]));
    wait(&mut d, "USW bit 1 clear and Z = 0", &|p| {
        usw(p) & 2 == 0 && z(p).abs() < 0.5
    });
}
