//! KERNEL output frames decoded into named values, from the core's own
//! tables: the fixed formats ([`imu_emu::kernel::formats::FORMATS`], ICD
//! Tables 5.5–5.12), the UDD types ([`imu_emu::kernel::udd::UDD_TYPES`],
//! Tables 5.13–5.15) and the fields' scaling
//! ([`imu_emu::kernel::fields::Field`]).
//!
//! (A typed decoder in the core, `imu_emu::kernel::decode`, is on its way;
//! the client switches to it when it lands. This module is the client's
//! stop-gap and stays small.)

use imu_emu::kernel::fields::Field;
use imu_emu::kernel::{formats, udd};
use imu_emu::model::Product;

/// One decoded frame: its identifier and `(column, value)` pairs in
/// payload order (physical units: deg/s, g, deg, °C, V, ns).
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// Message identifier (format code).
    pub id: u8,
    /// Columns and values.
    pub values: Vec<(&'static str, f64)>,
}

impl Decoded {
    /// The value of `column`, if the frame has it.
    pub fn get(&self, column: &str) -> Option<f64> {
        self.values.iter().find(|(c, _)| *c == column).map(|v| v.1)
    }
}

fn i16_at(p: &[u8], i: usize) -> f64 {
    f64::from(i16::from_le_bytes([p[i], p[i + 1]]))
}
fn u16_at(p: &[u8], i: usize) -> f64 {
    f64::from(u16::from_le_bytes([p[i], p[i + 1]]))
}
fn i32_at(p: &[u8], i: usize) -> f64 {
    f64::from(i32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]))
}

/// Column names and value of each item of `field` (none for reserved
/// bytes), scaled to physical units.
fn field_values(field: Field, p: &[u8], product: &Product, out: &mut Vec<(&'static str, f64)>) {
    let triad = |names: [&'static str; 3], k: f64, wide: bool, out: &mut Vec<_>| {
        for (i, n) in names.into_iter().enumerate() {
            let v = if wide {
                i32_at(p, 4 * i)
            } else {
                i16_at(p, 2 * i)
            };
            out.push((n, v / k));
        }
    };
    let kg = f64::from(product.gyro.kg());
    let ka = f64::from(product.accel.ka());
    match field {
        Field::Euler => {
            out.push(("heading", u16_at(p, 0) / 100.0));
            out.push(("pitch", i16_at(p, 2) / 100.0));
            out.push(("roll", i16_at(p, 4) / 100.0));
        }
        Field::EulerHr => triad(["heading", "pitch", "roll"], 1000.0, true, out),
        Field::Quat => {
            for (i, n) in ["q0", "q1", "q2", "q3"].into_iter().enumerate() {
                out.push((n, i16_at(p, 2 * i) / 10_000.0));
            }
        }
        Field::Gyro => triad(["gyro_x", "gyro_y", "gyro_z"], kg, false, out),
        Field::GyroHr => triad(["gyro_x", "gyro_y", "gyro_z"], 1e5, true, out),
        Field::Acc => triad(["acc_x", "acc_y", "acc_z"], ka, false, out),
        Field::AccHr => triad(["acc_x", "acc_y", "acc_z"], 1e6, true, out),
        Field::AuxAccHr => triad(["aux_acc_x", "aux_acc_y", "aux_acc_z"], 1e6, true, out),
        Field::GyroBiasCompHr => triad(["gyro_bc_x", "gyro_bc_y", "gyro_bc_z"], 1e5, true, out),
        Field::GyroBiasHr => triad(
            ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"],
            1e5,
            true,
            out,
        ),
        Field::FilteredAccHr => triad(["acc_f_x", "acc_f_y", "acc_f_z"], 1e6, true, out),
        Field::FilteredAuxAccHr => triad(
            ["aux_acc_f_x", "aux_acc_f_y", "aux_acc_f_z"],
            1e6,
            true,
            out,
        ),
        Field::Zero(_) => {}
        Field::Usw => out.push(("usw", u16_at(p, 0))),
        Field::UswExt => out.push(("usw_ext", u16_at(p, 0))),
        Field::Counter => out.push(("counter", u16_at(p, 0))),
        Field::Temperature => out.push(("temp_c", i16_at(p, 0) / 10.0)),
        Field::TimeFlags => out.push(("time_flags", u16_at(p, 0))),
        Field::SecondFraction => out.push((
            "second_fraction_ns",
            f64::from(u32::from_le_bytes([p[0], p[1], p[2], p[3]])),
        )),
        Field::ImuTime => {
            let mut b = [0u8; 8];
            b.copy_from_slice(&p[..8]);
            out.push(("imu_time_ns", u64::from_le_bytes(b) as f64));
        }
        Field::SupplyVoltage => out.push(("supply_v", u16_at(p, 0) / 100.0)),
    }
}

/// Decodes `fields` laid out in order in `payload`; `None` if the payload
/// is not exactly their size.
fn decode_fields(
    fields: &[Field],
    payload: &[u8],
    product: &Product,
) -> Option<Vec<(&'static str, f64)>> {
    let mut values = Vec::new();
    let mut at = 0;
    for &f in fields {
        let n = f.size();
        field_values(f, payload.get(at..at + n)?, product, &mut values);
        at += n;
    }
    (at == payload.len()).then_some(values)
}

/// Decodes a data frame's payload (`id` = format code; UDD frames carry
/// their own type list, Table 5.13). `None` for an unknown identifier or
/// a payload whose size does not match its layout. `product` gives the
/// KG/KA scale factors of the low-resolution fields (Table 5.6).
pub fn decode(id: u8, payload: &[u8], product: &Product) -> Option<Decoded> {
    let values = if id == formats::UDD {
        let n = usize::from(*payload.first()?);
        let types = payload.get(1..1 + n)?;
        let fields: Option<Vec<Field>> = types
            .iter()
            .map(|&t| udd::find(t).map(|u| u.field))
            .collect();
        decode_fields(&fields?, &payload[1 + n..], product)?
    } else {
        decode_fields(formats::find(id)?.fields, payload, product)?
    };
    Some(Decoded { id, values })
}

/// A format named by its Table 5.4 name (any case: `GA`, `gam`,
/// `quaternion`, `udd`) or its code (`0x8F`, `8f`, `143`).
pub fn format_code(s: &str) -> Option<u8> {
    if s.eq_ignore_ascii_case("udd") {
        return Some(formats::UDD);
    }
    if let Some(f) = formats::FORMATS.iter().find(|f| {
        f.name.eq_ignore_ascii_case(s) || f.name.replace(' ', "-").eq_ignore_ascii_case(s)
    }) {
        return Some(f.code);
    }
    let code = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u8::from_str_radix(h, 16).ok()?,
        None => s
            .parse::<u8>()
            .ok()
            .or_else(|| u8::from_str_radix(s, 16).ok())?,
    };
    formats::is_data_command(code).then_some(code)
}

