//! The ISB personality's streams and their output grid: the period grids
//! that advance every tick, the streams a GET or an RMC write starts, when
//! each is due and the packet it sends (module doc of [`super`]).

use super::*;

impl State {
    /// The period grids advance; pending flash writes happen; every
    /// periodic stream due sends.
    pub(super) fn tick(&mut self, cx: &mut impl Context<Integrals>, now: Instant) {
        let st = self;
        let (nav, imu) = (
            st.grid_ticks(cx, st.nav_dt_ms),
            st.grid_ticks(cx, st.imu_dt_ms),
        );
        let ticks = cx.time().ticks();
        // The receiver's models step half a navigation period after the
        // grid, on a tick of their own (the firmware's tick budget): a fix
        // enters the filter at the receiver's next epoch.
        if ticks % u64::from(st.grid_ticks(cx, ins::STEP_MS)) == u64::from(nav / 2) {
            let truth = st.truth(cx);
            st.nav.set_year(st.gps_time(cx).1.decimal_year());
            st.nav.step(ticks as f64 / f64::from(rate(cx)), &truth);
            if st.mag_cal.running() {
                st.mag_recal_sample(&truth, ticks);
            }
        }
        if ticks.is_multiple_of(u64::from(nav)) {
            st.nav_grid = [st.nav_grid[1], cx.chain().integrals()];
            st.navigate(cx);
        } else {
            st.nav_work(cx);
        }
        if ticks.is_multiple_of(u64::from(imu)) {
            st.imu_grid = [st.imu_grid[1], cx.chain().integrals()];
        }
        if st.save_pending {
            st.save(cx);
        }
        let mut sent = false;
        for i in 0..st.streams.len() {
            let s = &mut st.streams[i];
            if s.every == 0 {
                continue;
            }
            s.countdown = s.countdown.saturating_sub(1);
            if s.countdown == 0 {
                s.countdown = s.every;
                st.send_stream(cx, i, now);
                sent = true;
            }
        }
        if sent {
            // Saturation is reported since the previous packet.
            cx.chain_mut().restart_health_interval();
        }
        st.nmea_tick(cx, now);
    }

    /// A strobe (module doc).
    pub(super) fn strobe(&mut self, cx: &mut impl Context<Integrals>, at: Instant) {
        let st = self;
        st.strobe_count = st.strobe_count.wrapping_add(1);
        if let Some(i) = st.find(did::STROBE_IN_TIME) {
            st.send_stream(cx, i, at);
        }
        let due = st.nmea.due_on_strobe();
        st.send_nmea(cx, due, at);
    }

    pub(super) fn find(&self, did: u8) -> Option<usize> {
        self.streams.iter().position(|s| s.did == did)
    }

    /// Ticks per source period of `set` (at least 1).
    pub(super) fn source_ticks(&self, rate_hz: u32, set: &DataSet) -> u32 {
        let ms = set
            .source
            .period_ms(self.imu_dt_ms, self.nav_dt_ms, self.gps_dt_ms);
        (ms.saturating_mul(rate_hz) / 1000).max(1)
    }

    /// Ticks in `ms` (at least 1).
    pub(super) fn grid_ticks(&self, cx: &impl Context<Integrals>, ms: u32) -> u32 {
        (ms.saturating_mul(rate(cx)) / 1000).max(1)
    }

    /// The period grid a windowed data set lives on: IMU_RAW the IMU
    /// sample period's, the others the navigation period's.
    pub(super) fn grid(&self, did: u8) -> [Integrals; 2] {
        if matches!(did, did::IMU_RAW | did::IMU3_RAW) {
            self.imu_grid
        } else {
            self.nav_grid
        }
    }

    /// Ticks of the period of [`Self::grid`]`(did)`.
    pub(super) fn window_ticks(&self, cx: &impl Context<Integrals>, did: u8) -> u32 {
        let ms = if matches!(did, did::IMU_RAW | did::IMU3_RAW) {
            self.imu_dt_ms
        } else {
            self.nav_dt_ms
        };
        self.grid_ticks(cx, ms)
    }

