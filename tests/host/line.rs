//! The host runner's line and schedule under abuse, through the real
//! `imu-emu` binary (the host runner under abuse): a flood of
//! UART input must not starve the ticks, and a `--speed` factor beyond what
//! the host computes must neither pile up ticks nor ignore SIGTERM.

// Shared with the other host suites; not every helper is used here.
#[allow(dead_code)]
mod support;

use std::io::Write;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use support::{command, frame, read_ram, save, Conn, Emu, TIMEOUT};

const GA: u8 = 0x8F;
const DATA_RATE: u16 = 0x0012;
const BAUD_RATE: u16 = 0x03B2;

fn u16_at(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([p[i], p[i + 1]])
}

/// A UART flood (zeros, which the decoder skips, at whatever rate the host
/// takes) while GA streams at 2000 Hz on 2 Mbit/s: every frame arrives,
/// whole. The frames' own 2 kHz counter (Table 5.6, payload offset 24)
/// steps by exactly 1 from frame to frame — no wall clock involved.
#[test]
fn a_flood_of_input_while_streaming_ga_at_2_khz_keeps_every_frame() {
    let emu = Emu::tcp(&["--model", "K110"]);
    let s = TcpStream::connect_timeout(&emu.addr(), TIMEOUT).unwrap();
    let mut flood = s.try_clone().unwrap();
    let mut c = Conn::from_tcp(s);
    save(&mut c, BAUD_RATE, &[0x0B]); // 2 000 000 bit/s
    c.send(&command(0xC2)); // CommitBaudRate
    c.send(&read_ram(BAUD_RATE, 1));
    assert_eq!(c.frame_with_id(0xB1).payload(), &[0x0B]);
    save(&mut c, DATA_RATE, &2000u16.to_le_bytes());
    let cmd = command(GA);
    c.send(&cmd);
    assert_eq!(c.frame().bytes, frame(1, GA, &cmd[cmd.len() - 2..]));

    let stop = Arc::new(AtomicBool::new(false));
    let sent = Arc::new(AtomicU64::new(0));
    flood
        .set_write_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let flooder = {
        let (stop, sent) = (Arc::clone(&stop), Arc::clone(&sent));
        std::thread::spawn(move || {
            let zeros = vec![0u8; 64 * 1024];
            while !stop.load(Ordering::Relaxed) {
                match flood.write(&zeros) {
                    Ok(n) => {
                        sent.fetch_add(n as u64, Ordering::Relaxed);
                    }
                    Err(e)
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) => {}
                    Err(_) => break,
                }
            }
        })
    };

    let t0 = Instant::now();
    let mut prev = u16_at(c.frame_with_id(GA).payload(), 24);
    let mut frames = 0;
    while frames < 4000 {
        let f = c.frame();
        assert_eq!(f.id(), GA, "{:02X?}", f.bytes);
        assert_eq!(f.bytes.len(), 40);
        let k = u16_at(f.payload(), 24);
        assert_eq!(
            k.wrapping_sub(prev),
            1,
            "2 kHz counter {prev} → {k} at frame {frames}"
        );
        prev = k;
        frames += 1;
    }
    let took = t0.elapsed();
    stop.store(true, Ordering::Relaxed);
    flooder.join().unwrap();
    let flooded = sent.load(Ordering::Relaxed);
    eprintln!(
        "{frames} GA frames in {took:?} under a flood of {} MB ({:.0} MB/s)",
        flooded / 1_000_000,
        flooded as f64 / 1e6 / took.as_secs_f64()
    );
    assert_eq!(
        (c.bad, c.skipped),
        (0, 0),
        "no torn frame, nothing between frames"
    );
    // A real flood: far above what the 2 Mbit/s line itself could carry
    // (200 kB/s).
    assert!(flooded > 10 * 200_000, "flooded only {flooded} bytes");
    assert!(!emu.stderr().contains("overflowed"), "{}", emu.stderr());
}

/// `--speed 1000000` asks for far more device time than the host computes:
/// device time is held back (said on stderr), the device still answers at
/// once, and SIGTERM stops it within a pass.
#[test]
fn a_speed_beyond_the_host_still_answers_and_stops_on_sigterm() {
    let mut emu = Emu::tcp(&["--model", "K110", "--speed", "1000000"]);
    let mut c = emu.connect();
    std::thread::sleep(Duration::from_millis(300));
    for _ in 0..5 {
        let t0 = Instant::now();
        c.send(&read_ram(DATA_RATE, 2));
        assert_eq!(c.frame().bytes, frame(1, 0xB1, &100u16.to_le_bytes()));
        let took = t0.elapsed();
        assert!(
            took < Duration::from_millis(500),
            "ReadRAM answered after {took:?}"
        );
    }
    let t0 = Instant::now();
    let status = emu.terminate();
    let took = t0.elapsed();
    assert!(status.success(), "exit status {status}");
    assert!(
        took < Duration::from_secs(2),
        "stopped {took:?} after SIGTERM"
    );
    let log = emu.log_with("the host cannot keep up");
    assert!(log.contains("the host cannot keep up"), "{log}");
}
