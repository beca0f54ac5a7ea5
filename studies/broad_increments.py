"""Which noise a BROAD trial's misfit is (issue 42), read off the gyro's increments against the
reference's over a lag, outside the pipeline. Over a lag ``L`` the reference's relative rotation
``R(t)^T R(t + L)`` minus the gyro's increment (corrected by one 3x3 response, a bias and a latency,
fitted once) has three signatures:

- white reference noise: flat in ``L`` (about sqrt(2) times the reference's sigma);
- a white error on the gyro's rate (ARW, or a rate-proportional scale-factor noise): grows as sqrt(L);
- a systematic rate error (a scale-factor nonlinearity, a bias that changes with the motion): grows as L.

Binned by the mean rate over the lag, the growth with ``|omega|`` tells a gyro or reference term that
follows the motion from one that does not. At rest the same numbers give the ARW and the reference
noise a data sheet or an at-rest recording would.

    python studies/broad_increments.py ../shared/data/broad/01_undisturbed_slow_rotation_A.mat \
        [--figure docs/real-data/broad_increments.png]
"""

import argparse
from pathlib import Path

import numpy as np
from scipy.io import loadmat
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from gyrocal.model.units import ARCSEC_RAD

LAGS = (3, 29, 286, 858, 2860)
"""Lags in samples (0.01 s to 10 s at 285.7 Hz)."""
RATE_BINS_RAD_S = (0.0, 0.05, 0.5, 1.0, 2.0, 3.0, 5.0, 20.0)
"""Mean |omega| bins: the first is rest."""


def load(path: Path):
    """Rates (N, 3) rad/s, reference quaternions (N, 4) scalar last, their validity, the sample step."""
    m = loadmat(path)
    q = np.asarray(m["opt_quat"], float)[:, [1, 2, 3, 0]]
    return np.asarray(m["imu_gyr"], float), q, np.all(np.isfinite(q), axis=1), 1.0 / float(np.squeeze(m["sampling_rate"]))


def lag_errors(rate, quat, valid, step_s, lag, response, bias_rad_s, latency_s, stride=None):
    """Rotation-vector errors (rad) of the gyro's increment over ``lag`` samples against the reference's,
    the gyro corrected (``response @ (rate(t + latency) - bias)``, trapezoid increments as `gyrocal
    import` makes them), and the mean |rate| over each lag; one lag every ``stride`` samples."""
    t = np.arange(len(rate)) * step_s
    shifted = np.stack([np.interp(t + latency_s, t, rate[:, i]) for i in range(3)], axis=1)
    corrected = (shifted - bias_rad_s) @ np.asarray(response).T
    inc = 0.5 * (corrected[1:] + corrected[:-1]) * step_s
    starts = np.arange(0, len(rate) - lag - 1, stride or lag)
    starts = starts[valid[starts] & valid[starts + lag]]
    gyro = Rotation.identity(len(starts))
    for j in range(lag):
        gyro = gyro * Rotation.from_rotvec(inc[starts + j])
    ref = Rotation.from_quat(quat[starts]).inv() * Rotation.from_quat(quat[starts + lag])
    speed = np.linalg.norm(rate, axis=1)
    total = np.concatenate([[0.0], np.cumsum(speed)])
    mean_rate = (total[starts + lag + 1] - total[starts]) / (lag + 1)
    return (gyro.inv() * ref).as_rotvec(), mean_rate


def fit_gyro(rate, quat, valid, step_s, lag=29):
    """One 3x3 response, bias (rad/s) and latency (s, positive: the gyro late) from the increments over
    ``lag`` samples, by least squares."""
    def residual(p):
        e, _ = lag_errors(rate, quat, valid, step_s, lag, np.eye(3) + p[:9].reshape(3, 3), p[10:13], p[9] * 1e-3, 3 * lag)
        return e.ravel()
    p = least_squares(residual, np.zeros(13), x_scale=np.r_[np.full(9, 1e-3), 1.0, np.full(3, 1e-3)]).x
    return np.eye(3) + p[:9].reshape(3, 3), p[10:13], p[9] * 1e-3


def table(rate, quat, valid, step_s, response, bias, latency_s):
    """RMS error (arcsec, per axis) and count per (lag, rate bin)."""
    rows = []
    for lag in LAGS:
        e, mean_rate = lag_errors(rate, quat, valid, step_s, lag, response, bias, latency_s)
        which = np.digitize(mean_rate, RATE_BINS_RAD_S) - 1
        for b in range(len(RATE_BINS_RAD_S) - 1):
            sel = which == b
            if sel.sum() > 5:
                rows.append((lag * step_s, b, float(np.sqrt(np.mean(e[sel] ** 2)) / ARCSEC_RAD), int(sel.sum())))
    return rows


def main():
    p = argparse.ArgumentParser()
    p.add_argument("trials", type=Path, nargs="+")
    p.add_argument("--figure", type=Path)
    a = p.parse_args()
    results = {}
    for path in a.trials:
        rate, quat, valid, step = load(path)
        response, bias, latency = fit_gyro(rate, quat, valid, step)
        print(f"{path.stem}: response diagonal - 1 (ppm) {np.round((np.diag(response) - 1) * 1e6)}, "
              f"bias (deg/h) {np.round(np.degrees(bias) * 3600, 1)}, latency {latency * 1e3:.2f} ms (gyro late)")
        rows = table(rate, quat, valid, step, response, bias, latency)
        results[path.stem] = rows
        for lag_s, b, rms, n in rows:
            lo, hi = RATE_BINS_RAD_S[b], RATE_BINS_RAD_S[b + 1]
            print(f"  lag {lag_s:7.3f} s  |omega| {lo:4.2f}-{hi:5.2f} rad/s  RMS {rms:7.0f} arcsec per axis  ({n} lags)")
    if a.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4.2), squeeze=False)
        for ax, (name, rows) in zip(axes[0], results.items()):
            rows = np.array(rows)
            for b in np.unique(rows[:, 1]).astype(int):
                sel = rows[:, 1] == b
                label = "rest" if b == 0 else f"|omega| {RATE_BINS_RAD_S[b]}-{RATE_BINS_RAD_S[b + 1]} rad/s"
                ax.loglog(rows[sel, 0], rows[sel, 2], "o-", label=label)
            lags = rows[:, 0]
            ref = np.sqrt(lags / lags.min()) * rows[rows[:, 1] == 3, 2][0] if (rows[:, 1] == 3).any() else None
            if ref is not None:
                ax.loglog(lags, ref, "k:", label="grows as sqrt(lag)")
            ax.set(xlabel="lag (s)", ylabel="increment error RMS per axis (arcsec)", title=name)
            ax.legend(fontsize=7)
        fig.tight_layout()
        a.figure.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(a.figure, dpi=110)
        print("figure:", a.figure)


if __name__ == "__main__":
    main()
