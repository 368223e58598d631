//! Alignment_Angles (ICD Appendix B): the Figure B.1 example mountings.
//!
//! Expectations, derived from the text: the angles are the IMU's rotation
//! relative to the carrier — heading about Z clockwise positive, then pitch
//! about X and roll about Y counter-clockwise (right-hand) positive — so a
//! sensor axis `s` lies along `M·s` in carrier axes with
//! `M = Rz(−h)·Rx(p)·Ry(r)`:
//!
//! | angles | sensor X | sensor Y | sensor Z | the unit is … |
//! |---|---|---|---|---|
//! | 0 0 0 | +X | +Y | +Z | parallel to the carrier |
//! | 0 0 180 | −X | +Y | −Z | upside down, rolled about the longitudinal axis |
//! | −90 0 0 | +Y | −X | +Z | turned 90° counter-clockwise seen from above (its X looks forward) |
//! | 0 0 90 | −Z | +Y | +X | rolled 90° right side down (its Z looks right) |

use imu_emu::ahrs::Mounting;
use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::model::Product;
use imu_emu::sensor::{ErrorModel, Motion, TruthFrame};
use imu_emu::time::Instant;

type V = [f32; 3];

const EXAMPLES: [(V, [V; 3]); 4] = [
    (
        [0.0, 0.0, 0.0],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    ),
    (
        [0.0, 0.0, 180.0],
        [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
    ),
    (
        [-90.0, 0.0, 0.0],
        [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    ),
    (
        [0.0, 0.0, 90.0],
        [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    ),
];

fn close(a: &V, b: &V, tol: f32) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

#[test]
fn figure_b1_examples_map_sensor_axes_to_the_expected_carrier_axes() {
    for (angles, axes) in EXAMPLES {
        let m = Mounting::from_angles_deg(angles);
        for (i, expect) in axes.iter().enumerate() {
            let mut s = [0.0; 3];
            s[i] = 1.0;
            assert_eq!(&m.to_carrier(&s), expect, "{angles:?}: sensor axis {i}");
            assert_eq!(m.to_sensor(expect), s);
        }
    }
}

fn chain_with(angles: V) -> SignalChain {
    let product = Product::parse("K120").unwrap();
    let mut c = SignalChain::new(product, 9);
    *c.errors_mut() = ErrorModel::IDEAL;
    let mut cfg = ChainConfig::defaults(&product);
    cfg.alignment_angles_deg = angles;
    cfg.lpf = Bandwidth::Off;
    c.configure(&cfg);
    c
}

/// On the bench (the unit itself level, rotating about its own axes): the
/// carrier-axis output is the sensor data mapped by the table; a level unit
/// with `0 0 180` reports AccZ = −1 g and roll 180°, with `0 0 90` roll −90°.
#[test]
fn the_chain_reports_bench_motion_in_carrier_axes() {
    for (angles, axes) in EXAMPLES {
        for (i, expect) in axes.iter().enumerate() {
            let mut rate = [0.0; 3];
            rate[i] = 10.0;
            let mut c = chain_with(angles);
            c.set_motion(Motion::ConstantRotation {
                lat_deg: 0.0,
                heading_deg: 0.0,
                rate_dps: rate,
            });
            c.tick(Instant::from_micros(500));
            let s = c.output();
            // Earth rate at the equator is horizontal and tiny (4e-3 °/s).
            let expect_rate = [expect[0] * 10.0, expect[1] * 10.0, expect[2] * 10.0];
            assert!(
                close(&s.gyro, &expect_rate, 5e-3),
                "{angles:?} axis {i}: {:?}",
                s.gyro
            );
            // Gravity: sensor +Z up on the bench → carrier M·(0, 0, 1), on
            // both accelerometers and the filtered outputs.
            let z = axes[2];
            assert!(
                close(&s.acc, &z, 1e-6) && close(&s.aux_acc, &z, 1e-6),
                "{angles:?}: {:?}",
                s.acc
            );
            assert!(close(&s.acc_filtered, &z, 1e-6) && close(&s.aux_acc_filtered, &z, 1e-6));
            assert_eq!(c.last_sensor()[1], [0.0, 0.0, 1.0]);
        }
    }
    let mut c = chain_with([0.0, 0.0, 180.0]);
    c.tick(Instant::from_micros(500));
    c.skip_alignment();
    let s = c.output();
    assert!(
        (s.euler[2].abs() - 180.0).abs() < 1e-3 && s.euler[1].abs() < 1e-3,
        "{:?}",
        s.euler
    );
    let mut c = chain_with([0.0, 0.0, 90.0]);
    c.tick(Instant::from_micros(500));
    c.skip_alignment();
    let s = c.output();
    assert!(
        (s.euler[2] + 90.0).abs() < 1e-3 && s.euler[1].abs() < 1e-3,
        "{:?}",
        s.euler
    );
}

/// Motion of the carrier (the unit mounted per the angles): the output
/// reproduces the carrier's motion whatever the angles, and the sensors see
/// it rotated by Mᵀ.
#[test]
fn carrier_frame_truth_is_reproduced_for_any_mounting() {
    for (angles, axes) in EXAMPLES {
        let mut c = chain_with(angles);
        c.set_truth_frame(TruthFrame::Carrier);
        c.set_motion(Motion::ConstantRotation {
            lat_deg: 0.0,
            heading_deg: 0.0,
            rate_dps: [5.0, -7.0, 11.0],
        });
        for t in 1..=2000u64 {
            c.tick(Instant::from_micros(500 * t));
        }
        let s = c.output();
        assert!(
            close(&s.gyro, &[5.0, -7.0, 11.0], 5e-3),
            "{angles:?}: {:?}",
            s.gyro
        );
        // Sensor Z reads the carrier's vertical along M's third column
        // direction: at t = 0 the carrier is level, so sensor-axis gravity
        // is Mᵀ·(0,0,1) = the components of carrier Z in sensor axes.
        let mut c = chain_with(angles);
        c.set_truth_frame(TruthFrame::Carrier);
        c.tick(Instant::from_micros(500));
        let sensor_acc = c.last_sensor()[1];
        let expect = [axes[0][2], axes[1][2], axes[2][2]];
        assert!(
            close(&sensor_acc, &expect, 1e-6),
            "{angles:?}: {sensor_acc:?}"
        );
        assert!(close(&c.output().acc, &[0.0, 0.0, 1.0], 1e-6));
    }
}
