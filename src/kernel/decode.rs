//! Typed decoding of KERNEL data frames on the host (ICD 5.2.1–5.2.8,
//! Tables 5.5–5.15): a frame's payload as `(Field, Value)` pairs, from the
//! same tables the device encodes with — [`super::formats::FORMATS`] for the
//! fixed formats, [`super::udd::UDD_TYPES`] for User Defined Data — and the
//! same field scales ([`Field::read`] beside the writer in
//! [`super::fields`]). Values are in the ICD's units (deg, deg/s, g, °C, V,
//! ns; [`Value`]).
//!
//! No allocation: [`payload`] checks the payload's layout and length once
//! and returns an iterator over its fields — a fixed format's values
//! decoded at once by a decoder specialised for the format (its fields and
//! offsets constants), UDD's field by field.
//!
//! ```
//! use imu_emu::kernel::decode;
//! use imu_emu::kernel::fields::{Field, Scales, Value};
//! // A GA payload (Table 5.7): gyro X = 1 deg/s, acc Z = 1 g, 25.3 °C.
//! let mut p = [0u8; 32];
//! p[0..4].copy_from_slice(&100_000i32.to_le_bytes());
//! p[20..24].copy_from_slice(&1_000_000i32.to_le_bytes());
//! p[30..32].copy_from_slice(&253i16.to_le_bytes());
//! let scales = Scales { kg: 50, ka: 4000 };
//! let mut fields = decode::payload(0x8F, &p, scales).unwrap();
//! assert_eq!(fields.next(), Some((Field::GyroHr, Value::Rate([1.0, 0.0, 0.0]))));
//! assert_eq!(fields.next(), Some((Field::AccHr, Value::Accel([0.0, 0.0, 1.0]))));
//! assert_eq!(fields.last(), Some((Field::Temperature, Value::Celsius(25.3))));
//! ```

use super::fields::{Field, Scales, Value};
use super::formats::{FORMATS, UDD};
use super::frame::{Frame, TYPE_DATA};
use super::udd::UDD_TYPES;

/// The most fields a fixed format has.
const MAX_FIXED: usize = {
    let mut most = 0;
    let mut i = 0;
    while i < FORMATS.len() {
        if FORMATS[i].fields.len() > most {
            most = FORMATS[i].fields.len();
        }
        i += 1;
    }
    most
};

/// The values of a fixed format's fields, in order (the rest unused).
type FixedValues = [Value; MAX_FIXED];

/// The fixed format `FORMATS[I]`, with a decoder specialised for it: its
/// fields and their offsets are constants, so the values of a payload are
/// read by straight-line code (no dispatch on the field a value), all at
/// once when the payload is checked ([`payload`]).
struct Format<const I: usize>;

impl<const I: usize> Format<I> {
    const FIELDS: &'static [Field] = FORMATS[I].fields;
    const LEN: usize = {
        let mut len = 0;
        let mut j = 0;
        while j < Self::FIELDS.len() {
            len += Self::FIELDS[j].size();
            j += 1;
        }
        len
    };

    /// The values of `payload`, which is [`Format::LEN`] bytes long (the
    /// `Reserved` fallbacks are never taken).
    #[inline(always)]
    fn values(payload: &[u8], scales: Scales) -> FixedValues {
        let mut out = [Value::Reserved; MAX_FIXED];
        let mut at = 0;
        let mut j = 0;
        while j < Self::FIELDS.len() {
            let field = Self::FIELDS[j];
            let bytes = payload.get(at..).unwrap_or_default();
            out[j] = field.read(scales, bytes).unwrap_or(Value::Reserved);
            at += field.size();
            j += 1;
        }
        out
    }
}

/// The index in [`FORMATS`] of each data command code's fixed format,
/// [`UDD_INDEX`] for UDD, [`NOT_DATA`] for the others: built at compile
/// time, one load and one dispatch a frame ([`payload`]).
static FORMAT_OF: [u8; 256] = {
    let mut t = [NOT_DATA; 256];
    let mut i = 0;
    while i < FORMATS.len() {
        t[FORMATS[i].code as usize] = i as u8;
        i += 1;
    }
    t[UDD as usize] = UDD_INDEX;
    t
};

/// [`FORMAT_OF`] of UDD.
const UDD_INDEX: u8 = FORMATS.len() as u8;
/// [`FORMAT_OF`] of a code that is no data command.
const NOT_DATA: u8 = u8::MAX;

