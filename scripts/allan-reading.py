#!/usr/bin/env python3
"""How the datasheet reading of bias instability (the Allan minimum /
0.6643 over tau <= T/100, docs/sensors.md "The datasheet reading")
scatters over runs of a given length, for the emulator's noise model:
white noise of density N plus the flicker of src/sensor/errors.rs (six
Gauss-Markov terms with corners 1 ... 1e5 s, each of variance
B^2 ln10/pi), sampled at 10 Hz (the Allan deviation at tau >= 1 s is that
of any output rate), the overlapping estimator on the tau grid of
`imu-emu allan` (phases kept every S-th sample, at most 2^20; ten tau a
decade). Needs numpy and scipy (not project dependencies).

Usage: scripts/allan-reading.py CASE HOURS RUNS
CASE: kernel-mid-gyro, kernel-mid-acc, imx5-acc, aux
Prints the reading / B (mean, sd, min, max) for tau <= T/M, M = 30 ... 1000.
"""
import sys

import numpy as np
from scipy.signal import lfilter

FLOOR = 0.664282
G = 9.8106
CASES = {  # (N unit/sqrt(Hz), B unit), the built-in profiles' figures
    "kernel-mid-gyro": (0.2 / 60, 2 / 3600),
    "kernel-mid-acc": (0.03 / 60 / G, 7e-6),
    "imx5-acc": (0.02 / 60 / G, 19e-6),
    "aux": (0.3 / 60 / G, 200e-6),
}


def curve(n_density, b, hours, seed, fs=10.0):
    rng = np.random.default_rng(seed)
    n = int(hours * 3600 * fs)
    dt = 1 / fs
    y = rng.standard_normal(n) * n_density * np.sqrt(fs)
    q = b * np.sqrt(np.log(10) / np.pi)
    for k in range(6):
        a = np.exp(-dt / 10.0**k)
        x0 = rng.standard_normal() * q
        u = rng.standard_normal(n) * q * np.sqrt(1 - a * a)
        x, _ = lfilter([1], [1, -a], u, zi=[a * x0])
        y += x
    phase = np.concatenate([[0], np.cumsum(y) * dt])
    s = max(1, -(-n // (1 << 20)))
    xk = phase[::s]
    max_k = (len(xk) - 1) // 4
    ks, e = [], 0
    while 10 ** (e / 10) <= max_k:
        k = int(round(10 ** (e / 10)))
        if not ks or ks[-1] != k:
            ks.append(k)
        e += 1
    out = []
    for k in ks:
        d = xk[2 * k:] - 2 * xk[k:-k] + xk[:-2 * k]
        tau = k * s * dt
        out.append((tau, np.sqrt(np.mean(d * d) / (2 * tau * tau))))
    return np.array(out), n * dt


def main():
    case, hours, runs = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    n_density, b = CASES[case]
    res = {m: [] for m in (30, 100, 200, 300, 1000)}
    for seed in range(runs):
        c, t = curve(n_density, b, hours, seed)
        for m in res:
            res[m].append(c[c[:, 0] <= t / m][:, 1].min() / FLOOR / b)
    for m, v in res.items():
        v = np.array(v)
        print(f"{case} {hours:g} h, tau <= T/{m}: mean {v.mean():.3f} sd {v.std():.3f} "
              f"min {v.min():.3f} max {v.max():.3f}")


if __name__ == "__main__":
    main()
