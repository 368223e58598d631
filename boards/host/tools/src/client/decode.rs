//! KERNEL output frames as named columns: the values come from the core's
//! typed decoder ([`imu_emu::kernel::decode`], ICD Tables 5.5–5.15, the
//! same tables and scales the device encodes with); this module only names
//! them for the client's CSV / JSON rows and maps format names to codes
//! (Table 5.4).

use imu_emu::kernel::decode as kernel;
use imu_emu::kernel::formats;
use imu_emu::kernel::frame::{Decoder, TYPE_DATA};
use imu_emu::kernel::{Field, Scales, Value};
use imu_emu::model::Product;

/// The IMU channels: gyro X Y Z (°/s), acc X Y Z (g), and on the
/// K120/K220 the aux accelerometer X Y Z (g): the column names of the
/// KERNEL's frames (`client record`), the order `imu-emu allan` reads them
/// in.
pub const AXES: [&str; 9] = [
    "gyro_x",
    "gyro_y",
    "gyro_z",
    "acc_x",
    "acc_y",
    "acc_z",
    "aux_acc_x",
    "aux_acc_y",
    "aux_acc_z",
];

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

/// The client's column names of `field`'s items (none for reserved bytes).
fn columns(field: Field) -> &'static [&'static str] {
    match field {
        Field::Euler | Field::EulerHr => &["heading", "pitch", "roll"],
        Field::Quat => &["q0", "q1", "q2", "q3"],
        Field::Gyro | Field::GyroHr => &["gyro_x", "gyro_y", "gyro_z"],
        Field::Acc | Field::AccHr => &["acc_x", "acc_y", "acc_z"],
        Field::AuxAccHr => &["aux_acc_x", "aux_acc_y", "aux_acc_z"],
        Field::GyroBiasCompHr => &["gyro_bc_x", "gyro_bc_y", "gyro_bc_z"],
        Field::GyroBiasHr => &["gyro_bias_x", "gyro_bias_y", "gyro_bias_z"],
        Field::FilteredAccHr => &["acc_f_x", "acc_f_y", "acc_f_z"],
        Field::FilteredAuxAccHr => &["aux_acc_f_x", "aux_acc_f_y", "aux_acc_f_z"],
        Field::Zero(_) => &[],
        Field::Usw => &["usw"],
        Field::UswExt => &["usw_ext"],
        Field::Counter => &["counter"],
        Field::Temperature => &["temp_c"],
        Field::TimeFlags => &["time_flags"],
        Field::SecondFraction => &["second_fraction_ns"],
        Field::ImuTime => &["imu_time_ns"],
        Field::SupplyVoltage => &["supply_v"],
    }
}

/// Decodes a data frame's payload (`id` = format code; UDD frames carry
/// their own type list, Table 5.13) with [`kernel::payload`]. `None` for
/// an unknown identifier or a payload the core refuses (layout or length).
/// `product` gives the KG/KA scale factors of the low-resolution fields
/// (Table 5.6).
pub fn decode(id: u8, payload: &[u8], product: &Product) -> Option<Decoded> {
    let mut values = Vec::new();
    for (field, value) in kernel::payload(id, payload, Scales::of(product)).ok()? {
        let items: &[f64] = match &value {
            Value::Angles(v) | Value::Rate(v) | Value::Accel(v) => v,
            Value::Quat(v) => v,
            Value::Reserved => &[],
            Value::Word(w) => &[f64::from(*w)],
            Value::Celsius(x) | Value::Volts(x) => &[*x],
            Value::Nanos(n) => &[*n as f64],
        };
        values.extend(columns(field).iter().copied().zip(items.iter().copied()));
    }
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

/// The IMU samples of a raw KERNEL capture (`imu-emu allan --input`):
/// the first data format with gyro and accelerometer values sets the
/// stream (GA, GAm, GAA, GAAm, Orientation, Calibrated HR, or a UDD with
/// gyro and acc types; the aux accelerometer too when the format has it),
/// frames of other formats are skipped; each sample timed by the frames'
/// own clock ([`super::DeviceClock`]: the UDD's IMU time, else the 2 kHz
/// counter of GA and Calibrated HR). `product` gives the KG/KA scales of
/// the low-resolution fields (Table 5.6).
pub fn imu_samples(bytes: &[u8], product: &Product) -> super::tool_protocol::ImuSamples {
    let mut rx = Box::new(Decoder::<4096>::new());
    let mut input = bytes;
    let mut stream: Option<(u8, usize)> = None;
    let mut clock = super::DeviceClock::default();
    let mut rows = Vec::new();
    let mut skipped = 0usize;
    while let Some(f) = rx.next_frame(&mut input) {
        let d = (f.msg_type == TYPE_DATA)
            .then(|| decode(f.id, f.payload, product))
            .flatten();
        let Some(d) = d else {
            skipped += 1;
            continue;
        };
        // Gyro and acc, and the aux accelerometer when the format has it.
        let has = |names: &[&str]| names.iter().all(|n| d.get(n).is_some());
        if stream.is_none() && has(&AXES[..6]) {
            stream = Some((f.id, if has(&AXES) { 9 } else { 6 }));
        }
        let Some((_, channels)) = stream.filter(|s| s.0 == f.id) else {
            skipped += 1;
            continue;
        };
        if !has(&AXES[..channels]) {
            skipped += 1;
            continue;
        }
        let y = AXES[..channels]
            .iter()
            .map(|n| d.get(n).unwrap_or(0.0))
            .collect();
        rows.push((y, clock.time(&d)));
    }
    let name = stream.map_or("none".to_owned(), |(id, _)| {
        formats::find(id).map_or_else(|| "UDD".to_owned(), |f| f.name.to_owned())
    });
    super::tool_protocol::ImuSamples {
        rows,
        what: format!("KERNEL {name} frames, {skipped} other frames skipped"),
    }
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
