//! The ISB personality's NMEA hooks (`docs/isb.md` "NMEA"): `$ASCE`, the
//! sentences due at a tick, one sentence a frame on the line. The table,
//! the schedule and the sentences are [`crate::isb::asce`],
//! [`crate::isb::nmea_stream`] and [`crate::isb::nmea_out`].

use super::*;

/// The NMEA side (`docs/isb.md` "NMEA"; [`crate::isb::nmea_stream`]).
impl State {
    /// `$ASCE`: the table reply for `$ASCE` alone, else the table set (and
    /// saved with the persistent option); dropped pairs are counted.
    pub(super) fn asce(&mut self, cx: &mut impl Context<Integrals>, body: &[u8]) {
        if body == b"ASCE" {
            let mut l = crate::isb::nmea_out::Line::new();
            if self.nmea.table.reply(&mut l).is_ok() {
                if let Some(b) = l.finish() {
                    push_line(cx, b);
                }
            }
            return;
        }
        let a = self.nmea.table.apply(body);
        // Looked at from the next tick on.
        self.nmea.next_in = Some(1);
        self.nmea.rejected = self.nmea.rejected.wrapping_add(u32::from(a.rejected));
        if a.persistent {
            self.save_persistent(cx);
        }
    }

    /// The NMEA sentences due at this tick.
    pub(super) fn nmea_tick(&mut self, cx: &mut impl Context<Integrals>, now: Instant) {
        if self.nmea.table.bits == 0 {
            return;
        }
        let ticks = cx.time().ticks();
        let on_grid = |ms: u32| {
            let g = u64::from(self.grid_ticks(cx, ms));
            ticks.is_multiple_of(g).then_some(ticks / g)
        };
        let (nav, imu, ms) = (on_grid(self.nav_dt_ms), on_grid(self.imu_dt_ms), on_grid(1));
        let (since, gps) = self.gps_time(cx);
        let ns = if self.nav.gps_time_valid() {
            gps.week as u64 * nav::WEEK_S * 1_000_000_000 + gps.tow_ns
        } else {
            since
        };
        // An epoch begins at this tick when the previous tick was in another.
        let before = ns.saturating_sub(1_000_000_000 / u64::from(rate(cx)));
        let begins = |len: u64| (ns / len != before / len || ticks == 0).then_some(ns / len);
        let gps = begins(u64::from(self.gps_dt_ms) * 1_000_000);
        let gps_second = begins(1_000_000_000);
        let e = Epochs {
            nav,
            imu,
            ms,
            gps,
            gps_second,
        };
        let due = self.nmea.due(&e);
        self.send_nmea(cx, due, now);
        let tick_ns = 1_000_000_000 / u64::from(rate(cx));
        let grids =
            [self.nav_dt_ms, self.imu_dt_ms, 1].map(|ms| u64::from(self.grid_ticks(cx, ms)));
        let gps_ns = u64::from(self.gps_dt_ms) * 1_000_000;
        self.nmea.plan(ticks, ns, tick_ns, grids, gps_ns);
    }

    /// Sends the sentences of `due` now.
    pub(super) fn send_nmea(&mut self, cx: &mut impl Context<Integrals>, due: u32, now: Instant) {
        if due == 0 {
            return;
        }
        let decl = le::f32(&self.cfg.0, flash::MAG_DECLINATION);
        let sigma = self.nav.attitude_sigma_rad();
        let snap = Snapshot::fill(due, decl, sigma, |d, b| self.image_of(cx, d, b, now));
        self.nmea.render(due, &snap, |line| push_line(cx, line));
    }
}

/// Queues one NMEA sentence as one frame (whole, or dropped and counted
/// when the line is full).
fn push_line(cx: &mut impl Context<Integrals>, line: &[u8]) {
    cx.push_frame(line.len(), |f| {
        f.copy_from_slice(line);
        true
    });
}
