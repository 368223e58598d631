//! The signal chain as the device uses it: power-on state, determinism,
//! output variants (5.3.6), status words (5.4) and GetBIT (Table 5.18),
//! faults, temperature, the K201's 4 kHz rate.

use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::dsp::OutputVariant;
use imu_emu::kernel::config::{self, lpf_bandwidth};
use imu_emu::kernel::status::{usw, Status};
use imu_emu::math::rotation::{quat_conj, quat_mul, Quat};
use imu_emu::model::Product;
use imu_emu::sensor::{ErrorModel, Motion, Sample};
use imu_emu::time::Instant;

fn k(model: &str) -> Product {
    Product::parse(model).unwrap()
}

fn ticks(c: &mut SignalChain, from: &mut u64, n: u64) {
    for _ in 0..n {
        *from += 1;
        c.tick(Instant::from_micros(500 * *from));
    }
}

#[test]
fn size_of_the_chain() {
    let n = core::mem::size_of::<SignalChain>();
    println!("size_of::<SignalChain>() = {n} bytes");
    // FIR history 2 × 193 × 9 f32 = 13 896 bytes, the rest ≈ 2.5 KiB.
    assert!(n < 20 * 1024, "{n}");
}

/// `reset` (what a power cycle runs, in place) is a power-on: after any
/// history (filters full, another configuration, a motion, a fault, other
/// errors) the chain gives, tick for tick, what a new chain of the same
/// product and seed gives.
#[test]
fn reset_in_place_is_a_power_on() {
    for model in ["K110", "K120", "K201"] {
        let p = k(model);
        let mut a = SignalChain::new(p, 7);
        let mut t = 0;
        let mut cfg = ChainConfig::defaults(&p);
        cfg.output_variant = OutputVariant::Incremental;
        cfg.lpf = Bandwidth::Hz262;
        a.configure(&cfg);
        a.set_motion(Motion::Coning {
            lat_deg: 10.0,
            heading_deg: 30.0,
            half_angle_deg: 5.0,
            freq_hz: 2.0,
        });
        a.faults_mut().temperature_c = Some(70.0);
        a.errors_mut().gyro.axes[0].bias = 3.0;
        a.begin_alignment();
        ticks(&mut a, &mut t, 3000);
        a.output();

        a.reset(p, 7);
        let mut b = SignalChain::new(p, 7);
        let mut ta = 0;
        let mut tb = 0;
        for i in 0..400 {
            ticks(&mut a, &mut ta, 5);
            ticks(&mut b, &mut tb, 5);
            assert_eq!(a.output(), b.output(), "{model}, output {i}");
        }
        assert_eq!(a.ticks(), b.ticks());
    }
}

#[test]
fn power_on_is_static_level_z_up_with_earth_rate() {
    let p = k("K110");
    let mut c = SignalChain::new(p, 1);
    let mut t = 0;
    ticks(&mut c, &mut t, 2000);
    let s0 = c.output();
    assert!((s0.acc[2] - 1.0).abs() < 0.02, "{:?}", s0.acc);
    // 10 s averaged: the noise of the mean is N/√10 s ≈ 0.001 °/s.
    let mut cfg = ChainConfig::defaults(&p);
    cfg.output_variant = OutputVariant::Average;
    c.configure(&cfg);
    ticks(&mut c, &mut t, 20_000);
    let avg = c.output();
    let e = *c.errors();
    // AccZ ≈ +1 g (within the turn-on bias, scale factor, misalignment).
    assert!(
        (avg.acc[2] - 1.0).abs() < 0.01 && avg.acc[0].abs() < 0.01 && avg.acc[1].abs() < 0.01,
        "{:?}",
        avg.acc
    );
    // Gyro ≈ Earth rate (0, Ω cos 45°, Ω sin 45°) plus the turn-on bias.
    let omega = 15.041 / 3600.0 * std::f32::consts::FRAC_1_SQRT_2;
    let earth = [0.0, omega, omega];
    for (i, w) in earth.iter().enumerate() {
        let expect = w + e.gyro.axes[i].bias;
        assert!(
            (avg.gyro[i] - expect).abs() < 0.005,
            "axis {i}: {} vs {expect}",
            avg.gyro[i]
        );
    }
    let s = c.output();
    assert_eq!(s.aux_acc, [0.0; 3], "K110 has no aux accelerometer");
    // 11 s of warm-up: 25 + 8·(1 − e^(−11/600)) °C.
    assert!((s.temperature - 25.145).abs() < 0.01, "{}", s.temperature);
    assert_eq!(s.supply_voltage, 12.0);
    assert_eq!(
        Status::of(&c.health()),
        Status {
            usw: 0,
            usw_ext: 1,
            bit: [0; 4]
        }
    );
}

