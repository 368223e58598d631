//! Orientation (ICD Appendix C), initial alignment (5.7) and attitude
//! propagation.
//!
//! Conventions pinned here: heading is clockwise from north (a positive,
//! right-hand rotation about z *decreases* it), pitch is nose-up positive,
//! roll is right-side-down positive; the quaternion is output with q0 ≥ 0.
//!
//! Stated bounds (ideal sensors): constant rotations, 10 s — 0.01°; coning
//! 5° at 2 Hz, 10 s — 0.01°. With the K110's default errors after a 2 s
//! alignment: static 60 s — heading 0.1°, pitch/roll within 0.05° of the
//! tilt the accelerometer errors imply (bias/g, ≈ 0.06° for 1 mg); rotation
//! 90°/s × 4 s — 0.5° (scale factor and misalignment dominate).

use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::kernel::status::Status;
use imu_emu::math::rotation::*;
use imu_emu::model::Product;
use imu_emu::sensor::{ErrorModel, Motion};
use imu_emu::time::Instant;

const DEG: f32 = core::f32::consts::PI / 180.0;

fn mat_close(a: &Mat3, b: &Mat3, tol: f32) -> bool {
    (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() <= tol))
}

/// Angle between two attitudes, degrees (from the vector part of a*⊗b:
/// acos of a component near 1 would quantise to 0.04° in f32).
fn angle_between(a: &Quat, b: &Quat) -> f32 {
    let d = quat_mul(&quat_conj(a), b);
    let v = (f64::from(d[1]).powi(2) + f64::from(d[2]).powi(2) + f64::from(d[3]).powi(2)).sqrt();
    (2.0 * v.min(1.0).asin()).to_degrees() as f32
}

fn grid() -> Vec<(f32, f32, f32)> {
    let mut v = Vec::new();
    for h in [0.0, 30.0, 90.0, 179.0, 181.0, 270.0, 359.5] {
        for p in [-90.0, -89.9, -45.0, 0.0, 10.0, 60.0, 89.9, 90.0] {
            for r in [-179.0, -90.0, -20.0, 0.0, 45.0, 90.0, 135.0, 180.0] {
                v.push((h, p, r));
            }
        }
    }
    v
}

#[test]
fn euler_dcm_quaternion_round_trips_c1_to_c7() {
    for (h, p, r) in grid() {
        let (hr, pr, rr) = (h * DEG, p * DEG, r * DEG);
        let c = dcm_from_euler(hr, pr, rr); // C.1
        let q = quat_from_euler(hr, pr, rr);
        assert!(mat_close(&c, &dcm_from_quat(&q), 1e-5), "C.4 {h} {p} {r}");
        // C.6: DCM → quaternion → DCM, and q0 ≥ 0; the same quaternion as the
        // literal formula and as the canonical Euler quaternion.
        let q6 = quat_from_dcm(&c);
        assert!(q6[0] >= 0.0);
        let lit = quat_from_dcm_c6(&c);
        if q6[0] > 1e-3 {
            assert!(
                (0..4).all(|i| (lit[i] - q6[i]).abs() < 5e-4),
                "{h} {p} {r}: {lit:?} vs {q6:?}"
            );
            assert!(
                (0..4).all(|i| (q[i] - q6[i]).abs() < 1e-5),
                "{h} {p} {r}: {q:?} vs {q6:?}"
            );
        }
        assert!(
            mat_close(&c, &dcm_from_quat(&q6), 2e-5),
            "C.6 {h} {p} {r}: {q6:?}"
        );
        // C.2 / C.7: back to Euler angles; at θ = ±90° only the matrix is
        // unique, so compare matrices there.
        for e in [euler_from_dcm(&c), euler_from_quat(&q)] {
            assert!(
                mat_close(&c, &dcm_from_euler(e[0], e[1], e[2]), 3e-4),
                "C.2/C.7 {h} {p} {r}: {e:?}"
            );
            assert!(e[0] >= 0.0 && e[0] < core::f32::consts::TAU);
            if p.abs() < 89.0 {
                let dh = ((e[0] / DEG - h + 540.0) % 360.0) - 180.0;
                let dr = ((e[2] / DEG - r + 540.0) % 360.0) - 180.0;
                assert!(
                    dh.abs() < 1e-3 && (e[1] / DEG - p).abs() < 1e-3 && dr.abs() < 1e-3,
                    "{h} {p} {r}: {e:?}"
                );
            }
        }
        if p.abs() == 90.0 {
            let e = euler_from_dcm(&c);
            assert_eq!(e[2], 0.0, "roll reported 0 at the singularity");
            assert!((e[1] / DEG - p).abs() < 1e-3);
        }
    }
}

