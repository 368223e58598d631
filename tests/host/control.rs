//! End-to-end tests of the control socket's product side:
//! `help`, `status`, errors that name the syntax, events, and the link
//! faults, each checked by its effect on the wire of the real binary.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::time::{Duration, Instant};

use support::{command, frame, free_port, save_flash, sum16, Conn, Control, Emu, Frame};

const GA: u8 = 0x8F;
const STOP: u8 = 0xFE;
const GET_DEV_INFO: u8 = 0x12;
const DATA_RATE: u16 = 0x0012;

fn with_control(args: &[&str]) -> (Emu, Conn, Control) {
    let addr = format!("127.0.0.1:{}", free_port());
    let mut all = vec!["--control", addr.as_str()];
    all.extend_from_slice(args);
    let emu = Emu::tcp(&all);
    let c = emu.connect();
    let mut ctl = Control::connect(&addr);
    // The connection powers the device on at the runner's next pass.
    ctl.wait_powered();
    (emu, c, ctl)
}

/// The GA 2 kHz counter (Table 5.7, payload offset 24).
fn counter(f: &Frame) -> u16 {
    u16::from_le_bytes([f.payload()[24], f.payload()[25]])
}

fn start_ga(c: &mut Conn) {
    c.send(&command(GA));
    c.frame_with_id(GA);
}

/// The value of `key` in a `status` reply.
fn field<'a>(status: &'a str, key: &str) -> &'a str {
    status
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {status:?}"))
}

/// GA frames arriving within `d`, with their arrival times.
fn ga_frames_for(c: &mut Conn, d: Duration) -> Vec<(Instant, Frame)> {
    let end = Instant::now() + d;
    let mut v = Vec::new();
    while let Some(f) = c.frame_before(end) {
        assert_eq!(f.id(), GA, "{:02X?}", f.bytes);
        v.push((Instant::now(), f));
    }
    v
}

#[test]
fn a_single_device_answers_devices_and_dev_0() {
    let (emu, _c, mut ctl) = with_control(&[]);
    assert_eq!(
        ctl.cmd("devices"),
        format!("ok count=1 dev0=tcp:{}", emu.addr())
    );
    assert!(ctl.cmd("dev 0 status").starts_with("ok mode="));
    assert_eq!(
        ctl.cmd("dev 1 status"),
        "error no device 1: this run has one device, dev 0"
    );
    assert_eq!(ctl.cmd("dev 0 help"), "error not a device command: help");
}

#[test]
fn help_and_errors_name_the_syntax() {
    let (_emu, _c, mut ctl) = with_control(&[]);
    let help = ctl.cmd("help");
    assert!(help.starts_with("ok commands: help | status | pps | extrig high|low"));
    assert!(
        help.contains("| link stall <ms> | link cut | link clear"),
        "{help}"
    );
    assert_eq!(
        ctl.cmd("extrig sideways"),
        "error bad syntax: extrig sideways; expected extrig high|low"
    );
    assert_eq!(
        ctl.cmd("link"),
        "error bad syntax: link; expected link drop|corrupt|duplicate <rate 0..1> [tx|rx], \
         link noise <bytes> [tx|rx], link stall <ms>, link cut, or link clear"
    );
    assert_eq!(ctl.cmd("link drop 2"), "error not a probability in 0..1: 2");
    assert_eq!(
        ctl.cmd("link corrupt 0.5 up"),
        "error expected tx or rx, got up"
    );
    assert_eq!(
        ctl.cmd("link noise 0"),
        "error not a byte count in 1..=65536: 0"
    );
    assert_eq!(
        ctl.cmd("power-cycle boot=maybe"),
        "error bad syntax: power-cycle boot=maybe; expected power-cycle [boot=high|boot=low]"
    );
    assert_eq!(
        ctl.cmd("frobnicate 3"),
        "error unknown command: frobnicate 3; try help"
    );
    assert_eq!(ctl.cmd("status").split(' ').next(), Some("ok"));
}

