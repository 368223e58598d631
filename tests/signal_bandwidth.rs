//! A sensor profile's `bandwidth_hz` (docs/sensors.md "Bandwidth"): the
//! sensor's first-order −3 dB response, applied per axis at the internal
//! rate before the FIR, in the float build and (with `--features
//! fixed-point`) the fixed-point build — these tests run the same chain in
//! either. And the white noise at DC unchanged in both engines (the
//! fixed-point filter is pinned against the float one sample by sample in
//! `tests/signal_noise.rs`, `fixed_point_engine_tracks_the_float_engine`).

use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::model::Product;
use imu_emu::sensor::errors::{TriadEngine, TriadEngineFixed};
use imu_emu::sensor::profiles::{self, IMX5_PROFILE};
use imu_emu::sensor::rng::Rng;
use imu_emu::sensor::{ErrorModel, MotionSource, SensorProfile, Truth};
use imu_emu::time::Instant;

/// A sine of `amp` °/s on gyro X and of `amp`/100 g on acc Z (about 1 g)
/// at `freq` Hz, one value a tick.
struct Sine {
    n: u64,
    freq: f64,
    amp: f64,
}

impl MotionSource for Sine {
    fn next(&mut self, _now: Instant, dt: f32) -> Truth {
        let t = self.n as f64 * f64::from(dt);
        self.n += 1;
        let s = (std::f64::consts::TAU * self.freq * t).sin();
        Truth {
            rate_dps: [(self.amp * s) as f32, 0.0, 0.0],
            specific_force_g: [0.0, 0.0, (1.0 + self.amp / 100.0 * s) as f32],
            temperature_c: None,
        }
    }
}

/// The amplitude at `freq` of `y` sampled at `fs` (least squares of a
/// constant, a sine and a cosine over a whole number of periods).
fn amplitude(y: &[f64], freq: f64, fs: f64) -> f64 {
    let w = std::f64::consts::TAU * freq / fs;
    let n = y.len() as f64;
    let mean = y.iter().sum::<f64>() / n;
    let (mut s, mut c) = (0.0, 0.0);
    for (k, v) in y.iter().enumerate() {
        s += (v - mean) * (w * k as f64).sin();
        c += (v - mean) * (w * k as f64).cos();
    }
    2.0 * (s * s + c * c).sqrt() / n
}

/// The gyro X and acc Z amplitudes (relative to the input's) of a chain of
/// `product` with `profile`, its FIR off and an instant output every tick,
/// driven by a sine at `freq`.
fn gains(product: Product, profile: &'static SensorProfile, freq: f64) -> (f64, f64) {
    let mut chain = SignalChain::unpowered(product);
    chain.set_profile(Some(profile));
    chain.reset(product, 7);
    let mut cfg = ChainConfig::defaults(&product);
    cfg.lpf = Bandwidth::Off;
    chain.configure(&cfg);
    // Held at the warmed-up temperature: no drift under the sine.
    chain.faults_mut().temperature_c = Some(33.0);
    let fs = f64::from(product.model.internal_rate_hz);
    let amp = 20.0;
    let mut src = Sine { n: 0, freq, amp };
    let (mut g, mut a) = (Vec::new(), Vec::new());
    // 0.1 s to settle, then 1 s (a whole number of periods of every
    // frequency used here).
    let settle = (fs / 10.0) as u64;
    for t in 1..=settle + fs as u64 {
        chain.tick_with(Instant::from_micros(t * 500), &mut src);
        let s = chain.output();
        if t > settle {
            g.push(f64::from(s.gyro[0]));
            a.push(f64::from(s.acc[2]));
        }
    }
    (
        amplitude(&g, freq, fs) / amp,
        amplitude(&a, freq, fs) / (amp / 100.0),
    )
}

/// The bilinear-with-prewarp first order's gain at `f` for a bandwidth
/// `fc` at `fs`: 1/√(1 + (tan(πf/fs)/tan(πfc/fs))²), √½ at `fc`.
fn expected(f: f64, fc: f64, fs: f64) -> f64 {
    let r = (std::f64::consts::PI * f / fs).tan() / (std::f64::consts::PI * fc / fs).tan();
    1.0 / (1.0 + r * r).sqrt()
}

/// The K110's built-in (mid-grade) profile with `bandwidth_hz` = `gyro`
/// and `acc`: what a user's `--sensor-profile` file with the key gives.
fn k110_with(gyro: f32, acc: f32) -> &'static SensorProfile {
    let mut p = profiles::KERNEL_MID;
    p.gyro.bandwidth_hz = gyro;
    p.acc.bandwidth_hz = acc;
    assert_eq!(p.validate(), Ok(()));
    Box::leak(Box::new(p))
}

