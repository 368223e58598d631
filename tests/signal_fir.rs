//! FIR low-pass of ICD 5.6 / Table 5.29: group delay, −3 dB bandwidth,
//! end-to-end delay through the chain, fixed-point parity.

use imu_emu::chain::{ChainConfig, SignalChain, FIXED_SCALE};
use imu_emu::dsp::fir::{self, Bandwidth, FirBank, FirBankFixed, FirDesign, CHANNELS, DESIGNS};
use imu_emu::kernel::config::lpf_bandwidth;

#[test]
fn long_orders_are_two_stage_and_still_order_n_linear_phase() {
    // 16 Hz: P (16) + 4 × G (44) = 192; 33 Hz: 16 + 2 × 40 = 96.
    assert_eq!(
        (fir::FIR_16HZ_2K.stride, fir::FIR_16HZ_2K.stage.order),
        (4, 44)
    );
    assert_eq!(
        (fir::FIR_33HZ_2K.stride, fir::FIR_33HZ_2K.stage.order),
        (2, 40)
    );
    for d in DESIGNS {
        // The running bank's impulse response is the design's taps, all of
        // them non-zero at the ends (true order N), symmetric about N/2.
        let mut bank = FirBank::new(Some(d), &[0.0; CHANNELS]);
        for n in 0..=(d.order + 5) {
            let x = if n == 0 { 1.0 } else { 0.0 };
            let y = bank.push(&[x; CHANNELS])[3];
            let expect = if n <= d.order { d.tap(n) } else { 0.0 };
            assert!(
                (y - expect).abs() < 1e-7,
                "order {} n {n}: {y} vs {expect}",
                d.order
            );
        }
        assert!(d.tap(0) != 0.0 && d.tap(d.order) != 0.0);
    }
}
use imu_emu::model::Product;
use imu_emu::sensor::{ErrorModel, MotionSource, Truth};
use imu_emu::time::Instant;

/// Table 5.29 rows: bandwidth Hz, order at 2 kHz, delay s.
const TABLE_5_29: [(f32, usize, f32); 5] = [
    (16.0, 192, 0.048),
    (33.0, 96, 0.024),
    (66.0, 48, 0.012),
    (131.0, 24, 0.006),
    (262.0, 12, 0.003),
];

fn magnitude(d: &FirDesign, f: f64) -> f64 {
    let fs = f64::from(d.rate_hz);
    let c = d.order as f64 / 2.0;
    (0..=d.order)
        .map(|n| f64::from(d.tap(n)) * (core::f64::consts::TAU * f * (n as f64 - c) / fs).cos())
        .sum::<f64>()
        .abs()
}

