//! The chain's cumulative integrals (`imu_emu::dsp::integrals`): windows
//! taken by differences of two snapshots give the coning-corrected Δθ and
//! the rotation/sculling-corrected Δv, checked against the analytic truth of
//! a constant rotation and of classical coning, wherever the window lies.
//! Ideal sensors; the motion sources give each tick's mean rate (the exact
//! angle increment of the tick divided by its length).

// Axis loops index several vectors at once.
#![allow(clippy::needless_range_loop)]

use imu_emu::chain::{ChainConfig, SignalChain};
use imu_emu::dsp::integrals::{window, Increment, Integrals};
use imu_emu::math::G;
use imu_emu::model::Product;
use imu_emu::sensor::{ErrorModel, MotionSource, Truth};
use imu_emu::time::Instant;

const DEG: f64 = core::f64::consts::PI / 180.0;
const DT: f64 = 5e-4;

type V = [f64; 3];

fn cross(a: &V, b: &V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: &V) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn dist(a: &V, b: &V) -> f64 {
    norm(&[a[0] - b[0], a[1] - b[1], a[2] - b[2]])
}

/// A K110 with ideal sensors that keeps the integrals.
fn chain() -> SignalChain<Integrals> {
    let p = Product::parse("K110").unwrap();
    let mut c = SignalChain::<Integrals>::powered_on(p, 1);
    *c.errors_mut() = ErrorModel::IDEAL;
    c.faults_mut().temperature_c = Some(25.0);
    c.configure(&ChainConfig::defaults(&p));
    c
}

/// Runs `source` from tick 1 and takes the windows (start, length) in
/// ticks, in order and not overlapping.
fn windows(source: &mut dyn MotionSource, spans: &[(u64, u64)]) -> Vec<Increment> {
    let mut c = chain();
    assert_eq!(c.integrals(), Integrals::default());
    let mut k = 0u64;
    let mut out = Vec::new();
    for &(start, len) in spans {
        while k < start {
            k += 1;
            c.tick_with(Instant::from_micros(500 * k), source);
        }
        let a = c.integrals();
        while k < start + len {
            k += 1;
            c.tick_with(Instant::from_micros(500 * k), source);
        }
        let b = c.integrals();
        assert_eq!(b.samples, k);
        out.push(window(&a, &b, c.config().internal_rate_hz));
    }
    out
}

struct Constant {
    rate_dps: [f32; 3],
    force_g: [f32; 3],
}

impl MotionSource for Constant {
    fn next(&mut self, _now: Instant, _dt: f32) -> Truth {
        Truth {
            rate_dps: self.rate_dps,
            specific_force_g: self.force_g,
            temperature_c: None,
        }
    }
}

/// A constant rotation about a fixed axis: Δθ = ω T with no coning term,
/// Δv = ∫ exp([ω×] t) f dt (the start frame), which the second-order
/// formula meets within its third-order term T³|ω|²|f|/6.
#[test]
fn constant_rotation_matches_the_analytic_increments() {
    let rate = [10.0f32, -20.0, 30.0];
    let force = [0.1f32, -0.2, 1.0];
    let mut src = Constant {
        rate_dps: rate,
        force_g: force,
    };
    let spans = [(0, 200), (5_000, 200), (50_000, 400)];
    let incs = windows(&mut src, &spans);
    let w: V = rate.map(|r| f64::from(r) * DEG);
    let f: V = force.map(|a| f64::from(a) * f64::from(G));
    let wn = norm(&w);
    for (inc, &(_, n)) in incs.iter().zip(&spans) {
        let t = n as f64 * DT;
        assert_eq!(inc.samples, n);
        // Δθ: exact up to f64 rounding (the rates are on the 2⁻¹⁹ °/s grid).
        for i in 0..3 {
            assert!(
                (inc.dtheta_rad[i] - w[i] * t).abs() < 1e-12,
                "{n}: {:?}",
                inc.dtheta_rad
            );
            assert_eq!(inc.dtheta_rad[i], inc.dtheta_raw_rad[i], "no coning term");
        }
        // Δv: the closed form.
        let wf = cross(&w, &f);
        let wwf = cross(&w, &wf);
        let th = wn * t;
        let c1 = (1.0 - th.cos()) / (wn * wn);
        let c2 = (th - th.sin()) / (wn * wn * wn);
        let truth: V = core::array::from_fn(|i| t * f[i] + c1 * wf[i] + c2 * wwf[i]);
        let second: V = core::array::from_fn(|i| t * f[i] + 0.5 * t * t * wf[i]);
        let bound = t.powi(3) * wn * wn * norm(&f) / 6.0;
        let err = dist(&inc.dv_mps, &truth);
        let raw_err = dist(&inc.dv_raw_mps, &truth);
        println!(
            "T = {t} s: Δv error {err:.3e} m/s (bound {bound:.3e}), uncorrected {raw_err:.3e}"
        );
        // The formula itself, to the quantisation of the force (6e-8 g).
        assert!(
            dist(&inc.dv_mps, &second) < 1e-9 * t.max(1.0) + 1e-6 * t,
            "{n}"
        );
        assert!(err <= bound, "{n}: {err} > {bound}");
        assert!(raw_err > 10.0 * err, "{n}: {raw_err} vs {err}");
    }
    // The same window length at 0 and at tick 5000: the same uncorrected
    // bits, the corrections within the cross terms' rounding.
    assert_eq!(incs[0].dtheta_rad, incs[1].dtheta_rad);
    assert_eq!(incs[0].dv_raw_mps, incs[1].dv_raw_mps);
    let d = dist(&incs[0].dv_mps, &incs[1].dv_mps);
    assert!(d < 1e-11, "{d}");
}