#[test]
fn aux_accelerometer_only_on_k120_and_k220() {
    for (model, aux) in [
        ("K120", true),
        ("K220", true),
        ("K110", false),
        ("K201", false),
    ] {
        let mut c = SignalChain::new(k(model), 1);
        let mut t = 0;
        ticks(&mut c, &mut t, 100);
        let s = c.output();
        assert_eq!(s.aux_acc[2] > 0.9, aux, "{model}");
        assert_eq!(s.aux_acc_filtered[2] > 0.9, aux, "{model}");
    }
}

fn run_seq(seed: u64, cfg_mod: impl Fn(&mut ChainConfig)) -> Vec<Sample> {
    let p = k("K120");
    let mut c = SignalChain::new(p, seed);
    let mut cfg = ChainConfig::defaults(&p);
    cfg_mod(&mut cfg);
    c.configure(&cfg);
    c.set_motion(Motion::Coning {
        lat_deg: 45.0,
        heading_deg: 10.0,
        half_angle_deg: 2.0,
        freq_hz: 3.0,
    });
    c.begin_alignment();
    let mut t = 0;
    let mut v = Vec::new();
    for i in 0..300 {
        ticks(&mut c, &mut t, 20);
        if i == 100 {
            c.end_alignment();
        }
        v.push(c.output());
    }
    v
}

#[test]
fn same_seed_same_samples_different_seed_different_samples() {
    let all = |cfg: &mut ChainConfig| {
        cfg.lpf = Bandwidth::Hz16;
        cfg.cascade.mask = 7;
        cfg.output_variant = OutputVariant::Incremental;
        cfg.alignment_angles_deg = [10.0, -5.0, 3.0];
    };
    let a = run_seq(77, all);
    let b = run_seq(77, all);
    assert_eq!(a, b, "bit-identical for the same seed");
    let c = run_seq(78, all);
    assert_ne!(a, c);
    assert!(
        a.iter().zip(&c).all(|(x, y)| x.gyro != y.gyro),
        "every sample differs"
    );
    let d = run_seq(77, |_| {});
    assert_ne!(a, d);
}

/// A truth alternating between two rates every tick: instant shows the last,
/// average the mean, incremental (no rotation about other axes) the mean too.
#[test]
fn output_variants_instant_average_incremental() {
    struct Alternating(u64);
    impl imu_emu::sensor::MotionSource for Alternating {
        fn next(&mut self, _now: Instant, _dt: f32) -> imu_emu::sensor::Truth {
            self.0 += 1;
            let v = if self.0.is_multiple_of(2) { 2.0 } else { 0.0 };
            imu_emu::sensor::Truth {
                rate_dps: [0.0, 0.0, v],
                specific_force_g: [0.0, 0.0, 1.0 + v],
                temperature_c: None,
            }
        }
    }
    // Instant is the last tick's value at any interval (ICD 5.3.6), here
    // 2.0 after 40 ticks and each tick's value at one tick an interval
    // (below); the others the interval's mean.
    for (variant, expect) in [
        (OutputVariant::Instant, 2.0),
        (OutputVariant::Average, 1.0),
        (OutputVariant::Incremental, 1.0),
    ] {
        let p = k("K110");
        let mut c = SignalChain::new(p, 1);
        *c.errors_mut() = ErrorModel::IDEAL;
        let mut cfg = ChainConfig::defaults(&p);
        cfg.lpf = Bandwidth::Off;
        cfg.output_variant = variant;
        c.configure(&cfg);
        let mut src = Alternating(0);
        for t in 1..=40u64 {
            c.tick_with(Instant::from_micros(500 * t), &mut src);
        }
        let s = c.output();
        assert!(
            (s.gyro[2] - expect).abs() < 1e-4,
            "{variant:?}: {}",
            s.gyro[2]
        );
        assert!(
            (s.acc[2] - (1.0 + expect)).abs() < 1e-4,
            "{variant:?}: {}",
            s.acc[2]
        );
        assert!((c.output_interval() - 0.02).abs() < 1e-7);
        if variant == OutputVariant::Instant {
            for t in 41..=44u64 {
                c.tick_with(Instant::from_micros(500 * t), &mut src);
                let v = if t % 2 == 0 { 2.0 } else { 0.0 };
                assert_eq!(c.output().gyro[2], v, "tick {t}");
            }
        }
        // Average_Output_Data = 1 forces the average.
        assert_eq!(config::output_variant(0, 1), OutputVariant::Average);
        assert_eq!(config::output_variant(2, 1), OutputVariant::Average);
        assert_eq!(config::output_variant(2, 0), OutputVariant::Incremental);
    }
}

