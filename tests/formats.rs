//! Golden tests of every fixed format (ICD Tables 5.5–5.12) and every UDD
//! type (Table 5.15). Expected bytes were computed by hand from the tables
//! (scale, width, signedness, LSB first; values rounded half away from
//! zero), independently of the code under test.

use imu_emu::kernel::fields::{write_all, OutputCtx};
use imu_emu::kernel::{formats, udd};
use imu_emu::model::Product;
use imu_emu::sensor::Sample;

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

fn sample() -> Sample {
    Sample {
        gyro: [1.5, -2.25, 100.0],
        acc: [0.5, -0.25, 1.0],
        aux_acc: [2.0, -3.0, 90.0],
        euler: [350.5, -10.25, 45.0],
        quat: [0.5, -0.5, 0.5, -0.5],
        gyro_filtered: [0.75, -0.5, 0.125],
        gyro_bias: [0.01, -0.02, 0.03],
        acc_filtered: [0.125, 0.25, -1.0],
        aux_acc_filtered: [-2.5, 1.5, 45.0],
        temperature: 31.4,
        supply_voltage: 12.34,
    }
}

fn encode(fields: &[imu_emu::kernel::fields::Field], s: &Sample, product: &str) -> Vec<u8> {
    let product = Product::parse(product).unwrap();
    let ctx = OutputCtx {
        sample: s,
        product: &product,
        counter: 0x1234,
        usw: 0x0400,
        usw_ext: 0x0001,
        time_flags: 0x0009,
        second_fraction_ns: 123_456_789,
        imu_time_ns: 5_000_000_123,
    };
    let mut out = [0u8; 512];
    let n = write_all(fields, &ctx, &mut out).unwrap();
    out[..n].to_vec()
}

/// K110 G2000-A40: KG = 10, KA = 500 (Table 5.6).
const FIXED: &[(u8, &str)] = &[
    (0x33, "ea 88 ff fb 94 11 0f 00 e9 ff e8 03 fa 00 83 ff f4 01 00 00 00 00 00 00 00 00 00 00 00 04 00 00 3a 01"),
    (0x8F, "f0 49 02 00 18 91 fc ff 80 96 98 00 20 a1 07 00 70 2f fc ff 40 42 0f 00 34 12 00 04 00 00 3a 01"),
    (0x9B, "f0 49 02 00 18 91 fc ff 80 96 98 00 20 a1 07 00 70 2f fc ff 40 42 0f 00 09 00 15 cd 5b 07 3a 01"),
    (0xA5, "f0 49 02 00 18 91 fc ff 80 96 98 00 20 a1 07 00 70 2f fc ff 40 42 0f 00 80 84 1e 00 40 39 d2 ff 80 4a 5d 05 00 00 00 04 00 00 3a 01"),
    (0xA6, "f0 49 02 00 18 91 fc ff 80 96 98 00 20 a1 07 00 70 2f fc ff 40 42 0f 00 80 84 1e 00 40 39 d2 ff 80 4a 5d 05 09 00 15 cd 5b 07 3a 01"),
    (0x82, "ea 88 ff fb 94 11 88 13 78 ec 88 13 78 ec 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 04 00 00 3a 01"),
    (0x81, "24 59 05 00 f6 d7 ff ff c8 af 00 00 f0 49 02 00 18 91 fc ff 80 96 98 00 20 a1 07 00 70 2f fc ff 40 42 0f 00 00 00 00 00 00 00 34 12 00 00 00 04 00 00 3a 01"),
];

