//! The IMX-5's ±4000 °/s gyro range (docs/sensors.md "Fixed point: the
//! IMX-5's ±4000 °/s") in the float build and (with `--features
//! fixed-point`) the fixed-point build, which carries rates up to
//! ±4095 °/s (`RATE_TRUTH_LIMIT`): the two engines agree beyond 2048 °/s,
//! a chain reads 3000 and 3900 °/s on each axis, saturates at the range
//! with the over-range flag beyond it, and no configuration overflows (a
//! debug build panics on an integer overflow) at ±4095 °/s on all axes.

use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::dsp::OutputVariant;
use imu_emu::math::{GYRO_BITS, RATE_TRUTH_LIMIT};
use imu_emu::model::Product;
use imu_emu::sensor::errors::{TriadEngine, TriadEngineFixed};
use imu_emu::sensor::profiles::IMX5_PROFILE;
use imu_emu::sensor::rng::Rng;
use imu_emu::sensor::{ErrorModel, Motion, Truth};
use imu_emu::time::Instant;

const DT: f32 = 1.0 / 2000.0;

/// A rate of `dps` about `axis` (1 g up on Z).
fn spin(axis: usize, dps: f32) -> Truth {
    let mut rate_dps = [0.0; 3];
    rate_dps[axis] = dps;
    Truth {
        rate_dps,
        specific_force_g: [0.0, 0.0, 1.0],
        temperature_c: None,
    }
}

/// The float and the fixed-point engines, on the IMX-5 profile's gyro
/// errors (bias, scale factor, misalignment, noise, bandwidth), read the
/// same rate beyond 2048 °/s to well within the noise (the fixed point's
/// LSB is 1.9e-6 °/s), and both saturate at 4000 °/s with the flag.
#[test]
fn float_and_fixed_engines_agree_up_to_the_range() {
    let e = ErrorModel::from_profile(&IMX5_PROFILE, &mut Rng::new(3)).gyro;
    let unit = 1.0 / f64::from(1u32 << GYRO_BITS);
    for axis in 0..3 {
        for dps in [3000.0f32, 3900.0, -3900.0, 4500.0, -4500.0] {
            let mut fl = TriadEngine::new(4000.0);
            fl.configure(&e, 25.0, DT);
            let mut fx = TriadEngineFixed::new(4000.0, GYRO_BITS);
            fx.configure(&e, 25.0, DT);
            let (mut r1, mut r2) = (Rng::new(11), Rng::new(11));
            let t = spin(axis, dps).bounded();
            let force = [0, 0, 1 << 23];
            let fixed_truth = imu_emu::sensor::motion::TruthFixed::from_truth(&t).rate;
            let (mut s1, mut s2) = (0.0f64, 0.0f64);
            let n = 200;
            for _ in 0..n {
                let (a, o1) = fl.measure(&t.rate_dps, &t.specific_force_g, &mut r1);
                let (b, o2) = fx.measure(&fixed_truth, &force, &mut r2);
                assert_eq!(o1, o2, "over-range mask, axis {axis}, {dps} °/s");
                assert_eq!(o1 != 0, dps.abs() > 4000.0, "axis {axis}, {dps} °/s");
                s1 += f64::from(a[axis]);
                s2 += f64::from(b[axis]) * unit;
            }
            let (m1, m2) = (s1 / f64::from(n), s2 / f64::from(n));
            if dps.abs() > 4000.0 {
                assert_eq!(m1, 4000.0f64.copysign(f64::from(dps)));
                assert!((m2 - m1).abs() < 1e-5, "{m2} vs {m1}");
            } else {
                // Bias and scale factor within a percent; the two agree to
                // the f32's precision at 4000 °/s (and the noise's
                // rounding).
                assert!((m1 / f64::from(dps) - 1.0).abs() < 0.01, "{m1} at {dps}");
                assert!((m2 - m1).abs() < 2e-3, "axis {axis}, {dps}: {m2} vs {m1}");
            }
        }
    }
}

