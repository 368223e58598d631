//! Power-fail-safe parameter persistence over `embedded-storage` NorFlash.
//! (Being written: see the store helper's task.)

/// Length of the KERNEL parameter block (ICD Table 5.24: IDs are byte
/// offsets; the highest, Hold-off_Time 0x05FE, ends at 0x0600).
pub const PARAM_BLOCK_LEN: usize = 0x600;
