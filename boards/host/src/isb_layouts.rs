//! `imu-emu isb-layouts [--json]`: the layouts of the ISB data sets the
//! emulated IMX-5 serves, from the one declaration of each
//! (`imu_emu::isb::did::DATA_SETS` and the `data_set!` field tables): DID,
//! name, C struct, size and the named fields (offset, kind, unit).
//! `scripts/isb-layouts.py` writes the Python table
//! (`python/imu_emu/isb_layouts.py`) and the layout part of
//! `docs/isb-data-sets.md` from the JSON form; `python/tests` checks the
//! committed copies against it.

use std::fmt::Write as _;

use imu_emu::isb::did::{DataSet, DATA_SETS};

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

/// `{"data_sets": [...]}`, one set a line, in table order.
pub fn to_json(sets: &[DataSet]) -> String {
    let mut o = String::from("{\"data_sets\": [\n");
    for (i, s) in sets.iter().enumerate() {
        let fields: Vec<String> = s
            .fields
            .iter()
            .map(|f| {
                format!(
                    "{{\"name\": {}, \"offset\": {}, \"kind\": {}, \"unit\": {}}}",
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
    fn text_lists_each_set_then_its_fields() {
        let t = to_text(&DATA_SETS);
        assert!(t.starts_with("1 DEV_INFO dev_info_t (84 B)\n     2 u8     hardwareType\n"));
        assert!(t.contains("58 IMU imu_t (36 B)\n     0 f64    time s\n     8 u32    status\n"));
        assert!(t.contains("17 GPS1_VERSION gps_version_t (220 B)\n19 MAG_CAL"));
    }
}