#[test]
fn c6_handles_half_turns_where_q0_vanishes() {
    for axis in [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.6, -0.8, 0.0],
        [0.0, 0.6, -0.8],
        [-0.48, 0.6, 0.64],
    ] {
        for angle in [179.99f32, 180.0, 180.01] {
            let q = quat_axis_angle(&axis, angle * DEG);
            let c = dcm_from_quat(&q);
            let q6 = quat_from_dcm(&c);
            assert!(q6[0] >= 0.0);
            assert!(
                mat_close(&c, &dcm_from_quat(&q6), 1e-5),
                "{axis:?} {angle}: {q6:?}"
            );
            // The literal (C.6) agrees where it is determined (q0 clear of 0),
            // within its own √ε precision.
            if angle != 180.0 {
                let lit = quat_from_dcm_c6(&c);
                assert!(
                    (0..4).all(|i| (lit[i] - q6[i]).abs() < 5e-4),
                    "{lit:?} vs {q6:?}"
                );
            }
        }
    }
}

#[test]
fn sign_conventions_of_appendix_c() {
    // Heading 90°: the body's y axis (forward) points east.
    let c = dcm_from_euler(90.0 * DEG, 0.0, 0.0);
    let fwd = mat_vec(&c, &[0.0, 1.0, 0.0]);
    assert!((fwd[0] - 1.0).abs() < 1e-6, "{fwd:?}");
    // Pitch +30°: forward axis points up.
    let c = dcm_from_euler(0.0, 30.0 * DEG, 0.0);
    assert!(mat_vec(&c, &[0.0, 1.0, 0.0])[2] > 0.49);
    // Roll +30°: the right (x) axis points down.
    let c = dcm_from_euler(0.0, 0.0, 30.0 * DEG);
    assert!(mat_vec(&c, &[1.0, 0.0, 0.0])[2] < -0.49);
}

fn chain(model: &str, ideal: bool) -> (SignalChain, u64) {
    let product = Product::parse(model).unwrap();
    let mut c = SignalChain::new(product, 11);
    if ideal {
        *c.errors_mut() = ErrorModel::IDEAL;
    }
    c.faults_mut().temperature_c = Some(25.0);
    let cfg = ChainConfig::defaults(&product);
    c.configure(&cfg);
    (c, 0)
}

fn run(c: &mut SignalChain, t: &mut u64, ticks: u64) {
    for _ in 0..ticks {
        *t += 1;
        c.tick(Instant::from_micros(500 * *t));
    }
}

