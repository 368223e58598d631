//! The magnetometer recalibration behind DID_MAG_CAL (`mag_cal_t`, SDK
//! 2.7.1 `data_sets.h`; `docs/isb-data-sets.md` "MAG_CAL"): a command
//! (1 multi-axis, 2 single-axis) starts it, 101 aborts it; while it runs
//! `insStatus` has MAG_RECALIBRATING and MAG_CAL reads state 200 with a
//! progress computed from the magnetometer readings the unit takes — how
//! much of the turn the field has made in the body frame; at 100 % it ends
//! (state 201, `hdwStatus` MAG_RECAL_COMPLETE) and its result — the field's
//! magnitude and dip seen over the manoeuvre — becomes the reference the
//! navigation filter checks readings against. A unit that is not turned
//! never finishes.
//!
//! Coverage (the emulator's measure: the release's algorithm is not in
//! the SDK): the bearing of the field about a body axis, in [`SECTORS`]
//! sectors of 10°. Single-axis: about the body z axis (the unit turned
//! through 360° in heading, level). Multi-axis: the two best-covered of
//! the three body axes (turned through 360° about two axes).

use libm::{asin, atan2, sqrt};

use super::aux_sets::mag_cal_state as st;

/// `insStatus` MAG_RECALIBRATING (`eInsStatusFlags`).
pub(crate) const INS_STATUS_MAG_RECALIBRATING: u32 = 0x0040_0000;
/// `hdwStatus` MAG_RECAL_COMPLETE (`eHdwStatusFlags`).
pub(crate) const HDW_STATUS_MAG_RECAL_COMPLETE: u32 = 0x0000_4000;
/// Bearing sectors per axis (10° each).
pub(crate) const SECTORS: u32 = 36;

/// One recalibration (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Recal {
    /// `eMagCalState` as MAG_CAL reads it: 0, 200 running, 201 done.
    state: u32,
    /// The command that started it (1 multi-axis, 2 single-axis).
    mode: u32,
    /// Sectors the field's bearing visited about body z, x, y.
    cover: [u64; 3],
    /// Sums of the readings' magnitude and dip, and their count.
    norm_sum: f64,
    dip_sum: f64,
    n: u32,
}

impl Recal {
    /// A `state` written by a host: 1 or 2 start a recalibration (a
    /// running one starts over), 101 ends one without a result; any other
    /// value changes nothing.
    pub(crate) fn command(&mut self, state: u32) {
        match state {
            st::MULTI_AXIS | st::SINGLE_AXIS => {
                *self = Recal {
                    state: st::RECAL_RUNNING,
                    mode: state,
                    ..Recal::default()
                }
            }
            st::ABORT => *self = Recal::default(),
            _ => {}
        }
    }

    /// Whether it runs.
    pub(crate) fn running(&self) -> bool {
        self.state == st::RECAL_RUNNING
    }

    /// Whether the last one finished (until the next command or reset).
    pub(crate) fn complete(&self) -> bool {
        self.state == st::RECAL_COMPLETE
    }

    /// MAG_CAL `state`.
    pub(crate) fn state(&self) -> u32 {
        self.state
    }

    /// MAG_CAL `progress`, % (100 once done, 0 when none ran).
    pub(crate) fn progress(&self) -> f32 {
        match self.state {
            st::RECAL_COMPLETE => 100.0,
            st::RECAL_RUNNING => self.coverage() * 100.0,
            _ => 0.0,
        }
    }

    /// The covered share, 0..1 (module doc).
    fn coverage(&self) -> f32 {
        let mut c = self.cover.map(u64::count_ones);
        c.sort_unstable();
        let got = if self.mode == st::SINGLE_AXIS {
            self.cover[0].count_ones()
        } else {
            (c[1] + c[2]) / 2
        };
        got as f32 / SECTORS as f32
    }

    /// A magnetometer reading `m` (body axes) and the same levelled with
    /// the INS's roll and pitch (`level`): its bearings are covered, its
    /// magnitude and dip summed; when the coverage is whole the
    /// recalibration ends with its result, the mean magnitude and dip
    /// (rad), returned once.
    pub(crate) fn feed(&mut self, m: &[f32; 3], level: &[f64; 3]) -> Option<(f64, f64)> {
        if !self.running() {
            return None;
        }
        let m = m.map(f64::from);
        let norm = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if !norm.is_finite() || norm <= 0.0 {
            return None;
        }
        for (k, (a, b)) in [(m[0], m[1]), (m[1], m[2]), (m[2], m[0])]
            .into_iter()
            .enumerate()
        {
            self.cover[k] |= 1 << sector(atan2(b, a));
        }
        self.norm_sum += norm;
        self.dip_sum += asin((level[2] / norm).clamp(-1.0, 1.0));
        self.n += 1;
        if self.coverage() < 1.0 {
            return None;
        }
        self.state = st::RECAL_COMPLETE;
        let n = f64::from(self.n);
        Some((self.norm_sum / n, self.dip_sum / n))
    }
}

/// The sector of bearing `a` (rad, −π..π).
fn sector(a: f64) -> u32 {
    let s = ((a + core::f64::consts::PI) / core::f64::consts::TAU * f64::from(SECTORS)) as u32;
    s.min(SECTORS - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn turn(r: &mut Recal, steps: u32, axis: usize) -> Option<(f64, f64)> {
        let mut out = None;
        for i in 0..steps {
            let a = f64::from(i) / f64::from(steps) * core::f64::consts::TAU;
            // A field of magnitude 1, dip 60°, turned about `axis`.
            let (h, v) = (0.5f64, 0.866f64);
            let (c, s) = (libm::cos(a), libm::sin(a));
            let m = match axis {
                2 => [h * c, h * s, v],
                _ => [v, h * c, h * s],
            };
            let m32 = m.map(|x| x as f32);
            out = out.or(r.feed(&m32, &[h, 0.0, v]));
        }
        out
    }

    #[test]
    fn single_axis_completes_with_a_whole_turn_in_heading() {
        let mut r = Recal::default();
        r.command(st::SINGLE_AXIS);
        assert_eq!(r.state(), 200);
        assert!(turn(&mut r, 100, 2).is_none() || r.complete());
        assert!(r.complete());
        assert_eq!(r.progress(), 100.0);
    }

    #[test]
    fn multi_axis_needs_two_axes_and_a_fixed_field_gets_nowhere() {
        let mut r = Recal::default();
        r.command(st::MULTI_AXIS);
        for _ in 0..100 {
            r.feed(&[0.5, 0.0, 0.866], &[0.5, 0.0, 0.866]);
        }
        assert!(r.running() && r.progress() < 5.0, "{}", r.progress());
        assert!(turn(&mut r, 200, 2).is_none());
        assert!(r.running() && r.progress() < 100.0);
        let (norm, dip) = turn(&mut r, 200, 0).expect("done");
        assert!(r.complete());
        assert!((norm - 1.0).abs() < 1e-3, "{norm}");
        assert!((dip - core::f64::consts::FRAC_PI_3).abs() < 1e-3, "{dip}");
        r.command(st::ABORT);
        assert_eq!((r.state(), r.progress()), (0, 0.0));
    }
}
