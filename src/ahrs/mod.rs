//! Attitude and heading reference: orientation forms and conversions
//! (ICD Appendix C), the mounting rotation (Appendix B), initial alignment
//! (5.3.1, 5.7) and attitude propagation.

pub mod alignment;
pub mod attitude;
pub mod mounting;
pub mod rotation;

pub use alignment::{AlignConfig, AlignResult, Alignment};
pub use attitude::Attitude;
pub use mounting::Mounting;