/// Incremental output under coning: a host that composes the output
/// increments as rotation vectors (`q ← q ⊗ exp(Δθ)`, Δθ = gyro·interval)
/// follows the true attitude, because each Δθ carries the coning correction;
/// composing the plain average drifts.
#[test]
fn incremental_output_carries_the_coning_correction() {
    let p = k("K110");
    let mut errs = Vec::new();
    for variant in [OutputVariant::Incremental, OutputVariant::Average] {
        let mut c = SignalChain::new(p, 1);
        *c.errors_mut() = ErrorModel::IDEAL;
        let mut cfg = ChainConfig::defaults(&p);
        cfg.lpf = Bandwidth::Off;
        cfg.output_variant = variant;
        c.configure(&cfg);
        c.set_motion(Motion::Coning {
            lat_deg: 0.0,
            heading_deg: 0.0,
            half_angle_deg: 10.0,
            freq_hz: 5.0,
        });
        let mut t = 0;
        ticks(&mut c, &mut t, 1);
        c.output();
        let mut q: [f64; 4] = c.truth_attitude().unwrap().map(f64::from);
        for _ in 0..1000 {
            ticks(&mut c, &mut t, 20); // 100 Hz output, 10 s
            let s = c.output();
            let dt = f64::from(c.output_interval());
            let a: Vec<f64> = (0..3)
                .map(|i| f64::from(s.gyro[i]).to_radians() * dt)
                .collect();
            let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            let (sn, cs) = ((0.5 * n).sin(), (0.5 * n).cos());
            let d = [cs, sn * a[0] / n, sn * a[1] / n, sn * a[2] / n];
            q = [
                q[0] * d[0] - q[1] * d[1] - q[2] * d[2] - q[3] * d[3],
                q[0] * d[1] + q[1] * d[0] + q[2] * d[3] - q[3] * d[2],
                q[0] * d[2] - q[1] * d[3] + q[2] * d[0] + q[3] * d[1],
                q[0] * d[3] + q[1] * d[2] - q[2] * d[1] + q[3] * d[0],
            ];
        }
        let qf: Quat = q.map(|x| x as f32);
        let e = quat_mul(&quat_conj(&c.truth_attitude().unwrap()), &qf);
        let err = 2.0
            * (e[1].powi(2) + e[2].powi(2) + e[3].powi(2))
                .sqrt()
                .asin()
                .to_degrees();
        errs.push(err);
    }
    println!(
        "10 s of 10° coning at 5 Hz, composed at 100 Hz: incremental {}°, average {}°",
        errs[0], errs[1]
    );
    assert!(errs[0] < 0.1 && errs[1] > 5.0 * errs[0], "{errs:?}");
}

