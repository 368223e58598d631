//! Signal processing on the internal-rate tick: the FIR low-pass (ICD 5.6,
//! Table 5.29), the cascade filter (5.8) and the output-variant accumulator
//! (5.3.6), each in float and in fixed point (the integer arithmetic is
//! [`crate::math::fixed`]). Everything is fixed-size and O(1) per tick
//! apart from the FIR, whose cost is (N/2 + 1) multiply-adds per channel.

pub mod cascade;
pub mod fir;
pub mod integrals;
pub mod variant;

pub use cascade::{Cascade, CascadeConfig, SecondOrder};
pub use fir::{Bandwidth, FirBank, FirBankFixed, FirDesign};
pub use variant::{OutputVariant, VariantAccumulator};
