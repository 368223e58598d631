//! The parameter block (ICD 5.3.7 Table 5.24, cleaned in
//! `docs/protocol-facts.md`) — every
//! parameter is one row of [`PARAMS`].
//!
//! A parameter ID is the byte offset of the parameter in the device's
//! parameter block ([`BLOCK_LEN`] bytes); the block is stored whole in flash
//! by [`crate::store`]. Each row gives the length, type, default, validation
//! rule and *when a saved value reaches the running device* ([`Apply`]).

use crate::kernel::model::{self, Capability};
use crate::model::Product;

pub use super::block::{Block, BLOCK_LEN, UDD_CONFIG_OFFSET, UDD_MAX_TYPES};

/// Value type of a parameter (Table 5.24 "Value").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Byte.
    U8,
    /// Word (u16, LSB first).
    U16,
    /// IEEE-754 single, LSB first.
    F32,
    /// Three singles (Alignment_Angles).
    F32x3,
}

impl Kind {
    /// Length in bytes, as carried in SaveFlash/ReadRAM (Table 5.23/5.25).
    pub const fn byte_len(self) -> u16 {
        match self {
            Kind::U8 => 1,
            Kind::U16 => 2,
            Kind::F32 => 4,
            Kind::F32x3 => 12,
        }
    }
}

/// Factory default of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DefaultValue {
    /// An integer (written with the row's width).
    Int(u32),
    /// A float (or each of three floats for [`Kind::F32x3`]).
    Float(f32),
}

/// Validation of a value written by SaveFlash.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// Any value of the type.
    Any,
    /// An integer in `lo..=hi`.
    Range(u32, u32),
    /// Data_Rate: ≥ 1 Hz and a divisor of the internal rate (ICD 5.5).
    DivisorOfInternalRate,
    /// Alignment_Angles: heading −180..180, pitch −90..90, roll −180..180 (App. B).
    AlignmentAngles,
    /// A finite float ≥ 0.
    NonNegative,
    /// A finite float > 0.
    Positive,
    /// Auto_Start: 0, or a data command code the model runs (Table 5.16).
    AutoStart,
    /// LPF_Bandwidth: one of the model's codes (Table 5.24, K201 note).
    Lpf,
    /// 0 or 1; 1 needs `cap` and must not be on at the same time as the
    /// parameter `exclusive_with` (TOV and EXTRIG share a pin budget, 4.1.3).
    Switch {
        /// Capability the model needs to turn it on.
        cap: Option<Capability>,
        /// ID of the parameter that must be 0 to turn this one on.
        exclusive_with: Option<u16>,
    },
    /// Read-only: SaveFlash is refused (Sensors_Measurement_Range).
    ReadOnly,
    /// Reserved, not supported by KERNEL: SaveFlash is refused (IMU-P_Interface).
    Unsupported,
}

/// When a value saved by SaveFlash reaches the running device (RAM).
///
/// The ICD asks for a power cycle after SaveFlash "to ensure all modified
/// parameters are correctly applied" but leaves the rest open; the emulator
/// decides (docs/kernel.md "Protocol notes"):
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Apply {
    /// At once if the device is idle; while it streams or aligns, at the
    /// next data command or Stop (the running stream keeps the settings it
    /// started with). Host drivers save output settings while idle and then
    /// restart the stream expecting the new value.
    NextStream,
    /// Only on CommitBaudRate (5.3.9) or at power-on (Baud_Rate).
    CommitOrPowerCycle,
    /// Never written (read-only or unsupported).
    Never,
}

/// One row of Table 5.24.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Name as printed in Table 5.24.
    pub name: &'static str,
    /// ID = offset in the block.
    pub id: u16,
    /// Value type (gives the length).
    pub kind: Kind,
    /// Factory default.
    pub default: DefaultValue,
    /// Validation.
    pub rule: Rule,
    /// When a saved value reaches RAM.
    pub apply: Apply,
}