#[test]
fn rate_out_of_range_sets_usw_bits_per_axis_and_saturates() {
    let p = k("KERNEL-110-G2000-A40");
    let mut c = SignalChain::new(p, 1);
    *c.errors_mut() = ErrorModel::IDEAL;
    let mut cfg = ChainConfig::defaults(&p);
    cfg.lpf = Bandwidth::Off;
    c.configure(&cfg);
    c.set_motion(Motion::ConstantRotation {
        lat_deg: 45.0,
        heading_deg: 0.0,
        rate_dps: [0.0, 2500.0, 0.0],
    });
    let mut t = 0;
    ticks(&mut c, &mut t, 1);
    let s = c.output();
    assert_eq!(s.gyro[1], 2000.0, "clipped at the range");
    let st = Status::of(&c.health());
    assert_eq!(
        st.usw & (7 << 10),
        usw::RATE_X_RANGE << 1,
        "Y only: {:#06x}",
        st.usw
    );
    // The bit covers the interval the output covered, then clears.
    c.set_motion(Motion::default());
    ticks(&mut c, &mut t, 1);
    assert_ne!(
        Status::of(&c.health()).usw & (7 << 10),
        0,
        "still reported for the last interval"
    );
    c.output();
    assert_eq!(Status::of(&c.health()).usw & (7 << 10), 0);
}

#[test]
fn faults_drive_usw_and_getbit() {
    let mut c = SignalChain::new(k("K110"), 1);
    let mut t = 0;
    ticks(&mut c, &mut t, 10);
    let before = c.output();
    {
        let f = c.faults_mut();
        f.sensor_comm = true;
        f.sensor_config = true;
        f.gyro_bit = true;
        f.accel_bit = true;
        f.flash_check = true;
        f.temperature_c = Some(90.0);
        f.supply_voltage = Some(5.5);
    }
    ticks(&mut c, &mut t, 10);
    let s = c.output();
    let st = Status::of(&c.health());
    assert_eq!(
        st.usw,
        usw::SENSOR_COMM | usw::SENSOR_CONFIG | usw::TEMPERATURE
    );
    assert_eq!(st.bit, [0x05, 0x10, 0, 0]);
    assert_eq!(s.temperature, 90.0);
    assert_eq!(s.supply_voltage, 5.5);
    // Communication lost: the sensor data freeze.
    let frozen = c.last_sensor();
    ticks(&mut c, &mut t, 10);
    assert_eq!(c.last_sensor(), frozen);
    assert_ne!(before.gyro, s.gyro);
    c.faults_mut().temperature_c = Some(-41.0);
    ticks(&mut c, &mut t, 1);
    assert_ne!(Status::of(&c.health()).usw & usw::TEMPERATURE, 0);
    *c.faults_mut() = Default::default();
    ticks(&mut c, &mut t, 1);
    assert_eq!(Status::of(&c.health()).usw, 0);
    assert_eq!(Status::of(&c.health()).bit, [0; 4]);
}

#[test]
fn temperature_warms_up_from_ambient() {
    let mut c = SignalChain::new(k("K110"), 1);
    let mut t = 0;
    assert_eq!(c.temperature(), 25.0);
    ticks(&mut c, &mut t, 600 * 2000); // one time constant
    let expect = 25.0 + 8.0 * (1.0 - (-1.0f32).exp());
    assert!(
        (c.temperature() - expect).abs() < 0.05,
        "{}",
        c.temperature()
    );
}

/// Reconfiguring keeps the FIR history and starts the cascade in steady
/// state: a static unit's output does not jump at a data command.
#[test]
fn configure_has_no_transient() {
    let p = k("K110");
    let mut c = SignalChain::new(p, 1);
    *c.errors_mut() = ErrorModel::IDEAL;
    let mut t = 0;
    ticks(&mut c, &mut t, 500);
    for (lpf, mask) in [(0u8, 7u8), (4, 0), (0xFF, 3), (2, 4)] {
        let mut cfg = ChainConfig::defaults(&p);
        cfg.lpf = lpf_bandwidth(lpf);
        cfg.cascade.mask = mask;
        c.configure(&cfg);
        for _ in 0..50 {
            ticks(&mut c, &mut t, 1);
            let s = c.output();
            assert!(
                (s.acc[2] - 1.0).abs() < 1e-5 && (s.acc_filtered[2] - 1.0).abs() < 1e-5,
                "{lpf} {mask}: {s:?}"
            );
        }
    }
}

