"""What a BROAD trial's residual is made of (issue 42), by a direct least squares outside the pipeline:
the trial's rate samples integrated (trapezoid, as `gyrocal import` does, or as interval averages), cut
into windows of ``--window-s`` each with its own anchor attitude and bias, and one 3x3 gyro response
(scale factors and misalignments) and optionally a latency fitted to the reference attitude, sampled
every ``--every-s``. Prints the residual RMS per body axis after each step, so that each effect's share
of the misfit is a number, not a guess.

    python studies/broad_decompose.py ../shared/data/broad/01_undisturbed_slow_rotation_A.mat [--window-s 10]
"""

import argparse
import itertools

import numpy as np
from scipy.io import loadmat
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from gyrocal.model.kinematics import propagate
from gyrocal.model.units import ARCSEC_RAD


def load(path):
    m = loadmat(path)
    rate = np.asarray(m["imu_gyr"], float)
    q = np.asarray(m["opt_quat"], float)
    fs = float(np.squeeze(m["sampling_rate"]))
    return rate, q, fs, np.asarray(m["imu_acc"], float)


def increments(rate, dt, rule):
    """(N-1, 3) increments over each sample interval: the trapezoid of instantaneous rates, or each
    sample as the average over the interval it closes (``average``: a rate sensor's decimation filter)."""
    if rule == "trapezoid":
        return 0.5 * (rate[1:] + rate[:-1]) * dt
    return rate[1:] * dt


def model(params, inc, edges, query, dt, n_win, with_latency, acc_int=None):
    """Residual rotation vectors (body, rad) of the reference against the corrected gyro in each window."""
    M = np.eye(3) + params[:9].reshape(3, 3)
    tau = params[9] if with_latency else 0.0
    k = 10
    biases = params[k:k + 3 * n_win].reshape(n_win, 3)
    anchors = params[k + 3 * n_win:k + 6 * n_win].reshape(n_win, 3)
    g = params[k + 6 * n_win:k + 6 * n_win + 9].reshape(3, 3) if acc_int is not None else None
    out = []
    for w, (a, b) in enumerate(edges):
        d = inc[a:b] @ M.T - biases[w] * dt
        if g is not None:
            d = d - acc_int[a:b] @ g.T
        att = propagate(Rotation.from_rotvec(anchors[w]) * REF[a], d)
        # the gyro's sample j closes at row a+j+1; the reference late by tau: compare R_gyro(t - tau)
        rows = query[(query >= a) & (query <= b)]
        pos = np.clip(rows - a - tau / dt, 0, b - a - 1e-9)
        i = np.floor(pos).astype(int)
        frac = pos - i
        ai = att[i]
        step = Rotation.from_rotvec(frac[:, None] * np.vstack([d, np.zeros((1, 3))])[i])
        out.append(((ai * step).inv() * REF[rows]).as_rotvec())
    return np.concatenate(out)


REF = None


def main():
    global REF
    p = argparse.ArgumentParser()
    p.add_argument("mat")
    p.add_argument("--window-s", type=float, nargs="+", default=[199.0, 20.0, 10.0])
    p.add_argument("--every-s", type=float, default=0.05)
    p.add_argument("--rule", default="trapezoid", choices=["trapezoid", "average"])
    p.add_argument("--gsens", action="store_true")
    a = p.parse_args()
    rate, q, fs, acc = load(a.mat)
    dt = 1.0 / fs
    ok = np.all(np.isfinite(q), axis=1)
    qf = q.copy()
    qf[~ok] = [1, 0, 0, 0]
    REF = Rotation.from_quat(qf[:, [1, 2, 3, 0]])
    # mounting: the reference's frame to the IMU's, from the whole trial (Wahba on the increments' sum)
    inc = increments(rate, dt, a.rule)
    acc_int = 0.5 * (acc[1:] + acc[:-1]) * dt
    n = len(rate)
    every = max(1, round(a.every_s * fs))
    for window in a.window_s:
        n_win = max(1, round(n * dt / window))
        cut = np.linspace(0, n - 1, n_win + 1).round().astype(int)
        edges = list(itertools.pairwise(cut))
        query = np.arange(0, n, every)
        query = query[ok[query]]
        for with_latency in (False, True):
            x0 = np.zeros(10 + 6 * n_win + (9 if a.gsens else 0))
            def f(x, edges=edges, query=query, n_win=n_win, with_latency=with_latency):
                return model(x, inc, edges, query, dt, n_win, with_latency, acc_int if a.gsens else None).ravel()
            if not with_latency:
                x0[9] = 0.0
            fit = least_squares(f, x0, x_scale=np.r_[np.full(9, 1e-3), 1e-3, np.full(6 * n_win, 1e-3),
                                                   np.full(9 if a.gsens else 0, 1e-4)], method="trf", max_nfev=60)
            r = fit.fun.reshape(-1, 3) / ARCSEC_RAD
            M = fit.x[:9].reshape(3, 3)
            print(f"{a.mat.split('/')[-1][:30]} {a.rule}"
                  f" window {window:5.0f} s ({n_win}) latency "
                  f"{'%+.2f ms' % (1e3 * fit.x[9]) if with_latency else 'none':>9s}: "
                  f"RMS {np.sqrt(np.mean(r ** 2, axis=0)).round(0)} "
                  f"arcsec; sf {np.diag(M) * 1e6} ppm; lag-1 corr of increments "
                  f"{np.round([np.corrcoef(np.diff(r[:, i])[1:], np.diff(r[:, i])[:-1])[0, 1] for i in range(3)], 2)}",
                  flush=True)


if __name__ == "__main__":
    main()
