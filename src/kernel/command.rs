//! Host → device commands (ICD 5.3, Table A.1, Tables 5.22–5.25): typed,
//! parsed from and encoded to the payload of a `type 0, id 0` frame.

use super::frame::{self, TYPE_COMMAND};

/// SaveFlash command ID (payload bytes `B2 FF`, Table 5.23).
pub const SAVE_FLASH: u16 = 0xFFB2;
/// ReadRAM command ID (payload bytes `B1 FF`, Table 5.25).
pub const READ_RAM: u16 = 0xFFB1;
/// Stop (5.3.2).
pub const STOP: u8 = 0xFE;
/// GetDevInfo (5.3.3).
pub const GET_DEV_INFO: u8 = 0x12;
/// GetBIT (5.3.4).
pub const GET_BIT: u8 = 0x1A;
/// User_Def_Data_config (5.3.5).
pub const UDD_CONFIG: u8 = 0x96;
/// Get_User_Def_Data_struct (5.3.5).
pub const GET_UDD_STRUCT: u8 = 0x97;
/// CommitBaudRate (5.3.9).
pub const COMMIT_BAUD_RATE: u8 = 0xC2;
/// Vendor INS SDK "device parameters" request (`docs/protocol-facts.md`; not in the ICD).
pub const DEVICE_PARAMETERS: u8 = 0x41;

/// A command, borrowing value bytes from the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command<'a> {
    /// A data command (Table 5.16): 0x33 0x8F 0x9B 0xA5 0xA6 0x82 0x81 0x95.
    Data(u8),
    /// Stop.
    Stop,
    /// GetDevInfo.
    GetDevInfo,
    /// GetBIT.
    GetBit,
    /// User_Def_Data_config: the configuration message follows.
    UddConfig,
    /// The configuration message (Table 5.19 payload `N, list…`), with or
    /// without a leading 0x96 (`docs/protocol-facts.md`
    /// "KERNEL User Defined Data": both accepted).
    UddConfigMessage(&'a [u8]),
    /// Get_User_Def_Data_struct.
    GetUddStruct,
    /// CommitBaudRate.
    CommitBaudRate,
    /// Vendor SDK device-parameters request (0x41).
    DeviceParameters,
    /// SaveFlash (Table 5.23).
    SaveFlash {
        /// Parameter ID.
        id: u16,
        /// Parameter length field.
        len: u16,
        /// Value bytes (their count equals `len` when parsed from a frame).
        value: &'a [u8],
    },
    /// ReadRAM (Table 5.25).
    ReadRam {
        /// Parameter ID.
        id: u16,
        /// Parameter length field.
        len: u16,
    },
    /// A one-byte command code the device does not know.
    Unknown(u8),
}

/// Why a payload is not a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParseError {
    /// Empty payload.
    Empty,
    /// SaveFlash/ReadRAM whose size disagrees with its length field.
    BadLength,
    /// Several bytes not starting with a known multi-byte command.
    Unrecognised,
}

fn u16_at(p: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([p[i], p[i + 1]])
}

impl<'a> Command<'a> {
    /// Parses a command payload.
    pub fn parse(payload: &'a [u8]) -> Result<Command<'a>, ParseError> {
        match payload {
            [] => Err(ParseError::Empty),
            [code] => Ok(match *code {
                c if super::formats::is_data_command(c) => Command::Data(c),
                STOP => Command::Stop,
                GET_DEV_INFO => Command::GetDevInfo,
                GET_BIT => Command::GetBit,
                UDD_CONFIG => Command::UddConfig,
                GET_UDD_STRUCT => Command::GetUddStruct,
                COMMIT_BAUD_RATE => Command::CommitBaudRate,
                DEVICE_PARAMETERS => Command::DeviceParameters,
                c => Command::Unknown(c),
            }),
            [0xB2, 0xFF, ..] => {
                if payload.len() < 6 {
                    return Err(ParseError::BadLength);
                }
                let (id, len) = (u16_at(payload, 2), u16_at(payload, 4));
                let value = &payload[6..];
                if value.len() != usize::from(len) {
                    return Err(ParseError::BadLength);
                }
                Ok(Command::SaveFlash { id, len, value })
            }
            [0xB1, 0xFF, ..] => {
                if payload.len() != 6 {
                    return Err(ParseError::BadLength);
                }
                Ok(Command::ReadRam {
                    id: u16_at(payload, 2),
                    len: u16_at(payload, 4),
                })
            }
            [UDD_CONFIG, rest @ ..] => Ok(Command::UddConfigMessage(rest)),
            _ => Err(ParseError::Unrecognised),
        }
    }

    /// Encodes the command as a full frame into `out`; returns the length,
    /// or `None` if `out` is too small.
    pub fn encode(&self, out: &mut [u8]) -> Option<usize> {
        let mut p = [0u8; 6 + 256];
        let n = match *self {
            Command::Data(c) | Command::Unknown(c) => {
                p[0] = c;
                1
            }
            Command::Stop => one(&mut p, STOP),
            Command::GetDevInfo => one(&mut p, GET_DEV_INFO),
            Command::GetBit => one(&mut p, GET_BIT),
            Command::UddConfig => one(&mut p, UDD_CONFIG),
            Command::GetUddStruct => one(&mut p, GET_UDD_STRUCT),
            Command::CommitBaudRate => one(&mut p, COMMIT_BAUD_RATE),
            Command::DeviceParameters => one(&mut p, DEVICE_PARAMETERS),
            Command::UddConfigMessage(list) => {
                p[0] = UDD_CONFIG;
                let body = p.get_mut(1..1 + list.len())?;
                body.copy_from_slice(list);
                1 + list.len()
            }
            Command::SaveFlash { id, len, value } => {
                p[..2].copy_from_slice(&SAVE_FLASH.to_le_bytes());
                p[2..4].copy_from_slice(&id.to_le_bytes());
                p[4..6].copy_from_slice(&len.to_le_bytes());
                p.get_mut(6..6 + value.len())?.copy_from_slice(value);
                6 + value.len()
            }
            Command::ReadRam { id, len } => {
                p[..2].copy_from_slice(&READ_RAM.to_le_bytes());
                p[2..4].copy_from_slice(&id.to_le_bytes());
                p[4..6].copy_from_slice(&len.to_le_bytes());
                6
            }
        };
        frame::encode(TYPE_COMMAND, 0, &p[..n], out)
    }
}

fn one(p: &mut [u8], code: u8) -> usize {
    p[0] = code;
    1
}
