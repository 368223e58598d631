//! The output variant accumulator of ICD 5.3.6 (Output_Variant, and
//! Average_Output_Data which forces the average).
//!
//! Every tick adds the FIR-filtered gyro/acc/aux-acc and the cascade-filtered
//! channels; at an output tick [`VariantAccumulator::take`] gives, over the
//! interval since the previous output:
//!
//! - **Instant**: the last tick's values.
//! - **Average**: the mean of the interval's ticks ("if the IMU's data rate is
//!   500 Hz, … the mean of four values"; at the internal rate it is instant).
//! - **Incremental**: the angle increment Δθ and the velocity increment Δv
//!   over the interval, *divided by the interval* (5.3.6: "between the two
//!   data messages, divided by the time step of data output"), so the fields
//!   keep their °/s and g units (Table 5.15's "deg·KG"/"g·s·KA" describe Δθ
//!   and Δv before that division;
//!   [`crate::chain::SignalChain::output_interval`] gives them back). Δθ is the rotation vector over the interval with the
//!   two-sample coning correction `½ Σ α_{k−1} × Δα_k`; Δv carries the
//!   rotation compensation `½ α × υ` and the sculling correction
//!   `½ Σ (α_{k−1} × Δυ_k + υ_{k−1} × Δα_k)`, expressed in the body frame at
//!   the start of the interval. Without rotation it equals the average.
//!
//! The cascade-filtered channels (UDD 0x2D, 0x91, 0x92) are rates and
//! accelerations by definition (Table 5.15: deg/s, g), so they are instant in
//! the Instant variant and averaged otherwise.
//!
//! Sums are taken of the differences from the interval's first sample, which
//! keeps f32 rounding at the level of the signal's variation, not its size.

// Numeric code indexes parallel arrays (axes, channels) by one index.
#![allow(clippy::needless_range_loop)]

use super::fir::CHANNELS;
use crate::ahrs::rotation::{cross, Vec3};

/// Output_Variant (Table 5.24; 5.3.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OutputVariant {
    /// 0: instant values.
    #[default]
    Instant,
    /// 1: the mean over the output interval.
    Average,
    /// 2: Δθ/T and Δv/T over the output interval.
    Incremental,
}

impl OutputVariant {
    /// The variant of Output_Variant and Average_Output_Data: averaged data
    /// on forces [`OutputVariant::Average`]; Output_Variant values above 2
    /// read as instant.
    pub fn from_params(output_variant: u8, average_output_data: u8) -> Self {
        if average_output_data == 1 {
            return OutputVariant::Average;
        }
        match output_variant {
            1 => OutputVariant::Average,
            2 => OutputVariant::Incremental,
            _ => OutputVariant::Instant,
        }
    }
}

/// What [`VariantAccumulator::take`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VariantOutput {
    /// Gyro, acc, aux acc per the variant (°/s, g).
    pub main: [f32; CHANNELS],
    /// Cascade-filtered channels (°/s, g).
    pub filtered: [f32; CHANNELS],
    /// Ticks in the interval.
    pub ticks: u32,
}

/// The accumulator (module doc).
#[derive(Debug, Clone)]
pub struct VariantAccumulator {
    variant: OutputVariant,
    dt: f32,
    n: u32,
    first: [f32; CHANNELS],
    first_f: [f32; CHANNELS],
    sum: [f32; CHANNELS],
    sum_f: [f32; CHANNELS],
    last: [f32; CHANNELS],
    last_f: [f32; CHANNELS],
    /// Σ Δα (rad), coning term (rad).
    alpha: Vec3,
    coning: Vec3,
    /// Σ Δυ (g·s) per accelerometer, sculling term.
    upsilon: [Vec3; 2],
    sculling: [Vec3; 2],
}

const DEG: f32 = core::f32::consts::PI / 180.0;