#[test]
fn k201_runs_at_4khz_with_doubled_fir_order() {
    let p = k("K201");
    let cfg = ChainConfig::defaults(&p);
    assert_eq!(cfg.internal_rate_hz, 4000);
    assert_eq!(cfg.fir_design().unwrap().order, 24); // 262 Hz, 3 ms
    let mut c = SignalChain::new(p, 1);
    c.configure(&cfg);
    let mut t = 0;
    for _ in 0..4000 {
        t += 1;
        c.tick(Instant::from_micros(250 * t));
    }
    let s = c.output();
    assert!((s.acc[2] - 1.0).abs() < 0.02);
    assert_eq!(s.aux_acc, [0.0; 3]);
}

#[test]
fn from_block_reads_the_parameter_rows() {
    use imu_emu::kernel::params;
    let p = k("K120");
    let mut block = params::factory_block(&p);
    block[usize::from(params::LPF_BANDWIDTH.id)] = 1;
    block[usize::from(params::FILTER.id)] = 5;
    block[usize::from(params::OUTPUT_VARIANT.id)] = 2;
    block[usize::from(params::ZUPT.id)] = 1;
    let a = usize::from(params::ALIGNMENT_ANGLES.id);
    block[a..a + 4].copy_from_slice(&(-90.0f32).to_le_bytes());
    block[a + 8..a + 12].copy_from_slice(&(180.0f32).to_le_bytes());
    block[0x045A..0x045E].copy_from_slice(&(100.0f32).to_le_bytes());
    block[0x046A..0x046E].copy_from_slice(&(0.05f32).to_le_bytes());
    let cfg = config::chain_config(&block, &p);
    assert_eq!(cfg.lpf, Bandwidth::Hz33);
    assert_eq!(cfg.cascade.mask, 5);
    assert_eq!(cfg.cascade.filt1.omega, 100.0);
    assert_eq!(cfg.cascade.tau, 0.05);
    assert_eq!(cfg.output_variant, OutputVariant::Incremental);
    assert!(cfg.align.zupt);
    assert_eq!(cfg.alignment_angles_deg, [-90.0, 0.0, 180.0]);
    block[usize::from(params::AVERAGE_OUTPUT_DATA.id)] = 1;
    assert_eq!(
        config::chain_config(&block, &p).output_variant,
        OutputVariant::Average
    );
    let d = ChainConfig::defaults(&p);
    assert_eq!(
        (d.lpf, d.cascade.mask, d.output_variant),
        (Bandwidth::Hz262, 0, OutputVariant::Instant)
    );
}

/// The chain's share of RAM (the firmware has 64 KiB of static RAM for the
/// whole image; the device around the chain takes ~6 KiB): the chain fits
/// 12 KiB in either build (10 KiB before it carried the vehicle state a
/// board's source sets, ≈ 200 B of `f64`, and the flicker terms of the
/// sensor profiles).
#[test]
fn size_of_the_chain_fits_the_12_kib_budget() {
    let n = core::mem::size_of::<SignalChain>();
    assert!(n <= 12 * 1024, "{n}");
}

/// The neutral health reports accelerometer axes beyond their range too
/// (the KERNEL's USW has no bit for it: its words are unchanged).
#[test]
fn health_reports_accelerometer_over_range_per_axis() {
    let p = k("KERNEL-110-G2000-A8");
    let mut c = SignalChain::new(p, 1);
    *c.errors_mut() = ErrorModel::IDEAL;
    c.set_motion(Motion::Sample(imu_emu::sensor::Truth {
        rate_dps: [0.0; 3],
        specific_force_g: [0.0, 0.0, 12.0],
        temperature_c: None,
    }));
    let mut t = 0;
    ticks(&mut c, &mut t, 1);
    let h = c.health();
    assert_eq!((h.accel_over_range, h.gyro_over_range), (0b100, 0));
    assert_eq!(Status::of(&h).usw, 0);
    c.output();
    c.set_motion(Motion::default());
    ticks(&mut c, &mut t, 1);
    assert_eq!(c.health().accel_over_range, 0b100, "the last interval");
    c.output();
    assert_eq!(c.health().accel_over_range, 0);
}