/// `status` tells the mode, the format, the rates, what was sent (exactly
/// what the client received) and what the device rejected, and why.
#[test]
fn status_counts_what_was_sent_and_why_frames_were_rejected() {
    let (_emu, mut c, mut ctl) = with_control(&[]);
    let s = ctl.cmd("status");
    assert_eq!(field(&s, "mode"), "idle");
    assert_eq!(field(&s, "format"), "none");
    assert_eq!(field(&s, "output-rate"), "none");
    assert_eq!(field(&s, "line-rate"), "115200");
    assert_eq!(field(&s, "rejected"), "0");
    assert_eq!(field(&s, "link"), "clean");

    let mut frames = 0;
    start_ga(&mut c);
    frames += 1 + ga_frames_for(&mut c, Duration::from_millis(200)).len();
    let s = ctl.cmd("status");
    assert_eq!(field(&s, "mode"), "continuous");
    assert_eq!(field(&s, "format"), "0x8f");
    assert_eq!(field(&s, "output-rate"), "100");

    // Refused: a Data_Rate that does not divide 2000, an unknown command, a
    // bad checksum. GetDevInfo after them: once it is answered the device
    // has seen them all.
    c.send(&command(STOP));
    c.send(&save_flash(DATA_RATE, &33u16.to_le_bytes()));
    c.send(&command(0x77));
    let mut bad = command(GET_DEV_INFO);
    *bad.last_mut().unwrap() ^= 0x40;
    c.send(&bad);
    c.send(&frame(1, 0x33, &[1, 2]));
    c.send(&command(GET_DEV_INFO));
    loop {
        let f = c.frame();
        frames += 1;
        if f.id() == GET_DEV_INFO {
            break;
        }
    }
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(200))
        .is_none());
    let s = ctl.cmd("status");
    assert_eq!(field(&s, "mode"), "idle");
    assert_eq!(field(&s, "frames-sent"), frames.to_string(), "{s}");
    assert_eq!(field(&s, "bytes-sent"), c.received.to_string(), "{s}");
    assert_eq!(field(&s, "tx-dropped"), "0");
    assert_eq!(field(&s, "commands"), "5", "{s}");
    assert_eq!(field(&s, "rejected"), "4", "{s}");
    assert_eq!(field(&s, "rejected-checksum"), "1", "{s}");
    assert_eq!(field(&s, "rejected-not-command"), "1", "{s}");
    assert_eq!(field(&s, "rejected-unknown-command"), "1", "{s}");
    assert_eq!(field(&s, "rejected-bad-value"), "1", "{s}");
}

/// `link corrupt 1 tx`: every byte is hit, no frame passes its checksum
/// (bytes still arrive); `link clear`: good frames again, the counter
/// running on.
#[test]
fn link_corrupt_breaks_every_frame_and_clear_restores_them() {
    let (_emu, mut c, mut ctl) = with_control(&[]);
    start_ga(&mut c);
    c.frame_with_id(GA);
    assert_eq!(ctl.cmd("link corrupt 1 tx"), "ok");
    // What was on its way before the command.
    c.drain_for(Duration::from_millis(100));
    let before = c.received;
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(300))
        .is_none());
    // 30 frames of 40 bytes in 300 ms, all of them broken (a loaded host
    // may deliver fewer).
    assert!(c.received - before >= 400, "{}", c.received - before);
    let s = ctl.cmd("status");
    assert_eq!(field(&s, "link"), "corrupt-tx=1");
    assert_eq!(ctl.cmd("link clear"), "ok");
    c.drain_for(Duration::from_millis(50));
    let good = ga_frames_for(&mut c, Duration::from_millis(200));
    assert!(good.len() >= 8, "{}", good.len());
    for w in good.windows(2) {
        assert_eq!(counter(&w[1].1), counter(&w[0].1).wrapping_add(20));
    }
}

/// `link stall 200`: the output is held 200 ms and then sent at once: a
/// gap on the wire, then a burst whose counters cover the stall — no frame
/// lost.
#[test]
fn link_stall_holds_the_output_and_loses_nothing() {
    let (_emu, mut c, mut ctl) = with_control(&[]);
    start_ga(&mut c);
    // The frame before the stall, and every frame after it.
    let mut frames = vec![(Instant::now(), c.frame_with_id(GA))];
    assert_eq!(ctl.cmd("link stall 200"), "ok");
    frames.extend(ga_frames_for(&mut c, Duration::from_millis(700)));
    for w in frames.windows(2) {
        assert_eq!(
            counter(&w[1].1),
            counter(&w[0].1).wrapping_add(20),
            "a frame was lost"
        );
    }
    let (i, gap) = frames
        .windows(2)
        .enumerate()
        .map(|(i, w)| (i + 1, w[1].0 - w[0].0))
        .max_by_key(|&(_, g)| g)
        .unwrap();
    assert!(
        (Duration::from_millis(150)..Duration::from_millis(1000)).contains(&gap),
        "{gap:?}"
    );
    // The burst after the gap: the frames the stall held, ~200 ms of the
    // device's 2 kHz counter (400 counts) arriving at once.
    let t0 = frames[i].0;
    let burst: Vec<&Frame> = frames[i..]
        .iter()
        .take_while(|(t, _)| *t - t0 < Duration::from_millis(60))
        .map(|(_, f)| f)
        .collect();
    let span = counter(burst[burst.len() - 1]).wrapping_sub(counter(burst[0]));
    assert!(span >= 340, "burst covers {span} counts only");
}

