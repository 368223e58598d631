//! The sensor error model against its Allan-variance parameters.
//!
//! Long static runs of the noise model (the error engine alone, no FIR, so
//! 10⁶ samples take a fraction of a second) give an Allan deviation whose
//! white-noise slope reads the configured noise density N (ARW) and whose
//! flat floor reads the bias instability B by the datasheet rule (floor /
//! 0.6643, IEEE 952): the flicker of `sensor::errors` ("Flicker"). The
//! Allan deviation comes from the `allan` crate (checked here against a
//! direct overlapping computation).

// The fit indexes its normal equations by row and column.
#![allow(clippy::needless_range_loop)]

use allan::{Allan, DataType, Style};
use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::dsp::variant::OutputVariant;
use imu_emu::model::Product;
use imu_emu::sensor::errors::{AxisErrors, SensorErrors, TriadEngine};
use imu_emu::sensor::rng::Rng;
use imu_emu::sensor::ErrorModel;
use imu_emu::time::Instant;

const FS: f64 = 2000.0;
/// Samples averaged into one record (5 ms).
const BLOCK: usize = 10;

/// One gyro triad's errors: white noise `noise`, bias instability `bi`,
/// rate random walk `rrw`, nothing else.
fn white_flicker_walk(noise: f32, bi: f32, rrw: f32) -> SensorErrors {
    let axis = AxisErrors {
        noise_density: noise,
        bias_instability: bi,
        rate_random_walk: rrw,
        ..AxisErrors::default()
    };
    SensorErrors {
        axes: [axis; 3],
        ..SensorErrors::default()
    }
}

/// `seconds` of `sample` (°/s, one a tick) averaged over [`BLOCK`]s: the
/// block means and their Allan variance.
fn record_blocks(seconds: f64, mut sample: impl FnMut() -> f64) -> (Vec<f64>, Allan) {
    let mut allan = Allan::builder()
        .max_tau(4000)
        .style(Style::Decade125)
        .data_type(DataType::Frequency)
        .build_allan();
    let n = (seconds * FS) as usize / BLOCK;
    let mut blocks = Vec::with_capacity(n);
    for _ in 0..n {
        let m = (0..BLOCK).map(|_| sample()).sum::<f64>() / BLOCK as f64;
        allan.record(m);
        blocks.push(m);
    }
    (blocks, allan)
}

fn run(noise: f32, bi: f32, rrw: f32, seconds: f64, seed: u64) -> (Vec<f64>, Allan) {
    let errors = white_flicker_walk(noise, bi, rrw);
    let mut e = TriadEngine::new(1e9);
    e.configure(&errors, 25.0, (1.0 / FS) as f32);
    let mut rng = Rng::new(seed);
    e.randomize_slow(&errors, &mut rng);
    record_blocks(seconds, || {
        f64::from(e.measure(&[0.0; 3], &[0.0; 3], &mut rng).0[0])
    })
}

/// Overlapping Allan deviation of frequency data `y` at `m` samples.
fn adev(y: &[f64], m: usize) -> f64 {
    let mut x = vec![0.0];
    for v in y {
        x.push(x.last().unwrap() + v);
    }
    let n = x.len();
    let mut s = 0.0;
    for i in 0..n - 2 * m {
        let d = x[i + 2 * m] - 2.0 * x[i + m] + x[i];
        s += d * d;
    }
    (s / (2.0 * (n - 2 * m) as f64 * (m * m) as f64)).sqrt()
}

/// Flicker's flat Allan deviation / B: √(2 ln 2/π) (IEEE 952).
const FLICKER_FLOOR: f64 = 0.664_282;

/// Allan variance of a Gauss–Markov process of unit variance, τ/T_c = x.
fn gm_avar(x: f64) -> f64 {
    (2.0 / x) * (1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x))
}

/// The Allan variance of the engine's flicker per B² (its Gauss–Markov
/// terms of variance B²·ln 10/π at corners 10^k s): ≈ 0.4413 (= 0.6643²)
/// from 3 s to 3·10⁴ s, less outside.
fn flicker_avar(tau: f64) -> f64 {
    use imu_emu::sensor::errors::FLICKER_CORNERS_S;
    let q2 = std::f64::consts::LN_10 / std::f64::consts::PI;
    FLICKER_CORNERS_S
        .iter()
        .map(|&t| q2 * gm_avar(tau / f64::from(t)))
        .sum()
}

