//! The malformed-input catalogue: one test per class of bad
//! host → device input, each asserting
//!
//! 1. the documented reaction — the exact reply bytes, or exact silence
//!    (docs/kernel.md "Protocol notes", "Malformed input");
//! 2. that the device resyncs on the next good frame: a GetBIT (ICD 5.3.4)
//!    sent right behind the bad bytes — in the same chunk, in a chunk of its
//!    own, and byte by byte — is answered exactly once;
//! 3. that nothing else changed: every Table 5.24 parameter in RAM
//!    ([`Device::param_ram`]), the flash image (so the saved copy and the UDD
//!    configuration), the UDD configuration in force (Get_User_Def_Data_struct),
//!    mode, output rate, line rate and the TX drop counter.
//!
//! The device under test carries non-default settings first (Data_Rate,
//! LPF, alignment angles, Output_Variant, a UDD configuration), so "intact"
//! is not just "still factory".

mod common;
use common::xorshift::XorShift;
use common::*;

use imu_emu::device::{Device, Event, Mode};
use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::encode;
use imu_emu::kernel::params::PARAMS;
use imu_emu::kernel::rate::max_rate;
use imu_emu::kernel::{RX_FRAME_CAP, RX_IDLE_ABANDON_NS};
use imu_emu::time::Instant;
use imu_emu::Kernel;

/// GetBIT, the good frame every case ends with (ICD 5.3.4 example).
const GET_BIT: [u8; 9] = [0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00];
/// Its reply: type 1, id 0x1A, four zero result bytes, sum 0x0025.
const BIT_REPLY: [u8; 12] = [
    0xAA, 0x55, 0x01, 0x1A, 0x0A, 0x00, 0x00, 0x00, 0x00, 0x00, 0x25, 0x00,
];
/// The UDD configuration set up before every case.
const UDD_SETUP: [u8; 4] = [0x02, 0x21, 0x23, 0x53];

/// A command frame (`type 0, id 0`) with `payload`.
fn frame(payload: &[u8]) -> Vec<u8> {
    raw_frame(0, 0, payload)
}

fn raw_frame(msg_type: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; payload.len() + 8];
    let n = encode(msg_type, id, payload, &mut out).unwrap();
    out.truncate(n);
    out
}

/// The device frame (`type 1`) the device sends for `id` and `payload`.
fn reply(id: u8, payload: &[u8]) -> Vec<u8> {
    raw_frame(1, id, payload)
}

/// A device with non-default settings saved and in force, idle, nothing
/// queued.
fn bench(model: &str) -> Bench {
    let mut b = Bench::new(model);
    let rate = 50u16; // a divisor of 2000 and 4000, not the default 100
    let saves: [(u16, Vec<u8>); 5] = [
        (0x0012, rate.to_le_bytes().to_vec()),
        (0x03D7, vec![0x02]),
        (0x03D0, vec![0x01]),
        (0x0014, vec![0x00, 0x00]),
        (
            0x023A,
            [10.0f32, -5.0, 2.5]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
        ),
    ];
    for (id, value) in &saves {
        assert_eq!(b.save(*id, value).len(), 1, "setup save {id:#06x}");
    }
    let mut msg = vec![UDD_SETUP.len() as u8];
    msg.extend_from_slice(&UDD_SETUP);
    b.cmd(Command::UddConfigMessage(&msg));
    assert_eq!(b.drain()[0].payload[2], 0, "setup UDD config accepted");
    while b.dev.poll_event().is_some() {}
    b.raw.clear();
    b
}

/// Everything a malformed input must leave as it was.
#[derive(Debug, Clone, PartialEq, Eq)]
struct State {
    /// Every Table 5.24 parameter's RAM value.
    params: Vec<(u16, Vec<u8>)>,
    flash: Vec<u8>,
    mode: Mode,
    output_rate: Option<u32>,
    line_rate: u32,
    tx_dropped: u32,
}