/// [`by_index`] for the indices `$i` of [`FORMATS`], every one of them
/// (checked at compile time): one specialised decoder an index.
macro_rules! fixed_formats {
    ($($i:literal)*) => {
        const _: () = assert!([$($i),*].len() == FORMATS.len());

        /// [`payload`] of data command `id`, whose [`FORMAT_OF`] is
        /// `index`: fixed format `FORMATS[index]` (its values decoded if
        /// `payload` has its length), UDD or none.
        #[inline(always)]
        fn by_index(
            index: u8,
            id: u8,
            payload: &[u8],
            scales: Scales,
        ) -> Result<Fields<'_>, DecodeError> {
            let (fields, values) = match index {
                $($i => (
                    Format::<$i>::FIELDS,
                    (payload.len() == Format::<$i>::LEN)
                        .then(|| Format::<$i>::values(payload, scales))
                        .ok_or(DecodeError::Length {
                            expected: Format::<$i>::LEN,
                            got: payload.len(),
                        })?,
                ),)*
                UDD_INDEX => return udd(payload, scales),
                _ => return Err(DecodeError::UnknownId(id)),
            };
            Ok(Fields {
                kinds: Kinds::Fixed(fields, values, 0),
                data: &[],
                scales,
            })
        }
    };
}

fixed_formats!(0 1 2 3 4 5 6);

/// The field of each UDD type code, built from [`UDD_TYPES`] at compile
/// time.
static UDD_FIELD: [Option<Field>; 256] = {
    let mut t = [None; 256];
    let mut i = 0;
    while i < UDD_TYPES.len() {
        t[UDD_TYPES[i].code as usize] = Some(UDD_TYPES[i].field);
        i += 1;
    }
    t
};

/// The size of each UDD type code's field (0: not a UDD type), built from
/// [`UDD_TYPES`] at compile time.
static UDD_SIZE: [u8; 256] = {
    let mut t = [0; 256];
    let mut i = 0;
    while i < UDD_TYPES.len() {
        t[UDD_TYPES[i].code as usize] = UDD_TYPES[i].field.size() as u8;
        i += 1;
    }
    t
};

/// The field of UDD type `code` (Table 5.15), if it is one.
#[inline]
pub fn udd_field(code: u8) -> Option<Field> {
    UDD_FIELD[usize::from(code)]
}

/// Why a payload could not be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeError {
    /// The frame is not of message type 1 (data, Table 5.2).
    NotData(u8),
    /// The identifier is neither a fixed format nor UDD (Table 5.16).
    UnknownId(u8),
    /// A UDD payload without its header: empty, N = 0, or shorter than
    /// `1 + N` (Table 5.13).
    UddHeader,
    /// A UDD type code not in Table 5.15.
    UnknownUddType(u8),
    /// The payload is not as long as its layout says.
    Length {
        /// Length the layout gives.
        expected: usize,
        /// Length received.
        got: usize,
    },
}

// The fixed variant holds its values (no heap to box them in): a `Fields`
// lives on the stack of the loop that decodes a frame.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
enum Kinds<'a> {
    /// A fixed format's fields, their values decoded, the next one's index.
    Fixed(&'static [Field], FixedValues, usize),
    Udd(core::slice::Iter<'a, u8>),
}

/// The fields of one payload in order, with their values (see
/// [`payload`]).
#[derive(Debug, Clone)]
pub struct Fields<'a> {
    kinds: Kinds<'a>,
    data: &'a [u8],
    scales: Scales,
}

impl Iterator for Fields<'_> {
    type Item = (Field, Value);

    #[inline]
    fn next(&mut self) -> Option<(Field, Value)> {
        match &mut self.kinds {
            Kinds::Fixed(fields, values, at) => {
                let field = *fields.get(*at)?;
                let value = *values.get(*at)?;
                *at += 1;
                Some((field, value))
            }
            Kinds::Udd(it) => {
                let code = usize::from(*it.next()?);
                // The layout was checked by `payload`: these cannot fail.
                let field = UDD_FIELD[code]?;
                let (bytes, rest) = self.data.split_at_checked(usize::from(UDD_SIZE[code]))?;
                self.data = rest;
                Some((field, field.read(self.scales, bytes)?))
            }
        }
    }
}