/// Weighted linear least squares of the Allan variance in (N², B², K²) over
/// τ ≤ `tau_max`: `σ²(τ) = N²/τ + B²·φ(τ) + K²·τ/3` (white, the
/// engine's flicker [`flicker_avar`], rate random walk), and the (τ, σ)
/// points fitted; x[1] = B² (so B = √x[1]).
fn fit(allan: &Allan, tau0: f64, tau_max: f64, with_walk: bool) -> ([f64; 3], Vec<(f64, f64)>) {
    let mut rows = Vec::new();
    let mut points = Vec::new();
    for t in allan.iter() {
        let tau = t.tau() as f64 * tau0;
        let Some(v) = t.variance() else { continue };
        if tau > tau_max || v <= 0.0 {
            continue;
        }
        let f = [
            1.0 / tau,
            flicker_avar(tau),
            if with_walk { tau / 3.0 } else { 0.0 },
        ];
        rows.push((f, v));
        points.push((tau, v.sqrt()));
    }
    let n = if with_walk { 3 } else { 2 };
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for (f, v) in &rows {
        let w = 1.0 / (v * v);
        for i in 0..n {
            b[i] += w * f[i] * v;
            for j in 0..n {
                a[i][j] += w * f[i] * f[j];
            }
        }
    }
    // Gaussian elimination (n ≤ 3).
    for c in 0..n {
        for r in c + 1..n {
            let k = a[r][c] / a[c][c];
            for j in c..n {
                a[r][j] -= k * a[c][j];
            }
            b[r] -= k * b[c];
        }
    }
    let mut x = [0.0f64; 3];
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|j| a[c][j] * x[j]).sum();
        x[c] = (b[c] - s) / a[c][c];
    }
    (x, points)
}

#[test]
fn allan_deviation_recovers_arw_and_the_bias_instability_floor() {
    // ARW 0.3 °/√h (N = 0.005 °/s/√Hz); B = 0.02 °/s: the flicker floor
    // (0.0133 °/s) meets the white slope at τ ≈ 0.14 s and is flat from
    // 3 s on; 2000 s of data hold 20 of τ = 100 s.
    let (n_true, b_true) = (0.005f32, 0.02f32);
    let (blocks, allan) = run(n_true, b_true, 0.0, 2000.0, 42);
    let tau0 = BLOCK as f64 / FS;

    // The crate agrees with a direct overlapping computation.
    for m in [1usize, 20, 200] {
        let a = allan.get(m).unwrap().deviation().unwrap();
        let b = adev(&blocks, m);
        assert!((a / b - 1.0).abs() < 1e-4, "τ {m}: crate {a} vs direct {b}");
    }

    let (x, points) = fit(&allan, tau0, 200.0, false);
    let n_est = x[0].sqrt();
    let b_est = x[1].sqrt();
    println!("ADEV points (τ s, σ °/s): {points:?}");
    println!("N = {n_est:.5} (true {n_true}), B = {b_est:.5} (true {b_true})");
    assert!(
        (n_est / f64::from(n_true) - 1.0).abs() < 0.05,
        "ARW: {n_est}"
    );
    assert!((b_est / f64::from(b_true) - 1.0).abs() < 0.10, "B: {b_est}");

    // Read the way a datasheet is read: σ(τ)·√τ on the −½ slope gives N,
    // and the floor (here every τ from 3 s to 100 s, where the white
    // noise adds < 1 %) is 0.6643·B: a floor, not one Gauss–Markov bump.
    let s = allan.get(2).unwrap().deviation().unwrap() * (2.0 * tau0).sqrt();
    assert!(
        (s / f64::from(n_true) - 1.0).abs() < 0.10,
        "σ(10 ms)·√τ = {s}"
    );
    for &(tau, sigma) in points.iter().filter(|(t, _)| (3.0..=100.0).contains(t)) {
        let read = sigma / FLICKER_FLOOR;
        assert!(
            (read / f64::from(b_true) - 1.0).abs() < 0.10,
            "floor at τ {tau}: {read}"
        );
    }
}

