//! Cascade filter of ICD 5.8: the discretised sections against the analog
//! transfer functions, and the running filter against its own response.
//!
//! Tolerances (bilinear transform pre-warped at ω, f_s = 2 kHz):
//! - exactly (1e-6) at DC and at each section's ω;
//! - exactly (1e-5 relative) the analog response at the warped frequency
//!   `K·tan(πf/f_s)` at every f (the identity the bilinear map guarantees);
//! - against the analog response at the same frequency: within 0.2 dB and
//!   1.5° for f ≤ f_s/10 = 200 Hz (the frequency warping there is < 3 %).

use imu_emu::dsp::cascade::{Cascade, CascadeConfig, SecondOrder, Section};
use imu_emu::dsp::fir::CHANNELS;

type C = (f64, f64);

fn cmul(a: C, b: C) -> C {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}
fn cdiv(a: C, b: C) -> C {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}
fn mag_db(a: C) -> f64 {
    20.0 * (a.0 * a.0 + a.1 * a.1).sqrt().log10()
}
fn phase_deg(a: C) -> f64 {
    a.1.atan2(a.0).to_degrees()
}

/// Analog Filter1/2 at angular frequency `w` (rad/s).
fn analog_second(p: &SecondOrder, w: f64) -> C {
    let s = (0.0, w);
    let wn = f64::from(p.omega);
    let s2 = cmul(s, s);
    let num = (s2.0 + wn * wn, s2.1 + 2.0 * f64::from(p.zeta_num) * wn * w);
    let den = (s2.0 + wn * wn, s2.1 + 2.0 * f64::from(p.zeta_den) * wn * w);
    cdiv(num, den)
}

/// Analog Filter3.
fn analog_first(tau: f64, w: f64) -> C {
    cdiv((1.0, 0.0), (1.0, tau * w))
}

/// The analog cascade of `cfg` at `w`.
fn analog(cfg: &CascadeConfig, w: f64) -> C {
    let mut h = (1.0, 0.0);
    if cfg.mask & 1 != 0 {
        let f = analog_second(&cfg.filt1, w);
        h = cmul(h, cmul(f, f));
    }
    if cfg.mask & 2 != 0 {
        let f = analog_second(&cfg.filt2, w);
        h = cmul(h, cmul(f, f));
    }
    if cfg.mask & 4 != 0 {
        h = cmul(h, analog_first(f64::from(cfg.tau), w));
    }
    h
}

const FS: f64 = 2000.0;
/// Stated tolerance of the discretisation (module doc): up to 50 Hz, up to
/// 200 Hz (= f_s/10).
const TOL_DB: [f64; 2] = [0.1, 0.5];
const TOL_DEG: [f64; 2] = [1.0, 4.0];

fn configs() -> Vec<CascadeConfig> {
    let d = CascadeConfig::default();
    vec![
        CascadeConfig { mask: 0x07, ..d },
        CascadeConfig { mask: 0x01, ..d },
        CascadeConfig { mask: 0x02, ..d },
        CascadeConfig { mask: 0x04, ..d },
        // A notch (ζ1 = 0) at 50 Hz and a resonance (ζ1 > ζ2) at 20 Hz.
        CascadeConfig {
            mask: 0x03,
            filt1: SecondOrder {
                zeta_num: 0.0,
                zeta_den: 0.5,
                omega: 314.159_27,
            },
            filt2: SecondOrder {
                zeta_num: 0.9,
                zeta_den: 0.2,
                omega: 125.663_7,
            },
            tau: 0.005,
        },
        CascadeConfig {
            mask: 0x04,
            tau: 0.002,
            ..d
        },
    ]
}

#[test]
fn exact_at_dc_and_at_each_omega() {
    for cfg in configs() {
        let c = Cascade::new(&cfg, 2000, &[0.0; CHANNELS]);
        let dc = c.response(0.0, FS);
        assert!((dc.0 - 1.0).abs() < 1e-6 && dc.1.abs() < 1e-6, "{cfg:?}");
        for (bit, p) in [(1u8, cfg.filt1), (2, cfg.filt2)] {
            if cfg.mask & bit == 0 {
                continue;
            }
            let s = Section::second_order(&p, FS as f32);
            let f = f64::from(p.omega) / core::f64::consts::TAU;
            let d = s.response(f, FS);
            let a = analog_second(&p, f64::from(p.omega));
            let scale = a.0.hypot(a.1).max(1.0);
            assert!(
                (d.0 - a.0).hypot(d.1 - a.1) < 5e-5 * scale,
                "{p:?}: {d:?} vs {a:?}"
            );
        }
        if cfg.mask & 4 != 0 {
            let s = Section::first_order(cfg.tau, FS as f32);
            let w = 1.0 / f64::from(cfg.tau);
            let d = s.response(w / core::f64::consts::TAU, FS);
            let a = analog_first(f64::from(cfg.tau), w);
            assert!((d.0 - a.0).abs() < 1e-5 && (d.1 - a.1).abs() < 1e-5);
        }
    }
}