/// Classical coning: attitude q(t) = [cos β/2, sin β/2 cos Ωt, sin β/2 sin
/// Ωt, 0], body rate Ω(−sin β sin Ωt, sin β cos Ωt, −(1 − cos β)).
struct Coning {
    beta: f64,
    omega: f64,
    k: u64,
}

impl Coning {
    fn quat(&self, t: f64) -> [f64; 4] {
        let (s, c) = ((0.5 * self.beta).sin(), (0.5 * self.beta).cos());
        [
            c,
            s * (self.omega * t).cos(),
            s * (self.omega * t).sin(),
            0.0,
        ]
    }
}

impl MotionSource for Coning {
    fn next(&mut self, _now: Instant, _dt: f32) -> Truth {
        self.k += 1;
        let (p0, p1) = (
            self.omega * (self.k - 1) as f64 * DT,
            self.omega * self.k as f64 * DT,
        );
        let sb = self.beta.sin();
        // The tick's exact angle increment / DT, °/s.
        let inc = [
            sb * (p1.cos() - p0.cos()),
            sb * (p1.sin() - p0.sin()),
            -(1.0 - self.beta.cos()) * self.omega * DT,
        ];
        Truth {
            rate_dps: inc.map(|x| (x / DT / DEG) as f32),
            specific_force_g: [0.0; 3],
            temperature_c: None,
        }
    }
}

fn qmul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The rotation vector of a unit quaternion.
fn rotation_vector(q: &[f64; 4]) -> V {
    let s = if q[0] < 0.0 { -1.0 } else { 1.0 };
    let v = [s * q[1], s * q[2], s * q[3]];
    let n = norm(&v);
    let angle = 2.0 * n.atan2(s * q[0]);
    v.map(|x| x * angle / n)
}

/// The coning-corrected Δθ meets the true rotation of each window (the
/// rotation vector of q(t_a)* ⊗ q(t_b)) within the third-order term the
/// formula leaves out (Bortz: ∫ α × (α × ω)/12 ≤ L³/12 for the window's
/// angle path length L = |ω| T), far closer than Σ ω dt. Windows of up to
/// a tenth of the cone period, at their start and an hour-scale offset
/// apart (one cone period apart: the same true rotation).
#[test]
fn coning_matches_the_true_rotation_of_each_window() {
    let mut src = Coning {
        beta: 5.0 * DEG,
        omega: 2.0 * core::f64::consts::TAU,
        k: 0,
    };
    let spans = [(0, 100), (1_000, 100), (3_000, 50), (20_000, 200)];
    let truth_src = Coning { k: 0, ..src };
    // |ω| = Ω · 2 sin(β/2).
    let src_rate = src.omega * 2.0 * (0.5 * src.beta).sin();
    let incs = windows(&mut src, &spans);
    for (inc, &(a, n)) in incs.iter().zip(&spans) {
        let qa = truth_src.quat(a as f64 * DT);
        let qb = truth_src.quat((a + n) as f64 * DT);
        let qa_conj = [qa[0], -qa[1], -qa[2], -qa[3]];
        let truth = rotation_vector(&qmul(&qa_conj, &qb));
        let err = dist(&inc.dtheta_rad, &truth);
        let raw_err = dist(&inc.dtheta_raw_rad, &truth);
        let path = src_rate * n as f64 * DT;
        let bound = path.powi(3) / 12.0;
        println!(
            "window {a}+{n}: Δθ error {err:.3e} rad (bound {bound:.3e}), uncorrected {raw_err:.3e}"
        );
        assert!(err <= bound, "{a}+{n}: {err} > {bound}");
        assert!(raw_err > 10.0 * err, "{a}+{n}: {raw_err} vs {err}");
    }
}

/// Without integrals (the KERNEL's chain) the integrals take no room; with
/// them, a chain is the same chain otherwise: the same outputs, tick for
/// tick.
#[test]
fn integrals_change_nothing_else() {
    assert_eq!(
        core::mem::size_of::<SignalChain>() + core::mem::size_of::<Integrals>(),
        core::mem::size_of::<SignalChain<Integrals>>()
    );
    let p = Product::parse("K120").unwrap();
    let mut a = SignalChain::new(p, 3);
    let mut b = SignalChain::<Integrals>::powered_on(p, 3);
    let coning = imu_emu::sensor::Motion::Coning {
        lat_deg: 10.0,
        heading_deg: 30.0,
        half_angle_deg: 5.0,
        freq_hz: 2.0,
    };
    a.set_motion(coning);
    b.set_motion(coning);
    for k in 1..=2000u64 {
        a.tick(Instant::from_micros(500 * k));
        b.tick(Instant::from_micros(500 * k));
        if k % 20 == 0 {
            assert_eq!(a.output(), b.output(), "tick {k}");
        }
    }
    assert_eq!(b.integrals().samples, 2000);
}