fn state(dev: &Device<Flash, Kernel>) -> State {
    State {
        params: PARAMS
            .iter()
            .map(|p| (p.id, dev.param_ram(p.id).unwrap().to_vec()))
            .collect(),
        flash: dev.flash().image().to_vec(),
        mode: dev.mode(),
        output_rate: dev.output_rate(),
        line_rate: dev.line_rate(),
        tx_dropped: dev.tx_dropped(),
    }
}

/// The UDD configuration in force (Get_User_Def_Data_struct, 5.3.5); the
/// device must be idle.
fn udd_struct(b: &mut Bench) -> Vec<u8> {
    b.cmd(Command::GetUddStruct);
    let f = b.drain();
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].id, 0x97);
    b.raw.clear();
    f[0].payload.clone()
}

/// Sends `bad` and then GetBIT three ways (one chunk; two chunks; byte by
/// byte): each time the device sends exactly `expect` followed by the BIT
/// reply, and afterwards nothing but the TX bytes has changed.
fn case(model: &str, bad: &[u8], expect: &[u8]) {
    let mut want = expect.to_vec();
    want.extend_from_slice(&BIT_REPLY);
    for way in 0..3 {
        let mut b = bench(model);
        let before = state(&b.dev);
        let udd_before = udd_struct(&mut b);
        match way {
            0 => {
                let mut all = bad.to_vec();
                all.extend_from_slice(&GET_BIT);
                b.send(&all);
            }
            1 => {
                b.send(bad);
                b.send(&GET_BIT);
            }
            _ => {
                for &x in bad.iter().chain(&GET_BIT) {
                    b.send(&[x]);
                }
            }
        }
        b.drain();
        assert_eq!(b.raw, want, "{model}, way {way}: reply bytes");
        b.raw.clear();
        assert_eq!(state(&b.dev), before, "{model}, way {way}: state changed");
        assert_eq!(udd_struct(&mut b), udd_before, "{model}, way {way}: UDD");
        // And after a power cycle the saved parameters are what they were.
        b.dev.power_cycle(Instant(b.now));
        while b.dev.poll_event().is_some() {}
        assert_eq!(state(&b.dev), before, "{model}, way {way}: after power-on");
    }
}

/// [`case`] for silence.
fn silent(model: &str, bad: &[u8]) {
    case(model, bad, &[]);
}

/// The UDD config reply (Table 5.20 as corrected in protocol-facts.md).
fn udd_reply(checksum: u16, errors: u8, wrong: u16, max: u32) -> Vec<u8> {
    let c = checksum.to_le_bytes();
    let w = wrong.to_le_bytes();
    let m = (max as u16).to_le_bytes();
    reply(0x96, &[c[0], c[1], errors, w[0], w[1], m[0], m[1], 0])
}

/// Formula 5.1 maximum rate of the setup UDD configuration at 115200 bps.
fn setup_max(internal: u32) -> u32 {
    // N + 4 codes + IMU time 8 + gyro HR 12 + accel HR 12 + USW 2
    max_rate(115_200, 1 + 4 + 8 + 12 + 12 + 2, internal)
}

// ---------------------------------------------------------------- framing

#[test]
fn wrong_header_is_skipped_silently() {
    for bad in [
        // second byte not 0x55
        vec![0xAA, 0x56, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00],
        // first byte not 0xAA
        vec![0xAB, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00],
        // header bytes swapped
        vec![0x55, 0xAA, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x21, 0x00],
        // a lone 0xAA, then 0xAA 0x55 needs the second 0xAA to start a frame
        vec![0xAA, 0xAA],
    ] {
        silent("K110", &bad);
    }
}

#[test]
fn wrong_type_byte_or_id_is_ignored() {
    // Only `type 0, id 0` frames are commands (Table 5.2, protocol-facts.md): a
    // well-formed GetBIT as a device frame (type 1), an unknown type, or
    // with a non-zero id gets no answer.
    for (t, id) in [
        (0x01, 0x00),
        (0x02, 0x00),
        (0xFF, 0x00),
        (0x00, 0x1A),
        (0x00, 0x01),
    ] {
        silent("K110", &raw_frame(t, id, &[0x1A]));
    }
}

