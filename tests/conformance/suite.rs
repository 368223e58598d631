//! The conformance suite: the KERNEL protocol end to end, written once
//! ([`cases`]) and run against both targets ([`target::Kind`]):
//!
//! * `host::*` — the `imu-emu` host runner binary;
//! * `qemu::*` — the `boards/qemu-mps2` firmware under
//!   `qemu-system-arm -machine mps2-an386` (needs `qemu-system-arm`: without
//!   it these tests pass with a SKIPPED note, except under `CI`, where they
//!   fail; the image is built on first use, see [`target`]).
//!
//! Run one side with `cargo test -p imu-emu-host --test conformance host::`
//! (or `qemu::`). `qemu::tick_cost_*` also print the firmware's
//! instructions per tick measured under `-icount shift=0`.

// Shared with tests/host; not every helper is used here.
#[allow(dead_code)]
#[path = "../host/support.rs"]
mod support;

mod cases;
mod target;

/// One `#[test]` per case and target.
macro_rules! suite {
    ($kind:expr; $($case:ident),* $(,)?) => {
        $(
            #[test]
            fn $case() {
                if crate::target::available($kind) {
                    crate::cases::$case($kind);
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
            // QEMU only: the firmware's own figures.
            suite!(
                crate::target::Kind::Qemu;
                tick_cost_ga_2khz_at_2_mbaud,
                tick_cost_largest_udd,
                tick_cost_worst_case
            );
        }
    };
}

both!(
    get_dev_info_answers_166_bytes_with_the_seeded_serial,
    get_bit_answers_four_zero_bytes,
    read_ram_sensors_measurement_range,
    device_parameters_request_answers_60_bytes,
    every_fixed_format_streams_its_frame_at_the_data_rate,
    ga_streams_at_the_default_100_hz_and_stop_stops_it,
    k201_ticks_at_4_khz,
    stop_is_idempotent_and_unknown_commands_are_ignored,
    udd_config_is_answered_read_back_streamed_and_persisted,
    saved_parameters_survive_a_power_cycle,
    auto_start_announces_and_streams_after_a_power_cycle,
    invalid_save_flash_gets_no_answer_and_changes_nothing,
    bad_input_is_skipped_and_the_decoder_resyncs,
    commit_baud_rate_4800_caps_the_rate_and_the_throughput,
    two_megabaud_carries_ga_at_2000_hz,
    pps_sets_the_gam_time_flag_and_restarts_the_second,
    extrig_sends_one_frame_per_edge,
    tov_pulses_high_then_low_for_every_frame,
    boot_asserted_at_power_on_silences_the_device,
    replies_and_frames_leave_without_delay,
    a_fed_rotation_shows_in_the_ga_frames_and_silence_is_a_fault,
);
