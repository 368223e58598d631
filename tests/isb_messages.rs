//! The ISB message layer (`docs/protocol-facts.md` "ISB" and "what the vendor's
//! command-line tool needs"; the ISB protocol page): every hex example of
//! the page and of protocol-facts.md decoded and answered byte for byte, the
//! FLASH_CONFIG checksum against a hand computation, the NMEA commands and
//! the junk the vendor tool sends, and properties of the one input
//! classifier (any chunking, resync).

use imu_emu::isb::did::{self, Class, Source};
use imu_emu::isb::message::{
    self, apply_set, encode_ack, encode_data, encode_get, encode_nack, resolve_get, AckInfo,
    GetReply, GetRequest, Request, SetOutcome,
};
use imu_emu::isb::nmea::{self, Command, Dropped, Event, Input};
use imu_emu::isb::packet::{self, Decoder, Packet, MAX_PACKET};
use imu_emu::isb::sets::{self, flash, DevInfo, FlashConfig, Rmc, SystemCommand};
use proptest::prelude::*;

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

/// Decodes exactly one packet from `bytes` and hands it to `f`.
fn with_packet<R>(bytes: &[u8], f: impl FnOnce(Packet<'_>) -> R) -> R {
    let mut d = Decoder::<MAX_PACKET>::new();
    let mut input = bytes;
    let p = d.next_packet(&mut input).expect("one valid packet");
    assert!(input.is_empty());
    f(p)
}

fn ack_bytes(info: &AckInfo) -> Vec<u8> {
    let mut out = [0u8; 32];
    let n = encode_ack(info, &mut out).unwrap();
    out[..n].to_vec()
}

fn nack_bytes(info: &AckInfo) -> Vec<u8> {
    let mut out = [0u8; 32];
    let n = encode_nack(info, &mut out).unwrap();
    out[..n].to_vec()
}

fn get_packet(g: &GetRequest) -> Vec<u8> {
    let mut out = [0u8; 16];
    let n = encode_get(g, &mut out).unwrap();
    out[..n].to_vec()
}

// ---- golden: GET_DATA ----------------------------------------------------

#[test]
fn get_dev_info_once_is_served_whole_and_encodes_as_the_sdk() {
    let wire = hex("ef 49 03 00 08 00 01 00 00 00 00 00 00 00 44 43");
    let g = GetRequest {
        did: 1,
        size: 0,
        offset: 0,
        period: 0,
    };
    assert_eq!(get_packet(&g), wire);
    let req = with_packet(&wire, |p| match Request::of(&p) {
        Request::Get(g) => g,
        other => panic!("{other:?}"),
    });
    assert_eq!(req, g);
    match resolve_get(&req) {
        GetReply::Serve {
            set,
            offset,
            size,
            period,
        } => {
            assert_eq!((set.did, offset, size, period), (did::DEV_INFO, 0, 84, 0));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn get_imu_period_1_streams_every_nav_period() {
    let wire = hex("ef 49 03 00 08 00 3a 00 00 00 00 00 01 00 7e 0d");
    let g = GetRequest {
        did: 58,
        size: 0,
        offset: 0,
        period: 1,
    };
    assert_eq!(get_packet(&g), wire);
    let req = with_packet(&wire, |p| match Request::of(&p) {
        Request::Get(g) => g,
        other => panic!("{other:?}"),
    });
    match resolve_get(&req) {
        GetReply::Serve {
            set,
            offset: 0,
            size: 36,
            period: 1,
        } => {
            assert_eq!(set.did, did::IMU);
            assert_eq!(set.source, Source::NavDt);
            assert_eq!(set.rmc_bit, sets::rmc::BITS_IMU);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn nack_to_a_bad_get() {
    // GET of DID 132 (>= DID_COUNT), of DID 95, and a GET with a short
    // payload: each answered by the protocol-facts.md NACK.
    let golden = hex("ef 49 02 00 09 00 03 00 00 00 00 00 00 00 00 46 97");
    for d in [132u16, 95, 200, 0xFFFF] {
        let g = GetRequest {
            did: d,
            size: 0,
            offset: 0,
            period: 0,
        };
        let wire = get_packet(&g);
        let rx = with_packet(&wire, |p| {
            assert_eq!(Request::of(&p), Request::Get(g));
            (p.flags, p.did)
        });
        assert_eq!(resolve_get(&g), GetReply::Nack);
        assert_eq!(nack_bytes(&AckInfo::of(rx.0, rx.1)), golden);
    }
    let mut out = [0u8; 16];
    let n = packet::encode(3, 0, &[1, 0, 0, 0], &mut out).unwrap();
    with_packet(&out[..n], |p| {
        assert_eq!(
            Request::of(&p),
            Request::BadGet {
                rx_flags: 3,
                rx_did: 0
            }
        )
    });
    assert_eq!(nack_bytes(&AckInfo::of(3, 0)), golden);
}

#[test]
fn sys_fault_mag_cal_gps1_sig_gps1_version_port_monitor_imu3_raw_are_served() {
    for (d, size) in [
        (2u16, 32u16),
        (17, 220),
        (19, 12),
        (45, 708),
        (75, 223),
        (96, 84),
    ] {
        assert!(
            matches!(did::classify(d), Class::Supported(s) if s.size == size),
            "DID {d}"
        );
    }
}

#[test]
fn an_unsupported_in_range_did_gets_no_reply() {
    for d in [0u16, 14, 16, 54, 57, 121, 123, 131] {
        let g = GetRequest {
            did: d,
            size: 0,
            offset: 0,
            period: 0,
        };
        assert_eq!(resolve_get(&g), GetReply::Silent, "DID {d}");
        assert_eq!(did::classify(d), Class::Unsupported);
    }
}

#[test]
fn get_windows_follow_the_past_the_end_rule() {
    let at = |d: u16, size, offset| match resolve_get(&GetRequest {
        did: d,
        size,
        offset,
        period: 0,
    }) {
        GetReply::Serve { offset, size, .. } => (offset, size),
        other => panic!("{other:?}"),
    };
    assert_eq!(at(12, 4, 12), (12, 4));
    assert_eq!(at(12, 8, 284), (0, 288));
    assert_eq!(at(12, 4, 288), (0, 288));
    assert_eq!(at(10, 4, 44), (44, 4));
    assert_eq!(at(1, 0, 0), (0, 84));
}

// ---- golden: ACKs, stop commands -----------------------------------------

#[test]
fn stop_all_is_acked_with_the_notes_bytes() {
    let wire = hex("ef 49 06 00 00 00 3e 1f");
    let (flags, d) = with_packet(&wire, |p| {
        assert_eq!(Request::of(&p), Request::StopAllPorts);
        (p.flags, p.did)
    });
    assert_eq!(
        ack_bytes(&AckInfo::of(flags, d)),
        hex("ef 49 01 00 09 00 06 00 00 00 00 00 00 00 00 48 a5")
    );
}

#[test]
fn stop_current_port_is_acked_with_its_flags() {
    let wire = hex("ef 49 08 00 00 00 40 27");
    let (flags, d) = with_packet(&wire, |p| {
        assert_eq!(Request::of(&p), Request::StopCurrentPort);
        (p.flags, p.did)
    });
    let ack = ack_bytes(&AckInfo::of(flags, d));
    assert_eq!(
        &ack[..15],
        &hex("ef 49 01 00 09 00 08 00 00 00 00 00 00 00 00")[..]
    );
    assert_eq!(&ack[15..], &packet::checksum(&ack[..15]));
}

#[test]
fn stop_did_broadcast_names_the_did_in_the_header() {
    let wire = hex("ef 49 07 3a 00 00 79 d1");
    with_packet(&wire, |p| assert_eq!(Request::of(&p), Request::StopDid(58)));
}

#[test]
fn the_ppd_preset_packet_sets_rmc_and_gets_the_notes_ack() {
    // The page's RMC preset (pre-2.7 bits, options 0x100).
    let wire = hex("ef 49 05 09 0c 00 e2 3c 35 01 90 00 00 c0 00 01 00 00 f7 b0");
    let mut rmc = Rmc::default().encode();
    let out = with_packet(&wire, |p| match Request::of(&p) {
        Request::Set(s) => {
            assert_eq!((s.flags, s.did, s.offset, s.data.len()), (5, 9, 0, 12));
            apply_set(&s, &mut rmc)
        }
        other => panic!("{other:?}"),
    });
    let SetOutcome::Written { ack, offset, len } = out else {
        panic!("{out:?}")
    };
    assert_eq!((offset, len), (0, 12));
    assert_eq!(
        ack_bytes(&ack),
        hex("ef 49 01 00 09 00 05 09 00 00 09 0c 00 00 00 65 41")
    );
    let r = Rmc::decode(&rmc);
    assert_eq!(r.bits, 0xC000_0090_0135_3CE2);
    assert_eq!(r.options, sets::rmc::OPTIONS_PRESERVE_CTRL);
    // protocol-facts.md: the 2.7 preset differs from the page's in two bits.
    assert_eq!(sets::rmc::PRESET_PPD_2_7 ^ r.bits, 0x0000_6000_0000_0000);
    assert_ne!(r.bits & sets::rmc::BITS_PIMU, 0);
    assert_ne!(r.bits & sets::rmc::BITS_PRESET, 0);
}

#[test]
fn set_flash_config_with_offset_writes_and_acks_with_the_offset_flag() {
    let wire = hex("ef 49 25 0c 06 00 0c 00 02 00 00 00 7d b5");
    let mut cfg = FlashConfig::factory();
    let before = cfg.checksum();
    let out = with_packet(&wire, |p| match Request::of(&p) {
        Request::Set(s) => {
            assert_eq!(
                (s.flags, s.did, s.offset, s.data),
                (0x25, 12, 12, &[2u8, 0, 0, 0][..])
            );
            apply_set(&s, &mut cfg.0)
        }
        other => panic!("{other:?}"),
    });
    let SetOutcome::Written {
        ack,
        offset: 12,
        len: 4,
    } = out
    else {
        panic!("{out:?}")
    };
    let a = ack_bytes(&ack);
    assert_eq!(
        &a[..15],
        &hex("ef 49 01 00 09 00 25 0c 00 00 0c 04 00 0c 00")[..]
    );
    assert_eq!(cfg.startup_imu_dt_ms(), 2);
    // The word at 12 went 1 -> 2: the XOR changes by 1 ^ 2.
    assert_eq!(cfg.update_checksum(), before ^ 1 ^ 2);
    assert!(cfg.is_valid());
}

#[test]
fn set_sys_cmd_save_persistent_is_a_valid_command() {
    let wire = hex("ef 49 05 07 08 00 01 00 00 00 fe ff ff ff 48 9a");
    let mut img = [0u8; 8];
    let out = with_packet(&wire, |p| match Request::of(&p) {
        Request::Set(s) => apply_set(&s, &mut img),
        other => panic!("{other:?}"),
    });
    let SetOutcome::Written { ack, .. } = out else {
        panic!("{out:?}")
    };
    assert_eq!(
        ack,
        AckInfo {
            rx_flags: 5,
            rx_did: 7,
            id: 7,
            size: 8,
            offset: 0
        }
    );
    assert_eq!(
        SystemCommand::decode(&img).valid(),
        Some(sets::sys_cmd::SAVE_PERSISTENT_MESSAGES)
    );
}

#[test]
fn set_rules_nack_silence_ack_only_refusal() {
    let req = |did, offset, data: &'static [u8]| message::SetRequest {
        flags: if offset > 0 { 0x25 } else { 5 },
        did,
        offset,
        data,
    };
    let mut img = [0u8; 288];
    // DID >= 132 and 95: NACK.
    for d in [132u8, 95, 255] {
        assert_eq!(
            apply_set(&req(d, 0, &[1, 2, 3, 4]), &mut img),
            SetOutcome::Nack(AckInfo::of(5, d))
        );
    }
    // Empty data: no reply.
    assert_eq!(apply_set(&req(9, 0, &[]), &mut img), SetOutcome::Silent);
    // In range, not served: ACKed as the SDK does, nothing written.
    assert!(matches!(
        apply_set(&req(121, 0, &[1, 2, 3, 4]), &mut img),
        SetOutcome::AckOnly(AckInfo {
            id: 121,
            size: 4,
            ..
        })
    ));
    assert_eq!(img, [0u8; 288]);
    // DEV_INFO is read-only: a change is refused.
    let mut dev = [0u8; 84];
    assert!(matches!(
        apply_set(&req(1, 4, &[1, 0, 0, 0]), &mut dev),
        SetOutcome::Refused(_)
    ));
    assert_eq!(dev, [0u8; 84]);
    // SYS_PARAMS: only genFaultCode@52 may change.
    let mut sp = [0u8; 64];
    sp[52] = 0x10;
    assert!(matches!(
        apply_set(&req(10, 52, &[0, 0, 0, 0]), &mut sp),
        SetOutcome::Written {
            offset: 52,
            len: 4,
            ..
        }
    ));
    assert_eq!(sp[52], 0);
    assert!(matches!(
        apply_set(&req(10, 44, &[1, 0, 0, 0]), &mut sp),
        SetOutcome::Refused(_)
    ));
    // Under 4 bytes of room: dropped, no ACK.
    assert_eq!(
        apply_set(&req(9, 9, &[1, 2, 3]), &mut [0u8; 12]),
        SetOutcome::Silent
    );
    assert!(matches!(
        apply_set(&req(9, 8, &[1, 2, 3, 4, 5, 6]), &mut [0u8; 12]),
        SetOutcome::Written {
            offset: 8,
            len: 4,
            ..
        }
    ));
}

// ---- DATA encoder --------------------------------------------------------

#[test]
fn data_whole_set_has_no_offset_flag_a_part_has_one() {
    let dev = DevInfo {
        hardware_type: 3,
        hdw_run_state: 2,
        serial_number: 12345,
        hardware_ver: [5, 0, 0, 0],
        firmware_ver: [2, 1, 0, 0],
        build_number: 7,
        protocol_ver: sets::dev_info::PROTOCOL_2_1,
        repo_revision: 0,
        manufacturer: sets::str24("Inertial Sense Emulated"),
        build_type: b'r',
        build_date: [26, 12, 1],
        build_time: [20, 0, 0, 0],
        add_info: sets::str24("imu-emu"),
    };
    assert!(dev.accepted_by_sdk());
    let img = dev.encode();
    assert_eq!(DevInfo::decode(&img), dev);
    assert_eq!(&img[..8], &[0, 0, 3, 2, 0x39, 0x30, 0, 0]);
    assert_eq!(&img[20..24], &[2, 1, 0, 0]);
    let mut out = [0u8; 128];
    let n = encode_data(1, &img, 0, 84, &mut out).unwrap();
    assert_eq!(n, 84 + 8);
    assert_eq!(&out[..6], &[0xEF, 0x49, 0x04, 0x01, 84, 0]);
    assert_eq!(&out[6..90], &img[..]);
    assert_eq!(&out[90..92], &packet::checksum(&out[..90]));
    let n = encode_data(1, &img, 4, 4, &mut out).unwrap();
    assert_eq!(
        &out[..n - 2],
        &[0xEF, 0x49, 0x24, 0x01, 6, 0, 4, 0, 0x39, 0x30, 0, 0]
    );
    // A window outside the image or a short buffer: nothing.
    assert_eq!(encode_data(1, &img, 80, 8, &mut out), None);
    assert_eq!(encode_data(1, &img, 0, 84, &mut out[..91]), None);
}

#[test]
fn every_served_set_goes_out_whole_and_in_parts_and_comes_back_through_the_classifier() {
    for set in &did::DATA_SETS {
        let img: Vec<u8> = (0..set.size).map(|i| i as u8 ^ set.did).collect();
        let mut out = [0u8; did::MAX_SIZE + 10];
        let mut bytes = Vec::new();
        let n = encode_data(set.did, &img, 0, set.size, &mut out).unwrap();
        bytes.extend(&out[..n]);
        let n = encode_data(set.did, &img, 4, set.size - 4, &mut out).unwrap();
        bytes.extend(&out[..n]);
        let mut part = 4u16.to_le_bytes().to_vec();
        part.extend(&img[4..]);
        assert_eq!(
            events(&bytes, &[5]),
            vec![
                Ev::Pkt(4, set.did, img.clone()),
                Ev::Pkt(0x24, set.did, part)
            ],
            "{}",
            set.name
        );
        let p = set.source.period_ms(1, 4, 200);
        assert_eq!(
            p,
            match set.did {
                3 | 4 | 5 | 48 | 58 | 65 | 66 | 67 | 85 | 86 => 4,
                6 | 13 | 30 => 200,
                52 => 10,
                53 => 8,
                15 | 45 => 1000,
                _ => 1,
            },
            "{}",
            set.name
        );
    }
}

// ---- FLASH_CONFIG checksum -----------------------------------------------

#[test]
fn flash_checksum_matches_a_hand_computation() {
    // Two words set by hand: key@8 = 0x11223344, word@284 = 0x01010101.
    let mut img = [0u8; 288];
    img[8..12].copy_from_slice(&0x1122_3344u32.to_le_bytes());
    img[284..288].copy_from_slice(&0x0101_0101u32.to_le_bytes());
    // size and checksum words are outside the sum.
    img[0..4].copy_from_slice(&288u32.to_le_bytes());
    img[4..8].copy_from_slice(&0xDEAD_BEEFu32.to_le_bytes());
    assert_eq!(flash::checksum(&img), 0x1122_3344 ^ 0x0101_0101);

    // The factory image, word by word: key 1, imu dt 1, nav dt 4, three
    // baud rates 921600 (0x000E1000), dynamicModel 8, ioConfig 0x46,
    // gpsTimeSyncPeriodMs 1000, startupGPSDtMs 200, sensorConfig 0x33,
    // gpsMinimumElevation 10° (f32 0x3E32B8C2), magInterferenceThreshold
    // 3.0 (0x40400000), magCalibrationQualityThreshold 10.0 (0x41200000),
    // gnssCn0Minimum 30 and gnssCn0DynMinOffset 20 (word 0x0000141E).
    let words: [u32; 15] = [
        1,
        1,
        4,
        0x000E_1000,
        0x000E_1000,
        0x000E_1000,
        8,
        0x46,
        1000,
        200,
        0x33,
        0x3E32_B8C2,
        0x4040_0000,
        0x4120_0000,
        0x0000_141E,
    ];
    let hand = words.iter().fold(0, |x, w| x ^ w);
    assert_eq!(hand, 0x3F5C_BF85);
    let cfg = FlashConfig::factory();
    assert_eq!(cfg.checksum(), hand);
    assert_eq!(&cfg.0[4..8], &hand.to_le_bytes());
}

#[test]
fn the_tools_own_checksum_upload_comes_out_identical() {
    // protocol-facts.md: `-flashCfg=` uploads the changed words plus the checksum it
    // computed itself.
    let mut dev = FlashConfig::factory();
    let mut host = dev.clone();
    host.0[16..20].copy_from_slice(&8u32.to_le_bytes());
    let host_sum = flash::checksum(&host.0);
    for (offset, data) in [
        (16u16, host.0[16..20].to_vec()),
        (4, host_sum.to_le_bytes().to_vec()),
    ] {
        let req = message::SetRequest {
            flags: 0x25,
            did: did::FLASH_CONFIG,
            offset,
            data: &data,
        };
        assert!(matches!(
            apply_set(&req, &mut dev.0),
            SetOutcome::Written { .. }
        ));
    }
    assert_eq!(dev.update_checksum(), host_sum);
    assert_eq!(dev.startup_nav_dt_ms(), 8);
}

// ---- NMEA ----------------------------------------------------------------

#[test]
fn the_five_sentences_checksum_by_hand() {
    // XOR of the four body letters.
    assert_eq!(nmea::checksum(b"INFO"), 0x49 ^ 0x4E ^ 0x46 ^ 0x4F);
    assert_eq!(nmea::checksum(b"INFO"), 0x0E);
    assert_eq!(nmea::checksum(b"STPB"), 0x15);
    assert_eq!(nmea::checksum(b"STPC"), 0x14);
    assert_eq!(nmea::checksum(b"PERS"), 0x14);
    assert_eq!(nmea::checksum(b"SRST"), 0x06);
    for c in Command::ALL {
        assert_eq!(events(c.sentence().as_bytes(), &[1]), vec![Ev::Nmea(c)]);
    }
}

#[test]
fn info_reply_has_the_sdk_fields() {
    let dev = DevInfo {
        hardware_type: 3,
        hdw_run_state: 2,
        serial_number: 12345,
        hardware_ver: [5, 0, 0, 0],
        firmware_ver: [2, 1, 0, 0],
        build_number: 7,
        protocol_ver: [2, 1, 0, 0],
        repo_revision: 0,
        manufacturer: sets::str24("Inertial Sense Emulated"),
        build_type: b'r',
        build_date: [26, 12, 1],
        build_time: [20, 0, 0, 0],
        add_info: sets::str24("imu-emu"),
    };
    let mut out = [0u8; 200];
    let n = nmea::info_sentence(&dev, &mut out).unwrap();
    assert_eq!(
        std::str::from_utf8(&out[..n]).unwrap(),
        "$INFO,12345,5.0.0.0,2.1.0.0,7,2.1.0.0,0,Inertial Sense Emulated,\
         2026-12-01,20:00:00.00,imu-emu,3,2,r*0E\r\n"
    );
    // Too small a buffer: nothing, no panic.
    assert_eq!(nmea::info_sentence(&dev, &mut out[..n - 1]), None);
    // Strings are cut at NUL and cleaned of separators.
    let odd = DevInfo {
        manufacturer: sets::str24("a,b*c$"),
        build_type: 0,
        ..dev
    };
    let n = nmea::info_sentence(&odd, &mut out).unwrap();
    let s = std::str::from_utf8(&out[..n]).unwrap();
    assert!(s.contains(",a_b_c_,"), "{s}");
    assert!(s.contains(",3,2, *"), "{s}");
}

#[derive(Debug, Clone, PartialEq)]
enum Ev {
    Pkt(u8, u8, Vec<u8>),
    Nmea(Command),
    Asce(Vec<u8>),
}

fn feed_all(input: &mut Input, bytes: &[u8], chunks: &[usize]) -> Vec<Ev> {
    let mut out = Vec::new();
    let mut sizes = chunks.iter().copied().chain(std::iter::repeat(1));
    let mut rest = bytes;
    while !rest.is_empty() {
        let (chunk, tail) = rest.split_at(sizes.next().unwrap_or(1).clamp(1, rest.len()));
        rest = tail;
        input.feed(chunk, |e| {
            out.push(match e {
                Event::Packet(p) => Ev::Pkt(p.flags, p.did, p.payload.to_vec()),
                Event::Nmea(c) => Ev::Nmea(c),
                Event::Asce(b) => Ev::Asce(b.to_vec()),
            })
        });
    }
    out
}

fn events(bytes: &[u8], chunks: &[usize]) -> Vec<Ev> {
    feed_all(&mut Input::new(), bytes, chunks)
}

fn wire(flags: u8, did: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; payload.len() + 8];
    let n = packet::encode(flags, did, payload, &mut out).unwrap();
    out.truncate(n);
    out
}

#[test]
fn the_vendor_tools_connect_bytes_classify_exactly() {
    let get = |d: u16| {
        GetRequest {
            did: d,
            size: 0,
            offset: 0,
            period: 0,
        }
        .encode()
    };
    let mut bytes = b"$INFO*0E\r\n*56\r\n".to_vec();
    bytes.extend(wire(3, 0, &get(1)));
    bytes.extend([b'U'; 10]);
    bytes.extend([b'\n'; 5]);
    bytes.extend(b":020000041000EA");
    bytes.extend(wire(3, 0, &get(10)));
    bytes.extend(b"$STPC*14\r\n");
    let mut input = Input::new();
    let got = feed_all(&mut input, &bytes, &[3, 7, 1, 30]);
    assert_eq!(
        got,
        vec![
            Ev::Nmea(Command::Info),
            Ev::Pkt(3, 0, get(1).to_vec()),
            Ev::Pkt(3, 0, get(10).to_vec()),
            Ev::Nmea(Command::StopCurrentPort),
        ]
    );
    // "\n" after the first sentence, "*56\r\n", 10 U, 5 newlines, the
    // 15-byte Intel-HEX line, the "\n" after $STPC.
    assert_eq!(
        input.dropped(),
        Dropped {
            junk_bytes: 1 + 5 + 10 + 5 + 15 + 1,
            bad_sentences: 0,
            unknown_sentences: 0,
        }
    );
    assert!(!input.has_partial());
}

#[test]
fn sentence_endings_case_and_bad_sentences() {
    // "\n" alone and "\r" alone end a sentence; lower-case hex is accepted.
    assert_eq!(
        events(b"$STPB*15\n", &[1]),
        vec![Ev::Nmea(Command::StopAllPorts)]
    );
    assert_eq!(
        events(b"$SRST*06\r", &[1]),
        vec![Ev::Nmea(Command::SoftwareReset)]
    );
    assert_eq!(events(b"$ABCD*04\r\n", &[1]), vec![]);
    let mut input = Input::new();
    let bad: &[u8] = b"$INFO*0F\r\n$INFO*0\r\n$INFO\r\n$INF$PERS*14\r\n$ASCB*13\r\n";
    assert_eq!(
        feed_all(&mut input, bad, &[2]),
        vec![Ev::Nmea(Command::SavePersistent)]
    );
    let d = input.dropped();
    // Wrong checksum, a one-digit checksum, no checksum, cut by '$'.
    assert_eq!(d.bad_sentences, 4);
    assert_eq!(d.unknown_sentences, 1);
    // An over-long body is dropped, and the next sentence found.
    let mut long = vec![b'$'];
    long.extend([b'A'; 200]);
    long.extend(b"*00\r\n$PERS*14\r\n");
    assert_eq!(
        events(&long, &[64]),
        vec![Ev::Nmea(Command::SavePersistent)]
    );
    // Binary inside a sentence cuts it; the packet is still found.
    let mut mixed = b"$INF".to_vec();
    mixed.extend(wire(6, 0, &[]));
    assert_eq!(events(&mixed, &[1]), vec![Ev::Pkt(6, 0, vec![])]);
}

// ---- properties of the combined classifier -------------------------------

#[derive(Debug, Clone)]
enum Item {
    Packet(u8, u8, Vec<u8>),
    Sentence(Command),
    Junk(Vec<u8>),
}

fn arb_junk() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        Just(b"*56\r\n".to_vec()),
        Just(vec![b'U'; 10]),
        Just(vec![b'\n'; 5]),
        Just(b":020000041000EA".to_vec()),
        Just(b"\r\n".to_vec()),
        // Line noise that starts no message.
        prop::collection::vec(
            any::<u8>().prop_filter("no start byte", |b| *b != 0xEF && *b != b'$'),
            0..40
        ),
    ]
}

fn arb_item() -> impl Strategy<Value = Item> {
    prop_oneof![
        (
            1u8..9,
            any::<u8>(),
            prop::collection::vec(any::<u8>(), 0..200)
        )
            .prop_map(|(t, d, p)| Item::Packet(t, d, p)),
        prop::sample::select(Command::ALL.to_vec()).prop_map(Item::Sentence),
        arb_junk().prop_map(Item::Junk),
    ]
}

fn stream(items: &[Item]) -> (Vec<u8>, Vec<Ev>) {
    let mut bytes = Vec::new();
    let mut want = Vec::new();
    for it in items {
        match it {
            Item::Packet(t, d, p) => {
                bytes.extend(wire(*t, *d, p));
                want.push(Ev::Pkt(*t, *d, p.clone()));
            }
            Item::Sentence(c) => {
                bytes.extend(c.sentence().as_bytes());
                want.push(Ev::Nmea(*c));
            }
            Item::Junk(j) => bytes.extend(j),
        }
    }
    (bytes, want)
}

proptest! {
    #[test]
    fn any_chunking_gives_every_packet_and_sentence_in_order(
        items in prop::collection::vec(arb_item(), 1..12),
        chunks in prop::collection::vec(1usize..600, 0..30),
    ) {
        let (bytes, want) = stream(&items);
        prop_assert_eq!(&events(&bytes, &[1]), &want);
        prop_assert_eq!(&events(&bytes, &[bytes.len()]), &want);
        prop_assert_eq!(&events(&bytes, &chunks), &want);
    }

    #[test]
    fn after_a_corrupted_packet_the_classifier_resyncs(
        bad in (1u8..9, any::<u8>(), prop::collection::vec(any::<u8>(), 0..200)),
        at in any::<prop::sample::Index>(),
        flip in 1u8..=255,
        items in prop::collection::vec(arb_item(), 1..8),
        chunks in prop::collection::vec(1usize..600, 0..30),
    ) {
        let mut bytes = wire(bad.0, bad.1, &bad.2);
        let i = at.index(bytes.len());
        bytes[i] ^= flip;
        // A corrupted size may reach up to a whole packet further: idle-line
        // zeros resolve it (they are junk to the classifier).
        bytes.extend(std::iter::repeat_n(0u8, MAX_PACKET));
        let (tail, want) = stream(&items);
        bytes.extend(tail);
        let got = events(&bytes, &chunks);
        prop_assert!(got.len() >= want.len());
        prop_assert_eq!(&got[got.len() - want.len()..], &want[..]);
    }

    #[test]
    fn no_input_panics_or_grows_without_bound(
        bytes in prop::collection::vec(any::<u8>(), 0..3000),
        chunks in prop::collection::vec(1usize..600, 0..30),
    ) {
        let mut input = Input::new();
        let _ = feed_all(&mut input, &bytes, &chunks);
        input.abandon();
        prop_assert!(!input.has_partial());
    }

    #[test]
    fn set_never_writes_outside_the_struct_nor_panics(
        d in any::<u8>(),
        offset in any::<u16>(),
        data in prop::collection::vec(any::<u8>(), 0..400),
        img_len in 0usize..400,
    ) {
        let mut img = vec![0u8; img_len];
        let req = message::SetRequest { flags: 0x25, did: d, offset, data: &data };
        match apply_set(&req, &mut img) {
            SetOutcome::Written { offset, len, ack } => {
                let set = did::lookup(u16::from(d)).unwrap();
                let (o, l) = (usize::from(offset), usize::from(len));
                let size = usize::from(set.size).min(img_len);
                prop_assert!(o + l <= size);
                prop_assert!(size - o >= usize::from(message::MIN_SET_ROOM));
                prop_assert_eq!(l, data.len().min(size - o));
                prop_assert_eq!(ack.size, len);
                prop_assert_eq!(&img[o..o + l], &data[..l]);
            }
            SetOutcome::Nack(_) => prop_assert!(did::is_nacked(u16::from(d))),
            _ => {}
        }
    }
}

/// A stray `0xEF` (or an ISB header the decoder refuses: a wrong second
/// preamble byte, an impossible size) right before `$STPB`: the decoder
/// drops the candidate and the sentence still counts, in any chunking —
/// once it swallowed the `$`, and the first `$STPB` went unheard. A
/// candidate with a possible size still takes what follows (the 100 ms
/// abandon frees the line).
#[test]
fn a_stray_preamble_byte_does_not_swallow_the_next_sentence() {
    let stop = vec![Ev::Nmea(Command::StopAllPorts)];
    for pre in [
        &b"\xEF"[..],
        b"\xEF\x00",
        b"\xEF\xEF",
        b"\xEF\x49\x04\x01\xFF\xFF",
    ] {
        let mut bytes = pre.to_vec();
        bytes.extend(b"$STPB*15\r\n");
        for chunks in [&[bytes.len()][..], &[1], &[2, 3]] {
            assert_eq!(events(&bytes, chunks), stop, "{pre:02X?} {chunks:?}");
        }
    }
    // Then a packet still decodes.
    let mut bytes = b"\xEF$STPB*15\r\n".to_vec();
    bytes.extend(wire(4, 1, &[1, 2, 3, 4]));
    assert_eq!(
        events(&bytes, &[3]),
        vec![
            Ev::Nmea(Command::StopAllPorts),
            Ev::Pkt(4, 1, vec![1, 2, 3, 4])
        ]
    );
    // A possible size: the candidate takes the sentence.
    assert_eq!(
        events(b"\xEF\x49\x04\x01\x54\x00$STPB*15\r\n", &[16]),
        vec![]
    );
}