/// The fields of the payload of data command `id` (a fixed format of
/// Tables 5.5–5.12, or UDD, Table 5.13: `N`, `N` type codes, their fields),
/// after checking its layout and exact length. `scales` are the product's
/// KG and KA (Table 5.6), used by the 16-bit gyro and accelerometer fields.
#[inline]
pub fn payload(id: u8, payload: &[u8], scales: Scales) -> Result<Fields<'_>, DecodeError> {
    by_index(FORMAT_OF[usize::from(id)], id, payload, scales)
}

/// [`payload`] of UDD (Table 5.13).
#[inline(always)]
fn udd(payload: &[u8], scales: Scales) -> Result<Fields<'_>, DecodeError> {
    let (&n, rest) = payload.split_first().ok_or(DecodeError::UddHeader)?;
    let n = usize::from(n);
    if n == 0 || rest.len() < n {
        return Err(DecodeError::UddHeader);
    }
    let (types, data) = rest.split_at(n);
    let mut expected = 0;
    for &c in types {
        match UDD_SIZE[usize::from(c)] {
            0 => return Err(DecodeError::UnknownUddType(c)),
            size => expected += usize::from(size),
        }
    }
    if data.len() != expected {
        return Err(DecodeError::Length {
            expected: 1 + n + expected,
            got: payload.len(),
        });
    }
    Ok(Fields {
        kinds: Kinds::Udd(types.iter()),
        data,
        scales,
    })
}

