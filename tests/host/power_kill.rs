//! Power loss through the real binary (power loss at any instant):
//! `imu-emu --flash FILE` is killed with SIGKILL at random moments during
//! bursts of SaveFlash (ICD 5.3.7), 120 times in a row on one flash file.
//! After every restart the parameters (ReadRAM, 5.3.8) must equal the
//! state after some prefix of the burst's writes — one that includes every
//! write whose acknowledgement was read before the kill.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;
// Shared with the core suites; not every method is used here.
#[allow(dead_code)]
#[path = "../common/xorshift.rs"]
mod xorshift;

use std::time::{Duration, Instant};

use support::{read_ram, save_flash, Conn, Emu};
use xorshift::XorShift;

/// Parameters the bursts write (id, length) and how to make a valid value
/// of each: Data_Rate (divisors of 2000), Initial_Alignment_Time 0..30,
/// Min_Vinp/Max_Vinp_Threshold and Hold-off_Time (any u16).
const PARAMS: [(u16, u16); 5] = [
    (0x0012, 2),
    (0x0014, 2),
    (0x03DA, 2),
    (0x03DC, 2),
    (0x05FE, 2),
];
const RATES: [u16; 8] = [1, 10, 50, 100, 200, 250, 500, 1000];
const KILLS: usize = 120;

/// A valid value for `PARAMS[i]`.
fn value(rng: &mut XorShift, i: usize) -> Vec<u8> {
    let r = rng.next();
    let v: u16 = match i {
        0 => RATES[r as usize % RATES.len()],
        1 => (r % 31) as u16,
        _ => r as u16,
    };
    v.to_le_bytes().to_vec()
}

type State = Vec<Vec<u8>>;

/// The state at a burst's start, its writes (parameter index, value) and
/// how many acknowledgements were read before the kill.
type Burst = (State, Vec<(usize, Vec<u8>)>, usize);

/// Every burst parameter's RAM value (ReadRAM; right after power-on RAM is
/// what the flash holds).
fn read_state(c: &mut Conn) -> State {
    PARAMS
        .iter()
        .map(|&(id, len)| {
            c.send(&read_ram(id, len));
            let f = c.frame_with_id(0xB1);
            assert_eq!(f.payload().len(), usize::from(len));
            f.payload().to_vec()
        })
        .collect()
}

#[test]
fn sigkill_during_save_flash_bursts_keeps_a_prefix_with_every_acknowledged_write() {
    let dir = tempfile::tempdir().unwrap();
    let flash = dir.path().join("flash.bin");
    let flash = flash.to_str().unwrap();
    let mut rng = XorShift(0x0BAD_F00D);
    let mut last: Option<Burst> = None;
    let (mut mid_burst, mut inside, mut none_acked, mut all_acked) = (0, 0, 0, 0);
    for kill in 0..=KILLS {
        let emu = Emu::tcp(&["--flash", flash]);
        let mut c = emu.connect();
        let state = read_state(&mut c);
        if let Some((start, writes, acked)) = last.take() {
            // The states after each prefix of the writes.
            let mut prefix = start.clone();
            let mut states = vec![prefix.clone()];
            for (i, v) in &writes {
                prefix[*i] = v.clone();
                states.push(prefix.clone());
            }
            let j = (acked..=writes.len()).find(|&j| states[j] == state);
            assert!(
                j.is_some(),
                "kill {kill}: state {state:02X?} is no prefix ≥ {acked} of {} writes from {start:02X?}",
                writes.len()
            );
            let j = j.unwrap();
            if j > 0 && j < writes.len() {
                mid_burst += 1;
            }
        }
        if kill == KILLS {
            break;
        }
        // A burst of 1..=32 SaveFlash commands — every other time all in
        // one write, else one every 300 µs — and a kill at a random moment
        // of it (or a little after), reading the acknowledgements until
        // then.
        let n = 1 + rng.next() as usize % 32;
        let writes: Vec<(usize, Vec<u8>)> = (0..n)
            .map(|_| {
                let i = rng.next() as usize % PARAMS.len();
                (i, value(&mut rng, i))
            })
            .collect();
        let frames: Vec<Vec<u8>> = writes
            .iter()
            .map(|(i, v)| save_flash(PARAMS[*i].0, v))
            .collect();
        let span = n as u64 * 300 + 3_000;
        let kill_at = Instant::now() + Duration::from_micros(u64::from(rng.next()) % span);
        let (mut sent, mut acked) = (0, 0);
        if kill % 2 == 0 {
            c.send(&frames.concat());
            sent = n;
        }
        loop {
            if sent < n {
                c.send(&frames[sent]);
                sent += 1;
            }
            let step = (Instant::now() + Duration::from_micros(300)).min(kill_at);
            while let Some(f) = c.frame_before(step) {
                assert_eq!(f.id(), 0xB2, "only SaveFlash acknowledgements");
                let cmd = &frames[acked];
                assert_eq!(f.payload(), &cmd[cmd.len() - 2..], "acks in order");
                acked += 1;
            }
            if Instant::now() >= kill_at || acked == n {
                break;
            }
        }
        let writes = writes[..sent].to_vec();
        let n = sent;
        match acked {
            a if a == n => all_acked += 1,
            0 => none_acked += 1,
            _ => {}
        }
        if acked < n {
            inside += 1;
        }
        drop(emu); // SIGKILL (Child::kill), then wait
        drop(c);
        last = Some((state, writes, acked));
    }
    eprintln!(
        "{KILLS} kills: {inside} with acknowledgements outstanding ({none_acked} before any), \
         {all_acked} after every ack; {mid_burst} restarts showed a strict prefix"
    );
    // The kills did land inside bursts, not only after them.
    assert!(inside >= KILLS / 4, "only {inside} kills inside a burst");
}
