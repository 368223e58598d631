//! The ISB personality's navigation side: the truth of a tick, GPS time,
//! the INS stepped on the navigation grid and between it, `lastLla` kept,
//! and the bytes of the navigation data sets ([`crate::isb::ins`],
//! `docs/isb.md` "Navigation").

use super::*;

impl State {
    /// A magnetometer reading at tick `tick` (the one MAGNETOMETER reads
    /// then) into the running recalibration; its result, when it ends,
    /// becomes the navigation's field reference ([`magcal`]).
    pub(super) fn mag_recal_sample(&mut self, truth: &NavTruth, tick: u64) {
        let m = self.nav.magnetometer(truth, tick);
        let level = self.nav.mag_levelled(&m);
        if let Some((norm, dip)) = self.mag_cal.feed(&m, &level) {
            self.nav.set_mag_reference(norm, dip);
        }
        self.nav.set_mag_recalibrating(self.mag_cal.running());
    }

    /// The navigation truth at the last tick ([`nav::truth_of`], once a
    /// tick).
    pub(super) fn truth(&self, cx: &impl Context<Integrals>) -> NavTruth {
        let tick = cx.time().ticks();
        match self.truth.get() {
            Some((t, truth)) if t == tick => truth,
            _ => {
                let truth = nav::truth_of(cx.chain());
                self.truth.set(Some((tick, truth)));
                truth
            }
        }
    }

    /// `(since boot, GPS time)` at the last tick (on the sample grid).
    pub(super) fn gps_time(&self, cx: &impl Context<Integrals>) -> (u64, GpsTime) {
        let since_boot = cx.time().ticks() * (1_000_000_000 / u64::from(rate(cx)));
        let gps = self.gps_ns_at_zero + cx.time().powered_at().0 + since_boot;
        (since_boot, GpsTime::of_ns(gps))
    }

    /// The FLASH_CONFIG fields the navigation uses.
    pub(super) fn nav_config(&self) -> NavConfig {
        let b = &self.cfg.0;
        let f64x3 = |off: usize| [0, 8, 16].map(|k| le::f64(b, off + k));
        NavConfig {
            ref_lla: f64x3(flash::REF_LLA),
            last_lla: f64x3(flash::LAST_LLA),
            ins_rotation: le::f32x3(b, flash::INS_ROTATION),
            ins_offset: le::f32x3(b, flash::INS_OFFSET),
            gps1_ant_offset: le::f32x3(b, flash::GPS1_ANT_OFFSET),
            last_lla_week: le::u32(b, flash::LAST_LLA_WEEK),
            last_lla_update_distance: le::f32(b, flash::LAST_LLA_UPDATE_DISTANCE),
            sys_cfg_bits: le::u32(b, flash::SYS_CFG_BITS),
        }
    }

    /// One navigation period of the INS (at each boundary of the
    /// navigation grid): the chain's coning- and sculling-corrected
    /// increments of the period — the Δθ, Δv a PIMU of that period reports
    /// — in body axes, the receiver's fix, the magnetometer and barometer
    /// as the unit reads them; then `lastLla` saved if the INS asks. With
    /// the filter off (`Isb::set_navigation`) a period is only the epoch's
    /// truth, for the receiver's report made ready ahead of the epoch.
    pub(super) fn navigate(&mut self, cx: &mut impl Context<Integrals>) {
        let tick = cx.time().ticks();
        let t_s = tick as f64 / f64::from(rate(cx));
        let gps_dt_s = f64::from(self.gps_dt_ms) / 1000.0;
        // The aiding sensors are read at the receiver's epochs only, by the
        // INS on the ticks that follow (`nav_work`).
        let due = self.nav.epoch_due(t_s, gps_dt_s);
        // The filter off takes no increments (their conversion is soft
        // double precision on the RP2040, whose filter is off), and a
        // period without an epoch brings it nothing.
        let off = self.nav.phase() == ins::Phase::Off;
        if off && !due {
            return;
        }
        let [start, end] = &self.nav_grid;
        let dt = end.samples.wrapping_sub(start.samples) as f64 / f64::from(rate(cx));
        let inc = if off {
            mech::Increment {
                dtheta: [0.0; 3],
                dv: [0.0; 3],
                dt,
            }
        } else {
            let w = integrals::window(start, end, rate(cx));
            mech::Increment {
                dtheta: crate::vehicle::housing_to_body(&w.dtheta_rad),
                dv: crate::vehicle::housing_to_body(&w.dv_mps),
                dt,
            }
        };
        // FLASH_CONFIG with the epoch (the INS reads it for nothing else).
        let cfg = due.then(|| self.nav_config());
        let epoch = cfg.as_ref().map(|cfg| {
            let (_, gps) = self.gps_time(cx);
            let year = ins::decimal_year(gps.week as f64 * nav::WEEK_S as f64 + gps.tow_s());
            (self.truth(cx), tick, year, cfg)
        });
        self.nav.navigate_truth(t_s, &inc, gps_dt_s, epoch);
        self.save_last_lla(cx);
    }

    /// A share of the INS's pending work (its covariance propagation, a
    /// receiver epoch's aiding) on a tick between navigation periods:
    /// the firmware's tick budget (`docs/performance.md`).
    pub(super) fn nav_work(&mut self, cx: &mut impl Context<Integrals>) {
        if self.nav.work() {
            self.save_last_lla(cx);
        }
    }