/// An IMX-5 chain (its profile, FIR, bandwidth) spun at 3000 and
/// 3900 °/s about each axis reads the rate; at 4500 °/s it reads the
/// range, 4000 °/s, with the over-range flag — the same in both builds.
#[test]
fn an_imx5_chain_reads_up_to_its_range_and_flags_beyond() {
    let p = Product::imx5();
    for axis in 0..3 {
        for dps in [3000.0f32, -3000.0, 3900.0, -3900.0, 4500.0, -4500.0] {
            let mut c = SignalChain::unpowered(p);
            c.set_profile(Some(&IMX5_PROFILE));
            c.reset(p, 5);
            c.faults_mut().temperature_c = Some(33.0);
            c.set_motion(Motion::Sample(spin(axis, dps)));
            let mut over = 0;
            // 0.1 s to fill the FIR, then a 0.1 s interval.
            for t in 1..=400u64 {
                c.tick(Instant::from_micros(500 * t));
                if t == 200 {
                    c.output();
                } else if t > 200 {
                    over |= c.health().gyro_over_range;
                }
            }
            let out = c.output();
            let g = out.gyro[axis];
            if dps.abs() > 4000.0 {
                assert_eq!(over, 1 << axis, "axis {axis}, {dps} °/s");
                assert!((g - 4000.0f32.copysign(dps)).abs() < 0.01, "{g} at {dps}");
            } else {
                assert_eq!(over, 0, "axis {axis}, {dps} °/s");
                assert!((g / dps - 1.0).abs() < 0.01, "axis {axis}: {g} at {dps}");
            }
            for (i, v) in out.gyro.iter().enumerate() {
                if i != axis {
                    // Misalignment: within a percent of the rate.
                    assert!(v.abs() < 0.01 * dps.abs(), "axis {i}: {v} at {dps}");
                }
            }
        }
    }
}

/// Every configuration that carries the rate (mounting, the FIR's LPF,
/// the bandwidth, all cascade filters, the incremental variant, the
/// AHRS) at ±4095 °/s on all three axes at once, every sign: many ticks
/// without an overflow (a debug build panics on one) and outputs at the
/// range.
#[test]
fn the_largest_rates_on_every_axis_do_not_overflow() {
    let p = Product::imx5();
    let max = RATE_TRUTH_LIMIT as f32 / (1u32 << GYRO_BITS) as f32;
    for signs in 0..8u32 {
        let s = |i: u32| if signs >> i & 1 == 0 { max } else { -max };
        for (mounting, lpf, variant) in [
            ([0.0; 3], Bandwidth::Off, OutputVariant::Instant),
            (
                [10.0, -45.0, 30.0],
                Bandwidth::Hz262,
                OutputVariant::Incremental,
            ),
            ([45.0, 35.26, 0.0], Bandwidth::Hz16, OutputVariant::Average),
        ] {
            let mut c = SignalChain::unpowered(p);
            c.set_profile(Some(&IMX5_PROFILE));
            c.reset(p, 9);
            let mut cfg = ChainConfig::defaults(&p);
            cfg.lpf = lpf;
            cfg.cascade.mask = 7;
            cfg.output_variant = variant;
            cfg.alignment_angles_deg = mounting;
            c.configure(&cfg);
            c.set_motion(Motion::Sample(Truth {
                rate_dps: [s(0), s(1), s(2)],
                specific_force_g: [0.0, 0.0, 1.0],
                temperature_c: None,
            }));
            for t in 1..=4000u64 {
                c.tick(Instant::from_micros(500 * t));
                if t % 20 == 0 {
                    let o = c.output();
                    assert!(o.gyro.iter().all(|v| v.is_finite() && v.abs() < 8000.0));
                }
            }
            assert_ne!(c.health().gyro_over_range, 0);
            let q = c.attitude_mut().quat();
            let n = q.iter().map(|v| v * v).sum::<f32>();
            assert!((n - 1.0).abs() < 1e-3, "attitude norm² {n}");
        }
    }
}