#[test]
fn bad_checksum_is_dropped_silently() {
    let mut bad = GET_BIT;
    for (i, delta) in [(7, 1u8), (8, 1), (7, 0xFF)] {
        bad[i] = GET_BIT[i].wrapping_add(delta);
        silent("K110", &bad);
        bad = GET_BIT;
    }
    // A payload byte changed (sum no longer matches).
    silent(
        "K110",
        &[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x12, 0x21, 0x00],
    );
}

#[test]
fn length_below_6_is_dropped_silently() {
    for len in 0u8..6 {
        silent(
            "K110",
            &[0xAA, 0x55, 0x00, 0x00, len, 0x00, 0x1A, 0x21, 0x00],
        );
    }
}

#[test]
fn length_above_the_maximum_is_dropped_silently() {
    // The largest frame the decoder takes: a UDD config message with 255
    // types (length field 263, RX_FRAME_CAP = 265 bytes) — it is parsed and
    // refused (N > 16: Table 5.21 bit 1), so the boundary is exact.
    assert_eq!(RX_FRAME_CAP, 265);
    let mut payload = vec![0x96, 255];
    payload.extend(std::iter::repeat_n(0x02, 255));
    let largest = frame(&payload);
    assert_eq!(largest.len(), RX_FRAME_CAP);
    case("K110", &largest, &udd_reply(0, 0x02, 0, setup_max(2000)));
    // One byte more (length field 264), well-formed otherwise: dropped.
    payload.push(0x02);
    let too_long = frame(&payload);
    assert_eq!(u16::from_le_bytes([too_long[4], too_long[5]]), 264);
    silent("K110", &too_long);
    // Length fields far above: 0x0800, 0xFFFF.
    silent("K110", &[0xAA, 0x55, 0x00, 0x00, 0x00, 0x08, 0x1A]);
    silent("K110", &[0xAA, 0x55, 0x00, 0x00, 0xFF, 0xFF, 0x1A]);
}

#[test]
fn truncated_frame_is_abandoned_after_the_idle_timeout() {
    assert_eq!(RX_IDLE_ABANDON_NS, 100_000_000);
    let mut b = bench("K110");
    let before = state(&b.dev);
    // A frame announcing length 263 (265 bytes), cut after 6 bytes; then a
    // good GetBIT right behind it is taken as part of the long frame…
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x07, 0x01]);
    b.send(&GET_BIT);
    assert!(b.drain().is_empty());
    // …until the line has been idle for more than RX_IDLE_ABANDON_NS: the
    // candidate is abandoned, the scan restarts after its first byte and
    // finds the GetBIT inside it. At 2 kHz that is tick 201 (100.5 ms).
    let f = b.run_ticks(200);
    assert!(f.is_empty(), "nothing before 100 ms");
    assert!(b.raw.is_empty());
    let f = b.run_ticks(1);
    assert_eq!(f.len(), 1);
    assert_eq!(b.raw, BIT_REPLY);
    b.raw.clear();
    assert_eq!(state(&b.dev), before);
    // A frame cut short with nothing after it: after the timeout the next
    // good frame is answered at once.
    b.send(&[0xAA, 0x55, 0x00, 0x00, 0x0E, 0x00, 0xB2, 0xFF, 0x12]);
    b.run_ticks(201);
    b.send(&GET_BIT);
    b.drain();
    assert_eq!(b.raw, BIT_REPLY);
    b.raw.clear();
    assert_eq!(state(&b.dev), before);
    // A truncated SaveFlash whose missing bytes never come changes nothing,
    // also after a power cycle.
    b.dev.power_cycle(Instant(b.now));
    while b.dev.poll_event().is_some() {}
    assert_eq!(state(&b.dev), before);
}

// ---------------------------------------------------------------- commands