const UDD: &[(u8, &str)] = &[
    (0x02, "7b f2 05 2a 01 00 00 00"),
    (0x05, "15 cd 5b 07"),
    (0x07, "ea 88 ff fb 94 11"),
    (0x08, "24 59 05 00 f6 d7 ff ff c8 af 00 00"),
    (0x09, "88 13 78 ec 88 13 78 ec"),
    (0x20, "0f 00 e9 ff e8 03"),
    (0x21, "f0 49 02 00 18 91 fc ff 80 96 98 00"),
    (0x22, "fa 00 83 ff f4 01"),
    (0x23, "20 a1 07 00 70 2f fc ff 40 42 0f 00"),
    (0x2D, "f8 24 01 00 b0 3c ff ff d4 30 00 00"),
    (0x2E, "e8 03 00 00 30 f8 ff ff b8 0b 00 00"),
    (0x2F, "80 84 1e 00 40 39 d2 ff 80 4a 5d 05"),
    (0x91, "48 e8 01 00 90 d0 03 00 c0 bd f0 ff"),
    (0x92, "60 da d9 ff 60 e3 16 00 40 a5 ae 02"),
    (0x50, "d2 04"),
    (0x52, "3a 01"),
    (0x53, "00 04"),
    (0x5B, "01 00"),
];

#[test]
fn every_fixed_format_is_byte_exact() {
    assert_eq!(FIXED.len(), formats::FORMATS.len());
    for (code, want) in FIXED {
        let f = formats::find(*code).unwrap();
        assert_eq!(encode(f.fields, &sample(), "K110"), hex(want), "{}", f.name);
    }
}

#[test]
fn every_udd_type_is_byte_exact() {
    assert_eq!(UDD.len(), udd::UDD_TYPES.len());
    for (code, want) in UDD {
        let t = udd::find(*code).unwrap();
        assert_eq!(
            encode(&[t.field], &sample(), "K110"),
            hex(want),
            "{}",
            t.name
        );
    }
}

#[test]
fn kg_and_ka_follow_the_product_ranges() {
    // G450 (KG 50) / A8 (KA 4000): gyro 1.5 -> 75, acc 0.5 -> 2000.
    let f = formats::find(0x33).unwrap();
    let p = encode(f.fields, &sample(), "KERNEL-110-G450-A8");
    assert_eq!(&p[6..8], &[75, 0]);
    assert_eq!(&p[12..14], &2000i16.to_le_bytes());
    // G950 (KG 20) / A15 (KA 2000).
    let p = encode(f.fields, &sample(), "KERNEL-110-G950-A15");
    assert_eq!(&p[6..8], &30i16.to_le_bytes());
    assert_eq!(&p[12..14], &1000i16.to_le_bytes());
}

#[test]
fn fields_saturate_instead_of_wrapping() {
    let mut s = sample();
    s.gyro = [30_000.0, -30_000.0, f32::NAN];
    s.acc = [5_000.0, -5_000.0, 0.0];
    s.temperature = 10_000.0;
    let ga = encode(formats::find(0x8F).unwrap().fields, &s, "K110");
    assert_eq!(&ga[0..4], &[0xFF, 0xFF, 0xFF, 0x7F]);
    assert_eq!(&ga[4..8], &[0x00, 0x00, 0x00, 0x80]);
    assert_eq!(&ga[8..12], &[0, 0, 0, 0], "NaN encodes as 0");
    assert_eq!(&ga[12..16], &[0xFF, 0xFF, 0xFF, 0x7F]);
    assert_eq!(&ga[16..20], &[0x00, 0x00, 0x00, 0x80]);
    assert_eq!(&ga[30..32], &[0xFF, 0x7F]);
    let o = encode(formats::find(0x33).unwrap().fields, &s, "K110");
    assert_eq!(&o[6..8], &[0xFF, 0x7F]);
    assert_eq!(&o[8..10], &[0x00, 0x80]);
    assert_eq!(&o[12..14], &[0xFF, 0x7F]);
}

#[test]
fn heading_is_reported_in_0_to_360() {
    let mut s = sample();
    s.euler[0] = -90.0;
    let o = encode(formats::find(0x33).unwrap().fields, &s, "K110");
    assert_eq!(&o[0..2], &27000u16.to_le_bytes());
}