const fn row(
    name: &'static str,
    id: u16,
    kind: Kind,
    default: DefaultValue,
    rule: Rule,
) -> ParamSpec {
    let apply = match rule {
        Rule::ReadOnly | Rule::Unsupported => Apply::Never,
        _ => Apply::NextStream,
    };
    ParamSpec {
        name,
        id,
        kind,
        default,
        rule,
        apply,
    }
}

use DefaultValue::{Float, Int};
use Kind::*;

/// Data_Rate, Hz. Default 100 Hz: fits every fixed format at the default
/// 115200 bps (Table 5.28 gives ≥ 125 Hz for all).
pub const DATA_RATE: ParamSpec = row(
    "Data_Rate",
    0x0012,
    U16,
    Int(100),
    Rule::DivisorOfInternalRate,
);
/// Initial_Alignment_Time, s. Default 2 s per ICD 5.3.1 (Table 5.24 says 0:
/// erratum, the prose wins); 30 s is "the largest possible value" (5.3.1).
pub(crate) const INITIAL_ALIGNMENT_TIME: ParamSpec = row(
    "Initial_Alignment_Time",
    0x0014,
    U16,
    Int(2),
    Rule::Range(0, 30),
);
/// Alignment_Angles: heading, pitch, roll in degrees (Appendix B).
pub const ALIGNMENT_ANGLES: ParamSpec = row(
    "Alignment_Angles",
    0x023A,
    F32x3,
    Float(0.0),
    Rule::AlignmentAngles,
);
/// Sensors_Measurement_Range (read-only; set from the product code).
pub(crate) const SENSORS_MEASUREMENT_RANGE: ParamSpec = row(
    "Sensors_Measurement_Range",
    0x028F,
    U8,
    Int(0),
    Rule::ReadOnly,
);
/// Auto_Start: 0 off, else a Table 5.16 format code (section 6).
pub(crate) const AUTO_START: ParamSpec = row("Auto_Start", 0x03A9, U8, Int(0), Rule::AutoStart);
/// Baud_Rate code 0x00..0x10 (see [`baud_rate`]).
pub const BAUD_RATE: ParamSpec = ParamSpec {
    apply: Apply::CommitOrPowerCycle,
    ..row("Baud_Rate", 0x03B2, U8, Int(0), Rule::Range(0, 0x10))
};
/// Output_Variant: 0 instant, 1 average, 2 incremental (5.3.6).
pub const OUTPUT_VARIANT: ParamSpec = row("Output_Variant", 0x03D0, U8, Int(0), Rule::Range(0, 2));
/// LPF_Bandwidth: 0=16, 1=33, 2=66, 3=131, 4=262 Hz, 0xFF off (5.6).
/// Default 4 (262 Hz): the shortest FIR delay, available on every model.
pub const LPF_BANDWIDTH: ParamSpec = row("LPF_Bandwidth", 0x03D7, U8, Int(4), Rule::Lpf);
/// Min_Vinp_Threshold, VDC·100.
pub(crate) const MIN_VINP_THRESHOLD: ParamSpec =
    row("Min_Vinp_Threshold", 0x03DA, U16, Int(400), Rule::Any);
/// Max_Vinp_Threshold, VDC·100.
pub(crate) const MAX_VINP_THRESHOLD: ParamSpec =
    row("Max_Vinp_Threshold", 0x03DC, U16, Int(3000), Rule::Any);
/// Average_Output_Data: 0 instant, 1 averaged.
pub const AVERAGE_OUTPUT_DATA: ParamSpec =
    row("Average_Output_Data", 0x03E1, U8, Int(0), Rule::Range(0, 1));
