//! Motion beyond what `f32` or the sensor holds saturates as a real sensor
//! does: the axes read the range and the USW range bits (ICD Table 5.26,
//! bits 10–12, gyro X/Y/Z) are set — never all-zero axes with USW 0
//! (the host runner under abuse: a trajectory value of 3.5e38,
//! `motion rotate 1e6 0 0`).

use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::kernel::status::{self, usw};
use imu_emu::math::rotation::QuatIntegrator;
use imu_emu::model::Product;
use imu_emu::sensor::{ErrorModel, Motion, Truth};
use imu_emu::time::Instant;

/// Runs `n` ticks of 0.5 ms (the K110's 2 kHz).
fn ticks(c: &mut SignalChain, t: &mut u64, n: u64) {
    for _ in 0..n {
        *t += 1;
        c.tick(Instant::from_micros(500 * *t));
    }
}

/// A K110 with its FIR off; ideal sensors when `ideal`, else the model's
/// own errors (misalignment included: the products where ∞·0 gave NaN).
fn chain(code: &str, ideal: bool) -> SignalChain {
    let p = Product::parse(code).unwrap();
    let mut c = SignalChain::new(p, 1);
    if ideal {
        *c.errors_mut() = ErrorModel::IDEAL;
    }
    let mut cfg = ChainConfig::defaults(&p);
    cfg.lpf = Bandwidth::Off;
    c.configure(&cfg);
    c
}

fn rotate(rate_dps: [f32; 3]) -> Motion {
    Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps,
    }
}

const RANGE_BITS: u16 = 7 << 10;

/// `motion rotate 1e6 0 0` (8.7 rad a tick): X reads +range with USW bit 10,
/// and the attitude stays a rotation, so the accelerometers still read
/// gravity (1 g in magnitude) rather than NaN → 0.
#[test]
fn a_rotation_of_1e6_deg_s_saturates_x_and_keeps_gravity() {
    for (code, range) in [
        ("KERNEL-110-G2000-A40", 2000.0),
        ("KERNEL-110-G450-A40", 450.0),
    ] {
        let mut c = chain(code, true);
        c.set_motion(rotate([1e6, 0.0, 0.0]));
        let mut t = 0;
        for _ in 0..50 {
            // Instant: the sample at the output's tick (ICD 5.3.6), so
            // gravity keeps its magnitude while it whirls.
            ticks(&mut c, &mut t, 20);
            let s = c.output();
            assert!((s.gyro[0] - range).abs() < 1e-3, "{code}: {:?}", s.gyro);
            assert!(
                s.gyro[1].abs() < 1.0 && s.gyro[2].abs() < 1.0,
                "{code}: {:?}",
                s.gyro
            );
            let g = s.acc.iter().map(|a| a * a).sum::<f32>().sqrt();
            assert!((g - 1.0).abs() < 1e-3, "{code}: acc {:?}", s.acc);
            assert_eq!(
                status::usw(&c.health()) & RANGE_BITS,
                usw::RATE_X_RANGE,
                "{code}"
            );
        }
    }
}

/// The same with the model's errors (misalignment couples X into Y and Z):
/// every axis finite, X at the range, its bit set.
#[test]
fn a_huge_rotation_with_the_model_errors_stays_finite_and_flagged() {
    for rate in [1e6, 3.4e38, -1e9] {
        let mut c = chain("KERNEL-110-G2000-A40", false);
        c.set_motion(rotate([rate, 0.0, 0.0]));
        let mut t = 0;
        ticks(&mut c, &mut t, 200);
        let s = c.output();
        let want = 2000.0f32.copysign(rate);
        assert!((s.gyro[0] - want).abs() < 1e-3, "{rate}: {:?}", s.gyro);
        assert!(
            s.gyro.iter().chain(&s.acc).all(|v| v.is_finite()),
            "{rate}: {s:?}"
        );
        assert_ne!(s.acc, [0.0; 3], "{rate}");
        assert_ne!(status::usw(&c.health()) & usw::RATE_X_RANGE, 0, "{rate}");
    }
}

/// A sample beyond `f32` (a trajectory value of 3.5e38 becomes +∞) and one
/// at `f32::MAX`: each axis reads ± its range, the gyro bits are set on
/// exactly those axes, the accelerometer saturates too.
#[test]
fn infinite_and_huge_samples_saturate_every_axis_they_touch() {
    for ideal in [true, false] {
        let mut c = chain("KERNEL-110-G2000-A40", ideal);
        c.set_motion(Motion::Sample(Truth {
            rate_dps: [f32::INFINITY, 0.0, -f32::MAX],
            specific_force_g: [0.0, f32::NEG_INFINITY, 1.0],
            temperature_c: None,
        }));
        let mut t = 0;
        ticks(&mut c, &mut t, 20);
        let s = c.output();
        assert!(
            (s.gyro[0] - 2000.0).abs() < 1e-3,
            "ideal {ideal}: {:?}",
            s.gyro
        );
        assert!(
            (s.gyro[2] + 2000.0).abs() < 1e-3,
            "ideal {ideal}: {:?}",
            s.gyro
        );
        assert!((s.acc[1] + 40.0).abs() < 1e-3, "ideal {ideal}: {:?}", s.acc);
        assert!(s.gyro.iter().chain(&s.acc).all(|v| v.is_finite()));
        let bits = status::usw(&c.health()) & RANGE_BITS;
        if ideal {
            assert_eq!(bits, usw::RATE_X_RANGE | usw::RATE_X_RANGE << 2);
        } else {
            assert_ne!(bits & (usw::RATE_X_RANGE | usw::RATE_X_RANGE << 2), 0);
        }
    }
}

/// [`Truth::bounded`]: clamped to ±8192 °/s and ±128 g, NaN read as 0.
#[test]
fn bounded_truth_clamps_and_reads_nan_as_zero() {
    let t = Truth {
        rate_dps: [f32::INFINITY, -3e38, f32::NAN],
        specific_force_g: [1e30, 0.5, f32::NEG_INFINITY],
        temperature_c: Some(20.0),
    }
    .bounded();
    assert_eq!(t.rate_dps, [8192.0, -8192.0, 0.0]);
    assert_eq!(t.specific_force_g, [128.0, 0.5, -128.0]);
    assert_eq!(t.temperature_c, Some(20.0));
}

/// A large step keeps the integrated attitude a unit quaternion, and a
/// non-finite one leaves it unchanged; small steps are untouched.
#[test]
fn the_attitude_integrator_survives_any_step() {
    let mut q = QuatIntegrator::new([1.0, 0.0, 0.0, 0.0]);
    for _ in 0..1000 {
        q.rotate(&[8.7, 0.0, 0.0]);
        q.rotate(&[3e33, -1e20, 5.0]);
    }
    let n: f32 = q.get().iter().map(|v| v * v).sum();
    assert!((n - 1.0).abs() < 1e-5, "{:?}", q.get());
    let before = q.get();
    q.rotate(&[f32::INFINITY, 0.0, 0.0]);
    q.rotate(&[f32::NAN, 0.0, 0.0]);
    assert_eq!(q.get(), before);
    // π about X in one exact step: q = [0, 1, 0, 0].
    let mut q = QuatIntegrator::new([1.0, 0.0, 0.0, 0.0]);
    q.rotate(&[core::f32::consts::PI, 0.0, 0.0]);
    let g = q.get();
    assert!(g[0].abs() < 1e-6 && (g[1] - 1.0).abs() < 1e-6, "{g:?}");
}
