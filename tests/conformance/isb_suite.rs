//! The ISB conformance suite: the emulated IMX-5 end to end, written once
//! ([`isb_cases`]) and run against both targets ([`target::Kind`]):
//!
//! * `host::*` — `imu-emu --protocol isb`;
//! * `qemu::*` — the `boards/qemu-mps2` ISB image (`--features isb`) under
//!   `qemu-system-arm -machine mps2-an386` (needs `qemu-system-arm`:
//!   without it these tests pass with a SKIPPED note, except under `CI`,
//!   where they fail; the image is built on first use, see [`target`]).
//!
//! Run one side with `cargo test -p imu-emu-host --test conformance_isb
//! host::` (or `qemu::`).

// Shared with tests/host and the KERNEL suite; not every helper is used.
#[allow(dead_code)]
#[path = "../host/support.rs"]
mod support;

mod isb_cases;
#[allow(dead_code)]
mod target;

/// One `#[test]` per case and target.
macro_rules! suite {
    ($kind:expr; $($case:ident),* $(,)?) => {
        $(
            #[test]
            fn $case() {
                if crate::target::available($kind) {
                    crate::isb_cases::$case($kind);
                }
            }
        )*
    };
}

macro_rules! both {
    ($($case:ident),* $(,)?) => {
        mod host {
            suite!(crate::target::Kind::Host; $($case),*);
        }
        mod qemu {
            suite!(crate::target::Kind::Qemu; $($case),*);
        }
    };
}

both!(
    dev_info_is_answered_whole_and_accepted_by_the_sdk,
    sys_params_and_flash_config_checksums_agree,
    imu_every_4_ms_and_pimu_every_8_ms_on_device_time,
    flash_config_set_is_acked_read_back_and_kept,
    pers_then_srst_resumes_the_saved_stream,
    stop_all_is_acked_with_the_sdks_bytes,
    get_of_did_132_is_nacked,
    bad_checksum_then_a_good_packet_is_answered,
    navigation_streams_on_device_time_while_aligning,
    a_fed_rotation_shows_in_the_imu_packets,
    asce_streams_nmea_beside_isb,
    an_extrig_edge_gives_strobe_in_time_and_pstrb,
);

/// Cost figures exist on the QEMU image only.
mod qemu_cost {
    suite!(crate::target::Kind::Qemu; tick_cost_navigating);
}