/// A sine at the configured bandwidth comes out at −3 dB (0.707), one well
/// below it at ≈ 1, one above it by the first order's slope; through the
/// whole chain (profile → error engine → FIR off → instant output).
#[test]
fn a_sine_at_the_bandwidth_reads_minus_3_db() {
    let k110 = Product::parse("K110").unwrap();
    let p = k110_with(50.0, 30.0);
    for f in [5.0, 30.0, 50.0, 200.0] {
        let (g, a) = gains(k110, p, f);
        let (eg, ea) = (expected(f, 50.0, 2000.0), expected(f, 30.0, 2000.0));
        println!("K110 {f} Hz: gyro {g:.4} (expected {eg:.4}), acc {a:.4} (expected {ea:.4})");
        assert!((g / eg - 1.0).abs() < 0.01, "gyro at {f} Hz: {g} vs {eg}");
        assert!((a / ea - 1.0).abs() < 0.01, "acc at {f} Hz: {a} vs {ea}");
    }
    let (g, a) = gains(k110, p, 50.0);
    assert!((g - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.02, "{g}");
    let (_, a30) = gains(k110, p, 30.0);
    assert!(
        (a30 - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.02,
        "{a30}"
    );
    assert!(a < 0.6, "acc at 50 Hz through 30 Hz: {a}");
    let (g, a) = gains(k110, p, 5.0);
    assert!(g > 0.99 && a > 0.98, "{g} {a}");
}

/// The IMX-5's datasheet bandwidths (539 Hz gyro, 416 Hz acc, at its
/// 2 kHz internal rate) are applied: −3 dB at each.
#[test]
fn the_imx5_reads_minus_3_db_at_its_datasheet_bandwidths() {
    let imx5 = Product::imx5();
    let (g, _) = gains(imx5, &IMX5_PROFILE, 539.0);
    let (_, a) = gains(imx5, &IMX5_PROFILE, 416.0);
    println!("IMX-5: gyro at 539 Hz {g:.4}, acc at 416 Hz {a:.4}");
    assert!((g - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.02, "{g}");
    assert!((a - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.02, "{a}");
    let (g, a) = gains(imx5, &IMX5_PROFILE, 20.0);
    assert!(g > 0.995 && a > 0.995, "{g} {a}");
}

/// Bandwidth 0 (not given) and at or above Nyquist: no filter, a sine at
/// 400 Hz passes at full amplitude.
#[test]
fn no_filter_at_zero_or_at_nyquist() {
    let k110 = Product::parse("K110").unwrap();
    for bw in [0.0, 1000.0, 2000.0] {
        let (g, a) = gains(k110, k110_with(bw, bw), 400.0);
        assert!(
            (g - 1.0).abs() < 0.005 && (a - 1.0).abs() < 0.01,
            "{bw}: {g} {a}"
        );
    }
}

/// The validator's range of `bandwidth_hz` is unchanged (0 … 2000 Hz) and
/// so is its error.
#[test]
fn the_validator_keeps_its_range_and_error() {
    let mut p = profiles::KERNEL_MID;
    p.gyro.bandwidth_hz = 2000.0;
    assert_eq!(p.validate(), Ok(()));
    p.gyro.bandwidth_hz = 2001.0;
    assert_eq!(
        p.validate().unwrap_err().to_string(),
        "gyro.bandwidth_hz = 2001 is outside the allowed range 0 ..= 2000"
    );
    p.gyro.bandwidth_hz = 50.0;
    p.acc.bandwidth_hz = -1.0;
    assert_eq!(
        p.validate().unwrap_err().to_string(),
        "acc.bandwidth_hz = -1 is outside the allowed range 0 ..= 2000"
    );
}

/// σ of `blocks` means of `block` samples each.
fn block_sd(blocks: usize, block: usize, mut sample: impl FnMut() -> f64) -> f64 {
    let means: Vec<f64> = (0..blocks)
        .map(|_| (0..block).map(|_| sample()).sum::<f64>() / block as f64)
        .collect();
    let m = means.iter().sum::<f64>() / blocks as f64;
    (means.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (blocks - 1) as f64).sqrt()
}

/// The white noise at DC is the profile's: the filter's DC gain is 1, so a
/// mean over many samples (0.1 s blocks, far below the bandwidth) has the
/// same σ with the filter as without (the ARW the Allan slope reads), in
/// both engines.
#[test]
fn the_white_noise_density_at_dc_is_unchanged() {
    use imu_emu::math::GYRO_BITS;
    let dt = 1.0 / 2000.0f32;
    let (blocks, block) = (2000, 200);
    let errors = |bw: f32| {
        let mut e = ErrorModel::from_profile(&IMX5_PROFILE, &mut Rng::new(3)).gyro;
        e.bandwidth_hz = bw;
        for a in e.axes.iter_mut() {
            a.bias_instability = 0.0;
        }
        e
    };
    let float = |bw: f32| {
        let mut f = TriadEngine::new(4000.0);
        f.configure(&errors(bw), 25.0, dt);
        let mut rng = Rng::new(11);
        block_sd(blocks, block, || {
            f64::from(f.measure(&[0.0; 3], &[0.0; 3], &mut rng).0[0])
        })
    };
    let fixed = |bw: f32| {
        let mut f = TriadEngineFixed::new(2000.0, GYRO_BITS);
        f.configure(&errors(bw), 25.0, dt);
        let mut rng = Rng::new(11);
        let unit = 1.0 / f64::from(1u32 << GYRO_BITS);
        block_sd(blocks, block, || {
            f64::from(f.measure(&[0; 3], &[0; 3], &mut rng).0[0]) * unit
        })
    };
    let n = f64::from(IMX5_PROFILE.gyro.noise_density);
    // σ of a mean over T = 0.1 s of white noise N: N/√T.
    let expect = n / (block as f64 * f64::from(dt)).sqrt();
    for (name, sd) in [("float", &float as &dyn Fn(f32) -> f64), ("fixed", &fixed)] {
        let (off, on) = (sd(0.0), sd(50.0));
        println!(
            "{name}: σ of 0.1 s means {off:.6} without, {on:.6} with 50 Hz (N/√T = {expect:.6})"
        );
        assert!((off / expect - 1.0).abs() < 0.05, "{name}: {off}");
        assert!((on / off - 1.0).abs() < 0.03, "{name}: {on} vs {off}");
    }
}