#[test]
fn unknown_command_gets_no_answer() {
    for payload in [
        &[0x55][..],
        &[0x00],
        &[0x13],
        &[0xFF],
        &[0x12, 0x00],       // a known code with a trailing byte
        &[0xB1, 0x6C],       // the vendor SDK's 2-byte request (protocol-facts.md)
        &[0xB3, 0xFF, 0x12], // neither SaveFlash nor ReadRAM
    ] {
        silent("K110", &frame(payload));
    }
    // An empty payload (length field 6).
    silent("K110", &[0xAA, 0x55, 0x00, 0x00, 0x06, 0x00, 0x06, 0x00]);
    // A model without a format: Orientation on the K201 (like unknown).
    silent("K201", &frame(&[0x33]));
}

fn save_frame(id: u16, value: &[u8]) -> Vec<u8> {
    let mut p = [0u8; 300];
    let n = Command::SaveFlash {
        id,
        len: value.len() as u16,
        value,
    }
    .encode(&mut p)
    .unwrap();
    p[..n].to_vec()
}

fn read_frame(id: u16, len: u16) -> Vec<u8> {
    let mut p = [0u8; 32];
    let n = Command::ReadRam { id, len }.encode(&mut p).unwrap();
    p[..n].to_vec()
}

#[test]
fn save_flash_and_read_ram_with_an_unknown_id_get_no_answer() {
    for id in [0x0000, 0x0013, 0x0100, 0x05FF, 0x0600, 0xFFFF] {
        silent("K110", &save_frame(id, &[1]));
        silent("K110", &save_frame(id, &[1, 0]));
        silent("K110", &read_frame(id, 1));
        silent("K110", &read_frame(id, 2));
    }
}

#[test]
fn wrong_length_gets_no_answer() {
    // Length field not the parameter's length (consistent with the value).
    silent("K110", &save_frame(0x0012, &[0xE8]));
    silent("K110", &save_frame(0x0012, &[0xE8, 0x03, 0x00]));
    silent("K110", &save_frame(0x023A, &[0; 8]));
    // Length field disagreeing with the value bytes (2 announced, 1 sent;
    // 1 announced, 2 sent), and a SaveFlash too short for its header.
    silent("K110", &frame(&[0xB2, 0xFF, 0x12, 0x00, 0x02, 0x00, 0x64]));
    silent(
        "K110",
        &frame(&[0xB2, 0xFF, 0x12, 0x00, 0x01, 0x00, 0x64, 0x00]),
    );
    silent("K110", &frame(&[0xB2, 0xFF, 0x12, 0x00, 0x02]));
    // ReadRAM: wrong length field, extra byte, missing byte.
    silent("K110", &read_frame(0x0012, 1));
    silent("K110", &read_frame(0x0012, 4));
    silent("K110", &frame(&[0xB1, 0xFF, 0x12, 0x00, 0x02, 0x00, 0x00]));
    silent("K110", &frame(&[0xB1, 0xFF, 0x12, 0x00, 0x02]));
}

#[test]
fn out_of_range_value_gets_no_answer() {
    let heading_200 = [200.0f32, 0.0, 0.0];
    let heading_200: Vec<u8> = heading_200.iter().flat_map(|v| v.to_le_bytes()).collect();
    let bad: &[(u16, &[u8])] = &[
        (0x0012, &[0, 0]),       // Data_Rate 0 Hz
        (0x0012, &[3, 0]),       // not a divisor of 2000
        (0x0012, &[0xA0, 0x0F]), // 4000 > the internal rate
        (0x0014, &[31, 0]),      // alignment > 30 s
        (0x03B2, &[0x11]),       // no such baud code
        (0x03D0, &[3]),          // Output_Variant 0..2
        (0x03D7, &[5]),          // no such LPF code
        (0x03A9, &[0x12]),       // Auto_Start: not a data command
        (0x0451, &[8]),          // Filter mask 0..7
        (0x0413, &[2]),          // ZUPT 0/1
        (0x045A, &f32::NAN.to_le_bytes()),
        (0x045A, &0.0f32.to_le_bytes()), // ω must be > 0
        (0x03EE, &(-1.0f32).to_le_bytes()),
        (0x023A, &heading_200),
    ];
    for (id, value) in bad {
        silent("K110", &save_frame(*id, value));
    }
    // Model-dependent ranges: K201 has no 16/33 Hz LPF, no EXTRIG.
    silent("K201", &save_frame(0x03D7, &[0]));
    silent("K201", &save_frame(0x05FA, &[1]));
    // TOV and EXTRIG exclusive: TOV on while Trigger_Control is saved as 1.
    let mut b = bench("K110");
    assert_eq!(b.save(0x05FA, &[1]).len(), 1);
    b.raw.clear();
    let before = state(&b.dev);
    b.send(&save_frame(0x0499, &[1]));
    b.send(&GET_BIT);
    b.drain();
    assert_eq!(b.raw, BIT_REPLY);
    assert_eq!(state(&b.dev), before);
}