/// Rate random walk alone: the +½ slope, K recovered within 20 %.
#[test]
fn rate_random_walk_has_the_plus_half_slope() {
    let k_true = 1e-3f32;
    let (_, allan) = run(0.001, 0.0, k_true, 2000.0, 11);
    let tau0 = BLOCK as f64 / FS;
    let (x, _) = fit(&allan, tau0, 200.0, true);
    let k_est = x[2].max(0.0).sqrt();
    println!("K = {k_est:.3e} (true {k_true:e}), N = {:.5}", x[0].sqrt());
    assert!((k_est / f64::from(k_true) - 1.0).abs() < 0.20, "K: {k_est}");
}

#[test]
fn white_noise_alone_has_the_minus_half_slope() {
    let (_, allan) = run(0.01, 0.0, 0.0, 100.0, 7);
    let tau0 = BLOCK as f64 / FS;
    for m in [1usize, 10, 100, 1000] {
        let sigma = allan.get(m).unwrap().deviation().unwrap();
        let n = sigma * (m as f64 * tau0).sqrt();
        // Fewer independent τ at the long end: 5 %, 5 %, 8 %, 20 %.
        let tol = [0.05, 0.05, 0.08, 0.2][m.ilog10() as usize];
        assert!((n / 0.01 - 1.0).abs() < tol, "τ {m}: N {n}");
    }
}

/// End to end through the chain (LPF off, instant output at the internal
/// rate): the gyro's per-sample σ is N·√f_s and its mean is the turn-on bias
/// plus the Earth rate.
#[test]
fn chain_output_noise_and_mean_match_the_model() {
    let product = Product::parse("K110").unwrap();
    let mut chain = SignalChain::new(product, 3);
    let mut cfg = ChainConfig::defaults(&product);
    cfg.lpf = Bandwidth::Off;
    chain.configure(&cfg);
    *chain.errors_mut() = ErrorModel::IDEAL;
    let n_density = 0.004f32;
    chain.errors_mut().gyro.axes[2].noise_density = n_density;
    chain.errors_mut().gyro.axes[2].bias = 0.1;
    chain.faults_mut().temperature_c = Some(25.0);
    let ticks = 20_000;
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for t in 1..=ticks {
        chain.tick(Instant::from_micros(500 * t));
        let g = f64::from(chain.output().gyro[2]);
        s += g;
        s2 += g * g;
    }
    let mean = s / ticks as f64;
    let sd = (s2 / ticks as f64 - mean * mean).sqrt();
    let expect_sd = f64::from(n_density) * FS.sqrt();
    assert!((sd / expect_sd - 1.0).abs() < 0.03, "σ {sd} vs {expect_sd}");
    // Earth rate, vertical part at 45° N: 15.041 °/h · sin 45°.
    let earth_z = 15.041 / 3600.0 * std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        (mean - 0.1 - earth_z).abs() < 4.0 * expect_sd / (ticks as f64).sqrt(),
        "mean {mean}"
    );
}

/// `run` for the fixed-point engine (the `fixed-point` build's chain uses
/// it): the same parameters, measurements in °/s·2¹⁹.
fn run_fixed(noise: f32, bi: f32, rrw: f32, seconds: f64, seed: u64) -> Allan {
    use imu_emu::math::GYRO_BITS;
    use imu_emu::sensor::errors::TriadEngineFixed;
    let errors = white_flicker_walk(noise, bi, rrw);
    let mut e = TriadEngineFixed::new(1e9, GYRO_BITS);
    e.configure(&errors, 25.0, (1.0 / FS) as f32);
    let mut rng = Rng::new(seed);
    e.randomize_slow(&errors, &mut rng);
    let unit = 1.0 / f64::from(1u32 << GYRO_BITS);
    let sample = || f64::from(e.measure(&[0; 3], &[0; 3], &mut rng).0[0]) * unit;
    record_blocks(seconds, sample).1
}

