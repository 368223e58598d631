//! The sensor error model against its Allan-variance parameters.
//!
//! A long static run of the noise model (the error engine alone, no FIR, so
//! 10⁶ samples take a fraction of a second) gives an Allan deviation from
//! which a two-term fit `σ²(τ) = N²/τ + σ_GM² · h(τ/T_c)` (white noise plus
//! the exact Allan variance of a Gauss–Markov process) recovers the
//! configured noise density N (ARW) and bias instability B = σ_GM/1.076
//! within 10 %. The Allan deviation comes from the `allan` crate (checked
//! here against a direct overlapping computation).

use allan::{Allan, DataType, Style};
use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::fir::Bandwidth;
use imu_emu::model::Product;
use imu_emu::sensor::errors::{
    AxisErrors, SensorErrors, TriadEngine, GM_SIGMA_PER_BIAS_INSTABILITY,
};
use imu_emu::sensor::rng::Rng;
use imu_emu::sensor::ErrorModel;
use imu_emu::time::Instant;

const FS: f64 = 2000.0;
/// Samples averaged into one record (5 ms).
const BLOCK: usize = 10;

/// Allan variance of a Gauss–Markov process of unit variance, τ/T_c = x.
fn gm_avar(x: f64) -> f64 {
    (2.0 / x) * (1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x))
}

