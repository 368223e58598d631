//! `imu-emu isb-layouts [--json]`: the layouts of the ISB data sets the
//! emulated IMX-5 serves, from the one declaration of each
//! (`imu_emu::isb::did::DATA_SETS` and the `data_set!` field tables): DID,
//! name, C struct, size and the named fields (offset, kind, unit; for
//! FLASH_CONFIG also each field's factory value, read from the factory
//! image the emulated unit restores).
//! `scripts/isb-layouts.py` writes the Python table
//! (`python/imu_emu/isb_layouts.py`) and the layout part of
//! `docs/isb-data-sets.md` from the JSON form; `python/tests` checks the
//! committed copies against it.

use std::fmt::Write as _;

use imu_emu::isb::did::{self, DataSet, DATA_SETS};
use imu_emu::isb::layout::{self, FieldSpec, Kind, Value};
use imu_emu::isb::sets::FlashConfig;

/// `isb-layouts`: JSON (one data set a line) or a text table on stdout.
pub fn run(json: bool) -> anyhow::Result<()> {
    let out = if json {
        to_json(&DATA_SETS)
    } else {
        to_text(&DATA_SETS)
    };
    // A closed pipe (`| head`) is not an error.
    match std::io::Write::write_all(&mut std::io::stdout(), out.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// A JSON string literal of `s`.
fn quoted(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// The image a set starts from when the unit has one to restore: the
/// factory FLASH_CONFIG.
fn factory_image(did: u8) -> Option<Vec<u8>> {
    (did == did::FLASH_CONFIG).then(|| FlashConfig::factory().0.to_vec())
}

/// `field`'s value in `image` as the docs write it: integers in decimal
/// (bit words and the checksum also in hex), floats at their own
/// precision.
fn value_text(field: &FieldSpec, image: &[u8]) -> String {
    let float = |x: f64| match field.kind {
        // An f32 at the digits that round-trip it, not its f64 widening.
        Kind::F32 | Kind::F32x3 | Kind::F32x4 => format!("{}", x as f32),
        _ => format!("{x}"),
    };
    match layout::read(field, image) {
        Value::Unsigned(n) if n != 0 && is_bit_word(field.name) => format!("{n} (0x{n:X})"),
        Value::Unsigned(n) => n.to_string(),
        Value::Float(x) => float(x),
        Value::Vec3(v) => v.map(float).join(", "),
        Value::Vec4(v) => v.map(float).join(", "),
        Value::Version(v) => v.map(|b| b.to_string()).join("."),
        Value::Text(b, n) => String::from_utf8_lossy(&b[..n]).into_owned(),
    }
}

/// Whether a field is read as bits (`sysCfgBits`, `ioConfig`, …) or is
/// the checksum: its value is clearer in hex.
fn is_bit_word(name: &str) -> bool {
    name.ends_with("Bits") || name.ends_with("Config") || name == "checksum"
}

/// `{"data_sets": [...]}`, one set a line, in table order.
pub fn to_json(sets: &[DataSet]) -> String {
    let mut o = String::from("{\"data_sets\": [\n");
    for (i, s) in sets.iter().enumerate() {
        let image = factory_image(s.did);
        let fields: Vec<String> = s
            .fields
            .iter()
            .map(|f| {
                let factory = image
                    .as_deref()
                    .map(|b| format!(", \"factory\": {}", quoted(&value_text(f, b))))
                    .unwrap_or_default();
                format!(
                    "{{\"name\": {}, \"offset\": {}, \"kind\": {}, \"unit\": {}{factory}}}",
                    quoted(f.name),
                    f.offset,
                    quoted(f.kind.name()),
                    quoted(f.unit)
                )
            })
            .collect();
        let _ = writeln!(
            o,
            "{{\"did\": {}, \"name\": {}, \"struct\": {}, \"size\": {}, \"fields\": [{}]}}{}",
            s.did,
            quoted(s.did_name),
            quoted(s.name),
            s.size,
            fields.join(", "),
            if i + 1 < sets.len() { "," } else { "" }
        );
    }
    o.push_str("]}\n");
    o
}

/// One block a set: `DID NAME struct (size B)`, then `offset kind name unit`.
pub fn to_text(sets: &[DataSet]) -> String {
    let mut o = String::new();
    for s in sets {
        let _ = writeln!(o, "{} {} {} ({} B)", s.did, s.did_name, s.name, s.size);
        for f in s.fields {
            let line = format!(
                "  {:>4} {:<6} {} {}",
                f.offset,
                f.kind.name(),
                f.name,
                f.unit
            );
            let _ = writeln!(o, "{}", line.trim_end());
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_names_every_set_and_escapes() {
        let j = to_json(&DATA_SETS);
        assert_eq!(j.lines().count(), DATA_SETS.len() + 2);
        assert!(j.contains(
            "{\"did\": 58, \"name\": \"IMU\", \"struct\": \"imu_t\", \"size\": 36, \"fields\": [{\"name\": \"time\", \"offset\": 0, \"kind\": \"f64\", \"unit\": \"s\"}"
        ));
        assert_eq!(quoted("a\"b\\c\n"), "\"a\\\"b\\\\c\\u000a\"");
    }

    #[test]
    fn flash_config_fields_carry_the_factory_values() {
        let j = to_json(&DATA_SETS);
        let line = j.lines().find(|l| l.contains("\"FLASH_CONFIG\"")).unwrap();
        for want in [
            "{\"name\": \"startupNavDtMs\", \"offset\": 16, \"kind\": \"u32\", \"unit\": \"ms\", \"factory\": \"4\"}",
            "\"name\": \"ioConfig\", \"offset\": 132, \"kind\": \"u32\", \"unit\": \"\", \"factory\": \"70 (0x46)\"}",
            "\"name\": \"gpsMinimumElevation\", \"offset\": 200, \"kind\": \"f32\", \"unit\": \"rad\", \"factory\": \"0.17453292\"}",
            "\"name\": \"gnssCn0Minimum\", \"offset\": 276, \"kind\": \"u8\", \"unit\": \"dBHz\", \"factory\": \"30\"}",
        ] {
            assert!(line.contains(want), "{want} not in {line}");
        }
        // Sets without a factory image have no such key.
        let imu = j.lines().find(|l| l.contains("\"imu_t\"")).unwrap();
        assert!(!imu.contains("factory"), "{imu}");
    }

    #[test]
    fn text_lists_each_set_then_its_fields() {
        let t = to_text(&DATA_SETS);
        assert!(t.starts_with("1 DEV_INFO dev_info_t (84 B)\n     2 u8     hardwareType\n"));
        assert!(t.contains("58 IMU imu_t (36 B)\n     0 f64    time s\n     8 u32    status\n"));
        assert!(t.contains("17 GPS1_VERSION gps_version_t (220 B)\n19 MAG_CAL"));
    }
}