/// [`payload`] of a decoded data frame ([`super::frame::Decoder`]).
#[inline]
pub fn frame<'a>(frame: &Frame<'a>, scales: Scales) -> Result<Fields<'a>, DecodeError> {
    if frame.msg_type != TYPE_DATA {
        return Err(DecodeError::NotData(frame.msg_type));
    }
    payload(frame.id, frame.payload, scales)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::fields::{
        sat_i16, sat_i32, sat_u16, write_all, OutputCtx, ACC_HR_SCALE, ANGLE_HR_SCALE, ANGLE_SCALE,
        QUAT_SCALE, RATE_HR_SCALE, TEMPERATURE_SCALE, VOLTAGE_SCALE,
    };
    use crate::kernel::frame::{encode, Decoder};
    use crate::model::Product;
    use crate::sensor::Sample;
    use std::vec::Vec;

    struct Rng(u64);
    impl Rng {
        fn u64(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
        /// Mostly in-range values, some beyond every field's range.
        fn f32(&mut self, range: f32) -> f32 {
            let u = (self.u64() >> 40) as f32 / (1u64 << 24) as f32; // [0, 1)
            let x = (u * 2.0 - 1.0) * range;
            if self.u64().is_multiple_of(16) {
                x * 1e4
            } else {
                x
            }
        }
        fn v3(&mut self, range: f32) -> [f32; 3] {
            [self.f32(range), self.f32(range), self.f32(range)]
        }
    }

    fn sample(r: &mut Rng) -> Sample {
        Sample {
            gyro: r.v3(500.0),
            acc: r.v3(10.0),
            aux_acc: r.v3(40.0),
            euler: [r.f32(180.0) + 180.0, r.f32(90.0), r.f32(180.0)],
            quat: [r.f32(1.0), r.f32(1.0), r.f32(1.0), r.f32(1.0)],
            gyro_filtered: r.v3(500.0),
            gyro_bias: r.v3(1.0),
            acc_filtered: r.v3(10.0),
            aux_acc_filtered: r.v3(40.0),
            temperature: r.f32(80.0),
            supply_voltage: r.f32(30.0) + 30.0,
        }
    }

    /// What `field` must decode to after the device wrote `s` with `ctx`:
    /// the writer's integer over its scale.
    fn expected(field: Field, ctx: &OutputCtx<'_>, sc: Scales) -> Value {
        let s = ctx.sample;
        let hr = |v: &[f32; 3], k: u32| v.map(|x| f64::from(sat_i32(x, k)) / f64::from(k));
        let lo = |v: &[f32; 3], k: u32| v.map(|x| f64::from(sat_i16(x, k)) / f64::from(k));
        match field {
            Field::Euler => Value::Angles([
                f64::from(crate::kernel::fields::heading_code(s.euler[0], ANGLE_SCALE)) / 100.0,
                f64::from(sat_i16(s.euler[1], ANGLE_SCALE)) / 100.0,
                f64::from(sat_i16(s.euler[2], ANGLE_SCALE)) / 100.0,
            ]),
            Field::EulerHr => Value::Angles([
                f64::from(crate::kernel::fields::heading_code(
                    s.euler[0],
                    ANGLE_HR_SCALE,
                )) / 1000.0,
                f64::from(sat_i32(s.euler[1], ANGLE_HR_SCALE)) / 1000.0,
                f64::from(sat_i32(s.euler[2], ANGLE_HR_SCALE)) / 1000.0,
            ]),
            Field::Quat => {
                Value::Quat(s.quat.map(|q| f64::from(sat_i16(q, QUAT_SCALE)) / 10_000.0))
            }
            Field::Gyro => Value::Rate(lo(&s.gyro, sc.kg)),
            Field::Acc => Value::Accel(lo(&s.acc, sc.ka)),
            Field::GyroHr => Value::Rate(hr(&s.gyro, RATE_HR_SCALE)),
            Field::GyroBiasCompHr => Value::Rate(hr(&s.gyro_filtered, RATE_HR_SCALE)),
            Field::GyroBiasHr => Value::Rate(hr(&s.gyro_bias, RATE_HR_SCALE)),
            Field::AccHr => Value::Accel(hr(&s.acc, ACC_HR_SCALE)),
            Field::AuxAccHr => Value::Accel(hr(&s.aux_acc, ACC_HR_SCALE)),
            Field::FilteredAccHr => Value::Accel(hr(&s.acc_filtered, ACC_HR_SCALE)),
            Field::FilteredAuxAccHr => Value::Accel(hr(&s.aux_acc_filtered, ACC_HR_SCALE)),
            Field::Zero(_) => Value::Reserved,
            Field::Usw => Value::Word(ctx.usw),
            Field::UswExt => Value::Word(ctx.usw_ext),
            Field::Counter => Value::Word(ctx.counter),
            Field::TimeFlags => Value::Word(ctx.time_flags),
            Field::Temperature => {
                Value::Celsius(f64::from(sat_i16(s.temperature, TEMPERATURE_SCALE)) / 10.0)
            }
            Field::SecondFraction => Value::Nanos(u64::from(ctx.second_fraction_ns)),
            Field::ImuTime => Value::Nanos(ctx.imu_time_ns),
            Field::SupplyVoltage => {
                Value::Volts(f64::from(sat_u16(s.supply_voltage, VOLTAGE_SCALE)) / 100.0)
            }
        }
    }

    /// Writes `value` back as the wire integers (the inverse of `read`).
    fn rewrite(field: Field, value: Value, sc: Scales, out: &mut Vec<u8>) {
        let round = |x: f64, k: u32| (x * f64::from(k)).round() as i64;
        let put = |out: &mut Vec<u8>, v: &[f64], k: u32, wide: bool| {
            for &x in v {
                let r = round(x, k);
                if wide {
                    out.extend_from_slice(&(r as i32).to_le_bytes());
                } else {
                    out.extend_from_slice(&(r as i16).to_le_bytes());
                }
            }
        };
        match (field, value) {
            (Field::Euler, Value::Angles(a)) => {
                out.extend_from_slice(&(round(a[0], ANGLE_SCALE) as u16).to_le_bytes());
                put(out, &a[1..], ANGLE_SCALE, false);
            }
            (Field::EulerHr, Value::Angles(a)) => put(out, &a, ANGLE_HR_SCALE, true),
            (Field::Quat, Value::Quat(q)) => put(out, &q, QUAT_SCALE, false),
            (Field::Gyro, Value::Rate(v)) => put(out, &v, sc.kg, false),
            (Field::Acc, Value::Accel(v)) => put(out, &v, sc.ka, false),
            (Field::GyroHr | Field::GyroBiasCompHr | Field::GyroBiasHr, Value::Rate(v)) => {
                put(out, &v, RATE_HR_SCALE, true)
            }
            (
                Field::AccHr | Field::AuxAccHr | Field::FilteredAccHr | Field::FilteredAuxAccHr,
                Value::Accel(v),
            ) => put(out, &v, ACC_HR_SCALE, true),
            (Field::Zero(n), Value::Reserved) => out.extend(core::iter::repeat_n(0, n.into())),
            (Field::Usw | Field::UswExt | Field::Counter | Field::TimeFlags, Value::Word(w)) => {
                out.extend_from_slice(&w.to_le_bytes())
            }
            (Field::Temperature, Value::Celsius(t)) => {
                out.extend_from_slice(&(round(t, TEMPERATURE_SCALE) as i16).to_le_bytes())
            }
            (Field::SecondFraction, Value::Nanos(n)) => {
                out.extend_from_slice(&(n as u32).to_le_bytes())
            }
            (Field::ImuTime, Value::Nanos(n)) => out.extend_from_slice(&n.to_le_bytes()),
            (Field::SupplyVoltage, Value::Volts(v)) => {
                out.extend_from_slice(&(round(v, VOLTAGE_SCALE) as u16).to_le_bytes())
            }
            (f, v) => panic!("{f:?} decoded as {v:?}"),
        }
    }

    /// Every fixed format and every UDD type (alone, and all of them in one
    /// configuration), for the product ranges of Table 5.6: what the writer
    /// wrote decodes to its integers over their scales.
    #[test]
    fn every_format_and_udd_type_decodes_what_the_encoder_wrote() {
        let mut r = Rng(0x9E37_79B9_7F4A_7C15);
        let mut layouts: Vec<(u8, Vec<u8>, Vec<Field>)> = FORMATS
            .iter()
            .map(|f| (f.code, Vec::new(), f.fields.to_vec()))
            .collect();
        for t in UDD_TYPES {
            layouts.push((UDD, std::vec![1, t.code], std::vec![t.field]));
        }
        let all: Vec<u8> = UDD_TYPES.iter().map(|t| t.code).take(16).collect();
        let mut header = std::vec![all.len() as u8];
        header.extend_from_slice(&all);
        layouts.push((
            UDD,
            header,
            all.iter().map(|&c| udd_field(c).unwrap()).collect(),
        ));
        for model in ["K100", "K110-G950-A15", "K120-G2000-A40A90"] {
            let product = Product::parse(model).unwrap();
            let sc = Scales::of(&product);
            for _ in 0..2000 {
                let s = sample(&mut r);
                let ctx = OutputCtx {
                    sample: &s,
                    product: &product,
                    counter: r.u64() as u16,
                    usw: r.u64() as u16,
                    usw_ext: r.u64() as u16,
                    time_flags: r.u64() as u16,
                    second_fraction_ns: r.u64() as u32,
                    imu_time_ns: r.u64(),
                };
                for (code, header, fields) in &layouts {
                    let mut p = header.clone();
                    let at = p.len();
                    p.resize(at + crate::kernel::fields::payload_len(fields), 0xEE);
                    assert_eq!(write_all(fields, &ctx, &mut p[at..]), Some(p.len() - at));
                    let got: Vec<(Field, Value)> = payload(*code, &p, sc).unwrap().collect();
                    let want: Vec<(Field, Value)> =
                        fields.iter().map(|&f| (f, expected(f, &ctx, sc))).collect();
                    assert_eq!(got, want, "{model} {code:#x} {header:?}");
                    // And the values give the bytes back.
                    let mut again = header.clone();
                    for (f, v) in got {
                        rewrite(f, v, sc, &mut again);
                    }
                    assert_eq!(again, p, "{model} {code:#x}");
                }
            }
        }
    }

    /// Arbitrary payload bytes: decoding then writing the values back gives
    /// the same bytes (the decoded values are exact), every format and type.
    #[test]
    fn arbitrary_payload_bytes_round_trip_through_the_values() {
        let mut r = Rng(7);
        let sc = Scales { kg: 20, ka: 2000 };
        for _ in 0..3000 {
            for f in FORMATS {
                let mut p: Vec<u8> = (0..f.payload_len()).map(|_| r.u64() as u8).collect();
                // Reserved bytes decode to nothing: they are zero on the wire.
                let mut at = 0;
                for field in f.fields {
                    if let Field::Zero(n) = field {
                        p[at..at + usize::from(*n)].fill(0);
                    }
                    at += field.size();
                }
                let mut again = Vec::new();
                for (field, v) in payload(f.code, &p, sc).unwrap() {
                    rewrite(field, v, sc, &mut again);
                }
                assert_eq!(again, p, "{:#x}", f.code);
            }
            for t in UDD_TYPES {
                let mut p = std::vec![1, t.code];
                p.extend((0..t.field.size()).map(|_| r.u64() as u8));
                let mut again = std::vec![1, t.code];
                for (field, v) in payload(UDD, &p, sc).unwrap() {
                    rewrite(field, v, sc, &mut again);
                }
                assert_eq!(again, p, "{:#x}", t.code);
            }
        }
    }

    /// A GA frame computed by hand (Table 5.7): gyro 1, −2.5, 0.00001 deg/s
    /// (100 000, −250 000, 1), acc 0, 0.5, −1 g (0, 500 000, −1 000 000),
    /// counter 0x1234, USW 0x0100, reserved, 25.3 °C (253); checksum
    /// 0x09F0 (the bytes from type to the last payload byte sum to 2544).
    #[test]
    fn a_hand_computed_ga_frame() {
        let bytes = [
            0xAA, 0x55, 0x01, 0x8F, 0x26, 0x00, // header, len 38
            0xA0, 0x86, 0x01, 0x00, // 100 000
            0x70, 0x2F, 0xFC, 0xFF, // −250 000
            0x01, 0x00, 0x00, 0x00, // 1
            0x00, 0x00, 0x00, 0x00, // 0
            0x20, 0xA1, 0x07, 0x00, // 500 000
            0xC0, 0xBD, 0xF0, 0xFF, // −1 000 000
            0x34, 0x12, // counter
            0x00, 0x01, // USW
            0x00, 0x00, // reserved
            0xFD, 0x00, // 253
            0xF0, 0x09, // checksum
        ];
        let mut d = Decoder::<64>::new();
        let mut input = &bytes[..];
        let f = d.next_frame(&mut input).unwrap();
        let got: Vec<_> = frame(&f, Scales { kg: 50, ka: 4000 }).unwrap().collect();
        assert_eq!(
            got,
            [
                (Field::GyroHr, Value::Rate([1.0, -2.5, 0.00001])),
                (Field::AccHr, Value::Accel([0.0, 0.5, -1.0])),
                (Field::Counter, Value::Word(0x1234)),
                (Field::Usw, Value::Word(0x0100)),
                (Field::Zero(2), Value::Reserved),
                (Field::Temperature, Value::Celsius(25.3)),
            ]
        );
    }

    /// An Orientation payload by hand (Table 5.5, K100: KG 50, KA 4000):
    /// heading 359.99° (35 999), pitch −45° (−4500), roll 0.01° (1), gyro
    /// 1, −1, 655.34 deg/s (50, −50, 32 767), acc 1 g (4000), −0.25 g
    /// (−1000), 0; temperature −40 °C (−400).
    #[test]
    fn a_hand_computed_orientation_payload() {
        let p = [
            0x9F, 0x8C, 0x6C, 0xEE, 0x01, 0x00, // 35 999, −4500, 1
            0x32, 0x00, 0xCE, 0xFF, 0xFF, 0x7F, // 50, −50, 32 767
            0xA0, 0x0F, 0x18, 0xFC, 0x00, 0x00, // 4000, −1000, 0
            0, 0, 0, 0, 0, 0, 0, 0, 0, 0, // mag, reserved 4
            0x00, 0x00, 0, 0, // USW, reserved
            0x70, 0xFE, // −400
        ];
        let got: Vec<_> = payload(0x33, &p, Scales { kg: 50, ka: 4000 })
            .unwrap()
            .filter(|(_, v)| *v != Value::Reserved)
            .collect();
        assert_eq!(
            got,
            [
                (Field::Euler, Value::Angles([359.99, -45.0, 0.01])),
                (Field::Gyro, Value::Rate([1.0, -1.0, 655.34])),
                (Field::Acc, Value::Accel([1.0, -0.25, 0.0])),
                (Field::Usw, Value::Word(0)),
                (Field::Temperature, Value::Celsius(-40.0)),
            ]
        );
    }

    /// A UDD payload by hand (Table 5.13): N = 3, types 0x02 (IMU time),
    /// 0x50 (supply voltage), 0x08 (HR angles); 1.5 s, 12.34 V, heading
    /// 90.5°, pitch −0.001°, roll 180°.
    #[test]
    fn a_hand_computed_udd_payload() {
        let p = [
            0x03, 0x02, 0x50, 0x08, // N, types
            0x00, 0x2F, 0x68, 0x59, 0, 0, 0, 0, // 1 500 000 000 ns
            0xD2, 0x04, // 1234
            0x84, 0x61, 0x01, 0x00, // 90 500
            0xFF, 0xFF, 0xFF, 0xFF, // −1
            0x20, 0xBF, 0x02, 0x00, // 180 000
        ];
        let got: Vec<_> = payload(UDD, &p, Scales { kg: 50, ka: 4000 })
            .unwrap()
            .collect();
        assert_eq!(
            got,
            [
                (Field::ImuTime, Value::Nanos(1_500_000_000)),
                (Field::SupplyVoltage, Value::Volts(12.34)),
                (Field::EulerHr, Value::Angles([90.5, -0.001, 180.0])),
            ]
        );
    }

    /// The bits of a value (`f64` compared bit for bit, `-0.0` ≠ `0.0`).
    fn value_bits(v: Value) -> Vec<u64> {
        match v {
            Value::Angles(a) | Value::Rate(a) | Value::Accel(a) => a.map(f64::to_bits).to_vec(),
            Value::Quat(q) => q.map(f64::to_bits).to_vec(),
            Value::Celsius(x) | Value::Volts(x) => std::vec![x.to_bits(), 1],
            Value::Word(w) => std::vec![u64::from(w), 2],
            Value::Nanos(n) => std::vec![n, 3],
            Value::Reserved => std::vec![4],
        }
    }

    /// The specialised decoders of the fixed formats give, bit for bit,
    /// what [`Field::read`] gives field by field, for arbitrary payload
    /// bytes and every product's scales; a field's read needs all its
    /// bytes.
    #[test]
    fn the_fixed_format_decoders_are_the_field_reads() {
        let mut r = Rng(0x0123_4567_89AB_CDEF);
        for sc in [
            Scales { kg: 50, ka: 4000 },
            Scales { kg: 20, ka: 2000 },
            Scales { kg: 10, ka: 500 },
            Scales { kg: 1, ka: 7 },
        ] {
            for _ in 0..2000 {
                for f in FORMATS {
                    let p: Vec<u8> = (0..f.payload_len()).map(|_| r.u64() as u8).collect();
                    let got: Vec<_> = payload(f.code, &p, sc)
                        .unwrap()
                        .map(|(field, v)| (field, value_bits(v)))
                        .collect();
                    let mut want = Vec::new();
                    let mut at = 0;
                    for &field in f.fields {
                        let v = field.read(sc, &p[at..]).unwrap();
                        want.push((field, value_bits(v)));
                        at += field.size();
                    }
                    assert_eq!(got, want, "{:#x}", f.code);
                }
            }
        }
        let bytes = [0x5Au8; 16];
        let sc = Scales { kg: 50, ka: 4000 };
        let every = FORMATS.iter().flat_map(|f| f.fields.iter().copied());
        for field in every.chain(UDD_TYPES.iter().map(|t| t.field)) {
            let n = field.size();
            assert_eq!(field.read(sc, &bytes[..n - 1]), None, "{field:?}");
            assert!(field.read(sc, &bytes[..n]).is_some(), "{field:?}");
        }
    }

    #[test]
    fn bad_layouts_are_refused() {
        let sc = Scales { kg: 50, ka: 4000 };
        let e = |id, p: &[u8]| payload(id, p, sc).err();
        assert_eq!(
            e(0x8F, &[0; 31]),
            Some(DecodeError::Length {
                expected: 32,
                got: 31
            })
        );
        assert_eq!(e(0x90, &[0; 32]), Some(DecodeError::UnknownId(0x90)));
        assert_eq!(e(UDD, &[]), Some(DecodeError::UddHeader));
        assert_eq!(e(UDD, &[0]), Some(DecodeError::UddHeader));
        assert_eq!(e(UDD, &[2, 0x52]), Some(DecodeError::UddHeader));
        assert_eq!(
            e(UDD, &[1, 0x03, 0, 0]),
            Some(DecodeError::UnknownUddType(0x03))
        );
        assert_eq!(
            e(UDD, &[1, 0x52, 0]),
            Some(DecodeError::Length {
                expected: 4,
                got: 3
            })
        );
        let mut out = [0u8; 16];
        let n = encode(0, 0x8F, &[], &mut out).unwrap();
        let mut d = Decoder::<64>::new();
        let mut input = &out[..n];
        let f = d.next_frame(&mut input).unwrap();
        assert_eq!(frame(&f, sc).err(), Some(DecodeError::NotData(0)));
    }
}
