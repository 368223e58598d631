//! The KERNEL protocol personality (ICD section 5, Appendix A).

pub mod block;
pub mod command;
pub mod config;
pub mod decode;
pub mod device;
pub mod fields;
pub mod formats;
pub mod frame;
pub mod model;
pub mod params;
pub mod rate;
pub mod status;
pub mod udd;

pub use device::{Kernel, KernelDevice, MAX_FRAME, RX_FRAME_CAP, RX_IDLE_ABANDON_NS};
pub use model::{Capability, ProductError, MODELS};
