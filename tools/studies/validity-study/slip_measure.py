#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Offline check of two zero-slip measures on a sim CSV (per 1 s window):
  rms:   rms|di/dt| / rms|i| in the rotor frame (what the estimator uses now; noise
         enters squared, so it has a noise floor),
  cross: mean rotation rate of the rotor-frame current, sum(i x di/dt) / sum|i|^2
         (noise enters linearly and averages out; equals the slip frequency in
         steady state).
Front end as the estimator's: power-invariant 3-2, rotation by n_p*theta,
Butterworth-3 at 100 Hz (bilinear, prewarped), central differences.
usage: slip_measure.py FILE.csv POLE_PAIRS  -> prints window, rms*T_R_true, |cross|*T_R_true"""
import math
import sys

import numpy as np


def butter3(fc, fs):
    # bilinear transform of 1/(s^3 + 2 s^2 + 2 s + 1) with prewarping
    k = 1.0 / math.tan(math.pi * fc / fs)
    a = np.array([k**3 + 2 * k**2 + 2 * k + 1, -3 * k**3 - 2 * k**2 + 2 * k + 3,
                  3 * k**3 - 2 * k**2 - 2 * k + 3, -k**3 + 2 * k**2 - 2 * k + 1])
    b = np.array([1.0, 3.0, 3.0, 1.0]) / a[0]
    return b, a / a[0]


def lfilter(b, a, x):
    y = np.zeros_like(x)
    s1 = s2 = s3 = 0.0
    for n, xn in enumerate(x):  # transposed DF-II
        yn = b[0] * xn + s1
        s1 = b[1] * xn - a[1] * yn + s2
        s2 = b[2] * xn - a[2] * yn + s3
        s3 = b[3] * xn - a[3] * yn
        y[n] = yn
    return y


def main():
    path, npp = sys.argv[1], int(sys.argv[2])
    with open(path) as f:
        hdr = f.readline().strip().split(",")
    col = {h: j for j, h in enumerate(hdr)}
    use = [col[c] for c in ("t", "i_a", "i_b", "i_c", "theta", "T_R_true_s")]
    d = np.loadtxt(path, delimiter=",", skiprows=1, usecols=use)
    t, ia, ib, ic, th, trt = d.T
    fs = 1.0 / (t[1] - t[0])
    ial = math.sqrt(2 / 3) * (ia - 0.5 * ib - 0.5 * ic)
    ibe = math.sqrt(2 / 3) * (math.sqrt(3) / 2) * (ib - ic)
    ph = npp * th
    ix = np.cos(ph) * ial + np.sin(ph) * ibe
    iy = -np.sin(ph) * ial + np.cos(ph) * ibe
    b, a = butter3(100.0, fs)
    fx, fy = lfilter(b, a, ix), lfilter(b, a, iy)
    dx = (fx[2:] - fx[:-2]) * fs / 2
    dy = (fy[2:] - fy[:-2]) * fs / 2
    x, y, tr = fx[1:-1], fy[1:-1], trt[1:-1]
    n = int(round(fs))
    for k in range(len(x) // n):
        s = slice(k * n, (k + 1) * n)
        if k == 0:
            s = slice(int(0.2 * fs), n)  # skip the filter start
        i2 = np.sum(x[s] ** 2 + y[s] ** 2)
        rms = math.sqrt(np.sum(dx[s] ** 2 + dy[s] ** 2) / i2)
        cross = np.sum(x[s] * dy[s] - y[s] * dx[s]) / i2
        trm = float(np.mean(tr[s]))
        print("%d %.4f %.4f" % (k, rms * trm, abs(cross) * trm))


if __name__ == "__main__":
    main()