/// −3 dB frequency of the taps by bisection (the response falls monotonically
/// through the pass band).
fn minus_3db(d: &FirDesign) -> f64 {
    let (mut lo, mut hi) = (0.0, f64::from(d.bandwidth_hz) * 3.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if magnitude(d, mid) > core::f64::consts::FRAC_1_SQRT_2 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[test]
fn designs_follow_table_5_29_at_2khz_and_keep_delay_at_4khz() {
    for (code, &(bw, order, delay)) in TABLE_5_29.iter().enumerate() {
        let d = fir::design(lpf_bandwidth(code as u8), 2000).unwrap();
        assert_eq!((d.order, d.bandwidth_hz), (order, bw));
        assert!((d.delay_s() - delay).abs() < 1e-9, "code {code}");
        assert_eq!(d.delay_samples(), order / 2);
    }
    assert!(fir::design(Bandwidth::Off, 2000).is_none());
    // K201: codes 2..4 at 4 kHz, doubled order, same bandwidth and delay.
    for code in 2..=4u8 {
        let (bw, order, delay) = TABLE_5_29[code as usize];
        let d = fir::design(lpf_bandwidth(code), 4000).unwrap();
        assert_eq!((d.order, d.bandwidth_hz, d.rate_hz), (order * 2, bw, 4000));
        assert!((d.delay_s() - delay).abs() < 1e-9);
    }
    assert!(
        fir::design(Bandwidth::Hz16, 4000).is_none()
            && fir::design(Bandwidth::Hz33, 4000).is_none()
    );
}

#[test]
fn minus_3db_point_is_the_table_bandwidth() {
    for d in DESIGNS {
        let f3 = minus_3db(d);
        let bw = f64::from(d.bandwidth_hz);
        // f32 taps: within 0.1 % of the table value.
        assert!(
            (f3 - bw).abs() < 1e-3 * bw,
            "{} Hz design: −3 dB at {f3}",
            bw
        );
        // Fixed-point taps: within 0.5 %.
        let q: Vec<f32> = (0..=d.order).map(|n| d.tap_fixed(n)).collect();
        let fs = f64::from(d.rate_hz);
        let mag = |f: f64| {
            let c = d.order as f64 / 2.0;
            q.iter()
                .enumerate()
                .map(|(n, &h)| {
                    f64::from(h) * (core::f64::consts::TAU * f * (n as f64 - c) / fs).cos()
                })
                .sum::<f64>()
                .abs()
        };
        assert!(
            (mag(bw) - core::f64::consts::FRAC_1_SQRT_2).abs() < 5e-3,
            "Q15 {bw}"
        );
        // Pass band flat-ish, stop band deep: from 3.2× the bandwidth on,
        // ≥ 60 dB down (checked on a 0.25 Hz grid up to Nyquist).
        assert!(magnitude(d, bw * 0.25) > 0.95);
        let nyq = f64::from(d.rate_hz) / 2.0;
        let mut f = bw * 3.2;
        while f < nyq {
            assert!(magnitude(d, f) < 1e-3, "{bw}: {f} Hz: {}", magnitude(d, f));
            f += 0.25;
        }
    }
}

/// A sine at the bandwidth through the running filter comes out at −3 dB and
/// delayed by exactly N/2 samples (measured by quadrature demodulation).
#[test]
fn measured_sine_gain_and_delay_per_bandwidth() {
    for d in DESIGNS {
        let fs = f64::from(d.rate_hz);
        let mut bank = FirBank::new(Some(d), &[0.0; CHANNELS]);
        for f in [f64::from(d.bandwidth_hz) * 0.5, f64::from(d.bandwidth_hz)] {
            let w = core::f64::consts::TAU * f / fs;
            let (mut i_acc, mut q_acc, mut n) = (0.0, 0.0, 0.0);
            let total = 4 * d.order + (20.0 * fs / f) as usize;
            for k in 0..total {
                let x = (w * k as f64).sin() as f32;
                let y = bank.push(&[x; CHANNELS])[0];
                if k > 2 * d.order {
                    i_acc += f64::from(y) * (w * k as f64).sin();
                    q_acc += f64::from(y) * (w * k as f64).cos();
                    n += 1.0;
                }
            }
            let amp = 2.0 * (i_acc * i_acc + q_acc * q_acc).sqrt() / n;
            let phase = q_acc.atan2(i_acc); // y ∝ sin(wk + phase)
                                            // The phase is known modulo 2π: take the delay nearest N/2 (the
                                            // ambiguity, 2π/w ≥ 7 samples, still exposes any whole-sample error).
            let period = core::f64::consts::TAU / w;
            let raw = -phase / w;
            let m = ((d.order as f64 / 2.0 - raw) / period).round();
            let delay = raw + m * period;
            let expect = magnitude(d, f);
            assert!(
                (amp - expect).abs() < 0.01,
                "{f} Hz: gain {amp} vs {expect}"
            );
            assert!(
                (delay - d.order as f64 / 2.0).abs() < 0.05,
                "{f} Hz on order {}: delay {delay} samples",
                d.order
            );
        }
    }
}

/// A ramp comes out as the same ramp exactly N/2 samples late (a linear-phase
/// filter with unit DC gain delays a ramp without distortion).
#[test]
fn ramp_is_delayed_exactly_n_over_2() {
    for d in DESIGNS {
        let mut bank = FirBank::new(Some(d), &[0.0; CHANNELS]);
        let mut fixed = FirBankFixed::new(Some(d), &[0; CHANNELS]);
        for k in 0..(3 * d.order) {
            let x = k as f32 * 0.01;
            let y = bank.push(&[x; CHANNELS]);
            let yq = fixed.push(&[k as i32 * 1000; CHANNELS]);
            if k > d.order {
                let expect = (k - d.order / 2) as f32 * 0.01;
                assert!(
                    (y[4] - expect).abs() < 2e-4,
                    "order {} k {k}: {} vs {expect}",
                    d.order,
                    y[4]
                );
                // Fixed point: exact (integer ramp, unit DC gain, symmetric taps).
                assert_eq!(yq[7], (k - d.order / 2) as i32 * 1000, "order {}", d.order);
            }
        }
    }
}

/// A truth whose rate is a ramp in time.
struct RampRate {
    k: u64,
}

impl MotionSource for RampRate {
    fn next(&mut self, _now: Instant, _dt: f32) -> Truth {
        self.k += 1;
        Truth {
            rate_dps: [0.01 * self.k as f32, 0.0, 0.0],
            specific_force_g: [0.0, 0.0, 1.0],
            temperature_c: None,
        }
    }
}

/// Through the whole chain: the transmitted gyro is the truth N/2 ticks
/// earlier — no extra tick of latency anywhere.
#[test]
fn chain_delay_equals_table_5_29() {
    let product = Product::parse("K110").unwrap();
    for (code, &(_, order, _)) in TABLE_5_29.iter().enumerate() {
        let mut chain = SignalChain::new(product, 1);
        *chain.errors_mut() = ErrorModel::IDEAL;
        let mut cfg = ChainConfig::defaults(&product);
        cfg.lpf = lpf_bandwidth(code as u8);
        chain.configure(&cfg);
        let mut src = RampRate { k: 0 };
        for t in 1..=(2 * order as u64 + 10) {
            chain.tick_with(Instant::from_micros(500 * t), &mut src);
            let s = chain.output();
            if t > order as u64 + 1 {
                let expect = 0.01 * (t - order as u64 / 2) as f32;
                assert!(
                    (s.gyro[0] - expect).abs() < 1e-3 * expect.max(1.0),
                    "LPF {code}: tick {t}: {} vs {expect}",
                    s.gyro[0]
                );
            }
        }
    }
    // Off: no delay at all.
    let mut chain = SignalChain::new(product, 1);
    *chain.errors_mut() = ErrorModel::IDEAL;
    let mut cfg = ChainConfig::defaults(&product);
    cfg.lpf = Bandwidth::Off;
    chain.configure(&cfg);
    let mut src = RampRate { k: 0 };
    for t in 1..50u64 {
        chain.tick_with(Instant::from_micros(500 * t), &mut src);
        assert!((chain.output().gyro[0] - 0.01 * t as f32).abs() < 1e-5);
    }
}

/// Fixed-point vs float: |y_fixed − y_float| ≤ E·max|x| + 2 LSB (+ the f32
/// rounding of the float path), E = Σ|h − q/2¹⁵| ([`FirDesign::fixed_error_gain`]).
#[test]
fn fixed_point_matches_float_within_the_stated_bound() {
    let mut seed = 0x1234_5678u32;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        (seed as f32 / u32::MAX as f32) * 2.0 - 1.0
    };
    // Full-scale inputs: 2000 °/s gyro, 40 g acc, 90 g aux.
    let fs_in = [2000.0, 2000.0, 2000.0, 40.0, 40.0, 40.0, 90.0, 90.0, 90.0];
    for d in DESIGNS {
        let mut float = FirBank::new(Some(d), &[0.0; CHANNELS]);
        let mut fixed = FirBankFixed::new(Some(d), &[0; CHANNELS]);
        let e = d.fixed_error_gain();
        let mut worst = [0.0f32; CHANNELS];
        for k in 0..3000 {
            let mut x = [0.0f32; CHANNELS];
            let mut xq = [0i32; CHANNELS];
            for c in 0..CHANNELS {
                // Half the time a smooth sine, half white: both extremes.
                let v = if c % 2 == 0 {
                    (k as f32 * 0.05 + c as f32).sin()
                } else {
                    rnd()
                };
                x[c] = v * fs_in[c];
                xq[c] = (x[c] * FIXED_SCALE[c]).round() as i32;
                x[c] = xq[c] as f32 / FIXED_SCALE[c]; // same input for both
            }
            let y = float.push(&x);
            let yq = fixed.push(&xq);
            for c in 0..CHANNELS {
                let diff = (yq[c] as f32 / FIXED_SCALE[c] - y[c]).abs();
                let bound = e * fs_in[c] + 2.0 / FIXED_SCALE[c] + 1e-5 * fs_in[c];
                assert!(diff <= bound, "order {} ch {c}: {diff} > {bound}", d.order);
                worst[c] = worst[c].max(diff / fs_in[c]);
            }
        }
        // In practice far inside the bound: under 5e-4 of full scale even for
        // full-scale white input (Q15 taps: ≈ 1e-4 RMS).
        assert!(
            worst.iter().all(|&w| w < 5e-4),
            "order {}: {worst:?} (E = {e})",
            d.order
        );
        println!(
            "order {}: E = {e:.2e}, worst |Δ|/FS = {:.2e}",
            d.order,
            worst.iter().fold(0.0f32, |a, &b| a.max(b))
        );
    }
}