#[test]
fn read_only_target_gets_no_answer() {
    // Sensors_Measurement_Range is read-only, IMU-P_Interface unsupported.
    silent("K110", &save_frame(0x028F, &[0x66]));
    silent("K110", &save_frame(0x028F, &[0x96]));
    silent("K110", &save_frame(0x0496, &[0]));
    silent("K110", &save_frame(0x0496, &[1]));
    // Still readable.
    let mut b = bench("K110");
    b.send(&read_frame(0x028F, 1));
    b.drain();
    assert_eq!(b.raw, reply(0xB1, &[0x96]));
}

// ---------------------------------------------------------------- UDD

/// A UDD configuration message (`96 N list…`, Table 5.19) as one frame.
fn udd_msg(n: u8, list: &[u8]) -> Vec<u8> {
    let mut p = vec![0x96, n];
    p.extend_from_slice(list);
    frame(&p)
}

#[test]
fn udd_config_with_0_types_is_refused() {
    // N = 0: Table 5.21 bit 1; checksum 0; the max rate of the config in force.
    let r = udd_reply(0, 0x02, 0, setup_max(2000));
    case("K110", &udd_msg(0, &[]), &r);
    // N = 0 after the 0x96 command, as the second message.
    let mut both = frame(&[0x96]);
    both.extend_from_slice(&frame(&[0]));
    case("K110", &both, &r);
    // N = 0 but a type follows: structure (bit 0) and data (bit 1).
    case(
        "K110",
        &udd_msg(0, &[0x21]),
        &udd_reply(0, 0x03, 0, setup_max(2000)),
    );
}

#[test]
fn udd_config_with_a_duplicate_type_is_accepted() {
    // The ICD does not forbid a type twice; the device takes the list as
    // given (each occurrence is a field of the frame). The config changes —
    // and nothing else: parameters and mode stay.
    let mut b = bench("K110");
    let before = state(&b.dev);
    let msg = udd_msg(3, &[0x21, 0x53, 0x21]);
    let sum = u16::from_le_bytes([msg[msg.len() - 2], msg[msg.len() - 1]]);
    b.send(&msg);
    b.send(&GET_BIT);
    b.drain();
    // payload 1 + 3 + 12 + 2 + 12 = 30: 115200 / (11 · 38) = 275 → 250 Hz
    let mut want = udd_reply(sum, 0, 0, 250);
    want.extend_from_slice(&BIT_REPLY);
    assert_eq!(b.raw, want);
    b.raw.clear();
    assert_eq!(udd_struct(&mut b), [3, 0x21, 0x53, 0x21]);
    let after = state(&b.dev);
    assert_eq!(after.params, before.params);
    assert_eq!(after.mode, before.mode);
    b.cmd(Command::Data(0x95));
    let f = b.run_ticks(40);
    assert_eq!(f.len(), 2, "ack and one frame at 50 Hz");
    assert_eq!(f[1].payload.len(), 30);
    assert_eq!(&f[1].payload[..4], &[3, 0x21, 0x53, 0x21]);
}

