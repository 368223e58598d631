//! The KERNEL's parameters as the signal chain's neutral configuration:
//! which rows of the parameter block (ICD 5.3.7, Table 5.24) set what in a
//! [`ChainConfig`], and the KERNEL codes of the LPF bandwidth (Table 5.24
//! LPF_Bandwidth, Table 5.29) and of the output variant (Output_Variant,
//! Average_Output_Data; 5.3.6).
//!
//! The chain knows nothing of the block: a personality builds its
//! configuration. The factory block maps to exactly
//! [`ChainConfig::defaults`] (a unit test pins it), so the chain a power-on
//! builds before reading any parameter is the one the KERNEL configures.

use super::params::{self, Block};
use crate::ahrs::alignment::AlignConfig;
use crate::chain::ChainConfig;
use crate::dsp::cascade::{CascadeConfig, SecondOrder};
use crate::dsp::fir::Bandwidth;
use crate::dsp::variant::OutputVariant;
use crate::model::Product;

/// The bandwidth of LPF_Bandwidth `code` (Table 5.24; bandwidths Table
/// 5.29): 0 = 16 Hz, 1 = 33 Hz, 2 = 66 Hz, 3 = 131 Hz, 4 = 262 Hz; any other
/// value (0xFF) = off.
pub fn lpf_bandwidth(code: u8) -> Bandwidth {
    match code {
        0 => Bandwidth::Hz16,
        1 => Bandwidth::Hz33,
        2 => Bandwidth::Hz66,
        3 => Bandwidth::Hz131,
        4 => Bandwidth::Hz262,
        _ => Bandwidth::Off,
    }
}

/// The variant of Output_Variant and Average_Output_Data (Table 5.24,
/// 5.3.6): averaged data on forces [`OutputVariant::Average`]; Output_Variant
/// values above 2 read as instant.
pub fn output_variant(output_variant: u8, average_output_data: u8) -> OutputVariant {
    if average_output_data == 1 {
        return OutputVariant::Average;
    }
    match output_variant {
        1 => OutputVariant::Average,
        2 => OutputVariant::Incremental,
        _ => OutputVariant::Instant,
    }
}

/// The chain configuration the parameters of `block` (the live RAM copy,
/// Table 5.24) select for `product`: LPF_Bandwidth, Filter and the Filt1,
/// Filt2 and Tau rows (5.8), Output_Variant and Average_Output_Data
/// (5.3.6), Alignment_Angles (Appendix B), ZUPT, Align_Gyro_STD_Threshold
/// and the AHRS tuning rows (5.7). A float that is not finite reads as its
/// factory default.
pub fn chain_config(block: &Block, product: &Product) -> ChainConfig {
    let f = |id: u16, default: f32| {
        params::find(id)
            .map(|p| p.read_f32(block, 0))
            .filter(|v| v.is_finite())
            .unwrap_or(default)
    };
    let so = |base: u16, omega: f32| SecondOrder {
        zeta_num: f(base, 0.1),
        zeta_den: f(base + 4, 0.7),
        omega: f(base + 8, omega),
    };
    let angle = |i: usize| {
        let v = params::ALIGNMENT_ANGLES.read_f32(block, i);
        if v.is_finite() {
            v
        } else {
            0.0
        }
    };
    ChainConfig {
        internal_rate_hz: product.model.internal_rate_hz,
        lpf: lpf_bandwidth(params::LPF_BANDWIDTH.read_int(block) as u8),
        cascade: CascadeConfig {
            mask: params::FILTER.read_int(block) as u8 & 0x07,
            filt1: so(0x0452, 314.159_27),
            filt2: so(0x045E, 628.318_5),
            tau: f(params::TAU.id, 0.01),
        },
        output_variant: output_variant(
            params::OUTPUT_VARIANT.read_int(block) as u8,
            params::AVERAGE_OUTPUT_DATA.read_int(block) as u8,
        ),
        alignment_angles_deg: [angle(0), angle(1), angle(2)],
        align: AlignConfig {
            zupt: params::ZUPT.read_int(block) == 1,
            std_threshold_dps: f(params::ALIGN_GYRO_STD_THRESHOLD.id, 0.05),
            gyro_noise_rms: f(0x03EE, 0.1),
            gyro_bias_rms: f(0x03FA, 0.1),
            gyro_bias_drift: f(0x03F6, 0.001),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::model::MODELS;

    /// Power-on is unchanged: the chain's own defaults are what the KERNEL's
    /// factory block selects, for every product of every model.
    #[test]
    fn the_factory_block_maps_to_the_chain_defaults() {
        for m in MODELS {
            for &(gyro, accel) in m.products {
                let p = Product {
                    model: &m.model,
                    gyro_range_dps: gyro.full_scale(),
                    accel_range_g: accel.full_scale(),
                };
                let block = params::factory_block(&p);
                assert_eq!(
                    chain_config(&block, &p),
                    ChainConfig::defaults(&p),
                    "{}",
                    m.model.short
                );
            }
        }
    }

    #[test]
    fn lpf_codes_are_table_5_29_bandwidths() {
        let hz = [0u8, 1, 2, 3, 4, 5, 0xFF].map(|c| lpf_bandwidth(c).hz());
        assert_eq!(
            hz,
            [
                Some(16.0),
                Some(33.0),
                Some(66.0),
                Some(131.0),
                Some(262.0),
                None,
                None
            ]
        );
    }
}