#[test]
fn equals_the_analog_response_at_the_warped_frequency() {
    for cfg in configs() {
        for (bit, p) in [(1u8, cfg.filt1), (2, cfg.filt2)] {
            if cfg.mask & bit == 0 {
                continue;
            }
            let s = Section::second_order(&p, FS as f32);
            let wn = f64::from(p.omega);
            let k = wn / (wn / (2.0 * FS)).tan();
            for f in [1.0, 7.0, 20.0, 50.0, 120.0, 300.0, 600.0, 900.0] {
                let d = s.response(f, FS);
                let a = analog_second(&p, k * (core::f64::consts::PI * f / FS).tan());
                let err = ((d.0 - a.0).powi(2) + (d.1 - a.1).powi(2)).sqrt();
                assert!(
                    err < 5e-5 * (a.0.hypot(a.1)).max(1.0),
                    "{p:?} at {f} Hz: {err}"
                );
            }
        }
    }
}

#[test]
fn close_to_the_analog_response_up_to_a_tenth_of_the_rate() {
    let mut worst = [(0.0f64, 0.0f64); 2];
    for cfg in configs() {
        let c = Cascade::new(&cfg, 2000, &[0.0; CHANNELS]);
        for f in [1.0, 5.0, 10.0, 20.0, 35.0, 50.0, 80.0, 100.0, 150.0, 200.0] {
            let d = c.response(f, FS);
            let a = analog(&cfg, core::f64::consts::TAU * f);
            // Skip the depth of an exact notch, where dB is unbounded.
            if a.0.hypot(a.1) < 1e-3 {
                continue;
            }
            let dm = mag_db(d) - mag_db(a);
            let mut dp = phase_deg(d) - phase_deg(a);
            if dp > 180.0 {
                dp -= 360.0;
            }
            if dp < -180.0 {
                dp += 360.0;
            }
            let band = usize::from(f > 50.0);
            worst[band].0 = f64::max(worst[band].0, dm.abs());
            worst[band].1 = f64::max(worst[band].1, dp.abs());
            assert!(dm.abs() < TOL_DB[band], "{cfg:?} at {f} Hz: {dm} dB");
            assert!(dp.abs() < TOL_DEG[band], "{cfg:?} at {f} Hz: {dp}°");
        }
    }
    println!(
        "worst ≤ 50 Hz: {:.3} dB, {:.3}°; ≤ 200 Hz: {:.3} dB, {:.3}°",
        worst[0].0, worst[0].1, worst[1].0, worst[1].1
    );
}

/// The running filter (time domain) has the response its coefficients say:
/// a sine in, amplitude and phase out by quadrature demodulation.
#[test]
fn running_filter_matches_its_response_magnitude_and_phase() {
    for cfg in configs() {
        for f in [3.0, 25.0, 50.0, 140.0] {
            let mut c = Cascade::new(&cfg, 2000, &[0.0; CHANNELS]);
            let w = core::f64::consts::TAU * f / FS;
            let (mut i_acc, mut q_acc, mut n) = (0.0, 0.0, 0.0);
            let settle = 8000;
            let total = settle + (40.0 * FS / f) as usize;
            for k in 0..total {
                let mut x = [(w * k as f64).sin() as f32; CHANNELS];
                c.process(&mut x);
                if k >= settle {
                    i_acc += f64::from(x[2]) * (w * k as f64).sin();
                    q_acc += f64::from(x[2]) * (w * k as f64).cos();
                    n += 1.0;
                }
            }
            let measured = (2.0 * i_acc / n, 2.0 * q_acc / n); // re, im of the gain
            let expect = c.response(f, FS);
            let err = (measured.0 - expect.0).hypot(measured.1 - expect.1);
            assert!(
                err < 2e-3 + 2e-3 * expect.0.hypot(expect.1),
                "{cfg:?} {f} Hz: {measured:?} vs {expect:?}"
            );
        }
    }
}