#[test]
fn udd_config_with_an_unknown_type_is_refused() {
    // Bit 2, bitmap bit i for the i-th type.
    case(
        "K110",
        &udd_msg(3, &[0x21, 0x77, 0x00]),
        &udd_reply(0, 0x04, 0b110, setup_max(2000)),
    );
    case(
        "K110",
        &udd_msg(1, &[0x96]),
        &udd_reply(0, 0x04, 0b1, setup_max(2000)),
    );
}

#[test]
fn udd_config_with_a_model_forbidden_type_is_refused() {
    // 0x2F aux accelerometer: K120/K220 only; 0x50 supply voltage: K100/K102
    // only; K201: starred types only (0x20 is not).
    case(
        "K110",
        &udd_msg(2, &[0x21, 0x2F]),
        &udd_reply(0, 0x04, 0b10, setup_max(2000)),
    );
    case(
        "K110",
        &udd_msg(2, &[0x50, 0x21]),
        &udd_reply(0, 0x04, 0b01, setup_max(2000)),
    );
    case(
        "K201",
        &udd_msg(3, &[0x02, 0x20, 0x07]),
        &udd_reply(0, 0x04, 0b110, setup_max(4000)),
    );
}

#[test]
fn udd_config_with_too_many_types_is_refused() {
    // 17 valid types: N > 16 (bit 1); the bitmap covers the first 16.
    let list = [0x21u8; 17];
    case(
        "K110",
        &udd_msg(17, &list),
        &udd_reply(0, 0x02, 0, setup_max(2000)),
    );
    // 17 types with a bad one at position 16 (bitmap has no bit for it)
    // and one at position 0.
    let mut list = [0x21u8; 17];
    list[0] = 0x77;
    list[16] = 0x77;
    case(
        "K110",
        &udd_msg(17, &list),
        &udd_reply(0, 0x06, 0b1, setup_max(2000)),
    );
    // N says 16, 17 follow: structure.
    case(
        "K110",
        &udd_msg(16, &[0x21; 17]),
        &udd_reply(0, 0x01, 0, setup_max(2000)),
    );
}

// ---------------------------------------------------------------- streaming

/// A K110 streaming GA at 2000 Hz on a 2 Mbaud line, first frame drained.
fn streaming_2mbaud() -> Bench {
    let mut b = bench("K110");
    assert_eq!(b.save(0x03B2, &[0x0B]).len(), 1);
    b.cmd(Command::CommitBaudRate);
    b.drain();
    assert_eq!(b.dev.line_rate(), 2_000_000);
    while b.dev.poll_event().is_some() {}
    assert_eq!(b.save(0x0012, &2000u16.to_le_bytes()).len(), 1);
    b.cmd(Command::Data(0x8F));
    b.drain();
    assert_eq!(b.dev.output_rate(), Some(2000));
    b.raw.clear();
    b
}

/// GA frames' 2 kHz counters (Table 5.7, bytes 24–25) all consecutive.
fn assert_consecutive(frames: &[Rx]) -> u16 {
    let ga: Vec<&Rx> = frames.iter().filter(|f| f.id == 0x8F).collect();
    for w in ga.windows(2) {
        assert_eq!(w[1].tick, w[0].tick + 1, "one frame per tick");
        assert_eq!(
            u16_at(&w[1].payload, 24),
            u16_at(&w[0].payload, 24).wrapping_add(1),
            "2 kHz counter continuous"
        );
    }
    ga.len() as u16
}