#[test]
fn constant_rotations_have_the_appendix_c_signs_and_track_truth() {
    // (body rate °/s, seconds, expected heading, pitch, roll)
    let cases = [
        ([0.0, 0.0, 30.0], 3.0, 270.0, 0.0, 0.0), // ccw from above: heading −90
        ([0.0, 0.0, -30.0], 3.0, 90.0, 0.0, 0.0),
        ([10.0, 0.0, 0.0], 3.0, 0.0, 30.0, 0.0), // nose up
        ([0.0, 10.0, 0.0], 3.0, 0.0, 0.0, 30.0), // right side down
    ];
    for (rate, secs, h, p, r) in cases {
        let (mut c, mut t) = chain("K110", true);
        c.set_motion(Motion::ConstantRotation {
            lat_deg: 45.0,
            heading_deg: 0.0,
            rate_dps: rate,
        });
        c.skip_alignment();
        // The first tick samples t = 0: `secs` after it is one tick more.
        run(&mut c, &mut t, (secs * 2000.0) as u64 + 1);
        let s = c.output();
        let dh = ((s.euler[0] - h + 540.0) % 360.0) - 180.0;
        assert!(
            dh.abs() < 0.01 && (s.euler[1] - p).abs() < 0.01 && (s.euler[2] - r).abs() < 0.01,
            "{rate:?}: {:?}",
            s.euler
        );
        let truth = c.truth_attitude().unwrap();
        assert!(angle_between(&truth, &s.quat) < 0.01, "{rate:?}");
        assert!(s.quat[0] >= 0.0);
    }
    // A tumbling rotation about a skew axis for 10 s.
    let (mut c, mut t) = chain("K110", true);
    c.set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [40.0, -25.0, 60.0],
    });
    c.skip_alignment();
    for _ in 0..100 {
        run(&mut c, &mut t, 200);
        let s = c.output();
        let truth = c.truth_attitude().unwrap();
        assert!(
            angle_between(&truth, &s.quat) < 0.01,
            "t {t}: {}",
            angle_between(&truth, &s.quat)
        );
    }
}

#[test]
fn coning_does_not_drift() {
    let (mut c, mut t) = chain("K110", true);
    c.set_motion(Motion::Coning {
        lat_deg: 45.0,
        heading_deg: 0.0,
        half_angle_deg: 5.0,
        freq_hz: 2.0,
    });
    run(&mut c, &mut t, 1);
    // Start the AHRS on the truth (alignment cannot know the heading).
    c.skip_alignment();
    let q = c.truth_attitude().unwrap();
    c.attitude_mut().set(q);
    let mut worst = 0.0f32;
    for _ in 0..100 {
        run(&mut c, &mut t, 200);
        let s = c.output();
        let truth = c.truth_attitude().unwrap();
        worst = worst.max(angle_between(&truth, &s.quat));
    }
    println!("coning: worst {worst}°");
    assert!(worst < 0.01, "coning error {worst}°");
}

#[test]
fn static_after_alignment_with_default_errors() {
    let (mut c, mut t) = chain("K110", false);
    c.begin_alignment();
    run(&mut c, &mut t, 1);
    assert_eq!(Status::of(&c.health()).usw_ext & 1, 0, "aligning");
    run(&mut c, &mut t, 3999);
    c.end_alignment();
    let st = Status::of(&c.health());
    assert_eq!(st.usw_ext, 0x0001, "accepted: {:?}", c.gyro_bias());
    // The bias estimate is the turn-on bias (Earth rate removed).
    let e = c.errors().gyro;
    for i in 0..3 {
        assert!(
            (c.gyro_bias()[i] - e.axes[i].bias).abs() < 0.01,
            "axis {i}: {:?} vs {:?}",
            c.gyro_bias(),
            e.axes[i].bias
        );
    }
    run(&mut c, &mut t, 60 * 2000);
    let s = c.output();
    let dh = ((s.euler[0] + 540.0) % 360.0) - 180.0;
    assert!(dh.abs() < 0.1, "{:?}", s.euler);
    // Levelling sees the accelerometer's turn-on bias and misalignment as
    // tilt (as a real AHRS does): f = M·(0, 0, 1) + b.
    let a = c.errors().acc;
    let f = [
        a.misalignment[0][2] + a.axes[0].bias,
        a.misalignment[1][2] + a.axes[1].bias,
        1.0 + a.axes[2].scale_factor + a.axes[2].bias,
    ];
    let n = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let (pitch, roll) = ((f[1] / n).asin() / DEG, (-f[0]).atan2(f[2]) / DEG);
    // Within 0.1°: the residual gyro bias after a 2 s alignment (noise
    // N/√2 s ≈ 0.002 °/s, and the bias instability's flicker terms of 1 s
    // and 10 s corner moving over the minute, 0.86·B ≈ 5e-4 °/s each)
    // holds the tilt loop off by bias/k_p, a few hundredths of a degree.
    assert!(
        (s.euler[1] - pitch).abs() < 0.1 && (s.euler[2] - roll).abs() < 0.1,
        "{:?} vs {pitch} {roll}",
        s.euler
    );
}