#[test]
fn steady_state_reset_has_no_transient() {
    let cfg = CascadeConfig {
        mask: 0x07,
        ..CascadeConfig::default()
    };
    let x0 = [1.0, -2.0, 3.0, 0.0, 0.0, 1.0, 0.5, 0.5, 90.0];
    let mut c = Cascade::new(&cfg, 2000, &x0);
    for _ in 0..100 {
        let mut x = x0;
        c.process(&mut x);
        for ch in 0..CHANNELS {
            assert!((x[ch] - x0[ch]).abs() < 1e-4 * x0[ch].abs().max(1.0));
        }
    }
}

/// Fixed-point cascade (the `fixed-point` build) and float cascade against an
/// f64 evaluation of the same sections, on 600 °/s-scale inputs: both within
/// 5e-5 of the output's peak (+ 4 LSB for the fixed one). f32 rounding in a
/// lightly damped section (ζ2 = 0.2) is what the bound has to cover; the
/// fixed path (64-bit products, 4 guard bits) is the more accurate of the two.
/// A constant comes out exactly.
#[test]
fn fixed_point_cascade_matches_float() {
    use imu_emu::dsp::cascade::CascadeFixed;
    let scale = 131_072.0f32; // the gyro's fixed-point scale (2¹⁷ per °/s)
    let full = 2000.0f32;
    for cfg in configs() {
        let x0 = [0i32; CHANNELS];
        let mut f = Cascade::new(&cfg, 2000, &[0.0; CHANNELS]);
        let mut q = CascadeFixed::new(&cfg, 2000, &x0);
        let mut worst = 0.0f32;
        let mut worst_f = 0.0f64;
        let mut worst_q = 0.0f64;
        let mut peak = 0.0f64;
        // f64 reference of the same sections (the float path's coefficients).
        let secs: Vec<Section> = f.sections().to_vec();
        let mut st = vec![[[0.0f64; 4]; CHANNELS]; secs.len()];
        let mut seed = 99u32;
        for k in 0..6000 {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            let noise = (seed as f32 / u32::MAX as f32) - 0.5;
            let mut xq = [0i32; CHANNELS];
            let mut xf = [0.0f32; CHANNELS];
            for c in 0..CHANNELS {
                let v =
                    0.3 * full * ((k as f32) * 0.01 * (c + 1) as f32).sin() + 0.1 * full * noise;
                xq[c] = (v * scale).round() as i32;
                xf[c] = xq[c] as f32 / scale;
            }
            let mut xr: Vec<f64> = xf.iter().map(|&v| f64::from(v)).collect();
            for (s, st) in secs.iter().zip(st.iter_mut()) {
                for c in 0..CHANNELS {
                    let u = xr[c];
                    let v = &mut st[c];
                    let d = if s.first_order { u - v[0] } else { u - v[1] };
                    let w = f64::from(s.g) * d - f64::from(s.a1) * v[2] - f64::from(s.a2) * v[3];
                    *v = [u, v[0], w, v[2]];
                    xr[c] = u + w;
                }
            }
            f.process(&mut xf);
            q.process(&mut xq);
            for c in 0..CHANNELS {
                worst = worst.max((xq[c] as f32 / scale - xf[c]).abs());
                worst_f = worst_f.max((f64::from(xf[c]) - xr[c]).abs());
                worst_q = worst_q.max((f64::from(xq[c]) / f64::from(scale) - xr[c]).abs());
                peak = peak.max(xr[c].abs());
            }
        }
        println!("mask {}: float−fixed {worst:.2e}, float−f64 {worst_f:.2e}, fixed−f64 {worst_q:.2e} °/s, peak {peak:.0}", cfg.mask);
        assert!(worst_f < 5e-5 * peak, "{cfg:?}: float {worst_f}");
        assert!(
            worst_q < 5e-5 * peak + 4.0 / f64::from(scale),
            "{cfg:?}: fixed {worst_q}"
        );
        // Constant input: exactly itself after the transient.
        let c0 = [123_456_789i32; CHANNELS];
        let mut q = CascadeFixed::new(&cfg, 2000, &c0);
        for _ in 0..100 {
            let mut x = c0;
            q.process(&mut x);
            assert_eq!(x, c0);
        }
    }
}