/// The name of format `code` (`GA`, `UDD`), or its hex code.
pub fn format_name(code: u8) -> String {
    if code == formats::UDD {
        return "UDD".to_owned();
    }
    formats::find(code).map_or_else(|| format!("{code:#04x}"), |f| f.name.to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_codes() {
        assert_eq!(format_code("GA"), Some(0x8F));
        assert_eq!(format_code("gaam"), Some(0xA6));
        assert_eq!(format_code("calibrated-hr"), Some(0x81));
        assert_eq!(format_code("0x33"), Some(0x33));
        assert_eq!(format_code("udd"), Some(0x95));
        assert_eq!(format_code("0x12"), None);
        assert_eq!(format_name(0x8F), "GA");
    }

    #[test]
    fn ga_payload_decodes_to_units() {
        let p = Product::parse("K110").unwrap();
        let mut payload = Vec::new();
        for v in [100_000i32, -250_000, 0, 1_000_000, 0, -500_000] {
            payload.extend_from_slice(&v.to_le_bytes());
        }
        payload.extend_from_slice(&40u16.to_le_bytes());
        payload.extend_from_slice(&0u16.to_le_bytes());
        payload.extend_from_slice(&[0, 0]);
        payload.extend_from_slice(&253i16.to_le_bytes());
        let d = decode(0x8F, &payload, &p).unwrap();
        assert_eq!(d.get("gyro_x"), Some(1.0));
        assert_eq!(d.get("gyro_y"), Some(-2.5));
        assert_eq!(d.get("acc_x"), Some(1.0));
        assert_eq!(d.get("acc_z"), Some(-0.5));
        assert_eq!(d.get("counter"), Some(40.0));
        assert_eq!(d.get("temp_c"), Some(25.3));
        assert!(decode(0x8F, &payload[1..], &p).is_none());
        // UDD: N, types, data.
        let mut u = vec![2, 0x52, 0x53];
        u.extend_from_slice(&(-15i16).to_le_bytes());
        u.extend_from_slice(&7u16.to_le_bytes());
        let d = decode(0x95, &u, &p).unwrap();
        assert_eq!(d.values, [("temp_c", -1.5), ("usw", 7.0)]);
    }
}