/// TOV_Control: 0 off, 1 TOV output on (4.1.4); exclusive with EXTRIG.
pub(crate) const TOV_CONTROL: ParamSpec = row(
    "TOV_Control",
    0x0499,
    U8,
    Int(0),
    Rule::Switch {
        cap: None,
        exclusive_with: Some(0x05FA),
    },
);
/// Trigger_Control: 0 off, 1 EXTRIG on (4.1.3); only on EXTRIG models.
pub(crate) const TRIGGER_CONTROL: ParamSpec = row(
    "Trigger_Control",
    0x05FA,
    U8,
    Int(0),
    Rule::Switch {
        cap: Some(Capability::Extrig),
        exclusive_with: Some(0x0499),
    },
);
/// Polarity of EXTRIG: 0 negative (default), 1 positive.
pub(crate) const POLARITY: ParamSpec = row("Polarity", 0x05FB, U8, Int(0), Rule::Range(0, 1));
/// Hold-off_Time, ms.
pub(crate) const HOLD_OFF_TIME: ParamSpec = row("Hold-off_Time", 0x05FE, U16, Int(0), Rule::Any);
/// Motion_Type (AHRS tuning).
pub(crate) const MOTION_TYPE: ParamSpec = row("Motion_Type", 0x0412, U8, Int(0), Rule::Any);
/// ZUPT: 0 averaging, 1 Kalman-filter alignment (5.7).
pub const ZUPT: ParamSpec = row("ZUPT", 0x0413, U8, Int(0), Rule::Range(0, 1));
/// Align_Gyro_STD_Threshold, °/s (5.7).
pub(crate) const ALIGN_GYRO_STD_THRESHOLD: ParamSpec = row(
    "Align_Gyro_STD_Threshold",
    0x0414,
    F32,
    Float(0.05),
    Rule::NonNegative,
);
/// Filter mask: 0x01 Filter1², 0x02 Filter2², 0x04 Filter3 (5.8).
pub const FILTER: ParamSpec = row("Filter", 0x0451, U8, Int(0), Rule::Range(0, 7));
/// Tau of Filter3, s.
pub(crate) const TAU: ParamSpec = row("Tau", 0x046A, F32, Float(0.01), Rule::Positive);

/// Every parameter of Table 5.24.
pub static PARAMS: &[ParamSpec] = &[
    DATA_RATE,
    INITIAL_ALIGNMENT_TIME,
    ALIGNMENT_ANGLES,
    SENSORS_MEASUREMENT_RANGE,
    AUTO_START,
    BAUD_RATE,
    OUTPUT_VARIANT,
    LPF_BANDWIDTH,
    MIN_VINP_THRESHOLD,
    MAX_VINP_THRESHOLD,
    AVERAGE_OUTPUT_DATA,
    row("Gyro_Noise_RMS", 0x03EE, F32, Float(0.1), Rule::NonNegative),
    row(
        "Gyro_Scale_Factor_Error",
        0x03F2,
        F32,
        Float(0.001),
        Rule::NonNegative,
    ),
    row(
        "Gyro_Bias_Drift",
        0x03F6,
        F32,
        Float(0.001),
        Rule::NonNegative,
    ),
    row("Gyro_Bias_RMS", 0x03FA, F32, Float(0.1), Rule::NonNegative),
    row(
        "Accels_Noise_RMS",
        0x0406,
        F32,
        Float(0.001),
        Rule::NonNegative,
    ),
    row(
        "Accel_Dynamic_Gain",
        0x040A,
        F32,
        Float(1.0),
        Rule::NonNegative,
    ),
    row("Dynamic_LPF", 0x040E, F32, Float(1.0), Rule::NonNegative),
    MOTION_TYPE,
    ZUPT,
    ALIGN_GYRO_STD_THRESHOLD,
    FILTER,
    row("Filt1_Dzeta1", 0x0452, F32, Float(0.1), Rule::NonNegative),
    row("Filt1_Dzeta2", 0x0456, F32, Float(0.7), Rule::NonNegative),
    row("Filt1_W", 0x045A, F32, Float(314.159_27), Rule::Positive),
    row("Filt2_Dzeta1", 0x045E, F32, Float(0.1), Rule::NonNegative),
    row("Filt2_Dzeta2", 0x0462, F32, Float(0.7), Rule::NonNegative),
    row("Filt2_W", 0x0466, F32, Float(628.318_5), Rule::Positive),
    TAU,
    row("IMU-P_Interface", 0x0496, U8, Int(0), Rule::Unsupported),
    TOV_CONTROL,
    TRIGGER_CONTROL,
    POLARITY,
    HOLD_OFF_TIME,
];

