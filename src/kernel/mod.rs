//! The KERNEL protocol personality (ICD section 5, Appendix A).
//!
//! The codec façade a host tool needs: [`frame`] (framing: encode, the
//! streaming decoder), [`command`] (the commands), [`params`] (the
//! parameter table, 5.24), [`decode`] (typed values of every format and
//! UDD type; [`Field`], [`Value`]), [`formats`] (the format table),
//! [`rate`] (Formula 5.1), [`model`] (the models and product codes); the personality [`Kernel`]. The rest is the
//! personality's insides.

pub mod command;
pub mod decode;
pub mod formats;
pub mod frame;
pub mod model;

#[path = "params.rs"]
mod params_all;
facade! {
    /// The parameter table (ICD 5.24) a host tool reads and writes by
    /// name or ID, the baud-rate codes and the factory block; the named
    /// rows the device applies are the personality's.
    pub mod params = params_all {
        baud_rate, factory_block, find, Apply, Block, DefaultValue, Kind, ParamError,
        ParamSpec, Rule, BAUD_RATE, BAUD_RATES, DATA_RATE, PARAMS,
    }
}
pub mod rate;

internal! {
    mod block;
    mod config;
    mod device;
    mod fields;
    mod status;
    mod udd;
}

pub use device::{Kernel, KernelDevice, MAX_FRAME, RX_FRAME_CAP, RX_IDLE_ABANDON_NS};
pub use fields::{Field, Scales, Value};
pub use model::{Capability, ProductError, MODELS};
