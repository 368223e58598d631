//! One encoder per data set the ISB personality serves: the current bytes
//! of the set, from the device state; [`Encoders::ENCODERS`] has one row
//! per row of [`did::DATA_SETS`].

use super::*;

/// A data set image.
pub(super) type Image = [u8; did::MAX_SIZE];

/// An encoder: the bytes of its data set (`did`, for those that serve
/// several) at `now` into the image; their length.
pub(super) type Encoder<C> = fn(&State, &mut C, u8, Instant, &mut Image) -> usize;

/// The encoder of each data set served, by DID.
pub(super) trait Encoders: Context<Integrals> + Sized {
    /// `(DID, encoder)`, in the order of [`did::DATA_SETS`].
    const ENCODERS: [(u8, Encoder<Self>); did::DATA_SETS.len()];
}

impl<C: Context<Integrals>> Encoders for C {
    const ENCODERS: [(u8, Encoder<C>); did::DATA_SETS.len()] = [
        (did::DEV_INFO, dev_info),
        (did::SYS_FAULT, sys_fault),
        (did::PIMU, windowed_now),
        (did::SYS_CMD, sys_cmd),
        (did::NMEA_BCAST_PERIOD, nmea_bcast_period),
        (did::RMC, rmc),
        (did::SYS_PARAMS, sys_params),
        (did::FLASH_CONFIG, flash_config),
        (did::GPS1_VERSION, gps1_version),
        (did::MAG_CAL, mag_cal),
        (did::RTOS_INFO, rtos_info),
        (did::CAN_CONFIG, can_config),
        (did::IMU, windowed_now),
        (did::BIT, bit),
        (did::PORT_MONITOR, port_monitor),
        (did::STROBE_IN_TIME, strobe_in_time),
        (did::IMU3_RAW, windowed_now),
        (did::IMU_RAW, windowed_now),
        (did::INS_1, navigation),
        (did::INS_2, navigation),
        (did::INS_3, navigation),
        (did::INS_4, navigation),
        (did::INL2_STATES, navigation),
        (did::INL2_NED_SIGMA, navigation),
        (did::GPS1_POS, navigation),
        (did::GPS1_RCVR_POS, navigation),
        (did::GPS1_VEL, navigation),
        (did::GPS1_SAT, navigation),
        (did::GPS1_SIG, navigation),
        (did::MAGNETOMETER, navigation),
        (did::BAROMETER, navigation),
        (did::SYS_SENSORS, sys_sensors),
        (did::IMU_MAG, windowed_now),
        (did::PIMU_MAG, windowed_now),
    ];
}

/// `b` into `out`; its length.
fn put(out: &mut Image, b: &[u8]) -> usize {
    out[..b.len()].copy_from_slice(b);
    b.len()
}

