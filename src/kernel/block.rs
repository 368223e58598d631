//! The layout of the KERNEL parameter block, which both the parameter table
//! ([`super::params`], Table 5.24) and the UDD configuration ([`super::udd`],
//! 5.3.5) live in: its length, its type and the emulator-private UDD region.
//! Neither of those modules needs the other for it.

/// Length of the parameter block (the highest ID, Hold-off_Time 0x05FE,
/// ends at 0x0600).
pub const BLOCK_LEN: usize = crate::store::PARAM_BLOCK_LEN;

/// The parameter block: all parameters at their ID offsets, LSB first.
pub type Block = [u8; BLOCK_LEN];

/// Emulator-private region of the block (no Table 5.24 ID points into it,
/// so SaveFlash/ReadRAM cannot reach it): the UDD configuration (5.3.5),
/// `N` then up to [`UDD_MAX_TYPES`] type codes, persisted with the rest.
pub const UDD_CONFIG_OFFSET: usize = 0x0100;
/// Most UDD types in one configuration (the Table 5.20 bitmap has 16 bits).
pub const UDD_MAX_TYPES: usize = 16;
