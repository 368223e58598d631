//! Every hex string of the ICD and of the ISB protocol page / vendor SDK is
//! a golden test: decode it, re-encode it, compare bytes. The vectors are
//! read from the repository's `tests/data/vectors.txt` (one `meaning | hex`
//! per line; the facts behind them are in `docs/protocol-facts.md`).

use imu_emu::kernel::command::Command;
use imu_emu::kernel::frame::{self, Decoder};

/// The KERNEL vectors (the file's first section).
fn vectors() -> Vec<(String, Vec<u8>)> {
    section(false)
}

/// The vectors of one section: KERNEL, or ISB (after `# ISB`).
fn section(isb: bool) -> Vec<(String, Vec<u8>)> {
    // The package directory cargo runs the test in (it sets the variable at
    // run time too), so a binary built from another copy of the tree still
    // reads this copy's file.
    let root = std::env::var_os("CARGO_MANIFEST_DIR").map_or_else(
        || env!("CARGO_MANIFEST_DIR").into(),
        std::path::PathBuf::from,
    );
    let text = std::fs::read_to_string(root.join("tests/data/vectors.txt"))
        .expect("tests/data/vectors.txt in the repository");
    let mut out = Vec::new();
    let mut in_isb = false;
    for line in text.lines() {
        if line.starts_with("# ISB") {
            in_isb = true;
        }
        if line.starts_with('#') || line.trim().is_empty() || in_isb != isb {
            continue;
        }
        let (meaning, hex) = line.split_once('|').expect("meaning | hex");
        let bytes = hex
            .split_whitespace()
            .map(|h| u8::from_str_radix(h, 16).expect("hex byte"))
            .collect();
        out.push((meaning.trim().to_string(), bytes));
    }
    out
}

#[test]
fn all_23_kernel_vectors_are_read() {
    // 14 rows of Table A.1, 4 SaveFlash, 3 ReadRAM, 1 ReadRAM reply and
    // the AutoStart announcement.
    assert_eq!(vectors().len(), 23);
}

#[test]
fn every_kernel_vector_decodes_and_re_encodes_byte_for_byte() {
    for (meaning, bytes) in vectors() {
        let mut d = Decoder::<512>::new();
        let mut input = &bytes[..];
        let f = d
            .next_frame(&mut input)
            .unwrap_or_else(|| panic!("{meaning}: no frame"));
        assert!(input.is_empty(), "{meaning}: trailing bytes");
        let (ty, id, payload) = (f.msg_type, f.id, f.payload.to_vec());
        let mut out = [0u8; 512];
        let n = frame::encode(ty, id, &payload, &mut out).unwrap();
        assert_eq!(&out[..n], &bytes[..], "{meaning}: frame re-encode");
        if ty == frame::TYPE_COMMAND {
            let cmd = Command::parse(&payload).unwrap_or_else(|e| panic!("{meaning}: {e:?}"));
            assert!(
                !matches!(cmd, Command::Unknown(_)),
                "{meaning}: unknown command"
            );
            let n = cmd.encode(&mut out).unwrap();
            assert_eq!(&out[..n], &bytes[..], "{meaning}: command re-encode");
        }
    }
}

#[test]
fn typed_commands_encode_to_the_icd_bytes() {
    let mut out = [0u8; 64];
    let cases: &[(Command, &[u8])] = &[
        (
            Command::Data(0x33),
            &[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0x33, 0x3A, 0x00],
        ),
        (
            Command::Stop,
            &[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0xFE, 0x05, 0x01],
        ),
        (
            Command::CommitBaudRate,
            &[0xAA, 0x55, 0x00, 0x00, 0x07, 0x00, 0xC2, 0xC9, 0x00],
        ),
        (
            Command::SaveFlash {
                id: 0x0012,
                len: 2,
                value: &[0xD0, 0x07],
            },
            &[
                0xAA, 0x55, 0x00, 0x00, 0x0E, 0x00, 0xB2, 0xFF, 0x12, 0x00, 0x02, 0x00, 0xD0, 0x07,
                0xAA, 0x02,
            ],
        ),
        (
            Command::ReadRam { id: 0x028F, len: 1 },
            &[
                0xAA, 0x55, 0x00, 0x00, 0x0C, 0x00, 0xB1, 0xFF, 0x8F, 0x02, 0x01, 0x00, 0x4E, 0x02,
            ],
        ),
    ];
    for (cmd, bytes) in cases {
        let n = cmd.encode(&mut out).unwrap();
        assert_eq!(&out[..n], *bytes, "{cmd:?}");
    }
    // Alignment_Angles 10, 20, 30 (5.3.7.1 example 4).
    let mut v = Vec::new();
    for a in [10.0f32, 20.0, 30.0] {
        v.extend_from_slice(&a.to_le_bytes());
    }
    let n = Command::SaveFlash {
        id: 0x023A,
        len: 12,
        value: &v,
    }
    .encode(&mut out)
    .unwrap();
    assert_eq!(&out[n - 2..n], &[0x84, 0x04]);
}

#[test]
fn all_11_isb_vectors_are_read() {
    // 3 from the protocol page, 8 from the vendor SDK (docs/protocol-facts.md "ISB").
    assert_eq!(section(true).len(), 11);
}

/// Every ISB hex string: one packet, the type its meaning names, and the
/// same bytes re-encoded (checksum included).
#[test]
fn every_isb_vector_decodes_and_re_encodes_byte_for_byte() {
    use imu_emu::isb::packet::{self, PacketType};
    for (meaning, bytes) in section(true) {
        let mut d = packet::Decoder::<{ packet::MAX_PACKET }>::new();
        let mut input = &bytes[..];
        let p = d
            .next_packet(&mut input)
            .unwrap_or_else(|| panic!("{meaning}: no packet"));
        assert!(input.is_empty(), "{meaning}: trailing bytes");
        let expect = match meaning.split(':').nth(1).unwrap_or("").trim() {
            m if m.starts_with("stop broadcasts, all") => PacketType::StopBroadcastsAllPorts,
            m if m.starts_with("stop broadcasts, current") => PacketType::StopBroadcastsCurrentPort,
            m if m.starts_with("RMC") || m.starts_with("SET") => PacketType::SetData,
            m if m.starts_with("GET") => PacketType::GetData,
            m if m.starts_with("STOP_DID") => PacketType::StopDidBroadcast,
            m if m.starts_with("ACK") => PacketType::Ack,
            m if m.starts_with("NACK") => PacketType::Nack,
            m => panic!("{meaning}: no expected type for {m:?}"),
        };
        assert_eq!(p.kind(), Some(expect), "{meaning}");
        let (flags, did, payload) = (p.flags, p.did, p.payload.to_vec());
        let mut out = [0u8; 64];
        let n = packet::encode(flags, did, &payload, &mut out).unwrap();
        assert_eq!(&out[..n], &bytes[..], "{meaning}: re-encode");
    }
}

/// The SDK's SET of FLASH_CONFIG carries an offset (flag 0x20):
/// startupImuDtMs = 2 at offset 12.
#[test]
fn isb_set_with_offset_splits_offset_and_data() {
    use imu_emu::isb::packet;
    let bytes = [
        0xef, 0x49, 0x25, 0x0c, 0x06, 0x00, 0x0c, 0x00, 0x02, 0x00, 0x00, 0x00, 0x7d, 0xb5,
    ];
    let mut d = packet::Decoder::<64>::new();
    let p = d.next_packet(&mut &bytes[..]).unwrap();
    assert_eq!(p.did, 12);
    assert_eq!(p.offset_and_data(), Some((12, &[2u8, 0, 0, 0][..])));
}
