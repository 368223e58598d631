//! The Inertial Sense ISB protocol, the second device personality
//! (the Inertial Sense ISB protocol page, protocol 2.1; the facts the code uses
//! are in `docs/protocol-facts.md` "ISB").
//!
//! [`device::Isb`] is the personality (an IMX-5 in IMU mode on the device
//! shell); beneath it the protocol layer, pure and table-driven:
//! - [`packet`]: header, checksum, encoding, the streaming decoder;
//! - [`did`]: DID numbers and the table of the data sets the emulated
//!   IMX-5 (IMU mode) serves, with the NACK rule, and their fields by
//!   `data_sets.h` name, for hosts;
//! - [`layout`]: [`crate::data_set!`], the one declaration of each data
//!   set's layout and named fields;
//! - [`sets`]: byte layouts of those data sets, status bits, RMC bits and
//!   options, FLASH_CONFIG defaults and checksum (`docs/isb-data-sets.md`);
//! - [`message`]: GET_DATA / SET_DATA / stop requests, ACK / NACK and DATA
//!   encoders;
//! - [`aux_sets`]: SYS_FAULT, GPS1_VERSION, MAG_CAL, GPS1_SIG, IMU3_RAW;
//! - [`rtos`]: RTOS_INFO, the task table; [`can`]: CAN_CONFIG; [`magcal`]:
//!   the magnetometer recalibration behind MAG_CAL;
//! - [`nmea`]: the NMEA commands the vendor tool sends, the `$INFO` reply,
//!   and [`nmea::Input`], the one place every received byte goes;
//! - [`asce`]: the `$ASCE` table and parser; [`nmea_out`]: the sentences
//!   the IMX-5 prints; [`nmea_stream`]: when each is due.

//!
//! The codec façade a host tool needs is [`packet`] (framing), [`message`]
//! (the requests a host sends, the DATA it reads), [`did`] (the data sets and their sizes),
//! [`layout`] (decoding by field name: the field tables and
//! [`layout::read`]), [`sets`] (the data sets' layouts,
//! their typed decoders and the command sets: SYS_CMD, BIT, FLASH_CONFIG),
//! [`nmea`] (the NMEA checksum and commands), and the few items
//! re-exported here; the rest is the
//! personality's insides.

pub mod did;
pub mod layout;
pub mod packet;

#[path = "message.rs"]
mod message_all;
facade! {
    /// The requests a host tool sends (GET_DATA, SET_DATA) and the DATA
    /// it reads; the device's side of them is the personality's.
    pub mod message = message_all {
        encode_data, encode_get, encode_set, GetRequest, MAX_DATA_PAYLOAD,
    }
}

#[path = "nmea.rs"]
mod nmea_all;
facade! {
    /// The NMEA commands the vendor tool sends and the checksum; the
    /// device's input and `$INFO` reply are the personality's.
    pub mod nmea = nmea_all {
        checksum, Command, MAX_BODY,
    }
}

#[path = "sets.rs"]
mod sets_all;
facade! {
    /// The data sets' byte layouts a host tool reads (IMU, PIMU), their
    /// typed decoders, the command sets it writes (SYS_CMD, BIT,
    /// FLASH_CONFIG with its factory image) and the little-endian
    /// accessors; the module's other layouts and status bits are the
    /// personality's.
    pub mod sets = sets_all {
        bit, flash, imu, le, pimu, sys_cmd, Bit, FlashConfig, Imu, Pimu, SystemCommand,
    }
}

internal! {
    mod asce;
    mod aux_sets;
    mod can;
    mod device;
    mod ins;
    mod magcal;
    mod model;
    mod nav;
    mod nav_sets;
    mod nmea_out;
    mod nmea_stream;
    mod rtos;
}

pub use device::{Isb, RX_IDLE_ABANDON_NS};
pub use ins::NavFaults;
pub use model::IMX5;
pub use nav_sets::Ins2;
