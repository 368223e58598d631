//! The INS phases and `insStatus` of the IMX-5's navigation filter, set
//! from the filter's own covariance and aiding state (`docs/navigation.md`
//! "Status"; the bits: SDK 2.7.1 `eInsStatusFlags`,
//! [`crate::isb::nav_sets::ins_status`]).
//!
//! | bit | set when |
//! |---|---|
//! | HDG_ALIGN_FINE / COARSE | heading σ < [`HDG_FINE_RAD`] / < [`HDG_COARSE_RAD`] |
//! | VEL_ALIGN_FINE / COARSE | NAV, horizontal velocity σ (larger axis) < [`VEL_FINE_MPS`] / < [`VEL_COARSE_MPS`] |
//! | POS_ALIGN_FINE / COARSE | NAV, horizontal position σ (larger axis) < [`POS_FINE_M`] / < [`POS_COARSE_M`] |
//! | GPS_AIDING_POS, _VEL, fix 3D | NAV and the receiver has a fix (its updates enter the filter) |
//! | GPS_UPDATE_IN_SOLUTION | a GNSS update corrected the state in the last navigation period (the position may step there; everywhere else it is the integral of the velocity) |
//! | GPS_AIDING_HEADING | the above while moving faster than [`super::GPS_HEADING_MIN_SPEED`] |
//! | MAG_AIDING_HEADING | the last magnetometer heading entered the filter |
//! | MAG_INTERFERENCE_OR_BAD_CAL | the last magnetometer sample was refused (field or dip unlike alignment's, or gated) |
//! | NAV_MODE | NAV (from the first fix on) |
//! | solution | 0 off (no filter: [`super::NavState::set_enabled`]); 1 aligning; AHRS 5, or 6 when tilt σ > [`TILT_HIGH_VAR_RAD`] or heading σ > [`HDG_COARSE_RAD`]; NAV 3, or 4 when the position is no longer FINE |

use super::filter::{Filter, ATT, POS, VEL};
use crate::isb::nav_sets::ins_status::*;

/// Heading σ below which the heading is fine, rad (1°).
pub(crate) const HDG_FINE_RAD: f32 = 0.017_45;
/// Heading σ below which the heading is usable (coarse), rad (10°).
pub(crate) const HDG_COARSE_RAD: f32 = 0.174_5;
/// Roll/pitch σ above which an AHRS reports high variance, rad (2°).
pub(crate) const TILT_HIGH_VAR_RAD: f32 = 0.034_9;
/// Horizontal velocity σ below which the velocity is fine, m/s.
pub(crate) const VEL_FINE_MPS: f32 = 0.5;
/// … usable (coarse), m/s.
pub(crate) const VEL_COARSE_MPS: f32 = 5.0;
/// Horizontal position σ below which the position is fine, m.
pub(crate) const POS_FINE_M: f32 = 5.0;
/// … usable (coarse), m.
pub(crate) const POS_COARSE_M: f32 = 500.0;

/// The phase of the INS after power-on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// No navigation filter runs ([`super::NavState::set_enabled`]: an
    /// image whose processor cannot afford it): no solution.
    Off,
    /// Coarse alignment: the unit is assumed still, its accelerometers and
    /// magnetometer averaged ([`super::ALIGN_S`]).
    Aligning,
    /// Attitude and heading only: no GNSS fix yet.
    Ahrs,
    /// Position, velocity and attitude, GNSS-aided or dead reckoning.
    Nav,
}

/// What `insStatus` is made of.
pub(crate) struct Inputs<'a> {
    /// The phase.
    pub phase: Phase,
    /// The filter (its covariance).
    pub kf: &'a Filter,
    /// The receiver has a fix.
    pub fixed: bool,
    /// The last magnetometer heading was fused.
    pub mag_aiding: bool,
    /// The last magnetometer sample was refused.
    pub mag_interference: bool,
    /// Heading observable from GNSS (moving with a fix).
    pub gps_heading: bool,
    /// A GNSS update entered the solution in the last period.
    pub gps_step: bool,
}

/// `insStatus` of `x` (module doc).
pub fn ins_status(x: &Inputs<'_>) -> u32 {
    let kf = x.kf;
    let hdg = kf.sigma(ATT + 2);
    let tilt = kf.sigma(ATT).max(kf.sigma(ATT + 1));
    let mut s = 0;
    match x.phase {
        Phase::Off => return SOLUTION_OFF << SOLUTION_SHIFT,
        Phase::Aligning => return SOLUTION_ALIGNING << SOLUTION_SHIFT,
        _ => {}
    }
    if hdg < HDG_FINE_RAD {
        s |= HDG_ALIGN_FINE;
    } else if hdg < HDG_COARSE_RAD {
        s |= HDG_ALIGN_COARSE;
    }
    if x.mag_aiding {
        s |= MAG_AIDING_HEADING;
    }
    if x.mag_interference {
        s |= MAG_INTERFERENCE_OR_BAD_CAL;
    }
    if x.phase == Phase::Ahrs {
        let sol = if tilt > TILT_HIGH_VAR_RAD || hdg > HDG_COARSE_RAD {
            SOLUTION_AHRS_HIGH_VARIANCE
        } else {
            SOLUTION_AHRS
        };
        return s | (sol << SOLUTION_SHIFT);
    }
    s |= NAV_MODE;
    let vel = kf.sigma(VEL).max(kf.sigma(VEL + 1));
    let pos = kf.sigma(POS).max(kf.sigma(POS + 1));
    if vel < VEL_FINE_MPS {
        s |= VEL_ALIGN_FINE;
    } else if vel < VEL_COARSE_MPS {
        s |= VEL_ALIGN_COARSE;
    }
    let fine = pos < POS_FINE_M;
    if fine {
        s |= POS_ALIGN_FINE;
    } else if pos < POS_COARSE_M {
        s |= POS_ALIGN_COARSE;
    }
    if x.fixed {
        s |= GPS_AIDING_POS | GPS_AIDING_VEL | (GPS_NAV_FIX_3D << GPS_NAV_FIX_SHIFT);
        if x.gps_heading {
            s |= GPS_AIDING_HEADING;
        }
        if x.gps_step {
            s |= GPS_UPDATE_IN_SOLUTION;
        }
    }
    let sol = if fine {
        SOLUTION_NAV
    } else {
        SOLUTION_NAV_HIGH_VARIANCE
    };
    s | (sol << SOLUTION_SHIFT)
}