    /// `lastLla` saved if the INS asks, stamped with the GPS time of the
    /// navigation period it was found in.
    pub(super) fn save_last_lla(&mut self, cx: &mut impl Context<Integrals>) {
        let Some(lla) = self.nav.take_last_lla() else {
            return;
        };
        let (_, gps) = self.gps_time(cx);
        let nav_ticks = u64::from(self.grid_ticks(cx, self.nav_dt_ms));
        let back = (cx.time().ticks() % nav_ticks) * (1_000_000_000 / u64::from(rate(cx)));
        let gps = GpsTime::of_ns(
            (u64::from(gps.week) * nav::WEEK_S * 1_000_000_000 + gps.tow_ns).saturating_sub(back),
        );
        for (k, x) in lla.iter().enumerate() {
            le::put(&mut self.cfg.0, flash::LAST_LLA + 8 * k, &x.to_le_bytes());
        }
        le::put(
            &mut self.cfg.0,
            flash::LAST_LLA_TIME_OF_WEEK_MS,
            &gps.tow_ms().to_le_bytes(),
        );
        le::put(
            &mut self.cfg.0,
            flash::LAST_LLA_WEEK,
            &gps.week.to_le_bytes(),
        );
        self.cfg.update_checksum();
        self.save_pending = true;
    }

    /// The bytes of a navigation data set now (`docs/isb.md`
    /// "Navigation").
    pub(super) fn nav_image(
        &self,
        cx: &impl Context<Integrals>,
        did: u8,
        hdw: u32,
        out: &mut [u8; did::MAX_SIZE],
    ) -> usize {
        let mut put = |b: &[u8]| {
            out[..b.len()].copy_from_slice(b);
            b.len()
        };
        // The truth only for the data sets that read it (the INS's do
        // not: a conversion in soft double precision on the M4F).
        let truth = || self.truth(cx);
        let cfg = self.nav_config();
        let (since_ns, gps) = self.gps_time(cx);
        // INS, the filter's states and sigmas, magnetometer, barometer:
        // stamped on their output grid (the last multiple of the source
        // period: the navigation step the state is from), as streams are,
        // also in a one-shot GET and a stream's first packet.
        let back = match did::lookup(u16::from(did)) {
            Some(set)
                if matches!(
                    did,
                    did::INS_1
                        | did::INS_2
                        | did::INS_3
                        | did::INS_4
                        | did::INL2_STATES
                        | did::INL2_NED_SIGMA
                        | did::MAGNETOMETER
                        | did::BAROMETER
                ) =>
            {
                let ms = set
                    .source
                    .period_ms(self.imu_dt_ms, self.nav_dt_ms, self.gps_dt_ms);
                since_ns % (u64::from(ms.max(1)) * 1_000_000)
            }
            _ => 0,
        };
        let since_ns = since_ns - back;
        let gps = GpsTime::of_ns(
            (u64::from(gps.week) * nav::WEEK_S * 1_000_000_000 + gps.tow_ns).saturating_sub(back),
        );
        // Seconds (a soft double division on the M4F) where they are sent.
        let since_s = || since_ns as f64 / 1e9;
        let valid = self.nav.gps_time_valid();
        // The INS header only where one is sent.
        let h = || InsHeader {
            week: if valid { gps.week } else { 0 },
            time_of_week: if valid { gps.tow_s() } else { since_s() },
            ins_status: self.nav.ins_status(),
            hdw_status: hdw,
        };
        // The receiver's last epoch (GPS time a multiple of its period).
        let gps_dt_ns = u64::from(self.gps_dt_ms) * 1_000_000;
        let epoch = if valid {
            GpsTime {
                week: gps.week,
                tow_ns: gps.tow_ns - gps.tow_ns % gps_dt_ns,
            }
        } else {
            GpsTime {
                week: 0,
                tow_ns: since_ns - since_ns % gps_dt_ns,
            }
        };
        let tow_offset = || if valid { gps.tow_s() - since_s() } else { 0.0 };
        // The receiver's fix only where it is reported (a conversion in
        // soft double precision on the M4F).
        let fix = || self.nav.gnss(&truth(), &cfg);
        let tick = cx.time().ticks();
        match did {
            did::INS_1 => put(&ins::ins1(&h(), &self.nav.solution(&cfg), &cfg).encode()),
            did::INS_2 => put(&ins::ins2(&h(), &self.nav.solution(&cfg)).encode()),
            did::INS_3 => put(&ins::ins3(&h(), &self.nav.solution(&cfg)).encode()),
            did::INS_4 => put(&ins::ins4(&h(), &self.nav.solution(&cfg)).encode()),
            // Without RTK the receiver's solution is GPS1_POS.
            did::GPS1_POS | did::GPS1_RCVR_POS => {
                let r = self.nav.gps_report(&truth(), &cfg);
                put(&ins::gps_pos(&epoch, r.as_ref(), tow_offset()).encode())
            }
            did::GPS1_VEL => put(&ins::gps_vel(&epoch, fix()).encode()),
            did::GPS1_SAT => put(&self.nav.gps_sat(&epoch).encode()),
            // The signals of the satellites GPS1_SAT reports.
            did::GPS1_SIG => put(&aux_sets::gps_sig_of(&self.nav.gps_sat(&epoch)).encode()),
            did::MAGNETOMETER => {
                put(&ins::magnetometer(since_s(), self.nav.magnetometer(&truth(), tick)).encode())
            }
            did::BAROMETER => {
                let p = self.nav.pressure_kpa(&truth(), tick);
                put(&ins::barometer(since_s(), p, cx.chain().temperature()).encode())
            }
            did::INL2_STATES => put(&self.nav.inl2_states(h().time_of_week).encode()),
            did::INL2_NED_SIGMA => {
                let ms = if valid {
                    gps.tow_ms()
                } else {
                    (since_ns / 1_000_000) as u32
                };
                put(&self.nav.inl2_ned_sigma(ms).encode())
            }
            _ => 0,
        }
    }
}