#[test]
fn commands_mid_stream_at_2_mbaud_are_answered_between_frames() {
    let mut b = streaming_2mbaud();
    let before = state(&b.dev);
    // Commands arriving split across ticks, one byte per tick or in two
    // halves, interleaved with bad frames; a frame per tick all along.
    let good: Vec<(Vec<u8>, Vec<u8>)> = vec![
        (GET_BIT.to_vec(), BIT_REPLY.to_vec()),
        (read_frame(0x0012, 2), reply(0xB1, &2000u16.to_le_bytes())),
        (read_frame(0x03D7, 1), reply(0xB1, &[0x02])),
        (frame(&[0x97]), reply(0x97, &[4, 0x02, 0x21, 0x23, 0x53])),
    ];
    let bad: Vec<Vec<u8>> = vec![
        vec![0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x1A, 0x22, 0x00],
        read_frame(0x0013, 1),
        frame(&[0x55]),
        save_frame(0x0012, &[0, 0]),
    ];
    let mut all = Vec::new();
    let mut replies = Vec::new();
    for round in 0..50 {
        for ((cmd, want), junk) in good.iter().zip(&bad) {
            if round % 2 == 0 {
                for &x in junk.iter().chain(cmd) {
                    b.send(&[x]);
                    all.extend(b.run_ticks(1));
                }
            } else {
                let bytes: Vec<u8> = junk.iter().chain(cmd).copied().collect();
                let (x, y) = bytes.split_at(bytes.len() / 2);
                b.send(x);
                all.extend(b.run_ticks(1));
                b.send(y);
                all.extend(b.run_ticks(1));
            }
            replies.push(want.clone());
        }
    }
    all.extend(b.run_ticks(2));
    let n = assert_consecutive(&all);
    let ticks = all.last().unwrap().tick - all[0].tick;
    assert_eq!(u64::from(n), ticks + 1, "no frame lost or added");
    let got: Vec<Vec<u8>> = all
        .iter()
        .filter(|f| f.id != 0x8F)
        .map(|f| reply(f.id, &f.payload))
        .collect();
    assert_eq!(got, replies, "every good command answered once, in order");
    assert_eq!(state(&b.dev), before);
    assert_eq!(b.dev.tx_dropped(), 0);
}

#[test]
fn garbage_flood_at_line_rate_while_streaming_keeps_the_output_rate() {
    let mut b = streaming_2mbaud();
    let before = state(&b.dev);
    // 2 Mbaud = 200 000 bytes/s = 100 bytes per 500 µs tick, for 2 s; with
    // header bytes salted in so the decoder keeps starting candidates.
    let mut rng = XorShift(0x1357_9BDF);
    let mut all = Vec::new();
    let mut chunk = [0u8; 100];
    for _ in 0..4000 {
        for x in chunk.iter_mut() {
            let r = rng.next();
            *x = match r % 16 {
                0 => 0xAA,
                1 => 0x55,
                _ => (r >> 8) as u8,
            };
        }
        b.send(&chunk);
        all.extend(b.run_ticks(1));
    }
    // Output unchanged: 4000 frames in 4000 ticks, counter continuous.
    assert!(all.iter().all(|f| f.id == 0x8F), "the flood got no answer");
    assert_eq!(all.len(), 4000);
    assert_eq!(assert_consecutive(&all), 4000);
    let first = u16_at(&all[0].payload, 24);
    let last = u16_at(&all[3999].payload, 24);
    assert_eq!(last.wrapping_sub(first), 3999);
    assert_eq!(b.dev.output_rate(), Some(2000));
    assert_eq!(b.dev.tx_dropped(), 0);
    assert_eq!(state(&b.dev), before);
    // The line goes idle; the next good frame is answered.
    let mut f = b.run_ticks(201);
    b.send(&GET_BIT);
    f.extend(b.run_ticks(1));
    let replies: Vec<&Rx> = f.iter().filter(|f| f.id != 0x8F).collect();
    assert_eq!(replies.len(), 1);
    assert_eq!(reply(replies[0].id, &replies[0].payload), BIT_REPLY);
    assert_eq!(assert_consecutive(&f), 202);
}

#[test]
fn line_rate_event_is_not_disturbed_by_garbage() {
    // A CommitBaudRate followed by garbage in the same chunk still switches.
    let mut b = bench("K110");
    assert_eq!(b.save(0x03B2, &[0x0A]).len(), 1);
    let mut bytes = frame(&[0xC2]);
    bytes.extend_from_slice(&[0xAA, 0x55, 0x00, 0x00, 0xFF]);
    b.send(&bytes);
    assert_eq!(b.dev.poll_event(), Some(Event::LineRate(921_600)));
}
