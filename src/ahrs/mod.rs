//! Attitude and heading reference: the mounting rotation (ICD Appendix B),
//! initial alignment (5.3.1, 5.7) and attitude propagation. The orientation
//! forms and conversions they use (Appendix C) are [`crate::math::rotation`].

pub mod alignment;
pub mod attitude;
pub mod mounting;

pub use alignment::{AlignConfig, AlignResult, Alignment};
pub use attitude::Attitude;
pub use mounting::Mounting;
