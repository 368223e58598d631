//! DID_RTOS_INFO (38): the release's task table, `rtos_info_t` (SDK 2.7.1
//! `data_sets.h`, `docs/isb-data-sets.md` "RTOS_INFO"), filled from what
//! the emulated unit really has: the periods its work runs at and the
//! device time each piece of work last ran. What the emulator cannot
//! measure — CPU time, stack, heap, priorities — reads 0, never a made-up
//! figure (`docs/isb-data-sets.md` says what each field holds).

/// `MAX_TASK_NAME_LEN`: bytes of `rtos_task_t.name`.
pub(crate) const MAX_TASK_NAME_LEN: usize = 12;
/// `RTOS_NUM_TASKS`: entries of `rtos_info_t.task` (`eRtosTask`).
pub(crate) const RTOS_NUM_TASKS: usize = 6;

crate::data_set! {
    /// `rtos_task_t`, 60 bytes: one task of DID_RTOS_INFO.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct RtosTask in mod rtos_task, 60 bytes {
        /// Task name, NUL padded.
        name: [u8; MAX_TASK_NAME_LEN] = NAME @ 0,
        /// Task priority.
        priority: u32 = PRIORITY @ 12,
        /// Stack high-water mark: bytes never used.
        stack_unused: u32 = STACK_UNUSED @ 16,
        /// Task period, ms.
        period_ms: u32 = PERIOD_MS @ 20 => ["periodMs" in "ms"],
        /// Last run time, µs.
        runtime_us: u32 = RUNTIME_US @ 24,
        /// Average run time, µs.
        avg_runtime_us: f32 = AVG_RUNTIME_US @ 28,
        /// Average of the run times below the average, µs.
        lower_runtime_us: f32 = LOWER_RUNTIME_US @ 32,
        /// Average of the run times above the average, µs.
        upper_runtime_us: f32 = UPPER_RUNTIME_US @ 36,
        /// Longest run time, µs.
        max_runtime_us: u32 = MAX_RUNTIME_US @ 40,
        /// Start of the last run, µs since boot.
        start_time_us: u32 = START_TIME_US @ 44 => ["startTimeUs" in "us"],
        /// Runs that started later than their period.
        gap_count: u16 = GAP_COUNT @ 48,
        /// Runs that started two periods late.
        double_gap_count: u8 = DOUBLE_GAP_COUNT @ 50,
        /// Reserved.
        reserved: u8 = RESERVED @ 51,
        /// CPU share, %.
        cpu_usage: f32 = CPU_USAGE @ 52,
        /// The RTOS's task handle.
        handle: u32 = HANDLE @ 56,
    }
}

crate::data_set! {
    /// `rtos_info_t`, 372 bytes: DID_RTOS_INFO, heap figures and the six
    /// tasks of `eRtosTask` (sample, nav, communications, maintenance,
    /// idle, timer), in that order.
    #[derive(Debug, Clone, Copy, PartialEq, Default)]
    pub struct RtosInfo in mod rtos_info, 372 bytes {
        /// Free heap, bytes.
        free_heap_size: u32 = FREE_HEAP_SIZE @ 0 => ["freeHeapSize" in "B"],
        /// Bytes allocated.
        malloc_size: u32 = MALLOC_SIZE @ 4 => ["mallocSize" in "B"],
        /// Bytes freed.
        free_size: u32 = FREE_SIZE @ 8 => ["freeSize" in "B"],
        /// The tasks, by `eRtosTask`.
        task: [RtosTask; RTOS_NUM_TASKS] = TASK @ 12
            => [each "task" [0 1 2 3 4 5] ["periodMs", "startTimeUs"]],
    }
}

/// The task names, by `eRtosTask` (the emulator's spelling of the
/// header's enum: the release's own strings are in its firmware, not in
/// the SDK).
pub(crate) const TASK_NAMES: [&str; RTOS_NUM_TASKS] = ["SAMPLE", "NAV", "COMM", "MAINT", "IDLE", "TIMER"];

/// Where the emulated unit's work stands: each period it runs at (ms) and
/// the device tick it last ran at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Schedule {
    /// Ticks per second (the unit's internal rate).
    pub rate_hz: u32,
    /// Ticks since boot.
    pub ticks: u64,
    /// The IMU sample period, ms (`startupImuDtMs` latched at boot).
    pub imu_dt_ms: u32,
    /// The navigation period, ms (`startupNavDtMs` latched at boot).
    pub nav_dt_ms: u32,
    /// The period of the aiding models' step, ms (receiver, magnetometer,
    /// barometer: [`crate::isb::ins::STEP_MS`]).
    pub step_ms: u32,
    /// Ticks after the step's grid it runs at (half a navigation period).
    pub step_offset: u32,
}

impl Schedule {
    /// µs since boot of the last tick on the grid of `ms` shifted by
    /// `offset` ticks (ticks since boot minus `offset` a multiple of it; 0
    /// before the first).
    fn last_run_us(&self, ms: u32, offset: u32) -> u32 {
        let rate = u64::from(self.rate_hz.max(1));
        let every = (u64::from(ms) * rate / 1000).max(1);
        let offset = u64::from(offset) % every;
        let tick = match self.ticks.checked_sub(offset) {
            Some(t) => self.ticks - t % every,
            None => return 0,
        };
        (tick * 1_000_000 / rate) as u32
    }
}

/// DID_RTOS_INFO of the emulated unit at `s` (`docs/isb-data-sets.md`
/// "RTOS_INFO"): sample = the IMU sample grid, nav = the navigation
/// period, comm = the 1 ms grid the streams count in (served on every
/// tick), maint = the aiding models' step; idle and timer have no
/// counterpart (name only). No heap: the heap words read 0.
pub(crate) fn rtos_info(s: &Schedule) -> RtosInfo {
    let periods = [s.imu_dt_ms, s.nav_dt_ms, 1, s.step_ms, 0, 0];
    let mut task = [RtosTask::default(); RTOS_NUM_TASKS];
    for (k, t) in task.iter_mut().enumerate() {
        t.name = super::aux_sets::padded(TASK_NAMES[k]);
        t.period_ms = periods[k];
        if periods[k] > 0 {
            let offset = if k == 3 { s.step_offset } else { 0 };
            t.start_time_us = s.last_run_us(periods[k], offset);
        }
    }
    RtosInfo {
        free_heap_size: 0,
        malloc_size: 0,
        free_size: 0,
        task,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_the_headers() {
        assert_eq!(rtos_task::SIZE, 60);
        assert_eq!(rtos_info::SIZE, 372);
        assert_eq!(rtos_task::HANDLE, 56);
        assert_eq!(
            rtos_info::TASK + 5 * rtos_task::SIZE + rtos_task::PERIOD_MS,
            332
        );
    }

    #[test]
    fn each_task_reports_its_grid() {
        // 2 kHz, 1.2345 s after boot: IMU grid 1 ms, nav 4 ms, step 20 ms.
        let s = Schedule {
            rate_hz: 2000,
            ticks: 2469,
            imu_dt_ms: 1,
            nav_dt_ms: 4,
            step_ms: 20,
            step_offset: 4,
        };
        let r = rtos_info(&s);
        let starts = r.task.map(|t| t.start_time_us);
        assert_eq!(starts, [1_234_000, 1_232_000, 1_234_000, 1_222_000, 0, 0]);
        assert_eq!(&r.task[1].name[..4], b"NAV\0");
        assert_eq!(r.task[3].period_ms, 20);
    }
}
