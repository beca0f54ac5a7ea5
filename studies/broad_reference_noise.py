"""What a single BROAD trial's full-rate residual is made of (issues 41/42), straight from the files.

Per sample, the reference's body increment ``log(R_(k-1)^-1 R_k)`` less the gyro's (a 3x3 response and a
bias fitted per axis by least squares, optionally a latency: the increment's difference, ``tau d(omega)``)
gives the increment error the likelihood sees at 285.7 Hz. Printed and drawn: its sd and lag-1
correlation for the trapezoidal increment of instantaneous rates (what ``gyrocal import`` does) and for
each sample taken as the average over the interval it closes, with and without a latency; the
autocorrelation of the reference's increments in the longest rest (where the gyro, 1.7 arcsec a sample,
shows the reference's own noise); and the error's sd binned by the rate.

    python studies/broad_reference_noise.py ../shared/data/broad/*.mat --figure docs/real-data/broad_reference_noise.png
"""

import argparse
import itertools
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy.io import loadmat
from scipy.spatial.transform import Rotation

from gyrocal.model.units import ARCSEC_RAD

RATE_EDGES = (0.0, 0.1, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0)
LAGS = np.arange(1, 31)


def increments(path: Path):
    """The trial's gyro rates (rad/s), the reference's body increments (rad), which pairs of rows both
    hold an attitude, and the sample interval (s)."""
    m = loadmat(path)
    rate = np.asarray(m["imu_gyr"], float)
    quat = np.asarray(m["opt_quat"], float)
    ok = np.all(np.isfinite(quat), axis=1)
    quat[~ok] = (1.0, 0.0, 0.0, 0.0)
    ref = Rotation.from_quat(quat[:, [1, 2, 3, 0]])
    return rate, (ref[:-1].inv() * ref[1:]).as_rotvec(), ok[1:] & ok[:-1], 1.0 / float(np.squeeze(m["sampling_rate"]))


def increment_error(rate, d_ref, good, dt, rule: str, latency: bool):
    """Per axis, the reference's increment less the fitted gyro increment (rad), and the latency (s)."""
    d_gyro = 0.5 * (rate[1:] + rate[:-1]) * dt if rule == "trapezoid" else rate[1:] * dt
    change = np.vstack([np.zeros((1, 3)), np.diff(d_gyro, axis=0)])
    x = np.column_stack([d_gyro, np.full(len(d_gyro), dt)] + ([change] if latency else []))
    err, taus = np.zeros_like(d_ref), []
    for i in range(3):
        c = np.linalg.lstsq(x[good], d_ref[good, i], rcond=None)[0]
        err[:, i] = d_ref[:, i] - x @ c
        taus.append(-c[4 + i] * dt if latency else 0.0)
    err[~good] = 0.0
    return err, np.array(taus)


def acf(x, lags):
    x = x - x.mean()
    return np.array([np.dot(x[:-k], x[k:]) / np.dot(x, x) for k in lags])


def longest_rest(rate, good, threshold_rad_s=0.05):
    idx = np.flatnonzero(good & (np.linalg.norm(rate[1:], axis=1) < threshold_rad_s))
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    return max(runs, key=len)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("mat", type=Path, nargs="+")
    p.add_argument("--figure", type=Path)
    a = p.parse_args()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for path in a.mat:
        rate, d_ref, good, dt = increments(path)
        name = path.stem
        for rule in ("trapezoid", "average"):
            for latency in (False, True):
                err, tau = increment_error(rate, d_ref, good, dt, rule, latency)
                lag1 = [acf(err[good, i], [1])[0] for i in range(3)]
                told = "latency " + ", ".join(f"{1e3 * t:+.2f}" for t in tau) + " ms" if latency else "no latency"
                print(f"{name} {rule:9s} {told:32s}"
                      f" increment error sd {np.round(err[good].std(axis=0) / ARCSEC_RAD, 1)} arcsec, lag-1 {np.round(lag1, 2)}")
        rest = longest_rest(rate, good)
        x = d_ref[rest] - d_ref[rest].mean(axis=0)
        r = np.array([acf(x[:, i], LAGS) for i in range(3)])
        angle = np.cumsum(x, axis=0)[::10]
        print(f"{name} rest of {len(rest)} samples: reference increment sd {np.round(x.std(axis=0) / ARCSEC_RAD, 1)} arcsec "
              f"(gyro {np.round((rate[1:][rest] * dt).std(axis=0) / ARCSEC_RAD, 2)}); acf lags 1-5 "
              f"{np.round(r.mean(axis=0)[:5], 2)}, sum of lags 1-30 {np.round(r.sum(axis=1), 2)}; "
              f"its attitude noise sd "
              f"(differences 10 samples apart / sqrt 2) "
              f"{np.round(np.diff(angle, axis=0).std(axis=0) / np.sqrt(2) / ARCSEC_RAD, 1)} arcsec")
        axes[0].plot(LAGS, r.mean(axis=0), "o-", label=f"{name[:2]}: reference at rest")
        err, _ = increment_error(rate, d_ref, good, dt, "average", True)
        speed = np.linalg.norm(rate[1:], axis=1)
        mid, sd = [], []
        for lo, hi in itertools.pairwise(RATE_EDGES):
            sel = good & (speed >= lo) & (speed < hi)
            if sel.sum() > 50:
                mid.append(np.sqrt(np.mean(speed[sel] ** 2)))
                sd.append(err[sel].std(axis=0) / ARCSEC_RAD)
                print(f"    |omega| {lo}-{hi} rad/s, {sel.sum()} samples: increment error sd {np.round(sd[-1], 1)} arcsec")
        for i, axis in enumerate("xyz"):
            axes[1].plot(mid, np.array(sd)[:, i], "o-", label=f"{name[:2]} {axis}")
    axes[0].axhline(0, color="k", lw=0.5)
    axes[0].axhline(-0.5, color="grey", ls=":", lw=1, label="white attitude noise (lag 1 only)")
    axes[0].set(xlabel="lag (samples, 3.5 ms)", ylabel="autocorrelation of increments", title="reference at rest, 285.7 Hz")
    axes[1].axhline(1.7, color="grey", ls=":", lw=1, label="gyro ARW a sample")
    axes[1].set(xlabel="|omega| (rad/s)", ylabel="increment error sd (arcsec)", yscale="log",
                title="increment error (interval averages, latency out)")
    for ax in axes:
        ax.legend(fontsize=7)
    fig.tight_layout()
    if a.figure:
        fig.savefig(a.figure, dpi=110)
        print(f"wrote {a.figure}")


if __name__ == "__main__":
    main()