/// Line rates of the Baud_Rate codes 0x00..=0x10 (Table 5.24).
pub const BAUD_RATES: [u32; 17] = [
    115_200, 4_800, 9_600, 14_400, 19_200, 38_400, 57_600, 115_200, 230_400, 460_800, 921_600,
    2_000_000, 375_000, 1_843_200, 3_686_400, 1_000_000, 4_000_000,
];

/// Line rate in bit/s of a Baud_Rate code (115200 for an out-of-range code).
pub fn baud_rate(code: u8) -> u32 {
    BAUD_RATES
        .get(usize::from(code))
        .copied()
        .unwrap_or(BAUD_RATES[0])
}

/// Why SaveFlash refused a value (the device answers nothing, 5.3.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamError {
    /// No parameter has this ID.
    UnknownId,
    /// The length field is not the parameter's length.
    WrongLength,
    /// The value breaks the parameter's rule.
    BadValue,
    /// The parameter cannot be written.
    ReadOnly,
}

/// The row of a parameter ID.
pub fn find(id: u16) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.id == id)
}

impl ParamSpec {
    /// Length in bytes.
    pub const fn byte_len(&self) -> u16 {
        self.kind.byte_len()
    }

    /// Byte range of the parameter in the block.
    pub fn range(&self) -> core::ops::Range<usize> {
        let start = usize::from(self.id);
        start..start + usize::from(self.byte_len())
    }

    /// The parameter's bytes in `block`.
    pub fn bytes<'b>(&self, block: &'b Block) -> &'b [u8] {
        &block[self.range()]
    }

    /// Reads an integer parameter (U8/U16) from `block`.
    pub fn read_int(&self, block: &Block) -> u32 {
        let b = self.bytes(block);
        match self.kind {
            U8 => u32::from(b[0]),
            _ => u32::from(u16::from_le_bytes([b[0], b[1]])),
        }
    }

    /// Reads float number `i` of a float parameter from `block` (out of
    /// line: configuration code, several callers).
    #[inline(never)]
    pub fn read_f32(&self, block: &Block, i: usize) -> f32 {
        let at = usize::from(self.id) + 4 * i;
        match block.get(at..at + 4) {
            Some(b) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            None => 0.0,
        }
    }

    /// Writes the factory default into `block`.
    pub fn write_default(&self, block: &mut Block) {
        let r = self.range();
        match (self.kind, self.default) {
            (U8, Int(v)) => block[r.start] = v as u8,
            (U16, Int(v)) => block[r].copy_from_slice(&(v as u16).to_le_bytes()),
            (F32 | F32x3, Float(v)) => {
                for c in block[r].chunks_mut(4) {
                    c.copy_from_slice(&v.to_le_bytes());
                }
            }
            (_, _) => block[r].fill(0),
        }
    }

    /// Checks `value` (the SaveFlash value bytes, already of the right
    /// length) for `product`, given the other parameters in `block`.
    pub fn validate(
        &self,
        value: &[u8],
        product: &Product,
        block: &Block,
    ) -> Result<(), ParamError> {
        if value.len() != usize::from(self.byte_len()) {
            return Err(ParamError::WrongLength);
        }
        let int = || match self.kind {
            U8 => u32::from(value[0]),
            _ => u32::from(u16::from_le_bytes([value[0], value[1]])),
        };
        let float = |i: usize| {
            f32::from_le_bytes([
                value[4 * i],
                value[4 * i + 1],
                value[4 * i + 2],
                value[4 * i + 3],
            ])
        };
        let ok = match self.rule {
            Rule::ReadOnly | Rule::Unsupported => return Err(ParamError::ReadOnly),
            Rule::Any => true,
            Rule::Range(lo, hi) => (lo..=hi).contains(&int()),
            Rule::DivisorOfInternalRate => {
                let v = int();
                v >= 1 && product.model.internal_rate_hz.is_multiple_of(v)
            }
            Rule::AlignmentAngles => {
                let (h, p, r) = (float(0), float(1), float(2));
                (-180.0..=180.0).contains(&h)
                    && (-90.0..=90.0).contains(&p)
                    && (-180.0..=180.0).contains(&r)
            }
            Rule::NonNegative => {
                let v = float(0);
                v.is_finite() && v >= 0.0
            }
            Rule::Positive => {
                let v = float(0);
                v.is_finite() && v > 0.0
            }
            Rule::AutoStart => {
                let v = int();
                v == 0 || product.model.supports_format(v as u8)
            }
            Rule::Lpf => model::row(product.model).lpf_codes.contains(&(int() as u8)),
            Rule::Switch {
                cap,
                exclusive_with,
            } => match int() {
                0 => true,
                1 => {
                    cap.is_none_or(|c| product.model.has(c))
                        && exclusive_with
                            .and_then(find)
                            .is_none_or(|other| other.read_int(block) == 0)
                }
                _ => false,
            },
        };
        if ok {
            Ok(())
        } else {
            Err(ParamError::BadValue)
        }
    }
}