/// `link cut`: the rest of the frame being sent is lost: exactly one GA
/// frame missing (a counter step of 40 once), the frames after it good.
#[test]
fn link_cut_loses_the_rest_of_one_frame() {
    let (_emu, mut c, mut ctl) = with_control(&[]);
    start_ga(&mut c);
    let mut frames = vec![(Instant::now(), c.frame_with_id(GA))];
    let bad_before = c.bad;
    assert_eq!(ctl.cmd("link cut"), "ok");
    frames.extend(ga_frames_for(&mut c, Duration::from_millis(300)));
    let steps: Vec<u16> = frames
        .windows(2)
        .map(|w| counter(&w[1].1).wrapping_sub(counter(&w[0].1)))
        .collect();
    assert_eq!(steps.iter().filter(|&&s| s == 40).count(), 1, "{steps:?}");
    assert!(steps.iter().all(|&s| s == 20 || s == 40), "{steps:?}");
    assert!(c.bad > bad_before);
    let s = ctl.cmd("status");
    assert_ne!(field(&s, "link-cut"), "0");
}

/// `link drop 1 rx`: the device hears nothing (no answer); `link duplicate
/// 1 tx`: every byte twice; `link clear`: answers again.
#[test]
fn link_drop_and_duplicate_act_on_their_direction() {
    let (_emu, mut c, mut ctl) = with_control(&[]);
    assert_eq!(ctl.cmd("link drop 1 rx"), "ok");
    c.send(&command(GET_DEV_INFO));
    assert!(c
        .frame_before(Instant::now() + Duration::from_millis(300))
        .is_none());
    assert_eq!(c.received, 0);
    assert_eq!(ctl.cmd("link clear"), "ok");
    assert_eq!(ctl.cmd("link duplicate 1 tx"), "ok");
    c.send(&command(GET_DEV_INFO));
    let doubled = c.read_bytes(2 * 174);
    let once: Vec<u8> = doubled.iter().step_by(2).copied().collect();
    assert!(doubled.chunks(2).all(|p| p[0] == p[1]));
    assert_eq!(&once[..6], &[0xAA, 0x55, 0x01, GET_DEV_INFO, 0xAC, 0x00]);
    assert_eq!(sum16(&once[2..172]).to_le_bytes(), once[172..]);
    assert_eq!(ctl.cmd("link clear"), "ok");
    c.send(&command(GET_DEV_INFO));
    assert_eq!(c.frame_with_id(GET_DEV_INFO).bytes, once);
}

/// `link noise N`: N random bytes on the wire now, the same for the same
/// `--seed`, others for another seed.
#[test]
fn link_noise_is_deterministic_from_the_seed() {
    let noise = |seed: &str| {
        let (_emu, mut c, mut ctl) = with_control(&["--seed", seed]);
        assert_eq!(ctl.cmd("link noise 64"), "ok");
        let b = c.read_bytes(64);
        assert!(c.drain_for(Duration::from_millis(100)) == 0);
        b
    };
    let a = noise("5");
    assert_eq!(a, noise("5"));
    assert_ne!(a, noise("6"));
}

/// `-v`: every command the device received is logged, and a refused one
/// with the reason, decoded on the host side.
#[test]
fn verbose_logs_name_why_a_frame_was_refused() {
    let emu = Emu::tcp(&["-v"]);
    let mut c = emu.connect();
    c.send(&save_flash(DATA_RATE, &33u16.to_le_bytes()));
    c.send(&save_flash(DATA_RATE, &50u16.to_le_bytes()));
    c.frame_with_id(0xB2);
    c.send(&command(0x77));
    c.send(&command(GET_DEV_INFO));
    c.frame_with_id(GET_DEV_INFO);
    let log = emu.log_with("command GetDevInfo");
    assert!(
        log.contains("SaveFlash Data_Rate 33: not a divisor of 2000 — no reply, ICD 5.3.7"),
        "{log}"
    );
    assert!(log.contains("parameter saved: Data_Rate = 50"), "{log}");
    assert!(
        log.contains("command 0x77 ignored: unknown command — no reply, ICD 5.3"),
        "{log}"
    );
    assert!(log.contains("command GetDevInfo"), "{log}");
}
