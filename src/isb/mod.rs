//! The Inertial Sense ISB protocol, the second device personality
//! (the Inertial Sense ISB protocol page, protocol 2.1; the facts the code uses
//! are in `docs/protocol-facts.md` "ISB").
//!
//! [`device::Isb`] is the personality (an IMX-5 in IMU mode on the device
//! shell); beneath it the protocol layer, pure and table-driven:
//! - [`packet`]: header, checksum, encoding, the streaming decoder;
//! - [`did`]: DID numbers and the table of the data sets the emulated
//!   IMX-5 (IMU mode) serves, with the NACK rule;
//! - [`sets`]: byte layouts of those data sets, status bits, RMC bits and
//!   options, FLASH_CONFIG defaults and checksum (`docs/isb-data-sets.md`);
//! - [`message`]: GET_DATA / SET_DATA / stop requests, ACK / NACK and DATA
//!   encoders;
//! - [`aux_sets`]: SYS_FAULT, GPS1_VERSION, MAG_CAL, GPS1_SIG, IMU3_RAW;
//! - [`fields`]: the data sets' fields by `data_sets.h` name, for hosts;
//! - [`nmea`]: the NMEA commands the vendor tool sends, the `$INFO` reply,
//!   and [`nmea::Input`], the one place every received byte goes;
//! - [`asce`]: the `$ASCE` table and parser; [`nmea_out`]: the sentences
//!   the IMX-5 prints; [`nmea_stream`]: when each is due.

pub mod asce;
pub mod aux_sets;
pub mod device;
pub mod did;
pub mod fields;
pub mod ins;
pub mod layout;
pub mod message;
pub mod model;
pub mod nav;
pub mod nav_sets;
pub mod nmea;
pub mod nmea_out;
pub mod nmea_stream;
pub mod packet;
pub mod sets;

pub use device::Isb;
pub use model::IMX5;