/// One gyro triad's errors: white noise `noise`, bias instability `bi`
/// with correlation time `tc`, nothing else.
fn white_and_gm(noise: f32, bi: f32, tc: f32) -> SensorErrors {
    let axis = AxisErrors {
        noise_density: noise,
        bias_instability: bi,
        bias_corr_time_s: tc,
        ..AxisErrors::default()
    };
    SensorErrors {
        axes: [axis; 3],
        misalignment: [[0.0; 3]; 3],
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

fn run(noise: f32, bi: f32, tc: f32, seconds: f64, seed: u64) -> (Vec<f64>, Allan) {
    let errors = white_and_gm(noise, bi, tc);
    let mut e = TriadEngine::new(1e9);
    e.configure(&errors, 25.0, (1.0 / FS) as f32);
    let mut rng = Rng::new(seed);
    e.randomize_gm(&errors, &mut rng);
    record_blocks(seconds, || f64::from(e.measure(&[0.0; 3], &mut rng).0[0]))
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

/// Weighted linear least squares of the Allan variance in (N², σ_GM²) over
/// τ = 5 ms … 20 s (white noise plus a Gauss–Markov term of correlation time
/// `tc`), and the (τ, σ) points fitted.
fn fit_arw_gm(allan: &Allan, tau0: f64, tc: f32) -> (f64, f64, Vec<(f64, f64)>) {
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut points = Vec::new();
    for t in allan.iter() {
        let tau = t.tau() as f64 * tau0;
        if tau > 20.0 {
            continue;
        }
        let v = t.variance().unwrap();
        let (f1, f2) = (1.0 / tau, gm_avar(tau / f64::from(tc)));
        let w = 1.0 / (v * v);
        a11 += w * f1 * f1;
        a12 += w * f1 * f2;
        a22 += w * f2 * f2;
        b1 += w * f1 * v;
        b2 += w * f2 * v;
        points.push((tau, v.sqrt()));
    }
    let det = a11 * a22 - a12 * a12;
    let n2 = (b1 * a22 - b2 * a12) / det;
    let g2 = (a11 * b2 - a12 * b1) / det;
    (n2, g2, points)
}

#[test]
fn allan_deviation_recovers_arw_and_bias_instability_within_10_percent() {
    // ARW 0.3 °/√h (N = 0.005 °/s/√Hz); B = 0.02 °/s; T_c = 0.5 s: the GM
    // hump (peak 0.664·B at τ ≈ 0.95 s) stands above the white noise, and
    // 500 s of data hold > 500 of its τ.
    let (n_true, b_true, tc) = (0.005f32, 0.02f32, 0.5f32);
    let (blocks, allan) = run(n_true, b_true, tc, 500.0, 42);
    let tau0 = BLOCK as f64 / FS;

    // The crate agrees with a direct overlapping computation.
    for m in [1usize, 20, 200] {
        let a = allan.get(m).unwrap().deviation().unwrap();
        let b = adev(&blocks, m);
        assert!((a / b - 1.0).abs() < 1e-4, "τ {m}: crate {a} vs direct {b}");
    }

    let (n2, g2, points) = fit_arw_gm(&allan, tau0, tc);
    let n_est = n2.sqrt();
    let b_est = g2.sqrt() / f64::from(GM_SIGMA_PER_BIAS_INSTABILITY);
    println!("ADEV points (τ s, σ °/s): {points:?}");
    println!("N = {n_est:.5} (true {n_true}), B = {b_est:.5} (true {b_true})");
    assert!(
        (n_est / f64::from(n_true) - 1.0).abs() < 0.10,
        "ARW: {n_est}"
    );
    assert!((b_est / f64::from(b_true) - 1.0).abs() < 0.10, "B: {b_est}");

    // Read the way a datasheet is read: σ(τ)·√τ on the −½ slope gives N, and
    // the Allan maximum of the bias term is 0.664·B.
    let s = allan.get(2).unwrap().deviation().unwrap() * (2.0 * tau0).sqrt();
    assert!(
        (s / f64::from(n_true) - 1.0).abs() < 0.10,
        "σ(10 ms)·√τ = {s}"
    );
    let peak = points
        .iter()
        .map(|&(tau, sigma)| (sigma * sigma - n2 / tau).max(0.0).sqrt())
        .fold(0.0, f64::max);
    assert!(
        (peak / (0.6643 * f64::from(b_true)) - 1.0).abs() < 0.10,
        "peak {peak}"
    );
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
fn run_fixed(noise: f32, bi: f32, tc: f32, seconds: f64, seed: u64) -> Allan {
    use imu_emu::math::GYRO_BITS;
    use imu_emu::sensor::errors::TriadEngineFixed;
    let errors = white_and_gm(noise, bi, tc);
    let mut e = TriadEngineFixed::new(1e9, GYRO_BITS);
    e.configure(&errors, 25.0, (1.0 / FS) as f32);
    let mut rng = Rng::new(seed);
    e.randomize_gm(&errors, &mut rng);
    let unit = 1.0 / f64::from(1u32 << GYRO_BITS);
    let sample = || f64::from(e.measure(&[0; 3], &mut rng).0[0]) * unit;
    record_blocks(seconds, sample).1
}

/// The fixed-point engine (integer Irwin–Hall noise, integer Gauss–Markov)
/// has the same Allan deviation: the same two-term fit recovers N and B
/// within 10 %, and white noise alone keeps the −½ slope.
#[test]
fn fixed_point_engine_recovers_arw_and_bias_instability_within_10_percent() {
    let (n_true, b_true, tc) = (0.005f32, 0.02f32, 0.5f32);
    let allan = run_fixed(n_true, b_true, tc, 500.0, 42);
    let tau0 = BLOCK as f64 / FS;
    let (n2, g2, _) = fit_arw_gm(&allan, tau0, tc);
    let n_est = n2.sqrt();
    let b_est = g2.sqrt() / f64::from(GM_SIGMA_PER_BIAS_INSTABILITY);
    println!("fixed point: N = {n_est:.5} (true {n_true}), B = {b_est:.5} (true {b_true})");
    assert!(
        (n_est / f64::from(n_true) - 1.0).abs() < 0.10,
        "ARW: {n_est}"
    );
    assert!((b_est / f64::from(b_true) - 1.0).abs() < 0.10, "B: {b_est}");

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
/// output's 2⁻¹⁹ °/s, whatever the truth.
#[test]
fn fixed_point_engine_tracks_the_float_engine() {
    use imu_emu::math::GYRO_BITS;
    use imu_emu::sensor::errors::TriadEngineFixed;
    let product = Product::parse("K120").unwrap();
    let mut draw = Rng::new(5);
    let errors = ErrorModel::for_product(&product, &mut draw).gyro;
    let dt = (1.0 / FS) as f32;
    let mut f = TriadEngine::new(2000.0);
    let mut q = TriadEngineFixed::new(2000.0, GYRO_BITS);
    f.configure(&errors, 31.0, dt);
    q.configure(&errors, 31.0, dt);
    let (mut rf, mut rq) = (Rng::new(9), Rng::new(9));
    f.randomize_gm(&errors, &mut rf);
    q.randomize_gm(&errors, &mut rq);
    let scale = (1u32 << GYRO_BITS) as f32;
    let mut worst = 0.0f32;
    for k in 0..200_000 {
        let t = k as f32 * 1e-3;
        let truth = [
            300.0 * t.sin(),
            -50.0 + 10.0 * t.cos(),
            1500.0 * (0.1 * t).sin(),
        ];
        let tq = truth.map(|v| (v * scale).round() as i32);
        let (a, oa) = f.measure(&tq.map(|v| v as f32 / scale), &mut rf);
        let (b, ob) = q.measure(&tq, &mut rq);
        assert_eq!(oa, ob);
        for i in 0..3 {
            let d = (a[i] - b[i] as f32 / scale).abs();
            // 6e-5 of the error terms (≤ 1.5e-3 × 1500 °/s of scale and
            // misalignment, 0.6 °/s of noise) + the f32 rounding of the
            // float engine at 1500 °/s + 1 LSB.
            let tol = 6e-5 * (1.5e-3 * truth[i].abs() + 0.6) + 2e-4 + 2.0 / scale;
            worst = worst.max(d / tol);
            assert!(
                d <= tol,
                "{k} axis {i}: {} vs {}",
                a[i],
                b[i] as f32 / scale
            );
        }
    }
    println!("fixed vs float engine: worst {worst:.2} of the bound");
}