/// Declares encoders: `fn name(state, cx, did, now, out) { body }` with the
/// [`Encoder`] signature.
macro_rules! encoders {
    ($( $(#[$m:meta])* fn $name:ident($st:pat, $cx:pat, $did:pat, $now:pat, $out:ident) $body:block )*) => {$(
        $(#[$m])*
        fn $name<C: Context<Integrals>>(
            $st: &State,
            $cx: &mut C,
            $did: u8,
            $now: Instant,
            $out: &mut Image,
        ) -> usize $body
    )*};
}

encoders! {
    fn dev_info(_, cx, _, _, out) {
        put(out, &dev_info_of(cx).encode())
    }

    fn flash_config(st, _, _, _, out) {
        put(out, &st.cfg.0)
    }

    fn sys_params(st, cx, _, now, out) {
        put(out, &st.sys_params(cx, now).encode())
    }

    fn rmc(st, _, _, _, out) {
        put(
            out,
            &Rmc {
                bits: st.rmc_bits(),
                options: st.rmc_options,
            }
            .encode(),
        )
    }

    fn sys_cmd(_, _, _, _, out) {
        put(out, &SystemCommand::default().encode())
    }

    fn nmea_bcast_period(st, _, _, _, out) {
        put(out, &st.nmea.table.to_msgs())
    }

    fn bit(st, _, _, _, out) {
        put(out, &st.bit.encode())
    }

    /// A unit that never faulted: all zeros (`docs/isb-data-sets.md`).
    fn sys_fault(_, _, _, _, out) {
        put(out, &SystemFault::default().encode())
    }

    fn gps1_version(_, _, _, _, out) {
        put(out, &aux_sets::RECEIVER_VERSION.encode())
    }

    fn mag_cal(st, _, _, _, out) {
        put(out, &st.mag_cal_of().encode())
    }

    fn rtos_info(st, cx, _, _, out) {
        put(out, &rtos::rtos_info(&st.rtos_schedule(cx)).encode())
    }

    fn can_config(st, _, _, _, out) {
        put(out, &st.can.encode())
    }

    fn port_monitor(st, cx, _, now, out) {
        put(out, &st.port_monitor(cx, now).encode())
    }

    fn strobe_in_time(st, cx, _, now, out) {
        // GPS time of the edge once GPS time is known.
        let (week, time_of_week_ms) = if st.nav.gps_time_valid() {
            let since = now.since(cx.time().powered_at());
            let t = GpsTime::of_ns(st.gps_ns_at_zero + cx.time().powered_at().0 + since);
            (t.week, t.tow_ms())
        } else {
            (0, ms_since(cx, now))
        };
        put(
            out,
            &StrobeInTime {
                week,
                time_of_week_ms,
                pin: 0,
                count: st.strobe_count,
            }
            .encode(),
        )
    }

    /// INS_1..4, INL2_*, GPS1_*, MAGNETOMETER, BAROMETER ([`State::nav_image`]).
    fn navigation(st, cx, did, now, out) {
        // hdwStatus only where a header carries it (the INS sets).
        let hdw = match did {
            did::INS_1 | did::INS_2 | did::INS_3 | did::INS_4 => st.sys_params(cx, now).hdw_status,
            _ => 0,
        };
        st.nav_image(cx, did, hdw, out)
    }

    fn sys_sensors(st, cx, _, _, out) {
        put(out, &st.sys_sensors(cx).encode())
    }

    /// IMU, IMU_RAW, IMU3_RAW, PIMU, IMU_MAG, PIMU_MAG at once: the last whole
    /// period of their grid ([`State::windowed`]).
    fn windowed_now(st, cx, did, _, out) {
        let [a, b] = st.grid(did);
        let w = integrals::window(&a, &b, rate(cx));
        let end = cx.time().ticks() - cx.time().ticks() % u64::from(st.window_ticks(cx, did));
        st.windowed(cx, did, &w, end, out)
    }
}

impl State {
    /// The current bytes of data set `did` into `out` (its encoder's, from
    /// [`Encoders::ENCODERS`]); its size (0: not served).
    pub(super) fn image_of<C: Context<Integrals>>(
        &self,
        cx: &mut C,
        did: u8,
        out: &mut Image,
        now: Instant,
    ) -> usize {
        match C::ENCODERS.iter().find(|e| e.0 == did) {
            Some((_, encode)) => encode(self, cx, did, now, out),
            None => 0,
        }
    }

    /// IMU / IMU_RAW / PIMU (and IMU_MAG / PIMU_MAG: the same then the
    /// magnetometer at the window's end) of the window `w` into `image`
    /// (module doc); its size.
    pub(super) fn windowed(
        &self,
        cx: &impl Context<Integrals>,
        did: u8,
        w: &Increment,
        end_tick: u64,
        image: &mut [u8; did::MAX_SIZE],
    ) -> usize {
        let h = cx.chain().health();
        let status = imu_status_of(&h);
        // On the sample grid: the tick that ends the window.
        let time = end_tick as f64 / f64::from(rate(cx));
        let dt = w.samples as f64 / f64::from(rate(cx));
        let mut out = [0u8; sets::pimu::SIZE];
        let base = if matches!(did, did::PIMU | did::PIMU_MAG) {
            out.copy_from_slice(
                &Pimu {
                    time,
                    dt: dt as f32,
                    status,
                    theta: frd(w.dtheta_rad),
                    vel: frd(w.dv_mps),
                }
                .encode(),
            );
            sets::pimu::SIZE
        } else {
            let (pqr, acc) = if w.samples > 0 {
                let inv = 1.0 / dt;
                let mean = |v: [f64; 3]| frd([v[0] * inv, v[1] * inv, v[2] * inv]);
                (mean(w.dtheta_raw_rad), mean(w.dv_raw_mps))
            } else {
                // No whole period measured yet (a GET right after power-on):
                // the last measurement, as SYS_SENSORS reports it, not zeros.
                last_measurement(cx)
            };
            if did == did::IMU3_RAW {
                // The chain has one sensor: IMU_RAW averages the three
                // IMUs, so each of them reads what IMU_RAW reads
                // (`docs/isb-data-sets.md` "IMU3_RAW").
                let one = Imus { pqr, acc };
                let b = Imu3 {
                    time,
                    status,
                    imu: [one; 3],
                }
                .encode();
                image[..b.len()].copy_from_slice(&b);
                return b.len();
            }
            out[..sets::imu::SIZE].copy_from_slice(
                &Imu {
                    time,
                    status,
                    pqr,
                    acc,
                }
                .encode(),
            );
            sets::imu::SIZE
        };
        image[..base].copy_from_slice(&out[..base]);
        if !matches!(did, did::IMU_MAG | did::PIMU_MAG) {
            return base;
        }
        let truth = self.truth(cx);
        let m = ins::magnetometer(time, self.nav.magnetometer(&truth, end_tick)).encode();
        image[base..base + m.len()].copy_from_slice(&m);
        base + m.len()
    }

    /// MAG_CAL now (`docs/isb-data-sets.md` "MAG_CAL"): the
    /// recalibration's state and progress ([`magcal`]); the declination is
    /// FLASH_CONFIG's `magDeclination`.
    pub(super) fn mag_cal_of(&self) -> MagCal {
        MagCal {
            state: self.mag_cal.state(),
            progress: self.mag_cal.progress(),
            declination: le::f32(&self.cfg.0, flash::MAG_DECLINATION),
        }
    }

    /// What RTOS_INFO reports of the unit's work ([`rtos`]).
    pub(super) fn rtos_schedule(&self, cx: &impl Context<Integrals>) -> rtos::Schedule {
        rtos::Schedule {
            rate_hz: rate(cx),
            ticks: cx.time().ticks(),
            imu_dt_ms: self.imu_dt_ms,
            nav_dt_ms: self.nav_dt_ms,
            step_ms: ins::STEP_MS,
            step_offset: self.grid_ticks(cx, self.nav_dt_ms) / 2,
        }
    }

    /// SYS_SENSORS now: the last measurement (body axes), the magnetometer
    /// and barometer, the temperatures; supply 5 V, analog inputs 0.
    pub(super) fn sys_sensors(&self, cx: &impl Context<Integrals>) -> SysSensors {
        let tick = cx.time().ticks();
        let time = tick as f64 / f64::from(rate(cx));
        let truth = self.truth(cx);
        let (g, a) = last_measurement(cx);
        let temp = cx.chain().temperature();
        let bar = self.nav.pressure_kpa(&truth, tick);
        let b = ins::barometer(time, bar, temp);
        SysSensors {
            time,
            temp,
            pqr: g,
            acc: a,
            mag: self.nav.magnetometer(&truth, tick),
            bar,
            bar_temp: temp,
            msl_bar: b.msl_bar,
            humidity: b.humidity,
            vin: 5.0,
            ana: [0.0; 3],
        }
    }
}

/// The chain's last measurement in the IMX body frame: rate (rad/s) and
/// specific force (m/s²).
fn last_measurement(cx: &impl Context<Integrals>) -> ([f32; 3], [f32; 3]) {
    let [g, a, _] = cx.chain().last_sensor();
    (
        frd(g.map(|x| f64::from(x).to_radians())),
        frd(a.map(|x| f64::from(x) * f64::from(crate::math::G))),
    )
}

/// `(x, y, z)` of the chain's carrier frame (the KERNEL's housing axes:
/// right, forward, up; ICD Figure 2.2) in the IMX body frame (forward,
/// right, down), the vehicle's body frame ([`crate::vehicle::housing_to_body`]),
/// so an IMX on a vehicle reads forward motion on its x axis.
fn frd(v: [f64; 3]) -> [f32; 3] {
    crate::vehicle::housing_to_body(&v).map(|x| x as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::personality::fake::FakeContext;

    #[test]
    fn every_data_set_has_one_encoder_in_table_order() {
        let dids: heapless::Vec<u8, 64> = FakeContext::<Integrals>::ENCODERS
            .iter()
            .map(|e| e.0)
            .collect();
        let served: heapless::Vec<u8, 64> = did::DATA_SETS.iter().map(|s| s.did).collect();
        assert_eq!(dids, served);
    }
}