    /// Starts (or replaces) the stream of `set`.
    pub(super) fn start_stream(
        &mut self,
        cx: &impl Context<Integrals>,
        set: &DataSet,
        offset: u16,
        size: u16,
        period: u16,
    ) {
        let every = if set.did == did::STROBE_IN_TIME {
            0
        } else {
            self.source_ticks(cx.product().model.internal_rate_hz, set)
                .saturating_mul(u32::from(period))
        };
        // The first packet falls on the source period's grid (ticks since
        // power-on a multiple of it) and a windowed one covers `period`
        // whole source periods from the last boundary (module doc).
        let src = self.source_ticks(rate(cx), set);
        let phase = (cx.time().ticks() % u64::from(src)) as u32;
        let s = Stream {
            did: set.did,
            offset,
            size,
            period,
            every,
            countdown: every.saturating_sub(phase).max(1),
            start: self.grid(set.did)[1],
        };
        match self.find(set.did) {
            Some(i) => self.streams[i] = s,
            None => {
                let _ = self.streams.push(s);
            }
        }
    }

    pub(super) fn stop_stream(&mut self, did: u8) {
        if let Some(i) = self.find(did) {
            self.streams.remove(i);
        }
    }

    /// An RMC write (module doc).
    pub(super) fn rmc(&mut self, cx: &mut impl Context<Integrals>, r: &Rmc) {
        let preserve = r.options & rmc::OPTIONS_PRESERVE_CTRL != 0;
        let preset = r.bits & rmc::BITS_PRESET != 0;
        for set in did::DATA_SETS.iter().filter(|s| s.rmc_bit != 0) {
            if r.bits & set.rmc_bit != 0 {
                // A preset chooses the period multiples (docs/isb.md): in
                // a PPD preset INS_2 every 100 ms, everything else at its
                // source period.
                let ppd = preset && r.bits & rmc_nav::BITS_INTERNAL_PPD != 0;
                let n = if ppd && set.did == did::INS_2 {
                    (rmc_nav::PPD_NAV_PERIOD_MS / self.nav_dt_ms).max(1) as u16
                } else {
                    1
                };
                let same = self.find(set.did).map(|i| self.streams[i].period);
                if same.is_none() || (preset && same != Some(n)) {
                    self.start_stream(cx, set, 0, set.size, n);
                }
            } else if !preserve {
                self.stop_stream(set.did);
            }
        }
        self.rmc_options = r.options;
        if r.options & rmc::OPTIONS_PERSISTENT != 0 {
            self.save_persistent(cx);
        }
    }

    pub(super) fn rmc_bits(&self) -> u64 {
        self.streams
            .iter()
            .filter_map(|s| did::lookup(u16::from(s.did)))
            .fold(0, |b, set| b | set.rmc_bit)
    }

    /// One DATA packet of `set` now (the GET's reply).
    pub(super) fn send_once(
        &mut self,
        cx: &mut impl Context<Integrals>,
        set: &DataSet,
        offset: u16,
        size: u16,
        now: Instant,
    ) {
        let mut image = [0u8; did::MAX_SIZE];
        let n = self.image_of(cx, set.did, &mut image, now);
        send_data(cx, set.did, &image[..n], offset, size);
    }

    /// The packet of stream `i` at `now`; its window restarts.
    pub(super) fn send_stream(&mut self, cx: &mut impl Context<Integrals>, i: usize, now: Instant) {
        let s = self.streams[i];
        let mut image = [0u8; did::MAX_SIZE];
        let n = match s.did {
            d if is_windowed(d) => {
                let end = cx.chain().integrals();
                let w = integrals::window(&s.start, &end, rate(cx));
                self.streams[i].start = end;
                self.windowed(cx, s.did, &w, cx.time().ticks(), &mut image)
            }
            _ => self.image_of(cx, s.did, &mut image, now),
        };
        send_data(cx, s.did, &image[..n], s.offset, s.size);
    }
}

/// A DATA packet of `image[offset..offset + size]`.
fn send_data(cx: &mut impl Context<Integrals>, did: u8, image: &[u8], offset: u16, size: u16) {
    let whole = offset == 0 && usize::from(size) == image.len();
    let n = OVERHEAD + usize::from(size) + if whole { 0 } else { 2 };
    push(cx, n, |f| message::encode_data(did, image, offset, size, f));
}

/// Whether `did` is a window of the integrals (IMU, IMU_RAW, PIMU and
/// their `_MAG` forms).
fn is_windowed(did: u8) -> bool {
    matches!(
        did,
        did::IMU | did::IMU_RAW | did::IMU3_RAW | did::PIMU | did::IMU_MAG | did::PIMU_MAG
    )
}
