//! The plot of `imu-emu allan`, in the host tools' one plot style
//! ([`crate::plot`]): the Allan deviation of each axis on log-log axes,
//! one panel for the gyros (°/s), one for the accelerometers (g) and, on
//! the K120/K220, one for the aux accelerometer (g), with the profile's
//! lines (white noise N/√τ, the bias-instability floor 0.6643·B, the random
//! walk K·√(τ/3) where the profile has one) dashed.

use super::deviation::{Curve, FLICKER_FLOOR};
use crate::plot::{Corner, Figure, Panel, Scale, Series};
use imu_emu::sensor::profile::{SensorProfile, SensorSpec};

/// The figure of `curves` (three per sensor: gyro, acc, then aux if
/// present), with `profile`'s lines over the τ the curves cover.
pub fn figure(title: &str, curves: &[Curve], profile: Option<&SensorProfile>) -> Figure {
    let sensors = [
        ("gyro", "°/s", profile.map(|p| &p.gyro)),
        ("acc", "g", profile.map(|p| &p.acc)),
        ("aux acc", "g", profile.map(|p| &p.aux)),
    ];
    let panels = curves
        .chunks(3)
        .zip(sensors)
        .map(|(axes, (name, unit, spec))| {
            let mut series: Vec<Series> = axes
                .iter()
                .zip(["X", "Y", "Z"])
                .map(|(c, axis)| Series {
                    name: format!("{name} {axis}"),
                    points: c.points.iter().map(|p| (p.0, p.1)).collect(),
                    reference: false,
                })
                .collect();
            let taus = axes.iter().flat_map(|c| c.points.iter().map(|p| p.0));
            let (t0, t1) = taus.fold((f64::INFINITY, 0.0f64), |(a, b), t| (a.min(t), b.max(t)));
            if let Some(spec) = spec {
                if t1 > t0 {
                    series.extend(profile_lines(spec, t0, t1));
                }
            }
            Panel {
                title: format!("{name} ({unit})"),
                y_label: format!("Allan deviation σ(τ) ({unit})"),
                y_scale: Scale::Log,
                series,
                legend: Corner::LowerLeft,
            }
        })
        .collect();
    Figure {
        title: format!("Allan deviation: {title}"),
        x_label: "averaging time τ (s)".into(),
        x_scale: Scale::Log,
        panels,
    }
}

/// A profile term: legend, coefficient, σ(coefficient, τ).
type ProfileTerm = (&'static str, f64, fn(f64, f64) -> f64);

/// The profile's terms over τ ∈ [t0, t1] (a term the profile lacks is
/// left out).
fn profile_lines(spec: &SensorSpec, t0: f64, t1: f64) -> Vec<Series> {
    let n = f64::from(spec.noise_density);
    let b = f64::from(spec.bias_instability) * FLICKER_FLOOR;
    let k = f64::from(spec.rate_random_walk);
    let terms: [ProfileTerm; 3] = [
        ("profile: white N/√τ", n, |n, t| n / t.sqrt()),
        ("profile: 0.6643·B (bias instability)", b, |b, _| b),
        ("profile: RRW K·√(τ/3)", k, |k, t| k * (t / 3.0).sqrt()),
    ];
    terms
        .into_iter()
        .filter(|t| t.1 > 0.0)
        .map(|(name, v, f)| Series {
            name: name.into(),
            points: (0..=60)
                .map(|i| t0 * (t1 / t0).powf(f64::from(i) / 60.0))
                .map(|t| (t, f(v, t)))
                .collect(),
            reference: true,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panel_per_sensor_with_the_profile_lines_it_has() {
        let c = Curve {
            points: vec![(1.0, 1e-3, 100.0), (10.0, 3e-4, 10.0)],
        };
        let p = imu_emu::sensor::profiles::KERNEL_MID;
        let f = figure("t", &vec![c; 9], Some(&p));
        assert_eq!(f.panels.len(), 3);
        // Three axes, white and floor (no random walk in the profile).
        assert_eq!(f.panels[2].series.len(), 5);
        assert_eq!(f.panels[2].title, "aux acc (g)");
        assert!(f.panels[0].series[3].reference && !f.panels[0].series[2].reference);
    }
}