#[test]
fn rotation_with_default_errors_stays_within_half_a_degree() {
    let (mut c, mut t) = chain("K110", false);
    c.begin_alignment();
    run(&mut c, &mut t, 4000);
    c.end_alignment();
    c.set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [0.0, 0.0, 90.0],
    });
    run(&mut c, &mut t, 8000);
    let s = c.output();
    let truth = c.truth_attitude().unwrap();
    let err = angle_between(&truth, &s.quat);
    assert!(err < 0.5, "{err}° ({:?})", s.euler);
}

#[test]
fn earth_rate_is_removed_from_the_bias_and_a_static_unit_stays_put() {
    for heading in [0.0, 90.0] {
        let (mut c, mut t) = chain("K110", true);
        // The AHRS assumes the built-in site's Earth rate.
        c.set_motion(Motion::Static {
            lat_deg: imu_emu::sensor::motion::DEFAULT_LATITUDE_DEG,
            heading_deg: heading,
        });
        run(&mut c, &mut t, 10);
        c.begin_alignment();
        run(&mut c, &mut t, 4000);
        c.end_alignment();
        if heading == 0.0 {
            // Ideal sensors: the whole mean is Earth rate, so the bias is 0.
            assert!(
                c.gyro_bias().iter().all(|b| b.abs() < 2e-6),
                "{:?}",
                c.gyro_bias()
            );
        }
        run(&mut c, &mut t, 120 * 2000);
        let s = c.output();
        let dh = ((s.euler[0] + 540.0) % 360.0) - 180.0;
        assert!(
            dh.abs() < 1e-3 && s.euler[1].abs() < 1e-3 && s.euler[2].abs() < 1e-3,
            "heading {heading}: {:?}",
            s.euler
        );
    }
}

#[test]
fn vibration_rejects_the_averaged_bias_but_not_the_kalman_one() {
    let vib = Motion::Vibration {
        lat_deg: 45.0,
        heading_deg: 0.0,
        freq_hz: 7.0,
        acc_amp_g: [0.05, 0.05, 0.1],
        rate_amp_dps: [1.0, 1.0, 1.0],
    };
    for zupt in [false, true] {
        let product = Product::parse("K110").unwrap();
        let mut c = SignalChain::new(product, 5);
        c.faults_mut().temperature_c = Some(25.0);
        let mut cfg = ChainConfig::defaults(&product);
        cfg.align.zupt = zupt;
        c.configure(&cfg);
        c.set_motion(vib);
        c.begin_alignment();
        let mut t = 0;
        run(&mut c, &mut t, 4000);
        c.end_alignment();
        let st = Status::of(&c.health());
        if zupt {
            assert_eq!(st.usw_ext, 0x0001);
            let e = c.errors().gyro;
            for i in 0..3 {
                assert!(
                    (c.gyro_bias()[i] - e.axes[i].bias).abs() < 0.05,
                    "{:?}",
                    c.gyro_bias()
                );
            }
        } else {
            assert_eq!(
                st.usw_ext, 0x0003,
                "STD of a 1 °/s vibration is over 0.05 °/s"
            );
            assert_eq!(c.gyro_bias(), [0.0; 3]);
        }
    }
}

#[test]
fn skip_alignment_levels_at_once_without_bias() {
    let (mut c, mut t) = chain("K110", false);
    c.set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [0.0; 3],
    });
    run(&mut c, &mut t, 100);
    c.skip_alignment();
    assert_eq!(Status::of(&c.health()).usw_ext, 0x0001);
    assert_eq!(c.gyro_bias(), [0.0; 3]);
    let s = c.output();
    assert!(
        s.euler[1].abs() < 0.2 && s.euler[2].abs() < 0.2,
        "{:?}",
        s.euler
    );
}