/// The factory block for `product`: every default, the measurement range,
/// and the default UDD configuration.
pub fn factory_block(product: &Product) -> Block {
    let mut block = [0u8; BLOCK_LEN];
    for p in PARAMS {
        p.write_default(&mut block);
    }
    set_product_facts(&mut block, product);
    crate::kernel::udd::write_config(&mut block, crate::kernel::udd::DEFAULT_CONFIG);
    block
}

/// Writes what the product fixes (the read-only measurement range).
pub(crate) fn set_product_facts(block: &mut Block, product: &Product) {
    block[usize::from(SENSORS_MEASUREMENT_RANGE.id)] = product.measurement_range();
}

/// Repairs a block read from flash for `product`: every parameter that does
/// not validate (e.g. flash written by another model) gets its default.
pub(crate) fn sanitize(block: &mut Block, product: &Product) {
    for p in PARAMS {
        if matches!(p.rule, Rule::ReadOnly | Rule::Unsupported) {
            continue;
        }
        let mut value = [0u8; 12];
        let v = &mut value[..usize::from(p.byte_len())];
        v.copy_from_slice(p.bytes(block));
        if p.validate(v, product, block).is_err() {
            p.write_default(block);
        }
    }
    set_product_facts(block, product);
    if crate::kernel::udd::read_config(block, product).is_none() {
        crate::kernel::udd::write_config(block, crate::kernel::udd::DEFAULT_CONFIG);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_do_not_overlap_and_fit_the_block() {
        for (i, a) in PARAMS.iter().enumerate() {
            assert!(a.range().end <= BLOCK_LEN, "{}", a.name);
            assert!(
                a.range().end <= UDD_CONFIG_OFFSET
                    || a.range().start > UDD_CONFIG_OFFSET + UDD_MAX_TYPES
            );
            for b in &PARAMS[i + 1..] {
                let overlap = a.range().start < b.range().end && b.range().start < a.range().end;
                assert!(!overlap, "{} overlaps {}", a.name, b.name);
            }
        }
    }

    #[test]
    fn every_default_validates_on_every_model() {
        for m in crate::kernel::model::MODELS {
            let product = Product::parse(m.model.short).unwrap();
            let block = factory_block(&product);
            for p in PARAMS {
                if matches!(p.rule, Rule::ReadOnly | Rule::Unsupported) {
                    continue;
                }
                assert_eq!(
                    p.validate(p.bytes(&block), &product, &block),
                    Ok(()),
                    "{} on {}",
                    p.name,
                    m.model.short
                );
            }
        }
    }
}