impl VariantAccumulator {
    /// An empty accumulator for ticks of `dt` seconds.
    pub fn new(variant: OutputVariant, dt: f32) -> Self {
        VariantAccumulator {
            variant,
            dt,
            n: 0,
            first: [0.0; CHANNELS],
            first_f: [0.0; CHANNELS],
            sum: [0.0; CHANNELS],
            sum_f: [0.0; CHANNELS],
            last: [0.0; CHANNELS],
            last_f: [0.0; CHANNELS],
            alpha: [0.0; 3],
            coning: [0.0; 3],
            upsilon: [[0.0; 3]; 2],
            sculling: [[0.0; 3]; 2],
        }
    }

    /// The variant.
    pub fn variant(&self) -> OutputVariant {
        self.variant
    }

    /// Starts a new interval (keeps the last values for an empty interval).
    pub fn reset(&mut self) {
        self.n = 0;
        self.sum = [0.0; CHANNELS];
        self.sum_f = [0.0; CHANNELS];
        self.alpha = [0.0; 3];
        self.coning = [0.0; 3];
        self.upsilon = [[0.0; 3]; 2];
        self.sculling = [[0.0; 3]; 2];
    }

    /// Adds one tick: `main` = FIR outputs, `filtered` = cascade outputs.
    #[inline]
    pub fn add(&mut self, main: &[f32; CHANNELS], filtered: &[f32; CHANNELS]) {
        self.last = *main;
        self.last_f = *filtered;
        if self.variant == OutputVariant::Instant {
            self.n += 1;
            return;
        }
        if self.n == 0 {
            self.first = *main;
            self.first_f = *filtered;
        }
        self.n += 1;
        for c in 0..CHANNELS {
            self.sum[c] += main[c] - self.first[c];
            self.sum_f[c] += filtered[c] - self.first_f[c];
        }
        if self.variant == OutputVariant::Incremental {
            let k = self.dt * DEG;
            let da = [main[0] * k, main[1] * k, main[2] * k];
            let a0 = self.alpha;
            let c = cross(&a0, &da);
            for (i, ci) in c.iter().enumerate() {
                self.coning[i] += 0.5 * ci;
            }
            for s in 0..2 {
                let b = 3 + 3 * s;
                let dv = [
                    main[b] * self.dt,
                    main[b + 1] * self.dt,
                    main[b + 2] * self.dt,
                ];
                let u0 = self.upsilon[s];
                let t1 = cross(&a0, &dv);
                let t2 = cross(&u0, &da);
                for i in 0..3 {
                    self.sculling[s][i] += 0.5 * (t1[i] + t2[i]);
                    self.upsilon[s][i] += dv[i];
                }
            }
            for i in 0..3 {
                self.alpha[i] += da[i];
            }
        }
    }

    /// The interval's output per the variant; starts a new interval.
    pub fn take(&mut self) -> VariantOutput {
        let n = self.n;
        let mut out = VariantOutput {
            main: self.last,
            filtered: self.last_f,
            ticks: n.max(1),
        };
        if n > 0 && self.variant != OutputVariant::Instant {
            let inv = 1.0 / n as f32;
            for c in 0..CHANNELS {
                out.main[c] = self.first[c] + self.sum[c] * inv;
                out.filtered[c] = self.first_f[c] + self.sum_f[c] * inv;
            }
            if self.variant == OutputVariant::Incremental {
                let t = n as f32 * self.dt;
                let k = 1.0 / (t * DEG);
                for i in 0..3 {
                    out.main[i] = (self.alpha[i] + self.coning[i]) * k;
                }
                for s in 0..2 {
                    let b = 3 + 3 * s;
                    let rot = cross(&self.alpha, &self.upsilon[s]);
                    for i in 0..3 {
                        out.main[b + i] =
                            (self.upsilon[s][i] + 0.5 * rot[i] + self.sculling[s][i]) / t;
                    }
                }
            }
        }
        self.reset();
        out
    }
}