/// The fixed-point engine (integer Irwin–Hall noise, integer flicker and
/// random walk) has the same Allan deviation: the same fit recovers N and
/// B (and K), and white noise alone keeps the −½ slope.
#[test]
fn fixed_point_engine_recovers_arw_bias_instability_and_random_walk() {
    let (n_true, b_true) = (0.005f32, 0.02f32);
    let allan = run_fixed(n_true, b_true, 0.0, 2000.0, 42);
    let tau0 = BLOCK as f64 / FS;
    let (x, _) = fit(&allan, tau0, 200.0, false);
    let n_est = x[0].sqrt();
    let b_est = x[1].sqrt();
    println!("fixed point: N = {n_est:.5} (true {n_true}), B = {b_est:.5} (true {b_true})");
    assert!(
        (n_est / f64::from(n_true) - 1.0).abs() < 0.05,
        "ARW: {n_est}"
    );
    assert!((b_est / f64::from(b_true) - 1.0).abs() < 0.10, "B: {b_est}");

    let k_true = 1e-3f32;
    let allan = run_fixed(0.001, 0.0, k_true, 2000.0, 11);
    let (x, _) = fit(&allan, tau0, 200.0, true);
    let k_est = x[2].max(0.0).sqrt();
    assert!((k_est / f64::from(k_true) - 1.0).abs() < 0.20, "K: {k_est}");

    let allan = run_fixed(0.01, 0.0, 0.0, 100.0, 7);
    for m in [1usize, 10, 100, 1000] {
        let n = allan.get(m).unwrap().deviation().unwrap() * (m as f64 * tau0).sqrt();
        let tol = [0.05, 0.05, 0.08, 0.2][m.ilog10() as usize];
        assert!((n / 0.01 - 1.0).abs() < tol, "τ {m}: N {n}");
    }
}

/// Sample by sample, the fixed-point engine measures what the float engine
/// measures from the same random draws: scale factor, misalignment, bias
/// and its temperature terms, noise and Gauss–Markov state agree to the
/// coefficients' 14-bit mantissas (~6e-5 of each error term) and the
/// output's 2⁻¹⁹ °/s, whatever the truth; with the sensor's bandwidth
/// (`sensor::bandwidth`: 539 Hz, the IMX-5's gyro, 50 and 5 Hz) too, within
/// the float filter's own `f32` rounding, ulp(y)/(4·min(b, 1 − b)) (the
/// fixed-point coefficient's 30-bit mantissa adds nothing visible).
#[test]
fn fixed_point_engine_tracks_the_float_engine() {
    use imu_emu::math::{ACC_BITS, GYRO_BITS};
    use imu_emu::sensor::errors::TriadEngineFixed;
    let product = Product::parse("K120").unwrap();
    let mut draw = Rng::new(5);
    let mut errors = ErrorModel::from_profile(&product.sensor_profile(), &mut draw).gyro;
    // Every term of the model, the new ones too (the built-in profiles
    // have no non-linearity, g-sensitivity, random walk or resolution).
    for (i, a) in errors.axes.iter_mut().enumerate() {
        a.nonlinearity = [1e-3, -2e-3, 5e-4][i];
        a.g_sensitivity = [0.01, -0.02, 0.005][i];
        a.rate_random_walk = 1e-4;
    }
    let dt = (1.0 / FS) as f32;
    // Resolution a power of two: the same step in both engines; none with
    // a bandwidth, so that the filters are compared below its step.
    for (bw, resolution, ticks) in [
        (0.0f32, 1.0 / 1024.0, 200_000),
        (539.0, 0.0, 100_000),
        (539.0, 1.0 / 1024.0, 20_000),
        (50.0, 0.0, 100_000),
        (5.0, 0.0, 100_000),
    ] {
        errors.bandwidth_hz = bw;
        errors.resolution = resolution;
        // The float filter's rounding (0 without one).
        let b = imu_emu::sensor::bandwidth::coefficient(bw, dt).map_or(f32::INFINITY, |b| b as f32);
        let b_min = b.min(1.0 - b);
        let mut worst = 0.0f32;
        let mut f = TriadEngine::new(2000.0);
        let mut q = TriadEngineFixed::new(2000.0, GYRO_BITS);
        f.configure(&errors, 31.0, dt);
        q.configure(&errors, 31.0, dt);
        let (mut rf, mut rq) = (Rng::new(9), Rng::new(9));
        f.randomize_slow(&errors, &mut rf);
        q.randomize_slow(&errors, &mut rq);
        let scale = (1u32 << GYRO_BITS) as f32;
        for k in 0..ticks {
            let t = k as f32 * 1e-3;
            let truth = [
                300.0 * t.sin(),
                -50.0 + 10.0 * t.cos(),
                1500.0 * (0.1 * t).sin(),
            ];
            let tq = truth.map(|v| (v * scale).round() as i32);
            let force = [0.5 * t.cos(), -0.3, 1.0 + 0.2 * (2.0 * t).sin()];
            let fq = force.map(|v| (v * (1u32 << ACC_BITS) as f32).round() as i32);
            let fr = fq.map(|v| v as f32 / (1u32 << ACC_BITS) as f32);
            let (a, oa) = f.measure(&tq.map(|v| v as f32 / scale), &fr, &mut rf);
            let (b, ob) = q.measure(&tq, &fq, &mut rq);
            assert_eq!(oa, ob);
            for i in 0..3 {
                // Values within the rounding of the quantiser's boundary may
                // fall one step (resolution 2⁻¹⁰ °/s) apart.
                let d = (a[i] - b[i] as f32 / scale).abs();
                let d = if resolution > 0.0 {
                    d.min((d - resolution).abs())
                } else {
                    d
                };
                // 6e-5 of the error terms (≤ 1.5e-3 × 1500 °/s of scale and
                // misalignment, 0.6 °/s of noise, ≤ 2.3 °/s of non-linearity,
                // 0.03 °/s of g-sensitivity) + the f32 rounding of the float
                // engine at 1500 °/s + 1 LSB; + the float filter's rounding.
                let tol = 6e-5 * (1.5e-3 * truth[i].abs() + 3.0)
                    + 2e-4
                    + 2.0 / scale
                    + f32::EPSILON * a[i].abs().max(1.0) / (4.0 * b_min);
                worst = worst.max(d / tol);
                assert!(
                    d <= tol,
                    "{bw} Hz, {k} axis {i}: {} vs {}",
                    a[i],
                    b[i] as f32 / scale
                );
            }
        }
        println!("{bw} Hz, resolution {resolution}: fixed vs float engine, worst {worst:.2} of the bound");
    }
}

/// The white noise read at the output rate (σ of the output / √f_out,
/// the Allan deviation's −½ slope at τ = one output interval) of gyro Z
/// with white noise of density `n` only.
fn output_density(model: &str, lpf: Bandwidth, variant: OutputVariant, rate: u32, n: f32) -> f64 {
    let product = Product::parse(model).unwrap();
    let internal = product.model.internal_rate_hz;
    let mut chain = SignalChain::new(product, 5);
    let mut cfg = ChainConfig::defaults(&product);
    cfg.lpf = lpf;
    cfg.output_variant = variant;
    chain.configure(&cfg);
    *chain.errors_mut() = ErrorModel::IDEAL;
    chain.errors_mut().gyro.axes[2].noise_density = n;
    chain.faults_mut().temperature_c = Some(25.0);
    let every = internal / rate;
    let period_us = 1_000_000 / u64::from(internal);
    // Past the FIR's history, then 2000 outputs.
    let mut t = 0u64;
    for _ in 0..internal / 10 {
        t += period_us;
        chain.tick(Instant::from_micros(t));
    }
    chain.output();
    let outputs = 2000;
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..outputs {
        for _ in 0..every {
            t += period_us;
            chain.tick(Instant::from_micros(t));
        }
        let g = f64::from(chain.output().gyro[2]);
        s += g;
        s2 += g * g;
    }
    let mean = s / f64::from(outputs);
    let sd = (s2 / f64::from(outputs) - mean * mean).sqrt();
    sd / f64::from(rate).sqrt()
}

/// Σh² of the FIR `lpf` selects on `model` (its white-noise power gain),
/// from its impulse response read through the chain: Instant at an output
/// every tick, one tick of 100 °/s on gyro Z after a still start.
fn fir_noise_gain(model: &str, lpf: Bandwidth) -> f64 {
    struct Impulse(u32);
    impl imu_emu::sensor::MotionSource for Impulse {
        fn next(&mut self, _now: Instant, _dt: f32) -> imu_emu::sensor::Truth {
            self.0 += 1;
            let z = if self.0 == 1000 { 100.0 } else { 0.0 };
            imu_emu::sensor::Truth {
                rate_dps: [0.0, 0.0, z],
                specific_force_g: [0.0, 0.0, 1.0],
                temperature_c: Some(25.0),
            }
        }
    }
    let product = Product::parse(model).unwrap();
    let mut chain = SignalChain::new(product, 5);
    let mut cfg = ChainConfig::defaults(&product);
    cfg.lpf = lpf;
    cfg.output_variant = OutputVariant::Instant;
    chain.configure(&cfg);
    *chain.errors_mut() = ErrorModel::IDEAL;
    let period_us = 1_000_000 / u64::from(product.model.internal_rate_hz);
    let mut src = Impulse(0);
    let mut gain = 0.0;
    for t in 1..=3000u64 {
        chain.tick_with(Instant::from_micros(period_us * t), &mut src);
        let h = f64::from(chain.output().gyro[2]) / 100.0;
        gain += h * h;
    }
    gain
}

/// Decimation: Average and Incremental are band-limited by their mean
/// over the output interval and read at most the configured density at
/// every output rate and LPF setting (the unfiltered average reads it: it
/// keeps the whole band). Instant is the FIR's output sampled at the
/// output instant (ICD 5.3.6 "exact values as measured at that
/// instant"), as on a real unit: its σ is the FIR output's, N·√(f_s·Σh²),
/// whatever the output rate, so it reads √(f_s·Σh²/f_out)·N — at most N
/// while the FIR's band is below the output's Nyquist frequency, above
/// it (the band's noise aliased) at lower rates: a K110 at its factory
/// settings (262 Hz, instant, 100 Hz) reads 2.3 N, with the LPF off
/// √(f_s/f_out)·N (docs/sensors.md "Decimation").
#[test]
fn no_variant_or_lpf_raises_the_white_noise_above_the_profile() {
    use OutputVariant::*;
    let n = 0.003f32;
    let lpfs = [
        Bandwidth::Hz16,
        Bandwidth::Hz33,
        Bandwidth::Hz66,
        Bandwidth::Hz131,
        Bandwidth::Hz262,
        Bandwidth::Off,
    ];
    // σ of 2000 outputs: 1.6 % (1σ); 4σ.
    let tol = 1.065;
    for (model, rates) in [
        ("K201", &[4000u32, 2000, 500][..]),
        ("K110", &[2000, 1000, 400, 200, 80][..]),
    ] {
        let internal = Product::parse(model).unwrap().model.internal_rate_hz;
        for lpf in lpfs {
            if model == "K201" && matches!(lpf, Bandwidth::Hz16 | Bandwidth::Hz33) {
                continue; // not a K201 setting (Table 5.24)
            }
            let gain = fir_noise_gain(model, lpf);
            for variant in [Instant, Average, Incremental] {
                for &rate in rates {
                    let read = output_density(model, lpf, variant, rate, n) / f64::from(n);
                    println!("{model} {lpf:?} {variant:?} {rate} Hz: {read:.3} of N");
                    if variant == Instant {
                        let want = (f64::from(internal) * gain / f64::from(rate)).sqrt();
                        // Outputs closer than the FIR's memory are
                        // correlated (fewer independent samples): there
                        // only the bound.
                        let fc = lpf.hz().map_or(f64::INFINITY, f64::from);
                        if f64::from(rate) <= 2.0 * fc {
                            assert!(
                                (read / want - 1.0).abs() < tol - 1.0,
                                "{model} {lpf:?} Instant {rate} Hz: {read:.3} of N, \
                                 sampled FIR {want:.3}"
                            );
                        } else {
                            assert!(want < 1.0 && read < tol, "{model} {lpf:?} {rate} Hz");
                        }
                        continue;
                    }
                    assert!(
                        read < tol,
                        "{model} {lpf:?} {variant:?} {rate} Hz: {read:.3} of N"
                    );
                    if lpf == Bandwidth::Off && variant == Average {
                        // Unfiltered: the whole band, read at the figure.
                        assert!(read > 2.0 - tol, "{model} {variant:?} {rate} Hz: {read:.3}");
                    }
                }
            }
        }
    }
    // The factory settings of a K110: the 262 Hz band aliased into 100 Hz.
    let read = output_density("K110", Bandwidth::Hz262, Instant, 100, n) / f64::from(n);
    assert!(
        (2.0..2.6).contains(&read),
        "K110 factory Instant: {read:.3} of N"
    );
}
